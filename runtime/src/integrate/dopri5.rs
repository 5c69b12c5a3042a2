//! Dormand–Prince 5(4) (Hairer's `DOPRI5`).

use super::{
    check_len, derivative_at, interp_theta, Adaptive, AdaptiveOptions, Ode, Stats, Stepper,
};
use crate::RuntimeError;

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
    control: Adaptive,
    /// The state was modified through `state_mut`; `k1` is stale.
    dirty: bool,
    stages: Stages,
}

/// The working vectors of one step.
struct Stages {
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
        opts: AdaptiveOptions,
    ) -> Result<Self, RuntimeError> {
        let mut control = Adaptive::new(opts, 0.2 - opts.beta * 0.75, 6, t0, t_end)?;
        let k1 = control.start(&mut ode, 5, x0)?;
        let n = x0.len();
        let zeros = vec![0.0; n];
        let (x_stage, k2) = (zeros.clone(), zeros.clone());
        Ok(Dopri5 {
            ode,
            control,
            dirty: false,
            stages: Stages {
                x: x0.to_vec(),
                x_new: zeros.clone(),
                x_stage,
                k1,
                k2,
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

    /// Derivative `f(t, x)` at the current state (stale between [`Stepper::state_mut`] and the
    /// next [`Stepper::reset`] or [`Stepper::step`]).
    pub fn derivative(&self) -> &[f64] {
        &self.stages.k1
    }
}

impl Stages {
    /// Computes the six stages of a trial step of size `h` from `(t, x)`: `x_new` holds the
    /// 5th-order solution, `k7` its derivative, and the return value is the scaled error norm
    /// (NaN if anything is non-finite).
    fn trial<O: Ode>(
        &mut self,
        ode: &mut O,
        opts: &AdaptiveOptions,
        t: f64,
        h: f64,
    ) -> Result<f64, RuntimeError> {
        let n = self.x.len();
        for i in 0..n {
            self.x_stage[i] = self.x[i] + h * A21 * self.k1[i];
        }
        ode.rhs(t + C2 * h, &self.x_stage, &mut self.k2)?;
        for i in 0..n {
            self.x_stage[i] = self.x[i] + h * (A31 * self.k1[i] + A32 * self.k2[i]);
        }
        ode.rhs(t + C3 * h, &self.x_stage, &mut self.k3)?;
        for i in 0..n {
            self.x_stage[i] =
                self.x[i] + h * (A41 * self.k1[i] + A42 * self.k2[i] + A43 * self.k3[i]);
        }
        ode.rhs(t + C4 * h, &self.x_stage, &mut self.k4)?;
        for i in 0..n {
            self.x_stage[i] = self.x[i]
                + h * (A51 * self.k1[i] + A52 * self.k2[i] + A53 * self.k3[i] + A54 * self.k4[i]);
        }
        ode.rhs(t + C5 * h, &self.x_stage, &mut self.k5)?;
        for i in 0..n {
            self.x_stage[i] = self.x[i]
                + h * (A61 * self.k1[i]
                    + A62 * self.k2[i]
                    + A63 * self.k3[i]
                    + A64 * self.k4[i]
                    + A65 * self.k5[i]);
        }
        let t_new = t + h;
        ode.rhs(t_new, &self.x_stage, &mut self.k6)?;
        for i in 0..n {
            self.x_new[i] = self.x[i]
                + h * (A71 * self.k1[i]
                    + A73 * self.k3[i]
                    + A74 * self.k4[i]
                    + A75 * self.k5[i]
                    + A76 * self.k6[i]);
        }
        ode.rhs(t_new, &self.x_new, &mut self.k7)?;

        let (rtol, atol) = (opts.rtol, opts.atol);
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
        let Dopri5 {
            ode,
            control,
            stages,
            ..
        } = self;
        let opts = control.opts;
        if let Some(h) = control.advance(|t, h| stages.trial(ode, &opts, t, h))? {
            stages.store_dense(h);
            std::mem::swap(&mut stages.x, &mut stages.x_new);
            std::mem::swap(&mut stages.k1, &mut stages.k7);
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
        derivative_at(&mut self.ode, t, &s.x, &mut s.k1)?;
        self.dirty = false;
        Ok(())
    }

    fn interpolate(&mut self, t: f64, out: &mut [f64]) -> Result<(), RuntimeError> {
        let s = &self.stages;
        check_len("out", s.x.len(), out.len())?;
        let theta = interp_theta(t, self.control.t_prev, self.control.t)?;
        if theta == 1.0 {
            out.copy_from_slice(&s.x);
            return Ok(());
        }
        let theta1 = 1.0 - theta;
        let [c0, c1, c2, c3, c4] = &s.cont;
        for (i, o) in out.iter_mut().enumerate() {
            *o = c0[i] + theta * (c1[i] + theta1 * (c2[i] + theta * (c3[i] + theta1 * c4[i])));
        }
        Ok(())
    }

    fn set_t_end(&mut self, t_end: f64) -> Result<(), RuntimeError> {
        self.control.set_t_end(t_end)
    }

    fn stats(&self) -> Stats {
        self.control.stats
    }
}
