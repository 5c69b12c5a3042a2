//! What can go wrong in `mech fit` and `mech diagnose`: the experiment file, the command-line
//! requests (`--fit`, `--holdout`, `--cause`), the measured data against the experiment, the
//! model (opened, extended, solved) and the fits.
//!
//! Consumes: the facts of each failure (the file, the key, the data line and column, the
//! value as written, the expected dimension, the error of the layer below). Produces:
//! [`Error`] and [`KeyError`] (a key of an experiment file), whose `Display` is the one-line
//! message shown to the user.
//!
//! Typed errors of lower layers are kept as they are ([`session::Error`], [`DataError`],
//! [`LmError`], [`TransformError`], [`RuntimeError`], codegen's [`Errors`], the HAMR leg's
//! [`leg::Error`], codegen's [`QuantityError`]).

use std::fmt;
use std::path::PathBuf;

use mech_codegen::front::units::QuantityError;
use mech_codegen::ir::transform::TransformError;
use mech_codegen::ir::Dimension;
use mech_codegen::Errors;
use mech_runtime::RuntimeError;

use super::data::DataError;
use super::lm::LmError;
use crate::experiments::leg;
use crate::session;
use crate::toml_file::TomlError;

/// Why `mech fit` or `mech diagnose` cannot go on.
#[derive(Debug)]
pub enum Error {
    /// The experiment file cannot be read.
    ReadExperiment {
        path: PathBuf,
        error: std::io::Error,
    },
    /// The experiment file is not valid TOML, or a key is unknown, missing or of the wrong
    /// type.
    ExperimentToml { path: PathBuf, error: TomlError },
    /// A key of the experiment file has a value that cannot be used.
    Experiment { path: PathBuf, error: KeyError },
    /// A key of the experiment does not match the model it names (found once the model is
    /// open), or a value checked at load time is used again.
    Key(KeyError),
    /// A column of the measured data is missing, has the wrong unit or is out of order.
    Data(DataError),
    /// The measured angle's column has a unit that is no angle.
    NotAngleUnit {
        /// The data file.
        path: PathBuf,
        /// 1-based column index.
        index: usize,
        column: String,
        /// The unit as written (empty: none).
        unit_text: String,
    },
    /// A ring-down with fewer than two samples.
    TooFewSamples { path: PathBuf },
    /// A measured gain that is zero or negative (it is a magnitude).
    GainNotPositive { path: PathBuf, line: usize },
    /// A negative sensor distance of a force/deflection test.
    NegativeDistance { path: PathBuf, line: usize },
    /// A force/deflection table whose data rows are not one per `[[test]]`.
    TableRows {
        path: PathBuf,
        rows: usize,
        tests: usize,
    },
    /// A standard deviation (`…_sd` column) that is zero or negative.
    SpreadNotPositive {
        path: PathBuf,
        line: usize,
        column: &'static str,
    },
    /// `--fit TEXT` is neither `NAME` nor `NAME=LO..HI UNIT`.
    FitSyntax { text: String },
    /// A bound of `--fit TEXT` is no quantity; `message` is the unit parser's.
    FitBound {
        text: String,
        message: QuantityError,
    },
    /// The bounds of `--fit TEXT` are not in increasing order (or NaN).
    FitBoundsOrder { text: String },
    /// `--fit NAME` names no parameter of the model.
    UnknownParameter {
        name: String,
        model: String,
        /// The model's parameters.
        known: Vec<String>,
    },
    /// The bounds of `--fit NAME=LO..HI UNIT` have another dimension than the parameter.
    BoundUnit {
        name: String,
        found: Dimension,
        expected: Dimension,
    },
    /// `--holdout TEXT` is neither `every:N` nor `last:P%`.
    HoldoutSyntax { text: String },
    /// The hold-out rule leaves fewer than two values to fit or to test.
    HoldoutTooSmall { train: usize, holdout: usize },
    /// `mech diagnose` on an experiment without measurement noise.
    NoNoise,
    /// `--cause TEXT` matches no cause of the catalog for this experiment.
    UnknownCause {
        cause: String,
        /// The catalog's causes.
        catalog: Vec<String>,
    },
    /// The base model's trial failed, so nothing can be compared with it.
    BaseModel(Box<Error>),
    /// No assignment of twist axes to a loop's hinges gave a prediction.
    NoTwistAxes { hinges: String },
    /// The model file does not compile.
    Compile { model: PathBuf, errors: Errors },
    /// A model-form extension cannot be applied to the model.
    Transform {
        model: PathBuf,
        error: TransformError,
    },
    /// The extended model cannot be set up (`--set`, assembly).
    ExtendedSession {
        model: PathBuf,
        /// Where the extension acts (the extension's `location`).
        location: String,
        error: Box<session::Error>,
    },
    /// No static equilibrium for the drive of one data row.
    Equilibrium { line: usize, error: Box<leg::Error> },
    /// The model cannot be linearized about its rest equilibrium.
    Linearization(RuntimeError),
    /// The linear model has no frequency response at this frequency (Hz).
    Singular { frequency: f64 },
    /// The ring-down simulation of a pendulum failed.
    RingDown { model: String, error: RuntimeError },
    /// Levenberg–Marquardt could not fit (whose residuals may have failed with an [`Error`]).
    Fit(Box<LmError<Error>>),
    /// The HAMR leg (`experiments/leg/`): opening it, its ports, its equilibria.
    Leg(Box<leg::Error>),
}

/// What is wrong with a key of an experiment file; the key is part of each message.
#[derive(Debug)]
pub enum KeyError {
    /// `outputs` is empty.
    NoOutputs,
    /// `noise` has neither one value per output nor none.
    NoiseCount { values: usize, outputs: usize },
    /// A noise `NUMBER %` whose number does not parse.
    NotPercentage { key: &'static str, text: String },
    /// A noise that is zero, negative or not finite.
    NoiseNotPositive { key: &'static str, text: String },
    /// A noise whose unit is not that of what it is the noise of (`0.05 mm` for an angle).
    NoiseUnit {
        key: &'static str,
        text: String,
        found: Dimension,
        expected: Dimension,
    },
    /// A quantity the unit parser rejects; `message` is the parser's.
    Quantity {
        key: &'static str,
        text: String,
        message: QuantityError,
    },
    /// A quantity of another dimension than a voltage.
    NotVoltage { key: &'static str, text: String },
    /// A quantity of another dimension than an angle.
    NotAngle { key: &'static str, text: String },
    /// A frequency response with both or half of the forms `input`/`output` and `[[channel]]`.
    ChannelForms,
    /// A frequency response with neither `input`/`output` nor `[[channel]]`.
    NoChannels,
    /// `off_axis_fraction` outside [-1, 1].
    OffAxisFraction { value: f64 },
    /// A force/deflection table without `[[test]]` tables.
    NoTests,
    /// A `[[test]]`'s `direction` that is not `±z` (lift) or `±x` (swing); `index` 1-based.
    TestDirection {
        index: usize,
        dof: &'static str,
        text: String,
    },
    /// A name of `outputs` that is no output of the model.
    UnknownOutput { name: String },
    /// A transfer function's input or output that the model does not have.
    UnknownChannelPort {
        /// The `[[channel]]`'s name; `None` for the single-channel keys `input`/`output`.
        channel: Option<String>,
        /// `input` or `output`.
        port: &'static str,
        name: String,
    },
    /// `angle` is no output or coordinate of the model.
    UnknownAngle { angle: String, outputs: Vec<String> },
    /// `coordinate` is no coordinate of the model.
    UnknownCoordinate(Box<session::Error>),
    /// No `coordinate` given and the model has several degrees of freedom.
    CoordinateAmbiguous { model: String, dofs: usize },
    /// `coordinate` is not an independent coordinate of the assembly.
    CoordinateNotIndependent { coordinate: String },
}

impl Error {
    /// An error of the HAMR leg.
    pub fn leg(error: leg::Error) -> Error {
        Error::Leg(Box::new(error))
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::ReadExperiment { path, error } => {
                write!(f, "cannot read experiment `{}`: {error}", path.display())
            }
            // `experiment `…`, line 4: unknown key …`: the line belongs to the file.
            Error::ExperimentToml {
                path,
                error: error @ TomlError::UnknownKey { .. },
            } => write!(f, "experiment `{}`, {error}", path.display()),
            Error::ExperimentToml { path, error } => {
                write!(f, "experiment `{}`: {error}", path.display())
            }
            Error::Experiment { path, error } => {
                write!(f, "experiment `{}`: {error}", path.display())
            }
            Error::Key(error) => write!(f, "{error}"),
            Error::Data(error) => write!(f, "{error}"),
            Error::NotAngleUnit {
                path,
                index,
                column,
                unit_text,
            } => {
                write!(
                    f,
                    "`{}`, column {index} (`{column}`): expected an angle unit, `[deg]` or \
                     `[rad]`, found ",
                    path.display()
                )?;
                if unit_text.is_empty() {
                    f.write_str("no unit")
                } else {
                    write!(f, "`[{unit_text}]`")
                }
            }
            Error::TooFewSamples { path } => write!(
                f,
                "`{}`: a ring-down needs more than one sample",
                path.display()
            ),
            Error::GainNotPositive { path, line } => write!(
                f,
                "`{}`, line {line}: the gain must be positive (a magnitude)",
                path.display()
            ),
            Error::NegativeDistance { path, line } => write!(
                f,
                "`{}`, line {line}: the sensor distance must not be negative (it is measured \
                 from the foot's rest position along its free motion)",
                path.display()
            ),
            Error::TableRows { path, rows, tests } => write!(
                f,
                "`{}`: {rows} data rows, but the experiment lists {tests} `[[test]]` tables; \
                 give one row per test, in the same order",
                path.display()
            ),
            Error::SpreadNotPositive { path, line, column } => write!(
                f,
                "`{}`, line {line}, column `{column}`: a standard deviation must be positive \
                 (it weighs the value in the fit)",
                path.display()
            ),
            Error::FitSyntax { text } => write!(
                f,
                "--fit `{text}`: expected NAME or NAME=LO..HI UNIT, e.g. `k_s3=10..100 uN*m/rad`"
            ),
            Error::FitBound { text, message } => write!(f, "--fit `{text}`: {message}"),
            Error::FitBoundsOrder { text } => write!(
                f,
                "--fit `{text}`: the lower bound must be below the upper bound"
            ),
            Error::UnknownParameter { name, model, known } => write!(
                f,
                "--fit: unknown parameter `{name}`; parameters of `{model}`: {}",
                known.join(", ")
            ),
            Error::BoundUnit {
                name,
                found,
                expected,
            } => write!(
                f,
                "--fit {name}: the bounds have unit {found}, but `{name}` needs {expected}"
            ),
            Error::HoldoutSyntax { text } => write!(
                f,
                "--holdout `{text}`: expected `every:N` (N ≥ 2), `last:P%` (0 < P < 100) or \
                 `none`"
            ),
            Error::HoldoutTooSmall { train, holdout } => write!(
                f,
                "the hold-out rule leaves {train} values to fit and {holdout} to test; need at \
                 least 2 of each (or `--holdout none` for a few summary values)"
            ),
            Error::NoNoise => f.write_str(
                "`mech diagnose` needs the measurement noise in the experiment file (`noise`, \
                 or `gain_noise` and `phase_noise`): without it no residual can be called \
                 significant",
            ),
            Error::UnknownCause { cause, catalog } => write!(
                f,
                "--cause `{cause}`: no cause of the catalog for this experiment contains it \
                 (the catalog: {})",
                catalog.join(", ")
            ),
            Error::BaseModel(error) => write!(f, "the base model: {error}"),
            Error::NoTwistAxes { hinges } => write!(
                f,
                "no static equilibrium with flexures {hinges} twisting about any of their \
                 possible length axes"
            ),
            Error::Compile { model, errors } => write!(f, "model `{}`: {errors}", model.display()),
            Error::Transform { model, error } => {
                write!(f, "model `{}`: {error}", model.display())
            }
            Error::ExtendedSession {
                model,
                location,
                error,
            } => write!(
                f,
                "model `{}` extended ({location}): {error}",
                model.display()
            ),
            Error::Equilibrium { line, error } => write!(f, "line {line}: {error}"),
            Error::Linearization(error) => write!(f, "linearization failed: {error}"),
            Error::Singular { frequency } => {
                write!(f, "the linear model is singular at {frequency} Hz")
            }
            Error::RingDown { model, error } => write!(f, "ring-down of `{model}`: {error}"),
            Error::Fit(error) => write!(f, "{error}"),
            Error::Leg(error) => write!(f, "{error}"),
        }
    }
}

impl fmt::Display for KeyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            KeyError::NoOutputs => f.write_str("key `outputs`: name at least one measured output"),
            KeyError::NoiseCount { values, outputs } => write!(
                f,
                "key `noise`: {values} values for {outputs} outputs (give one per output, or \
                 none)"
            ),
            KeyError::NotPercentage { key, text } => {
                write!(f, "key `{key}`: `{text}` is not a percentage")
            }
            KeyError::NoiseNotPositive { key, text } => {
                write!(f, "key `{key}`: expected a positive noise, got `{text}`")
            }
            KeyError::NoiseUnit {
                key,
                text,
                found,
                expected,
            } => {
                write!(
                    f,
                    "key `{key}`: `{text}` has unit {found}, but this noise needs "
                )?;
                if *expected == Dimension::NONE {
                    write!(
                        f,
                        "an angle (`3 deg`), a plain number or a percentage (`5 %`)"
                    )
                } else {
                    write!(f, "{expected}")
                }
            }
            KeyError::Quantity { key, text, message } => {
                write!(f, "key `{key}`: `{text}`: {message}")
            }
            KeyError::NotVoltage { key, text } => {
                write!(f, "key `{key}`: `{text}` is not a voltage (e.g. \"225 V\")")
            }
            KeyError::NotAngle { key, text } => write!(
                f,
                "key `{key}`: expected an angle such as `10 deg`, got `{text}`"
            ),
            KeyError::ChannelForms => f.write_str(
                "give both `input` and `output` for one transfer function, or `[[channel]]` \
                 tables (name, input, output) for several, not both",
            ),
            KeyError::NoChannels => {
                f.write_str("missing `input` and `output` (or `[[channel]]` tables)")
            }
            KeyError::OffAxisFraction { value } => write!(
                f,
                "key `off_axis_fraction`: expected a fraction between -1 and 1, got {value}"
            ),
            KeyError::NoTests => f.write_str(
                "no `[[test]]` tables: list each force/deflection test (`dof`, optional \
                 `direction`), one per data row",
            ),
            KeyError::TestDirection { index, dof, text } => {
                let axis = if *dof == "lift" { 'z' } else { 'x' };
                write!(
                    f,
                    "key `test[{index}].direction`: expected `+{axis}` or `-{axis}` for {dof} \
                     (the way the foot moved along the test's axis), got `{text}`"
                )
            }
            KeyError::UnknownOutput { name } => {
                write!(f, "key `outputs`: the model has no output `{name}`")
            }
            KeyError::UnknownChannelPort {
                channel,
                port,
                name,
            } => match channel {
                Some(channel) => {
                    write!(f, "channel `{channel}`: the model has no {port} `{name}`")
                }
                None => write!(f, "key `{port}`: the model has no {port} `{name}`"),
            },
            KeyError::UnknownAngle { angle, outputs } => write!(
                f,
                "key `angle`: the model has no output or coordinate `{angle}`; its outputs: {}",
                outputs.join(", ")
            ),
            KeyError::UnknownCoordinate(error) => write!(f, "key `coordinate`: {error}"),
            KeyError::CoordinateAmbiguous { model, dofs } => write!(
                f,
                "key `coordinate`: model `{model}` has {dofs} degrees of freedom; name the \
                 released one"
            ),
            KeyError::CoordinateNotIndependent { coordinate } => write!(
                f,
                "key `coordinate`: `{coordinate}` is not an independent coordinate of the \
                 assembly; list it in `independent`"
            ),
        }
    }
}

// The messages above already include the underlying error's text, so `source` stays `None`:
// a reporter walking the chain would otherwise print it twice.
impl std::error::Error for Error {}
impl std::error::Error for KeyError {}

impl From<KeyError> for Error {
    fn from(error: KeyError) -> Error {
        Error::Key(error)
    }
}

impl From<DataError> for Error {
    fn from(error: DataError) -> Error {
        Error::Data(error)
    }
}

impl From<LmError<Error>> for Error {
    fn from(error: LmError<Error>) -> Error {
        Error::Fit(Box::new(error))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::candidates::{Holdout, Verdict};
    use crate::diagnose::lm::StopReason;
    use crate::diagnose::observations::noise_value;

    /// The messages users see name the key or option and the value as written.
    #[test]
    fn messages_name_the_key_and_the_value() {
        let message = |r: Result<f64, KeyError>| r.unwrap_err().to_string();
        assert_eq!(
            message(noise_value("gain_noise", "five %", Dimension::NONE)),
            "key `gain_noise`: `five %` is not a percentage"
        );
        assert_eq!(
            message(noise_value("noise", "-2 um", Dimension::LENGTH)),
            "key `noise`: expected a positive noise, got `-2 um`"
        );
        assert_eq!(
            Holdout::parse("every:1").unwrap_err().to_string(),
            "--holdout `every:1`: expected `every:N` (N ≥ 2), `last:P%` (0 < P < 100) or `none`"
        );
        let port = |channel: Option<&str>| KeyError::UnknownChannelPort {
            channel: channel.map(str::to_string),
            port: "input",
            name: "v_x".into(),
        };
        assert_eq!(
            port(None).to_string(),
            "key `input`: the model has no input `v_x`"
        );
        assert_eq!(
            port(Some("lift")).to_string(),
            "channel `lift`: the model has no input `v_x`"
        );
        let wrapped = Error::from(KeyError::NoOutputs).to_string();
        assert_eq!(wrapped, "key `outputs`: name at least one measured output");
    }

    /// A force/deflection table's keys: `--holdout none`, each test's direction, the tests.
    #[test]
    fn table_keys_are_checked_with_the_key_named() {
        assert_eq!(Holdout::parse("none").unwrap(), Holdout::Nothing);
        let parse = |text: &str| {
            crate::diagnose::experiment::parse(
                std::path::Path::new("t.toml"),
                &format!(
                    "kind = \"force_deflection_table\"\ntitle = \"t\"\nmodel = \"m.mech\"\n\
                     voltage = \"225 V\"\n{text}"
                ),
            )
            .map(|_| ())
            .map_err(|e| e.to_string())
        };
        assert_eq!(
            parse("[[test]]\ndof = \"lift\"\ndirection = \"-x\"\n"),
            Err(
                "experiment `t.toml`: key `test[1].direction`: expected `+z` or `-z` for lift \
                 (the way the foot moved along the test's axis), got `-x`"
                    .into()
            )
        );
        assert_eq!(
            parse("test = []\n"),
            Err(
                "experiment `t.toml`: no `[[test]]` tables: list each force/deflection test \
                 (`dof`, optional `direction`), one per data row"
                    .into()
            )
        );
        assert_eq!(
            parse("[[test]]\ndof = \"swing\"\ndirection = \"+x\"\n"),
            Ok(())
        );
    }

    /// A fit's failure shows the parameter values without Rust's debug notation.
    #[test]
    fn fit_errors_show_plain_numbers() {
        let error: Error = LmError::NonFiniteResidual {
            params: vec![1.0, 0.25, 2.5e-6, 0.0],
            index: 3,
        }
        .into();
        assert_eq!(
            error.to_string(),
            "residual 3 is NaN or infinite at p = [1, 0.25, 2.5e-6, 0]; check the model and \
             the starting values"
        );
    }

    /// The JSON names of verdicts and stop reasons are snake_case, not Rust's variant names.
    #[test]
    fn json_names_are_snake_case() {
        let json = |v: serde_json::Value| v.as_str().unwrap().to_string();
        assert_eq!(
            json(serde_json::json!(Verdict::NoSignificantDiscrepancy)),
            "no_significant_discrepancy"
        );
        assert_eq!(
            json(serde_json::json!(StopReason::CostReduction)),
            "cost_reduction"
        );
    }
}
