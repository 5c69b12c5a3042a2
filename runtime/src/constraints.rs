//! Loop-closure constraints at run time: mobility, assembly, constrained accelerations and
//! drift projection, all rank-revealing so that redundant rows (planar loops in 3D, the
//! spherical five-bar) are normal rather than fatal.
//!
//! Consumes: a [`Model`] with `nc() > 0` (`φ(q)`, `J(q)`, `J̇u`). Produces: [`Mobility`]
//! reports, assembled states, and `u̇` of `M u̇ = F + Jᵀλ`, `J u̇ = −J̇u`.
//!
//! Rank decisions use singular values relative to the largest one: a value below
//! `RANK_TOLERANCE · σ₁` counts as zero.

use std::fmt;

use nalgebra::{DMatrix, DVector};

use crate::{dense, Model, RuntimeError};

/// Relative threshold on singular values for rank decisions.
pub const RANK_TOLERANCE: f64 = 1e-9;

/// Mobility of a constrained model at one configuration: `dof = nq − rank(J)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Mobility {
    pub coordinates: usize,
    pub rows: usize,
    pub rank: usize,
    /// Singular values of `J`, descending.
    pub singular_values: Vec<f64>,
    /// Values below this count as zero (`RANK_TOLERANCE · σ₁`).
    pub threshold: f64,
}

impl Mobility {
    /// Degrees of freedom.
    pub fn dof(&self) -> usize {
        self.coordinates - self.rank
    }

    /// The singular values within three decades of the threshold, on either side: the rank
    /// decision is fragile if any exist (e.g. axes that nearly, but not exactly, meet).
    pub fn near_threshold(&self) -> Vec<f64> {
        self.singular_values
            .iter()
            .copied()
            .filter(|&s| s > self.threshold * 1e-3 && s < self.threshold * 1e3)
            .collect()
    }
}

impl fmt::Display for Mobility {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let plural = if self.dof() == 1 { "" } else { "s" };
        write!(
            f,
            "{} coordinates, {} constraint rows, rank {}: {} degree{plural} of freedom",
            self.coordinates,
            self.rows,
            self.rank,
            self.dof()
        )
    }
}

/// `J(q)` as a matrix.
pub fn jacobian<M: Model + ?Sized>(model: &M, t: f64, q: &[f64]) -> DMatrix<f64> {
    let mut j = DMatrix::zeros(model.nc(), model.nq());
    model.constraint_jacobian(t, q, j.as_mut_slice());
    j
}

/// `φ(q)` as a vector.
pub fn residual<M: Model + ?Sized>(model: &M, t: f64, q: &[f64]) -> DVector<f64> {
    let mut phi = DVector::zeros(model.nc());
    model.constraints(t, q, phi.as_mut_slice());
    phi
}

/// Rank of `J` at `q` from its singular values.
pub fn mobility<M: Model + ?Sized>(model: &M, t: f64, q: &[f64]) -> Mobility {
    let j = jacobian(model, t, q);
    let mut singular_values: Vec<f64> = if j.is_empty() {
        Vec::new()
    } else {
        j.singular_values().iter().copied().collect()
    };
    singular_values.sort_by(|a, b| b.total_cmp(a));
    let threshold = singular_values.first().copied().unwrap_or(0.0) * RANK_TOLERANCE;
    let rank = singular_values.iter().filter(|&&s| s > threshold).count();
    Mobility {
        coordinates: model.nq(),
        rows: model.nc(),
        rank,
        singular_values,
        threshold,
    }
}

/// Least-squares minimum-norm solution of `A x = b`, treating singular values below
/// `RANK_TOLERANCE · σ₁` as zero.
pub fn solve_least_squares(a: &DMatrix<f64>, b: &DVector<f64>) -> DVector<f64> {
    if a.is_empty() {
        return DVector::zeros(a.ncols());
    }
    let svd = a.clone().svd(true, true);
    let largest = svd.singular_values.max();
    let threshold = largest * RANK_TOLERANCE;
    match svd.solve(b, threshold.max(f64::MIN_POSITIVE)) {
        Ok(x) => x,
        Err(_) => DVector::zeros(a.ncols()),
    }
}

/// Independent coordinates for a model that names none: the coordinates declared first
/// are kept (they are usually the drivers: a crank, an actuator), and the dependent ones are
/// taken from the end of the list, each only if it adds a well-conditioned direction to the
/// columns of `J` already taken (Gram–Schmidt with a relative threshold).
pub fn choose_independent(j: &DMatrix<f64>) -> Vec<usize> {
    let scale = (0..j.ncols())
        .map(|c| j.column(c).norm())
        .fold(0.0, f64::max);
    let mut basis: Vec<DVector<f64>> = Vec::new();
    let mut dependent = Vec::new();
    for c in (0..j.ncols()).rev() {
        let mut column = j.column(c).into_owned();
        for direction in &basis {
            let along = column.dot(direction);
            column -= direction * along;
        }
        let norm = column.norm();
        if norm > scale * 1e-6 {
            basis.push(column / norm);
            dependent.push(c);
        }
    }
    (0..j.ncols()).filter(|c| !dependent.contains(c)).collect()
}

/// Settings of [`assemble`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AssemblyOptions {
    /// Converged when `max |φ| ≤ tolerance` (model units, SI).
    pub tolerance: f64,
    pub max_iterations: usize,
}

impl Default for AssemblyOptions {
    fn default() -> Self {
        AssemblyOptions {
            tolerance: 1e-13,
            max_iterations: 100,
        }
    }
}

/// Solves `φ(q) = 0` for the coordinates not listed in `fixed`, starting from `q` (updated
/// in place): damped Newton steps `Δq_free = −J_free⁺ φ` (rank-revealing least squares),
/// halved until `|φ|` decreases. Fails with the loop rows that remain open.
pub fn assemble<M: Model + ?Sized>(
    model: &M,
    t: f64,
    q: &mut [f64],
    fixed: &[usize],
    options: &AssemblyOptions,
) -> Result<usize, RuntimeError> {
    let free: Vec<usize> = (0..model.nq()).filter(|c| !fixed.contains(c)).collect();
    let mut phi = residual(model, t, q);
    for iteration in 0..options.max_iterations {
        if phi.amax() <= options.tolerance {
            return Ok(iteration);
        }
        let j = jacobian(model, t, q);
        let j_free = j.select_columns(&free);
        let step = solve_least_squares(&j_free, &(-&phi));
        let mut scale = 1.0;
        let before = phi.norm();
        let mut trial = q.to_vec();
        loop {
            for (k, &c) in free.iter().enumerate() {
                trial[c] = q[c] + scale * step[k];
            }
            let trial_phi = residual(model, t, &trial);
            if trial_phi.norm() < before || scale < 1e-6 {
                q.copy_from_slice(&trial);
                phi = trial_phi;
                break;
            }
            scale *= 0.5;
        }
        if scale < 1e-6 {
            break;
        }
    }
    if phi.amax() <= options.tolerance {
        return Ok(options.max_iterations);
    }
    Err(assembly_error(model, &phi))
}

fn assembly_error<M: Model + ?Sized>(model: &M, phi: &DVector<f64>) -> RuntimeError {
    let worst = (0..phi.len())
        .max_by(|&a, &b| phi[a].abs().total_cmp(&phi[b].abs()))
        .unwrap_or(0);
    RuntimeError::AssemblyFailed {
        row: model.constraint_name(worst).to_string(),
        residual: phi[worst],
        norm: phi.norm(),
    }
}

/// Speeds consistent with `J u = 0`: keeps `u` of the `fixed` coordinates and solves the
/// others by least squares (`J_free u_free = −J_fixed u_fixed`).
pub fn assemble_speeds<M: Model + ?Sized>(
    model: &M,
    t: f64,
    q: &[f64],
    u: &mut [f64],
    fixed: &[usize],
) {
    let j = jacobian(model, t, q);
    let free: Vec<usize> = (0..model.nq()).filter(|c| !fixed.contains(c)).collect();
    let mut rhs = DVector::zeros(model.nc());
    for &c in fixed {
        rhs -= j.column(c) * u[c];
    }
    let solution = solve_least_squares(&j.select_columns(&free), &rhs);
    for (k, &c) in free.iter().enumerate() {
        u[c] = solution[k];
    }
}

/// Workspace for constrained dynamics and projection. [`accelerations`](Self::accelerations)
/// allocates nothing: `M` by Cholesky, `J M⁻¹ Jᵀ` by a diagonally pivoted Cholesky that
/// drops redundant rows (`u̇` is unique even where `λ` is not).
#[derive(Clone, Debug)]
pub struct ConstrainedSolver {
    nq: usize,
    nc: usize,
    mass: DMatrix<f64>,
    force: DVector<f64>,
    jacobian: DMatrix<f64>,
    bias: DVector<f64>,
    phi: DVector<f64>,
    /// `M⁻¹ Jᵀ`, `nq × nc`.
    m_inv_jt: Vec<f64>,
    /// `J M⁻¹ Jᵀ` and then its pivoted factor, `nc × nc`.
    coupling: Vec<f64>,
    mismatch: Vec<f64>,
    multipliers: Vec<f64>,
    order: Vec<usize>,
    work: Vec<f64>,
}

impl ConstrainedSolver {
    pub fn new(nq: usize, nc: usize) -> ConstrainedSolver {
        ConstrainedSolver {
            nq,
            nc,
            mass: DMatrix::zeros(nq, nq),
            force: DVector::zeros(nq),
            jacobian: DMatrix::zeros(nc, nq),
            bias: DVector::zeros(nc),
            phi: DVector::zeros(nc),
            m_inv_jt: vec![0.0; nq * nc],
            coupling: vec![0.0; nc * nc],
            mismatch: vec![0.0; nc],
            multipliers: vec![0.0; nc],
            order: vec![0; nc],
            work: vec![0.0; nc],
        }
    }

    /// Multipliers `λ` of the last [`accelerations`](Self::accelerations) call (zero on rows
    /// found redundant).
    pub fn multipliers(&self) -> &[f64] {
        &self.multipliers
    }

    /// `u̇` of `M u̇ = F + Jᵀλ`, `J u̇ = −J̇u`: with `a₀ = M⁻¹F` and `Y = M⁻¹Jᵀ`,
    /// `(J Y) λ = −J̇u − J a₀` (pivoted Cholesky, rank-revealing) and `u̇ = a₀ + Y λ`.
    pub fn accelerations<M: Model + ?Sized>(
        &mut self,
        model: &M,
        t: f64,
        q: &[f64],
        u: &[f64],
        inputs: &[f64],
        udot: &mut [f64],
    ) -> Result<(), RuntimeError> {
        let (n, nc) = (self.nq, self.nc);
        model.mass_matrix(t, q, inputs, self.mass.as_mut_slice());
        model.forcing(t, q, u, inputs, self.force.as_mut_slice());
        model.constraint_jacobian(t, q, self.jacobian.as_mut_slice());
        model.constraint_bias(t, q, u, self.bias.as_mut_slice());
        let finite = |s: &[f64]| s.iter().all(|v| v.is_finite());
        let inputs_finite = [
            self.mass.as_slice(),
            self.force.as_slice(),
            self.jacobian.as_slice(),
            self.bias.as_slice(),
        ]
        .iter()
        .all(|s| finite(s));
        if !inputs_finite {
            udot.fill(f64::NAN);
            return Err(RuntimeError::NonFiniteState { t });
        }
        let mass = self.mass.as_mut_slice();
        if !dense::cholesky(mass, n) {
            return Err(RuntimeError::SingularMassMatrix { t });
        }
        // a₀ = M⁻¹ F, into udot.
        udot.copy_from_slice(self.force.as_slice());
        dense::cholesky_solve(mass, n, udot);
        // Y = M⁻¹ Jᵀ, column r = M⁻¹ (row r of J).
        let jacobian = self.jacobian.as_slice();
        for r in 0..nc {
            let column = &mut self.m_inv_jt[r * n..(r + 1) * n];
            for (c, value) in column.iter_mut().enumerate() {
                *value = jacobian[r + nc * c];
            }
            dense::cholesky_solve(mass, n, column);
        }
        // J Y (symmetric; the lower triangle is what the factorization reads) and the
        // right-hand side −J̇u − J a₀.
        for r in 0..nc {
            for s in 0..=r {
                let y = &self.m_inv_jt[s * n..(s + 1) * n];
                self.coupling[r + nc * s] = (0..n).map(|c| jacobian[r + nc * c] * y[c]).sum();
            }
            let j_a0: f64 = (0..n).map(|c| jacobian[r + nc * c] * udot[c]).sum();
            self.mismatch[r] = -self.bias[r] - j_a0;
        }
        // J M⁻¹ Jᵀ squares J's singular values, and round-off leaves ~1e-16 relative on its
        // null directions, so pivots below 1e-12 of the largest count as redundant.
        let rank = dense::pivoted_cholesky(&mut self.coupling, nc, 1e-12, &mut self.order);
        dense::pivoted_solve(
            &self.coupling,
            nc,
            rank,
            &self.order,
            &self.mismatch,
            &mut self.multipliers,
            &mut self.work,
        );
        for r in 0..nc {
            let lambda = self.multipliers[r];
            for (value, y) in udot.iter_mut().zip(&self.m_inv_jt[r * n..(r + 1) * n]) {
                *value += y * lambda;
            }
        }
        if !finite(udot) {
            udot.fill(f64::NAN);
            return Err(RuntimeError::NonFiniteState { t });
        }
        Ok(())
    }

    /// Solves `(J W Jᵀ) x = rhs` (pivoted Cholesky) for `W = I` (`weighted` false) or
    /// `W = M⁻¹` (with `m_inv_jt` holding `M⁻¹Jᵀ`), leaving `x` in `multipliers`.
    fn solve_coupled(&mut self, weighted: bool, rhs: &[f64]) {
        let (n, nc) = (self.nq, self.nc);
        let jacobian = self.jacobian.as_slice();
        for r in 0..nc {
            for s in 0..=r {
                self.coupling[r + nc * s] = (0..n)
                    .map(|c| {
                        jacobian[r + nc * c]
                            * if weighted {
                                self.m_inv_jt[s * n + c]
                            } else {
                                jacobian[s + nc * c]
                            }
                    })
                    .sum();
            }
        }
        let rank = dense::pivoted_cholesky(&mut self.coupling, nc, 1e-12, &mut self.order);
        dense::pivoted_solve(
            &self.coupling,
            nc,
            rank,
            &self.order,
            rhs,
            &mut self.multipliers,
            &mut self.work,
        );
    }

    /// Moves `q` back onto `φ(q) = 0` (minimum-norm Gauss–Newton, `Δq = −Jᵀ(J Jᵀ)⁺φ`) and
    /// `u` onto `J u = 0` (the kinetic-energy-closest correction `Δu = −M⁻¹Jᵀ(J M⁻¹ Jᵀ)⁺ J u`).
    /// Allocates nothing.
    pub fn project<M: Model + ?Sized>(
        &mut self,
        model: &M,
        t: f64,
        q: &mut [f64],
        u: &mut [f64],
        inputs: &[f64],
        tolerance: f64,
    ) -> Result<(), RuntimeError> {
        let (n, nc) = (self.nq, self.nc);
        for _ in 0..10 {
            model.constraints(t, q, self.phi.as_mut_slice());
            if self.phi.amax() <= tolerance {
                break;
            }
            model.constraint_jacobian(t, q, self.jacobian.as_mut_slice());
            self.mismatch.copy_from_slice(self.phi.as_slice());
            let rhs = std::mem::take(&mut self.mismatch);
            self.solve_coupled(false, &rhs);
            self.mismatch = rhs;
            let jacobian = self.jacobian.as_slice();
            for (c, value) in q.iter_mut().enumerate() {
                *value -= (0..nc)
                    .map(|r| jacobian[r + nc * c] * self.multipliers[r])
                    .sum::<f64>();
            }
        }
        model.constraint_jacobian(t, q, self.jacobian.as_mut_slice());
        let jacobian = self.jacobian.as_slice();
        for r in 0..nc {
            self.mismatch[r] = (0..n).map(|c| jacobian[r + nc * c] * u[c]).sum();
        }
        if self.mismatch.iter().all(|&v| v == 0.0) {
            return Ok(());
        }
        model.mass_matrix(t, q, inputs, self.mass.as_mut_slice());
        let mass = self.mass.as_mut_slice();
        if !dense::cholesky(mass, n) {
            return Err(RuntimeError::SingularMassMatrix { t });
        }
        for r in 0..nc {
            let column = &mut self.m_inv_jt[r * n..(r + 1) * n];
            for (c, value) in column.iter_mut().enumerate() {
                *value = jacobian[r + nc * c];
            }
            dense::cholesky_solve(mass, n, column);
        }
        let rhs = std::mem::take(&mut self.mismatch);
        self.solve_coupled(true, &rhs);
        self.mismatch = rhs;
        for r in 0..nc {
            let lambda = self.multipliers[r];
            for (value, y) in u.iter_mut().zip(&self.m_inv_jt[r * n..(r + 1) * n]) {
                *value -= y * lambda;
            }
        }
        Ok(())
    }
}
