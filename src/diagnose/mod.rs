//! Foundations of `mech diagnose` and `mech fit` (design notes §7: measured data → cause →
//! extension → gain). Each part is plain data in, plain data out:
//!
//! - [`data`]: a measured-data CSV file (columns `name [unit]`) → columns in SI units, each
//!   with its physical dimension, or every problem of the file with its line and column;
//! - [`lm`]: residual function + parameters (bounds, scales) → Levenberg–Marquardt fit with
//!   covariance, standard errors, identifiability flags, and information criteria (AIC, AICc,
//!   BIC) for comparing model forms;
//! - [`experiment`]: a diagnosis experiment file + data → the measured values and, for any
//!   parameter values, the model's prediction of them;
//! - [`fit`]: experiment + data + parameters to fit → fitted values, standard errors and the
//!   residual before and after (`mech fit`, the command in `cli/fit.rs`);
//! - [`pendulum`]: the flexure pendulum's ring-down (`kind = "pendulum"`) and the screening
//!   of a decay trace for what no parameter can fit (amplitude-dependent damping, a
//!   drifting baseline), reported as flags;
//! - [`features`]: a response (data or prediction) → what a designer reads off it (resonance
//!   frequency, quality factor, blocked force, …) and the residual RMS per series;
//! - [`candidates`]: experiment + data + hold-out rule → every catalog candidate fitted and
//!   ranked on held-out data, and a verdict (`mech diagnose`);
//! - [`separate`]: causes the data support equally → the standard test that would tell them
//!   apart;
//! - [`error`]: what can go wrong in all of these, as [`Error`] (with a message for users).
//!
//! The file format and the fitting method are documented in `docs/diagnose.md`.

pub mod candidates;
pub mod data;
pub mod error;
pub mod experiment;
pub mod extend;
pub mod features;
pub mod fit;
pub mod lm;
pub mod observations;
pub mod pendulum;
pub mod separate;

pub use data::{Column, DataError, DataErrors, MeasuredData};
pub use error::{Error, KeyError};
pub use lm::{
    information_criteria, levenberg_marquardt, Difference, FitResult, InformationCriteria, LmError,
    LmOptions, NoiseModel, Parameter, ParameterStatus, StopReason,
};
