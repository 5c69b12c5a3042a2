//! What several commands share on their command line: the model arguments (`MODEL --set
//! --input --independent`) with the checks of their outputs against their inputs, the files
//! a fit or a diagnosis reads, and the parsers of numbers and quantities given as option
//! values, each saying which values the option takes.
//!
//! Consumes: argument text. Produces: typed values, or a [`Error::Usage`] (clap's value
//! parsers: a `String` clap prints after the option's name).

use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

use clap::Args;
use mech_codegen::ir::Dimension;

use super::Error;
use crate::quantity::parse_si;
use crate::session::Session;

/// What every linear-analysis command takes.
#[derive(Args, Clone, Debug)]
pub struct ModelArgs {
    /// The `.mech` file.
    pub model: PathBuf,
    /// Set a parameter: `--set 'm=12 g'` (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub sets: Vec<String>,
    /// Drive an input: a constant `--input 'drive=2 mN'`, or for `simulate` a signal
    /// `--input drive='sine(amplitude=1 mN, frequency=10 Hz)'` (the other commands use its
    /// value at t = 0; repeatable).
    #[arg(long = "input", value_name = "NAME=VALUE")]
    pub inputs: Vec<String>,
    /// For models with loops: a coordinate kept independent (`NAME` or `NAME=VALUE` for the
    /// starting guess); default: chosen by pivoting.
    #[arg(long = "independent", value_name = "NAME[=VALUE]")]
    pub independent: Vec<String>,
}

impl ModelArgs {
    /// The files the run reads: the model and the tables of `--input x=csv(...)`.
    fn reads(&self) -> Vec<crate::output::Read> {
        let model = crate::output::Read {
            path: self.model.clone(),
            what: "the model",
        };
        let tables = self.inputs.iter().filter_map(|assignment| {
            let (_, spec) = crate::signal_spec::parse_assignment(assignment).ok()?;
            Some(crate::output::Read {
                path: crate::signal_spec::file_read(&spec)?,
                what: "the input table",
            })
        });
        std::iter::once(model).chain(tables).collect()
    }

    /// Refuses, before the command's work, outputs that would replace one of its inputs or
    /// that name one file twice, and a plot path of no known format; returns the inputs for
    /// [`crate::output::write_all`].
    pub(super) fn check_outputs(
        &self,
        outputs: &[Option<&Path>],
        plot: Option<&Path>,
    ) -> Result<Vec<crate::output::Read>, Error> {
        let reads = self.reads();
        let paths = outputs.iter().copied().chain([plot]).flatten();
        crate::output::check_outputs(paths, &reads)?;
        if let Some(plot) = plot {
            crate::render::plot::check_path(plot)?;
        }
        Ok(reads)
    }

    /// Opens the model for `simulate`, which takes signals (`sine(...)`) as inputs.
    pub(super) fn open_with_signals(&self) -> Result<Session, Error> {
        Ok(Session::open(&self.model, &self.sets, &self.inputs)?)
    }

    /// Opens the model for `command`, which holds the inputs constant, and returns it with
    /// the input values. A signal that varies in time is refused, not read at t = 0.
    pub(super) fn open(&self, command: &str) -> Result<(Session, Vec<f64>), Error> {
        let session = self.open_with_signals()?;
        for (index, signal) in session.signals.iter().enumerate() {
            if !matches!(signal, mech_runtime::Signal::Constant(_)) {
                let name = mech_runtime::Model::input_name(&session.model, index);
                return Err(Error::Usage(format!(
                    "--input {name}: `mech {command}` holds inputs constant; give a value such \
                     as `{name}=2 {}` (signals that vary in time are for `mech simulate`)",
                    session.input_dimension(index)
                )));
            }
        }
        let inputs: Vec<f64> = session.signals.iter().map(|s| s.value(0.0)).collect();
        Ok((session, inputs))
    }
}

/// The files a fit or a diagnosis reads, which its outputs must not replace: the experiment
/// file, its model and the measured data.
pub(super) fn data_run_reads(
    experiment_file: &Path,
    experiment: &crate::diagnose::experiment::Experiment,
    data: &Path,
) -> Vec<crate::output::Read> {
    let read = |path: &Path, what| crate::output::Read {
        path: path.to_path_buf(),
        what,
    };
    vec![
        read(experiment_file, "the experiment file"),
        read(&experiment.model.path, "the model"),
        read(data, "the data file"),
    ]
}

/// A plain number from the command line, with the range it must lie in. clap's parser for
/// `f64` takes `NaN` and `inf`; this one says which numbers the option takes.
fn number_in(text: &str, accept: impl Fn(f64) -> bool, expected: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(value) if value.is_finite() && accept(value) => Ok(value),
        Ok(_) => Err(format!("expected {expected}")),
        Err(_) => Err(format!(
            "expected {expected}, as a plain number such as `0.5`"
        )),
    }
}

/// clap value parser: a finite number above zero (`--rtol 1e-9`).
pub(crate) fn positive_number(text: &str) -> Result<f64, String> {
    number_in(text, |v| v > 0.0, "a number above zero")
}

/// clap value parser: a finite number at or above zero (`--loss-factor 0.02`).
pub(crate) fn non_negative_number(text: &str) -> Result<f64, String> {
    number_in(text, |v| v >= 0.0, "a number at or above zero")
}

/// clap value parser: Poisson's ratio of an isotropic solid, −1 < ν < ½.
pub(crate) fn poisson_ratio(text: &str) -> Result<f64, String> {
    number_in(
        text,
        |v| v > -1.0 && v < 0.5,
        "Poisson's ratio between -1 and 0.5 (exclusive)",
    )
}

/// Most frequencies or samples a command computes and stores: enough for any plot, small
/// enough that a typo (`--points 1e8`) cannot take the machine's memory.
pub(crate) const MAX_POINTS: usize = 1_000_000;

/// clap value parser: a number of frequencies, at least 2 (a sweep needs two ends).
pub(crate) fn point_count(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if (2..=MAX_POINTS).contains(&n) => Ok(n),
        _ => Err(format!("expected a whole number from 2 to {MAX_POINTS}")),
    }
}

/// clap value parser: a whole number at least 1 (`--max-steps 20000`).
pub(crate) fn positive_count(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err("expected a whole number of at least 1".to_string()),
    }
}

/// A time given with a unit (`2 s`, `500 ms`) or as plain seconds.
pub(crate) fn parse_time(what: &str, text: &str) -> Result<f64, Error> {
    let (value, dimension) = mech_codegen::front::units::parse_quantity(text)
        .map_err(|e| Error::Usage(format!("{what}: {e}")))?;
    let seconds_ok = dimension == mech_codegen::ir::Dimension::TIME
        || dimension == mech_codegen::ir::Dimension::NONE;
    if !seconds_ok || !value.is_finite() || value <= 0.0 {
        return Err(Error::Usage(format!(
            "{what}: expected a positive time such as `2 s` or `500 ms`, got `{text}`"
        )));
    }
    Ok(value)
}

/// A positive frequency such as `10 Hz` (or plain hertz).
pub(crate) fn frequency_value(what: &str, text: &str) -> Result<f64, Error> {
    let (value, dimension) = mech_codegen::front::units::parse_quantity(text)
        .map_err(|e| Error::Usage(format!("{what}: {e}")))?;
    let hertz = mech_codegen::ir::Dimension {
        time: -1,
        ..mech_codegen::ir::Dimension::NONE
    };
    if (dimension != hertz && dimension != mech_codegen::ir::Dimension::NONE)
        || value.is_nan()
        || value <= 0.0
    {
        return Err(Error::Usage(format!(
            "{what}: expected a positive frequency such as `10 Hz`, got `{text}`"
        )));
    }
    Ok(value)
}

/// A positive length such as `25 um`.
pub(crate) fn length(what: &str, text: &str) -> Result<f64, Error> {
    positive(what, parse_si(what, text, Dimension::LENGTH, false)?)
}

/// `value` itself if it is positive and finite.
pub(crate) fn positive(what: &str, value: f64) -> Result<f64, Error> {
    if value > 0.0 && value.is_finite() {
        Ok(value)
    } else {
        Err(Error::Usage(format!(
            "{what} must be positive, got {value}"
        )))
    }
}

/// An angular frequency (rad/s) from `40 Hz` (cycles per second) or `250 rad/s`.
pub(crate) fn angular_frequency(what: &str, text: &str) -> Result<f64, Error> {
    let frequency = Dimension::TIME.powi(-1);
    let value = parse_si(what, text, frequency, false)?;
    let angular = text.contains("rad") || text.contains("deg");
    let omega = if angular {
        // `deg/s` parses to (π/180)/s; `rad/s` to 1/s: already angular.
        value
    } else {
        TAU * value
    };
    positive(what, omega)
}

/// A positive voltage such as `225 V`.
pub(crate) fn voltage(what: &str, text: &str) -> Result<f64, Error> {
    let volt = Dimension::MASS
        .mul(Dimension::LENGTH.powi(2))
        .div(Dimension::TIME.powi(3))
        .div(Dimension::CURRENT);
    positive(what, parse_si(what, text, volt, false)?)
}
