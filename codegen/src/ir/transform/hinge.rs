//! Flexure hinges beyond the model as written: named hinges twisting about a length axis
//! (Doshi et al. Sec. V-A, Eq. 8) and a hinge's bending axis misaligned, each with every
//! other hinge compliant off its axis so the closed loops can take up the deformation.
//!
//! Consumes: a checked model and the hinges by name. Produces: the model changed in place,
//! with [`TWIST_FACTOR`], [`MISALIGNMENT`] and [`OFF_AXIS_COMPLIANCE`] appended.
//!
//! In a rigid closed loop a single extra twist axis is locked by the other hinges (and a
//! twist at a loop closure is free only to first order), so every revolute loop closure
//! becomes compliant: its points stay together, and springs hold its axis in line — the
//! twisting hinge's own twist spring and, for the other closures, stiff springs
//! (`LATERAL_STIFFNESS_FACTOR · k`, the order of a hinge's in-plane stiffness) about both
//! off-axis directions.

use super::{
    add_twist, append_param, constant_direction, find_flexure, hinge_axis, perpendicular, scaled,
    spring, unit, TransformError, Twist, AXES, LATERAL_STIFFNESS_FACTOR,
};
use crate::ir::{
    AxisAngle, ClosureKind, Dimension, Expr, Flexure, FlexureAngle, Function, Model, Motion, Vec3,
};
use crate::sym::Number;

/// The fitted factor on Eq. 8's twist stiffness.
pub const TWIST_FACTOR: &str = "twist_factor";

/// The off-axis (lateral, and twist of the hinges not named) compliance, per unit bending
/// compliance: the inverse of the off-axis stiffness per unit k.
pub const OFF_AXIS_COMPLIANCE: &str = "off_axis_compliance";

/// Poisson's ratio of Kapton (seed Sec. V-A), in Eq. 8's `2/(1 + ν)` = 100/67.
const TWIST_RATIO: (i128, i128) = (100, 67);

/// The fitted misalignment angle (rad) of `Extension::Misalignment` (the diagnosis).
pub const MISALIGNMENT: &str = "misalignment";
/// `hinges` (name, length axis in the hinge's frame: 0 = x, 1 = y, 2 = z) twist with
/// stiffness [`TWIST_FACTOR`] · 2k/(1 + ν); every other hinge is compliant off its axis.
pub fn twist(model: &mut Model, hinges: &[(String, usize)]) -> Result<(), TransformError> {
    let names: Vec<String> = hinges.iter().map(|(name, _)| name.clone()).collect();
    let springs = TwistSprings::append(model, &names);
    for (name, axis) in hinges {
        let flexure = find_flexure(model, name)?;
        let twist = Twist {
            axis: unit(*axis),
            twist: spring(&flexure, "twist", &springs.eq8),
            lateral: Some(spring(&flexure, "lateral", &springs.stiff)),
            span: flexure.span,
        };
        add_twist(model, flexure.angle, twist).map_err(|error| TransformError::Twist {
            flexure: name.clone(),
            about: format!("about {}", AXES[*axis]),
            error,
        })?;
    }
    compliant_off_axis(model, springs.others, &springs.stiff)
}

/// The parameter of [`twist_choices`] that picks hinge `flexure`'s twist axis.
pub fn twist_choice(flexure: &str) -> String {
    format!("twist_axis_{flexure}")
}

/// [`twist`] with each hinge's length axis left open: each of `hinges` (bending about a
/// coordinate axis) twists about one of the two coordinate axes ⊥ it, picked at run time by
/// its parameter [`twist_choice`] (0: the first, 1: the second; the two springs trade
/// stiffnesses linearly between) — so a search can try every assignment of length axes
/// (2ⁿ for n hinges) on one derivation. At 0 or 1 it equals [`twist`] about that axis to
/// first order in the angles (the twist and lateral frames nest in the other order).
/// Appends [`TWIST_FACTOR`], [`OFF_AXIS_COMPLIANCE`], then the choices in the order of
/// `hinges`; returns each hinge's two axes.
pub fn twist_choices(
    model: &mut Model,
    hinges: &[String],
) -> Result<Vec<[usize; 2]>, TransformError> {
    let springs = TwistSprings::append(model, hinges);
    let mut choices = Vec::new();
    for name in hinges {
        let flexure = find_flexure(model, name)?;
        let axes = twist_axes(model, &flexure)
            .ok_or_else(|| TransformError::AxisNotConstant(name.clone()))?;
        let choice = append_param(
            model,
            &twist_choice(name),
            0.0,
            Dimension::NONE,
            "Which axis ⊥ the bending axis the hinge twists about (0 or 1; mech diagnose).",
        );
        let blend = |soft: Expr, stiff: Expr| {
            Expr::Add(
                Box::new(scaled(&soft, &springs.eq8)),
                Box::new(scaled(&stiff, &springs.stiff)),
            )
        };
        let other = Expr::Sub(Box::new(Expr::one()), Box::new(choice.clone()));
        // Soft about the first axis at 0 (lateral, about bending × first = ± the second,
        // stiff), the other way round at 1.
        let twist = Twist {
            axis: unit(axes[0]),
            twist: spring(&flexure, "twist", &blend(other.clone(), choice.clone())),
            lateral: Some(spring(&flexure, "lateral", &blend(choice, other))),
            span: flexure.span,
        };
        add_twist(model, flexure.angle, twist).map_err(|error| TransformError::Twist {
            flexure: name.clone(),
            about: "off its axis".into(),
            error,
        })?;
        choices.push(axes);
    }
    compliant_off_axis(model, springs.others, &springs.stiff)?;
    Ok(choices)
}

/// The two coordinate axes a hinge bending about a coordinate axis can twist about, in the
/// order of [`twist_choice`] (`None`: its axis is not a coordinate axis).
pub fn twist_axes(model: &Model, flexure: &Flexure) -> Option<[usize; 2]> {
    let axis = constant_direction(&hinge_axis(model, flexure.angle)?)?;
    let bending = (0..3).find(|&i| axis[i].abs() > 1.0 - 1e-12)?;
    Some([(bending + 1) % 3, (bending + 2) % 3])
}

/// What [`twist`] and [`twist_choices`] share: the appended twist factor (as Eq. 8's
/// stiffness factor) and off-axis stiffness factor, and the hinges not named.
struct TwistSprings {
    eq8: Expr,
    stiff: Expr,
    others: Vec<Flexure>,
}

impl TwistSprings {
    fn append(model: &mut Model, named: &[String]) -> TwistSprings {
        let factor = append_param(
            model,
            TWIST_FACTOR,
            1.0,
            Dimension::NONE,
            "Factor on Eq. 8's twist stiffness 2k/(1 + ν) (mech diagnose).",
        );
        let stiff = off_axis_stiffness(model);
        let eq8 = scaled(
            &factor,
            &Expr::Number(Number::rational(TWIST_RATIO.0, TWIST_RATIO.1)),
        );
        // The model's own hinges, before the springs added get flexure records of their own.
        let others: Vec<Flexure> = model
            .flexures
            .iter()
            .filter(|f| !named.contains(&f.name))
            .cloned()
            .collect();
        TwistSprings { eq8, stiff, others }
    }
}

/// The off-axis stiffness factor `1/c` of [`OFF_AXIS_COMPLIANCE`] `c` (appended): c → 0 is
/// rigid off-axis, the base model.
fn off_axis_stiffness(model: &mut Model) -> Expr {
    let compliance = append_param(
        model,
        OFF_AXIS_COMPLIANCE,
        1.0 / LATERAL_STIFFNESS_FACTOR as f64,
        Dimension::NONE,
        "Off-axis compliance of the hinges, per unit bending compliance 1/k.",
    );
    Expr::Div(Box::new(Expr::one()), Box::new(compliance))
}

/// Makes each of `flexures` stiff (`stiff`·k) in both off-axis directions, so the loops can
/// deform.
fn compliant_off_axis(
    model: &mut Model,
    flexures: Vec<Flexure>,
    stiff: &Expr,
) -> Result<(), TransformError> {
    for flexure in flexures {
        let Some(axis) = hinge_axis(model, flexure.angle).and_then(|a| perpendicular(&a)) else {
            continue;
        };
        let twist = Twist {
            axis,
            twist: spring(&flexure, "off_axis", stiff),
            lateral: Some(spring(&flexure, "lateral", stiff)),
            span: flexure.span,
        };
        add_twist(model, flexure.angle, twist).map_err(|error| TransformError::Twist {
            flexure: flexure.name.clone(),
            about: "off its axis".into(),
            error,
        })?;
    }
    Ok(())
}

/// Tilts `name`'s bending axis `a` by the fitted angle α about the coordinate axis `p` (a
/// rotation about `p`, so `a` leans towards `p × a`). At α = 0 it is the base model.
///
/// A pin's axis and its off-axis axes turn by Rodrigues' formula (`rotate`). A loop
/// closure's axis is read as a constant by the closure's geometry (its reference and twist
/// directions are built ⊥ it): instead both interframes turn by α about `p` (the last
/// rotation of each, so `p` is in the axis's own coordinates), which tilts the axis and every
/// direction tied to it alike and leaves the closure unstrained.
pub fn misalign(model: &mut Model, name: &str, about: usize) -> Result<(), TransformError> {
    let angle = append_param(
        model,
        MISALIGNMENT,
        0.0,
        Dimension::NONE,
        "Tilt of the flexure's bending axis (rad, mech diagnose).",
    );
    let stiff = off_axis_stiffness(model);
    let flexure = find_flexure(model, name)?;
    let all: Vec<Flexure> = model.flexures.clone();
    compliant_off_axis(model, all, &stiff)?;
    let tiltable = |axis: &Vec3| -> Result<[f64; 3], TransformError> {
        let a = constant_direction(axis)
            .ok_or_else(|| TransformError::AxisNotConstant(name.to_string()))?;
        if a[about].abs() > 0.1 {
            return Err(TransformError::TiltAboutOwnAxis {
                flexure: name.to_string(),
                about,
            });
        }
        Ok(a)
    };
    match flexure.angle {
        FlexureAngle::Coordinate(coordinate) => {
            // The hinge's own axis and the off-axis axes `compliant_off_axis` inserted above
            // it turn together: R(Ra, q) = R·R(a, q)·Rᵀ, so the chain of the three is the
            // aligned hinge conjugated by R — the whole hinge tilted, its springs still
            // about its own (tilted) directions.
            let hinge_frames: Vec<_> = model
                .frames
                .iter()
                .filter_map(|(handle, frame)| match &frame.motion {
                    Motion::Revolute { coordinate: c, .. } => {
                        let coordinate_name = &model.coordinates[*c].name;
                        let own = *c == coordinate;
                        let off_axis = [format!("{name}_off_axis"), format!("{name}_lateral")]
                            .contains(coordinate_name);
                        (own || off_axis).then_some((handle, own))
                    }
                    _ => None,
                })
                .collect();
            if !hinge_frames.iter().any(|&(_, own)| own) {
                return Err(TransformError::NotOnPin(name.to_string()));
            }
            for (frame, own) in hinge_frames {
                let Motion::Revolute { axis, .. } = &mut model.frames.get_mut(frame).motion else {
                    unreachable!("found as revolute")
                };
                if own {
                    tiltable(axis)?;
                }
                rotate(axis, about, &angle)
                    .ok_or_else(|| TransformError::AxisNotConstant(name.to_string()))?;
            }
            Ok(())
        }
        FlexureAngle::Loop(index) => match model.loops.get_mut(index).map(|c| &mut c.kind) {
            Some(ClosureKind::Revolute {
                axis,
                parent_orientation,
                child_orientation,
                ..
            }) => {
                tiltable(axis)?;
                for orientation in [parent_orientation, child_orientation] {
                    orientation.push(AxisAngle {
                        axis: unit(about),
                        angle: angle.clone(),
                    });
                }
                Ok(())
            }
            _ => Err(TransformError::NotOnRevoluteLoop(name.to_string())),
        },
        _ => Err(TransformError::NotABendingHinge(name.to_string())),
    }
}

/// `axis` (a constant direction `a`) turned by `angle` about the coordinate axis `about`
/// (`p`), by Rodrigues' formula `a cos α + (p × a) sin α + p (p·a)(1 − cos α)`; `None` if `a`
/// is not constant.
fn rotate(axis: &mut Vec3, about: usize, angle: &Expr) -> Option<()> {
    let a = constant_direction(axis)?;
    let p = [0, 1, 2].map(|i| if i == about { 1.0 } else { 0.0 });
    let p_cross_a = [
        p[1] * a[2] - p[2] * a[1],
        p[2] * a[0] - p[0] * a[2],
        p[0] * a[1] - p[1] * a[0],
    ];
    let number = |x: f64| Expr::Number(Number::Float(x));
    let cos = Expr::Call(Function::Cos, vec![angle.clone()]);
    let sin = Expr::Call(Function::Sin, vec![angle.clone()]);
    let one_minus_cos = Expr::Sub(Box::new(Expr::one()), Box::new(cos.clone()));
    for (i, component) in axis.iter_mut().enumerate() {
        *component = Expr::Add(
            Box::new(Expr::Add(
                Box::new(scaled(&cos, &number(a[i]))),
                Box::new(scaled(&sin, &number(p_cross_a[i]))),
            )),
            Box::new(scaled(&one_minus_cos, &number(p[i] * a[about]))),
        );
    }
    Some(())
}

/// The flexures around each loop closure, in `model.flexures` order: the closure's own
/// hinge and those on the shortest path through the rest of the mechanism between its two
/// points (a moving frame or another closure counts one step, a fixed frame none). A twist
/// unlocks a closed loop only when its hinges give way together (the module docs), so these
/// are the hinges a loop's twist acts at. Two closures sharing one shortest cycle give equal
/// sets (the caller dedupes).
pub fn loop_flexures(model: &Model) -> Vec<Vec<String>> {
    #[derive(Clone, Copy, PartialEq)]
    enum Edge {
        /// A frame to its parent.
        Frame(usize),
        /// A loop closure.
        Loop(usize),
    }
    let frames = model.frames.len();
    let mut neighbours: Vec<Vec<(usize, Edge, usize)>> = vec![Vec::new(); frames];
    for (handle, frame) in model.frames.iter() {
        if let Some(parent) = frame.parent {
            let cost = usize::from(frame.motion != Motion::Fixed);
            let edge = Edge::Frame(handle.index());
            neighbours[handle.index()].push((parent.index(), edge, cost));
            neighbours[parent.index()].push((handle.index(), edge, cost));
        }
    }
    let ends = |closure: &crate::ir::LoopClosure| {
        (
            model.points[closure.parent].frame.index(),
            model.points[closure.child].frame.index(),
        )
    };
    for (index, closure) in model.loops.iter().enumerate() {
        let (a, b) = ends(closure);
        neighbours[a].push((b, Edge::Loop(index), 1));
        neighbours[b].push((a, Edge::Loop(index), 1));
    }
    model
        .loops
        .iter()
        .enumerate()
        .map(|(closure, loop_closure)| {
            let (from, to) = ends(loop_closure);
            // 0-1 breadth-first search (a deque: cost-0 steps in front) without this closure.
            let mut distance = vec![usize::MAX; frames];
            let mut reached_by: Vec<Option<(usize, Edge)>> = vec![None; frames];
            let mut queue = std::collections::VecDeque::from([from]);
            distance[from] = 0;
            while let Some(node) = queue.pop_front() {
                for &(next, edge, cost) in &neighbours[node] {
                    if edge == Edge::Loop(closure) || distance[node] + cost >= distance[next] {
                        continue;
                    }
                    distance[next] = distance[node] + cost;
                    reached_by[next] = Some((node, edge));
                    if cost == 0 {
                        queue.push_front(next);
                    } else {
                        queue.push_back(next);
                    }
                }
            }
            let mut path = vec![Edge::Loop(closure)];
            let mut node = to;
            while let Some((previous, edge)) = reached_by[node] {
                path.push(edge);
                node = previous;
            }
            model
                .flexures
                .iter()
                .filter(|flexure| match flexure.angle {
                    FlexureAngle::Coordinate(coordinate) => super::pin_frame(model, coordinate)
                        .is_some_and(|(frame, _)| path.contains(&Edge::Frame(frame.index()))),
                    FlexureAngle::Loop(index) => path.contains(&Edge::Loop(index)),
                    FlexureAngle::LoopTwist(_) | FlexureAngle::LoopLateral(_) => false,
                })
                .map(|flexure| flexure.name.clone())
                .collect()
        })
        .collect()
}
