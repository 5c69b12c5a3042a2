//! Points of the model in N and the lines between them: a point's position, the partial
//! velocities of two points' relative motion, and a point-to-point spring's length `L` and
//! stretch rate `L̇ = ê·(v_B − v_A)`.
//!
//! Consumes: the tree kinematics and the model's points. Produces: pool expressions (N's
//! basis).

use super::kinematics::{self, Kinematics};
use super::vector::{self, Vec3};
use crate::ir::{self, Model};
use crate::sym::{ExprId, ExprPool, Number, Symbol};

/// Position of a point from the Newtonian origin, in N's basis.
pub(super) fn point_position(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    point: &ir::Point,
) -> Vec3 {
    let (dcm, origin) = kinematics.to_newtonian(pool, point.frame);
    let offset = kinematics::lower_vec(pool, &point.position);
    let offset = vector::mat_vec(pool, &dcm, offset);
    vector::add(pool, origin, offset)
}

/// `Σ_r partial_r · u_r`.
pub(super) fn combine_partials(pool: &mut ExprPool, partials: &kinematics::Partials) -> Vec3 {
    let mut total = vector::zero(pool);
    for &(r, v) in partials {
        let u = pool.symbol(Symbol::Speed(r as u32));
        let term = vector::scale(pool, v, u);
        total = vector::add(pool, total, term);
    }
    total
}

/// `∂(v_B − v_A)/∂u_r` of two points A (`end(pool, 0)`) and B (`end(pool, 1)`), each given by
/// the frame it is fixed in and its offset in that frame's basis, in N's basis: the partial
/// velocities of each end (B with `+`, A with `−`, each from [`Kinematics::point_partials`]
/// re-expressed in N). Each end is built when its turn comes (B first), the order the pool
/// numbers them in.
pub(super) fn relative_partials_at(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    mut end: impl FnMut(&mut ExprPool, usize) -> (ir::Handle<ir::Frame>, Vec3),
) -> kinematics::Partials {
    let mut relative: kinematics::Partials = Vec::new();
    for (index, sign) in [(1, Number::ONE), (0, Number::MINUS_ONE)] {
        let (frame, offset) = end(pool, index);
        let partials: kinematics::Partials = kinematics
            .point_partials(pool, frame, offset)
            .into_iter()
            .map(|(r, v)| {
                let v = kinematics.express(pool, v, frame, Model::NEWTONIAN);
                (r, vector::scale_number(pool, v, sign))
            })
            .collect();
        relative = kinematics::merge(pool, &relative, &partials);
    }
    relative
}

/// `∂(v_B − v_A)/∂u_r` of two points `ends = [A, B]`, in N's basis ([`relative_partials_at`]).
pub(super) fn relative_partials(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    ends: [ir::Handle<ir::Point>; 2],
) -> kinematics::Partials {
    relative_partials_at(pool, kinematics, |pool, end| {
        let point = &model.points[ends[end]];
        (point.frame, kinematics::lower_vec(pool, &point.position))
    })
}

/// The line of a point-to-point spring between `ends = [A, B]`, in N's basis.
pub(super) struct SpringLine {
    /// `L = |r_B − r_A|`.
    pub(super) length: ExprId,
    /// `ê·∂(v_B − v_A)/∂u_r = ∂L/∂q_r` for every speed r that moves an end (`ê = d/L`).
    pub(super) stretch_rates: Vec<(usize, ExprId)>,
}

/// `d = r_B − r_A` and `L = |d|` of a spring's ends, in N (positions from [`point_position`]).
pub(super) fn spring_length(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    ends: [ir::Handle<ir::Point>; 2],
) -> (Vec3, ExprId) {
    let [a, b] = ends.map(|end| point_position(pool, kinematics, &model.points[end]));
    let d = vector::sub(pool, b, a);
    let square = vector::dot(pool, d, d);
    (d, pool.sqrt(square))
}

impl SpringLine {
    /// `ê` from the ends' positions, and the ends' relative partial velocities projected on it.
    pub(super) fn new(
        pool: &mut ExprPool,
        kinematics: &mut Kinematics,
        model: &Model,
        ends: [ir::Handle<ir::Point>; 2],
    ) -> SpringLine {
        let (d, length) = spring_length(pool, kinematics, model, ends);
        let inverse = pool.pow(length, Number::MINUS_ONE);
        let direction = vector::scale(pool, d, inverse);
        let relative = relative_partials(pool, kinematics, model, ends);
        let stretch_rates = relative
            .into_iter()
            .map(|(r, v)| (r, vector::dot(pool, direction, v)))
            .collect();
        SpringLine {
            length,
            stretch_rates,
        }
    }

    /// `L̇ = ê·(v_B − v_A) = Σ_r (ê·∂(v_B − v_A)/∂u_r) u_r`.
    pub(super) fn stretch_speed(&self, pool: &mut ExprPool) -> ExprId {
        let terms: Vec<ExprId> = self
            .stretch_rates
            .iter()
            .map(|&(r, rate)| {
                let u = pool.symbol(Symbol::Speed(r as u32));
                pool.mul(rate, u)
            })
            .collect();
        pool.add_all(&terms)
    }
}
