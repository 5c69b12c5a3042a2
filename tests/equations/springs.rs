//! Point-to-point springs (`spring NAME between A and B { … }`) against equations written by
//! hand: the spring pendulum of `models/spring_pendulum.mech` as a mass on a spring in
//! Cartesian coordinates (`m ẍ = −T (x − x_A)/L`, `m ÿ = −T (y − y_A)/L − m g`,
//! `T = k (L − L0) + c L̇`): its accelerations `M⁻¹F` at random states, a DOPRI5 run of its
//! tape against a fixed-step RK4 of the hand-written equations, its energy (conserved without
//! damping, decreasing with it), its static forcing, a run against its Lagrangian integrated
//! by the SymPy cross-check script; and springs with both ends moving (two
//! sliders, two pendulums) against their hand-written forces, equal and opposite.
//!
//! Consumes: `models/spring_pendulum.mech` and model texts written here. Produces: tests only.

use crate::common;

use common::Rng;
use mech::tape_model::TapeModel;
use mech_runtime::Model;

fn param(model: &dyn Model, name: &str) -> f64 {
    model.param(model.param_index(name).unwrap())
}

/// The spring pendulum's parameters, read from the model (the equations are not).
struct Pendulum {
    m: f64,
    k: f64,
    rest: f64,
    c: f64,
    g: f64,
    anchor: [f64; 2],
}

impl Pendulum {
    fn of(model: &dyn Model) -> Pendulum {
        Pendulum {
            m: param(model, "m"),
            k: param(model, "k"),
            rest: param(model, "L0"),
            c: param(model, "c"),
            g: param(model, "g"),
            // `newtonian { point anchor = [5 mm, 10 mm, 0]; }`
            anchor: [0.005, 0.010],
        }
    }

    /// `(ẍ, ÿ)` of a mass on a spring–damper hung from the anchor, under gravity −g ŷ.
    fn acceleration(&self, [x, y, vx, vy]: [f64; 4]) -> [f64; 2] {
        let (dx, dy) = (x - self.anchor[0], y - self.anchor[1]);
        let length = dx.hypot(dy);
        let stretch_speed = (dx * vx + dy * vy) / length;
        let tension = self.k * (length - self.rest) + self.c * stretch_speed;
        [
            -tension * dx / length / self.m,
            -tension * dy / length / self.m - self.g,
        ]
    }

    fn derivative(&self, state: [f64; 4]) -> [f64; 4] {
        let [ax, ay] = self.acceleration(state);
        [state[2], state[3], ax, ay]
    }

    /// One classical Runge–Kutta step of the hand-written equations.
    fn rk4_step(&self, s: [f64; 4], h: f64) -> [f64; 4] {
        let along = |s: [f64; 4], d: [f64; 4], f: f64| std::array::from_fn(|i| s[i] + f * d[i]);
        let k1 = self.derivative(s);
        let k2 = self.derivative(along(s, k1, h / 2.0));
        let k3 = self.derivative(along(s, k2, h / 2.0));
        let k4 = self.derivative(along(s, k3, h));
        std::array::from_fn(|i| s[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
    }
}

#[test]
fn spring_pendulum_accelerations_match_the_cartesian_equations() {
    let model = common::tape("spring_pendulum");
    let pendulum = Pendulum::of(&model);
    let mut rng = Rng::new(15);
    let mut worst = 0.0_f64;
    for _ in 0..50 {
        let q = [rng.uniform(-0.1, 0.1), rng.uniform(-0.15, 0.05)];
        let u = [rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)];
        let derived = common::accelerations(&model, &q, &u);
        let expected = pendulum.acceleration([q[0], q[1], u[0], u[1]]);
        let scale = expected[0].abs().max(expected[1].abs());
        for i in 0..2 {
            let error = (derived[i] - expected[i]).abs() / scale;
            worst = worst.max(error);
            assert!(
                error <= 1e-10,
                "q = {q:?}, u = {u:?}: M⁻¹F[{i}] = {} vs {}",
                derived[i],
                expected[i]
            );
        }
    }
    eprintln!("spring pendulum M⁻¹F vs Cartesian equations: worst relative error {worst:.1e}");
}

#[test]
fn spring_pendulum_simulation_matches_rk4_of_the_cartesian_equations() {
    let model = common::tape("spring_pendulum");
    let pendulum = Pendulum::of(&model);
    let (mut q0, mut u0) = (vec![0.0; 2], vec![0.0; 2]);
    model.initial_state(&mut q0, &mut u0);
    u0[0] = 0.3; // a swing as well as a bounce
    let options = common::dopri5_options(1.0, 0.01, 1e-12, 1e-14);
    let run = common::simulate_at_default_inputs(&model, &q0, &u0, &options);

    // RK4 at 10 µs (ωh ≈ 4.5e-4 with ω = √(k/m) ≈ 45 rad/s): its error is far below 1e-7.
    let steps_per_sample = 1000;
    let h = 0.01 / steps_per_sample as f64;
    let mut state = [q0[0], q0[1], u0[0], u0[1]];
    let position_scale = run.q.iter().flatten().fold(0.0_f64, |s, x| s.max(x.abs()));
    let speed_scale = run.u.iter().flatten().fold(0.0_f64, |s, x| s.max(x.abs()));
    let mut worst = 0.0_f64;
    for (sample, &t) in run.times.iter().enumerate() {
        assert!((t - 0.01 * sample as f64).abs() < 1e-12, "sample times");
        let errors = [
            (run.q[sample][0] - state[0]).abs() / position_scale,
            (run.q[sample][1] - state[1]).abs() / position_scale,
            (run.u[sample][0] - state[2]).abs() / speed_scale,
            (run.u[sample][1] - state[3]).abs() / speed_scale,
        ];
        let error = errors.into_iter().fold(0.0_f64, f64::max);
        worst = worst.max(error);
        assert!(
            error <= 1e-7,
            "t = {t}: DOPRI5 q = {:?}, u = {:?}; RK4 {state:?}",
            run.q[sample],
            run.u[sample]
        );
        for _ in 0..steps_per_sample {
            state = pendulum.rk4_step(state, h);
        }
    }
    assert_eq!(run.times.len(), 101);
    eprintln!("spring pendulum DOPRI5 (tape) vs RK4 over 1 s: worst relative error {worst:.1e}");
}

/// The same pendulum against its Lagrangian in polar coordinates about the anchor, written
/// and integrated independently by `tests/peers/sympy_models.py` (SymPy, Lagrange's
/// equations with a Rayleigh function for the damper; mpmath's Taylor-series integrator at
/// 30 digits; fixture `models.spring_pendulum_lagrange`): the bob's position and velocity at
/// 0.25, 0.5, 1, 1.5 and 2 s from a start that swings and bounces. mech's DOPRI5 at rtol
/// 1e-12 is held to 1e-9 m and 1e-8 m/s (the bob moves ~0.1 m at ~1 m/s).
#[test]
fn spring_pendulum_follows_its_lagrangian_integrated_independently() {
    let fixture = common::sympy_fixture();
    let reference = &fixture["models"]["spring_pendulum_lagrange"];
    let model = common::tape("spring_pendulum");
    for name in ["m", "k", "L0", "c", "g"] {
        let value: f64 = reference["params"][name].as_str().unwrap().parse().unwrap();
        let relative = (param(&model, name) - value).abs() / value;
        assert!(relative < 1e-15, "{name}: model and fixture differ");
    }
    let start = &reference["start"];
    let (q0, u0) = (
        common::json_numbers(&start["q"]),
        common::json_numbers(&start["u"]),
    );
    let options = common::dopri5_options(2.0, 0.25, 1e-12, 1e-14);
    let run = common::simulate_at_default_inputs(&model, &q0, &u0, &options);
    let (mut worst_position, mut worst_speed) = (0.0_f64, 0.0_f64);
    for sample in reference["samples"].as_array().unwrap() {
        let t = sample["t"].as_f64().unwrap();
        let k = run
            .times
            .iter()
            .position(|&s| (s - t).abs() < 1e-12)
            .unwrap();
        for (axis, (q, u)) in common::json_numbers(&sample["q"])
            .into_iter()
            .zip(common::json_numbers(&sample["u"]))
            .enumerate()
        {
            worst_position = worst_position.max((run.q[k][axis] - q).abs());
            worst_speed = worst_speed.max((run.u[k][axis] - u).abs());
        }
    }
    eprintln!(
        "spring pendulum vs its Lagrangian (mpmath Taylor): |Δq| ≤ {worst_position:.1e} m, \
         |Δu| ≤ {worst_speed:.1e} m/s over 2 s"
    );
    assert!(worst_position < 1e-9 && worst_speed < 1e-8);
}

/// `kinetic_energy + potential_energy` at each sample of a 2 s run.
fn energies(model: &TapeModel) -> Vec<f64> {
    let (mut q0, mut u0) = (vec![0.0; 2], vec![0.0; 2]);
    model.initial_state(&mut q0, &mut u0);
    u0[0] = 0.3;
    let options = common::dopri5_options(2.0, 0.005, 1e-13, 1e-15);
    let run = common::simulate_at_default_inputs(model, &q0, &u0, &options);
    let (ke, pe) = (
        model.output_index("ke").unwrap(),
        model.output_index("pe").unwrap(),
    );
    run.outputs.iter().map(|y| y[ke] + y[pe]).collect()
}

#[test]
fn without_damping_the_energy_is_conserved_and_with_it_it_decreases() {
    let mut model = common::tape("spring_pendulum");
    model.set_param(model.param_index("c").unwrap(), 0.0);
    let conserved = energies(&model);
    let scale = conserved[0].abs();
    let drift = conserved
        .iter()
        .map(|e| (e - conserved[0]).abs() / scale)
        .fold(0.0_f64, f64::max);
    assert!(
        drift <= 1e-9,
        "relative energy drift {drift:.1e} without damping"
    );
    eprintln!("spring pendulum, c = 0: relative energy drift over 2 s {drift:.1e}");

    let damped = energies(&common::tape("spring_pendulum"));
    // dE/dt = −c L̇² ≤ 0: never up by more than the integration error.
    let rises = damped
        .windows(2)
        .map(|pair| (pair[1] - pair[0]) / scale)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        rises <= 1e-12,
        "energy rose by {rises:.1e} (relative) with damping"
    );
    let lost = (damped[0] - damped[damped.len() - 1]) / scale;
    assert!(
        lost > 1e-2,
        "damping dissipated only {lost:.1e} of the energy"
    );
    eprintln!("spring pendulum, c > 0: largest rise {rises:.1e}, lost {lost:.2} over 2 s");
}

#[test]
fn spring_pendulum_rests_where_the_spring_holds_the_weight() {
    let model = common::tape("spring_pendulum");
    let p = Pendulum::of(&model);
    let sag = p.rest + p.m * p.g / p.k;
    let q = [p.anchor[0], p.anchor[1] - sag];
    let inputs = common::default_inputs(&model);
    let mut at_rest = vec![0.0; 2];
    model.static_forcing(0.0, &q, &inputs, &mut at_rest);
    for (i, f) in at_rest.iter().enumerate() {
        assert!(
            f.abs() <= 1e-14,
            "static forcing[{i}] = {f} at the equilibrium"
        );
    }
    // Away from it the static forcing is the forcing at u = 0 (the damper drops out).
    let q = [0.02, -0.09];
    model.static_forcing(0.0, &q, &inputs, &mut at_rest);
    assert_eq!(at_rest, common::forcing(&model, &q, &[0.0, 0.0]));
}

/// Two carts on perpendicular rails (a along x, b along y through x = 30 mm), joined by a
/// spring between their origins; b also feels gravity.
const TWO_SLIDERS: &str = "
param ma = 30 g;
param mb = 20 g;
gravity = [0, -9.81 m/s^2, 0];
body a { mass = ma; }
body b { mass = mb; }
joint xa = slider(newtonian, a) { axis = x; }
joint yb = slider(newtonian, b) { axis = y; parent_point = [30 mm, 0, 0]; }
spring link between a and b { stiffness = 25 N/m; rest_length = 12 mm; damping = 0.04 N*s/m; }
";

#[test]
fn a_spring_between_two_sliders_pulls_both_ends_equally() {
    let model = common::tape_from_text("two_sliders", TWO_SLIDERS);
    let (ma, mb, k, rest, c, g) = (0.030, 0.020, 25.0, 0.012, 0.04, 9.81);
    let mut rng = Rng::new(16);
    let mut worst = 0.0_f64;
    for _ in 0..50 {
        let q = [rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05)];
        let u = [rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)];
        // d = r_b − r_a = (0.03 − xa, yb); T ê acts on a, −T ê on b.
        let d = [0.03 - q[0], q[1]];
        let length = d[0].hypot(d[1]);
        let e = [d[0] / length, d[1] / length];
        let stretch_speed = e[0] * (0.0 - u[0]) + e[1] * u[1];
        let tension = k * (length - rest) + c * stretch_speed;
        let expected = [tension * e[0] / ma, -tension * e[1] / mb - g];
        let derived = common::accelerations(&model, &q, &u);
        let scale = expected[0].abs().max(expected[1].abs());
        for i in 0..2 {
            let error = (derived[i] - expected[i]).abs() / scale;
            worst = worst.max(error);
            assert!(error <= 1e-10, "q = {q:?}: {derived:?} vs {expected:?}");
        }
    }
    eprintln!("two sliders: worst relative error {worst:.1e}");
}

/// Two pendulums hung side by side, a spring between points off their axes.
const TWO_PENDULUMS: &str = "
newtonian { point right = [40 mm, 5 mm, 0]; }
body a { mass = 10 g; com = [0, -15 mm, 0]; inertia = [5e-7, 5e-7, 1e-6] * 1 kg*m^2; point tip = [3 mm, -30 mm, 0]; }
body b { mass = 15 g; com = [0, -20 mm, 0]; inertia = [1e-6, 1e-6, 2e-6] * 1 kg*m^2; point tip = [-2 mm, -25 mm, 0]; }
joint qa = pin(newtonian, a) { axis = z; }
joint qb = pin(newtonian, b) { axis = z; parent_point = newtonian.right; }
gravity = [0, -9.81 m/s^2, 0];
output pe = potential_energy;
";

const PENDULUM_SPRING: &str =
    "spring link between a.tip and b.tip { stiffness = 30 N/m; rest_length = 20 mm; damping = 0.05 N*s/m; }";

#[test]
fn a_spring_between_two_pendulums_adds_its_hand_written_generalized_forces() {
    let with = common::tape_from_text("linked", &format!("{TWO_PENDULUMS}{PENDULUM_SPRING}"));
    let without = common::tape_from_text("free", TWO_PENDULUMS);
    let (k, rest, c) = (30.0, 0.020, 0.05);
    // A point p fixed in a body turned by θ about z from a pivot o: o + R(θ) p, and its
    // derivative along θ, R'(θ) p.
    let place = |o: [f64; 2], p: [f64; 2], theta: f64| {
        let (s, cs) = theta.sin_cos();
        let at = [o[0] + cs * p[0] - s * p[1], o[1] + s * p[0] + cs * p[1]];
        let along = [-s * p[0] - cs * p[1], cs * p[0] - s * p[1]];
        (at, along)
    };
    let mut rng = Rng::new(17);
    let mut worst = 0.0_f64;
    for _ in 0..50 {
        let q = [rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)];
        let u = [rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0)];
        let (ra, ta) = place([0.0, 0.0], [0.003, -0.030], q[0]);
        let (rb, tb) = place([0.040, 0.005], [-0.002, -0.025], q[1]);
        let d = [rb[0] - ra[0], rb[1] - ra[1]];
        let length = d[0].hypot(d[1]);
        let e = [d[0] / length, d[1] / length];
        let dot = |a: [f64; 2], b: [f64; 2]| a[0] * b[0] + a[1] * b[1];
        let stretch_speed = dot(e, tb) * u[1] - dot(e, ta) * u[0];
        let tension = k * (length - rest) + c * stretch_speed;
        // +T ê at a's tip, −T ê at b's tip.
        let expected = [tension * dot(e, ta), -tension * dot(e, tb)];
        let (f_with, f_without) = (
            common::forcing(&with, &q, &u),
            common::forcing(&without, &q, &u),
        );
        let scale = expected[0].abs().max(expected[1].abs());
        for i in 0..2 {
            let error = ((f_with[i] - f_without[i]) - expected[i]).abs() / scale;
            worst = worst.max(error);
            assert!(
                error <= 1e-10,
                "q = {q:?}: F[{i}] {f_with:?} − {f_without:?} vs {expected:?}"
            );
        }
        // The spring's energy ½ k (L − L0)² is in the potential energy output.
        let energy = |model: &TapeModel| common::output(model, "pe", &q, &u);
        let spring_energy = 0.5 * k * (length - rest).powi(2);
        common::assert_close(
            "spring energy",
            energy(&with) - energy(&without),
            spring_energy,
            1e-10,
            1e-12,
        );
    }
    eprintln!("two pendulums: worst relative error {worst:.1e}");
}
