//! `mech`: check, derive and simulate `.mech` models from the command line.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};
use mech::session::{self, Session};
use mech::{describe, output, plot};
use mech_codegen::Compiled;
use mech_runtime::{Method, Model, SimOptions};

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
    Check {
        /// The `.mech` file.
        model: PathBuf,
    },
    /// Derive the equations of motion and print generated code or equations.
    Derive {
        model: PathBuf,
        /// What to print.
        #[arg(long, value_enum, default_value_t = Emit::Equations)]
        emit: Emit,
        /// Write to this file instead of standard output.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Simulate a model and write the trajectory as CSV (and optionally a plot).
    Simulate {
        model: PathBuf,
        /// End time, with a unit (`2 s`, `500 ms`) or in seconds.
        #[arg(long)]
        t_end: String,
        /// Set a parameter: `--set m=12 g` (repeatable).
        #[arg(long = "set", value_name = "NAME=VALUE")]
        sets: Vec<String>,
        /// Drive an input: `--input drive='sine(amplitude=1 mN, frequency=10 Hz)'` (repeatable).
        #[arg(long = "input", value_name = "NAME=SIGNAL")]
        inputs: Vec<String>,
        /// CSV file for time, q, u and outputs.
        #[arg(long)]
        out: PathBuf,
        /// Plot file (`.svg` or `.png`).
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Integrator.
        #[arg(long, value_enum, default_value_t = Integrator::Dopri5)]
        method: Integrator,
        /// Relative tolerance (adaptive methods).
        #[arg(long, default_value_t = 1e-9)]
        rtol: f64,
        /// Absolute tolerance (adaptive methods).
        #[arg(long, default_value_t = 1e-12)]
        atol: f64,
        /// Step size for rk4, with a unit or in seconds.
        #[arg(long, default_value = "0.1 ms")]
        step: String,
        /// Output sampling interval, with a unit or in seconds (default: t_end / 1000).
        #[arg(long)]
        dt_out: Option<String>,
        /// For models with loops: hold this coordinate (at VALUE, or its q0) while closing
        /// the loops, e.g. `--independent crank_angle=1rad` (repeatable; default: chosen by
        /// pivoting on the constraint Jacobian).
        #[arg(long = "independent", value_name = "NAME[=VALUE]")]
        independent: Vec<String>,
    },
    /// Static equilibrium under the inputs and loads, with loop reactions and the forces
    /// of fixtures (e.g. a foot held against a force sensor).
    Statics(mech::linear_cli::StaticsArgs),
    /// Linearize about the static equilibrium in minimal coordinates: M, C, K, B and the
    /// normal modes.
    Linearize(mech::linear_cli::LinearizeArgs),
    /// Frequency response from an input to an output (Bode plot), with resonances and Q.
    Bode(mech::linear_cli::BodeArgs),
    /// Close the loops of a model: mobility, the singular values deciding it, and a
    /// consistent state (CSV with --out).
    Assemble {
        model: PathBuf,
        /// Set a parameter: `--set 'm=12 g'` (repeatable).
        #[arg(long = "set", value_name = "NAME=VALUE")]
        sets: Vec<String>,
        /// Hold this coordinate (at VALUE, or its q0): `--independent crank_angle=1rad`.
        #[arg(long = "independent", value_name = "NAME[=VALUE]")]
        independent: Vec<String>,
        /// CSV file for the assembled coordinates and speeds.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Flexure hinges: stiffness and damping (seed Eqs. 2, 5, 8) and the pendulum fit (Sec. IV).
    Flexure {
        #[command(subcommand)]
        command: mech::flexure_fit::cli::FlexureCommand,
    },
    /// Piezo bending actuator: blocked force, free deflection, series stiffness, energy density.
    Actuator(mech::flexure_fit::cli::ActuatorArgs),
    /// Run one experiment file (`experiments/*.toml`): CSV, plots and tables.
    Experiment(mech::experiments::report::ExperimentArgs),
    /// Run every experiment in `experiments/` and write an HTML and Markdown report.
    Report(mech::experiments::report::ReportArgs),
    /// Fit model parameters to measured data (Levenberg–Marquardt, standard errors), with the
    /// residual before and after; see docs/diagnose.md.
    Fit(mech::diagnose::command::FitArgs),
    /// Find what the model gets wrong: fit every catalog cause, rank on held-out data, and
    /// name the cause (or say there is none, or that none explains it); see docs/diagnose.md.
    Diagnose(mech::diagnose::command::DiagnoseArgs),
}

#[derive(Clone, Copy, ValueEnum)]
enum Emit {
    /// Equations of motion as s-expressions, with operation counts.
    Equations,
    /// The generated Rust source.
    Rust,
    /// The tape (register instructions), with operation counts.
    Tape,
}

#[derive(Clone, Copy, ValueEnum)]
enum Integrator {
    /// Adaptive Dormand–Prince 5(4).
    Dopri5,
    /// Adaptive Dormand–Prince 8(5,3): fewer evaluations at tight tolerances.
    Dop853,
    /// Fixed-step classical Runge–Kutta.
    Rk4,
    /// Linearly implicit Rosenbrock 2(3) (L-stable), in the independent coordinates.
    Rosenbrock,
    /// Exponential Rosenbrock 4(3): follows lightly damped fast modes at long steps, in the
    /// independent coordinates.
    ExpRosenbrock,
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

fn main() -> ExitCode {
    restore_default_sigpipe();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Check { model } => check(&model),
        Command::Derive { model, emit, out } => derive(&model, emit, out.as_deref()),
        Command::Simulate {
            model,
            t_end,
            sets,
            inputs,
            out,
            plot,
            method,
            rtol,
            atol,
            step,
            dt_out,
            independent,
        } => {
            let request = SimulateRequest {
                t_end,
                sets,
                inputs,
                out,
                plot,
                method,
                rtol,
                atol,
                step,
                dt_out,
                independent,
            };
            simulate(&model, &request)
        }
        Command::Assemble {
            model,
            sets,
            independent,
            out,
        } => assemble(&model, &sets, &independent, out.as_deref()),
        Command::Flexure { command } => mech::flexure_fit::cli::flexure(command),
        Command::Actuator(args) => mech::flexure_fit::cli::actuator(&args),
        Command::Statics(args) => mech::linear_cli::statics(&args),
        Command::Linearize(args) => mech::linear_cli::linearize_command(&args),
        Command::Bode(args) => mech::linear_cli::bode(&args),
        Command::Experiment(args) => mech::experiments::report::experiment_command(&args),
        Command::Report(args) => mech::experiments::report::report_command(&args),
        Command::Fit(args) => mech::diagnose::command::fit_command(&args),
        Command::Diagnose(args) => mech::diagnose::command::diagnose_command(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("{}", message.trim_end());
            ExitCode::FAILURE
        }
    }
}

fn compile(path: &Path) -> Result<Compiled, String> {
    Compiled::from_path(path).map_err(|errors| errors.to_string())
}

fn check(path: &Path) -> Result<(), String> {
    let session = Session::open(path, &[], &[])?;
    let compiled = &session.compiled;
    let model = &compiled.model;
    println!("model `{}` ({})", model.name, path.display());
    if model.loops.is_empty() {
        println!(
            "  {} bodies, {} joints, {} degrees of freedom",
            model.bodies.len(),
            model.joints.len(),
            model.coordinates.len()
        );
    } else {
        let state = session.assemble(&[])?;
        let mobility = state
            .mobility
            .as_ref()
            .map(ToString::to_string)
            .unwrap_or_default();
        println!(
            "  {} bodies, {} joints, {} loops; at the assembled q0: {mobility}",
            model.bodies.len(),
            model.joints.len(),
            model.loops.len()
        );
        // The singular values that decide the rank, and any warning about them.
        let report = session::assembly_report(&session.model, &state);
        for line in report.lines().skip(1).take_while(|line| !line.is_empty()) {
            println!("  {line}");
        }
    }
    println!("\ncoordinates (q, with u = q̇):");
    for (_, joint) in model.joints.iter() {
        for &c in &joint.coordinates {
            let coordinate = &model.coordinates[c];
            let unit = if coordinate.dimension == mech_codegen::ir::Dimension::NONE {
                "rad"
            } else {
                "m"
            };
            println!(
                "  {:<16} {:?} joint `{}`, q0 = {} {unit}, u0 = {} {unit}/s",
                coordinate.name,
                joint.kind,
                joint.name,
                coordinate.initial,
                coordinate.initial_speed
            );
        }
    }
    println!("\nbodies:");
    for (_, body) in model.bodies.iter() {
        let parent = model
            .joints
            .iter()
            .find(|(_, j)| model.bodies[j.child].name == body.name);
        let attached = parent.map_or("?".to_string(), |(_, joint)| {
            let parent_name = joint
                .parent
                .map_or("newtonian", |b| model.bodies[b].name.as_str());
            format!(
                "child of `{parent_name}` by {:?} joint `{}`",
                joint.kind, joint.name
            )
        });
        println!("  {:<16} {attached}", body.name);
    }
    let list = |title: &str, items: Vec<String>| {
        if !items.is_empty() {
            println!("\n{title}: {}", items.join(", "));
        }
    };
    list(
        "parameters",
        model
            .params
            .iter()
            .map(|(_, p)| format!("{} = {} {}", p.name, p.value, p.dimension))
            .collect(),
    );
    list(
        "inputs",
        model
            .inputs
            .iter()
            .map(|(_, i)| format!("{} [{}]", i.name, i.dimension))
            .collect(),
    );
    list("outputs", compiled.equations.output_names.clone());
    Ok(())
}

fn derive(path: &Path, emit: Emit, out: Option<&Path>) -> Result<(), String> {
    let compiled = compile(path)?;
    let text = match emit {
        Emit::Rust => {
            let options = mech_codegen::RustOptions {
                source_name: path.display().to_string(),
                ..Default::default()
            };
            compiled.rust(&options)
        }
        Emit::Tape => describe::tape_text(&compiled),
        Emit::Equations => describe::equations_text(&compiled),
    };
    match out {
        Some(file) => output::write_atomic(file, text.as_bytes())
            .map_err(|e| format!("cannot write {}: {e}", file.display())),
        None => {
            print!("{text}");
            Ok(())
        }
    }
}

fn assemble(
    path: &Path,
    sets: &[String],
    independent: &[String],
    out: Option<&Path>,
) -> Result<(), String> {
    let session = Session::open(path, sets, &[])?;
    let state = session.assemble(independent)?;
    print!("{}", session::assembly_report(&session.model, &state));
    if let Some(out) = out {
        let model = &session.model;
        let names: Vec<&str> = (0..model.nq()).map(|i| model.coordinate_name(i)).collect();
        let mut header: Vec<String> = names.iter().map(|n| format!("q_{n}")).collect();
        header.extend(names.iter().map(|n| format!("u_{n}")));
        let row: Vec<f64> = state.q.iter().chain(&state.u).copied().collect();
        output::write_csv(out, &header, &[row])
            .map_err(|e| format!("cannot write {}: {e}", out.display()))?;
        println!("\nwritten to {}", out.display());
    }
    Ok(())
}

struct SimulateRequest {
    t_end: String,
    sets: Vec<String>,
    inputs: Vec<String>,
    out: PathBuf,
    plot: Option<PathBuf>,
    method: Integrator,
    rtol: f64,
    atol: f64,
    step: String,
    dt_out: Option<String>,
    independent: Vec<String>,
}

/// A time given with a unit (`2 s`, `500 ms`) or as plain seconds.
fn parse_time(what: &str, text: &str) -> Result<f64, String> {
    let (value, dimension) =
        mech_codegen::front::units::parse_quantity(text).map_err(|e| format!("{what}: {e}"))?;
    let seconds_ok = dimension == mech_codegen::ir::Dimension::TIME
        || dimension == mech_codegen::ir::Dimension::NONE;
    if !seconds_ok || !value.is_finite() || value <= 0.0 {
        return Err(format!(
            "{what}: expected a positive time such as `2 s` or `500 ms`, got `{text}`"
        ));
    }
    Ok(value)
}

fn simulate(path: &Path, request: &SimulateRequest) -> Result<(), String> {
    let session = Session::open(path, &request.sets, &request.inputs)?;
    let state = session.assemble(&request.independent)?;
    if let Some(mobility) = &state.mobility {
        println!("assembled `{}`: {mobility}", session.model.name());
    }
    let (model, signals) = (&session.model, &session.signals);
    let t_end = parse_time("--t-end", &request.t_end)?;
    let dt_out = match &request.dt_out {
        Some(text) => parse_time("--dt-out", text)?,
        None => t_end / 1000.0,
    };
    let method = match request.method {
        Integrator::Dopri5 => Method::Dopri5 {
            rtol: request.rtol,
            atol: request.atol,
            h_max: f64::INFINITY,
        },
        Integrator::Dop853 => Method::Dop853 {
            rtol: request.rtol,
            atol: request.atol,
            h_max: f64::INFINITY,
        },
        Integrator::Rk4 => Method::Rk4 {
            step: parse_time("--step", &request.step)?,
        },
        Integrator::Rosenbrock => Method::Rosenbrock {
            rtol: request.rtol,
            atol: request.atol,
            h_max: f64::INFINITY,
        },
        Integrator::ExpRosenbrock => Method::ExpRosenbrock {
            rtol: request.rtol,
            atol: request.atol,
            h_max: f64::INFINITY,
        },
    };
    let options = SimOptions {
        t_end,
        output_interval: dt_out,
        method,
        ..SimOptions::default()
    };

    let (q0, u0) = (&state.q, &state.u);
    let bar = indicatif::ProgressBar::new(1000);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "simulating {bar:40} {percent:>3}% t = {msg} [{elapsed} / ~{eta}]",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut progress = |t: f64| {
        bar.set_position((1000.0 * t / t_end) as u64);
        bar.set_message(format!("{t:.4} s"));
    };
    let trajectory = if method.is_reduced() {
        let independent = &state.independent;
        mech_runtime::simulate_reduced(model, q0, u0, independent, signals, &options, &mut progress)
    } else {
        mech_runtime::simulate(model, q0, u0, signals, &options, &mut progress)
    };
    bar.finish_and_clear();
    let trajectory =
        trajectory.map_err(|e| format!("simulation of `{}` failed: {e}", model.name()))?;

    let coordinate_names: Vec<String> = (0..model.nq())
        .map(|i| model.coordinate_name(i).to_string())
        .collect();
    let output_names: Vec<String> = (0..model.noutputs())
        .map(|i| model.output_name(i).to_string())
        .collect();
    let mut header = vec!["t".to_string()];
    header.extend(coordinate_names.iter().map(|n| format!("q_{n}")));
    header.extend(coordinate_names.iter().map(|n| format!("u_{n}")));
    header.extend(output_names.iter().cloned());
    let rows: Vec<Vec<f64>> = (0..trajectory.times.len())
        .map(|k| {
            let mut row = vec![trajectory.times[k]];
            row.extend(&trajectory.q[k]);
            row.extend(&trajectory.u[k]);
            row.extend(&trajectory.outputs[k]);
            row
        })
        .collect();
    output::write_csv(&request.out, &header, &rows)
        .map_err(|e| format!("cannot write {}: {e}", request.out.display()))?;
    println!(
        "simulated `{}` to t = {t_end} s: {} samples written to {}",
        model.name(),
        trajectory.times.len(),
        request.out.display()
    );

    if let Some(plot_path) = &request.plot {
        let column = |values: &Vec<Vec<f64>>, i: usize| {
            values.iter().map(|row| row[i]).collect::<Vec<f64>>()
        };
        let series = |names: &[String], values: &Vec<Vec<f64>>, prefix: &str| {
            names
                .iter()
                .enumerate()
                .map(|(i, n)| plot::Series {
                    name: format!("{prefix}{n}"),
                    values: column(values, i),
                })
                .collect::<Vec<_>>()
        };
        let mut panels = vec![
            plot::Panel {
                title: "coordinates".into(),
                y_label: "q".into(),
                series: series(&coordinate_names, &trajectory.q, "q_"),
            },
            plot::Panel {
                title: "speeds".into(),
                y_label: "u".into(),
                series: series(&coordinate_names, &trajectory.u, "u_"),
            },
        ];
        if !output_names.is_empty() {
            panels.push(plot::Panel {
                title: "outputs".into(),
                y_label: "y".into(),
                series: series(&output_names, &trajectory.outputs, ""),
            });
        }
        let title = format!("{} — {}", model.name(), path.display());
        plot::plot_time_series(plot_path, &title, &trajectory.times, &panels)
            .map_err(|e| format!("cannot plot: {e}"))?;
        println!("plot written to {}", plot_path.display());
    }
    Ok(())
}
