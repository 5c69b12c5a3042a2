//! Diagnostics shared by every phase: spans into a source file, a [`Diagnostic`] with labels
//! and a help line, and [`Errors`], the public error of the pipeline.
//!
//! Consumes: byte spans produced by the front end (pest positions are byte offsets).
//! Produces: plain-text renderings in the codespan style, e.g.
//!
//! ```text
//! error[E0201]: unknown body `forearm2`
//!   ┌─ models/arm.mech:14:33
//!    │
//! 14 │ joint elbow = pin(upper_arm, forearm2) {
//!    │                              ^^^^^^^^ not declared in this model
//!    = help: bodies in scope: upper_arm, forearm
//! ```
//!
//! `Debug` renders the same text as `Display`, so `build.rs` code that `unwrap()`s or returns
//! `Result<(), Errors>` from `main` prints readable diagnostics.

use std::fmt;
use std::sync::Arc;

/// A byte range `start..end` in one source file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Span {
    pub start: u32,
    pub end: u32,
}

impl Span {
    pub fn new(start: usize, end: usize) -> Span {
        Span {
            start: start as u32,
            end: end as u32,
        }
    }
    /// The smallest span covering both.
    pub fn to(self, other: Span) -> Span {
        Span {
            start: self.start.min(other.start),
            end: self.end.max(other.end),
        }
    }
}

/// A source file: its path as shown in diagnostics (relative to the crate root when the
/// build API knows it) and its text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SourceFile {
    pub path: String,
    pub text: String,
}

impl SourceFile {
    pub fn new(path: impl Into<String>, text: impl Into<String>) -> SourceFile {
        SourceFile {
            path: path.into(),
            text: text.into(),
        }
    }

    /// 1-based line and column (in characters) of a byte offset.
    pub fn line_col(&self, offset: u32) -> (usize, usize) {
        let offset = (offset as usize).min(self.text.len());
        let before = &self.text[..floor_char_boundary(&self.text, offset)];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        (line, before[line_start..].chars().count() + 1)
    }

    fn line_text(&self, line: usize) -> &str {
        self.text.lines().nth(line - 1).unwrap_or("")
    }
}

fn floor_char_boundary(text: &str, mut offset: usize) -> usize {
    while offset > 0 && !text.is_char_boundary(offset) {
        offset -= 1;
    }
    offset
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Severity {
    Error,
    Warning,
}

/// A message attached to a span. The first label of a diagnostic is the primary one.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Label {
    pub span: Span,
    pub message: String,
}

/// One user-facing message: what is wrong (`message`), where (`labels`), and what to do (`help`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    pub severity: Severity,
    /// Stable code, `E01xx` for syntax, `E02xx` names, `E03xx` dimensions, `E04xx` structure,
    /// `E05xx` physical plausibility.
    pub code: &'static str,
    pub message: String,
    pub labels: Vec<Label>,
    pub notes: Vec<String>,
    pub help: Option<String>,
}

impl Diagnostic {
    pub fn error(code: &'static str, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            severity: Severity::Error,
            code,
            message: message.into(),
            labels: Vec::new(),
            notes: Vec::new(),
            help: None,
        }
    }
    pub fn warning(code: &'static str, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            severity: Severity::Warning,
            ..Diagnostic::error(code, message)
        }
    }
    pub fn with_label(mut self, span: Span, message: impl Into<String>) -> Diagnostic {
        self.labels.push(Label {
            span,
            message: message.into(),
        });
        self
    }
    pub fn with_note(mut self, note: impl Into<String>) -> Diagnostic {
        self.notes.push(note.into());
        self
    }
    pub fn with_help(mut self, help: impl Into<String>) -> Diagnostic {
        self.help = Some(help.into());
        self
    }

    /// Renders as plain text (no colour) against the file it refers to.
    pub fn render(&self, file: &SourceFile) -> String {
        let mut out = String::new();
        let kind = match self.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
        };
        out.push_str(&format!("{kind}[{}]: {}\n", self.code, self.message));
        let gutter = self
            .labels
            .iter()
            .map(|l| file.line_col(l.span.start).0.to_string().len())
            .max()
            .unwrap_or(1);
        let pad = " ".repeat(gutter);
        for (i, label) in self.labels.iter().enumerate() {
            let (line, col) = file.line_col(label.span.start);
            if i == 0 {
                out.push_str(&format!("{pad}┌─ {}:{line}:{col}\n", file.path));
            } else {
                out.push_str(&format!("{pad}├─ {}:{line}:{col}\n", file.path));
            }
            out.push_str(&format!("{pad} │\n"));
            let text = file.line_text(line);
            let (end_line, end_col) = file.line_col(label.span.end);
            let width = if end_line == line {
                end_col.saturating_sub(col).max(1)
            } else {
                text.chars().count().saturating_sub(col - 1).max(1)
            };
            let (text, col, width) = excerpt(text, col, width);
            out.push_str(&format!("{line:>gutter$} │ {text}\n"));
            let marker = if i == 0 { "^" } else { "-" };
            out.push_str(&format!(
                "{pad} │ {}{} {}\n",
                " ".repeat(col - 1),
                marker.repeat(width),
                label.message
            ));
        }
        for note in &self.notes {
            out.push_str(&format!("{pad} = note: {note}\n"));
        }
        if let Some(help) = &self.help {
            out.push_str(&format!("{pad} = help: {help}\n"));
        }
        out
    }
}

/// Longest source line a diagnostic shows, in characters; a longer one (a generated file of
/// megabytes on one line) is cut around the label, with `…` where it is cut.
const MAX_LINE: usize = 160;

/// The part of `text` shown for a label at 1-based character column `col`, `width`
/// characters wide, and the label's column and width in that part.
fn excerpt(text: &str, col: usize, width: usize) -> (String, usize, usize) {
    if text.chars().count() <= MAX_LINE {
        return (text.to_string(), col, width);
    }
    let start = (col - 1).saturating_sub(MAX_LINE / 4);
    let shown: String = text.chars().skip(start).take(MAX_LINE).collect();
    let cut_end = text.chars().count() > start + MAX_LINE;
    let (before, after) = (
        if start > 0 { "…" } else { "" },
        if cut_end { "…" } else { "" },
    );
    let col = col - start + usize::from(start > 0);
    let width = width
        .min(MAX_LINE + 1 + usize::from(start > 0) - col)
        .max(1);
    (format!("{before}{shown}{after}"), col, width)
}

/// All errors of the phase that failed, with the file they refer to.
#[derive(Clone, PartialEq, Eq)]
pub struct Errors {
    pub file: Arc<SourceFile>,
    pub diagnostics: Vec<Diagnostic>,
}

impl Errors {
    pub fn new(file: Arc<SourceFile>, diagnostics: Vec<Diagnostic>) -> Errors {
        Errors { file, diagnostics }
    }
    /// An error that is not about a place in the file (unreadable file, I/O failure).
    pub fn io(path: &str, error: &std::io::Error) -> Errors {
        let file = Arc::new(SourceFile::new(path, ""));
        let diagnostic =
            Diagnostic::error("E0001", format!("cannot read or write `{path}`: {error}"));
        Errors {
            file,
            diagnostics: vec![diagnostic],
        }
    }
}

/// Diagnostics `Display` renders; the others are only counted. The first ones are what to
/// fix, and thousands (a generated file gone wrong) took seconds to print.
pub const MAX_SHOWN: usize = 100;

impl fmt::Display for Errors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, diagnostic) in self.diagnostics.iter().take(MAX_SHOWN).enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            f.write_str(&diagnostic.render(&self.file))?;
        }
        let hidden = self.diagnostics.len().saturating_sub(MAX_SHOWN);
        if hidden > 0 {
            writeln!(f, "\n… and {hidden} more not shown")?;
        }
        let errors = self
            .diagnostics
            .iter()
            .filter(|d| d.severity == Severity::Error)
            .count();
        if errors > 1 {
            writeln!(f, "\n{errors} errors in {}", self.file.path)?;
        }
        Ok(())
    }
}

impl fmt::Debug for Errors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "\n{self}")
    }
}

impl std::error::Error for Errors {}

/// Most names [`closest`] searches.
pub const MAX_CANDIDATES: usize = 1000;

/// The candidate closest to `name` by edit distance, if it is close enough to be a typo.
/// Not searched among more than [`MAX_CANDIDATES`]: a file of thousands of names and as many
/// typos (generated text gone wrong) made the search quadratic, 80 s for 16,000.
pub fn closest<'c>(name: &str, candidates: &[&'c str]) -> Option<&'c str> {
    const LONGEST: usize = 64;
    let length = name.chars().count();
    if length > LONGEST || candidates.len() > MAX_CANDIDATES {
        return None;
    }
    // Short names only match up to case (`mn` → `mN`); longer ones allow a typo per 3 chars.
    let limit = if length < 3 { 0 } else { (length / 3).max(1) };
    let lower = name.to_lowercase();
    candidates
        .iter()
        // The distance is at least the difference in length.
        .filter(|c| c.chars().count().abs_diff(length) <= limit && **c != name)
        .map(|c| {
            (
                (
                    edit_distance(&lower, &c.to_lowercase()),
                    edit_distance(name, c),
                ),
                *c,
            )
        })
        .filter(|((folded, _), _)| *folded <= limit)
        .min_by_key(|(key, _)| *key)
        .map(|(_, c)| c)
}

/// Levenshtein distance over characters.
pub fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let substitution = diagonal + usize::from(ca != *cb);
            diagonal = row[j + 1];
            row[j + 1] = substitution.min(row[j] + 1).min(row[j + 1] + 1);
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shows_the_first_diagnostics_and_counts_the_rest() {
        let text = "x\n".repeat(MAX_SHOWN + 5);
        let file = Arc::new(SourceFile::new("m.mech", text));
        let diagnostics = (0..MAX_SHOWN + 5)
            .map(|i| {
                Diagnostic::error("E0204", format!("unknown name number {i}"))
                    .with_label(Span::new(2 * i, 2 * i + 1), "here")
            })
            .collect();
        let shown = Errors::new(file, diagnostics).to_string();
        assert!(shown.contains(&format!("number {}\n", MAX_SHOWN - 1)));
        assert!(!shown.contains(&format!("number {}\n", MAX_SHOWN)));
        assert!(shown.ends_with(&format!(
            "\n… and 5 more not shown\n\n{} errors in m.mech\n",
            MAX_SHOWN + 5
        )));
    }

    #[test]
    fn a_long_line_is_cut_around_its_label() {
        let text = format!("param a = {}2 * ;\n", "1 + ".repeat(1000));
        let at = text.find("* ;").expect("the error") + 2;
        let file = SourceFile::new("m.mech", text);
        let d =
            Diagnostic::error("E0101", "syntax error").with_label(Span::new(at, at + 1), "here");
        let rendered = d.render(&file);
        let lines: Vec<&str> = rendered.lines().collect();
        let (source, marker) = (lines[3], lines[4]);
        assert!(
            source.starts_with("1 │ …") && source.ends_with("2 * ;"),
            "{source}"
        );
        assert!(source.chars().count() < MAX_LINE + 10);
        // The marker stands under the `;`.
        let column =
            |line: &str, pattern: &str| line.find(pattern).map(|b| line[..b].chars().count());
        assert_eq!(column(marker, "^ here"), column(source, ";"));
    }

    #[test]
    fn renders_label_under_the_right_column_after_non_ascii() {
        let file = SourceFile::new("m.mech", "// θ ω\nparam l = 2 * ;\n");
        let d = Diagnostic::error("E0101", "syntax error")
            .with_label(Span::new(23, 24), "expected an expression")
            .with_help("finish the expression");
        let text = d.render(&file);
        assert_eq!(
            text,
            "error[E0101]: syntax error\n ┌─ m.mech:2:15\n  │\n2 │ param l = 2 * ;\n  │               ^ expected an expression\n  = help: finish the expression\n"
        );
    }
}
