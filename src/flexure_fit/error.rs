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

use mech_codegen::ir::Dimension;

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
    /// A time or angle that is NaN or infinite (the CSV reader accepts `nan` and `inf` as
    /// numbers; a trace cannot use them).
    NotFinite {
        /// The trace file.
        path: PathBuf,
        /// File line of the first such value (1-based, comments counted).
        line: u64,
        /// Column (1-based) and its name.
        column: usize,
        name: String,
        /// The value read.
        value: f64,
        /// How many values of that column are not finite.
        count: usize,
    },
    /// The time does not increase strictly from one data row to the next.
    TimeNotIncreasing {
        /// The trace file.
        path: PathBuf,
        /// File line of the offending row.
        line: u64,
        /// Column (1-based) and name of the time.
        column: usize,
        name: String,
        /// The time on the row before and on this row (s).
        previous: f64,
        time: f64,
    },
    /// The trace's amplitude is implausible for the rig in the declared angle unit; most
    /// often angles in degrees read as radians.
    /// A unit in a trace's header that is unknown, of the wrong dimension, or in conflict
    /// with the specimen's `angle_unit`.
    TraceUnit {
        path: PathBuf,
        /// Column (1-based) and header.
        column: usize,
        name: String,
        message: String,
    },
    AngleAmplitude {
        /// The trace file.
        path: PathBuf,
        /// Column (1-based) and name of the angle.
        column: usize,
        name: String,
        /// The amplitude as written in the file ([`super::trace::robust_amplitude`]).
        amplitude: f64,
        /// The declared `angle_unit`, `rad` or `deg`.
        unit: &'static str,
        /// The specimen file that declares it.
        specimen: PathBuf,
        /// The largest amplitude (rad) the analysis accepts.
        limit: f64,
    },
    /// The measured stiffness k_m (Eq. 4) is zero or negative: the pendulum swings slower than
    /// its gravity stiffness alone would make it.
    NonPositiveStiffness {
        /// The trace file.
        path: PathBuf,
        /// `I_p ω_n²` (N·m/rad).
        total: f64,
        /// The gravity term subtracted, `m g L_cm ⟨2J₁(A)/A⟩` (N·m/rad).
        gravity: f64,
    },
    /// The uncastellated fit's Young's modulus is not positive, or wildly outside the range of
    /// the film (by default a factor 10 either side of Kapton's 2.56 GPa).
    ImplausibleModulus {
        /// The fitted modulus (Pa).
        modulus: f64,
        /// The plausible range (Pa).
        range: (f64, f64),
        /// The specimens of the fit.
        specimens: Vec<String>,
    },
    /// Some traces or specimen files of a data set were rejected; the fits use the others.
    Rejected {
        /// Every problem found, each naming its file.
        problems: Vec<Error>,
        /// Traces analysed (accepted and rejected).
        traces: usize,
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
    /// A plain number (SI) far too large for the rig: meant in another unit.
    PlainNumberTooLarge {
        key: &'static str,
        value: f64,
        unit: Dimension,
    },
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
            Error::NotFinite {
                path,
                line,
                column,
                name,
                value,
                count,
            } => {
                write!(
                    f,
                    "`{}`, line {line}, column {column} (`{name}`): `{value}` is not a finite \
                     number",
                    path.display()
                )?;
                if *count > 1 {
                    write!(f, " ({count} such values in the column, the first shown)")?;
                }
                f.write_str("; remove or fill the row (a dropped camera frame?)")
            }
            Error::TimeNotIncreasing {
                path,
                line,
                column,
                name,
                previous,
                time,
            } => write!(
                f,
                "`{}`, line {line}, column {column} (`{name}`): time {time} s does not increase \
                 (previous row {previous} s): times must be strictly increasing",
                path.display()
            ),
            Error::TraceUnit {
                path,
                column,
                name,
                message,
            } => write!(
                f,
                "`{}`, column {column} (`{name}`): {message}",
                path.display()
            ),
            Error::AngleAmplitude {
                path,
                column,
                name,
                amplitude,
                unit,
                specimen,
                limit,
            } => {
                let head = format!("`{}`, column {column} (`{name}`)", path.display());
                let plausible_in_degrees = amplitude.to_radians() <= *limit;
                let limit = limit.to_degrees();
                if *unit == "rad" && plausible_in_degrees {
                    write!(
                        f,
                        "{head}: the angles look like degrees: amplitude {amplitude:.4} read as \
                         rad is {:.0}°, beyond the {limit:.0}° the analysis accepts (the rig \
                         swings 5–15°), but {amplitude:.4}° is plausible; set \
                         `angle_unit = \"deg\"` in `{}`",
                        amplitude.to_degrees(),
                        specimen.display()
                    )
                } else {
                    let degrees = if *unit == "deg" {
                        *amplitude
                    } else {
                        amplitude.to_degrees()
                    };
                    write!(
                        f,
                        "{head}: amplitude {amplitude:.4} {unit} ({degrees:.0}°) is beyond the \
                         {limit:.0}° the analysis accepts (the rig swings 5–15°): is the angle \
                         measured from the vertical (the rest position), and is `angle_unit` \
                         in `{}` right?",
                        specimen.display()
                    )
                }
            }
            Error::NonPositiveStiffness {
                path,
                total,
                gravity,
            } => write!(
                f,
                "`{}`: measured stiffness k_m = I_p ω_n² − m g L_cm = {total:.4e} − {gravity:.4e} \
                 = {:.4e} N·m/rad is not positive (Eq. 4): the pendulum swings slower than \
                 gravity alone would make it; check pendulum.inertia (about the pivot), \
                 pendulum.mass and pendulum.com_distance, and the angle unit",
                path.display(),
                total - gravity
            ),
            Error::ImplausibleModulus {
                modulus,
                range,
                specimens,
            } => write!(
                f,
                "the uncastellated fit gives Young's modulus E = {:.4} GPa, outside the \
                 plausible {:.3}–{:.3} GPa (Kapton: 2.56 GPa), so it is not reported; specimens \
                 {}: check flexure.thickness (it enters cubed), flexure.length and \
                 flexure.width, and the pendulum; for another film set --modulus-range",
                modulus * 1e-9,
                range.0 * 1e-9,
                range.1 * 1e-9,
                specimens.join(", ")
            ),
            Error::Rejected { problems, traces } => {
                let rejected_traces = problems.iter().filter(|p| p.is_trace_problem()).count();
                write!(
                    f,
                    "{} problem{} in the data set ({rejected_traces} of {traces} traces \
                     rejected; the fits above use the others):",
                    problems.len(),
                    if problems.len() == 1 { "" } else { "s" }
                )?;
                for problem in problems {
                    write!(f, "\n  - {problem}")?;
                }
                Ok(())
            }
            Error::Trace { path, error } => write!(f, "`{}`: {error}", path.display()),
            Error::EncodeCsv { path, message } => {
                write!(f, "cannot write `{}`: {message}", path.display())
            }
            // These messages come from layers that already name the file.
            Error::ReadTrace { message, .. } | Error::Plot { message, .. } => f.write_str(message),
        }
    }
}

impl Error {
    /// Whether this problem rejects one trace (rather than a specimen file, or a fit across
    /// specimens).
    pub fn is_trace_problem(&self) -> bool {
        matches!(
            self,
            Error::ReadTrace { .. }
                | Error::MissingAngleColumn { .. }
                | Error::NoAngleColumn { .. }
                | Error::NotFinite { .. }
                | Error::TimeNotIncreasing { .. }
                | Error::AngleAmplitude { .. }
                | Error::NonPositiveStiffness { .. }
                | Error::Trace { .. }
        )
    }
}

impl fmt::Display for SpecimenError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SpecimenError::Toml { message } => f.write_str(message),
            SpecimenError::Quantity(error) => write!(f, "{error}"),
            SpecimenError::PlainNumberTooLarge { key, value, unit } => {
                let short = key.rsplit('.').next().unwrap_or(key);
                let example = match *unit {
                    Dimension::MASS => "g",
                    Dimension::LENGTH => "mm",
                    _ => "g*mm^2",
                };
                write!(
                    f,
                    "{key} = {value} is {value} {unit} (plain numbers are SI), too large for a \
                     flexure rig; give the unit, e.g. `{short} = \"{value} {example}\"`"
                )
            }
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
