//! `universal`, `cylindrical` and `planar` joints against the same bodies on explicit pins and
//! sliders with massless links between them (an independent formulation: the chain of
//! single-coordinate joints the compound joint stands for, written out by hand):
//! - universal = a pin about `axis`, then a pin about `axis2` in the turned frame;
//! - cylindrical = a slider along `axis`, then a pin about it;
//! - planar = sliders along the plane's two directions (for `axis = y`: z, then x), then a
//!   pin about `axis`.
//!
//! Each pair has the same coordinates in the same order, so `M(q)`, `F(q, u)` and the
//! energies agree at random states to 1e-12 (springs and dampers given per coordinate on the
//! compound joint, per joint on the chain), and the initial state written as vectors on the
//! compound joint is the chain's. The language reference's examples of these kinds simulate,
//! conserving energy where they have no damper.

use crate::common;

use crate::language_doc::language_reference_examples;
use crate::quaternion_joints::energy_drift_over_one_second;
use common::Rng;
use mech_runtime::Model;

/// `M` and `F` of both models at `count` random states, to 1e-12 relative to their size.
fn assert_same_equations(compound: &dyn Model, chain: &dyn Model, count: usize) {
    assert_eq!((compound.nq(), compound.nu()), (chain.nq(), chain.nu()));
    let (nq, nu) = (compound.nq(), compound.nu());
    let (mut ic, mut uc) = (vec![0.0; nq], vec![0.0; nu]);
    let (mut ie, mut ue) = (vec![0.0; nq], vec![0.0; nu]);
    compound.initial_state(&mut ic, &mut uc);
    chain.initial_state(&mut ie, &mut ue);
    assert_eq!((&ic, &uc), (&ie, &ue), "initial states differ");
    let inputs = common::default_inputs(compound);
    let mut rng = Rng::new(15);
    for _ in 0..count {
        let q = rng.vector(nq, -2.0, 2.0);
        let u = rng.vector(nu, -3.0, 3.0);
        let t = rng.uniform(0.0, 1.0);
        let (mut mc, mut me) = (vec![0.0; nu * nu], vec![0.0; nu * nu]);
        compound.mass_matrix(t, &q, &inputs, &mut mc);
        chain.mass_matrix(t, &q, &inputs, &mut me);
        let (mut fc, mut fe) = (vec![0.0; nu], vec![0.0; nu]);
        compound.forcing(t, &q, &u, &inputs, &mut fc);
        chain.forcing(t, &q, &u, &inputs, &mut fe);
        for (what, a, b) in [("M", &mc, &me), ("F", &fc, &fe)] {
            let scale = b.iter().fold(1.0_f64, |m, x| m.max(x.abs()));
            for (i, (x, y)) in a.iter().zip(b.iter()).enumerate() {
                assert!(
                    (x - y).abs() <= 1e-12 * scale,
                    "{what}[{i}] at q = {q:?}, u = {u:?}: {x} (compound) vs {y} (chain)"
                );
            }
        }
        let (mut oc, mut oe) = (vec![0.0; compound.noutputs()], vec![0.0; chain.noutputs()]);
        compound.outputs(t, &q, &u, &inputs, &mut oc);
        chain.outputs(t, &q, &u, &inputs, &mut oe);
        for (x, y) in oc.iter().zip(&oe) {
            assert!(
                (x - y).abs() <= 1e-12 * (1.0 + y.abs()),
                "outputs {oc:?} vs {oe:?}"
            );
        }
    }
}

const BODIES: &str = "
    gravity = [0.5 m/s^2, -9.81 m/s^2, 1.5 m/s^2];
    body base { mass = 0.7 kg; com = [0.03 m, -0.02 m, 0.05 m]; inertia = [3e-3, 5e-3, 4e-3] * 1 kg*m^2; frame tilted = rotate(x, 20 deg); }
    body arm { mass = 0.3 kg; com = [0.02 m, -0.1 m, 0.03 m]; inertia = [2e-3, 3e-3, 4e-3] * 1 kg*m^2; point hole = [0.01 m, 0.04 m, 0]; }
    output ke = kinetic_energy;
    output pe = potential_energy;
";

fn pair(name: &str, compound: &str, chain: &str) -> (impl Model, impl Model) {
    (
        common::tape_from_text(&format!("{name}_compound"), &format!("{BODIES}{compound}")),
        common::tape_from_text(&format!("{name}_chain"), &format!("{BODIES}{chain}")),
    )
}

/// A universal joint on a moving base (pinned to ground), tilted by `parent_frame`, with
/// springs and dampers, against two pins and a massless gimbal.
#[test]
fn universal_is_two_pins_in_series() {
    let (compound, chain) = pair(
        "universal",
        "joint mount = pin(newtonian, base) { axis = z; q0 = 5 deg; }
         joint hooke = universal(base, arm) {
             axis = x; axis2 = [0, 3, 4];
             parent_point = [0.05 m, 0, 0]; parent_frame = base.tilted; child_point = arm.hole;
             q0 = [10 deg, -20 deg]; u0 = [1 rad/s, -2 rad/s];
             stiffness = [0.5 N*m/rad, 0.2 N*m/rad]; rest = [5 deg, 0 deg];
             damping = [0.01 N*m*s/rad, 0.03 N*m*s/rad];
         }",
        "body gimbal { mass = 0 kg; }
         joint mount = pin(newtonian, base) { axis = z; q0 = 5 deg; }
         joint first = pin(base, gimbal) {
             axis = x; parent_point = [0.05 m, 0, 0]; parent_frame = base.tilted;
             q0 = 10 deg; u0 = 1 rad/s; stiffness = 0.5 N*m/rad; rest = 5 deg; damping = 0.01 N*m*s/rad;
         }
         joint second = pin(gimbal, arm) {
             axis = [0, 3, 4]; child_point = arm.hole;
             q0 = -20 deg; u0 = -2 rad/s; stiffness = 0.2 N*m/rad; damping = 0.03 N*m*s/rad;
         }",
    );
    assert_eq!(compound.coordinate_name(1), "hooke.angle1");
    assert_eq!(compound.coordinate_name(2), "hooke.angle2");
    assert_same_equations(&compound, &chain, 50);
}

/// A universal joint without axes turns about x, then y.
#[test]
fn universal_axes_default_to_x_then_y() {
    let (compound, chain) = pair(
        "universal_default",
        "joint mount = weld(newtonian, base);
         joint hooke = universal(base, arm);",
        "body gimbal { mass = 0 kg; }
         joint mount = weld(newtonian, base);
         joint first = pin(base, gimbal) { axis = x; }
         joint second = pin(gimbal, arm) { axis = y; }",
    );
    assert_same_equations(&compound, &chain, 20);
}

#[test]
fn cylindrical_is_a_slider_then_a_pin() {
    let (compound, chain) = pair(
        "cylindrical",
        "joint mount = pin(newtonian, base) { axis = y; }
         joint sleeve = cylindrical(base, arm) {
             axis = [1, 2, 2]; parent_point = [0, 0.1 m, 0]; parent_frame = base.tilted;
             q0 = [3 mm, 30 deg]; u0 = [0.1 m/s, 2 rad/s];
             stiffness = [40 N/m, 0.3 N*m/rad]; rest = [1 mm, 0 deg];
             damping = [0.2 N*s/m, 0.01 N*m*s/rad];
         }",
        "body carriage { mass = 0 kg; }
         joint mount = pin(newtonian, base) { axis = y; }
         joint along = slider(base, carriage) {
             axis = [1, 2, 2]; parent_point = [0, 0.1 m, 0]; parent_frame = base.tilted;
             q0 = 3 mm; u0 = 0.1 m/s; stiffness = 40 N/m; rest = 1 mm; damping = 0.2 N*s/m;
         }
         joint about = pin(carriage, arm) {
             axis = [1, 2, 2]; q0 = 30 deg; u0 = 2 rad/s; stiffness = 0.3 N*m/rad; damping = 0.01 N*m*s/rad;
         }",
    );
    assert_eq!(compound.coordinate_name(1), "sleeve.slide");
    assert_eq!(compound.coordinate_name(2), "sleeve.angle");
    assert_same_equations(&compound, &chain, 50);
}

/// A planar joint normal to y slides along z, then x (the right-handed pair after y), then
/// turns about y.
#[test]
fn planar_is_two_sliders_then_a_pin() {
    let (compound, chain) = pair(
        "planar",
        "joint mount = pin(newtonian, base) { axis = x; q0 = 10 deg; }
         joint table = planar(base, arm) {
             axis = y; parent_point = [0, 0.02 m, 0.01 m]; child_point = arm.hole;
             q0 = [1 mm, 2 mm, 45 deg]; u0 = [0.1 m/s, -0.2 m/s, 3 rad/s];
             stiffness = [30 N/m, 50 N/m, 0.1 N*m/rad];
             damping = [0.1 N*s/m, 0.3 N*s/m, 0.002 N*m*s/rad];
         }",
        "body first_carriage { mass = 0 kg; }
         body second_carriage { mass = 0 kg; }
         joint mount = pin(newtonian, base) { axis = x; q0 = 10 deg; }
         joint along_z = slider(base, first_carriage) {
             axis = z; parent_point = [0, 0.02 m, 0.01 m];
             q0 = 1 mm; u0 = 0.1 m/s; stiffness = 30 N/m; damping = 0.1 N*s/m;
         }
         joint along_x = slider(first_carriage, second_carriage) {
             axis = x; q0 = 2 mm; u0 = -0.2 m/s; stiffness = 50 N/m; damping = 0.3 N*s/m;
         }
         joint about_y = pin(second_carriage, arm) {
             axis = y; child_point = arm.hole;
             q0 = 45 deg; u0 = 3 rad/s; stiffness = 0.1 N*m/rad; damping = 0.002 N*m*s/rad;
         }",
    );
    let names: Vec<&str> = (1..4).map(|i| compound.coordinate_name(i)).collect();
    assert_eq!(names, ["table.slide1", "table.slide2", "table.angle"]);
    assert_same_equations(&compound, &chain, 50);
}

/// A planar joint about a slanted normal n = (0, 3, 4)/5 slides along the projection of x
/// (after n's largest component, z), (1, 0, 0), then n × x = (0, 4, −3)/5.
#[test]
fn planar_about_a_slanted_normal() {
    let (compound, chain) = pair(
        "planar_slanted",
        "joint mount = weld(newtonian, base);
         joint table = planar(base, arm) { axis = [0, 3, 4]; q0 = [1 mm, 2 mm, 45 deg]; }",
        "body first_carriage { mass = 0 kg; }
         body second_carriage { mass = 0 kg; }
         joint mount = weld(newtonian, base);
         joint a = slider(base, first_carriage) { axis = x; q0 = 1 mm; }
         joint b = slider(first_carriage, second_carriage) { axis = [0, 4, -3]; q0 = 2 mm; }
         joint c = pin(second_carriage, arm) { axis = [0, 3, 4]; q0 = 45 deg; }",
    );
    assert_same_equations(&compound, &chain, 20);
}

/// The `universal`, `cylindrical` and `planar` examples of `docs/mech-language.md` run for
/// 1 s; those without a damper keep their energy to 1e-9.
#[test]
fn language_reference_examples_of_compound_joints_simulate() {
    let mut checked = 0;
    for (name, text) in language_reference_examples() {
        let kinds = ["= universal(", "= cylindrical(", "= planar("];
        if !kinds.iter().any(|kind| text.contains(kind)) {
            continue;
        }
        checked += 1;
        let model = common::tape_from_text(&name, &text);
        let drift = energy_drift_over_one_second(&model);
        eprintln!("{name}: energy drift {drift:.1e} over 1 s");
        if !text.contains("damping") {
            assert!(drift < 1e-9, "{name}: energy drift {drift:e}");
        }
    }
    assert!(checked >= 3, "only {checked} examples of compound joints");
}
