//! A spec file's TOML text read into its serde type, with the parser's complaints about a key
//! pinned to the key's line: the experiment, study and diagnosis files share this.
//!
//! Consumes: TOML text and the hint that says where the file's keys are listed. Produces: the
//! spec, or a [`TomlError`] whose `Display` is the message users read.

use std::fmt;

use serde::de::DeserializeOwned;

/// Why TOML text is not the spec it should be.
#[derive(Debug)]
pub enum TomlError {
    /// A key the spec does not have (`line` of the file, 1-based, where it is set).
    UnknownKey {
        key: String,
        line: usize,
        /// Where the keys are listed, e.g. `docs/sweep.md lists a study's keys`.
        hint: &'static str,
    },
    /// A key whose value has the wrong type (a number where a quantity string is expected).
    MistypedKey {
        key: String,
        line: usize,
        /// The parser's message.
        message: String,
    },
    /// Not TOML of the spec (the parser's message, with its line).
    Other { message: String },
}

/// Parses `text` as a `T`; `hint` says where an unknown key's message sends the reader.
pub fn parse<T: DeserializeOwned>(text: &str, hint: &'static str) -> Result<T, TomlError> {
    toml::from_str(text).map_err(|error| {
        let message = error.to_string();
        if let Some((key, line)) = unknown_key(text, &message) {
            TomlError::UnknownKey { key, line, hint }
        } else if let Some((key, line)) = mistyped_key(text, &message) {
            TomlError::MistypedKey { key, line, message }
        } else {
            TomlError::Other {
                message: message.trim_end().to_string(),
            }
        }
    })
}

impl fmt::Display for TomlError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TomlError::UnknownKey { key, line, hint } => {
                write!(f, "line {line}: unknown key `{key}`\n  hint: {hint}")
            }
            TomlError::MistypedKey { key, line, message } => mistyped_text(f, key, *line, message),
            TomlError::Other { message } => f.write_str(message),
        }
    }
}

impl std::error::Error for TomlError {}

/// The key and line of the parser's "unknown field" `message` on `text`. The keys every kind
/// shares are flattened into the kind's (serde's `flatten`), which loses the parser's span
/// of the offending key, so its line is found by name: the first `key = …` line.
fn unknown_key(text: &str, message: &str) -> Option<(String, usize)> {
    let key = message.split("unknown field `").nth(1)?.split('`').next()?;
    let line = text.lines().position(|line| {
        line.trim_start()
            .strip_prefix(key)
            .is_some_and(|rest| rest.trim_start().starts_with('='))
    })?;
    Some((key.to_string(), line + 1))
}

/// The message of [`mistyped_key`]'s finding: line, key, the parser's reason and a hint.
fn mistyped_text(f: &mut fmt::Formatter<'_>, key: &str, line: usize, message: &str) -> fmt::Result {
    let message = message.lines().last().unwrap_or_default();
    write!(f, "line {line}: key `{key}`: {message}")?;
    if message.contains("expected a string") {
        write!(
            f,
            "\n  hint: quantities are strings with a unit, e.g. `{key} = \"0.5 mN\"`"
        )?;
    }
    Ok(())
}

/// The key and line of the value the parser's "invalid type" `message` is about, on `text`
/// (e.g. "invalid type: floating point `0.05`, expected a string"): flattened keys lose
/// their span, so the parser points at the file's start. Found as the only `key = VALUE`
/// line with that value; `None` if there is no such line or more than one.
fn mistyped_key(text: &str, message: &str) -> Option<(String, usize)> {
    let found = message.split("invalid type: ").nth(1)?;
    let value = match found.split_once('`') {
        Some((_, rest)) => rest.split('`').next()?.to_string(),
        // Strings are quoted: `string "abc"`.
        None => format!("\"{}\"", found.split('"').nth(1)?),
    };
    let mut matches = text.lines().enumerate().filter_map(|(k, line)| {
        let (key, rest) = line.split_once('=')?;
        let rest = rest.split('#').next().unwrap_or_default().trim();
        (rest == value).then(|| (key.trim().to_string(), k + 1))
    });
    let first = matches.next()?;
    matches.next().is_none().then_some(first)
}
