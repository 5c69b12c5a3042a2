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

/// A failed command. The layers' errors display as they are (their messages name the file,
/// option or key); the variants with fields add what the command was doing.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A command-line value that cannot be used; the message names the option and the
    /// expected form.
    #[error("{0}")]
    Usage(String),
    #[error(transparent)]
    Compile(#[from] mech_codegen::Errors),
    /// `mech import urdf --length/--mass/--time` with a unit of another quantity.
    #[error("{0}")]
    ImportUnits(#[from] mech_codegen::urdf::UnitError),
    #[error(transparent)]
    Session(#[from] session::Error),
    /// `derive --emit equations` of a model too large to print as trees.
    #[error(transparent)]
    Equations(#[from] crate::describe::TooLarge),
    #[error(transparent)]
    Experiments(#[from] experiments::Error),
    /// The model of `mech fit`, opened as a leg.
    #[error(transparent)]
    Leg(#[from] experiments::leg::Error),
    #[error(transparent)]
    Sweep(#[from] crate::sweep::Error),
    #[error(transparent)]
    SweepRender(#[from] render::sweep::Error),
    #[error(transparent)]
    FlexureFit(#[from] flexure_fit::Error),
    #[error(transparent)]
    Physics(#[from] physics::Invalid),
    #[error(transparent)]
    Quantity(#[from] quantity::Error),
    /// Measured data that cannot be read (every problem of the file).
    #[error(transparent)]
    Data(#[from] DataErrors),
    /// Boxed: the diagnosis error is large and commands return errors often by value.
    #[error(transparent)]
    Diagnose(Box<diagnose::Error>),
    /// A fit to the data in `data` failed.
    #[error("fit to `{}`: {error}", data.display())]
    Fit {
        data: PathBuf,
        error: Box<diagnose::Error>,
    },
    /// A JSON summary could not be encoded.
    #[error("cannot encode the JSON summary: {0}")]
    Json(#[from] serde_json::Error),
    #[error(transparent)]
    Render(#[from] render::Error),
    #[error("cannot plot: {0}")]
    Plot(#[from] PlotError),
    #[error("chirp simulation failed: {0}")]
    Chirp(RuntimeError),
    /// The reduced mass matrix is not positive definite: no modes.
    #[error("the reduced mass matrix is not positive definite")]
    NoModes,
    /// The linear model is singular at a frequency of the sweep.
    #[error("the linear model is singular at some frequency")]
    SingularResponse,
    /// A resonance could not be refined on the linear model's response.
    #[error("resonance refinement: {0}")]
    Refine(#[from] crate::frequency::RefineError),
    /// A CSV file named on the command line cannot be read (the message names it).
    #[error(transparent)]
    Csv(#[from] crate::output::CsvError),
    #[error(transparent)]
    Animation(#[from] crate::animation::Error),
    /// A file could not be rendered (the message names the file).
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// The run's files were not written (the message names the file).
    #[error(transparent)]
    Output(#[from] crate::output::WriteError),
    /// An output file or folder could not be written.
    #[error("cannot write {}: {message}", path.display())]
    Write { path: PathBuf, message: String },
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

impl From<diagnose::Error> for Error {
    fn from(error: diagnose::Error) -> Error {
        Error::Diagnose(Box::new(error))
    }
}
