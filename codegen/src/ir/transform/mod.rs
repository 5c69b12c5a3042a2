//! Model transformations: rewrites of a checked [`Model`] that keep the IR invariants.
//!
//! Consumes: a model and a description of the change. Produces: the changed model (in place),
//! with every frame handle remapped so that parents still come first.
//!
//! - [`insert_revolute_above`]: a moving frame in the kinematic tree;
//! - [`add_twist`]: a flexure hinge twists about its length axis (Doshi et al. Eq. 8): a pin
//!   joint gains a revolute frame, a revolute loop closure becomes compliant in twist;
//! - [`hinge`]: physics a model of flexure hinges leaves out — named hinges twisting with
//!   every other hinge compliant off its axis, a hinge's axis misaligned;
//! - [`actuator`]: an actuator's compliant base, a mass on its tip, a preload.
//!
//! The transforms of [`hinge`] and [`actuator`] append their new parameters after the
//! model's own (so those keep their indices), at values where the model is unchanged.

use super::{ClosureKind, Dimension, Flexure, FlexureAngle, Param};
use super::{Coordinate, Expr, Frame, FrameVector, Handle, Load, Model, Motion, OutputKind, Vec3};
use crate::diag::Span;
use crate::sym::Number;

pub mod actuator;
pub mod hinge;
pub mod skeleton;

/// Lateral (in-plane) bending stiffness of a compliant loop closure, per unit bending
/// stiffness `k`. A thin hinge's in-plane stiffness is `(w/t)²·k` (Eq. 2 with width and
/// thickness swapped): ~1600 for w = 1 mm of 25 µm Kapton. A round, stiff value stands in for
/// it when the geometry is not given; it only has to make the closure stiff laterally.
pub const LATERAL_STIFFNESS_FACTOR: i64 = 1000;

/// A spring about one direction of a flexure hinge: its stiffness, time-domain damper and
/// loss factor, recorded as a flexure named `name` (for frequency-domain losses).
#[derive(Clone, Debug, PartialEq)]
pub struct HingeSpring {
    pub name: String,
    pub stiffness: Expr,
    pub damping: Expr,
    pub loss_factor: Expr,
}

/// A flexure hinge's twist about its length axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Twist {
    /// Components in the pin joint's frame, or in the loop's parent interframe (where it
    /// must not be parallel to the hinge axis).
    pub axis: Vec3,
    /// Twist spring, `2k/(1 + ν)` by Eq. 8.
    pub twist: HingeSpring,
    /// The spring on the hinge's lateral (in-plane, stiff) bending about `hinge axis × twist
    /// axis`: a second new coordinate on a pin joint (`None`: the pin stays rigid laterally);
    /// required on a loop closure, whose alignment rows it replaces with the twist spring.
    pub lateral: Option<HingeSpring>,
    pub span: Span,
}

/// Why a twist cannot be added.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TwistError {
    /// The hinge is neither a revolute pin joint nor a revolute loop closure.
    NotAHinge,
    /// A loop's twist axis along its hinge axis (or not a constant direction).
    AlongHingeAxis,
    /// The loop is already compliant.
    AlreadyTwists,
    /// A loop closure needs a lateral spring.
    NoLateralSpring,
}

impl std::fmt::Display for TwistError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            TwistError::NotAHinge => "it is neither a pin joint nor a revolute loop closure",
            TwistError::AlongHingeAxis => "the twist axis lies along the hinge axis",
            TwistError::AlreadyTwists => "it already twists",
            TwistError::NoLateralSpring => "a loop closure needs a lateral spring",
        })
    }
}

/// Why a transform of [`hinge`] or [`actuator`] cannot be applied; the messages name the
/// element and say what it is instead.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TransformError {
    NoFlexure(String),
    NoCoordinate(String),
    /// A slider coordinate without an actuator's spring and force.
    NoActuator(String),
    /// The model has no actuator at all.
    NoActuators,
    NotASlider(String),
    Twist {
        flexure: String,
        /// The axis, as shown (`x`, or `off its axis`).
        about: String,
        error: TwistError,
    },
    AxisNotConstant(String),
    TiltAboutOwnAxis {
        flexure: String,
        about: usize,
    },
    NotOnPin(String),
    NotOnRevoluteLoop(String),
    NotABendingHinge(String),
}

/// The coordinate axes by index, as reports show them.
pub const AXES: [&str; 3] = ["x", "y", "z"];

impl std::fmt::Display for TransformError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TransformError::NoFlexure(name) => write!(f, "no flexure `{name}`"),
            TransformError::NoCoordinate(name) => write!(f, "no coordinate `{name}`"),
            TransformError::NoActuator(slider) => write!(f, "no actuator along `{slider}`"),
            TransformError::NoActuators => f.write_str("no actuator to preload"),
            TransformError::NotASlider(name) => write!(f, "`{name}` is not a slider joint"),
            TransformError::Twist {
                flexure,
                about,
                error,
            } => write!(f, "flexure `{flexure}` cannot twist {about}: {error}"),
            TransformError::AxisNotConstant(name) => {
                write!(f, "flexure `{name}`: its axis is not a constant direction")
            }
            TransformError::TiltAboutOwnAxis { flexure, about } => write!(
                f,
                "flexure `{flexure}`: cannot tilt about {}, its own axis",
                AXES[*about]
            ),
            TransformError::NotOnPin(name) => write!(f, "flexure `{name}` is not on a pin joint"),
            TransformError::NotOnRevoluteLoop(name) => {
                write!(f, "flexure `{name}` is not on a revolute loop")
            }
            TransformError::NotABendingHinge(name) => {
                write!(f, "flexure `{name}` is not a bending hinge")
            }
        }
    }
}

impl std::error::Error for TransformError {}

/// Appends a parameter and returns it as an expression.
pub(crate) fn append_param(
    model: &mut Model,
    name: &str,
    value: f64,
    dimension: Dimension,
    doc: &str,
) -> Expr {
    Expr::Param(model.params.append(Param {
        name: name.into(),
        value,
        dimension,
        docs: vec![doc.into()],
        span: Default::default(),
    }))
}

/// `factor · value`.
pub(crate) fn scaled(factor: &Expr, value: &Expr) -> Expr {
    Expr::Mul(Box::new(factor.clone()), Box::new(value.clone()))
}

/// A spring about one direction of `flexure`: its stiffness and damper times `factor`.
pub(crate) fn spring(flexure: &Flexure, suffix: &str, factor: &Expr) -> HingeSpring {
    HingeSpring {
        name: format!("{}_{suffix}", flexure.name),
        stiffness: scaled(factor, &flexure.stiffness),
        damping: scaled(factor, &flexure.damping),
        loss_factor: flexure.loss_factor.clone(),
    }
}

/// The flexure named `name`.
pub(crate) fn find_flexure(model: &Model, name: &str) -> Result<Flexure, TransformError> {
    model
        .flexures
        .iter()
        .find(|f| f.name == name)
        .cloned()
        .ok_or_else(|| TransformError::NoFlexure(name.to_string()))
}

/// The unit vector along coordinate axis `axis`.
pub(crate) fn unit(axis: usize) -> Vec3 {
    let mut direction = [Expr::zero(), Expr::zero(), Expr::zero()];
    direction[axis] = Expr::one();
    direction
}

/// Gives `hinge` a twist. A pin joint's frame gets a revolute frame above it (a new
/// coordinate with the twist spring and damper). A revolute loop closure becomes compliant:
/// its alignment rows give way to springs on its twist and its lateral bending, so a loop
/// can deform (a single twist axis in a rigid closed loop is locked by the other hinges).
/// Pushes the springs' flexure records and returns the twist's angle.
pub fn add_twist(
    model: &mut Model,
    hinge: FlexureAngle,
    twist: Twist,
) -> Result<FlexureAngle, TwistError> {
    let span = twist.span;
    match hinge {
        FlexureAngle::Coordinate(coordinate) => {
            let (frame, hinge_axis) = pin_frame(model, coordinate).ok_or(TwistError::NotAHinge)?;
            if !perpendicular_enough(&hinge_axis, &twist.axis) {
                return Err(TwistError::AlongHingeAxis);
            }
            let mut springs = vec![(twist.axis.clone(), twist.twist)];
            if let Some(lateral) = twist.lateral {
                let normal = cross(&hinge_axis, &twist.axis).ok_or(TwistError::AlongHingeAxis)?;
                springs.push((normal, lateral));
            }
            let mut angles = Vec::new();
            for (axis, spring) in springs {
                let (_, new) = insert_revolute_above(model, frame, &spring.name, axis, span);
                model.loads.push(Load::Spring {
                    coordinate: new,
                    stiffness: spring.stiffness.clone(),
                    rest: Expr::zero(),
                    span,
                });
                model.loads.push(Load::Damper {
                    coordinate: new,
                    damping: spring.damping.clone(),
                    span,
                });
                let angle = FlexureAngle::Coordinate(new);
                push_flexure(model, angle, spring, span);
                angles.push(angle);
            }
            Ok(angles[0])
        }
        FlexureAngle::Loop(closure) => {
            let Some(ClosureKind::Revolute {
                axis, twist_axis, ..
            }) = model.loops.get_mut(closure).map(|c| &mut c.kind)
            else {
                return Err(TwistError::NotAHinge);
            };
            if twist_axis.is_some() {
                return Err(TwistError::AlreadyTwists);
            }
            if !perpendicular_enough(axis, &twist.axis) {
                return Err(TwistError::AlongHingeAxis);
            }
            let lateral = twist.lateral.ok_or(TwistError::NoLateralSpring)?;
            *twist_axis = Some(Box::new(twist.axis));
            let springs = [
                (FlexureAngle::LoopTwist(closure), twist.twist),
                (FlexureAngle::LoopLateral(closure), lateral),
            ];
            for (angle, spring) in springs {
                model.loads.push(Load::AngleSpring {
                    angle,
                    stiffness: spring.stiffness.clone(),
                    rest: Expr::zero(),
                    span,
                });
                model.loads.push(Load::AngleDamper {
                    angle,
                    damping: spring.damping.clone(),
                    span,
                });
                push_flexure(model, angle, spring, span);
            }
            Ok(FlexureAngle::LoopTwist(closure))
        }
        FlexureAngle::LoopTwist(_) | FlexureAngle::LoopLateral(_) => Err(TwistError::AlreadyTwists),
    }
}

fn push_flexure(model: &mut Model, angle: FlexureAngle, spring: HingeSpring, span: Span) {
    model.flexures.push(Flexure {
        name: spring.name,
        angle,
        stiffness: spring.stiffness,
        loss_factor: spring.loss_factor,
        damping: spring.damping,
        span,
    });
}

/// The frame of the revolute joint moved by `coordinate`, and its axis.
fn pin_frame(model: &Model, coordinate: Handle<Coordinate>) -> Option<(Handle<Frame>, Vec3)> {
    model
        .frames
        .iter()
        .find_map(|(handle, frame)| match &frame.motion {
            Motion::Revolute {
                axis,
                coordinate: c,
            } if *c == coordinate => Some((handle, axis.clone())),
            _ => None,
        })
}

/// The bending axis of a hinge: a revolute pin joint's or a revolute loop's (components in
/// its frame or parent interframe); `None` for anything else.
pub fn hinge_axis(model: &Model, hinge: FlexureAngle) -> Option<Vec3> {
    match hinge {
        FlexureAngle::Coordinate(coordinate) => pin_frame(model, coordinate).map(|(_, axis)| axis),
        FlexureAngle::Loop(index) => match &model.loops.get(index)?.kind {
            ClosureKind::Revolute { axis, .. } => Some(axis.clone()),
            _ => None,
        },
        FlexureAngle::LoopTwist(_) | FlexureAngle::LoopLateral(_) => None,
    }
}

/// A unit direction perpendicular to the constant `axis`: `axis × e`, with `e` the
/// coordinate axis least aligned with it.
pub fn perpendicular(axis: &Vec3) -> Option<Vec3> {
    let numbers = constant_numbers(axis)?;
    let least = (0..3)
        .min_by(|&i, &j| {
            numbers[i]
                .to_f64()
                .abs()
                .total_cmp(&numbers[j].to_f64().abs())
        })
        .unwrap_or(0);
    let mut helper = [Expr::zero(), Expr::zero(), Expr::zero()];
    helper[least] = Expr::one();
    let direction = cross(axis, &helper)?;
    let unit = constant_direction(&direction)?;
    Some(unit.map(|v| Expr::Number(Number::Float(v))))
}

/// The components of a constant direction (axes are numbers after lowering).
fn constant_numbers(v: &Vec3) -> Option<[Number; 3]> {
    let number = |e: &Expr| match e {
        Expr::Number(n) => Some(*n),
        _ => None,
    };
    Some([number(&v[0])?, number(&v[1])?, number(&v[2])?])
}

/// A constant direction's components as numbers, normalized (`None`: not constant, or zero).
pub fn constant_direction(v: &Vec3) -> Option<[f64; 3]> {
    let values = constant_numbers(v)?.map(Number::to_f64);
    let norm = values.iter().map(|x| x * x).sum::<f64>().sqrt();
    (norm > 0.0).then(|| values.map(|x| x / norm))
}

/// `a × b` of two constant directions, exactly.
fn cross(a: &Vec3, b: &Vec3) -> Option<Vec3> {
    let (a, b) = (constant_numbers(a)?, constant_numbers(b)?);
    let component = |i: usize, j: usize| Expr::Number(a[i].mul(b[j]).sub(a[j].mul(b[i])));
    Some([component(1, 2), component(2, 0), component(0, 1)])
}

/// Whether two constant directions are far from parallel (|cos| < 0.99): a twist axis must
/// leave a well-defined normal `a × t`.
fn perpendicular_enough(a: &Vec3, b: &Vec3) -> bool {
    let (Some(a), Some(b)) = (constant_numbers(a), constant_numbers(b)) else {
        return false;
    };
    let (a, b) = (a.map(Number::to_f64), b.map(Number::to_f64));
    let dot: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
    let norm = |v: &[f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    dot.abs() < 0.99 * norm(&a) * norm(&b)
}

/// Inserts a frame rotating about `axis` between `frame` and its parent: the new frame takes
/// `frame`'s placement (origin and orientation in the parent), and `frame` hangs from it with
/// no offset. So everything on `frame` — a joint's child body, its points, its children —
/// rides on the new rotation (a hinge's twist moves the body the hinge carries). `axis` has
/// components in `frame`'s basis at zero rotation. Returns the new frame and its coordinate
/// (appended after the existing ones).
pub fn insert_revolute_above(
    model: &mut Model,
    frame: Handle<Frame>,
    name: &str,
    axis: Vec3,
    span: Span,
) -> (Handle<Frame>, Handle<Coordinate>) {
    let coordinate = model.coordinates.append(Coordinate {
        name: name.to_string(),
        dimension: Dimension::NONE,
        initial: 0.0,
        initial_speed: 0.0,
        span,
    });
    let inserted = frame.index();
    // Old index i → new index: unchanged before `frame`, shifted by one from it on (the new
    // frame takes `frame`'s old index, so parents still come first).
    let remap = |old: Handle<Frame>| {
        if old.index() < inserted {
            old
        } else {
            Handle::new(old.index() + 1)
        }
    };
    let new_frame = Handle::<Frame>::new(inserted);

    let old = std::mem::take(&mut model.frames);
    for (handle, original) in old.iter() {
        let mut copy = original.clone();
        copy.parent = original.parent.map(remap);
        if handle == frame {
            let zero = [Expr::zero(), Expr::zero(), Expr::zero()];
            model.frames.append(Frame {
                name: name.to_string(),
                parent: copy.parent,
                origin: std::mem::replace(&mut copy.origin, zero),
                orientation: std::mem::take(&mut copy.orientation),
                motion: Motion::Revolute {
                    axis: axis.clone(),
                    coordinate,
                },
                span,
            });
            copy.parent = Some(new_frame);
        }
        model.frames.append(copy);
    }
    remap_handles(model, &remap);
    (new_frame, coordinate)
}

/// Applies `remap` to every frame handle held outside the frame arena.
fn remap_handles(model: &mut Model, remap: &dyn Fn(Handle<Frame>) -> Handle<Frame>) {
    let remap_vector = |v: &mut FrameVector| v.frame = remap(v.frame);
    for handle in model.bodies.handles().collect::<Vec<_>>() {
        let body = model.bodies.get_mut(handle);
        body.frame = remap(body.frame);
    }
    for handle in model.points.handles().collect::<Vec<_>>() {
        let point = model.points.get_mut(handle);
        point.frame = remap(point.frame);
    }
    for load in &mut model.loads {
        match load {
            Load::Force { force, .. } => remap_vector(force),
            Load::Torque { frame, torque, .. } => {
                *frame = remap(*frame);
                remap_vector(torque);
            }
            Load::Bushing { frames, .. } => *frames = frames.map(remap),
            Load::Spring { .. }
            | Load::Damper { .. }
            | Load::LoopSpring { .. }
            | Load::LoopDamper { .. }
            | Load::AngleSpring { .. }
            | Load::AngleDamper { .. }
            | Load::PointSpring { .. }
            | Load::Contact { .. }
            | Load::GeneralizedForce { .. } => {}
        }
    }
    for output in &mut model.outputs {
        if let OutputKind::Position { frame, .. } | OutputKind::Velocity { frame, .. } =
            &mut output.kind
        {
            *frame = remap(*frame);
        }
    }
    for closure in &mut model.loops {
        if let ClosureKind::Coincident { frame, .. } = &mut closure.kind {
            *frame = remap(*frame);
        }
    }
    for constraint in &mut model.velocity_constraints {
        if let crate::ir::VelocityKind::PointVelocity { body, frame, .. } = &mut constraint.kind {
            *body = remap(*body);
            *frame = remap(*frame);
        }
    }
    for speed in &mut model.speeds {
        match &mut speed.kind {
            crate::ir::SpeedKind::AngularVelocity { body, frame, .. } => {
                *body = remap(*body);
                *frame = remap(*frame);
            }
            crate::ir::SpeedKind::PointVelocity { frame, .. } => *frame = remap(*frame),
            crate::ir::SpeedKind::Scalar(_) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn values(v: &Vec3) -> [f64; 3] {
        constant_numbers(v).unwrap().map(Number::to_f64)
    }

    #[test]
    fn perpendicular_is_a_unit_normal_for_any_constant_axis() {
        let number = |x: f64| Expr::Number(Number::Float(x));
        let skew = [number(0.6), number(0.0), number(0.8)];
        let axes = [[Expr::zero(), Expr::zero(), Expr::one()], skew];
        for axis in &axes {
            let n = values(&perpendicular(axis).unwrap());
            let a = values(axis);
            let dot: f64 = (0..3).map(|i| a[i] * n[i]).sum();
            let norm: f64 = n.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!(dot.abs() < 1e-15 && (norm - 1.0).abs() < 1e-15, "{n:?}");
        }
        assert!(
            perpendicular(&[Expr::Param(Handle::new(0)), Expr::zero(), Expr::zero()]).is_none()
        );
        assert!(!perpendicular_enough(&axes[0], &axes[0]));
    }
}
