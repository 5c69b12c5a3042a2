//! The tape back end: straight-line programs over `f64` registers, and their evaluator.
//!
//! Consumes: [`Equations`]. Produces: a [`Tape`] with one [`Program`] each for `M`, `F`, the
//! outputs (and `q̇ = W(q) u` for models with quaternions), so the command line can run any `.mech` file without compiling Rust.
//! Instruction `i` writes register `i` (static single assignment); operands are earlier
//! registers. Constants and symbol loads are deduplicated.

use rustc_hash::FxHashMap;

use super::lower::{lower_node, operand, schedule, Binary, Lowered, Operand, Unary};
use crate::kane::Equations;
use crate::sym::{power, ExprId, ExprPool, Func, Number, Symbol};

/// One instruction; `u32` operands are register indices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Op {
    Const(f64),
    Coordinate(u32),
    Speed(u32),
    Param(u32),
    Input(u32),
    Time,
    Add(u32, u32),
    Sub(u32, u32),
    Mul(u32, u32),
    Div(u32, u32),
    Atan2(u32, u32),
    Neg(u32),
    Sqrt(u32),
    Call(Func, u32),
    Powi(u32, i32),
    Powf(u32, f64),
}

impl Op {
    /// Loads and constants cost nothing; everything else is one arithmetic operation.
    pub fn is_arithmetic(&self) -> bool {
        !matches!(
            self,
            Op::Const(_)
                | Op::Coordinate(_)
                | Op::Speed(_)
                | Op::Param(_)
                | Op::Input(_)
                | Op::Time
        )
    }

    /// The registers it reads: none for a leaf, the second only for a binary operation.
    pub fn operands(&self) -> (Option<u32>, Option<u32>) {
        match *self {
            Op::Add(a, b) | Op::Sub(a, b) | Op::Mul(a, b) | Op::Div(a, b) | Op::Atan2(a, b) => {
                (Some(a), Some(b))
            }
            Op::Neg(a) | Op::Sqrt(a) | Op::Call(_, a) | Op::Powi(a, _) | Op::Powf(a, _) => {
                (Some(a), None)
            }
            Op::Const(_)
            | Op::Coordinate(_)
            | Op::Speed(_)
            | Op::Param(_)
            | Op::Input(_)
            | Op::Time => (None, None),
        }
    }

    /// The instruction with each register it reads renamed by `rename`.
    fn with_operands(self, rename: impl Fn(u32) -> u32) -> Op {
        match self {
            Op::Add(a, b) => Op::Add(rename(a), rename(b)),
            Op::Sub(a, b) => Op::Sub(rename(a), rename(b)),
            Op::Mul(a, b) => Op::Mul(rename(a), rename(b)),
            Op::Div(a, b) => Op::Div(rename(a), rename(b)),
            Op::Atan2(a, b) => Op::Atan2(rename(a), rename(b)),
            Op::Neg(a) => Op::Neg(rename(a)),
            Op::Sqrt(a) => Op::Sqrt(rename(a)),
            Op::Call(f, a) => Op::Call(f, rename(a)),
            Op::Powi(a, n) => Op::Powi(rename(a), n),
            Op::Powf(a, e) => Op::Powf(rename(a), e),
            leaf => leaf,
        }
    }
}

/// Values of the free symbols during one evaluation.
#[derive(Clone, Copy, Debug)]
pub struct Env<'a> {
    pub t: f64,
    pub q: &'a [f64],
    pub u: &'a [f64],
    pub params: &'a [f64],
    pub inputs: &'a [f64],
}

/// A straight-line program computing `results` (register indices).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Program {
    pub ops: Vec<Op>,
    pub results: Vec<u32>,
}

impl Program {
    /// Compiles the expressions `roots` of `pool`.
    pub fn compile(pool: &ExprPool, roots: &[ExprId]) -> Program {
        let mut builder = Builder::default();
        for id in schedule(pool, roots) {
            let register = builder.flatten(&lower_node(pool, id));
            builder.node_registers.insert(id, register);
        }
        let results = roots
            .iter()
            .map(|&root| builder.operand(operand(pool, root)))
            .collect();
        Program {
            ops: builder.ops,
            results,
        }
    }

    /// The program of the results at `results` (indices into `self.results`, in that order):
    /// the instructions they need, in the same order, so each value is computed by the same
    /// operations and comes out the same bits.
    pub fn restricted(&self, results: &[usize]) -> Program {
        let mut needed = vec![false; self.ops.len()];
        for &k in results {
            needed[self.results[k] as usize] = true;
        }
        for i in (0..self.ops.len()).rev() {
            if needed[i] {
                let (first, second) = self.ops[i].operands();
                for operand in first.into_iter().chain(second) {
                    needed[operand as usize] = true;
                }
            }
        }
        let mut renamed = vec![u32::MAX; self.ops.len()];
        let mut ops = Vec::new();
        for (i, op) in self.ops.iter().enumerate().filter(|&(i, _)| needed[i]) {
            renamed[i] = ops.len() as u32;
            ops.push(op.with_operands(|k| renamed[k as usize]));
        }
        let results = results
            .iter()
            .map(|&k| renamed[self.results[k] as usize])
            .collect();
        Program { ops, results }
    }

    /// Number of arithmetic operations (additions, multiplications, function calls, ...).
    pub fn operation_count(&self) -> usize {
        self.ops.iter().filter(|op| op.is_arithmetic()).count()
    }

    /// Evaluates into `out` (length `results.len()`), using `registers` as scratch (resized
    /// once, then reused without allocating). Missing symbol values read as NaN.
    pub fn eval(&self, env: &Env, registers: &mut Vec<f64>, out: &mut [f64]) {
        registers.resize(self.ops.len(), 0.0);
        let get = |slice: &[f64], i: u32| slice.get(i as usize).copied().unwrap_or(f64::NAN);
        for (i, op) in self.ops.iter().enumerate() {
            let r = |k: u32| registers[k as usize];
            let value = match *op {
                Op::Const(c) => c,
                Op::Coordinate(k) => get(env.q, k),
                Op::Speed(k) => get(env.u, k),
                Op::Param(k) => get(env.params, k),
                Op::Input(k) => get(env.inputs, k),
                Op::Time => env.t,
                Op::Add(a, b) => r(a) + r(b),
                Op::Sub(a, b) => r(a) - r(b),
                Op::Mul(a, b) => r(a) * r(b),
                Op::Div(a, b) => r(a) / r(b),
                Op::Atan2(a, b) => r(a).atan2(r(b)),
                Op::Neg(a) => -r(a),
                Op::Sqrt(a) => r(a).sqrt(),
                Op::Call(f, a) => f.apply(r(a)),
                Op::Powi(a, n) => power(r(a), Number::int(n as i64)),
                Op::Powf(a, e) => r(a).powf(e),
            };
            registers[i] = value;
        }
        for (slot, &register) in out.iter_mut().zip(&self.results) {
            *slot = registers[register as usize];
        }
    }
}

#[derive(Default)]
struct Builder {
    ops: Vec<Op>,
    node_registers: FxHashMap<ExprId, u32>,
    /// Constants (by bit pattern) and symbol loads already emitted.
    leaves: FxHashMap<LeafKey, u32>,
}

#[derive(Clone, Copy, PartialEq, Eq, Hash)]
enum LeafKey {
    Const(u64),
    Symbol(Symbol),
}

impl Builder {
    fn push(&mut self, op: Op) -> u32 {
        self.ops.push(op);
        (self.ops.len() - 1) as u32
    }

    fn operand(&mut self, operand: Operand) -> u32 {
        match operand {
            Operand::Node(id) => self.node_registers[&id],
            Operand::Const(c) => self.leaf(LeafKey::Const(c.to_bits()), Op::Const(c)),
            Operand::Symbol(s) => {
                let op = match s {
                    Symbol::Coordinate(i) => Op::Coordinate(i),
                    Symbol::Speed(i) => Op::Speed(i),
                    Symbol::Param(i) => Op::Param(i),
                    Symbol::Input(i) => Op::Input(i),
                    Symbol::Time => Op::Time,
                    Symbol::Acceleration(_) => Op::Const(f64::NAN),
                };
                self.leaf(LeafKey::Symbol(s), op)
            }
        }
    }

    fn leaf(&mut self, key: LeafKey, op: Op) -> u32 {
        if let Some(&register) = self.leaves.get(&key) {
            return register;
        }
        let register = self.push(op);
        self.leaves.insert(key, register);
        register
    }

    fn flatten(&mut self, tree: &Lowered) -> u32 {
        match tree {
            Lowered::Operand(o) => self.operand(*o),
            Lowered::Binary(op, a, b) => {
                let (a, b) = (self.flatten(a), self.flatten(b));
                self.push(match op {
                    Binary::Add => Op::Add(a, b),
                    Binary::Sub => Op::Sub(a, b),
                    Binary::Mul => Op::Mul(a, b),
                    Binary::Div => Op::Div(a, b),
                    Binary::Atan2 => Op::Atan2(a, b),
                })
            }
            Lowered::Unary(op, a) => {
                let a = self.flatten(a);
                self.push(match op {
                    Unary::Neg => Op::Neg(a),
                    Unary::Sqrt => Op::Sqrt(a),
                    Unary::Call(f) => Op::Call(*f, a),
                })
            }
            Lowered::Powi(a, n) => {
                let a = self.flatten(a);
                self.push(Op::Powi(a, *n))
            }
            Lowered::Powf(a, e) => {
                let a = self.flatten(a);
                self.push(Op::Powf(a, *e))
            }
        }
    }
}

/// Programs for every function of a model.
#[derive(Clone, Debug, PartialEq)]
pub struct Tape {
    pub nq: usize,
    pub nu: usize,
    /// `M(q)`, column-major `nu × nu`.
    pub mass_matrix: Program,
    pub forcing: Program,
    /// `F(t, q, 0, inputs)` (`Equations::static_forcing`): on the extended HAMR leg a
    /// fraction of `forcing`'s operations, and the statics evaluate it dof times per Newton
    /// iteration.
    pub static_forcing: Option<Program>,
    /// The contacts' damping `D(t, q, u, inputs)`, column-major `nu × nu`
    /// (`Equations::contact_damping`); `None` without contacts.
    pub contact_damping: Option<Program>,
    pub outputs: Program,
    /// Each output row alone: for callers that need a few outputs many times (the fixtures of
    /// the statics hold the foot, 225 of the extended HAMR leg's 2,604 output operations; its
    /// kinetic energy alone takes 2,060).
    pub output_rows: Vec<Program>,
    /// Number of loop-closure rows.
    pub nc: usize,
    /// `φ(q)`.
    pub constraints: Program,
    /// `J(q)`, column-major `nc × nq`.
    pub constraint_jacobian: Program,
    /// `J̇(q, u) u`.
    pub constraint_bias: Program,
    /// Number of flexures.
    pub nflexures: usize,
    /// `[θ…, k…, b…, η…]` of the flexures.
    pub flexures: Program,
    /// `q̇ = W(q) u` (`Equations::kinematic_rates`); `None` where `q̇ = u`.
    pub kinematic_rates: Option<Program>,
}

impl Tape {
    pub fn new(equations: &Equations) -> Tape {
        Tape {
            nq: equations.nq,
            nu: equations.nu,
            mass_matrix: Program::compile(&equations.pool, &equations.mass_matrix),
            forcing: Program::compile(&equations.pool, &equations.forcing),
            static_forcing: equations
                .static_forcing
                .as_ref()
                .map(|roots| Program::compile(&equations.pool, roots)),
            contact_damping: equations
                .contact_damping
                .as_ref()
                .map(|roots| Program::compile(&equations.pool, roots)),
            outputs: Program::compile(&equations.pool, &equations.outputs),
            output_rows: equations
                .outputs
                .iter()
                .map(|&row| Program::compile(&equations.pool, &[row]))
                .collect(),
            nc: equations.nc(),
            constraints: Program::compile(&equations.pool, &equations.constraints.residual),
            constraint_jacobian: Program::compile(&equations.pool, &equations.constraints.jacobian),
            constraint_bias: Program::compile(&equations.pool, &equations.constraints.bias),
            nflexures: equations.flexures.names.len(),
            flexures: Program::compile(&equations.pool, &equations.flexures.all()),
            kinematic_rates: equations
                .kinematic_rates
                .as_ref()
                .map(|roots| Program::compile(&equations.pool, roots)),
        }
    }
}
