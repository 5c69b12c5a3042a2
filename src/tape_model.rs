//! A model run through the tape evaluator, so any `.mech` file can be simulated without
//! compiling Rust.
//!
//! Consumes: a [`Compiled`] model (IR + equations). Produces: a [`TapeModel`] implementing
//! [`mech_runtime::Model`], the same contract generated code implements.
//!
//! Each program of the tape runs as native code ([`mech_jit`], Cranelift) once it has been
//! called [`NATIVE_AFTER_CALLS`] times: compiled then, on the first thread that gets there,
//! and shared (`Arc`) with every clone of the model. Programs called fewer times, or that
//! Cranelift cannot compile, run through the interpreter ([`Program::eval`]); both give the
//! same numbers bit for bit (`mech_jit`'s module header says why). `MECH_JIT=0` in the
//! environment (read when a model is built) or [`Backend::Interpreter`] turns native code off.

use std::cell::RefCell;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, OnceLock};

use mech_codegen::back::tape::{Env, Program, Tape};
use mech_codegen::Compiled;
use mech_jit::{JitProgram, Scratch};

use crate::helper_thread::{Evaluation, HelperThread};
use mech_runtime::model::{rates_equal_speeds, terms_by_part};

/// How a [`TapeModel`] evaluates its programs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// Native code for programs called often, the interpreter for the others.
    Native,
    /// The interpreter only.
    Interpreter,
}

impl Backend {
    /// [`Backend::Interpreter`] if the environment sets `MECH_JIT=0`, else [`Backend::Native`].
    pub fn from_env() -> Backend {
        match std::env::var_os("MECH_JIT") {
            Some(value) if value == "0" => Backend::Interpreter,
            _ => Backend::Native,
        }
    }
}

/// Calls of a program through the interpreter before it is compiled: a program evaluated
/// once or twice (a check, one output row) never pays Cranelift's compile time.
pub const NATIVE_AFTER_CALLS: u32 = 3;

/// The size of `[M, F, J, J̇u]` (instructions) from which [`TapeModel::use_second_thread`]
/// splits it: a hand-over to the helper thread and back costs about a microsecond, the
/// evaluation of this many instructions a few.
const TWO_THREADS_FROM_OPS: usize = 5_000;

/// The tape's programs in a fixed order: the slot of each in [`Native::programs`].
#[derive(Clone, Copy, Debug)]
enum Slot {
    MassMatrix,
    Forcing,
    StaticForcing,
    Outputs,
    Constraints,
    ConstraintJacobian,
    ConstraintBias,
    Flexures,
    /// `[M, F, J, J̇u]` in one program (native code only).
    ConstrainedTerms,
    /// `[M, F, J̇u]` in one program (native code only).
    DynamicsTerms,
    /// `[M, J, J̇u]` and `F`: `ConstrainedTerms` in two programs, run on two threads
    /// ([`TapeModel::use_second_thread`]).
    ConstrainedHere,
    ConstrainedBeside,
    /// `q̇ = W(q) u`, for models with quaternions.
    KinematicRates,
    /// The contacts' damping `D`, for models with contacts.
    ContactDamping,
    OutputRow(usize),
}

impl Slot {
    const FIXED: usize = 14;
    fn index(self) -> usize {
        match self {
            Slot::MassMatrix => 0,
            Slot::Forcing => 1,
            Slot::StaticForcing => 2,
            Slot::Outputs => 3,
            Slot::Constraints => 4,
            Slot::ConstraintJacobian => 5,
            Slot::ConstraintBias => 6,
            Slot::Flexures => 7,
            Slot::ConstrainedTerms => 8,
            Slot::DynamicsTerms => 9,
            Slot::KinematicRates => 10,
            Slot::ContactDamping => 11,
            Slot::ConstrainedHere => 12,
            Slot::ConstrainedBeside => 13,
            Slot::OutputRow(row) => Slot::FIXED + row,
        }
    }
}

/// One program's native code: compiled on demand, `None` inside if compilation failed.
#[derive(Debug, Default)]
struct NativeProgram {
    calls: AtomicU32,
    code: OnceLock<Option<JitProgram>>,
}

/// The native code of all programs of one tape, shared by the clones of a model, and the
/// fused programs only native code runs.
#[derive(Debug)]
struct Native {
    programs: Vec<NativeProgram>,
    /// `[M, F, J, J̇u]` and `[M, F, J̇u]` (column-major matrices), each one program sharing
    /// subexpressions across its parts, as the generated `constrained_terms` and
    /// `dynamics_terms` (for models without loops too). Each value is computed by the same
    /// instructions as in the separate programs, so the numbers are the same.
    fused: Option<(Program, Program)>,
    /// `ConstrainedTerms` split by [`Program::restricted`] into `[M, J, J̇u]` and `F`
    /// (made on first use): the two parts share few instructions (the robot's 37,206 are
    /// 20,621 + 17,008), so on two threads they take about the time of the larger.
    split: OnceLock<(Program, Program)>,
}

/// The tape of a model with its names, defaults and current parameter values.
#[derive(Clone, Debug)]
pub struct TapeModel {
    name: String,
    tape: Tape,
    coordinate_names: Vec<String>,
    speed_names: Vec<String>,
    /// Index in `q` of each quaternion's scalar part.
    unit_quaternions: Vec<usize>,
    /// Number of coordinates with `q̇ = u`, first in `q` (`Model::plain_coordinates`): none
    /// when `speed` declarations chose the speeds (`q̇ = W(q) u` for every coordinate).
    plain_coordinates: usize,
    input_names: Vec<String>,
    output_names: Vec<String>,
    /// `(target, rate)` outputs a simulation integrates (`Equations::integrated_outputs`).
    integrated_outputs: Vec<(usize, usize)>,
    constraint_names: Vec<String>,
    /// The last rows of the constraints that are velocity constraints (`φ` = 0 there).
    velocity_rows: usize,
    flexure_names: Vec<String>,
    param_names: Vec<String>,
    params: Vec<f64>,
    input_defaults: Vec<f64>,
    q0: Vec<f64>,
    u0: Vec<f64>,
    /// The `q0` and `u0` written as expressions of params, evaluated at the current values.
    initial_values: Vec<mech_codegen::ir::InitialValue>,
    /// Registers reused across evaluations (the evaluator never allocates after warm-up).
    registers: RefCell<Vec<f64>>,
    /// Native code, `None` for [`Backend::Interpreter`].
    native: Option<Arc<Native>>,
    /// This clone's memory for the native code (spilled values), reused like `registers`.
    scratch: RefCell<Scratch>,
    /// The values of a fused program before they are split into its parts.
    fused_out: RefCell<Vec<f64>>,
    /// Whether `constrained_terms` may evaluate `F` on a second thread.
    second_thread: bool,
    /// That thread, started on first use (each clone its own).
    helper: HelperSlot,
    /// `q` with its unit quaternions at unit norm, where the programs evaluate
    /// ([`TapeModel::with_env`]).
    unit_q: RefCell<Vec<f64>>,
}

impl TapeModel {
    /// Calls `f` with the tape's environment at `(t, q, u, inputs)` and the current
    /// parameter values, the unit quaternions of `q` scaled to unit norm: between an
    /// integrator's renormalizations a stage's quaternion is slightly off the unit sphere,
    /// and `M`, `F`, `J` must still be those of the rotation it stands for (as the generated
    /// Rust does, `mech_runtime::__codegen::unit_quaternions`).
    fn with_env<R>(
        &self,
        (t, q, u, inputs): (f64, &[f64], &[f64], &[f64]),
        f: impl FnOnce(&Env) -> R,
    ) -> R {
        let params = &self.params;
        if self.unit_quaternions.is_empty() {
            return f(&Env {
                t,
                q,
                u,
                params,
                inputs,
            });
        }
        // Taken, not borrowed: a nested call (none today) would get its own buffer.
        let mut unit = std::mem::take(&mut *self.unit_q.borrow_mut());
        unit.clear();
        unit.extend_from_slice(q);
        mech_runtime::normalize_quaternions(&self.unit_quaternions, &mut unit);
        let result = f(&Env {
            t,
            q: &unit,
            u,
            params,
            inputs,
        });
        *self.unit_q.borrow_mut() = unit;
        result
    }

    /// The model with the backend of [`Backend::from_env`].
    pub fn new(compiled: &Compiled) -> TapeModel {
        TapeModel::with_backend(compiled, Backend::from_env())
    }

    pub fn with_backend(compiled: &Compiled, backend: Backend) -> TapeModel {
        let model = &compiled.model;
        let tape = compiled.tape();
        let native = (backend == Backend::Native).then(|| {
            let equations = &compiled.equations;
            // Also without loops (`J` and `J̇u` empty): `constrained_terms` is what the
            // runtime's `ConstrainedSolver` calls for every model.
            let fused = Some(()).map(|()| {
                let constraints = &equations.constraints;
                let dynamics: Vec<_> = [&equations.mass_matrix, &equations.forcing]
                    .into_iter()
                    .flatten()
                    .copied()
                    .collect();
                let constrained: Vec<_> = dynamics
                    .iter()
                    .chain(&constraints.jacobian)
                    .chain(&constraints.bias)
                    .copied()
                    .collect();
                let dynamics: Vec<_> = dynamics
                    .into_iter()
                    .chain(constraints.bias.iter().copied())
                    .collect();
                (
                    Program::compile(&equations.pool, &constrained),
                    Program::compile(&equations.pool, &dynamics),
                )
            });
            Arc::new(Native {
                programs: (0..Slot::FIXED + tape.output_rows.len())
                    .map(|_| NativeProgram::default())
                    .collect(),
                fused,
                split: OnceLock::new(),
            })
        });
        TapeModel {
            name: model.name.clone(),
            tape,
            coordinate_names: model.coordinate_names(),
            speed_names: model.speed_names(),
            unit_quaternions: model
                .quaternions
                .iter()
                .map(|(e, _)| model.quaternion_coordinate(e, 0))
                .collect(),
            plain_coordinates: match (model.speeds.is_empty(), model.has_kinematic_rates()) {
                (false, _) => 0,
                (true, true) => model.coordinates.len(),
                (true, false) => model.nq(),
            },
            input_names: model.inputs.iter().map(|(_, i)| i.name.clone()).collect(),
            output_names: compiled.equations.output_names.clone(),
            integrated_outputs: compiled.equations.integrated_outputs.clone(),
            constraint_names: compiled.equations.constraints.names.clone(),
            velocity_rows: compiled.equations.constraints.velocity_rows,
            flexure_names: compiled.equations.flexures.names.clone(),
            param_names: model.params.iter().map(|(_, p)| p.name.clone()).collect(),
            params: model.params.iter().map(|(_, p)| p.value).collect(),
            input_defaults: model.inputs.iter().map(|(_, i)| i.default).collect(),
            q0: model.initial_coordinates(),
            u0: model.initial_speeds(),
            // With chosen speeds `u0 = Y(q0) ū0` was formed at compile time from the joints'
            // rates: a param-dependent `q0`/`u0` then keeps its default value.
            initial_values: match model.speeds.is_empty() {
                true => model.initial_values.clone(),
                false => Vec::new(),
            },
            registers: RefCell::new(Vec::new()),
            native,
            scratch: RefCell::new(Scratch::default()),
            fused_out: RefCell::new(Vec::new()),
            second_thread: false,
            helper: HelperSlot::default(),
            unit_q: RefCell::new(Vec::new()),
        }
    }

    /// Lets `constrained_terms` (the loops' `M`, `F`, `J`, `J̇u`, every step's work) evaluate
    /// `F` on a second thread beside the rest, with native code: for a simulation that runs
    /// alone on a machine with a free core. The values are the same bits. Off by default:
    /// where simulations already fill every core (sweeps, diagnoses), the helper would only
    /// contend with them.
    pub fn use_second_thread(&mut self, on: bool) {
        self.second_thread = on;
        if !on {
            *self.helper.0.borrow_mut() = Helper::NotStarted;
        }
    }

    /// Whether `constrained_terms` has run on two threads (a helper thread is started).
    pub fn runs_on_two_threads(&self) -> bool {
        matches!(*self.helper.0.borrow(), Helper::Running(_))
    }

    pub fn tape(&self) -> &Tape {
        &self.tape
    }

    pub fn backend(&self) -> Backend {
        if self.native.is_some() {
            Backend::Native
        } else {
            Backend::Interpreter
        }
    }

    /// The slots of the tape's programs.
    fn slots(&self) -> impl Iterator<Item = Slot> + '_ {
        [
            Slot::MassMatrix,
            Slot::Forcing,
            Slot::StaticForcing,
            Slot::Outputs,
            Slot::Constraints,
            Slot::ConstraintJacobian,
            Slot::ConstraintBias,
            Slot::Flexures,
        ]
        .into_iter()
        .filter(|slot| !matches!(slot, Slot::StaticForcing) || self.tape.static_forcing.is_some())
        .chain(
            self.tape
                .kinematic_rates
                .as_ref()
                .map(|_| Slot::KinematicRates),
        )
        .chain(
            self.tape
                .contact_damping
                .as_ref()
                .map(|_| Slot::ContactDamping),
        )
        .chain(
            self.native
                .as_ref()
                .filter(|native| native.fused.is_some())
                .map(|_| [Slot::ConstrainedTerms, Slot::DynamicsTerms])
                .into_iter()
                .flatten(),
        )
        .chain((0..self.tape.output_rows.len()).map(Slot::OutputRow))
    }

    /// Compiles every program to native code now (a no-op for [`Backend::Interpreter`]);
    /// returns how many are native. For benchmarks and tests: models otherwise compile a
    /// program when it has been called [`NATIVE_AFTER_CALLS`] times.
    pub fn compile_native(&self) -> usize {
        let Some(native) = &self.native else {
            return 0;
        };
        self.slots()
            .filter(|&slot| {
                native.programs[slot.index()]
                    .code
                    .get_or_init(|| JitProgram::compile(self.program(slot)).ok())
                    .is_some()
            })
            .count()
    }

    fn program(&self, slot: Slot) -> &Program {
        let tape = &self.tape;
        match slot {
            Slot::MassMatrix => &tape.mass_matrix,
            Slot::Forcing => &tape.forcing,
            Slot::StaticForcing => tape.static_forcing.as_ref().unwrap_or(&tape.forcing),
            Slot::Outputs => &tape.outputs,
            Slot::Constraints => &tape.constraints,
            Slot::ConstraintJacobian => &tape.constraint_jacobian,
            Slot::ConstraintBias => &tape.constraint_bias,
            Slot::Flexures => &tape.flexures,
            // Only listed in `slots` (and called) for a tape with the program.
            Slot::KinematicRates => tape.kinematic_rates.as_ref().unwrap_or(&tape.forcing),
            Slot::ContactDamping => tape.contact_damping.as_ref().unwrap_or(&tape.forcing),
            Slot::ConstrainedTerms
            | Slot::DynamicsTerms
            | Slot::ConstrainedHere
            | Slot::ConstrainedBeside => {
                let native = self.native.as_ref();
                let fused = native.and_then(|native| native.fused.as_ref());
                let (constrained, dynamics) = fused.expect("fused programs with native code");
                match slot {
                    Slot::ConstrainedTerms => constrained,
                    Slot::DynamicsTerms => dynamics,
                    _ => {
                        let (nu, nc) = (self.tape.nu, self.tape.nc);
                        let (here, beside) = native
                            .expect("fused programs with native code")
                            .split
                            .get_or_init(|| {
                                // [M, F, J, J̇u] → [M, J, J̇u] and F.
                                let forcing = nu * nu..nu * nu + nu;
                                let rest: Vec<usize> = (0..nu * nu)
                                    .chain(forcing.end..forcing.end + nc * nu + nc)
                                    .collect();
                                let forcing: Vec<usize> = forcing.collect();
                                (
                                    constrained.restricted(&rest),
                                    constrained.restricted(&forcing),
                                )
                            });
                        match slot {
                            Slot::ConstrainedHere => here,
                            _ => beside,
                        }
                    }
                }
            }
            Slot::OutputRow(row) => &tape.output_rows[row],
        }
    }

    /// Runs a fused program into its parts (`out` of the fused length as scratch), by
    /// `code` where given (else as [`run`](Self::run) does).
    fn run_fused(
        &self,
        slot: Slot,
        code: Option<&JitProgram>,
        env: &Env,
        parts: &mut [&mut [f64]],
    ) {
        let (nu, nc) = (self.tape.nu, self.tape.nc);
        let lengths = match slot {
            Slot::ConstrainedTerms => [nu * nu, nu, nc * nu, nc],
            Slot::ConstrainedHere => [nu * nu, nc * nu, nc, 0],
            _ => [nu * nu, nu, nc, 0],
        };
        let mut out = std::mem::take(&mut *self.fused_out.borrow_mut());
        out.resize(lengths.iter().sum(), 0.0);
        match code {
            Some(code) => code.eval(env, &mut self.scratch.borrow_mut(), &mut out),
            None => self.run(slot, env, &mut out),
        }
        let mut rest = &out[..];
        for (part, &length) in parts.iter_mut().zip(&lengths) {
            let (values, tail) = rest.split_at(length);
            for (slot, value) in part.iter_mut().zip(values) {
                *slot = *value;
            }
            rest = tail;
        }
        *self.fused_out.borrow_mut() = out;
    }

    /// `M`, `F`, `J`, `J̇u` with `F` on the second thread ([`use_second_thread`]), compiling
    /// the two programs now (a simulation calls them at every step): `false` where there is
    /// no native code or no thread (the caller then runs the fused program).
    ///
    /// [`use_second_thread`]: Self::use_second_thread
    fn run_on_two_threads(&self, env: &Env, parts: [&mut [f64]; 4]) -> bool {
        let Some(native) = &self.native else {
            return false;
        };
        if self.program(Slot::ConstrainedTerms).ops.len() < TWO_THREADS_FROM_OPS {
            return false;
        }
        let compiled = |slot: Slot| {
            native.programs[slot.index()]
                .code
                .get_or_init(|| JitProgram::compile(self.program(slot)).ok())
                .as_ref()
        };
        let (Some(here), Some(_)) = (
            compiled(Slot::ConstrainedHere),
            compiled(Slot::ConstrainedBeside),
        ) else {
            return false;
        };
        let mut helper = self.helper.0.borrow_mut();
        if matches!(*helper, Helper::NotStarted) {
            let native = Arc::clone(native);
            let mut scratch = Scratch::default();
            let beside: Evaluation = Box::new(move |env, out| {
                let code = native.programs[Slot::ConstrainedBeside.index()].code.get();
                let code = code.and_then(Option::as_ref);
                // A panic here reaches the caller (`HelperThread::eval_beside`).
                let code = code.expect("`F`'s native code, compiled before the helper started");
                code.eval(env, &mut scratch, out);
            });
            *helper = match HelperThread::spawn(beside, self.tape.nu) {
                Some(thread) => Helper::Running(thread),
                None => Helper::Unavailable,
            };
        }
        let Helper::Running(helper) = &mut *helper else {
            return false;
        };
        let [mass, forcing, jacobian, bias] = parts;
        helper.eval_beside(env, forcing, || {
            let parts = &mut [mass, jacobian, bias];
            self.run_fused(Slot::ConstrainedHere, Some(here), env, parts)
        });
        true
    }

    /// Whether the fused programs exist (native code).
    fn fused(&self) -> bool {
        self.native
            .as_ref()
            .is_some_and(|native| native.fused.is_some())
    }

    fn run(&self, slot: Slot, env: &Env, out: &mut [f64]) {
        let program = self.program(slot);
        if let Some(native) = &self.native {
            let entry = &native.programs[slot.index()];
            let code = match entry.code.get() {
                Some(code) => code.as_ref(),
                None if entry.calls.fetch_add(1, Ordering::Relaxed) >= NATIVE_AFTER_CALLS => entry
                    .code
                    .get_or_init(|| JitProgram::compile(program).ok())
                    .as_ref(),
                None => None,
            };
            if let Some(code) = code {
                return code.eval(env, &mut self.scratch.borrow_mut(), out);
            }
        }
        program.eval(env, &mut self.registers.borrow_mut(), out);
    }

    /// Runs the program of `slot` at `(t, q, u, inputs)` into `out`.
    fn eval(&self, slot: Slot, t: f64, q: &[f64], u: &[f64], inputs: &[f64], out: &mut [f64]) {
        self.with_env((t, q, u, inputs), |env| self.run(slot, env, out));
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
    fn speed_name(&self, i: usize) -> &str {
        name_at(&self.speed_names, i)
    }
    fn kinematic_rates(&self, t: f64, q: &[f64], u: &[f64], out: &mut [f64]) {
        match self.tape.kinematic_rates {
            Some(_) => self.eval(Slot::KinematicRates, t, q, u, &[], out),
            None => rates_equal_speeds(u, out),
        }
    }
    fn unit_quaternions(&self) -> &[usize] {
        &self.unit_quaternions
    }
    fn plain_coordinates(&self) -> usize {
        self.plain_coordinates
    }
    fn input_name(&self, i: usize) -> &str {
        name_at(&self.input_names, i)
    }
    fn output_name(&self, i: usize) -> &str {
        name_at(&self.output_names, i)
    }
    fn integrated_outputs(&self) -> &[(usize, usize)] {
        &self.integrated_outputs
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
        mech_codegen::ir::InitialValue::apply(&self.initial_values, &self.params, q, u);
    }
    fn mass_matrix(&self, t: f64, q: &[f64], inputs: &[f64], out: &mut [f64]) {
        self.eval(Slot::MassMatrix, t, q, &[], inputs, out);
    }
    fn forcing(&self, t: f64, q: &[f64], u: &[f64], inputs: &[f64], out: &mut [f64]) {
        self.eval(Slot::Forcing, t, q, u, inputs, out);
    }
    fn static_forcing(&self, t: f64, q: &[f64], inputs: &[f64], out: &mut [f64]) {
        if self.tape.static_forcing.is_none() {
            return self.forcing(t, q, &vec![0.0; self.tape.nu], inputs, out);
        };
        self.eval(Slot::StaticForcing, t, q, &[], inputs, out);
    }
    fn contact_damping(
        &self,
        t: f64,
        q: &[f64],
        u: &[f64],
        inputs: &[f64],
        out: &mut [f64],
    ) -> bool {
        if self.tape.contact_damping.is_none() {
            return false;
        }
        self.eval(Slot::ContactDamping, t, q, u, inputs, out);
        true
    }
    fn outputs(&self, t: f64, q: &[f64], u: &[f64], inputs: &[f64], out: &mut [f64]) {
        self.eval(Slot::Outputs, t, q, u, inputs, out);
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
        self.with_env((t, q, u, inputs), |env| {
            for (&row, value) in which.iter().zip(out.iter_mut()) {
                self.run(Slot::OutputRow(row), env, std::slice::from_mut(value));
            }
        });
        true
    }
    fn nc(&self) -> usize {
        self.tape.nc
    }
    fn velocity_rows(&self) -> usize {
        self.velocity_rows
    }
    fn constraint_name(&self, i: usize) -> &str {
        name_at(&self.constraint_names, i)
    }
    fn constraints(&self, t: f64, q: &[f64], out: &mut [f64]) {
        self.eval(Slot::Constraints, t, q, &[], &[], out);
    }
    fn constraint_jacobian(&self, t: f64, q: &[f64], out: &mut [f64]) {
        self.eval(Slot::ConstraintJacobian, t, q, &[], &[], out);
    }
    fn constraint_bias(&self, t: f64, q: &[f64], u: &[f64], out: &mut [f64]) {
        self.eval(Slot::ConstraintBias, t, q, u, &[], out);
    }
    #[allow(clippy::too_many_arguments)]
    fn constrained_terms(
        &self,
        t: f64,
        q: &[f64],
        u: &[f64],
        inputs: &[f64],
        mass: &mut [f64],
        forcing: &mut [f64],
        jacobian: &mut [f64],
        bias: &mut [f64],
    ) {
        if !self.fused() {
            let parts = [mass, forcing, bias];
            return terms_by_part(self, t, q, u, inputs, parts, Some(jacobian));
        }
        self.with_env((t, q, u, inputs), |env| {
            if self.second_thread {
                // Reborrowed: the fused program below needs them where this declines.
                let parts = [&mut *mass, &mut *forcing, &mut *jacobian, &mut *bias];
                if self.run_on_two_threads(env, parts) {
                    return;
                }
            }
            let parts = &mut [mass, forcing, jacobian, bias];
            self.run_fused(Slot::ConstrainedTerms, None, env, parts)
        });
    }
    #[allow(clippy::too_many_arguments)]
    fn dynamics_terms(
        &self,
        t: f64,
        q: &[f64],
        u: &[f64],
        inputs: &[f64],
        mass: &mut [f64],
        forcing: &mut [f64],
        bias: &mut [f64],
    ) {
        if !self.fused() {
            return terms_by_part(self, t, q, u, inputs, [mass, forcing, bias], None);
        }
        self.with_env((t, q, u, inputs), |env| {
            self.run_fused(Slot::DynamicsTerms, None, env, &mut [mass, forcing, bias])
        });
    }
    fn nflexures(&self) -> usize {
        self.tape.nflexures
    }
    fn flexure_name(&self, i: usize) -> &str {
        name_at(&self.flexure_names, i)
    }
    fn flexures(&self, t: f64, q: &[f64], out: &mut [f64]) {
        self.eval(Slot::Flexures, t, q, &[], &[], out);
    }
}

/// A model's helper thread: each clone starts its own (a clone may run on another thread).
#[derive(Debug, Default)]
struct HelperSlot(RefCell<Helper>);

#[derive(Debug, Default)]
enum Helper {
    #[default]
    NotStarted,
    Running(HelperThread),
    /// The system refused a thread: not asked again at every evaluation.
    Unavailable,
}

impl Clone for HelperSlot {
    fn clone(&self) -> HelperSlot {
        HelperSlot::default()
    }
}
