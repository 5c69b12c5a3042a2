//! From a read URDF [`Robot`] to `.mech` text: names resolved, the tree checked (one root,
//! no link with two parents, no cycle), the zero pose computed for the loop closures'
//! misses and `--snap`, and every declaration written with the user's units.
//!
//! Consumes: a [`Robot`] and the [`Options`]. Produces: an [`Import`] (the text, the warnings
//! as spanned diagnostics) or [`Errors`] for names that do not resolve and structures that
//! are not a tree. The output depends only on the input and the options (no maps are
//! iterated), so importing twice gives the same bytes.

use std::collections::HashMap;
use std::fmt::Write;
use std::sync::Arc;

use super::pose::{self, Axis, Frame, Vec3};
use super::read::{float_literal, ForceKind, LinearSpring, Name, Num, Pose, Robot, SkippedKind};
use super::{Base, Import, Options};
use crate::diag::{self, Diagnostic, Errors, SourceFile, Span};
use crate::front::DECLARATION_KEYWORDS;

/// Words of the `.mech` grammar besides the declaration keywords, and reserved names: an
/// identifier from the URDF that is one of these gets a `_` appended.
const RESERVED: &[&str] = &[
    "model",
    "point",
    "frame",
    "at",
    "on",
    "in",
    "between",
    "and",
    "t",
    "pi",
    "kinetic_energy",
    "potential_energy",
    "com",
];

/// A closure's points are reported (and snapped) when they miss each other by more than this
/// fraction of the robot's size: larger than the round-off of summing the file's decimals,
/// far smaller than any intended offset.
const MISS_FRACTION: f64 = 1e-9;

/// A snap moves points by at most this fraction of the robot's size: a larger miss is a
/// modelling error to fix by hand, not round-off.
const SNAP_FRACTION: f64 = 1e-5;

/// The axes that take part in a snap cross the closure's axis within this many times its
/// miss (the miss is what spreads them apart).
const CROSSING_FACTOR: f64 = 100.0;

/// Unique `.mech` identifiers for names of the URDF.
#[derive(Default)]
struct Identifiers {
    taken: Vec<String>,
}

impl Identifiers {
    fn take(&mut self, raw: &str) -> String {
        let mut base: String = raw
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '_' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        if base.is_empty() || base.starts_with(|c: char| c.is_ascii_digit()) {
            base.insert(0, '_');
        }
        if RESERVED.contains(&base.as_str()) || DECLARATION_KEYWORDS.contains(&base.as_str()) {
            base.push('_');
        }
        let mut name = base.clone();
        let mut n = 2;
        while self.taken.contains(&name) {
            name = format!("{base}_{n}");
            n += 1;
        }
        self.taken.push(name.clone());
        name
    }
}

/// What a tree joint becomes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Pin,
    Slider,
    Weld,
    Ball,
    Free,
}

impl Kind {
    fn keyword(self) -> &'static str {
        match self {
            Kind::Pin => "pin",
            Kind::Slider => "slider",
            Kind::Weld => "weld",
            Kind::Ball => "ball",
            Kind::Free => "free",
        }
    }
}

/// A joint or loop's spring and damper, as parameter names.
#[derive(Clone, Default)]
struct Elastic {
    stiffness: Option<String>,
    rest: Option<String>,
    damping: Option<String>,
}

/// A parameter to declare: name, literal, unit, doc comment.
struct Param {
    name: String,
    value: String,
    unit: String,
    doc: String,
}

struct Units<'a> {
    length: &'a str,
    mass: &'a str,
    time: &'a str,
}

impl Units<'_> {
    fn inertia(&self) -> String {
        format!("{}*{}^2", self.mass, self.length)
    }
    /// Torque per radian: mass·length²/time²/rad.
    fn torsional_stiffness(&self) -> String {
        format!("{}*{}^2/{}^2/rad", self.mass, self.length, self.time)
    }
    fn torsional_damping(&self) -> String {
        format!("{}*{}^2/{}/rad", self.mass, self.length, self.time)
    }
    fn linear_stiffness(&self) -> String {
        format!("{}/{}^2", self.mass, self.time)
    }
    fn linear_damping(&self) -> String {
        format!("{}/{}", self.mass, self.time)
    }
}

pub fn emit(file: &Arc<SourceFile>, robot: Robot, options: &Options) -> Result<Import, Errors> {
    let mut robot = robot;
    let mut errors = Vec::new();
    let mut warnings = Vec::new();
    let units = Units {
        length: &options.units.length,
        mass: &options.units.mass,
        time: &options.units.time,
    };

    // ------------------------------------------------------------ names
    let mut link_index: HashMap<&str, usize> = HashMap::new();
    for (i, link) in robot.links.iter().enumerate() {
        if let Some(&first) = link_index.get(link.name.text.as_str()) {
            errors.push(duplicate("link", &link.name, robot.links[first].name.span));
        } else {
            link_index.insert(&link.name.text, i);
        }
    }
    let link_names: Vec<&str> = robot.links.iter().map(|l| l.name.text.as_str()).collect();
    let resolve = |name: &Name,
                   errors: &mut Vec<Diagnostic>,
                   warnings: &mut Vec<Diagnostic>|
     -> Option<usize> {
        if let Some(&i) = link_index.get(name.text.as_str()) {
            return Some(i);
        }
        let folded: Vec<usize> = (0..link_names.len())
            .filter(|&i| link_names[i].eq_ignore_ascii_case(&name.text))
            .collect();
        if let [only] = folded[..] {
            warnings.push(
                Diagnostic::warning(
                    "U0601",
                    format!("no link `{}`: read as `{}`", name.text, link_names[only]),
                )
                .with_label(name.span, "names differ only in case")
                .with_help("URDF names are case-sensitive; correct the file to silence this"),
            );
            return Some(only);
        }
        let mut error = Diagnostic::error("U0201", format!("unknown link `{}`", name.text))
            .with_label(name.span, "no `<link>` has this name");
        error = match diag::closest(&name.text, &link_names) {
            Some(close) => error.with_help(format!("did you mean `{close}`?")),
            None => error.with_help(format!("the links of this file: {}", listing(&link_names))),
        };
        errors.push(error);
        None
    };

    // ------------------------------------------------------------ the tree
    let mut parent_joint: Vec<Option<usize>> = vec![None; robot.links.len()];
    let mut ends: Vec<Option<(usize, usize)>> = Vec::new();
    let mut joint_names: HashMap<&str, usize> = HashMap::new();
    for (j, joint) in robot.joints.iter().enumerate() {
        if let Some(&first) = joint_names.get(joint.name.text.as_str()) {
            errors.push(duplicate(
                "joint",
                &joint.name,
                robot.joints[first].name.span,
            ));
        } else {
            joint_names.insert(&joint.name.text, j);
        }
        let parent = resolve(&joint.parent, &mut errors, &mut warnings);
        let child = resolve(&joint.child, &mut errors, &mut warnings);
        ends.push(parent.zip(child));
        let Some(child) = child else { continue };
        match parent_joint[child] {
            Some(first) => errors.push(
                Diagnostic::error(
                    "U0401",
                    format!(
                        "link `{}` has two parent joints, `{}` and `{}`: a kinematic cycle",
                        robot.links[child].name.text, robot.joints[first].name.text, joint.name.text
                    ),
                )
                .with_label(joint.child.span, "second parent joint")
                .with_label(robot.joints[first].child.span, "first parent joint")
                .with_help(format!(
                    "a URDF tree gives each link one parent; close the cycle with Drake's `<loop_joint name=\"{}\" type=\"continuous\">` (axis, link1, link2) instead of this `<joint>`",
                    joint.name.text
                )),
            ),
            None => parent_joint[child] = Some(j),
        }
    }
    if !errors.is_empty() {
        return Err(Errors::new(file.clone(), errors));
    }
    let roots: Vec<usize> = (0..robot.links.len())
        .filter(|&i| parent_joint[i].is_none())
        .collect();
    let root = match roots[..] {
        [root] => root,
        [] if robot.links.is_empty() => {
            return Err(Errors::new(
                file.clone(),
                vec![Diagnostic::error("U0402", "the robot has no links")
                    .with_label(Span::new(0, 1), "no `<link>` in this file")
                    .with_help("a URDF robot has at least one `<link name=\"...\">`")],
            ))
        }
        [] => {
            let joint = &robot.joints[parent_joint[0].unwrap_or(0)];
            return Err(Errors::new(
                file.clone(),
                vec![Diagnostic::error("U0401", "every link has a parent joint: the joints form a cycle and the tree has no root")
                    .with_label(joint.span, "one joint of the cycle")
                    .with_help("make one joint of the cycle a Drake `<loop_joint>` (axis, link1, link2)")],
            ));
        }
        _ => {
            let mut error = Diagnostic::error(
                "U0403",
                format!(
                    "{} links have no parent joint; a URDF tree has one root",
                    roots.len()
                ),
            );
            for &r in &roots {
                error = error.with_label(
                    robot.links[r].name.span,
                    "no joint has this link as its child",
                );
            }
            return Err(Errors::new(
                file.clone(),
                vec![error.with_help(
                    "join the extra roots to the tree with a `<joint>` (type fixed to weld them)",
                )],
            ));
        }
    };
    // Zero pose, depth first from the root with siblings in the file's order (the order of
    // `.mech` coordinates); a link not reached from the root sits on a cycle.
    let mut world: Vec<Option<Frame>> = vec![None; robot.links.len()];
    world[root] = Some(Frame::ROOT);
    let mut order = Vec::new();
    let mut stack = vec![root];
    while let Some(parent) = stack.pop() {
        order.push(parent);
        let frame = world[parent].unwrap_or(Frame::ROOT);
        let mut children = Vec::new();
        for (j, joint) in robot.joints.iter().enumerate() {
            let Some((p, c)) = ends[j] else { continue };
            if p == parent && world[c].is_none() {
                world[c] = Some(frame.then(values(&joint.origin.xyz), &rotation(&joint.origin)));
                children.push(c);
            }
        }
        stack.extend(children.into_iter().rev());
    }
    if let Some(lost) = (0..robot.links.len()).find(|&i| world[i].is_none()) {
        let joint = &robot.joints[parent_joint[lost].unwrap_or(0)];
        return Err(Errors::new(
            file.clone(),
            vec![Diagnostic::error(
                "U0401",
                format!(
                    "link `{}` is on a cycle of joints not connected to the root `{}`",
                    robot.links[lost].name.text, robot.links[root].name.text
                ),
            )
            .with_label(joint.span, "a joint of the cycle")
            .with_help("make one joint of the cycle a Drake `<loop_joint>` (axis, link1, link2)")],
        ));
    }
    let world: Vec<Frame> = world
        .into_iter()
        .map(|f| f.unwrap_or(Frame::ROOT))
        .collect();
    let size = world
        .iter()
        .map(|f| pose::norm(f.origin))
        .fold(0.0_f64, f64::max)
        .max(f64::MIN_POSITIVE);

    // ------------------------------------------------------------ identifiers
    let mut frames = Identifiers::default();
    let mut params = Identifiers::default();
    let fixed_root = options.base == Base::Fixed;
    let body_ident: Vec<String> = robot
        .links
        .iter()
        .enumerate()
        .map(|(i, link)| {
            if i == root && fixed_root {
                "newtonian".to_string()
            } else {
                frames.take(&link.name.text)
            }
        })
        .collect();
    let joint_ident: Vec<String> = robot
        .joints
        .iter()
        .map(|j| frames.take(&j.name.text))
        .collect();

    // ------------------------------------------------------------ joint kinds
    let mut kinds = Vec::new();
    for joint in &robot.joints {
        let kind = match joint.kind.text.as_str() {
            "revolute" | "continuous" => Kind::Pin,
            "prismatic" => Kind::Slider,
            "fixed" | "Fixed" => Kind::Weld,
            "floating" => Kind::Free,
            "ball" | "spherical" => Kind::Ball,
            "planar" => {
                warnings.push(
                    Diagnostic::warning(
                        "U0602",
                        format!(
                            "joint `{}` is planar: `.mech` has no planar joint; welded instead",
                            joint.name.text
                        ),
                    )
                    .with_label(joint.kind.span, "3 degrees of freedom lost")
                    .with_help("replace the weld by two sliders and a pin through massless bodies"),
                );
                Kind::Weld
            }
            other => {
                errors.push(
                    Diagnostic::error("U0204", format!("unknown joint type `{other}`"))
                        .with_label(joint.kind.span, "not a URDF joint type")
                        .with_help("URDF joint types: revolute, continuous, prismatic, fixed, floating, planar"),
                );
                Kind::Weld
            }
        };
        if matches!(kind, Kind::Pin | Kind::Slider) && values(&joint.axis) == [0.0; 3] {
            errors.push(
                Diagnostic::error(
                    "U0303",
                    format!("joint `{}` has a zero axis", joint.name.text),
                )
                .with_label(joint.axis[0].span, "axis `0 0 0`")
                .with_help("a revolute or prismatic joint needs a nonzero `<axis xyz=\"...\"/>`"),
            );
        }
        kinds.push(kind);
    }

    // ------------------------------------------------------------ loop closures
    struct Closure {
        ident: String,
        revolute: bool,
        link1: usize,
        link2: usize,
        snapped: Option<pose::Snap>,
    }
    let mut closures: Vec<Option<Closure>> = Vec::new();
    for closure in &robot.loops {
        let first = resolve(&closure.link1, &mut errors, &mut warnings);
        let second = resolve(&closure.link2, &mut errors, &mut warnings);
        let revolute = match closure.kind.text.as_str() {
            "continuous" | "revolute" => true,
            "ball" | "spherical" => false,
            other => {
                warnings.push(
                    Diagnostic::warning("U0603", format!("loop_joint `{}` of type `{other}` is not translated", closure.name.text))
                        .with_label(closure.kind.span, "`.mech` closes loops with revolute (continuous) and coincident (ball) closures")
                        .with_help("write the closure by hand: `loop NAME = coincident(...)` with the components it fixes"),
                );
                closures.push(None);
                continue;
            }
        };
        closures.push(first.zip(second).map(|(link1, link2)| Closure {
            ident: frames.take(&closure.name.text),
            revolute,
            link1,
            link2,
            snapped: None,
        }));
    }
    if !errors.is_empty() {
        return Err(Errors::new(file.clone(), errors));
    }
    // Hinge axes at the zero pose, for snapping.
    let mut axes: Vec<Axis> = Vec::new();
    for (j, joint) in robot.joints.iter().enumerate() {
        if kinds[j] == Kind::Pin {
            if let (Some((_, child)), Some(direction)) = (ends[j], pose::unit(values(&joint.axis)))
            {
                axes.push(Axis {
                    name: joint.name.text.clone(),
                    point: world[child].origin,
                    direction: world[child].direction(direction),
                });
            }
        }
    }
    for (closure, c) in robot.loops.iter().zip(&closures) {
        if let (Some(c), Some(direction)) = (c, pose::unit(values(&closure.axis))) {
            if c.revolute {
                let frame =
                    world[c.link1].then(values(&closure.pose1.xyz), &rotation(&closure.pose1));
                axes.push(Axis {
                    name: closure.name.text.clone(),
                    point: frame.origin,
                    direction: frame.direction(direction),
                });
            }
        }
    }
    let mut snap_notes = Vec::new();
    // Snapped coordinates are printed to the decimals the file's positions are written
    // with (more would be round-off of the arithmetic); those that move by less than a
    // thousandth of a reported miss keep their literal.
    let resolution = robot
        .joints
        .iter()
        .flat_map(|j| j.origin.xyz.iter())
        .chain(
            robot
                .loops
                .iter()
                .flat_map(|l| l.pose1.xyz.iter().chain(&l.pose2.xyz)),
        )
        .map(|n| decimals(&n.literal))
        .max()
        .unwrap_or(0)
        .max(3);
    let unmoved = 1e-3 * MISS_FRACTION * size;
    for (l, closure) in robot.loops.iter_mut().enumerate() {
        let Some(c) = closures[l].as_mut() else {
            continue;
        };
        let first = world[c.link1].point(values(&closure.pose1.xyz));
        let second = world[c.link2].point(values(&closure.pose2.xyz));
        let miss = pose::miss(first, second);
        if miss.distance <= MISS_FRACTION * size {
            continue;
        }
        let length = &units.length;
        let gap = miss.gap.map(|g| format!("{g:.3e}")).join(", ");
        let mut warning = Diagnostic::warning(
            "U0604",
            format!(
                "the points of loop_joint `{}` miss each other by {:.3e} {length} at the zero pose",
                closure.name.text, miss.distance
            ),
        )
        .with_label(
            closure.span,
            format!("link2's point minus link1's: [{gap}] {length}"),
        );
        let snappable = miss.distance <= SNAP_FRACTION * size;
        if !snappable {
            warnings.push(warning.with_help("the closure does not hold at the zero pose: check the loop points (--snap only fixes misses of round-off size)"));
            continue;
        }
        let direction = pose::unit(values(&closure.axis)).unwrap_or([1.0, 0.0, 0.0]);
        let world_direction = world[c.link1]
            .then(values(&closure.pose1.xyz), &rotation(&closure.pose1))
            .direction(direction);
        let fix = if c.revolute {
            let others: Vec<Axis> = axes
                .iter()
                .filter(|a| a.name != closure.name.text)
                .cloned()
                .collect();
            let tolerance = (CROSSING_FACTOR * miss.distance).max(MISS_FRACTION * size);
            pose::snap(world_direction, first, second, &others, tolerance)
        } else {
            let midpoint = pose::scale(pose::add(first, second), 0.5);
            pose::Snap {
                centre: midpoint,
                through: Vec::new(),
                first: midpoint,
                second: midpoint,
            }
        };
        let new1 = world[c.link1].local(fix.first);
        let new2 = world[c.link2].local(fix.second);
        let moves = |pose_xyz: &[Num; 3], new: Vec3, link: &str| -> Vec<String> {
            ["x", "y", "z"]
                .iter()
                .zip(pose_xyz.iter().zip(new))
                .filter(|(_, (old, new))| (old.value - new).abs() > unmoved)
                .map(|(axis, (old, new))| {
                    format!(
                        "{link} {axis} {} -> {}",
                        old.literal,
                        decimal(new, old.span, resolution).literal
                    )
                })
                .collect()
        };
        let mut moved = moves(
            &closure.pose1.xyz,
            new1,
            &format!("link1 ({})", closure.link1.text),
        );
        moved.extend(moves(
            &closure.pose2.xyz,
            new2,
            &format!("link2 ({})", closure.link2.text),
        ));
        let centre = fix
            .centre
            .map(|v| decimal(v, closure.span, resolution).literal)
            .join(", ");
        let how = if fix.through.is_empty() {
            format!("both points to their midpoint [{centre}] {length}")
        } else {
            format!(
                "both points onto the `{}` axis through [{centre}] {length}, where the axes of {} meet it",
                closure.name.text,
                fix.through.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
            )
        };
        let summary = format!("{how}: {}", moved.join(", "));
        if options.snap {
            warning = warning.with_note(format!("--snap moved {summary}"));
            snap_notes.push(format!(
                "loop_joint `{}`: moved {summary}",
                closure.name.text
            ));
            for (pose_xyz, new) in [
                (&mut closure.pose1.xyz, new1),
                (&mut closure.pose2.xyz, new2),
            ] {
                for (num, value) in pose_xyz.iter_mut().zip(new) {
                    if (num.value - value).abs() > unmoved {
                        *num = decimal(value, num.span, resolution);
                    }
                }
            }
            c.snapped = Some(fix);
        } else {
            warning = warning.with_help(format!("--snap moves {summary}"));
        }
        warnings.push(warning);
    }

    // ------------------------------------------------------------ force elements
    let loop_names: HashMap<&str, usize> = robot
        .loops
        .iter()
        .enumerate()
        .map(|(i, l)| (l.name.text.as_str(), i))
        .collect();
    let mut joint_elastic: Vec<Elastic> = vec![Elastic::default(); robot.joints.len()];
    let mut loop_elastic: Vec<Elastic> = vec![Elastic::default(); robot.loops.len()];
    let mut declared: Vec<Param> = Vec::new();
    let mut springs: Vec<String> = Vec::new();
    let mut untranslated: Vec<String> = Vec::new();
    // Ends of point-to-point springs: (link, spring identifier, point, element name).
    let mut spring_points: Vec<(usize, String, [Num; 3], String)> = Vec::new();
    for force in &robot.forces {
        let (joint, stiffness, rest, torsional) = match &force.kind {
            ForceKind::Torsional {
                joint,
                stiffness,
                rest,
            } => (joint, stiffness, rest, true),
            ForceKind::Prismatic {
                joint,
                stiffness,
                rest,
            } => (joint, stiffness, rest, false),
            ForceKind::LinearSpringDamper(spring) => {
                let LinearSpring {
                    stiffness,
                    damping,
                    rest_length,
                    link1,
                    point1,
                    link2,
                    point2,
                } = spring.as_ref();
                let (Some(a), Some(b)) = (
                    resolve(link1, &mut errors, &mut warnings),
                    resolve(link2, &mut errors, &mut warnings),
                ) else {
                    continue;
                };
                if a == b {
                    warnings.push(
                        Diagnostic::warning(
                            "U0605",
                            format!(
                                "force_element `{}` joins two points of one link: not translated",
                                force.name.text
                            ),
                        )
                        .with_label(force.span, "its length never changes"),
                    );
                    untranslated.push(format!(
                        "force_element `{}`: a spring between two points of one link",
                        force.name.text
                    ));
                    continue;
                }
                let ident = params.take(&force.name.text);
                let length = pose::norm(pose::sub(
                    world[b].point(values(point2)),
                    world[a].point(values(point1)),
                ));
                if length <= MISS_FRACTION * size {
                    warnings.push(
                        Diagnostic::warning("U0606", format!("the points of force_element `{}` coincide at the zero pose", force.name.text))
                            .with_label(force.span, format!("{length:.3e} {} apart", units.length))
                            .with_help("a `.mech` spring's direction is undefined where its length is zero (its force is NaN there); move a point or model it as a joint spring"),
                    );
                }
                declared.push(Param {
                    name: ident.clone(),
                    value: stiffness.literal.clone(),
                    unit: units.linear_stiffness(),
                    doc: format!(
                        "`{}`: Drake linear_spring_damper stiffness.",
                        force.name.text
                    ),
                });
                let mut fields = vec![format!("stiffness = {ident};")];
                if let Some(rest) = rest_length {
                    let name = params.take(&format!("{}_rest_length", force.name.text));
                    declared.push(Param {
                        name: name.clone(),
                        value: rest.literal.clone(),
                        unit: units.length.to_string(),
                        doc: format!("`{}`: rest length.", force.name.text),
                    });
                    fields.push(format!("rest_length = {name};"));
                }
                if let Some(damping) = damping.as_ref().filter(|d| d.value != 0.0) {
                    let name = params.take(&format!("{}_damping", force.name.text));
                    declared.push(Param {
                        name: name.clone(),
                        value: damping.literal.clone(),
                        unit: units.linear_damping(),
                        doc: format!("`{}`: damping.", force.name.text),
                    });
                    fields.push(format!("damping = {name};"));
                }
                spring_points.push((a, ident.clone(), point1.clone(), force.name.text.clone()));
                spring_points.push((b, ident.clone(), point2.clone(), force.name.text.clone()));
                springs.push(format!(
                    "/// Drake force_element `{}` (linear_spring_damper), line {}.\nspring {ident} between {} and {} {{ {} }}\n",
                    force.name.text,
                    file.line_col(force.span.start).0,
                    point_of(&body_ident[a], &ident),
                    point_of(&body_ident[b], &ident),
                    fields.join(" ")
                ));
                continue;
            }
        };
        let target_joint = joint_names.get(joint.text.as_str()).copied();
        let target_loop = loop_names.get(joint.text.as_str()).copied();
        let fits = match (target_joint, target_loop) {
            (Some(j), _) => {
                (torsional && kinds[j] == Kind::Pin) || (!torsional && kinds[j] == Kind::Slider)
            }
            (None, Some(l)) => torsional && closures[l].as_ref().is_some_and(|c| c.revolute),
            (None, None) => {
                let mut candidates: Vec<&str> = joint_names.keys().copied().collect();
                candidates.extend(loop_names.keys().copied());
                candidates.sort_unstable();
                let mut error =
                    Diagnostic::error("U0202", format!("unknown joint `{}`", joint.text))
                        .with_label(
                            joint.span,
                            format!(
                                "force_element `{}` acts on no joint of this name",
                                force.name.text
                            ),
                        );
                error = error.with_help(match diag::closest(&joint.text, &candidates) {
                    Some(close) => format!("did you mean `{close}`?"),
                    None => format!(
                        "the joints and loop joints of this file: {}",
                        listing(&candidates)
                    ),
                });
                errors.push(error);
                continue;
            }
        };
        let elastic = match (target_joint, target_loop) {
            (Some(j), _) => &mut joint_elastic[j],
            (None, Some(l)) => &mut loop_elastic[l],
            (None, None) => continue,
        };
        if !fits || elastic.stiffness.is_some() {
            let why = if fits {
                "its joint already has a spring"
            } else if torsional {
                "a torsional spring needs a revolute joint or loop_joint"
            } else {
                "a prismatic spring needs a prismatic joint"
            };
            warnings.push(
                Diagnostic::warning(
                    "U0605",
                    format!(
                        "force_element `{}` is not translated: {why}",
                        force.name.text
                    ),
                )
                .with_label(force.span, "listed as a comment in the output"),
            );
            untranslated.push(format!(
                "force_element `{}` on `{}`: {why}",
                force.name.text, joint.text
            ));
            continue;
        }
        let ident = params.take(&force.name.text);
        let (unit, rest_unit, what) = if torsional {
            (
                units.torsional_stiffness(),
                "rad".to_string(),
                "torsional_spring",
            )
        } else {
            (
                units.linear_stiffness(),
                units.length.to_string(),
                "prismatic_spring",
            )
        };
        declared.push(Param {
            name: ident.clone(),
            value: stiffness.literal.clone(),
            unit,
            doc: format!("`{}`: Drake {what} on `{}`.", force.name.text, joint.text),
        });
        elastic.stiffness = Some(ident.clone());
        if let Some(rest) = rest.as_ref().filter(|r| r.value != 0.0) {
            let name = params.take(&format!("{}_rest", force.name.text));
            declared.push(Param {
                name: name.clone(),
                value: rest.literal.clone(),
                unit: rest_unit,
                doc: format!("`{}`: rest value.", force.name.text),
            });
            elastic.rest = Some(name);
        }
    }
    if !errors.is_empty() {
        return Err(Errors::new(file.clone(), errors));
    }
    for (j, joint) in robot.joints.iter().enumerate() {
        let Some(damping) = joint.damping.as_ref().filter(|d| d.value != 0.0) else {
            continue;
        };
        let unit = match kinds[j] {
            Kind::Pin => units.torsional_damping(),
            Kind::Slider => units.linear_damping(),
            _ => {
                warnings.push(
                    Diagnostic::warning(
                        "U0605",
                        format!(
                            "the damping of joint `{}` is not translated",
                            joint.name.text
                        ),
                    )
                    .with_label(
                        damping.span,
                        format!(
                            "`.mech` damping acts on pins and sliders, not on a {} joint",
                            kinds[j].keyword()
                        ),
                    ),
                );
                untranslated.push(format!(
                    "joint `{}`: damping {}",
                    joint.name.text, damping.literal
                ));
                continue;
            }
        };
        let name = params.take(&format!("{}_damping", joint.name.text));
        declared.push(Param {
            name: name.clone(),
            value: damping.literal.clone(),
            unit,
            doc: format!("Joint `{}`: `<dynamics damping>`.", joint.name.text),
        });
        joint_elastic[j].damping = Some(name);
    }
    if !fixed_root && !robot.loops.is_empty() {
        warnings.push(
            Diagnostic::warning("U0607", "loop closures in a model with a free joint are not supported by `mech` yet")
                .with_label(robot.loops[0].span, "the first of the closures")
                .with_help("`mech check` rejects the imported model (E0416) until it is; `--base fixed` holds the root link still"),
        );
    }

    // ------------------------------------------------------------ what is not translated
    let mut skipped_notes = Vec::new();
    for kind in [SkippedKind::Display, SkippedKind::Limit, SkippedKind::Other] {
        let items: Vec<_> = robot.skipped.iter().filter(|s| s.kind == kind).collect();
        let Some(first) = items.first() else { continue };
        let (what, why) = match kind {
            SkippedKind::Display => ("visual and material elements", "display only, not dynamics"),
            SkippedKind::Limit => ("joint limits", "`.mech` joints have no limits"),
            SkippedKind::Other => ("elements", "`mech import urdf` has no translation for them"),
        };
        let mut warning = Diagnostic::warning(
            "U0608",
            format!("{} {what} not translated: {why}", items.len()),
        )
        .with_label(first.span, "the first of them");
        if kind != SkippedKind::Display {
            warning =
                warning.with_note("each is listed as a comment at its link or joint in the output");
        }
        warnings.push(warning);
        skipped_notes.push(format!("{} {what} ({why})", items.len()));
    }
    if !robot.transmissions.is_empty() {
        warnings.push(
            Diagnostic::warning("U0609", format!("{} transmissions not translated", robot.transmissions.len()))
                .with_label(robot.transmissions[0].span, "the first of them")
                .with_help("drive the joints with an `input` and an `actuator` (sliders) or a `torque`, written by hand; the transmissions are listed as comments at the end of the output"),
        );
        skipped_notes.push(format!(
            "{} transmissions (listed at the end)",
            robot.transmissions.len()
        ));
    }
    if let Some(&first) = robot.commas.first() {
        warnings.push(
            Diagnostic::warning(
                "U0610",
                format!(
                    "{} attributes separate their numbers with commas; read as spaces",
                    robot.commas.len()
                ),
            )
            .with_label(first, "the first of them")
            .with_help("URDF separates numbers with spaces; other readers may reject commas"),
        );
    }
    skipped_notes.extend(untranslated);

    // ------------------------------------------------------------ text
    let mut out = String::new();
    let shown = file.path.rsplit('/').next().unwrap_or(&file.path);
    let _ = writeln!(
        out,
        "//! Imported from `{shown}` (robot `{}`) by `mech import urdf`.",
        robot.name
    );
    let _ = writeln!(
        out,
        "//! The URDF's numbers are read in {}, {}, {} (length, mass, time: --length, --mass, --time).",
        units.length, units.mass, units.time
    );
    let root_name = &robot.links[root].name.text;
    if fixed_root {
        let _ = writeln!(out, "//! The root link `{root_name}` is the Newtonian frame, held fixed (`--base floating` puts it on a free joint).");
    } else {
        let _ = writeln!(out, "//! The root link `{root_name}` is a body on the free joint `{root_name}_base` (`--base floating`).");
    }
    let _ = writeln!(
        out,
        "//! Gravity: a URDF gives none; 9.81 m/s^2 along -z, as Drake and ROS assume."
    );
    if options.snap && !snap_notes.is_empty() {
        let _ = writeln!(out, "//! --snap: loop points that miss each other at the zero pose by round-off were moved:");
        for note in &snap_notes {
            let _ = writeln!(out, "//! - {note}.");
        }
    }
    if !skipped_notes.is_empty() {
        let _ = writeln!(out, "//! Not translated (also reported as warnings):");
        for note in &skipped_notes {
            let _ = writeln!(out, "//! - {note}.");
        }
    }
    let model_name = Identifiers::default().take(&robot.name);
    let _ = writeln!(out, "model {model_name};\n");
    let _ = writeln!(out, "gravity = [0, 0, -9.81 m/s^2];\n");

    if !declared.is_empty() {
        let _ = writeln!(out, "// ---------------------------------------------------------------- springs and dampers\n");
        for param in &declared {
            let _ = writeln!(
                out,
                "/// {}\nparam {} = {} {};",
                param.doc, param.name, param.value, param.unit
            );
        }
        out.push('\n');
    }

    // Points and frames each body needs: collision origins, spring ends, frames of rotated
    // joint origins (on the parent), loop interframes.
    let mut members: Vec<Vec<String>> = vec![Vec::new(); robot.links.len()];
    let length = units.length;
    for (i, link) in robot.links.iter().enumerate() {
        let mut points = Identifiers::default();
        for collision in &link.collisions {
            let name = points.take(collision.name.as_deref().unwrap_or("collision"));
            members[i].push(format!(
                "/// Collision origin ({}).\npoint {name} = {};",
                collision.geometry,
                vector(&collision.origin.xyz, length)
            ));
            if collision.origin.is_rotated() {
                members[i].push(format!(
                    "// The collision frame's rpy {} is not used: a point has no orientation.",
                    literals(&collision.origin.rpy)
                ));
            }
        }
    }
    for (link, ident, point, element) in &spring_points {
        members[*link].push(format!(
            "/// End of spring `{element}`.\npoint {ident} = {};",
            vector(point, length)
        ));
    }
    let mut joint_frames: Vec<Option<String>> = vec![None; robot.joints.len()];
    for (j, joint) in robot.joints.iter().enumerate() {
        if joint.origin.is_rotated() {
            let (parent, _) = ends[j].unwrap_or((root, root));
            let name = format!("{}_origin", joint_ident[j]);
            members[parent].push(format!(
                "/// Joint `{}`'s origin rpy.\nframe {name} = {};",
                joint.name.text,
                rotate(&joint.origin.rpy)
            ));
            joint_frames[j] = Some(format!("{}.{name}", body_ident[parent]));
        }
    }
    let mut loop_frames: Vec<[Option<String>; 2]> = vec![[None, None]; robot.loops.len()];
    for (l, closure) in robot.loops.iter().enumerate() {
        let Some(c) = &closures[l] else { continue };
        for (side, (link, pose)) in [(c.link1, &closure.pose1), (c.link2, &closure.pose2)]
            .into_iter()
            .enumerate()
        {
            if pose.is_rotated() {
                let name = format!("{}_link{}", c.ident, side + 1);
                members[link].push(format!(
                    "/// Loop joint `{}`'s frame on this link.\nframe {name} = {};",
                    closure.name.text,
                    rotate(&pose.rpy)
                ));
                loop_frames[l][side] = Some(format!("{}.{name}", body_ident[link]));
            }
        }
    }

    if fixed_root {
        let _ = writeln!(out, "// ---------------------------------------------------------------- root link `{root_name}`");
        if let Some(inertial) = &robot.links[root].inertial {
            let _ = writeln!(
                out,
                "// Held fixed, so its inertia does not enter the equations: mass {} {}, com {}, inertia {} * 1 {}.",
                inertial.mass.literal,
                units.mass,
                vector(&inertial.origin.xyz, length),
                literals(&inertial.inertia),
                units.inertia()
            );
        }
        if !members[root].is_empty() {
            let _ = writeln!(out, "newtonian {{");
            for member in &members[root] {
                let _ = writeln!(out, "{}", indent(member));
            }
            let _ = writeln!(out, "}}");
        }
        out.push('\n');
    }

    let _ = writeln!(
        out,
        "// ---------------------------------------------------------------- links"
    );
    let _ = writeln!(out, "// Mass, centre of mass (link frame) and inertia about it (link axes, tensor convention).\n");
    for &i in &order {
        if i == root && fixed_root {
            continue;
        }
        let link = &robot.links[i];
        let _ = writeln!(
            out,
            "/// URDF link `{}`, line {}.",
            link.name.text,
            file.line_col(link.span.start).0
        );
        let _ = writeln!(out, "body {} {{", body_ident[i]);
        match &link.inertial {
            Some(inertial) => {
                let _ = writeln!(out, "    mass = {} {};", inertial.mass.literal, units.mass);
                if values(&inertial.origin.xyz) != [0.0; 3] {
                    let _ = writeln!(out, "    com = {};", vector(&inertial.origin.xyz, length));
                }
                let tensor = if inertial.origin.is_rotated() {
                    let _ = writeln!(
                        out,
                        "    // The inertial frame's rpy {} turned into link axes.",
                        literals(&inertial.origin.rpy)
                    );
                    rotated_inertia(&inertial.inertia, &rotation(&inertial.origin))
                } else {
                    literals(&inertial.inertia)
                };
                let _ = writeln!(out, "    inertia = {tensor} * 1 {};", units.inertia());
            }
            None => {
                let _ = writeln!(
                    out,
                    "    mass = 0 {}; // no <inertial>: massless",
                    units.mass
                );
            }
        }
        for member in &members[i] {
            let _ = writeln!(out, "{}", indent(member));
        }
        let _ = writeln!(out, "}}\n");
    }

    let _ = writeln!(
        out,
        "// ---------------------------------------------------------------- joints\n"
    );
    if !fixed_root {
        let base = frames.take(&format!("{root_name}_base"));
        let _ = writeln!(out, "/// The root link's six degrees of freedom (--base floating).\njoint {base} = free(newtonian, {});\n", body_ident[root]);
    }
    // Joints in the order of the tree (parents first), siblings in the file's order, as
    // `.mech` orders coordinates.
    for &c in order.iter().skip(1) {
        let Some(j) = parent_joint[c] else { continue };
        let joint = &robot.joints[j];
        let (parent, child) = ends[j].unwrap_or((root, c));
        let _ = writeln!(
            out,
            "/// URDF joint `{}` ({}), line {}.",
            joint.name.text,
            joint.kind.text,
            file.line_col(joint.span.start).0
        );
        for skipped in robot
            .skipped
            .iter()
            .filter(|s| s.owner == joint.name.text && s.kind != SkippedKind::Display)
        {
            let _ = writeln!(out, "// Not translated: {}", skipped.what);
        }
        let mut fields = Vec::new();
        if matches!(kinds[j], Kind::Pin | Kind::Slider) {
            fields.push(format!("axis = {};", axis(&joint.axis)));
        }
        if values(&joint.origin.xyz) != [0.0; 3] {
            fields.push(format!(
                "parent_point = {};",
                vector(&joint.origin.xyz, length)
            ));
        }
        if let Some(frame) = &joint_frames[j] {
            fields.push(format!("parent_frame = {frame};"));
        }
        let elastic = &joint_elastic[j];
        if let Some(k) = &elastic.stiffness {
            fields.push(format!("stiffness = {k};"));
        }
        if let Some(rest) = &elastic.rest {
            fields.push(format!("rest = {rest};"));
        }
        if let Some(c) = &elastic.damping {
            fields.push(format!("damping = {c};"));
        }
        let head = format!(
            "joint {} = {}({}, {})",
            joint_ident[j],
            kinds[j].keyword(),
            body_ident[parent],
            body_ident[child]
        );
        if fields.is_empty() {
            let _ = writeln!(out, "{head};\n");
        } else {
            let _ = writeln!(out, "{head} {{");
            for field in fields {
                let _ = writeln!(out, "    {field}");
            }
            let _ = writeln!(out, "}}\n");
        }
    }

    if !robot.loops.is_empty() {
        let _ = writeln!(out, "// ---------------------------------------------------------------- loop closures (Drake loop_joint)\n");
    }
    for (l, closure) in robot.loops.iter().enumerate() {
        let line = file.line_col(closure.span.start).0;
        let Some(c) = &closures[l] else {
            let _ = writeln!(
                out,
                "// Not translated: loop_joint `{}` of type `{}`, line {line}.\n",
                closure.name.text, closure.kind.text
            );
            continue;
        };
        let _ = writeln!(
            out,
            "/// Drake loop_joint `{}` ({}), line {line}.",
            closure.name.text, closure.kind.text
        );
        if c.snapped.is_some() {
            let _ = writeln!(out, "/// Its points were moved by --snap (see the header).");
        }
        for skipped in robot
            .skipped
            .iter()
            .filter(|s| s.owner == closure.name.text)
        {
            let _ = writeln!(out, "// Not translated: {}", skipped.what);
        }
        let kind = if c.revolute { "revolute" } else { "coincident" };
        let _ = writeln!(
            out,
            "loop {} = {kind}({}, {}) {{",
            c.ident, body_ident[c.link1], body_ident[c.link2]
        );
        if c.revolute {
            let _ = writeln!(out, "    axis = {};", axis(&closure.axis));
        }
        let _ = writeln!(
            out,
            "    parent_point = {};",
            vector(&closure.pose1.xyz, length)
        );
        let _ = writeln!(
            out,
            "    child_point = {};",
            vector(&closure.pose2.xyz, length)
        );
        if c.revolute {
            for (field, frame) in ["parent_frame", "child_frame"].iter().zip(&loop_frames[l]) {
                if let Some(frame) = frame {
                    let _ = writeln!(out, "    {field} = {frame};");
                }
            }
            let elastic = &loop_elastic[l];
            for (field, value) in [("stiffness", &elastic.stiffness), ("rest", &elastic.rest)] {
                if let Some(value) = value {
                    let _ = writeln!(out, "    {field} = {value};");
                }
            }
        }
        let _ = writeln!(out, "}}\n");
    }

    if !springs.is_empty() {
        let _ = writeln!(out, "// ---------------------------------------------------------------- springs between points\n");
        for spring in &springs {
            let _ = writeln!(out, "{spring}");
        }
    }

    if !robot.transmissions.is_empty() {
        let _ = writeln!(out, "// ---------------------------------------------------------------- transmissions (not translated)");
        for t in &robot.transmissions {
            let _ = writeln!(
                out,
                "// `{}` ({}), line {}: actuator {} drives joint {}, mechanical reduction {}.",
                t.name,
                t.kind,
                file.line_col(t.span.start).0,
                t.actuators.join(", "),
                t.joints.join(", "),
                t.reduction.as_deref().unwrap_or("not given")
            );
        }
        out.push('\n');
    }

    let _ = writeln!(
        out,
        "// ---------------------------------------------------------------- outputs\n"
    );
    for (i, link) in robot.links.iter().enumerate() {
        if i == root && fixed_root {
            continue;
        }
        let mut names = Identifiers::default();
        for collision in &link.collisions {
            let point = names.take(collision.name.as_deref().unwrap_or("collision"));
            let output = params.take(&format!("{}_{point}", link.name.text));
            let _ = writeln!(out, "/// Collision origin of `{}` in the root frame.\noutput {output} = position({}.{point}) in newtonian;", link.name.text, body_ident[i]);
        }
    }
    let _ = writeln!(
        out,
        "output ke = kinetic_energy;\noutput pe = potential_energy;"
    );

    let bodies = robot.links.len() - usize::from(fixed_root);
    Ok(Import {
        file: file.clone(),
        text: out,
        warnings,
        bodies,
        joints: robot.joints.len() + usize::from(!fixed_root),
        loops: closures.iter().flatten().count(),
    })
}

/// `body.point`, or `newtonian.point` for the fixed root.
fn point_of(body: &str, point: &str) -> String {
    format!("{body}.{point}")
}

/// Names for a help line: the first ten, then how many more.
fn listing(names: &[&str]) -> String {
    const SHOWN: usize = 10;
    let mut text = names
        .iter()
        .take(SHOWN)
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > SHOWN {
        text.push_str(&format!(" and {} more", names.len() - SHOWN));
    }
    text
}

/// Digits after the decimal point of a literal written without an exponent (0 otherwise).
fn decimals(literal: &str) -> usize {
    match literal.split_once('.') {
        Some((_, fraction)) if !fraction.contains(['e', 'E']) => fraction.len(),
        _ => 0,
    }
}

/// `value` rounded to `places` decimals, trailing zeros dropped: a computed position printed
/// at the file's own resolution.
fn decimal(value: f64, span: Span, places: usize) -> Num {
    let text = format!("{value:.places$}");
    let text = if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    };
    let text = if text == "-0" { "0".to_string() } else { text };
    Num {
        value: text.parse().unwrap_or(value),
        literal: text,
        span,
    }
}

fn duplicate(what: &str, name: &Name, first: Span) -> Diagnostic {
    Diagnostic::error("U0203", format!("two {what}s are named `{}`", name.text))
        .with_label(name.span, "second")
        .with_label(first, "first")
        .with_help(format!("{what} names must be unique; rename one"))
}

fn values(numbers: &[Num; 3]) -> Vec3 {
    [numbers[0].value, numbers[1].value, numbers[2].value]
}

fn rotation(pose: &Pose) -> pose::Mat3 {
    pose::rpy_matrix(values(&pose.rpy))
}

fn literals(numbers: &[Num]) -> String {
    let items: Vec<&str> = numbers.iter().map(|n| n.literal.as_str()).collect();
    format!("[{}]", items.join(", "))
}

/// `[x, y, z] * 1 mm`, or `[0, 0, 0]`.
fn vector(numbers: &[Num; 3], unit: &str) -> String {
    if values(numbers) == [0.0; 3] {
        "[0, 0, 0]".to_string()
    } else {
        format!("{} * 1 {unit}", literals(numbers))
    }
}

/// `x`, `-z`, or `[ax, ay, az]` (normalized by `.mech`).
fn axis(numbers: &[Num; 3]) -> String {
    let v = values(numbers);
    let nonzero: Vec<usize> = (0..3).filter(|&i| v[i] != 0.0).collect();
    match nonzero[..] {
        [i] => format!(
            "{}{}",
            if v[i] < 0.0 { "-" } else { "" },
            ["x", "y", "z"][i]
        ),
        _ => literals(numbers),
    }
}

/// URDF rpy as `.mech` body-fixed rotations: `Rz(yaw) Ry(pitch) Rx(roll)` is yaw about z,
/// then pitch about the new y, then roll about the newest x.
fn rotate(rpy: &[Num; 3]) -> String {
    let factors: Vec<String> = [(2, "z"), (1, "y"), (0, "x")]
        .iter()
        .filter(|(i, _)| rpy[*i].value != 0.0)
        .map(|(i, axis)| format!("rotate({axis}, {})", rpy[*i].literal))
        .collect();
    factors.join(" * ")
}

/// The inertia tensor of an inertial frame turned by `r` into link axes, `R I Rᵀ`, as
/// `[ixx, iyy, izz, ixy, iyz, ixz]`.
fn rotated_inertia(entries: &[Num; 6], r: &pose::Mat3) -> String {
    let [ixx, iyy, izz, ixy, iyz, ixz] = [0, 1, 2, 3, 4, 5].map(|i| entries[i].value);
    let tensor = [[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]];
    let turned = pose::mul(&pose::mul(r, &tensor), &pose::transpose(r));
    let items = [
        turned[0][0],
        turned[1][1],
        turned[2][2],
        turned[0][1],
        turned[1][2],
        turned[0][2],
    ];
    // Entries that are round-off of the rotation (a product of 6e-17 after a quarter turn)
    // are zero.
    let largest = items.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let items = items.map(|v| {
        if v.abs() <= 8.0 * f64::EPSILON * largest {
            0.0
        } else {
            v
        }
    });
    format!("[{}]", items.map(float_literal).join(", "))
}

fn indent(member: &str) -> String {
    member
        .lines()
        .map(|l| format!("    {l}"))
        .collect::<Vec<_>>()
        .join("\n")
}
