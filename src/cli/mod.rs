//! The command line: one file per command, named after it, and the only code that parses
//! arguments, prints and decides which files to write. Each command file holds its clap
//! arguments (`XArgs`) and a `run` that calls the library's analyses (which return data)
//! and the renderers of [`crate::render`].
//!
//! Consumes: the process arguments. Produces: text on stdout/stderr, files, the exit code.
//!
//! `print!` and `println!` in this module and its command files are those of `print.rs`, not
//! std's: everything printed passes through [`terminal_safe`], because messages quote file
//! contents, file names and titles that may hold escape sequences. What several commands
//! share is in `args.rs` (the model arguments, the parsers of option values) and
//! `progress.rs`; `mod.rs` holds the command list and `main`.

#[macro_use]
mod print;

mod args;
mod progress;

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

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

use crate::render::terminal::terminal_safe;

pub use args::ModelArgs;
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
