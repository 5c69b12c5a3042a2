//! Compliant loop closures: a flexure with `twist_axis` on a revolute loop (Doshi et al.
//! Eq. 8), and the twist extension `mech diagnose` builds on the HAMR leg.

mod common;

use mech::diagnose::extend::{open_leg, Extension};
use mech::experiments::ModelSpec;
use mech::tape_model::TapeModel;
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
    let looped = TapeModel::new(&common::compile_text("loop_twist", LOOP_TWIST));
    let tree = TapeModel::new(&common::compile_text("tree", TREE));
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

fn hamr_spec() -> ModelSpec {
    ModelSpec {
        model: std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/hamr_vi.mech"),
        set: Vec::new(),
        independent: vec!["qsact".into(), "qlact".into()],
    }
}

/// The twist extension on the HAMR leg: s3 twists about x (Eq. 8) and every hinge becomes
/// compliant off its axis (stiff springs), so the loops can deform. Its generalized forces
/// are the gradient of its potential energy (the new closure springs are conservative and
/// consistent with the energy), and the mobility grows by the new coordinates.
#[test]
fn the_twist_extension_is_conservative_and_frees_the_loops() {
    let leg = open_leg(&hamr_spec(), &Extension::Twist(vec![("s3".into(), 0)])).unwrap();
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
