//! Native code for tape programs at load time, through Cranelift: the speed of the
//! build-time generated Rust for a `.mech` file read at run time, without cargo.
//!
//! Consumes: a [`Program`] of `mech_codegen::back::tape` (straight-line SSA over `f64`
//! registers). Produces: a [`JitProgram`], the same program as native functions, evaluated
//! by [`JitProgram::eval`] with the interpreter's contract ([`Program::eval`]): the same
//! [`Env`], results written to `out` (as many as both have), missing symbol values read as
//! NaN.
//!
//! Why a crate of its own: Cranelift is ~40 crates of compile time, and `mech-codegen` is a
//! build dependency of every crate that embeds a model (`build.rs`), which never needs a JIT.
//! Only the application crate (`mech`, for `TapeModel`) depends on this one.
//!
//! The same numbers as the interpreter, bit for bit: add, subtract, multiply, divide, negate,
//! `abs` and `sqrt` are single IEEE instructions (correctly rounded, as Rust's); `x^n` for an
//! integer `n` is the multiply chain of `f64::powi`'s run-time implementation (compiler
//! builtins' `__powidf2`: square-and-multiply from the low bit, `1/x^|n|` for `n < 0`); the
//! transcendental functions (`sin`, …, `atan2`, `powf`) call `extern "C"` shims around the
//! very functions the interpreter calls. Cranelift neither reassociates nor fuses floating
//! point operations.
//!
//! Long programs are split into chunks of at most [`Options::chunk_ops`] instructions, each a
//! function of its own, run one after the other; a value used by a later chunk goes through a
//! spill array in memory (constants and symbol loads are re-materialized instead). That keeps
//! Cranelift's compile time and memory linear in the program's length: register allocation
//! on one function of 10⁵ instructions is what would not be. The chunks compile on every
//! core (each function apart; linked in order, so the code does not depend on the threads).

use std::fmt;

use cranelift_codegen::control::ControlPlane;
use cranelift_codegen::ir::{
    types, AbiParam, InstBuilder, MemFlags, Signature, UserFuncName, Value,
};
use cranelift_codegen::packed_option::ReservedValue;
use cranelift_codegen::settings::{self, Configurable};
use cranelift_codegen::Context;
use cranelift_frontend::{FunctionBuilder, FunctionBuilderContext};
use cranelift_jit::{JITBuilder, JITModule};
use cranelift_module::{default_libcall_names, Linkage, Module, ModuleReloc};
use mech_codegen::back::tape::{Env, Op, Program};
use mech_codegen::sym::{power, Func, Number};

/// How programs are compiled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Options {
    /// Instructions per native function (the last chunk may be shorter).
    pub chunk_ops: usize,
    /// Cranelift's optimizer: `true` for `opt_level=speed`, `false` for `none`.
    pub optimize: bool,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            chunk_ops: 2000,
            optimize: true,
        }
    }
}

/// Programs longer than this compile without Cranelift's optimizer, in chunks of
/// [`UNOPTIMIZED_CHUNK_OPS`]. Measured (`examples/jit_performance.rs`, docs/benchmarks.md §13):
/// on the 32-link chain's `M` (88,768 instructions, chunks of 2,000) `opt_level=speed`
/// compiles 2.6–3.6× slower than `none` (1.5–2.1 s against 0.43–0.69 s) and ran no faster in
/// three runs; on HAMR-VI's `M` and `F` (1,281) both compile in 5–10 ms and `speed` ran
/// 1.1–2.5× faster. On the HAMR-VI robot's programs of 4,334 to 8,877 instructions (`M`, `J`,
/// the outputs, the contacts' damping; two runs of a scratch harness, minima over 30 batches)
/// `speed` compiled 1.5–2.5× slower than `none` in chunks of 500 and ran −13 % to +7 % as
/// fast: no gain, so the optimizer stops below them.
pub const OPTIMIZE_UP_TO: usize = 4_000;

/// Chunk length of the programs compiled without the optimizer. Register allocation's time
/// grows faster than a chunk's length: on the robot's fused `M, F, J, J̇u` (37,744
/// instructions) chunks of 500 compiled in 108–112 ms against 183–186 ms for 2,000, and its
/// `J` (8,877) in 28–29 ms against 48–52 ms, evaluating as fast (within 2 %, the machine's
/// noise); longer chunks pay off only with the optimizer.
pub const UNOPTIMIZED_CHUNK_OPS: usize = 500;

impl Options {
    /// The optimizer and the default chunks up to [`OPTIMIZE_UP_TO`] instructions; longer
    /// programs without it, in chunks of [`UNOPTIMIZED_CHUNK_OPS`].
    pub fn for_length(ops: usize) -> Options {
        match ops <= OPTIMIZE_UP_TO {
            true => Options::default(),
            false => Options {
                chunk_ops: UNOPTIMIZED_CHUNK_OPS,
                optimize: false,
            },
        }
    }
}

/// Why a program could not be compiled (the caller then interprets it).
#[derive(Debug)]
pub enum Error {
    /// The host's instruction set is not one Cranelift supports.
    UnsupportedHost(String),
    /// Cranelift refused a setting, a function or the final link.
    Cranelift(String),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::UnsupportedHost(why) => write!(f, "no native code for this host: {why}"),
            Error::Cranelift(why) => write!(f, "native code generation failed: {why}"),
        }
    }
}

impl std::error::Error for Error {}

fn cranelift(error: impl fmt::Display) -> Error {
    Error::Cranelift(error.to_string())
}

/// One chunk: `(q, u, params, inputs, t, out, spill)`.
type ChunkFn =
    unsafe extern "C" fn(*const f64, *const f64, *const f64, *const f64, f64, *mut f64, *mut f64);

/// The JIT module that owns the code's memory; freed when the program is dropped.
struct Code(Option<JITModule>);

// SAFETY: after `finalize_definitions` the module is only kept to own the executable memory
// (read-only from then on, and callable from any thread); it is touched again only by `Drop`,
// which has the one and only owner.
unsafe impl Send for Code {}
unsafe impl Sync for Code {}

impl Drop for Code {
    fn drop(&mut self) {
        if let Some(module) = self.0.take() {
            // SAFETY: the function pointers live in the same `JitProgram` as this module and
            // are dropped with it; no call can be running (`eval` borrows the program).
            unsafe { module.free_memory() };
        }
    }
}

/// A program compiled to native code. `Send + Sync`: share it (`Arc`) between threads; each
/// caller brings its own [`Scratch`].
pub struct JitProgram {
    chunks: Vec<ChunkFn>,
    /// The slice lengths the code may read: `[q, u, params, inputs]` (largest index + 1).
    needs: [usize; 4],
    results: usize,
    spills: usize,
    ops: usize,
    _code: Code,
}

impl fmt::Debug for JitProgram {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("JitProgram")
            .field("ops", &self.ops)
            .field("chunks", &self.chunks.len())
            .field("spills", &self.spills)
            .field("results", &self.results)
            .finish()
    }
}

/// Per-caller memory of [`JitProgram::eval`]: the spill array, the results when `out` is
/// shorter than the program's, and copies of symbol slices shorter than the program reads
/// (padded with NaN). Allocated on first use, then reused.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    spill: Vec<f64>,
    results: Vec<f64>,
    padded: [Vec<f64>; 4],
}

impl JitProgram {
    /// Compiles `program` with [`Options::for_length`].
    pub fn compile(program: &Program) -> Result<JitProgram, Error> {
        JitProgram::compile_with(program, Options::for_length(program.ops.len()))
    }

    /// Compiles `program`.
    pub fn compile_with(program: &Program, options: Options) -> Result<JitProgram, Error> {
        let mut flags = settings::builder();
        let opt = if options.optimize { "speed" } else { "none" };
        // Cranelift's IR verifier checks this crate's lowering: on in debug builds (the
        // tests, which also compare every model's JIT with the interpreter bit for bit), off
        // in release, where it took ~4 % of the compile time.
        let verify = if cfg!(debug_assertions) {
            "true"
        } else {
            "false"
        };
        for (name, value) in [
            ("opt_level", opt),
            ("use_colocated_libcalls", "false"),
            ("is_pic", "false"),
            ("enable_verifier", verify),
        ] {
            flags.set(name, value).map_err(cranelift)?;
        }
        let isa = cranelift_native::builder()
            .map_err(|why| Error::UnsupportedHost(why.to_string()))?
            .finish(settings::Flags::new(flags))
            .map_err(cranelift)?;
        let mut module = JITModule::new(JITBuilder::with_isa(isa.clone(), default_libcall_names()));
        let layout = Layout::new(program, options.chunk_ops.max(1));
        let pointer = module.target_config().pointer_type();
        let mut signature = module.make_signature();
        signature.params.extend(
            [pointer; 4]
                .into_iter()
                .chain([types::F64])
                .chain([pointer; 2])
                .map(AbiParam::new),
        );
        let ids = (0..layout.chunks.len())
            .map(|chunk| {
                module
                    .declare_function(&format!("chunk{chunk}"), Linkage::Local, &signature)
                    .map_err(cranelift)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let compile = |chunk: usize,
                       context: &mut Context,
                       builder_context: &mut FunctionBuilderContext|
         -> Result<Machine, Error> {
            context.clear();
            context.func.signature = signature.clone();
            context.func.name = UserFuncName::user(0, chunk as u32);
            emit_chunk(program, &layout, chunk, context, builder_context, pointer);
            context
                .compile(&*isa, &mut ControlPlane::default())
                .map_err(|error| cranelift(error.inner))?;
            let code = context
                .compiled_code()
                .ok_or_else(|| cranelift("no code after compiling"))?;
            Ok(Machine {
                alignment: u64::from(code.buffer.alignment),
                bytes: code.code_buffer().to_vec(),
                relocs: code
                    .buffer
                    .relocs()
                    .iter()
                    .map(|reloc| ModuleReloc::from_mach_reloc(reloc, &context.func, ids[chunk]))
                    .collect(),
            })
        };
        for (chunk, machine) in in_parallel(layout.chunks.len(), compile)?
            .into_iter()
            .enumerate()
        {
            module
                .define_function_bytes(
                    ids[chunk],
                    machine.alignment,
                    &machine.bytes,
                    &machine.relocs,
                )
                .map_err(cranelift)?;
        }
        module.finalize_definitions().map_err(cranelift)?;
        let chunks = ids
            .into_iter()
            .map(|id| {
                let address = module.get_finalized_function(id);
                // SAFETY: the function was declared with exactly `ChunkFn`'s signature in
                // the host's default calling convention, which `extern "C"` is.
                unsafe { std::mem::transmute::<*const u8, ChunkFn>(address) }
            })
            .collect();
        Ok(JitProgram {
            chunks,
            needs: layout.needs,
            results: program.results.len(),
            spills: layout.spills,
            ops: program.ops.len(),
            _code: Code(Some(module)),
        })
    }

    /// Number of native functions the program was split into.
    pub fn chunk_count(&self) -> usize {
        self.chunks.len()
    }

    /// Evaluates into `out` as [`Program::eval`] does: `min(out.len(), results)` values.
    pub fn eval(&self, env: &Env, scratch: &mut Scratch, out: &mut [f64]) {
        let Scratch {
            spill,
            results,
            padded,
        } = scratch;
        spill.resize(self.spills, 0.0);
        let slices = [env.q, env.u, env.params, env.inputs];
        let mut pointers = [std::ptr::null::<f64>(); 4];
        for ((pointer, (slice, need)), pad) in pointers
            .iter_mut()
            .zip(slices.iter().zip(self.needs))
            .zip(padded.iter_mut())
        {
            *pointer = if slice.len() >= need {
                slice.as_ptr()
            } else {
                pad.clear();
                pad.extend_from_slice(slice);
                pad.resize(need, f64::NAN);
                pad.as_ptr()
            };
        }
        let direct = out.len() >= self.results;
        let target = if direct {
            out.as_mut_ptr()
        } else {
            results.resize(self.results, 0.0);
            results.as_mut_ptr()
        };
        for chunk in &self.chunks {
            // SAFETY: every pointer covers what the code reads or writes: the symbol slices
            // at least `needs` values (padded above), `target` `self.results` values, the
            // spill array `self.spills`; the code reads and writes nothing else.
            unsafe {
                chunk(
                    pointers[0],
                    pointers[1],
                    pointers[2],
                    pointers[3],
                    env.t,
                    target,
                    spill.as_mut_ptr(),
                )
            };
        }
        if !direct {
            out.copy_from_slice(&results[..out.len()]);
        }
    }
}

/// One chunk's machine code, compiled apart from the module that links it.
struct Machine {
    alignment: u64,
    bytes: Vec<u8>,
    relocs: Vec<ModuleReloc>,
}

/// `compile(i, …)` for every chunk `i < count`, on as many threads as the host has cores
/// (taking chunks in turn), with a Cranelift context per thread; the results in chunk order.
/// Register allocation dominates the compile time and is independent per function, so a
/// long program compiles in about `1/cores` of the time; the code is the same bytes whichever
/// thread compiles it, and is linked in chunk order.
fn in_parallel<F>(count: usize, compile: F) -> Result<Vec<Machine>, Error>
where
    F: Fn(usize, &mut Context, &mut FunctionBuilderContext) -> Result<Machine, Error> + Sync,
{
    let threads = std::thread::available_parallelism()
        .map_or(1, usize::from)
        .min(count);
    let worker = |first: usize| -> Vec<(usize, Result<Machine, Error>)> {
        let mut context = Context::new();
        let mut builder_context = FunctionBuilderContext::new();
        (first..count)
            .step_by(threads.max(1))
            .map(|chunk| (chunk, compile(chunk, &mut context, &mut builder_context)))
            .collect()
    };
    let mut compiled: Vec<(usize, Result<Machine, Error>)> = if threads <= 1 {
        worker(0)
    } else {
        std::thread::scope(|scope| {
            let others: Vec<_> = (1..threads)
                .map(|first| scope.spawn(move || worker(first)))
                .collect();
            let mut all = worker(0);
            for other in others {
                // A panic in Cranelift on another thread is re-raised here, as it would be
                // had that chunk compiled on this one.
                all.extend(
                    other
                        .join()
                        .unwrap_or_else(|panic| std::panic::resume_unwind(panic)),
                );
            }
            all
        })
    };
    compiled.sort_by_key(|(chunk, _)| *chunk);
    compiled.into_iter().map(|(_, machine)| machine).collect()
}

/// Where each register lives: which chunk computes it, which spill slot (if any) carries it
/// to later chunks, and which results each chunk stores.
struct Layout {
    /// `[start, end)` of each chunk's instructions.
    chunks: Vec<(usize, usize)>,
    /// Spill slot of each register, `u32::MAX` for none.
    slot: Vec<u32>,
    spills: usize,
    /// `(result index, register)`, grouped by the chunk that computes the register.
    stores: Vec<Vec<(usize, u32)>>,
    needs: [usize; 4],
}

const NO_SLOT: u32 = u32::MAX;

fn is_leaf(op: &Op) -> bool {
    !op.is_arithmetic()
}

impl Layout {
    fn new(program: &Program, chunk_ops: usize) -> Layout {
        let n = program.ops.len();
        let chunks: Vec<(usize, usize)> = (0..n.div_ceil(chunk_ops).max(1))
            .map(|c| (c * chunk_ops, ((c + 1) * chunk_ops).min(n)))
            .collect();
        let chunk_of = |register: u32| register as usize / chunk_ops;
        let mut slot = vec![NO_SLOT; n];
        let mut spills = 0;
        let mut needs = [0usize; 4];
        for (i, op) in program.ops.iter().enumerate() {
            let (a, b) = op.operands();
            for operand in [a, b].into_iter().flatten() {
                let defined = operand as usize;
                if chunk_of(operand) != i / chunk_ops
                    && !is_leaf(&program.ops[defined])
                    && slot[defined] == NO_SLOT
                {
                    slot[defined] = spills;
                    spills += 1;
                }
            }
            let need = match *op {
                Op::Coordinate(k) => Some((0, k)),
                Op::Speed(k) => Some((1, k)),
                Op::Param(k) => Some((2, k)),
                Op::Input(k) => Some((3, k)),
                _ => None,
            };
            if let Some((which, k)) = need {
                needs[which] = needs[which].max(k as usize + 1);
            }
        }
        let mut stores = vec![Vec::new(); chunks.len()];
        for (index, &register) in program.results.iter().enumerate() {
            stores[chunk_of(register)].push((index, register));
        }
        Layout {
            chunks,
            slot,
            spills: spills as usize,
            stores,
            needs,
        }
    }
}

/// Emits chunk `chunk` of `program` into `context.func`.
fn emit_chunk(
    program: &Program,
    layout: &Layout,
    chunk: usize,
    context: &mut Context,
    builder_context: &mut FunctionBuilderContext,
    pointer: types::Type,
) {
    let (start, end) = layout.chunks[chunk];
    let mut b = FunctionBuilder::new(&mut context.func, builder_context);
    let block = b.create_block();
    b.append_block_params_for_function_params(block);
    b.switch_to_block(block);
    b.seal_block(block);
    let params = b.block_params(block).to_vec();
    let (symbols, t, out, spill) = (
        [params[0], params[1], params[2], params[3]],
        params[4],
        params[5],
        params[6],
    );
    let flags = MemFlags::trusted();
    let mut unary = Signature::new(b.func.signature.call_conv);
    unary.params.push(AbiParam::new(types::F64));
    unary.returns.push(AbiParam::new(types::F64));
    let unary = b.import_signature(unary.clone());
    let mut binary_signature = Signature::new(b.func.signature.call_conv);
    binary_signature
        .params
        .extend([AbiParam::new(types::F64); 2]);
    binary_signature.returns.push(AbiParam::new(types::F64));
    let binary = b.import_signature(binary_signature);
    let mut integer_signature = Signature::new(b.func.signature.call_conv);
    integer_signature
        .params
        .extend([AbiParam::new(types::F64), AbiParam::new(types::I32)]);
    integer_signature.returns.push(AbiParam::new(types::F64));
    let integer = b.import_signature(integer_signature);

    // Values of this chunk's registers, then of earlier registers brought in (a spill slot
    // loaded, a leaf re-materialized), each at most once.
    let mut local: Vec<Option<Value>> = vec![None; end - start];
    let mut imported: std::collections::HashMap<u32, Value> = std::collections::HashMap::new();

    let leaf = |b: &mut FunctionBuilder, op: &Op| -> Value {
        let load = |b: &mut FunctionBuilder, base: Value, k: u32| {
            b.ins().load(types::F64, flags, base, (k as i32) * 8)
        };
        match *op {
            Op::Const(c) => b.ins().f64const(c),
            Op::Coordinate(k) => load(b, symbols[0], k),
            Op::Speed(k) => load(b, symbols[1], k),
            Op::Param(k) => load(b, symbols[2], k),
            Op::Input(k) => load(b, symbols[3], k),
            Op::Time => t,
            _ => unreachable!("not a leaf: {op:?}"),
        }
    };

    for i in start..end {
        let op = program.ops[i];
        let mut get = |b: &mut FunctionBuilder, register: u32| -> Value {
            let r = register as usize;
            if r >= start {
                return local[r - start].expect("operands precede their users");
            }
            *imported.entry(register).or_insert_with(|| {
                let defined = &program.ops[r];
                if is_leaf(defined) {
                    leaf(b, defined)
                } else {
                    let slot = layout.slot[r];
                    debug_assert_ne!(slot, NO_SLOT, "register {r} used later but not spilled");
                    b.ins().load(types::F64, flags, spill, (slot as i32) * 8)
                }
            })
        };
        let call = |b: &mut FunctionBuilder, signature, function: usize, args: &[Value]| {
            let callee = b.ins().iconst(pointer, function as i64);
            let inst = b.ins().call_indirect(signature, callee, args);
            b.inst_results(inst)[0]
        };
        // The operands first, in the order the operation reads them (`Op::operands`, as the
        // layout counted them); one it does not have is Cranelift's reserved value, which no
        // arm below reads.
        let (first, second) = op.operands();
        let mut value_of =
            |register: Option<u32>| register.map_or(Value::reserved_value(), |r| get(&mut b, r));
        let (x, y) = (value_of(first), value_of(second));
        let value = match op {
            Op::Add(..) => b.ins().fadd(x, y),
            Op::Sub(..) => b.ins().fsub(x, y),
            Op::Mul(..) => b.ins().fmul(x, y),
            Op::Div(..) => b.ins().fdiv(x, y),
            // `atan2` of the first operand over the second (the tape's `Atan2(y, x)`).
            Op::Atan2(..) => call(&mut b, binary, shim_atan2 as *const () as usize, &[x, y]),
            Op::Neg(_) => b.ins().fneg(x),
            Op::Sqrt(_) => b.ins().sqrt(x),
            Op::Call(Func::Abs, _) => b.ins().fabs(x),
            Op::Call(f, _) => {
                // `Func::ALL` is in declaration order (a codegen test checks it).
                let shim = FUNC_SHIMS[f as usize];
                call(&mut b, unary, shim as *const () as usize, &[x])
            }
            Op::Powi(_, n) if n.unsigned_abs() <= MAX_INLINE_POWI => powi_inline(&mut b, x, n),
            Op::Powi(_, n) => {
                let n = b.ins().iconst(types::I32, i64::from(n));
                call(&mut b, integer, shim_powi as *const () as usize, &[x, n])
            }
            Op::Powf(_, e) => {
                let e = b.ins().f64const(e);
                call(&mut b, binary, shim_powf as *const () as usize, &[x, e])
            }
            leaf_op => leaf(&mut b, &leaf_op),
        };
        local[i - start] = Some(value);
        let slot = layout.slot[i];
        if slot != NO_SLOT {
            b.ins().store(flags, value, spill, (slot as i32) * 8);
        }
    }
    for &(index, register) in &layout.stores[chunk] {
        let value = local[register as usize - start].expect("a result of this chunk");
        b.ins().store(flags, value, out, (index as i32) * 8);
    }
    b.ins().return_(&[]);
    b.finalize();
}

/// Exponents up to this size are multiplied out inline; larger ones call the shim.
const MAX_INLINE_POWI: u32 = 64;

/// `x^n` by `__powidf2`'s steps: `mul = 1; loop { if bit: mul *= a; next bit; a *= a }`,
/// then `1 / mul` for `n < 0`. `1 · a` is `a` exactly, so the first product is skipped.
fn powi_inline(b: &mut FunctionBuilder, x: Value, n: i32) -> Value {
    let mut power = n.unsigned_abs();
    let mut a = x;
    let mut mul: Option<Value> = None;
    loop {
        if power & 1 != 0 {
            mul = Some(match mul {
                None => a,
                Some(m) => b.ins().fmul(m, a),
            });
        }
        power >>= 1;
        if power == 0 {
            break;
        }
        a = b.ins().fmul(a, a);
    }
    let mul = mul.unwrap_or_else(|| b.ins().f64const(1.0));
    if n < 0 {
        let one = b.ins().f64const(1.0);
        b.ins().fdiv(one, mul)
    } else {
        mul
    }
}

// The shims: the interpreter's own functions (`Func::apply`, `sym::power`, `f64::atan2`,
// `f64::powf`) behind the C calling convention.
/// `Func::ALL[INDEX].apply` behind the C calling convention.
extern "C" fn shim_func<const INDEX: usize>(x: f64) -> f64 {
    Func::ALL[INDEX].apply(x)
}
/// The shims of [`Func::ALL`], in its order.
const FUNC_SHIMS: [extern "C" fn(f64) -> f64; Func::ALL.len()] = [
    shim_func::<0>,
    shim_func::<1>,
    shim_func::<2>,
    shim_func::<3>,
    shim_func::<4>,
    shim_func::<5>,
    shim_func::<6>,
    shim_func::<7>,
];
extern "C" fn shim_atan2(y: f64, x: f64) -> f64 {
    y.atan2(x)
}
extern "C" fn shim_powf(x: f64, e: f64) -> f64 {
    x.powf(e)
}
extern "C" fn shim_powi(x: f64, n: i32) -> f64 {
    power(x, Number::int(i64::from(n)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SplitMix64.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        }
        fn below(&mut self, n: usize) -> usize {
            (self.next() % n as u64) as usize
        }
        fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * (self.next() >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    const SPECIAL: [f64; 12] = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        0.5,
        -2.75,
        1e-310,
        1e300,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
        std::f64::consts::PI,
    ];

    fn interpreted(program: &Program, env: &Env, out_len: usize) -> Vec<f64> {
        let mut out = vec![-7.0; out_len];
        program.eval(env, &mut Vec::new(), &mut out);
        out
    }

    fn native(program: &Program, options: Options, env: &Env, out_len: usize) -> Vec<f64> {
        let code = JitProgram::compile_with(program, options).unwrap();
        let mut out = vec![-7.0; out_len];
        code.eval(env, &mut Scratch::default(), &mut out);
        out
    }

    fn assert_same_bits(what: &str, a: &[f64], b: &[f64]) {
        assert_eq!(a.len(), b.len());
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            assert!(
                x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()),
                "{what}[{i}]: native {x:e} vs interpreter {y:e}"
            );
        }
    }

    fn env<'a>(q: &'a [f64], u: &'a [f64], params: &'a [f64], inputs: &'a [f64]) -> Env<'a> {
        Env {
            t: 0.25,
            q,
            u,
            params,
            inputs,
        }
    }

    /// Every operation on special values, every integer power the tape can hold at its edges.
    #[test]
    fn every_operation_matches_the_interpreter_bit_for_bit() {
        let mut ops: Vec<Op> = SPECIAL.iter().map(|&c| Op::Const(c)).collect();
        ops.extend([
            Op::Coordinate(0),
            Op::Speed(1),
            Op::Param(2),
            Op::Input(0),
            Op::Time,
        ]);
        let leaves = ops.len() as u32;
        for a in 0..leaves {
            ops.extend([Op::Neg(a), Op::Sqrt(a)]);
            for f in Func::ALL {
                ops.push(Op::Call(f, a));
            }
            for e in [0.5, -1.5, 3.0, 1e-3, f64::NAN] {
                ops.push(Op::Powf(a, e));
            }
            for k in (-70..=70).chain([100, -100, 1000, 12345, i32::MAX, i32::MIN, i32::MIN + 1]) {
                ops.push(Op::Powi(a, k));
            }
            for b in (0..leaves).step_by(3) {
                ops.extend([
                    Op::Add(a, b),
                    Op::Sub(a, b),
                    Op::Mul(a, b),
                    Op::Div(a, b),
                    Op::Atan2(a, b),
                ]);
            }
        }
        let program = Program {
            results: (0..ops.len() as u32).collect(),
            ops,
        };
        let (q, u, params, inputs) = ([1.3], [0.0, -0.7], [0.0, 0.0, 2.0e-3], [-4.5]);
        let env = env(&q, &u, &params, &inputs);
        let expected = interpreted(&program, &env, program.results.len());
        for chunk_ops in [1, 5, 2000] {
            let options = Options {
                chunk_ops,
                optimize: chunk_ops != 5,
            };
            let got = native(&program, options, &env, program.results.len());
            assert_same_bits(&format!("chunks of {chunk_ops}"), &got, &expected);
        }
    }

    /// A random program: values carried across many chunks, results anywhere, repeated.
    fn random_program(rng: &mut Rng, len: usize) -> Program {
        let mut ops = vec![
            Op::Coordinate(0),
            Op::Coordinate(1),
            Op::Speed(0),
            Op::Const(0.75),
        ];
        while ops.len() < len {
            let r = ops.len();
            // Operands mostly recent, sometimes far back (spilled across chunks).
            let pick = |rng: &mut Rng| {
                if rng.below(4) == 0 {
                    rng.below(r) as u32
                } else {
                    (r - 1 - rng.below(r.min(8))) as u32
                }
            };
            let (a, b) = (pick(rng), pick(rng));
            ops.push(match rng.below(14) {
                0 | 1 => Op::Add(a, b),
                2 | 3 => Op::Sub(a, b),
                4 | 5 => Op::Mul(a, b),
                6 => Op::Div(a, b),
                7 => Op::Neg(a),
                8 => Op::Sqrt(a),
                9 => Op::Call(Func::Sin, a),
                10 => Op::Atan2(a, b),
                11 => Op::Powi(a, rng.below(7) as i32 - 3),
                12 => Op::Param(rng.below(3) as u32),
                _ => Op::Const(rng.uniform(-2.0, 2.0)),
            });
        }
        let results = (0..40).map(|_| rng.below(len) as u32).collect();
        Program { ops, results }
    }

    #[test]
    fn chunked_programs_match_the_interpreter() {
        let mut rng = Rng(7);
        for len in [4, 30, 500] {
            let program = random_program(&mut rng, len);
            let (q, u, params) = ([0.3, -0.8], [1.1], [0.5, -1.25, 2.0]);
            let env = env(&q, &u, &params, &[]);
            let expected = interpreted(&program, &env, 40);
            for chunk_ops in [1, 3, 64, 10_000] {
                let options = Options {
                    chunk_ops,
                    optimize: true,
                };
                let code = JitProgram::compile_with(&program, options).unwrap();
                assert_eq!(code.chunk_count(), len.div_ceil(chunk_ops));
                let got = native(&program, options, &env, 40);
                assert_same_bits(
                    &format!("{len} ops in chunks of {chunk_ops}"),
                    &got,
                    &expected,
                );
            }
        }
    }

    /// Symbol slices shorter than the program reads give NaN, as in the interpreter; `out`
    /// shorter or longer than the results gets as many values as both have.
    #[test]
    fn short_slices_and_any_output_length_behave_as_the_interpreter() {
        let program = Program {
            ops: vec![
                Op::Coordinate(2),
                Op::Speed(0),
                Op::Param(1),
                Op::Input(3),
                Op::Add(0, 1),
                Op::Mul(2, 4),
                Op::Add(3, 5),
            ],
            results: vec![4, 5, 6, 0],
        };
        let code = JitProgram::compile(&program).unwrap();
        let mut scratch = Scratch::default();
        let (q, u, params, inputs) = ([1.0, 2.0, 3.0], [4.0], [5.0, 6.0], [7.0, 8.0, 9.0, 10.0]);
        type Slices<'a> = (&'a [f64], &'a [f64], &'a [f64], &'a [f64]);
        let cases: [Slices; 4] = [
            (&q, &u, &params, &inputs),
            (&q[..2], &u, &params, &inputs),
            (&q, &[], &params[..1], &inputs[..3]),
            (&[], &[], &[], &[]),
        ];
        for (q, u, params, inputs) in cases {
            let env = env(q, u, params, inputs);
            for out_len in [0, 2, 4, 6] {
                let mut got = vec![-7.0; out_len];
                code.eval(&env, &mut scratch, &mut got);
                assert_same_bits(
                    &format!("q {q:?}, out {out_len}"),
                    &got,
                    &interpreted(&program, &env, out_len),
                );
            }
        }
    }

    #[test]
    fn an_empty_program_compiles() {
        let program = Program::default();
        let code = JitProgram::compile(&program).unwrap();
        code.eval(&env(&[], &[], &[], &[]), &mut Scratch::default(), &mut []);
    }
}
