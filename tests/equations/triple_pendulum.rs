//! The 3D triple pendulum (full inertia tensors, skewed axis): definiteness of `M`, `M`
//! against the kinetic energy, and conservation of energy under integration.

use crate::common;

use common::{assert_close, mass_matrix, output, Rng};
use mech_runtime::Model;
use nalgebra::DMatrix;

#[test]
fn mass_matrix_is_symmetric_positive_definite_and_matches_kinetic_energy() {
    let model = mech::models::compiled("triple_pendulum_3d").unwrap();
    let mut rng = Rng::new(7);
    for _ in 0..50 {
        let q = rng.vector(3, -std::f64::consts::PI, std::f64::consts::PI);
        let u = rng.vector(3, -2.0, 2.0);
        let m = mass_matrix(model.as_ref(), &q);
        let matrix = DMatrix::from_fn(3, 3, |r, c| m[r][c]);
        assert_eq!(matrix, matrix.transpose(), "M must be exactly symmetric");
        assert!(
            matrix.clone().cholesky().is_some(),
            "M not positive definite at q = {q:?}"
        );
        // KE = ½ uᵀ M u, computed independently from the body velocities.
        let u_vec = nalgebra::DVector::from_column_slice(&u);
        let quadratic = 0.5 * (u_vec.transpose() * &matrix * &u_vec)[0];
        assert_close(
            "KE vs ½uᵀMu",
            output(model.as_ref(), "ke", &q, &u),
            quadratic,
            1e-13,
            1e-3,
        );
    }
}

#[test]
fn energy_is_conserved_over_ten_seconds() {
    let model = common::tape("triple_pendulum_3d");
    let mut q0 = [0.0; 3];
    let mut u0 = [0.0; 3];
    model.initial_state(&mut q0, &mut u0);
    let options = common::dopri5_options(10.0, 0.01, 1e-12, 1e-14);
    let run = common::simulate_at_default_inputs(&model, &q0, &u0, &options);
    let (scale, drift) = common::energy_drift(&model, &run);
    assert!(
        scale > 1.0,
        "the pendulum should swing vigorously (max KE {scale})"
    );
    assert!(drift < 1e-8, "relative energy drift {drift:e}");
}
