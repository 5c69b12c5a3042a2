//! Helpers shared by the integration tests.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use mech::diagnose::data::MeasuredData;
use mech::diagnose::experiment::{self, Experiment};
use mech::experiments::leg::{Dof, Leg};
use mech::tape_model::TapeModel;
use mech_codegen::Compiled;
use mech_runtime::{Method, Model, SimOptions, Trajectory};
use serde_json::Value;

mod written;
#[allow(unused_imports)]
pub use written::{hamr_vi_written, WrittenEffect, FOOT_SIDE_FORCE};

/// The path of a bundled model, `models/NAME.mech`.
pub fn bundled_path(name: &str) -> String {
    format!("{}/models/{name}.mech", env!("CARGO_MANIFEST_DIR"))
}

/// The text of a bundled model.
pub fn bundled_source(name: &str) -> String {
    std::fs::read_to_string(bundled_path(name)).unwrap()
}

/// HAMR-VI as a leg (`models/hamr_vi.mech`), the actuator coordinates (swing and lift)
/// held independent.
pub fn hamr_vi_spec() -> mech::session::ModelSpec {
    mech::session::ModelSpec {
        path: bundled_path("hamr_vi").into(),
        set: Vec::new(),
        independent: vec!["qsact".into(), "qlact".into()],
    }
}

/// Compiles a bundled model from `models/`.
pub fn compile_bundled(name: &str) -> Compiled {
    let path = bundled_path(name);
    Compiled::from_path(&path).unwrap_or_else(|errors| panic!("{errors}"))
}

/// Compiles model text given inline.
pub fn compile_text(name: &str, text: &str) -> Compiled {
    Compiled::from_source(mech_codegen::SourceFile::new(format!("{name}.mech"), text))
        .unwrap_or_else(|e| panic!("{e}"))
}

pub fn tape(name: &str) -> TapeModel {
    TapeModel::new(&compile_bundled(name))
}

/// The tape of model text given inline.
pub fn tape_from_text(name: &str, text: &str) -> TapeModel {
    TapeModel::new(&compile_text(name, text))
}

/// The model's own `q0`, `u0`.
pub fn initial_state(model: &dyn Model) -> (Vec<f64>, Vec<f64>) {
    let (mut q, mut u) = (vec![0.0; model.nq()], vec![0.0; model.nu()]);
    model.initial_state(&mut q, &mut u);
    (q, u)
}

/// Every input of `model` at its default value.
pub fn default_inputs(model: &dyn Model) -> Vec<f64> {
    (0..model.ninputs())
        .map(|i| model.input_default(i))
        .collect()
}

/// `M` as a dense row-major `Vec<Vec<f64>>` (the trait writes column-major).
pub fn mass_matrix(model: &dyn Model, q: &[f64]) -> Vec<Vec<f64>> {
    let n = model.nu();
    let mut m = vec![0.0; n * n];
    let inputs = default_inputs(model);
    model.mass_matrix(0.0, q, &inputs, &mut m);
    (0..n)
        .map(|r| (0..n).map(|c| m[r + n * c]).collect())
        .collect()
}

pub fn forcing(model: &dyn Model, q: &[f64], u: &[f64]) -> Vec<f64> {
    let mut f = vec![0.0; model.nu()];
    let inputs = default_inputs(model);
    model.forcing(0.0, q, u, &inputs, &mut f);
    f
}

/// `u̇ = M⁻¹F` at `(q, u)` and the default inputs, by LU.
pub fn accelerations(model: &dyn Model, q: &[f64], u: &[f64]) -> Vec<f64> {
    use mech_runtime::nalgebra::{DMatrix, DVector};
    let n = model.nu();
    let mut m = vec![0.0; n * n];
    model.mass_matrix(0.0, q, &default_inputs(model), &mut m);
    let f = DVector::from_vec(forcing(model, q, u));
    let solved = DMatrix::from_vec(n, n, m).lu().solve(&f);
    solved.expect("M is invertible").iter().copied().collect()
}

pub fn outputs(model: &dyn Model, q: &[f64], u: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; model.noutputs()];
    let inputs = default_inputs(model);
    model.outputs(0.0, q, u, &inputs, &mut y);
    y
}

pub fn output(model: &dyn Model, name: &str, q: &[f64], u: &[f64]) -> f64 {
    let index = model
        .output_index(name)
        .unwrap_or_else(|| panic!("model has no output `{name}`"));
    outputs(model, q, u)[index]
}

/// A deterministic pseudo-random generator (SplitMix64), so tests need no extra crate.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `(0, 1)`: the midpoints of the 2⁻⁵³ grid, so never 0 (for a logarithm).
    pub fn uniform_open(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    /// Uniform in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        let z = self.next_u64();
        lo + (hi - lo) * (z >> 11) as f64 / (1u64 << 53) as f64
    }
    /// A standard normal variate: Box–Muller on `uniform(1e-12, 1)` (never 0) and
    /// `uniform(0, 1)`.
    pub fn normal(&mut self) -> f64 {
        let (a, b) = (self.uniform(1e-12, 1.0), self.uniform(0.0, 1.0));
        box_muller(a, b)
    }
    /// Uniform in `0..n` (`n > 0`).
    pub fn index(&mut self, n: usize) -> usize {
        (self.uniform(0.0, n as f64) as usize).min(n - 1)
    }
    pub fn vector(&mut self, n: usize, lo: f64, hi: f64) -> Vec<f64> {
        (0..n).map(|_| self.uniform(lo, hi)).collect()
    }
}

/// `(value − reference) / reference`.
pub fn relative_error(value: f64, reference: f64) -> f64 {
    (value - reference) / reference
}

/// `|a − b| ≤ tol · scale` with `scale = max(|b|, floor)`.
pub fn assert_close(what: &str, a: f64, b: f64, tol: f64, floor: f64) {
    let scale = b.abs().max(floor);
    assert!(
        (a - b).abs() <= tol * scale,
        "{what}: {a} vs {b} (difference {:e}, allowed {:e})",
        (a - b).abs(),
        tol * scale
    );
}

/// A standard normal variate from two uniform variates in `(0, 1]` and `[0, 1)` (Box–Muller).
pub fn box_muller(u1: f64, u2: f64) -> f64 {
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// One classical Runge–Kutta step of `θ̈ = accel(θ, θ̇)` (the pendulum generators' own
/// integrator, independent of the runtime's).
pub fn rk4_step((theta, omega): (f64, f64), h: f64, accel: impl Fn(f64, f64) -> f64) -> (f64, f64) {
    let (k1x, k1v) = (omega, accel(theta, omega));
    let (k2x, k2v) = (
        omega + 0.5 * h * k1v,
        accel(theta + 0.5 * h * k1x, omega + 0.5 * h * k1v),
    );
    let (k3x, k3v) = (
        omega + 0.5 * h * k2v,
        accel(theta + 0.5 * h * k2x, omega + 0.5 * h * k2v),
    );
    let (k4x, k4v) = (omega + h * k3v, accel(theta + h * k3x, omega + h * k3v));
    (
        theta + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
        omega + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
    )
}

/// A directory of `name` under Cargo's scratch directory for integration tests, created.
pub fn scratch_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// SymPy's reference values: `tests/peers/fixture.json`, written by
/// `tests/peers/sympy_models.py`.
pub fn sympy_fixture() -> Value {
    let path = format!("{}/tests/peers/fixture.json", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A JSON array of numbers.
pub fn json_numbers(value: &Value) -> Vec<f64> {
    value
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect()
}

/// A JSON array of strings.
pub fn json_strings(value: &Value) -> Vec<&str> {
    value
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect()
}

/// DOPRI5 at `rtol` and `atol` with no cap on the step, sampled every `output_interval` from 0
/// to `t_end`.
pub fn dopri5_options(t_end: f64, output_interval: f64, rtol: f64, atol: f64) -> SimOptions {
    SimOptions {
        t_end,
        output_interval,
        method: Method::Dopri5 {
            rtol,
            atol,
            h_max: f64::INFINITY,
        },
        ..SimOptions::default()
    }
}

/// Simulates `model` from `(q0, u0)` with every input held at its default.
pub fn simulate_at_default_inputs(
    model: &dyn Model,
    q0: &[f64],
    u0: &[f64],
    options: &SimOptions,
) -> Trajectory {
    let signals = mech_runtime::default_signals(model);
    mech_runtime::simulate(model, q0, u0, &signals, options, &mut |_| {}).unwrap()
}

/// Over a run of a model with outputs `ke` and `pe`: the largest kinetic energy reached (the
/// scale: the total energy itself may be near zero), and the largest departure of the total
/// energy from its first sample, relative to that scale.
pub fn energy_drift(model: &dyn Model, run: &Trajectory) -> (f64, f64) {
    let (ke, pe) = (
        model.output_index("ke").unwrap(),
        model.output_index("pe").unwrap(),
    );
    let energy: Vec<f64> = run.outputs.iter().map(|y| y[ke] + y[pe]).collect();
    let scale = run.outputs.iter().map(|y| y[ke]).fold(0.0_f64, f64::max);
    let drift = energy
        .iter()
        .map(|e| (e - energy[0]).abs())
        .fold(0.0_f64, f64::max);
    (scale, drift / scale)
}

/// Times at which `signal` crosses zero upwards, by linear interpolation between samples.
pub fn upward_crossings(times: &[f64], signal: &[f64]) -> Vec<f64> {
    let mut crossings = Vec::new();
    for k in 1..times.len() {
        let (a, b) = (signal[k - 1], signal[k]);
        if a < 0.0 && b >= 0.0 {
            let fraction = -a / (b - a);
            crossings.push(times[k - 1] + fraction * (times[k] - times[k - 1]));
        }
    }
    crossings
}

// The diagnosis experiments on HAMR-VI.

/// A diagnosis experiment on HAMR-VI: `toml` (without its `model` line) written into `dir`
/// as `experiment.toml` and loaded.
pub fn hamr_vi_experiment_in(dir: &Path, toml: &str) -> Experiment {
    let path = dir.join("experiment.toml");
    let model = bundled_path("hamr_vi");
    std::fs::write(&path, format!("model = \"{model}\"\n{toml}")).unwrap();
    experiment::load(&path).unwrap()
}

/// `text` written into `dir` as `measured.csv` and loaded.
pub fn measured_data(dir: &Path, text: &str) -> MeasuredData {
    let path = dir.join("measured.csv");
    std::fs::write(&path, text).unwrap();
    MeasuredData::load(&path).unwrap()
}

/// Sets the parameter `name` of the leg's model.
pub fn set_leg_param(leg: &mut Leg, name: &str, value: f64) {
    let index = leg.model().param_index(name).unwrap();
    leg.session.model.set_param(index, value);
}

/// The foot at rest and under 225 V on each actuator, lift then swing (static equilibria
/// from rest, m).
pub fn feet_at_rest_and_225_volts(leg: &Leg) -> Vec<[f64; 3]> {
    let rest_inputs = leg.inputs(0.0, 0.0);
    let rest = leg.equilibrium(&leg.q0, &rest_inputs, &[]).unwrap().q;
    let mut feet = vec![leg.foot_at(&rest, &rest_inputs)];
    for dof in [Dof::Lift, Dof::Swing] {
        let inputs = leg.drive(dof, 225.0);
        let q = leg.equilibrium(&rest, &inputs, &[]).unwrap().q;
        feet.push(leg.foot_at(&q, &inputs));
    }
    feet
}

/// `leg`'s quasi-static foot positions at 8 points of the paper's 225 V drive (lift
/// 225 sin φ, swing 225 cos φ), each equilibrium started from the last: `(lift, swing, foot)`.
pub fn feet_along_the_drive(leg: &Leg) -> Vec<(f64, f64, [f64; 3])> {
    let mut q = leg.q0.clone();
    (0..8)
        .map(|k| {
            let phase = 2.0 * std::f64::consts::PI * k as f64 / 8.0;
            let (lift, swing) = (225.0 * phase.sin(), 225.0 * phase.cos());
            let inputs = leg.inputs(lift, swing);
            q = leg.equilibrium(&q, &inputs, &[]).unwrap().q;
            (lift, swing, leg.foot_at(&q, &inputs))
        })
        .collect()
}
