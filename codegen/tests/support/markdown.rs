//! The fenced examples of a Markdown page (```` ```mech ```` and ```` ```mech,fail ````), for
//! the tests that keep `docs/mech-language.md` true (codegen's loading test, the root crate's
//! assembly test).
//!
//! Consumes: Markdown text. Produces: [`Example`]s with their line numbers.

#![allow(dead_code)]

/// A fenced example: its first line number, whether it must fail, and its text.
pub struct Example {
    pub line: usize,
    pub must_fail: bool,
    pub text: String,
}

pub fn examples(markdown: &str) -> Vec<Example> {
    let mut examples = Vec::new();
    let mut current: Option<Example> = None;
    for (index, line) in markdown.lines().enumerate() {
        let trimmed = line.trim();
        match current.take() {
            Some(example) if trimmed == "```" => examples.push(example),
            Some(mut example) => {
                example.text.push_str(line);
                example.text.push('\n');
                current = Some(example);
            }
            None => {
                let tag = trimmed.strip_prefix("```").map(str::trim);
                if let Some(must_fail) = match tag {
                    Some("mech") => Some(false),
                    Some("mech,fail") => Some(true),
                    _ => None,
                } {
                    current = Some(Example {
                        line: index + 2,
                        must_fail,
                        text: String::new(),
                    });
                }
            }
        }
    }
    examples
}
