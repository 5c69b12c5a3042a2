//! The HAMR leg's performance numbers of `docs/benchmarks.md` §9: derivation and generated
//! code size, one constrained `u̇`, 1 s of motion under the paper's 1 Hz drive with each
//! integrator (and its foot accuracy against DOP853 at rtol 1e-9), a 1–150 Hz chirp, and the
//! Bode computation, for both bundled legs.
//!
//! ```text
//! cargo run --release --example hamr_performance            # prints a Markdown table
//! ```
//!
//! The motion starts at rest in the static equilibrium under the drive's initial voltages (as
//! the paper's quasi-static experiments do); the lift drive starts at its steepest, which
//! excites the 80–110 Hz modes by ~10 µm at the foot, decaying over ~0.5 s. The Rosenbrock
//! methods integrate the reduced dynamics in the actuator coordinates. The reference foot is
//! compared with the quasi-static equilibrium at the same drive phase, a check that 1 Hz is
//! quasi-static for the model.

use std::hint::black_box;
use std::time::{Duration, Instant};

use mech::experiments::leg::Leg;
use mech_codegen::{Compiled, RustOptions};
use mech_runtime::{
    ConstrainedSolver, FlexureDamping, Method, Model, Signal, SimOptions, Trajectory,
};

mod common;

/// Median wall time of `work` over at least `min_runs` runs and at least `budget`.
fn median_time<T>(min_runs: usize, budget: Duration, mut work: impl FnMut() -> T) -> (f64, T) {
    let started = Instant::now();
    let mut times = Vec::new();
    let mut last = None;
    while times.len() < min_runs || started.elapsed() < budget {
        let t0 = Instant::now();
        last = Some(black_box(work()));
        times.push(t0.elapsed().as_secs_f64());
        if times.len() >= 10_000 {
            break;
        }
    }
    times.sort_by(f64::total_cmp);
    (times[times.len() / 2], last.expect("at least one run"))
}

fn seconds(s: f64) -> String {
    match s {
        s if s >= 1.0 => format!("{s:.2} s"),
        s if s >= 1e-3 => format!("{:.2} ms", s * 1e3),
        s if s >= 1e-6 => format!("{:.2} µs", s * 1e6),
        s => format!("{:.0} ns", s * 1e9),
    }
}

/// The paper's quasi-static drive: both actuators at ±225 V, 1 Hz, swing 90° ahead of lift.
fn drive(leg: &Leg, amplitude: f64) -> Vec<Signal> {
    let mut signals = leg.session.signals.clone();
    let sine = |phase_rad: f64| Signal::Sine {
        amplitude,
        frequency_hz: 1.0,
        phase_rad,
        offset: 0.0,
    };
    signals[leg.v_lift()] = sine(0.0);
    signals[leg.v_swing()] = sine(std::f64::consts::FRAC_PI_2);
    signals
}

/// From rest at `q0`; the Rosenbrock methods in the leg's independent coordinates (the
/// actuators).
fn simulate(
    model: &dyn Model,
    q0: &[f64],
    signals: &[Signal],
    t_end: f64,
    output_interval: f64,
    method: Method,
    leg: &Leg,
) -> Trajectory {
    let options = SimOptions {
        t_end,
        output_interval,
        method,
        ..SimOptions::default()
    };
    let u0 = vec![0.0; model.nu()];
    let run = if method.is_reduced() {
        let independent = &leg.independent;
        mech_runtime::simulate_reduced(model, q0, &u0, independent, signals, &options, &mut |_| {})
    } else {
        mech_runtime::simulate(model, q0, &u0, signals, &options, &mut |_| {})
    };
    run.unwrap_or_else(|e| panic!("{}: simulation failed: {e}", model.name()))
}

/// The largest foot distance of `run` from `reference` at the samples they share (the
/// reference's interval divides the run's), m.
fn foot_difference(leg: &Leg, run: &Trajectory, reference: &Trajectory) -> f64 {
    let every = ((run.times[1] - run.times[0]) / (reference.times[1] - reference.times[0])).round()
        as usize;
    let mut worst: f64 = 0.0;
    for (k, y) in run.outputs.iter().enumerate() {
        let r = &reference.outputs[k * every];
        assert!((run.times[k] - reference.times[k * every]).abs() < 1e-9);
        for &i in &leg.foot() {
            worst = worst.max((y[i] - r[i]).abs());
        }
    }
    worst
}

fn main() {
    let budget = Duration::from_millis(1500);
    println!("| measurement | HAMR-VI | HAMR-V2.0 |");
    println!("|---|---|---|");
    let mut rows: Vec<(String, Vec<String>)> = Vec::new();
    let mut row = |label: &str, value: String| {
        match rows.iter_mut().find(|(l, _)| l == label) {
            Some((_, values)) => values.push(value),
            None => rows.push((label.to_string(), vec![value])),
        };
    };
    for name in ["hamr_vi", "hamr_v2"] {
        let path = format!("{}/models/{name}.mech", env!("CARGO_MANIFEST_DIR"));
        let (derive, compiled) = median_time(5, budget, || {
            Compiled::from_path(&path).expect("the bundled model compiles")
        });
        let (emit, rust) = median_time(3, budget, || compiled.rust(&RustOptions::default()));
        let (tape_time, _) = median_time(3, budget, || compiled.tape());
        row("derivation (parse, lower, Kane, φ/J/J̇u)", seconds(derive));
        row("Rust emission (quote → prettyplease)", seconds(emit));
        row("tape construction", seconds(tape_time));
        row(
            "generated Rust: bytes / lines",
            format!("{} kB / {} lines", rust.len() / 1000, rust.lines().count()),
        );

        let leg = Leg::open(&common::leg_spec(name)).expect("the leg opens");
        let model = mech::models::compiled(name).expect("bundled");
        let amplitude = 225.0;
        let signals = drive(&leg, amplitude);
        let start_inputs: Vec<f64> = signals.iter().map(|s| s.value(0.0)).collect();
        let q0 = leg
            .equilibrium(&leg.q0, &start_inputs, &[])
            .expect("the starting equilibrium")
            .q;

        let mut solver = ConstrainedSolver::for_model(model.as_ref());
        let (u0, mut udot) = (vec![0.0; model.nu()], vec![0.0; model.nu()]);
        let (udot_time, _) = median_time(1000, Duration::from_millis(300), || {
            for _ in 0..100 {
                solver
                    .accelerations(
                        model.as_ref(),
                        0.0,
                        black_box(&q0),
                        &u0,
                        &start_inputs,
                        &mut udot,
                    )
                    .expect("u̇");
            }
        });
        row(
            "one constrained u̇ (generated Rust)",
            seconds(udot_time / 100.0),
        );

        // The reference for accuracy: DOP853 at a tight tolerance, 1 kHz samples.
        let tight = Method::Dop853 {
            rtol: 1e-9,
            atol: 1e-12,
            h_max: f64::INFINITY,
        };
        let reference = simulate(model.as_ref(), &q0, &signals, 1.0, 1e-3, tight, &leg);
        let (ode23s, exprb43) = (
            |rtol| Method::Rosenbrock {
                rtol,
                atol: 1e-6,
                h_max: f64::INFINITY,
            },
            |rtol| Method::ExpRosenbrock {
                rtol,
                atol: 1e-6,
                h_max: f64::INFINITY,
            },
        );
        let explicit = |dop853: bool| {
            let (rtol, atol, h_max) = (1e-6, 1e-9, f64::INFINITY);
            if dop853 {
                Method::Dop853 { rtol, atol, h_max }
            } else {
                Method::Dopri5 { rtol, atol, h_max }
            }
        };
        let motions = [
            ("DOPRI5 rtol 1e-6", explicit(false), 1e-3),
            ("DOP853 rtol 1e-6", explicit(true), 1e-3),
            ("Rosenbrock (ode23s) rtol 1e-3", ode23s(1e-3), 1e-3),
            ("exp. Rosenbrock (exprb43) rtol 1e-2", exprb43(1e-2), 1e-3),
            ("exp. Rosenbrock (exprb43) rtol 1e-2", exprb43(1e-2), 1e-2),
            ("exp. Rosenbrock (exprb43) rtol 3e-3", exprb43(3e-3), 1e-2),
            ("exp. Rosenbrock (exprb43) rtol 1e-3", exprb43(1e-3), 1e-2),
        ];
        // Quasi-static check: the equilibria at each quarter of the cycle, against which each
        // run's foot is compared (with the reference's, a check that 1 Hz is quasi-static).
        let mut quarters = Vec::new();
        let mut q_start = q0.clone();
        for k in 1..=4 {
            let t = 0.25 * k as f64;
            let inputs: Vec<f64> = signals.iter().map(|s| s.value(t)).collect();
            let q_static = leg
                .equilibrium(&q_start, &inputs, &[])
                .expect("a quasi-static equilibrium")
                .q;
            quarters.push((t, leg.foot_at(&q_static, &inputs)));
            q_start = q_static;
        }
        let quasi_static_difference = |run: &Trajectory| {
            let mut worst: f64 = 0.0;
            for &(t, foot) in &quarters {
                let k = run
                    .times
                    .iter()
                    .position(|&s| (s - t).abs() < 1e-9)
                    .expect("a sample at each quarter cycle");
                let simulated = leg.foot_at(&run.q[k], &run.inputs[k]);
                for (a, b) in simulated.iter().zip(foot) {
                    worst = worst.max((a - b).abs());
                }
            }
            worst
        };
        row(
            "DOP853 rtol 1e-9 (the reference): largest foot difference from quasi-static at the quarter cycles",
            format!("{:.2} µm", quasi_static_difference(&reference) * 1e6),
        );
        for (label, method, interval) in motions {
            let (wall, run) = median_time(3, budget, || {
                simulate(model.as_ref(), &q0, &signals, 1.0, interval, method, &leg)
            });
            let samples = if interval < 5e-3 { "1 kHz" } else { "100 Hz" };
            let jacobians = if run.stats.jacobian_evaluations > 0 {
                format!(", {} Jacobians", run.stats.jacobian_evaluations)
            } else {
                String::new()
            };
            let evaluations = if method.is_reduced() {
                "reduced z̈"
            } else {
                "u̇"
            };
            row(
                &format!("1 s at 1 Hz, 225 V, {label} ({samples} samples)"),
                format!(
                    "{} ({:.0}× real time; {} steps, {} {evaluations}{jacobians})",
                    seconds(wall),
                    1.0 / wall,
                    run.stats.accepted_steps + run.stats.rejected_steps,
                    run.stats.rhs_evaluations
                ),
            );
            row(
                &format!("… {label}, {samples}: largest foot difference from DOP853 rtol 1e-9; from quasi-static at the quarter cycles"),
                format!(
                    "{:.3} µm; {:.2} µm",
                    foot_difference(&leg, &run, &reference) * 1e6,
                    quasi_static_difference(&run) * 1e6
                ),
            );
        }
        let chirp_signals = {
            let mut s = leg.session.signals.clone();
            s[leg.v_lift()] = Signal::Chirp {
                amplitude: 2.0,
                f0_hz: 1.0,
                f1_hz: 150.0,
                duration: 2.0,
                offset: 0.0,
            };
            s
        };
        let rest_inputs = leg.inputs(0.0, 0.0);
        let rest = leg.equilibrium(&leg.q0, &rest_inputs, &[]).expect("rest").q;
        let chirp_method = Method::Dopri5 {
            rtol: 1e-7,
            atol: 1e-12,
            h_max: 1.0 / (20.0 * 150.0),
        };
        let (wall, run) = median_time(1, budget, || {
            simulate(
                model.as_ref(),
                &rest,
                &chirp_signals,
                2.0,
                1.0 / (20.0 * 150.0),
                chirp_method,
                &leg,
            )
        });
        row(
            "2 s chirp 1–150 Hz, 2 V, lift (as the Bode experiment)",
            format!(
                "{} ({:.0}× real time; {} u̇)",
                seconds(wall),
                2.0 / wall,
                run.stats.rhs_evaluations
            ),
        );

        let frequencies = mech::frequency::log_space(1.0, 150.0, 300);
        let (wall, _) = median_time(3, budget, || {
            let linear =
                mech_runtime::linearize(model.as_ref(), 0.0, &rest, &rest_inputs, &leg.independent)
                    .expect("linearization");
            let mut points = 0;
            for (input, output) in [
                (leg.v_lift(), leg.foot()[2]),
                (leg.v_swing(), leg.foot()[0]),
            ] {
                for damping in [FlexureDamping::Hysteretic, FlexureDamping::Viscous] {
                    points += mech::frequency::linear_response(
                        &linear,
                        input,
                        output,
                        &frequencies,
                        damping,
                    )
                    .expect("a regular linear model")
                    .len();
                }
            }
            points
        });
        row(
            "Bode: linearize + 2 channels × 2 loss models × 300 frequencies",
            seconds(wall),
        );
    }
    for (label, values) in rows {
        println!("| {label} | {} |", values.join(" | "));
    }
}
