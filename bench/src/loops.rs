//! The two bundled loop models, `models/four_bar.mech` and `models/spherical_five_bar.mech`,
//! compiled to Rust by `build.rs` (the same generated code as `mech::models`), and what
//! `docs/benchmarks.md` measures on them beside SymPy/PyDy + SciPy: assembly, one constrained
//! `u̇` (`ConstrainedSolver::accelerations`) and 1 s of motion through
//! `mech_runtime::simulate` (DOP853 as the peers' `solve_ivp`, and DOPRI5; projection after
//! every accepted step).

use std::hint::black_box;
use std::time::Duration;

use mech_runtime::{
    assemble, assemble_speeds, AdaptiveOptions, AssemblyOptions, ConstrainedSolver, Dop853, Method,
    Model, ModelOde, SimOptions, Stats, Stepper,
};

use crate::timing::{list_json, num, per_call_ns, per_run_s, summary_json, Summary};

#[allow(non_snake_case)]
pub mod four_bar {
    mech_runtime::include_model!("four_bar");
}

#[allow(non_snake_case)]
pub mod spherical_five_bar {
    mech_runtime::include_model!("spherical_five_bar");
}

/// The tolerance of the SymPy peers' `solve_ivp` (`rtol = atol = 1e-9`), used for DOPRI5 too.
pub const TOLERANCE: f64 = 1e-9;

/// Coordinates held during assembly: the crank of the four-bar (as `sympy_fourbar.py` holds
/// q1), the first two hinges of the five-bar (as `tests/loops.rs` and `sympy_fivebar.py` do).
pub const FOUR_BAR_FIXED: &[usize] = &[0];
pub const FIVE_BAR_FIXED: &[usize] = &[0, 1];

/// How long and how often to time things.
#[derive(Clone, Copy, Debug)]
pub struct LoopConfig {
    pub batches: usize,
    pub batch_time: Duration,
    /// Runs of the 1 s simulation: at least `min_runs`, then until `budget`, at most `max_runs`.
    pub min_runs: usize,
    pub max_runs: usize,
    pub budget: Duration,
}

/// One simulation of 1 s and its end state.
#[derive(Clone, Debug)]
pub struct Motion {
    pub wall: Summary,
    pub stats: Stats,
    pub q_final: Vec<f64>,
    pub u_final: Vec<f64>,
    /// `max |φ|` and `max |J u|` at t = 1 s.
    pub phi_final: f64,
    pub ju_final: f64,
    /// `(ke + pe)(1 s) − (ke + pe)(0)`, from the model's outputs.
    pub energy_drift: f64,
}

/// Everything measured on one loop model.
#[derive(Clone, Debug)]
pub struct LoopRecord {
    pub model: &'static str,
    pub nq: usize,
    pub nc: usize,
    pub fixed: Vec<usize>,
    /// The model's `q0` (before assembly) and the assembled state.
    pub q0: Vec<f64>,
    pub q: Vec<f64>,
    pub u: Vec<f64>,
    /// `assemble` (positions, from `q0`) and `assemble_speeds`, in ns per call.
    pub assemble: Summary,
    pub assemble_iterations: usize,
    pub assemble_speeds: Summary,
    /// The generated functions alone, through the `Model` trait (ns per call).
    pub mass_matrix: Summary,
    pub forcing: Summary,
    pub jacobian: Summary,
    pub bias: Summary,
    pub constraints: Summary,
    /// `ConstrainedSolver::accelerations` at the assembled state (ns per call).
    pub udot: Summary,
    pub udot_value: Vec<f64>,
    /// `ConstrainedSolver::project` from the assembled state with `q` and `u` nudged off the
    /// manifold by 1e-9 (one Newton step and a velocity projection), ns per call.
    pub project: Summary,
    /// 1 s through `simulate` with DOP853, samples at 0 and 1 s only (as `solve_ivp` without
    /// `t_eval`).
    pub motion: Motion,
    /// The same with DOPRI5.
    pub motion_dopri5: Motion,
    /// DOP853 with the default 1 kHz output grid (dense output + projection per sample).
    pub motion_1khz: Motion,
    /// DOP853 on `ModelOde` stepped directly, no projection (what the SymPy peers do).
    pub motion_unprojected: Motion,
}

fn max_abs(values: &[f64]) -> f64 {
    values.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// The assembled initial state of a model: `q0` with the `fixed` coordinates held, the other
/// coordinates solved for `φ = 0`, then `u` solved for `J u = 0` with the fixed speeds held.
pub fn assembled<M: Model>(model: &M, fixed: &[usize]) -> (Vec<f64>, Vec<f64>, usize) {
    let mut q = vec![0.0; model.nq()];
    let mut u = vec![0.0; model.nu()];
    model.initial_state(&mut q, &mut u);
    let iterations = assemble(model, 0.0, &mut q, fixed, &AssemblyOptions::default())
        .unwrap_or_else(|e| panic!("{} does not assemble: {e}", model.name()));
    assemble_speeds(model, 0.0, &q, &mut u, fixed).unwrap();
    (q, u, iterations)
}

/// DOP853, as the SymPy peers' `solve_ivp(method="DOP853")`: the headline comparison.
pub const DOP853: Method = Method::Dop853 {
    rtol: TOLERANCE,
    atol: TOLERANCE,
    h_max: f64::INFINITY,
};

/// DOPRI5 at the same tolerance, for comparison.
const DOPRI5: Method = Method::Dopri5 {
    rtol: TOLERANCE,
    atol: TOLERANCE,
    h_max: f64::INFINITY,
};

fn sim_options(output_interval: f64, method: Method) -> SimOptions {
    SimOptions {
        t_start: 0.0,
        t_end: 1.0,
        output_interval,
        method,
        ..SimOptions::default()
    }
}

fn energy<M: Model>(model: &M, q: &[f64], u: &[f64]) -> f64 {
    let mut y = vec![0.0; model.noutputs()];
    model.outputs(1.0, q, u, &[], &mut y);
    let ke = model.output_index("ke").map_or(0.0, |i| y[i]);
    let pe = model.output_index("pe").map_or(0.0, |i| y[i]);
    ke + pe
}

fn end_state<M: Model>(
    model: &M,
    q0: &[f64],
    u0: &[f64],
    q: &[f64],
    u: &[f64],
    stats: Stats,
    wall: Summary,
) -> Motion {
    let mut phi = vec![0.0; model.nc()];
    model.constraints(1.0, q, &mut phi);
    let mut j = vec![0.0; model.nc() * model.nq()];
    model.constraint_jacobian(1.0, q, &mut j);
    let nc = model.nc();
    let ju: Vec<f64> = (0..nc)
        .map(|r| (0..model.nq()).map(|c| j[r + nc * c] * u[c]).sum())
        .collect();
    Motion {
        wall,
        stats,
        q_final: q.to_vec(),
        u_final: u.to_vec(),
        phi_final: max_abs(&phi),
        ju_final: max_abs(&ju),
        energy_drift: energy(model, q, u) - energy(model, q0, u0),
    }
}

fn motion<M: Model>(
    model: &M,
    q0: &[f64],
    u0: &[f64],
    output_interval: f64,
    method: Method,
    config: &LoopConfig,
) -> Motion {
    let options = sim_options(output_interval, method);
    let run = || {
        mech_runtime::simulate(model, q0, u0, &[], &options, &mut |_| {})
            .unwrap_or_else(|e| panic!("{}: simulate failed: {e}", model.name()))
    };
    let (wall, trajectory) = per_run_s(run, config.min_runs, config.max_runs, config.budget);
    let (q, u) = (
        trajectory.q.last().expect("samples"),
        trajectory.u.last().expect("samples"),
    );
    end_state(model, q0, u0, q, u, trajectory.stats, wall)
}

fn motion_unprojected<M: Model>(model: &M, q0: &[f64], u0: &[f64], config: &LoopConfig) -> Motion {
    let x0: Vec<f64> = q0.iter().chain(u0).copied().collect();
    let options = AdaptiveOptions::dop853().with_tolerances(TOLERANCE, TOLERANCE);
    let run = || {
        let ode = ModelOde::new(model, &[]).expect("an ODE");
        let mut stepper = Dop853::new(ode, 0.0, &x0, 1.0, options).expect("a stepper");
        while !stepper.is_finished() {
            stepper.step().expect("a step");
        }
        (stepper.state().to_vec(), stepper.stats())
    };
    let (wall, (x, stats)) = per_run_s(run, config.min_runs, config.max_runs, config.budget);
    let (q, u) = x.split_at(model.nq());
    end_state(model, q0, u0, q, u, stats, wall)
}

/// Measures one loop model (its generated Rust).
pub fn measure_loop<M: Model>(
    name: &'static str,
    model: &M,
    fixed: &[usize],
    config: &LoopConfig,
) -> LoopRecord {
    let (nq, nc) = (model.nq(), model.nc());
    let (batches, batch) = (config.batches, config.batch_time);
    let (mut q0, mut u0) = (vec![0.0; nq], vec![0.0; nq]);
    model.initial_state(&mut q0, &mut u0);
    let (q, u, assemble_iterations) = assembled(model, fixed);

    let options = AssemblyOptions::default();
    let mut scratch = q0.clone();
    let assemble_time = per_call_ns(
        || {
            scratch.copy_from_slice(&q0);
            black_box(assemble(model, 0.0, black_box(&mut scratch), fixed, &options).ok());
        },
        batches,
        batch,
    );
    let mut speeds = u0.clone();
    let assemble_speeds_time = per_call_ns(
        || {
            speeds.copy_from_slice(&u0);
            assemble_speeds(model, 0.0, black_box(&q), black_box(&mut speeds), fixed).unwrap();
        },
        batches,
        batch,
    );

    let mut mass = vec![0.0; nq * nq];
    let mut vector = vec![0.0; nq];
    let mut rows = vec![0.0; nc];
    let mut jacobian = vec![0.0; nc * nq];
    let mass_matrix = per_call_ns(
        || model.mass_matrix(0.0, black_box(&q), &[], black_box(&mut mass)),
        batches,
        batch,
    );
    let forcing = per_call_ns(
        || {
            model.forcing(
                0.0,
                black_box(&q),
                black_box(&u),
                &[],
                black_box(&mut vector),
            )
        },
        batches,
        batch,
    );
    let jacobian_time = per_call_ns(
        || model.constraint_jacobian(0.0, black_box(&q), black_box(&mut jacobian)),
        batches,
        batch,
    );
    let bias = per_call_ns(
        || model.constraint_bias(0.0, black_box(&q), black_box(&u), black_box(&mut rows)),
        batches,
        batch,
    );
    let constraints = per_call_ns(
        || model.constraints(0.0, black_box(&q), black_box(&mut rows)),
        batches,
        batch,
    );

    let mut solver = ConstrainedSolver::new(nq, nq, nc);
    let mut udot = vec![0.0; nq];
    let udot_time = per_call_ns(
        || {
            black_box(
                solver
                    .accelerations(model, 0.0, black_box(&q), black_box(&u), &[], &mut udot)
                    .is_ok(),
            );
        },
        batches,
        batch,
    );
    solver
        .accelerations(model, 0.0, &q, &u, &[], &mut udot)
        .expect("u̇ at the assembled state");
    let udot_value = udot.clone();

    let (mut qp, mut up) = (q.clone(), u.clone());
    let project = per_call_ns(
        || {
            for (i, (a, b)) in qp.iter_mut().zip(&q).enumerate() {
                *a = b + 1e-9 * (i as f64 + 1.0);
            }
            for (i, (a, b)) in up.iter_mut().zip(&u).enumerate() {
                *a = b - 1e-9 * (i as f64 + 1.0);
            }
            black_box(
                solver
                    .project(model, 0.0, &mut qp, &mut up, &[], 1e-12)
                    .is_ok(),
            );
        },
        batches,
        batch,
    );

    LoopRecord {
        model: name,
        nq,
        nc,
        fixed: fixed.to_vec(),
        q0,
        q: q.clone(),
        u: u.clone(),
        assemble: assemble_time,
        assemble_iterations,
        assemble_speeds: assemble_speeds_time,
        mass_matrix,
        forcing,
        jacobian: jacobian_time,
        bias,
        constraints,
        udot: udot_time,
        udot_value,
        project,
        motion: motion(model, &q, &u, 1.0, DOP853, config),
        motion_dopri5: motion(model, &q, &u, 1.0, DOPRI5, config),
        motion_1khz: motion(model, &q, &u, 1e-3, DOP853, config),
        motion_unprojected: motion_unprojected(model, &q, &u, config),
    }
}

/// Both loop models.
pub fn measure_loops(config: &LoopConfig) -> Vec<LoopRecord> {
    vec![
        measure_loop(
            "four_bar",
            &four_bar::FourBar::new(),
            FOUR_BAR_FIXED,
            config,
        ),
        measure_loop(
            "spherical_five_bar",
            &spherical_five_bar::SphericalFiveBar::new(),
            FIVE_BAR_FIXED,
            config,
        ),
    ]
}

fn motion_json(m: &Motion) -> String {
    format!(
        "{{\"wall_s\":{},\"accepted_steps\":{},\"rejected_steps\":{},\"rhs_evaluations\":{},\
         \"q_final\":{},\"u_final\":{},\"phi_final\":{},\"ju_final\":{},\"energy_drift\":{}}}",
        summary_json(&m.wall),
        m.stats.accepted_steps,
        m.stats.rejected_steps,
        m.stats.rhs_evaluations,
        list_json(&m.q_final),
        list_json(&m.u_final),
        num(m.phi_final),
        num(m.ju_final),
        num(m.energy_drift)
    )
}

/// One JSON line (`"record":"loop"`).
pub fn loop_json(r: &LoopRecord) -> String {
    format!(
        "{{\"record\":\"loop\",\"model\":\"{}\",\"nq\":{},\"nc\":{},\"fixed\":[{}],\"tolerance\":{},\
         \"q0\":{},\"q\":{},\"u\":{},\"assemble_ns\":{},\"assemble_iterations\":{},\
         \"assemble_speeds_ns\":{},\"mass_matrix_ns\":{},\"forcing_ns\":{},\"jacobian_ns\":{},\
         \"bias_ns\":{},\"constraints_ns\":{},\"udot_ns\":{},\"udot\":{},\"project_ns\":{},\
         \"sim1s\":{},\"sim1s_dopri5\":{},\"sim1s_1khz\":{},\"sim1s_unprojected\":{}}}",
        r.model,
        r.nq,
        r.nc,
        r.fixed
            .iter()
            .map(|c| c.to_string())
            .collect::<Vec<_>>()
            .join(","),
        num(TOLERANCE),
        list_json(&r.q0),
        list_json(&r.q),
        list_json(&r.u),
        summary_json(&r.assemble),
        r.assemble_iterations,
        summary_json(&r.assemble_speeds),
        summary_json(&r.mass_matrix),
        summary_json(&r.forcing),
        summary_json(&r.jacobian),
        summary_json(&r.bias),
        summary_json(&r.constraints),
        summary_json(&r.udot),
        list_json(&r.udot_value),
        summary_json(&r.project),
        motion_json(&r.motion),
        motion_json(&r.motion_dopri5),
        motion_json(&r.motion_1khz),
        motion_json(&r.motion_unprojected)
    )
}
