//! Linearly implicit Rosenbrock 2(3) of Shampine & Reichelt (MATLAB's `ode23s`): the stages,
//! error estimate and continuous extension that the adaptive shell ([`AdaptiveStepper`]) steps
//! with.
//!
//! Consumes the right-hand side through the shell (and its finite-difference Jacobian);
//! produces the order-2 solution of each step, its scaled error norm and the quadratic dense
//! output.

use super::adaptive::{error_norm, AdaptiveMethod, DenseWithStep, Point, Step};
use super::{AdaptiveStepper, Jacobian, Ode, Stats};
use crate::{dense, RuntimeError};
// For the documentation's links only.
#[cfg(doc)]
use super::AdaptiveOptions;

// L. F. Shampine and M. W. Reichelt, "The MATLAB ODE Suite", SIAM J. Sci. Comput. 18(1),
// 1997, §3: with W = I − h·d·J and T = ∂f/∂t,
//   k1 = W⁻¹(F0 + h·d·T),          F0 = f(t, y)
//   k2 = W⁻¹(F1 − k1) + k1,        F1 = f(t + h/2, y + h/2·k1)
//   y_new = y + h·k2,               F2 = f(t + h, y_new)
//   k3 = W⁻¹(F2 − e32(k2 − F1) − 2(k1 − F0) + h·d·T)
//   error ≈ h/6·(k1 − 2k2 + k3)
// and the continuous extension y(t + s·h) = y + h·(s(1−s)·k1 + s(s−2d)·k2)/(1−2d).
/// `d = 1/(2 + √2)`: the method is L-stable.
const D: f64 = 0.292_893_218_813_452_5;
/// `e32 = 6 + √2`.
const E32: f64 = 7.414_213_562_373_095;

/// Adaptive linearly implicit Rosenbrock method of order 2 with a 3rd-order error estimate
/// (Shampine & Reichelt's `ode23s`), for stiff systems, with dense output.
///
/// L-stable: modes far faster than the step are damped, not resolved, so the step follows the
/// accuracy of the slow motion. Each step solves three linear systems with
/// `W = I − h·d·J` (LU, `n × n`) and costs two evaluations of the right-hand side (the third
/// is the first of the next step). `J = ∂f/∂x` and `∂f/∂t` are forward differences
/// (`n + 1` evaluations, counted in [`Stats::rhs_evaluations`]; the Jacobians in
/// [`Stats::jacobian_evaluations`]).
///
/// The order-2 solution is a W-method (order 2 for any `J`), but the error estimate is
/// asymptotically correct only with the exact `J`: with a stale one it can under-estimate
/// the error (by 10× or more). So `J` is re-evaluated at the start of every step by default;
/// [`Rosenbrock::reuse_jacobian`] trades that for speed where `J` varies slowly. After a
/// rejected step `J` is always re-evaluated at the current point.
///
/// Non-finite values (or a singular `W`) reject the trial step and shrink the step by
/// `fac_min`; if that drives the step to underflow, the error is
/// [`RuntimeError::NonFiniteState`]. Start from [`AdaptiveOptions::rosenbrock`] for the
/// step-size controller's usual settings.
pub type Rosenbrock<O> = AdaptiveStepper<O, RosenbrockMethod>;

/// The working vectors of one step, the Jacobian and the factor of `W`; `F0 = f(t, x)` is
/// the shell's current derivative, `F2 = f(t + h, y_new)` the derivative at the step's end.
pub struct RosenbrockMethod {
    x_stage: Vec<f64>,
    f1: Vec<f64>,
    k1: Vec<f64>,
    k2: Vec<f64>,
    k3: Vec<f64>,
    /// `W = I − h·d·J` and its solve.
    linear: LinearSolve,
    /// Dense output of the last step: `x_prev`, `h·k1/(1−2d)`, `h·k2/(1−2d)`.
    cont: [Vec<f64>; 3],
}

impl<O: Ode> Rosenbrock<O> {
    /// Lets a Jacobian serve `steps` accepted steps after the one it was evaluated for
    /// (default 0: a fresh `J` every step). Re-using it saves `n + 1` evaluations per step
    /// but weakens the error estimate (see the type's docs); a rejection still forces a
    /// fresh `J`.
    pub fn reuse_jacobian(&mut self, steps: usize) {
        self.method.linear.jacobian_reuse = steps;
    }
}

impl DenseWithStep for RosenbrockMethod {}

impl AdaptiveMethod for RosenbrockMethod {
    const ORDER: i32 = 2;
    const EVALUATIONS_PER_TRIAL: usize = 2;

    /// The error estimate is O(h³): exponent 1/3, less the Lund stabilisation.
    fn error_exponent(beta: f64) -> f64 {
        1.0 / 3.0 - 0.75 * beta
    }

    fn new(x0: &[f64]) -> Self {
        let n = x0.len();
        let zeros = vec![0.0; n];
        RosenbrockMethod {
            x_stage: zeros.clone(),
            f1: zeros.clone(),
            k1: zeros.clone(),
            k2: zeros.clone(),
            k3: zeros.clone(),
            linear: LinearSolve::new(n),
            cont: [x0.to_vec(), zeros.clone(), zeros],
        }
    }

    fn derivative_refreshed(&mut self) {
        self.linear.derivative_refreshed();
    }

    /// A trial step of size `h` from `(t, x)`: `x_new`, `f2 = f(t + h, x_new)` (the step's
    /// end), and the scaled error norm (NaN also if `W` is singular). A Jacobian evaluated
    /// first is counted in `stats`.
    // Indexed loops, so that each line reads as the formula at the top of the file.
    #[allow(clippy::needless_range_loop)]
    fn trial<O: Ode>(&mut self, ode: &mut O, step: Step<'_>) -> Result<f64, RuntimeError> {
        let (opts, now, next, t, h) = (step.opts, step.now, step.next, step.t, step.h);
        let (x, f0) = (&now.x, &now.f);
        let (x_new, f2) = (&mut next.x, &mut next.f);
        let n = x.len();
        let hd = h * D;
        if !self.linear.prepare(ode, step.stats, t, x, f0, hd)? {
            return Ok(f64::NAN);
        }
        let dfdt = &self.linear.jacobian.dfdt;
        for i in 0..n {
            self.k1[i] = f0[i] + hd * dfdt[i];
        }
        self.linear.solve(ode, &mut self.k1);
        for i in 0..n {
            self.x_stage[i] = x[i] + 0.5 * h * self.k1[i];
        }
        ode.rhs(t + 0.5 * h, &self.x_stage, &mut self.f1)?;
        for i in 0..n {
            self.k2[i] = self.f1[i] - self.k1[i];
        }
        self.linear.solve(ode, &mut self.k2);
        for i in 0..n {
            self.k2[i] += self.k1[i];
            x_new[i] = x[i] + h * self.k2[i];
        }
        ode.rhs(t + h, x_new, f2)?;
        let dfdt = &self.linear.jacobian.dfdt;
        for i in 0..n {
            self.k3[i] =
                f2[i] - E32 * (self.k2[i] - self.f1[i]) - 2.0 * (self.k1[i] - f0[i]) + hd * dfdt[i];
        }
        self.linear.solve(ode, &mut self.k3);

        let error = |i: usize| h / 6.0 * (self.k1[i] - 2.0 * self.k2[i] + self.k3[i]);
        Ok(error_norm(opts, x, x_new, f2, error))
    }

    fn accept<O: Ode>(&mut self, _ode: &mut O, step: Step<'_>) -> Result<(), RuntimeError> {
        self.store_dense(step.now, step.h);
        self.linear.accepted();
        Ok(())
    }

    fn interpolate(&mut self, _t: f64, theta: f64, out: &mut [f64]) -> Result<(), RuntimeError> {
        let [c0, c1, c2] = &self.cont;
        let (a, b) = (theta * (1.0 - theta), theta * (theta - 2.0 * D));
        for (i, o) in out.iter_mut().enumerate() {
            *o = c0[i] + a * c1[i] + b * c2[i];
        }
        Ok(())
    }
}

/// The linear systems of a linearly implicit step, `W k = r` with `W = I − γ J`: by the
/// system's own solve where it has one ([`Ode::prepare_implicit`], a W-method's `J̃`; then
/// `∂f/∂t` is taken as 0), otherwise with `J` and `∂f/∂t` by differences and an LU factor of
/// `W`. Shared by [`Rosenbrock`] and [`Ros34pw2`](super::Ros34pw2).
pub(super) struct LinearSolve {
    /// `J` and `∂f/∂t` (the differences' path; `∂f/∂t` zero on the system's).
    pub(super) jacobian: Jacobian,
    /// Accepted steps since `J` was evaluated.
    jacobian_age: usize,
    /// Steps a Jacobian may serve after the one it was evaluated for.
    pub(super) jacobian_reuse: usize,
    /// Trial steps tried from the current point.
    attempts: usize,
    /// LU factor of `W` and its pivots, for `factor_gamma` (NaN: none).
    factor: Vec<f64>,
    pivots: Vec<usize>,
    factor_gamma: f64,
    /// The system solves (set by each [`LinearSolve::prepare`]).
    supplied: bool,
}

impl LinearSolve {
    pub(super) fn new(n: usize) -> Self {
        LinearSolve {
            jacobian: Jacobian::new(n),
            jacobian_age: usize::MAX,
            jacobian_reuse: 0,
            attempts: 0,
            factor: vec![0.0; n * n],
            pivots: vec![0; n],
            factor_gamma: f64::NAN,
            supplied: false,
        }
    }

    /// The derivative at the current point was refreshed: `J` is no longer current.
    pub(super) fn derivative_refreshed(&mut self) {
        self.jacobian.current = false;
    }

    /// A step was accepted: the next trial starts from a new point.
    pub(super) fn accepted(&mut self) {
        self.jacobian.current = false;
        self.jacobian_age = self.jacobian_age.saturating_add(1);
        self.attempts = 0;
    }

    /// Prepares `W = I − γ J` for a trial from `(t, x)`, `f0 = f(t, x)`: the system's solve,
    /// or `J` by differences (fresh unless it may serve this step; always after a
    /// rejection) and the LU factor. `false` if `W` is singular.
    pub(super) fn prepare<O: Ode>(
        &mut self,
        ode: &mut O,
        stats: &mut Stats,
        t: f64,
        x: &[f64],
        f0: &[f64],
        gamma: f64,
    ) -> Result<bool, RuntimeError> {
        self.attempts += 1;
        // The system's W is fresh for every trial: on the robot, its contacts' damping moves
        // with the slip too fast to serve a second step (re-using it for 2 to 20 steps took
        // 35–45 % more steps).
        if let Some(prepared) = ode.prepare_implicit(t, x, gamma) {
            stats.jacobian_evaluations += 1;
            self.supplied = true;
            self.jacobian.dfdt.fill(0.0);
            return prepared;
        }
        self.supplied = false;
        let n = x.len();
        let stale = self.attempts > 1 || self.jacobian_age > self.jacobian_reuse;
        if !self.jacobian.current && stale {
            self.jacobian.evaluate(ode, t, x, f0, stats)?;
            self.jacobian_age = 0;
            self.factor_gamma = f64::NAN;
        }
        if self.factor_gamma != gamma {
            for (w, j) in self.factor.iter_mut().zip(&self.jacobian.dfdx) {
                *w = -gamma * j;
            }
            for i in 0..n {
                self.factor[i + n * i] += 1.0;
            }
            if !dense::lu(&mut self.factor, n, &mut self.pivots) {
                self.factor_gamma = f64::NAN;
                return Ok(false);
            }
            self.factor_gamma = gamma;
        }
        Ok(true)
    }

    /// `v ← W⁻¹ v` with the last prepared `W`.
    pub(super) fn solve<O: Ode>(&self, ode: &mut O, v: &mut [f64]) {
        if self.supplied {
            ode.solve_implicit(v);
        } else {
            dense::lu_solve(&self.factor, v.len(), &self.pivots, v);
        }
    }
}

impl RosenbrockMethod {
    /// Stores the dense output of the accepted step of size `h` from `now.x`.
    fn store_dense(&mut self, now: &Point, h: f64) {
        let [c0, c1, c2] = &mut self.cont;
        let scale = h / (1.0 - 2.0 * D);
        for i in 0..now.x.len() {
            c0[i] = now.x[i];
            c1[i] = scale * self.k1[i];
            c2[i] = scale * self.k2[i];
        }
    }
}
