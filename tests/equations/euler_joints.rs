//! `ball` and `free` joints with `rotation = euler(SEQ)` (three body-fixed angles; speeds the
//! angular velocity in the child frame, as with a quaternion) against formulations written
//! here:
//! - for each of the twelve sequences, the child's direction cosines (outputs of points on its
//!   axes) against the product of elementary rotations written out here, and `q̇ = W(q) u`
//!   against the body angular velocity from finite differences of that rotation matrix
//!   (`[ω]× = Rᵀ Ṙ`);
//! - a torque-free body with three distinct inertias against the same body on a quaternion
//!   ball: angular velocity and direction cosines agree over 5 s; energy and the angular
//!   momentum in N are conserved;
//! - a heavy symmetric top on `euler(zxz)` precesses steadily: `φ = φ̇ t`, `θ` constant, at the
//!   closed-form rate;
//! - the bundled `models/gimbal_rig.mech`: generated Rust and the tape agree on `q̇ = W(q) u`.

use crate::common;

use crate::quaternion_joints::{dop853, heavy_top, mat_mul, run};
use common::Rng;
use mech_runtime::Model;

type M3 = [[f64; 3]; 3];

const SEQUENCES: [&str; 12] = [
    "xyz", "xzy", "yxz", "yzx", "zxy", "zyx", "xyx", "xzx", "yxy", "yzy", "zxz", "zyz",
];

/// The rotation by `angle` about coordinate axis `axis` (0 = x), written out.
fn elementary(axis: usize, angle: f64) -> M3 {
    let (c, s) = (angle.cos(), angle.sin());
    match axis {
        0 => [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
        1 => [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
        _ => [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
    }
}

fn axes_of(sequence: &str) -> [usize; 3] {
    let mut axes = sequence.bytes().map(|b| usize::from(b - b'x'));
    [0; 3].map(|_| axes.next().unwrap())
}

/// `R = R(a₁, q₁) R(a₂, q₂) R(a₃, q₃)`, the columns the child's axes in the parent.
fn euler_matrix(sequence: &str, q: &[f64]) -> M3 {
    let axes = axes_of(sequence);
    let r12 = mat_mul(&elementary(axes[0], q[0]), &elementary(axes[1], q[1]));
    mat_mul(&r12, &elementary(axes[2], q[2]))
}

/// A body whose points `px`, `py`, `pz` sit on its axes at unit distance: their positions are
/// the columns of its rotation.
fn body_on_ball(rotation: &str, inertia: [f64; 3], extra: &str) -> String {
    let [a, b, c] = inertia;
    format!(
        "body b {{ mass = 1 kg; inertia = [{a}, {b}, {c}] * 1 kg*m^2;
                   point px = [1 m, 0, 0]; point py = [0, 1 m, 0]; point pz = [0, 0, 1 m]; }}
         joint tip = ball(newtonian, b) {{ {rotation} {extra} }}
         output ex = position(b.px); output ey = position(b.py); output ez = position(b.pz);
         output ke = kinetic_energy; output pe = potential_energy;"
    )
}

/// The rotation matrix read off the outputs `ex`, `ey`, `ez` (its columns).
fn rotation_from_outputs(model: &dyn Model, y: &[f64]) -> M3 {
    let mut r = [[0.0; 3]; 3];
    for (j, name) in ["ex.x", "ey.x", "ez.x"].into_iter().enumerate() {
        let start = model.output_index(name).unwrap();
        for (i, row) in r.iter_mut().enumerate() {
            row[j] = y[start + i];
        }
    }
    r
}

/// `max |a_ij − b_ij|`.
fn largest_difference(a: &M3, b: &M3) -> f64 {
    a.iter()
        .flatten()
        .zip(b.iter().flatten())
        .fold(0.0, |worst, (x, y)| worst.max((x - y).abs()))
}

fn outputs(model: &dyn Model, q: &[f64], u: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; model.noutputs()];
    model.outputs(0.0, q, u, &common::default_inputs(model), &mut y);
    y
}

/// For every sequence at random angles (away from its singularity) and angular velocities:
/// the rotation is the product written here (1e-14), and `q̇ = W(q) u` turns the rotation at
/// `ω = u` in the body: `Rᵀ (R(q + h q̇) − R(q − h q̇)) / 2h = [u]×` to 1e-8.
#[test]
fn euler_rotation_and_rates_match_the_rotation_matrix_for_every_sequence() {
    let mut rng = Rng::new(1515);
    for sequence in SEQUENCES {
        // Proper sequences are singular at the default q0 = 0 (E0419): start them tilted.
        let text = body_on_ball(
            &format!("rotation = euler({sequence});"),
            [1.0, 2.0, 3.0],
            "q0 = [0, 30 deg, 0];",
        );
        let model = common::tape_from_text(&format!("euler_{sequence}"), &text);
        assert_eq!((model.nq(), model.nu()), (3, 3), "{sequence}");
        assert!(model.unit_quaternions().is_empty());
        assert_eq!(model.plain_coordinates(), 0);
        assert!(!model.rates_are_speeds());
        assert_eq!(model.coordinate_name(1), "tip.angle2");
        assert_eq!(model.speed_name(2), "tip.wz");
        let proper = sequence.as_bytes()[0] == sequence.as_bytes()[2];
        for _ in 0..20 {
            let mut q = rng.vector(3, -3.0, 3.0);
            // Middle angle at least 0.2 rad from the singularity.
            q[1] = match proper {
                true => rng.uniform(0.2, std::f64::consts::PI - 0.2),
                false => rng.uniform(-1.37, 1.37),
            };
            let u = rng.vector(3, -2.0, 2.0);
            let r = euler_matrix(sequence, &q);
            let found = rotation_from_outputs(&model, &outputs(&model, &q, &u));
            for i in 0..3 {
                for j in 0..3 {
                    assert!(
                        (found[i][j] - r[i][j]).abs() < 1e-14,
                        "{sequence}: R[{i}][{j}] = {} vs {} at q = {q:?}",
                        found[i][j],
                        r[i][j]
                    );
                }
            }
            let mut rates = [0.0; 3];
            model.kinematic_rates(0.0, &q, &u, &mut rates);
            let h = 1e-6;
            let shifted = |sign: f64| -> M3 {
                let moved: Vec<f64> = (0..3).map(|i| q[i] + sign * h * rates[i]).collect();
                euler_matrix(sequence, &moved)
            };
            let (ahead, behind) = (shifted(1.0), shifted(-1.0));
            // [ω]× = Rᵀ Ṙ: ω_x = (RᵀṘ)[2][1], ω_y = (RᵀṘ)[0][2], ω_z = (RᵀṘ)[1][0].
            let body_rate = |i: usize, j: usize| -> f64 {
                (0..3)
                    .map(|k| r[k][i] * (ahead[k][j] - behind[k][j]) / (2.0 * h))
                    .sum()
            };
            let omega = [body_rate(2, 1), body_rate(0, 2), body_rate(1, 0)];
            for i in 0..3 {
                assert!(
                    (omega[i] - u[i]).abs() < 1e-8,
                    "{sequence}: ω[{i}] = {} from Ṙ vs u = {} at q = {q:?}",
                    omega[i],
                    u[i]
                );
            }
        }
    }
}

/// A torque-free body with inertias 1, 2, 3 kg·m², spun mostly about its major axis z
/// (`euler(xyz)`: the middle angle stays near 0, far from ±90°), on Euler angles and on a
/// quaternion from the same start: over 5 s the angular velocities and the direction cosines
/// agree to 1e-8, and on the Euler angles the kinetic energy and the angular momentum in N
/// (`H = R I ω`, R written here) are conserved to 1e-10.
#[test]
fn torque_free_body_on_euler_angles_follows_the_quaternion_ball() {
    let inertia = [1.0, 2.0, 3.0];
    let start = "u0 = [0.3 rad/s, 0.2 rad/s, 2 rad/s];";
    let euler = common::tape_from_text(
        "torque_free_euler",
        &body_on_ball("rotation = euler(xyz);", inertia, start),
    );
    let quaternion =
        common::tape_from_text("torque_free_quaternion", &body_on_ball("", inertia, start));
    let options = dop853(5.0, 0.01, 1e-13, 1e-15);
    let (qe, ue) = common::initial_state(&euler);
    let (qq, uq) = common::initial_state(&quaternion);
    assert_eq!(ue, uq);
    let on_euler = run(&euler, &qe, &ue, &options);
    let on_quaternion = run(&quaternion, &qq, &uq, &options);
    assert_eq!(on_euler.len(), on_quaternion.len());
    let momentum = |q: &[f64], u: &[f64]| -> [f64; 3] {
        let r = euler_matrix("xyz", q);
        let body = [0, 1, 2].map(|i| inertia[i] * u[i]);
        [0, 1, 2].map(|i| (0..3).map(|k| r[i][k] * body[k]).sum())
    };
    let energy = |u: &[f64]| 0.5 * (0..3).map(|i| inertia[i] * u[i] * u[i]).sum::<f64>();
    let (h0, t0) = (momentum(&qe, &ue), energy(&ue));
    let h_scale = h0.iter().map(|x| x * x).sum::<f64>().sqrt();
    let (mut worst_w, mut worst_r, mut worst_h, mut worst_t, mut widest) =
        (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
    for k in 0..on_euler.len() {
        let (q, u) = (&on_euler.q[k], &on_euler.u[k]);
        widest = widest.max(q[1].abs());
        for (x, y) in u.iter().zip(&on_quaternion.u[k]) {
            worst_w = worst_w.max((x - y).abs());
        }
        let r_euler = rotation_from_outputs(&euler, &on_euler.outputs[k]);
        let r_quaternion = rotation_from_outputs(&quaternion, &on_quaternion.outputs[k]);
        worst_r = worst_r.max(largest_difference(&r_euler, &r_quaternion));
        let h = momentum(q, u);
        let dh = (0..3).map(|i| (h[i] - h0[i]).powi(2)).sum::<f64>().sqrt();
        worst_h = worst_h.max(dh / h_scale);
        worst_t = worst_t.max((energy(u) - t0).abs() / t0);
    }
    eprintln!(
        "torque-free body, 5 s, euler(xyz) vs quaternion: max |Δω| = {worst_w:.1e} rad/s, \
         max |ΔR| = {worst_r:.1e}; on Euler angles max |ΔH|/|H| = {worst_h:.1e}, \
         max |ΔT|/T = {worst_t:.1e}; max |q₂| = {widest:.2} rad"
    );
    assert!(
        widest < 1.0,
        "the middle angle came near the singularity: {widest}"
    );
    assert!(worst_w < 1e-8, "angular velocities differ by {worst_w:e}");
    assert!(worst_r < 1e-8, "direction cosines differ by {worst_r:e}");
    assert!(worst_h < 1e-10, "angular momentum drifts by {worst_h:e}");
    assert!(worst_t < 1e-10, "kinetic energy drifts by {worst_t:e}");
}

/// A heavy symmetric top on `euler(zxz)` (precession φ, nutation θ, spin ψ), tilted θ₀ = 0.5
/// rad and started with the angular velocity of steady precession (as in the quaternion
/// test, Goldstein Eq. 5.76): φ grows at the closed-form rate, θ stays at θ₀.
#[test]
fn heavy_symmetric_top_on_euler_angles_precesses_at_the_closed_form_rate() {
    let fields = "rotation = euler(zxz); q0 = [0, 0.5 rad, 0];";
    let (model, theta, spin, rate) = heavy_top("top_euler", fields);
    let (q0, _) = common::initial_state(&model);
    assert_eq!(q0, [0.0, theta, 0.0]);
    let u0 = [0.0, rate * theta.sin(), spin];
    let t_end = 2.0;
    let trajectory = run(&model, &q0, &u0, &dop853(t_end, 1e-3, 1e-12, 1e-14));
    let (mut worst_tilt, mut worst_phase) = (0.0_f64, 0.0_f64);
    for (k, &t) in trajectory.times.iter().enumerate() {
        let q = &trajectory.q[k];
        worst_tilt = worst_tilt.max((q[1] - theta).abs());
        worst_phase = worst_phase.max((q[0] - rate * t).abs());
    }
    let measured = trajectory.q.last().unwrap()[0] / t_end;
    eprintln!(
        "heavy top on euler(zxz): φ̇ = {measured:.12} rad/s simulated, {rate:.12} rad/s closed \
         form; max |θ − θ₀| = {worst_tilt:.1e} rad, max |φ − φ̇t| = {worst_phase:.1e} rad"
    );
    assert!(worst_tilt < 1e-9, "the top nutates by {worst_tilt:e} rad");
    assert!(
        worst_phase < 1e-9 * rate * t_end,
        "φ off by {worst_phase:e}"
    );
    let (_, drift) = common::energy_drift(&model, &trajectory);
    assert!(drift < 1e-10, "energy drift {drift:e}");
}

/// The bundled model with every new joint: the generated Rust and the tape give the same
/// `q̇ = W(q) u` and plain-coordinate count.
#[test]
fn gimbal_rig_rates_agree_in_both_back_ends() {
    let tape = common::tape("gimbal_rig");
    let compiled = mech::models::compiled("gimbal_rig").unwrap();
    assert_eq!(compiled.plain_coordinates(), tape.plain_coordinates());
    assert!(!tape.rates_are_speeds());
    let mut rng = Rng::new(7);
    for _ in 0..20 {
        let q = rng.vector(tape.nq(), -1.0, 1.0);
        let u = rng.vector(tape.nu(), -1.0, 1.0);
        let (mut a, mut b) = (vec![0.0; tape.nq()], vec![0.0; tape.nq()]);
        compiled.kinematic_rates(0.0, &q, &u, &mut a);
        tape.kinematic_rates(0.0, &q, &u, &mut b);
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-12 * (1.0 + y.abs()), "{a:?} vs {b:?}");
        }
    }
}

/// A body turning about its y axis on `euler(xyz)` passes close to the singularity (the
/// middle angle within 0.02 rad of 90° at t ≈ π/2, where the first and third angles swing by
/// ~π): the integrator takes small steps there, and the rotation stays that of the
/// quaternion ball from the same start (1e-6 over 3 s; the rates peak at ~1/cos q₂).
#[test]
fn passing_near_the_singularity_keeps_the_motion() {
    let start = "u0 = [0.01 rad/s, 1 rad/s, 0];";
    let inertia = [1.0, 2.0, 3.0];
    let euler = common::tape_from_text(
        "near_singular_euler",
        &body_on_ball("rotation = euler(xyz);", inertia, start),
    );
    let quaternion = common::tape_from_text(
        "near_singular_quaternion",
        &body_on_ball("", inertia, start),
    );
    let options = dop853(3.0, 0.01, 1e-12, 1e-14);
    let (qe, ue) = common::initial_state(&euler);
    let (qq, uq) = common::initial_state(&quaternion);
    let on_euler = run(&euler, &qe, &ue, &options);
    let on_quaternion = run(&quaternion, &qq, &uq, &options);
    let (mut closest, mut worst_r) = (f64::INFINITY, 0.0_f64);
    for k in 0..on_euler.len() {
        closest = closest.min(on_euler.q[k][1].cos().abs());
        let r_euler = rotation_from_outputs(&euler, &on_euler.outputs[k]);
        let r_quaternion = rotation_from_outputs(&quaternion, &on_quaternion.outputs[k]);
        worst_r = worst_r.max(largest_difference(&r_euler, &r_quaternion));
    }
    eprintln!(
        "near the singularity of euler(xyz): min |cos q₂| = {closest:.1e}, max |ΔR| against \
         the quaternion = {worst_r:.1e}, {} steps ({} on the quaternion)",
        on_euler.stats.accepted_steps, on_quaternion.stats.accepted_steps
    );
    assert!(
        closest < 0.05,
        "did not come near the singularity: {closest}"
    );
    assert!(worst_r < 1e-6, "direction cosines differ by {worst_r:e}");
}

/// A `free` joint with `rotation = euler(zyx)` (slides, then Euler angles) against the same
/// throw on a quaternion: over 2 s under gravity the mass centre and the rotation agree to
/// 1e-9 (its tilt stays far from the singularity at y = ±90°).
#[test]
fn free_joint_on_euler_angles_follows_the_quaternion() {
    let throw = |rotation: &str| {
        format!(
            "gravity = [0, 0, -9.81 m/s^2];
             body b {{ mass = 0.2 kg; com = [0.1 m, 0, 0]; inertia = [1e-3, 2e-3, 3e-3] * 1 kg*m^2;
                       point px = [1 m, 0, 0]; point py = [0, 1 m, 0]; point pz = [0, 0, 1 m]; }}
             joint throw = free(newtonian, b) {{ {rotation} u0 = [0.2 rad/s, 0.1 rad/s, 2 rad/s]; v0 = [1 m/s, 0, 3 m/s]; }}
             output ex = position(b.px); output ey = position(b.py); output ez = position(b.pz);
             output centre = position(b.com);"
        )
    };
    let euler = common::tape_from_text("free_euler", &throw("rotation = euler(zyx);"));
    let quaternion = common::tape_from_text("free_quaternion", &throw(""));
    assert_eq!((euler.nq(), euler.nu()), (6, 6));
    assert_eq!(euler.plain_coordinates(), 0);
    assert_eq!(euler.coordinate_name(0), "throw.angle1");
    assert_eq!(euler.coordinate_name(3), "throw.x");
    let options = dop853(2.0, 0.01, 1e-12, 1e-14);
    let (qe, ue) = common::initial_state(&euler);
    let (qq, uq) = common::initial_state(&quaternion);
    let on_euler = run(&euler, &qe, &ue, &options);
    let on_quaternion = run(&quaternion, &qq, &uq, &options);
    let centre = euler.output_index("centre.x").unwrap();
    let (mut worst_r, mut worst_centre) = (0.0_f64, 0.0_f64);
    for k in 0..on_euler.len() {
        let (ye, yq) = (&on_euler.outputs[k], &on_quaternion.outputs[k]);
        let r_euler = rotation_from_outputs(&euler, ye);
        let r_quaternion = rotation_from_outputs(&quaternion, yq);
        worst_r = worst_r.max(largest_difference(&r_euler, &r_quaternion));
        for i in centre..centre + 3 {
            worst_centre = worst_centre.max((ye[i] - yq[i]).abs());
        }
    }
    eprintln!(
        "free joint, euler(zyx) vs quaternion, 2 s: max |ΔR| = {worst_r:.1e}, \
         max |Δr_G| = {worst_centre:.1e} m"
    );
    assert!(worst_r < 1e-9 && worst_centre < 1e-9);
}

/// A session sets an Euler angle by name with its unit (`--q0 tip.angle2=40deg`) and knows
/// the units of the angles and their angular speeds.
#[test]
fn a_session_sets_euler_angles_by_name() {
    use mech::session::Session;
    let text = body_on_ball("rotation = euler(zxy);", [1.0, 2.0, 3.0], "");
    let compiled = common::compile_text("session_euler", &text);
    let session = Session::from_compiled(compiled, &[], &[]).unwrap();
    let (q, _) = session
        .initial_state(
            &["tip.angle2=40deg".to_string()],
            &["tip.wy=2rad/s".to_string()],
        )
        .unwrap();
    common::assert_close("angle2", q[1], 40f64.to_radians(), 1e-15, 0.0);
    let (angle, rate) = session.coordinate_units("tip.angle1").unwrap();
    assert_eq!((angle.as_str(), rate.as_str()), ("rad", ""));
    assert_eq!(session.speed_unit("tip.wz"), "rad/s");
}

/// A `free` joint's `v0` is written in the joint frame whatever the start orientation: on
/// Euler angles that start turned, the speeds are `v0` seen from the child (`Rᵀ v0`), so the
/// origin's velocity in N (an output, computed from the kinematics) is `v0` again. A session
/// sets the position (m) and the velocity speeds (m/s) by name with their units.
#[test]
fn free_joint_v0_is_the_joint_frame_velocity_at_any_start_orientation() {
    let text =
        "body b { mass = 0.2 kg; inertia = [1e-3, 2e-3, 3e-3] * 1 kg*m^2; point o = [0, 0, 0]; }
         joint throw = free(newtonian, b) {
             rotation = euler(zyx); q0 = [0.3 rad, -0.4 rad, 0.5 rad];
             u0 = [0.2 rad/s, 0.1 rad/s, 2 rad/s]; v0 = [1 m/s, -2 m/s, 0.5 m/s];
         }
         output origin_velocity = velocity(b.o);";
    let model = common::tape_from_text("turned_throw", text);
    let (q, u) = common::initial_state(&model);
    let mut y = vec![0.0; model.noutputs()];
    model.outputs(0.0, &q, &u, &vec![0.0; model.ninputs()], &mut y);
    let at = model.output_index("origin_velocity.x").unwrap();
    for (k, expected) in [1.0, -2.0, 0.5].into_iter().enumerate() {
        common::assert_close(
            "velocity of the origin in N",
            y[at + k],
            expected,
            1e-15,
            1.0,
        );
    }
    let vx = (0..model.nu())
        .find(|&i| model.speed_name(i) == "throw.vx")
        .unwrap();
    assert!(
        (u[vx] - 1.0).abs() > 0.1,
        "the speeds are the child's measure numbers: {u:?}"
    );

    use mech::session::Session;
    let session =
        Session::from_compiled(common::compile_text("turned_throw", text), &[], &[]).unwrap();
    let (q, u) = session
        .initial_state(&["throw.z=5mm".to_string()], &["throw.vy=3m/s".to_string()])
        .unwrap();
    common::assert_close(
        "z",
        q[model.coordinate_index("throw.z").unwrap()],
        5e-3,
        1e-15,
        0.0,
    );
    common::assert_close("vy", u[vx + 1], 3.0, 1e-15, 0.0);
    let (length, rate) = session.coordinate_units("throw.x").unwrap();
    assert_eq!((length.as_str(), rate.as_str()), ("m", ""));
    assert_eq!(session.speed_unit("throw.vz"), "m/s");
}
