//! Why an experiment cannot run: the errors of the HAMR experiments and of the leg they
//! drive, each naming the file, key, model or part of the experiment it concerns.
//!
//! Consumes: the typed errors of the layers below ([`session::Error`], [`RuntimeError`],
//! [`PlotError`], [`RefineError`]). Produces: [`Error`], whose `Display` is the message users read.

use std::fmt;
use std::path::PathBuf;

use mech_runtime::RuntimeError;

use crate::frequency::RefineError;
use crate::render::plot::PlotError;
use crate::{quantity, session};

#[derive(Debug)]
pub enum Error {
    /// A file or folder could not be read (`what`: `experiment`, `the experiments folder`).
    Read {
        what: &'static str,
        path: PathBuf,
        message: String,
    },
    NoExperimentFiles {
        folder: PathBuf,
    },
    /// The file is not TOML of any experiment kind (the parser's message, with its line).
    Toml {
        message: String,
    },
    MissingKind,
    /// A key no kind has (`line` of the file, 1-based, where it is set).
    UnknownKey {
        key: String,
        line: usize,
    },
    /// A key whose value has the wrong type (a number where a quantity string is expected).
    MistypedKey {
        key: String,
        line: usize,
        /// The parser's message.
        message: String,
    },
    /// A key's value is unreadable or out of range (the message names the key).
    Key {
        message: String,
    },
    /// A quantity with units that does not parse, has the wrong dimension or sign.
    Quantity(quantity::Error),
    /// In the experiment file at `path`.
    InFile {
        path: PathBuf,
        error: Box<Error>,
    },
    /// In a named part of an experiment: `robot `HAMR-VI``, `channel `lift``, `lift drive`.
    In {
        part: String,
        error: Box<Error>,
    },
    /// The model could not be opened (`model` as the experiment names it).
    Model {
        model: PathBuf,
        error: Box<session::Error>,
    },
    /// Boxed, as in `Model`: a session error is large and these errors travel by value.
    Session(Box<session::Error>),
    /// A diagnosis of the paper's values (`table_diagnosis`) failed.
    Diagnosis(Box<crate::diagnose::Error>),
    /// The model lacks a port the HAMR experiments drive or read.
    NotHamr {
        model: String,
        missing: String,
    },
    NoParameter {
        model: String,
        name: String,
        /// What the experiment needs it for, if it says.
        purpose: Option<String>,
    },
    /// No static equilibrium (of `model`).
    Statics {
        model: String,
        error: RuntimeError,
    },
    Assembly(RuntimeError),
    Linearization(RuntimeError),
    /// The reduced mass matrix is not positive definite: no modes.
    NoModes,
    /// The linear model is singular at a frequency of the sweep.
    SingularResponse,
    /// A resonance could not be refined on the linear model's response.
    Refine(RefineError),
    Chirp(RuntimeError),
    /// A force/deflection test that cannot be set up or does not end.
    Test(&'static str),
    /// A sweep whose own design point is missing from its results.
    ChosenDesignMissing,
    Write {
        path: PathBuf,
        message: String,
    },
    Plot(PlotError),
    /// A tolerance study (`tolerance`) that cannot be read or run.
    Sweep(Box<crate::sweep::Error>),
    /// Its outcome could not be rendered.
    SweepRender(Box<crate::render::sweep::Error>),
    /// A walk could not be animated (`locomotion`).
    Animation(crate::animation::Error),
}

impl Error {
    /// This error, in the experiment file at `path`.
    pub fn in_file(self, path: &std::path::Path) -> Error {
        Error::InFile {
            path: path.to_path_buf(),
            error: Box::new(self),
        }
    }

    /// This error, in the named part of an experiment.
    pub fn within(self, part: impl Into<String>) -> Error {
        Error::In {
            part: part.into(),
            error: Box::new(self),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Read {
                what,
                path,
                message,
            } => write!(f, "cannot read {what} `{}`: {message}", path.display()),
            Error::NoExperimentFiles { folder } => {
                write!(f, "no `*.toml` experiment files in `{}`", folder.display())
            }
            Error::Toml { message } => f.write_str(message),
            Error::UnknownKey { key, line } => write!(
                f,
                "line {line}: unknown key `{key}`\n  hint: docs/experiments.md lists the keys of \
                 each kind"
            ),
            Error::MistypedKey { key, line, message } => mistyped_text(f, key, *line, message),
            Error::MissingKind => f.write_str(
                "missing key `kind`: expected one of \"trajectory\", \"force_deflection\", \
                 \"ratio_sweep\", \"compare\", \"bode\", \"table_diagnosis\", \"tolerance\", \
                 \"locomotion\"",
            ),
            Error::Key { message } => f.write_str(message),
            Error::Quantity(error) => write!(f, "{error}"),
            Error::InFile { path, error } => {
                write!(f, "experiment `{}`: {error}", path.display())
            }
            Error::In { part, error } => write!(f, "{part}: {error}"),
            Error::Model { model, error } => write!(f, "model `{}`: {error}", model.display()),
            Error::Session(error) => write!(f, "{error}"),
            Error::Diagnosis(error) => write!(f, "{error}"),
            Error::NotHamr { model, missing } => write!(f, "model `{model}` has no {missing}"),
            Error::NoParameter {
                model,
                name,
                purpose,
            } => {
                write!(f, "model `{model}` has no parameter `{name}`")?;
                match purpose {
                    Some(purpose) => write!(f, " ({purpose})"),
                    None => Ok(()),
                }
            }
            Error::Statics { model, error } => write!(f, "statics of `{model}`: {error}"),
            Error::Assembly(error) => write!(f, "{error}"),
            Error::Linearization(error) => write!(f, "linearization failed: {error}"),
            Error::NoModes => f.write_str("the reduced mass matrix is not positive definite"),
            Error::SingularResponse => {
                f.write_str("the linear model is singular at some frequency")
            }
            Error::Refine(error) => write!(f, "resonance refinement: {error}"),
            Error::Chirp(error) => write!(f, "chirp simulation failed: {error}"),
            Error::Test(message) => f.write_str(message),
            Error::ChosenDesignMissing => f.write_str("the chosen design is missing"),
            Error::Write { path, message } => {
                write!(f, "cannot write {}: {message}", path.display())
            }
            Error::Plot(error) => write!(f, "{error}"),
            Error::Sweep(error) => write!(f, "{error}"),
            Error::SweepRender(error) => write!(f, "{error}"),
            Error::Animation(error) => write!(f, "animation of the walk: {error}"),
        }
    }
}

impl std::error::Error for Error {}

impl From<session::Error> for Error {
    fn from(error: session::Error) -> Error {
        Error::Session(Box::new(error))
    }
}

impl From<quantity::Error> for Error {
    fn from(error: quantity::Error) -> Error {
        Error::Quantity(error)
    }
}

impl From<RefineError> for Error {
    fn from(error: RefineError) -> Error {
        Error::Refine(error)
    }
}

impl From<PlotError> for Error {
    fn from(error: PlotError) -> Error {
        Error::Plot(error)
    }
}

/// The key and line of the parser's "unknown field" `message` on `text`. The keys every kind
/// shares are flattened into the kind's (serde's `flatten`), which loses the parser's span
/// of the offending key, so its line is found by name: the first `key = …` line.
pub(crate) fn unknown_key(text: &str, message: &str) -> Option<(String, usize)> {
    let key = message.split("unknown field `").nth(1)?.split('`').next()?;
    let line = text.lines().position(|line| {
        line.trim_start()
            .strip_prefix(key)
            .is_some_and(|rest| rest.trim_start().starts_with('='))
    })?;
    Some((key.to_string(), line + 1))
}

/// The message of [`mistyped_key`]'s finding: line, key, the parser's reason and a hint.
pub(crate) fn mistyped_text(
    f: &mut fmt::Formatter<'_>,
    key: &str,
    line: usize,
    message: &str,
) -> fmt::Result {
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
pub(crate) fn mistyped_key(text: &str, message: &str) -> Option<(String, usize)> {
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
