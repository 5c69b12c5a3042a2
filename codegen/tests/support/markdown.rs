//! The fenced blocks of a Markdown page, for the tests that keep the docs true: the
//! ```` ```mech ```` and ```` ```mech,fail ```` examples of `docs/mech-language.md` (codegen's
//! loading test, the root crate's assembly test) and the documented commands with their
//! printed output (the root crate's docs test).
//!
//! Consumes: Markdown text. Produces: [`Block`]s (and the [`Example`]s among them) with their
//! line numbers.

#![allow(dead_code)]

/// A fenced block: the line of its first content line, the fence's tag (` ```text ` → `text`),
/// the last non-blank line before the fence, and the content.
pub struct Block {
    pub line: usize,
    pub tag: String,
    pub preceding: String,
    pub text: String,
}

/// Every fenced block of `markdown`, in order.
pub fn blocks(markdown: &str) -> Vec<Block> {
    let mut blocks = Vec::new();
    let mut current: Option<Block> = None;
    let mut preceding = "";
    for (index, line) in markdown.lines().enumerate() {
        let trimmed = line.trim();
        match current.take() {
            Some(block) if trimmed == "```" => blocks.push(block),
            Some(mut block) => {
                block.text.push_str(line);
                block.text.push('\n');
                current = Some(block);
            }
            None => match trimmed.strip_prefix("```") {
                Some(tag) => {
                    current = Some(Block {
                        line: index + 2,
                        tag: tag.trim().to_string(),
                        preceding: preceding.to_string(),
                        text: String::new(),
                    })
                }
                None if !trimmed.is_empty() => preceding = trimmed,
                None => {}
            },
        }
    }
    blocks
}

/// A `.mech` example: its first line number, whether it must fail, and its text.
pub struct Example {
    pub line: usize,
    pub must_fail: bool,
    pub text: String,
}

pub fn examples(markdown: &str) -> Vec<Example> {
    blocks(markdown)
        .into_iter()
        .filter_map(|block| {
            let must_fail = match block.tag.as_str() {
                "mech" => false,
                "mech,fail" => true,
                _ => return None,
            };
            Some(Example {
                line: block.line,
                must_fail,
                text: block.text,
            })
        })
        .collect()
}
