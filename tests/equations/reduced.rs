//! The reduced (minimal-coordinate) dynamics and the simulations that use them: `z̈` against
//! the multiplier form of the constrained dynamics on every bundled model with loops, the
//! four-bar's motion against SymPy, and 1 s of the HAMR-VI leg under the paper's 1 Hz drive
//! with both Rosenbrock methods against DOP853 at a tight tolerance.

use crate::common;
use crate::loops::four_bar_second_matches_sympy;

use common::Rng;
use mech::experiments::leg::Leg;
use mech_runtime::constraints::choose_independent;
use mech_runtime::{
    assemble, AssemblyOptions, ConstrainedSolver, Method, Model, Reduced, Signal, SimOptions,
    Trajectory,
};

fn max_abs(values: &[f64]) -> f64 {
    values.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// `max |φ(q)|` and `max |J u|` of a full state.
fn residuals(model: &dyn Model, q: &[f64], u: &[f64]) -> (f64, f64) {
    let (nq, nc) = (model.nq(), model.nc());
    let mut phi = vec![0.0; nc];
    model.constraints(0.0, q, &mut phi);
    let mut jacobian = vec![0.0; nc * nq];
    model.constraint_jacobian(0.0, q, &mut jacobian);
    let ju: Vec<f64> = (0..nc)
        .map(|r| (0..nq).map(|c| jacobian[r + nc * c] * u[c]).sum())
        .collect();
    (max_abs(&phi), max_abs(&ju))
}

/// At random independent coordinates, rates and inputs of every bundled model with loops:
/// the reduced `z̈` equals `u̇` of the multiplier form on `z`, the state closes the loops to
/// the tolerance, and `J u = 0` to round-off.
#[test]
fn reduced_accelerations_match_the_multiplier_form() {
    let mut rng = Rng::new(7);
    let mut checked = 0;
    for name in mech::models::NAMES {
        let model = mech::models::compiled(name).unwrap();
        let (nq, nc) = (model.nq(), model.nc());
        // The reduced dynamics hold independent coordinates, which a quaternion has not, and
        // refuse velocity constraints.
        if nc == 0 || !model.rates_are_speeds() || model.velocity_rows() > 0 {
            continue;
        }
        let mut q = vec![0.0; nq];
        let mut u = vec![0.0; nq];
        model.initial_state(&mut q, &mut u);
        assemble(
            model.as_ref(),
            0.0,
            &mut q,
            &[],
            &AssemblyOptions::default(),
        )
        .unwrap();
        let mut jacobian = vec![0.0; nc * nq];
        model.constraint_jacobian(0.0, &q, &mut jacobian);
        let independent =
            choose_independent(&mech_runtime::nalgebra::DMatrix::from_vec(nc, nq, jacobian));
        let signals = mech_runtime::default_signals(model.as_ref());
        let mut reduced = Reduced::new(model.as_ref(), &signals, 0.0, &q, &independent, 1e-12)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let mut solver = ConstrainedSolver::new(nq, nq, nc);
        let nz = independent.len();
        let z0: Vec<f64> = independent.iter().map(|&i| q[i]).collect();
        for _ in 0..5 {
            // Small moves of z (each closure starts from the last; 0.1 mm or mrad, within the
            // range of the HAMR actuators), moderate rates.
            let z: Vec<f64> = z0.iter().map(|v| v + rng.uniform(-1e-4, 1e-4)).collect();
            let zdot = rng.vector(nz, -0.1, 0.1);
            let inputs = rng.vector(model.ninputs(), -1.0, 1.0);
            let mut zddot = vec![0.0; nz];
            reduced
                .accelerations(0.0, &z, &zdot, &inputs, &mut zddot)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            let (q, u) = (reduced.q().to_vec(), reduced.u().to_vec());
            let (phi, ju) = residuals(model.as_ref(), &q, &u);
            assert!(phi <= 1e-12, "{name}: |φ| = {phi:e}");
            assert!(ju <= 1e-12 * max_abs(&u).max(1.0), "{name}: |J u| = {ju:e}");
            for (k, &i) in independent.iter().enumerate() {
                assert_eq!((q[i], u[i]), (z[k], zdot[k]), "{name}: z and ż are kept");
            }
            let mut udot = vec![0.0; nq];
            solver
                .accelerations(model.as_ref(), 0.0, &q, &u, &inputs, &mut udot)
                .unwrap();
            let scale = max_abs(&udot).max(1.0);
            for (k, &i) in independent.iter().enumerate() {
                assert!(
                    (zddot[k] - udot[i]).abs() <= 1e-9 * scale,
                    "{name}: z̈ {} vs u̇ {} (scale {scale:e})",
                    zddot[k],
                    udot[i]
                );
            }
        }
        checked += 1;
    }
    assert!(checked >= 4, "only {checked} models with loops");
}

/// The four-bar's free motion (SymPy + SciPy DOP853 at 1e-9 give q1(1 s) = 3.350095189957,
/// `sim1s_DOP853.q1_final` of `tests/peers/sympy_fourbar.py`) with the exponential Rosenbrock
/// method through `simulate`, which picks the crank as the independent coordinate: the same
/// value, the loop closed at every sample.
#[test]
fn four_bar_reduced_motion_matches_sympy() {
    let model = mech::models::compiled("four_bar").unwrap();
    let method = Method::ExpRosenbrock {
        rtol: 1e-10,
        atol: 1e-10,
        h_max: f64::INFINITY,
    };
    let run = four_bar_second_matches_sympy(model.as_ref(), method, 5e-9);
    for (q, u) in run.q.iter().zip(&run.u) {
        let (phi, ju) = residuals(model.as_ref(), q, u);
        assert!(phi <= 1e-12 && ju <= 1e-11, "|φ| = {phi:e}, |J u| = {ju:e}");
    }
}

/// The HAMR-VI leg and the paper's quasi-static drive (both actuators ±225 V at 1 Hz, swing
/// 90° ahead), from the static equilibrium under the initial voltages, as
/// `examples/hamr_performance.rs` runs it.
struct Drive {
    leg: Leg,
    model: Box<dyn Model>,
    signals: Vec<Signal>,
    q0: Vec<f64>,
}

impl Drive {
    fn new() -> Drive {
        let leg = Leg::open(&common::hamr_vi_spec()).unwrap();
        let mut signals = leg.session.signals.clone();
        for (input, phase_rad) in [
            (leg.v_lift(), 0.0),
            (leg.v_swing(), std::f64::consts::FRAC_PI_2),
        ] {
            signals[input] = Signal::Sine {
                amplitude: 225.0,
                frequency_hz: 1.0,
                phase_rad,
                offset: 0.0,
            };
        }
        let start: Vec<f64> = signals.iter().map(|s| s.value(0.0)).collect();
        let q0 = leg.equilibrium(&leg.q0, &start, &[]).unwrap().q;
        Drive {
            model: mech::models::compiled("hamr_vi").unwrap(),
            leg,
            signals,
            q0,
        }
    }

    fn run(&self, method: Method) -> Trajectory {
        let options = SimOptions {
            t_end: 1.0,
            output_interval: 1e-3,
            method,
            ..SimOptions::default()
        };
        let u0 = vec![0.0; self.model.nu()];
        let model = self.model.as_ref();
        let independent = &self.leg.independent;
        let run = if method.is_reduced() {
            mech_runtime::simulate_reduced(
                model,
                &self.q0,
                &u0,
                independent,
                &self.signals,
                &options,
                &mut |_| {},
            )
        } else {
            mech_runtime::simulate(model, &self.q0, &u0, &self.signals, &options, &mut |_| {})
        };
        run.unwrap()
    }

    /// The largest foot distance between two runs over their common samples, m.
    fn foot_difference(&self, a: &Trajectory, b: &Trajectory) -> f64 {
        let mut worst: f64 = 0.0;
        for (ya, yb) in a.outputs.iter().zip(&b.outputs) {
            for &i in &self.leg.foot() {
                worst = worst.max((ya[i] - yb[i]).abs());
            }
        }
        worst
    }
}

/// 1 s of the leg: the exponential Rosenbrock method follows DOP853 at 1e-9 (the start
/// excites the 79 and 106 Hz modes by ~10 µm at the foot, decaying over ~0.5 s) to well below
/// a micrometre in an eighth of the steps; the L-stable Rosenbrock method gets within a
/// few µm only at a tolerance that makes it resolve that transient. Every sample of both
/// closes the loops to the constraint tolerance with `J u = 0`.
#[test]
fn hamr_leg_one_second_reduced_methods_match_dop853() {
    let drive = Drive::new();
    let reference = drive.run(Method::Dop853 {
        rtol: 1e-9,
        atol: 1e-12,
        h_max: f64::INFINITY,
    });
    let exp = drive.run(Method::ExpRosenbrock {
        rtol: 1e-3,
        atol: 1e-6,
        h_max: f64::INFINITY,
    });
    let rosenbrock = drive.run(Method::Rosenbrock {
        rtol: 1e-4,
        atol: 1e-7,
        h_max: f64::INFINITY,
    });
    let model = drive.model.as_ref();
    for (name, run, bound) in [("exprb43", &exp, 1e-6), ("ode23s", &rosenbrock, 3e-6)] {
        assert_eq!(run.len(), reference.len());
        let difference = drive.foot_difference(run, &reference);
        println!(
            "{name}: foot within {:.3} µm of DOP853 (rtol 1e-9, {} steps); {:?}",
            difference * 1e6,
            reference.stats.accepted_steps,
            run.stats
        );
        assert!(difference < bound, "{name}: {:.3} µm", difference * 1e6);
        for (q, u) in run.q.iter().zip(&run.u) {
            let (phi, ju) = residuals(model, q, u);
            assert!(phi <= 1e-12, "{name}: |φ| = {phi:e}");
            assert!(ju <= 1e-12 * max_abs(u), "{name}: |J u| = {ju:e}");
        }
    }
    assert!(exp.stats.accepted_steps * 5 < reference.stats.accepted_steps);
}
