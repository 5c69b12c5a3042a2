//! A model run through the tape evaluator, so any `.mech` file can be simulated without
//! compiling Rust.
//!
//! Consumes: a [`Compiled`] model (IR + equations). Produces: a [`TapeModel`] implementing
//! [`mech_runtime::Model`], the same contract generated code implements.

use std::cell::RefCell;

use mech_codegen::back::tape::{Env, Program, Tape};
use mech_codegen::Compiled;

/// The tape of a model with its names, defaults and current parameter values.
#[derive(Clone, Debug)]
pub struct TapeModel {
    name: String,
    tape: Tape,
    coordinate_names: Vec<String>,
    input_names: Vec<String>,
    output_names: Vec<String>,
    constraint_names: Vec<String>,
    flexure_names: Vec<String>,
    param_names: Vec<String>,
    params: Vec<f64>,
    input_defaults: Vec<f64>,
    q0: Vec<f64>,
    u0: Vec<f64>,
    /// Registers reused across evaluations (the evaluator never allocates after warm-up).
    registers: RefCell<Vec<f64>>,
}

impl TapeModel {
    /// The tape's environment at `(t, q, u, inputs)` with the current parameter values.
    fn env<'a>(&'a self, t: f64, q: &'a [f64], u: &'a [f64], inputs: &'a [f64]) -> Env<'a> {
        Env {
            t,
            q,
            u,
            params: &self.params,
            inputs,
        }
    }

    pub fn new(compiled: &Compiled) -> TapeModel {
        let model = &compiled.model;
        TapeModel {
            name: model.name.clone(),
            tape: compiled.tape(),
            coordinate_names: model
                .coordinates
                .iter()
                .map(|(_, c)| c.name.clone())
                .collect(),
            input_names: model.inputs.iter().map(|(_, i)| i.name.clone()).collect(),
            output_names: compiled.equations.output_names.clone(),
            constraint_names: compiled.equations.constraints.names.clone(),
            flexure_names: compiled.equations.flexures.names.clone(),
            param_names: model.params.iter().map(|(_, p)| p.name.clone()).collect(),
            params: model.params.iter().map(|(_, p)| p.value).collect(),
            input_defaults: model.inputs.iter().map(|(_, i)| i.default).collect(),
            q0: model.coordinates.iter().map(|(_, c)| c.initial).collect(),
            u0: model
                .coordinates
                .iter()
                .map(|(_, c)| c.initial_speed)
                .collect(),
            registers: RefCell::new(Vec::new()),
        }
    }

    pub fn tape(&self) -> &Tape {
        &self.tape
    }

    fn run(&self, program: &Program, env: &Env, out: &mut [f64]) {
        program.eval(env, &mut self.registers.borrow_mut(), out);
    }

    /// Runs `program` at `(t, q, u, inputs)` into `out`.
    fn eval(
        &self,
        program: &Program,
        t: f64,
        q: &[f64],
        u: &[f64],
        inputs: &[f64],
        out: &mut [f64],
    ) {
        self.run(program, &self.env(t, q, u, inputs), out);
    }
}

fn name_at(names: &[String], i: usize) -> &str {
    names.get(i).map_or("", String::as_str)
}

impl mech_runtime::Model for TapeModel {
    fn name(&self) -> &str {
        &self.name
    }
    fn nq(&self) -> usize {
        self.tape.nq
    }
    fn nu(&self) -> usize {
        self.tape.nu
    }
    fn ninputs(&self) -> usize {
        self.input_names.len()
    }
    fn noutputs(&self) -> usize {
        self.output_names.len()
    }
    fn nparams(&self) -> usize {
        self.params.len()
    }
    fn coordinate_name(&self, i: usize) -> &str {
        name_at(&self.coordinate_names, i)
    }
    fn input_name(&self, i: usize) -> &str {
        name_at(&self.input_names, i)
    }
    fn output_name(&self, i: usize) -> &str {
        name_at(&self.output_names, i)
    }
    fn param_name(&self, i: usize) -> &str {
        name_at(&self.param_names, i)
    }
    fn param(&self, i: usize) -> f64 {
        self.params.get(i).copied().unwrap_or(f64::NAN)
    }
    fn set_param(&mut self, i: usize, value: f64) {
        if let Some(slot) = self.params.get_mut(i) {
            *slot = value;
        }
    }
    fn input_default(&self, i: usize) -> f64 {
        self.input_defaults.get(i).copied().unwrap_or(f64::NAN)
    }
    fn initial_state(&self, q: &mut [f64], u: &mut [f64]) {
        for (slot, value) in q.iter_mut().zip(&self.q0) {
            *slot = *value;
        }
        for (slot, value) in u.iter_mut().zip(&self.u0) {
            *slot = *value;
        }
    }
    fn mass_matrix(&self, t: f64, q: &[f64], inputs: &[f64], out: &mut [f64]) {
        self.eval(&self.tape.mass_matrix, t, q, &[], inputs, out);
    }
    fn forcing(&self, t: f64, q: &[f64], u: &[f64], inputs: &[f64], out: &mut [f64]) {
        self.eval(&self.tape.forcing, t, q, u, inputs, out);
    }
    fn static_forcing(&self, t: f64, q: &[f64], inputs: &[f64], out: &mut [f64]) {
        let Some(program) = &self.tape.static_forcing else {
            return self.forcing(t, q, &vec![0.0; self.tape.nu], inputs, out);
        };
        self.eval(program, t, q, &[], inputs, out);
    }
    fn outputs(&self, t: f64, q: &[f64], u: &[f64], inputs: &[f64], out: &mut [f64]) {
        self.eval(&self.tape.outputs, t, q, u, inputs, out);
    }
    fn selected_outputs(
        &self,
        t: f64,
        q: &[f64],
        u: &[f64],
        inputs: &[f64],
        which: &[usize],
        out: &mut [f64],
    ) -> bool {
        let env = self.env(t, q, u, inputs);
        for (&row, value) in which.iter().zip(out.iter_mut()) {
            self.run(
                &self.tape.output_rows[row],
                &env,
                std::slice::from_mut(value),
            );
        }
        true
    }
    fn nc(&self) -> usize {
        self.tape.nc
    }
    fn constraint_name(&self, i: usize) -> &str {
        name_at(&self.constraint_names, i)
    }
    fn constraints(&self, t: f64, q: &[f64], out: &mut [f64]) {
        self.eval(&self.tape.constraints, t, q, &[], &[], out);
    }
    fn constraint_jacobian(&self, t: f64, q: &[f64], out: &mut [f64]) {
        self.eval(&self.tape.constraint_jacobian, t, q, &[], &[], out);
    }
    fn constraint_bias(&self, t: f64, q: &[f64], u: &[f64], out: &mut [f64]) {
        self.eval(&self.tape.constraint_bias, t, q, u, &[], out);
    }
    fn nflexures(&self) -> usize {
        self.tape.nflexures
    }
    fn flexure_name(&self, i: usize) -> &str {
        name_at(&self.flexure_names, i)
    }
    fn flexures(&self, t: f64, q: &[f64], out: &mut [f64]) {
        self.eval(&self.tape.flexures, t, q, &[], &[], out);
    }
}
