//! Classical fixed-step Runge–Kutta of order 4.
//!
//! Consumes an [`Ode`], a start, an end time and the step; produces the states on the step
//! grid and the cubic Hermite interpolant between them.

use super::{
    all_finite, begin_interpolation, check_len, check_times, derivative_at, hermite, Ode, Stats,
    Stepper,
};
use crate::RuntimeError;

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
        let zeros = vec![0.0; n];
        let mut f = zeros.clone();
        derivative_at(&mut ode, t0, x0, &mut f)?;
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
        self.stats.rhs_evaluations += 1;
        derivative_at(&mut self.ode, self.t, &self.x, &mut self.f)?;
        self.dirty = false;
        Ok(())
    }

    fn interpolate(&mut self, t: f64, out: &mut [f64]) -> Result<(), RuntimeError> {
        let Some(s) = begin_interpolation(t, self.t_prev, self.t, &self.x, out)? else {
            return Ok(());
        };
        let h = self.t - self.t_prev;
        let (start, end) = (
            (&self.x_prev[..], &self.f_prev[..]),
            (&self.x[..], &self.f[..]),
        );
        hermite(s, h, start, end, out);
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
