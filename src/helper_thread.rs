//! A second thread that evaluates one program beside the caller's, for evaluations too short
//! (tens of microseconds) to hand to a thread pool.
//!
//! Consumes: a closure evaluating a program at an [`Env`] (it owns its program and scratch).
//! Produces: [`HelperThread::eval_beside`], which starts that evaluation on the helper,
//! runs the caller's own work meanwhile, waits and copies the helper's values out.
//!
//! Why hand-written: [`crate::parallel`] starts threads per batch of jobs, and a pool's idle
//! worker (rayon's) goes to sleep in the kernel between jobs, to be woken by a system call
//! whose latency is of the order of the work itself (~10 µs). Here the helper spins on an
//! atomic request counter while requests come (an integration asks every ~20 µs) and parks
//! only after `SPIN` of silence; the caller unparks it with each request (an atomic
//! operation when it is not parked). The arguments and values pass through a mutex that the
//! two sides take in turn, never at the same time, so it costs an uncontended lock.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use mech_codegen::back::tape::Env;

/// How long the helper spins without a request before it parks.
const SPIN: Duration = Duration::from_micros(200);
/// Spins between readings of the clock (a reading costs as much as tens of spins).
const SPINS_PER_READING: u32 = 64;
/// How long the caller spins for the helper's values before it also yields its core (the
/// helper was descheduled: a loaded machine).
const PATIENCE: Duration = Duration::from_micros(100);

/// What the helper evaluates: a program at an environment, into `out`.
pub type Evaluation = Box<dyn FnMut(&Env, &mut [f64]) + Send>;

/// The arguments of one request (copies of the caller's slices) and the helper's values.
#[derive(Default)]
struct Job {
    t: f64,
    q: Vec<f64>,
    u: Vec<f64>,
    params: Vec<f64>,
    inputs: Vec<f64>,
    out: Vec<f64>,
}

struct Shared {
    /// The number of the last request the caller made, and of the last the helper finished.
    requested: AtomicU64,
    finished: AtomicU64,
    /// The helper's evaluation panicked (a bug): the caller panics too rather than wait.
    failed: AtomicBool,
    stop: AtomicBool,
    job: Mutex<Job>,
}

/// A helper thread with its evaluation; stopped and joined on drop.
pub struct HelperThread {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    requests: u64,
}

impl std::fmt::Debug for HelperThread {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HelperThread")
            .field("requests", &self.requests)
            .finish()
    }
}

impl HelperThread {
    /// Starts a helper that evaluates `evaluation` into `outputs` values; `None` where the
    /// system refuses a thread.
    pub fn spawn(mut evaluation: Evaluation, outputs: usize) -> Option<HelperThread> {
        let shared = Arc::new(Shared {
            requested: AtomicU64::new(0),
            finished: AtomicU64::new(0),
            failed: AtomicBool::new(false),
            stop: AtomicBool::new(false),
            job: Mutex::new(Job {
                out: vec![0.0; outputs],
                ..Job::default()
            }),
        });
        let theirs = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("mech-helper".into())
            .spawn(move || serve(&theirs, &mut evaluation))
            .ok()?;
        Some(HelperThread {
            shared,
            thread: Some(thread),
            requests: 0,
        })
    }

    /// Evaluates the helper's program at `env` into `out` while `here` runs on this thread;
    /// returns `here`'s result once both are done.
    pub fn eval_beside<R>(&mut self, env: &Env, out: &mut [f64], here: impl FnOnce() -> R) -> R {
        {
            let mut guard = lock(&self.shared.job);
            let job = &mut *guard;
            job.t = env.t;
            for (copy, slice) in [
                (&mut job.q, env.q),
                (&mut job.u, env.u),
                (&mut job.params, env.params),
                (&mut job.inputs, env.inputs),
            ] {
                copy.clear();
                copy.extend_from_slice(slice);
            }
        }
        self.requests += 1;
        self.shared
            .requested
            .store(self.requests, Ordering::Release);
        if let Some(thread) = &self.thread {
            thread.thread().unpark();
        }
        let result = here();
        // The clock is read only once the wait is longer than a few spins (mostly it is not).
        let mut waiting: Option<Instant> = None;
        let mut spins = 0;
        while self.shared.finished.load(Ordering::Acquire) != self.requests {
            if self.shared.failed.load(Ordering::Acquire) {
                panic!("the helper thread's evaluation panicked");
            }
            spins += 1;
            if spins % SPINS_PER_READING != 0
                || waiting.get_or_insert_with(Instant::now).elapsed() < PATIENCE
            {
                std::hint::spin_loop();
            } else {
                std::thread::yield_now();
            }
        }
        let job = lock(&self.shared.job);
        let n = out.len().min(job.out.len());
        out[..n].copy_from_slice(&job.out[..n]);
        result
    }
}

impl Drop for HelperThread {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Release);
        if let Some(thread) = self.thread.take() {
            thread.thread().unpark();
            let _ = thread.join();
        }
    }
}

/// The mutex's contents even if a panic poisoned it (the values are overwritten by each
/// request; a panic is reported through `failed`).
fn lock(job: &Mutex<Job>) -> std::sync::MutexGuard<'_, Job> {
    job.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The helper's loop: wait for a request (spinning, then parked), evaluate, report.
fn serve(shared: &Shared, evaluation: &mut Evaluation) {
    let mut served = 0;
    loop {
        let idle = Instant::now();
        let mut spins = 0;
        let request = loop {
            if shared.stop.load(Ordering::Acquire) {
                return;
            }
            let request = shared.requested.load(Ordering::Acquire);
            if request != served {
                break request;
            }
            spins += 1;
            if spins % SPINS_PER_READING != 0 || idle.elapsed() < SPIN {
                std::hint::spin_loop();
            } else {
                std::thread::park();
            }
        };
        let outcome = {
            let mut job = lock(&shared.job);
            let Job {
                t,
                q,
                u,
                params,
                inputs,
                out,
            } = &mut *job;
            let env = Env {
                t: *t,
                q,
                u,
                params,
                inputs,
            };
            catch_unwind(AssertUnwindSafe(|| evaluation(&env, out)))
        };
        if outcome.is_err() {
            shared.failed.store(true, Ordering::Release);
            return;
        }
        served = request;
        shared.finished.store(request, Ordering::Release);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The helper's values are those of its evaluation at the caller's environment, request
    /// after request, with the caller's own work done meanwhile.
    #[test]
    fn evaluates_beside_the_caller() {
        let mut helper = HelperThread::spawn(
            Box::new(|env: &Env, out: &mut [f64]| {
                out[0] = env.t + env.q.iter().sum::<f64>();
                out[1] = env.u.iter().product::<f64>() * env.params[0] - env.inputs[0];
            }),
            2,
        )
        .expect("a thread");
        for k in 0..1000 {
            let x = k as f64;
            let (q, u, params, inputs) = ([x, 1.0], [2.0, x], [3.0], [x * x]);
            let env = Env {
                t: 0.5,
                q: &q,
                u: &u,
                params: &params,
                inputs: &inputs,
            };
            let mut out = [0.0; 2];
            let here = helper.eval_beside(&env, &mut out, || 2.0 * x);
            assert_eq!(here, 2.0 * x);
            assert_eq!(out, [0.5 + x + 1.0, 2.0 * x * 3.0 - x * x]);
            if k % 250 == 0 {
                // Long enough for the helper to park: it must wake for the next request.
                std::thread::sleep(Duration::from_millis(2));
            }
        }
    }

    #[test]
    fn a_panicking_evaluation_is_reported_not_awaited() {
        let mut helper = HelperThread::spawn(Box::new(|_: &Env, _: &mut [f64]| panic!("a bug")), 1)
            .expect("a thread");
        let env = Env {
            t: 0.0,
            q: &[],
            u: &[],
            params: &[],
            inputs: &[],
        };
        let outcome = catch_unwind(AssertUnwindSafe(|| {
            helper.eval_beside(&env, &mut [0.0], || ())
        }));
        assert!(outcome.is_err());
    }
}
