//! The command line: one file per command, named after it, and the only code that parses
//! arguments, prints and decides which files to write. Each command file holds its clap
//! arguments (`XArgs`) and a `run` that calls the library's analyses (which return data)
//! and the renderers of [`crate::render`].
//!
//! Consumes: the process arguments. Produces: text on stdout/stderr, files, the exit code.
//!
//! `print!` and `println!` in this module and its command files are the two macros below,
//! not std's: everything printed passes through [`terminal_safe`], because messages quote
//! file contents, file names and titles that may hold escape sequences.

/// std's `print!`, with control characters made visible ([`terminal_safe`]).
macro_rules! print {
    ($($arg:tt)*) => {
        ::std::print!("{}", $crate::render::terminal::terminal_safe(&format!($($arg)*)))
    };
}

/// std's `println!`, with control characters made visible ([`terminal_safe`]).
macro_rules! println {
    () => { ::std::println!() };
    ($($arg:tt)*) => {
        ::std::println!("{}", $crate::render::terminal::terminal_safe(&format!($($arg)*)))
    };
}

pub mod actuator;
pub mod animate;
pub mod assemble;
pub mod bode;
pub mod check;
pub mod derive;
pub mod diagnose;
pub mod error;
pub mod experiment;
pub mod fit;
pub mod flexure;
pub mod import;
pub mod linearize;
pub mod report;
pub mod simulate;
pub mod statics;
pub mod sweep;

use std::f64::consts::TAU;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand};
use mech_codegen::ir::Dimension;

use crate::quantity::parse_si;
use crate::render::terminal::terminal_safe;
use crate::session::Session;

pub use error::Error;

#[derive(Parser)]
#[command(
    name = "mech",
    version,
    about = "A Kane's-method compiler for flexure-based microrobots"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Validate a model and print its coordinates, bodies and degrees of freedom.
    Check(check::CheckArgs),
    /// Derive the equations of motion and print generated code or equations.
    Derive(derive::DeriveArgs),
    /// Simulate a model and write the trajectory as CSV (and optionally a plot).
    Simulate(simulate::SimulateArgs),
    /// Static equilibrium under the inputs and loads, with loop reactions and the forces
    /// of fixtures (e.g. a foot held against a force sensor).
    Statics(statics::StaticsArgs),
    /// Linearize about the static equilibrium in minimal coordinates: M, C, K, B and the
    /// normal modes.
    Linearize(linearize::LinearizeArgs),
    /// Frequency response from an input to an output (Bode plot), with resonances and Q.
    Bode(bode::BodeArgs),
    /// Close the loops of a model: mobility, the singular values deciding it, and a
    /// consistent state (CSV with --out).
    Assemble(assemble::AssembleArgs),
    /// Flexure hinges: stiffness and damping (seed Eqs. 2, 5, 8) and the pendulum fit (Sec. IV).
    Flexure {
        #[command(subcommand)]
        command: flexure::FlexureCommand,
    },
    /// Piezo bending actuator: blocked force, free deflection, series stiffness, energy density.
    Actuator(actuator::ActuatorArgs),
    /// Run one experiment file (`experiments/*.toml`): CSV, plots and tables.
    Experiment(experiment::ExperimentArgs),
    /// Run every experiment in `experiments/` and write an HTML and Markdown report.
    Report(report::ReportArgs),
    /// Parameter grids and Monte-Carlo tolerance studies (a TOML study): CSV of the samples,
    /// summaries, histograms, scatter plots and a Spearman sensitivity ranking.
    Sweep(sweep::SweepArgs),
    /// Fit model parameters to measured data (Levenberg–Marquardt, standard errors), with the
    /// residual before and after; see docs/diagnose.md.
    Fit(fit::FitArgs),
    /// Find what the model gets wrong: fit every catalog cause, rank on held-out data, and
    /// name the cause (or say there is none, or that none explains it); see docs/diagnose.md.
    Diagnose(diagnose::DiagnoseArgs),
    /// Translate a robot description into a `.mech` model (`mech import urdf FILE --out M.mech`).
    Import {
        #[command(subcommand)]
        command: import::ImportCommand,
    },
    /// Play a simulated run in 3D: a self-contained HTML page of the model's bodies moving
    /// (`mech animate MODEL RUN.csv --out view.html`).
    Animate(animate::AnimateArgs),
}

/// Restores the default SIGPIPE action, so `mech ... | head` ends quietly instead of
/// panicking on a closed pipe (Rust ignores SIGPIPE by default).
#[cfg(unix)]
fn restore_default_sigpipe() {
    unsafe extern "C" {
        fn signal(signum: i32, handler: usize) -> usize;
    }
    const SIGPIPE: i32 = 13;
    const SIG_DFL: usize = 0;
    // SAFETY: setting a signal's disposition to SIG_DFL is async-signal-safe and has no
    // preconditions; it runs before any other thread exists.
    unsafe {
        signal(SIGPIPE, SIG_DFL);
    }
}

#[cfg(not(unix))]
fn restore_default_sigpipe() {}

/// Parses the process arguments, runs the command, prints its error (if any) on stderr.
pub fn main() -> ExitCode {
    restore_default_sigpipe();
    let command = accept_leading_hyphens(Cli::command());
    let matches = command.clone().get_matches();
    let cli = refuse_options_as_values(&command, &matches)
        .and_then(|()| Cli::from_arg_matches(&matches))
        .unwrap_or_else(|error| error.exit());
    let result = match cli.command {
        Command::Check(args) => check::run(&args),
        Command::Derive(args) => derive::run(&args),
        Command::Simulate(args) => simulate::run(&args),
        Command::Statics(args) => statics::run(&args),
        Command::Linearize(args) => linearize::run(&args),
        Command::Bode(args) => bode::run(&args),
        Command::Assemble(args) => assemble::run(&args),
        Command::Flexure { command } => flexure::run(command),
        Command::Actuator(args) => actuator::run(&args),
        Command::Experiment(args) => experiment::run(&args),
        Command::Report(args) => report::run(&args),
        Command::Sweep(args) => sweep::run(&args),
        Command::Fit(args) => fit::run(&args),
        Command::Diagnose(args) => diagnose::run(&args),
        Command::Import { command } => import::run(&command),
        Command::Animate(args) => animate::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("{}", terminal_safe(message.to_string().trim_end()));
            ExitCode::FAILURE
        }
    }
}

/// Lets every option take a value that starts with `-` (`--t-end -1`, `--rtol -1e-6`), so
/// the option's own check says what is wrong with it instead of clap's tip to write `-- -1`
/// (clap's `allow_negative_numbers` misses `-1e-6` and `-1 ms`). Not for positionals: a list
/// of files would swallow the options after it.
fn accept_leading_hyphens(command: clap::Command) -> clap::Command {
    command
        .mut_args(|arg| {
            if arg.get_action().takes_values() && !arg.is_positional() {
                arg.allow_hyphen_values(true)
            } else {
                arg
            }
        })
        .mut_subcommands(accept_leading_hyphens)
}

/// With [`accept_leading_hyphens`], `--out --plot run.svg` would read `--plot` as the file
/// name: a value that looks like one of the command's options is refused instead.
fn refuse_options_as_values(
    command: &clap::Command,
    matches: &clap::ArgMatches,
) -> Result<(), clap::Error> {
    if let Some((name, sub_matches)) = matches.subcommand() {
        if let Some(sub_command) = command.find_subcommand(name) {
            return refuse_options_as_values(sub_command, sub_matches);
        }
    }
    for arg in command.get_arguments() {
        let Some(long) = arg.get_long() else { continue };
        let Ok(Some(values)) = matches.try_get_raw(arg.get_id().as_str()) else {
            continue;
        };
        for value in values {
            let value = value.to_string_lossy();
            let named = value.strip_prefix("--").unwrap_or_default();
            let name = named.split('=').next().unwrap_or_default();
            if command.get_arguments().any(|a| a.get_long() == Some(name)) {
                let mut command = command.clone();
                return Err(command.error(
                    clap::error::ErrorKind::InvalidValue,
                    format!(
                        "--{long} needs a value, but the next argument is the option `--{name}`"
                    ),
                ));
            }
        }
    }
    Ok(())
}

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
    fn check_outputs(
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
    fn open_with_signals(&self) -> Result<Session, Error> {
        Ok(Session::open(&self.model, &self.sets, &self.inputs)?)
    }

    /// Opens the model for `command`, which holds the inputs constant, and returns it with
    /// the input values. A signal that varies in time is refused, not read at t = 0.
    fn open(&self, command: &str) -> Result<(Session, Vec<f64>), Error> {
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
fn data_run_reads(
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

/// A progress bar drawn with `template` (indicatif's syntax) on stderr.
fn progress_bar(length: u64, template: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(length);
    bar.set_style(
        indicatif::ProgressStyle::with_template(template)
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}

// ------------------------------------------------------------------ quantities

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
