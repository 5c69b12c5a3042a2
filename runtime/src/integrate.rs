//! Explicit Runge–Kutta integrators with a step-by-step API and dense output.
//!
//! * [`Dopri5`]: adaptive Dormand–Prince 5(4), a transcription of Hairer's `DOPRI5` (same
//!   coefficients, FSAL, Lund-stabilised PI step-size control, initial step-size heuristic,
//!   and Shampine's 4th-order continuous extension), with the same defaults. On the Arenstorf
//!   orbit it takes exactly the steps the Fortran code takes.
//! * [`Rk4`]: classical fixed-step Runge–Kutta of order 4, with cubic Hermite dense output.
//!
//! Both own their [`Ode`] and implement [`Stepper`]: `step()` advances by one accepted step
//! toward the end time, `interpolate()` evaluates the solution inside the last step, and
//! `state_mut()` lets the caller change the state between steps (e.g. to project it back onto
//! constraints; the derivative at the modified state is recomputed before the next step).
//! All working storage is allocated when the integrator is created; stepping never allocates.
//!
//! Integration runs forward in time only (`t_end >= t0`).
//!
//! ```
//! use mech_runtime::integrate::{Dopri5, Dopri5Options, Ode, Stepper};
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
//! let opts = Dopri5Options { rtol: 1e-10, atol: 1e-12, ..Default::default() };
//! let mut solver = Dopri5::new(Decay, 0.0, &[1.0], 2.0, opts)?;
//! while !solver.is_finished() {
//!     solver.step()?;
//! }
//! assert!((solver.state()[0] - (-2.0f64).exp()).abs() < 1e-10);
//! # Ok::<(), RuntimeError>(())
//! ```

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
    /// derivative refreshes after [`Stepper::state_mut`].
    pub rhs_evaluations: usize,
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
    fn interpolate(&self, t: f64, out: &mut [f64]) -> Result<(), RuntimeError>;
    /// Moves the end time to `t_end >= t()`, e.g. to continue an integration.
    fn set_t_end(&mut self, t_end: f64) -> Result<(), RuntimeError>;
    /// Work counters so far.
    fn stats(&self) -> Stats;
}

fn all_finite(x: &[f64]) -> bool {
    x.iter().all(|v| v.is_finite())
}

fn check_len(what: &'static str, expected: usize, found: usize) -> Result<(), RuntimeError> {
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

// ---------------------------------------------------------------------------------------------
// Dormand–Prince 5(4)
// ---------------------------------------------------------------------------------------------

// Dormand & Prince (1980) coefficients, as in Hairer's CDOPRI.
const C2: f64 = 0.2;
const C3: f64 = 0.3;
const C4: f64 = 0.8;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 0.2;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
// Shampine's (1986) dense output.
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// Unit roundoff used in Hairer's step-size underflow test.
const UROUND: f64 = 2.3e-16;

/// Options of [`Dopri5`]. The defaults are those of Hairer's `DOPRI5` except the tolerances.
///
/// A step is accepted when
/// `sqrt(mean_i((err_i / (atol + rtol·max(|x_i|, |x_new_i|)))²)) <= 1`, where `err` is the
/// difference between the 5th- and 4th-order solutions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dopri5Options {
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
    /// Smallest ratio of a new step to the previous one, in (0, 1]. Default `0.2`.
    pub fac_min: f64,
    /// Largest ratio of a new step to the previous one, ≥ 1. Default `10`.
    pub fac_max: f64,
    /// Lund stabilisation (PI control) exponent, in [0, 0.2]; `0` gives the standard
    /// controller. Default `0.04`.
    pub beta: f64,
}

impl Default for Dopri5Options {
    fn default() -> Self {
        Dopri5Options {
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

impl Dopri5Options {
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

/// Adaptive Dormand–Prince 5(4) integrator (Hairer's `DOPRI5`) with dense output.
///
/// Error control uses the 4th-order embedded solution; the 5th-order solution is propagated
/// (local extrapolation). The last stage is the derivative at the new point (FSAL), so an
/// accepted step costs 6 evaluations of the right-hand side. The step that would reach within
/// 1% of the end time is stretched to land on it exactly.
///
/// Non-finite values produced by a trial step reject it and shrink the step by `fac_min`; if
/// that drives the step to underflow, the error is [`RuntimeError::NonFiniteState`].
pub struct Dopri5<O: Ode> {
    ode: O,
    opts: Dopri5Options,
    t: f64,
    t_prev: f64,
    t_end: f64,
    /// Step size to try next.
    h: f64,
    /// Size of the last accepted step.
    h_last: f64,
    fac_old: f64,
    /// The previous attempt was rejected.
    reject: bool,
    /// The state was modified through `state_mut`; `k1` is stale.
    dirty: bool,
    stats: Stats,
    x: Vec<f64>,
    x_new: Vec<f64>,
    x_stage: Vec<f64>,
    k1: Vec<f64>,
    k2: Vec<f64>,
    k3: Vec<f64>,
    k4: Vec<f64>,
    k5: Vec<f64>,
    k6: Vec<f64>,
    k7: Vec<f64>,
    /// Dense output coefficients of the last step.
    cont: [Vec<f64>; 5],
}

impl<O: Ode> Dopri5<O> {
    /// Creates the integrator at `(t0, x0)`, integrating toward `t_end >= t0`, and evaluates
    /// the derivative at `x0` (plus once more for the initial step-size heuristic).
    pub fn new(
        mut ode: O,
        t0: f64,
        x0: &[f64],
        t_end: f64,
        opts: Dopri5Options,
    ) -> Result<Self, RuntimeError> {
        opts.validate()?;
        check_times(t0, t_end)?;
        let n = ode.dim();
        check_len("x0", n, x0.len())?;
        if !all_finite(x0) {
            return Err(RuntimeError::NonFiniteState { t: t0 });
        }
        let zeros = vec![0.0; n];
        let mut k1 = zeros.clone();
        ode.rhs(t0, x0, &mut k1)?;
        if !all_finite(&k1) {
            return Err(RuntimeError::NonFiniteState { t: t0 });
        }
        let mut s = Dopri5 {
            ode,
            opts,
            t: t0,
            t_prev: t0,
            t_end,
            h: 0.0,
            h_last: 0.0,
            fac_old: 1e-4,
            reject: false,
            dirty: false,
            stats: Stats {
                rhs_evaluations: 1,
                ..Stats::default()
            },
            x: x0.to_vec(),
            x_new: zeros.clone(),
            x_stage: zeros.clone(),
            k1,
            k2: zeros.clone(),
            k3: zeros.clone(),
            k4: zeros.clone(),
            k5: zeros.clone(),
            k6: zeros.clone(),
            k7: zeros.clone(),
            cont: [
                x0.to_vec(),
                zeros.clone(),
                zeros.clone(),
                zeros.clone(),
                zeros,
            ],
        };
        s.h = match opts.h_init {
            Some(h) => h.min(opts.h_max),
            None if t_end > t0 => s.initial_step()?,
            None => 0.0,
        };
        Ok(s)
    }

    /// Hairer's starting step-size heuristic (`HINIT`; Hairer, Nørsett & Wanner, *Solving
    /// Ordinary Differential Equations I*, §II.4), with root-mean-square norms.
    fn initial_step(&mut self) -> Result<f64, RuntimeError> {
        let n = self.x.len().max(1) as f64;
        let (rtol, atol, h_max) = (self.opts.rtol, self.opts.atol, self.opts.h_max);
        let (mut dnf, mut dny) = (0.0, 0.0);
        for (x, f) in self.x.iter().zip(&self.k1) {
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
        for ((xs, x), f) in self.x_stage.iter_mut().zip(&self.x).zip(&self.k1) {
            *xs = x + h * f;
        }
        self.ode.rhs(self.t + h, &self.x_stage, &mut self.k2)?;
        self.stats.rhs_evaluations += 1;
        let mut der2 = 0.0;
        for ((x, f0), f1) in self.x.iter().zip(&self.k1).zip(&self.k2) {
            let sk = atol + rtol * x.abs();
            der2 += ((f1 - f0) / sk).powi(2);
        }
        let der2 = (der2 / n).sqrt() / h;
        // `f64::max` ignores a NaN operand, so a non-finite trial derivative falls back on dnf.
        let der12 = der2.abs().max(dnf.sqrt());
        let h1 = if der12 <= 1e-15 {
            (h * 1e-3).max(1e-6)
        } else {
            (0.01 / der12).powf(1.0 / 5.0)
        };
        let h = (100.0 * h).min(h1).min(h_max);
        Ok(if h.is_finite() && h > 0.0 { h } else { 1e-6 })
    }

    /// The system being integrated.
    pub fn ode(&self) -> &O {
        &self.ode
    }

    /// Mutable access to the system (e.g. to change a parameter). Call [`Stepper::reset`]
    /// afterwards if the change alters the derivative at the current state.
    pub fn ode_mut(&mut self) -> &mut O {
        self.dirty = true;
        &mut self.ode
    }

    /// Consumes the integrator, returning the system.
    pub fn into_ode(self) -> O {
        self.ode
    }

    /// The options in use.
    pub fn options(&self) -> &Dopri5Options {
        &self.opts
    }

    /// Step size that the next step will try (before clipping to the end time).
    pub fn next_step_size(&self) -> f64 {
        self.h
    }

    /// Derivative `f(t, x)` at the current state (stale between [`Stepper::state_mut`] and the
    /// next [`Stepper::reset`] or [`Stepper::step`]).
    pub fn derivative(&self) -> &[f64] {
        &self.k1
    }

    /// Computes the six stages of a trial step of size `h` from `(t, x)`: `x_new` holds the
    /// 5th-order solution, `k7` its derivative, and the return value is the scaled error norm
    /// (NaN if anything is non-finite).
    fn trial_step(&mut self, h: f64) -> Result<f64, RuntimeError> {
        let t = self.t;
        let n = self.x.len();
        for i in 0..n {
            self.x_stage[i] = self.x[i] + h * A21 * self.k1[i];
        }
        self.ode.rhs(t + C2 * h, &self.x_stage, &mut self.k2)?;
        for i in 0..n {
            self.x_stage[i] = self.x[i] + h * (A31 * self.k1[i] + A32 * self.k2[i]);
        }
        self.ode.rhs(t + C3 * h, &self.x_stage, &mut self.k3)?;
        for i in 0..n {
            self.x_stage[i] =
                self.x[i] + h * (A41 * self.k1[i] + A42 * self.k2[i] + A43 * self.k3[i]);
        }
        self.ode.rhs(t + C4 * h, &self.x_stage, &mut self.k4)?;
        for i in 0..n {
            self.x_stage[i] = self.x[i]
                + h * (A51 * self.k1[i] + A52 * self.k2[i] + A53 * self.k3[i] + A54 * self.k4[i]);
        }
        self.ode.rhs(t + C5 * h, &self.x_stage, &mut self.k5)?;
        for i in 0..n {
            self.x_stage[i] = self.x[i]
                + h * (A61 * self.k1[i]
                    + A62 * self.k2[i]
                    + A63 * self.k3[i]
                    + A64 * self.k4[i]
                    + A65 * self.k5[i]);
        }
        let t_new = t + h;
        self.ode.rhs(t_new, &self.x_stage, &mut self.k6)?;
        for i in 0..n {
            self.x_new[i] = self.x[i]
                + h * (A71 * self.k1[i]
                    + A73 * self.k3[i]
                    + A74 * self.k4[i]
                    + A75 * self.k5[i]
                    + A76 * self.k6[i]);
        }
        self.ode.rhs(t_new, &self.x_new, &mut self.k7)?;
        self.stats.rhs_evaluations += 6;

        let (rtol, atol) = (self.opts.rtol, self.opts.atol);
        let mut sum = 0.0;
        let mut finite = true;
        for i in 0..n {
            let err = (E1 * self.k1[i]
                + E3 * self.k3[i]
                + E4 * self.k4[i]
                + E5 * self.k5[i]
                + E6 * self.k6[i]
                + E7 * self.k7[i])
                * h;
            let sk = atol + rtol * self.x[i].abs().max(self.x_new[i].abs());
            sum += (err / sk).powi(2);
            finite &= self.x_new[i].is_finite() && self.k7[i].is_finite();
        }
        let err = (sum / n.max(1) as f64).sqrt();
        Ok(if finite { err } else { f64::NAN })
    }

    /// Stores the dense output coefficients of the step of size `h` from `x` to `x_new`.
    fn store_dense(&mut self, h: f64) {
        let [c0, c1, c2, c3, c4] = &mut self.cont;
        for i in 0..self.x.len() {
            let ydiff = self.x_new[i] - self.x[i];
            let bspl = h * self.k1[i] - ydiff;
            c0[i] = self.x[i];
            c1[i] = ydiff;
            c2[i] = bspl;
            c3[i] = -h * self.k7[i] + ydiff - bspl;
            c4[i] = h
                * (D1 * self.k1[i]
                    + D3 * self.k3[i]
                    + D4 * self.k4[i]
                    + D5 * self.k5[i]
                    + D6 * self.k6[i]
                    + D7 * self.k7[i]);
        }
    }
}

impl<O: Ode> Stepper for Dopri5<O> {
    fn step(&mut self) -> Result<(), RuntimeError> {
        self.reset()?;
        if self.t >= self.t_end {
            return Ok(());
        }
        let o = self.opts;
        let expo1 = 0.2 - o.beta * 0.75;
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
            let last = self.t + 1.01 * h - self.t_end > 0.0;
            if last {
                h = self.t_end - self.t;
            }

            let err = self.trial_step(h)?;
            if err.is_nan() || err.is_infinite() {
                // Non-finite trial: shrink hard and retry.
                nonfinite = true;
                self.reject = true;
                self.stats.rejected_steps += 1;
                self.h = h * o.fac_min;
                continue;
            }
            let fac11 = err.powf(expo1);
            // Lund stabilisation.
            let fac = fac11 / self.fac_old.powf(o.beta);
            // The new step is h/fac, with fac_min <= 1/fac <= fac_max.
            let fac = (1.0 / o.fac_max).max((1.0 / o.fac_min).min(fac / o.safety));
            let mut h_new = h / fac;
            if err <= 1.0 {
                self.fac_old = err.max(1e-4);
                self.stats.accepted_steps += 1;
                self.store_dense(h);
                std::mem::swap(&mut self.x, &mut self.x_new);
                std::mem::swap(&mut self.k1, &mut self.k7);
                self.t_prev = self.t;
                self.t = if last { self.t_end } else { self.t + h };
                self.h_last = h;
                h_new = h_new.min(o.h_max);
                if self.reject {
                    h_new = h_new.min(h);
                }
                self.reject = false;
                self.h = h_new;
                return Ok(());
            }
            self.h = h / (1.0 / o.fac_min).min(fac11 / o.safety);
            self.reject = true;
            self.stats.rejected_steps += 1;
        }
    }

    fn t(&self) -> f64 {
        self.t
    }

    fn t_prev(&self) -> f64 {
        self.t_prev
    }

    fn t_end(&self) -> f64 {
        self.t_end
    }

    fn state(&self) -> &[f64] {
        &self.x
    }

    fn state_mut(&mut self) -> &mut [f64] {
        self.dirty = true;
        &mut self.x
    }

    fn reset(&mut self) -> Result<(), RuntimeError> {
        if !self.dirty {
            return Ok(());
        }
        if !all_finite(&self.x) {
            return Err(RuntimeError::NonFiniteState { t: self.t });
        }
        self.ode.rhs(self.t, &self.x, &mut self.k1)?;
        self.stats.rhs_evaluations += 1;
        if !all_finite(&self.k1) {
            return Err(RuntimeError::NonFiniteState { t: self.t });
        }
        self.dirty = false;
        Ok(())
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) -> Result<(), RuntimeError> {
        check_len("out", self.x.len(), out.len())?;
        let theta = interp_theta(t, self.t_prev, self.t)?;
        if theta == 1.0 {
            out.copy_from_slice(&self.x);
            return Ok(());
        }
        let theta1 = 1.0 - theta;
        let [c0, c1, c2, c3, c4] = &self.cont;
        for (i, o) in out.iter_mut().enumerate() {
            *o = c0[i] + theta * (c1[i] + theta1 * (c2[i] + theta * (c3[i] + theta1 * c4[i])));
        }
        Ok(())
    }

    fn set_t_end(&mut self, t_end: f64) -> Result<(), RuntimeError> {
        check_times(self.t, t_end)?;
        self.t_end = t_end;
        Ok(())
    }

    fn stats(&self) -> Stats {
        self.stats
    }
}

// ---------------------------------------------------------------------------------------------
// Classical RK4
// ---------------------------------------------------------------------------------------------

/// Classical 4th-order Runge–Kutta with a fixed step `h`.
///
/// Steps end at `t0 + k·h` (computed by multiplication, so times do not drift); the last step
/// is shortened to end exactly at `t_end` (a remainder shorter than `1e-9·h` is merged into
/// the previous step instead). Each step costs 4 evaluations (the derivative at the end of a
/// step is the first stage of the next). Dense output is the cubic Hermite interpolant of the
/// states and derivatives at both ends of the step (3rd order).
pub struct Rk4<O: Ode> {
    ode: O,
    h: f64,
    /// Origin of the step grid and number of steps taken since it was set.
    t_origin: f64,
    n_since_origin: u64,
    t: f64,
    t_prev: f64,
    t_end: f64,
    dirty: bool,
    stats: Stats,
    x: Vec<f64>,
    f: Vec<f64>,
    x_prev: Vec<f64>,
    f_prev: Vec<f64>,
    x_stage: Vec<f64>,
    k2: Vec<f64>,
    k3: Vec<f64>,
    k4: Vec<f64>,
}

impl<O: Ode> Rk4<O> {
    /// Creates the integrator at `(t0, x0)` with step `h > 0`, integrating toward
    /// `t_end >= t0`; evaluates the derivative at `x0`.
    pub fn new(mut ode: O, t0: f64, x0: &[f64], t_end: f64, h: f64) -> Result<Self, RuntimeError> {
        check_times(t0, t_end)?;
        if !(h > 0.0 && h.is_finite()) {
            return Err(RuntimeError::InvalidOptions(format!(
                "the RK4 step must be finite and > 0 (got {h})"
            )));
        }
        let n = ode.dim();
        check_len("x0", n, x0.len())?;
        if !all_finite(x0) {
            return Err(RuntimeError::NonFiniteState { t: t0 });
        }
        let zeros = vec![0.0; n];
        let mut f = zeros.clone();
        ode.rhs(t0, x0, &mut f)?;
        if !all_finite(&f) {
            return Err(RuntimeError::NonFiniteState { t: t0 });
        }
        Ok(Rk4 {
            ode,
            h,
            t_origin: t0,
            n_since_origin: 0,
            t: t0,
            t_prev: t0,
            t_end,
            dirty: false,
            stats: Stats {
                rhs_evaluations: 1,
                ..Stats::default()
            },
            x: x0.to_vec(),
            f: f.clone(),
            x_prev: x0.to_vec(),
            f_prev: f,
            x_stage: zeros.clone(),
            k2: zeros.clone(),
            k3: zeros.clone(),
            k4: zeros,
        })
    }

    /// The system being integrated.
    pub fn ode(&self) -> &O {
        &self.ode
    }

    /// Mutable access to the system; the derivative is recomputed before the next step.
    pub fn ode_mut(&mut self) -> &mut O {
        self.dirty = true;
        &mut self.ode
    }

    /// Consumes the integrator, returning the system.
    pub fn into_ode(self) -> O {
        self.ode
    }

    /// The fixed step size.
    pub fn step_size(&self) -> f64 {
        self.h
    }
}

impl<O: Ode> Stepper for Rk4<O> {
    fn step(&mut self) -> Result<(), RuntimeError> {
        self.reset()?;
        if self.t >= self.t_end {
            return Ok(());
        }
        let next = self.t_origin + (self.n_since_origin + 1) as f64 * self.h;
        let t_new = if next >= self.t_end - 1e-9 * self.h {
            self.t_end
        } else {
            next
        };
        let (t, h) = (self.t, t_new - self.t);
        let n = self.x.len();
        for i in 0..n {
            self.x_stage[i] = self.x[i] + 0.5 * h * self.f[i];
        }
        self.ode.rhs(t + 0.5 * h, &self.x_stage, &mut self.k2)?;
        for i in 0..n {
            self.x_stage[i] = self.x[i] + 0.5 * h * self.k2[i];
        }
        self.ode.rhs(t + 0.5 * h, &self.x_stage, &mut self.k3)?;
        for i in 0..n {
            self.x_stage[i] = self.x[i] + h * self.k3[i];
        }
        self.ode.rhs(t_new, &self.x_stage, &mut self.k4)?;
        for i in 0..n {
            self.x_stage[i] = self.x[i]
                + h / 6.0 * (self.f[i] + 2.0 * self.k2[i] + 2.0 * self.k3[i] + self.k4[i]);
        }
        // The derivative at the new point goes into k2 (free now), then becomes `f`.
        self.ode.rhs(t_new, &self.x_stage, &mut self.k2)?;
        self.stats.rhs_evaluations += 4;
        if !all_finite(&self.x_stage) || !all_finite(&self.k2) {
            return Err(RuntimeError::NonFiniteState { t });
        }
        std::mem::swap(&mut self.x_prev, &mut self.x);
        std::mem::swap(&mut self.x, &mut self.x_stage);
        std::mem::swap(&mut self.f_prev, &mut self.f);
        std::mem::swap(&mut self.f, &mut self.k2);
        self.t_prev = t;
        self.t = t_new;
        self.n_since_origin += 1;
        self.stats.accepted_steps += 1;
        Ok(())
    }

    fn t(&self) -> f64 {
        self.t
    }

    fn t_prev(&self) -> f64 {
        self.t_prev
    }

    fn t_end(&self) -> f64 {
        self.t_end
    }

    fn state(&self) -> &[f64] {
        &self.x
    }

    fn state_mut(&mut self) -> &mut [f64] {
        self.dirty = true;
        &mut self.x
    }

    fn reset(&mut self) -> Result<(), RuntimeError> {
        if !self.dirty {
            return Ok(());
        }
        if !all_finite(&self.x) {
            return Err(RuntimeError::NonFiniteState { t: self.t });
        }
        self.ode.rhs(self.t, &self.x, &mut self.f)?;
        self.stats.rhs_evaluations += 1;
        if !all_finite(&self.f) {
            return Err(RuntimeError::NonFiniteState { t: self.t });
        }
        self.dirty = false;
        Ok(())
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) -> Result<(), RuntimeError> {
        check_len("out", self.x.len(), out.len())?;
        let s = interp_theta(t, self.t_prev, self.t)?;
        if s == 1.0 {
            out.copy_from_slice(&self.x);
            return Ok(());
        }
        let h = self.t - self.t_prev;
        let (s2, s3) = (s * s, s * s * s);
        let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
        let h10 = s3 - 2.0 * s2 + s;
        let h01 = -2.0 * s3 + 3.0 * s2;
        let h11 = s3 - s2;
        for (i, o) in out.iter_mut().enumerate() {
            *o = h00 * self.x_prev[i]
                + h10 * h * self.f_prev[i]
                + h01 * self.x[i]
                + h11 * h * self.f[i];
        }
        Ok(())
    }

    fn set_t_end(&mut self, t_end: f64) -> Result<(), RuntimeError> {
        check_times(self.t, t_end)?;
        self.t_end = t_end;
        // Restart the step grid at the current time (the last step may have been shortened).
        self.t_origin = self.t;
        self.n_since_origin = 0;
        Ok(())
    }

    fn stats(&self) -> Stats {
        self.stats
    }
}
