//! Reduced (minimal-coordinate) dynamics: the state is the independent coordinates `z ⊂ q`
//! and their rates `ż`; the dependent coordinates `d` follow by closing the loops, and `z̈` by
//! projecting the equations of motion onto the motions the loops allow.
//!
//! Consumes: a [`Model`], the indices of `z` in `q`, a configuration near the motion (the
//! first guess of `d`), and input [`Signal`]s (for the [`Ode`] form) or explicit input values.
//! Produces: the full state `(q, u)` at `(z, ż)`, `z̈`, and `ẋ = [ż; z̈]` as an [`Ode`] on
//! `x = [z; ż]`, which has no constraint drift (every evaluation closes the loops).
//!
//! With `J = [J_z J_d]`: `d` by Newton on `φ(z, d) = 0` (least squares in `J_d`), warm-started
//! from the last closed configuration moved by `T_d Δz` and reusing its factor while that
//! converges fast (a new `z` usually costs two `φ`, one `J` and one factorization, the same `z`
//! none of them); `u = T ż` with `T = [I; T_d]`, `T_d = −J_d⁺ J_z`; `u̇ = T z̈ + s` with
//! `s = [0; −J_d⁺ J̇u]`. Projecting `M u̇ = F + Jᵀλ` onto `T` (`J T = 0` removes `λ`) leaves
//! `(TᵀMT) z̈ = Tᵀ(F − M s)`, a Cholesky solve of size `dim z` instead of the multiplier system
//! of [`ConstrainedSolver`](crate::ConstrainedSolver). Redundant loop rows are consistent on
//! the closed loops, so the least-squares solves are exact there, whatever the weight of each
//! row: they are normal equations of `J_d` with its rows scaled to unit length, which keeps
//! their condition number small (rows in metres and in radians differ by the lever arms; for
//! the HAMR leg `κ(J_d)` ≈ 4400 becomes ≈ 5). For a model without loops `z = q`, `T = I` and
//! this is `M q̈ = F`. Nothing allocates after construction.

use crate::constraints::{assembly_error, mobility};
use crate::integrate::{check_indices, check_len, Ode};
use crate::signal::{check_inputs, values_at};
use crate::{dense, Model, RuntimeError, Signal};

/// Newton iterations allowed per closure; warm-started closures take one or two.
const MAX_NEWTON_ITERATIONS: usize = 12;
/// A Newton iteration that shrinks `max |φ|` by less than this factor refactors `J_d` at the
/// iterate (otherwise the factor of the last closed configuration serves).
const SLOW_CONTRACTION: f64 = 0.1;

/// The reduced dynamics of a model in the independent coordinates `z`; see the module docs.
pub struct Reduced<'a, M: Model + ?Sized> {
    model: &'a M,
    signals: &'a [Signal],
    independent: Vec<usize>,
    dependent: Vec<usize>,
    /// Loops are closed when `max |φ| ≤ tolerance`.
    tolerance: f64,
    /// The last closed configuration: `z`, `q`, `u`, and `T = ∂q/∂z` there (`nq × nz`).
    z: Vec<f64>,
    q: Vec<f64>,
    u: Vec<f64>,
    speed_map: Vec<f64>,
    /// Newton iterate.
    trial: Vec<f64>,
    phi: Vec<f64>,
    jacobian: Vec<f64>,
    /// `W J_d` on the rows of `J_d` that are not zero (`rows`, `nr × nd` with `nr =
    /// rows.len()`), `W` their inverse norms (`weights`), and the Cholesky factor of
    /// `(W J_d)ᵀ(W J_d)` (`nd × nd`): at `q` when `factor_at_q`, else at a Newton iterate.
    scaled: Vec<f64>,
    rows: Vec<usize>,
    weights: Vec<f64>,
    /// `W b` on `rows`.
    gathered: Vec<f64>,
    factor: Vec<f64>,
    /// `((W J_d)ᵀ(W J_d))⁻¹` from `factor` (`nd × nd`): every solve is then two products,
    /// without the divisions of triangular solves in a chain.
    inverse: Vec<f64>,
    factor_at_q: bool,
    /// Solution of the last [`Reduced::solve_dependent`].
    solution: Vec<f64>,
    work: Vec<f64>,
    mass: Vec<f64>,
    force: Vec<f64>,
    bias: Vec<f64>,
    /// `s`, the acceleration of the dependent coordinates at `z̈ = 0`.
    drift: Vec<f64>,
    /// `M T`, `nq × nz`.
    mass_map: Vec<f64>,
    reduced_mass: Vec<f64>,
    inputs: Vec<f64>,
}

impl<'a, M: Model + ?Sized> Reduced<'a, M> {
    /// The reduced dynamics in the coordinates `independent` (indices into `q`; all of them
    /// for a model without loops), closing the loops from `q` at time `t` to
    /// `max |φ| ≤ tolerance` (model units). `signals` (one per model input) drive the [`Ode`]
    /// form. Errors: wrong lengths, an invalid signal or tolerance, as many independent
    /// coordinates as the loops leave degrees of freedom not given, or loops that do not close.
    pub fn new(
        model: &'a M,
        signals: &'a [Signal],
        t: f64,
        q: &[f64],
        independent: &[usize],
        tolerance: f64,
    ) -> Result<Self, RuntimeError> {
        let (nq, nc) = (model.nq(), model.nc());
        model.require_rates_are_speeds("the reduced dynamics")?;
        model.require_holonomic("the reduced dynamics")?;
        check_len("q", nq, q.len())?;
        check_inputs(model, signals)?;
        if !(tolerance > 0.0 && tolerance.is_finite()) {
            return Err(RuntimeError::InvalidOptions(format!(
                "the constraint tolerance must be finite and > 0 (got {tolerance})"
            )));
        }
        check_indices("independent coordinates", independent, nq)?;
        let dof = if nc == 0 {
            nq
        } else {
            mobility(model, t, q)?.dof()
        };
        if independent.len() != dof {
            return Err(RuntimeError::InvalidOptions(format!(
                "model `{}` has {dof} degrees of freedom here but {} independent coordinates \
                 were given",
                model.name(),
                independent.len()
            )));
        }
        let dependent: Vec<usize> = (0..nq).filter(|i| !independent.contains(i)).collect();
        let (nz, nd) = (independent.len(), dependent.len());
        let z: Vec<f64> = independent.iter().map(|&i| q[i]).collect();
        let mut speed_map = vec![0.0; nq * nz];
        for (k, &i) in independent.iter().enumerate() {
            speed_map[i + nq * k] = 1.0;
        }
        let mut reduced = Reduced {
            model,
            signals,
            independent: independent.to_vec(),
            dependent,
            tolerance,
            z: z.clone(),
            q: q.to_vec(),
            u: vec![0.0; nq],
            speed_map,
            trial: vec![0.0; nq],
            phi: vec![0.0; nc],
            jacobian: vec![0.0; nc * nq],
            scaled: vec![0.0; nc * nd],
            rows: Vec::with_capacity(nc),
            weights: vec![0.0; nc],
            gathered: vec![0.0; nc],
            factor: vec![0.0; nd * nd],
            inverse: vec![0.0; nd * nd],
            factor_at_q: false,
            solution: vec![0.0; nd],
            work: vec![0.0; nc.max(nq)],
            mass: vec![0.0; nq * nq],
            force: vec![0.0; nq],
            bias: vec![0.0; nc],
            drift: vec![0.0; nq],
            mass_map: vec![0.0; nq * nz],
            reduced_mass: vec![0.0; nz * nz],
            inputs: vec![0.0; model.ninputs()],
        };
        reduced.close(t, &z)?;
        Ok(reduced)
    }

    /// Indices of `z` in `q`.
    pub fn independent(&self) -> &[usize] {
        &self.independent
    }

    /// `q` of the last evaluation (loops closed).
    pub fn q(&self) -> &[f64] {
        &self.q
    }

    /// `u` of the last [`Reduced::state`] or [`Reduced::accelerations`] (`J u = 0`).
    pub fn u(&self) -> &[f64] {
        &self.u
    }

    /// Closes the loops at `z` and sets the speeds from `ż`: afterwards [`Reduced::q`] and
    /// [`Reduced::u`] hold the full state. Errors: [`RuntimeError::AssemblyFailed`] (the state
    /// stays at the last closed configuration), or
    /// [`RuntimeError::SingularDependentJacobian`].
    pub fn state(&mut self, t: f64, z: &[f64], zdot: &[f64]) -> Result<(), RuntimeError> {
        let nz = self.independent.len();
        check_len("z", nz, z.len())?;
        check_len("zdot", nz, zdot.len())?;
        self.close(t, z)?;
        let nq = self.q.len();
        for (i, u) in self.u.iter_mut().enumerate() {
            *u = (0..nz).map(|k| self.speed_map[i + nq * k] * zdot[k]).sum();
        }
        Ok(())
    }

    /// `z̈` at `(z, ż)` under the given input values (the signals are not used); the full state
    /// is left in [`Reduced::q`], [`Reduced::u`]. Errors: those of [`Reduced::state`],
    /// [`RuntimeError::SingularMassMatrix`] if `TᵀMT` is not positive definite, and
    /// [`RuntimeError::NonFiniteState`].
    pub fn accelerations(
        &mut self,
        t: f64,
        z: &[f64],
        zdot: &[f64],
        inputs: &[f64],
        zddot: &mut [f64],
    ) -> Result<(), RuntimeError> {
        check_len("inputs", self.model.ninputs(), inputs.len())?;
        check_len("zddot", self.independent.len(), zddot.len())?;
        self.state(t, z, zdot)?;
        let (nq, nc, nz, nd) = (
            self.q.len(),
            self.phi.len(),
            self.independent.len(),
            self.dependent.len(),
        );
        // No `J`: the closure left the factor of `J_d` at `q`.
        self.model.dynamics_terms(
            t,
            &self.q,
            &self.u,
            inputs,
            &mut self.mass,
            &mut self.force,
            &mut self.bias,
        );
        // s = [0; −J_d⁺ J̇u], with the factor of J_d at q from the closure.
        self.drift.fill(0.0);
        if nd > 0 {
            self.work[..nc].copy_from_slice(&self.bias);
            self.solve_dependent();
            for (&d, x) in self.dependent.iter().zip(&self.solution) {
                self.drift[d] = -x;
            }
        }
        // F − M s into `force`; M T into `mass_map`; then TᵀMT and Tᵀ(F − M s).
        for (column, &s) in self.mass.chunks_exact(nq).zip(&self.drift) {
            if s != 0.0 {
                for (f, m) in self.force.iter_mut().zip(column) {
                    *f -= m * s;
                }
            }
        }
        self.mass_map.fill(0.0);
        for (map, speeds) in self
            .mass_map
            .chunks_exact_mut(nq)
            .zip(self.speed_map.chunks_exact(nq))
        {
            for (column, &speed) in self.mass.chunks_exact(nq).zip(speeds) {
                if speed != 0.0 {
                    for (out, m) in map.iter_mut().zip(column) {
                        *out += m * speed;
                    }
                }
            }
        }
        for (k, speeds) in self.speed_map.chunks_exact(nq).enumerate() {
            for (l, map) in self.mass_map.chunks_exact(nq).enumerate() {
                self.reduced_mass[k + nz * l] = speeds.iter().zip(map).map(|(a, b)| a * b).sum();
            }
            zddot[k] = speeds.iter().zip(&self.force).map(|(a, b)| a * b).sum();
        }
        if !dense::cholesky(&mut self.reduced_mass, nz) {
            return Err(if self.reduced_mass.iter().all(|v| v.is_finite()) {
                RuntimeError::SingularMassMatrix { t }
            } else {
                RuntimeError::NonFiniteState { t }
            });
        }
        dense::cholesky_solve(&self.reduced_mass, nz, zddot);
        if zddot.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(RuntimeError::NonFiniteState { t })
        }
    }

    /// Newton on the dependent coordinates from the last closed configuration moved by
    /// `T_d Δz`; on success `z`, `q`, the factor of `J_d` and `T` describe the new point.
    fn close(&mut self, t: f64, z: &[f64]) -> Result<(), RuntimeError> {
        if self.factor_at_q && z == self.z.as_slice() {
            return Ok(());
        }
        let (nq, nc) = (self.q.len(), self.phi.len());
        self.trial.copy_from_slice(&self.q);
        for (k, &i) in self.independent.iter().enumerate() {
            let step = z[k] - self.z[k];
            self.trial[i] = z[k];
            let column = &self.speed_map[nq * k..nq * (k + 1)];
            for &d in &self.dependent {
                self.trial[d] += column[d] * step;
            }
        }
        let mut previous = f64::INFINITY;
        let mut closed = false;
        // The factor was computed at the iterate the last update started from (true Newton).
        let mut fresh = false;
        let mut factored = self.factor_at_q;
        for _ in 0..MAX_NEWTON_ITERATIONS {
            self.model.constraints(t, &self.trial, &mut self.phi);
            let size = self.phi.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
            if self.phi.iter().any(|v| v.is_nan()) || (fresh && size >= previous) {
                break;
            }
            if size <= self.tolerance {
                closed = true;
                break;
            }
            fresh = !factored || size > SLOW_CONTRACTION * previous;
            if fresh {
                self.factor_at_q = false;
                if !self.factor_at_trial(t) {
                    break;
                }
                factored = true;
            }
            previous = size;
            self.work[..nc].copy_from_slice(&self.phi);
            self.solve_dependent();
            for (&d, x) in self.dependent.iter().zip(&self.solution) {
                self.trial[d] -= x;
            }
        }
        if !closed {
            return Err(assembly_error(self.model, &self.phi));
        }
        self.factor_at_q = false;
        if !self.factor_at_trial(t) {
            return Err(RuntimeError::SingularDependentJacobian { t });
        }
        self.factor_at_q = true;
        self.q.copy_from_slice(&self.trial);
        self.z.copy_from_slice(z);
        // T_d = −J_d⁺ J_z, column by column.
        for k in 0..self.independent.len() {
            let i = self.independent[k];
            self.work[..nc].copy_from_slice(&self.jacobian[nc * i..nc * (i + 1)]);
            self.solve_dependent();
            let column = &mut self.speed_map[nq * k..nq * (k + 1)];
            for (&d, x) in self.dependent.iter().zip(&self.solution) {
                column[d] = -x;
            }
        }
        Ok(())
    }

    /// `J` at the Newton iterate and the factor of its dependent columns; false if they are
    /// not of full rank (or not finite).
    fn factor_at_trial(&mut self, t: f64) -> bool {
        let (nc, nd) = (self.phi.len(), self.dependent.len());
        if nd == 0 {
            return true;
        }
        self.model
            .constraint_jacobian(t, &self.trial, &mut self.jacobian);
        self.weights.fill(0.0);
        for &d in &self.dependent {
            for (w, j) in self
                .weights
                .iter_mut()
                .zip(&self.jacobian[nc * d..nc * (d + 1)])
            {
                *w += j * j;
            }
        }
        // Rows that are zero for every dependent coordinate (e.g. the out-of-plane rows of a
        // planar loop) carry nothing: leave them out.
        self.rows.clear();
        for (r, w) in self.weights.iter_mut().enumerate() {
            if *w > 0.0 {
                *w = 1.0 / w.sqrt();
                self.rows.push(r);
            }
        }
        let nr = self.rows.len();
        if nr < nd {
            return false;
        }
        for (k, &d) in self.dependent.iter().enumerate() {
            let column = &self.jacobian[nc * d..nc * (d + 1)];
            for (s, &r) in self.scaled[nr * k..nr * (k + 1)].iter_mut().zip(&self.rows) {
                *s = column[r] * self.weights[r];
            }
        }
        dense::gram_lower(&self.scaled, nr, nd, &mut self.factor);
        if !dense::cholesky(&mut self.factor, nd) {
            return false;
        }
        dense::cholesky_inverse(&self.factor, nd, &mut self.inverse);
        true
    }

    /// The least-squares solution of `J_d x = b` into `solution`, for `b` in `work[..nc]` (which
    /// it overwrites).
    fn solve_dependent(&mut self) {
        let (nr, nd) = (self.rows.len(), self.dependent.len());
        for (g, &r) in self.gathered.iter_mut().zip(&self.rows) {
            *g = self.work[r] * self.weights[r];
        }
        dense::transpose_times(&self.scaled, nr, nd, &self.gathered, &mut self.work[..nd]);
        self.solution.fill(0.0);
        dense::add_times(&self.inverse, nd, nd, &self.work[..nd], &mut self.solution);
    }
}

impl<M: Model + ?Sized> Ode for Reduced<'_, M> {
    fn dim(&self) -> usize {
        2 * self.independent.len()
    }

    /// `[ż; z̈]` with the inputs from the signals at `t`. A closure that fails or a non-finite
    /// result writes NaN (the adaptive integrators retry a smaller step); a singular reduced
    /// mass matrix is an error.
    fn rhs(&mut self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), RuntimeError> {
        let nz = self.independent.len();
        values_at(self.signals, t, &mut self.inputs);
        let (z, zdot) = x.split_at(nz);
        let (velocity, acceleration) = dxdt.split_at_mut(nz);
        velocity.copy_from_slice(zdot);
        let inputs = std::mem::take(&mut self.inputs);
        let result = self.accelerations(t, z, zdot, &inputs, acceleration);
        self.inputs = inputs;
        match result {
            Ok(()) => Ok(()),
            Err(
                RuntimeError::AssemblyFailed { .. }
                | RuntimeError::NonFiniteConstraints { .. }
                | RuntimeError::SingularDependentJacobian { .. }
                | RuntimeError::NonFiniteState { .. },
            ) => {
                acceleration.fill(f64::NAN);
                Ok(())
            }
            Err(error) => Err(error),
        }
    }
}
