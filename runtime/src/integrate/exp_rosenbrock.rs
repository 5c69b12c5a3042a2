//! Exponential Rosenbrock method `exprb43` of Hochbruck, Ostermann & Schweitzer.

use super::phi::PhiFunctions;
use super::{
    check_len, derivative_at, finite_difference_jacobian, interp_theta, Adaptive, AdaptiveOptions,
    Ode, Stats, Stepper,
};
use crate::RuntimeError;

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
/// the step to underflow, the error is [`RuntimeError::NonFiniteState`].
pub struct ExpRosenbrock<O: Ode> {
    ode: O,
    control: Adaptive,
    /// The state was modified through `state_mut`; `f0` is stale.
    dirty: bool,
    stages: Stages,
}

/// The working vectors of one step (length `n`).
struct Stages {
    x: Vec<f64>,
    /// `f(t, x)`.
    f0: Vec<f64>,
    x_new: Vec<f64>,
    f_new: Vec<f64>,
    x_stage: Vec<f64>,
    f_stage: Vec<f64>,
    /// `∂f/∂x` (`n × n`, column-major) and `∂f/∂t` at the start of the step.
    jacobian: Vec<f64>,
    dfdt: Vec<f64>,
    jacobian_current: bool,
    jacobian_evaluations: usize,
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

impl<O: Ode> ExpRosenbrock<O> {
    /// Creates the integrator at `(t0, x0)`, integrating toward `t_end >= t0`, and evaluates
    /// the derivative at `x0` (plus once more for the initial step-size heuristic). Use
    /// [`AdaptiveOptions::rosenbrock`] for the step-size controller's usual settings.
    pub fn new(
        mut ode: O,
        t0: f64,
        x0: &[f64],
        t_end: f64,
        opts: AdaptiveOptions,
    ) -> Result<Self, RuntimeError> {
        // The error estimate is O(h⁴): exponent 1/4, less the Lund stabilisation.
        let mut control = Adaptive::new(opts, 0.25 - 0.75 * opts.beta, 3, t0, t_end)?;
        let f0 = control.start(&mut ode, 4, x0)?;
        let n = x0.len();
        let zeros = vec![0.0; n];
        let (x_stage, f_stage) = (zeros.clone(), zeros.clone());
        Ok(ExpRosenbrock {
            ode,
            control,
            dirty: false,
            stages: Stages {
                x: x0.to_vec(),
                f0,
                x_new: zeros.clone(),
                f_new: zeros.clone(),
                x_stage,
                f_stage,
                jacobian: vec![0.0; n * n],
                dfdt: zeros.clone(),
                jacobian_current: false,
                jacobian_evaluations: 0,
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
            },
        })
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
    pub fn options(&self) -> &AdaptiveOptions {
        &self.control.opts
    }

    /// Step size that the next step will try (before clipping to the end time).
    pub fn next_step_size(&self) -> f64 {
        self.control.h
    }
}

impl Stages {
    /// The φ-functions of `τ·∂f/∂x`; false if not finite.
    fn phi_at(&mut self, tau: f64) -> bool {
        if self.phi_h == tau {
            return true;
        }
        let ok = self
            .phi
            .compute_multiple(&self.jacobian, tau, !self.phi_balanced);
        // A non-finite Jacobian leaves the balancing's norm NaN: every τ fails.
        self.phi_balanced = true;
        self.phi_h = if ok { tau } else { f64::NAN };
        ok
    }

    /// `out = τ·φ1(τJ)·[f; 1] = τ·(φ1(τ∂f/∂x)·f + τ·φ2(τ∂f/∂x)·∂f/∂t)` for the φ-functions at
    /// `τ` (`half`: at `τ` for the functions of half the argument).
    fn linear_flow(
        phi: &mut PhiFunctions,
        half: bool,
        tau: f64,
        f: &[f64],
        dfdt: &[f64],
        out: &mut [f64],
        work: &mut [f64],
    ) {
        out.fill(0.0);
        for (w, d) in work.iter_mut().zip(dfdt) {
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
    fn remainder(&self, ch: f64, d: &mut [f64]) {
        let n = self.x.len();
        for (((d, f), f0), dfdt) in d
            .iter_mut()
            .zip(&self.f_stage)
            .zip(&self.f0)
            .zip(&self.dfdt)
        {
            *d = f - f0 - dfdt * ch;
        }
        for j in 0..n {
            let dx = self.x_stage[j] - self.x[j];
            for (i, di) in d.iter_mut().enumerate() {
                *di -= self.jacobian[i + n * j] * dx;
            }
        }
    }

    /// A trial step of size `h` from `(t, x)`: `x_new`, `f_new = f(t + h, x_new)` and the
    /// scaled error norm (NaN if anything is non-finite). Returns the number of extra
    /// evaluations spent on the Jacobian.
    fn trial<O: Ode>(
        &mut self,
        ode: &mut O,
        opts: &AdaptiveOptions,
        t: f64,
        h: f64,
    ) -> Result<(f64, usize), RuntimeError> {
        let n = self.x.len();
        let mut extra = 0;
        if !self.jacobian_current {
            finite_difference_jacobian(
                ode,
                t,
                &self.x,
                &self.f0,
                &mut self.jacobian,
                &mut self.dfdt,
                &mut self.x_stage,
                &mut self.f_stage,
            )?;
            self.jacobian_evaluations += 1;
            self.jacobian_current = true;
            self.phi_h = f64::NAN;
            self.phi_balanced = false;
            extra = n + 1;
        }
        if !self.phi_at(h) {
            return Ok((f64::NAN, extra));
        }
        // U2 = x + h/2·φ1(hJ/2)·F.
        Self::linear_flow(
            &mut self.phi,
            true,
            0.5 * h,
            &self.f0,
            &self.dfdt,
            &mut self.flow,
            &mut self.work,
        );
        for i in 0..n {
            self.x_stage[i] = self.x[i] + self.flow[i];
        }
        ode.rhs(t + 0.5 * h, &self.x_stage, &mut self.f_stage)?;
        let mut d2 = std::mem::take(&mut self.d2);
        self.remainder(0.5 * h, &mut d2);
        self.d2 = d2;

        // The flow h·φ1·F, and U3 = x + h·φ1·F + h·φ1·D2.
        Self::linear_flow(
            &mut self.phi,
            false,
            h,
            &self.f0,
            &self.dfdt,
            &mut self.flow,
            &mut self.work,
        );
        self.work.fill(0.0);
        self.phi.add_apply(1, &self.d2, &mut self.work);
        for i in 0..n {
            self.x_stage[i] = self.x[i] + self.flow[i] + h * self.work[i];
        }
        ode.rhs(t + h, &self.x_stage, &mut self.f_stage)?;
        let mut d3 = std::mem::take(&mut self.d3);
        self.remainder(h, &mut d3);
        self.d3 = d3;

        // x_new = x + h·φ1·F + φ3·w3 + φ4·w4, error φ4·w4.
        for i in 0..n {
            self.work[i] = h * (16.0 * self.d2[i] - 2.0 * self.d3[i]);
            self.x_new[i] = self.x[i] + self.flow[i];
        }
        self.error.fill(0.0);
        self.phi.add_apply(3, &self.work, &mut self.error);
        for i in 0..n {
            self.x_new[i] += self.error[i];
            self.work[i] = h * (-48.0 * self.d2[i] + 12.0 * self.d3[i]);
        }
        self.error.fill(0.0);
        self.phi.add_apply(4, &self.work, &mut self.error);
        for i in 0..n {
            self.x_new[i] += self.error[i];
        }
        ode.rhs(t + h, &self.x_new, &mut self.f_new)?;

        let (rtol, atol) = (opts.rtol, opts.atol);
        let mut sum = 0.0;
        let mut finite = true;
        for i in 0..n {
            let sk = atol + rtol * self.x[i].abs().max(self.x_new[i].abs());
            sum += (self.error[i] / sk).powi(2);
            finite &= self.x_new[i].is_finite() && self.f_new[i].is_finite();
        }
        let err = (sum / n.max(1) as f64).sqrt();
        Ok((if finite { err } else { f64::NAN }, extra))
    }

    /// Keeps what the dense output of the accepted step of size `h` needs.
    fn store_dense(&mut self, h: f64) {
        let [x0, f, d2, d3] = &mut self.cont;
        x0.copy_from_slice(&self.x);
        f.copy_from_slice(&self.f0);
        d2.copy_from_slice(&self.d2);
        d3.copy_from_slice(&self.d3);
        self.cont_h = h;
    }
}

impl<O: Ode> Stepper for ExpRosenbrock<O> {
    fn step(&mut self) -> Result<(), RuntimeError> {
        self.reset()?;
        let ExpRosenbrock {
            ode,
            control,
            stages,
            ..
        } = self;
        let opts = control.opts;
        let mut extra = 0;
        let accepted = control.advance(|t, h| {
            let (err, spent) = stages.trial(ode, &opts, t, h)?;
            extra += spent;
            Ok(err)
        });
        control.stats.rhs_evaluations += extra;
        if let Some(h) = accepted? {
            stages.store_dense(h);
            std::mem::swap(&mut stages.x, &mut stages.x_new);
            std::mem::swap(&mut stages.f0, &mut stages.f_new);
            // The Jacobian of the last step stays for its dense output; the next step starts
            // with a new one.
            stages.jacobian_current = false;
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
        &self.stages.x
    }

    fn state_mut(&mut self) -> &mut [f64] {
        self.dirty = true;
        &mut self.stages.x
    }

    fn reset(&mut self) -> Result<(), RuntimeError> {
        if !self.dirty {
            return Ok(());
        }
        self.control.stats.rhs_evaluations += 1;
        let (t, s) = (self.control.t, &mut self.stages);
        derivative_at(&mut self.ode, t, &s.x, &mut s.f0)?;
        s.jacobian_current = false;
        self.dirty = false;
        Ok(())
    }

    fn interpolate(&mut self, t: f64, out: &mut [f64]) -> Result<(), RuntimeError> {
        let n = self.stages.x.len();
        check_len("out", n, out.len())?;
        let theta = interp_theta(t, self.control.t_prev, self.control.t)?;
        let s = &mut self.stages;
        if theta == 1.0 {
            out.copy_from_slice(&s.x);
            return Ok(());
        }
        out.copy_from_slice(&s.cont[0]);
        if theta == 0.0 {
            return Ok(());
        }
        let tau = theta * s.cont_h;
        if !s.phi_at(tau) {
            return Err(RuntimeError::NonFiniteState { t });
        }
        let [_, f, d2, d3] = &s.cont;
        Stages::linear_flow(&mut s.phi, false, tau, f, &s.dfdt, &mut s.flow, &mut s.work);
        for (o, w) in out.iter_mut().zip(&s.flow) {
            *o += w;
        }
        let (a, b) = (2.0 * theta * theta * tau, 6.0 * theta.powi(3) * tau);
        for (order, coefficients) in [(3, (8.0 * a, -a)), (4, (-8.0 * b, 2.0 * b))] {
            for i in 0..n {
                s.error[i] = coefficients.0 * d2[i] + coefficients.1 * d3[i];
            }
            s.work.fill(0.0);
            s.phi.add_apply(order, &s.error, &mut s.work);
            for (o, w) in out.iter_mut().zip(&s.work) {
                *o += w;
            }
        }
        Ok(())
    }

    fn set_t_end(&mut self, t_end: f64) -> Result<(), RuntimeError> {
        self.control.set_t_end(t_end)
    }

    fn stats(&self) -> Stats {
        Stats {
            jacobian_evaluations: self.stages.jacobian_evaluations,
            ..self.control.stats
        }
    }
}
