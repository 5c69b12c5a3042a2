//! The contract between a model (generated Rust, or the tape evaluator) and everything that
//! runs it: integrators, analyses, the command line.
//!
//! A model is `M(q) u̇ = F(t, q, u, inputs)` with `q̇ = W(q) u` (`q̇ = u` unless it has
//! quaternions), plus outputs `y(t, q, u, inputs)`.
//! Slices keep the trait object-safe and size-agnostic; generated models also offer
//! fixed-size inherent methods (`mass_matrix_fixed` → `SMatrix<f64, NU, NU>`, …) for
//! embedding, named apart from the trait's so that neither shadows the other.

use crate::RuntimeError;

/// `q̇ = u` into `out`; an entry of `out` past the end of `u` is NaN (a model with more
/// coordinates than speeds that does not give its own `q̇` fails loudly, not silently).
pub fn rates_equal_speeds(u: &[f64], out: &mut [f64]) {
    for (i, slot) in out.iter_mut().enumerate() {
        *slot = u.get(i).copied().unwrap_or(f64::NAN);
    }
}

/// `M`, `F`, `J̇u` and, if asked for, `J`, each by its own method: the default of
/// [`Model::constrained_terms`] (with `J`) and [`Model::dynamics_terms`] (without), and what
/// a model with a fused pass of them falls back to where it has none.
pub fn terms_by_part<M: Model + ?Sized>(
    model: &M,
    t: f64,
    q: &[f64],
    u: &[f64],
    inputs: &[f64],
    [mass, forcing, bias]: [&mut [f64]; 3],
    jacobian: Option<&mut [f64]>,
) {
    model.mass_matrix(t, q, inputs, mass);
    model.forcing(t, q, u, inputs, forcing);
    model.constraint_bias(t, q, u, bias);
    if let Some(jacobian) = jacobian {
        model.constraint_jacobian(t, q, jacobian);
    }
}

/// A multibody model in Kane's form `M(q) u̇ = F(t, q, u, inputs)`, `q̇ = W(q) u`
/// ([`Model::kinematic_rates`]; `W = I` and `nq == nu` unless the model has unit quaternions).
///
/// Matrices are written column-major into `out` (the layout of nalgebra's `DMatrix`).
/// Implementations never allocate and never panic for slices of the documented lengths.
pub trait Model {
    /// Model name, snake_case, as in the `.mech` file.
    fn name(&self) -> &str;
    /// Number of generalized coordinates `q`.
    fn nq(&self) -> usize;
    /// Number of generalized speeds `u` (equal to `nq` unless the model has quaternions: each
    /// has four coordinates and three speeds).
    fn nu(&self) -> usize;
    /// Number of named inputs.
    fn ninputs(&self) -> usize;
    /// Number of scalar outputs.
    fn noutputs(&self) -> usize;
    /// Number of parameters.
    fn nparams(&self) -> usize;

    fn coordinate_name(&self, i: usize) -> &str;
    /// Name of speed `i`: the coordinate's where `u_i = q̇_i` (the default), `ball.wx` for
    /// an angular speed of a quaternion joint.
    fn speed_name(&self, i: usize) -> &str {
        self.coordinate_name(i)
    }
    fn input_name(&self, i: usize) -> &str;
    fn output_name(&self, i: usize) -> &str;
    fn param_name(&self, i: usize) -> &str;
    fn param(&self, i: usize) -> f64;
    fn set_param(&mut self, i: usize, value: f64);
    /// Value an input takes when no signal is supplied.
    fn input_default(&self, i: usize) -> f64;

    /// Initial `q` and `u` written in the model (`q0`, `u0` of each joint).
    fn initial_state(&self, q: &mut [f64], u: &mut [f64]);

    /// The contacts' damping `D ≈ ∂F/∂u` (`nu × nu`, column-major, symmetric negative
    /// semidefinite): the stiff part of `F` that [`crate::Method::RosenbrockW`] takes
    /// implicitly. Writes it and returns `true`, or returns `false` (leaving `out` as it is)
    /// for a model without contacts (both back ends generate it for the others).
    fn contact_damping(
        &self,
        _t: f64,
        _q: &[f64],
        _u: &[f64],
        _inputs: &[f64],
        _out: &mut [f64],
    ) -> bool {
        false
    }

    /// `M(q)`, `nu × nu`, column-major, symmetric positive definite for a well-posed model.
    fn mass_matrix(&self, t: f64, q: &[f64], inputs: &[f64], out: &mut [f64]);
    /// `F(t, q, u, inputs)`: generalized active forces plus the velocity-dependent part of the
    /// generalized inertia forces, so that `M u̇ = F`.
    fn forcing(&self, t: f64, q: &[f64], u: &[f64], inputs: &[f64], out: &mut [f64]);
    /// `F(t, q, 0, inputs)`, the forcing at rest (statics). The default evaluates
    /// [`Model::forcing`] with zero speeds; a model may supply a cheaper form without the
    /// velocity terms.
    fn static_forcing(&self, t: f64, q: &[f64], inputs: &[f64], out: &mut [f64]) {
        self.forcing(t, q, &vec![0.0; self.nu()], inputs, out);
    }
    /// The kinematic differential equations `q̇ = W(q) u` into `out` (length `nq`). The default
    /// is `q̇ = u` ([`rates_equal_speeds`]), right for every model with `nq == nu`; a model with
    /// quaternions overrides it.
    fn kinematic_rates(&self, _t: f64, _q: &[f64], u: &[f64], out: &mut [f64]) {
        rates_equal_speeds(u, out);
    }
    /// Index in `q` of the scalar part of each unit quaternion (followed by its vector part):
    /// integrators keep these four coordinates at unit norm. Empty by default.
    fn unit_quaternions(&self) -> &[usize] {
        &[]
    }
    /// Number of coordinates with `q̇ᵢ = uᵢ` (pins, sliders): they come first in `q`, and
    /// the same index addresses their speed. The first quaternion's index, or `nq`; a model
    /// with Euler angles (three coordinates, `q̇ ≠ u`, no unit norm to keep) overrides it.
    fn plain_coordinates(&self) -> usize {
        self.unit_quaternions()
            .iter()
            .copied()
            .min()
            .unwrap_or(self.nq())
    }
    /// Whether `q̇ = u` ([`Model::kinematic_rates`] is the identity): as many speeds as
    /// coordinates, every one plain (no quaternion, no Euler angles). Analyses written for
    /// `q̇ = u` refuse other models.
    fn rates_are_speeds(&self) -> bool {
        self.nq() == self.nu() && self.plain_coordinates() == self.nq()
    }
    /// `Ok` where `q̇ = u`; else [`RuntimeError::QuaternionsUnsupported`] for `analysis`.
    fn require_rates_are_speeds(&self, analysis: &'static str) -> Result<(), RuntimeError> {
        match self.rates_are_speeds() {
            true => Ok(()),
            false => Err(RuntimeError::QuaternionsUnsupported {
                analysis,
                model: self.name().to_string(),
            }),
        }
    }
    /// `Ok` without velocity constraints; else
    /// [`RuntimeError::VelocityConstraintsUnsupported`] for `analysis`.
    fn require_holonomic(&self, analysis: &'static str) -> Result<(), RuntimeError> {
        match self.velocity_rows() {
            0 => Ok(()),
            _ => Err(RuntimeError::VelocityConstraintsUnsupported {
                analysis,
                model: self.name().to_string(),
            }),
        }
    }
    /// Outputs `y(t, q, u, inputs)`.
    fn outputs(&self, t: f64, q: &[f64], u: &[f64], inputs: &[f64], out: &mut [f64]);
    /// Outputs that are integrals over a simulation, as `(target, rate)` output indices: a
    /// simulation samples output `target` as `∫ y_rate dt` from its start, integrated with the
    /// motion (a state of its own under the integrator's error test); [`Model::outputs`]
    /// writes 0 there (no run, nothing integrated). A contact's `.dissipated` energy, the
    /// integral of its `.power`. Default: none.
    fn integrated_outputs(&self) -> &[(usize, usize)] {
        &[]
    }
    /// The outputs listed in `which` alone, `out[k] = y[which[k]]`, for callers that need a
    /// few outputs many times (the fixtures of the statics). False, with `out` untouched,
    /// where the model evaluates its outputs only together (the default); the caller then
    /// uses [`Model::outputs`].
    fn selected_outputs(
        &self,
        _t: f64,
        _q: &[f64],
        _u: &[f64],
        _inputs: &[f64],
        _which: &[usize],
        _out: &mut [f64],
    ) -> bool {
        false
    }

    /// Number of loop-closure constraint rows `φ(q) = 0` (0 for tree models). Rows may be
    /// redundant (rank-deficient `J`).
    fn nc(&self) -> usize {
        0
    }
    /// Number of velocity-constraint rows `A(q) u = 0` (nonholonomic): the last
    /// `velocity_rows()` of the `nc` rows, whose `φ` is 0 (they have no position form). They
    /// enter `J`, `J̇u` and so the multipliers like loop rows; position-level steps (assembly,
    /// projection of `q`) leave them out. 0 by default.
    fn velocity_rows(&self) -> usize {
        0
    }
    /// Number of loop-closure rows `φ(q) = 0`: the first `nc − velocity_rows` rows.
    fn holonomic_rows(&self) -> usize {
        self.nc() - self.velocity_rows()
    }
    /// Name of constraint row `i`, e.g. `fb2.x` or `fb2.align1`.
    fn constraint_name(&self, _i: usize) -> &str {
        ""
    }
    /// `φ(q)`, length `nc`.
    fn constraints(&self, _t: f64, _q: &[f64], _out: &mut [f64]) {}
    /// `J(q)` with `φ̇ = J u`, `nc × nu`, column-major: `∂φ/∂q` where `q̇ = u`, `∂φ/∂q W(q)`
    /// with quaternions (so that `J u = 0`, `M u̇ = F + Jᵀλ` hold in the speeds).
    fn constraint_jacobian(&self, _t: f64, _q: &[f64], _out: &mut [f64]) {}
    /// `J̇(q, u) u`, so that `J u̇ + J̇u = 0` keeps `J u = 0`.
    fn constraint_bias(&self, _t: f64, _q: &[f64], _u: &[f64], _out: &mut [f64]) {}

    /// `M`, `F`, `J` and `J̇u` in one call (matrices column-major), for constrained dynamics.
    /// Generated code overrides it with one pass that shares subexpressions between the four
    /// (the sines and cosines of the coordinates, above all).
    #[allow(clippy::too_many_arguments)]
    fn constrained_terms(
        &self,
        t: f64,
        q: &[f64],
        u: &[f64],
        inputs: &[f64],
        mass: &mut [f64],
        forcing: &mut [f64],
        jacobian: &mut [f64],
        bias: &mut [f64],
    ) {
        terms_by_part(self, t, q, u, inputs, [mass, forcing, bias], Some(jacobian));
    }

    /// `M`, `F` and `J̇u` in one call (`M` column-major): [`Model::constrained_terms`] without
    /// `J`, for callers that already hold `J` at `q` (the reduced dynamics factor it when
    /// they close the loops). Generated code overrides it with the fused pass of
    /// `constrained_terms` minus what only `J` needs.
    #[allow(clippy::too_many_arguments)]
    fn dynamics_terms(
        &self,
        t: f64,
        q: &[f64],
        u: &[f64],
        inputs: &[f64],
        mass: &mut [f64],
        forcing: &mut [f64],
        bias: &mut [f64],
    ) {
        terms_by_part(self, t, q, u, inputs, [mass, forcing, bias], None);
    }

    /// Number of flexures (compliant hinges with a loss factor).
    fn nflexures(&self) -> usize {
        0
    }
    /// Name of flexure `i`.
    fn flexure_name(&self, _i: usize) -> &str {
        ""
    }
    /// `[θ…, k…, b…, η…]` (length `4·nflexures`): each flexure's bending angle, stiffness,
    /// time-domain damping `kη/ω_ref` and loss factor `η`. Frequency-domain analyses replace
    /// the damping `b` by the complex stiffness `k(1 + iη)`.
    fn flexures(&self, _t: f64, _q: &[f64], _out: &mut [f64]) {}

    /// Index of the generalized coordinate called `name`, as [`Model::coordinate_name`]
    /// spells it (e.g. `crank_angle`); the same index addresses `q` and `u`.
    fn coordinate_index(&self, name: &str) -> Option<usize> {
        (0..self.nq()).find(|&i| self.coordinate_name(i) == name)
    }
    /// Index of the parameter called `name`.
    fn param_index(&self, name: &str) -> Option<usize> {
        (0..self.nparams()).find(|&i| self.param_name(i) == name)
    }
    /// Index of the input called `name`.
    fn input_index(&self, name: &str) -> Option<usize> {
        (0..self.ninputs()).find(|&i| self.input_name(i) == name)
    }
    /// Index of the output called `name`.
    fn output_index(&self, name: &str) -> Option<usize> {
        (0..self.noutputs()).find(|&i| self.output_name(i) == name)
    }
}

/// Scales each unit quaternion of `q` (four coordinates from each index in `quaternions`)
/// back to unit norm, the projection onto `|e| = 1` along `e`; returns whether any changed.
/// Integrating `ė = ½ e ⊗ (0, ω)` keeps `|e|` constant only up to the integrator's error.
pub fn normalize_quaternions(quaternions: &[usize], q: &mut [f64]) -> bool {
    let mut changed = false;
    for &start in quaternions {
        let Some(e) = q.get_mut(start..start + 4) else {
            continue;
        };
        let norm = e.iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm > 0.0 && norm.is_finite() && norm != 1.0 {
            e.iter_mut().for_each(|v| *v /= norm);
            changed = true;
        }
    }
    changed
}

#[cfg(test)]
mod tests {
    use super::normalize_quaternions;

    #[test]
    fn quaternions_are_scaled_to_unit_norm_and_nothing_else_moves() {
        let mut q = [0.5, 2.0, 0.0, 0.0, 0.0, 3.0, 0.25];
        assert!(normalize_quaternions(&[1], &mut q));
        assert_eq!(q[0], 0.5);
        assert_eq!(&q[1..5], &[1.0, 0.0, 0.0, 0.0]);
        assert_eq!(&q[5..], &[3.0, 0.25]);
        // Already unit: unchanged, reported as such; an index past the end is skipped.
        assert!(!normalize_quaternions(&[1, 6], &mut q));
        let mut zero = [0.0; 4];
        assert!(
            !normalize_quaternions(&[0], &mut zero),
            "no direction to scale"
        );
    }
}
