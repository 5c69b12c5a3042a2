//! Compliant loop closures: a flexure with `twist_axis` on a revolute loop (Doshi et al.
//! Eq. 8), and the twist extension `mech diagnose` builds on the HAMR leg.

use crate::common;

use mech::diagnose::extend::{open_leg, Extension};
use mech_runtime::Model;

/// A plate on two pins (x, then y) whose revolute closure to the ground about x is compliant
/// in twist about y. The closure's bending angle is exactly `qa`, its twist exactly `qb` and
/// its lateral bending zero (derivation in the test), so its springs and dampers must equal
/// joint springs and dampers `k` on `qa`, `2k/(1 + ν)` on `qb`.
const LOOP_TWIST: &str = "
    body arm { mass = 1 mg; com = [0, 2 mm, 0]; inertia = [1e-12 kg*m^2, 2e-12 kg*m^2, 3e-12 kg*m^2]; }
    body plate {
        mass = 2 mg; com = [1 mm, 3 mm, -1 mm]; inertia = [4e-12 kg*m^2, 5e-12 kg*m^2, 6e-12 kg*m^2];
        point hinge = [0, 0, 0] * 1 m;
    }
    joint qa = pin(newtonian, arm) { axis = x; }
    joint qb = pin(arm, plate) { axis = y; }
    newtonian { point hinge = [0, 0, 0] * 1 m; }
    loop closure = revolute(newtonian, plate) {
        axis = x;
        parent_point = newtonian.hinge;
        child_point = plate.hinge;
    }
    flexure bend on closure {
        material = kapton; stiffness = 50 uN*m/rad; loss_factor = 0.08;
        reference_frequency = 40 Hz; twist_axis = y;
    }
    output pe = potential_energy;
";

/// The same springs and dampers as joint springs (2/(1 + 0.34) = 100/67).
const TREE: &str = "
    body arm { mass = 1 mg; com = [0, 2 mm, 0]; inertia = [1e-12 kg*m^2, 2e-12 kg*m^2, 3e-12 kg*m^2]; }
    body plate { mass = 2 mg; com = [1 mm, 3 mm, -1 mm]; inertia = [4e-12 kg*m^2, 5e-12 kg*m^2, 6e-12 kg*m^2]; }
    joint qa = pin(newtonian, arm) { axis = x; }
    joint qb = pin(arm, plate) { axis = y; }
    flexure bend on qa { stiffness = 50 uN*m/rad; loss_factor = 0.08; reference_frequency = 40 Hz; }
    flexure twist on qb {
        stiffness = 50 uN*m/rad * 100 / 67; loss_factor = 0.08; reference_frequency = 40 Hz;
    }
    output pe = potential_energy;
";

#[test]
fn a_loop_twist_spring_equals_the_joint_springs_it_reduces_to() {
    let looped = common::tape_from_text("loop_twist", LOOP_TWIST);
    let tree = common::tape_from_text("tree", TREE);
    // 3 position rows only: the compliant closure drops both alignment rows.
    assert_eq!(looped.nc(), 3);
    assert_eq!(looped.nflexures(), 3, "bending, twist and lateral");
    for (q, u) in [([0.3, -0.2], [1.5, -0.7]), ([-1.1, 0.9], [0.2, 2.0])] {
        let (mut f_loop, mut f_tree) = ([0.0; 2], [0.0; 2]);
        looped.forcing(0.0, &q, &u, &[], &mut f_loop);
        tree.forcing(0.0, &q, &u, &[], &mut f_tree);
        for r in 0..2 {
            assert!(
                (f_loop[r] - f_tree[r]).abs() < 1e-12 * f_tree[r].abs().max(1e-9),
                "F[{r}] at q = {q:?}: loop {} tree {}",
                f_loop[r],
                f_tree[r]
            );
        }
        let (mut pe_loop, mut pe_tree) = ([0.0], [0.0]);
        looped.outputs(0.0, &q, &u, &[], &mut pe_loop);
        tree.outputs(0.0, &q, &u, &[], &mut pe_tree);
        assert!((pe_loop[0] - pe_tree[0]).abs() < 1e-12 * pe_tree[0].abs());
        // The flexure angles: bending qa, twist qb, lateral 0.
        let mut rows = vec![0.0; 4 * looped.nflexures()];
        looped.flexures(0.0, &q, &mut rows);
        assert!((rows[0] - q[0]).abs() < 1e-14 && (rows[1] - q[1]).abs() < 1e-14);
        assert!(rows[2].abs() < 1e-14);
    }
}

/// A twist axis along the loop's own axis is a clear error, not a singular model.
#[test]
fn a_loop_twist_axis_along_the_hinge_axis_is_rejected() {
    let source = LOOP_TWIST.replace("twist_axis = y;", "twist_axis = x;");
    let error = mech_codegen::Compiled::from_source(mech_codegen::SourceFile::new(
        "bad_twist.mech",
        source,
    ))
    .unwrap_err()
    .to_string();
    assert!(
        error.contains("E0403") && error.contains("along the hinge axis"),
        "{error}"
    );
}

/// The twist extension on the HAMR leg: s3 twists about x (Eq. 8) and every hinge becomes
/// compliant off its axis (stiff springs), so the loops can deform. Its generalized forces
/// are the gradient of its potential energy (the new closure springs are conservative and
/// consistent with the energy), and the mobility grows by the new coordinates.
#[test]
fn the_twist_extension_is_conservative_and_frees_the_loops() {
    let leg = open_leg(
        &common::hamr_vi_spec(),
        &Extension::Twist(vec![("s3".into(), 0)]),
    )
    .unwrap();
    let model = leg.model();
    let nq = model.nq();
    // 8 tree coordinates, 2 per pin flexure (6 pins): 20; 3 position rows per closure.
    assert_eq!((nq, model.nc()), (20, 9));
    assert!(leg.independent.len() > 2, "{:?}", leg.independent);
    let pe_index = model.output_index("pe").unwrap();
    let potential = |q: &[f64]| {
        let mut y = vec![0.0; model.noutputs()];
        model.outputs(0.0, q, &vec![0.0; nq], &[0.0, 0.0], &mut y);
        y[pe_index]
    };
    // A configuration off the closures (the springs and rows all strained).
    let q: Vec<f64> = (0..nq)
        .map(|i| 1e-3 * ((i * 7 % 11) as f64 - 5.0))
        .collect();
    let mut force = vec![0.0; nq];
    model.forcing(0.0, &q, &vec![0.0; nq], &[0.0, 0.0], &mut force);
    let scale = force.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
    for i in 0..nq {
        let h = 1e-6;
        let (mut plus, mut minus) = (q.clone(), q.clone());
        plus[i] += h;
        minus[i] -= h;
        let gradient = (potential(&plus) - potential(&minus)) / (2.0 * h);
        assert!(
            (force[i] + gradient).abs() < 1e-6 * scale,
            "coordinate {i} ({}): F = {}, −∂V/∂q = {}",
            model.coordinate_name(i),
            force[i],
            -gradient
        );
    }
}

/// A misaligned hinge (`mech diagnose`'s misalignment): the extension turns a pin's axis `a`
/// by α about a coordinate axis `p` (Rodrigues' formula in expressions of α), and a loop
/// closure's two interframes by α about `p` (its axis and the directions tied to it alike).
/// Independent construction: the same model with the hinge's axis written as the numbers of
/// `R(p, α)·a` (for a loop closure, its reference and twist directions are then computed ⊥
/// the tilted axis by the derivation itself) and α = 0. For l3 (the lift crank's loop
/// hinge, about y) and l2 (a pin of the lift linkage, about y) the two must give the same
/// rest configuration and the same foot under a 225 V lift drive and a 225 V swing drive (to
/// 1e-9 m), and differ from the aligned model by far more.
#[test]
fn a_tilted_hinge_equals_one_written_tilted() {
    use mech::diagnose::extend::apply;
    use mech::experiments::leg::Leg;
    use mech::session::Session;
    use mech_codegen::ir::transform::constant_direction;
    use mech_codegen::ir::transform::hinge::MISALIGNMENT;
    use mech_codegen::ir::{ClosureKind, Expr, FlexureAngle, Motion};
    use mech_codegen::sym::Number;
    use mech_codegen::Compiled;

    let spec = common::hamr_vi_spec();
    let alpha = 0.03_f64;
    let leg_of = |model: mech_codegen::ir::Model, tilt: f64| {
        let session = Session::from_compiled(Compiled::from_model(model), &[], &[]).unwrap();
        let mut leg = Leg::from_session(session, &spec, &[]).unwrap();
        let index = leg.model().param_index(MISALIGNMENT).unwrap();
        leg.session.model.set_param(index, tilt);
        leg
    };
    let feet = common::feet_at_rest_and_225_volts;
    let base = Compiled::from_path(&spec.path).unwrap().model;
    for (hinge, about) in [("l3", 1), ("l2", 1)] {
        let extension = Extension::Misalignment {
            flexure: hinge.into(),
            about,
        };
        let mut turned = base.clone();
        apply(&mut turned, &extension).unwrap();

        let mut written = base.clone();
        let angle = written
            .flexures
            .iter()
            .find(|f| f.name == hinge)
            .unwrap()
            .angle;
        let axis = match angle {
            FlexureAngle::Loop(index) => match &mut written.loops[index].kind {
                ClosureKind::Revolute { axis, .. } => axis,
                _ => panic!("a revolute closure"),
            },
            FlexureAngle::Coordinate(coordinate) => {
                let frame = written
                    .frames
                    .iter()
                    .find_map(|(handle, frame)| match &frame.motion {
                        Motion::Revolute { coordinate: c, .. } if *c == coordinate => Some(handle),
                        _ => None,
                    })
                    .unwrap();
                match &mut written.frames.get_mut(frame).motion {
                    Motion::Revolute { axis, .. } => axis,
                    _ => panic!("a pin"),
                }
            }
            _ => panic!("a bending hinge"),
        };
        // R(p, α)·a for the unit coordinate axis p, a ⊥ p: a cos α + (p × a) sin α.
        let a = constant_direction(axis).unwrap();
        let (j, k) = ((about + 1) % 3, (about + 2) % 3);
        let mut p_cross_a = [0.0; 3];
        p_cross_a[j] = -a[k];
        p_cross_a[k] = a[j];
        let tilted: Vec<Expr> = (0..3)
            .map(|i| {
                Expr::Number(Number::Float(
                    a[i] * alpha.cos() + p_cross_a[i] * alpha.sin(),
                ))
            })
            .collect();
        *axis = [tilted[0].clone(), tilted[1].clone(), tilted[2].clone()];
        apply(&mut written, &extension).unwrap();

        let mut aligned = base.clone();
        apply(&mut aligned, &extension).unwrap();

        let (turned, written, aligned) = (
            feet(&leg_of(turned, alpha)),
            feet(&leg_of(written, 0.0)),
            feet(&leg_of(aligned, 0.0)),
        );
        let (same, tilt_effect) = (
            largest_foot_difference(&turned, &written),
            largest_foot_difference(&turned, &aligned),
        );
        eprintln!("{hinge}: turned vs written {same:.3e} m, vs aligned {tilt_effect:.3e} m");
        assert!(
            same < 1e-9,
            "{hinge}: turned {turned:?}\nwritten {written:?}"
        );
        assert!(
            tilt_effect > 1e-6,
            "{hinge}: the tilt moves the foot by only {tilt_effect:.3e} m"
        );
    }
}

/// The hinge extensions `mech diagnose` fits against the same effects written by hand as
/// pins and rigid loops (`common::WrittenEffect`): fb3 twisting about y (Eq. 8) with the
/// other hinges 4e-4 compliant off their axes (the catalog's twist), and l2 tilted 1.5° about
/// y with every hinge 1e-4 compliant (its misalignment). The two formulations differ only at
/// second order in the off-axis angles. Measured: the blocked swing force (225 V, 30 % side
/// load) within 6e-5 relative of each other, the twist removing 42 % of it; the feet along the
/// 225 V drive within 5 nm, the tilt moving them by up to 1 mm.
#[test]
fn the_hinge_extensions_equal_the_effects_written_by_hand() {
    use common::WrittenEffect;
    use mech::experiments::leg::Leg;
    use mech_codegen::ir::transform::hinge::{MISALIGNMENT, OFF_AXIS_COMPLIANCE, TWIST_FACTOR};

    let dir = common::scratch_dir("written_hinges");
    let transformed = |extension: Extension, params: &[(&str, f64)]| {
        let mut leg = open_leg(&common::hamr_vi_spec(), &extension).unwrap();
        for &(name, value) in params {
            common::set_leg_param(&mut leg, name, value);
        }
        leg
    };
    let blocked = blocked_swing_force;
    let feet = |leg: &Leg| -> Vec<[f64; 3]> {
        common::feet_along_the_drive(leg)
            .into_iter()
            .map(|(_, _, foot)| foot)
            .collect()
    };
    let base = Leg::open(&common::hamr_vi_spec()).unwrap();

    let c = 4e-4;
    let effect = WrittenEffect::Twist {
        hinges: &[("fb3", 1)],
        off_axis_compliance: c,
    };
    let written = common::hamr_vi_written(effect, &dir);
    let fitted = transformed(
        Extension::Twist(vec![("fb3".into(), 1)]),
        &[(TWIST_FACTOR, 1.0), (OFF_AXIS_COMPLIANCE, c)],
    );
    let (written_force, fitted_force) = (blocked(&written), blocked(&fitted));
    let loss = 1.0 - written_force / blocked(&base);
    assert!(
        (written_force / fitted_force - 1.0).abs() < 1e-3 && loss > 0.3,
        "blocked swing force: written {written_force}, transformed {fitted_force}, \
         loss {loss}"
    );
    let same = largest_foot_difference(&feet(&written), &feet(&fitted));
    assert!(same < 2e-8, "twist: feet {same:e} m apart");

    let angle = 1.5f64.to_radians();
    let effect = WrittenEffect::Tilt {
        flexure: "l2",
        about: 1,
        angle,
        off_axis_compliance: 1e-4,
    };
    let written = feet(&common::hamr_vi_written(effect, &dir));
    let fitted = feet(&transformed(
        Extension::Misalignment {
            flexure: "l2".into(),
            about: 1,
        },
        &[(MISALIGNMENT, angle), (OFF_AXIS_COMPLIANCE, 1e-4)],
    ));
    let (same, effect) = (
        largest_foot_difference(&written, &fitted),
        largest_foot_difference(&written, &feet(&base)),
    );
    assert!(
        same < 2e-8 && effect > 5e-4,
        "tilt: feet {same:e} m apart, {effect:e} m from the aligned leg's"
    );
}

/// The largest coordinate difference between two lists of foot positions (m).
fn largest_foot_difference(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(a, b)| (0..3).map(move |i| (a[i] - b[i]).abs()))
        .fold(0.0_f64, f64::max)
}

/// The hinges around each loop of the HAMR-VI leg: each crank-slider's three (the slider
/// is no hinge) and the spherical five-bar's five, which shares s3 and l3 with the
/// crank-sliders (read off the model's comment: chassis, swing crank, SFB swing link, leg,
/// lift crank); and the four-bar's four.
#[test]
fn the_hinges_around_each_loop_are_the_shortest_cycles() {
    use mech_codegen::ir::transform::hinge::loop_flexures;
    let loops = |path: &str| {
        let compiled = mech_codegen::Compiled::from_path(path).unwrap();
        loop_flexures(&compiled.model)
    };
    let names = |sets: &[&[&str]]| -> Vec<Vec<String>> {
        sets.iter()
            .map(|set| set.iter().map(|s| s.to_string()).collect())
            .collect()
    };
    assert_eq!(
        loops("models/hamr_vi.mech"),
        names(&[
            &["s1", "s2", "s3"],
            &["l1", "l2", "l3"],
            &["s3", "l3", "fb1", "fb2", "fb3"],
        ])
    );
    assert_eq!(
        loops("models/compliant_four_bar.mech"),
        names(&[&["crank_hinge", "coupler_hinge", "rocker_hinge", "tip_hinge"]])
    );
}

/// The model on which `mech diagnose` searches a loop's twist axes (one derivation, a
/// parameter per hinge picking its length axis) equals the twist written by hand with the
/// axes it picks: four hinges of the spherical five-bar twisting (which unlocks the loop and
/// removes ~43 % of the blocked swing force), the blocked swing force within 1e-3 relative
/// (first order in the off-axis angles, as above); the opposite picks differ by over 10 %.
#[test]
fn the_twist_axis_search_equals_the_twist_written_by_hand() {
    use common::WrittenEffect;
    use mech::experiments::leg::Leg;
    use mech_codegen::ir::transform::hinge::{twist_choice, OFF_AXIS_COMPLIANCE};

    let dir = common::scratch_dir("written_loop_twist");
    let blocked = blocked_swing_force;
    let c = 1e-4;
    let effect = WrittenEffect::Twist {
        hinges: &[("s3", 0), ("fb1", 2), ("fb2", 2), ("fb3", 0)],
        off_axis_compliance: c,
    };
    let written = blocked(&common::hamr_vi_written(effect, &dir));
    let hinges = ["s3", "fb1", "fb2", "fb3"];
    let extension = Extension::TwistChoices(hinges.iter().map(|h| h.to_string()).collect());
    let searched = |picks: [f64; 4]| {
        let mut leg = open_leg(&common::hamr_vi_spec(), &extension).unwrap();
        common::set_leg_param(&mut leg, OFF_AXIS_COMPLIANCE, c);
        for (hinge, pick) in hinges.iter().zip(picks) {
            common::set_leg_param(&mut leg, &twist_choice(hinge), pick);
        }
        blocked(&leg)
    };
    // Bending z: x then y; x: y then z; y: z then x.
    let same = searched([0.0, 1.0, 0.0, 0.0]);
    let opposite = searched([1.0, 0.0, 1.0, 1.0]);
    let base = blocked(&Leg::open(&common::hamr_vi_spec()).unwrap());
    assert!(
        (same / written - 1.0).abs() < 1e-3
            && (opposite / written - 1.0).abs() > 0.1
            && 1.0 - written / base > 0.3,
        "blocked swing force: written {written}, searched {same}, opposite {opposite}, \
         base {base}"
    );
}

/// The blocked swing force at 225 V with the sensor's 30 % side load (N).
fn blocked_swing_force(leg: &mech::experiments::leg::Leg) -> f64 {
    use mech::experiments::leg::{Dof, ForceTest, Sensor};
    ForceTest::new(Dof::Swing, 225.0, Sensor::Blocked)
        .off_axis(0.3)
        .run(leg)
        .unwrap()
        .blocked_force()
}
