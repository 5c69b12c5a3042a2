//! Text for a terminal: what a file or an argument says is shown, never obeyed.
//!
//! Consumes: any text bound for stdout or stderr (messages quote file contents, file names,
//! TOML titles). Produces: the same text with every control character made visible, so an
//! escape sequence in an input file cannot clear the screen, recolour it, retitle the
//! window or hide a line (ECMA-48 C0/C1 controls; Unicode bidirectional overrides, which can
//! reorder what a reader sees).

use std::borrow::Cow;

/// `text` with its control characters replaced: C0 controls (except line feed and tab) and
/// DEL by their Unicode Control Pictures (`␛` for ESC: one column wide, so a diagnostic's
/// caret stays under its column), C1 controls and bidirectional overrides and isolates by
/// `\u{…}`.
pub fn terminal_safe(text: &str) -> Cow<'_, str> {
    if !text.chars().any(needs_escape) {
        return Cow::Borrowed(text);
    }
    let mut safe = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        match c {
            c if !needs_escape(c) => safe.push(c),
            '\u{0}'..='\u{1f}' => safe.push(char::from_u32(0x2400 + c as u32).unwrap_or('?')),
            '\u{7f}' => safe.push('\u{2421}'),
            c => safe.push_str(&format!("\\u{{{:x}}}", c as u32)),
        }
    }
    Cow::Owned(safe)
}

fn needs_escape(c: char) -> bool {
    match c {
        '\n' | '\t' => false,
        '\u{0}'..='\u{1f}' | '\u{7f}'..='\u{9f}' => true,
        '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}' => true,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::terminal_safe;

    #[test]
    fn controls_are_shown_not_obeyed() {
        assert_eq!(terminal_safe("plain\ttext\n"), "plain\ttext\n");
        assert!(matches!(terminal_safe("ok"), std::borrow::Cow::Borrowed(_)));
        assert_eq!(terminal_safe("\u{1b}[2Jq"), "␛[2Jq");
        assert_eq!(terminal_safe("a\rb\u{7}\u{0}"), "a␍b␇␀");
        assert_eq!(terminal_safe("\u{7f}"), "␡");
        assert_eq!(terminal_safe("\u{9b}31m"), "\\u{9b}31m");
        assert_eq!(terminal_safe("x\u{202e}y"), "x\\u{202e}y");
        // Other non-ASCII text is left alone.
        assert_eq!(terminal_safe("χ² µm ␛"), "χ² µm ␛");
    }
}
