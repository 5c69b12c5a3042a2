//! The equations of motion as plain data: what [`derive`](super::derive) produces and the
//! back ends read.
//!
//! Consumes: nothing (declarations only). Produces: [`Equations`] and [`FlexureRows`], root
//! ids into the expression pool they carry.

use super::constraints;
use crate::sym::{ExprId, ExprPool};

/// The equations of motion of a model, ready for the back ends.
#[derive(Clone, Debug)]
pub struct Equations {
    pub pool: ExprPool,
    /// Number of generalized coordinates and speeds (equal without quaternions).
    pub nq: usize,
    pub nu: usize,
    /// The kinematic differential equations `q̇ = W(q) u`, length `nq`, where they are not
    /// `q̇ = u`: `None` for models without quaternions, Euler angles or chosen speeds
    /// (`speed` declarations, whose `W = Y⁻¹` this carries).
    pub kinematic_rates: Option<Vec<ExprId>>,
    /// `M(q)`, `nu × nu`, column-major; symmetric (`M[r + nu*s] == M[s + nu*r]`, same id).
    pub mass_matrix: Vec<ExprId>,
    /// `F(t, q, u, inputs)`, length `nu`.
    pub forcing: Vec<ExprId>,
    /// `F(t, q, 0, inputs)`: the forcing at rest, for statics (no velocity term of `F_r*`, no
    /// damper); `None` where a speed sits under a negative power (no value at `u = 0`).
    pub static_forcing: Option<Vec<ExprId>>,
    /// The contacts' damping `D ≈ ∂F/∂u` (`nu × nu`, column-major, symmetric negative
    /// semidefinite; `ContactState::add_damping` in `contact.rs`): the stiff part of `F` that a
    /// linearly implicit integrator takes implicitly. `None` for models without contacts.
    pub contact_damping: Option<Vec<ExprId>>,
    /// Scalar outputs in declaration order (vector outputs expanded to `.x`, `.y`, `.z`).
    pub outputs: Vec<ExprId>,
    pub output_names: Vec<String>,
    /// Outputs that a simulation integrates, as `(target, rate)` indices into `outputs`: the
    /// target (0 in `outputs`) is sampled as `∫ rate dt` from the start of the run (a
    /// contact's dissipated energy; `Model::integrated_outputs` in the runtime).
    pub integrated_outputs: Vec<(usize, usize)>,
    /// Loop-closure rows: `φ(q)`, `J` (`nc × nu`, column-major; `∂φ/∂q` where `q̇ = u`) and
    /// `J̇u`; the velocity constraints' rows `A(q) u = 0` last (`φ` = 0, `J` rows `A`, bias
    /// `Ȧu`).
    pub constraints: constraints::Constraints,
    /// Flexures: their angles `θ(q)`, stiffness `k`, time-domain damping `b` and loss factor
    /// `η`, for frequency-domain analyses (complex stiffness `k(1 + iη)`).
    pub flexures: FlexureRows,
}

/// Per-flexure expressions, in `Model::flexures` order.
#[derive(Clone, Debug, Default)]
pub struct FlexureRows {
    pub names: Vec<String>,
    pub angles: Vec<ExprId>,
    pub stiffness: Vec<ExprId>,
    pub damping: Vec<ExprId>,
    pub loss_factor: Vec<ExprId>,
}

impl FlexureRows {
    /// `[θ…, k…, b…, η…]`, the layout of the generated `flexures` function.
    pub fn all(&self) -> Vec<ExprId> {
        [
            &self.angles,
            &self.stiffness,
            &self.damping,
            &self.loss_factor,
        ]
        .into_iter()
        .flatten()
        .copied()
        .collect()
    }
}

impl Equations {
    /// Number of constraint rows `NC` (redundant rows and velocity rows included).
    pub fn nc(&self) -> usize {
        self.constraints.residual.len()
    }
}
