//! Expressions of the state: a load's or output's [`ir::StateTerm`]s (coordinates, speeds,
//! point distances and their rates, the energies) lowered to pool expressions, and the
//! kinetic and potential energies themselves.
//!
//! Consumes: the tree kinematics and the model. Produces: pool expressions. The potential
//! energy sums every spring the forcing has, so it reads the closures' angles
//! (`closure.rs`), the contacts (`contact.rs`) and the bushings (`bushing.rs`).

use super::bushing::bushing_springs;
use super::closure::{self, flexure_angle};
use super::contact;
use super::kinematics::{self, inertia_matrix, lower_expr, lower_expr_with, Kinematics};
use super::points::{combine_partials, spring_length, SpringLine};
use super::vector::{self, Vec3};
use crate::ir::{self, Load, Model};
use crate::sym::{ExprId, ExprPool, Number, Symbol};

/// Lowers an expression of a load or output: its [`ir::StateTerm`]s become the coordinate
/// and speed symbols, a distance `L = |r_B − r_A|`, its rate `L̇ = ê·(v_B − v_A)`, or the
/// energies, from the kinematics.
pub fn lower_state_expr(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    expr: &ir::Expr,
) -> ExprId {
    lower_expr_with(pool, expr, &mut |pool, term| match term {
        ir::StateTerm::Coordinate(c) => pool.symbol(Symbol::Coordinate(c.index() as u32)),
        ir::StateTerm::Speed(c) => pool.symbol(Symbol::Speed(c.index() as u32)),
        ir::StateTerm::Distance(ends) => spring_length(pool, kinematics, model, ends).1,
        ir::StateTerm::DistanceRate(ends) => {
            SpringLine::new(pool, kinematics, model, ends).stretch_speed(pool)
        }
        ir::StateTerm::KineticEnergy => kinetic_energy(pool, kinematics, model),
        ir::StateTerm::PotentialEnergy => potential_energy(pool, kinematics, model),
    })
}

/// [`lower_state_expr`] of each component.
pub(super) fn lower_state_vec(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    v: &ir::Vec3,
) -> Vec3 {
    [
        lower_state_expr(pool, kinematics, model, &v[0]),
        lower_state_expr(pool, kinematics, model, &v[1]),
        lower_state_expr(pool, kinematics, model, &v[2]),
    ]
}

/// `½ Σ_bodies (m v_G·v_G + ω·I ω)`.
pub(super) fn kinetic_energy(
    pool: &mut ExprPool,
    kinematics: &Kinematics,
    model: &Model,
) -> ExprId {
    let mut terms = Vec::new();
    for (_, body) in model.bodies.iter() {
        let mass = lower_expr(pool, &body.mass);
        let com = kinematics::lower_vec(pool, &body.center_of_mass);
        let partials = kinematics.point_partials(pool, body.frame, com);
        let v = combine_partials(pool, &partials);
        let omega = kinematics.frames[body.frame.index()].omega;
        let inertia = inertia_matrix(pool, &body.inertia);
        let i_omega = vector::mat_vec(pool, &inertia, omega);
        let v2 = vector::dot(pool, v, v);
        terms.push(pool.mul(mass, v2));
        terms.push(vector::dot(pool, omega, i_omega));
    }
    let twice = pool.add_all(&terms);
    pool.scale(twice, Number::rational(1, 2))
}

/// `−Σ_bodies m g·r_G + Σ_springs ½ k (x − rest)²`, x a joint coordinate, a closure or
/// flexure angle, or a point-to-point spring's length, plus each contact's
/// `k δ^(e+1)/(e+1)` and each bushing's `½ Σ k s²`.
pub(super) fn potential_energy(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
) -> ExprId {
    let mut terms = Vec::new();
    let gravity = kinematics.frames[ir::Model::NEWTONIAN.index()].gravity;
    for (_, body) in model.bodies.iter() {
        let mass = lower_expr(pool, &body.mass);
        let (dcm, origin) = kinematics.to_newtonian(pool, body.frame);
        let com = kinematics::lower_vec(pool, &body.center_of_mass);
        let com = vector::mat_vec(pool, &dcm, com);
        let position = vector::add(pool, origin, com);
        let height_work = vector::dot(pool, gravity, position);
        let work = pool.mul(mass, height_work);
        terms.push(pool.neg(work));
    }
    for load in &model.loads {
        // ½ k (x − rest)² for joint springs (x = q), closure and angle springs (x = θ),
        // point-to-point springs (x = L).
        let (stiffness, rest, stretched) = match load {
            Load::Spring {
                coordinate,
                stiffness,
                rest,
                ..
            } => (
                stiffness,
                rest,
                pool.symbol(Symbol::Coordinate(coordinate.index() as u32)),
            ),
            Load::LoopSpring {
                closure,
                stiffness,
                rest,
                ..
            } => {
                let Some(geometry) = closure::closure_geometry(pool, kinematics, model, *closure)
                else {
                    continue;
                };
                (stiffness, rest, closure::relative_angle(pool, &geometry))
            }
            Load::AngleSpring {
                angle,
                stiffness,
                rest,
                ..
            } => (
                stiffness,
                rest,
                flexure_angle(pool, kinematics, model, *angle),
            ),
            Load::PointSpring {
                ends,
                stiffness,
                rest_length,
                ..
            } => (
                stiffness,
                rest_length,
                spring_length(pool, kinematics, model, *ends).1,
            ),
            Load::Contact { .. } => {
                if let Some(contact) = contact::ContactState::new(pool, kinematics, model, load) {
                    terms.push(contact.energy);
                }
                continue;
            }
            Load::Bushing {
                frames,
                stiffness,
                damping,
                ..
            } => {
                // ½ Σ k s².
                for (s, k, _) in bushing_springs(pool, kinematics, *frames, stiffness, damping) {
                    let square = pool.pow(s, Number::int(2));
                    let energy = pool.mul(k, square);
                    terms.push(pool.scale(energy, Number::rational(1, 2)));
                }
                continue;
            }
            _ => continue,
        };
        let k = lower_expr(pool, stiffness);
        let rest = lower_expr(pool, rest);
        let stretch = pool.sub(stretched, rest);
        let square = pool.pow(stretch, Number::int(2));
        let energy = pool.mul(k, square);
        terms.push(pool.scale(energy, Number::rational(1, 2)));
    }
    pool.add_all(&terms)
}
