//! Runge–Kutta and Rosenbrock integrators with a step-by-step API and dense output.
//!
//! * [`Dopri5`]: adaptive Dormand–Prince 5(4), a transcription of Hairer's `DOPRI5` (same
//!   coefficients, FSAL, Lund-stabilised PI step-size control, initial step-size heuristic,
//!   and Shampine's 4th-order continuous extension), with the same defaults. On the Arenstorf
//!   orbit it takes exactly the steps the Fortran code takes.
//! * [`Dop853`]: adaptive Dormand–Prince 8(5,3), a transcription of Hairer's `DOP853` (12
//!   stages, FSAL, the combined 5th/3rd-order error estimate, and the 7th-order continuous
//!   extension, computed only for steps that are interpolated). On van der Pol's equation it
//!   takes exactly the steps the Fortran code takes. Fewer evaluations than [`Dopri5`] at
//!   tight tolerances (≲ 1e-7).
//! * [`Rk4`]: classical fixed-step Runge–Kutta of order 4, with cubic Hermite dense output.
//! * [`Rosenbrock`]: adaptive linearly implicit Rosenbrock 2(3) (Shampine & Reichelt's
//!   `ode23s`), L-stable, for stiff systems: its step follows the accuracy of the slow motion,
//!   not the stability limit of the fast modes. Finite-difference Jacobian, an `n × n` LU per
//!   step.
//! * [`ExpRosenbrock`]: adaptive exponential Rosenbrock 4(3) (`exprb43` of Hochbruck,
//!   Ostermann & Schweitzer): integrates the linearization of each step exactly (matrix
//!   φ-functions), so lightly damped fast modes are followed at steps far longer than their
//!   period. For small systems.
//!
//! All own their [`Ode`] and implement [`Stepper`]: `step()` advances by one accepted step
//! toward the end time, `interpolate()` evaluates the solution inside the last step, and
//! `state_mut()` lets the caller change the state between steps (e.g. to project it back onto
//! constraints; the derivative at the modified state is recomputed before the next step).
//! All working storage is allocated when the integrator is created; stepping never allocates.
//! The adaptive methods share the step-size controller and the initial step heuristic, the
//! implicit ones the finite-difference Jacobian.
//!
//! Integration runs forward in time only (`t_end >= t0`).
//!
//! ```
//! use mech_runtime::integrate::{AdaptiveOptions, Dopri5, Ode, Stepper};
//! use mech_runtime::RuntimeError;
//!
//! /// y' = -y
//! struct Decay;
//! impl Ode for Decay {
//!     fn dim(&self) -> usize { 1 }
//!     fn rhs(&mut self, _t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), RuntimeError> {
//!         dxdt[0] = -x[0];
//!         Ok(())
//!     }
//! }
//!
//! let opts = AdaptiveOptions { rtol: 1e-10, atol: 1e-12, ..Default::default() };
//! let mut solver = Dopri5::new(Decay, 0.0, &[1.0], 2.0, opts)?;
//! while !solver.is_finished() {
//!     solver.step()?;
//! }
//! assert!((solver.state()[0] - (-2.0f64).exp()).abs() < 1e-10);
//! # Ok::<(), RuntimeError>(())
//! ```

mod dop853;
mod dopri5;
mod exp_rosenbrock;
mod phi;
mod rk4;
mod rosenbrock;

pub use dop853::Dop853;
pub use dopri5::Dopri5;
pub use exp_rosenbrock::ExpRosenbrock;
pub use rk4::Rk4;
pub use rosenbrock::Rosenbrock;

use crate::RuntimeError;

/// A first-order system `ẋ = f(t, x)`.
///
/// `rhs` may keep scratch storage in `self` (hence `&mut self`). It should write a NaN into
/// `dxdt` rather than fail when the state is merely outside the region where `f` is finite: the
/// adaptive integrator then retries with a smaller step. Errors it returns (e.g.
/// [`RuntimeError::SingularMassMatrix`]) stop the integration at once.
pub trait Ode {
    /// Dimension of `x`.
    fn dim(&self) -> usize;
    /// Writes `f(t, x)` into `dxdt` (both of length [`Ode::dim`]).
    fn rhs(&mut self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), RuntimeError>;
}

impl<O: Ode + ?Sized> Ode for &mut O {
    fn dim(&self) -> usize {
        (**self).dim()
    }
    fn rhs(&mut self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), RuntimeError> {
        (**self).rhs(t, x, dxdt)
    }
}

/// Work counters of an integrator.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Accepted steps.
    pub accepted_steps: usize,
    /// Rejected steps: error test failures, and trial steps that produced non-finite values
    /// (always 0 for fixed-step methods).
    pub rejected_steps: usize,
    /// Evaluations of [`Ode::rhs`], including those of the initial step-size heuristic and of
    /// derivative refreshes after [`Stepper::state_mut`], and those of Jacobians.
    pub rhs_evaluations: usize,
    /// Jacobians evaluated (by finite differences; [`Rosenbrock`] and [`ExpRosenbrock`]).
    pub jacobian_evaluations: usize,
}

/// The step-by-step interface shared by the integrators.
///
/// The state is `x(t)`; the *last step* is the interval `[t_prev(), t()]` covered by the most
/// recent call to [`Stepper::step`] (of zero length before the first step).
pub trait Stepper {
    /// Advances by one accepted step, never past [`Stepper::t_end`]; does nothing once
    /// [`Stepper::is_finished`]. On error the state stays at the last accepted step.
    fn step(&mut self) -> Result<(), RuntimeError>;
    /// Current time.
    fn t(&self) -> f64;
    /// Start of the last step.
    fn t_prev(&self) -> f64;
    /// Time at which integration stops.
    fn t_end(&self) -> f64;
    /// Whether the end time has been reached.
    fn is_finished(&self) -> bool {
        self.t() >= self.t_end()
    }
    /// Current state `x(t)`.
    fn state(&self) -> &[f64];
    /// Mutable access to the current state, to modify it between steps (e.g. projection onto
    /// constraints, or a discrete event). The derivative at the modified state is recomputed
    /// before the next step (or by [`Stepper::reset`]). Dense output of the last step keeps
    /// describing the step as it was computed, except that `interpolate(t())` returns the
    /// modified state.
    fn state_mut(&mut self) -> &mut [f64];
    /// Recomputes the derivative at the current state now (instead of at the next step), so
    /// that errors from the right-hand side surface here. Cheap no-op if the state was not
    /// modified.
    fn reset(&mut self) -> Result<(), RuntimeError>;
    /// Writes the solution at time `t` into `out` (length [`Ode::dim`]), for `t` within the last
    /// step `[t_prev(), t()]` (a relative slack of about 1e-12 of the step is allowed).
    /// `&mut` because a method may compute its continuous extension on first use.
    fn interpolate(&mut self, t: f64, out: &mut [f64]) -> Result<(), RuntimeError>;
    /// Moves the end time to `t_end >= t()`, e.g. to continue an integration.
    fn set_t_end(&mut self, t_end: f64) -> Result<(), RuntimeError>;
    /// Work counters so far.
    fn stats(&self) -> Stats;
}

/// `f(t, x)` into `f`, for a state and a derivative that must both be finite (the start of an
/// integration, or the state after [`Stepper::state_mut`]).
fn derivative_at<O: Ode + ?Sized>(
    ode: &mut O,
    t: f64,
    x: &[f64],
    f: &mut [f64],
) -> Result<(), RuntimeError> {
    if !all_finite(x) {
        return Err(RuntimeError::NonFiniteState { t });
    }
    ode.rhs(t, x, f)?;
    if all_finite(f) {
        Ok(())
    } else {
        Err(RuntimeError::NonFiniteState { t })
    }
}

/// `J = ∂f/∂x` (`n × n`, column-major) and `∂f/∂t` at `(t, x)` by forward differences from
/// `f0 = f(t, x)`, with Hairer's increments `√(UROUND·max(1e-5, |x_j|))` (as in `RODAS`);
/// `n + 1` evaluations. `x_scratch` and `f_scratch` are working vectors of length `n`.
///
/// The time column comes first, then the state columns from the last to the first: a system
/// whose state is `[positions; rates]` and which keeps work that depends on the positions
/// only (the loops closed by [`Reduced`](crate::Reduced)) evaluates every column that leaves
/// the positions at `x` before it moves them, instead of moving away and back.
#[allow(clippy::too_many_arguments)]
fn finite_difference_jacobian<O: Ode + ?Sized>(
    ode: &mut O,
    t: f64,
    x: &[f64],
    f0: &[f64],
    jacobian: &mut [f64],
    dfdt: &mut [f64],
    x_scratch: &mut [f64],
    f_scratch: &mut [f64],
) -> Result<(), RuntimeError> {
    let n = x.len();
    let t_plus = t + (UROUND * t.abs().max(1e-5)).sqrt();
    ode.rhs(t_plus, x, f_scratch)?;
    let delta = t_plus - t;
    for ((out, f), f0) in dfdt.iter_mut().zip(&*f_scratch).zip(f0) {
        *out = (f - f0) / delta;
    }
    x_scratch.copy_from_slice(x);
    for j in (0..n).rev() {
        x_scratch[j] = x[j] + (UROUND * x[j].abs().max(1e-5)).sqrt();
        // The increment as represented, so that the quotient has no rounding bias.
        let delta = x_scratch[j] - x[j];
        ode.rhs(t, x_scratch, f_scratch)?;
        for ((out, f), f0) in jacobian[n * j..n * (j + 1)]
            .iter_mut()
            .zip(&*f_scratch)
            .zip(f0)
        {
            *out = (f - f0) / delta;
        }
        x_scratch[j] = x[j];
    }
    Ok(())
}

fn all_finite(x: &[f64]) -> bool {
    x.iter().all(|v| v.is_finite())
}

pub(crate) fn check_len(
    what: &'static str,
    expected: usize,
    found: usize,
) -> Result<(), RuntimeError> {
    if expected == found {
        Ok(())
    } else {
        Err(RuntimeError::LengthMismatch {
            what,
            expected,
            found,
        })
    }
}

fn check_times(t0: f64, t_end: f64) -> Result<(), RuntimeError> {
    if !t0.is_finite() || !t_end.is_finite() {
        return Err(RuntimeError::InvalidOptions(format!(
            "start and end times must be finite (got {t0} and {t_end})"
        )));
    }
    if t_end < t0 {
        return Err(RuntimeError::InvalidOptions(format!(
            "end time {t_end} is before start time {t0}: integration runs forward only"
        )));
    }
    Ok(())
}

/// Relative slack allowed when interpolating at the ends of a step.
const INTERP_SLACK: f64 = 1e-12;

fn interp_theta(t: f64, t_prev: f64, t_cur: f64) -> Result<f64, RuntimeError> {
    let h = t_cur - t_prev;
    let slack = INTERP_SLACK * h.abs().max(t_cur.abs() * f64::EPSILON);
    if !(t >= t_prev - slack && t <= t_cur + slack) {
        return Err(RuntimeError::InterpolationOutOfRange {
            t,
            t_start: t_prev,
            t_end: t_cur,
        });
    }
    Ok(if h > 0.0 {
        ((t - t_prev) / h).clamp(0.0, 1.0)
    } else {
        1.0
    })
}

/// Unit roundoff used in Hairer's step-size underflow test.
const UROUND: f64 = 2.3e-16;

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
#[derive(Debug, Clone, Copy)]
struct Adaptive {
    opts: AdaptiveOptions,
    /// `1/(p+1) − β·c`, the controller's exponent for a method whose error estimate is of
    /// order `p` (`DOPRI5`: `0.2 − 0.75β`; `DOP853`: `1/8 − 0.2β`).
    expo1: f64,
    /// Right-hand side evaluations per trial step.
    evaluations_per_trial: usize,
    t: f64,
    t_prev: f64,
    t_end: f64,
    /// Step size to try next.
    h: f64,
    fac_old: f64,
    /// The previous attempt was rejected.
    reject: bool,
    stats: Stats,
}

impl Adaptive {
    fn new(
        opts: AdaptiveOptions,
        expo1: f64,
        evaluations_per_trial: usize,
        t0: f64,
        t_end: f64,
    ) -> Result<Self, RuntimeError> {
        opts.validate()?;
        check_times(t0, t_end)?;
        Ok(Adaptive {
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
                let (mut x1, mut f1) = (vec![0.0; n], vec![0.0; n]);
                initial_step(ode, &opts, order, self.t, x0, &f0, &mut x1, &mut f1)?
            }
            None => 0.0,
        };
        Ok(f0)
    }

    /// Tries steps from `t` until one passes the error test. `trial(t, h)` computes a step of
    /// size `h` and returns its scaled error norm (NaN if anything was non-finite; such a trial
    /// is rejected and the step shrunk by `fac_min`). On success `t`, `t_prev` and the next
    /// step size are updated and the accepted `h` is returned; the caller then takes the new
    /// state. Does nothing (returns `None`) once `t_end` is reached.
    fn advance(
        &mut self,
        mut trial: impl FnMut(f64, f64) -> Result<f64, RuntimeError>,
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
            let err = trial(self.t, h)?;
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
/// Euler step (one evaluation of `ode`, written into `f1`; `x1` is scratch).
#[allow(clippy::too_many_arguments)]
fn initial_step<O: Ode>(
    ode: &mut O,
    opts: &AdaptiveOptions,
    order: i32,
    t: f64,
    x: &[f64],
    f0: &[f64],
    x1: &mut [f64],
    f1: &mut [f64],
) -> Result<f64, RuntimeError> {
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
    ode.rhs(t + h, x1, f1)?;
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
