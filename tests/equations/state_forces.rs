//! Forces that depend on the motion (`joint.q`, `joint.u`, `distance(A, B)`,
//! `distance_rate(A, B)` in `force`/`torque`) and point-to-point springs, against references
//! that mech did not compute:
//! - Andrews' squeezing mechanism (`models/andrews.mech`, its spring a native `spring`)
//!   against the IVP Test Set's reference solution at t = 0.03 s, on both back ends, and the
//!   work of its driving torque against the change of its kinetic plus potential energy;
//! - energy: an undamped spring system keeps `kinetic_energy + potential_energy` (an output
//!   combining them), a damped one loses exactly the damper's dissipated power `c L̇²`,
//!   integrated here by Simpson's rule (1e-9 of the loss);
//! - linearization: a mass on a rail held by a spring from above (`ω² = k (1 − L0/h) / m`,
//!   the geometric stiffness of the tension) and a force written as an expression
//!   (`−k x − k3 x³ − c u`: `K = k`, `C = c`), and the linearization of `state_forces`
//!   against central differences of `M⁻¹F` taken here.
//!
//! The SymPy cross-check of `models/state_forces.mech` is in `sympy_cross_check.rs`.
//!
//! Consumes: `models/andrews.mech`, `models/state_forces.mech` and model texts written here.
//! Produces: tests only.

use crate::common;

use mech::session::Session;
use mech_runtime::{Method, Model, SimOptions};

/// The Test Set's reference positions at t = 0.03 s (problem `andrews`, Mazzia & Magherini,
/// Test Set for IVP Solvers, release 2.4: β, Θ, γ, Φ, δ, Ω, ε).
const ANDREWS_REFERENCE: [(&str, f64); 7] = [
    ("beta", 0.1581077119629904e2),
    ("Theta", -0.1575637105984298e2),
    ("gamma", 0.4082224013073101e-1),
    ("Phi", -0.5347301163226948),
    ("delta", 0.5244099658805304),
    ("Omega", 0.5347301163226948),
    ("epsilon", 0.1048080741042263e1),
];

/// DOP853 at `rtol` with `atol = 1e-14`, sampled at `output_interval`.
fn dop853(t_end: f64, output_interval: f64, rtol: f64) -> SimOptions {
    SimOptions {
        t_end,
        output_interval,
        method: Method::Dop853 {
            rtol,
            atol: 1e-14,
            h_max: f64::INFINITY,
        },
        ..SimOptions::default()
    }
}

fn coordinate(model: &dyn Model, name: &str) -> usize {
    (0..model.nq())
        .find(|&i| model.coordinate_name(i) == name)
        .unwrap_or_else(|| panic!("no coordinate {name}"))
}

/// Both back ends of Andrews' mechanism, from the Test Set's consistent initial state (the
/// `q0` of the file, at rest), to 1e-8 rad of the reference positions (the bound).
/// Measured: 1.43e-9 rad on β ≈ 15.8 rad (7e-11 relative), 2.8e-10 relative on γ, the same
/// at rtol 1e-12, 1e-13 and 1e-14 (so it is the reference's own accuracy, not the
/// integrator's); and the torque's work `mom (β(t) − β(0))` equals the change of
/// `energy = ke + pe` (spring included) to 6e-13 J of 0.52 J.
#[test]
fn andrews_with_a_native_spring_matches_the_test_set() {
    let tape = common::tape("andrews");
    let generated = mech::models::compiled("andrews").unwrap();
    for model in [&tape as &dyn Model, generated.as_ref()] {
        let (q0, u0) = common::initial_state(model);
        let run = common::simulate_at_default_inputs(model, &q0, &u0, &dop853(0.03, 0.03, 1e-12));
        let last = run.q.last().unwrap();
        let worst = ANDREWS_REFERENCE
            .iter()
            .map(|(name, reference)| (last[coordinate(model, name)] - reference).abs())
            .fold(0.0_f64, f64::max);
        eprintln!("andrews: largest |q − q_ref| at 0.03 s {worst:.2e} rad");
        for (name, reference) in ANDREWS_REFERENCE {
            let error = (last[coordinate(model, name)] - reference).abs();
            assert!(
                error < 1e-8,
                "{name}: {} vs {reference}",
                last[coordinate(model, name)]
            );
        }
        let beta = coordinate(model, "beta");
        let torque = model.param(model.param_index("mom").unwrap());
        let work = torque * (last[beta] - q0[beta]);
        let energy = model.output_index("energy").unwrap();
        let gained = run.outputs.last().unwrap()[energy] - run.outputs[0][energy];
        eprintln!(
            "andrews: energy gained − work {:.2e} J of {work:.4} J",
            gained - work
        );
        assert!(
            (gained - work).abs() < 1e-9 * work,
            "energy gained {gained} J, work of the torque {work} J"
        );
    }
}

/// Two pendulums side by side under gravity, their tips joined by a spring with a rest
/// length (and optionally a damper), the rest written as outputs of the motion.
fn coupled_pendulums(damping: &str) -> String {
    format!(
        "
gravity = [0, -9.81 m/s^2, 0];
newtonian {{ point right = [60 mm, 0, 0]; }}
body left_arm {{ mass = 10 g; com = [0, -40 mm, 0]; inertia = [1e-6, 0, 1e-6] * 1 kg*m^2; point tip = [0, -50 mm, 0]; }}
body right_arm {{ mass = 15 g; com = [0, -45 mm, 0]; inertia = [1e-6, 0, 1e-6] * 1 kg*m^2; point tip = [0, -50 mm, 0]; }}
joint a = pin(newtonian, left_arm) {{ axis = z; q0 = 0.4 rad; }}
joint b = pin(newtonian, right_arm) {{ axis = z; parent_point = newtonian.right; q0 = -0.2 rad; }}
spring coupling between left_arm.tip and right_arm.tip {{ stiffness = 20 N/m; rest_length = 45 mm; {damping} }}
output ke = kinetic_energy;
output pe = potential_energy;
output energy = kinetic_energy + potential_energy;
output stretch_rate = distance_rate(left_arm.tip, right_arm.tip);
"
    )
}

/// Undamped: `energy` (one output combining both energies) stays at its start to 1e-10 of
/// the largest kinetic energy over 2 s.
#[test]
fn an_undamped_spring_system_keeps_its_energy() {
    let model = common::tape_from_text("coupled", &coupled_pendulums(""));
    let (q0, u0) = common::initial_state(&model);
    let run = common::simulate_at_default_inputs(&model, &q0, &u0, &dop853(2.0, 1e-3, 1e-12));
    let (scale, drift) = common::energy_drift(&model, &run);
    assert!(scale > 1e-4, "the pendulums move ({scale} J)");
    eprintln!("undamped: relative energy drift {drift:.2e} over 2 s");
    assert!(drift < 1e-10, "relative energy drift {drift:e}");
    let energy = model.output_index("energy").unwrap();
    let (ke, pe) = (
        model.output_index("ke").unwrap(),
        model.output_index("pe").unwrap(),
    );
    for y in &run.outputs {
        // The sum is simplified with the rest of the outputs: equal to round-off.
        let sum = y[ke] + y[pe];
        assert!((y[energy] - sum).abs() <= 1e-14 * (y[ke].abs() + y[pe].abs()));
    }
}

/// Damped: the energy lost from 0 to t equals `∫ c L̇² dt` (the damper's power, from the
/// `stretch_rate` output, by Simpson's rule on 0.1 ms samples) to 1e-9 of the loss (measured 3e-12).
#[test]
fn a_damped_spring_loses_exactly_the_dampers_dissipation() {
    let c = 0.05;
    let model = common::tape_from_text(
        "coupled_damped",
        &coupled_pendulums(&format!("damping = {c} N*s/m;")),
    );
    let (q0, u0) = common::initial_state(&model);
    let run = common::simulate_at_default_inputs(&model, &q0, &u0, &dop853(1.0, 1e-4, 1e-12));
    let energy = model.output_index("energy").unwrap();
    let rate = model.output_index("stretch_rate").unwrap();
    let power: Vec<f64> = run.outputs.iter().map(|y| c * y[rate] * y[rate]).collect();
    let h = run.times[1] - run.times[0];
    let intervals = power.len() - 1;
    assert_eq!(
        intervals % 2,
        0,
        "Simpson's rule needs an even number of intervals"
    );
    let dissipated: f64 = (0..intervals / 2)
        .map(|k| h / 3.0 * (power[2 * k] + 4.0 * power[2 * k + 1] + power[2 * k + 2]))
        .sum();
    let lost = run.outputs[0][energy] - run.outputs.last().unwrap()[energy];
    eprintln!(
        "damped: lost {lost:.6e} J, dissipated {dissipated:.6e} J, relative difference {:.2e}",
        (lost - dissipated) / lost
    );
    assert!(lost > 0.0 && dissipated > 1e-4, "lost {lost} J");
    assert!(
        (lost - dissipated).abs() < 1e-9 * lost,
        "lost {lost} J, dissipated {dissipated} J"
    );
}

fn session(name: &str, text: &str) -> Session {
    Session::from_compiled(common::compile_text(name, text), &[], &[]).unwrap()
}

/// A mass on a rail along x, hung from an anchor a height h above by a spring of rest length
/// L0 < h: at x = 0 the tension k (h − L0) pulls straight up, and a lateral step x tilts it
/// by x/h, so the rail stiffness is `k (1 − L0/h)` and `ω = √(k (1 − L0/h) / m)`.
#[test]
fn a_spring_across_a_rail_linearizes_to_its_geometric_stiffness() {
    let (m, k, h, rest): (f64, f64, f64, f64) = (0.02, 40.0, 0.05, 0.03);
    let text = format!(
        "
newtonian {{ point anchor = [0, {h} m, 0]; }}
body slider {{ mass = {m} kg; }}
joint x = slider(newtonian, slider) {{ axis = x; q0 = 1 mm; }}
spring hanger between newtonian.anchor and slider {{ stiffness = {k} N/m; rest_length = {rest} m; }}
"
    );
    let linear = session("rail", &text).linearization(&[], &[]).unwrap();
    let expected = (k * (1.0 - rest / h) / m).sqrt();
    let modes = linear.modes().unwrap();
    eprintln!(
        "rail: ω {} rad/s, closed form {expected} rad/s",
        modes[0].natural_frequency
    );
    assert!(
        (modes[0].natural_frequency - expected).abs() < 1e-8 * expected,
        "ω = {} rad/s, closed form {expected}",
        modes[0].natural_frequency
    );
}

/// A force written as an expression of the coordinate and speed, `−k x − k3 x³ − c u`,
/// linearizes about x = 0 to `K = k`, `C = c` (the cubic term has no slope there), and its
/// mode has `ω = √(k/m)`.
#[test]
fn a_force_of_the_state_linearizes_to_its_slopes() {
    let (m, k, c): (f64, f64, f64) = (0.05, 12.0, 0.03);
    let text = format!(
        "
param k3 = 4e5 N/m^3;
body cart {{ mass = {m} kg; }}
joint x = slider(newtonian, cart) {{ axis = x; q0 = 2 mm; }}
force restoring at cart = [-{k} N/m * x.q - k3 * x.q^3 - {c} N*s/m * x.u, 0, 0];
"
    );
    let linear = session("cubic", &text).linearization(&[], &[]).unwrap();
    assert!(linear.q[0].abs() < 1e-12, "equilibrium at {}", linear.q[0]);
    assert!((linear.stiffness[(0, 0)] - k).abs() < 1e-7 * k);
    assert!((linear.damping[(0, 0)] - c).abs() < 1e-7 * c);
    let omega = linear.modes().unwrap()[0].natural_frequency;
    assert!((omega - (k / m).sqrt()).abs() < 1e-8 * omega);
}

/// The linearization of `state_forces` about its equilibrium (`K = −M ∂f/∂q`,
/// `C = −M ∂f/∂u` with `f = M⁻¹F`) against five-point central differences of `M⁻¹F` taken
/// here at the same point: the forces of q, u and the distances enter both.
#[test]
fn the_linearization_takes_the_forces_of_the_state_into_account() {
    let session =
        Session::from_compiled(common::compile_bundled("state_forces"), &[], &[]).unwrap();
    let linear = session.linearization(&[], &[]).unwrap();
    let model = common::tape("state_forces");
    let n = model.nu();
    let q = linear.q.clone();
    let zero = vec![0.0; n];
    let slope = |column: usize, of_speed: bool| -> Vec<f64> {
        let h = 1e-4;
        let at = |step: f64| {
            let (mut q, mut u) = (q.clone(), zero.clone());
            if of_speed {
                u[column] += step;
            } else {
                q[column] += step;
            }
            common::accelerations(&model, &q, &u)
        };
        let (f2, f1, b1, b2) = (at(2.0 * h), at(h), at(-h), at(-2.0 * h));
        (0..n)
            .map(|r| (-f2[r] + 8.0 * f1[r] - 8.0 * b1[r] + b2[r]) / (12.0 * h))
            .collect()
    };
    for column in 0..n {
        for (of_speed, matrix) in [(false, &linear.stiffness), (true, &linear.damping)] {
            let df = slope(column, of_speed);
            for row in 0..n {
                // K = −M ∂f/∂q and C = −M ∂f/∂u.
                let expected: f64 = -(0..n).map(|s| linear.mass[(row, s)] * df[s]).sum::<f64>();
                let scale = matrix.iter().fold(0.0_f64, |a, b| a.max(b.abs()));
                assert!(
                    (matrix[(row, column)] - expected).abs() < 1e-6 * scale,
                    "{} [{row}, {column}]: {} vs {expected}",
                    if of_speed { "C" } else { "K" },
                    matrix[(row, column)]
                );
            }
        }
    }
    // The forces of the state do enter: the cubic rail force has no slope at s = 0, but
    // the speed-dependent ones give C ≠ 0 where no joint has a damper.
    assert!(linear.damping.iter().any(|c| c.abs() > 1e-3));
}

/// A mass on two sliders hung from an anchor by a spring whose law is written out,
/// `tension = k (L − L0) + k3 (L − L0)³ + c L̇` with `L = distance(anchor, bob)`.
fn tension_law_pendulum(spring: &str) -> String {
    format!(
        "
gravity = [0, -9.81 m/s^2, 0];
newtonian {{ point anchor = [5 mm, 10 mm, 0]; }}
body carriage {{ mass = 0 kg; }}
body bob {{ mass = 20 g; }}
joint x = slider(newtonian, carriage) {{ axis = x; q0 = 40 mm; }}
joint y = slider(carriage, bob) {{ axis = y; q0 = -60 mm; }}
spring hanger between newtonian.anchor and bob {{ {spring} }}
"
    )
}

/// The law as a `tension` field against the Cartesian equations written here,
/// `m r̈ = −T (r − r_A)/L − m g ŷ`, at 50 random states; and its linear part written as a law
/// gives the forcing of the built-in `stiffness`, `rest_length` and `damping`.
#[test]
fn a_tension_law_acts_along_the_line_between_the_points() {
    let (m, k, k3, rest, c, g) = (0.02, 40.0, 2e5, 0.05, 0.02, 9.81);
    let (ax, ay) = (0.005, 0.010);
    let law = "tension = 40 N/m * (distance(newtonian.anchor, bob) - 50 mm) \
               + 2e5 N/m^3 * (distance(newtonian.anchor, bob) - 50 mm)^3 \
               + 0.02 N*s/m * distance_rate(newtonian.anchor, bob);";
    let written = common::tape_from_text("tension_law", &tension_law_pendulum(law));
    let linear_law = "tension = 40 N/m * (distance(newtonian.anchor, bob) - 50 mm) \
                      + 0.02 N*s/m * distance_rate(newtonian.anchor, bob);";
    let as_law = common::tape_from_text("linear_law", &tension_law_pendulum(linear_law));
    let built_in = common::tape_from_text(
        "built_in",
        &tension_law_pendulum("stiffness = 40 N/m; rest_length = 50 mm; damping = 0.02 N*s/m;"),
    );
    let mut rng = common::Rng::new(15);
    for _ in 0..50 {
        let q = vec![rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1)];
        let u = vec![rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)];
        let (dx, dy) = (q[0] - ax, q[1] - ay);
        let length = dx.hypot(dy);
        let rate = (dx * u[0] + dy * u[1]) / length;
        let stretch = length - rest;
        let tension = k * stretch + k3 * stretch.powi(3) + c * rate;
        let expected = [-tension * dx / length / m, -tension * dy / length / m - g];
        let derived = common::accelerations(&written, &q, &u);
        for i in 0..2 {
            assert!(
                (derived[i] - expected[i]).abs() < 1e-10 * (1.0 + expected[i].abs()),
                "{derived:?} vs {expected:?}"
            );
        }
        let (a, b) = (
            common::forcing(&as_law, &q, &u),
            common::forcing(&built_in, &q, &u),
        );
        for i in 0..2 {
            assert!(
                (a[i] - b[i]).abs() < 1e-12 * (1.0 + b[i].abs()),
                "{a:?} vs {b:?}"
            );
        }
    }
}
