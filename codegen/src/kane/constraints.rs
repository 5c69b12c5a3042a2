//! Loop-closure constraints: `φ(q) = 0`, its Jacobian `J` with `φ̇ = J u` (`J = ∂φ/∂q` where
//! `q̇ = u`; `∂φ/∂q W(q)` with quaternions, [`KinematicRates`]) and the acceleration bias
//! `J̇u`, so that `J u = 0` and `J u̇ + J̇u = 0` along any motion.
//!
//! Consumes: `model.loops` and the tree kinematics. Produces: [`Constraints`] (root ids in
//! the pool) and the generalized forces of closure springs and dampers.
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

use super::kinematics::{self, lower_vec, orientation, Kinematics};
use super::rates::KinematicRates;
use super::vector::{self, Mat3, Vec3};
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

/// Orientation (`C_{A←F}`) of a loop's interframe and position of its point, in the basis
/// of the closure's frame A ([`closure_frame`]).
struct Side {
    dcm: Mat3,
    position: Vec3,
}

/// The frame A a closure is measured in: the nearest common ancestor of its two points'
/// frames. The same zeros as in N (`φ_A = C_{N←A}ᵀ φ_N` for the vector rows, the alignment
/// rows are dot products), but the revolute and distance rows are then functions of the
/// coordinates below A only: on a floating robot whose loops close within a leg, the base's
/// pose is absent from their `φ`, `J` and `J̇u` symbolically, not just in exact arithmetic.
/// (A coincident row named in a frame outside A's subtree goes back through that frame.)
fn closure_frame(
    kinematics: &Kinematics,
    model: &Model,
    closure: &ir::LoopClosure,
) -> ir::Handle<ir::Frame> {
    let frame = |point: ir::Handle<ir::Point>| model.points[point].frame;
    kinematics.common_ancestor(frame(closure.parent), frame(closure.child))
}

/// The closure's frame A and its parent and child sides measured there.
fn sides(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    closure: &ir::LoopClosure,
    parent_rotation: &[ir::AxisAngle],
    child_rotation: &[ir::AxisAngle],
) -> (ir::Handle<ir::Frame>, Side, Side) {
    let frame = closure_frame(kinematics, model, closure);
    let parent = side(
        pool,
        kinematics,
        model,
        closure.parent,
        parent_rotation,
        frame,
    );
    let child = side(
        pool,
        kinematics,
        model,
        closure.child,
        child_rotation,
        frame,
    );
    (frame, parent, child)
}

fn side(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    point: ir::Handle<ir::Point>,
    rotation: &[ir::AxisAngle],
    ancestor: ir::Handle<ir::Frame>,
) -> Side {
    let point = &model.points[point];
    let (frame_dcm, origin) = kinematics.relative_to(pool, point.frame, ancestor);
    let offset = lower_vec(pool, &point.position);
    let offset = vector::mat_vec(pool, &frame_dcm, offset);
    let position = vector::add(pool, origin, offset);
    let interframe = orientation(pool, rotation);
    let dcm = vector::mat_mul(pool, &frame_dcm, &interframe);
    Side { dcm, position }
}

/// Two unit vectors perpendicular to the unit `axis` and to each other (`e₂ = a × e₁`),
/// built from the coordinate axis least aligned with `a`.
pub fn perpendiculars(axis: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let least = (0..3)
        .min_by(|&i, &j| axis[i].abs().total_cmp(&axis[j].abs()))
        .unwrap_or(0);
    let mut helper = [0.0; 3];
    helper[least] = 1.0;
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let e1 = cross(axis, helper);
    let norm = (e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]).sqrt();
    let e1 = [e1[0] / norm, e1[1] / norm, e1[2] / norm];
    (e1, cross(axis, e1))
}

/// Numeric values of a constant vector (loop axes are constants after lowering).
fn constant_vector(pool: &ExprPool, v: Vec3) -> [f64; 3] {
    let value = |id| pool.as_number(id).map_or(f64::NAN, Number::to_f64);
    [value(v[0]), value(v[1]), value(v[2])]
}

fn number_vector(pool: &mut ExprPool, v: [f64; 3]) -> Vec3 {
    let number = |pool: &mut ExprPool, x: f64| if x == 0.0 { pool.zero() } else { pool.float(x) };
    [number(pool, v[0]), number(pool, v[1]), number(pool, v[2])]
}

/// The revolute closure's axis (from the parent side) and the reference directions `e₁`
/// fixed in each interframe, in the basis of `frame`.
pub(super) struct RevoluteGeometry {
    /// The closure's frame A ([`closure_frame`]), the basis of every vector here.
    pub frame: ir::Handle<ir::Frame>,
    pub axis: Vec3,
    pub reference_parent: Vec3,
    pub reference_child: Vec3,
    pub perpendicular_child: Vec3,
    /// For a closure compliant in twist: the directions fixed in the child interframe.
    pub twist: Option<TwistGeometry>,
}

/// A compliant closure's twist axis `t` and its normal `n = a × t`, fixed in the child
/// interframe (in A), and the hinge axis `a_C` seen from the child.
pub(super) struct TwistGeometry {
    pub axis_child: Vec3,
    pub twist_child: Vec3,
    pub normal_child: Vec3,
}

fn revolute_geometry(
    pool: &mut ExprPool,
    frame: ir::Handle<ir::Frame>,
    parent: &Side,
    child: &Side,
    axis: &ir::Vec3,
    twist_axis: Option<&ir::Vec3>,
) -> RevoluteGeometry {
    let axis_local = lower_vec(pool, axis);
    let axis_numbers = constant_vector(pool, axis_local);
    let (e1, e2) = perpendiculars(axis_numbers);
    let (e1, e2) = (number_vector(pool, e1), number_vector(pool, e2));
    let twist = twist_axis.map(|twist_axis| {
        let twist_local = lower_vec(pool, twist_axis);
        let (t, n) = twist_directions(axis_numbers, constant_vector(pool, twist_local));
        let (t, n) = (number_vector(pool, t), number_vector(pool, n));
        TwistGeometry {
            axis_child: vector::mat_vec(pool, &child.dcm, axis_local),
            twist_child: vector::mat_vec(pool, &child.dcm, t),
            normal_child: vector::mat_vec(pool, &child.dcm, n),
        }
    });
    RevoluteGeometry {
        frame,
        axis: vector::mat_vec(pool, &parent.dcm, axis_local),
        reference_parent: vector::mat_vec(pool, &parent.dcm, e1),
        reference_child: vector::mat_vec(pool, &child.dcm, e1),
        perpendicular_child: vector::mat_vec(pool, &child.dcm, e2),
        twist,
    }
}

/// The unit twist axis `t` (the given direction with its component along the unit hinge
/// axis `a` removed) and `n = a × t`. The front end rejects twist axes parallel to `a`.
fn twist_directions(axis: [f64; 3], twist: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let along = axis[0] * twist[0] + axis[1] * twist[1] + axis[2] * twist[2];
    let t = [0, 1, 2].map(|i| twist[i] - along * axis[i]);
    let norm = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
    let t = t.map(|c| c / norm);
    let n = [
        axis[1] * t[2] - axis[2] * t[1],
        axis[2] * t[0] - axis[0] * t[2],
        axis[0] * t[1] - axis[1] * t[0],
    ];
    (t, n)
}

/// The geometry of closure `index` (revolute closures only).
pub(super) fn closure_geometry(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    index: usize,
) -> Option<RevoluteGeometry> {
    let closure = &model.loops[index];
    let ClosureKind::Revolute {
        axis,
        parent_orientation,
        child_orientation,
        twist_axis,
        ..
    } = &closure.kind
    else {
        return None;
    };
    let (frame, parent, child) = sides(
        pool,
        kinematics,
        model,
        closure,
        parent_orientation,
        child_orientation,
    );
    Some(revolute_geometry(
        pool,
        frame,
        &parent,
        &child,
        axis,
        twist_axis.as_deref(),
    ))
}

/// Relative rotation of a revolute closure about its axis:
/// `θ = atan2((e₁_P × e₁_C)·a, e₁_P·e₁_C)`.
pub(super) fn relative_angle(pool: &mut ExprPool, geometry: &RevoluteGeometry) -> ExprId {
    let cross = vector::cross(pool, geometry.reference_parent, geometry.reference_child);
    let sine = vector::dot(pool, cross, geometry.axis);
    let cosine = vector::dot(pool, geometry.reference_parent, geometry.reference_child);
    pool.atan2(sine, cosine)
}

/// The two ways a compliant closure's child axis leaves the parent's: twist about `t` and
/// lateral bending about `n = a × t`. Exact for a pure rotation: twist by β turns `n` towards
/// `a` (`n_C = n cos β + a sin β`), lateral bending by γ turns `t` away from it
/// (`t_C = t cos γ − a sin γ`), so `β = atan2(a_P·n_C, a_P·a_C)` and
/// `γ = atan2(−a_P·t_C, a_P·a_C)`. Zero for a rigid closure.
pub(super) fn off_axis_angle(
    pool: &mut ExprPool,
    geometry: &RevoluteGeometry,
    lateral: bool,
) -> ExprId {
    let Some(twist) = &geometry.twist else {
        return pool.zero();
    };
    let sine = if lateral {
        let along = vector::dot(pool, geometry.axis, twist.twist_child);
        pool.neg(along)
    } else {
        vector::dot(pool, geometry.axis, twist.normal_child)
    };
    let cosine = vector::dot(pool, geometry.axis, twist.axis_child);
    pool.atan2(sine, cosine)
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
        let centre = super::point_position(pool, kinematics, centre_point);
        let plane = super::point_position(pool, kinematics, &model.points[*plane]);
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
            let position = super::point_position(pool, kinematics, &model.points[*point]);
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
            let row = super::lower_state_expr(pool, kinematics, model, expr);
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

/// `−k(θ − rest)` or `−c ω_rel` about a revolute closure's axis, as generalized forces:
/// the torque `T·a` on the child and `−T·a` on the parent give `Q_r = T a·(W_C,r − W_P,r)`.
pub(super) fn closure_torque_forces(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    closure: usize,
    torque: impl FnOnce(&mut ExprPool, &mut Kinematics, &RevoluteGeometry) -> ExprId,
    forcing: &mut [Vec<ExprId>],
) {
    let Some(geometry) = closure_geometry(pool, kinematics, model, closure) else {
        return;
    };
    let magnitude = torque(pool, kinematics, &geometry);
    let torque_vector = vector::scale(pool, geometry.axis, magnitude);
    let loop_closure = &model.loops[closure];
    let sides = [
        (loop_closure.child, Number::ONE),
        (loop_closure.parent, Number::MINUS_ONE),
    ];
    for (point, sign) in sides {
        let frame = model.points[point].frame;
        let local = kinematics.express(pool, torque_vector, geometry.frame, frame);
        for (r, w) in kinematics.frames[frame.index()].partial_omega.clone() {
            let power = vector::dot(pool, local, w);
            forcing[r].push(pool.scale(power, sign));
        }
    }
}

/// `(ω_C − ω_P)·a` of a revolute closure, in the closure's frame.
pub(super) fn relative_rate(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    closure: usize,
    geometry: &RevoluteGeometry,
) -> ExprId {
    let loop_closure = &model.loops[closure];
    let mut rate = pool.zero();
    for (point, sign) in [
        (loop_closure.child, Number::ONE),
        (loop_closure.parent, Number::MINUS_ONE),
    ] {
        let frame = model.points[point].frame;
        let omega = kinematics.frames[frame.index()].omega;
        let omega = kinematics.express(pool, omega, frame, geometry.frame);
        let along = vector::dot(pool, omega, geometry.axis);
        let signed = pool.scale(along, sign);
        rate = pool.add(rate, signed);
    }
    rate
}
