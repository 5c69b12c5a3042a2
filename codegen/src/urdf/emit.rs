//! From a read URDF [`Robot`] to `.mech` text, in phases of a [`Translation`]: the tree
//! (`tree.rs`), joint kinds, loop closures, their misses at the zero pose and `--snap`, force
//! elements and dampers, what is not translated, and the text, written with the user's units.
//!
//! Consumes: a [`Robot`] and the [`Options`]. Produces: an [`Import`] (the text, the warnings
//! as spanned diagnostics) or [`Errors`] for names that do not resolve and structures that
//! are not a tree. The output depends only on the input and the options (no maps are
//! iterated), so importing twice gives the same bytes.

use std::fmt::Write;
use std::sync::Arc;

use super::options::{Base, Import, Options};
use super::pose::{self, Axis, Vec3};
use super::read::{float_literal, ForceKind, LinearSpring, LoopJoint, Num, Robot, SkippedKind};
use super::tree::{listing, rotation, values, Tree};
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
    /// No `.mech` kind: two sliders in the plane and a pin about its normal (the URDF
    /// axis), through two massless bodies.
    Planar,
}

impl Kind {
    fn keyword(self) -> &'static str {
        match self {
            Kind::Pin => "pin",
            Kind::Slider => "slider",
            Kind::Weld => "weld",
            Kind::Ball => "ball",
            Kind::Free => "free",
            Kind::Planar => "planar",
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

pub fn emit(file: &Arc<SourceFile>, robot: &Robot, options: &Options) -> Result<Import, Errors> {
    let mut warnings = Vec::new();
    let tree = Tree::build(file, robot, &mut warnings)?;
    let mut translation = Translation::new(file, robot, options, tree, warnings);
    translation.joint_kinds();
    translation.loop_closures();
    translation.stop_on_errors()?;
    translation.loop_misses();
    translation.force_elements();
    translation.stop_on_errors()?;
    translation.joint_dampers();
    translation.not_translated();
    Ok(translation.finish())
}

/// A `loop_joint` that is translated.
struct Closure {
    ident: String,
    /// `revolute` (continuous, revolute) or `coincident` (ball).
    revolute: bool,
    link1: usize,
    link2: usize,
    /// The points on `link1` and `link2` as written, or as `--snap` moved them.
    points: [[Num; 3]; 2],
    snapped: bool,
}

/// An end of a point-to-point spring: a point declared on its body.
struct SpringEnd {
    link: usize,
    /// The spring's identifier, also the point's name.
    ident: String,
    point: [Num; 3],
    element: String,
}

/// The state of one translation, filled phase by phase.
struct Translation<'a> {
    file: &'a Arc<SourceFile>,
    robot: &'a Robot,
    options: &'a Options,
    units: Units<'a>,
    fixed_root: bool,
    tree: Tree,
    errors: Vec<Diagnostic>,
    warnings: Vec<Diagnostic>,
    /// Bodies, joints and loops share one `.mech` namespace.
    frames: Identifiers,
    /// Parameters and outputs.
    params: Identifiers,
    /// Each link's `.mech` name (`newtonian` for a fixed root).
    body_ident: Vec<String>,
    joint_ident: Vec<String>,
    kinds: Vec<Kind>,
    /// One per `loop_joint`, `None` where its type is not translated.
    closures: Vec<Option<Closure>>,
    snap_notes: Vec<String>,
    joint_elastic: Vec<Elastic>,
    loop_elastic: Vec<Elastic>,
    declared: Vec<Param>,
    springs: Vec<String>,
    spring_ends: Vec<SpringEnd>,
    /// The header's list of what is not translated.
    notes: Vec<String>,
}

impl<'a> Translation<'a> {
    fn new(
        file: &'a Arc<SourceFile>,
        robot: &'a Robot,
        options: &'a Options,
        tree: Tree,
        warnings: Vec<Diagnostic>,
    ) -> Translation<'a> {
        let fixed_root = options.base == Base::Fixed;
        let mut frames = Identifiers::default();
        let body_ident = robot
            .links
            .iter()
            .enumerate()
            .map(|(i, link)| match i == tree.root && fixed_root {
                true => "newtonian".to_string(),
                false => frames.take(&link.name.text),
            })
            .collect();
        let joint_ident = robot
            .joints
            .iter()
            .map(|j| frames.take(&j.name.text))
            .collect();
        Translation {
            file,
            robot,
            options,
            units: Units {
                length: &options.units.length,
                mass: &options.units.mass,
                time: &options.units.time,
            },
            fixed_root,
            tree,
            errors: Vec::new(),
            warnings,
            frames,
            params: Identifiers::default(),
            body_ident,
            joint_ident,
            kinds: Vec::new(),
            closures: Vec::new(),
            snap_notes: Vec::new(),
            joint_elastic: vec![Elastic::default(); robot.joints.len()],
            loop_elastic: vec![Elastic::default(); robot.loops.len()],
            declared: Vec::new(),
            springs: Vec::new(),
            spring_ends: Vec::new(),
            notes: Vec::new(),
        }
    }

    fn stop_on_errors(&mut self) -> Result<(), Errors> {
        match self.errors.is_empty() {
            true => Ok(()),
            false => Err(Errors::new(
                self.file.clone(),
                std::mem::take(&mut self.errors),
            )),
        }
    }

    fn joint_kinds(&mut self) {
        for joint in &self.robot.joints {
            let kind = match joint.kind.text.as_str() {
                "revolute" | "continuous" => Kind::Pin,
                "prismatic" => Kind::Slider,
                "fixed" | "Fixed" => Kind::Weld,
                "floating" => Kind::Free,
                "ball" | "spherical" => Kind::Ball,
                "planar" => Kind::Planar,
                other => {
                    self.errors.push(
                        Diagnostic::error("U0204", format!("unknown joint type `{other}`"))
                            .with_label(joint.kind.span, "not a URDF joint type")
                            .with_help("URDF joint types: revolute, continuous, prismatic, fixed, floating, planar"),
                    );
                    Kind::Weld
                }
            };
            if matches!(kind, Kind::Pin | Kind::Slider | Kind::Planar)
                && values(&joint.axis) == [0.0; 3]
            {
                self.errors.push(
                    Diagnostic::error(
                        "U0303",
                        format!("joint `{}` has a zero axis", joint.name.text),
                    )
                    .with_label(joint.axis[0].span, "axis `0 0 0`")
                    .with_help(
                        "a revolute, prismatic or planar joint needs a nonzero `<axis xyz=\"...\"/>`",
                    ),
                );
            }
            self.kinds.push(kind);
        }
    }

    fn loop_closures(&mut self) {
        for closure in &self.robot.loops {
            let links = &self.tree.links;
            let first = links.resolve(&closure.link1, &mut self.errors, &mut self.warnings);
            let second = links.resolve(&closure.link2, &mut self.errors, &mut self.warnings);
            let revolute = match closure.kind.text.as_str() {
                "continuous" | "revolute" => true,
                "ball" | "spherical" => false,
                other => {
                    self.warnings.push(
                        Diagnostic::warning("U0603", format!("loop_joint `{}` of type `{other}` is not translated", closure.name.text))
                            .with_label(closure.kind.span, "`.mech` closes loops with revolute (continuous) and coincident (ball) closures")
                            .with_help("write the closure by hand: `loop NAME = coincident(...)` with the components it fixes"),
                    );
                    self.closures.push(None);
                    continue;
                }
            };
            let ident = self.frames.take(&closure.name.text);
            self.closures
                .push(first.zip(second).map(|(link1, link2)| Closure {
                    ident,
                    revolute,
                    link1,
                    link2,
                    points: [closure.pose1.xyz.clone(), closure.pose2.xyz.clone()],
                    snapped: false,
                }));
        }
    }

    /// Hinge axes at the zero pose (revolute joints and revolute loop joints), for snapping,
    /// each with the links it joins below the root (a joint's child twice; a loop joint's
    /// `link1` and `link2`).
    fn hinge_axes(&self) -> Vec<(Axis, [usize; 2])> {
        let world = &self.tree.world;
        let mut axes = Vec::new();
        for ((joint, &(_, child)), kind) in self
            .robot
            .joints
            .iter()
            .zip(&self.tree.ends)
            .zip(&self.kinds)
        {
            if let (Kind::Pin, Some(direction)) = (kind, pose::unit(values(&joint.axis))) {
                let axis = Axis {
                    name: joint.name.text.clone(),
                    point: world[child].origin,
                    direction: world[child].direction(direction),
                };
                axes.push((axis, [child, child]));
            }
        }
        for (closure, c) in self.robot.loops.iter().zip(&self.closures) {
            if let (Some(c), Some(direction)) = (c, pose::unit(values(&closure.axis))) {
                if c.revolute {
                    let frame =
                        world[c.link1].then(values(&closure.pose1.xyz), &rotation(&closure.pose1));
                    let axis = Axis {
                        name: closure.name.text.clone(),
                        point: frame.origin,
                        direction: frame.direction(direction),
                    };
                    axes.push((axis, [c.link1, c.link2]));
                }
            }
        }
        axes
    }

    /// Warns of loop points that miss each other at the zero pose, with the numbers and the
    /// `--snap` fix; applies it with `--snap`.
    fn loop_misses(&mut self) {
        let axes = self.hinge_axes();
        let size = self.tree.size;
        // Snapped coordinates are printed to the decimals the file's positions are written
        // with (more would be round-off of the arithmetic); those that move by less than a
        // thousandth of a reported miss keep their literal.
        let resolution = self
            .robot
            .joints
            .iter()
            .flat_map(|j| j.origin.xyz.iter())
            .chain(
                self.robot
                    .loops
                    .iter()
                    .flat_map(|l| l.pose1.xyz.iter().chain(&l.pose2.xyz)),
            )
            .map(|n| decimals(&n.literal))
            .max()
            .unwrap_or(0)
            .max(3);
        let unmoved = 1e-3 * MISS_FRACTION * size;
        let length = self.units.length;
        for (closure, c) in self.robot.loops.iter().zip(self.closures.iter_mut()) {
            let Some(c) = c.as_mut() else { continue };
            let world = &self.tree.world;
            let first = world[c.link1].point(values(&closure.pose1.xyz));
            let second = world[c.link2].point(values(&closure.pose2.xyz));
            let miss = pose::miss(first, second);
            if miss.distance <= MISS_FRACTION * size {
                continue;
            }
            let gap = miss.gap.map(|g| format!("{g:.3e}")).join(", ");
            let warning = Diagnostic::warning(
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
            if miss.distance > SNAP_FRACTION * size {
                self.warnings.push(warning.with_help("the closure does not hold at the zero pose: check the loop points (--snap only fixes misses of round-off size)"));
                continue;
            }
            let fix = if c.revolute {
                let direction = pose::unit(values(&closure.axis)).unwrap_or([1.0, 0.0, 0.0]);
                let direction = world[c.link1]
                    .then(values(&closure.pose1.xyz), &rotation(&closure.pose1))
                    .direction(direction);
                // The hinges of the mechanism the closure belongs to: those below the same
                // children of the root (one leg of a robot, not the axes of the other legs
                // that happen to cross this one).
                let branches = [self.tree.branch(c.link1), self.tree.branch(c.link2)];
                let others: Vec<Axis> = axes
                    .iter()
                    .filter(|(a, links)| {
                        let root = self.tree.root;
                        let mine = |link: &usize| {
                            *link != root && branches.contains(&self.tree.branch(*link))
                        };
                        a.name != closure.name.text && links.iter().any(mine)
                    })
                    .map(|(a, _)| a.clone())
                    .collect();
                let tolerance = (CROSSING_FACTOR * miss.distance).max(MISS_FRACTION * size);
                pose::snap(direction, first, second, &others, tolerance)
            } else {
                let midpoint = pose::scale(pose::add(first, second), 0.5);
                pose::Snap {
                    centre: midpoint,
                    through: Vec::new(),
                    first: midpoint,
                    second: midpoint,
                }
            };
            let moved_to = [
                world[c.link1].local(fix.first),
                world[c.link2].local(fix.second),
            ];
            let mut moves = Vec::new();
            for (side, (link, new)) in [&closure.link1, &closure.link2]
                .into_iter()
                .zip(moved_to)
                .enumerate()
            {
                for ((axis, old), new) in ["x", "y", "z"].iter().zip(&c.points[side]).zip(new) {
                    if (old.value - new).abs() > unmoved {
                        let new = decimal(new, old.span, resolution).literal;
                        moves.push(format!(
                            "link{} ({}) {axis} {} -> {new}",
                            side + 1,
                            link.text,
                            old.literal
                        ));
                    }
                }
            }
            let centre = fix
                .centre
                .map(|v| decimal(v, closure.span, resolution).literal)
                .join(", ");
            let how = match fix.through.is_empty() {
                true => format!("both points to their midpoint [{centre}] {length}"),
                false => format!(
                    "both points onto the `{}` axis through [{centre}] {length}, where the axes of {} meet it",
                    closure.name.text,
                    fix.through.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
                ),
            };
            let summary = format!("{how}: {}", moves.join(", "));
            if !self.options.snap {
                self.warnings
                    .push(warning.with_help(format!("--snap moves {summary}")));
                continue;
            }
            self.warnings
                .push(warning.with_note(format!("--snap moved {summary}")));
            self.snap_notes.push(format!(
                "loop_joint `{}`: moved {summary}",
                closure.name.text
            ));
            for (points, new) in c.points.iter_mut().zip(moved_to) {
                for (num, value) in points.iter_mut().zip(new) {
                    if (num.value - value).abs() > unmoved {
                        *num = decimal(value, num.span, resolution);
                    }
                }
            }
            c.snapped = true;
        }
    }

    /// Drake force elements: joint and loop springs as parameters on their joints, point
    /// springs as `spring` declarations.
    fn force_elements(&mut self) {
        let robot = self.robot;
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
                    self.point_spring(&force.name.text, force.span, spring);
                    continue;
                }
            };
            let target_joint = self.tree.joint_index.get(&joint.text).copied();
            let target_loop = robot.loops.iter().position(|l| l.name.text == joint.text);
            let fits = match (target_joint, target_loop) {
                (Some(j), _) => {
                    (torsional && self.kinds[j] == Kind::Pin)
                        || (!torsional && self.kinds[j] == Kind::Slider)
                }
                (None, Some(l)) => {
                    torsional && self.closures[l].as_ref().is_some_and(|c| c.revolute)
                }
                (None, None) => {
                    let mut candidates: Vec<&str> =
                        robot.joints.iter().map(|j| j.name.text.as_str()).collect();
                    candidates.extend(robot.loops.iter().map(|l| l.name.text.as_str()));
                    let error =
                        Diagnostic::error("U0202", format!("unknown joint `{}`", joint.text))
                            .with_label(
                                joint.span,
                                format!(
                                    "force_element `{}` acts on no joint of this name",
                                    force.name.text
                                ),
                            );
                    self.errors.push(error.with_help(
                        match diag::closest(&joint.text, &candidates) {
                            Some(close) => format!("did you mean `{close}`?"),
                            None => format!(
                                "the joints and loop joints of this file: {}",
                                listing(&candidates)
                            ),
                        },
                    ));
                    continue;
                }
            };
            let elastic = match (target_joint, target_loop) {
                (Some(j), _) => &mut self.joint_elastic[j],
                (None, Some(l)) => &mut self.loop_elastic[l],
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
                self.warnings.push(
                    Diagnostic::warning(
                        "U0605",
                        format!(
                            "force_element `{}` is not translated: {why}",
                            force.name.text
                        ),
                    )
                    .with_label(force.span, "listed as a comment in the output"),
                );
                self.notes.push(format!(
                    "force_element `{}` on `{}`: {why}",
                    force.name.text, joint.text
                ));
                continue;
            }
            let ident = self.params.take(&force.name.text);
            let (unit, rest_unit, what) = match torsional {
                true => (
                    self.units.torsional_stiffness(),
                    "rad".to_string(),
                    "torsional_spring",
                ),
                false => (
                    self.units.linear_stiffness(),
                    self.units.length.to_string(),
                    "prismatic_spring",
                ),
            };
            self.declared.push(Param {
                name: ident.clone(),
                value: stiffness.literal.clone(),
                unit,
                doc: format!("`{}`: Drake {what} on `{}`.", force.name.text, joint.text),
            });
            elastic.stiffness = Some(ident);
            if let Some(rest) = rest.as_ref().filter(|r| r.value != 0.0) {
                let name = self.params.take(&format!("{}_rest", force.name.text));
                self.declared.push(Param {
                    name: name.clone(),
                    value: rest.literal.clone(),
                    unit: rest_unit,
                    doc: format!("`{}`: rest value.", force.name.text),
                });
                elastic.rest = Some(name);
            }
        }
    }

    /// A `linear_spring_damper` as a `spring` between points declared on its two bodies.
    fn point_spring(&mut self, element: &str, span: Span, spring: &LinearSpring) {
        let links = &self.tree.links;
        let a = links.resolve(&spring.link1, &mut self.errors, &mut self.warnings);
        let b = links.resolve(&spring.link2, &mut self.errors, &mut self.warnings);
        let (Some(a), Some(b)) = (a, b) else { return };
        if a == b {
            self.warnings.push(
                Diagnostic::warning(
                    "U0605",
                    format!(
                        "force_element `{element}` joins two points of one link: not translated"
                    ),
                )
                .with_label(span, "its length never changes"),
            );
            self.notes.push(format!(
                "force_element `{element}`: a spring between two points of one link"
            ));
            return;
        }
        let world = &self.tree.world;
        let length = pose::norm(pose::sub(
            world[b].point(values(&spring.point2)),
            world[a].point(values(&spring.point1)),
        ));
        if length <= MISS_FRACTION * self.tree.size {
            self.warnings.push(
                Diagnostic::warning("U0606", format!("the points of force_element `{element}` coincide at the zero pose"))
                    .with_label(span, format!("{length:.3e} {} apart", self.units.length))
                    .with_help("a `.mech` spring's direction is undefined where its length is zero (its force is NaN there); move a point or model it as a joint spring"),
            );
        }
        let ident = self.params.take(element);
        self.declared.push(Param {
            name: ident.clone(),
            value: spring.stiffness.literal.clone(),
            unit: self.units.linear_stiffness(),
            doc: format!("`{element}`: Drake linear_spring_damper stiffness."),
        });
        let mut fields = vec![format!("stiffness = {ident};")];
        if let Some(rest) = &spring.rest_length {
            let name = self.params.take(&format!("{element}_rest_length"));
            self.declared.push(Param {
                name: name.clone(),
                value: rest.literal.clone(),
                unit: self.units.length.to_string(),
                doc: format!("`{element}`: rest length."),
            });
            fields.push(format!("rest_length = {name};"));
        }
        if let Some(damping) = spring.damping.as_ref().filter(|d| d.value != 0.0) {
            let name = self.params.take(&format!("{element}_damping"));
            self.declared.push(Param {
                name: name.clone(),
                value: damping.literal.clone(),
                unit: self.units.linear_damping(),
                doc: format!("`{element}`: damping."),
            });
            fields.push(format!("damping = {name};"));
        }
        for (link, point) in [(a, &spring.point1), (b, &spring.point2)] {
            self.spring_ends.push(SpringEnd {
                link,
                ident: ident.clone(),
                point: point.clone(),
                element: element.to_string(),
            });
        }
        self.springs.push(format!(
            "/// Drake force_element `{element}` (linear_spring_damper), line {}.\nspring {ident} between {} and {} {{ {} }}\n",
            self.file.line_col(span.start).0,
            point_of(&self.body_ident[a], &ident),
            point_of(&self.body_ident[b], &ident),
            fields.join(" ")
        ));
    }

    /// `<dynamics damping>` of pins and sliders as parameters.
    fn joint_dampers(&mut self) {
        for (j, joint) in self.robot.joints.iter().enumerate() {
            let Some(damping) = joint.damping.as_ref().filter(|d| d.value != 0.0) else {
                continue;
            };
            let unit = match self.kinds[j] {
                Kind::Pin => self.units.torsional_damping(),
                Kind::Slider => self.units.linear_damping(),
                other => {
                    self.warnings.push(
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
                                other.keyword()
                            ),
                        ),
                    );
                    self.notes.push(format!(
                        "joint `{}`: damping {}",
                        joint.name.text, damping.literal
                    ));
                    continue;
                }
            };
            let name = self.params.take(&format!("{}_damping", joint.name.text));
            self.declared.push(Param {
                name: name.clone(),
                value: damping.literal.clone(),
                unit,
                doc: format!("Joint `{}`: `<dynamics damping>`.", joint.name.text),
            });
            self.joint_elastic[j].damping = Some(name);
        }
    }

    /// One warning per kind of element not translated, and the header's notes.
    fn not_translated(&mut self) {
        let robot = self.robot;
        let mut notes = Vec::new();
        for kind in [SkippedKind::Display, SkippedKind::Limit, SkippedKind::Other] {
            let items: Vec<_> = robot.skipped.iter().filter(|s| s.kind == kind).collect();
            let Some(first) = items.first() else { continue };
            let (what, why) = match kind {
                SkippedKind::Display => {
                    ("visual and material elements", "display only, not dynamics")
                }
                SkippedKind::Limit => ("joint limits", "`.mech` joints have no limits"),
                SkippedKind::Other => {
                    ("elements", "`mech import urdf` has no translation for them")
                }
            };
            let mut warning = Diagnostic::warning(
                "U0608",
                format!("{} {what} not translated: {why}", items.len()),
            )
            .with_label(first.span, "the first of them");
            if kind != SkippedKind::Display {
                warning = warning
                    .with_note("each is listed as a comment in the output, at its link or joint");
            }
            self.warnings.push(warning);
            notes.push(format!("{} {what} ({why})", items.len()));
        }
        if !robot.transmissions.is_empty() {
            self.warnings.push(
                Diagnostic::warning("U0609", format!("{} transmissions not translated", robot.transmissions.len()))
                    .with_label(robot.transmissions[0].span, "the first of them")
                    .with_help("drive the joints with an `input` and an `actuator` (sliders) or a `torque`, written by hand; the transmissions are listed as comments at the end of the output"),
            );
            notes.push(format!(
                "{} transmissions (listed at the end)",
                robot.transmissions.len()
            ));
        }
        if let Some(&first) = robot.commas.first() {
            self.warnings.push(
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
        notes.append(&mut self.notes);
        self.notes = notes;
    }

    fn finish(mut self) -> Import {
        let text = self.text();
        let fixed = usize::from(self.fixed_root);
        Import {
            file: self.file.clone(),
            text,
            warnings: self.warnings,
            bodies: self.robot.links.len() - fixed,
            joints: self.robot.joints.len() + 1 - fixed,
            loops: self.closures.iter().flatten().count(),
        }
    }

    /// The `.mech` model.
    fn text(&mut self) -> String {
        let mut out = String::new();
        self.write_header(&mut out);
        let members = self.members();
        self.write_root(&mut out, &members);
        self.write_bodies(&mut out, &members);
        self.write_joints(&mut out, &members);
        self.write_loops(&mut out, &members);
        self.write_tail(&mut out);
        out
    }

    fn write_header(&self, out: &mut String) {
        let (robot, file, units) = (self.robot, self.file, &self.units);
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
        let root_name = &robot.links[self.tree.root].name.text;
        if self.fixed_root {
            let _ = writeln!(out, "//! The root link `{root_name}` is the Newtonian frame, held fixed (`--base floating` puts it on a free joint).");
        } else {
            let _ = writeln!(out, "//! The root link `{root_name}` is a body on the free joint `{root_name}_base` (`--base floating`).");
        }
        let _ = writeln!(
            out,
            "//! Gravity: a URDF gives none; 9.81 m/s^2 along -z, as Drake and ROS assume."
        );
        write_header_list(
            out,
            "--snap: loop points that miss each other at the zero pose by round-off were moved:",
            &self.snap_notes,
        );
        write_header_list(
            out,
            "Not translated (also reported as warnings):",
            &self.notes,
        );
        let model_name = Identifiers::default().take(&robot.name);
        let _ = writeln!(out, "model {model_name};\n");
        let _ = writeln!(out, "gravity = [0, 0, -9.81 m/s^2];\n");
        if !self.declared.is_empty() {
            let _ = writeln!(out, "// ---------------------------------------------------------------- springs and dampers\n");
            for param in &self.declared {
                let _ = writeln!(
                    out,
                    "/// {}\nparam {} = {} {};",
                    param.doc, param.name, param.value, param.unit
                );
            }
            out.push('\n');
        }
    }

    /// The points and frames each body declares (collision origins, spring ends, frames of
    /// rotated joint origins on the parent, loop interframes), and the names of those frames.
    fn members(&self) -> Members {
        let robot = self.robot;
        let length = self.units.length;
        let mut members = Members {
            of_link: vec![Vec::new(); robot.links.len()],
            joint_frames: vec![None; robot.joints.len()],
            loop_frames: vec![[None, None]; robot.loops.len()],
        };
        for (i, link) in robot.links.iter().enumerate() {
            let mut points = Identifiers::default();
            for collision in &link.collisions {
                let name = points.take(collision.name.as_deref().unwrap_or("collision"));
                members.of_link[i].push(format!(
                    "/// Collision origin ({}).\npoint {name} = {};",
                    collision.geometry,
                    vector(&collision.origin.xyz, length)
                ));
                if collision.origin.is_rotated() {
                    members.of_link[i].push(format!(
                        "// The collision frame's rpy {} is not used: a point has no orientation.",
                        literals(&collision.origin.rpy)
                    ));
                }
            }
        }
        for end in &self.spring_ends {
            members.of_link[end.link].push(format!(
                "/// End of spring `{}`.\npoint {} = {};",
                end.element,
                end.ident,
                vector(&end.point, length)
            ));
        }
        for (j, joint) in robot.joints.iter().enumerate() {
            if joint.origin.is_rotated() {
                let (parent, _) = self.tree.ends[j];
                let name = format!("{}_origin", self.joint_ident[j]);
                members.of_link[parent].push(format!(
                    "/// Joint `{}`'s origin rpy.\nframe {name} = {};",
                    joint.name.text,
                    rotate(&joint.origin.rpy)
                ));
                members.joint_frames[j] = Some(format!("{}.{name}", self.body_ident[parent]));
            }
        }
        for (l, closure) in robot.loops.iter().enumerate() {
            let Some(c) = &self.closures[l] else { continue };
            let sides = [(c.link1, &closure.pose1), (c.link2, &closure.pose2)];
            for (side, (link, pose)) in sides.into_iter().enumerate() {
                if pose.is_rotated() {
                    let name = format!("{}_link{}", c.ident, side + 1);
                    members.of_link[link].push(format!(
                        "/// Loop joint `{}`'s frame on this link.\nframe {name} = {};",
                        closure.name.text,
                        rotate(&pose.rpy)
                    ));
                    members.loop_frames[l][side] =
                        Some(format!("{}.{name}", self.body_ident[link]));
                }
            }
        }
        members
    }

    fn write_root(&self, out: &mut String, members: &Members) {
        if !self.fixed_root {
            return;
        }
        let root = self.tree.root;
        let units = &self.units;
        let _ = writeln!(
            out,
            "// ---------------------------------------------------------------- root link `{}`",
            self.robot.links[root].name.text
        );
        if let Some(inertial) = &self.robot.links[root].inertial {
            let _ = writeln!(
                out,
                "// Held fixed, so its inertia does not enter the equations: mass {} {}, com {}, inertia {} * 1 {}.",
                inertial.mass.literal,
                units.mass,
                vector(&inertial.origin.xyz, units.length),
                literals(&inertial.inertia),
                units.inertia()
            );
        }
        if !members.of_link[root].is_empty() {
            let _ = writeln!(out, "newtonian {{");
            for member in &members.of_link[root] {
                let _ = writeln!(out, "{}", indent(member));
            }
            let _ = writeln!(out, "}}");
        }
        out.push('\n');
    }

    fn write_bodies(&self, out: &mut String, members: &Members) {
        let units = &self.units;
        let _ = writeln!(
            out,
            "// ---------------------------------------------------------------- links"
        );
        let _ = writeln!(out, "// Mass, centre of mass (link frame) and inertia about it (link axes, tensor convention).\n");
        for &i in &self.tree.order {
            if i == self.tree.root && self.fixed_root {
                continue;
            }
            let link = &self.robot.links[i];
            let _ = writeln!(
                out,
                "/// URDF link `{}`, line {}.",
                link.name.text,
                self.file.line_col(link.span.start).0
            );
            for skipped in self
                .robot
                .skipped
                .iter()
                .filter(|s| s.owner == link.name.text && s.kind != SkippedKind::Display)
            {
                let _ = writeln!(out, "// Not translated: {}", skipped.what);
            }
            let _ = writeln!(out, "body {} {{", self.body_ident[i]);
            match &link.inertial {
                Some(inertial) => {
                    let _ = writeln!(out, "    mass = {} {};", inertial.mass.literal, units.mass);
                    if values(&inertial.origin.xyz) != [0.0; 3] {
                        let _ = writeln!(
                            out,
                            "    com = {};",
                            vector(&inertial.origin.xyz, units.length)
                        );
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
            for member in &members.of_link[i] {
                let _ = writeln!(out, "{}", indent(member));
            }
            let _ = writeln!(out, "}}\n");
        }
    }

    fn write_joints(&mut self, out: &mut String, members: &Members) {
        let robot = self.robot;
        let root = self.tree.root;
        let _ = writeln!(
            out,
            "// ---------------------------------------------------------------- joints\n"
        );
        if !self.fixed_root {
            let base = self
                .frames
                .take(&format!("{}_base", robot.links[root].name.text));
            let _ = writeln!(out, "/// The root link's six degrees of freedom (--base floating).\njoint {base} = free(newtonian, {});\n", self.body_ident[root]);
        }
        // In the order of the tree (parents first), siblings in the file's order, as `.mech`
        // orders coordinates.
        let order = self.tree.order.clone();
        for &c in order.iter().skip(1) {
            let Some(j) = self.tree.parent_joint[c] else {
                continue;
            };
            let joint = &robot.joints[j];
            let (parent, child) = self.tree.ends[j];
            let _ = writeln!(
                out,
                "/// URDF joint `{}` ({}), line {}.",
                joint.name.text,
                joint.kind.text,
                self.file.line_col(joint.span.start).0
            );
            for skipped in robot
                .skipped
                .iter()
                .filter(|s| s.owner == joint.name.text && s.kind != SkippedKind::Display)
            {
                let _ = writeln!(out, "// Not translated: {}", skipped.what);
            }
            if self.kinds[j] == Kind::Planar {
                self.write_planar(out, j, members);
                continue;
            }
            let mut fields = Vec::new();
            if matches!(self.kinds[j], Kind::Pin | Kind::Slider) {
                fields.push(format!("axis = {};", axis(&joint.axis)));
            }
            if values(&joint.origin.xyz) != [0.0; 3] {
                fields.push(format!(
                    "parent_point = {};",
                    vector(&joint.origin.xyz, self.units.length)
                ));
            }
            if let Some(frame) = &members.joint_frames[j] {
                fields.push(format!("parent_frame = {frame};"));
            }
            let elastic = &self.joint_elastic[j];
            for (field, value) in [
                ("stiffness", &elastic.stiffness),
                ("rest", &elastic.rest),
                ("damping", &elastic.damping),
            ] {
                if let Some(value) = value {
                    fields.push(format!("{field} = {value};"));
                }
            }
            let head = format!(
                "joint {} = {}({}, {})",
                self.joint_ident[j],
                self.kinds[j].keyword(),
                self.body_ident[parent],
                self.body_ident[child]
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
    }

    /// A planar joint as two sliders along directions in the plane and a pin about its
    /// normal, through two massless bodies: three coordinates, `NAME_1`, `NAME_2` (lengths)
    /// and `NAME` (the angle).
    fn write_planar(&mut self, out: &mut String, j: usize, members: &Members) {
        let joint = &self.robot.joints[j];
        let (parent, child) = self.tree.ends[j];
        let normal = pose::unit(values(&joint.axis)).unwrap_or([0.0, 0.0, 1.0]);
        let [first, second] = in_plane(normal);
        let bodies = [1, 2].map(|i| self.frames.take(&format!("{}_slide{i}", joint.name.text)));
        let slides = [1, 2].map(|i| self.frames.take(&format!("{}_{i}", joint.name.text)));
        let _ = writeln!(
            out,
            "// As two sliders in the plane and a pin about its normal, through two massless bodies."
        );
        for body in &bodies {
            let _ = writeln!(out, "body {body} {{ mass = 0 {}; }}", self.units.mass);
        }
        let _ = writeln!(
            out,
            "joint {} = slider({}, {}) {{",
            slides[0], self.body_ident[parent], bodies[0]
        );
        let _ = writeln!(out, "    axis = {};", direction(first));
        if values(&joint.origin.xyz) != [0.0; 3] {
            let point = vector(&joint.origin.xyz, self.units.length);
            let _ = writeln!(out, "    parent_point = {point};");
        }
        if let Some(frame) = &members.joint_frames[j] {
            let _ = writeln!(out, "    parent_frame = {frame};");
        }
        let _ = writeln!(out, "}}");
        let _ = writeln!(
            out,
            "joint {} = slider({}, {}) {{ axis = {}; }}",
            slides[1],
            bodies[0],
            bodies[1],
            direction(second)
        );
        let _ = writeln!(
            out,
            "joint {} = pin({}, {}) {{ axis = {}; }}\n",
            self.joint_ident[j],
            bodies[1],
            self.body_ident[child],
            axis(&joint.axis)
        );
    }

    fn write_loops(&self, out: &mut String, members: &Members) {
        let robot = self.robot;
        if !robot.loops.is_empty() {
            let _ = writeln!(out, "// ---------------------------------------------------------------- loop closures (Drake loop_joint)\n");
        }
        for (l, closure) in robot.loops.iter().enumerate() {
            let line = self.file.line_col(closure.span.start).0;
            let Some(c) = &self.closures[l] else {
                let _ = writeln!(
                    out,
                    "// Not translated: loop_joint `{}` of type `{}`, line {line}.\n",
                    closure.name.text, closure.kind.text
                );
                continue;
            };
            write_loop(out, closure, c, line, &self.body_ident, self.units.length);
            if c.revolute {
                for (field, frame) in ["parent_frame", "child_frame"]
                    .iter()
                    .zip(&members.loop_frames[l])
                {
                    if let Some(frame) = frame {
                        let _ = writeln!(out, "    {field} = {frame};");
                    }
                }
                let elastic = &self.loop_elastic[l];
                for (field, value) in [("stiffness", &elastic.stiffness), ("rest", &elastic.rest)] {
                    if let Some(value) = value {
                        let _ = writeln!(out, "    {field} = {value};");
                    }
                }
            }
            let _ = writeln!(out, "}}\n");
        }
        for skipped in robot
            .skipped
            .iter()
            .filter(|s| robot.loops.iter().any(|l| l.name.text == s.owner))
        {
            let _ = writeln!(
                out,
                "// Not translated, of loop_joint `{}`: {}",
                skipped.owner, skipped.what
            );
        }
    }

    /// Point springs, transmissions (as comments) and outputs.
    fn write_tail(&mut self, out: &mut String) {
        let robot = self.robot;
        if !self.springs.is_empty() {
            let _ = writeln!(out, "// ---------------------------------------------------------------- springs between points\n");
            for spring in &self.springs {
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
                    self.file.line_col(t.span.start).0,
                    t.actuators.join(", "),
                    t.joints.join(", "),
                    t.reduction.as_deref().unwrap_or("not given")
                );
            }
            out.push('\n');
        }
        let of_robot: Vec<_> = robot
            .skipped
            .iter()
            .filter(|s| s.owner == "robot" && s.kind != SkippedKind::Display)
            .collect();
        if !of_robot.is_empty() {
            let _ = writeln!(out, "// ---------------------------------------------------------------- other elements (not translated)");
            for skipped in of_robot {
                let _ = writeln!(
                    out,
                    "// line {}: {}",
                    self.file.line_col(skipped.span.start).0,
                    skipped.what
                );
            }
            out.push('\n');
        }
        let _ = writeln!(
            out,
            "// ---------------------------------------------------------------- outputs\n"
        );
        for (i, link) in robot.links.iter().enumerate() {
            if i == self.tree.root && self.fixed_root {
                continue;
            }
            let mut names = Identifiers::default();
            for collision in &link.collisions {
                let point = names.take(collision.name.as_deref().unwrap_or("collision"));
                let output = self.params.take(&format!("{}_{point}", link.name.text));
                let _ = writeln!(out, "/// Collision origin of `{}` in the root frame.\noutput {output} = position({}.{point}) in newtonian;", link.name.text, self.body_ident[i]);
            }
        }
        let _ = writeln!(
            out,
            "output ke = kinetic_energy;\noutput pe = potential_energy;"
        );
    }
}

/// What [`Translation::members`] gives each body and the frames it names.
struct Members {
    of_link: Vec<Vec<String>>,
    joint_frames: Vec<Option<String>>,
    loop_frames: Vec<[Option<String>; 2]>,
}

/// A list in the model's header: `heading`, then `//! - note.` for each note; nothing
/// without notes.
fn write_header_list(out: &mut String, heading: &str, notes: &[String]) {
    if notes.is_empty() {
        return;
    }
    let _ = writeln!(out, "//! {heading}");
    for note in notes {
        let _ = writeln!(out, "//! - {note}.");
    }
}

/// A loop closure's head, axis and points (the frames and springs follow).
fn write_loop(
    out: &mut String,
    closure: &LoopJoint,
    c: &Closure,
    line: usize,
    body_ident: &[String],
    length: &str,
) {
    let _ = writeln!(
        out,
        "/// Drake loop_joint `{}` ({}), line {line}.",
        closure.name.text, closure.kind.text
    );
    if c.snapped {
        let _ = writeln!(out, "/// Its points were moved by --snap (see the header).");
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
    let _ = writeln!(out, "    parent_point = {};", vector(&c.points[0], length));
    let _ = writeln!(out, "    child_point = {};", vector(&c.points[1], length));
}

/// `body.point`, or `newtonian.point` for the fixed root.
fn point_of(body: &str, point: &str) -> String {
    format!("{body}.{point}")
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

/// Two unit vectors spanning the plane normal to `normal`: the coordinate axis least along
/// the normal, made normal to it, then the normal crossed with that (x, y for a normal z).
fn in_plane(normal: Vec3) -> [Vec3; 2] {
    let least = (0..3)
        .min_by(|&a, &b| normal[a].abs().total_cmp(&normal[b].abs()))
        .unwrap_or(0);
    let mut along = [0.0; 3];
    along[least] = 1.0;
    let first = pose::unit(pose::sub(
        along,
        pose::scale(normal, pose::dot(along, normal)),
    ))
    .unwrap_or(along);
    [first, pose::cross(normal, first)]
}

/// `x`, `-y`, … for a coordinate axis, else the components.
fn direction(v: Vec3) -> String {
    let nonzero: Vec<usize> = (0..3).filter(|&i| v[i] != 0.0).collect();
    match nonzero[..] {
        [i] if v[i].abs() == 1.0 => format!(
            "{}{}",
            if v[i] < 0.0 { "-" } else { "" },
            ["x", "y", "z"][i]
        ),
        _ => format!("[{}]", v.map(float_literal).join(", ")),
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
