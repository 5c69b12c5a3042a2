//! Simulation tests with hand-written models.

use mech_runtime::{
    accelerations, default_signals, simulate, Method, Model, ModelOde, RuntimeError, Signal,
    SimOptions, Trajectory,
};
use std::f64::consts::{PI, TAU};

mod common;
use common::model_metadata;

/// Planar pendulum: q = angle from the downward vertical, M = m l², F = −m g l sin q.
/// Input 0 is a torque at the pivot (default 0). Outputs: kinetic + potential energy, and the
/// applied torque.
struct Pendulum {
    m: f64,
    l: f64,
    g: f64,
}

impl Pendulum {
    fn energy(&self, q: f64, u: f64) -> f64 {
        0.5 * self.m * self.l * self.l * u * u + self.m * self.g * self.l * (1.0 - q.cos())
    }
}

impl Model for Pendulum {
    model_metadata! {
        name: "pendulum",
        coordinates: ["theta"],
        initial_q: [0.1],
        inputs: ["torque"],
        outputs: ["energy", "torque"],
        params: [m, l, g],
    }
    fn mass_matrix(&self, _t: f64, _q: &[f64], _inputs: &[f64], out: &mut [f64]) {
        out[0] = self.m * self.l * self.l;
    }
    fn forcing(&self, _t: f64, q: &[f64], _u: &[f64], inputs: &[f64], out: &mut [f64]) {
        out[0] = -self.m * self.g * self.l * q[0].sin() + inputs[0];
    }
    fn outputs(&self, _t: f64, q: &[f64], u: &[f64], inputs: &[f64], out: &mut [f64]) {
        out[0] = self.energy(q[0], u[0]);
        out[1] = inputs[0];
    }
}

const PENDULUM: Pendulum = Pendulum {
    m: 0.3,
    l: 0.7,
    g: 9.81,
};

fn dopri(rtol: f64, atol: f64) -> Method {
    Method::Dopri5 {
        rtol,
        atol,
        h_max: f64::INFINITY,
    }
}

fn no_progress() -> impl FnMut(f64) {
    |_| {}
}

/// Zero crossings (downward or upward) of q, located on the cubic Hermite interpolant of the
/// samples (q and q̇ = u at both ends; 4th-order accurate), by bisection.
fn zero_crossings(times: &[f64], q: &[f64], u: &[f64]) -> Vec<f64> {
    let mut roots = vec![];
    for k in 0..times.len() - 1 {
        if q[k] == 0.0 || q[k].signum() == q[k + 1].signum() {
            continue;
        }
        let h = times[k + 1] - times[k];
        let p = |s: f64| {
            let (s2, s3) = (s * s, s * s * s);
            (2.0 * s3 - 3.0 * s2 + 1.0) * q[k]
                + (s3 - 2.0 * s2 + s) * h * u[k]
                + (-2.0 * s3 + 3.0 * s2) * q[k + 1]
                + (s3 - s2) * h * u[k + 1]
        };
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if p(lo).signum() == p(mid).signum() {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        roots.push(times[k] + 0.5 * (lo + hi) * h);
    }
    roots
}

/// Exact period of a pendulum of amplitude θ0: 2π√(l/g) / AGM(1, cos(θ0/2)).
fn exact_period(p: &Pendulum, theta0: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (theta0 / 2.0).cos());
    for _ in 0..30 {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    TAU * (p.l / p.g).sqrt() / a
}

fn simulate_pendulum(theta0: f64, t_end: f64, method: Method) -> Trajectory {
    let options = SimOptions {
        t_end,
        output_interval: 1e-3,
        method,
        ..SimOptions::default()
    };
    simulate(
        &PENDULUM,
        &[theta0],
        &[0.0],
        &default_signals(&PENDULUM),
        &options,
        &mut no_progress(),
    )
    .unwrap()
}

/// PENDULUM released from rest at `theta0` under the pivot torque `torque`.
fn pendulum_from_rest(
    theta0: f64,
    torque: Signal,
    options: &SimOptions,
) -> Result<Trajectory, RuntimeError> {
    simulate(
        &PENDULUM,
        &[theta0],
        &[0.0],
        &[torque],
        options,
        &mut no_progress(),
    )
}

fn period_from(traj: &Trajectory) -> f64 {
    let q: Vec<f64> = traj.q.iter().map(|v| v[0]).collect();
    let u: Vec<f64> = traj.u.iter().map(|v| v[0]).collect();
    let roots = zero_crossings(&traj.times, &q, &u);
    assert!(roots.len() >= 4, "{roots:?}");
    // Crossings are half a period apart; average over the whole record.
    2.0 * (roots[roots.len() - 1] - roots[0]) / (roots.len() - 1) as f64
}

#[test]
fn pendulum_conserves_energy() {
    let theta0 = 1.0;
    let traj = simulate_pendulum(theta0, 10.0, dopri(1e-10, 1e-12));
    let e0 = PENDULUM.energy(theta0, 0.0);
    let drift = traj
        .outputs
        .iter()
        .map(|y| ((y[0] - e0) / e0).abs())
        .fold(0.0, f64::max);
    assert!(drift < 1e-8, "relative energy drift {drift:e}");
    // The energy output is computed from the sampled state: check one by hand.
    let k = 1234;
    assert_eq!(
        traj.outputs[k][0],
        PENDULUM.energy(traj.q[k][0], traj.u[k][0])
    );
}

#[test]
fn pendulum_small_angle_period() {
    let theta0 = 1e-3;
    let traj = simulate_pendulum(theta0, 10.0, dopri(1e-10, 1e-14));
    let small = TAU * (PENDULUM.l / PENDULUM.g).sqrt();
    let period = period_from(&traj);
    assert!(
        ((period - small) / small).abs() < 1e-6,
        "{period} vs {small}"
    );
}

#[test]
fn pendulum_large_angle_period_is_exact() {
    let theta0 = 2.0;
    let traj = simulate_pendulum(theta0, 10.0, dopri(1e-11, 1e-13));
    let exact = exact_period(&PENDULUM, theta0);
    let period = period_from(&traj);
    assert!(
        ((period - exact) / exact).abs() < 1e-9,
        "{period} vs {exact}"
    );
    // Far from the small-angle value, so the test tells them apart.
    let small = TAU * (PENDULUM.l / PENDULUM.g).sqrt();
    assert!(exact / small > 1.3);
}

#[test]
fn pendulum_with_rk4_agrees_with_dopri5() {
    let a = simulate_pendulum(1.0, 2.0, dopri(1e-11, 1e-13));
    let b = simulate_pendulum(1.0, 2.0, Method::Rk4 { step: 1e-3 });
    assert_eq!(a.times, b.times);
    let worst =
        a.q.iter()
            .zip(&b.q)
            .map(|(x, y)| (x[0] - y[0]).abs())
            .fold(0.0, f64::max);
    assert!(worst < 1e-10, "{worst:e}");
    assert_eq!(b.stats.rejected_steps, 0);
    assert_eq!(b.stats.accepted_steps, 2000);
}

#[test]
fn output_grid_and_progress() {
    let mut calls = vec![];
    let options = SimOptions {
        t_start: 1.0,
        t_end: 2.0,
        output_interval: 0.3,
        ..SimOptions::default()
    };
    let traj = simulate(
        &PENDULUM,
        &[0.5],
        &[0.0],
        &[Signal::Constant(0.0)],
        &options,
        &mut |t| calls.push(t),
    )
    .unwrap();
    let mut expected: Vec<f64> = (0..4).map(|k| 1.0 + k as f64 * 0.3).collect();
    expected.push(2.0);
    assert_eq!(traj.times, expected);
    assert_eq!(traj.len(), 5);
    assert_eq!((traj.q.len(), traj.u.len()), (5, 5));
    assert_eq!((traj.outputs.len(), traj.inputs.len()), (5, 5));
    assert_eq!(traj.q[0], vec![0.5]);
    assert_eq!(calls.len(), traj.stats.accepted_steps);
    assert_eq!(*calls.last().unwrap(), 2.0);
    assert!(calls.windows(2).all(|w| w[0] < w[1]));
    // The grid does not restrict the steps: a smooth problem takes fewer steps than samples
    // when the grid is fine.
    let fine = SimOptions {
        output_interval: 1e-4,
        method: dopri(1e-6, 1e-8),
        ..options
    };
    let traj = pendulum_from_rest(0.5, Signal::Constant(0.0), &fine).unwrap();
    assert_eq!(traj.len(), 10_001);
    assert_eq!(*traj.times.last().unwrap(), 2.0);
    assert!(traj.stats.accepted_steps < 200, "{:?}", traj.stats);

    // Exact multiples end on t_end without a duplicate.
    let options = SimOptions {
        t_end: 1.0,
        output_interval: 0.25,
        ..SimOptions::default()
    };
    let traj = pendulum_from_rest(0.5, Signal::Constant(0.0), &options).unwrap();
    assert_eq!(traj.times, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
}

/// A free mass driven by a force input: M = m, F = input. From rest under
/// `A sin(2π f t)`, u(t) = A/(m·2πf)·(1 − cos 2πft) and q(t) = A/(m·2πf)·(t − sin(2πft)/(2πf)).
struct ForcedMass {
    m: f64,
}

impl Model for ForcedMass {
    model_metadata! {
        name: "forced_mass",
        coordinates: ["x"],
        initial_q: [0.0],
        inputs: ["force"],
        outputs: ["momentum"],
        params: [m],
    }
    fn mass_matrix(&self, _t: f64, _q: &[f64], _inputs: &[f64], out: &mut [f64]) {
        out[0] = self.m;
    }
    fn forcing(&self, _t: f64, _q: &[f64], _u: &[f64], inputs: &[f64], out: &mut [f64]) {
        out[0] = inputs[0];
    }
    fn outputs(&self, _t: f64, _q: &[f64], u: &[f64], _inputs: &[f64], out: &mut [f64]) {
        out[0] = self.m * u[0];
    }
}

#[test]
fn inputs_drive_the_model_and_are_recorded() {
    let model = ForcedMass { m: 2.0 };
    let (a, f) = (3.0, 1.5);
    let signal = Signal::Sine {
        amplitude: a,
        frequency_hz: f,
        phase_rad: 0.0,
        offset: 0.0,
    };
    let options = SimOptions {
        t_end: 2.0,
        output_interval: 0.01,
        method: dopri(1e-10, 1e-12),
        ..SimOptions::default()
    };
    let signals = [signal.clone()];
    let traj = simulate(
        &model,
        &[0.0],
        &[0.0],
        &signals,
        &options,
        &mut no_progress(),
    )
    .unwrap();
    let w = TAU * f;
    for (k, &t) in traj.times.iter().enumerate() {
        let u = a / (model.m * w) * (1.0 - (w * t).cos());
        let q = a / (model.m * w) * (t - (w * t).sin() / w);
        assert!((traj.u[k][0] - u).abs() < 1e-9, "t = {t}");
        assert!((traj.q[k][0] - q).abs() < 1e-9, "t = {t}");
        assert_eq!(traj.inputs[k], vec![signal.value(t)]);
        assert_eq!(traj.outputs[k], vec![model.m * traj.u[k][0]]);
    }
}

/// Two coordinates with a configurable constant 2×2 mass matrix (column-major) and
/// F = (1, 2).
struct TwoDof {
    mass: [f64; 4],
}

impl Model for TwoDof {
    model_metadata! {
        name: "two_dof",
        coordinates: ["a", "b"],
        initial_q: [0.0, 0.0],
        inputs: [],
        outputs: [],
        params: [],
    }
    fn mass_matrix(&self, _t: f64, _q: &[f64], _inputs: &[f64], out: &mut [f64]) {
        out.copy_from_slice(&self.mass);
    }
    fn forcing(&self, _t: f64, _q: &[f64], _u: &[f64], _inputs: &[f64], out: &mut [f64]) {
        out.copy_from_slice(&[1.0, 2.0]);
    }
    fn outputs(&self, _t: f64, _q: &[f64], _u: &[f64], _inputs: &[f64], _out: &mut [f64]) {}
}

/// The name lookups of [`Model`] (`coordinate_index` and the like), found and not found.
#[test]
fn every_kind_of_name_is_looked_up() {
    let two_dof = TwoDof { mass: [0.0; 4] };
    assert_eq!(two_dof.coordinate_index("a"), Some(0));
    assert_eq!(two_dof.coordinate_index("b"), Some(1));
    assert_eq!(PENDULUM.coordinate_index("phi"), None);
    assert_eq!(PENDULUM.param_index("l"), Some(1));
    assert_eq!(PENDULUM.input_index("torque"), Some(0));
    assert_eq!(PENDULUM.output_index("torque"), Some(1));
    assert_eq!(PENDULUM.output_index("m"), None);
}

fn udot_of(mass: [f64; 4]) -> Result<[f64; 2], RuntimeError> {
    let mut udot = [0.0; 2];
    accelerations(&TwoDof { mass }, 0.0, &[0.0; 2], &[0.0; 2], &[], &mut udot)?;
    Ok(udot)
}

#[test]
fn accelerations_solve_the_mass_matrix() {
    // SPD: [[2, 1], [1, 3]] u̇ = (1, 2) → u̇ = (1/5, 3/5) (Cholesky path).
    let u = udot_of([2.0, 1.0, 1.0, 3.0]).unwrap();
    assert!(
        (u[0] - 0.2).abs() < 1e-15 && (u[1] - 0.6).abs() < 1e-15,
        "{u:?}"
    );
    // Symmetric indefinite: [[0, 1], [1, 0]] → u̇ = (2, 1) (LU fallback, needs pivoting).
    let u = udot_of([0.0, 1.0, 1.0, 0.0]).unwrap();
    assert_eq!(u, [2.0, 1.0]);
    // Not symmetric: column-major [[1, 2], [0, 1]] → u̇ = (1 − 2·2, 2) = (−3, 2). Cholesky reads
    // only the lower triangle, so this checks the symmetry test.
    let u = udot_of([1.0, 0.0, 2.0, 1.0]).unwrap();
    assert_eq!(u, [-3.0, 2.0]);
}

#[test]
fn singular_mass_matrix_is_reported() {
    for mass in [
        [1.0, 1.0, 1.0, 1.0],
        [0.0; 4],
        [1.0, 0.0, 0.0, 0.0],
        // Singular to working precision: rank one up to roundoff.
        [0.1, 0.3, 0.3, 0.9],
    ] {
        assert!(
            matches!(
                udot_of(mass),
                Err(RuntimeError::SingularMassMatrix { t: 0.0 })
            ),
            "{mass:?}: {:?}",
            udot_of(mass)
        );
        let model = TwoDof { mass };
        let result = simulate(
            &model,
            &[0.0; 2],
            &[0.0; 2],
            &[],
            &SimOptions::default(),
            &mut no_progress(),
        );
        assert!(
            matches!(result, Err(RuntimeError::SingularMassMatrix { .. })),
            "{result:?}"
        );
    }
}

#[test]
fn lengths_and_options_are_validated() {
    let sim = |q0: &[f64], u0: &[f64], signals: &[Signal], options: SimOptions| {
        simulate(&PENDULUM, q0, u0, signals, &options, &mut no_progress())
    };
    let one = [Signal::Constant(0.0)];
    let ok = SimOptions::default();
    assert!(matches!(
        sim(&[0.0, 1.0], &[0.0], &one, ok),
        Err(RuntimeError::LengthMismatch {
            what: "q0",
            expected: 1,
            found: 2
        })
    ));
    assert!(matches!(
        sim(&[0.0], &[], &one, ok),
        Err(RuntimeError::LengthMismatch { what: "u0", .. })
    ));
    assert!(matches!(
        sim(&[0.0], &[0.0], &[], ok),
        Err(RuntimeError::LengthMismatch {
            what: "signals",
            ..
        })
    ));
    let bad_table = [Signal::Chirp {
        amplitude: 1.0,
        f0_hz: 1.0,
        f1_hz: 2.0,
        duration: 0.0,
        offset: 0.0,
    }];
    assert!(matches!(
        sim(&[0.0], &[0.0], &bad_table, ok),
        Err(RuntimeError::InvalidSignal(_))
    ));
    for options in [
        SimOptions { t_end: -1.0, ..ok },
        SimOptions {
            output_interval: 0.0,
            ..ok
        },
        SimOptions {
            t_end: f64::NAN,
            ..ok
        },
        SimOptions {
            method: dopri(1e-8, -1.0),
            ..ok
        },
        SimOptions {
            method: Method::Rk4 { step: 0.0 },
            ..ok
        },
    ] {
        assert!(
            matches!(
                sim(&[0.0], &[0.0], &one, options),
                Err(RuntimeError::InvalidOptions(_))
            ),
            "{options:?}"
        );
    }
    // A zero-length simulation is one sample.
    let traj = sim(&[0.3], &[0.0], &one, SimOptions { t_end: 0.0, ..ok }).unwrap();
    assert_eq!(traj.times, vec![0.0]);
    assert_eq!(traj.q, vec![vec![0.3]]);
}

#[test]
fn step_budget_and_non_finite_states_are_errors() {
    let options = SimOptions {
        t_end: 100.0,
        max_steps: 50,
        ..SimOptions::default()
    };
    let result = pendulum_from_rest(1.0, Signal::Constant(0.0), &options);
    assert!(
        matches!(result, Err(RuntimeError::TooManySteps { steps: 50, .. })),
        "{result:?}"
    );
    let options = SimOptions {
        t_end: 100.0,
        max_steps: 50,
        method: Method::Rk4 { step: 0.01 },
        ..SimOptions::default()
    };
    let result = pendulum_from_rest(1.0, Signal::Constant(0.0), &options);
    assert!(
        matches!(result, Err(RuntimeError::TooManySteps { steps: 50, .. })),
        "{result:?}"
    );
    // A torque ramping to f64::MAX makes the accelerations overflow.
    let nan_after = Signal::table(vec![0.0, 0.5], vec![0.0, f64::MAX]).unwrap();
    let options = SimOptions {
        t_end: 1.0,
        ..SimOptions::default()
    };
    let result = pendulum_from_rest(1.0, nan_after, &options);
    assert!(
        matches!(
            result,
            Err(RuntimeError::NonFiniteState { .. } | RuntimeError::StepSizeUnderflow { .. })
        ),
        "{result:?}"
    );
}

#[test]
fn model_ode_exposes_accelerations_and_inputs() {
    let signals = [Signal::Constant(0.25)];
    let mut ode = ModelOde::new(&PENDULUM, &signals).unwrap();
    let mut inputs = [0.0];
    ode.inputs_at(3.0, &mut inputs);
    assert_eq!(inputs, [0.25]);
    let mut udot = [0.0];
    ode.accelerations(0.0, &[PI / 2.0], &[0.0], &inputs, &mut udot)
        .unwrap();
    let (m, l, g) = (PENDULUM.m, PENDULUM.l, PENDULUM.g);
    let expected = (-m * g * l + 0.25) / (m * l * l);
    assert!((udot[0] - expected).abs() < 1e-14);
    assert!(matches!(
        ode.accelerations(0.0, &[0.0, 1.0], &[0.0], &inputs, &mut udot),
        Err(RuntimeError::LengthMismatch { what: "q", .. })
    ));
}
