//! Static equilibrium: `F(q, 0, inputs) + Jᵀλ = 0` with `φ(q) = 0`, including fixtures (a
//! model point held at a given place, e.g. a foot pressed against a force sensor), with the
//! reactions they carry.
//!
//! Consumes: a [`Model`], inputs, a starting configuration, optional [`Fixture`]s and
//! [`SideLoad`]s on them. Produces: an [`Equilibrium`]: `q`, the loop multipliers `λ` and the
//! force each fixture exerts on the model; and, for tests, the [`ReducedEquilibrium`] at a
//! configuration (bases, multipliers, stiffness).
//!
//! Method: Newton on the reduced equilibrium, in the tangent space of `φ = 0` (loops and
//! fixtures together). Every iterate satisfies `φ = 0`; there the least-squares multipliers
//! leave `F + Jᵀλ = Z Zᵀ F`, the part of `F` tangent to the constraints (`Z` an orthonormal
//! basis of the null space of `J`, from its SVD, so redundant loop rows are harmless). The
//! step `Δq = Z Δz` solves `Zᵀ ∂(F + Jᵀλ)/∂q Z Δz = −Zᵀ F` with `λ` held, so the curvature
//! of the constraints (`λ·∇²φ`) is part of the stiffness; the loops and fixtures are then
//! closed again ([`constraints::close`]: Gauss–Newton, first with the Jacobian of the point
//! the step left), and the step is halved until `|F + Jᵀλ|` decreases. Convergence is
//! quadratic; once within tolerance, one more step takes the residuals to round-off. With
//! side loads the reactions act along `G ≠ J` and the tangent force is replaced by the part
//! of `F` in the null space of `G`.
//!
//! Cost: the model's functions dominate. Per Newton iteration with `dof` tangent directions
//! and fixtures: dof evaluations of `F` at rest ([`Model::static_forcing`]) and of the loops'
//! analytic `J` (the stiffness and the loops' curvature, by forward differences; none for
//! the polishing step, which reuses the last stiffness), ~dof² + dof + 1 of the outputs (the fixtures' curvature; 2–4·dof²
//! of outputs and loop `φ` with the mixed second differences of `λ·φ` this replaced), 2·nq
//! of the outputs for the fixtures' rows of `J` at each point, and one `φ` per closing step
//! (Gauss–Newton with `J` afresh took 2·nq outputs more per step). "Outputs" are those the
//! fixtures read, where the model evaluates them alone ([`Model::selected_outputs`]: the
//! foot of the extended HAMR leg is 225 of its 2,604 output operations).
//!
//! Why closing after each step: a tangent step leaves a curved constraint manifold by
//! O(|Δq|²). Newton on the full KKT system in `(q, λ)` must weigh that error against the
//! force residual in its line search, and on soft mechanisms (flexures of ~1e-4 N·m/rad
//! against ~1 kN/m actuators) it rejected nearly every full step (the Maratos effect): with
//! both HAMR-VI actuators driven it stalled at ~1/32 steps and needed load continuation,
//! 138–229 iterations and 20–36 ms per equilibrium, against 4 iterations and ~0.2 ms now.

use nalgebra::{DMatrix, DVector, DVectorView};

use crate::constraints::{
    self, non_finite_rows, solve_least_squares, svd, AssemblyOptions, Unclosed, RANK_TOLERANCE,
};
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

/// A load at a fixture's point in proportion to the fixture's reaction along one of the
/// components it holds: `ratio` times that reaction, along a component it does not hold (a
/// force sensor that also pushes sideways, as in the HAMR force tests' ~30 % off-axis load;
/// friction at a given ratio). The fixture's reaction then acts along `e_held + ratio·e_along`.
#[derive(Clone, Debug, PartialEq)]
pub struct SideLoad {
    /// Index of the fixture, in the list passed with the loads.
    pub fixture: usize,
    /// The held component whose reaction sets the load (0 = x, 1 = y, 2 = z).
    pub held: usize,
    /// The component the load acts along (one the fixture does not hold).
    pub along: usize,
    pub ratio: f64,
}

/// An equilibrium and the forces holding it. Where several rows could carry the same load
/// (redundant loops, a fixture along a direction the mechanism already holds), the reported
/// multipliers are the minimum-norm ones.
#[derive(Clone, Debug, PartialEq)]
pub struct Equilibrium {
    pub q: Vec<f64>,
    /// Multipliers of the model's loop rows (generalized constraint force `Jᵀλ`).
    pub loop_multipliers: Vec<f64>,
    /// Per fixture, the force it exerts on the model at the point, side loads included,
    /// Newtonian components (zero for components it neither holds nor loads).
    pub fixture_forces: Vec<[f64; 3]>,
    /// `max |F + Jᵀλ|` at the solution (model units; with side loads, `Jᵀ` has each loaded
    /// fixture row's reaction direction).
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
    /// generalized force magnitude seen at the start ...
    pub relative_force_tolerance: f64,
    /// ... or below this (SI forces and torques): a model without loads starts at a zero
    /// force scale, where only round-off (~1e-32) is left and the relative test can never
    /// pass.
    pub absolute_force_tolerance: f64,
}

impl Default for StaticsOptions {
    fn default() -> Self {
        StaticsOptions {
            max_iterations: 60,
            constraint_tolerance: 1e-12,
            relative_force_tolerance: 1e-10,
            absolute_force_tolerance: 1e-24,
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
    /// Per fixture row, its side loads: (the component they act along, ratio).
    sides: Vec<Vec<(usize, f64)>>,
    /// The outputs the fixture rows read (held and side-loaded components), ascending.
    read: Vec<usize>,
}

impl<'a, M: Model + ?Sized> Problem<'a, M> {
    fn new(
        model: &'a M,
        t: f64,
        inputs: &'a [f64],
        fixtures: &'a [Fixture],
        loads: &[SideLoad],
    ) -> Result<Self, RuntimeError> {
        let mut sides = Vec::new();
        for (index, fixture) in fixtures.iter().enumerate() {
            for &c in &fixture.components {
                sides.push(
                    loads
                        .iter()
                        .filter(|load| load.fixture == index && load.held == c)
                        .map(|load| (load.along, load.ratio))
                        .collect(),
                );
            }
        }
        for load in loads {
            let valid = fixtures.get(load.fixture).is_some_and(|fixture| {
                fixture.components.contains(&load.held)
                    && load.along < 3
                    && !fixture.components.contains(&load.along)
            });
            if !valid {
                return Err(RuntimeError::InvalidOptions(format!(
                    "side load {load:?}: it needs a fixture that holds component {} and not \
                     component {} (0 = x, 1 = y, 2 = z)",
                    load.held, load.along
                )));
            }
        }
        let mut read: Vec<usize> = fixtures
            .iter()
            .flat_map(|fixture| fixture.components.iter().map(|&c| fixture.outputs[c]))
            .chain(
                loads
                    .iter()
                    .map(|load| fixtures[load.fixture].outputs[load.along]),
            )
            .collect();
        read.sort_unstable();
        read.dedup();
        Ok(Problem {
            model,
            t,
            inputs,
            fixtures,
            nq: model.nq(),
            nc: model.nc(),
            nf: sides.len(),
            sides,
            read,
        })
    }
}

impl<M: Model + ?Sized> Problem<'_, M> {
    /// `φ` of the loops and fixtures.
    fn residual(&self, q: &[f64]) -> DVector<f64> {
        let mut phi = DVector::zeros(self.nc + self.nf);
        self.model
            .constraints(self.t, q, &mut phi.as_mut_slice()[..self.nc]);
        if self.nf > 0 {
            let y = self.outputs(q);
            self.fixture_rows(&y, false, &mut phi.as_mut_slice()[self.nc..]);
        }
        phi
    }

    /// The fixture rows of `φ` from the outputs `y`, or with `sides` the functions whose
    /// gradients are the reaction directions: each fixture row plus its side loads'
    /// `ratio·y_along`.
    fn fixture_rows(&self, y: &[f64], sides: bool, out: &mut [f64]) {
        let mut row = 0;
        for fixture in self.fixtures {
            for &c in &fixture.components {
                out[row] = y[fixture.outputs[c]] - fixture.target[c];
                if sides {
                    for &(along, ratio) in &self.sides[row] {
                        out[row] += ratio * y[fixture.outputs[along]];
                    }
                }
                row += 1;
            }
        }
    }

    /// The outputs at `q` with zero speeds: those the fixtures read, or all where the model
    /// evaluates them only together (the others are then left zero).
    fn outputs(&self, q: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.model.noutputs()];
        let zero = vec![0.0; self.nq];
        let mut read = vec![0.0; self.read.len()];
        if self
            .model
            .selected_outputs(self.t, q, &zero, self.inputs, &self.read, &mut read)
        {
            for (&row, value) in self.read.iter().zip(read) {
                y[row] = value;
            }
        } else {
            self.model.outputs(self.t, q, &zero, self.inputs, &mut y);
        }
        y
    }

    fn has_side_loads(&self) -> bool {
        self.sides.iter().any(|s| !s.is_empty())
    }

    /// `J` of loops (analytic) and fixtures (central differences of the outputs), and with
    /// `reactions` and side loads, the reaction directions `G` (`J` with the loaded fixture
    /// rows tilted).
    fn jacobians(&self, q: &[f64], reactions: bool) -> (DMatrix<f64>, Option<DMatrix<f64>>) {
        let rows = self.nc + self.nf;
        let mut j = DMatrix::zeros(rows, self.nq);
        let mut loops = DMatrix::zeros(self.nc, self.nq);
        self.model
            .constraint_jacobian(self.t, q, loops.as_mut_slice());
        j.rows_mut(0, self.nc).copy_from(&loops);
        let mut g = (reactions && self.has_side_loads()).then(|| j.clone());
        if self.nf > 0 {
            let (mut a, mut b) = (vec![0.0; self.nf], vec![0.0; self.nf]);
            for c in 0..self.nq {
                let h = OUTPUT_STEP * q[c].abs().max(1.0);
                let (mut plus, mut minus) = (q.to_vec(), q.to_vec());
                plus[c] += h;
                minus[c] -= h;
                let (y_plus, y_minus) = (self.outputs(&plus), self.outputs(&minus));
                for (matrix, sides) in [(Some(&mut j), false), (g.as_mut(), true)] {
                    if let Some(matrix) = matrix {
                        self.fixture_rows(&y_plus, sides, &mut a);
                        self.fixture_rows(&y_minus, sides, &mut b);
                        for r in 0..self.nf {
                            matrix[(self.nc + r, c)] = (a[r] - b[r]) / (2.0 * h);
                        }
                    }
                }
            }
        }
        (j, g)
    }

    /// `F(q, 0, inputs)`.
    fn force(&self, q: &[f64]) -> DVector<f64> {
        let mut f = DVector::zeros(self.nq);
        self.model
            .static_forcing(self.t, q, self.inputs, f.as_mut_slice());
        f
    }

    /// Closes the loops and fixtures at `q` (in place): minimum-norm Gauss–Newton, as
    /// [`constraints::close`] does for assembly, to a thousandth of `tolerance` where
    /// round-off allows (so that equilibria reached from different starts agree to round-off,
    /// not to the tolerance). False if `|φ|` stays above `tolerance`.
    ///
    /// With `chord`, the Jacobian of a nearby closed point (the one a Newton step left):
    /// first up to [`CHORD_ITERATIONS`] steps with it held (corrections normal to that
    /// point's tangent space; the error left shrinks by about `|Δq|·curvature` per step),
    /// then Gauss–Newton as above if that has not closed. Each step then costs one `φ` instead
    /// of `J`, whose fixture rows are 2·nq output evaluations.
    fn close(&self, q: &mut [f64], tolerance: f64, chord: Option<&DMatrix<f64>>) -> bool {
        let options = AssemblyOptions {
            tolerance: tolerance * 1e-3,
            ..AssemblyOptions::default()
        };
        if let Some(j) = chord {
            let held = AssemblyOptions {
                max_iterations: CHORD_ITERATIONS,
                ..options
            };
            if constraints::close(|q| self.residual(q), |_| j.clone(), q, &[], &held).is_ok() {
                return true;
            }
        }
        match constraints::close(
            |q| self.residual(q),
            |q| self.jacobians(q, false).0,
            q,
            &[],
            &options,
        ) {
            Ok(_) => true,
            Err(Unclosed::Open(phi)) => phi.amax() <= tolerance,
            Err(_) => false,
        }
    }

    /// The closed configuration after `step` from `point`, if the loops and fixtures close
    /// (and its equations are finite: a step into a NaN is a step rejected).
    fn step(&self, point: &Point, step: &DVector<f64>, tolerance: f64) -> Option<Point> {
        let mut q: Vec<f64> = point
            .q
            .iter()
            .zip(step.iter())
            .map(|(q, d)| q + d)
            .collect();
        // Held only with fixtures: without them `J` is the analytic loop Jacobian, no dearer
        // than the extra steps (each with its SVD) the chord takes.
        let chord = (self.nf > 0).then_some(&point.jacobian);
        self.close(&mut q, tolerance, chord)
            .then(|| self.point(q).ok())
            .flatten()
    }

    /// The equilibrium equations at `q`; an error if `F` or `J` is not finite there (no
    /// decomposition is fed a NaN).
    fn point(&self, q: Vec<f64>) -> Result<Point, RuntimeError> {
        let phi = self.residual(&q);
        let (j, g) = self.jacobians(&q, true);
        let force = self.force(&q);
        if force.iter().any(|x| !x.is_finite()) {
            return Err(RuntimeError::NonFinite {
                what: "the generalized forces at rest, F(q, 0, inputs),",
            });
        }
        let rows = non_finite_rows(g.as_ref().unwrap_or(&j));
        if let Some(&first) = rows.first() {
            return Err(if first < self.nc {
                let loop_rows = rows.iter().take_while(|&&r| r < self.nc);
                RuntimeError::NonFiniteConstraints {
                    rows: loop_rows
                        .map(|&r| self.model.constraint_name(r).to_string())
                        .collect(),
                    jacobian: true,
                }
            } else {
                RuntimeError::NonFinite {
                    what: "the fixtures' rows of the constraint Jacobian",
                }
            });
        }
        // Both are finite here, so the decompositions below only fail if an SVD does not
        // converge (never seen for finite matrices), reported as the same error.
        let not_finite = || RuntimeError::NonFinite {
            what: "the static equilibrium's constraint Jacobian",
        };
        let tangent = null_space(&j).ok_or_else(not_finite)?;
        let (lambda, balance) = match &g {
            None => (
                solve_least_squares(&j.transpose(), &(-&force)).ok_or_else(not_finite)?,
                tangent.clone(),
            ),
            Some(g) => (
                solve_least_squares(&g.transpose(), &(-&force)).ok_or_else(not_finite)?,
                null_space(g).ok_or_else(not_finite)?,
            ),
        };
        let residual = &balance * (balance.transpose() * &force);
        Ok(Point {
            jacobian: j,
            tangent,
            balance,
            q,
            phi,
            force,
            lambda,
            residual,
        })
    }

    /// `Wᵀ ∂(F + Gᵀλ)/∂q Z` at `point` with `λ` held (`Z` its tangent basis, `W` the
    /// directions its reactions `G` cannot balance; `W = Z`, `G = J` without side loads):
    /// the stiffness of the reduced equilibrium, curvature of the constraints (`λ·∇²g`)
    /// included. The loops' part of `F + Gᵀλ` is `F + J_loopsᵀλ_loops`, differenced along
    /// each column of `Z` with the analytic `J`; the
    /// fixtures' part is the curvature of `s = λ_fixtures·g_fixtures`, a function of the
    /// outputs alone, from its Hessian on the span of `Z` and `W` ([`Self::fixture_curvature`]).
    ///
    /// `central`: central differences (error O(h²), 2·dof evaluations); otherwise forward
    /// differences from `point` itself (O(h) ≈ 1e-6 relative, dof evaluations), which is all
    /// a Newton step needs: it changes the contraction of the iteration by that much, not the
    /// equilibrium it converges to.
    fn reduced_stiffness(&self, point: &Point, central: bool) -> DMatrix<f64> {
        let (z, w) = (&point.tangent, &point.balance);
        let loops = point.lambda.rows(0, self.nc);
        let mut stiffness = DMatrix::zeros(w.ncols(), z.ncols());
        let at_point = (!central).then(|| {
            let loop_rows = point.jacobian.rows(0, self.nc);
            &point.force + loop_rows.tr_mul(&loops)
        });
        for k in 0..z.ncols() {
            let loaded = |h: f64| {
                let q: Vec<f64> = point
                    .q
                    .iter()
                    .zip(z.column(k).iter())
                    .map(|(q, d)| q + h * d)
                    .collect();
                self.loop_loaded_force(&q, &loops)
            };
            let difference = match &at_point {
                Some(center) => (loaded(FORCE_STEP) - center) / FORCE_STEP,
                None => (loaded(FORCE_STEP) - loaded(-FORCE_STEP)) / (2.0 * FORCE_STEP),
            };
            stiffness.set_column(k, &(w.transpose() * difference));
        }
        let fixtures = point.lambda.rows(self.nc, self.nf);
        if !stiffness.is_empty() && fixtures.iter().any(|&l| l != 0.0) {
            let basis = span(z, w);
            let hessian = self.fixture_curvature(&point.q, &basis, &fixtures);
            stiffness += w.transpose() * &basis * hessian * (basis.transpose() * z);
        }
        stiffness
    }

    /// `F + J_loopsᵀ λ_loops` at `q` (`F` alone for a tree model).
    fn loop_loaded_force(&self, q: &[f64], loops: &DVectorView<'_, f64>) -> DVector<f64> {
        let mut f = self.force(q);
        if self.nc > 0 {
            let mut j = DMatrix::zeros(self.nc, self.nq);
            self.model.constraint_jacobian(self.t, q, j.as_mut_slice());
            f += j.tr_mul(loops);
        }
        f
    }

    /// `Bᵀ ∇²s B` at `q` for `s = λ·g` over the fixture rows (`g` with side loads: the rows
    /// whose gradients are the reaction directions), `B` an orthonormal basis (columns), by
    /// central second differences of `s` from the outputs: `s(q ± h bᵢ)` give the diagonal,
    /// `s(q ± h(bᵢ + bⱼ))` the rest (`Hᵢⱼ = [s(+ᵢⱼ) + s(−ᵢⱼ) − s(±ᵢ) − s(±ⱼ) + 2s]/2h²`,
    /// error O(h²)): m² + m + 1 output evaluations for m columns, against 4 per entry of
    /// the four-point mixed difference.
    fn fixture_curvature(
        &self,
        q: &[f64],
        basis: &DMatrix<f64>,
        lambda: &DVectorView<'_, f64>,
    ) -> DMatrix<f64> {
        let sides = self.has_side_loads();
        let mut rows = vec![0.0; self.nf];
        let h = CURVATURE_STEP;
        let mut work = |coefficients: &[(usize, f64)]| {
            let mut shifted = q.to_vec();
            for &(i, a) in coefficients {
                for (value, d) in shifted.iter_mut().zip(basis.column(i).iter()) {
                    *value += a * d;
                }
            }
            self.fixture_rows(&self.outputs(&shifted), sides, &mut rows);
            lambda.iter().zip(&rows).map(|(l, g)| l * g).sum::<f64>()
        };
        let m = basis.ncols();
        let center = work(&[]);
        let plus: Vec<f64> = (0..m).map(|i| work(&[(i, h)])).collect();
        let minus: Vec<f64> = (0..m).map(|i| work(&[(i, -h)])).collect();
        let mut hessian = DMatrix::zeros(m, m);
        for i in 0..m {
            hessian[(i, i)] = (plus[i] + minus[i] - 2.0 * center) / (h * h);
            for j in 0..i {
                let both = work(&[(i, h), (j, h)]) + work(&[(i, -h), (j, -h)]);
                let value =
                    (both - plus[i] - minus[i] - plus[j] - minus[j] + 2.0 * center) / (2.0 * h * h);
                hessian[(i, j)] = value;
                hessian[(j, i)] = value;
            }
        }
        hessian
    }
}

/// Relative step of the central differences of the fixture outputs (at least this, absolute):
/// positions are affine in slider coordinates and vary on the scale of a radian in angles,
/// so the step is large enough to keep round-off (≈ ε·|y|/h) near 1e-13 of the derivative.
const OUTPUT_STEP: f64 = 1e-5;
/// Steps of [`Problem::close`] with the Jacobian held before it evaluates `J` afresh.
const CHORD_ITERATIONS: usize = 10;
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
    /// `F + Jᵀλ = W WᵀF`: the part of `F` the constraints cannot carry.
    residual: DVector<f64>,
    /// `J` of the loops and fixtures.
    jacobian: DMatrix<f64>,
    /// `Z`: orthonormal basis of the null space of `J` (`nq × dof`), the directions the
    /// configuration may move in.
    tangent: DMatrix<f64>,
    /// `W`: orthonormal basis of the null space of the reaction directions `G` (`Z` itself
    /// without side loads), the directions of the force the reactions cannot balance.
    balance: DMatrix<f64>,
}

/// Orthonormal basis of the span of the columns of `z` and `w` (both orthonormal): `z`, then
/// the parts of `w`'s columns outside what is already spanned (Gram–Schmidt, twice for
/// orthogonality to round-off), those below `RANK_TOLERANCE` dropped. Not an SVD of `[z w]`:
/// with `w` close to `z` that matrix has a cluster of singular values at √2, and nalgebra's
/// SVD returned factors off by ~5e-2 from it (on the extended HAMR leg with a side load).
fn span(z: &DMatrix<f64>, w: &DMatrix<f64>) -> DMatrix<f64> {
    let mut columns: Vec<DVector<f64>> = z.column_iter().map(|c| c.into_owned()).collect();
    for column in w.column_iter() {
        let mut v = column.into_owned();
        for _ in 0..2 {
            for b in &columns {
                v -= b * b.dot(&v);
            }
        }
        let norm = v.norm();
        if norm > RANK_TOLERANCE {
            columns.push(v / norm);
        }
    }
    DMatrix::from_columns(&columns)
}

/// Orthonormal basis of the null space of `j` (singular values at most `RANK_TOLERANCE·σ₁`
/// count as zero, as in [`solve_least_squares`]); `None` if `j` is not finite.
fn null_space(j: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let nq = j.ncols();
    // Zero rows up to a square matrix, so that the SVD's Vᵀ spans all of q.
    let mut padded = DMatrix::zeros(j.nrows().max(nq), nq);
    padded.rows_mut(0, j.nrows()).copy_from(j);
    let svd = svd(padded, false, true)?;
    let v_t = svd.v_t?;
    let threshold = svd.singular_values.max() * RANK_TOLERANCE;
    let null: Vec<usize> = (0..nq)
        .filter(|&i| svd.singular_values[i] <= threshold)
        .collect();
    Some(DMatrix::from_fn(nq, null.len(), |r, c| v_t[(null[c], r)]))
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
    solve_statics_with_loads(model, t, q, inputs, fixtures, &[], options)
}

/// [`solve_statics`] with side loads on the fixtures.
pub fn solve_statics_with_loads<M: Model + ?Sized>(
    model: &M,
    t: f64,
    q: &mut [f64],
    inputs: &[f64],
    fixtures: &[Fixture],
    loads: &[SideLoad],
    options: &StaticsOptions,
) -> Result<Equilibrium, RuntimeError> {
    model.require_rates_are_speeds("statics")?;
    model.require_holonomic("statics")?;
    let start = q.to_vec();
    let first = newton(
        &Problem::new(model, t, inputs, fixtures, loads)?,
        q,
        options,
    );
    if first.is_ok() || inputs.iter().all(|&x| x == 0.0) {
        return first;
    }
    for steps in [4, 16, 64] {
        q.copy_from_slice(&start);
        let mut result = first.clone();
        for k in 1..=steps {
            let fraction = k as f64 / steps as f64;
            let ramped: Vec<f64> = inputs.iter().map(|x| x * fraction).collect();
            result = newton(
                &Problem::new(model, t, &ramped, fixtures, loads)?,
                q,
                options,
            );
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

/// The reduced equilibrium at `q` as the Newton of [`solve_statics_with_loads`] sees it:
/// bases, multipliers and stiffness. `q` should close the loops and fixtures. For checking
/// the stiffness against an independent difference of `F + Gᵀλ` (tests), and for looking
/// into a solve that converges slowly.
#[derive(Clone, Debug, PartialEq)]
pub struct ReducedEquilibrium {
    /// `Z` (`nq × dof`): orthonormal basis of the directions that keep the loops and
    /// fixtures closed.
    pub tangent: DMatrix<f64>,
    /// `W`: orthonormal basis of the directions the reactions cannot balance (`Z` without
    /// side loads).
    pub balance: DMatrix<f64>,
    /// `λ`: least-squares multipliers of the loop rows, then of the fixture rows.
    pub multipliers: DVector<f64>,
    /// `Wᵀ ∂(F + Gᵀλ)/∂q Z` with `λ` held (`G`: the reaction directions, `J` without side
    /// loads).
    pub stiffness: DMatrix<f64>,
}

/// [`ReducedEquilibrium`] at `q`.
pub fn reduced_equilibrium<M: Model + ?Sized>(
    model: &M,
    t: f64,
    q: &[f64],
    inputs: &[f64],
    fixtures: &[Fixture],
    loads: &[SideLoad],
) -> Result<ReducedEquilibrium, RuntimeError> {
    model.require_rates_are_speeds("statics")?;
    model.require_holonomic("statics")?;
    let problem = Problem::new(model, t, inputs, fixtures, loads)?;
    let point = problem.point(q.to_vec())?;
    Ok(ReducedEquilibrium {
        stiffness: problem.reduced_stiffness(&point, true),
        tangent: point.tangent,
        balance: point.balance,
        multipliers: point.lambda,
    })
}

/// Newton on the reduced equilibrium from `q` (see the module docs).
fn newton<M: Model + ?Sized>(
    problem: &Problem<'_, M>,
    q: &mut [f64],
    options: &StaticsOptions,
) -> Result<Equilibrium, RuntimeError> {
    let force_scale = problem.force(q).amax().max(f64::MIN_POSITIVE);
    let tolerance = options.constraint_tolerance;
    if !problem.close(q, tolerance, None) {
        return Err(RuntimeError::InvalidOptions(format!(
            "the loops and fixtures do not close from the start (|φ| = {:.3e}); start closer \
             to a configuration that satisfies them",
            problem.residual(q).amax()
        )));
    }
    let mut point = problem.point(q.to_vec())?;
    // Loops that cannot close exactly (rows contradicting each other by up to
    // `AssemblyOptions::inconsistency`, accepted by the close above) leave a floor no step
    // goes below: converged within twice it.
    let tolerance = tolerance.max(2.0 * point.phi.amax());
    let mut iterations = 0;
    let converged = |point: &Point| {
        let force_tolerance =
            (options.relative_force_tolerance * force_scale).max(options.absolute_force_tolerance);
        point.residual.amax() <= force_tolerance && point.phi.amax() <= tolerance
    };
    // Once within tolerance, one more full Newton step: it costs little and, convergence
    // being quadratic, takes the residual to round-off, so that equilibria reached from
    // different starts agree to round-off rather than to the tolerance. That step reuses the
    // last iteration's stiffness (a chord step: its point is within |Δq| of this one, so the
    // residual still shrinks by ~|Δq|·∂K/∂q / K), carried to this point's bases.
    let mut polished = false;
    let mut last: Option<(DMatrix<f64>, DMatrix<f64>, DMatrix<f64>)> = None;
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
        let stiffness = match &last {
            Some((stiffness, z, w))
                if within
                    && z.ncols() == point.tangent.ncols()
                    && w.ncols() == point.balance.ncols() =>
            {
                point
                    .balance
                    .tr_mul(&(w * (stiffness * z.tr_mul(&point.tangent))))
            }
            _ => problem.reduced_stiffness(&point, false),
        };
        last = Some((
            stiffness.clone(),
            point.tangent.clone(),
            point.balance.clone(),
        ));
        let unbalanced = point.balance.transpose() * &point.force;
        let along =
            solve_least_squares(&stiffness, &(-unbalanced)).ok_or(RuntimeError::NonFinite {
                what: "the static stiffness (forces differenced along the free directions)",
            })?;
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
    let mut fixture_forces = Vec::with_capacity(problem.fixtures.len());
    let mut row = problem.nc;
    for fixture in problem.fixtures {
        // The fixture row is φ = y − target, so its generalized force Jᵀλ is the force λ
        // applied at the point along that component (and `ratio·λ` along a side load's).
        let mut force_on_model = [0.0; 3];
        for &c in &fixture.components {
            force_on_model[c] = lambda[row];
            for &(along, ratio) in &problem.sides[row - problem.nc] {
                force_on_model[along] += ratio * lambda[row];
            }
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
