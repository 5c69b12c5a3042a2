//! The examples of `docs/mech-language.md` stay true: every ```` ```mech ```` block loads,
//! every ```` ```mech,fail ```` block is rejected.
//!
//! Consumes: `docs/mech-language.md`.
//! Produces: one test reporting every example that does not behave as tagged.

use std::sync::Arc;

use mech_codegen::diag::SourceFile;
use mech_codegen::front;

#[path = "support/markdown.rs"]
mod markdown;

use markdown::examples;

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
