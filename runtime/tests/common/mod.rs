//! Helpers shared by the runtime's test binaries (each includes this file with `mod common;`).

// Each binary uses only some of these.
#![allow(dead_code, unused_macros, unused_imports)]

use mech_runtime::integrate::Stepper;

/// Steps `stepper` to its end time.
pub fn run_to_end(stepper: &mut dyn Stepper) {
    while !stepper.is_finished() {
        stepper.step().unwrap();
    }
}

/// Steps `stepper` to its end time and returns the largest `error(t, x)` of its dense output
/// `x` at the fractions `thetas` of every step.
pub fn worst_dense_error(
    stepper: &mut dyn Stepper,
    thetas: &[f64],
    mut error: impl FnMut(f64, &[f64]) -> f64,
) -> f64 {
    let mut out = vec![0.0; stepper.state().len()];
    let mut worst: f64 = 0.0;
    while !stepper.is_finished() {
        stepper.step().unwrap();
        for theta in thetas {
            let t = stepper.t_prev() + theta * (stepper.t() - stepper.t_prev());
            stepper.interpolate(t, &mut out).unwrap();
            worst = worst.max(error(t, &out));
        }
    }
    worst
}

/// The `Model` methods that only describe a hand-written model: its name, the names of its
/// coordinates (one speed each), inputs (default 0) and outputs, its parameters (fields of the
/// struct, named after them) and its initial state (at rest at `initial_q`). Written inside an
/// `impl Model for …` block, so that each test model spells out only its dynamics.
macro_rules! model_metadata {
    (
        name: $name:literal,
        coordinates: [$($coordinate:literal),* $(,)?],
        initial_q: [$($q0:expr),* $(,)?],
        inputs: [$($input:literal),* $(,)?],
        outputs: [$($output:literal),* $(,)?],
        params: [$($param:ident),* $(,)?] $(,)?
    ) => {
        fn name(&self) -> &str {
            $name
        }
        fn nq(&self) -> usize {
            <[&str]>::len(&[$($coordinate),*])
        }
        fn nu(&self) -> usize {
            self.nq()
        }
        fn ninputs(&self) -> usize {
            <[&str]>::len(&[$($input),*])
        }
        fn noutputs(&self) -> usize {
            <[&str]>::len(&[$($output),*])
        }
        fn nparams(&self) -> usize {
            <[&str]>::len(&[$(stringify!($param)),*])
        }
        fn coordinate_name(&self, i: usize) -> &str {
            [$($coordinate),*][i]
        }
        fn input_name(&self, i: usize) -> &str {
            let names: &[&str] = &[$($input),*];
            names[i]
        }
        fn output_name(&self, i: usize) -> &str {
            let names: &[&str] = &[$($output),*];
            names[i]
        }
        fn param_name(&self, i: usize) -> &str {
            let names: &[&str] = &[$(stringify!($param)),*];
            names[i]
        }
        fn param(&self, i: usize) -> f64 {
            let values: &[f64] = &[$(self.$param),*];
            values[i]
        }
        fn set_param(&mut self, i: usize, value: f64) {
            let fields: &mut [&mut f64] = &mut [$(&mut self.$param),*];
            *fields[i] = value;
        }
        fn input_default(&self, _i: usize) -> f64 {
            0.0
        }
        fn initial_state(&self, q: &mut [f64], u: &mut [f64]) {
            q.copy_from_slice(&[$($q0),*]);
            u.fill(0.0);
        }
    };
}

pub(crate) use model_metadata;
