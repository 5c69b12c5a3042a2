//! Why a study cannot run, and why one of its samples has no outputs.
//!
//! Consumes: the typed errors of the layers below (the leg the outputs are computed on,
//! session, quantities, resonance refinement, the sampler). Produces: [`Error`], naming the
//! study file, the key and its line, and [`SampleError`], kept in the table beside the
//! failed sample.

use std::fmt;
use std::path::PathBuf;

use mech_codegen::front::units::parse_quantity;
use mech_codegen::ir::Dimension;

use super::sample::DrawError;
use crate::experiments::leg;
use crate::frequency::RefineError;
use crate::toml_file::TomlError;
use crate::{quantity, session};

#[derive(Debug)]
pub enum Error {
    Read {
        path: PathBuf,
        message: String,
    },
    /// Not TOML of a study: an unknown key, a mistyped value, …
    Toml(TomlError),
    /// A key's value that cannot be used; `line` 0: a command-line option.
    Key {
        key: String,
        line: usize,
        message: String,
    },
    /// A quantity (voltage, frequencies) that does not parse or has the wrong unit.
    Quantity {
        line: usize,
        error: quantity::Error,
    },
    /// A parameter's value whose text is not a quantity.
    BadQuantity {
        key: String,
        line: usize,
        text: String,
        error: mech_codegen::front::units::QuantityError,
    },
    /// A parameter's value with a unit of another dimension than the model's parameter.
    WrongUnit {
        key: String,
        line: usize,
        parameter: String,
        text: String,
        found: Dimension,
        expected: Dimension,
        relative: bool,
    },
    /// A key an output needs.
    Missing {
        key: &'static str,
        output: String,
    },
    /// Neither `model` nor `[[robot]]`, or both.
    ModelOrRobots,
    /// A model that cannot be opened, or is not the kind the outputs need.
    Model(Box<leg::Error>),
    /// In the `[[robot]]` of this name.
    Robot {
        name: String,
        error: Box<Error>,
    },
    TooManySamples {
        key: String,
        line: Option<usize>,
        max: usize,
    },
    /// `--samples` given for a grid.
    GridSamples,
    IndexOutOfRange {
        index: usize,
        samples: usize,
    },
    InFile {
        path: PathBuf,
        error: Box<Error>,
    },
}

impl Error {
    pub(crate) fn key(key: &str, line: usize, message: impl Into<String>) -> Error {
        Error::Key {
            key: key.to_string(),
            line,
            message: message.into(),
        }
    }

    /// This error, in the robot `name` if any.
    pub(crate) fn within(self, name: Option<&str>) -> Error {
        match name {
            Some(name) => Error::Robot {
                name: name.to_string(),
                error: Box::new(self),
            },
            None => self,
        }
    }

    pub fn in_file(self, path: &std::path::Path) -> Error {
        Error::InFile {
            path: path.to_path_buf(),
            error: Box::new(self),
        }
    }
}

/// `line N: ` (nothing for line 0, a command-line option).
fn at(f: &mut fmt::Formatter<'_>, line: usize) -> fmt::Result {
    match line {
        0 => Ok(()),
        line => write!(f, "line {line}: "),
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Read { path, message } => {
                write!(f, "cannot read study `{}`: {message}", path.display())
            }
            Error::Toml(error) => write!(f, "{error}"),
            Error::Key { key, line, message } => {
                at(f, *line)?;
                match key.starts_with("--") {
                    true => write!(f, "{key}: {message}"),
                    false => write!(f, "key `{key}`: {message}"),
                }
            }
            Error::Quantity { line, error } => write!(f, "line {line}: {error}"),
            Error::BadQuantity {
                key,
                line,
                text,
                error,
            } => write!(f, "line {line}: key `{key}`: `{text}`: {error}"),
            Error::WrongUnit {
                key,
                line,
                parameter,
                text,
                found,
                expected,
                relative,
            } => {
                write!(f, "line {line}: key `{key}`: `{text}` ")?;
                match (relative, *found == Dimension::NONE) {
                    (true, _) => write!(
                        f,
                        "has unit {found}, but `relative = true` values are plain factors of \
                         the model's value of `{parameter}` (e.g. `1.05`)"
                    ),
                    (false, true) => write!(
                        f,
                        "has no unit, but parameter `{parameter}` is in {expected} (write \
                         e.g. `\"{text} {expected}\"`, or `relative = true` for factors)"
                    ),
                    (false, false) => write!(
                        f,
                        "has unit {found}, but parameter `{parameter}` is in {expected}"
                    ),
                }
            }
            Error::Missing { key, output } => {
                write!(f, "missing key `{key}`: output `{output}` needs it")
            }
            Error::ModelOrRobots => f.write_str(
                "give either `model` (one model) or `[[robot]]` tables (several), not both or \
                 neither",
            ),
            Error::Model(error) => write!(f, "{error}"),
            Error::Robot { name, error } => write!(f, "robot `{name}`: {error}"),
            Error::TooManySamples { key, line, max } => {
                at(f, line.unwrap_or(0))?;
                let key = match key.starts_with("--") {
                    true => key.clone(),
                    false => format!("key `{key}`"),
                };
                write!(f, "{key}: more than {max} samples; split the study")
            }
            Error::GridSamples => f.write_str(
                "--samples: the study is a grid, whose samples are its points; it takes no \
                 sample count",
            ),
            Error::IndexOutOfRange { index, samples } => write!(
                f,
                "sample index {index} is out of range: the study has {samples} samples"
            ),
            Error::InFile { path, error } => write!(f, "study `{}`: {error}", path.display()),
        }
    }
}

impl std::error::Error for Error {}

/// Why one sample has no outputs (for one robot, or for all).
#[derive(Debug)]
pub enum SampleError {
    /// Its values could not be drawn.
    Draw(DrawError),
    /// A value breaks the model's physical rules (a negative stiffness).
    Setting(Box<session::Error>),
    /// The analysis failed (e.g. statics did not converge).
    Analysis(Box<leg::Error>),
    /// A resonance could not be refined on the linear model's response.
    Resonances(RefineError),
}

impl fmt::Display for SampleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SampleError::Draw(e) => write!(f, "{e}"),
            SampleError::Setting(e) => write!(f, "{e}"),
            SampleError::Analysis(e) => write!(f, "{e}"),
            SampleError::Resonances(e) => write!(f, "resonance refinement: {e}"),
        }
    }
}

impl std::error::Error for SampleError {}

impl From<leg::Error> for SampleError {
    fn from(error: leg::Error) -> SampleError {
        SampleError::Analysis(Box::new(error))
    }
}

impl From<RefineError> for SampleError {
    fn from(error: RefineError) -> SampleError {
        SampleError::Resonances(error)
    }
}

/// A parameter's value `text` (key `key`, on `line`) in SI, checked against `expected`
/// (the model parameter `parameter`'s dimension, or none for a relative factor).
pub(crate) fn quantity(
    key: &str,
    line: usize,
    text: &str,
    expected: Dimension,
    parameter: &str,
) -> Result<f64, Error> {
    let (value, found) = parse_quantity(text).map_err(|error| Error::BadQuantity {
        key: key.to_string(),
        line,
        text: text.to_string(),
        error,
    })?;
    if found != expected {
        return Err(Error::WrongUnit {
            key: key.to_string(),
            line,
            parameter: parameter.to_string(),
            text: text.to_string(),
            found,
            expected,
            relative: expected == Dimension::NONE && found != Dimension::NONE,
        });
    }
    if !value.is_finite() {
        return Err(Error::key(key, line, format!("`{text}` is not finite")));
    }
    Ok(value)
}

/// A standard deviation: not negative.
pub(crate) fn spread(key: &str, line: usize, sd: f64) -> Result<f64, Error> {
    match sd >= 0.0 {
        true => Ok(sd),
        false => Err(Error::key(
            key,
            line,
            "a standard deviation cannot be negative",
        )),
    }
}

/// Bounds `low < high`.
pub(crate) fn ordered(key: &str, line: usize, low: f64, high: f64) -> Result<(), Error> {
    match low < high {
        true => Ok(()),
        false => Err(Error::key(key, line, "must be above `low`")),
    }
}
