//! The kinematic differential equations `q̇ = W(q) u` and the chain rule through them.
//!
//! Consumes: a model's coordinates, rotations and free joints' translations. Produces:
//! [`KinematicRates`], which turns a function `f(q)` into its rate `ḟ = Σᵢ ∂f/∂qᵢ q̇ᵢ` and
//! its partial rates `∂ḟ/∂u_r = Σᵢ ∂f/∂qᵢ W_ir` (Kane & Levinson §2.14: what a partial
//! velocity is to a position). Where every coordinate is a pin's or slider's `W = I`, and
//! both reduce to `∂f/∂q_r` and `Σ ∂f/∂qᵢ uᵢ` built exactly as before quaternions existed, so
//! the equations of such models (and their golden files) do not change.
//!
//! With a quaternion the coordinates `e₀…e₃` have no speeds of their own: their rates are
//! `ė = ½ e ⊗ (0, ω)`, linear in the body's angular speeds, so a loop row `φ(q)` has
//! `J_r = ∂φ̇/∂u_r = Σᵢ ∂φ/∂qᵢ W_ir`, `nc × nu` like the mass matrix. A free joint's
//! position `(x, y, z)` likewise moves by the velocity speeds turned by the child's rotation.

use std::collections::HashMap;

use super::{kinematics, vector};
use crate::ir::{Model, Motion};
use crate::sym::{ExprId, ExprPool, Symbol};

/// Per speed r, the nonzero `W_ir = ∂q̇ᵢ/∂u_r` as `(i, W_ir)`.
type Columns = Vec<Vec<(usize, ExprId)>>;

/// `q̇ = W(q) u`, for derivatives along the motion.
pub struct KinematicRates {
    nu: usize,
    /// `q̇ᵢ` per coordinate, and `W` by columns; `None` where `q̇ = u`.
    chain: Option<(Vec<ExprId>, Columns)>,
}

impl KinematicRates {
    /// `q̇ = u` for a model without quaternions, else `q̇ᵢ = uᵢ` for the coordinates and
    /// `ė = ½ e ⊗ (0, ω)` for each quaternion (as [`rates`] builds them). The chain is built
    /// only for a model with loops, velocity constraints or bushings, the places a function
    /// of a quaternion's coordinates meets it (loop rows, loop flexure angles, the rate `Ȧu`
    /// of a velocity row, a bushing's offsets): a pin or
    /// slider coordinate's partial rates are `∂q_c/∂q_r` either way, and other models keep
    /// their pool numbering.
    pub fn new(pool: &mut ExprPool, model: &Model) -> KinematicRates {
        let nu = model.nu();
        let bushing = model
            .loads
            .iter()
            .any(|load| matches!(load, crate::ir::Load::Bushing { .. }));
        let needed = !model.loops.is_empty() || !model.velocity_constraints.is_empty() || bushing;
        let chain = needed.then(|| rates(pool, model)).flatten().map(|rates| {
            let mut columns = vec![Vec::new(); nu];
            for (i, &rate) in rates.iter().enumerate() {
                for (r, column) in columns.iter_mut().enumerate() {
                    let entry = pool.diff(rate, Symbol::Speed(r as u32));
                    if !pool.is_zero(entry) {
                        column.push((i, entry));
                    }
                }
            }
            (rates, columns)
        });
        KinematicRates { nu, chain }
    }

    /// `∂ḟ/∂u_r` for every speed r: `∂f/∂q_r` where `q̇ = u`.
    pub fn partial_rates(&self, pool: &mut ExprPool, f: ExprId) -> Vec<ExprId> {
        let Some((_, columns)) = &self.chain else {
            return (0..self.nu)
                .map(|r| pool.diff(f, Symbol::Coordinate(r as u32)))
                .collect();
        };
        columns
            .iter()
            .map(|column| {
                let terms: Vec<ExprId> = column
                    .iter()
                    .map(|&(i, w)| {
                        let slope = pool.diff(f, Symbol::Coordinate(i as u32));
                        pool.mul(slope, w)
                    })
                    .collect();
                pool.add_all(&terms)
            })
            .collect()
    }

    /// `ḟ = Σᵢ ∂f/∂qᵢ q̇ᵢ + ∂f/∂t` of a function of `q` and `t` ([`ExprPool::time_derivative`]
    /// where `q̇ = u`).
    pub fn rate(&self, pool: &mut ExprPool, f: ExprId) -> ExprId {
        let Some((rates, _)) = &self.chain else {
            return pool.time_derivative(f);
        };
        let mut along = coordinate_rates(pool, rates.len(), Some(rates));
        along.insert(Symbol::Time, pool.one());
        pool.derivative_along(f, &along)
    }

    /// `ḟ` of `f(q, u)` with `u̇` held (the velocity-dependent part of a second derivative:
    /// `J̇u = Σᵢ ∂(J u)/∂qᵢ q̇ᵢ`), by one forward pass along `q̇` ([`ExprPool::derivative_along`]).
    pub fn rate_at_fixed_speeds(&self, pool: &mut ExprPool, f: ExprId, nq: usize) -> ExprId {
        let rates = self.chain.as_ref().map(|(rates, _)| &rates[..]);
        let along = coordinate_rates(pool, nq, rates);
        pool.derivative_along(f, &along)
    }
}

/// `q̇ᵢ` by coordinate symbol: `rates[i]`, or `uᵢ` where `q̇ = u`.
fn coordinate_rates(
    pool: &mut ExprPool,
    nq: usize,
    rates: Option<&[ExprId]>,
) -> HashMap<Symbol, ExprId> {
    (0..nq)
        .map(|i| {
            let rate = match rates {
                Some(rates) => rates[i],
                None => pool.symbol(Symbol::Speed(i as u32)),
            };
            (Symbol::Coordinate(i as u32), rate)
        })
        .collect()
}

/// `q̇ = W(q) u`: `q̇ᵢ = uᵢ` for the coordinates, `ė = ½ e ⊗ (0, ω)` for each quaternion,
/// [`vector::euler_rates`] for each set of Euler angles, `(ẋ, ẏ, ż) = R v` for each free
/// joint's translation (`v` in the child's basis, `R` its rotation); `None` without any of
/// them (`q̇ = u`).
pub fn rates(pool: &mut ExprPool, model: &Model) -> Option<Vec<ExprId>> {
    if !model.has_kinematic_rates() {
        return None;
    }
    let mut rates: Vec<ExprId> = (0..model.coordinates.len())
        .map(|i| pool.symbol(Symbol::Speed(i as u32)))
        .collect();
    for (quaternion, _) in model.quaternions.iter() {
        let e = kinematics::coordinate_run(pool, model.quaternion_coordinate(quaternion, 0));
        let omega = kinematics::speed_run(pool, model.angular_speed(quaternion, 0)).map(|(_, u)| u);
        rates.extend(vector::quaternion_rates(pool, e, omega));
    }
    for (angles, rotation) in model.euler_angles.iter() {
        let q = kinematics::coordinate_run(pool, model.euler_coordinate(angles, 0));
        let omega = kinematics::speed_run(pool, model.euler_speed(angles, 0)).map(|(_, u)| u);
        rates.extend(vector::euler_rates(pool, rotation.sequence, q, omega));
    }
    for (translation, _) in model.translations.iter() {
        let rotation = model
            .frames
            .iter()
            .find_map(|(_, frame)| match frame.motion {
                Motion::Free {
                    rotation,
                    translation: moved,
                } if moved == translation => Some(rotation),
                _ => None,
            });
        let rotation = rotation.expect("each translation is driven by one free motion (IR)");
        let turn = kinematics::joint_rotation(pool, model, rotation);
        let first = model.translation_speed(translation, 0);
        let velocity = [0, 1, 2].map(|axis| pool.symbol(Symbol::Speed((first + axis) as u32)));
        rates.extend(vector::mat_vec(pool, &turn, velocity));
    }
    Some(rates)
}
