//! Simulation of a [`Model`]: the first-order form of its equations of motion, and a driver
//! that integrates it and samples the trajectory on a regular output grid.
//!
//! Two formulations: in full coordinates ([`simulate`] with the explicit methods) the state is
//! `x = [q; u]` and `ẋ = [W(q) u; M(q)⁻¹·F(t, q, u, inputs)]` (`W = I` unless the model has unit
//! quaternions, which are scaled back to unit norm after every step and at every sample),
//! and loops are held by projection after every step; in minimal coordinates ([`simulate_reduced`], and [`simulate`] with the
//! Rosenbrock methods) the state is `[z; ż]` of the independent coordinates ([`Reduced`]),
//! which closes the loops at every evaluation, and each sample is closed again from its `z`. The accelerations are
//! obtained by a Cholesky factorisation of `M` (symmetric positive definite for a well-posed
//! model); if `M` is not symmetric, or Cholesky fails or is ill-conditioned, by LU with partial
//! pivoting. The inputs are evaluated from one [`Signal`] per model input, in the model's input
//! order.

use crate::constraints::{choose_independent, jacobian, ConstrainedSolver};
use crate::integrate::{
    check_len, AdaptiveOptions, Dop853, Dopri5, ExpRosenbrock, Ode, Rk4, Ros34pw2, Rosenbrock,
    Stats, Stepper,
};
use crate::model::normalize_quaternions;
use crate::reduced::Reduced;
pub use crate::signal::default_signals;
use crate::signal::{check_inputs, values_at};
use crate::{dense, Model, RuntimeError, Signal};
use nalgebra::{Cholesky, DMatrix, DVector};

/// Integration method of [`simulate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    /// Adaptive Dormand–Prince 5(4) ([`Dopri5`]); see [`AdaptiveOptions`] for the error test.
    Dopri5 {
        /// Relative tolerance (≥ 0).
        rtol: f64,
        /// Absolute tolerance (> 0), in the units of each state component (q and u alike).
        atol: f64,
        /// Largest step in seconds (> 0; `f64::INFINITY` for no limit).
        h_max: f64,
    },
    /// Adaptive Dormand–Prince 8(5,3) ([`Dop853`]) with Hairer's `DOP853` controller
    /// settings: fewer evaluations than `Dopri5` at tight tolerances (≲ 1e-7).
    Dop853 {
        /// Relative tolerance (≥ 0).
        rtol: f64,
        /// Absolute tolerance (> 0), in the units of each state component.
        atol: f64,
        /// Largest step in seconds (> 0; `f64::INFINITY` for no limit).
        h_max: f64,
    },
    /// Classical fixed-step RK4 ([`Rk4`]).
    Rk4 {
        /// Step size in seconds (> 0).
        step: f64,
    },
    /// Linearly implicit Rosenbrock 2(3) ([`Rosenbrock`], `ode23s`), L-stable, on the reduced
    /// dynamics: fast modes are damped, so the step follows the slow motion once they have
    /// decayed below the tolerance. Error test on `[z; ż]`.
    Rosenbrock {
        /// Relative tolerance (≥ 0).
        rtol: f64,
        /// Absolute tolerance (> 0), in the units of each reduced state component.
        atol: f64,
        /// Largest step in seconds (> 0; `f64::INFINITY` for no limit).
        h_max: f64,
    },
    /// The Rosenbrock W-method ROS34PW2 ([`Ros34pw2`]: order 3, embedded order 2, L-stable)
    /// in full coordinates `[q; u]` (loops projected, quaternions allowed, as
    /// [`Method::Dopri5`]), implicit in the contacts' damping only:
    /// `J̃ = [[0, W(q)], [0, S D]]` with `D` the model's [`Model::contact_damping`] and `S` the
    /// loops' constrained inverse of `M`, so each stage solves `(M − γD) y + Jᵀν = γ D r`,
    /// `J y = 0` ([`ConstrainedSolver`]). A W-method keeps its order with any `J̃`; taking the
    /// regularized friction's damper of a light foot implicitly lifts the explicit methods'
    /// stability limit on the step. For models without contacts it is an explicit method of
    /// order 3 (no use).
    RosenbrockW {
        /// Relative tolerance (≥ 0).
        rtol: f64,
        /// Absolute tolerance (> 0), in the units of each state component (q and u alike).
        atol: f64,
        /// Largest step in seconds (> 0; `f64::INFINITY` for no limit).
        h_max: f64,
    },
    /// Exponential Rosenbrock 4(3) ([`ExpRosenbrock`], `exprb43`) on the reduced dynamics:
    /// the linearization over each step is integrated exactly, so lightly damped fast modes
    /// are followed at steps longer than their period. Error test on `[z; ż]`.
    ExpRosenbrock {
        /// Relative tolerance (≥ 0).
        rtol: f64,
        /// Absolute tolerance (> 0), in the units of each reduced state component.
        atol: f64,
        /// Largest step in seconds (> 0; `f64::INFINITY` for no limit).
        h_max: f64,
    },
}

impl Method {
    /// Whether the method integrates the reduced dynamics (also when given to [`simulate`]).
    pub fn is_reduced(&self) -> bool {
        matches!(
            self,
            Method::Rosenbrock { .. } | Method::ExpRosenbrock { .. }
        )
    }
}

impl Default for Method {
    /// `Dopri5` with `rtol = 1e-8`, `atol = 1e-10` and no step limit.
    fn default() -> Self {
        Method::Dopri5 {
            rtol: 1e-8,
            atol: 1e-10,
            h_max: f64::INFINITY,
        }
    }
}

/// Options of [`simulate`]. Times are in seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimOptions {
    /// Start time (default `0`).
    pub t_start: f64,
    /// End time, ≥ `t_start` (default `1`).
    pub t_end: f64,
    /// Spacing of the returned samples (> 0; default `1e-3`, i.e. 1 kHz). Samples are taken at
    /// `t_start + k·output_interval` and at `t_end`, by dense output: the interval does not
    /// restrict the integrator's steps.
    pub output_interval: f64,
    /// Integration method (default [`Method::default`]).
    pub method: Method,
    /// Budget of integration steps, accepted and rejected (default `1_000_000`).
    pub max_steps: usize,
    /// For models with loop closures, in full coordinates: after every accepted step (and at
    /// every sample) the state is projected back until `max |φ(q)| ≤ constraint_tolerance`
    /// (model units, SI; default `1e-12`) and, when `max |J u|` exceeds the same number (per
    /// second), onto `J u = 0` (kinetic-energy-closest correction). A state already within
    /// both is left as it is (and the integrator keeps its derivative there). In minimal
    /// coordinates: the loops are closed to `max |φ(q)| ≤ constraint_tolerance` at every
    /// evaluation and sample (`J u = 0` holds by construction).
    pub constraint_tolerance: f64,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            t_start: 0.0,
            t_end: 1.0,
            output_interval: 1e-3,
            method: Method::default(),
            max_steps: 1_000_000,
            constraint_tolerance: 1e-12,
        }
    }
}

/// A sampled simulation result. The outer index of every `Vec<Vec<f64>>` is the sample
/// (matching `times`), the inner one the model's coordinate, speed, output or input index.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trajectory {
    /// Sample times in seconds: `t_start + k·output_interval`, then `t_end`.
    pub times: Vec<f64>,
    /// Generalized coordinates `q` at each sample.
    pub q: Vec<Vec<f64>>,
    /// Generalized speeds `u = q̇` at each sample.
    pub u: Vec<Vec<f64>>,
    /// Model outputs `y(t, q, u, inputs)` at each sample.
    pub outputs: Vec<Vec<f64>>,
    /// Input values (from the signals) at each sample.
    pub inputs: Vec<Vec<f64>>,
    /// Integrator work counters.
    pub stats: Stats,
}

impl Trajectory {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }
}

/// Workspace for solving `M u̇ = F` without allocating.
struct AccelSolver {
    mass: DMatrix<f64>,
    factor: DMatrix<f64>,
    force: DVector<f64>,
    pivots: Vec<usize>,
}

impl AccelSolver {
    fn new(nu: usize) -> Self {
        AccelSolver {
            mass: DMatrix::zeros(nu, nu),
            factor: DMatrix::zeros(nu, nu),
            force: DVector::zeros(nu),
            pivots: vec![0; nu],
        }
    }

    /// Solves `M u̇ = F` into `udot`. Errors: [`RuntimeError::SingularMassMatrix`], or
    /// [`RuntimeError::NonFiniteState`] with `udot` NaN if `M`, `F` or `u̇` is not finite.
    fn solve<M: Model + ?Sized>(
        &mut self,
        model: &M,
        t: f64,
        q: &[f64],
        u: &[f64],
        inputs: &[f64],
        udot: &mut [f64],
    ) -> Result<(), RuntimeError> {
        model.mass_matrix(t, q, inputs, self.mass.as_mut_slice());
        model.forcing(t, q, u, inputs, self.force.as_mut_slice());
        let finite = |s: &[f64]| s.iter().all(|v| v.is_finite());
        if !finite(self.mass.as_slice()) || !finite(self.force.as_slice()) {
            udot.fill(f64::NAN);
            return Err(RuntimeError::NonFiniteState { t });
        }
        // A factorisation with acceptable pivots and a non-finite result means F overflowed
        // through M⁻¹ (not a singular M): report it as non-finite.
        let factored = (self.is_symmetric() && self.cholesky(udot)) || self.lu(udot);
        if !factored {
            Err(RuntimeError::SingularMassMatrix { t })
        } else if finite(udot) {
            Ok(())
        } else {
            udot.fill(f64::NAN);
            Err(RuntimeError::NonFiniteState { t })
        }
    }

    /// Symmetric to 1e-10 relative to the largest entry.
    fn is_symmetric(&self) -> bool {
        let n = self.mass.nrows();
        let scale = self.mass.amax();
        (0..n).all(|j| {
            (j + 1..n).all(|i| (self.mass[(i, j)] - self.mass[(j, i)]).abs() <= 1e-10 * scale)
        })
    }

    /// Cholesky solve into `udot`; false if `M` is not (numerically) positive definite:
    /// `min_j L_jj² <= ε·max_j M_jj`, which implies `cond(M) >= 1/ε`.
    fn cholesky(&mut self, udot: &mut [f64]) -> bool {
        let n = self.mass.nrows();
        self.factor.copy_from(&self.mass);
        // Factor in place: move the storage into the decomposition and take it back after.
        let storage = std::mem::replace(&mut self.factor, DMatrix::zeros(0, 0));
        let chol = Cholesky::new_unchecked(storage);
        let l = chol.l_dirty();
        let max_diag = (0..n).map(|j| self.mass[(j, j)]).fold(0.0, f64::max);
        let ok = (0..n).all(|j| {
            let d = l[(j, j)];
            d.is_finite() && d > 0.0 && d * d > f64::EPSILON * max_diag
        });
        if ok {
            let mut rhs = nalgebra::DVectorViewMut::from_slice(udot, n);
            rhs.copy_from(&self.force);
            chol.solve_mut(&mut rhs);
        }
        self.factor = chol.unpack_dirty();
        ok
    }

    /// LU with partial pivoting (in `factor`) and solve into `udot`; false if a pivot is
    /// below `n·ε·max|M_ij|`.
    fn lu(&mut self, udot: &mut [f64]) -> bool {
        let n = self.mass.nrows();
        self.factor.copy_from(&self.mass);
        if !dense::lu(self.factor.as_mut_slice(), n, &mut self.pivots) {
            return false;
        }
        udot.copy_from_slice(self.force.as_slice());
        dense::lu_solve(self.factor.as_slice(), n, &self.pivots, udot);
        true
    }
}

/// A [`Model`] driven by input [`Signal`]s, as a first-order [`Ode`] on `x = [q; u]`:
/// `ẋ = [W(q) u; M(q)⁻¹·F(t, q, u, inputs(t))]` ([`Model::kinematic_rates`]).
///
/// Holds preallocated storage for `M`, `F`, the factorisation and the inputs, so evaluating the
/// right-hand side never allocates. A non-finite `M`, `F` or `u̇` yields a NaN derivative (which
/// makes the adaptive integrator retry with a smaller step, and eventually report
/// [`RuntimeError::NonFiniteState`]); a singular `M` is [`RuntimeError::SingularMassMatrix`].
pub struct ModelOde<'a, M: Model + ?Sized> {
    model: &'a M,
    signals: &'a [Signal],
    nq: usize,
    nu: usize,
    inputs: Vec<f64>,
    solver: AccelSolver,
    /// Present for models with loop closures: `M u̇ = F + Jᵀλ`, `J u̇ = −J̇u`.
    constrained: Option<ConstrainedSolver>,
    /// Present for [`Method::RosenbrockW`]: the W-method's linear solve.
    implicit: Option<ContactImplicit>,
}

/// The linear solve of [`Method::RosenbrockW`]: `(I − γ J̃) k = r` with
/// `J̃ = [[0, W(q)], [0, S D]]` ([`Ode::prepare_implicit`]). With `y = k_u − r_u`:
/// `(M − γD) y + Jᵀν = γ D r_u`, `J y = 0` (since `k_u = r_u + γ S D k_u` and `S` maps into
/// `J`'s null space), then `k_q = r_q + γ W(q) k_u`.
struct ContactImplicit {
    solver: ConstrainedSolver,
    /// `D` at the prepared point (zero for a model without it), `nu × nu`.
    damping: Vec<f64>,
    gamma: f64,
    t: f64,
    q: Vec<f64>,
    /// `γ D r_u`, then `y`; and `W(q) k_u`.
    speeds: Vec<f64>,
    rates: Vec<f64>,
    /// The loops' projection of each accepted step ([`Ode::correct`],
    /// [`SimOptions::constraint_tolerance`]).
    tolerance: f64,
}

impl<'a, M: Model + ?Sized> ModelOde<'a, M> {
    /// Wraps `model` with one signal per model input. Errors if `signals` has the wrong length,
    /// a signal is invalid, or `nq != nu` without quaternions.
    pub fn new(model: &'a M, signals: &'a [Signal]) -> Result<Self, RuntimeError> {
        let (nq, nu) = (model.nq(), model.nu());
        if nq != nu && model.unit_quaternions().is_empty() {
            return Err(RuntimeError::InvalidOptions(format!(
                "model `{}` has {nq} coordinates but {nu} speeds and no unit quaternion; \
                 simulation knows q̇ = W(q) u only for quaternions",
                model.name()
            )));
        }
        check_inputs(model, signals)?;
        Ok(ModelOde {
            model,
            signals,
            nq,
            nu,
            inputs: vec![0.0; model.ninputs()],
            solver: AccelSolver::new(nu),
            constrained: (model.nc() > 0).then(|| ConstrainedSolver::new(nq, nu, model.nc())),
            implicit: None,
        })
    }

    /// The same system, offering [`Method::RosenbrockW`]'s linear solve
    /// ([`Ode::prepare_implicit`]) and the correction of its accepted steps
    /// ([`Ode::correct`]: quaternions to unit norm, the loops projected to `tolerance`).
    pub fn implicit_in_contacts(mut self, tolerance: f64) -> Self {
        let (nq, nu) = (self.nq, self.nu);
        self.implicit = Some(ContactImplicit {
            solver: ConstrainedSolver::new(nq, nu, self.model.nc()),
            damping: vec![0.0; nu * nu],
            gamma: 0.0,
            t: 0.0,
            q: vec![0.0; nq],
            speeds: vec![0.0; nu],
            rates: vec![0.0; nq],
            tolerance,
        });
        self
    }

    /// The wrapped model.
    pub fn model(&self) -> &'a M {
        self.model
    }

    /// The input signals.
    pub fn signals(&self) -> &'a [Signal] {
        self.signals
    }

    /// Writes the input values at time `t` into `out` (length `ninputs`).
    pub fn inputs_at(&self, t: f64, out: &mut [f64]) {
        values_at(self.signals, t, out);
    }

    /// Solves `M(q) u̇ = F(t, q, u, inputs)` for `u̇` with the given input values (the signals
    /// are not used). Errors: [`RuntimeError::SingularMassMatrix`] or, if `M`, `F` or the
    /// result is not finite, [`RuntimeError::NonFiniteState`].
    pub fn accelerations(
        &mut self,
        t: f64,
        q: &[f64],
        u: &[f64],
        inputs: &[f64],
        udot: &mut [f64],
    ) -> Result<(), RuntimeError> {
        check_len("q", self.nq, q.len())?;
        check_len("u", self.nu, u.len())?;
        check_len("inputs", self.inputs.len(), inputs.len())?;
        check_len("udot", self.nu, udot.len())?;
        self.inputs.copy_from_slice(inputs);
        self.solve(t, q, u, udot)
    }

    /// The constraint multipliers `λ` of the last [`accelerations`](Self::accelerations) (rows
    /// found redundant hold zero; `M u̇ = F + Jᵀλ`); empty for a model without loops.
    pub fn multipliers(&self) -> &[f64] {
        self.constrained
            .as_ref()
            .map_or(&[], ConstrainedSolver::multipliers)
    }

    /// `u̇` at `(t, q, u)` under the input values in `self.inputs`, with the loops closed where
    /// the model has them. A non-finite `u̇` is [`RuntimeError::NonFiniteState`], `udot` NaN.
    fn solve(
        &mut self,
        t: f64,
        q: &[f64],
        u: &[f64],
        udot: &mut [f64],
    ) -> Result<(), RuntimeError> {
        match &mut self.constrained {
            Some(constrained) => constrained.accelerations(self.model, t, q, u, &self.inputs, udot),
            None => self.solver.solve(self.model, t, q, u, &self.inputs, udot),
        }
    }
}

/// An [`Ode`] of a model's motion whose state gives the model's `(q, u)`.
trait MotionOde: Ode {
    /// `q` and `u` at the state `x` of the last [`Ode::rhs`] call.
    fn motion<'s>(&'s self, x: &'s [f64]) -> (&'s [f64], &'s [f64]);
}

impl<M: Model + ?Sized> MotionOde for ModelOde<'_, M> {
    fn motion<'s>(&'s self, x: &'s [f64]) -> (&'s [f64], &'s [f64]) {
        x[..self.nq + self.nu].split_at(self.nq)
    }
}

impl<M: Model + ?Sized> MotionOde for Reduced<'_, M> {
    fn motion<'s>(&'s self, _x: &'s [f64]) -> (&'s [f64], &'s [f64]) {
        (self.q(), self.u())
    }
}

/// The motion `x` extended by the integrals `w` of the model's integrated outputs
/// ([`Model::integrated_outputs`]): `[x; w]` with `ẇ_j = y_rate_j(t, q, u, inputs)`. So an
/// integral such as a contact's dissipated energy is integrated by the same method, under
/// the same error test and step-size control as the motion, rather than summed afterwards
/// from samples (which would miss what happens between them).
struct Integrating<'a, O, M: Model + ?Sized> {
    inner: O,
    model: &'a M,
    signals: &'a [Signal],
    /// `dim` of the motion.
    motion: usize,
    rates: Vec<usize>,
    inputs: Vec<f64>,
    outputs: Vec<f64>,
}

impl<'a, O: MotionOde, M: Model + ?Sized> Integrating<'a, O, M> {
    fn new(inner: O, model: &'a M, signals: &'a [Signal]) -> Self {
        let rates = model.integrated_outputs().iter().map(|&(_, r)| r).collect();
        Integrating {
            motion: inner.dim(),
            inner,
            model,
            signals,
            rates,
            inputs: vec![0.0; signals.len()],
            outputs: vec![0.0; model.noutputs()],
        }
    }
}

impl<O: MotionOde, M: Model + ?Sized> Ode for Integrating<'_, O, M> {
    fn dim(&self) -> usize {
        self.motion + self.rates.len()
    }

    fn rhs(&mut self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), RuntimeError> {
        let (motion, rates) = dxdt.split_at_mut(self.motion);
        self.inner.rhs(t, &x[..self.motion], motion)?;
        if self.rates.is_empty() {
            return Ok(());
        }
        values_at(self.signals, t, &mut self.inputs);
        let (q, u) = self.inner.motion(&x[..self.motion]);
        let selected = self.model.selected_outputs(
            t,
            q,
            u,
            &self.inputs,
            &self.rates,
            &mut self.outputs[..self.rates.len()],
        );
        if selected {
            rates.copy_from_slice(&self.outputs[..self.rates.len()]);
        } else {
            self.model.outputs(t, q, u, &self.inputs, &mut self.outputs);
            for (rate, &index) in rates.iter_mut().zip(&self.rates) {
                *rate = self.outputs[index];
            }
        }
        Ok(())
    }

    /// The integrals' rows of `J̃` are zero: their part of `k` is `r`'s.
    fn prepare_implicit(
        &mut self,
        t: f64,
        x: &[f64],
        gamma: f64,
    ) -> Option<Result<bool, RuntimeError>> {
        self.inner.prepare_implicit(t, &x[..self.motion], gamma)
    }

    fn solve_implicit(&mut self, r: &mut [f64]) {
        self.inner.solve_implicit(&mut r[..self.motion]);
    }

    fn correct(&mut self, t: f64, x: &mut [f64]) -> Result<bool, RuntimeError> {
        self.inner.correct(t, &mut x[..self.motion])
    }
}

impl<M: Model + ?Sized> Ode for ModelOde<'_, M> {
    fn dim(&self) -> usize {
        self.nq + self.nu
    }

    fn rhs(&mut self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), RuntimeError> {
        let (q, u) = x.split_at(self.nq);
        values_at(self.signals, t, &mut self.inputs);
        let (qdot, udot) = dxdt.split_at_mut(self.nq);
        self.model.kinematic_rates(t, q, u, qdot);
        // A non-finite derivative (NaN) makes the adaptive integrator retry a smaller step.
        match self.solve(t, q, u, udot) {
            Ok(()) | Err(RuntimeError::NonFiniteState { .. }) => Ok(()),
            Err(error) => Err(error),
        }
    }

    fn prepare_implicit(
        &mut self,
        t: f64,
        x: &[f64],
        gamma: f64,
    ) -> Option<Result<bool, RuntimeError>> {
        let implicit = self.implicit.as_mut()?;
        let (q, u) = x.split_at(self.nq);
        values_at(self.signals, t, &mut self.inputs);
        let model = self.model;
        if !model.contact_damping(t, q, u, &self.inputs, &mut implicit.damping) {
            implicit.damping.fill(0.0);
        }
        implicit.gamma = gamma;
        implicit.t = t;
        implicit.q.copy_from_slice(q);
        let damping = &implicit.damping;
        // The step's first trial factors where the derivative was just evaluated (the
        // accepted state, after its correction): M and J are the right-hand side's.
        let factored = match &self.constrained {
            Some(evaluated) if evaluated.evaluated_at(t, q, &self.inputs) => implicit
                .solver
                .factor_shifted_from(evaluated, gamma, damping),
            _ => implicit
                .solver
                .factor_shifted(model, t, q, u, &self.inputs, gamma, damping),
        };
        Some(Ok(factored))
    }

    fn correct(&mut self, t: f64, x: &mut [f64]) -> Result<bool, RuntimeError> {
        let Some(implicit) = self.implicit.as_mut() else {
            return Ok(false);
        };
        let (q, u) = x.split_at_mut(self.nq);
        let normalized = normalize_quaternions(self.model.unit_quaternions(), q);
        if self.model.nc() == 0 {
            return Ok(normalized);
        }
        values_at(self.signals, t, &mut self.inputs);
        let projected =
            implicit
                .solver
                .project(self.model, t, q, u, &self.inputs, implicit.tolerance)?;
        Ok(normalized || projected)
    }

    fn solve_implicit(&mut self, r: &mut [f64]) {
        let Some(implicit) = self.implicit.as_mut() else {
            return;
        };
        let (nu, gamma) = (self.nu, implicit.gamma);
        let (r_q, r_u) = r.split_at_mut(self.nq);
        // γ D r_u, then y; k_u = r_u + y.
        implicit.speeds.fill(0.0);
        for (column, &value) in implicit.damping.chunks_exact(nu).zip(r_u.iter()) {
            for (out, &d) in implicit.speeds.iter_mut().zip(column) {
                *out += gamma * d * value;
            }
        }
        implicit.solver.solve_shifted(&mut implicit.speeds);
        for (k, y) in r_u.iter_mut().zip(&implicit.speeds) {
            *k += y;
        }
        self.model
            .kinematic_rates(implicit.t, &implicit.q, r_u, &mut implicit.rates);
        for (k, rate) in r_q.iter_mut().zip(&implicit.rates) {
            *k += gamma * rate;
        }
    }
}

/// Accelerations `u̇` solving `M(q) u̇ = F(t, q, u, inputs)` at one state, with explicit input
/// values (length `ninputs`). Allocates a workspace per call; for repeated use build a
/// [`ModelOde`] and call [`ModelOde::accelerations`].
pub fn accelerations<M: Model + ?Sized>(
    model: &M,
    t: f64,
    q: &[f64],
    u: &[f64],
    inputs: &[f64],
    udot: &mut [f64],
) -> Result<(), RuntimeError> {
    let signals = default_signals(model);
    let mut ode = ModelOde::new(model, &signals)?;
    ode.accelerations(t, q, u, inputs, udot)
}

/// What [`accelerations_along`] finds at each sample of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct SampledAccelerations {
    /// `u̇` at each sample.
    pub udot: Vec<Vec<f64>>,
    /// `λ` at each sample (empty rows for a model without loops).
    pub multipliers: Vec<Vec<f64>>,
}

/// The accelerations `u̇` and the constraint multipliers `λ` (empty without loops) at every
/// sample of `run`, from the sample's own `t`, `q`, `u` and inputs: `M u̇ = F + Jᵀλ`,
/// `J u̇ = −J̇u`, as the integrator solved them.
pub fn accelerations_along<M: Model + ?Sized>(
    model: &M,
    signals: &[Signal],
    run: &Trajectory,
) -> Result<SampledAccelerations, RuntimeError> {
    let mut ode = ModelOde::new(model, signals)?;
    let mut udots = Vec::with_capacity(run.len());
    let mut multipliers = Vec::with_capacity(run.len());
    for k in 0..run.len() {
        let mut udot = vec![0.0; model.nu()];
        ode.accelerations(
            run.times[k],
            &run.q[k],
            &run.u[k],
            &run.inputs[k],
            &mut udot,
        )?;
        udots.push(udot);
        multipliers.push(ode.multipliers().to_vec());
    }
    Ok(SampledAccelerations {
        udot: udots,
        multipliers,
    })
}

/// The output grid: `t_start + k·dt` while `<= t_end` (a point within `1e-9·dt` of `t_end` is
/// replaced by it), then `t_end`.
fn output_grid(t_start: f64, t_end: f64, dt: f64) -> Vec<f64> {
    let span = t_end - t_start;
    let n = ((span / dt) * (1.0 + 1e-12)).floor() as usize;
    let mut times: Vec<f64> = (0..=n).map(|k| t_start + k as f64 * dt).collect();
    let last = times.last_mut().expect("the grid has at least t_start");
    if t_end - *last <= 1e-9 * dt {
        *last = t_end;
    } else {
        times.push(t_end);
    }
    times
}

/// Simulates `model` from `(q0, u0)` at `options.t_start` to `options.t_end`, driven by one
/// signal per model input (in the model's input order), and returns the trajectory sampled on
/// the output grid.
///
/// The Rosenbrock methods run [`simulate_reduced`] with the independent coordinates chosen by
/// [`choose_independent`] at `q0` (all coordinates for a model without loops); to choose them,
/// call [`simulate_reduced`].
///
/// `progress` is called with the current time after every accepted step (cheap calls; throttle
/// any display on the caller's side).
///
/// Errors: wrong slice lengths, invalid options or signals, a singular mass matrix, a
/// non-finite state, step-size underflow or an exhausted step budget. The state is never
/// silently truncated: an error means no trajectory.
pub fn simulate<M: Model + ?Sized>(
    model: &M,
    q0: &[f64],
    u0: &[f64],
    signals: &[Signal],
    options: &SimOptions,
    progress: &mut dyn FnMut(f64),
) -> Result<Trajectory, RuntimeError> {
    let nq = check_initial_state(model, q0, u0)?;
    if options.method.is_reduced() {
        model.require_rates_are_speeds("simulation in reduced coordinates (Rosenbrock)")?;
        model.require_holonomic("simulation in reduced coordinates (Rosenbrock)")?;
        let independent = if model.nc() == 0 {
            (0..nq).collect()
        } else {
            choose_independent(&jacobian(model, options.t_start, q0))
        };
        return simulate_reduced(model, q0, u0, &independent, signals, options, progress);
    }
    let mut ode = ModelOde::new(model, signals)?;
    // The W-method's system projects its accepted steps itself (`Ode::correct`).
    let corrects = matches!(options.method, Method::RosenbrockW { .. });
    if corrects {
        ode = ode.implicit_in_contacts(options.constraint_tolerance);
    }
    let sampling = Sampling::new(model, signals, options, progress)?;
    let mut x0 = Vec::with_capacity(nq + model.nu());
    x0.extend_from_slice(q0);
    x0.extend_from_slice(u0);
    normalize_quaternions(model.unit_quaternions(), &mut x0[..nq]);
    let mut full = FullCoordinates {
        model,
        signals,
        nq,
        projector: (model.nc() > 0).then(|| ConstrainedSolver::new(nq, model.nu(), model.nc())),
        inputs: vec![0.0; signals.len()],
        tolerance: options.constraint_tolerance,
        corrected: corrects,
    };
    integrate(ode, &x0, options, sampling, &mut full)
}

/// Simulates `model` as [`simulate`] does, in the minimal coordinates `independent` (indices
/// into `q`; all of them for a model without loops): the state is `[z; ż]` with `z` these
/// coordinates ([`Reduced`]). The loops are closed from `q0` with `z = q0[independent]`, and
/// the initial speeds are `ż = u0[independent]` (the other entries of `u0` follow from the
/// loops). Any [`Method`]; the Rosenbrock methods are meant for it.
///
/// Errors: those of [`simulate`], and those of [`Reduced::new`] (the independent coordinates
/// must be as many as the degrees of freedom and determine the others).
pub fn simulate_reduced<M: Model + ?Sized>(
    model: &M,
    q0: &[f64],
    u0: &[f64],
    independent: &[usize],
    signals: &[Signal],
    options: &SimOptions,
    progress: &mut dyn FnMut(f64),
) -> Result<Trajectory, RuntimeError> {
    check_initial_state(model, q0, u0)?;
    model.require_rates_are_speeds("simulation in reduced coordinates")?;
    model.require_holonomic("simulation in reduced coordinates")?;
    let sampling = Sampling::new(model, signals, options, progress)?;
    let (t0, tolerance) = (options.t_start, options.constraint_tolerance);
    let ode = Reduced::new(model, signals, t0, q0, independent, tolerance)?;
    let mut x0: Vec<f64> = independent.iter().map(|&i| q0[i]).collect();
    x0.extend(independent.iter().map(|&i| u0[i]));
    let mut reduced = ReducedCoordinates {
        sampler: Reduced::new(model, signals, t0, q0, independent, tolerance)?,
        nz: independent.len(),
    };
    integrate(ode, &x0, options, sampling, &mut reduced)
}

/// Checks that `q0` and `u0` have one entry per coordinate and speed of `model`; returns the
/// number of coordinates.
fn check_initial_state<M: Model + ?Sized>(
    model: &M,
    q0: &[f64],
    u0: &[f64],
) -> Result<usize, RuntimeError> {
    let nq = model.nq();
    check_len("q0", nq, q0.len())?;
    check_len("u0", model.nu(), u0.len())?;
    Ok(nq)
}

/// Most samples a trajectory stores: a typo in the output interval (`1e-12 s`) must not
/// allocate without bound (each sample holds q, u and the outputs).
pub const MAX_SAMPLES: usize = 1_000_000;

/// The output grid of `options`, after checking the times.
fn checked_grid(options: &SimOptions) -> Result<Vec<f64>, RuntimeError> {
    let SimOptions {
        t_start,
        t_end,
        output_interval,
        ..
    } = *options;
    if !(t_start.is_finite() && t_end.is_finite() && t_end >= t_start) {
        return Err(RuntimeError::InvalidOptions(format!(
            "need finite times with t_end >= t_start (got t_start = {t_start}, t_end = {t_end})"
        )));
    }
    if !(output_interval > 0.0 && output_interval.is_finite()) {
        return Err(RuntimeError::InvalidOptions(format!(
            "output_interval must be finite and > 0 (got {output_interval})"
        )));
    }
    let samples = (t_end - t_start) / output_interval;
    if samples > MAX_SAMPLES as f64 {
        return Err(RuntimeError::InvalidOptions(format!(
            "an output interval of {output_interval:e} s over {:e} s gives {samples:.3e} samples, \
             more than the {MAX_SAMPLES} a run stores; choose an interval of at least {:.3e} s",
            t_end - t_start,
            (t_end - t_start) / MAX_SAMPLES as f64
        )));
    }
    Ok(output_grid(t_start, t_end, output_interval))
}

/// Integrates `ode` from `x0` with `options.method`, with the model's integrated outputs
/// from zero ([`Integrating`]), and samples it through `map`.
fn integrate<O: MotionOde, M: Model + ?Sized>(
    ode: O,
    x0: &[f64],
    options: &SimOptions,
    sampling: Sampling<'_, M>,
    map: &mut dyn StateMap,
) -> Result<Trajectory, RuntimeError> {
    let ode = Integrating::new(ode, sampling.model, sampling.signals);
    let mut x0 = x0.to_vec();
    x0.resize(ode.dim(), 0.0);
    let x0 = &x0[..];
    let (t0, t1) = (options.t_start, options.t_end);
    let opts = adaptive_options(options);
    match options.method {
        Method::Dopri5 { .. } => run(Dopri5::new(ode, t0, x0, t1, opts)?, sampling, map),
        Method::Dop853 { .. } => run(Dop853::new(ode, t0, x0, t1, opts)?, sampling, map),
        Method::Rk4 { step } => run(Rk4::new(ode, t0, x0, t1, step)?, sampling, map),
        Method::Rosenbrock { .. } => run(Rosenbrock::new(ode, t0, x0, t1, opts)?, sampling, map),
        Method::RosenbrockW { .. } => run(Ros34pw2::new(ode, t0, x0, t1, opts)?, sampling, map),
        Method::ExpRosenbrock { .. } => {
            run(ExpRosenbrock::new(ode, t0, x0, t1, opts)?, sampling, map)
        }
    }
}

/// The options of an adaptive `options.method`: Hairer's defaults for the method (`RODAS`'s
/// for both Rosenbrock methods) with its tolerances, step limit and `options.max_steps`. RK4
/// has none: the defaults, unused.
fn adaptive_options(options: &SimOptions) -> AdaptiveOptions {
    let (defaults, rtol, atol, h_max) = match options.method {
        Method::Dopri5 { rtol, atol, h_max } => (AdaptiveOptions::default(), rtol, atol, h_max),
        Method::Dop853 { rtol, atol, h_max } => (AdaptiveOptions::dop853(), rtol, atol, h_max),
        Method::Rosenbrock { rtol, atol, h_max }
        | Method::RosenbrockW { rtol, atol, h_max }
        | Method::ExpRosenbrock { rtol, atol, h_max } => {
            (AdaptiveOptions::rosenbrock(), rtol, atol, h_max)
        }
        Method::Rk4 { .. } => return AdaptiveOptions::default(),
    };
    AdaptiveOptions {
        rtol,
        atol,
        h_max,
        max_steps: options.max_steps,
        ..defaults
    }
}

/// How the integrator's state relates to the model's `(q, u)`.
trait StateMap {
    /// Corrects the state after an accepted step in place; returns whether it changed.
    fn after_step(&mut self, t: f64, x: &mut [f64]) -> Result<bool, RuntimeError>;
    /// The model's `q` and `u` at a sample `(t, x)`.
    fn full_state(&mut self, t: f64, x: &[f64]) -> Result<(Vec<f64>, Vec<f64>), RuntimeError>;
}

/// `x = [q; u]`, projected onto the loops after every step and at every sample.
struct FullCoordinates<'a, M: Model + ?Sized> {
    model: &'a M,
    signals: &'a [Signal],
    nq: usize,
    projector: Option<ConstrainedSolver>,
    inputs: Vec<f64>,
    tolerance: f64,
    /// The integrator's system corrects every accepted step itself ([`Ode::correct`]).
    corrected: bool,
}

impl<M: Model + ?Sized> StateMap for FullCoordinates<'_, M> {
    /// Projects `x` in place; returns whether it changed (a state already within tolerance is
    /// left bit for bit as it was).
    fn after_step(&mut self, t: f64, x: &mut [f64]) -> Result<bool, RuntimeError> {
        if self.corrected {
            return Ok(false);
        }
        let normalized = normalize_quaternions(self.model.unit_quaternions(), &mut x[..self.nq]);
        let Some(projector) = self.projector.as_mut() else {
            return Ok(normalized);
        };
        values_at(self.signals, t, &mut self.inputs);
        let (q, u) = x.split_at_mut(self.nq);
        projector.project(self.model, t, q, u, &self.inputs, self.tolerance)
    }

    fn full_state(&mut self, t: f64, x: &[f64]) -> Result<(Vec<f64>, Vec<f64>), RuntimeError> {
        let (mut q, mut u) = (x[..self.nq].to_vec(), x[self.nq..].to_vec());
        normalize_quaternions(self.model.unit_quaternions(), &mut q);
        if let Some(projector) = self.projector.as_mut() {
            values_at(self.signals, t, &mut self.inputs);
            projector.project(self.model, t, &mut q, &mut u, &self.inputs, self.tolerance)?;
        }
        Ok((q, u))
    }
}

/// `x = [z; ż]`; each sample closes the loops from the previous one.
struct ReducedCoordinates<'a, M: Model + ?Sized> {
    sampler: Reduced<'a, M>,
    nz: usize,
}

impl<M: Model + ?Sized> StateMap for ReducedCoordinates<'_, M> {
    fn after_step(&mut self, _t: f64, _x: &mut [f64]) -> Result<bool, RuntimeError> {
        Ok(false)
    }

    fn full_state(&mut self, t: f64, x: &[f64]) -> Result<(Vec<f64>, Vec<f64>), RuntimeError> {
        let (z, zdot) = x.split_at(self.nz);
        self.sampler.state(t, z, zdot)?;
        Ok((self.sampler.q().to_vec(), self.sampler.u().to_vec()))
    }
}

/// What [`run`] samples and how.
struct Sampling<'a, M: Model + ?Sized> {
    model: &'a M,
    signals: &'a [Signal],
    grid: Vec<f64>,
    max_steps: usize,
    progress: &'a mut dyn FnMut(f64),
}

impl<'a, M: Model + ?Sized> Sampling<'a, M> {
    /// The sampling of a simulation of `model` with `options`, after checking its times.
    fn new(
        model: &'a M,
        signals: &'a [Signal],
        options: &SimOptions,
        progress: &'a mut dyn FnMut(f64),
    ) -> Result<Self, RuntimeError> {
        Ok(Sampling {
            model,
            signals,
            grid: checked_grid(options)?,
            max_steps: options.max_steps,
            progress,
        })
    }
}

/// Steps `stepper` to its end time, sampling `grid` by dense output through `map`.
fn run<M: Model + ?Sized, S: Stepper>(
    mut stepper: S,
    sampling: Sampling<'_, M>,
    map: &mut dyn StateMap,
) -> Result<Trajectory, RuntimeError> {
    let Sampling {
        model,
        signals,
        grid,
        max_steps,
        progress,
    } = sampling;
    let mut traj = Trajectory {
        q: Vec::with_capacity(grid.len()),
        u: Vec::with_capacity(grid.len()),
        outputs: Vec::with_capacity(grid.len()),
        inputs: Vec::with_capacity(grid.len()),
        ..Trajectory::default()
    };
    let mut x = vec![0.0; stepper.state().len()];
    // The corrected state after a step, written back (which makes the stepper re-evaluate its
    // derivative there) only when the correction moved it.
    let mut corrected = x.clone();
    // The integrated outputs' states follow the motion's (`Integrating`).
    let integrated = model.integrated_outputs();
    let motion = x.len() - integrated.len();
    let record = |map: &mut dyn StateMap,
                  t: f64,
                  x: &[f64],
                  traj: &mut Trajectory|
     -> Result<(), RuntimeError> {
        let (q, u) = map.full_state(t, &x[..motion])?;
        let mut inputs = vec![0.0; signals.len()];
        values_at(signals, t, &mut inputs);
        let mut outputs = vec![0.0; model.noutputs()];
        model.outputs(t, &q, &u, &inputs, &mut outputs);
        for (&(target, _), &value) in integrated.iter().zip(&x[motion..]) {
            outputs[target] = value;
        }
        traj.q.push(q);
        traj.u.push(u);
        traj.inputs.push(inputs);
        traj.outputs.push(outputs);
        Ok(())
    };
    x.copy_from_slice(stepper.state());
    record(map, grid[0], &x, &mut traj)?;
    let mut next = 1;
    while next < grid.len() {
        let steps = stepper.stats().accepted_steps + stepper.stats().rejected_steps;
        if steps >= max_steps {
            return Err(RuntimeError::TooManySteps {
                t: stepper.t(),
                steps,
            });
        }
        stepper.step()?;
        corrected.copy_from_slice(stepper.state());
        if map.after_step(stepper.t(), &mut corrected[..motion])? {
            stepper.state_mut().copy_from_slice(&corrected);
            stepper.reset()?;
        }
        progress(stepper.t());
        while next < grid.len() && grid[next] <= stepper.t() {
            stepper.interpolate(grid[next], &mut x)?;
            record(map, grid[next], &x, &mut traj)?;
            next += 1;
        }
        if stepper.is_finished() {
            // The grid ends at t_end, where the stepper stops exactly; this is a safeguard.
            x.copy_from_slice(stepper.state());
            while next < grid.len() {
                record(map, grid[next], &x, &mut traj)?;
                next += 1;
            }
        }
    }
    traj.times = grid;
    traj.stats = stepper.stats();
    Ok(traj)
}
