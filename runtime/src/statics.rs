//! Static equilibrium: `F(q, 0, inputs) + Jᵀλ = 0` with `φ(q) = 0`, including fixtures (a
//! model point held at a given place, e.g. a foot pressed against a force sensor), with the
//! reactions they carry.
//!
//! Consumes: a [`Model`], inputs, a starting configuration and optional [`Fixture`]s.
//! Produces: an [`Equilibrium`]: `q`, the loop multipliers `λ` and the force each fixture
//! exerts on the model.
//!
//! Method: damped Newton on the KKT system `R(q, λ) = [F + Jᵀλ; s·φ] = 0`, whose Jacobian
//! `[[∂(F + Jᵀλ)/∂q, Jᵀ], [s·J, 0]]` is formed by central differences in `q` and solved
//! by rank-revealing least squares, so redundant loop rows are harmless. The constraint
//! rows and the multipliers are scaled by `s` (`λ = s·μ`) so both blocks weigh alike.

use nalgebra::{DMatrix, DVector};

use crate::constraints::solve_least_squares;
use crate::{Model, RuntimeError};

/// A point of the model (given by three position outputs, components in the Newtonian frame)
/// held at `target`; only the listed `components` (0 = x, 1 = y, 2 = z) are held.
#[derive(Clone, Debug, PartialEq)]
pub struct Fixture {
    pub name: String,
    /// Indices of the model outputs giving the point's x, y, z in the Newtonian frame.
    pub outputs: [usize; 3],
    pub target: [f64; 3],
    pub components: Vec<usize>,
}

/// An equilibrium and the forces holding it. Where several rows could carry the same load
/// (redundant loops, a fixture along a direction the mechanism already holds), the reported
/// multipliers are the minimum-norm ones.
#[derive(Clone, Debug, PartialEq)]
pub struct Equilibrium {
    pub q: Vec<f64>,
    /// Multipliers of the model's loop rows (generalized constraint force `Jᵀλ`).
    pub loop_multipliers: Vec<f64>,
    /// Per fixture, the force it exerts on the model at the point, Newtonian components
    /// (zero for components it does not hold).
    pub fixture_forces: Vec<[f64; 3]>,
    /// `max |F + Jᵀλ|` at the solution (model units).
    pub force_residual: f64,
    /// `max |φ|` at the solution, fixtures included.
    pub constraint_residual: f64,
    pub iterations: usize,
}

/// Settings of [`solve_statics`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StaticsOptions {
    pub max_iterations: usize,
    /// Converged when the constraint residual is below this (SI lengths) ...
    pub constraint_tolerance: f64,
    /// ... and the generalized force residual is below this fraction of the largest
    /// generalized force magnitude seen at the start.
    pub relative_force_tolerance: f64,
}

impl Default for StaticsOptions {
    fn default() -> Self {
        StaticsOptions {
            max_iterations: 60,
            constraint_tolerance: 1e-12,
            relative_force_tolerance: 1e-10,
        }
    }
}

struct Problem<'a, M: Model + ?Sized> {
    model: &'a M,
    t: f64,
    inputs: &'a [f64],
    fixtures: &'a [Fixture],
    nq: usize,
    nc: usize,
    nf: usize,
}

impl<M: Model + ?Sized> Problem<'_, M> {
    /// `φ` of the loops and fixtures.
    fn residual(&self, q: &[f64]) -> DVector<f64> {
        let mut phi = DVector::zeros(self.nc + self.nf);
        self.model
            .constraints(self.t, q, &mut phi.as_mut_slice()[..self.nc]);
        let mut row = self.nc;
        if self.nf > 0 {
            let y = self.outputs(q);
            for fixture in self.fixtures {
                for &c in &fixture.components {
                    phi[row] = y[fixture.outputs[c]] - fixture.target[c];
                    row += 1;
                }
            }
        }
        phi
    }

    fn outputs(&self, q: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.model.noutputs()];
        let zero = vec![0.0; self.nq];
        self.model.outputs(self.t, q, &zero, self.inputs, &mut y);
        y
    }

    /// `J` of loops (analytic) and fixtures (central differences of the outputs).
    fn jacobian(&self, q: &[f64]) -> DMatrix<f64> {
        let mut j = DMatrix::zeros(self.nc + self.nf, self.nq);
        let mut loops = DMatrix::zeros(self.nc, self.nq);
        self.model
            .constraint_jacobian(self.t, q, loops.as_mut_slice());
        j.rows_mut(0, self.nc).copy_from(&loops);
        if self.nf > 0 {
            for c in 0..self.nq {
                let h = 1e-7 * q[c].abs().max(1e-3);
                let (mut plus, mut minus) = (q.to_vec(), q.to_vec());
                plus[c] += h;
                minus[c] -= h;
                let (a, b) = (self.residual(&plus), self.residual(&minus));
                for r in self.nc..self.nc + self.nf {
                    j[(r, c)] = (a[r] - b[r]) / (2.0 * h);
                }
            }
        }
        j
    }

    /// `F(q, 0, inputs)`.
    fn force(&self, q: &[f64]) -> DVector<f64> {
        let mut f = DVector::zeros(self.nq);
        self.model.forcing(
            self.t,
            q,
            &vec![0.0; self.nq],
            self.inputs,
            f.as_mut_slice(),
        );
        f
    }

    /// `F + Jᵀλ` and `φ`.
    fn kkt_residual(&self, q: &[f64], lambda: &DVector<f64>) -> (DVector<f64>, DVector<f64>) {
        let j = self.jacobian(q);
        (self.force(q) + j.transpose() * lambda, self.residual(q))
    }
}

/// Solves for a static equilibrium near `q` (updated in place).
///
/// If Newton does not converge from `q` (large loads on a stiff, strongly nonlinear
/// mechanism), the inputs are ramped up from zero in 4, then 16, then 64 equal steps, each
/// solved from the previous equilibrium (load continuation).
pub fn solve_statics<M: Model + ?Sized>(
    model: &M,
    t: f64,
    q: &mut [f64],
    inputs: &[f64],
    fixtures: &[Fixture],
    options: &StaticsOptions,
) -> Result<Equilibrium, RuntimeError> {
    let start = q.to_vec();
    let first = newton(model, t, q, inputs, fixtures, options);
    if first.is_ok() || inputs.iter().all(|&x| x == 0.0) {
        return first;
    }
    for steps in [4, 16, 64] {
        q.copy_from_slice(&start);
        let mut result = first.clone();
        for k in 1..=steps {
            let fraction = k as f64 / steps as f64;
            let ramped: Vec<f64> = inputs.iter().map(|x| x * fraction).collect();
            result = newton(model, t, q, &ramped, fixtures, options);
            if result.is_err() {
                break;
            }
        }
        if result.is_ok() {
            return result;
        }
    }
    q.copy_from_slice(&start);
    first
}

/// Damped Newton on the KKT system from `q` (see the module docs).
fn newton<M: Model + ?Sized>(
    model: &M,
    t: f64,
    q: &mut [f64],
    inputs: &[f64],
    fixtures: &[Fixture],
    options: &StaticsOptions,
) -> Result<Equilibrium, RuntimeError> {
    let nf = fixtures.iter().map(|f| f.components.len()).sum();
    let problem = Problem {
        model,
        t,
        inputs,
        fixtures,
        nq: model.nq(),
        nc: model.nc(),
        nf,
    };
    let rows = problem.nc + nf;
    let mut lambda = DVector::zeros(rows);
    let (mut force, mut phi) = problem.kkt_residual(q, &lambda);
    let force_scale = force.amax().max(f64::MIN_POSITIVE);
    let mut iterations = 0;
    let converged = |force: &DVector<f64>, phi: &DVector<f64>| {
        force.amax() <= options.relative_force_tolerance * force_scale
            && phi.amax() <= options.constraint_tolerance
    };
    while !converged(&force, &phi) {
        if iterations == options.max_iterations {
            return Err(RuntimeError::InvalidOptions(format!(
                "no static equilibrium found in {iterations} Newton iterations (|F + Jᵀλ| = {:.3e}, |φ| = {:.3e}); \
                 start closer to one, or check that the loads can be balanced",
                force.amax(),
                phi.amax()
            )));
        }
        iterations += 1;
        let kkt = kkt_matrix(&problem, q, &lambda);
        let scale = constraint_scale(&kkt, problem.nq);
        let mut residual = DVector::zeros(problem.nq + rows);
        residual.rows_mut(0, problem.nq).copy_from(&force);
        residual
            .rows_mut(problem.nq, rows)
            .copy_from(&(&phi * scale));
        // Rows and columns of the constraint block scaled alike (λ = s·μ) keep it symmetric.
        let mut scaled = kkt.clone();
        scaled.rows_mut(problem.nq, rows).scale_mut(scale);
        scaled.columns_mut(problem.nq, rows).scale_mut(scale);
        let step = solve_least_squares(&scaled, &(-&residual));
        let merit = |force: &DVector<f64>, phi: &DVector<f64>| force.norm() + scale * phi.norm();
        let before = merit(&force, &phi);
        let mut fraction = 1.0;
        loop {
            let trial_q: Vec<f64> = q
                .iter()
                .zip(step.iter())
                .map(|(q, d)| q + fraction * d)
                .collect();
            let trial_lambda = &lambda + step.rows(problem.nq, rows) * (fraction * scale);
            let (trial_force, trial_phi) = problem.kkt_residual(&trial_q, &trial_lambda);
            if merit(&trial_force, &trial_phi) < before || fraction < 1e-4 {
                q.copy_from_slice(&trial_q);
                lambda = trial_lambda;
                (force, phi) = (trial_force, trial_phi);
                break;
            }
            fraction *= 0.5;
        }
    }
    // Newton steps may leave λ with a component in the null space of Jᵀ (loads shared by
    // redundant rows are statically indeterminate); report the minimum-norm multipliers.
    if rows > 0 {
        let j = problem.jacobian(q);
        lambda = solve_least_squares(&j.transpose(), &(-problem.force(q)));
    }
    let mut fixture_forces = Vec::with_capacity(fixtures.len());
    let mut row = problem.nc;
    for fixture in fixtures {
        // The fixture row is φ = y − target, so its generalized force Jᵀλ is the force λ
        // applied at the point along that component.
        let mut force_on_model = [0.0; 3];
        for &c in &fixture.components {
            force_on_model[c] = lambda[row];
            row += 1;
        }
        fixture_forces.push(force_on_model);
    }
    Ok(Equilibrium {
        q: q.to_vec(),
        loop_multipliers: lambda.rows(0, problem.nc).iter().copied().collect(),
        fixture_forces,
        force_residual: force.amax(),
        constraint_residual: phi.amax(),
        iterations,
    })
}

/// `[[∂(F + Jᵀλ)/∂q, Jᵀ], [J, 0]]` with the q-derivatives by central differences.
fn kkt_matrix<M: Model + ?Sized>(
    problem: &Problem<'_, M>,
    q: &[f64],
    lambda: &DVector<f64>,
) -> DMatrix<f64> {
    let (nq, rows) = (problem.nq, problem.nc + problem.nf);
    let mut kkt = DMatrix::zeros(nq + rows, nq + rows);
    for c in 0..nq {
        let h = 1e-7 * q[c].abs().max(1e-3);
        let (mut plus, mut minus) = (q.to_vec(), q.to_vec());
        plus[c] += h;
        minus[c] -= h;
        let (force_plus, _) = problem.kkt_residual(&plus, lambda);
        let (force_minus, _) = problem.kkt_residual(&minus, lambda);
        kkt.view_mut((0, c), (nq, 1))
            .copy_from(&((force_plus - force_minus) / (2.0 * h)));
    }
    let j = problem.jacobian(q);
    kkt.view_mut((0, nq), (nq, rows)).copy_from(&j.transpose());
    kkt.view_mut((nq, 0), (rows, nq)).copy_from(&j);
    kkt
}

/// Ratio of the force block's size to the constraint block's, so both weigh alike in the
/// least-squares solve (rank decisions are relative to the largest singular value).
fn constraint_scale(kkt: &DMatrix<f64>, nq: usize) -> f64 {
    let rows = kkt.nrows() - nq;
    if rows == 0 {
        return 1.0;
    }
    let stiffness = kkt.view((0, 0), (nq, nq)).amax();
    let jacobian = kkt.view((nq, 0), (rows, nq)).amax();
    if stiffness > 0.0 && jacobian > 0.0 {
        stiffness / jacobian
    } else {
        1.0
    }
}
