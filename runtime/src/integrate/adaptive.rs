//! The shell shared by the adaptive methods ([`Dopri5`], [`Dop853`], [`Rosenbrock`],
//! [`ExpRosenbrock`]).
//!
//! Consumes an [`Ode`], a start `(t0, x0)`, an end time and [`AdaptiveOptions`]; produces an
//! [`AdaptiveStepper`], which implements [`Stepper`] once for all of them. The shell owns
//! what every adaptive method has: the system, the step-size controller ([`StepControl`]:
//! times, step size, Hairer's accept/reject logic, counters), the current point and the end
//! of the trial step, the derivative refresh after [`Stepper::state_mut`], and the checks of
//! interpolation. A method ([`AdaptiveMethod`]) supplies only its stages: a trial step with
//! its error norm, what it keeps of an accepted step, and its continuous extension.

use super::{
    all_finite, begin_interpolation, check_len, check_times, derivative_at, Ode, Stats, Stepper,
    UROUND,
};
use crate::RuntimeError;
// For the documentation's links only.
#[cfg(doc)]
use super::{Dop853, Dopri5, ExpRosenbrock, Rosenbrock};

/// A point of an integration: the state `x(t)` and the derivative `f(t, x)`. At the current
/// point the derivative is the first stage of the next step for every adaptive method.
pub struct Point {
    pub(super) x: Vec<f64>,
    pub(super) f: Vec<f64>,
}

impl Point {
    fn zeros(n: usize) -> Self {
        Point {
            x: vec![0.0; n],
            f: vec![0.0; n],
        }
    }
}

/// A step of size `h` from the current point `(t, now)` to `next`, as the shell hands it to a
/// method: to try ([`AdaptiveMethod::trial`]), then, once accepted, to keep
/// ([`AdaptiveMethod::accept`]).
pub struct Step<'a> {
    /// The options of the error test.
    pub(super) opts: &'a AdaptiveOptions,
    /// The counters, for work beyond the shell's count of evaluations.
    pub(super) stats: &'a mut Stats,
    pub(super) now: &'a Point,
    /// The end of the step: the trial writes its state (and its derivative, where the error
    /// test needs it; otherwise the acceptance does).
    pub(super) next: &'a mut Point,
    pub(super) t: f64,
    pub(super) h: f64,
}

impl<'a> Step<'a> {
    fn new(
        opts: &'a AdaptiveOptions,
        stats: &'a mut Stats,
        now: &'a Point,
        next: &'a mut Point,
        t: f64,
        h: f64,
    ) -> Self {
        Step {
            opts,
            stats,
            now,
            next,
            t,
            h,
        }
    }
}

/// The method-specific part of an adaptive integrator: its working storage and stages.
///
/// The shell calls [`AdaptiveMethod::trial`] until the controller accepts a step, then
/// [`AdaptiveMethod::accept`], and then makes the step's end the current [`Point`].
pub trait AdaptiveMethod {
    /// Order of the propagated solution, for the initial step-size heuristic.
    const ORDER: i32;
    /// Evaluations of the right-hand side in every trial step.
    const EVALUATIONS_PER_TRIAL: usize;

    /// The controller's exponent `1/(p+1) − c·β` for an error estimate of order `p` and the
    /// Lund stabilisation exponent `beta`.
    fn error_exponent(beta: f64) -> f64;

    /// Working storage for a start at `x0`. Every vector is allocated here; stepping never
    /// allocates.
    fn new(x0: &[f64]) -> Self;

    /// The derivative was refreshed at a modified state: drop what depended on the old one.
    fn derivative_refreshed(&mut self) {}

    /// A trial step: computes the new state into `step.next` (kept until
    /// [`AdaptiveMethod::accept`] or the next trial) and returns the scaled error norm, NaN
    /// if anything is non-finite. The shell has counted
    /// [`AdaptiveMethod::EVALUATIONS_PER_TRIAL`]; any other work goes into `step.stats`.
    fn trial<O: Ode>(&mut self, ode: &mut O, step: Step<'_>) -> Result<f64, RuntimeError>;

    /// The last trial step was accepted: completes `step.next` (its derivative, if the trial
    /// did not evaluate it) and keeps what the step's dense output needs. The shell then
    /// makes `step.next` the current point.
    fn accept<O: Ode>(&mut self, ode: &mut O, step: Step<'_>) -> Result<(), RuntimeError>;

    /// Makes the dense output of the last step `[control.t_prev, control.t]` ready, for a
    /// method that computes it on first use.
    fn prepare_dense<O: Ode>(
        &mut self,
        _ode: &mut O,
        _control: &mut StepControl,
    ) -> Result<(), RuntimeError> {
        Ok(())
    }

    /// Writes the solution at `t`, the fraction `theta` in `[0, 1)` of the last step, into
    /// `out` (its length checked), once [`AdaptiveMethod::prepare_dense`] has run.
    fn interpolate(&mut self, t: f64, theta: f64, out: &mut [f64]) -> Result<(), RuntimeError>;
}

/// An adaptive integrator: the shell shared by [`Dopri5`], [`Dop853`], [`Rosenbrock`] and
/// [`ExpRosenbrock`] (type aliases of it), around the method's stages `M`.
pub struct AdaptiveStepper<O: Ode, M> {
    pub(super) ode: O,
    pub(super) control: StepControl,
    pub(super) now: Point,
    /// The end of the trial step.
    next: Point,
    /// The state (or the system) was modified; `now.f` is stale.
    pub(super) dirty: bool,
    pub(super) method: M,
}

impl<O: Ode, M: AdaptiveMethod> AdaptiveStepper<O, M> {
    /// Creates the integrator at `(t0, x0)`, integrating toward `t_end >= t0`, and evaluates
    /// the derivative at `x0` (plus once more for the initial step-size heuristic, unless
    /// `opts.h_init` is given).
    pub fn new(
        mut ode: O,
        t0: f64,
        x0: &[f64],
        t_end: f64,
        opts: AdaptiveOptions,
    ) -> Result<Self, RuntimeError> {
        let expo1 = M::error_exponent(opts.beta);
        let mut control = StepControl::new(opts, expo1, M::EVALUATIONS_PER_TRIAL, t0, t_end)?;
        let f0 = control.start(&mut ode, M::ORDER, x0)?;
        Ok(AdaptiveStepper {
            ode,
            control,
            now: Point {
                x: x0.to_vec(),
                f: f0,
            },
            next: Point::zeros(x0.len()),
            dirty: false,
            method: M::new(x0),
        })
    }

    /// The system being integrated.
    pub fn ode(&self) -> &O {
        &self.ode
    }

    /// Consumes the integrator, returning the system.
    pub fn into_ode(self) -> O {
        self.ode
    }

    /// The options in use.
    pub fn options(&self) -> &AdaptiveOptions {
        &self.control.opts
    }

    /// Step size that the next step will try (before clipping to the end time).
    pub fn next_step_size(&self) -> f64 {
        self.control.h
    }
}

/// The methods whose dense output is computed with the step, so that changing the system
/// afterwards cannot alter it ([`Dop853`] computes its on first use).
pub trait DenseWithStep {}

impl<O: Ode, M: AdaptiveMethod + DenseWithStep> AdaptiveStepper<O, M> {
    /// Mutable access to the system (e.g. to change a parameter). Call [`Stepper::reset`]
    /// afterwards if the change alters the derivative at the current state.
    pub fn ode_mut(&mut self) -> &mut O {
        self.dirty = true;
        &mut self.ode
    }
}

impl<O: Ode, M: AdaptiveMethod> Stepper for AdaptiveStepper<O, M> {
    fn step(&mut self) -> Result<(), RuntimeError> {
        self.reset()?;
        let AdaptiveStepper {
            ode,
            control,
            now,
            next,
            method,
            ..
        } = self;
        let opts = control.opts;
        let accepted = control
            .advance(|stats, t, h| method.trial(ode, Step::new(&opts, stats, now, next, t, h)))?;
        let Some(h) = accepted else {
            return Ok(());
        };
        let t = control.t_prev;
        method.accept(ode, Step::new(&opts, &mut control.stats, now, next, t, h))?;
        std::mem::swap(now, next);
        // Only a method that evaluates the derivative on acceptance (DOP853) can get here
        // with a non-finite one: the others' error test rejects it.
        if !all_finite(&now.f) {
            return Err(RuntimeError::NonFiniteState { t: control.t });
        }
        Ok(())
    }

    fn t(&self) -> f64 {
        self.control.t
    }

    fn t_prev(&self) -> f64 {
        self.control.t_prev
    }

    fn t_end(&self) -> f64 {
        self.control.t_end
    }

    fn state(&self) -> &[f64] {
        &self.now.x
    }

    fn state_mut(&mut self) -> &mut [f64] {
        self.dirty = true;
        &mut self.now.x
    }

    fn reset(&mut self) -> Result<(), RuntimeError> {
        if !self.dirty {
            return Ok(());
        }
        self.control.stats.rhs_evaluations += 1;
        let now = &mut self.now;
        derivative_at(&mut self.ode, self.control.t, &now.x, &mut now.f)?;
        self.method.derivative_refreshed();
        self.dirty = false;
        Ok(())
    }

    fn interpolate(&mut self, t: f64, out: &mut [f64]) -> Result<(), RuntimeError> {
        let (t_prev, t_cur) = (self.control.t_prev, self.control.t);
        let Some(theta) = begin_interpolation(t, t_prev, t_cur, &self.now.x, out)? else {
            return Ok(());
        };
        self.method
            .prepare_dense(&mut self.ode, &mut self.control)?;
        self.method.interpolate(t, theta, out)
    }

    fn set_t_end(&mut self, t_end: f64) -> Result<(), RuntimeError> {
        self.control.set_t_end(t_end)
    }

    fn stats(&self) -> Stats {
        self.control.stats
    }
}

/// The error test's norm of a trial step from `x` to `x_new`, whose derivative there is
/// `f_new`: `sqrt(mean_i((error(i) / sk_i)²))` with `sk_i = atol + rtol·max(|x_i|, |x_new_i|)`
/// for the local error estimate `error(i)`; NaN (a rejection) if `x_new` or `f_new` is not
/// finite.
pub(super) fn error_norm(
    opts: &AdaptiveOptions,
    x: &[f64],
    x_new: &[f64],
    f_new: &[f64],
    error: impl Fn(usize) -> f64,
) -> f64 {
    let mut sum = 0.0;
    let mut finite = true;
    for (i, ((x, x_new), f_new)) in x.iter().zip(x_new).zip(f_new).enumerate() {
        let sk = opts.atol + opts.rtol * x.abs().max(x_new.abs());
        sum += (error(i) / sk).powi(2);
        finite &= x_new.is_finite() && f_new.is_finite();
    }
    let norm = (sum / x.len().max(1) as f64).sqrt();
    if finite {
        norm
    } else {
        f64::NAN
    }
}

/// Options of the adaptive methods [`Dopri5`], [`Dop853`], [`Rosenbrock`] and
/// [`ExpRosenbrock`]. [`Default`] gives those of Hairer's `DOPRI5`, [`AdaptiveOptions::dop853`]
/// those of `DOP853` and [`AdaptiveOptions::rosenbrock`] those of `RODAS`, except the
/// tolerances.
///
/// A step is accepted when its scaled error norm is at most 1: for [`Dopri5`]
/// `sqrt(mean_i((err_i / sk_i)²))` with `sk_i = atol + rtol·max(|x_i|, |x_new_i|)` and `err` the
/// difference between the 5th- and 4th-order solutions; [`Dop853`] combines the 5th- and
/// 3rd-order estimates (see there).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveOptions {
    /// Relative tolerance (≥ 0). Default `1e-8`.
    pub rtol: f64,
    /// Absolute tolerance (> 0), in the units of the state. Default `1e-10`.
    pub atol: f64,
    /// First step size to try; `None` (default) uses Hairer's heuristic (`HINIT`).
    pub h_init: Option<f64>,
    /// Smallest step allowed (≥ 0); a smaller proposed step is a
    /// [`RuntimeError::StepSizeUnderflow`]. Default `0`: only the roundoff limit
    /// `h <= 10·2.3e-16·|t|` applies.
    pub h_min: f64,
    /// Largest step allowed (> 0, may be infinite). Default `f64::INFINITY`. Bound it when
    /// inputs contain short events that a long step could step over.
    pub h_max: f64,
    /// Budget of steps (accepted + rejected) per integrator. Default `1_000_000`.
    pub max_steps: usize,
    /// Safety factor of the step-size controller, in (1e-4, 1). Default `0.9`.
    pub safety: f64,
    /// Smallest ratio of a new step to the previous one, in (0, 1]. Default `0.2` (`DOP853`:
    /// 0.333).
    pub fac_min: f64,
    /// Largest ratio of a new step to the previous one, ≥ 1. Default `10` (`DOP853`: 6).
    pub fac_max: f64,
    /// Lund stabilisation (PI control) exponent, in [0, 0.2]; `0` gives the standard
    /// controller. Default `0.04` (`DOP853`: 0).
    pub beta: f64,
}

impl Default for AdaptiveOptions {
    fn default() -> Self {
        AdaptiveOptions {
            rtol: 1e-8,
            atol: 1e-10,
            h_init: None,
            h_min: 0.0,
            h_max: f64::INFINITY,
            max_steps: 1_000_000,
            safety: 0.9,
            fac_min: 0.2,
            fac_max: 10.0,
            beta: 0.04,
        }
    }
}

impl AdaptiveOptions {
    /// Hairer's `DOP853` defaults: safety 0.9, step ratio in [0.333, 6], no Lund
    /// stabilisation (`beta = 0`); tolerances as [`Default`].
    pub fn dop853() -> Self {
        AdaptiveOptions {
            fac_min: 0.333,
            fac_max: 6.0,
            beta: 0.0,
            ..AdaptiveOptions::default()
        }
    }

    /// Hairer's `RODAS` step-size settings: safety 0.9, step ratio in [0.2, 6], no Lund
    /// stabilisation; tolerances as [`Default`].
    pub fn rosenbrock() -> Self {
        AdaptiveOptions {
            fac_min: 0.2,
            fac_max: 6.0,
            beta: 0.0,
            ..AdaptiveOptions::default()
        }
    }

    /// These options with `rtol` and `atol` replaced.
    pub fn with_tolerances(self, rtol: f64, atol: f64) -> Self {
        AdaptiveOptions { rtol, atol, ..self }
    }

    /// Checks every option against its documented range.
    pub fn validate(&self) -> Result<(), RuntimeError> {
        let bad = |msg: String| Err(RuntimeError::InvalidOptions(msg));
        if !(self.rtol >= 0.0 && self.rtol.is_finite()) {
            return bad(format!("rtol must be finite and >= 0 (got {})", self.rtol));
        }
        if !(self.atol > 0.0 && self.atol.is_finite()) {
            return bad(format!("atol must be finite and > 0 (got {})", self.atol));
        }
        if let Some(h) = self.h_init {
            if !(h > 0.0 && h.is_finite()) {
                return bad(format!("h_init must be finite and > 0 (got {h})"));
            }
        }
        if !(self.h_min >= 0.0 && self.h_min.is_finite()) {
            return bad(format!(
                "h_min must be finite and >= 0 (got {})",
                self.h_min
            ));
        }
        if !(self.h_max > 0.0 && self.h_max >= self.h_min) {
            return bad(format!(
                "h_max must be > 0 and >= h_min (got {})",
                self.h_max
            ));
        }
        if !(self.safety > 1e-4 && self.safety < 1.0) {
            return bad(format!("safety must be in (1e-4, 1) (got {})", self.safety));
        }
        if !(self.fac_min > 0.0 && self.fac_min <= 1.0) {
            return bad(format!("fac_min must be in (0, 1] (got {})", self.fac_min));
        }
        if !(self.fac_max >= 1.0 && self.fac_max.is_finite()) {
            return bad(format!(
                "fac_max must be finite and >= 1 (got {})",
                self.fac_max
            ));
        }
        if !(0.0..=0.2).contains(&self.beta) {
            return bad(format!("beta must be in [0, 0.2] (got {})", self.beta));
        }
        Ok(())
    }
}

/// The state of an adaptive integration shared by the adaptive methods: time, step size,
/// Hairer's step-size controller (`FAC11 = err^expo1`, Lund stabilisation `/facold^beta`,
/// `fac_min ≤ h_new/h ≤ fac_max`, no growth right after a rejection) and the counters.
#[derive(Debug, Clone)]
pub struct StepControl {
    opts: AdaptiveOptions,
    /// `1/(p+1) − β·c`, the controller's exponent for a method whose error estimate is of
    /// order `p` (`DOPRI5`: `0.2 − 0.75β`; `DOP853`: `1/8 − 0.2β`).
    expo1: f64,
    /// Right-hand side evaluations per trial step.
    evaluations_per_trial: usize,
    pub(super) t: f64,
    pub(super) t_prev: f64,
    t_end: f64,
    /// Step size to try next.
    h: f64,
    fac_old: f64,
    /// The previous attempt was rejected.
    reject: bool,
    pub(super) stats: Stats,
}

impl StepControl {
    fn new(
        opts: AdaptiveOptions,
        expo1: f64,
        evaluations_per_trial: usize,
        t0: f64,
        t_end: f64,
    ) -> Result<Self, RuntimeError> {
        opts.validate()?;
        check_times(t0, t_end)?;
        Ok(StepControl {
            opts,
            expo1,
            evaluations_per_trial,
            t: t0,
            t_prev: t0,
            t_end,
            h: 0.0,
            fac_old: 1e-4,
            reject: false,
            stats: Stats {
                rhs_evaluations: 1,
                ..Stats::default()
            },
        })
    }

    /// The start shared by the adaptive methods: checks `x0`, evaluates `f(t0, x0)` (returned)
    /// and picks the first step, `opts.h_init` or Hairer's `HINIT` for a method of `order`.
    fn start<O: Ode>(
        &mut self,
        ode: &mut O,
        order: i32,
        x0: &[f64],
    ) -> Result<Vec<f64>, RuntimeError> {
        let n = ode.dim();
        check_len("x0", n, x0.len())?;
        let mut f0 = vec![0.0; n];
        derivative_at(ode, self.t, x0, &mut f0)?;
        let opts = self.opts;
        self.h = match opts.h_init {
            Some(h) => h.min(opts.h_max),
            None if self.t_end > self.t => {
                self.stats.rhs_evaluations += 1;
                initial_step(ode, &opts, order, self.t, x0, &f0)?
            }
            None => 0.0,
        };
        Ok(f0)
    }

    /// Tries steps from `t` until one passes the error test. `trial(stats, t, h)` computes a
    /// step of size `h` (counting any work beyond `evaluations_per_trial` in `stats`) and
    /// returns its scaled error norm (NaN if anything was non-finite; such a trial
    /// is rejected and the step shrunk by `fac_min`). On success `t`, `t_prev` and the next
    /// step size are updated and the accepted `h` is returned; the caller then takes the new
    /// state. Does nothing (returns `None`) once `t_end` is reached.
    fn advance(
        &mut self,
        mut trial: impl FnMut(&mut Stats, f64, f64) -> Result<f64, RuntimeError>,
    ) -> Result<Option<f64>, RuntimeError> {
        if self.t >= self.t_end {
            return Ok(None);
        }
        let o = self.opts;
        let mut nonfinite = false;
        loop {
            let steps = self.stats.accepted_steps + self.stats.rejected_steps;
            if steps >= o.max_steps {
                return Err(RuntimeError::TooManySteps { t: self.t, steps });
            }
            let mut h = self.h;
            if h < o.h_min || 0.1 * h <= self.t.abs() * UROUND || h <= 0.0 {
                return Err(if nonfinite {
                    RuntimeError::NonFiniteState { t: self.t }
                } else {
                    RuntimeError::StepSizeUnderflow { t: self.t, h }
                });
            }
            // The step that would reach within 1% of the end is stretched to land on it.
            let last = self.t + 1.01 * h - self.t_end > 0.0;
            if last {
                h = self.t_end - self.t;
            }
            self.stats.rhs_evaluations += self.evaluations_per_trial;
            let err = trial(&mut self.stats, self.t, h)?;
            if !err.is_finite() {
                nonfinite = true;
                self.reject = true;
                self.stats.rejected_steps += 1;
                self.h = h * o.fac_min;
                continue;
            }
            let fac11 = err.powf(self.expo1);
            let fac = fac11 / self.fac_old.powf(o.beta);
            // The new step is h/fac, with fac_min <= 1/fac <= fac_max.
            let fac = (1.0 / o.fac_max).max((1.0 / o.fac_min).min(fac / o.safety));
            let mut h_new = h / fac;
            if err <= 1.0 {
                self.fac_old = err.max(1e-4);
                self.stats.accepted_steps += 1;
                self.t_prev = self.t;
                self.t = if last { self.t_end } else { self.t + h };
                h_new = h_new.min(o.h_max);
                if self.reject {
                    h_new = h_new.min(h);
                }
                self.reject = false;
                self.h = h_new;
                return Ok(Some(h));
            }
            self.h = h / (1.0 / o.fac_min).min(fac11 / o.safety);
            self.reject = true;
            self.stats.rejected_steps += 1;
        }
    }

    fn set_t_end(&mut self, t_end: f64) -> Result<(), RuntimeError> {
        check_times(self.t, t_end)?;
        self.t_end = t_end;
        Ok(())
    }
}

/// Hairer's starting step-size heuristic (`HINIT`; Hairer, Nørsett & Wanner, *Solving
/// Ordinary Differential Equations I*, §II.4) for a method of order `order`, with
/// root-mean-square norms: `h` such that `h^order · max(‖f0‖, ‖f'‖) = 0.01`, from one explicit
/// Euler step (one evaluation of `ode`).
fn initial_step<O: Ode>(
    ode: &mut O,
    opts: &AdaptiveOptions,
    order: i32,
    t: f64,
    x: &[f64],
    f0: &[f64],
) -> Result<f64, RuntimeError> {
    let (mut x1, mut f1) = (vec![0.0; x.len()], vec![0.0; x.len()]);
    let n = x.len().max(1) as f64;
    let (rtol, atol, h_max) = (opts.rtol, opts.atol, opts.h_max);
    let (mut dnf, mut dny) = (0.0, 0.0);
    for (x, f) in x.iter().zip(f0) {
        let sk = atol + rtol * x.abs();
        dnf += (f / sk).powi(2);
        dny += (x / sk).powi(2);
    }
    let (dnf, dny) = (dnf / n, dny / n);
    let mut h = if dnf <= 1e-10 || dny <= 1e-10 {
        1e-6
    } else {
        (dny / dnf).sqrt() * 0.01
    };
    h = h.min(h_max);
    // One explicit Euler step, to estimate the second derivative.
    for ((xs, x), f) in x1.iter_mut().zip(x).zip(f0) {
        *xs = x + h * f;
    }
    ode.rhs(t + h, &x1, &mut f1)?;
    let mut der2 = 0.0;
    for ((x, f0), f1) in x.iter().zip(f0).zip(f1.iter()) {
        let sk = atol + rtol * x.abs();
        der2 += ((f1 - f0) / sk).powi(2);
    }
    let der2 = (der2 / n).sqrt() / h;
    // `f64::max` ignores a NaN operand, so a non-finite trial derivative falls back on dnf.
    let der12 = der2.abs().max(dnf.sqrt());
    let h1 = if der12 <= 1e-15 {
        (h * 1e-3).max(1e-6)
    } else {
        (0.01 / der12).powf(1.0 / f64::from(order))
    };
    let h = (100.0 * h).min(h1).min(h_max);
    Ok(if h.is_finite() && h > 0.0 { h } else { 1e-6 })
}
