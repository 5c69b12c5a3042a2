//! A loop closure's geometry in its frame A (the nearest common ancestor of its points'
//! frames): its parent and child sides, a revolute closure's axis and reference directions,
//! its relative angle `θ` and rate, a compliant closure's twist and lateral angles, and the
//! generalized forces of a torque about its axis; and with them the angle `θ(q)` of any
//! flexure.
//!
//! Consumes: the tree kinematics and `model.loops`. Produces: pool expressions, shared by
//! the constraint rows (`constraints.rs`), the closure springs and dampers of the forcing and
//! the potential energy.

use super::kinematics::{lower_vec, orientation, Kinematics};
use super::vector::{self, constant_vector, number_vector, perpendiculars, Mat3, Vec3};
use crate::ir::{self, ClosureKind, Model};
use crate::sym::{ExprId, ExprPool, Number, Symbol};

/// Orientation (`C_{A←F}`) of a loop's interframe and position of its point, in the basis
/// of the closure's frame A ([`closure_frame`]).
pub(super) struct Side {
    dcm: Mat3,
    pub(super) position: Vec3,
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
pub(super) fn sides(
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

pub(super) fn revolute_geometry(
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
fn off_axis_angle(pool: &mut ExprPool, geometry: &RevoluteGeometry, lateral: bool) -> ExprId {
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

/// `θ(q)` of a flexure angle.
pub(super) fn flexure_angle(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    angle: ir::FlexureAngle,
) -> ExprId {
    use ir::FlexureAngle::{Coordinate, Loop, LoopLateral, LoopTwist};
    let closure = match angle {
        Coordinate(c) => return pool.symbol(Symbol::Coordinate(c.index() as u32)),
        Loop(closure) | LoopTwist(closure) | LoopLateral(closure) => closure,
    };
    let Some(geometry) = closure_geometry(pool, kinematics, model, closure) else {
        return pool.zero();
    };
    match angle {
        LoopTwist(_) => off_axis_angle(pool, &geometry, false),
        LoopLateral(_) => off_axis_angle(pool, &geometry, true),
        _ => relative_angle(pool, &geometry),
    }
}
