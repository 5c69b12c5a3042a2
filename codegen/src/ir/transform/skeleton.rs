//! A stick figure of a model, for drawing its motion: per body, the points that show where
//! it is (its origin, centre of mass and the points fixed in it), as position outputs in the
//! Newtonian frame.
//!
//! Consumes: a checked [`Model`]. Produces: the same model with one vector output per shown
//! point appended after the model's own outputs (so those keep their indices), and the
//! [`Skeleton`] that names them.

use super::super::{Expr, Frame, Handle, Model, Motion, Output, OutputKind, Point};
use crate::diag::Span;

/// The shown points of one body; the outputs `<output>.x`, `.y`, `.z` are its position in N.
#[derive(Clone, Debug, PartialEq)]
pub struct SkeletonBody {
    pub name: String,
    /// `(point name, output name)`: the origin first, then the centre of mass, then the
    /// declared points in declaration order.
    pub points: Vec<(String, String)>,
}

/// Every body's shown points.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Skeleton {
    pub bodies: Vec<SkeletonBody>,
}

/// The body frame `frame` is fixed in: itself, or the nearest ancestor reached through fixed
/// frames only (interframes, welds' frames).
fn fixed_in(model: &Model, frame: Handle<Frame>) -> Handle<Frame> {
    let mut frame = frame;
    while model.frames[frame].motion == Motion::Fixed {
        match model.frames[frame].parent {
            Some(parent) if !model.bodies.iter().any(|(_, b)| b.frame == frame) => frame = parent,
            _ => break,
        }
    }
    frame
}

/// Appends the outputs of [`Skeleton`]'s points (named `skeleton.<body>.<k>`) to `model`.
pub fn add_skeleton_outputs(model: &mut Model) -> Skeleton {
    let mut skeleton = Skeleton::default();
    let bodies: Vec<_> = model
        .bodies
        .iter()
        .map(|(_, body)| (body.name.clone(), body.frame, body.center_of_mass.clone()))
        .collect();
    for (name, frame, center_of_mass) in bodies {
        let mut shown = vec![
            (
                format!("{name} origin"),
                Point {
                    name: format!("{name}.skeleton_origin"),
                    frame,
                    position: [Expr::zero(), Expr::zero(), Expr::zero()],
                    span: Span::default(),
                },
            ),
            (
                format!("{name} centre of mass"),
                Point {
                    name: format!("{name}.skeleton_com"),
                    frame,
                    position: center_of_mass,
                    span: Span::default(),
                },
            ),
        ];
        for (_, point) in model.points.iter() {
            if fixed_in(model, point.frame) == frame && !point.name.contains("skeleton_") {
                shown.push((point.name.clone(), point.clone()));
            }
        }
        let mut points = Vec::new();
        for (k, (label, point)) in shown.into_iter().enumerate() {
            let handle = model.points.append(point);
            let output = format!("skeleton.{name}.{k}");
            model.outputs.push(Output {
                name: output.clone(),
                kind: OutputKind::Position {
                    point: handle,
                    frame: Model::NEWTONIAN,
                },
                docs: Vec::new(),
                span: Span::default(),
            });
            points.push((label, output));
        }
        skeleton.bodies.push(SkeletonBody { name, points });
    }
    skeleton
}
