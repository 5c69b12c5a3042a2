//! Model transformations: rewrites of a checked [`Model`] that keep the IR invariants.
//!
//! Consumes: a model and a description of the change. Produces: the changed model (in place),
//! with every frame handle remapped so that parents still come first.
//!
//! The first transformation inserts a moving frame into the kinematic tree, e.g. the twist
//! degree of freedom of a flexure hinge (Doshi et al. Eq. 8) or, later, compliance of a loop
//! closure.

use super::{ClosureKind, Dimension};
use super::{Coordinate, Expr, Frame, FrameVector, Handle, Load, Model, Motion, OutputKind, Vec3};
use crate::diag::Span;

/// Inserts a frame rotating about `axis` (components in `parent`'s basis) right below
/// `parent`: the frame's former children hang from it instead. Returns its frame and its
/// new coordinate (appended after the existing ones).
pub fn insert_revolute_below(
    model: &mut Model,
    parent: Handle<Frame>,
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
    let inserted = parent.index() + 1;
    // Old index i → new index: unchanged up to `parent`, shifted by one after it.
    let remap = |frame: Handle<Frame>| {
        if frame.index() < inserted {
            frame
        } else {
            Handle::new(frame.index() + 1)
        }
    };
    let new_frame = Handle::<Frame>::new(inserted);

    let old = std::mem::take(&mut model.frames);
    for (handle, frame) in old.iter() {
        let mut copy = frame.clone();
        copy.parent = frame
            .parent
            .map(|p| if p == parent { new_frame } else { remap(p) });
        model.frames.append(copy);
        if handle == parent {
            model.frames.append(Frame {
                name: name.to_string(),
                parent: Some(parent),
                origin: [Expr::zero(), Expr::zero(), Expr::zero()],
                orientation: Vec::new(),
                motion: Motion::Revolute {
                    axis: axis.clone(),
                    coordinate,
                },
                span,
            });
        }
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
            Load::Spring { .. }
            | Load::Damper { .. }
            | Load::LoopSpring { .. }
            | Load::LoopDamper { .. }
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
}
