//! Steady rotations through `linearize_steady` against closed forms, in Euler angles (rates
//! that are not the speeds): a torque-free body spinning about a principal axis (Euler's
//! equations linearized: `λ² = −Ω² (I₃−I₁)(I₃−I₂) / (I₁I₂)` for a spin about axis 3, a real
//! pair about the intermediate axis), where every angle is cyclic; and a heavy top spinning
//! upright on `euler(xyz)` angles, whose third angle is cyclic to first order only (`A` turns
//! with it), which `cyclic_change` must show.

use mech_runtime::{linearize_steady, Model};

use crate::common;

/// A body with principal inertias `inertia` on a ball with `euler(xyz)` angles, spinning at
/// `spin` rad/s about its body axis `axis`, its centre of mass `lever` above the joint (a top,
/// under gravity) or at it.
fn spinning_body(inertia: [f64; 3], axis: usize, spin: f64, lever: f64) -> String {
    let [a, b, c] = inertia;
    let mut omega = ["0".to_string(), "0".to_string(), "0".to_string()];
    omega[axis] = format!("{spin} rad/s");
    format!(
        "gravity = [0, 0, -9.81 m/s^2];
         body b {{ mass = 1 kg; com = [0, 0, {lever} m]; inertia = [{a}, {b}, {c}] * 1 kg*m^2; }}
         joint tip = ball(newtonian, b) {{ rotation = euler(xyz); u0 = [{}]; }}",
        omega.join(", ")
    )
}

fn steady(text: &str) -> mech_runtime::SteadyLinearization {
    let model = common::tape_from_text("spinning", text);
    let (q, u) = common::initial_state(&model);
    let all: Vec<usize> = (0..model.nq()).collect();
    let inputs = common::default_inputs(&model);
    linearize_steady(&model, 0.0, (&q, &u), &inputs, &all, &all).unwrap()
}

#[test]
fn torque_free_spin_about_each_principal_axis() {
    let (i1, i2, i3) = (1.0, 2.0, 3.0);
    let spin = 2.5;
    for axis in 0..3 {
        let linear = steady(&spinning_body([i1, i2, i3], axis, spin, 0.0));
        assert_eq!(linear.cyclic.len(), 3, "every angle is cyclic");
        assert!(linear.cyclic_change < 1e-12, "{}", linear.cyclic_change);
        assert!(linear.unsteadiness() < 1e-12);
        let inertia = [i1, i2, i3];
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        let (ia, ib, ic) = (inertia[a], inertia[b], inertia[axis]);
        // λ² = Ω² (I_c − I_a)(I_b − I_c) / (I_a I_b): negative (oscillation) about the largest
        // and smallest axes, positive (the flip) about the intermediate one.
        let squared = spin * spin * (ic - ia) * (ib - ic) / (ia * ib);
        let values = linear.eigenvalues();
        let largest = values.iter().fold(0.0_f64, |m, z| m.max(z.norm()));
        assert!(
            (largest - squared.abs().sqrt()).abs() < 1e-9,
            "axis {axis}: {values:?}"
        );
        let oscillates = values.iter().any(|z| z.im.abs() > 1e-6);
        assert_eq!(oscillates, squared < 0.0, "axis {axis}: {values:?}");
        println!(
            "spin about axis {}: eigenvalues {values:?}, closed form ±√({squared:.6})",
            axis + 1
        );
    }
}

#[test]
fn a_coordinate_cyclic_to_first_order_only_is_flagged() {
    // A symmetric top spinning upright: the tilt in the fixed frame turns with the spin angle.
    let linear = steady(&spinning_body([1.0, 1.0, 0.5], 2, 30.0, 0.1));
    let model = common::tape_from_text("spinning", &spinning_body([1.0, 1.0, 0.5], 2, 30.0, 0.1));
    let cyclic: Vec<&str> = linear
        .cyclic
        .iter()
        .map(|&i| model.coordinate_name(i))
        .collect();
    assert_eq!(cyclic, ["tip.angle3"]);
    assert!(linear.cyclic_change > 1e-3, "{}", linear.cyclic_change);
    println!(
        "upright top on euler(xyz): A changes by {:.2e} when angle3 moves",
        linear.cyclic_change
    );
}

/// Chosen speeds (`models/double_pendulum_speeds.mech`: the upper link's angular velocity and
/// the tip's velocity along the lower link) at rest in the equilibrium: the eigenvalues are
/// ±i ω of the normal modes of the same pendulum in joint rates, from `linearize` about its
/// statics (an independent path: reduced dynamics, `K v = ω² M v`).
#[test]
fn chosen_speeds_at_rest_give_the_normal_modes_of_the_joint_rates() {
    use mech_runtime::{linearize, solve_statics, StaticsOptions};
    let text = common::bundled_source("double_pendulum_speeds");
    let plain: String = text
        .lines()
        .filter(|line| !line.trim_start().starts_with("speed "))
        .map(|line| format!("{line}\n"))
        .collect();
    let joint_rates = common::tape_from_text("joint_rates", &plain);
    let inputs = common::default_inputs(&joint_rates);
    let (mut q, _) = common::initial_state(&joint_rates);
    let options = StaticsOptions::default();
    solve_statics(&joint_rates, 0.0, &mut q, &inputs, &[], &options).unwrap();
    let modes = linearize(&joint_rates, 0.0, &q, &inputs, &[0, 1])
        .unwrap()
        .modes()
        .unwrap();
    let chosen = common::tape_from_text("chosen", &text);
    assert!(!chosen.rates_are_speeds());
    let u = vec![0.0; chosen.nu()];
    let linear = linearize_steady(&chosen, 0.0, (&q, &u), &inputs, &[0, 1], &[0, 1]).unwrap();
    assert!(linear.cyclic.is_empty() && linear.unsteadiness() < 1e-9);
    let mut frequencies: Vec<f64> = linear
        .eigenvalues()
        .iter()
        .inspect(|z| assert!(z.re.abs() < 1e-9, "{z}"))
        .filter(|z| z.im > 0.0)
        .map(|z| z.im)
        .collect();
    frequencies.sort_by(f64::total_cmp);
    for (ours, mode) in frequencies.iter().zip(&modes) {
        // Measured 1e-15 relative; central differences of the rates allow 1e-10.
        assert!(
            (ours - mode.natural_frequency).abs() < 1e-10 * mode.natural_frequency,
            "{ours} vs {}",
            mode.natural_frequency
        );
    }
    assert_eq!(frequencies.len(), modes.len());
    println!(
        "chosen speeds at rest: ω = {frequencies:?}; joint rates' modes: {:?}",
        modes
            .iter()
            .map(|m| m.natural_frequency)
            .collect::<Vec<_>>()
    );
}
