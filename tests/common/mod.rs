//! Helpers shared by the integration tests.

#![allow(dead_code)]

use mech::tape_model::TapeModel;
use mech_codegen::Compiled;
use mech_runtime::Model;

/// Compiles a bundled model from `models/`.
pub fn compile_bundled(name: &str) -> Compiled {
    let path = format!("{}/models/{name}.mech", env!("CARGO_MANIFEST_DIR"));
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

/// `M` as a dense row-major `Vec<Vec<f64>>` (the trait writes column-major).
pub fn mass_matrix(model: &dyn Model, q: &[f64]) -> Vec<Vec<f64>> {
    let n = model.nu();
    let mut m = vec![0.0; n * n];
    let inputs: Vec<f64> = (0..model.ninputs())
        .map(|i| model.input_default(i))
        .collect();
    model.mass_matrix(0.0, q, &inputs, &mut m);
    (0..n)
        .map(|r| (0..n).map(|c| m[r + n * c]).collect())
        .collect()
}

pub fn forcing(model: &dyn Model, q: &[f64], u: &[f64]) -> Vec<f64> {
    let mut f = vec![0.0; model.nu()];
    let inputs: Vec<f64> = (0..model.ninputs())
        .map(|i| model.input_default(i))
        .collect();
    model.forcing(0.0, q, u, &inputs, &mut f);
    f
}

pub fn outputs(model: &dyn Model, q: &[f64], u: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; model.noutputs()];
    let inputs: Vec<f64> = (0..model.ninputs())
        .map(|i| model.input_default(i))
        .collect();
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
    /// Uniform in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        lo + (hi - lo) * (z >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in `0..n` (`n > 0`).
    pub fn index(&mut self, n: usize) -> usize {
        (self.uniform(0.0, n as f64) as usize).min(n - 1)
    }
    pub fn vector(&mut self, n: usize, lo: f64, hi: f64) -> Vec<f64> {
        (0..n).map(|_| self.uniform(lo, hi)).collect()
    }
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
