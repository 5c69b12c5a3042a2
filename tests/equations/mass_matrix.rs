//! `M` of every bundled model against its kinetic energy: `T = ½ uᵀ M u` at random states,
//! with `T` from `kinetic_energy`, which sums `½ m v_G² + ½ ω·I ω` body by body
//! (`kane::kinetic_energy`), independently of how Kane's method assembles `M` (by composite
//! bodies, `kane/composite.rs`). Also: `M` exactly symmetric and positive definite there.

use crate::common::{self, Rng};
use mech_runtime::Model;
use nalgebra::{DMatrix, DVector};

/// Every top-level bundled model and the robot; the bicycle benchmark is checked against
/// the paper's matrices in `bicycle.rs`.
fn models() -> Vec<(String, String)> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    let mut paths: Vec<_> = std::fs::read_dir(&root)
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == "mech"))
        .collect();
    paths.push(root.join("robots/hamr_vi_robot.mech"));
    paths.sort();
    paths
        .into_iter()
        .map(|path| {
            let name = path.file_stem().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read_to_string(&path).unwrap())
        })
        .collect()
}

/// A configuration near `q0`, every coordinate moved by up to ±`spread`, the unit quaternions
/// put back on the unit sphere (loops need not close: `M` and `T` are tree quantities).
fn near(model: &dyn Model, q0: &[f64], rng: &mut Rng, spread: f64) -> Vec<f64> {
    let mut q: Vec<f64> = q0
        .iter()
        .map(|&x| x + rng.uniform(-spread, spread))
        .collect();
    mech_runtime::normalize_quaternions(model.unit_quaternions(), &mut q);
    q
}

/// `|T − ½ uᵀ M u| / T` at `(q, u)`, `T` from the output `kinetic_energy_check`; asserts that
/// `M` is exactly symmetric and positive definite there.
fn kinetic_energy_mismatch(model: &dyn Model, name: &str, q: &[f64], u: &[f64]) -> f64 {
    let n = model.nu();
    let m = common::mass_matrix(model, q);
    let matrix = DMatrix::from_fn(n, n, |r, c| m[r][c]);
    assert_eq!(matrix, matrix.transpose(), "{name}: M not symmetric");
    assert!(
        matrix.clone().cholesky().is_some(),
        "{name}: M not positive definite at q = {q:?}"
    );
    let speeds = DVector::from_column_slice(u);
    let quadratic = 0.5 * (speeds.transpose() * &matrix * &speeds)[0];
    let energy = common::output(model, "kinetic_energy_check", q, u);
    (energy - quadratic).abs() / energy.abs().max(quadratic.abs()).max(f64::MIN_POSITIVE)
}

#[test]
fn mass_matrix_is_twice_the_kinetic_energy_of_every_bundled_model() {
    let mut rng = Rng::new(2026);
    for (name, text) in models() {
        let text = format!("{text}\noutput kinetic_energy_check = kinetic_energy;\n");
        let model = common::tape_from_text(&name, &text);
        let (q0, _) = common::initial_state(&model);
        let n = model.nu();
        let mut worst: f64 = 0.0;
        for _ in 0..20 {
            // Near the model's own start (loops need not close: M and T are tree quantities).
            let q = near(&model, &q0, &mut rng, 0.3);
            let u = rng.vector(n, -2.0, 2.0);
            worst = worst.max(kinetic_energy_mismatch(&model, &name, &q, &u));
        }
        eprintln!("{name}: largest |T − ½uᵀMu| / T = {worst:.1e}");
        assert!(worst < 1e-12, "{name}: T and ½uᵀMu differ by {worst:e}");
    }
}

/// Every joint kind in one tree, with what the bundled models lack: a body welded to another
/// (two composites meeting at one frame), tilted joint frames, a child frame that is not
/// the body's, a massless link between massive ones, a slider below a ball. Checked the same
/// way, `T = ½ uᵀ M u`, with `M` from composite bodies and `T` body by body, and `F` by
/// the energy balance (no force but gravity: `d(T + V)/dt = 0` along `u̇ = M⁻¹F`).
#[test]
fn mass_matrix_and_forcing_agree_with_the_energies_for_every_joint_kind() {
    let text = "\
model every_joint;
gravity = [0, 0, -9.81 m/s^2];
body base { mass = 2 kg; com = [0.1 m, 0, 0.05 m]; inertia = [0.02, 0.03, 0.04, 0.001, 0.002, 0.003] * 1 kg*m^2;
            point pivot = [0.2 m, 0.1 m, 0]; frame side = rotate(y, 30 deg); }
body plate { mass = 0.5 kg; com = [0, 0.03 m, 0.01 m]; inertia = [2e-3, 2.5e-3, 3e-3, 1e-4, 0, 2e-4] * 1 kg*m^2; }
body link { mass = 0 kg; point end = [0, 0, -0.3 m]; }
body arm { mass = 0.3 kg; com = [0.02 m, 0, -0.1 m]; inertia = [2e-3, 2e-3, 1e-4, 0, 1e-4, 0] * 1 kg*m^2;
           point hole = [0, 0.01 m, 0]; frame skew = rotate(x, 20 deg); }
body cart { mass = 0.2 kg; com = [0.01 m, 0.02 m, 0]; inertia = [2e-4, 2.5e-4, 3e-4, 1e-5, 2e-5, 3e-5] * 1 kg*m^2; }
body rotor { mass = 0.1 kg; com = [0, 0, 0.02 m]; inertia = [5e-5, 6e-5, 7e-5, 1e-6, 2e-6, 3e-6] * 1 kg*m^2; }
body sleeve { mass = 0.15 kg; com = [0.01 m, 0, 0]; inertia = [1e-4, 1e-4, 2e-4] * 1 kg*m^2; }
body puck { mass = 0.05 kg; com = [0, 0.01 m, 0.005 m]; inertia = [2e-5, 2.5e-5, 3e-5, 0, 1e-6, 0] * 1 kg*m^2; }
body top { mass = 0.08 kg; com = [0, 0, 0.04 m]; inertia = [2e-5, 3e-5, 4e-5, 1e-6, 0, 2e-6] * 1 kg*m^2; }
joint float = free(newtonian, base) { parent_point = [0, 0, 1 m]; }
joint glue = weld(base, plate) { parent_point = [0, -0.1 m, 0.02 m]; parent_frame = base.side; }
joint shoulder = ball(base, link) { parent_point = base.pivot; }
joint elbow = universal(link, arm) { parent_point = link.end; child_point = arm.hole; child_frame = arm.skew; }
joint rail = slider(arm, cart) { axis = [0, 0.6, 0.8]; parent_frame = arm.skew; }
joint spin = pin(cart, rotor) { axis = [1, 1, 0]; parent_point = [0.02 m, 0, 0]; }
joint post = cylindrical(plate, sleeve) { axis = x; parent_point = [0, 0.05 m, 0]; }
joint table = planar(sleeve, puck) { axis = z; }
joint wrist = ball(puck, top) { rotation = euler(zxy); q0 = [0, 10 deg, 0]; }
";
    let text = format!(
        "{text}output kinetic_energy_check = kinetic_energy;\n\
         output potential_energy_check = potential_energy;\n"
    );
    let model = common::tape_from_text("every_joint", &text);
    let (q0, _) = common::initial_state(&model);
    let n = model.nu();
    let mut rng = Rng::new(17);
    let mut worst: f64 = 0.0;
    for _ in 0..50 {
        let q = near(&model, &q0, &mut rng, 0.5);
        let u = rng.vector(n, -2.0, 2.0);
        worst = worst.max(kinetic_energy_mismatch(&model, "every_joint", &q, &u));
    }
    eprintln!("every joint kind: {n} speeds, largest |T − ½uᵀMu| / T = {worst:.1e}");
    assert!(worst < 1e-12, "T and ½uᵀMu differ by {worst:e}");

    // F through the energy: only gravity acts, so along u̇ = M⁻¹F the rate of T + V (both
    // summed body by body) is zero. Central difference along (q̇, u̇), h = 1e-6 s: its error
    // is ~1e-12 of the power scale Σ|u_r F_r|, and a wrong term of F would show at O(1).
    let energy = |q: &[f64], u: &[f64]| {
        common::output(&model, "kinetic_energy_check", q, u)
            + common::output(&model, "potential_energy_check", q, u)
    };
    let mut worst_rate: f64 = 0.0;
    for _ in 0..20 {
        let q = near(&model, &q0, &mut rng, 0.5);
        let u = rng.vector(n, -2.0, 2.0);
        let udot = common::accelerations(&model, &q, &u);
        let mut qdot = vec![0.0; model.nq()];
        model.kinematic_rates(0.0, &q, &u, &mut qdot);
        let h = 1e-6;
        let step = |sign: f64| {
            let q: Vec<f64> = q.iter().zip(&qdot).map(|(x, d)| x + sign * h * d).collect();
            let u: Vec<f64> = u.iter().zip(&udot).map(|(x, d)| x + sign * h * d).collect();
            energy(&q, &u)
        };
        let rate = (step(1.0) - step(-1.0)) / (2.0 * h);
        let forcing = common::forcing(&model, &q, &u);
        let power: f64 = u.iter().zip(&forcing).map(|(a, b)| (a * b).abs()).sum();
        worst_rate = worst_rate.max(rate.abs() / power);
    }
    eprintln!("every joint kind: largest |d(T + V)/dt| / Σ|u F| = {worst_rate:.1e}");
    assert!(
        worst_rate < 1e-7,
        "energy rate {worst_rate:e} of the power scale"
    );
}
