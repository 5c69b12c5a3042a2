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

use nalgebra::{DMatrix, DVector, Dyn, SVD};

use crate::partition::Partition;
use crate::{dense, Model, RuntimeError};

/// Relative threshold on singular values for rank decisions.
pub const RANK_TOLERANCE: f64 = 1e-9;

/// Mobility of a constrained model at one configuration: `dof = nq − quaternions − rank(J)`
/// (each unit quaternion's norm is one more condition on `q`) over the loop rows `φ(q) = 0`;
/// with velocity constraints `A(q) u = 0` also the rank they add, and the speeds' freedom
/// `nu − rank([J; A])`.
#[derive(Clone, Debug, PartialEq)]
pub struct Mobility {
    pub coordinates: usize,
    /// Unit quaternions among the coordinates (four coordinates, three degrees of freedom).
    pub unit_quaternions: usize,
    /// Loop-closure rows and the rank of their `J`.
    pub rows: usize,
    pub rank: usize,
    /// Singular values of the loop rows' `J`, descending.
    pub singular_values: Vec<f64>,
    /// Values below this count as zero (`RANK_TOLERANCE · σ₁`).
    pub threshold: f64,
    /// Velocity-constraint rows, and the rank they add to the loop rows' (`rank([J; A]) −
    /// rank(J)`, the same relative threshold on `[J; A]`'s singular values).
    pub velocity_rows: usize,
    pub velocity_rank: usize,
    /// Number of speeds.
    pub speeds: usize,
}

impl Mobility {
    /// Degrees of freedom of the configuration.
    pub fn dof(&self) -> usize {
        self.coordinates - self.unit_quaternions - self.rank
    }

    /// Degrees of freedom of the motion: the speeds that remain free, `nu − rank([J; A])`
    /// (equal to [`Mobility::dof`] without velocity constraints).
    pub fn speed_dof(&self) -> usize {
        self.speeds - self.rank - self.velocity_rank
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
        let quaternions = match self.unit_quaternions {
            0 => String::new(),
            1 => " (1 unit quaternion)".to_string(),
            n => format!(" ({n} unit quaternions)"),
        };
        write!(
            f,
            "{} coordinates{quaternions}, {} constraint rows, rank {}",
            self.coordinates, self.rows, self.rank,
        )?;
        if self.velocity_rows == 0 {
            return write!(f, ": {} degree{plural} of freedom", self.dof());
        }
        write!(
            f,
            "; {} velocity rows, rank {}: {} degree{plural} of freedom in the configuration, {} in the motion",
            self.velocity_rows,
            self.velocity_rank,
            self.dof(),
            self.speed_dof()
        )
    }
}

/// `J(q)` as a matrix (`nc × nu`: `φ̇ = J u`), the velocity constraints' rows `A` included.
pub fn jacobian<M: Model + ?Sized>(model: &M, t: f64, q: &[f64]) -> DMatrix<f64> {
    let mut j = DMatrix::zeros(model.nc(), model.nu());
    model.constraint_jacobian(t, q, j.as_mut_slice());
    j
}

/// The loop rows of `J(q)` (the first [`Model::holonomic_rows`]): what moves `φ(q)`.
pub fn holonomic_jacobian<M: Model + ?Sized>(model: &M, t: f64, q: &[f64]) -> DMatrix<f64> {
    jacobian(model, t, q)
        .rows(0, model.holonomic_rows())
        .into_owned()
}

/// `φ(q)` as a vector (0 on velocity-constraint rows).
pub fn residual<M: Model + ?Sized>(model: &M, t: f64, q: &[f64]) -> DVector<f64> {
    let mut phi = DVector::zeros(model.nc());
    model.constraints(t, q, phi.as_mut_slice());
    phi
}

/// The loop rows of `φ(q)` (the first [`Model::holonomic_rows`]).
pub fn holonomic_residual<M: Model + ?Sized>(model: &M, t: f64, q: &[f64]) -> DVector<f64> {
    residual(model, t, q)
        .rows(0, model.holonomic_rows())
        .into_owned()
}

/// Iteration cap of every SVD here. nalgebra's default iterates until convergence, which a
/// matrix of the sizes met here reaches in tens of sweeps; 10,000 only bounds the loop.
const MAX_SVD_ITERATIONS: usize = 10_000;

/// The SVD of `a`, or `None` if `a` has a NaN or an infinity (nalgebra's SVD of one panics
/// with "Singular value was NaN" or never returns) or the iteration does not converge.
pub fn svd(a: DMatrix<f64>, u: bool, v: bool) -> Option<SVD<f64, Dyn, Dyn>> {
    if !a.iter().all(|x| x.is_finite()) {
        return None;
    }
    // nalgebra's `svd()` convergence threshold, so that results match it bit for bit.
    SVD::try_new(a, u, v, 5.0 * f64::EPSILON, MAX_SVD_ITERATIONS)
}

/// Indices of the rows of `a` with an entry that is NaN or infinite.
pub fn non_finite_rows(a: &DMatrix<f64>) -> Vec<usize> {
    (0..a.nrows())
        .filter(|&r| a.row(r).iter().any(|x| !x.is_finite()))
        .collect()
}

/// The names of constraint `rows` of `model`.
fn row_names<M: Model + ?Sized>(model: &M, rows: &[usize]) -> Vec<String> {
    rows.iter()
        .map(|&r| model.constraint_name(r).to_string())
        .collect()
}

/// Singular values of `j`, descending, the threshold below which they count as zero and the
/// rank; an error naming the rows of `model` if `j` is not finite.
fn ranked<M: Model + ?Sized>(
    model: &M,
    j: DMatrix<f64>,
) -> Result<(Vec<f64>, f64, usize), RuntimeError> {
    let mut singular_values: Vec<f64> = if j.is_empty() {
        Vec::new()
    } else {
        let rows = non_finite_rows(&j);
        let decomposition =
            svd(j, false, false).ok_or_else(|| RuntimeError::NonFiniteConstraints {
                rows: row_names(model, &rows),
                jacobian: true,
            })?;
        decomposition.singular_values.iter().copied().collect()
    };
    singular_values.sort_by(|a, b| b.total_cmp(a));
    let threshold = singular_values.first().copied().unwrap_or(0.0) * RANK_TOLERANCE;
    let rank = singular_values.iter().filter(|&&s| s > threshold).count();
    Ok((singular_values, threshold, rank))
}

/// Rank of the loop rows' `J` at `q` from its singular values, and the rank the velocity
/// constraints add (of `[J; A]`); an error naming the rows if `J` is not finite there.
pub fn mobility<M: Model + ?Sized>(model: &M, t: f64, q: &[f64]) -> Result<Mobility, RuntimeError> {
    let (singular_values, threshold, rank) = ranked(model, holonomic_jacobian(model, t, q))?;
    let velocity_rows = model.velocity_rows();
    let velocity_rank = match velocity_rows {
        0 => 0,
        _ => ranked(model, jacobian(model, t, q))?.2.saturating_sub(rank),
    };
    Ok(Mobility {
        coordinates: model.nq(),
        unit_quaternions: model.unit_quaternions().len(),
        rows: model.holonomic_rows(),
        rank,
        singular_values,
        threshold,
        velocity_rows,
        velocity_rank,
        speeds: model.nu(),
    })
}

/// Least-squares minimum-norm solution of `A x = b`, treating singular values below
/// `RANK_TOLERANCE · σ₁` as zero, refined by one step of iterative refinement with the same
/// factorization: nalgebra's SVD reproduces some rank-deficient matrices only to ~1e-8 of
/// their entries (dimforge/nalgebra#1172; seen on the HAMR-VI loop Jacobian with a fixture
/// row, where the plain solve left `|A x − b|` at 2e-9 of `|b|` for a consistent system),
/// and the correction solve takes that to round-off. `None` if `a` or `b` is not finite.
pub fn solve_least_squares(a: &DMatrix<f64>, b: &DVector<f64>) -> Option<DVector<f64>> {
    if a.is_empty() {
        return Some(DVector::zeros(a.ncols()));
    }
    if !b.iter().all(|x| x.is_finite()) {
        return None;
    }
    let svd = svd(a.clone(), true, true)?;
    let largest = svd.singular_values.max();
    let threshold = (largest * RANK_TOLERANCE).max(f64::MIN_POSITIVE);
    let solve = |rhs: &DVector<f64>| {
        svd.solve(rhs, threshold)
            .unwrap_or_else(|_| DVector::zeros(a.ncols()))
    };
    let x = solve(b);
    let correction = solve(&(b - a * &x));
    Some(x + correction)
}

/// Independent coordinates for a model that names none: the coordinates declared first
/// are kept (they are usually the drivers: a crank, an actuator), and the dependent ones are
/// taken from the end of the list, each only if it adds a well-conditioned direction to the
/// columns of `J` already taken (Gram–Schmidt with a relative threshold).
pub fn choose_independent(j: &DMatrix<f64>) -> Vec<usize> {
    complete_independent(j, &[])
}

/// As [`choose_independent`], keeping the `held` coordinates independent: completes a
/// user's list (the actuators) when the mechanism has more degrees of freedom than it names
/// (a model extension that adds a twist, say).
pub fn complete_independent(j: &DMatrix<f64>, held: &[usize]) -> Vec<usize> {
    let scale = (0..j.ncols())
        .map(|c| j.column(c).norm())
        .fold(0.0, f64::max);
    let mut basis: Vec<DVector<f64>> = Vec::new();
    let mut dependent = Vec::new();
    for c in (0..j.ncols()).rev().filter(|c| !held.contains(c)) {
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

/// Independent speeds of a model with velocity constraints, from `J` with all its rows
/// (`[J_loops; A]`, `nc × nu`): the speeds not in `independent` (the coordinates chosen
/// for the loops, [`complete_independent`]) are dependent on the loops; then, in declaration
/// order, each further speed is dependent if its column adds a well-conditioned direction
/// (Gram–Schmidt, relative threshold 1e-6) to those taken, skipping the `held` speeds (named
/// by the user). Declaration order makes the tree's root speeds dependent first: a floating
/// base's translation rather than a wheel's spin, so the rates of turning, leaning and
/// rolling written as `u0` are kept and the base's velocity follows from them.
pub fn independent_speeds(j: &DMatrix<f64>, independent: &[usize], held: &[usize]) -> Vec<usize> {
    let scale = (0..j.ncols())
        .map(|c| j.column(c).norm())
        .fold(0.0, f64::max);
    let mut basis: Vec<DVector<f64>> = Vec::new();
    let mut dependent: Vec<usize> = (0..j.ncols())
        .filter(|c| !independent.contains(c))
        .collect();
    let add = |c: usize, basis: &mut Vec<DVector<f64>>| {
        let mut column = j.column(c).into_owned();
        for direction in basis.iter() {
            let along = column.dot(direction);
            column -= direction * along;
        }
        let norm = column.norm();
        let new = norm > scale * 1e-6;
        if new {
            basis.push(column / norm);
        }
        new
    };
    for &c in &dependent {
        add(c, &mut basis);
    }
    for c in 0..j.ncols() {
        if dependent.contains(&c) || held.contains(&c) {
            continue;
        }
        if add(c, &mut basis) {
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
    /// Loops that cannot close exactly — rows that contradict each other, as axes meant to
    /// meet that miss by a little (HAMR-VI's published five-bar points: 1.4e-10 m) — are
    /// accepted when the steps stall at a least-squares solution (`J_freeᵀ φ ≈ 0`) with
    /// `max |φ|` at most this; the caller reads the `φ` left (a warning, not an error).
    pub inconsistency: f64,
}

impl Default for AssemblyOptions {
    fn default() -> Self {
        AssemblyOptions {
            tolerance: 1e-13,
            max_iterations: 100,
            // A nanometre: below any fabrication tolerance, far above round-off.
            inconsistency: 1e-9,
        }
    }
}

/// Solves `φ(q) = 0` moving along the speeds not listed in `fixed`, starting from `q`
/// (updated in place): damped Newton steps `δ_free = −J_free⁺ φ` (rank-revealing least
/// squares), `q ← q ⊕ δ` ([`retract`]: `q + δ` where `q̇ = u`), halved until `|φ|` decreases.
/// Fails with the loop rows that remain open, that are not finite, or that no step can move
/// (see [`Unclosed`]).
pub fn assemble<M: Model + ?Sized>(
    model: &M,
    t: f64,
    q: &mut [f64],
    fixed: &[usize],
    options: &AssemblyOptions,
) -> Result<usize, RuntimeError> {
    // Velocity constraints have no position form: only the loop rows are closed.
    let residual = |q: &[f64]| holonomic_residual(model, t, q);
    let jacobian = |q: &[f64]| holonomic_jacobian(model, t, q);
    let closed = if model.rates_are_speeds() {
        close(residual, jacobian, q, fixed, options)
    } else {
        let retract = |q: &[f64], delta: &[f64], out: &mut [f64]| retract(model, t, q, delta, out);
        close_with(residual, jacobian, &retract, q, fixed, options)
    };
    closed.map_err(|unclosed| match unclosed {
        Unclosed::Open(phi) => assembly_error(model, phi.as_slice()),
        Unclosed::NonFinite { rows, jacobian } => RuntimeError::NonFiniteConstraints {
            rows: row_names(model, &rows),
            jacobian,
        },
        Unclosed::Stationary { row, residual } => RuntimeError::StationaryConstraint {
            row: model.constraint_name(row).to_string(),
            residual,
        },
    })
}

/// Moves the `fixed` coordinates of a closed configuration `q` to `target` (their values,
/// in `fixed`'s order) in steps, closing the loops at each from the last (natural-parameter
/// continuation): from held values far from the closed ones a single Newton solve can stall
/// (HAMR-VI at the ±0.3 mm corners of its actuator grid: the SFB's fb2 rows stayed 2e-4
/// open). Each step is the rest of the way or what last worked, halved on failure down to
/// 1/1024 of the way; doubled after a success. Returns the Newton iterations taken; on
/// failure `q` is left at the last closed configuration.
pub fn assemble_along<M: Model + ?Sized>(
    model: &M,
    t: f64,
    q: &mut [f64],
    fixed: &[usize],
    target: &[f64],
    options: &AssemblyOptions,
) -> Result<usize, RuntimeError> {
    let start: Vec<f64> = fixed.iter().map(|&c| q[c]).collect();
    let (mut done, mut step, mut iterations) = (0.0_f64, 1.0_f64, 0);
    while done < 1.0 {
        let next = (done + step).min(1.0);
        let mut trial = q.to_vec();
        for (k, &c) in fixed.iter().enumerate() {
            trial[c] = start[k] + next * (target[k] - start[k]);
        }
        match assemble(model, t, &mut trial, fixed, options) {
            Ok(taken) => {
                iterations += taken;
                q.copy_from_slice(&trial);
                done = next;
                step = (2.0 * step).min(1.0);
            }
            Err(error) if step <= 1.0 / 1024.0 => return Err(error),
            Err(_) => step *= 0.5,
        }
    }
    Ok(iterations)
}

/// Why [`close`] stopped short of `φ = 0` (rows are indices into `φ`).
#[derive(Clone, Debug, PartialEq)]
pub enum Unclosed {
    /// The steps stalled or the iterations ran out with this `φ`.
    Open(DVector<f64>),
    /// `φ` at the current `q` (or, with `jacobian`, `J` of the free coordinates) has a NaN or
    /// an infinity in these rows.
    NonFinite { rows: Vec<usize>, jacobian: bool },
    /// The steps stalled, and row `row`, open by `residual`, has a zero gradient in the free
    /// coordinates (below `RANK_TOLERANCE` of the largest row's): no step can close it.
    Stationary { row: usize, residual: f64 },
}

/// `q ⊕ δ = q + W(q) δ` into `out`, each unit quaternion scaled back to unit norm: a step of
/// `δ` along the speeds' directions (`δ` has length `nu`). To first order it moves `φ` by
/// `J δ`, so Newton steps through it converge as in coordinates where `q̇ = u`.
pub fn retract<M: Model + ?Sized>(model: &M, t: f64, q: &[f64], delta: &[f64], out: &mut [f64]) {
    model.kinematic_rates(t, q, delta, out);
    for (value, start) in out.iter_mut().zip(q) {
        *value += start;
    }
    crate::model::normalize_quaternions(model.unit_quaternions(), out);
}

/// [`assemble`] for any residual `φ(q)` and its Jacobian (e.g. loops and fixtures together,
/// in the statics), for coordinates where `q̇ = u`: returns the iterations taken, or why it
/// stopped. No step is taken to a `q` where `φ` is not finite, so `q` stays where `φ` was
/// last finite.
pub fn close(
    residual: impl Fn(&[f64]) -> DVector<f64>,
    jacobian: impl Fn(&[f64]) -> DMatrix<f64>,
    q: &mut [f64],
    fixed: &[usize],
    options: &AssemblyOptions,
) -> Result<usize, Unclosed> {
    let add = |q: &[f64], delta: &[f64], out: &mut [f64]| {
        for ((value, start), step) in out.iter_mut().zip(q).zip(delta) {
            *value = start + step;
        }
    };
    close_with(residual, jacobian, &add, q, fixed, options)
}

/// `retract(q, δ, out)`: the configuration a step `δ` along the Jacobian's columns reaches.
pub type Retraction<'a> = &'a dyn Fn(&[f64], &[f64], &mut [f64]);

/// [`close`] with the Jacobian's columns along the directions of `retract(q, δ, out)`
/// ([`retract`] for a model with quaternions): `fixed` lists columns held.
pub fn close_with(
    residual: impl Fn(&[f64]) -> DVector<f64>,
    jacobian: impl Fn(&[f64]) -> DMatrix<f64>,
    retract: Retraction<'_>,
    q: &mut [f64],
    fixed: &[usize],
    options: &AssemblyOptions,
) -> Result<usize, Unclosed> {
    let mut phi = residual(q);
    let non_finite = |phi: &DVector<f64>| phi.iter().any(|x| !x.is_finite());
    if non_finite(&phi) {
        let rows = (0..phi.len()).filter(|&r| !phi[r].is_finite()).collect();
        return Err(Unclosed::NonFinite {
            rows,
            jacobian: false,
        });
    }
    let mut j_free = DMatrix::zeros(0, 0);
    for iteration in 0..options.max_iterations {
        if phi.amax() <= options.tolerance {
            return Ok(iteration);
        }
        let j = jacobian(q);
        let columns = j.ncols();
        let free: Vec<usize> = (0..columns).filter(|c| !fixed.contains(c)).collect();
        j_free = j.select_columns(&free);
        let rows = non_finite_rows(&j_free);
        if !rows.is_empty() {
            return Err(Unclosed::NonFinite {
                rows,
                jacobian: true,
            });
        }
        let Some(step) = solve_least_squares(&j_free, &(-&phi)) else {
            break;
        };
        // Next to the least-squares fit of contradicting rows: the Gauss–Newton step itself
        // predicts no real decrease (for rows that can close it predicts φ ≈ 0); this step
        // lands on the fit, and is the last.
        let predicted = &phi + &j_free * &step;
        let at_floor = phi.amax() <= options.inconsistency && predicted.norm() >= 0.99 * phi.norm();
        let mut scale = 1.0;
        let before = phi.norm();
        let mut trial = q.to_vec();
        let mut delta = vec![0.0; columns];
        loop {
            for (k, &c) in free.iter().enumerate() {
                delta[c] = scale * step[k];
            }
            retract(q, &delta, &mut trial);
            let trial_phi = residual(&trial);
            if trial_phi.norm() < before || (scale < 1e-6 && !non_finite(&trial_phi)) {
                q.copy_from_slice(&trial);
                phi = trial_phi;
                break;
            }
            if scale < 1e-6 {
                break;
            }
            scale *= 0.5;
        }
        if scale < 1e-6 {
            break;
        }
        if at_floor {
            return Ok(iteration + 1);
        }
    }
    if phi.amax() <= options.tolerance || least_squares_floor(&phi, &j_free, options) {
        return Ok(options.max_iterations);
    }
    Err(stationary_row(&phi, &j_free, options.tolerance).unwrap_or(Unclosed::Open(phi)))
}

/// The stalled `φ` is a small least-squares residual of rows that contradict each other:
/// `max |φ| ≤ options.inconsistency` and `φ` (nearly) normal to every free column of `j`,
/// `|jᵀφ| ≤ 1e-6·‖j‖·|φ|`, so no step can reduce it.
fn least_squares_floor(phi: &DVector<f64>, j: &DMatrix<f64>, options: &AssemblyOptions) -> bool {
    if phi.amax() > options.inconsistency || j.nrows() != phi.len() || j.ncols() == 0 {
        return false;
    }
    (j.transpose() * phi).norm() <= 1e-6 * j.norm() * phi.norm()
}

/// The open row (`|φ| > tolerance`) with the largest residual among those whose gradient
/// `j` (the free columns, at the last Newton step) is zero relative to the largest row's.
fn stationary_row(phi: &DVector<f64>, j: &DMatrix<f64>, tolerance: f64) -> Option<Unclosed> {
    // With nothing free, every row is open rather than stationary.
    if j.nrows() != phi.len() || j.ncols() == 0 {
        return None;
    }
    let largest = j.row_iter().map(|row| row.norm()).fold(0.0, f64::max);
    (0..phi.len())
        .filter(|&r| phi[r].abs() > tolerance && j.row(r).norm() <= largest * RANK_TOLERANCE)
        .max_by(|&a, &b| phi[a].abs().total_cmp(&phi[b].abs()))
        .map(|row| Unclosed::Stationary {
            row,
            residual: phi[row],
        })
}

/// The open loop row with the largest residual in `phi`, as an error (the rows that are
/// not finite, if any are).
pub(crate) fn assembly_error<M: Model + ?Sized>(model: &M, phi: &[f64]) -> RuntimeError {
    let rows: Vec<usize> = (0..phi.len()).filter(|&r| !phi[r].is_finite()).collect();
    if !rows.is_empty() {
        return RuntimeError::NonFiniteConstraints {
            rows: row_names(model, &rows),
            jacobian: false,
        };
    }
    let worst = (0..phi.len())
        .max_by(|&a, &b| phi[a].abs().total_cmp(&phi[b].abs()))
        .unwrap_or(0);
    RuntimeError::AssemblyFailed {
        row: model.constraint_name(worst).to_string(),
        residual: phi.get(worst).copied().unwrap_or(0.0),
        norm: phi.iter().map(|v| v * v).sum::<f64>().sqrt(),
    }
}

/// Speeds consistent with `J u = 0`: keeps the `fixed` speeds and solves the others by least
/// squares (`J_free u_free = −J_fixed u_fixed`). An error naming the rows if `J` is not finite
/// at `q`.
pub fn assemble_speeds<M: Model + ?Sized>(
    model: &M,
    t: f64,
    q: &[f64],
    u: &mut [f64],
    fixed: &[usize],
) -> Result<(), RuntimeError> {
    let j = jacobian(model, t, q);
    let free: Vec<usize> = (0..model.nu()).filter(|c| !fixed.contains(c)).collect();
    let mut rhs = DVector::zeros(model.nc());
    for &c in fixed {
        rhs -= j.column(c) * u[c];
    }
    let solution = solve_least_squares(&j.select_columns(&free), &rhs).ok_or_else(|| {
        let rows = non_finite_rows(&j);
        // Finite J with a non-finite right-hand side: the given speeds are not finite.
        if rows.is_empty() {
            return RuntimeError::NonFinite {
                what: "the speeds u0 of the independent coordinates",
            };
        }
        RuntimeError::NonFiniteConstraints {
            rows: row_names(model, &rows),
            jacobian: true,
        }
    })?;
    for (k, &c) in free.iter().enumerate() {
        u[c] = solution[k];
    }
    Ok(())
}

/// Workspace for constrained dynamics and projection. [`accelerations`](Self::accelerations)
/// and [`project`](Self::project) allocate nothing: `M = L Lᵀ` by Cholesky, then
/// `Z = L⁻¹ Jᵀ` by forward substitution, so that `J M⁻¹ Jᵀ = Zᵀ Z` (a Gram matrix, symmetric
/// positive semidefinite by construction) is factored by a diagonally pivoted Cholesky that
/// drops redundant rows (`u̇` is unique even where `λ` is not).
///
/// Redundancy is mostly structural (a planar loop closed by a spatial revolute has three
/// rows that follow from the other two everywhere): once a solve finds rows redundant, the
/// accelerations use only the pivoted Cholesky's independent rows (`active`) — on the HAMR
/// robot 24 of 60, two fifths of the work in `Z` and a sixth in `Zᵀ Z`. The choice is
/// undone when those rows lose rank, or when [`project`](Self::project), which always uses
/// every row, finds a speed violation (a row that was redundant no longer is).
///
/// Where the independent rows fall into blocks that share no dependent speed (each leg of a
/// walking robot closing its own loops), the accelerations and the shifted systems switch to
/// coordinate partitioning (`partition.rs`): each block's rows solved for as many of its
/// speeds, then the independent speeds' `Nᵀ M N` (HAMR-VI's robot: four 6 × 6 blocks and a
/// 14 × 14 system where the range space works on 38 × 38 and 24 × 24; its trot's integration
/// ~25 % faster). The same `u̇`, and `λ` on the independent rows, to round-off
/// (`tests/equations/hamr_robot.rs`). The range-space solve remains the first one and the one
/// for every state the partition does not fit.
#[derive(Clone, Debug)]
pub struct ConstrainedSolver {
    /// Speeds (the size of `M`) and constraint rows.
    nu: usize,
    nc: usize,
    /// `q ⊕ δ` of a speed-space correction `δ` ([`retract`]; models with quaternions, empty
    /// where `q̇ = u`).
    rates: Vec<f64>,
    /// `M`, then its Cholesky factor `L` (lower triangle).
    mass: DMatrix<f64>,
    force: DVector<f64>,
    jacobian: DMatrix<f64>,
    bias: DVector<f64>,
    phi: DVector<f64>,
    /// `Z = L⁻¹ Jᵀ`, `nu × nc` column-major: column r is `L⁻¹` (row r of J).
    scaled: Vec<f64>,
    /// `Zᵀ Z = J M⁻¹ Jᵀ` (or `J Jᵀ`), then its pivoted factor, `nc × nc`.
    coupling: Vec<f64>,
    mismatch: Vec<f64>,
    multipliers: Vec<f64>,
    order: Vec<usize>,
    work: Vec<f64>,
    /// Rows of `J` the accelerations use, increasing (all, until some are found redundant).
    active: Vec<usize>,
    /// The rows of the last factorization of `Zᵀ Z` (`active`, or all rows where the active
    /// ones lost rank), and its rank.
    factored: Vec<usize>,
    rank: usize,
    /// Where `mass` holds the factor of `M` (its strict upper triangle still `M`'s, the
    /// diagonal of `M` in `mass_diagonal`) and `jacobian` holds `J`: the `(t, q, inputs)` of
    /// the last successful [`accelerations`](Self::accelerations), for
    /// [`factor_shifted_from`](Self::factor_shifted_from); `None` once they are overwritten.
    evaluated_at: Option<f64>,
    evaluated_q: Vec<f64>,
    evaluated_inputs: Vec<f64>,
    mass_diagonal: Vec<f64>,
    /// Dependent and independent speeds for the active rows where those fall into blocks
    /// ([`Partition`]): the accelerations and shifted systems are then solved in the
    /// independent speeds, `mass` left as `M` (or `M − γD`).
    partition: Option<Partition>,
    /// The active rows for which [`Partition::choose`] last declined.
    declined: Vec<usize>,
    /// Whether the last [`factor_shifted`](Self::factor_shifted) factored by `partition`.
    shifted_by_partition: bool,
    /// Whether the last `accelerations` or `factor_shifted` solved by `partition`.
    last_by_partition: bool,
}

/// Whether every value is finite (no early exit: branch-free, and these slices are short).
fn all_finite(s: &[f64]) -> bool {
    s.iter().fold(true, |ok, v| ok & v.is_finite())
}

/// Relative pivot threshold of the pivoted Cholesky of `J M⁻¹ Jᵀ` and `J Jᵀ`: these square
/// J's singular values, and round-off leaves ~1e-16 relative on their null directions, so
/// pivots below 1e-12 of the largest count as redundant.
const PIVOT_TOLERANCE: f64 = 1e-12;

impl ConstrainedSolver {
    /// Storage for `model`'s sizes ([`ConstrainedSolver::new`]).
    pub fn for_model<M: Model + ?Sized>(model: &M) -> ConstrainedSolver {
        ConstrainedSolver::new(model.nq(), model.nu(), model.nc())
    }

    /// Storage for a model with `nu` speeds and `nc` constraint rows (`nq == nu`, or `nq`
    /// coordinates for a model with quaternions, whose position corrections go through
    /// `q̇ = W(q) u`).
    pub fn new(nq: usize, nu: usize, nc: usize) -> ConstrainedSolver {
        ConstrainedSolver {
            rates: if nq == nu { Vec::new() } else { vec![0.0; nq] },
            nu,
            nc,
            mass: DMatrix::zeros(nu, nu),
            force: DVector::zeros(nu),
            jacobian: DMatrix::zeros(nc, nu),
            bias: DVector::zeros(nc),
            phi: DVector::zeros(nc),
            scaled: vec![0.0; nu * nc],
            coupling: vec![0.0; nc * nc],
            mismatch: vec![0.0; nc],
            multipliers: vec![0.0; nc],
            order: vec![0; nc],
            work: vec![0.0; nc],
            active: (0..nc).collect(),
            factored: Vec::with_capacity(nc),
            rank: 0,
            evaluated_at: None,
            evaluated_q: Vec::with_capacity(nq),
            evaluated_inputs: Vec::new(),
            mass_diagonal: vec![0.0; nu],
            partition: None,
            declined: Vec::with_capacity(nc),
            shifted_by_partition: false,
            last_by_partition: false,
        }
    }

    /// Multipliers `λ` of the last [`accelerations`](Self::accelerations) call (zero on rows
    /// found redundant).
    pub fn multipliers(&self) -> &[f64] {
        &self.multipliers
    }

    /// `Z = L⁻¹ Jᵀ` (into `scaled`) from the factor in `mass` and the Jacobian in `jacobian`,
    /// on the rows `rows` (column k of `Z` is row `rows[k]` of `J`), and the lower triangle of
    /// `Zᵀ Z = J M⁻¹ Jᵀ` on them (into `coupling`).
    fn couple_rows(&mut self, rows: &[usize]) {
        let n = self.nu;
        self.gather_rows(rows, self.nc);
        dense::forward_substitute_columns(self.mass.as_slice(), n, &mut self.scaled, rows.len());
        dense::gram_lower(&self.scaled, n, rows.len(), &mut self.coupling);
    }

    /// Factors the first `rows × rows` of `coupling` (pivoted) and solves it for `mismatch`
    /// into `multipliers`; returns the rank.
    fn solve_coupling(&mut self, rows: usize) -> usize {
        let rank =
            dense::pivoted_cholesky(&mut self.coupling, rows, PIVOT_TOLERANCE, &mut self.order);
        dense::pivoted_solve(
            &self.coupling,
            rows,
            rank,
            &self.order,
            &self.mismatch,
            &mut self.multipliers,
            &mut self.work,
        );
        rank
    }

    /// With `M`'s Cholesky factor `L` in `mass` and `J` in `jacobian`: `Z = L⁻¹ Jᵀ` (into
    /// `scaled`) and the pivoted factor of `Zᵀ Z = J M⁻¹ Jᵀ` (into `coupling`) on the active
    /// rows, or on every row where those have lost rank; the rows and rank into `factored`
    /// and `rank`. When some of every row are found redundant, `active` becomes the
    /// independent ones, for the next factorization.
    fn factor_coupling(&mut self) {
        let (n, nc) = (self.nu, self.nc);
        let mut rows = std::mem::take(&mut self.factored);
        rows.clear();
        rows.extend_from_slice(&self.active);
        loop {
            let used = rows.len();
            self.couple_rows(&rows);
            self.rank =
                dense::pivoted_cholesky(&mut self.coupling, used, PIVOT_TOLERANCE, &mut self.order);
            // A non-finite J says nothing of which rows are redundant.
            if self.rank == used || !all_finite(&self.scaled[..n * used]) {
                break;
            }
            if used == nc {
                self.active.clear();
                self.active.extend(self.order[..self.rank].iter().copied());
                self.active.sort_unstable();
                break;
            }
            // The active rows lost rank: every row (and choose again).
            rows.clear();
            rows.extend(0..nc);
        }
        self.factored = rows;
    }

    /// Solves `M x = f + Jᵀλ`, `J x = −b` with the factors of
    /// [`factor_coupling`](Self::factor_coupling): `f` in `x` on entry, `x` on return; `b`
    /// is the model's `J̇u` in `bias` where `with_bias`, 0 otherwise. With `w = L⁻¹ f`,
    /// `(Zᵀ Z) λ = −b − Zᵀ w` and `x = L⁻ᵀ (w + Z λ)`; `λ` into `multipliers` (0 on the rows
    /// not factored). Returns whether the right-hand side of `λ` was finite.
    fn solve_factored(&mut self, x: &mut [f64], with_bias: bool) -> bool {
        let n = self.nu;
        dense::forward_substitute(self.mass.as_slice(), n, x);
        let used = self.factored.len();
        dense::transpose_times(&self.scaled, n, used, x, &mut self.mismatch);
        for (m, &row) in self.mismatch.iter_mut().zip(&self.factored) {
            let bias = if with_bias { self.bias[row] } else { 0.0 };
            *m = -bias - *m;
        }
        let finite = all_finite(&self.mismatch[..used]);
        dense::pivoted_solve(
            &self.coupling,
            used,
            self.rank,
            &self.order,
            &self.mismatch,
            &mut self.multipliers,
            &mut self.work,
        );
        dense::add_times(&self.scaled, n, used, &self.multipliers, x);
        dense::back_substitute(self.mass.as_slice(), n, x);
        self.work[..used].copy_from_slice(&self.multipliers[..used]);
        self.multipliers.fill(0.0);
        for (&row, &value) in self.factored.iter().zip(&self.work[..used]) {
            self.multipliers[row] = value;
        }
        finite
    }

    /// `M`, `F`, `J` and `J̇u` at `(t, q, u)` into the solver's storage.
    fn evaluate<M: Model + ?Sized>(
        &mut self,
        model: &M,
        t: f64,
        q: &[f64],
        u: &[f64],
        inputs: &[f64],
    ) {
        self.evaluated_at = None;
        model.constrained_terms(
            t,
            q,
            u,
            inputs,
            self.mass.as_mut_slice(),
            self.force.as_mut_slice(),
            self.jacobian.as_mut_slice(),
            self.bias.as_mut_slice(),
        );
    }

    /// `u̇` of `M u̇ = F + Jᵀλ`, `J u̇ = −J̇u`: with `M = L Lᵀ`, `w = L⁻¹F` and `Z = L⁻¹Jᵀ`,
    /// `(Zᵀ Z) λ = −J̇u − Zᵀ w` (that is `(J M⁻¹ Jᵀ) λ = −J̇u − J M⁻¹F`; pivoted Cholesky,
    /// rank-revealing) and `u̇ = L⁻ᵀ (w + Z λ)`; or by the partition, where there is one.
    pub fn accelerations<M: Model + ?Sized>(
        &mut self,
        model: &M,
        t: f64,
        q: &[f64],
        u: &[f64],
        inputs: &[f64],
        udot: &mut [f64],
    ) -> Result<(), RuntimeError> {
        let n = self.nu;
        self.evaluate(model, t, q, u, inputs);
        for (i, diagonal) in self.mass_diagonal.iter_mut().enumerate() {
            *diagonal = self.mass[(i, i)];
        }
        self.last_by_partition = self.accelerations_partitioned(udot);
        if self.last_by_partition {
            self.record_evaluation(t, q, inputs);
            return Ok(());
        }
        // Non-finite inputs are found where they surface, not by scanning all of them first:
        // a NaN or infinity in (the lower triangle of) M fails the factorization, and one in
        // F, J or J̇u reaches the right-hand side `−J̇u − Zᵀw` or `u̇` (0·∞ and 0·NaN are NaN).
        if !dense::cholesky(self.mass.as_mut_slice(), n) {
            // Rare path: M again (the failed factorization overwrote part of it).
            model.mass_matrix(t, q, inputs, self.mass.as_mut_slice());
            let inputs_finite = all_finite(self.mass.as_slice())
                && all_finite(self.force.as_slice())
                && all_finite(self.jacobian.as_slice())
                && all_finite(self.bias.as_slice());
            if !inputs_finite {
                udot.fill(f64::NAN);
                return Err(RuntimeError::NonFiniteState { t });
            }
            return Err(RuntimeError::SingularMassMatrix { t });
        }
        self.factor_coupling();
        let udot = &mut udot[..n];
        udot.copy_from_slice(self.force.as_slice());
        let mismatch_finite = self.solve_factored(udot, true);
        if !(mismatch_finite && all_finite(udot)) {
            udot.fill(f64::NAN);
            return Err(RuntimeError::NonFiniteState { t });
        }
        self.choose_partition();
        self.record_evaluation(t, q, inputs);
        Ok(())
    }

    fn record_evaluation(&mut self, t: f64, q: &[f64], inputs: &[f64]) {
        self.evaluated_at = Some(t);
        self.evaluated_q.clear();
        self.evaluated_q.extend_from_slice(q);
        self.evaluated_inputs.clear();
        self.evaluated_inputs.extend_from_slice(inputs);
    }

    /// After a range-space factorization on independent active rows: a [`Partition`] of
    /// them, unless one exists or it declined these rows before.
    fn choose_partition(&mut self) {
        let independent = self.rank == self.factored.len() && self.factored == self.active;
        if self.partition.is_some() || !independent || self.declined == self.active {
            return;
        }
        self.partition =
            Partition::choose(self.jacobian.as_slice(), self.nc, self.nu, &self.active);
        if self.partition.is_none() {
            self.declined.clone_from(&self.active);
        }
    }

    /// The partition's factors of `A` in `mass` with `J` (and `J̇u` where `bias`); drops a
    /// partition that no longer fits the rows or the state. Leaves `mass` as it was.
    fn factor_partitioned(&mut self, bias: bool) -> bool {
        let Some(partition) = self.partition.as_mut() else {
            return false;
        };
        let bias = bias.then_some(self.bias.as_slice());
        if !partition.is_for(&self.active) || !partition.factor(self.jacobian.as_slice(), bias) {
            self.partition = None;
            return false;
        }
        partition.reduce(self.mass.as_slice())
    }

    /// `u̇` and `λ` by the partition, where there is one that fits; `false` leaves the solve
    /// (and the diagnosis of anything singular or not finite) to the range-space path, with
    /// `M` untouched.
    fn accelerations_partitioned(&mut self, udot: &mut [f64]) -> bool {
        if !self.factor_partitioned(true) {
            return false;
        }
        let Some(partition) = self.partition.as_mut() else {
            return false;
        };
        let udot = &mut udot[..self.nu];
        udot.copy_from_slice(self.force.as_slice());
        partition.solve(self.mass.as_slice(), udot);
        partition.multipliers(
            self.mass.as_slice(),
            self.force.as_slice(),
            udot,
            &mut self.multipliers,
        );
        all_finite(udot) && all_finite(&self.multipliers)
    }

    /// The number of blocks of the coordinate partitioning (dependent speeds solved for blocks
    /// of loop rows apart, then the independent speeds' system) by which
    /// the last [`accelerations`](Self::accelerations),
    /// [`factor_shifted`](Self::factor_shifted) or [`project`](Self::project) (its speeds)
    /// solved; `None` where it was the range-space solve (the first calls, loops in one
    /// block, or a partition that no longer fitted).
    pub fn partition_blocks(&self) -> Option<usize> {
        self.partition
            .as_ref()
            .filter(|_| self.last_by_partition)
            .map(Partition::block_count)
    }

    /// Whether the last successful [`accelerations`](Self::accelerations) was at exactly
    /// `(t, q, inputs)` and its `M` and `J` are still held (see
    /// [`factor_shifted_from`](Self::factor_shifted_from)).
    pub fn evaluated_at(&self, t: f64, q: &[f64], inputs: &[f64]) -> bool {
        // Bit for bit: a state that merely compares equal (−0 and 0) is another point.
        let same = |a: &[f64], b: &[f64]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
        };
        self.evaluated_at
            .is_some_and(|at| at.to_bits() == t.to_bits())
            && same(&self.evaluated_q, q)
            && same(&self.evaluated_inputs, inputs)
    }

    /// Factors the system of a linearly implicit step at `(t, q, u)`: `M − γ D` with the
    /// loops' `J` (`D` the caller's, `nu × nu` column-major, e.g. [`Model::contact_damping`];
    /// `γ ≥ 0`), for [`solve_shifted`](Self::solve_shifted). `M`, `J` are the model's at the
    /// point (its `F` and `J̇u` are computed and not used). Returns `false` where `M − γ D` is
    /// not positive definite (or not finite).
    #[allow(clippy::too_many_arguments)]
    pub fn factor_shifted<M: Model + ?Sized>(
        &mut self,
        model: &M,
        t: f64,
        q: &[f64],
        u: &[f64],
        inputs: &[f64],
        gamma: f64,
        damping: &[f64],
    ) -> bool {
        self.evaluate(model, t, q, u, inputs);
        self.factor_shifted_mass(gamma, damping)
    }

    /// [`factor_shifted`](Self::factor_shifted) at the point of `evaluated`'s last
    /// [`accelerations`](Self::accelerations) (check [`evaluated_at`](Self::evaluated_at)
    /// first), with its `M` and `J` instead of evaluating them again: a linearly implicit
    /// step factors at the state whose derivative it has just evaluated. `M` comes back from
    /// its factor's untouched strict upper triangle and the saved diagonal: bit for bit for
    /// generated models, whose `M` is symmetric to the bit (one expression for both
    /// triangles); a hand-written `Model` whose triangles differ in round-off gets its upper
    /// one, as good a matrix for a W-method. Returns `false` as `factor_shifted` does, and
    /// where `evaluated` no longer holds `M` and `J`.
    pub fn factor_shifted_from(
        &mut self,
        evaluated: &ConstrainedSolver,
        gamma: f64,
        damping: &[f64],
    ) -> bool {
        let n = self.nu;
        if evaluated.evaluated_at.is_none() || evaluated.nu != n || evaluated.nc != self.nc {
            return false;
        }
        self.evaluated_at = None;
        let (source, target) = (evaluated.mass.as_slice(), self.mass.as_mut_slice());
        for j in 0..n {
            for i in 0..j {
                target[i + n * j] = source[i + n * j];
                target[j + n * i] = source[i + n * j];
            }
            target[j + n * j] = evaluated.mass_diagonal[j];
        }
        self.jacobian.copy_from(&evaluated.jacobian);
        self.factor_shifted_mass(gamma, damping)
    }

    /// With `M` in `mass` and `J` in `jacobian`: the factors of `M − γ D` and of the coupling.
    fn factor_shifted_mass(&mut self, gamma: f64, damping: &[f64]) -> bool {
        for (m, d) in self.mass.as_mut_slice().iter_mut().zip(damping) {
            *m -= gamma * d;
        }
        self.shifted_by_partition = self.factor_partitioned(false);
        self.last_by_partition = self.shifted_by_partition;
        if self.shifted_by_partition {
            return true;
        }
        if !dense::cholesky(self.mass.as_mut_slice(), self.nu) {
            return false;
        }
        self.factor_coupling();
        self.choose_partition();
        true
    }

    /// Solves `(M − γ D) x = f + Jᵀλ`, `J x = 0` with the factors of
    /// [`factor_shifted`](Self::factor_shifted): `f` in `x` on entry, `x` on return.
    pub fn solve_shifted(&mut self, x: &mut [f64]) {
        match (self.shifted_by_partition, self.partition.as_mut()) {
            (true, Some(partition)) => partition.solve(self.mass.as_slice(), &mut x[..self.nu]),
            _ => {
                self.solve_factored(x, false);
            }
        }
    }

    /// Moves `q` back onto `φ(q) = 0` (minimum-norm Gauss–Newton over the loop rows,
    /// `Δq = −Jᵀ(J Jᵀ)⁺φ`, until `max |φ| ≤ tolerance`, at most 10 steps) and then, unless
    /// `max |J u|` is already within `tolerance`, `u` onto `J u = 0` over every row, the
    /// velocity constraints' `A u = 0` included (the kinetic-energy-closest correction
    /// `Δu = −M⁻¹Jᵀ(J M⁻¹ Jᵀ)⁺ J u`). Returns whether `q` or `u` was changed (a state already
    /// within tolerance is left bit for bit as it was). Allocates nothing.
    ///
    /// Both corrections use the independent rows the last factorization chose (`active`):
    /// they span every row's directions, so the redundant rows' `φ` and `J u` go to zero with
    /// theirs, at a fraction of the cost (HAMR-VI's robot: 24 of 60 rows). Every row is used
    /// where that fails: the position steps stall, or `J u` is left above `tolerance`.
    pub fn project<M: Model + ?Sized>(
        &mut self,
        model: &M,
        t: f64,
        q: &mut [f64],
        u: &mut [f64],
        inputs: &[f64],
        tolerance: f64,
    ) -> Result<bool, RuntimeError> {
        let (n, nc) = (self.nu, self.nc);
        self.evaluated_at = None;
        let mut rows = std::mem::take(&mut self.factored);
        rows.clear();
        rows.extend_from_slice(&self.active);
        let mut changed = false;
        let mut previous = f64::INFINITY;
        for _ in 0..10 {
            model.constraints(t, q, self.phi.as_mut_slice());
            let open = self.phi.amax();
            if open <= tolerance {
                break;
            }
            if open >= previous {
                rows.clear();
                rows.extend(0..nc);
            }
            previous = open;
            model.constraint_jacobian(t, q, self.jacobian.as_mut_slice());
            self.gather_rows(&rows, model.holonomic_rows());
            let used = rows.len();
            dense::gram_lower(&self.scaled, n, used, &mut self.coupling);
            for (m, &r) in self.mismatch.iter_mut().zip(&rows) {
                *m = self.phi[r];
            }
            self.solve_coupling(used);
            // Δq = −J_rowsᵀ x: with quaternions the step is along the speeds, `q ← q ⊕ Δq`.
            let delta = self.force.as_mut_slice();
            delta.fill(0.0);
            dense::add_times(&self.scaled, n, used, &self.multipliers, delta);
            if self.rates.is_empty() {
                for (value, step) in q.iter_mut().zip(delta.iter()) {
                    *value -= step;
                }
            } else {
                delta.iter_mut().for_each(|step| *step = -*step);
                retract(model, t, q, self.force.as_slice(), &mut self.rates);
                q.copy_from_slice(&self.rates);
            }
            changed = true;
        }
        model.constraint_jacobian(t, q, self.jacobian.as_mut_slice());
        if self.constraint_speeds(u) <= tolerance {
            self.factored = rows;
            return Ok(changed);
        }
        model.mass_matrix(t, q, inputs, self.mass.as_mut_slice());
        self.last_by_partition = self.project_speeds_partitioned(u);
        if self.last_by_partition && self.constraint_speeds(u) <= tolerance {
            self.factored = rows;
            return Ok(true);
        }
        if !dense::cholesky(self.mass.as_mut_slice(), n) {
            self.factored = rows;
            return Err(RuntimeError::SingularMassMatrix { t });
        }
        rows.clear();
        rows.extend_from_slice(&self.active);
        loop {
            let used = rows.len();
            self.couple_rows(&rows);
            // `phi` holds `J u` of every row (`constraint_speeds`).
            for (m, &r) in self.mismatch.iter_mut().zip(&rows) {
                *m = self.phi[r];
            }
            self.rank = self.solve_coupling(used);
            // Δu = −M⁻¹J_rowsᵀλ = −L⁻ᵀ (Z λ), built in `force` (scratch here).
            let correction = self.force.as_mut_slice();
            correction.fill(0.0);
            dense::add_times(&self.scaled, n, used, &self.multipliers, correction);
            dense::back_substitute(self.mass.as_slice(), n, correction);
            let spanning = self.rank == used;
            if used == nc || spanning {
                for (value, delta) in u.iter_mut().zip(correction.iter()) {
                    *value -= delta;
                }
            }
            if used == nc {
                // Every row's pivoted factor chose the independent ones: the next
                // projections and accelerations use those (as `factor_coupling` does; a
                // non-finite `J` says nothing of which rows are redundant: every row).
                self.active.clear();
                if all_finite(&self.scaled[..n * nc]) {
                    self.active.extend(self.order[..self.rank].iter().copied());
                    self.active.sort_unstable();
                } else {
                    self.active.extend(0..nc);
                }
                break;
            }
            if spanning && self.constraint_speeds(u) <= tolerance {
                break;
            }
            // The active rows lost rank (`u` untouched) or miss a direction of the others
            // (`phi` holds the `J u` left): every row.
            rows.clear();
            rows.extend(0..nc);
        }
        self.factored = rows;
        self.choose_partition();
        Ok(true)
    }

    /// The kinetic-energy-closest `u` with `J u = 0` on the partition's rows, `N (NᵀMN)⁻¹
    /// NᵀM u` (the range-space correction's result, in the independent speeds), with `M` in
    /// `mass` (left as it is) and `J` in `jacobian`; `false`, `u` untouched, where there is
    /// no partition that fits.
    fn project_speeds_partitioned(&mut self, u: &mut [f64]) -> bool {
        if !self.factor_partitioned(false) {
            return false;
        }
        let Some(partition) = self.partition.as_mut() else {
            return false;
        };
        let n = self.nu;
        let momentum = self.force.as_mut_slice();
        momentum.fill(0.0);
        dense::add_times(self.mass.as_slice(), n, n, u, momentum);
        partition.solve(self.mass.as_slice(), momentum);
        if !all_finite(momentum) {
            return false;
        }
        u.copy_from_slice(momentum);
        true
    }

    /// `J u` of every row into `phi` (scratch), from `J` in `jacobian`; returns `max |J u|`,
    /// NaN where a value is not finite (so that it never passes as within a tolerance).
    fn constraint_speeds(&mut self, u: &[f64]) -> f64 {
        let nc = self.nc;
        self.phi.fill(0.0);
        // J u = (Jᵀ)ᵀ u; column-major J is Jᵀ row by row, so accumulate column by column.
        dense::add_times(
            self.jacobian.as_slice(),
            nc,
            self.nu,
            u,
            self.phi.as_mut_slice(),
        );
        if all_finite(self.phi.as_slice()) {
            self.phi.amax()
        } else {
            f64::NAN
        }
    }

    /// The loop rows `rows` of `J` as the columns of `J_rowsᵀ` (`nu × rows.len()`, column k
    /// row `rows[k]`) into `scaled`; velocity rows (index `holonomic` and up, no position
    /// form) as zeros, so that the pivoted factor drops them and a step moves `φ` of the loop
    /// rows alone.
    fn gather_rows(&mut self, rows: &[usize], holonomic: usize) {
        let (n, nc) = (self.nu, self.nc);
        let jacobian = self.jacobian.as_slice();
        for (k, &r) in rows.iter().enumerate() {
            let column = &mut self.scaled[n * k..n * (k + 1)];
            for (c, value) in column.iter_mut().enumerate() {
                *value = if r < holonomic {
                    jacobian[r + nc * c]
                } else {
                    0.0
                };
            }
        }
    }
}
