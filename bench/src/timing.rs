//! Timing: medians over batches of a tight loop (evaluation) and over repeated one-shot runs
//! (derivation). Medians, because the machine is shared and noise is one-sided.

use std::hint::black_box;
use std::time::{Duration, Instant};

/// Summary of repeated measurements, in the unit of the caller (ns per call or seconds).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    pub median: f64,
    pub min: f64,
    pub max: f64,
    /// Number of measurements (batches or runs).
    pub samples: usize,
    /// Calls per batch (1 for one-shot runs).
    pub calls_per_sample: u64,
}

impl Summary {
    pub fn of(mut values: Vec<f64>, calls_per_sample: u64) -> Summary {
        assert!(!values.is_empty());
        values.sort_by(f64::total_cmp);
        let n = values.len();
        let median = if n % 2 == 1 {
            values[n / 2]
        } else {
            0.5 * (values[n / 2 - 1] + values[n / 2])
        };
        Summary {
            median,
            min: values[0],
            max: values[n - 1],
            samples: n,
            calls_per_sample,
        }
    }
}

/// Nanoseconds per call of `f`: warm up, pick a batch size so that one batch takes about
/// `batch_time`, then time `batches` batches. `f` should `black_box` its inputs and result.
pub fn per_call_ns(f: impl FnMut(), batches: usize, batch_time: Duration) -> Summary {
    per_call_by(f, batches, batch_time, || {
        let start = Instant::now();
        move || start.elapsed().as_secs_f64() * 1e9
    })
}

/// The CPU time of the calling thread in ns (`/proc/thread-self/schedstat`, its first field),
/// or `None` where that file cannot be read.
pub fn thread_cpu_ns() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

/// As [`per_call_ns`], in the CPU time of this thread: what the calls cost on a shared
/// machine, without the time other processes hold the core. `None` without
/// [`thread_cpu_ns`].
pub fn per_call_cpu_ns(f: impl FnMut(), batches: usize, batch_time: Duration) -> Option<Summary> {
    thread_cpu_ns()?;
    Some(per_call_by(f, batches, batch_time, || {
        let start = thread_cpu_ns().unwrap_or(f64::NAN);
        move || thread_cpu_ns().unwrap_or(f64::NAN) - start
    }))
}

/// [`per_call_ns`] with its clock: `start()` returns a function giving the ns elapsed since.
fn per_call_by<S, E>(mut f: impl FnMut(), batches: usize, batch_time: Duration, start: S) -> Summary
where
    S: Fn() -> E,
    E: Fn() -> f64,
{
    // Warm-up and calibration: double the count until a batch takes a tenth of the target.
    let mut calls: u64 = 1;
    loop {
        let start = Instant::now();
        for _ in 0..calls {
            f();
        }
        let elapsed = start.elapsed();
        if elapsed >= batch_time / 10 || calls >= 1 << 40 {
            let per_call = elapsed.as_secs_f64() / calls as f64;
            calls = ((batch_time.as_secs_f64() / per_call.max(1e-12)) as u64).max(1);
            break;
        }
        calls *= 2;
    }
    let values = (0..batches)
        .map(|_| {
            let elapsed = start();
            for _ in 0..calls {
                f();
            }
            elapsed() / calls as f64
        })
        .collect();
    Summary::of(values, calls)
}

/// Seconds per run of `f` (each run a fresh computation): at least `min_runs`, then more
/// until `budget` is spent, at most `max_runs`. Returns the summary and the last result.
pub fn per_run_s<T>(
    mut f: impl FnMut() -> T,
    min_runs: usize,
    max_runs: usize,
    budget: Duration,
) -> (Summary, T) {
    let started = Instant::now();
    let mut values = Vec::new();
    loop {
        let start = Instant::now();
        let result = black_box(f());
        values.push(start.elapsed().as_secs_f64());
        let done =
            values.len() >= max_runs || (values.len() >= min_runs && started.elapsed() >= budget);
        if done {
            return (Summary::of(values, 1), result);
        }
        drop(result);
    }
}

/// A JSON number (`null` when not finite).
pub fn num(x: f64) -> String {
    if x.is_finite() {
        format!("{x:e}")
    } else {
        "null".to_string()
    }
}

/// A JSON array of numbers ([`num`] each).
pub fn list_json(values: &[f64]) -> String {
    format!(
        "[{}]",
        values.iter().map(|&x| num(x)).collect::<Vec<_>>().join(",")
    )
}

/// A [`Summary`] as a JSON object.
pub fn summary_json(s: &Summary) -> String {
    format!(
        "{{\"median\":{},\"min\":{},\"max\":{},\"samples\":{},\"calls_per_sample\":{}}}",
        num(s.median),
        num(s.min),
        num(s.max),
        s.samples,
        s.calls_per_sample
    )
}
