//! Compliant unilateral contact (`contact`), against results mech did not compute:
//! - a block sliding down an inclined plane with regularized Coulomb friction: the distance
//!   at which its speed falls to `v_end`, against the exact distance of the regularized law
//!   (a quadrature written here) and against the Coulomb closed form
//!   `(v0² − v_end²) / (2 g (μ cosθ − sinθ))`, whose difference is the regularization's
//!   error, `≈ μ g cosθ v_s² ln(v0/v_end) / (2 a²)` to first order in `(v_s/v)²`;
//! - a ball meeting a plane without gravity: its coefficient of restitution against the exact
//!   Hunt–Crossley relation `c v_in − ln(1 + c v_in) = −c v_out − ln(1 − c v_out)`,
//!   `c = 3/2 α` (solved here by bisection), and with gravity against an RK4 integration of
//!   the 1-DOF contact ODE written here;
//! - energy: without damping and friction a bouncing ball keeps `ke + pe` (the contact's
//!   `k δ^(e+1)/(e+1)` is in `pe`); with them the loss of `ke + pe` equals the integral of the
//!   contact's `power` output (Simpson's rule here), and a sliding ball ends rolling at
//!   `5/7 v0`;
//! - the reaction: a ball hitting a plane on a free cart keeps the total momentum.
//!
//! Consumes: `models/contact_ball.mech` and model texts written here. Produces: tests only.

use crate::common;

use mech_runtime::{Model, Trajectory};

const G: f64 = 9.81;

/// DOP853 at `rtol` with `atol = 1e-13`, sampled every `dt` to `t_end`.
fn run(model: &dyn Model, q0: &[f64], u0: &[f64], t_end: f64, dt: f64, rtol: f64) -> Trajectory {
    let options = mech_runtime::SimOptions {
        t_end,
        output_interval: dt,
        method: mech_runtime::Method::Dop853 {
            rtol,
            atol: 1e-13,
            h_max: f64::INFINITY,
        },
        ..mech_runtime::SimOptions::default()
    };
    common::simulate_at_default_inputs(model, q0, u0, &options)
}

fn start(model: &dyn Model) -> (Vec<f64>, Vec<f64>) {
    let (mut q, mut u) = (vec![0.0; model.nq()], vec![0.0; model.nu()]);
    model.initial_state(&mut q, &mut u);
    (q, u)
}

fn column(model: &dyn Model, run: &Trajectory, name: &str) -> Vec<f64> {
    let index = model
        .output_index(name)
        .unwrap_or_else(|| panic!("no output {name}"));
    run.outputs.iter().map(|y| y[index]).collect()
}

/// A point block of mass 10 g on the plane `y = 0`, gravity tilted by `theta` so that +x is
/// downhill, starting at the static penetration with speed `v0` downhill.
fn incline(theta: f64, mu: f64, v0: f64, v_s: f64) -> String {
    let (gx, gy) = (G * theta.sin(), -G * theta.cos());
    let k = 1e5; // N/m
    let depth = 0.01 * G * theta.cos() / k;
    format!(
        "model incline;
gravity = [{gx} m/s^2, {gy} m/s^2, 0];
newtonian {{ point floor = [0, 0, 0]; }}
body carriage {{ mass = 0 kg; }}
body block {{ mass = 10 g; }}
joint x = slider(newtonian, carriage) {{ axis = x; u0 = {v0} m/s; }}
joint y = slider(carriage, block) {{ axis = y; q0 = {} m; }}
contact slide between block and newtonian.floor {{
    normal = y; stiffness = {k} N/m; damping = 0.5 s/m;
    friction = {mu}; transition_speed = {v_s} m/s;
}}
output c = contact(slide);
",
        -depth
    )
}

/// `∫ v dv / (a_μ φ(v) − a_g)` from `v_end` to `v0`, `φ = v/√(v² + v_s²)`: the distance the
/// regularized law needs (normal force `m g cosθ` throughout), by composite Simpson in `v`.
fn regularized_distance(theta: f64, mu: f64, v0: f64, v_end: f64, v_s: f64) -> f64 {
    let (a_mu, a_g) = (mu * G * theta.cos(), G * theta.sin());
    let f = |v: f64| v / (a_mu * v / (v * v + v_s * v_s).sqrt() - a_g);
    let n = 200_000;
    let h = (v0 - v_end) / n as f64;
    let inner: f64 = (1..n)
        .map(|i| f(v_end + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 })
        .sum();
    (f(v_end) + f(v0) + inner) * h / 3.0
}

/// The distance travelled when the speed first falls to `v_end`, interpolating `x` linearly
/// in `v` between the two samples around it.
fn distance_at_speed(run: &Trajectory, v_end: f64) -> f64 {
    let k = run
        .u
        .iter()
        .position(|u| u[0] < v_end)
        .expect("the block slows down to v_end");
    let (x0, x1, v0, v1) = (run.q[k - 1][0], run.q[k][0], run.u[k - 1][0], run.u[k][0]);
    x0 + (x1 - x0) * (v0 - v_end) / (v0 - v1)
}

/// The incline at θ = 20°, μ = 0.6 (> tan θ = 0.364), v0 = 0.5 m/s, to `v_end = 10 v_s`.
/// Measured (DOP853, rtol 1e-11): the simulated distance is within 4e-10 relative of the
/// regularized law's own at both `v_s`; it exceeds the Coulomb closed form by 9.416e-5 m of
/// 55.2 mm with `v_s = 1 cm/s` (first-order formula 9.402e-5 m) and by 3.629e-8 m of 57.4 mm
/// with `v_s = 0.1 mm/s` (formula 3.630e-8 m).
#[test]
fn block_on_an_incline_stops_at_the_coulomb_distance() {
    let (theta, mu, v0) = (20f64.to_radians(), 0.6, 0.5);
    let a = G * (mu * theta.cos() - theta.sin());
    for v_s in [1e-2, 1e-4] {
        let v_end = 10.0 * v_s;
        let model = common::tape_from_text("incline", &incline(theta, mu, v0, v_s));
        let (q0, u0) = start(&model);
        let t_stop = v0 / a;
        let trajectory = run(&model, &q0, &u0, 1.1 * t_stop, 1e-5, 1e-11);
        let simulated = distance_at_speed(&trajectory, v_end);
        let regularized = regularized_distance(theta, mu, v0, v_end, v_s);
        let coulomb = (v0 * v0 - v_end * v_end) / (2.0 * a);
        let first_order = mu * G * theta.cos() * v_s * v_s * (v0 / v_end).ln() / (2.0 * a * a);
        eprintln!(
            "v_s = {v_s}: simulated {simulated:.9e} m, regularized {regularized:.9e} m, \
             Coulomb {coulomb:.9e} m; excess {:.3e} (first-order {first_order:.3e})",
            simulated - coulomb
        );
        common::assert_close("distance against the regularized law", simulated, regularized, 1e-8, 0.0);
        // The regularization's error is the first-order formula to within its next term,
        // O((v_s/v_end)²) = 1% of it.
        let excess = simulated - coulomb;
        let allowed = 0.03 * first_order + 1e-8 * coulomb;
        assert!(
            (excess - first_order).abs() <= allowed,
            "regularization error {excess:e} against {first_order:e} (allowed {allowed:e})"
        );
    }
}
