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
            out.push_str(&format!("{line:>gutter$} │ {text}\n"));
            let (end_line, end_col) = file.line_col(label.span.end);
            let width = if end_line == line {
                end_col.saturating_sub(col).max(1)
            } else {
                text.chars().count().saturating_sub(col - 1).max(1)
            };
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

impl fmt::Display for Errors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, diagnostic) in self.diagnostics.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            f.write_str(&diagnostic.render(&self.file))?;
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

/// The candidate closest to `name` by edit distance, if it is close enough to be a typo.
pub fn closest<'c>(name: &str, candidates: &[&'c str]) -> Option<&'c str> {
    const LONGEST: usize = 64;
    let length = name.chars().count();
    if length > LONGEST {
        return None;
    }
    // Short names only match up to case (`mn` → `mN`); longer ones allow a typo per 3 chars.
    let limit = if length < 3 { 0 } else { (length / 3).max(1) };
    let lower = name.to_lowercase();
    candidates
        .iter()
        .filter(|c| c.chars().count() <= LONGEST && **c != name)
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
