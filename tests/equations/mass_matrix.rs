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
            let mut q: Vec<f64> = q0.iter().map(|&x| x + rng.uniform(-0.3, 0.3)).collect();
            for &first in model.unit_quaternions() {
                let norm = q[first..first + 4]
                    .iter()
                    .map(|x| x * x)
                    .sum::<f64>()
                    .sqrt();
                q[first..first + 4].iter_mut().for_each(|x| *x /= norm);
            }
            let u = rng.vector(n, -2.0, 2.0);
            let m = common::mass_matrix(&model, &q);
            let matrix = DMatrix::from_fn(n, n, |r, c| m[r][c]);
            assert_eq!(matrix, matrix.transpose(), "{name}: M not symmetric");
            assert!(
                matrix.clone().cholesky().is_some(),
                "{name}: M not positive definite at q = {q:?}"
            );
            let u = DVector::from_column_slice(&u);
            let quadratic = 0.5 * (u.transpose() * &matrix * &u)[0];
            let energy = common::output(&model, "kinetic_energy_check", &q, u.as_slice());
            let scale = energy.abs().max(quadratic.abs()).max(f64::MIN_POSITIVE);
            worst = worst.max((energy - quadratic).abs() / scale);
        }
        eprintln!("{name}: largest |T − ½uᵀMu| / T = {worst:.1e}");
        assert!(worst < 1e-12, "{name}: T and ½uᵀMu differ by {worst:e}");
    }
}
