//! Bushings (`bushing NAME between A and B`), against closed forms mech did not compute:
//! - a plate on a bushing with diagonal stiffness, free in the plane (x, y sliders and a pin
//!   about z): small-oscillation frequencies `√(k_x/m)`, `√(k_y/m)`, `√(k_θz/I_zz)` from the
//!   linearization, with the bushing's axes turned 30° from the sliders';
//! - energy: a body turning through large angles about three axes and translating, on an
//!   anisotropic undamped bushing, keeps `ke + pe` (the bushing's `½ Σ k s²` is in `pe`); with
//!   damping the energy never rises.
//!
//! Consumes: model texts written here. Produces: tests only.

use crate::common;

use mech::session::Session;
use mech_runtime::Model;

fn session(name: &str, text: &str) -> Session {
    Session::from_compiled(common::compile_text(name, text), &[], &[]).unwrap()
}

/// Measured: the three frequencies to 5.3e-12 relative (the linearization's differences).
#[test]
fn a_plate_on_a_bushing_oscillates_at_the_closed_form_frequencies() {
    let (m, izz, kx, ky, kt): (f64, f64, f64, f64, f64) = (0.02, 3e-6, 40.0, 90.0, 0.02);
    let text = format!(
        "
newtonian {{ frame seat = rotate(z, 30 deg); }}
body carriage {{ mass = 0 kg; }}
body lift {{ mass = 0 kg; }}
body plate {{ mass = {m} kg; inertia = [2e-6, 2e-6, {izz}] * 1 kg*m^2; }}
joint x = slider(newtonian, carriage) {{ axis = x; }}
joint y = slider(carriage, lift) {{ axis = y; }}
joint turn = pin(lift, plate) {{ axis = z; }}
bushing mount between newtonian.seat and plate {{
    stiffness = [{kx}, {ky}, 500] * 1 N/m;
    rotational_stiffness = [1, 1, {kt}] * 1 N*m/rad;
}}
"
    );
    let linear = session("plate", &text).linearization(&[], &[]).unwrap();
    let mut omega: Vec<f64> = linear
        .modes()
        .unwrap()
        .iter()
        .map(|mode| mode.natural_frequency)
        .collect();
    omega.sort_by(f64::total_cmp);
    let mut expected = [(kx / m).sqrt(), (ky / m).sqrt(), (kt / izz).sqrt()];
    expected.sort_by(f64::total_cmp);
    eprintln!("bushing plate: ω {omega:?}, closed forms {expected:?}");
    for (w, e) in omega.iter().zip(expected) {
        assert!((w - e).abs() < 1e-9 * e, "ω {w} against {e}");
    }
}

fn tumbler(damping: &str) -> String {
    format!(
        "
gravity = [0, -9.81 m/s^2, 0];
newtonian {{ frame seat = rotate(x, 20 deg) * rotate(z, 10 deg) at [0, 10 mm, 0]; }}
body c1 {{ mass = 0 kg; }}
body c2 {{ mass = 0 kg; }}
body c3 {{ mass = 0 kg; }}
body g1 {{ mass = 0 kg; }}
body g2 {{ mass = 0 kg; }}
body block {{ mass = 0.05 kg; com = [2 mm, 1 mm, 0]; inertia = [2e-5, 3e-5, 4e-5] * 1 kg*m^2; frame tip = rotate(y, 5 deg) at [10 mm, 0, 5 mm]; }}
joint x = slider(newtonian, c1) {{ axis = x; q0 = 5 mm; }}
joint y = slider(c1, c2) {{ axis = y; q0 = -3 mm; }}
joint z = slider(c2, c3) {{ axis = z; }}
joint roll = pin(c3, g1) {{ axis = x; q0 = 40 deg; }}
joint pitch = pin(g1, g2) {{ axis = y; q0 = -30 deg; }}
joint yaw = pin(g2, block) {{ axis = z; q0 = 60 deg; u0 = 2 rad/s; }}
bushing mount between newtonian.seat and block.tip {{
    stiffness = [40, 60, 80] * 1 N/m;
    rotational_stiffness = [0.01, 0.02, 0.03] * 1 N*m/rad;
    {damping}
}}
output ke = kinetic_energy;
output pe = potential_energy;
"
    )
}

/// Measured: drift 2.7e-12 of the largest kinetic energy at rtol 1e-12 over 0.5 s; with
/// damping 1.06e-2 J of 1.31e-2 J lost, never rising.
#[test]
fn an_undamped_bushing_keeps_the_energy_and_a_damped_one_loses_it() {
    let model = common::tape_from_text("tumbler", &tumbler(""));
    let (q0, u0) = common::initial_state(&model);
    let options = common::dopri5_options(0.5, 1e-3, 1e-12, 1e-14);
    let run = common::simulate_at_default_inputs(&model, &q0, &u0, &options);
    let (scale, drift) = common::energy_drift(&model, &run);
    eprintln!("tumbler: energy drift {drift:e} of {scale:e} J");
    assert!(scale > 1e-4, "it moves ({scale:e} J)");
    assert!(drift < 1e-9, "energy drifts by {drift:e}");

    let damped =
        "damping = [0.1, 0.1, 0.1] * 1 N*s/m; rotational_damping = [1, 1, 1] * 1e-4 N*m*s/rad;";
    let model = common::tape_from_text("tumbler", &tumbler(damped));
    let run = common::simulate_at_default_inputs(&model, &q0, &u0, &options);
    let (ke, pe) = (
        model.output_index("ke").unwrap(),
        model.output_index("pe").unwrap(),
    );
    let energy: Vec<f64> = run.outputs.iter().map(|y| y[ke] + y[pe]).collect();
    let rises = energy.windows(2).filter(|w| w[1] > w[0] + 1e-12).count();
    let lost = energy[0] - energy[energy.len() - 1];
    eprintln!("damped tumbler: lost {lost:e} J, {rises} rises");
    assert_eq!(rises, 0);
    assert!(lost > 0.1 * scale, "the dampers dissipate ({lost:e} J)");
}

/// The tumbler on a `free` joint (a unit quaternion, speeds the angular velocity in the block's
/// axes) against the same block on three sliders and three pins, both from the block's
/// unturned start with the same motion: the bushing's offsets go through `q̇ = W(q) u` in the
/// first and through `q̇ = u` in the second. Measured: the corner's paths 2e-13 of their size
/// apart over 0.5 s, the free version's energy drift 2.6e-12.
#[test]
fn a_bushing_on_a_free_body_moves_as_on_six_scalar_joints() {
    let euler = tumbler("")
        .replace("q0 = 40 deg; ", "")
        .replace("q0 = -30 deg; ", "")
        .replace("q0 = 60 deg; ", "")
        .replace(
            "frame tip = ",
            "point corner = [10 mm, 0, 5 mm]; frame tip = ",
        )
        + "output tip = position(block.corner);\n";
    let six = &euler[euler.find("joint x = ").unwrap()..euler.find("bushing mount").unwrap()];
    let free = euler
        .replace(
            six,
            "joint move = free(newtonian, block) { u0 = [0, 0, 2 rad/s]; }\n",
        )
        .lines()
        .filter(|line| !(line.starts_with("body c") || line.starts_with("body g")))
        .collect::<Vec<_>>()
        .join("\n");
    let options = common::dopri5_options(0.5, 1e-3, 1e-12, 1e-14);
    let runs = [("six", &euler), ("free", &free)].map(|(name, text)| {
        let model = common::tape_from_text(name, text);
        let (mut q0, u0) = common::initial_state(&model);
        for (coordinate, value) in [("move.x", 5e-3), ("move.y", -3e-3)] {
            if let Some(i) = model.coordinate_index(coordinate) {
                q0[i] = value;
            }
        }
        let run = common::simulate_at_default_inputs(&model, &q0, &u0, &options);
        let tip = model.output_index("tip.x").unwrap();
        let path: Vec<[f64; 3]> = run
            .outputs
            .iter()
            .map(|y| [y[tip], y[tip + 1], y[tip + 2]])
            .collect();
        (common::energy_drift(&model, &run), path)
    });
    let size = runs[0]
        .1
        .iter()
        .flatten()
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    let apart = runs[0]
        .1
        .iter()
        .zip(&runs[1].1)
        .flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs()))
        .fold(0.0, f64::max);
    let ((scale, drift), _) = runs[1];
    eprintln!(
        "free tumbler: path {:.1e} of its size apart, energy drift {drift:e} of {scale:e} J",
        apart / size
    );
    assert!(scale > 1e-4, "it moves ({scale:e} J)");
    assert!(apart < 1e-8 * size, "paths differ by {apart:e} m");
    assert!(drift < 1e-9, "energy drifts by {drift:e}");
}
