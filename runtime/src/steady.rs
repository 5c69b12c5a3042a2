//! Linearization about a steady motion: a state that moves (a bicycle at a forward speed, a
//! spinning top, a disc rolling upright) but whose shape and speeds stay constant, so that
//! only cyclic coordinates — those the motion does not depend on — change.
//!
//! Consumes: a [`Model`] (loops and velocity constraints allowed; no unit quaternions), a
//! consistent operating point `(q, u)`, the coordinates kept independent by the
//! loops and the speeds kept independent by all constraint rows.
//! Produces: a [`SteadyLinearization`], `δẋ = A δx` on `x = [z; w]`: the independent
//! coordinates `z` that are not cyclic and the independent speeds `w`, with the reduced mass
//! matrix `M̃ = Tᵀ M T` of Kane's nonholonomic form and the eigenvalues.
//!
//! The map `x ↦ (q, u)` closes the loops for `z` (Newton from the operating point, the other
//! independent coordinates held) and solves the dependent speeds from `[J; A] u = 0` for `w`,
//! so every state it reaches satisfies every constraint; `ẋ = [q̇_z; u̇_w]` with `u̇` from the
//! multiplier form (`ModelOde::accelerations`), which for ideal constraints equals Kane's reduced
//! equations `M̃ ẇ = F̃`. Its Jacobian is taken by central differences with one Richardson step
//! (as [`linearize`](fn@crate::linearize)), over all independent coordinates; the largest set of
//! coordinates that no state outside the set feels (their columns are zero there) is cyclic
//! and is dropped with its rows, which leaves the block on which the steady motion is an
//! equilibrium (the dropped rows may depend on anything: a wheel's position on its heading).
//! That the dropped coordinates are cyclic beyond first order (a symmetry) is checked by
//! moving them on and taking `A` again ([`SteadyLinearization::cyclic_change`]).
//!
//! Coordinates whose rates are not the speeds (Euler angles, chosen speeds) are moved in the
//! chart by adding to them, with `ẋ`'s rows from `q̇ = W(q) u`; unit quaternions are not (the
//! chart would need a retraction), nor, with such coordinates, loops.

use nalgebra::{Complex, DMatrix};

use crate::constraints::{assemble, assemble_speeds, AssemblyOptions};
use crate::integrate::{check_indices, check_len};
use crate::linearize::{derivative, step_for};
use crate::signal::default_signals;
use crate::simulate::ModelOde;
use crate::{Model, RuntimeError};

/// An entry of `∂ẋ/∂z` below this fraction of the Jacobian's largest is zero (a state does
/// not feel that coordinate). Central differences leave ~1e-10
/// relative of noise on a zero entry (loops closed to 1e-13, steps of 1e-5 relative).
const CYCLIC_TOLERANCE: f64 = 1e-7;

/// How far the cyclic coordinates are moved to check that nothing depends on them (SI).
const CYCLIC_SHIFT: f64 = 0.37;

/// One state of a [`SteadyLinearization`]: a coordinate or a speed, by its index in `q`/`u`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SteadyState {
    Coordinate(usize),
    Speed(usize),
}

/// `δẋ = A δx` about a steady motion; see the module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct SteadyLinearization {
    /// The operating point and the inputs held there.
    pub q: Vec<f64>,
    pub u: Vec<f64>,
    pub inputs: Vec<f64>,
    /// The coordinates kept independent by the loops (indices into `q`), all of them without
    /// loops.
    pub coordinates: Vec<usize>,
    /// Those of `coordinates` the motion does not depend on (dropped from the state).
    pub cyclic: Vec<usize>,
    /// The independent speeds `w` (indices into `u`).
    pub speeds: Vec<usize>,
    /// The state `x`: the non-cyclic independent coordinates, then the independent speeds.
    pub states: Vec<SteadyState>,
    /// `A = ∂ẋ/∂x` at the operating point.
    pub a: DMatrix<f64>,
    /// `ẋ` at the operating point: zero, up to round-off, for a steady motion.
    pub drift: Vec<f64>,
    /// How much `A` changes, relative to its largest entry, when the cyclic coordinates move
    /// on by 0.37 (SI units): round-off for a true symmetry; otherwise the dropped coordinates
    /// are cyclic only to first order here and `A` holds at this instant only (a periodic
    /// motion, which needs Floquet analysis, or a poor choice of coordinates).
    pub cyclic_change: f64,
    /// Whether the model's coordinate rates are its speeds (the second-order form needs it).
    pub rates_are_speeds: bool,
    /// `M̃ = Tᵀ M T` with `T = ∂u/∂w` (the independent speeds' partial velocities): the mass
    /// matrix of Kane's reduced equations, rows and columns in the order of `speeds`.
    pub mass: DMatrix<f64>,
}

/// Second-order form `M δz̈ + C δż + K δz = 0` of a steady linearization in the coordinates
/// whose rates are among the independent speeds (see [`SteadyLinearization::second_order`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SecondOrder {
    /// The coordinates `z` (indices into `q`; their speeds have the same indices in `u`).
    pub coordinates: Vec<usize>,
    pub mass: DMatrix<f64>,
    pub damping: DMatrix<f64>,
    pub stiffness: DMatrix<f64>,
}

impl SteadyLinearization {
    /// The eigenvalues of `A`, sorted by real part, then imaginary part.
    pub fn eigenvalues(&self) -> Vec<Complex<f64>> {
        let mut values: Vec<Complex<f64>> = self.a.complex_eigenvalues().iter().copied().collect();
        values.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
        values
    }

    /// The largest `|ẋ|` at the operating point: how far it is from a steady motion.
    pub fn unsteadiness(&self) -> f64 {
        self.drift.iter().fold(0.0, |m, x| m.max(x.abs()))
    }

    /// `M δz̈ + C δż + K δz = 0` over the non-cyclic coordinates, when each of their speeds
    /// is an independent speed (a coordinate's rate is its speed): `M` is `M̃` on those speeds,
    /// `C = −M ∂ż̇/∂ż` and `K = −M ∂z̈/∂z`. The other independent speeds (a wheel's spin
    /// setting the forward speed) are held at the operating point; they must not be coupled
    /// to `z` through `M̃` (`None` otherwise, and when a coordinate's speed is dependent).
    pub fn second_order(&self) -> Option<SecondOrder> {
        if !self.rates_are_speeds {
            return None;
        }
        let coordinates: Vec<usize> = self
            .states
            .iter()
            .filter_map(|state| match state {
                SteadyState::Coordinate(i) => Some(*i),
                SteadyState::Speed(_) => None,
            })
            .collect();
        let n = coordinates.len();
        // Position of each coordinate's speed among `speeds`, and among the states.
        let in_speeds: Vec<usize> = coordinates
            .iter()
            .map(|i| self.speeds.iter().position(|s| s == i))
            .collect::<Option<_>>()?;
        let others: Vec<usize> = (0..self.speeds.len())
            .filter(|k| !in_speeds.contains(k))
            .collect();
        let scale = self.mass.amax();
        let coupled = in_speeds.iter().any(|&r| {
            others
                .iter()
                .any(|&c| self.mass[(r, c)].abs() > 1e-12 * scale)
        });
        if coupled {
            return None;
        }
        let mass = DMatrix::from_fn(n, n, |r, c| self.mass[(in_speeds[r], in_speeds[c])]);
        let row = |k: usize| n + in_speeds[k];
        let position = DMatrix::from_fn(n, n, |r, c| self.a[(row(r), c)]);
        let velocity = DMatrix::from_fn(n, n, |r, c| self.a[(row(r), row(c))]);
        Some(SecondOrder {
            coordinates,
            damping: -(&mass * velocity),
            stiffness: -(&mass * position),
            mass,
        })
    }
}

/// The map from the chart `x = [z; w]` to consistent states and their rates.
struct Chart<'a, M: Model + ?Sized> {
    model: &'a M,
    ode: ModelOde<'a, M>,
    t: f64,
    q: &'a [f64],
    u: &'a [f64],
    inputs: &'a [f64],
    coordinates: &'a [usize],
    speeds: &'a [usize],
}

impl<M: Model + ?Sized> Chart<'_, M> {
    /// `∂ẋ/∂(z, w)` at `(z, w)`, each column by central differences.
    fn jacobian(&mut self, z0: &[f64], w0: &[f64]) -> Result<DMatrix<f64>, RuntimeError> {
        let (nz, nw) = (z0.len(), w0.len());
        let mut jacobian = DMatrix::zeros(nz + nw, nz + nw);
        for k in 0..nz + nw {
            let base = if k < nz { z0[k] } else { w0[k - nz] };
            let column = derivative(
                |h| {
                    let (mut z, mut w) = (z0.to_vec(), w0.to_vec());
                    match k < nz {
                        true => z[k] += h,
                        false => w[k - nz] += h,
                    }
                    self.rates(&z, &w)
                },
                step_for(base),
            )?;
            jacobian.column_mut(k).copy_from_slice(&column);
        }
        match jacobian.iter().all(|x| x.is_finite()) {
            true => Ok(jacobian),
            false => Err(RuntimeError::NonFinite {
                what: "the steady-motion linearization",
            }),
        }
    }

    /// `(q, u)` at `z` (every independent coordinate), `w`: the loops closed from the operating
    /// point, the dependent speeds solved from the constraint rows.
    fn state(&self, z: &[f64], w: &[f64]) -> Result<(Vec<f64>, Vec<f64>), RuntimeError> {
        let model = self.model;
        let mut q = self.q.to_vec();
        for (&i, &value) in self.coordinates.iter().zip(z) {
            q[i] = value;
        }
        if model.holonomic_rows() > 0 {
            assemble(
                model,
                self.t,
                &mut q,
                self.coordinates,
                &AssemblyOptions::default(),
            )?;
        }
        let mut u = self.u.to_vec();
        for (&i, &value) in self.speeds.iter().zip(w) {
            u[i] = value;
        }
        if model.nc() > 0 {
            assemble_speeds(model, self.t, &q, &mut u, self.speeds)?;
        }
        Ok((q, u))
    }

    /// `ẋ = [q̇_z; u̇_w]` at `(z, w)`.
    fn rates(&mut self, z: &[f64], w: &[f64]) -> Result<Vec<f64>, RuntimeError> {
        let (q, u) = self.state(z, w)?;
        let mut udot = vec![0.0; self.model.nu()];
        self.ode
            .accelerations(self.t, &q, &u, self.inputs, &mut udot)?;
        let mut qdot = vec![0.0; self.model.nq()];
        self.model.kinematic_rates(self.t, &q, &u, &mut qdot);
        let rates = self.coordinates.iter().map(|&i| qdot[i]);
        let accelerations = self.speeds.iter().map(|&i| udot[i]);
        Ok(rates.chain(accelerations).collect())
    }
}

/// Linearizes `model` about the steady motion through `(q, u)` (consistent: loops closed,
/// `[J; A] u = 0`) under constant `inputs`. `coordinates` are the coordinates the loops leave
/// independent (all of them without loops), `speeds` the speeds all constraint rows leave
/// independent (`coordinates` without velocity constraints); the session's assembly chooses
/// both. Errors: a model with quaternions, wrong lengths, loops that do not close near the
/// operating point, a linear model that is not finite.
pub fn linearize_steady<M: Model + ?Sized>(
    model: &M,
    t: f64,
    (q, u): (&[f64], &[f64]),
    inputs: &[f64],
    coordinates: &[usize],
    speeds: &[usize],
) -> Result<SteadyLinearization, RuntimeError> {
    // The chart moves coordinates by adding to them: no unit quaternions; and it closes the
    // loops in coordinates, so with loops their rates must be the speeds.
    if !model.unit_quaternions().is_empty()
        || (!model.rates_are_speeds() && model.holonomic_rows() > 0)
    {
        model.require_rates_are_speeds("steady-motion linearization")?;
    }
    check_len("q", model.nq(), q.len())?;
    check_len("u", model.nu(), u.len())?;
    check_len("inputs", model.ninputs(), inputs.len())?;
    check_indices("independent coordinates", coordinates, model.nq())?;
    check_indices("independent speeds", speeds, model.nu())?;
    let signals = default_signals(model);
    let mut chart = Chart {
        model,
        ode: ModelOde::new(model, &signals)?,
        t,
        q,
        u,
        inputs,
        coordinates,
        speeds,
    };
    let z0: Vec<f64> = coordinates.iter().map(|&i| q[i]).collect();
    let w0: Vec<f64> = speeds.iter().map(|&i| u[i]).collect();
    let (nz, nw) = (z0.len(), w0.len());
    let drift_all = chart.rates(&z0, &w0)?;
    let jacobian = chart.jacobian(&z0, &w0)?;
    let largest = jacobian.amax();
    let felt =
        |row: usize, column: usize| jacobian[(row, column)].abs() > CYCLIC_TOLERANCE * largest;
    // The largest set of coordinates that no other state feels: start from all of them, drop
    // each that a state outside the set feels, until none is dropped. (A cyclic coordinate's
    // own rate may depend on anything: a rolling wheel's position on its heading.)
    let mut cyclic_set: Vec<usize> = (0..nz).collect();
    loop {
        let outside: Vec<usize> = (0..nz + nw).filter(|r| !cyclic_set.contains(r)).collect();
        let before = cyclic_set.len();
        cyclic_set.retain(|&k| !outside.iter().any(|&r| felt(r, k)));
        if cyclic_set.len() == before {
            break;
        }
    }
    let kept: Vec<usize> = (0..nz + nw).filter(|k| !cyclic_set.contains(k)).collect();
    let cyclic = cyclic_set.iter().map(|&k| coordinates[k]).collect();
    let states = kept
        .iter()
        .map(|&k| match k < nz {
            true => SteadyState::Coordinate(coordinates[k]),
            false => SteadyState::Speed(speeds[k - nz]),
        })
        .collect();
    let a = jacobian.select_rows(&kept).select_columns(&kept);
    // Cyclic to first order is not enough: the kept equations must not depend on the dropped
    // coordinates at all (a symmetry), or A changes as they run on. Moved by a finite step
    // (0.37 in SI units), A must stay the same.
    let mut shifted = z0.clone();
    for &k in &cyclic_set {
        shifted[k] += CYCLIC_SHIFT;
    }
    let cyclic_change = match cyclic_set.is_empty() {
        true => 0.0,
        false => {
            let moved = chart.jacobian(&shifted, &w0)?;
            let moved = moved.select_rows(&kept).select_columns(&kept);
            (moved - &a).amax() / a.amax().max(f64::MIN_POSITIVE)
        }
    };
    let drift = kept.iter().map(|&k| drift_all[k]).collect();
    // T = ∂u/∂w: the speed map is linear in w, so its columns are exact.
    let mut transform = DMatrix::zeros(model.nu(), nw);
    for k in 0..nw {
        let mut column = vec![0.0; model.nu()];
        column[speeds[k]] = 1.0;
        if model.nc() > 0 {
            assemble_speeds(model, t, q, &mut column, speeds)?;
        }
        transform.column_mut(k).copy_from_slice(&column);
    }
    let mut full_mass = DMatrix::zeros(model.nu(), model.nu());
    model.mass_matrix(t, q, inputs, full_mass.as_mut_slice());
    let mass = transform.transpose() * full_mass * &transform;
    Ok(SteadyLinearization {
        q: q.to_vec(),
        u: u.to_vec(),
        inputs: inputs.to_vec(),
        coordinates: coordinates.to_vec(),
        cyclic,
        speeds: speeds.to_vec(),
        states,
        a,
        drift,
        cyclic_change,
        rates_are_speeds: model.rates_are_speeds(),
        mass,
    })
}
