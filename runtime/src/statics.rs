//! Static equilibrium: `F(q, 0, inputs) + Jᵀλ = 0` with `φ(q) = 0`, including fixtures (a
//! model point held at a given place, e.g. a foot pressed against a force sensor), with the
//! reactions they carry.
//!
//! Consumes: a [`Model`], inputs, a starting configuration and optional [`Fixture`]s.
//! Produces: an [`Equilibrium`]: `q`, the loop multipliers `λ` and the force each fixture
//! exerts on the model.
//!
//! Method: Newton on the reduced equilibrium, in the tangent space of `φ = 0` (loops and
//! fixtures together). Every iterate satisfies `φ = 0`; there the least-squares multipliers
//! leave `F + Jᵀλ = Z Zᵀ F`, the part of `F` tangent to the constraints (`Z` an orthonormal
//! basis of the null space of `J`, from its SVD, so redundant loop rows are harmless). The
//! step `Δq = Z Δz` solves `Zᵀ ∂(F + Jᵀλ)/∂q Z Δz = −Zᵀ F` with `λ` held, so the curvature
//! of the constraints (`λ·∇²φ`) is part of the stiffness; the loops and fixtures are then
//! closed again ([`constraints::close`], minimum-norm Gauss–Newton), and the step is halved
//! until `|F + Jᵀλ|` decreases. Convergence is quadratic.
//!
//! Why closing after each step: a tangent step leaves a curved constraint manifold by
//! O(|Δq|²). Newton on the full KKT system in `(q, λ)` must weigh that error against the
//! force residual in its line search, and on soft mechanisms (flexures of ~1e-4 N·m/rad
//! against ~1 kN/m actuators) it rejected nearly every full step (the Maratos effect): the
//! HAMR leg with both actuators driven took 20–50 iterations of 1/32 steps.

use nalgebra::{DMatrix, DVector};

use crate::constraints::{self, solve_least_squares, AssemblyOptions, RANK_TOLERANCE};
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
                let h = OUTPUT_STEP * q[c].abs().max(1.0);
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

    /// Closes the loops and fixtures at `q` (in place): minimum-norm Gauss–Newton, as
    /// [`constraints::close`] does for assembly, to a thousandth of `tolerance` where
    /// round-off allows (so that equilibria reached from different starts agree to round-off,
    /// not to the tolerance). False if `|φ|` stays above `tolerance`.
    fn close(&self, q: &mut [f64], tolerance: f64) -> bool {
        let options = AssemblyOptions {
            tolerance: tolerance * 1e-3,
            ..AssemblyOptions::default()
        };
        match constraints::close(|q| self.residual(q), |q| self.jacobian(q), q, &[], &options) {
            Ok(_) => true,
            Err(phi) => phi.amax() <= tolerance,
        }
    }

    /// The closed configuration after `step` from `point`, if the loops and fixtures close.
    fn step(&self, point: &Point, step: &DVector<f64>, tolerance: f64) -> Option<Point> {
        let mut q: Vec<f64> = point
            .q
            .iter()
            .zip(step.iter())
            .map(|(q, d)| q + d)
            .collect();
        self.close(&mut q, tolerance).then(|| self.point(q))
    }

    /// The equilibrium equations at `q`.
    fn point(&self, q: Vec<f64>) -> Point {
        let phi = self.residual(&q);
        let j = self.jacobian(&q);
        let force = self.force(&q);
        let lambda = solve_least_squares(&j.transpose(), &(-&force));
        let tangent = null_space(&j);
        let residual = &tangent * (tangent.transpose() * &force);
        Point {
            tangent,
            q,
            phi,
            force,
            lambda,
            residual,
        }
    }

    /// `Zᵀ ∂(F + Jᵀλ)/∂q Z` at `point` with `λ` held, `Z` its tangent basis: the stiffness of
    /// the reduced equilibrium. `F` by central differences along each column of `Z`, the
    /// constraint curvature `Zᵀ ∇²(λ·φ) Z` by second differences of the scalar `λ·φ` (no
    /// differences of differenced Jacobians).
    fn reduced_stiffness(&self, point: &Point) -> DMatrix<f64> {
        let z = &point.tangent;
        let d = z.ncols();
        let at = |steps: &[(usize, f64)]| -> Vec<f64> {
            let mut q = point.q.clone();
            for &(k, h) in steps {
                for (value, dz) in q.iter_mut().zip(z.column(k).iter()) {
                    *value += h * dz;
                }
            }
            q
        };
        let mut stiffness = DMatrix::zeros(d, d);
        for k in 0..d {
            let difference = (self.force(&at(&[(k, FORCE_STEP)]))
                - self.force(&at(&[(k, -FORCE_STEP)])))
                / (2.0 * FORCE_STEP);
            stiffness.set_column(k, &(z.transpose() * difference));
        }
        if point.lambda.is_empty() {
            return stiffness;
        }
        let work = |steps: &[(usize, f64)]| point.lambda.dot(&self.residual(&at(steps)));
        let h = CURVATURE_STEP;
        let center = work(&[]);
        for k in 0..d {
            stiffness[(k, k)] += (work(&[(k, h)]) - 2.0 * center + work(&[(k, -h)])) / (h * h);
            for j in 0..k {
                let cross =
                    (work(&[(j, h), (k, h)]) - work(&[(j, h), (k, -h)]) - work(&[(j, -h), (k, h)])
                        + work(&[(j, -h), (k, -h)]))
                        / (4.0 * h * h);
                stiffness[(j, k)] += cross;
                stiffness[(k, j)] += cross;
            }
        }
        stiffness
    }
}

/// Relative step of the central differences of the fixture outputs (at least this, absolute):
/// positions are affine in slider coordinates and vary on the scale of a radian in angles,
/// so the step is large enough to keep round-off (≈ ε·|y|/h) near 1e-13 of the derivative.
const OUTPUT_STEP: f64 = 1e-5;
/// Step along a unit tangent direction for the central differences of `F`.
const FORCE_STEP: f64 = 1e-6;
/// Step along a unit tangent direction for the second differences of `λ·φ`.
const CURVATURE_STEP: f64 = 1e-4;

/// A closed configuration with its forces.
struct Point {
    q: Vec<f64>,
    phi: DVector<f64>,
    /// `F(q, 0, inputs)`.
    force: DVector<f64>,
    /// The least-squares (minimum-norm) multipliers: `F + Jᵀλ` as small as it can be.
    lambda: DVector<f64>,
    /// `F + Jᵀλ`: the part of `F` the constraints cannot carry, tangent to `φ = 0`.
    residual: DVector<f64>,
    /// Orthonormal basis of the null space of `J` (`nq × dof`).
    tangent: DMatrix<f64>,
}

/// Orthonormal basis of the null space of `j` (singular values at most `RANK_TOLERANCE·σ₁`
/// count as zero, as in [`solve_least_squares`]).
fn null_space(j: &DMatrix<f64>) -> DMatrix<f64> {
    let nq = j.ncols();
    // Zero rows up to a square matrix, so that the SVD's Vᵀ spans all of q.
    let mut padded = DMatrix::zeros(j.nrows().max(nq), nq);
    padded.rows_mut(0, j.nrows()).copy_from(j);
    let svd = padded.svd(false, true);
    let v_t = svd.v_t.expect("requested");
    let threshold = svd.singular_values.max() * RANK_TOLERANCE;
    let null: Vec<usize> = (0..nq)
        .filter(|&i| svd.singular_values[i] <= threshold)
        .collect();
    DMatrix::from_fn(nq, null.len(), |r, c| v_t[(null[c], r)])
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

/// Newton on the reduced equilibrium from `q` (see the module docs).
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
    let force_scale = problem.force(q).amax().max(f64::MIN_POSITIVE);
    let tolerance = options.constraint_tolerance;
    if !problem.close(q, tolerance) {
        return Err(RuntimeError::InvalidOptions(format!(
            "the loops and fixtures do not close from the start (|φ| = {:.3e}); start closer \
             to a configuration that satisfies them",
            problem.residual(q).amax()
        )));
    }
    let mut point = problem.point(q.to_vec());
    let mut iterations = 0;
    let converged = |point: &Point| {
        point.residual.amax() <= options.relative_force_tolerance * force_scale
            && point.phi.amax() <= tolerance
    };
    // Once within tolerance, one more full Newton step: it costs little and, convergence
    // being quadratic, takes the residual to round-off, so that equilibria reached from
    // different starts agree to round-off rather than to the tolerance.
    let mut polished = false;
    loop {
        let within = converged(&point);
        if within && polished {
            break;
        }
        if !within && iterations == options.max_iterations {
            return Err(RuntimeError::InvalidOptions(format!(
                "no static equilibrium found in {iterations} Newton iterations (|F + Jᵀλ| = {:.3e}, |φ| = {:.3e}); \
                 start closer to one, or check that the loads can be balanced",
                point.residual.amax(),
                point.phi.amax()
            )));
        }
        iterations += 1;
        let stiffness = problem.reduced_stiffness(&point);
        let along = solve_least_squares(&stiffness, &(-(point.tangent.transpose() * &point.force)));
        let step = &point.tangent * along;
        let before = point.residual.norm();
        if within {
            polished = true;
            if let Some(candidate) = problem.step(&point, &step, tolerance) {
                if candidate.residual.norm() < before {
                    point = candidate;
                }
            }
            continue;
        }
        // Halved until `|F + Jᵀλ|` decreases (after 14 halvings the step is taken anyway).
        let mut fraction = 1.0;
        point = loop {
            let trial = problem.step(&point, &(&step * fraction), tolerance);
            match trial {
                Some(candidate) if candidate.residual.norm() < before || fraction < 1e-4 => {
                    break candidate;
                }
                None if fraction < 1e-4 => {
                    return Err(RuntimeError::InvalidOptions(format!(
                        "the loops and fixtures do not close after a Newton step (|F + Jᵀλ| = {:.3e})",
                        point.residual.amax()
                    )));
                }
                _ => fraction *= 0.5,
            }
        };
    }
    q.copy_from_slice(&point.q);
    let lambda = &point.lambda;
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
        force_residual: point.residual.amax(),
        constraint_residual: point.phi.amax(),
        iterations,
    })
}
