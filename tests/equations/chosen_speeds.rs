//! Generalized speeds chosen by `speed` declarations (`u = Y(q) ū`, `q̇ = W(q) u`) against
//! the same models in their default speeds `u = q̇`:
//! - a planar double pendulum with absolute-angle speeds (`u₁ = ω₁`, `u₂ = ω₂` in N) moves
//!   exactly as with the joint rates: the same `q(t)` to 1e-10, and `M̃ = Wᵀ M W`,
//!   `F̃ = Wᵀ (F − M Ẇ u)` at random states, on the tape and in its native code alike;
//! - a combination of joint speeds with a coefficient of `q` (`s = a.u + cos(a.q) b.u`) and a
//!   point's velocity as a speed give the same motion too;
//! - energy is conserved with chosen speeds (a conservative example, to 1e-10);
//! - the bundled `double_pendulum_speeds` as generated Rust: `q̇ = W(q) u` as the tape's, the
//!   joint rates' motion (its `M`, `F` against SymPy are in `sympy_cross_check.rs`);
//! - a four-bar's loop in chosen speeds: the same motion, energy kept;
//! - the errors: too many or too few speeds, speeds dependent at `q0`, a speed not linear.

use crate::common;

use mech_runtime::Model;

/// A planar double pendulum; `SPEEDS` is replaced by the speed declarations under test.
const DOUBLE_PENDULUM: &str = r#"
model double_pendulum;
param m1 = 1.3 kg;
param m2 = 0.7 kg;
param l1 = 0.9 m;
param l2 = 0.6 m;
gravity = [0, -9.81 m/s^2, 0];
body upper { mass = m1; inertia = [0.05, 0.07, 0.11] * 1 kg*m^2; com = [0.1, -0.4, 0] * 1 m; point elbow = [0, -l1, 0]; }
body lower { mass = m2; inertia = [0.02, 0.03, 0.04] * 1 kg*m^2; com = [0.05, -0.3, 0] * 1 m; point tip = [0, -l2, 0]; }
joint shoulder = pin(newtonian, upper) { axis = z; q0 = 50 deg; u0 = 1.5 rad/s; }
joint elbow = pin(upper, lower) { axis = z; parent_point = upper.elbow; q0 = -20 deg; u0 = -0.7 rad/s; }
SPEEDS
output ke = kinetic_energy;
output pe = potential_energy;
"#;

/// `u₁ = ω of upper`, `u₂ = ω of lower`, both along N's z: `Y = [[1, 0], [1, 1]]`.
const ABSOLUTE: &str = "speed w_upper = angular_velocity(upper) in newtonian { axis = z; }\n\
                        speed w_lower = angular_velocity(lower) in newtonian { axis = z; }";

fn pendulum(speeds: &str) -> mech::tape_model::TapeModel {
    common::tape_from_text(
        "double_pendulum",
        &DOUBLE_PENDULUM.replace("SPEEDS", speeds),
    )
}

/// Runs `model` from its own initial state for 3 s at tight tolerances.
fn run(model: &dyn Model) -> mech_runtime::Trajectory {
    let (q0, u0) = common::initial_state(model);
    let options = common::dopri5_options(3.0, 0.05, 1e-13, 1e-13);
    common::simulate_at_default_inputs(model, &q0, &u0, &options)
}

/// The largest difference in `q` between two runs sampled at the same times.
fn largest_q_difference(a: &mech_runtime::Trajectory, b: &mech_runtime::Trajectory) -> f64 {
    assert_eq!(a.times.len(), b.times.len());
    a.q.iter()
        .zip(&b.q)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(x, y)| (x - y).abs()))
        .fold(0.0, f64::max)
}

#[test]
fn absolute_angle_speeds_move_as_the_joint_rates() {
    let default = pendulum("");
    let absolute = pendulum(ABSOLUTE);
    assert_eq!(absolute.speed_name(0), "w_upper");
    assert!(!absolute.rates_are_speeds());
    let (q0, u0) = common::initial_state(&absolute);
    assert_eq!(u0, vec![1.5, 1.5 - 0.7], "u0 = Y(q0) q̇0");
    let (q0_default, _) = common::initial_state(&default);
    assert_eq!(q0, q0_default);
    let difference = largest_q_difference(&run(&default), &run(&absolute));
    println!("absolute-angle speeds: largest |Δq| over 3 s = {difference:.2e}");
    assert!(difference < 1e-10, "|Δq| = {difference:e}");
}

#[test]
fn mass_matrix_and_forcing_are_w_transpose_of_the_defaults() {
    // W = Y⁻¹ = [[1, 0], [−1, 1]] is constant: Ẇ = 0, M̃ = Wᵀ M W, F̃ = Wᵀ F(q, W u).
    let default = pendulum("");
    let absolute = pendulum(ABSOLUTE);
    let w = [[1.0, 0.0], [-1.0, 1.0]];
    let mut rng = common::Rng::new(15);
    let mut largest = 0.0_f64;
    for _ in 0..20 {
        let q = rng.vector(2, -3.0, 3.0);
        let u = rng.vector(2, -4.0, 4.0);
        let joint_rates: Vec<f64> = (0..2).map(|i| w[i][0] * u[0] + w[i][1] * u[1]).collect();
        let mut qdot = vec![0.0; 2];
        absolute.kinematic_rates(0.0, &q, &u, &mut qdot);
        assert_eq!(qdot, joint_rates, "q̇ = W u");
        let m = common::mass_matrix(&default, &q);
        let f = common::forcing(&default, &q, &joint_rates);
        let m_new = common::mass_matrix(&absolute, &q);
        let f_new = common::forcing(&absolute, &q, &u);
        for r in 0..2 {
            let expected_f: f64 = (0..2).map(|i| w[i][r] * f[i]).sum();
            largest = largest.max((f_new[r] - expected_f).abs());
            for s in 0..2 {
                let expected: f64 = (0..2)
                    .flat_map(|i| (0..2).map(move |j| (i, j)))
                    .map(|(i, j)| w[i][r] * m[i][j] * w[j][s])
                    .sum();
                largest = largest.max((m_new[r][s] - expected).abs());
            }
        }
    }
    assert!(largest < 1e-12, "largest difference {largest:e}");
}

#[test]
fn speeds_with_a_coefficient_of_q_and_a_point_velocity_move_as_the_joint_rates() {
    // Y depends on q: Ẇ u ≠ 0 enters F̃.
    let combination = "speed s1 = shoulder.u;\n\
                       speed s2 = cos(shoulder.q) * elbow.u + 2 * shoulder.u;";
    let point = "speed vx = velocity(lower.tip) in newtonian { axis = x; }\n\
                 speed w = angular_velocity(lower) in lower { axis = z; }";
    let reference = run(&pendulum(""));
    for speeds in [combination, point] {
        let model = pendulum(speeds);
        let difference = largest_q_difference(&reference, &run(&model));
        println!("{speeds}: largest |Δq| over 3 s = {difference:.2e}");
        assert!(difference < 1e-9, "{speeds}: |Δq| = {difference:e}");
        let (scale, drift) = common::energy_drift(&model, &run(&model));
        assert!(
            scale > 0.1 && drift < 1e-10,
            "{speeds}: energy drift {drift:e}"
        );
    }
}

#[test]
fn energy_is_conserved_in_absolute_angle_speeds() {
    let model = pendulum(ABSOLUTE);
    let (scale, drift) = common::energy_drift(&model, &run(&model));
    println!("absolute-angle speeds: energy drift {drift:.2e} of the largest KE {scale:.3} J");
    assert!(scale > 0.1 && drift < 1e-10, "drift {drift:e}");
}

/// The diagnostics of a model with the speed declarations `speeds`.
fn errors(speeds: &str) -> String {
    let text = DOUBLE_PENDULUM.replace("SPEEDS", speeds);
    let source = mech_codegen::SourceFile::new("double_pendulum.mech", text);
    match mech_codegen::Compiled::from_source(source) {
        Ok(_) => panic!("`{speeds}` compiled"),
        Err(errors) => errors.to_string(),
    }
}

#[test]
fn wrong_speed_declarations_are_refused_with_their_reasons() {
    let one = "speed w = angular_velocity(upper) in newtonian { axis = z; }";
    assert!(errors(one).contains("E0440"), "{}", errors(one));
    let three = format!("{ABSOLUTE}\nspeed extra = shoulder.u;");
    assert!(errors(&three).contains("E0440"), "{}", errors(&three));
    let dependent = "speed a = shoulder.u + elbow.u;\n\
                     speed b = angular_velocity(lower) in newtonian { axis = z; }";
    assert!(errors(dependent).contains("E0441"), "{}", errors(dependent));
    let square = "speed a = shoulder.u * elbow.u;\nspeed b = elbow.u;";
    assert!(errors(square).contains("E0442"), "{}", errors(square));
    let affine = "speed a = shoulder.u + shoulder.q / 1 s;\nspeed b = elbow.u;";
    assert!(errors(affine).contains("E0443"), "{}", errors(affine));
    let out_of_plane = "speed a = angular_velocity(upper) in newtonian { axis = x; }\n\
                        speed b = elbow.u;";
    assert!(
        errors(out_of_plane).contains("E0441"),
        "{}",
        errors(out_of_plane)
    );
}

/// `models/double_pendulum_speeds.mech` (the tip's speed along the lower link: `W` depends on
/// `q`) as generated Rust: `q̇ = W(q) u` as the tape's, and the same motion as the joint
/// rates' to 1e-10.
#[test]
fn the_bundled_model_as_generated_rust_moves_as_the_joint_rates() {
    let generated = mech::models::compiled("double_pendulum_speeds").unwrap();
    let tape = common::tape("double_pendulum_speeds");
    assert!(!generated.rates_are_speeds() && generated.plain_coordinates() == 0);
    let mut rng = common::Rng::new(16);
    for _ in 0..10 {
        let (q, u) = (rng.vector(2, -3.0, 3.0), rng.vector(2, -4.0, 4.0));
        let (mut from_rust, mut from_tape) = (vec![0.0; 2], vec![0.0; 2]);
        generated.kinematic_rates(0.0, &q, &u, &mut from_rust);
        tape.kinematic_rates(0.0, &q, &u, &mut from_tape);
        for (a, b) in from_rust.iter().zip(&from_tape) {
            assert!((a - b).abs() <= 1e-14 * (1.0 + b.abs()), "{a} vs {b}");
        }
    }
    let reference = run(&pendulum(""));
    let difference = largest_q_difference(&reference, &run(generated.as_ref()));
    println!("bundled model, generated Rust: largest |Δq| over 3 s = {difference:.2e}");
    assert!(difference < 1e-10, "|Δq| = {difference:e}");
    let (scale, drift) = common::energy_drift(generated.as_ref(), &run(generated.as_ref()));
    println!("bundled model, generated Rust: energy drift {drift:.2e} of {scale:.3} J");
    assert!(drift < 1e-10, "drift {drift:e}");
}

/// The language reference's `speed` example simulates and keeps its energy.
#[test]
fn language_reference_speed_example_conserves_energy() {
    let (_, text) = crate::language_doc::language_reference_examples()
        .into_iter()
        .find(|(_, text)| text.contains("speed w_upper"))
        .expect("an example of `speed`");
    let model = common::tape_from_text("speed_example", &text);
    assert_eq!(model.speed_name(1), "w_lower");
    let (scale, drift) = common::energy_drift(&model, &run(&model));
    assert!(scale > 0.1 && drift < 1e-10, "drift {drift:e}");
}

/// A four-bar (a loop closure) in speeds with a coefficient of `q`: the constraint rows in the
/// new speeds (`J W`, `b + J Ẇ u`) hold the loop closed and give the default speeds' motion.
#[test]
fn a_closed_loop_in_chosen_speeds_moves_as_in_the_joint_rates() {
    use mech_runtime::{assemble, assemble_speeds, AssemblyOptions};
    let text = common::bundled_source("four_bar");
    let chosen = format!(
        "{text}\nspeed crank_rate = crank_angle.u;\n\
         speed coupler_rate = crank_angle.u + (2 + sin(coupler_angle.q)) * coupler_angle.u;\n\
         speed rocker_rate = rocker_angle.u;\n"
    );
    let default = common::tape_from_text("four_bar", &text);
    let model = common::tape_from_text("four_bar_speeds", &chosen);
    let (mut q, mut qdot) = common::initial_state(&default);
    assemble(&default, 0.0, &mut q, &[0], &AssemblyOptions::default()).unwrap();
    assemble_speeds(&default, 0.0, &q, &mut qdot, &[0]).unwrap();
    let u = [qdot[0], qdot[0] + (2.0 + q[1].sin()) * qdot[1], qdot[2]];
    let options = common::dopri5_options(2.0, 0.05, 1e-12, 1e-12);
    let reference = common::simulate_at_default_inputs(&default, &q, &qdot, &options);
    let run = common::simulate_at_default_inputs(&model, &q, &u, &options);
    let difference = largest_q_difference(&reference, &run);
    println!("four-bar in chosen speeds: largest |Δq| over 2 s = {difference:.2e}");
    assert!(difference < 1e-8, "|Δq| = {difference:e}");
    let (scale, drift) = common::energy_drift(&model, &run);
    println!("four-bar in chosen speeds: energy drift {drift:.2e} of {scale:.3} J");
    assert!(drift < 1e-8, "drift {drift:e}");
}
