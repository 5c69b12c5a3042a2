//! What a command reports when it fails: the typed error of the layer that failed, or a
//! command-line value that cannot be used.
//!
//! Consumes: the errors of the library's layers. Produces: [`Error`], printed by
//! [`super::main`] on stderr (exit code 1).

use std::fmt;
use std::path::{Path, PathBuf};

use mech_runtime::RuntimeError;

use crate::diagnose::DataErrors;
use crate::render::PlotError;
use crate::{diagnose, experiments, flexure_fit, physics, quantity, render, session};

#[derive(Debug)]
pub enum Error {
    /// A command-line value that cannot be used; the message names the option and the
    /// expected form.
    Usage(String),
    Compile(mech_codegen::Errors),
    Session(session::Error),
    Experiments(experiments::Error),
    FlexureFit(flexure_fit::Error),
    Physics(physics::Invalid),
    Quantity(quantity::Error),
    /// Measured data that cannot be read (every problem of the file).
    Data(DataErrors),
    /// Boxed: the diagnosis error is large and commands return errors often by value.
    Diagnose(Box<diagnose::Error>),
    /// A fit to the data in `data` failed.
    Fit {
        data: PathBuf,
        error: Box<diagnose::Error>,
    },
    /// A JSON summary could not be encoded.
    Json(serde_json::Error),
    Render(render::Error),
    Plot(PlotError),
    Simulation {
        model: String,
        error: RuntimeError,
    },
    Chirp(RuntimeError),
    /// The reduced mass matrix is not positive definite: no modes.
    NoModes,
    /// The linear model is singular at a frequency of the sweep.
    SingularResponse,
    /// A file written atomically could not be (the message names the file).
    Io(std::io::Error),
    /// An output file or folder could not be written.
    Write {
        path: PathBuf,
        message: String,
    },
}

impl Error {
    /// A failed write of `path`.
    pub fn write(path: impl AsRef<Path>, error: impl fmt::Display) -> Error {
        Error::Write {
            path: path.as_ref().to_path_buf(),
            message: error.to_string(),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Usage(message) => f.write_str(message),
            Error::Data(errors) => write!(f, "{errors}"),
            Error::Diagnose(error) => write!(f, "{error}"),
            Error::Fit { data, error } => write!(f, "fit to `{}`: {error}", data.display()),
            Error::Io(error) => write!(f, "{error}"),
            Error::Json(error) => write!(f, "cannot encode the JSON summary: {error}"),
            Error::Compile(errors) => write!(f, "{errors}"),
            Error::Session(error) => write!(f, "{error}"),
            Error::Experiments(error) => write!(f, "{error}"),
            Error::FlexureFit(error) => write!(f, "{error}"),
            Error::Physics(error) => write!(f, "{error}"),
            Error::Quantity(error) => write!(f, "{error}"),
            Error::Render(error) => write!(f, "{error}"),
            Error::Plot(error) => write!(f, "cannot plot: {error}"),
            Error::Simulation { model, error } => {
                write!(f, "simulation of `{model}` failed: {error}")
            }
            Error::Chirp(error) => write!(f, "chirp simulation failed: {error}"),
            Error::NoModes => f.write_str("the reduced mass matrix is not positive definite"),
            Error::SingularResponse => {
                f.write_str("the linear model is singular at some frequency")
            }
            Error::Write { path, message } => {
                write!(f, "cannot write {}: {message}", path.display())
            }
        }
    }
}

impl std::error::Error for Error {}

macro_rules! from_layer {
    ($($variant:ident($error:ty)),* $(,)?) => {
        $(
            impl From<$error> for Error {
                fn from(error: $error) -> Error {
                    Error::$variant(error)
                }
            }
        )*
    };
}

from_layer!(
    Compile(mech_codegen::Errors),
    Session(session::Error),
    Experiments(experiments::Error),
    FlexureFit(flexure_fit::Error),
    Physics(physics::Invalid),
    Quantity(quantity::Error),
    Render(render::Error),
    Plot(PlotError),
    Json(serde_json::Error),
    Io(std::io::Error),
    Data(DataErrors),
);

impl From<diagnose::Error> for Error {
    fn from(error: diagnose::Error) -> Error {
        Error::Diagnose(Box::new(error))
    }
}
