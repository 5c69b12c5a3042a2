//! Closed kinematic loops against closed forms and SymPy: the four-bar of
//! `tests/peers/sympy_fourbar.py`, the slider-crank, an over-constrained (redundant)
//! closure, `J` and `J̇u` against finite differences, and drift control over long runs.

use crate::common;

use common::Rng;
use mech_runtime::{
    assemble, assemble_speeds, mobility, AssemblyOptions, Method, Model, SimOptions, Trajectory,
};

/// The bundled models with constraint rows, by name.
fn models_with_loops() -> impl Iterator<Item = (&'static str, mech::tape_model::TapeModel)> {
    mech::models::NAMES
        .iter()
        .map(|&name| (name, common::tape(name)))
        .filter(|(_, model)| model.nc() > 0)
}

fn assembled(model: &dyn Model, fixed: &[usize]) -> (Vec<f64>, Vec<f64>) {
    let mut q = vec![0.0; model.nq()];
    let mut u = vec![0.0; model.nu()];
    model.initial_state(&mut q, &mut u);
    assemble(model, 0.0, &mut q, fixed, &AssemblyOptions::default()).unwrap();
    assemble_speeds(model, 0.0, &q, &mut u, fixed).unwrap();
    (q, u)
}

fn tight(t_end: f64, output_interval: f64) -> SimOptions {
    common::dopri5_options(t_end, output_interval, 1e-11, 1e-12)
}

/// Values printed by `tests/peers/sympy_fourbar.py` (its `x0`: SymPy KanesMethod with
/// dependent coordinates, fsolve at xtol 1e-14; the command is in tests/peers/README.md), for
/// q1 = 1 rad, u1 = 2 rad/s. Our coupler angle is relative to the crank, so its absolute angle
/// is q1 + q2.
#[test]
fn four_bar_assembly_matches_sympy() {
    let model = common::tape("four_bar");
    let (q, u) = assembled(&model, &[0]);
    let expected = [
        (q[0] + q[1], 0.475489408807),
        (q[2], 1.68958837975),
        (u[0] + u[1], -0.543165183136),
        (u[2], 0.534428998589),
    ];
    for (value, reference) in expected {
        assert!((value - reference).abs() < 2e-12, "{value} vs {reference}");
    }
    assert_eq!(
        mobility(&model, 0.0, &q).unwrap().to_string(),
        "3 coordinates, 2 constraint rows, rank 2: 1 degree of freedom"
    );
}

/// After 1 s of free motion the four-bar's q1 is SymPy's ([`SYMPY_FOUR_BAR_Q1_AT_1_S`]).
#[test]
fn four_bar_motion_matches_sympy_and_holds_the_loop() {
    for model in [
        Box::new(common::tape("four_bar")) as Box<dyn Model>,
        mech::models::compiled("four_bar").unwrap(),
    ] {
        four_bar_second_matches_sympy(model.as_ref(), tight(1.0, 0.01).method, 5e-9);
    }
}

/// q1(1 s) of the four-bar's free motion from SymPy's equations integrated by SciPy's DOP853
/// at rtol = atol = 1e-9 (`sim1s_DOP853.q1_final` of `tests/peers/sympy_fourbar.py`).
const SYMPY_FOUR_BAR_Q1_AT_1_S: f64 = 3.350095189957;

/// The bundled four-bar `model`'s free motion with `method` for 1 s (101 samples) from its
/// `q0`, `u0` assembled holding the crank; asserts that q1(1 s) is SymPy's to `tol`.
pub(crate) fn four_bar_second_matches_sympy(
    model: &dyn Model,
    method: Method,
    tol: f64,
) -> Trajectory {
    let (q, u) = assembled(model, &[0]);
    let options = SimOptions {
        t_end: 1.0,
        output_interval: 0.01,
        method,
        ..SimOptions::default()
    };
    let run = mech_runtime::simulate(model, &q, &u, &[], &options, &mut |_| {}).unwrap();
    let q1 = run.q.last().unwrap()[0];
    assert!(
        (q1 - SYMPY_FOUR_BAR_Q1_AT_1_S).abs() < tol,
        "q1(1 s) = {q1}"
    );
    run
}

/// The same motion with DOP853 at the peer's own tolerance (rtol = atol = 1e-9, the
/// projection after each step, 100 samples through the continuous extension): SciPy's DOP853
/// on SymPy's equations gives q1(1 s) = 3.350095189957 (`tests/peers/sympy_fourbar.py`), and both
/// integrate to 1e-9, so they agree to a few 1e-9; the loop holds at every sample.
#[test]
fn four_bar_dop853_at_the_peer_tolerance_matches_sympy() {
    let model = mech::models::compiled("four_bar").unwrap();
    let method = Method::Dop853 {
        rtol: 1e-9,
        atol: 1e-9,
        h_max: f64::INFINITY,
    };
    let run = four_bar_second_matches_sympy(model.as_ref(), method, 3e-9);
    let mut phi = vec![0.0; model.nc()];
    for q in &run.q {
        model.constraints(0.0, q, &mut phi);
        assert!(max_abs(&phi) < 1e-9, "|φ| = {:e}", max_abs(&phi));
    }
    assert_eq!(run.len(), 101);
}

fn max_abs(values: &[f64]) -> f64 {
    values.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// Ten seconds of free motion: energy conserved, `|φ|` and `|J u|` below 1e-9 at every sample.
#[test]
fn four_bar_conserves_energy_and_controls_drift_over_ten_seconds() {
    let model = mech::models::compiled("four_bar").unwrap();
    let (q, u) = assembled(model.as_ref(), &[0]);
    let run = mech_runtime::simulate(model.as_ref(), &q, &u, &[], &tight(10.0, 0.01), &mut |_| {})
        .unwrap();
    let (_, drift) = common::energy_drift(model.as_ref(), &run);
    assert!(drift < 1e-8, "relative energy drift {drift:e}");
    let (nc, nq) = (model.nc(), model.nq());
    for (q, u) in run.q.iter().zip(&run.u) {
        let mut phi = vec![0.0; nc];
        model.constraints(0.0, q, &mut phi);
        let mut j = vec![0.0; nc * nq];
        model.constraint_jacobian(0.0, q, &mut j);
        let ju: Vec<f64> = (0..nc)
            .map(|r| (0..nq).map(|c| j[r + nc * c] * u[c]).sum())
            .collect();
        assert!(
            max_abs(&phi) < 1e-9 && max_abs(&ju) < 1e-9,
            "|φ| = {:e}, |Ju| = {:e}",
            max_abs(&phi),
            max_abs(&ju)
        );
    }
}

/// Rocker and coupler angles from the circle-intersection solution, on the branch of the
/// reference assembly, against assembly by continuation over a full crank turn.
#[test]
fn four_bar_positions_match_the_closed_form_over_a_crank_turn() {
    let model = common::tape("four_bar");
    let (l0, l1, l2, l3) = (3.0_f64, 1.0_f64, 2.5_f64, 2.0_f64);
    let closed_form = |crank: f64, branch: f64| {
        let (ax, ay) = (l1 * crank.cos(), l1 * crank.sin());
        let (dx, dy) = (ax - l0, ay);
        let d = (dx * dx + dy * dy).sqrt();
        let beta = ((l3 * l3 + d * d - l2 * l2) / (2.0 * l3 * d)).acos();
        let rocker = dy.atan2(dx) + branch * beta;
        let (cx, cy) = (l0 + l3 * rocker.cos(), l3 * rocker.sin());
        (rocker, (cy - ay).atan2(cx - ax))
    };
    let wrap = |a: f64| {
        (a + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI
    };
    let (mut q, _) = assembled(&model, &[0]);
    let branch = [1.0, -1.0]
        .into_iter()
        .find(|&b| (wrap(closed_form(q[0], b).0 - q[2])).abs() < 1e-9)
        .expect("one branch matches");
    for step in 0..=72 {
        q[0] = 1.0 + step as f64 * std::f64::consts::TAU / 72.0;
        assemble(&model, 0.0, &mut q, &[0], &AssemblyOptions::default()).unwrap();
        let (rocker, coupler) = closed_form(q[0], branch);
        assert!(
            wrap(q[2] - rocker).abs() < 1e-10,
            "rocker at crank {}: {} vs {rocker}",
            q[0],
            q[2]
        );
        assert!(
            wrap(q[0] + q[1] - coupler).abs() < 1e-10,
            "coupler at crank {}",
            q[0]
        );
    }
}

/// x = r cos θ + √(L² − r² sin²θ) and its rate, over a crank turn.
#[test]
fn slider_crank_position_and_velocity_match_the_analytic_expressions() {
    let model = common::tape("slider_crank");
    let (r, rod) = (5e-3_f64, 15e-3_f64);
    let slide = model.output_index("slider_x").unwrap();
    let rate = model.output_index("slider_v").unwrap();
    let (mut q, mut u) = assembled(&model, &[0]);
    for step in 0..=48 {
        let theta = step as f64 * std::f64::consts::TAU / 48.0;
        let omega = 20.0;
        q[0] = theta;
        u[0] = omega;
        assemble(&model, 0.0, &mut q, &[0], &AssemblyOptions::default()).unwrap();
        assemble_speeds(&model, 0.0, &q, &mut u, &[0]).unwrap();
        let root = (rod * rod - r * r * theta.sin().powi(2)).sqrt();
        let x = r * theta.cos() + root;
        let v = -r * omega * theta.sin() - r * r * omega * theta.sin() * theta.cos() / root;
        let y = common::outputs(&model, &q, &u);
        // Assembly closes the loop to 1e-13 m.
        assert!(
            (y[slide] - x).abs() < 2e-13,
            "x at θ = {theta}: {} vs {x}",
            y[slide]
        );
        assert!(
            (y[rate] - v).abs() < 1e-12,
            "v at θ = {theta}: {} vs {v}",
            y[rate]
        );
    }
}

/// The four-bar closed by a revolute closure in 3D: 3 position rows + 2 axis-alignment rows,
/// of which only 2 are independent. The rank must be found, and the motion must be the same
/// as with the minimal (x, y) closure.
#[test]
fn redundant_closure_reports_mobility_and_simulates() {
    let source = common::bundled_source("four_bar");
    let redundant = source.replace(
        "loop tip = coincident(coupler, rocker) {",
        "loop tip = revolute(coupler, rocker) {\n    axis = z;",
    );
    let redundant = redundant.replace("    components = [x, y];\n", "");
    assert!(redundant.contains("revolute(coupler, rocker)"));
    let model = common::tape_from_text("four_bar_redundant", &redundant);
    let (q, u) = assembled(&model, &[0]);
    let report = mobility(&model, 0.0, &q).unwrap();
    assert_eq!(
        report.to_string(),
        "3 coordinates, 5 constraint rows, rank 2: 1 degree of freedom"
    );
    let run = mech_runtime::simulate(&model, &q, &u, &[], &tight(1.0, 0.01), &mut |_| {}).unwrap();
    let q1 = run.q.last().unwrap()[0];
    assert!(
        (q1 - SYMPY_FOUR_BAR_Q1_AT_1_S).abs() < 5e-9,
        "q1(1 s) = {q1}"
    );
}

/// `q + h W(q) v`: a straight step along the coordinates' rates for speeds `v` (`q + h v`
/// where `q̇ = u`).
fn step_along(model: &dyn Model, q: &[f64], v: &[f64], h: f64) -> Vec<f64> {
    let mut rates = vec![0.0; model.nq()];
    model.kinematic_rates(0.0, q, v, &mut rates);
    q.iter().zip(&rates).map(|(q, r)| q + h * r).collect()
}

/// `J` against central differences of `φ` along each speed's direction (`∂φ/∂q` where
/// `q̇ = u`, `∂φ/∂q W(q)` with a quaternion), and `J̇u` against central differences of `J u`
/// along `q̇ = W(q) u`, at random states (unit quaternions) of every bundled model with loops.
#[test]
fn jacobian_and_bias_match_finite_differences() {
    let mut rng = Rng::new(11);
    let mut checked = 0;
    for name in mech::models::NAMES {
        let model = common::tape(name);
        let (nq, nu, nc) = (model.nq(), model.nu(), model.nc());
        // Velocity rows have no `φ` to difference (tests/equations/rolling_disc.rs checks them).
        if nc == 0 || model.velocity_rows() > 0 {
            continue;
        }
        checked += 1;
        for _ in 0..5 {
            let mut q = rng.vector(nq, -1.0, 1.0);
            mech_runtime::normalize_quaternions(model.unit_quaternions(), &mut q);
            let u = rng.vector(nu, -1.0, 1.0);
            let mut j = vec![0.0; nc * nu];
            model.constraint_jacobian(0.0, &q, &mut j);
            let h = 1e-6;
            for c in 0..nu {
                let mut direction = vec![0.0; nu];
                direction[c] = 1.0;
                let plus = step_along(&model, &q, &direction, h);
                let minus = step_along(&model, &q, &direction, -h);
                let (mut phi_plus, mut phi_minus) = (vec![0.0; nc], vec![0.0; nc]);
                model.constraints(0.0, &plus, &mut phi_plus);
                model.constraints(0.0, &minus, &mut phi_minus);
                for r in 0..nc {
                    let fd = (phi_plus[r] - phi_minus[r]) / (2.0 * h);
                    assert!(
                        (fd - j[r + nc * c]).abs() < 1e-7,
                        "{name}: J[{r},{c}] = {} vs {fd}",
                        j[r + nc * c]
                    );
                }
            }
            let ju = |q: &[f64]| {
                let mut j = vec![0.0; nc * nu];
                model.constraint_jacobian(0.0, q, &mut j);
                (0..nc)
                    .map(|r| (0..nu).map(|c| j[r + nc * c] * u[c]).sum::<f64>())
                    .collect::<Vec<f64>>()
            };
            let ahead = step_along(&model, &q, &u, h);
            let behind = step_along(&model, &q, &u, -h);
            let (a, b) = (ju(&ahead), ju(&behind));
            let mut bias = vec![0.0; nc];
            model.constraint_bias(0.0, &q, &u, &mut bias);
            for r in 0..nc {
                let fd = (a[r] - b[r]) / (2.0 * h);
                assert!(
                    (fd - bias[r]).abs() < 1e-7,
                    "{name}: J̇u[{r}] = {} vs {fd}",
                    bias[r]
                );
            }
        }
    }
    assert!(checked >= 2, "expected bundled loop models");
}

/// A loop that cannot close names the row and the residual.
#[test]
fn impossible_assembly_is_a_clear_error() {
    let source = common::bundled_source("four_bar");
    let too_short = source.replace(
        "param coupler_length = 2.5 m;",
        "param coupler_length = 0.5 m;",
    );
    let model = common::tape_from_text("four_bar_open", &too_short);
    let mut q = vec![0.0; 3];
    let mut u = vec![0.0; 3];
    model.initial_state(&mut q, &mut u);
    let error = assemble(&model, 0.0, &mut q, &[0], &AssemblyOptions::default()).unwrap_err();
    let message = error.to_string();
    assert!(
        message.contains("cannot close the loops: row `tip."),
        "{message}"
    );
}

/// The spherical five-bar (five hinge axes through one point): 4 tree coordinates, 5 closure
/// rows of rank 2, so 2 degrees of freedom; undamped motion conserves energy and keeps the
/// loop closed, with no singular-matrix failure on the redundant rows.
#[test]
fn spherical_five_bar_mobility_and_motion() {
    let mut model = common::tape("spherical_five_bar");
    let damping = model.param_index("c").unwrap();
    model.set_param(damping, 0.0);
    let (q, u) = assembled(&model, &[0, 1]);
    assert_eq!(
        mobility(&model, 0.0, &q).unwrap().to_string(),
        "4 coordinates, 5 constraint rows, rank 2: 2 degrees of freedom"
    );
    let run = mech_runtime::simulate(&model, &q, &u, &[], &tight(0.5, 0.001), &mut |_| {}).unwrap();
    let (scale, drift) = common::energy_drift(&model, &run);
    assert!(scale > 0.0, "the five-bar should move");
    assert!(drift < 1e-8, "relative energy drift {drift:e}");
    for q in &run.q {
        let mut phi = vec![0.0; model.nc()];
        model.constraints(0.0, q, &mut phi);
        assert!(max_abs(&phi) < 1e-9, "|φ| = {:e}", max_abs(&phi));
    }
}

/// The constrained accelerations keep only the independent rows once a solve has found some
/// redundant (`ConstrainedSolver`'s row choice): at closed random states of every bundled
/// model with loops, a solver reused from state to state gives the `u̇` of a fresh one (which
/// solves with every row) to round-off, and `u̇` meets every row, `J u̇ = −J̇u`, also the rows
/// left out.
#[test]
fn accelerations_on_the_chosen_rows_meet_every_row() {
    let mut rng = Rng::new(23);
    let mut redundant = 0;
    for (name, model) in models_with_loops() {
        let (nu, nc) = (model.nu(), model.nc());
        let (q0, _) = assembled(&model, &[]);
        let mut reused = mech_runtime::ConstrainedSolver::for_model(&model);
        for _ in 0..4 {
            // A closed state near the assembly with consistent speeds.
            let mut q = q0.clone();
            let nudge = rng.vector(nu, -1e-3, 1e-3);
            q = step_along(&model, &q, &nudge, 1.0);
            mech_runtime::normalize_quaternions(model.unit_quaternions(), &mut q);
            assemble(&model, 0.0, &mut q, &[], &AssemblyOptions::default()).unwrap();
            let mut u = rng.vector(nu, -1.0, 1.0);
            let free = mech_runtime::constraints::choose_independent(
                &mech_runtime::constraints::jacobian(&model, 0.0, &q),
            );
            assemble_speeds(&model, 0.0, &q, &mut u, &free).unwrap();
            let inputs = rng.vector(model.ninputs(), -1.0, 1.0);
            let mut fresh_udot = vec![0.0; nu];
            mech_runtime::ConstrainedSolver::for_model(&model)
                .accelerations(&model, 0.0, &q, &u, &inputs, &mut fresh_udot)
                .unwrap();
            let mut udot = vec![0.0; nu];
            reused
                .accelerations(&model, 0.0, &q, &u, &inputs, &mut udot)
                .unwrap();
            let scale = max_abs(&fresh_udot).max(1.0);
            for (a, b) in udot.iter().zip(&fresh_udot) {
                assert!((a - b).abs() <= 1e-10 * scale, "{name}: u̇ {a} vs {b}");
            }
            let mut j = vec![0.0; nc * nu];
            model.constraint_jacobian(0.0, &q, &mut j);
            let mut bias = vec![0.0; nc];
            model.constraint_bias(0.0, &q, &u, &mut bias);
            for r in 0..nc {
                let row: f64 = (0..nu).map(|c| j[r + nc * c] * udot[c]).sum();
                let size = (0..nu)
                    .map(|c| (j[r + nc * c] * udot[c]).abs())
                    .sum::<f64>();
                assert!(
                    (row + bias[r]).abs() <= 1e-9 * size.max(bias[r].abs()).max(1.0),
                    "{name}: row {r}: J u̇ = {row:e}, −J̇u = {:e}",
                    -bias[r]
                );
            }
        }
        redundant += usize::from(mobility(&model, 0.0, &q0).unwrap().rank < nc);
    }
    assert!(
        redundant >= 2,
        "only {redundant} models with redundant rows"
    );
}

/// The drift projection on the rows a solve chose (`ConstrainedSolver::project` after
/// `accelerations`) against the same projection on every row (a fresh solver): from closed
/// states of every bundled model with loops, moved off the loops by 1e-7 along random speeds
/// and given speeds that break `J u = 0`, both close every row, `φ` and `J u`, to the
/// tolerance, and land on the same state: `u` to round-off (the kinetic-energy projection
/// onto `J`'s null space, which the chosen rows span), `q` to the square of the offset (both
/// Gauss–Newton steps are minimum-norm on the same row space). What it cannot see: a wrong
/// step on the chosen rows that leaves a row open is repaired by the fall-back to every row
/// (by design); the chosen rows' use shows in the time (docs/benchmarks.md §16), not here.
#[test]
fn projection_on_the_chosen_rows_is_the_projection_on_every_row() {
    let mut rng = Rng::new(29);
    let tolerance = 1e-12;
    for (name, model) in models_with_loops() {
        let (nu, nc) = (model.nu(), model.nc());
        let (q0, u0) = assembled(&model, &[]);
        let inputs = vec![0.0; model.ninputs()];
        let mut chosen = mech_runtime::ConstrainedSolver::for_model(&model);
        let mut udot = vec![0.0; nu];
        chosen
            .accelerations(&model, 0.0, &q0, &u0, &inputs, &mut udot)
            .unwrap();
        for _ in 0..3 {
            let offset = rng.vector(nu, -1e-7, 1e-7);
            let mut start_q = step_along(&model, &q0, &offset, 1.0);
            mech_runtime::normalize_quaternions(model.unit_quaternions(), &mut start_q);
            let start_u = rng.vector(nu, -1.0, 1.0);
            let project = |solver: &mut mech_runtime::ConstrainedSolver| {
                let (mut q, mut u) = (start_q.clone(), start_u.clone());
                let changed = solver
                    .project(&model, 0.0, &mut q, &mut u, &inputs, tolerance)
                    .unwrap();
                assert!(changed, "{name}: nothing projected");
                let mut phi = vec![0.0; nc];
                model.constraints(0.0, &q, &mut phi);
                let mut j = vec![0.0; nc * nu];
                model.constraint_jacobian(0.0, &q, &mut j);
                for (r, value) in phi.iter().enumerate().take(model.holonomic_rows()) {
                    assert!(value.abs() <= tolerance, "{name}: φ[{r}] = {value:e}");
                }
                for r in 0..nc {
                    let speed: f64 = (0..nu).map(|c| j[r + nc * c] * u[c]).sum();
                    assert!(speed.abs() <= 1e-12, "{name}: (J u)[{r}] = {speed:e}");
                }
                (q, u)
            };
            let (q_all, u_all) = project(&mut mech_runtime::ConstrainedSolver::for_model(&model));
            let (q_chosen, u_chosen) = project(&mut chosen);
            for (a, b) in u_chosen.iter().zip(&u_all) {
                assert!((a - b).abs() <= 1e-12, "{name}: u {a} vs {b}");
            }
            for (a, b) in q_chosen.iter().zip(&q_all) {
                assert!((a - b).abs() <= 1e-12, "{name}: q {a} vs {b}");
            }
        }
    }
}

/// A linearly implicit step's factorization from the `M` and `J` of the accelerations just
/// solved at the same point (`ConstrainedSolver::factor_shifted_from`, what the W-method's
/// first trial of a step uses) against evaluating them again (`factor_shifted`): at closed
/// random states of every bundled model with loops, with a random symmetric negative
/// semidefinite `D`, the two solve the shifted system to the same bits; and the reuse is
/// offered only at that very point, not after the solver has moved on (`project`) or at
/// another `q`.
#[test]
fn shifted_factors_from_the_last_evaluation_are_the_evaluated_ones() {
    let mut rng = Rng::new(31);
    for (name, model) in models_with_loops() {
        let nu = model.nu();
        let (q0, u0) = assembled(&model, &[]);
        let inputs = rng.vector(model.ninputs(), -1.0, 1.0);
        let mut evaluated = mech_runtime::ConstrainedSolver::for_model(&model);
        let mut udot = vec![0.0; nu];
        evaluated
            .accelerations(&model, 0.25, &q0, &u0, &inputs, &mut udot)
            .unwrap();
        assert!(evaluated.evaluated_at(0.25, &q0, &inputs), "{name}");
        assert!(!evaluated.evaluated_at(0.5, &q0, &inputs), "{name}");
        let mut moved = q0.clone();
        moved[0] += 1e-9;
        assert!(!evaluated.evaluated_at(0.25, &moved, &inputs), "{name}");
        // D = −G Gᵀ.
        let g = rng.vector(nu * nu, -1.0, 1.0);
        let mut damping = vec![0.0; nu * nu];
        for r in 0..nu {
            for c in 0..nu {
                damping[r + nu * c] = -(0..nu).map(|k| g[r + nu * k] * g[c + nu * k]).sum::<f64>();
            }
        }
        let gamma = 1e-3;
        let mut reused = mech_runtime::ConstrainedSolver::for_model(&model);
        assert!(
            reused.factor_shifted_from(&evaluated, gamma, &damping),
            "{name}"
        );
        let mut fresh = mech_runtime::ConstrainedSolver::for_model(&model);
        assert!(
            fresh.factor_shifted(&model, 0.25, &q0, &u0, &inputs, gamma, &damping),
            "{name}"
        );
        let rhs = rng.vector(nu, -1.0, 1.0);
        let (mut x_reused, mut x_fresh) = (rhs.clone(), rhs);
        reused.solve_shifted(&mut x_reused);
        fresh.solve_shifted(&mut x_fresh);
        for (a, b) in x_reused.iter().zip(&x_fresh) {
            assert_eq!(a.to_bits(), b.to_bits(), "{name}: {a} vs {b}");
        }
        let (mut q, mut u) = (q0.clone(), u0.clone());
        evaluated
            .project(&model, 0.25, &mut q, &mut u, &inputs, 1e-12)
            .unwrap();
        assert!(!evaluated.evaluated_at(0.25, &q0, &inputs), "{name}");
        assert!(
            !reused.factor_shifted_from(&evaluated, gamma, &damping),
            "{name}"
        );
    }
}
