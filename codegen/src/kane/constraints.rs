//! Loop-closure constraints: `φ(q) = 0`, its Jacobian `J` with `φ̇ = J u` (`J = ∂φ/∂q` where
//! `q̇ = u`; `∂φ/∂q W(q)` with quaternions, `KinematicRates` in `rates.rs`) and the
//! acceleration bias `J̇u`, so that `J u = 0` and `J u̇ + J̇u = 0` along any motion.
//!
//! Consumes: `model.loops`, `model.velocity_constraints` and the tree kinematics (a closure's
//! sides and axes from `closure.rs`). Produces: [`Constraints`] (root ids in the pool).
//!
//! Rows per closure, measured in the closure's frame A (the nearest common ancestor of its
//! two points' frames, N where their chains meet only there; positions from A's origin):
//! - coincident: the listed components of `r_C − r_P` in the basis of the named frame;
//! - revolute: `r_C − r_P` in A (3 rows), then `a_P·e₁_C` and `a_P·e₂_C`, where `a_P` is
//!   the axis in the parent interframe and `e₁, e₂ ⊥ a` are fixed in the child interframe
//!   (zero exactly when the two axes are parallel); a compliant closure (with a twist axis
//!   `t`) keeps only the 3 position rows: its twist about `t` and its lateral bending about
//!   `n = a × t` are flexure angles held by springs;
//! - distance: `(|r_C − r_P|² − length²) / (2 length)`, zero where `|r_C − r_P| = length`.
//!
//! `J` and `J̇u = Σᵢ ∂(J u)/∂qᵢ q̇ᵢ` are exact symbolic derivatives of `φ` (`J̇u` as the second
//! rate of `φ` along `q̇`, two forward passes, [`ExprPool::derivative_along`]).
//!
//! Velocity (nonholonomic) constraints `A(q) u = 0` (`model.velocity_constraints`) follow
//! the loop rows: their `J` rows are `A` (the coefficients of the speeds, exact: a point
//! velocity is `Σ_r ∂v/∂u_r u_r` from the partial velocities, a scalar row is differentiated
//! by each speed), their bias is `Ȧu = Σᵢ ∂(A u)/∂qᵢ q̇ᵢ`, and their `φ` is 0 (there is no
//! position form; [`Constraints::velocity_rows`] counts them so the run time leaves them out
//! of every position-level step). The run time appends them to the multiplier equations
//! `M u̇ = F + Jᵀλ`, `J u̇ = −J̇u`: for ideal constraints that is Kane's nonholonomic form
//! (the multipliers' forces `Aᵀλ` do no work on any motion with `A u = 0`).

use super::closure::{revolute_geometry, sides};
use super::kinematics::{self, lower_vec, Kinematics};
use super::points::point_position;
use super::rates::KinematicRates;
use super::state::lower_state_expr;
use super::vector::{self, constant_vector, number_vector, perpendiculars, Vec3};
use crate::ir::{self, ClosureKind, Model};
use crate::sym::{ExprId, ExprPool, Number, Symbol};

/// The constraint rows of a model.
#[derive(Clone, Debug, Default)]
pub struct Constraints {
    /// `φ(q)`, one entry per row.
    pub residual: Vec<ExprId>,
    /// `J(q)` with `φ̇ = J u`, `rows × nu`, column-major (`∂φ/∂q` where `q̇ = u`).
    pub jacobian: Vec<ExprId>,
    /// `J̇(q, u) u`.
    pub bias: Vec<ExprId>,
    /// `<loop>.x`, `<loop>.align1`, `<loop>.distance`, ..., then `<constraint>.x` or
    /// `<constraint>` of the velocity rows.
    pub names: Vec<String>,
    /// The last `velocity_rows` rows are velocity constraints (`φ` is 0 there).
    pub velocity_rows: usize,
}

/// Derives every constraint row of the model.
pub fn derive(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    rates: &KinematicRates,
    model: &Model,
) -> Constraints {
    let mut residual = Vec::new();
    let mut names = Vec::new();
    for closure in &model.loops {
        let no_rotation: &[ir::AxisAngle] = &[];
        let (parent_rotation, child_rotation) = match &closure.kind {
            ClosureKind::Revolute {
                parent_orientation,
                child_orientation,
                ..
            } => (&parent_orientation[..], &child_orientation[..]),
            _ => (no_rotation, no_rotation),
        };
        let (ancestor, parent, child) = sides(
            pool,
            kinematics,
            model,
            closure,
            parent_rotation,
            child_rotation,
        );
        let gap = vector::sub(pool, child.position, parent.position);
        match &closure.kind {
            ClosureKind::Coincident { frame, components } => {
                let local = kinematics.express(pool, gap, ancestor, *frame);
                for &c in components {
                    residual.push(local[c]);
                    names.push(format!("{}.{}", closure.name, ["x", "y", "z"][c]));
                }
            }
            ClosureKind::Revolute {
                axis, twist_axis, ..
            } => {
                for (c, &component) in gap.iter().enumerate() {
                    residual.push(component);
                    names.push(format!("{}.{}", closure.name, ["x", "y", "z"][c]));
                }
                let geometry =
                    revolute_geometry(pool, ancestor, &parent, &child, axis, twist_axis.as_deref());
                // A compliant closure's axes are held by springs (its twist and lateral
                // flexure angles), not by rows.
                if geometry.twist.is_none() {
                    residual.push(vector::dot(pool, geometry.axis, geometry.reference_child));
                    residual.push(vector::dot(
                        pool,
                        geometry.axis,
                        geometry.perpendicular_child,
                    ));
                    names.push(format!("{}.align1", closure.name));
                    names.push(format!("{}.align2", closure.name));
                }
            }
            ClosureKind::Distance { length } => {
                // (|r|² − L²) / 2L rather than |r| − L: the same zeros for L > 0 (the front end
                // rejects other lengths) and the same gradient r̂ᵀ∂r/∂q where satisfied (so λ
                // is still the force along the line), but polynomial in r: finite where the
                // points coincide, where |r| has no gradient.
                let length = kinematics::lower_expr(pool, length);
                let square = vector::dot(pool, gap, gap);
                let length_squared = pool.pow(length, Number::int(2));
                let excess = pool.sub(square, length_squared);
                residual.push(pool.product(
                    Number::rational(1, 2),
                    &[(excess, Number::ONE), (length, Number::MINUS_ONE)],
                ));
                names.push(format!("{}.distance", closure.name));
            }
        }
    }

    for constraint in &model.velocity_constraints {
        if let ir::VelocityKind::Rolling { .. } = &constraint.kind {
            let wheel = Wheel::new(pool, kinematics, model, &constraint.kind);
            residual.push(wheel.height);
            names.push(format!("{}.height", constraint.name));
        }
    }
    let (nq, nu) = (model.nq(), model.nu());
    let rows = residual.len();
    let zero = pool.zero();
    let mut jacobian = vec![zero; rows * nu];
    for (r, &phi) in residual.iter().enumerate() {
        for (j, entry) in rates.partial_rates(pool, phi).into_iter().enumerate() {
            jacobian[r + rows * j] = entry;
        }
    }
    // `J̇u` as the second rate of `φ` along `q̇` (`φ̇ = J u` is the first): two forward
    // passes over `φ`, a fraction of the size of one over `J u`'s `nu` columns.
    let bias = residual
        .iter()
        .map(|&phi| {
            let velocity = rates.rate_at_fixed_speeds(pool, phi, nq);
            rates.rate_at_fixed_speeds(pool, velocity, nq)
        })
        .collect();
    let mut constraints = Constraints {
        residual,
        jacobian,
        bias,
        names,
        velocity_rows: 0,
    };
    if !model.velocity_constraints.is_empty() {
        append_velocity_rows(pool, kinematics, rates, model, &mut constraints);
    }
    constraints
}

/// A rolling wheel's contact ([`ir::VelocityKind::Rolling`]), in N: with `a` the axle and
/// `n` the plane's normal (unit vectors), `d = n − (n·a) a` points from the contact to the
/// centre P within the wheel's plane, `|d| = √(1 − (n·a)²)`, the contact point is
/// `K = P − ρ d/|d|` and its height above the plane through Q is
/// `n·(K − Q) = n·(P − Q) − ρ |d|` (a loop row). Undefined where the wheel lies flat
/// (`a ∥ n`).
struct Wheel {
    height: ExprId,
    contact: Vec3,
    frame: ir::Handle<ir::Frame>,
    normal: [f64; 3],
}

impl Wheel {
    fn new(
        pool: &mut ExprPool,
        kinematics: &mut Kinematics,
        model: &Model,
        kind: &ir::VelocityKind,
    ) -> Wheel {
        let ir::VelocityKind::Rolling {
            centre,
            axle,
            radius,
            plane,
            normal,
        } = kind
        else {
            unreachable!("Wheel::new of a rolling constraint only")
        };
        let centre_point = &model.points[*centre];
        let frame = centre_point.frame;
        let centre = point_position(pool, kinematics, centre_point);
        let plane = point_position(pool, kinematics, &model.points[*plane]);
        let (dcm, _) = kinematics.to_newtonian(pool, frame);
        let axle = lower_vec(pool, axle);
        let axle = vector::mat_vec(pool, &dcm, axle);
        let normal = lower_vec(pool, normal);
        let normal_numbers = constant_vector(pool, normal);
        let n = number_vector(pool, normal_numbers);
        let along = vector::dot(pool, n, axle);
        let tilt = vector::scale(pool, axle, along);
        let d = vector::sub(pool, n, tilt);
        let square = vector::dot(pool, d, d);
        let length = pool.sqrt(square);
        let radius = kinematics::lower_expr(pool, radius);
        let inverse = pool.pow(length, Number::MINUS_ONE);
        let reach = pool.mul(radius, inverse);
        let down = vector::scale(pool, d, reach);
        let contact = vector::sub(pool, centre, down);
        let apart = vector::sub(pool, centre, plane);
        let above = vector::dot(pool, n, apart);
        let lowest = pool.mul(radius, length);
        Wheel {
            height: pool.sub(above, lowest),
            contact,
            frame,
            normal: normal_numbers,
        }
    }
}

/// `∂v/∂u_r` (in `body`'s basis) of `body`'s material point at `position` (in N): the offset
/// `d = C_Bᵀ (r − r_B)` held fixed in B, `V_r + W_r × d` (Kane & Levinson §2.7 and §2.14).
fn material_partials(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    body: ir::Handle<ir::Frame>,
    position: Vec3,
) -> kinematics::Partials {
    let (dcm, origin) = kinematics.to_newtonian(pool, body);
    let apart = vector::sub(pool, position, origin);
    let offset = vector::mat_t_vec(pool, &dcm, apart);
    kinematics.point_partials(pool, body, offset)
}

/// The rows of `A(q)` (`nu` coefficients each) of one velocity constraint, with their names.
fn velocity_rows(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    constraint: &ir::VelocityConstraint,
) -> Vec<(String, Vec<ExprId>)> {
    let nu = model.nu();
    match &constraint.kind {
        ir::VelocityKind::PointVelocity {
            point,
            body,
            frame,
            components,
        } => {
            let position = point_position(pool, kinematics, &model.points[*point]);
            let zero = pool.zero();
            let mut coefficients = vec![vec![zero; nu]; 3];
            for (r, v) in material_partials(pool, kinematics, *body, position) {
                let v = kinematics.express(pool, v, *body, *frame);
                for (c, row) in coefficients.iter_mut().enumerate() {
                    row[r] = v[c];
                }
            }
            components
                .iter()
                .map(|&c| {
                    let name = format!("{}.{}", constraint.name, ["x", "y", "z"][c]);
                    (name, coefficients[c].clone())
                })
                .collect()
        }
        kind @ ir::VelocityKind::Rolling { .. } => {
            // No slip along the plane: the wheel's material point at the contact has no
            // velocity along t₁, t₂ ⊥ n (its normal velocity is the height row's rate).
            let wheel = Wheel::new(pool, kinematics, model, kind);
            let (t1, t2) = perpendiculars(wheel.normal);
            let zero = pool.zero();
            let mut coefficients = vec![vec![zero; nu]; 2];
            for (r, v) in material_partials(pool, kinematics, wheel.frame, wheel.contact) {
                let v = kinematics.express(pool, v, wheel.frame, Model::NEWTONIAN);
                for (row, t) in coefficients.iter_mut().zip([t1, t2]) {
                    let t = number_vector(pool, t);
                    row[r] = vector::dot(pool, v, t);
                }
            }
            let name = |suffix: &str| format!("{}.{suffix}", constraint.name);
            let [first, second] = [coefficients[0].clone(), coefficients[1].clone()];
            vec![(name("slip1"), first), (name("slip2"), second)]
        }
        ir::VelocityKind::Scalar(expr) => {
            let row = lower_state_expr(pool, kinematics, model, expr);
            let coefficients = (0..nu)
                .map(|r| pool.diff(row, Symbol::Speed(r as u32)))
                .collect();
            vec![(constraint.name.clone(), coefficients)]
        }
    }
}

/// Appends the velocity constraints' rows: `φ = 0`, `J` rows `A`, bias `Ȧu`.
fn append_velocity_rows(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    rates: &KinematicRates,
    model: &Model,
    constraints: &mut Constraints,
) {
    let (nq, nu) = (model.nq(), model.nu());
    let mut rows = Vec::new();
    for constraint in &model.velocity_constraints {
        rows.extend(velocity_rows(pool, kinematics, model, constraint));
    }
    let (holonomic, added) = (constraints.residual.len(), rows.len());
    let total = holonomic + added;
    let zero = pool.zero();
    let mut jacobian = vec![zero; total * nu];
    for j in 0..nu {
        for r in 0..holonomic {
            jacobian[r + total * j] = constraints.jacobian[r + holonomic * j];
        }
        for (k, (_, coefficients)) in rows.iter().enumerate() {
            jacobian[holonomic + k + total * j] = coefficients[j];
        }
    }
    for (name, coefficients) in rows {
        // Ȧu = Σᵢ ∂(A u)/∂qᵢ q̇ᵢ, u̇ held.
        let terms: Vec<ExprId> = coefficients
            .iter()
            .enumerate()
            .map(|(j, &a)| {
                let u = pool.symbol(Symbol::Speed(j as u32));
                pool.mul(a, u)
            })
            .collect();
        let velocity = pool.add_all(&terms);
        constraints
            .bias
            .push(rates.rate_at_fixed_speeds(pool, velocity, nq));
        constraints.residual.push(zero);
        constraints.names.push(name);
    }
    constraints.jacobian = jacobian;
    constraints.velocity_rows = added;
}
