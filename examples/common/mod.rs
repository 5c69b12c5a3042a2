//! Helpers shared by the timing examples (each includes this file with `mod common;`).

// Each example uses only some of these.
#![allow(dead_code)]

use std::time::Instant;

use mech::session::ModelSpec;

/// A bundled HAMR leg model (`models/NAME.mech`) with the actuator coordinates, swing and
/// lift, held independent.
pub fn leg_spec(name: &str) -> ModelSpec {
    ModelSpec {
        path: format!("{}/models/{name}.mech", env!("CARGO_MANIFEST_DIR")).into(),
        set: Vec::new(),
        independent: vec!["qsact".into(), "qlact".into()],
    }
}

/// The fastest of `runs` runs of `work`, in seconds, with its last result.
pub fn fastest<T>(runs: usize, mut work: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..runs {
        let t0 = Instant::now();
        last = Some(work());
        best = best.min(t0.elapsed().as_secs_f64());
    }
    (best, last.expect("at least one run"))
}
