//! Why an experiment cannot run: the errors of the HAMR experiments, each naming the file,
//! key, model or part of the experiment it concerns.
//!
//! Consumes: the typed errors of the layers below ([`leg::Error`] of the leg they drive,
//! [`session::Error`], [`RuntimeError`], [`PlotError`], [`RefineError`], [`TomlError`], and
//! those of the diagnosis and the study that two kinds run). Produces: [`Error`], whose
//! `Display` is the message users read.

use std::fmt;
use std::path::PathBuf;

use mech_runtime::RuntimeError;

use super::leg;
use crate::frequency::RefineError;
use crate::render::plot::PlotError;
use crate::toml_file::TomlError;
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
    /// The file is not TOML of any experiment kind: a key no kind has, a mistyped value, …
    Toml(TomlError),
    MissingKind,
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
    /// Boxed: a session error is large and these errors travel by value.
    Session(Box<session::Error>),
    /// The HAMR leg the experiment drives: its model, ports, equilibria and tests.
    Leg(leg::Error),
    /// A diagnosis of the paper's values (`table_diagnosis`) failed.
    Diagnosis(Box<crate::diagnose::Error>),
    /// The linear model is singular at a frequency of the sweep.
    SingularResponse,
    /// A resonance could not be refined on the linear model's response.
    Refine(RefineError),
    Chirp(RuntimeError),
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
            Error::Toml(error) => write!(f, "{error}"),
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
            Error::Session(error) => write!(f, "{error}"),
            Error::Leg(error) => write!(f, "{error}"),
            Error::Diagnosis(error) => write!(f, "{error}"),
            Error::SingularResponse => {
                f.write_str("the linear model is singular at some frequency")
            }
            Error::Refine(error) => write!(f, "resonance refinement: {error}"),
            Error::Chirp(error) => write!(f, "chirp simulation failed: {error}"),
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

impl From<leg::Error> for Error {
    fn from(error: leg::Error) -> Error {
        Error::Leg(error)
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
