//! A study file as written: the TOML keys of `mech sweep` (docs/sweep.md), read with the
//! line of every parameter key so that errors can name it.
//!
//! Consumes: TOML text. Produces: a [`StudyFile`] (unchecked values: quantities are still
//! text; [`super::prepare`] checks them against the models), or an [`Error`] naming the key
//! and its line.

use std::path::PathBuf;

use serde::Deserialize;
use toml::Spanned;

use super::Error;
use crate::session::ModelSpec;
use crate::toml_file;

/// The whole file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    pub title: Option<String>,
    #[serde(default)]
    pub notes: Vec<String>,
    /// The model, when the study has one (else `[[robot]]` tables).
    pub model: Option<PathBuf>,
    #[serde(default)]
    pub set: Vec<String>,
    #[serde(default)]
    pub independent: Vec<String>,
    /// Several models under the same parameter values (e.g. two robots' tolerances).
    #[serde(default)]
    pub robot: Vec<Robot>,
    /// Monte-Carlo samples (a grid has as many as its points).
    pub samples: Option<Spanned<i64>>,
    /// The seed of the Monte-Carlo draws.
    #[serde(default)]
    pub seed: u64,
    /// Drive voltage of the HAMR outputs (`225 V`).
    pub voltage: Option<Spanned<String>>,
    /// The frequency range searched for resonances (`["10 Hz", "300 Hz"]`).
    pub frequencies: Option<Spanned<Vec<String>>>,
    /// The outputs, e.g. `["free_stroke.lift", "natural_frequency.1"]`.
    pub outputs: Spanned<Vec<String>>,
    pub parameter: Vec<ParameterFile>,
}

/// One `[[robot]]`: a name and its model.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Robot {
    pub name: String,
    #[serde(flatten)]
    pub model: ModelSpec,
}

/// A number or a quantity's text, as a study writes a value (`1.05`, `"65 uN*m/rad"`).
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum Value {
    Number(f64),
    Text(String),
}

impl Value {
    pub fn text(&self) -> String {
        match self {
            Value::Number(x) => format!("{x:?}"),
            Value::Text(text) => text.clone(),
        }
    }
}

/// One `[[parameter]]`: a model parameter and where its values come from.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParameterFile {
    pub name: Spanned<String>,
    /// The values are factors of each model's own value (plain numbers), not quantities.
    #[serde(default)]
    pub relative: bool,
    /// `normal`, `uniform` or `truncated_normal`.
    pub distribution: Option<Spanned<String>>,
    pub mean: Option<Spanned<Value>>,
    pub sd: Option<Spanned<Value>>,
    pub low: Option<Spanned<Value>>,
    pub high: Option<Spanned<Value>>,
    /// A grid's values.
    pub values: Option<Spanned<Vec<Value>>>,
    /// A grid's evenly spaced values, `"LOW .. HIGH : N"`.
    pub range: Option<Spanned<String>>,
}

/// The 1-based line of byte `offset` of `text`.
pub fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

/// Parses a study's TOML text; unknown and mistyped keys are named with their line.
pub fn parse(text: &str) -> Result<StudyFile, Error> {
    toml_file::parse(text, "docs/sweep.md lists a study's keys").map_err(Error::Toml)
}
