//! Why a leg cannot be opened or driven: its model, its HAMR ports and parameters, its
//! equilibria, linearization and force/deflection test.
//!
//! Consumes: [`session::Error`] and [`RuntimeError`]. Produces: [`Error`], which the layers
//! above the leg (the experiments, `diagnose`, `sweep`) wrap; its `Display` is the message
//! users read.

use std::fmt;
use std::path::PathBuf;

use mech_runtime::RuntimeError;

use crate::session;

#[derive(Debug)]
pub enum Error {
    /// The model could not be opened (`model` as the experiment names it).
    Model {
        model: PathBuf,
        error: Box<session::Error>,
    },
    /// Boxed, as in `Model`: a session error is large and these errors travel by value.
    Session(Box<session::Error>),
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
    /// A force/deflection test that cannot be set up or does not end.
    Test(&'static str),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Model { model, error } => write!(f, "model `{}`: {error}", model.display()),
            Error::Session(error) => write!(f, "{error}"),
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
            Error::Test(message) => f.write_str(message),
        }
    }
}

impl std::error::Error for Error {}

impl From<session::Error> for Error {
    fn from(error: session::Error) -> Error {
        Error::Session(Box::new(error))
    }
}
