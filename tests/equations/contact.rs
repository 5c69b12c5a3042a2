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
        let (q0, u0) = common::initial_state(&model);
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
        common::assert_close(
            "distance against the regularized law",
            simulated,
            regularized,
            1e-8,
            0.0,
        );
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

/// A 10 g ball of radius 10 mm on one vertical slider over the floor `y = 0`, `k δ₀ (δ/δ₀)^{3/2}`
/// with `k = 2e4 N/m` at `δ₀ = 0.1 mm`, damping `alpha`, gravity `g` down.
fn dropped_ball(alpha: f64, g: f64, y0: f64, v0: f64) -> String {
    format!(
        "model drop;
gravity = [0, {} m/s^2, 0];
newtonian {{ point floor = [0, 0, 0]; }}
body ball {{ mass = 10 g; }}
joint y = slider(newtonian, ball) {{ axis = y; q0 = {y0} m; u0 = {v0} m/s; }}
contact ground between ball and newtonian.floor {{
    normal = y; radius = 10 mm; stiffness = 2e4 N/m; reference_depth = 0.1 mm;
    damping = {alpha} s/m;
}}
output c = contact(ground);
output ke = kinetic_energy;
output pe = potential_energy;
",
        -g
    )
}

/// The rebound speed of the Hunt–Crossley law `m δ̈ = −k δ^e (1 + c δ̇)` without gravity, from
/// its first integral: `∫ v dv / (1 + c v) = −(k/m) ∫ δ^e dδ`, whose right side vanishes over
/// the whole impact, so `G(v_in) = G(−v_out)` with `G(v) = v/c − ln(1 + c v)/c²`: the root
/// `v_out ∈ (0, 1/c)` of `−c v_out − ln(1 − c v_out) = c v_in − ln(1 + c v_in)`, by bisection.
fn hunt_crossley_rebound(c: f64, v_in: f64) -> f64 {
    let target = c * v_in - (c * v_in).ln_1p();
    let (mut lo, mut hi) = (0.0, 1.0 / c);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if -c * mid - (-c * mid).ln_1p() < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Without gravity the rebound speed is exact: the coefficient of restitution `v_out/v_in`
/// against [`hunt_crossley_rebound`] (independent of `k`, `m` and the exponent) at three
/// impact speeds. Measured: e = 0.97087, 0.86934, 0.76800 at 0.1, 0.5, 1 m/s with
/// α = 0.3 s/m, the exact relation's to 2e-10 (the first-order `1 − α v_in` gives 0.97,
/// 0.85, 0.70).
#[test]
fn restitution_of_a_ball_matches_the_hunt_crossley_relation() {
    let alpha = 0.3;
    let c = 1.5 * alpha;
    for v_in in [0.1, 0.5, 1.0] {
        let model = common::tape_from_text("drop", &dropped_ball(alpha, 0.0, 0.011, -v_in));
        let (q0, u0) = common::initial_state(&model);
        // 1 mm of flight, the impact (≈ 1 ms) and flight again.
        let t_end = 2e-3 / v_in + 5e-3;
        let trajectory = run(&model, &q0, &u0, t_end, t_end / 100.0, 1e-12);
        let (y, v_out) = (
            trajectory.q.last().unwrap()[0],
            trajectory.u.last().unwrap()[0],
        );
        assert!(y > 0.010, "the ball has left the floor ({y} m)");
        let e = v_out / v_in;
        let expected = hunt_crossley_rebound(c, v_in) / v_in;
        eprintln!(
            "v_in = {v_in}: e = {e:.10} (exact relation {expected:.10}, first order {:.4})",
            1.0 - alpha * v_in
        );
        common::assert_close("coefficient of restitution", e, expected, 1e-9, 0.0);
    }
}

/// With gravity: the ball dropped from 12 mm, against an RK4 integration of
/// `ÿ = −g + f_n/m` written here (step 1 µs), over 0.15 s (three impacts): the heights agree
/// to 1e-9 m (measured 2.3e-11 m).
#[test]
fn a_dropped_ball_bounces_as_the_contact_ode_integrated_here() {
    let alpha = 0.3;
    let model = common::tape_from_text("drop", &dropped_ball(alpha, G, 0.012, 0.0));
    let (q0, u0) = common::initial_state(&model);
    let t_end = 0.15;
    let trajectory = run(&model, &q0, &u0, t_end, 1e-3, 1e-12);
    // k δ₀ (δ/δ₀)^{3/2} = k δ₀^{-1/2} δ^{3/2}.
    let k = 2e4 / 1e-4f64.sqrt();
    let accel = |y: f64, v: f64| {
        let delta = (0.010 - y).max(0.0);
        let f = (k * delta.powf(1.5) * (1.0 - 1.5 * alpha * v)).max(0.0);
        -G + f / 0.010
    };
    let h = 1e-6;
    let mut state = (0.012, 0.0);
    let mut worst = 0.0_f64;
    let mut touched = 0;
    for (k_sample, t) in trajectory.times.iter().enumerate() {
        let steps = (t / h).round() as usize
            - (trajectory.times[k_sample.saturating_sub(1)] / h).round() as usize;
        for _ in 0..steps {
            state = common::rk4_step(state, h, accel);
        }
        worst = worst.max((trajectory.q[k_sample][0] - state.0).abs());
        if state.0 < 0.010 {
            touched += 1;
        }
    }
    eprintln!("dropped ball: largest height difference {worst:e} m, {touched} samples in contact");
    assert!(touched > 0, "the ball reached the floor");
    assert!(worst < 1e-9, "heights differ by {worst:e} m");
}

/// Without damping and friction the contact is conservative: `ke + pe` (with the contact's
/// `k δ^(5/2)/(5/2)`) stays constant over bounces of the bundled ball, on both back ends.
/// Measured: 5 impacts in 0.3 s, drift 1.8e-11 of the largest kinetic energy at rtol 1e-13
/// (1.3e-9 at 1e-12, 8.9e-8 at 1e-10: the integrator's error, which the force's kink at
/// first touch (`δ^{3/2}`) keeps from shrinking faster).
#[test]
fn an_elastic_bouncing_ball_keeps_its_energy() {
    let tape = common::tape("contact_ball");
    let generated = mech::models::compiled("contact_ball").unwrap();
    for mut model in [Box::new(tape) as Box<dyn Model>, generated] {
        for name in ["alpha", "mu"] {
            let i = (0..model.nparams())
                .find(|&i| model.param_name(i) == name)
                .unwrap();
            model.set_param(i, 0.0);
        }
        let (q0, u0) = common::initial_state(model.as_ref());
        let trajectory = run(model.as_ref(), &q0, &u0, 0.3, 1e-4, 1e-13);
        let (scale, drift) = common::energy_drift(model.as_ref(), &trajectory);
        let penetration = column(model.as_ref(), &trajectory, "ground.penetration");
        let bounces = penetration
            .windows(2)
            .filter(|w| w[0] == 0.0 && w[1] > 0.0)
            .count();
        eprintln!(
            "{}: {bounces} impacts, energy drift {drift:e} of {scale:e} J",
            model.name()
        );
        assert!(bounces >= 2, "the ball bounced ({bounces})");
        assert!(drift < 1e-9, "energy drifts by {drift:e}");
    }
}

/// `∫ y dt` over the samples by Simpson's rule (an even number of equal intervals).
fn simpson(values: &[f64], dt: f64) -> Vec<f64> {
    let mut integral = vec![0.0; values.len()];
    for k in (2..values.len()).step_by(2) {
        integral[k] =
            integral[k - 2] + dt / 3.0 * (values[k - 2] + 4.0 * values[k - 1] + values[k]);
    }
    integral
}

/// With damping and friction the ball (thrown sliding, without spin) bounces, slides and ends
/// rolling: the loss of `ke + pe` equals the `ground.dissipated` output (integrated by the
/// simulation) at every sample, and the `ground.power` output summed here at every even one,
/// and the final speed is `5/7 v0` (the angular momentum about the contact line is kept by
/// forces through it), on both back ends. Measured: 3.98e-4 J lost; against `dissipated` the
/// balance closes to 1e-12 J, against Simpson's sum of `power` to 6.8e-11 J at 2.5 µs
/// samples (4.2e-9 J at 10 µs: Simpson's error, 62× smaller at 4× the rate); the ball rolls
/// at 0.7142857142857137 v0.
#[test]
fn a_damped_sliding_ball_loses_what_its_contact_dissipates_and_ends_rolling() {
    let tape = common::tape("contact_ball");
    let generated = mech::models::compiled("contact_ball").unwrap();
    for model in [&tape as &dyn Model, generated.as_ref()] {
        let (q0, u0) = common::initial_state(model);
        let dt = 2.5e-6;
        let trajectory = run(model, &q0, &u0, 0.4, dt, 1e-12);
        let energy: Vec<f64> = trajectory
            .outputs
            .iter()
            .map(|y| y[model.output_index("ke").unwrap()] + y[model.output_index("pe").unwrap()])
            .collect();
        let summed = simpson(&column(model, &trajectory, "ground.power"), dt);
        let integrated = column(model, &trajectory, "ground.dissipated");
        let (mut worst_summed, mut worst_integrated) = (0.0_f64, 0.0_f64);
        for k in 0..energy.len() {
            let lost = energy[0] - energy[k];
            worst_integrated = worst_integrated.max((lost - integrated[k]).abs());
            if k % 2 == 0 {
                worst_summed = worst_summed.max((lost - summed[k]).abs());
            }
        }
        let loss = energy[0] - energy[energy.len() - 1];
        eprintln!(
            "{}: lost {loss:e} J; balance off by {worst_integrated:e} J against `dissipated`, \
             {worst_summed:e} J against Simpson on `power`",
            model.name()
        );
        assert!(loss > 1e-4, "the contact dissipates ({loss:e} J)");
        assert!(
            worst_summed < 1e-6 * loss,
            "loss and summed power differ by {worst_summed:e} J"
        );
        assert!(
            worst_integrated < 1e-8 * loss,
            "loss and `dissipated` differ by {worst_integrated:e} J"
        );
        let (v0, v_end) = (u0[0], trajectory.u.last().unwrap()[0]);
        let (omega, r) = (trajectory.u.last().unwrap()[2], 0.010);
        eprintln!(
            "  final speed {v_end} m/s = {} v0, ω r = {}",
            v_end / v0,
            -omega * r
        );
        common::assert_close("rolling speed", v_end, 5.0 / 7.0 * v0, 1e-9, 0.0);
    }
}

/// The reaction acts on the plane's body: a ball thrown at a plane fixed in a free cart
/// (no gravity) keeps the total momentum, in both directions, through the impact.
#[test]
fn the_reaction_acts_on_the_planes_body() {
    let text = "model cart;
newtonian { point origin = [0, 0, 0]; }
body sled { mass = 0 kg; }
body cart { mass = 30 g; point face = [0, 0, 0]; }
body carriage { mass = 0 kg; }
body ball { mass = 10 g; inertia = [4e-7, 4e-7, 4e-7] * 1 kg*m^2; }
joint cx = slider(newtonian, sled) { axis = x; }
joint cy = slider(sled, cart) { axis = y; }
joint bx = slider(newtonian, carriage) { axis = x; u0 = 0.3 m/s; }
joint by = slider(carriage, ball) { axis = y; q0 = 12 mm; u0 = -0.5 m/s; }
contact hit between ball and cart.face {
    normal = y; radius = 10 mm; stiffness = 2e4 N/m; reference_depth = 0.1 mm;
    damping = 0.3 s/m; friction = 0.5; transition_speed = 1 mm/s;
}
";
    let model = common::tape_from_text("cart", text);
    let (q0, u0) = common::initial_state(&model);
    let trajectory = run(&model, &q0, &u0, 0.02, 1e-4, 1e-12);
    let momentum = |u: &[f64]| [0.030 * u[0] + 0.010 * u[2], 0.030 * u[1] + 0.010 * u[3]];
    let first = momentum(&trajectory.u[0]);
    let last = momentum(trajectory.u.last().unwrap());
    let cart = trajectory.u.last().unwrap()[1];
    eprintln!("momentum {first:?} → {last:?}; cart speed {cart}");
    assert!(cart < -1e-3, "the cart was pushed ({cart} m/s)");
    for i in 0..2 {
        assert!(
            (first[i] - last[i]).abs() < 1e-12,
            "momentum {i}: {first:?} → {last:?}"
        );
    }
}

/// The dissipated energy in minimal coordinates too (the Rosenbrock methods integrate the
/// reduced dynamics, whose full state the integral reads from `Reduced`): the loss of
/// `ke + pe` of the damped sliding ball equals `ground.dissipated` to the method's tolerance,
/// and the final value agrees with DOP853's. Measured (rtol 1e-8): 5.2e-6 relative of the
/// loss, 3.9e-6 of DOP853's value.
#[test]
fn the_dissipated_energy_is_integrated_in_reduced_coordinates() {
    let model = common::tape("contact_ball");
    let (q0, u0) = common::initial_state(&model);
    let options = mech_runtime::SimOptions {
        t_end: 0.4,
        output_interval: 1e-3,
        method: mech_runtime::Method::Rosenbrock {
            rtol: 1e-8,
            atol: 1e-12,
            h_max: f64::INFINITY,
        },
        ..mech_runtime::SimOptions::default()
    };
    let reduced = common::simulate_at_default_inputs(&model, &q0, &u0, &options);
    let reference = run(&model, &q0, &u0, 0.4, 1e-3, 1e-12);
    let energy = |run: &Trajectory, k: usize| {
        let y = &run.outputs[k];
        y[model.output_index("ke").unwrap()] + y[model.output_index("pe").unwrap()]
    };
    let dissipated = column(&model, &reduced, "ground.dissipated");
    let last = reduced.len() - 1;
    let loss = energy(&reduced, 0) - energy(&reduced, last);
    let expected = *column(&model, &reference, "ground.dissipated")
        .last()
        .unwrap();
    eprintln!(
        "Rosenbrock: loss {loss:e} J, dissipated {:e} J, DOP853 {expected:e} J",
        dissipated[last]
    );
    common::assert_close(
        "reduced loss against dissipated",
        dissipated[last],
        loss,
        1e-5,
        0.0,
    );
    common::assert_close(
        "reduced against DOP853",
        dissipated[last],
        expected,
        1e-5,
        0.0,
    );
}

/// The contact never pulls: at a penetration with the damping term larger than the elastic
/// one (separating at `u_y > 1/(3/2 α)`) the normal force is exactly 0 and `F` is gravity
/// alone; just below that speed it pushes; out of contact it is exactly 0 whatever the speed.
/// On both back ends.
#[test]
fn the_contact_never_pulls() {
    let tape = common::tape("contact_ball");
    let generated = mech::models::compiled("contact_ball").unwrap();
    let alpha = 0.3;
    let limit = 1.0 / (1.5 * alpha);
    for model in [&tape as &dyn Model, generated.as_ref()] {
        let (q_in, q_out) = ([0.0, 0.0099, 0.0], [0.0, 0.0101, 0.0]);
        let fast = [0.0, 1.01 * limit, 0.0];
        let slow = [0.0, 0.99 * limit, 0.0];
        assert_eq!(
            common::output(model, "ground.normal_force", &q_in, &fast),
            0.0
        );
        assert_eq!(common::forcing(model, &q_in, &fast)[1], -0.010 * G);
        assert!(common::output(model, "ground.normal_force", &q_in, &slow) > 0.0);
        for u in [fast, slow, [0.0, -limit, 0.0]] {
            assert_eq!(
                common::output(model, "ground.normal_force", &q_out, &u),
                0.0
            );
            assert_eq!(common::output(model, "ground.penetration", &q_out, &u), 0.0);
        }
        assert!((common::output(model, "ground.penetration", &q_in, &fast) - 1e-4).abs() < 1e-15);
    }
}

/// The contacts' damping `D` (`Model::contact_damping`, the stiff part of `∂F/∂u` that the
/// W-method takes implicitly) against central differences of `F` in `u`, on the incline's
/// block sliding and at rest: without Hunt–Crossley damping (α = 0, so that `f_n` does not
/// follow `u` and `D` is all of `∂F/∂u`, the block having no velocity terms in `M u̇ = F`) the
/// two agree to the differences' own error; with α = 0.5 s/m they differ by the term `D`
/// leaves out on purpose, `μ c (v_t/s) nᵀ` projected (`c = 3/2 α k δ`), which is checked
/// too; and the generated Rust's `D` is the tape's. Measured: 5e-8, 5e-9 and 3e-10 of `|D|`
/// in the three cases (the differences' own error).
#[test]
fn contact_damping_is_the_slope_of_the_contact_force() {
    let (theta, mu, v_s) = (20f64.to_radians(), 0.6, 1e-3);
    for (alpha, v0) in [(0.0, 0.5), (0.0, 3e-4), (0.5, 0.5)] {
        let text = incline(theta, mu, v0, v_s)
            .replace("damping = 0.5 s/m;", &format!("damping = {alpha} s/m;"));
        let model = common::tape_from_text("incline", &text);
        let (mut q, u) = common::initial_state(&model);
        // A moving penetration, so that the normal damping acts too.
        let mut u = u;
        u[1] = -1e-3;
        q[1] *= 1.5;
        let nu = model.nu();
        let mut damping = vec![0.0; nu * nu];
        assert!(model.contact_damping(0.0, &q, &u, &[], &mut damping));
        let scale = damping.iter().fold(0.0_f64, |m, d| m.max(d.abs()));
        let mut worst = 0.0_f64;
        // Rounding in the differences: a few ulps of |F| over the step.
        let mut noise = 0.0_f64;
        for s in 0..nu {
            let step = 1e-4 * (u[s].abs() + v_s);
            let mut forcing = [vec![0.0; nu], vec![0.0; nu]];
            for (sign, out) in [1.0, -1.0].into_iter().zip(forcing.iter_mut()) {
                let mut shifted = u.clone();
                shifted[s] += sign * step;
                model.forcing(0.0, &q, &shifted, &[], out);
            }
            let largest = forcing
                .iter()
                .flatten()
                .fold(0.0_f64, |m, f| m.max(f.abs()));
            noise = noise.max(8.0 * f64::EPSILON * largest / step);
            for r in 0..nu {
                let slope = (forcing[0][r] - forcing[1][r]) / (2.0 * step);
                // The left-out term: F = f·p with p = e_x, e_y; f_t,x = −μ f_n v_x/s and
                // ∂f_n/∂u_y = −c (n = +y, δ̇ = −u_y), so ∂F_x/∂u_y gains μ c v_x / s.
                let left_out = if (r, s) == (0, 1) {
                    let k = 1e5;
                    let c = 1.5 * alpha * k * (-q[1]);
                    mu * c * u[0] / (u[0] * u[0] + v_s * v_s).sqrt()
                } else {
                    0.0
                };
                worst = worst.max((slope - left_out - damping[r + nu * s]).abs());
            }
        }
        eprintln!(
            "α = {alpha}, v = {v0}: |D| {scale:e}, largest difference {worst:e} ({:e}), \
             rounding {noise:e}",
            worst / scale
        );
        assert!(
            worst < 1e-6 * scale + noise,
            "D against ∂F/∂u: {worst:e} of {scale:e}"
        );
    }
    // Both back ends emit it: the generated Rust of `contact_ball` against its tape, the
    // ball pressed into the floor, sliding and spinning.
    let tape = common::tape("contact_ball");
    let generated = mech::models::compiled("contact_ball").unwrap();
    let (mut q, mut u) = common::initial_state(&tape);
    q[1] = 0.0099;
    u.copy_from_slice(&[0.2, -0.05, 3.0]);
    let nu = tape.nu();
    let [mut from_tape, mut from_rust] = [vec![0.0; nu * nu], vec![0.0; nu * nu]];
    assert!(tape.contact_damping(0.0, &q, &u, &[], &mut from_tape));
    assert!(generated.contact_damping(0.0, &q, &u, &[], &mut from_rust));
    for (a, b) in from_tape.iter().zip(&from_rust) {
        common::assert_close("D, generated Rust against the tape", *b, *a, 1e-12, 1e-12);
    }
    assert!(from_tape.iter().any(|d| d.abs() > 1e-3), "{from_tape:?}");
}

/// The regularized friction on a block at rest on the incline is a damper of time constant
/// `τ = v_s / (μ g cos θ)` (18 µs with `v_s = 0.1 mm/s`): an explicit method's steps stay
/// below it for as long as the block creeps. The W-method (`Method::RosenbrockW`, implicit in
/// `Model::contact_damping`) steps past it: the block slides from 0.5 m/s, stops (the
/// distance at `v_end = 10 v_s` against the regularized law's, as in
/// [`block_on_an_incline_stops_at_the_coulomb_distance`]) and creeps at the speed where the
/// regularized friction balances gravity, `v = v_s tanθ / √(μ² − tan²θ)`, the closed form.
/// Measured (rtol 1e-8, 1.5 s): creep speed to 1e-10, distance to 3e-9; 607 trial steps
/// (2,404 evaluations of `u̇` and 607 factorizations) against DOPRI5's 10,770 (64,622
/// evaluations), which needs more steps for the 1.27 s of creep than the W-method for the
/// whole run.
#[test]
fn the_contact_implicit_method_steps_past_the_friction_time_constant() {
    let (theta, mu, v0, v_s) = (20f64.to_radians(), 0.6, 0.5, 1e-4);
    let model = common::tape_from_text("incline", &incline(theta, mu, v0, v_s));
    let (q0, u0) = common::initial_state(&model);
    let t_end = 1.5;
    let simulate = |method| {
        let options = mech_runtime::SimOptions {
            t_end,
            output_interval: 1e-5,
            method,
            ..mech_runtime::SimOptions::default()
        };
        common::simulate_at_default_inputs(&model, &q0, &u0, &options)
    };
    let (rtol, atol, h_max) = (1e-8, 1e-13, f64::INFINITY);
    let implicit = simulate(mech_runtime::Method::RosenbrockW { rtol, atol, h_max });
    let explicit = simulate(mech_runtime::Method::Dopri5 { rtol, atol, h_max });
    let creep = v_s * theta.tan() / (mu * mu - theta.tan().powi(2)).sqrt();
    let v_end = 10.0 * v_s;
    for (name, run) in [("W-method", &implicit), ("DOPRI5", &explicit)] {
        eprintln!(
            "{name}: {:?}; final speed {:.9e} (creep {creep:.9e}); distance at 10 v_s {:.9e} \
             (regularized {:.9e})",
            run.stats,
            run.u.last().unwrap()[0],
            distance_at_speed(run, v_end),
            regularized_distance(theta, mu, v0, v_end, v_s)
        );
    }
    common::assert_close(
        "creep speed",
        implicit.u.last().unwrap()[0],
        creep,
        1e-6,
        0.0,
    );
    common::assert_close(
        "distance against the regularized law",
        distance_at_speed(&implicit, v_end),
        regularized_distance(theta, mu, v0, v_end, v_s),
        1e-6,
        0.0,
    );
    // Work: evaluations of `u̇`, and the W-method's factorizations of `M − γD` (each one
    // evaluation of `M`, `J` and `D`).
    let work = |run: &Trajectory| run.stats.rhs_evaluations + run.stats.jacobian_evaluations;
    assert!(
        10 * work(&implicit) < work(&explicit),
        "the W-method's work {}, DOPRI5's {}",
        work(&implicit),
        work(&explicit)
    );
}
