//! The examples of `docs/mech-language.md` stay true: every ```` ```mech ```` block loads,
//! every ```` ```mech,fail ```` block is rejected.
//!
//! Consumes: `docs/mech-language.md`.
//! Produces: one test reporting every example that does not behave as tagged.

use std::sync::Arc;

use mech_codegen::diag::SourceFile;
use mech_codegen::front;

/// A fenced example: its first line number, whether it must fail, and its text.
struct Example {
    line: usize,
    must_fail: bool,
    text: String,
}

fn examples(markdown: &str) -> Vec<Example> {
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

#[test]
fn language_reference_examples_load_as_tagged() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/mech-language.md");
    let markdown = std::fs::read_to_string(path).expect("docs/mech-language.md is readable");
    let examples = examples(&markdown);
    assert!(
        examples.len() >= 8,
        "found only {} examples",
        examples.len()
    );
    let mut failures = Vec::new();
    for example in &examples {
        let file = SourceFile::new(
            format!("docs/mech-language.md:{}", example.line),
            example.text.clone(),
        );
        match (front::load(Arc::new(file)), example.must_fail) {
            (Ok(_), false) | (Err(_), true) => {}
            (Ok(_), true) => failures.push(format!(
                "example at line {} loaded but is tagged `mech,fail`",
                example.line
            )),
            (Err(errors), false) => failures.push(format!(
                "example at line {} failed:\n{errors}",
                example.line
            )),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
