//! Joints and the kinematic tree: joint fields, tree order from `newtonian`, and the IR frames,
//! coordinates, points and bodies in parents-first order.
//!
//! Consumes: `joint` declarations and the [`Owner`](super::body::Owner)s.
//! Produces: `model.frames` (newtonian, its frames, then per joint in depth-first order:
//! `j` (first, for a `free` joint `j.x`, `j.y`, `j.z`; for a joint of several coordinates
//! one frame per coordinate but the last, `j.angle1`, `j.slide`, `j.slide1`, `j.slide2`),
//! optionally `j.child`, the child body's frame and its named frames), coordinates,
//! quaternions or Euler angles (`ball`, `free`), joints, springs and dampers (one per
//! coordinate given one), points and bodies; `E04xx` tree errors.

use crate::diag::{Diagnostic, Span};
use crate::front::ast::{self, ExprKind};
use crate::ir::{self, AxisAngle, Dimension, Expr, Handle, JointKind, Motion, Vec3};
use crate::sym::Number;

use super::body::{missing_field, normalize, zeros, FrameRef};
use super::expr::{is_vector, neg, unparen, Ctx, Expect};
use super::{names, Lowerer};

/// A joint after its fields are lowered.
pub struct JointInfo<'a> {
    pub decl: &'a ast::JointDecl,
    pub kind: Option<JointKind>,
    pub parent: Option<usize>,
    pub child: Option<usize>,
    axis: Vec3,
    /// `universal`: the second pin's axis, in the frame turned by the first.
    axis2: Vec3,
    parent_point: Vec3,
    child_point: Vec3,
    /// Rotation of `parent_frame` relative to the parent's body frame.
    parent_frame: Vec<AxisAngle>,
    /// Rotation of `child_frame` relative to the child's body frame, if it is not that frame.
    child_frame: Option<Vec<AxisAngle>>,
    /// Per coordinate of a pin, slider, universal, cylindrical or planar joint (in the order
    /// of [`coordinate_parts`]): initial value and speed, spring and damper.
    q0: Vec<f64>,
    u0: Vec<f64>,
    /// Those of `q0`, `u0` written with params (`u0 = v / r`): evaluated again at run time.
    q0_expr: Vec<Option<Expr>>,
    u0_expr: Vec<Option<Expr>>,
    /// `ball` and `free`: the initial angular velocity relative to the parent (child frame).
    angular_velocity0: [f64; 3],
    /// `ball` and `free` with `rotation = euler(…)`: the sequence's axes (0 = x) and the
    /// initial angles; `None` for a unit quaternion.
    euler: Option<([usize; 3], [f64; 3])>,
    /// `free`: the initial velocity of the child's origin, components in the joint frame.
    velocity0: [f64; 3],
    stiffness: Vec<Option<(Expr, Span)>>,
    rest: Vec<Expr>,
    damping: Vec<Option<(Expr, Span)>>,
    pub coordinate: Option<Handle<ir::Coordinate>>,
    pub frame: Option<Handle<ir::Frame>>,
}

const JOINT_FIELDS: [&str; 13] = [
    "axis",
    "axis2",
    "parent_point",
    "child_point",
    "parent_frame",
    "child_frame",
    "q0",
    "u0",
    "v0",
    "stiffness",
    "rest",
    "damping",
    "rotation",
];

/// Why a joint of `kind` does not take `field` of `JOINT_FIELDS` (the label of E0403), or
/// `None` if it does.
fn field_not_allowed(kind: JointKind, field: &str) -> Option<&'static str> {
    use JointKind::*;
    let dynamics = matches!(
        field,
        "axis" | "axis2" | "q0" | "u0" | "v0" | "stiffness" | "rest" | "damping"
    );
    match (kind, field) {
        (Ball | Free, "rotation") => None,
        (_, "rotation") => Some("only a ball or free joint has a `rotation`"),
        (Weld, _) if dynamics => Some("a weld has no degree of freedom"),
        (Ball, "u0" | "q0") | (Free, "u0" | "v0" | "q0") => None,
        (Ball, _) if dynamics => Some("a ball joint has no single axis or angle"),
        (Free, _) if dynamics => Some("a free joint has no single axis or angle"),
        (Pin | Slider | Universal | Cylindrical | Planar, "v0") => {
            Some("only a free joint has `v0`")
        }
        (Pin | Slider | Cylindrical | Planar, "axis2") => {
            Some("only a universal joint has `axis2`")
        }
        _ => None,
    }
}

/// Every joint kind, as written.
const JOINT_KINDS: [(&str, JointKind); 8] = [
    ("pin", JointKind::Pin),
    ("slider", JointKind::Slider),
    ("weld", JointKind::Weld),
    ("ball", JointKind::Ball),
    ("free", JointKind::Free),
    ("universal", JointKind::Universal),
    ("cylindrical", JointKind::Cylindrical),
    ("planar", JointKind::Planar),
];

/// The coordinates a joint of `kind` adds, in order, each with its name after the joint's
/// (`JOINT.PART`; `""` for the joint's own name) and whether it is a slide (a length) rather
/// than a turn (an angle). Empty for a weld, and for `ball` and `free`, whose coordinates are
/// built with their quaternion.
fn coordinate_parts(kind: JointKind) -> &'static [(&'static str, bool)] {
    match kind {
        JointKind::Pin => &[("", false)],
        JointKind::Slider => &[("", true)],
        JointKind::Universal => &[("angle1", false), ("angle2", false)],
        JointKind::Cylindrical => &[("slide", true), ("angle", false)],
        JointKind::Planar => &[("slide1", true), ("slide2", true), ("angle", false)],
        JointKind::Weld | JointKind::Ball | JointKind::Free => &[],
    }
}

/// The name a joint kind is written with.
fn kind_name(kind: JointKind) -> &'static str {
    JOINT_KINDS
        .iter()
        .find(|(_, known)| *known == kind)
        .map_or("weld", |(name, _)| name)
}

/// One frame of a joint moved by one coordinate: a slide along `axis` or a turn about it.
struct MovingFrame {
    frame: String,
    coordinate: String,
    slide: bool,
    axis: Vec3,
    q0: f64,
    u0: f64,
    /// `q0`, `u0` as written, where they depend on params.
    q0_expr: Option<Expr>,
    u0_expr: Option<Expr>,
}

/// The dimension a joint field must have for one coordinate: a turn's (angles) or a slide's
/// (lengths).
fn joint_expect(field: &'static str, slide: bool) -> Expect<'static> {
    let (mass, length, time, example) = match (field, slide) {
        ("q0" | "rest", false) => (0, 0, 0, "30 deg"),
        ("q0" | "rest", true) => (0, 1, 0, "1 mm"),
        ("u0", false) => (0, 0, -1, "1 rad/s"),
        ("u0", true) => (0, 1, -1, "1 mm/s"),
        ("stiffness", false) => (1, 2, -2, "0.1 uN*m/rad"),
        ("stiffness", true) => (1, 0, -2, "10 N/m"),
        ("damping", false) => (1, 2, -1, "1e-9 N*m*s/rad"),
        _ => (1, 0, -1, "1e-3 N*s/m"),
    };
    let what = match field {
        "q0" => "`q0`",
        "rest" => "`rest`",
        "u0" => "`u0`",
        "stiffness" => "`stiffness`",
        _ => "`damping`",
    };
    Expect::mechanical(what, example, [mass, length, time])
}

impl<'a> Lowerer<'a> {
    pub(super) fn lower_joints(&mut self, items: &'a [ast::Item]) {
        let decls: Vec<&'a ast::JointDecl> = items
            .iter()
            .filter_map(|item| {
                if let ast::Item::Joint(j) = item {
                    Some(j)
                } else {
                    None
                }
            })
            .collect();
        for (index, decl) in decls.iter().enumerate() {
            self.joint_index
                .entry(decl.name.name.clone())
                .or_insert(index);
        }
        for decl in decls {
            let info = self.lower_joint(decl);
            self.joints.push(info);
        }
    }

    fn lower_joint(&mut self, decl: &'a ast::JointDecl) -> JointInfo<'a> {
        let kind = self.joint_kind(&decl.kind);
        let parent = self.resolve_owner(&decl.parent);
        let child = self.joint_child(decl);
        self.check_distinct_ends("joint", decl, parent, child);
        let fields = self.joint_fields(decl, kind);
        let field = |name: &str| fields.iter().copied().find(|f| f.name.name == name);
        let mut info = JointInfo {
            decl,
            kind,
            parent,
            child,
            axis: zeros(),
            axis2: zeros(),
            parent_point: zeros(),
            child_point: zeros(),
            parent_frame: Vec::new(),
            child_frame: None,
            q0: Vec::new(),
            u0: Vec::new(),
            q0_expr: Vec::new(),
            u0_expr: Vec::new(),
            angular_velocity0: [0.0; 3],
            euler: None,
            velocity0: [0.0; 3],
            stiffness: Vec::new(),
            rest: Vec::new(),
            damping: Vec::new(),
            coordinate: None,
            frame: None,
        };
        if kind == Some(JointKind::Universal) {
            (info.axis, info.axis2) = (unit_axis(0), unit_axis(1));
        }
        if let Some(axis) = self.joint_axis(decl, kind, field("axis")) {
            info.axis = axis;
        }
        if let Some(f) = field("axis2") {
            if let Some(axis2) = self.axis(&f.value, "a joint's second axis") {
                info.axis2 = axis2;
            }
        }
        if kind == Some(JointKind::Universal) {
            let span = field("axis2")
                .or(field("axis"))
                .map_or(decl.span, |f| f.value.span);
            self.check_universal_axes(&info, span);
        }
        if let Some(f) = field("parent_point") {
            info.parent_point = self
                .joint_point(f, parent, "`parent_point`", "parent")
                .unwrap_or_else(zeros);
        }
        if let Some(f) = field("child_point") {
            info.child_point = self
                .joint_point(f, child, "`child_point`", "child")
                .unwrap_or_else(zeros);
        }
        if let Some(f) = field("parent_frame") {
            info.parent_frame = self
                .joint_frame(f, parent, "parent")
                .flatten()
                .unwrap_or_default();
        }
        if let Some(f) = field("child_frame") {
            info.child_frame = self.joint_frame(f, child, "child").flatten();
        }
        match kind {
            Some(JointKind::Ball | JointKind::Free) => self.lower_initial_rates(&mut info, &field),
            Some(kind) => self.lower_joint_dynamics(&mut info, kind, &field),
            None => {}
        }
        info
    }

    /// E0416 when a universal joint's two axes are parallel (it would turn about one axis).
    fn check_universal_axes(&mut self, info: &JointInfo, span: Span) {
        let value = |axis: &Vec3| {
            axis.clone().map(|c| match c {
                Expr::Number(n) => n.to_f64(),
                _ => f64::NAN,
            })
        };
        let (a, b) = (value(&info.axis), value(&info.axis2));
        let cross = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        if cross.iter().map(|c| c * c).sum::<f64>() > 1e-12 {
            return;
        }
        self.error(
            Diagnostic::error(
                "E0416",
                format!(
                    "the axes of universal joint `{}` are parallel",
                    info.decl.name.name
                ),
            )
            .with_label(span, "parallel to `axis`")
            .with_help(
                "a universal joint turns about two different axes, e.g. `axis = x; axis2 = y;`",
            ),
        );
    }

    /// `u0` (angular velocity, rad/s) and `v0` (velocity, m/s) of a `ball` or `free` joint:
    /// constant vectors.
    fn lower_initial_rates<'f>(
        &mut self,
        info: &mut JointInfo,
        field: &dyn Fn(&str) -> Option<&'f ast::Field>,
    ) {
        let rates = [
            (
                "u0",
                "`u0` (angular velocity)",
                "[0, 0, 10 rad/s]",
                [0, 0, -1],
            ),
            ("v0", "`v0` (velocity)", "[0, 0, 1 m/s]", [0, 1, -1]),
        ];
        if let Some(f) = field("rotation") {
            let sequence = self.euler_sequence(f);
            info.euler = sequence.map(|sequence| (sequence, [0.0; 3]));
        }
        if let Some(f) = field("q0") {
            self.lower_initial_angles(info, f);
        }
        if let Some(f) = field("q0").or(field("rotation")) {
            self.check_euler_start(info, f.value.span);
        }
        for (name, what, example, dimension) in rates {
            let Some(f) = field(name) else { continue };
            let expect = Expect::mechanical(what, example, dimension);
            let ctx = Ctx::Static("a joint property");
            let Some(vector) = self.lower_vector_as(&f.value, ctx, &expect) else {
                continue;
            };
            let values = vector.map(|e| self.evaluate(&e, f.value.span));
            match name {
                "u0" => info.angular_velocity0 = values,
                _ => info.velocity0 = values,
            }
        }
    }

    /// `rotation = euler(SEQ)` (`Some` axes) or `rotation = quaternion` (`None`, the default);
    /// E0412 for anything else, with the twelve sequences.
    fn euler_sequence(&mut self, f: &ast::Field) -> Option<[usize; 3]> {
        let value = unparen(&f.value);
        let written = match &value.kind {
            ExprKind::Path(path) if path.segments.len() == 1 => {
                if path.segments[0].name == "quaternion" {
                    return None;
                }
                None
            }
            ExprKind::Call { function, args } if function.name == "euler" => {
                match args.as_slice() {
                    [arg] => match &unparen(arg).kind {
                        ExprKind::Path(path) if path.segments.len() == 1 => {
                            Some(path.segments[0].name.clone())
                        }
                        _ => None,
                    },
                    _ => None,
                }
            }
            _ => None,
        };
        let sequence = written.as_deref().and_then(parse_euler_sequence);
        if sequence.is_none() {
            self.error(
                Diagnostic::error(
                    "E0412",
                    "expected a rotation: `quaternion` or `euler(SEQUENCE)`",
                )
                .with_label(f.value.span, "not a rotation")
                .with_help(format!(
                    "write `rotation = euler(zxy);` with one of the body-fixed sequences {}, \
                         or `rotation = quaternion;` (the default)",
                    EULER_SEQUENCES.join(", ")
                )),
            );
        }
        sequence
    }

    /// `q0` of a ball or free joint with Euler angles: its three angles; E0403 with a
    /// quaternion, which starts at the identity.
    fn lower_initial_angles(&mut self, info: &mut JointInfo, f: &ast::Field) {
        let Some((sequence, _)) = info.euler else {
            let kind = &info.decl.kind.name;
            self.error(
                Diagnostic::error(
                    "E0403",
                    format!("`q0` is not allowed on a {kind} joint with a quaternion"),
                )
                .with_label(f.name.span, "a unit quaternion starts at the identity")
                .with_help(
                    "turn the start with `parent_frame`, or give the joint Euler angles: \
                         `rotation = euler(zxy); q0 = [10 deg, 0 deg, 0 deg];`",
                ),
            );
            return;
        };
        let expect = Expect::mechanical("`q0` (Euler angles)", "[10 deg, 0 deg, 0 deg]", [0, 0, 0]);
        let Some(angles) = self.lower_vector_as(&f.value, Ctx::Static("a joint property"), &expect)
        else {
            return;
        };
        let angles = angles.map(|e| self.evaluate(&e, f.value.span));
        info.euler = Some((sequence, angles));
    }

    /// E0419 when Euler angles start where `q̇ = W(q) u` has no value: `cos q₂ = 0` for a
    /// sequence of three different axes, `sin q₂ = 0` for one that repeats its first (as
    /// `zxz` does at the default `q0 = 0`).
    fn check_euler_start(&mut self, info: &JointInfo, span: Span) {
        let Some((sequence, angles)) = info.euler else {
            return;
        };
        let proper = sequence[0] == sequence[2];
        let distance = match proper {
            true => angles[1].sin().abs(),
            false => angles[1].cos().abs(),
        };
        if distance > 1e-6 {
            return;
        }
        let condition = match proper {
            true => "sin q₂ = 0",
            false => "cos q₂ = 0",
        };
        self.error(
            Diagnostic::error(
                "E0419",
                format!(
                    "the Euler angles of joint `{}` start at their singularity",
                    info.decl.name.name
                ),
            )
            .with_label(
                span,
                format!("{condition} here: the angle rates have no value"),
            )
            .with_help(
                "start the second angle away from it (`q0 = [0, 30 deg, 0];`), or choose a \
                 sequence whose singularity the motion avoids (`euler(zxy)` is singular at \
                 x = ±90°, `euler(zxz)` at x = 0 and 180°), or a quaternion (no `rotation`)",
            ),
        );
    }

    /// `q0`, `u0`, `stiffness`, `rest` and `damping` of a joint with coordinates: a scalar for
    /// a pin or slider, a vector with one entry per coordinate (each of its coordinate's
    /// dimension) for a universal, cylindrical or planar joint.
    fn lower_joint_dynamics<'f>(
        &mut self,
        info: &mut JointInfo,
        kind: JointKind,
        field: &dyn Fn(&str) -> Option<&'f ast::Field>,
    ) {
        let count = coordinate_parts(kind).len();
        info.q0 = vec![0.0; count];
        info.u0 = vec![0.0; count];
        info.q0_expr = vec![None; count];
        info.u0_expr = vec![None; count];
        info.stiffness = vec![None; count];
        info.rest = vec![Expr::zero(); count];
        info.damping = vec![None; count];
        for name in ["q0", "u0", "stiffness", "rest", "damping"] {
            let Some(f) = field(name) else { continue };
            let Some(values) = self.joint_field_values(f, name, kind) else {
                continue;
            };
            for (i, (expr, span)) in values.into_iter().enumerate() {
                match name {
                    "q0" => {
                        info.q0[i] = self.evaluate(&expr, span);
                        info.q0_expr[i] = Some(expr).filter(Expr::has_params);
                    }
                    "u0" => {
                        info.u0[i] = self.evaluate(&expr, span);
                        info.u0_expr[i] = Some(expr).filter(Expr::has_params);
                    }
                    "stiffness" => info.stiffness[i] = Some((expr, span)),
                    "rest" => info.rest[i] = expr,
                    _ => info.damping[i] = Some((expr, span)),
                }
            }
        }
    }

    /// The values of joint field `name`, one per coordinate with its span; `None` after an
    /// error (E0411 when a joint with several coordinates is given a scalar).
    fn joint_field_values(
        &mut self,
        f: &ast::Field,
        name: &'static str,
        kind: JointKind,
    ) -> Option<Vec<(Expr, Span)>> {
        let ctx = Ctx::Static("a joint property");
        let parts = coordinate_parts(kind);
        if let [(_, slide)] = parts {
            let expr = self.lower_scalar_as(&f.value, ctx, &joint_expect(name, *slide))?;
            return Some(vec![(expr, f.value.span)]);
        }
        if !is_vector(unparen(&f.value)) {
            let coordinates: Vec<String> = parts.iter().map(|(p, _)| format!("`{p}`")).collect();
            let examples: Vec<&str> = parts
                .iter()
                .map(|&(_, slide)| joint_expect(name, slide).example)
                .collect();
            let kind = kind_name(kind);
            self.error(
                Diagnostic::error(
                    "E0411",
                    format!("`{name}` of a {kind} joint needs one value per coordinate"),
                )
                .with_label(f.value.span, "a single value")
                .with_help(format!(
                    "a {kind} joint has coordinates {}: write `{name} = [{}];`",
                    coordinates.join(", "),
                    examples.join(", ")
                )),
            );
            return None;
        }
        let what = joint_expect(name, false).what;
        let items = self.vector_items(&f.value, what, parts.len())?;
        let values: Vec<Option<(Expr, Span)>> = items
            .iter()
            .zip(parts)
            .map(|(item, &(_, slide))| {
                let expr = self.lower_scalar_as(item, ctx, &joint_expect(name, slide))?;
                Some((expr, item.span))
            })
            .collect();
        values.into_iter().collect()
    }

    /// E0408 when a joint or loop connects a body to itself.
    pub(super) fn check_distinct_ends(
        &mut self,
        what: &str,
        decl: &ast::JointDecl,
        parent: Option<usize>,
        child: Option<usize>,
    ) {
        if parent.is_none() || parent != child {
            return;
        }
        self.error(
            Diagnostic::error(
                "E0408",
                format!(
                    "{what} `{}` connects `{}` to itself",
                    decl.name.name, decl.parent.name
                ),
            )
            .with_label(decl.child.span, "the child")
            .with_label(decl.parent.span, "is also the parent")
            .with_help(format!(
                "a {what} connects two different bodies: `{}(parent, child)`",
                decl.kind.name
            )),
        );
    }

    fn joint_kind(&mut self, kind: &ast::Ident) -> Option<JointKind> {
        if let Some(&(_, known)) = JOINT_KINDS.iter().find(|(name, _)| *name == kind.name) {
            return Some(known);
        }
        let synonym = match kind.name.as_str() {
            "revolute" | "hinge" => Some("pin"),
            "prismatic" => Some("slider"),
            "fixed" | "rigid" => Some("weld"),
            "spherical" | "socket" => Some("ball"),
            "floating" | "free_flyer" | "freejoint" | "six_dof" => Some("free"),
            "cardan" | "hooke" | "u_joint" | "gimbal" => Some("universal"),
            "cylinder" | "cylindric" => Some("cylindrical"),
            "plane" | "planar_joint" => Some("planar"),
            _ => None,
        };
        let known = JOINT_KINDS.map(|(name, _)| name);
        self.error(names::unknown_kind("joint", "joint", kind, &known, synonym));
        None
    }

    fn joint_child(&mut self, decl: &ast::JointDecl) -> Option<usize> {
        if decl.child.name == "newtonian" {
            self.error(
                Diagnostic::error(
                    "E0409",
                    format!("the child of joint `{}` is `newtonian`", decl.name.name),
                )
                .with_label(decl.child.span, "the Newtonian frame cannot be a child")
                .with_help(format!(
                    "the parent comes first: `{}({}, {})`",
                    decl.kind.name, decl.child.name, decl.parent.name
                )),
            );
            return None;
        }
        self.resolve_body(&decl.child)
    }

    /// The fields of a joint that are known, not repeated, and allowed for its kind.
    fn joint_fields<'f>(
        &mut self,
        decl: &'f ast::JointDecl,
        kind: Option<JointKind>,
    ) -> Vec<&'f ast::Field> {
        let mut fields: Vec<&ast::Field> = Vec::new();
        for field in &decl.fields {
            let (list, label) = ("fields of a joint", "not a joint field");
            if !self.check_field(field, &fields, &JOINT_FIELDS, list, label) {
                continue;
            }
            let name = field.name.name.as_str();
            let Some(kind) = kind else {
                fields.push(field);
                continue;
            };
            if let Some(why) = field_not_allowed(kind, name) {
                let takes: Vec<&str> = JOINT_FIELDS
                    .iter()
                    .copied()
                    .filter(|f| field_not_allowed(kind, f).is_none())
                    .collect();
                let kind_name = &decl.kind.name;
                self.error(
                    Diagnostic::error(
                        "E0403",
                        format!("`{name}` is not allowed on a {kind_name} joint"),
                    )
                    .with_label(field.name.span, why)
                    .with_help(match kind {
                        JointKind::Weld => {
                            "remove this field, or use a `pin` or `slider` joint".to_string()
                        }
                        _ => format!(
                            "remove this field; a {kind_name} joint takes {}",
                            names::list(&takes)
                        ),
                    }),
                );
                continue;
            }
            fields.push(field);
        }
        fields
    }

    fn joint_axis(
        &mut self,
        decl: &ast::JointDecl,
        kind: Option<JointKind>,
        field: Option<&ast::Field>,
    ) -> Option<Vec3> {
        match (kind, field) {
            (_, Some(field)) => self.axis(&field.value, "a joint axis"),
            (
                Some(
                    JointKind::Pin | JointKind::Slider | JointKind::Cylindrical | JointKind::Planar,
                ),
                None,
            ) => {
                let what = format!("{} joint", decl.kind.name);
                let help =
                    "add `axis = z;` (or `x`, `y`, `-z`, `[ax, ay, az]`), in the joint frame";
                self.error(missing_field(&what, &decl.name, "axis", help));
                None
            }
            _ => None,
        }
    }

    /// `parent_point` / `child_point`: body-frame coordinates, or a point of that body.
    pub(super) fn joint_point(
        &mut self,
        field: &ast::Field,
        owner: Option<usize>,
        what: &str,
        side: &str,
    ) -> Option<Vec3> {
        let value = unparen(&field.value);
        match &value.kind {
            _ if is_vector(value) => {
                let expect = Expect::new(Dimension::LENGTH, what, "[0, 5 mm, 0]");
                self.lower_vector_as(value, Ctx::Static("a joint point"), &expect)
            }
            ExprKind::Path(path) => {
                let point = self.resolve_point(path)?;
                let point_owner = Self::point_owner(point);
                self.check_owner(owner?, point_owner, path, "point", side)?;
                Some(self.point_position(point))
            }
            _ => {
                self.error(
                    Diagnostic::error("E0412", format!("expected a point for {what}"))
                        .with_label(value.span, "not a point")
                        .with_help(format!("write coordinates in the {side}'s frame, `[x, y, z]`, or a point such as `body.pivot`")),
                );
                None
            }
        }
    }

    /// `parent_frame` / `child_frame`: the body's own frame (`Some(None)`) or one of its frames.
    pub(super) fn joint_frame(
        &mut self,
        field: &ast::Field,
        owner: Option<usize>,
        side: &str,
    ) -> Option<Option<Vec<AxisAngle>>> {
        let ExprKind::Path(path) = &unparen(&field.value).kind else {
            self.error(
                Diagnostic::error(
                    "E0412",
                    format!("expected a frame for `{}`", field.name.name),
                )
                .with_label(field.value.span, "not a frame")
                .with_help("name a frame of that body, such as `base.tilted`, or the body itself"),
            );
            return None;
        };
        let frame = self.resolve_frame(path, false)?;
        match frame {
            FrameRef::Owner(o) => {
                self.check_owner(owner?, o, path, "frame", side)?;
                Some(None)
            }
            FrameRef::Named(o, index) => {
                self.check_owner(owner?, o, path, "frame", side)?;
                Some(Some(self.owners[o].frames[index].rotation.clone()))
            }
            FrameRef::Joint(_) => None,
        }
    }

    fn check_owner(
        &mut self,
        expected: usize,
        actual: usize,
        path: &ast::Path,
        kind: &str,
        side: &str,
    ) -> Option<()> {
        if expected == actual {
            return Some(());
        }
        let expected_name = self.owners[expected].name.clone();
        self.error(
            Diagnostic::error(
                "E0414",
                format!("this {kind} is not fixed in the joint's {side} `{expected_name}`"),
            )
            .with_label(
                path.span,
                format!("belongs to `{}`", self.owners[actual].name),
            )
            .with_help(format!(
                "use a {kind} of `{expected_name}`, or coordinates in its body frame"
            )),
        );
        None
    }

    // -----------------------------------------------------------------------------------------
    // Tree order
    // -----------------------------------------------------------------------------------------

    /// Joints in depth-first order from `newtonian` (declaration order among siblings);
    /// reports bodies with two parents, disconnected bodies and detached cycles.
    pub(super) fn tree_order(&mut self) -> Vec<usize> {
        let parent_joint = self.parent_joints();
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); self.owners.len()];
        for joint in &parent_joint {
            if let Some(j) = *joint {
                if let Some(parent) = self.joints[j].parent {
                    children[parent].push(j);
                }
            }
        }
        for list in &mut children {
            list.sort_unstable();
        }
        let mut order = Vec::new();
        let mut reached = vec![false; self.owners.len()];
        reached[0] = true;
        let mut stack: Vec<usize> = children[0].iter().rev().copied().collect();
        while let Some(j) = stack.pop() {
            let Some(child) = self.joints[j].child else {
                continue;
            };
            if reached[child] {
                continue;
            }
            reached[child] = true;
            order.push(j);
            stack.extend(children[child].iter().rev().copied());
        }
        self.report_unreached(&reached, &parent_joint);
        order
    }

    /// For each owner, the first joint (in declaration order) with it as child.
    fn parent_joints(&mut self) -> Vec<Option<usize>> {
        let mut parent_joint: Vec<Option<usize>> = vec![None; self.owners.len()];
        for j in 0..self.joints.len() {
            let (Some(parent), Some(child)) = (self.joints[j].parent, self.joints[j].child) else {
                continue;
            };
            if parent == child {
                continue;
            }
            match parent_joint[child] {
                None => parent_joint[child] = Some(j),
                Some(first) => self.two_parents(first, j),
            }
        }
        parent_joint
    }

    fn two_parents(&mut self, first: usize, second: usize) {
        let (a, b) = (self.joints[first].decl, self.joints[second].decl);
        self.error(
            Diagnostic::error(
                "E0406",
                format!(
                    "cycle in the joint tree: body `{}` has two parent joints, `{}` and `{}`",
                    b.child.name, a.name.name, b.name.name
                ),
            )
            .with_label(b.child.span, format!("second parent joint `{}`", b.name.name))
            .with_label(a.child.span, format!("first parent joint `{}`", a.name.name))
            .with_help(format!("every body has exactly one parent joint; close a kinematic loop with a `loop` declaration instead, e.g. `loop {} = revolute({}, {}) {{ axis = z; ... }}`", b.name.name, b.parent.name, b.child.name)),
        );
    }

    fn report_unreached(&mut self, reached: &[bool], parent_joint: &[Option<usize>]) {
        // A joint with an error already explains why its bodies are not in the tree.
        let broken_joint = self
            .joints
            .iter()
            .any(|j| j.parent.is_none() || j.child.is_none() || j.parent == j.child);
        let mut reported = vec![false; self.owners.len()];
        for owner in 1..self.owners.len() {
            if reached[owner] || reported[owner] {
                continue;
            }
            match parent_joint[owner] {
                None if broken_joint => {}
                None => self.disconnected(owner),
                Some(_) => self.detached_cycle(owner, parent_joint, &mut reported),
            }
        }
    }

    fn disconnected(&mut self, owner: usize) {
        let name = self.owners[owner].name.clone();
        self.error(
            Diagnostic::error("E0407", format!("disconnected body `{name}`"))
                .with_label(self.owners[owner].name_span, "no joint has this body as its child")
                .with_help(format!(
                    "connect it to the tree with a joint, e.g. `joint {name}_mount = weld(newtonian, {name});`"
                )),
        );
    }

    /// Follows parent joints up from `start`; reports the cycle found, if any, once.
    fn detached_cycle(
        &mut self,
        start: usize,
        parent_joint: &[Option<usize>],
        reported: &mut [bool],
    ) {
        let mut path = vec![start];
        let mut current = start;
        loop {
            let Some(parent) = parent_joint[current].and_then(|j| self.joints[j].parent) else {
                return;
            };
            if reported[parent] || parent == 0 {
                return;
            }
            if let Some(position) = path.iter().position(|&o| o == parent) {
                let cycle = path[position..].to_vec();
                for &o in &cycle {
                    reported[o] = true;
                }
                self.report_cycle(&cycle, parent_joint);
                return;
            }
            path.push(parent);
            current = parent;
        }
    }

    fn report_cycle(&mut self, cycle: &[usize], parent_joint: &[Option<usize>]) {
        let mut joints: Vec<usize> = cycle.iter().filter_map(|&o| parent_joint[o]).collect();
        joints.sort_unstable();
        let joint_names: Vec<String> = joints
            .iter()
            .map(|&j| format!("`{}`", self.joints[j].decl.name.name))
            .collect();
        let mut diagnostic = Diagnostic::error(
            "E0410",
            format!(
                "joints {} form a cycle that is not connected to newtonian",
                joint_names.join(", ")
            ),
        );
        for &j in &joints {
            diagnostic = diagnostic.with_label(self.joints[j].decl.name.span, "part of the cycle");
        }
        let help = "the joints must form a tree rooted at `newtonian`: \
                    connect one body to `newtonian` and remove one joint of the cycle";
        self.error(diagnostic.with_help(help));
    }

    // -----------------------------------------------------------------------------------------
    // Building the IR
    // -----------------------------------------------------------------------------------------

    /// Appends the frames of the tree, parents first, with coordinates, joints and joint loads.
    pub(super) fn build_tree(&mut self, order: &[usize]) {
        self.owners[0].frame = Some(ir::Model::NEWTONIAN);
        self.append_named_frames(0);
        for &j in order {
            self.build_joint(j);
        }
    }

    fn append_named_frames(&mut self, owner: usize) {
        let Some(parent) = self.owners[owner].frame else {
            return;
        };
        let prefix = self.owners[owner].name.clone();
        let mut handles = Vec::new();
        for info in &self.owners[owner].frames {
            handles.push(Some(self.model.frames.append(ir::Frame {
                name: format!("{prefix}.{}", info.name.name),
                parent: Some(parent),
                origin: info.origin.clone(),
                orientation: info.rotation.clone(),
                motion: Motion::Fixed,
                span: info.name.span,
            })));
        }
        self.owners[owner].frame_handles = handles;
    }

    fn build_joint(&mut self, j: usize) {
        let info = &self.joints[j];
        let (Some(p), Some(c)) = (info.parent, info.child) else {
            return;
        };
        let Some(parent_frame) = self.owners[p].frame else {
            return;
        };
        let decl = info.decl;
        let kind = info.kind.unwrap_or(JointKind::Weld);
        let joint_frame = match kind {
            JointKind::Ball | JointKind::Free => self.build_spherical(j, parent_frame),
            _ => self.build_moving(j, parent_frame),
        };
        let info = &self.joints[j];
        let mut previous = joint_frame;
        if let Some(rotation) = &info.child_frame {
            previous = self.model.frames.append(ir::Frame {
                name: format!("{}.child", decl.name.name),
                parent: Some(joint_frame),
                origin: zeros(),
                orientation: inverse(rotation),
                motion: Motion::Fixed,
                span: decl.span,
            });
        }
        let child_origin = info.child_point.clone().map(neg);
        let child_frame = self.model.frames.append(ir::Frame {
            name: self.owners[c].name.clone(),
            parent: Some(previous),
            origin: child_origin,
            orientation: Vec::new(),
            motion: Motion::Fixed,
            span: self.owners[c].name_span,
        });
        self.owners[c].frame = Some(child_frame);
        self.append_named_frames(c);
    }

    /// The frames of a joint whose coordinates have `u = q̇`, at `parent_point`, oriented by
    /// `parent_frame`: one per coordinate, each moved by it (a weld's one frame is fixed). The
    /// last is the joint's frame `j`; the ones before it are named after their coordinates:
    /// `j.angle1` (universal), `j.slide` (cylindrical), `j.slide1`, `j.slide2` (planar).
    fn build_moving(&mut self, j: usize, parent_frame: Handle<ir::Frame>) -> Handle<ir::Frame> {
        let info = &self.joints[j];
        let (decl, kind) = (info.decl, info.kind.unwrap_or(JointKind::Weld));
        let name = &decl.name.name;
        let axes: Vec<Vec3> = match kind {
            JointKind::Universal => vec![info.axis.clone(), info.axis2.clone()],
            JointKind::Cylindrical => vec![info.axis.clone(), info.axis.clone()],
            JointKind::Planar => {
                let [first, second] = plane_axes(&info.axis);
                vec![first, second, info.axis.clone()]
            }
            _ => vec![info.axis.clone()],
        };
        let parts = coordinate_parts(kind);
        let steps: Vec<MovingFrame> = parts
            .iter()
            .zip(axes)
            .enumerate()
            .map(|(i, (&(part, slide), axis))| {
                let coordinate = match part {
                    "" => name.clone(),
                    _ => format!("{name}.{part}"),
                };
                MovingFrame {
                    frame: if i + 1 == parts.len() {
                        name.clone()
                    } else {
                        coordinate.clone()
                    },
                    coordinate,
                    slide,
                    axis,
                    q0: info.q0[i],
                    u0: info.u0[i],
                    q0_expr: info.q0_expr[i].clone(),
                    u0_expr: info.u0_expr[i].clone(),
                }
            })
            .collect();
        let (origin, orientation) = (info.parent_point.clone(), info.parent_frame.clone());
        let (joint_frame, coordinates) = match steps.is_empty() {
            true => (
                self.model.frames.append(ir::Frame {
                    name: name.clone(),
                    parent: Some(parent_frame),
                    origin,
                    orientation,
                    motion: Motion::Fixed,
                    span: decl.span,
                }),
                Vec::new(),
            ),
            false => self.append_moving_frames(decl, parent_frame, origin, orientation, steps),
        };
        self.record_joint(j, coordinates, None, joint_frame);
        joint_frame
    }

    /// Appends a chain of frames, each moved by a new coordinate of `u = q̇`, the first placed
    /// at `origin` with `orientation` in `parent`; returns the last frame and the coordinates.
    fn append_moving_frames(
        &mut self,
        decl: &ast::JointDecl,
        mut parent: Handle<ir::Frame>,
        mut origin: Vec3,
        mut orientation: Vec<AxisAngle>,
        steps: Vec<MovingFrame>,
    ) -> (Handle<ir::Frame>, Vec<Handle<ir::Coordinate>>) {
        let mut coordinates = Vec::with_capacity(steps.len());
        for step in steps {
            let coordinate = self.model.coordinates.append(ir::Coordinate {
                name: step.coordinate,
                dimension: match step.slide {
                    true => Dimension::LENGTH,
                    false => Dimension::NONE,
                },
                initial: step.q0,
                initial_speed: step.u0,
                span: decl.name.span,
            });
            coordinates.push(coordinate);
            for (expr, speed) in [(step.q0_expr, false), (step.u0_expr, true)] {
                if let Some(expr) = expr {
                    let value = ir::InitialValue {
                        coordinate,
                        speed,
                        expr,
                    };
                    self.model.initial_values.push(value);
                }
            }
            let axis = step.axis;
            parent = self.model.frames.append(ir::Frame {
                name: step.frame,
                parent: Some(parent),
                origin: std::mem::replace(&mut origin, zeros()),
                orientation: std::mem::take(&mut orientation),
                motion: match step.slide {
                    true => Motion::Prismatic { axis, coordinate },
                    false => Motion::Revolute { axis, coordinate },
                },
                span: decl.span,
            });
        }
        (parent, coordinates)
    }

    /// The frame of a `ball` joint (turned by a quaternion or Euler angles) or a `free` joint
    /// (also moved by a [`ir::Translation`] along the axes of the frame at `parent_point`
    /// oriented by `parent_frame`): the free joint's speeds are the velocity of the child's
    /// origin and the child's angular velocity, both in the child's own basis. `v0` is written
    /// in the joint frame and turned into the child's basis at the start orientation.
    fn build_spherical(&mut self, j: usize, parent_frame: Handle<ir::Frame>) -> Handle<ir::Frame> {
        let info = &self.joints[j];
        let decl = info.decl;
        let name = decl.name.name.clone();
        let (rotation, quaternion, velocity0) = match info.euler {
            Some((sequence, initial_angles)) => {
                let angles = ir::EulerAngles {
                    name: name.clone(),
                    sequence,
                    initial_angles,
                    initial_angular_velocity: info.angular_velocity0,
                    span: decl.name.span,
                };
                let velocity0 = angles.initially_seen_from_frame(info.velocity0);
                let angles = self.model.euler_angles.append(angles);
                (ir::Rotation::Euler(angles), None, velocity0)
            }
            None => {
                let quaternion = self.model.quaternions.append(ir::Quaternion {
                    name: name.clone(),
                    initial_angular_velocity: info.angular_velocity0,
                    span: decl.name.span,
                });
                let velocity0 = info.velocity0;
                (
                    ir::Rotation::Quaternion(quaternion),
                    Some(quaternion),
                    velocity0,
                )
            }
        };
        let motion = match info.kind {
            Some(JointKind::Free) => Motion::Free {
                rotation,
                translation: self.model.translations.append(ir::Translation {
                    name: name.clone(),
                    initial_velocity: velocity0,
                    span: decl.name.span,
                }),
            },
            _ => Motion::Spherical { rotation },
        };
        let info = &self.joints[j];
        let joint_frame = self.model.frames.append(ir::Frame {
            name,
            parent: Some(parent_frame),
            origin: info.parent_point.clone(),
            orientation: info.parent_frame.clone(),
            motion,
            span: decl.span,
        });
        self.record_joint(j, Vec::new(), quaternion, joint_frame);
        joint_frame
    }

    /// The IR joint, and the springs and dampers of its coordinates.
    fn record_joint(
        &mut self,
        j: usize,
        coordinates: Vec<Handle<ir::Coordinate>>,
        quaternion: Option<Handle<ir::Quaternion>>,
        frame: Handle<ir::Frame>,
    ) {
        let info = &mut self.joints[j];
        let coordinate = match (info.kind, coordinates.as_slice()) {
            (Some(JointKind::Pin | JointKind::Slider), &[coordinate]) => Some(coordinate),
            _ => None,
        };
        info.coordinate = coordinate;
        info.frame = Some(frame);
        let (Some(p), Some(c)) = (info.parent, info.child) else {
            return;
        };
        self.model.joints.append(ir::Joint {
            name: info.decl.name.name.clone(),
            kind: info.kind.unwrap_or(JointKind::Weld),
            parent: (p != 0).then(|| Handle::new(p - 1)),
            child: Handle::new(c - 1),
            coordinates: coordinates.clone(),
            quaternion,
            span: info.decl.span,
        });
        for (i, &coordinate) in coordinates.iter().enumerate() {
            if let Some((stiffness, span)) = info.stiffness.get(i).cloned().flatten() {
                let rest = info.rest[i].clone();
                self.model.loads.push(ir::Load::Spring {
                    coordinate,
                    stiffness,
                    rest,
                    span,
                });
            }
            if let Some((damping, span)) = info.damping.get(i).cloned().flatten() {
                self.model.loads.push(ir::Load::Damper {
                    coordinate,
                    damping,
                    span,
                });
            }
        }
    }

    /// Points: newtonian's named points, then per body its origin, `com` and named points.
    pub(super) fn build_points(&mut self) {
        for owner in 0..self.owners.len() {
            let Some(frame) = self.owners[owner].frame else {
                continue;
            };
            let name = self.owners[owner].name.clone();
            if let Some(body) = &self.owners[owner].body {
                let (span, com) = (self.owners[owner].name_span, body.com.clone());
                let origin = self.model.points.append(ir::Point {
                    name: name.clone(),
                    frame,
                    position: zeros(),
                    span,
                });
                let com = self.model.points.append(ir::Point {
                    name: format!("{name}.com"),
                    frame,
                    position: com,
                    span,
                });
                self.owners[owner].origin_point = Some(origin);
                self.owners[owner].com_point = Some(com);
            }
            let mut handles = Vec::new();
            for point in &self.owners[owner].points {
                handles.push(Some(self.model.points.append(ir::Point {
                    name: format!("{name}.{}", point.name.name),
                    frame,
                    position: point.position.clone(),
                    span: point.name.span,
                })));
            }
            self.owners[owner].point_handles = handles;
        }
    }

    /// Bodies in declaration order (only when every body is in the tree).
    pub(super) fn build_bodies(&mut self) {
        if self
            .owners
            .iter()
            .skip(1)
            .any(|o| o.frame.is_none() || o.body.is_none())
        {
            return;
        }
        for owner in &self.owners[1..] {
            let (Some(frame), Some(body)) = (owner.frame, &owner.body) else {
                continue;
            };
            self.model.bodies.append(ir::Body {
                name: owner.name.clone(),
                frame,
                mass: body.mass.clone(),
                center_of_mass: body.com.clone(),
                inertia: body.inertia.clone(),
                docs: body.docs.clone(),
                span: body.span,
            });
        }
    }
}

/// The inverse of a body-fixed rotation sequence: reversed, with negated angles.
fn inverse(rotation: &[AxisAngle]) -> Vec<AxisAngle> {
    rotation
        .iter()
        .rev()
        .map(|r| AxisAngle {
            axis: r.axis.clone(),
            angle: neg(r.angle.clone()),
        })
        .collect()
}

/// The unit vector along axis `index` (0 = x) of a frame.
fn unit_axis(index: usize) -> Vec3 {
    let mut unit = zeros();
    unit[index] = Expr::one();
    unit
}

/// The two slide directions of a planar joint with unit normal `normal`, so that they and
/// `normal` are right-handed: the axis after `normal`'s largest component in the cycle
/// x → y → z → x, made normal to it (`first`), then `normal × first`. For `normal` = z they
/// are x and y; for x, y and z; for y, z and x.
fn plane_axes(normal: &Vec3) -> [Vec3; 2] {
    let n = normal.clone().map(|c| match c {
        Expr::Number(n) => n,
        _ => Number::int(0),
    });
    let largest = (0..3)
        .max_by(|&a, &b| n[a].to_f64().abs().total_cmp(&n[b].to_f64().abs()))
        .unwrap_or(2);
    let next = (largest + 1) % 3;
    // e − (e·n) n with e the unit vector `next`.
    let along = n[next];
    let projected: Vec<Number> = (0..3)
        .map(|i| {
            let e = Number::int(i64::from(i == next));
            e.sub(along.mul(n[i]))
        })
        .collect();
    let first = normalize(&projected).unwrap_or_else(|| unit_axis(next));
    let f = first.clone().map(|c| match c {
        Expr::Number(n) => n,
        _ => Number::int(0),
    });
    let second = [
        n[1].mul(f[2]).sub(n[2].mul(f[1])),
        n[2].mul(f[0]).sub(n[0].mul(f[2])),
        n[0].mul(f[1]).sub(n[1].mul(f[0])),
    ];
    let second = normalize(&second).unwrap_or_else(|| unit_axis((next + 1) % 3));
    [first, second]
}

/// The twelve body-fixed Euler sequences, as written in `rotation = euler(…)`.
const EULER_SEQUENCES: [&str; 12] = [
    "xyz", "xzy", "yxz", "yzx", "zxy", "zyx", "xyx", "xzx", "yxy", "yzy", "zxz", "zyz",
];

/// The axes (0 = x) of a sequence of [`EULER_SEQUENCES`].
fn parse_euler_sequence(written: &str) -> Option<[usize; 3]> {
    if !EULER_SEQUENCES.contains(&written) {
        return None;
    }
    let mut axes = written.bytes().map(|b| usize::from(b - b'x'));
    Some([axes.next()?, axes.next()?, axes.next()?])
}
