//! Exponential Rosenbrock method `exprb43` of Hochbruck, Ostermann & Schweitzer: the stages,
//! error estimate and continuous extension that the adaptive shell ([`AdaptiveStepper`]) steps
//! with.
//!
//! Consumes the right-hand side through the shell (its finite-difference Jacobian, and the
//! matrix φ-functions of [`PhiFunctions`]); produces the order-4 solution of each step, its
//! scaled error norm and the dense output of the same variation-of-constants formula.

use super::adaptive::{error_norm, AdaptiveMethod, DenseWithStep, Point, Step};
use super::phi::PhiFunctions;
use super::{AdaptiveStepper, Jacobian, Ode};
use crate::RuntimeError;
// For the documentation's links only.
#[cfg(doc)]
use super::{AdaptiveOptions, Stats};

// M. Hochbruck, A. Ostermann and J. Schweitzer, "Exponential Rosenbrock-type methods",
// SIAM J. Numer. Anal. 47(1), 2009, pp. 786–803, scheme exprb43 (order 4, embedded order 3);
// also Hochbruck & Ostermann, "Exponential integrators", Acta Numerica 19, 2010, §2.4.
// Time is appended to the state (y = [x; t], F = [f; 1]), so J = F'(y_n) carries ∂f/∂t in
// its last column. With g(y) = F(y) − J y and D_i = g(U_i) − g(y_n), all φ_k at hJ:
//   U2      = y_n + h/2·φ1(hJ/2)·F(y_n)
//   U3      = y_n + h·φ1·F(y_n) + h·φ1·D2
//   y_{n+1} = y_n + h·φ1·F(y_n) + h·(16φ3 − 48φ4)·D2 + h·(−2φ3 + 12φ4)·D3
// The embedded order-3 solution drops the φ4 terms: error ≈ h·φ4·(−48·D2 + 12·D3).
// Dense output (the same variation-of-constants integral with g(y(t_n + s)) − g(y_n)
// interpolated by the cubic a·s² + b·s³ through D2 at h/2 and D3 at h), θ = τ/h:
//   y(t_n + τ) = y_n + τ·φ1(τJ)·F(y_n) + τ·(2θ²(8·D2 − D3)·φ3(τJ) + 6θ³(2·D3 − 8·D2)·φ4(τJ)),
// which is y_{n+1} at τ = h. The time row of J is zero, so φ_k of it never needs forming:
// with H = h·∂f/∂x and g = h·∂f/∂t, φ_k(hJ)·[v; c] = [φ_k(H)·v + c·φ_{k+1}(H)·g; c/k!],
// and every D_i has c = 0 (φ-functions of the n × n matrix only).

/// Adaptive exponential Rosenbrock integrator of order 4 with a 3rd-order error estimate
/// (`exprb43`), with dense output: for systems whose stiffness is lightly damped oscillation.
///
/// The linearization at the start of each step is integrated exactly (through the matrix
/// φ-functions of `h·J`), so modes far faster than the step are followed, not damped (as an
/// L-stable method would) nor resolved step by step (as an explicit one must): the step
/// follows the accuracy of the nonlinear remainder, which for a mechanism driven slowly
/// through lightly damped resonances is the slow motion. Each step costs three evaluations of
/// the right-hand side, a forward-difference Jacobian (`n + 1` more, counted in
/// [`Stats::rhs_evaluations`]; the Jacobians in [`Stats::jacobian_evaluations`]) and the
/// φ-functions of an `n × n` matrix; each interpolated point costs another set of
/// φ-functions. Suited to small systems (the φ-functions are dense, `O(n³)`).
///
/// The exact Jacobian is part of the method's order, so it is evaluated at every step.
/// Non-finite values reject the trial step and shrink the step by `fac_min`; if that drives
/// the step to underflow, the error is [`RuntimeError::NonFiniteState`]. Start from
/// [`AdaptiveOptions::rosenbrock`] for the step-size controller's usual settings.
pub type ExpRosenbrock<O> = AdaptiveStepper<O, ExpRosenbrockMethod>;

/// The working vectors of one step (length `n`); `F(y_n) = f(t, x)` is the shell's current
/// derivative.
pub struct ExpRosenbrockMethod {
    x_stage: Vec<f64>,
    f_stage: Vec<f64>,
    /// `∂f/∂x` and `∂f/∂t` at the start of the step.
    jacobian: Jacobian,
    /// φ-functions of `h·∂f/∂x` for `phi_h` (NaN: none, or of another argument).
    phi: PhiFunctions,
    phi_h: f64,
    /// `phi` holds the balancing of the Jacobian in `jacobian`.
    phi_balanced: bool,
    /// `D2`, `D3`, `h·φ1(hJ)·F` (the linearized flow), and scratch.
    d2: Vec<f64>,
    d3: Vec<f64>,
    flow: Vec<f64>,
    work: Vec<f64>,
    error: Vec<f64>,
    /// Dense output of the last step: `x` and `f(t, x)` at its start, `D2`, `D3` (with the
    /// Jacobian, still that of the last step).
    cont: [Vec<f64>; 4],
    cont_h: f64,
}

impl DenseWithStep for ExpRosenbrockMethod {}

impl AdaptiveMethod for ExpRosenbrockMethod {
    const ORDER: i32 = 4;
    const EVALUATIONS_PER_TRIAL: usize = 3;

    /// The error estimate is O(h⁴): exponent 1/4, less the Lund stabilisation.
    fn error_exponent(beta: f64) -> f64 {
        0.25 - 0.75 * beta
    }

    fn new(x0: &[f64]) -> Self {
        let n = x0.len();
        let zeros = vec![0.0; n];
        ExpRosenbrockMethod {
            x_stage: zeros.clone(),
            f_stage: zeros.clone(),
            jacobian: Jacobian::new(n),
            phi: PhiFunctions::new(n),
            phi_h: f64::NAN,
            phi_balanced: false,
            d2: zeros.clone(),
            d3: zeros.clone(),
            flow: zeros.clone(),
            work: zeros.clone(),
            error: zeros.clone(),
            cont: [x0.to_vec(), zeros.clone(), zeros.clone(), zeros],
            cont_h: 0.0,
        }
    }

    fn derivative_refreshed(&mut self) {
        self.jacobian.current = false;
    }

    /// A trial step of size `h` from `(t, x)`: `x_new`, `f_new = f(t + h, x_new)` (the step's
    /// end) and the scaled error norm. The Jacobian of the step, evaluated first, is counted
    /// in `stats`.
    // Indexed loops, so that each line reads as the formula at the top of the file.
    #[allow(clippy::needless_range_loop)]
    fn trial<O: Ode>(&mut self, ode: &mut O, step: Step<'_>) -> Result<f64, RuntimeError> {
        let (opts, now, next, t, h) = (step.opts, step.now, step.next, step.t, step.h);
        let (x_new, f_new) = (&mut next.x, &mut next.f);
        let n = now.x.len();
        if !self.jacobian.current {
            self.jacobian.evaluate(ode, t, &now.x, &now.f, step.stats)?;
            self.phi_h = f64::NAN;
            self.phi_balanced = false;
        }
        if !self.phi_at(h) {
            return Ok(f64::NAN);
        }
        // U2 = x + h/2·φ1(hJ/2)·F.
        self.linear_flow(true, 0.5 * h, &now.f);
        for i in 0..n {
            self.x_stage[i] = now.x[i] + self.flow[i];
        }
        ode.rhs(t + 0.5 * h, &self.x_stage, &mut self.f_stage)?;
        let mut d2 = std::mem::take(&mut self.d2);
        self.remainder(now, 0.5 * h, &mut d2);
        self.d2 = d2;

        // The flow h·φ1·F, and U3 = x + h·φ1·F + h·φ1·D2.
        self.linear_flow(false, h, &now.f);
        self.work.fill(0.0);
        self.phi.add_apply(1, &self.d2, &mut self.work);
        for i in 0..n {
            self.x_stage[i] = now.x[i] + self.flow[i] + h * self.work[i];
        }
        ode.rhs(t + h, &self.x_stage, &mut self.f_stage)?;
        let mut d3 = std::mem::take(&mut self.d3);
        self.remainder(now, h, &mut d3);
        self.d3 = d3;

        // x_new = x + h·φ1·F + φ3·w3 + φ4·w4, error φ4·w4.
        for i in 0..n {
            self.work[i] = h * (16.0 * self.d2[i] - 2.0 * self.d3[i]);
            x_new[i] = now.x[i] + self.flow[i];
        }
        self.error.fill(0.0);
        self.phi.add_apply(3, &self.work, &mut self.error);
        for i in 0..n {
            x_new[i] += self.error[i];
            self.work[i] = h * (-48.0 * self.d2[i] + 12.0 * self.d3[i]);
        }
        self.error.fill(0.0);
        self.phi.add_apply(4, &self.work, &mut self.error);
        for i in 0..n {
            x_new[i] += self.error[i];
        }
        ode.rhs(t + h, x_new, f_new)?;

        let error = |i: usize| self.error[i];
        Ok(error_norm(opts, &now.x, x_new, f_new, error))
    }

    fn accept<O: Ode>(&mut self, _ode: &mut O, step: Step<'_>) -> Result<(), RuntimeError> {
        self.store_dense(step.now, step.h);
        // The Jacobian of the last step stays for its dense output; the next step starts
        // with a new one.
        self.jacobian.current = false;
        Ok(())
    }

    fn interpolate(&mut self, t: f64, theta: f64, out: &mut [f64]) -> Result<(), RuntimeError> {
        let n = out.len();
        out.copy_from_slice(&self.cont[0]);
        if theta == 0.0 {
            return Ok(());
        }
        let tau = theta * self.cont_h;
        if !self.phi_at(tau) {
            return Err(RuntimeError::NonFiniteState { t });
        }
        // The derivative at the step's start, taken out of `cont` for the call.
        let f = std::mem::take(&mut self.cont[1]);
        self.linear_flow(false, tau, &f);
        self.cont[1] = f;
        for (o, w) in out.iter_mut().zip(&self.flow) {
            *o += w;
        }
        let [_, _, d2, d3] = &self.cont;
        let (a, b) = (2.0 * theta * theta * tau, 6.0 * theta.powi(3) * tau);
        for (order, coefficients) in [(3, (8.0 * a, -a)), (4, (-8.0 * b, 2.0 * b))] {
            for i in 0..n {
                self.error[i] = coefficients.0 * d2[i] + coefficients.1 * d3[i];
            }
            self.work.fill(0.0);
            self.phi.add_apply(order, &self.error, &mut self.work);
            for (o, w) in out.iter_mut().zip(&self.work) {
                *o += w;
            }
        }
        Ok(())
    }
}

impl ExpRosenbrockMethod {
    /// The φ-functions of `τ·∂f/∂x`; false if not finite.
    fn phi_at(&mut self, tau: f64) -> bool {
        if self.phi_h == tau {
            return true;
        }
        let ok = self
            .phi
            .compute_multiple(&self.jacobian.dfdx, tau, !self.phi_balanced);
        // A non-finite Jacobian leaves the balancing's norm NaN: every τ fails.
        self.phi_balanced = true;
        self.phi_h = if ok { tau } else { f64::NAN };
        ok
    }

    /// `flow = τ·φ1(τJ)·[f; 1] = τ·(φ1(τ∂f/∂x)·f + τ·φ2(τ∂f/∂x)·∂f/∂t)` for the φ-functions
    /// at `τ` (`half`: at `τ` for the functions of half the argument).
    fn linear_flow(&mut self, half: bool, tau: f64, f: &[f64]) {
        let (phi, out, work) = (&mut self.phi, &mut self.flow, &mut self.work);
        out.fill(0.0);
        for (w, d) in work.iter_mut().zip(&self.jacobian.dfdt) {
            *w = tau * d;
        }
        if half {
            phi.add_apply_half(1, f, out);
            phi.add_apply_half(2, work, out);
        } else {
            phi.add_apply(1, f, out);
            phi.add_apply(2, work, out);
        }
        for o in out.iter_mut() {
            *o *= tau;
        }
    }

    /// `D = f(t + c·h, x_stage) − f0 − J (x_stage − x) − ∂f/∂t·c·h` into `d`, from `f_stage`.
    fn remainder(&self, now: &Point, ch: f64, d: &mut [f64]) {
        let n = now.x.len();
        let (dfdx, dfdt) = (&self.jacobian.dfdx, &self.jacobian.dfdt);
        for (((d, f), f0), dfdt) in d.iter_mut().zip(&self.f_stage).zip(&now.f).zip(dfdt) {
            *d = f - f0 - dfdt * ch;
        }
        for j in 0..n {
            let dx = self.x_stage[j] - now.x[j];
            for (i, di) in d.iter_mut().enumerate() {
                *di -= dfdx[i + n * j] * dx;
            }
        }
    }

    /// Keeps what the dense output of the accepted step of size `h` needs.
    fn store_dense(&mut self, now: &Point, h: f64) {
        let [x0, f, d2, d3] = &mut self.cont;
        x0.copy_from_slice(&now.x);
        f.copy_from_slice(&now.f);
        d2.copy_from_slice(&self.d2);
        d3.copy_from_slice(&self.d3);
        self.cont_h = h;
    }
}
