//! `mech simulate MODEL --t-end T --out run.csv`: integrate the equations of motion from the
//! assembled initial state and write the trajectory (and optionally a plot).
//!
//! Consumes: the model path, `--set`/`--input` strings, the integrator settings. Produces:
//! a CSV of time, q, u and outputs, written atomically, and an optional plot.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use mech_runtime::{Method, Model, SimOptions, Trajectory};

use super::args::{parse_time, ModelArgs};
use super::Error;
use crate::output;
use crate::render::plot;
use crate::render::run::{coordinate_names, output_names, speed_names, trajectory_table};
use crate::session::Session;

#[derive(Args, Clone, Debug)]
pub struct SimulateArgs {
    #[command(flatten)]
    pub common: ModelArgs,
    /// End time, with a unit (`2 s`, `500 ms`) or in seconds.
    #[arg(long)]
    pub t_end: String,
    /// CSV file for time, q, u and outputs.
    #[arg(long)]
    pub out: PathBuf,
    /// Plot file (`.svg` or `.png`).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Integrator.
    #[arg(long, value_enum, default_value_t = Integrator::Dopri5)]
    pub method: Integrator,
    /// Relative tolerance (adaptive methods).
    #[arg(long, default_value_t = 1e-9, value_parser = super::args::positive_number)]
    pub rtol: f64,
    /// Absolute tolerance (adaptive methods).
    #[arg(long, default_value_t = 1e-12, value_parser = super::args::positive_number)]
    pub atol: f64,
    /// Step size for rk4, with a unit or in seconds.
    #[arg(long, default_value = "0.1 ms")]
    pub step: String,
    /// Output sampling interval, with a unit or in seconds (default: t_end / 1000).
    #[arg(long)]
    pub dt_out: Option<String>,
    /// Start a coordinate at VALUE instead of its `q0`, with its unit: `--q0 'swing=20 deg'`
    /// (repeatable; with loops, a starting guess: hold it with `--independent NAME=VALUE`).
    #[arg(long = "q0", value_name = "NAME=VALUE")]
    pub q0: Vec<String>,
    /// Start a speed at VALUE instead of its `u0`: `--u0 'x=2 mm/s'` (repeatable; with loops,
    /// the speeds are then made consistent with them).
    #[arg(long = "u0", value_name = "NAME=VALUE")]
    pub u0: Vec<String>,
    /// Add the accelerations `u̇` (columns `udot_NAME`) and, for a model with loops, the
    /// constraint multipliers `λ` of `M u̇ = F + Jᵀλ` (columns `lambda_ROW`) to the CSV.
    #[arg(long)]
    pub accelerations: bool,
    /// Budget of integration steps, accepted and rejected: the run stops with an error when it
    /// is used up.
    #[arg(long, default_value_t = SimOptions::default().max_steps, value_parser = super::args::positive_count)]
    pub max_steps: usize,
    /// Threads for one run: with 2, the forcing `F` is evaluated beside `M`, `J` and `J̇u`
    /// (models of 5,000 instructions or more, native code), the same numbers; 1 keeps the run on one core
    /// (for running several simulations side by side). Default: 2 where the machine has two
    /// cores or more.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=2))]
    pub threads: Option<u8>,
    /// Print the integrator's work after the run: its wall time (with the JIT compile of the
    /// programs it calls), steps accepted and rejected, evaluations of the right-hand side
    /// (each a constrained solve for `u̇`), Jacobians.
    #[arg(long)]
    pub stats: bool,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Integrator {
    /// Adaptive Dormand–Prince 5(4).
    Dopri5,
    /// Adaptive Dormand–Prince 8(5,3): fewer evaluations at tight tolerances.
    Dop853,
    /// Fixed-step classical Runge–Kutta.
    Rk4,
    /// Linearly implicit Rosenbrock 2(3) (L-stable), in the independent coordinates.
    Rosenbrock,
    /// Rosenbrock W-method ROS34PW2, order 3(2) (L-stable), in all coordinates, implicit in
    /// the contacts' damping: long steps where regularized friction on light feet holds the
    /// explicit methods back.
    RosenbrockW,
    /// Exponential Rosenbrock 4(3): follows lightly damped fast modes at long steps, in the
    /// independent coordinates.
    ExpRosenbrock,
}

pub fn run(request: &SimulateArgs) -> Result<(), Error> {
    let path = request.common.model.as_path();
    let plot_path = request.plot.as_deref();
    let reads = (request.common).check_outputs(&[Some(&request.out)], plot_path)?;
    let mut session = request.common.open_with_signals()?;
    let threads = request
        .threads
        .map_or_else(crate::parallel::threads, usize::from);
    session.model.use_second_thread(threads >= 2);
    let start = session.initial_state(&request.q0, &request.u0)?;
    let state = session.assemble_from(&request.common.independent, start)?;
    if let Some(mobility) = &state.mobility {
        println!("assembled `{}`: {mobility}", session.model.name());
    }
    let model = &session.model;
    let t_end = parse_time("--t-end", &request.t_end)?;
    let options = SimOptions {
        t_end,
        output_interval: match &request.dt_out {
            Some(text) => parse_time("--dt-out", text)?,
            None => t_end / 1000.0,
        },
        method: method(request)?,
        max_steps: request.max_steps,
        ..SimOptions::default()
    };

    let bar = super::progress::progress_bar(
        1000,
        "simulating {bar:40} {percent:>3}% t = {msg} [{elapsed} / ~{eta}]",
    );
    let mut progress = |t: f64| {
        bar.set_position((1000.0 * t / t_end) as u64);
        bar.set_message(format!("{t:.4} s"));
    };
    let clock = std::time::Instant::now();
    let trajectory = session.simulate(&state, &options, &mut progress);
    let integration_seconds = clock.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let trajectory = trajectory?;

    let (mut header, mut rows) = trajectory_table(model, &trajectory);
    if request.accelerations {
        let sampled = mech_runtime::accelerations_along(model, &session.signals, &trajectory)
            .map_err(|error| crate::session::Error::Simulation {
                model: model.name().to_string(),
                error,
            })?;
        header.extend(speed_names(model).iter().map(|n| format!("udot_{n}")));
        header.extend((0..model.nc()).map(|i| format!("lambda_{}", model.constraint_name(i))));
        let columns = sampled.udot.iter().zip(&sampled.multipliers);
        for (row, (udot, lambda)) in rows.iter_mut().zip(columns) {
            row.extend(udot);
            row.extend(lambda);
        }
    }
    let mut files = vec![output::File::csv(&request.out, &header, &rows)?];
    if let Some(plot_path) = &request.plot {
        let title = format!("{} — {}", model.name(), path.display());
        let panels = trajectory_panels(&session, &trajectory);
        files.push(plot::plot_time_series(
            plot_path,
            &title,
            &trajectory.times,
            &panels,
        )?);
    }
    output::write_all(&files, &reads)?;
    println!(
        "simulated `{}` to t = {t_end} s: {} samples written to {}",
        model.name(),
        trajectory.times.len(),
        request.out.display()
    );
    if let Some(plot_path) = &request.plot {
        println!("plot written to {}", plot_path.display());
    }
    if request.stats {
        println!(
            "integrated in {integration_seconds:.3} s: {}",
            work(&trajectory.stats)
        );
    }
    Ok(())
}

/// `N steps accepted, R rejected, E evaluations of the right-hand side[, J Jacobians]`.
fn work(stats: &mech_runtime::Stats) -> String {
    let mut text = format!(
        "{} steps accepted, {} rejected, {} evaluations of the right-hand side",
        stats.accepted_steps, stats.rejected_steps, stats.rhs_evaluations
    );
    if stats.jacobian_evaluations > 0 {
        text.push_str(&format!(", {} Jacobians", stats.jacobian_evaluations));
    }
    text
}

/// The integrator and its settings as `--method`, `--rtol`, `--atol` and `--step` give them.
fn method(request: &SimulateArgs) -> Result<Method, Error> {
    let (rtol, atol, h_max) = (request.rtol, request.atol, f64::INFINITY);
    Ok(match request.method {
        Integrator::Dopri5 => Method::Dopri5 { rtol, atol, h_max },
        Integrator::Dop853 => Method::Dop853 { rtol, atol, h_max },
        Integrator::Rk4 => Method::Rk4 {
            step: parse_time("--step", &request.step)?,
        },
        Integrator::Rosenbrock => Method::Rosenbrock { rtol, atol, h_max },
        Integrator::RosenbrockW => Method::RosenbrockW { rtol, atol, h_max },
        Integrator::ExpRosenbrock => Method::ExpRosenbrock { rtol, atol, h_max },
    })
}

/// A panel of `mech simulate --plot`: its title, the y axis symbol and the unit (`None`: not
/// declared).
type PanelKey = (&'static str, &'static str, Option<String>);

/// One panel per kind of value (coordinates, speeds, outputs) and unit, in order of first
/// appearance, the unit on the y axis: a rad and a m coordinate never share an axis.
fn trajectory_panels(session: &Session, trajectory: &Trajectory) -> Vec<plot::Panel> {
    let model = &session.model;
    let (coordinates, outputs) = (coordinate_names(model), output_names(model));
    let units = |name: &str| session.coordinate_units(name).unwrap_or_default();
    let mut panels: Vec<(PanelKey, Vec<plot::Series>)> = Vec::new();
    let mut add = |key: PanelKey, name: String, values| {
        let series = plot::Series { name, values };
        match panels.iter_mut().find(|(k, _)| *k == key) {
            Some((_, list)) => list.push(series),
            None => panels.push((key, vec![series])),
        }
    };
    let column = |rows: &[Vec<f64>], i: usize| rows.iter().map(|row| row[i]).collect();
    for (i, name) in coordinates.iter().enumerate() {
        let unit = units(name).0;
        add(
            ("coordinates", "q", Some(unit)),
            format!("q_{name}"),
            column(&trajectory.q, i),
        );
    }
    for (i, name) in speed_names(model).iter().enumerate() {
        let unit = session.speed_unit(name);
        add(
            ("speeds", "u", Some(unit)),
            format!("u_{name}"),
            column(&trajectory.u, i),
        );
    }
    for (i, name) in outputs.iter().enumerate() {
        let unit = session.output_unit(name);
        add(
            ("outputs", "y", unit),
            name.clone(),
            column(&trajectory.outputs, i),
        );
    }
    panels
        .into_iter()
        .map(|((title, symbol, unit), series)| match unit {
            Some(unit) => plot::Panel {
                title: format!("{title} [{unit}]"),
                y_label: format!("{symbol} [{unit}]"),
                series,
            },
            None => plot::Panel {
                title: format!("{title} (expressions: unit not declared)"),
                y_label: symbol.to_string(),
                series,
            },
        })
        .collect()
}
