//! What can go wrong in the flexure characterization, from reading the command line's DATA
//! arguments to writing the tables and plots.
//!
//! Consumes: the facts of each failure (the file, the key, the value, what was expected).
//! Produces: [`Error`] and [`SpecimenError`], whose `Display` is the one-line message shown
//! to the user; every message names the file it is about.
//!
//! Errors of other layers (I/O, TOML, CSV, plots, the unit parser) are kept as their message
//! text, as in [`crate::diagnose::DataError`], so that these errors stay `Clone` and
//! `PartialEq` and tests can compare them.

use std::fmt;
use std::path::PathBuf;

use super::trace::TraceError;

/// Why the flexure characterization cannot go on.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// A specimen file cannot be read.
    ReadSpecimen {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        message: String,
    },
    /// A specimen file is read but its content is wrong.
    Specimen {
        /// The file.
        path: PathBuf,
        /// What is wrong in it.
        error: SpecimenError,
    },
    /// A directory named on the command line cannot be listed.
    ReadDirectory {
        /// The directory.
        path: PathBuf,
        /// The operating system's reason.
        message: String,
    },
    /// A directory named on the command line holds no `.toml` file.
    NoSpecimenFiles {
        /// The directory.
        path: PathBuf,
    },
    /// A command-line argument is neither a `.toml` file nor a directory.
    NotSpecimenFile {
        /// The argument.
        path: PathBuf,
    },
    /// A trace CSV file cannot be read or is not a numeric table.
    ReadTrace {
        /// The trace file.
        path: PathBuf,
        /// The CSV reader's message, which names the file (and line and column).
        message: String,
    },
    /// The specimen's `angle_column` is not a column of the trace.
    MissingAngleColumn {
        /// The trace file.
        path: PathBuf,
        /// The column asked for.
        column: String,
        /// The trace's columns.
        columns: Vec<String>,
    },
    /// The trace has a single column, so no angle next to the time.
    NoAngleColumn {
        /// The trace file.
        path: PathBuf,
    },
    /// The trace is read but cannot be analysed.
    Trace {
        /// The trace file.
        path: PathBuf,
        /// What is wrong with the trace.
        error: TraceError,
    },
    /// A CSV output file cannot be encoded.
    EncodeCsv {
        /// The output file.
        path: PathBuf,
        /// The CSV writer's reason.
        message: String,
    },
    /// An output file cannot be written.
    Write {
        /// The output file.
        path: PathBuf,
        /// The reason, which names the file.
        message: String,
    },
    /// A plot cannot be made.
    Plot {
        /// The plot file.
        path: PathBuf,
        /// The plotter's reason, which names the file.
        message: String,
    },
}

/// What is wrong inside a specimen file; the key it is about is part of each variant.
#[derive(Debug, Clone, PartialEq)]
pub enum SpecimenError {
    /// Not valid TOML, or a key unknown, missing or of the wrong type.
    Toml {
        /// The TOML parser's message (with the line and a snippet).
        message: String,
    },
    /// A quantity with a wrong unit or that cannot be parsed (the error names the key, e.g.
    /// `pendulum.mass`).
    Quantity(crate::quantity::Error),
    /// A quantity that is zero, negative or not finite.
    NotPositive {
        /// The key.
        key: &'static str,
        /// Its value in SI.
        value: f64,
    },
    /// `flexure.kind` is none of the known kinds.
    UnknownKind {
        /// The kind as written (lower case).
        kind: String,
    },
    /// `pendulum.inertia` is less than `m L_cm²`, so not about the pivot.
    InertiaBelowPointMass {
        /// I_p (kg·m²).
        inertia: f64,
        /// m L_cm² (kg·m²).
        point_mass_inertia: f64,
    },
    /// `angle_unit` is neither `rad` nor `deg`.
    UnknownAngleUnit {
        /// The unit as written.
        unit: String,
    },
    /// `traces` lists no file.
    NoTraces,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::ReadSpecimen { path, message } => {
                write!(f, "cannot read `{}`: {message}", path.display())
            }
            Error::Specimen { path, error } => write!(f, "`{}`: {error}", path.display()),
            Error::ReadDirectory { path, message } => {
                write!(f, "cannot read directory `{}`: {message}", path.display())
            }
            Error::NoSpecimenFiles { path } => write!(
                f,
                "directory `{}` contains no `.toml` specimen files",
                path.display()
            ),
            Error::NotSpecimenFile { path } => write!(
                f,
                "`{}`: expected a `.toml` specimen file (naming its CSV traces) or a directory \
                 of them; see docs/flexure-and-actuator.md",
                path.display()
            ),
            Error::MissingAngleColumn {
                path,
                column,
                columns,
            } => write!(
                f,
                "`{}` has no column `{column}`; its columns are {}",
                path.display(),
                columns.join(", ")
            ),
            Error::NoAngleColumn { path } => write!(
                f,
                "`{}` needs two columns, time [s] and angle",
                path.display()
            ),
            Error::Trace { path, error } => write!(f, "`{}`: {error}", path.display()),
            Error::EncodeCsv { path, message } => {
                write!(f, "cannot write `{}`: {message}", path.display())
            }
            // These messages come from layers that already name the file.
            Error::ReadTrace { message, .. }
            | Error::Write { message, .. }
            | Error::Plot { message, .. } => f.write_str(message),
        }
    }
}

impl fmt::Display for SpecimenError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SpecimenError::Toml { message } => f.write_str(message),
            SpecimenError::Quantity(error) => write!(f, "{error}"),
            SpecimenError::NotPositive { key, value } => {
                write!(f, "{key} must be positive, got {value}")
            }
            SpecimenError::UnknownKind { kind } => write!(
                f,
                "flexure.kind `{kind}`: expected `uncastellated` or `castellated`"
            ),
            SpecimenError::InertiaBelowPointMass {
                inertia,
                point_mass_inertia,
            } => write!(
                f,
                "pendulum.inertia {inertia:e} kg·m² is less than m·L_cm² = \
                 {point_mass_inertia:e} kg·m²: I_p must be the inertia about the pivot, not \
                 about the centre of mass"
            ),
            SpecimenError::UnknownAngleUnit { unit } => {
                write!(f, "angle_unit `{unit}`: expected `rad` or `deg`")
            }
            SpecimenError::NoTraces => f.write_str("`traces` is empty: list at least one CSV file"),
        }
    }
}

// The messages above already include the underlying error's text, so `source` stays `None`:
// a reporter walking the chain would otherwise print it twice.
impl std::error::Error for Error {}
impl std::error::Error for SpecimenError {}
