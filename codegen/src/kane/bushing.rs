//! A bushing's six springs between two frames ([`ir::Load::Bushing`]): the offsets `s(q)`
//! of one frame from the other and the laws that act on them, shared by the forcing and the
//! potential energy.
//!
//! Consumes: the tree kinematics and the bushing's frames and laws. Produces: pool
//! expressions.

use super::kinematics::{self, Kinematics};
use super::vector;
use crate::ir;
use crate::sym::{ExprId, ExprPool, Number};

/// The six offsets `s(q)` of a bushing's frame B from its frame A ([`ir::Load::Bushing`]), in
/// A's basis: `d = C_Aᵀ (o_B − o_A)`, then `θ = vee(R − Rᵀ)/2` of `R = C_Aᵀ C_B`
/// (`R_ij = (column i of C_A)·(column j of C_B)`).
fn bushing_offsets(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    frames: [ir::Handle<ir::Frame>; 2],
) -> [ExprId; 6] {
    let (dcm_a, origin_a) = kinematics.to_newtonian(pool, frames[0]);
    let (dcm_b, origin_b) = kinematics.to_newtonian(pool, frames[1]);
    let apart = vector::sub(pool, origin_b, origin_a);
    let [dx, dy, dz] = vector::mat_t_vec(pool, &dcm_a, apart);
    let column = |c: &vector::Mat3, i: usize| [c[0][i], c[1][i], c[2][i]];
    let mut r = |i: usize, j: usize| vector::dot(pool, column(&dcm_a, i), column(&dcm_b, j));
    let pairs = [((2, 1), (1, 2)), ((0, 2), (2, 0)), ((1, 0), (0, 1))];
    let [tx, ty, tz] = pairs.map(|((i, j), (k, l))| (r(i, j), r(k, l)));
    let half = |pool: &mut ExprPool, (a, b): (ExprId, ExprId)| {
        let difference = pool.sub(a, b);
        pool.scale(difference, Number::rational(1, 2))
    };
    let (tx, ty, tz) = (half(pool, tx), half(pool, ty), half(pool, tz));
    [dx, dy, dz, tx, ty, tz]
}

/// A bushing's six springs: each offset `s` ([`bushing_offsets`]) with its stiffness `k` and
/// damping `c`. The laws are lowered before the offsets: the order fixes the pool's
/// numbering, and with it the generated code.
pub(super) fn bushing_springs(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    frames: [ir::Handle<ir::Frame>; 2],
    stiffness: &[ir::Vec3; 2],
    damping: &[ir::Vec3; 2],
) -> [(ExprId, ExprId, ExprId); 6] {
    let six = |pool: &mut ExprPool, v: &[ir::Vec3; 2]| {
        let [a, b, c] = kinematics::lower_vec(pool, &v[0]);
        let [d, e, f] = kinematics::lower_vec(pool, &v[1]);
        [a, b, c, d, e, f]
    };
    let (k, c) = (six(pool, stiffness), six(pool, damping));
    let s = bushing_offsets(pool, kinematics, frames);
    std::array::from_fn(|i| (s[i], k[i], c[i]))
}
