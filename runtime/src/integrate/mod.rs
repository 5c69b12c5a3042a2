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
//! The adaptive methods are one shell, [`AdaptiveStepper`] (the step-size controller, the
//! initial step heuristic, the state bookkeeping of [`Stepper`]), around each method's stages;
//! the implicit ones share the finite-difference Jacobian.
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

mod adaptive;
mod dop853;
mod dopri5;
mod exp_rosenbrock;
mod phi;
mod rk4;
mod ros34pw2;
mod rosenbrock;

pub use adaptive::{AdaptiveOptions, AdaptiveStepper};
pub use dop853::Dop853;
pub use dopri5::Dopri5;
pub use exp_rosenbrock::ExpRosenbrock;
pub use rk4::Rk4;
pub use ros34pw2::{Ros34pw2, Ros34pw2Method};
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
    /// For [`Rosenbrock`], a W-method: prepares solving `(I − γ J̃) k = r` at `(t, x)` with
    /// `J̃ ≈ ∂f/∂x` of the system's own choosing (the stiff part of `f`, cheaper than `∂f/∂x`
    /// by differences). `None` (the default): the system has none, and the method takes
    /// finite differences. `Some(Ok(false))`: the matrix is singular.
    fn prepare_implicit(
        &mut self,
        _t: f64,
        _x: &[f64],
        _gamma: f64,
    ) -> Option<Result<bool, RuntimeError>> {
        None
    }
    /// Solves `(I − γ J̃) k = r` in place (`r` in, `k` out) after [`Ode::prepare_implicit`]
    /// returned `Some(Ok(true))`.
    fn solve_implicit(&mut self, _r: &mut [f64]) {}
    /// Moves the state of an accepted step onto the system's manifold (e.g. constraints),
    /// before [`Ros34pw2`] evaluates the derivative there; returns whether it changed it. The
    /// default leaves it.
    fn correct(&mut self, _t: f64, _x: &mut [f64]) -> Result<bool, RuntimeError> {
        Ok(false)
    }
}

impl<O: Ode + ?Sized> Ode for &mut O {
    fn dim(&self) -> usize {
        (**self).dim()
    }
    fn rhs(&mut self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), RuntimeError> {
        (**self).rhs(t, x, dxdt)
    }
    fn prepare_implicit(
        &mut self,
        t: f64,
        x: &[f64],
        gamma: f64,
    ) -> Option<Result<bool, RuntimeError>> {
        (**self).prepare_implicit(t, x, gamma)
    }
    fn solve_implicit(&mut self, r: &mut [f64]) {
        (**self).solve_implicit(r)
    }
    fn correct(&mut self, t: f64, x: &mut [f64]) -> Result<bool, RuntimeError> {
        (**self).correct(t, x)
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

/// `J = ∂f/∂x` (`n × n`, column-major) and `∂f/∂t` at a point, by forward differences: the
/// linearization that the implicit methods ([`Rosenbrock`], [`ExpRosenbrock`]) step with.
struct Jacobian {
    dfdx: Vec<f64>,
    dfdt: Vec<f64>,
    /// Evaluated at the current point (the method clears it when the point moves).
    current: bool,
    /// Working vectors of the differences.
    x_scratch: Vec<f64>,
    f_scratch: Vec<f64>,
}

impl Jacobian {
    fn new(n: usize) -> Self {
        Jacobian {
            dfdx: vec![0.0; n * n],
            dfdt: vec![0.0; n],
            current: false,
            x_scratch: vec![0.0; n],
            f_scratch: vec![0.0; n],
        }
    }

    /// Evaluates `J` and `∂f/∂t` at `(t, x)` from `f0 = f(t, x)`, with Hairer's increments
    /// `√(UROUND·max(1e-5, |x_j|))` (as in `RODAS`): `n + 1` evaluations, counted in `stats`
    /// with the Jacobian.
    ///
    /// The time column comes first, then the state columns from the last to the first: a
    /// system whose state is `[positions; rates]` and which keeps work that depends on the
    /// positions only (the loops closed by [`Reduced`](crate::Reduced)) evaluates every
    /// column that leaves the positions at `x` before it moves them, instead of moving away
    /// and back.
    fn evaluate<O: Ode + ?Sized>(
        &mut self,
        ode: &mut O,
        t: f64,
        x: &[f64],
        f0: &[f64],
        stats: &mut Stats,
    ) -> Result<(), RuntimeError> {
        let n = x.len();
        let (x_scratch, f_scratch) = (&mut self.x_scratch, &mut self.f_scratch);
        let t_plus = t + (UROUND * t.abs().max(1e-5)).sqrt();
        ode.rhs(t_plus, x, f_scratch)?;
        let delta = t_plus - t;
        for ((out, f), f0) in self.dfdt.iter_mut().zip(&*f_scratch).zip(f0) {
            *out = (f - f0) / delta;
        }
        x_scratch.copy_from_slice(x);
        for j in (0..n).rev() {
            x_scratch[j] = x[j] + (UROUND * x[j].abs().max(1e-5)).sqrt();
            // The increment as represented, so that the quotient has no rounding bias.
            let delta = x_scratch[j] - x[j];
            ode.rhs(t, x_scratch, f_scratch)?;
            for ((out, f), f0) in self.dfdx[n * j..n * (j + 1)]
                .iter_mut()
                .zip(&*f_scratch)
                .zip(f0)
            {
                *out = (f - f0) / delta;
            }
            x_scratch[j] = x[j];
        }
        stats.rhs_evaluations += n + 1;
        stats.jacobian_evaluations += 1;
        self.current = true;
        Ok(())
    }
}

/// The cubic Hermite interpolant at the fraction `theta` of a step of length `h` from
/// `(x0, f0)` to `(x1, f1)` (states and derivatives), into `out`.
fn hermite(theta: f64, h: f64, start: (&[f64], &[f64]), end: (&[f64], &[f64]), out: &mut [f64]) {
    let (s, s2, s3) = (theta, theta * theta, theta * theta * theta);
    let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
    let h10 = s3 - 2.0 * s2 + s;
    let h01 = -2.0 * s3 + 3.0 * s2;
    let h11 = s3 - s2;
    let ((x0, f0), (x1, f1)) = (start, end);
    for (i, o) in out.iter_mut().enumerate() {
        *o = h00 * x0[i] + h10 * h * f0[i] + h01 * x1[i] + h11 * h * f1[i];
    }
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

/// `Ok` if `indices` (of `what`, e.g. `"independent coordinates"`) are distinct and below
/// `bound`.
pub(crate) fn check_indices(
    what: &str,
    indices: &[usize],
    bound: usize,
) -> Result<(), RuntimeError> {
    let mut sorted = indices.to_vec();
    sorted.sort_unstable();
    sorted.dedup();
    match sorted.len() == indices.len() && sorted.last().is_none_or(|&i| i < bound) {
        true => Ok(()),
        false => Err(RuntimeError::InvalidOptions(format!(
            "{what} {indices:?}: need distinct indices below {bound}"
        ))),
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

/// The start of [`Stepper::interpolate`] shared by the integrators: checks the length of `out`
/// and that `t` lies in the last step `[t_prev, t_cur]`, and returns the fraction `θ` of the
/// step at `t`, except at its end (`θ = 1`), where it writes the current `state` into `out`
/// and returns `None` (so that a state modified through [`Stepper::state_mut`] is returned).
fn begin_interpolation(
    t: f64,
    t_prev: f64,
    t_cur: f64,
    state: &[f64],
    out: &mut [f64],
) -> Result<Option<f64>, RuntimeError> {
    check_len("out", state.len(), out.len())?;
    let h = t_cur - t_prev;
    let slack = INTERP_SLACK * h.abs().max(t_cur.abs() * f64::EPSILON);
    if !(t >= t_prev - slack && t <= t_cur + slack) {
        return Err(RuntimeError::InterpolationOutOfRange {
            t,
            t_start: t_prev,
            t_end: t_cur,
        });
    }
    let theta = if h > 0.0 {
        ((t - t_prev) / h).clamp(0.0, 1.0)
    } else {
        1.0
    };
    if theta == 1.0 {
        out.copy_from_slice(state);
        return Ok(None);
    }
    Ok(Some(theta))
}

/// Unit roundoff used in Hairer's step-size underflow test.
const UROUND: f64 = 2.3e-16;
