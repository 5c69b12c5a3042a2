//! Dormand–Prince 5(4) (Hairer's `DOPRI5`): the stages, error estimate and continuous
//! extension that the adaptive shell ([`AdaptiveStepper`]) steps with.
//!
//! Consumes the right-hand side through the shell; produces the 5th-order solution of each
//! step, its scaled error norm and the coefficients of Shampine's 4th-order dense output.

use super::adaptive::{error_norm, AdaptiveMethod, DenseWithStep, Point, Step};
use super::{AdaptiveStepper, Ode};
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
pub type Dopri5<O> = AdaptiveStepper<O, Dopri5Method>;

/// The stages of [`Dopri5`]: the working vectors of one step and the dense output of the last.
/// `k1 = f(t, x)` is the shell's current derivative, `k7 = f(t + h, x_new)` the derivative at
/// the step's end.
pub struct Dopri5Method {
    x_stage: Vec<f64>,
    k2: Vec<f64>,
    k3: Vec<f64>,
    k4: Vec<f64>,
    k5: Vec<f64>,
    k6: Vec<f64>,
    /// Dense output coefficients of the last step.
    cont: [Vec<f64>; 5],
}

impl<O: Ode> Dopri5<O> {
    /// Derivative `f(t, x)` at the current state (stale between [`Stepper::state_mut`] and the
    /// next [`Stepper::reset`] or [`Stepper::step`]).
    ///
    /// [`Stepper::state_mut`]: super::Stepper::state_mut
    /// [`Stepper::reset`]: super::Stepper::reset
    /// [`Stepper::step`]: super::Stepper::step
    pub fn derivative(&self) -> &[f64] {
        &self.now.f
    }
}

impl DenseWithStep for Dopri5Method {}

impl AdaptiveMethod for Dopri5Method {
    const ORDER: i32 = 5;
    const EVALUATIONS_PER_TRIAL: usize = 6;

    fn error_exponent(beta: f64) -> f64 {
        0.2 - beta * 0.75
    }

    fn new(x0: &[f64]) -> Self {
        let zeros = vec![0.0; x0.len()];
        Dopri5Method {
            x_stage: zeros.clone(),
            k2: zeros.clone(),
            k3: zeros.clone(),
            k4: zeros.clone(),
            k5: zeros.clone(),
            k6: zeros.clone(),
            cont: [
                x0.to_vec(),
                zeros.clone(),
                zeros.clone(),
                zeros.clone(),
                zeros,
            ],
        }
    }

    /// Computes the six stages of a trial step of size `h` from `(t, x)`: `x_new` (the step's
    /// end) holds the 5th-order solution and `k7` its derivative.
    fn trial<O: Ode>(&mut self, ode: &mut O, step: Step<'_>) -> Result<f64, RuntimeError> {
        let (opts, now, next, t, h) = (step.opts, step.now, step.next, step.t, step.h);
        let (x, k1) = (&now.x, &now.f);
        let (x_new, k7) = (&mut next.x, &mut next.f);
        let n = x.len();
        for i in 0..n {
            self.x_stage[i] = x[i] + h * A21 * k1[i];
        }
        ode.rhs(t + C2 * h, &self.x_stage, &mut self.k2)?;
        for i in 0..n {
            self.x_stage[i] = x[i] + h * (A31 * k1[i] + A32 * self.k2[i]);
        }
        ode.rhs(t + C3 * h, &self.x_stage, &mut self.k3)?;
        for i in 0..n {
            self.x_stage[i] = x[i] + h * (A41 * k1[i] + A42 * self.k2[i] + A43 * self.k3[i]);
        }
        ode.rhs(t + C4 * h, &self.x_stage, &mut self.k4)?;
        for i in 0..n {
            self.x_stage[i] =
                x[i] + h * (A51 * k1[i] + A52 * self.k2[i] + A53 * self.k3[i] + A54 * self.k4[i]);
        }
        ode.rhs(t + C5 * h, &self.x_stage, &mut self.k5)?;
        for i in 0..n {
            self.x_stage[i] = x[i]
                + h * (A61 * k1[i]
                    + A62 * self.k2[i]
                    + A63 * self.k3[i]
                    + A64 * self.k4[i]
                    + A65 * self.k5[i]);
        }
        let t_new = t + h;
        ode.rhs(t_new, &self.x_stage, &mut self.k6)?;
        for i in 0..n {
            x_new[i] = x[i]
                + h * (A71 * k1[i]
                    + A73 * self.k3[i]
                    + A74 * self.k4[i]
                    + A75 * self.k5[i]
                    + A76 * self.k6[i]);
        }
        ode.rhs(t_new, x_new, k7)?;

        let error = |i: usize| {
            (E1 * k1[i]
                + E3 * self.k3[i]
                + E4 * self.k4[i]
                + E5 * self.k5[i]
                + E6 * self.k6[i]
                + E7 * k7[i])
                * h
        };
        Ok(error_norm(opts, x, x_new, k7, error))
    }

    fn accept<O: Ode>(&mut self, _ode: &mut O, step: Step<'_>) -> Result<(), RuntimeError> {
        self.store_dense(step.now, step.next, step.h);
        Ok(())
    }

    fn interpolate(&mut self, _t: f64, theta: f64, out: &mut [f64]) -> Result<(), RuntimeError> {
        let theta1 = 1.0 - theta;
        let [c0, c1, c2, c3, c4] = &self.cont;
        for (i, o) in out.iter_mut().enumerate() {
            *o = c0[i] + theta * (c1[i] + theta1 * (c2[i] + theta * (c3[i] + theta1 * c4[i])));
        }
        Ok(())
    }
}

impl Dopri5Method {
    /// Stores the dense output coefficients of the step of size `h` from `now` to `next`.
    fn store_dense(&mut self, now: &Point, next: &Point, h: f64) {
        let (x, k1) = (&now.x, &now.f);
        let (x_new, k7) = (&next.x, &next.f);
        let [c0, c1, c2, c3, c4] = &mut self.cont;
        for i in 0..x.len() {
            let ydiff = x_new[i] - x[i];
            let bspl = h * k1[i] - ydiff;
            c0[i] = x[i];
            c1[i] = ydiff;
            c2[i] = bspl;
            c3[i] = -h * k7[i] + ydiff - bspl;
            c4[i] = h
                * (D1 * k1[i]
                    + D3 * self.k3[i]
                    + D4 * self.k4[i]
                    + D5 * self.k5[i]
                    + D6 * self.k6[i]
                    + D7 * k7[i]);
        }
    }
}
