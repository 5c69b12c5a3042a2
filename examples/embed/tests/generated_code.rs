//! The generated double pendulum (default and split into 8-statement parts, both written
//! by build.rs) against direct evaluation of its symbolic equations, at random states.

pub mod whole {
    mech_runtime::include_model!("double_pendulum");
}

pub mod split {
    include!(concat!(env!("OUT_DIR"), "/split/double_pendulum.rs"));
}

use mech_runtime::Model;

#[test]
fn generated_code_matches_the_symbolic_equations() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/models/double_pendulum.mech");
    let compiled = mech_codegen::Compiled::from_path(path).unwrap();
    let eqs = &compiled.equations;
    let whole = whole::DoublePendulum::new();
    let split = split::DoublePendulum::new();
    let params: Vec<f64> = (0..whole.nparams()).map(|i| whole.param(i)).collect();
    let mut seed = 0.1_f64;
    for _ in 0..25 {
        let mut next = || {
            seed = (seed * 7919.0 + 0.123).fract();
            2.0 * seed - 1.0
        };
        let (q, u) = ([next(), next()], [next(), next()]);
        let value_of = |s: mech_codegen::sym::Symbol| match s {
            mech_codegen::sym::Symbol::Coordinate(i) => q[i as usize],
            mech_codegen::sym::Symbol::Speed(i) => u[i as usize],
            mech_codegen::sym::Symbol::Param(i) => params[i as usize],
            _ => f64::NAN,
        };
        let expected_m = eqs.pool.eval(&eqs.mass_matrix, &value_of);
        let expected_f = eqs.pool.eval(&eqs.forcing, &value_of);
        for model in [&whole as &dyn Model, &split] {
            let mut m = [0.0; 4];
            let mut f = [0.0; 2];
            model.mass_matrix(0.0, &q, &[], &mut m);
            model.forcing(0.0, &q, &u, &[], &mut f);
            for (a, b) in m.iter().chain(&f).zip(expected_m.iter().chain(&expected_f)) {
                assert!((a - b).abs() <= 1e-12 * b.abs().max(1e-6), "{a} vs {b}");
            }
        }
    }
}

/// The trait's methods and the `_fixed` ones give the same numbers, and both are callable
/// on a value of the generated type (neither shadows the other).
#[test]
fn fixed_size_functions_agree_with_the_trait_methods() {
    let model = whole::DoublePendulum::new();
    let q = mech_runtime::SVector::<f64, 2>::new(0.3, -0.7);
    let u = mech_runtime::SVector::<f64, 2>::new(1.1, 0.4);
    let inputs = mech_runtime::nalgebra::SVector::<f64, 0>::zeros();
    let (mut m, mut f, mut y) = ([0.0; 4], [0.0; 2], vec![0.0; model.noutputs()]);
    model.mass_matrix(0.0, q.as_slice(), &[], &mut m);
    model.forcing(0.0, q.as_slice(), u.as_slice(), &[], &mut f);
    model.outputs(0.0, q.as_slice(), u.as_slice(), &[], &mut y);
    assert_eq!(model.mass_matrix_fixed(0.0, &q, &inputs).as_slice(), &m);
    assert_eq!(model.forcing_fixed(0.0, &q, &u, &inputs).as_slice(), &f);
    assert_eq!(model.outputs_fixed(0.0, &q, &u, &inputs).as_slice(), &y[..]);
    assert_eq!(model.coordinate_index("elbow"), Some(1));
}

#[test]
fn split_build_really_has_parts() {
    let source =
        std::fs::read_to_string(concat!(env!("OUT_DIR"), "/split/double_pendulum.rs")).unwrap();
    assert!(source.contains("fn forcing_part1("));
}
