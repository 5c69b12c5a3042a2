//! Embeds a generated model and simulates it, using only mech-runtime at run time.

pub mod double_pendulum {
    mech_runtime::include_model!("double_pendulum");
}

/// The same model generated with very short functions (see build.rs).
pub mod double_pendulum_split {
    include!(concat!(env!("OUT_DIR"), "/split/double_pendulum.rs"));
}

use double_pendulum::DoublePendulum;
use mech_runtime::{Model, SimOptions};

fn main() -> Result<(), mech_runtime::RuntimeError> {
    let mut model = DoublePendulum::new();
    model.params.m2 = 0.015; // parameters are plain fields, settable at run time

    // The fixed-size API: M(q) and F(t, q, u) on nalgebra types, no allocation.
    let q = DoublePendulum::initial_q();
    let u = DoublePendulum::initial_u();
    let inputs = mech_runtime::nalgebra::SVector::<f64, 0>::zeros();
    let mass = model.mass_matrix_fixed(0.0, &q, &inputs);
    let forcing = model.forcing_fixed(0.0, &q, &u, &inputs);
    println!("M(q0) = {mass}F(q0, u0) = {forcing}");

    // The runtime's integrator through the Model trait.
    let options = SimOptions {
        t_end: 1.0,
        output_interval: 0.25,
        ..SimOptions::default()
    };
    let signals = mech_runtime::default_signals(&model);
    let run = mech_runtime::simulate(
        &model,
        q.as_slice(),
        u.as_slice(),
        &signals,
        &options,
        &mut |_| {},
    )?;
    let energy = model.output_index("energy").expect("declared in the model");
    for (t, y) in run.times.iter().zip(&run.outputs) {
        println!("t = {t:.2} s  kinetic energy = {:.6e} J", y[energy]);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The generated code (default and split into 8-statement parts) against direct
    /// evaluation of the symbolic equations, at random states.
    #[test]
    fn generated_code_matches_the_symbolic_equations() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/models/double_pendulum.mech");
        let compiled = mech_codegen::Compiled::from_path(path).unwrap();
        let eqs = &compiled.equations;
        let whole = DoublePendulum::new();
        let split = double_pendulum_split::DoublePendulum::new();
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

    #[test]
    fn split_build_really_has_parts() {
        let source =
            std::fs::read_to_string(concat!(env!("OUT_DIR"), "/split/double_pendulum.rs")).unwrap();
        assert!(source.contains("fn forcing_part1("));
    }
}
