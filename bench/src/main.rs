//! `mech-bench`: derivation time, operation counts and evaluation time of mech on the
//! N-link 3D chain, N = 1, 2, 4, 8, 16, 32. Prints a table and writes one JSON line per N
//! (plus a first `meta` line) to the results file. `bench/run.sh` runs it beside the peers
//! and turns everything into `docs/benchmarks.md`.
//!
//! Then the two loop models (four-bar, spherical five-bar: assembly, constrained `u̇`, 1 s of
//! motion; one `loop` line each), unless `--no-loops` or `--eval-only`.
//!
//! ```text
//! cargo run --release -p mech-bench -- [--out FILE] [--sizes 1,2,4] [--quick] [--eval-only]
//!     [--loops-only] [--no-loops]
//! ```

use std::fmt::Write as _;
use std::hint::black_box;
use std::io::Write as _;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use mech_bench::timing::{list_json, num, per_call_ns, per_run_s, summary_json, Summary};
use mech_bench::{
    bench_speeds, chain_source, chain_source_per_link, cholesky_solve, param_values, SIZES,
};
use mech_codegen::back::tape::{Env, Program};
use mech_codegen::{Compiled, RustOptions, SourceFile};

struct Config {
    out: PathBuf,
    sizes: Vec<usize>,
    /// Evaluation: batches per measurement and the target time of one batch.
    batches: usize,
    batch_time: Duration,
    /// Derivation: minimum and maximum runs, and the time budget after the minimum.
    min_runs: usize,
    max_runs: usize,
    budget: Duration,
    /// Only the evaluation timings of the generated code (for the paired rounds of run.sh).
    eval_only: bool,
    /// Measure the loop models (four-bar, spherical five-bar); `--no-loops` turns it off.
    loops: bool,
    /// Only the loop models, no chains (for the paired rounds of run.sh).
    loops_only: bool,
}

impl Config {
    fn from_args() -> Result<Config, String> {
        let mut config = Config {
            out: PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/results/mech.jsonl")),
            sizes: SIZES.to_vec(),
            batches: 21,
            batch_time: Duration::from_millis(20),
            min_runs: 5,
            max_runs: 41,
            budget: Duration::from_secs(3),
            eval_only: false,
            loops: true,
            loops_only: false,
        };
        let mut args = std::env::args().skip(1);
        while let Some(arg) = args.next() {
            match arg.as_str() {
                "--out" => config.out = args.next().ok_or("--out needs a file")?.into(),
                "--sizes" => {
                    let list = args.next().ok_or("--sizes needs a list like 1,2,4")?;
                    config.sizes = list
                        .split(',')
                        .map(|s| {
                            s.trim()
                                .parse::<usize>()
                                .map_err(|e| format!("--sizes {s:?}: {e}"))
                        })
                        .collect::<Result<_, _>>()?;
                }
                "--quick" => {
                    config.batches = 3;
                    config.batch_time = Duration::from_millis(2);
                    config.min_runs = 1;
                    config.max_runs = 2;
                    config.budget = Duration::ZERO;
                }
                "--eval-only" => {
                    config.eval_only = true;
                    config.loops = false;
                }
                "--loops-only" => config.loops_only = true,
                "--no-loops" => config.loops = false,
                "-h" | "--help" => {
                    println!(
                        "usage: mech-bench [--out FILE] [--sizes 1,2,4,...] [--quick] [--eval-only] \
                         [--loops-only] [--no-loops]"
                    );
                    std::process::exit(0);
                }
                other => return Err(format!("unknown argument {other:?} (try --help)")),
            }
        }
        Ok(config)
    }
}

/// Evaluation timings of one chain (ns per call) and its accelerations.
struct Eval {
    /// "generated" (Rust from build.rs) or "tape" (interpreted).
    path: &'static str,
    mass_matrix: Summary,
    forcing: Summary,
    /// `M`, `F`, then the in-place Cholesky solve.
    udot: Summary,
    /// `M` then `F`, no solve (generated code only).
    mass_forcing: Option<Summary>,
    /// The in-place Cholesky solve alone, on a copy of `M` and `F` (generated code only).
    solve: Option<Summary>,
    /// `M`, `F`, then nalgebra's `SMatrix::cholesky().solve()` (stack only).
    udot_nalgebra: Option<Summary>,
    /// `u̇` at `q = 0.5`, `u = 0` (cross-check with the peers' `qdd0`).
    udot_rest: Vec<f64>,
    /// `u̇` at `q = 0.5`, `u` = [`bench_speeds`] (the timed state).
    udot_moving: Vec<f64>,
}

/// Times the generated Rust of one chain: `$ty` its struct, `$n` its size.
macro_rules! measure_generated {
    ($ty:ty, $n:literal, $config:expr) => {{
        use mech_runtime::nalgebra::{SMatrix, SVector};
        let config: &Config = $config;
        let model = <$ty>::new();
        let q = SVector::<f64, $n>::from_element(0.5);
        let u = SVector::<f64, $n>::from_column_slice(&bench_speeds($n));
        let inputs = SVector::<f64, 0>::zeros();
        let solve = |q: &SVector<f64, $n>, u: &SVector<f64, $n>| -> SVector<f64, $n> {
            let mut m: SMatrix<f64, $n, $n> = model.mass_matrix_fixed(0.0, q, &inputs);
            let mut f = model.forcing_fixed(0.0, q, u, &inputs);
            if !mech_bench::cholesky_solve_fixed(&mut m, &mut f) {
                f.fill(f64::NAN);
            }
            f
        };
        let (batches, batch) = (config.batches, config.batch_time);
        let mass_matrix = per_call_ns(
            || {
                black_box(model.mass_matrix_fixed(0.0, &black_box(q), &inputs));
            },
            batches,
            batch,
        );
        let forcing = per_call_ns(
            || {
                black_box(model.forcing_fixed(0.0, &black_box(q), &black_box(u), &inputs));
            },
            batches,
            batch,
        );
        let udot = per_call_ns(
            || {
                black_box(solve(&black_box(q), &black_box(u)));
            },
            batches,
            batch,
        );
        let mass_forcing = per_call_ns(
            || {
                let (q, u) = (black_box(q), black_box(u));
                black_box(model.mass_matrix_fixed(0.0, &q, &inputs));
                black_box(model.forcing_fixed(0.0, &q, &u, &inputs));
            },
            batches,
            batch,
        );
        let (m0, f0) = (
            model.mass_matrix_fixed(0.0, &q, &inputs),
            model.forcing_fixed(0.0, &q, &u, &inputs),
        );
        let solve_only = per_call_ns(
            || {
                let (mut m, mut f) = (black_box(m0), black_box(f0));
                black_box(mech_bench::cholesky_solve_fixed(&mut m, &mut f));
                black_box(f);
            },
            batches,
            batch,
        );
        let udot_nalgebra = per_call_ns(
            || {
                let (q, u) = (black_box(q), black_box(u));
                let m = model.mass_matrix_fixed(0.0, &q, &inputs);
                let f = model.forcing_fixed(0.0, &q, &u, &inputs);
                black_box(m.cholesky().map(|c| c.solve(&f)));
            },
            batches,
            batch,
        );
        Eval {
            path: "generated",
            mass_matrix,
            forcing,
            udot,
            mass_forcing: Some(mass_forcing),
            solve: Some(solve_only),
            udot_nalgebra: Some(udot_nalgebra),
            udot_rest: solve(&q, &SVector::zeros()).as_slice().to_vec(),
            udot_moving: solve(&q, &u).as_slice().to_vec(),
        }
    }};
}

/// Times the chain of size `n` through its generated Rust, if `build.rs` generated it.
fn measure_generated(n: usize, config: &Config) -> Option<Eval> {
    macro_rules! visit {
        ($ty:ty, $n:literal) => {
            if n == $n {
                return Some(measure_generated!($ty, $n, config));
            }
        };
    }
    mech_bench::for_each_generated_chain!(visit);
    None
}

/// `M` and `F` through the tape (interpreted), then the same Cholesky solve.
struct TapeEval<'a> {
    tape: &'a mech_codegen::Tape,
    params: Vec<f64>,
    n: usize,
    registers: Vec<f64>,
    m: Vec<f64>,
    f: Vec<f64>,
}

impl TapeEval<'_> {
    fn env<'b>(&'b self, q: &'b [f64], u: &'b [f64]) -> Env<'b> {
        Env {
            t: 0.0,
            q,
            u,
            params: &self.params,
            inputs: &[],
        }
    }

    fn mass_matrix(&mut self, q: &[f64]) {
        let (mut registers, mut m) = (
            std::mem::take(&mut self.registers),
            std::mem::take(&mut self.m),
        );
        self.tape
            .mass_matrix
            .eval(&self.env(q, &[]), &mut registers, &mut m);
        (self.registers, self.m) = (registers, m);
    }

    fn forcing(&mut self, q: &[f64], u: &[f64]) {
        let (mut registers, mut f) = (
            std::mem::take(&mut self.registers),
            std::mem::take(&mut self.f),
        );
        self.tape
            .forcing
            .eval(&self.env(q, u), &mut registers, &mut f);
        (self.registers, self.f) = (registers, f);
    }

    fn solve(&mut self, q: &[f64], u: &[f64]) -> &[f64] {
        self.mass_matrix(q);
        self.forcing(q, u);
        if !cholesky_solve(&mut self.m, &mut self.f, self.n) {
            self.f.fill(f64::NAN);
        }
        &self.f
    }
}

fn measure_tape(compiled: &Compiled, tape: &mech_codegen::Tape, config: &Config) -> Eval {
    let n = compiled.equations.nu;
    let mut eval = TapeEval {
        tape,
        params: param_values(compiled),
        n,
        registers: Vec::new(),
        m: vec![0.0; n * n],
        f: vec![0.0; n],
    };
    let q = vec![0.5; n];
    let u = bench_speeds(n);
    let (batches, batch) = (config.batches, config.batch_time);
    let mass_matrix = per_call_ns(|| eval.mass_matrix(black_box(&q)), batches, batch);
    let forcing = per_call_ns(
        || eval.forcing(black_box(&q), black_box(&u)),
        batches,
        batch,
    );
    let udot = per_call_ns(
        || {
            black_box(eval.solve(black_box(&q), black_box(&u)));
        },
        batches,
        batch,
    );
    let udot_rest = eval.solve(&q, &vec![0.0; n]).to_vec();
    let udot_moving = eval.solve(&q, &u).to_vec();
    Eval {
        path: "tape",
        mass_matrix,
        forcing,
        udot,
        mass_forcing: None,
        solve: None,
        udot_nalgebra: None,
        udot_rest,
        udot_moving,
    }
}

/// Everything measured for one chain size.
struct Record {
    n: usize,
    derive: Summary,
    kane_only: Summary,
    emit: Summary,
    emit_lines: usize,
    emit_bytes: usize,
    tape_build: Summary,
    ops_mass_matrix: usize,
    ops_forcing: usize,
    ops_outputs: usize,
    ops_mass_forcing_joint: usize,
    per_link_derive: Summary,
    per_link_ops_mass_matrix: usize,
    per_link_ops_forcing: usize,
    per_link_ops_mass_forcing_joint: usize,
    pool_nodes: usize,
    generated: Option<Eval>,
    tape: Eval,
    /// Largest |u̇_generated − u̇_tape| at the timed state (0 when there is no generated code).
    generated_vs_tape: f64,
}

fn compile(name: &str, text: &str) -> Compiled {
    match Compiled::from_source(SourceFile::new(name, text.to_string())) {
        Ok(compiled) => compiled,
        Err(errors) => panic!("{name} does not compile: {errors:?}"),
    }
}

fn joint_ops(compiled: &Compiled) -> usize {
    let equations = &compiled.equations;
    let roots: Vec<_> = equations
        .mass_matrix
        .iter()
        .chain(&equations.forcing)
        .copied()
        .collect();
    Program::compile(&equations.pool, &roots).operation_count()
}

fn measure(n: usize, config: &Config) -> Record {
    let name = format!("chain{n}.mech");
    let text = chain_source(n);
    let (min, max, budget) = (config.min_runs, config.max_runs, config.budget);

    // Parse + lower + Kane derivation, from source text to equations.
    let (derive, compiled) = per_run_s(|| compile(&name, &text), min, max, budget);
    let (kane_only, _) = per_run_s(
        || mech_codegen::kane::derive(&compiled.model),
        min,
        max,
        budget,
    );
    let options = RustOptions {
        source_name: name.clone(),
        ..RustOptions::default()
    };
    let (emit, rust) = per_run_s(|| compiled.rust(&options), min, max, budget);
    let (tape_build, tape) = per_run_s(|| compiled.tape(), min, max, budget);

    let per_link_name = format!("chain{n}_per_link.mech");
    let per_link_text = chain_source_per_link(n);
    let (per_link_derive, per_link) =
        per_run_s(|| compile(&per_link_name, &per_link_text), min, max, budget);
    let per_link_tape = per_link.tape();

    let generated = measure_generated(n, config);
    let tape_eval = measure_tape(&compiled, &tape, config);
    let generated_vs_tape = generated.as_ref().map_or(0.0, |g| {
        g.udot_moving
            .iter()
            .zip(&tape_eval.udot_moving)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    });

    Record {
        n,
        derive,
        kane_only,
        emit,
        emit_lines: rust.lines().count(),
        emit_bytes: rust.len(),
        tape_build,
        ops_mass_matrix: tape.mass_matrix.operation_count(),
        ops_forcing: tape.forcing.operation_count(),
        ops_outputs: tape.outputs.operation_count(),
        ops_mass_forcing_joint: joint_ops(&compiled),
        per_link_derive,
        per_link_ops_mass_matrix: per_link_tape.mass_matrix.operation_count(),
        per_link_ops_forcing: per_link_tape.forcing.operation_count(),
        per_link_ops_mass_forcing_joint: joint_ops(&per_link),
        pool_nodes: compiled.equations.pool.len(),
        generated,
        tape: tape_eval,
        generated_vs_tape,
    }
}

// ---- output ----

fn eval_json(e: &Eval) -> String {
    format!(
        "{{\"path\":\"{}\",\"mass_matrix_ns\":{},\"forcing_ns\":{},\"udot_ns\":{},\"udot_nalgebra_ns\":{},\
         \"mass_forcing_ns\":{},\"solve_ns\":{},\"udot_rest\":{},\"udot_moving\":{}}}",
        e.path,
        summary_json(&e.mass_matrix),
        summary_json(&e.forcing),
        summary_json(&e.udot),
        e.udot_nalgebra.as_ref().map_or("null".to_string(), summary_json),
        e.mass_forcing.as_ref().map_or("null".to_string(), summary_json),
        e.solve.as_ref().map_or("null".to_string(), summary_json),
        list_json(&e.udot_rest),
        list_json(&e.udot_moving)
    )
}

fn record_json(r: &Record) -> String {
    let mut s = String::new();
    let _ = write!(
        s,
        "{{\"record\":\"chain\",\"N\":{},\"derive_s\":{},\"kane_only_s\":{},\"emit_rust_s\":{},\
         \"emit_rust_lines\":{},\"emit_rust_bytes\":{},\"tape_build_s\":{},\"ops_mass_matrix\":{},\
         \"ops_forcing\":{},\"ops_outputs\":{},\"ops_mass_forcing_joint\":{},\"pool_nodes\":{},\
         \"per_link_derive_s\":{},\"per_link_ops_mass_matrix\":{},\"per_link_ops_forcing\":{},\
         \"per_link_ops_mass_forcing_joint\":{},\"generated\":{},\"tape\":{},\"generated_vs_tape_maxabs\":{}}}",
        r.n,
        summary_json(&r.derive),
        summary_json(&r.kane_only),
        summary_json(&r.emit),
        r.emit_lines,
        r.emit_bytes,
        summary_json(&r.tape_build),
        r.ops_mass_matrix,
        r.ops_forcing,
        r.ops_outputs,
        r.ops_mass_forcing_joint,
        r.pool_nodes,
        summary_json(&r.per_link_derive),
        r.per_link_ops_mass_matrix,
        r.per_link_ops_forcing,
        r.per_link_ops_mass_forcing_joint,
        r.generated.as_ref().map_or("null".to_string(), eval_json),
        eval_json(&r.tape),
        num(r.generated_vs_tape)
    );
    s
}

fn loadavg() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.trim().to_string())
        .unwrap_or_default()
}

fn main() {
    let config = match Config::from_args() {
        Ok(config) => config,
        Err(message) => {
            eprintln!("mech-bench: {message}");
            std::process::exit(2);
        }
    };
    if let Some(dir) = config.out.parent() {
        std::fs::create_dir_all(dir).expect("create the results folder");
    }
    let mut file = std::fs::File::create(&config.out).expect("create the results file");
    let started = Instant::now();
    let threads = std::thread::available_parallelism().map_or(0, |n| n.get());
    writeln!(
        file,
        "{{\"record\":\"meta\",\"available_parallelism\":{threads},\"loadavg_start\":\"{}\",\"debug_assertions\":{}}}",
        loadavg(),
        cfg!(debug_assertions)
    )
    .expect("write results");
    println!(
        "{:>3} {:>10} {:>10} {:>9} {:>9} {:>9} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "N",
        "derive ms",
        "emit ms",
        "ops M",
        "ops F",
        "ops M+F",
        "ops M+F pl",
        "M ns",
        "F ns",
        "u̇ ns",
        "u̇ na ns",
        "tape u̇ ns",
        "path"
    );
    let sizes: &[usize] = if config.loops_only {
        &[]
    } else {
        &config.sizes
    };
    for &n in sizes {
        if config.eval_only {
            let Some(e) = measure_generated(n, &config) else {
                eprintln!("mech-bench: chain{n} was not compiled to Rust");
                continue;
            };
            println!(
                "{:>3} {:>10} {:>10} {:>9} {:>9} {:>9} {:>10} {:>10.1} {:>10.1} {:>10.1} {:>10} {:>10} {:>10}",
                n, "-", "-", "-", "-", "-", "-", e.mass_matrix.median, e.forcing.median, e.udot.median,
                e.udot_nalgebra.map_or("-".to_string(), |s| format!("{:.1}", s.median)), "-", e.path
            );
            eprintln!(
                "N = {n}: M then F {:.1} ns, Cholesky solve alone {:.1} ns",
                e.mass_forcing.map_or(f64::NAN, |s| s.median),
                e.solve.map_or(f64::NAN, |s| s.median)
            );
            writeln!(
                file,
                "{{\"record\":\"eval\",\"N\":{n},\"generated\":{}}}",
                eval_json(&e)
            )
            .expect("write results");
            continue;
        }
        let r = measure(n, &config);
        let e = r.generated.as_ref().unwrap_or(&r.tape);
        println!(
            "{:>3} {:>10.3} {:>10.3} {:>9} {:>9} {:>9} {:>10} {:>10.1} {:>10.1} {:>10.1} {:>10} {:>10.1} {:>10}",
            n,
            r.derive.median * 1e3,
            r.emit.median * 1e3,
            r.ops_mass_matrix,
            r.ops_forcing,
            r.ops_mass_forcing_joint,
            r.per_link_ops_mass_forcing_joint,
            e.mass_matrix.median,
            e.forcing.median,
            e.udot.median,
            e.udot_nalgebra.map_or("-".to_string(), |s| format!("{:.1}", s.median)),
            r.tape.udot.median,
            e.path
        );
        writeln!(file, "{}", record_json(&r)).expect("write results");
    }
    if config.loops || config.loops_only {
        let loop_config = mech_bench::loops::LoopConfig {
            batches: config.batches,
            batch_time: config.batch_time,
            min_runs: if config.min_runs > 1 { 21 } else { 1 },
            max_runs: if config.max_runs > 2 { 201 } else { 2 },
            budget: config.budget,
        };
        for r in mech_bench::loops::measure_loops(&loop_config) {
            println!(
                "{}: assemble {:.2} µs, u̇ {:.1} ns, 1 s of motion {:.1} µs ({} steps, {} rhs), \
                 q1(1 s) = {:.10}",
                r.model,
                r.assemble.median * 1e-3,
                r.udot.median,
                r.motion.wall.median * 1e6,
                r.motion.stats.accepted_steps,
                r.motion.stats.rhs_evaluations,
                r.motion.q_final[0]
            );
            writeln!(file, "{}", mech_bench::loops::loop_json(&r)).expect("write results");
        }
    }
    writeln!(
        file,
        "{{\"record\":\"end\",\"loadavg_end\":\"{}\",\"wall_s\":{}}}",
        loadavg(),
        num(started.elapsed().as_secs_f64())
    )
    .expect("write results");
    eprintln!("wrote {}", config.out.display());
}
