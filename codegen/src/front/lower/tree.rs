//! Joints and the kinematic tree: joint fields, tree order from `newtonian`, and the IR frames,
//! coordinates, points and bodies in parents-first order.
//!
//! Consumes: `joint` declarations and the [`Owner`](super::body::Owner)s.
//! Produces: `model.frames` (newtonian, its frames, then per joint in depth-first order:
//! `j` (for a `free` joint `j.x`, `j.y`, `j.z` first), optionally `j.child`, the child body's
//! frame and its named frames), coordinates, quaternions (`ball`, `free`), joints, springs
//! and dampers, points and bodies; `E04xx` tree errors.

use crate::diag::{Diagnostic, Span};
use crate::front::ast::{self, ExprKind};
use crate::ir::{self, AxisAngle, Dimension, Expr, Handle, JointKind, Motion, Vec3};

use super::body::{missing_field, zeros, FrameRef};
use super::expr::{is_vector, neg, unparen, Ctx, Expect};
use super::{names, Lowerer};

/// A joint after its fields are lowered.
pub struct JointInfo<'a> {
    pub decl: &'a ast::JointDecl,
    pub kind: Option<JointKind>,
    pub parent: Option<usize>,
    pub child: Option<usize>,
    axis: Vec3,
    parent_point: Vec3,
    child_point: Vec3,
    /// Rotation of `parent_frame` relative to the parent's body frame.
    parent_frame: Vec<AxisAngle>,
    /// Rotation of `child_frame` relative to the child's body frame, if it is not that frame.
    child_frame: Option<Vec<AxisAngle>>,
    q0: f64,
    u0: f64,
    /// `q0`, `u0` where they depend on params (`u0 = v / r`): evaluated again at run time.
    q0_expr: Option<Expr>,
    u0_expr: Option<Expr>,
    /// `ball` and `free`: the initial angular velocity relative to the parent (child frame).
    angular_velocity0: [f64; 3],
    /// `free`: the initial velocity of the child's origin, components in the joint frame.
    velocity0: [f64; 3],
    stiffness: Option<(Expr, Span)>,
    rest: Expr,
    damping: Option<(Expr, Span)>,
    pub coordinate: Option<Handle<ir::Coordinate>>,
    pub frame: Option<Handle<ir::Frame>>,
}

const JOINT_FIELDS: [&str; 11] = [
    "axis",
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
];

/// The fields of `JOINT_FIELDS` a joint of `kind` does not take, and why (the label of E0403).
fn fields_not_allowed(kind: JointKind) -> (&'static [&'static str], &'static str) {
    match kind {
        JointKind::Pin | JointKind::Slider => (&["v0"], "only a free joint has `v0`"),
        JointKind::Weld => (
            &["axis", "q0", "u0", "v0", "stiffness", "rest", "damping"],
            "a weld has no degree of freedom",
        ),
        JointKind::Ball => (
            &["axis", "q0", "v0", "stiffness", "rest", "damping"],
            "a ball joint has no single axis or angle",
        ),
        JointKind::Free => (
            &["axis", "q0", "stiffness", "rest", "damping"],
            "a free joint has no single axis or angle",
        ),
    }
}

/// Every joint kind, as written.
const JOINT_KINDS: [(&str, JointKind); 5] = [
    ("pin", JointKind::Pin),
    ("slider", JointKind::Slider),
    ("weld", JointKind::Weld),
    ("ball", JointKind::Ball),
    ("free", JointKind::Free),
];

/// The dimension a scalar joint field must have (pin: angles, slider: lengths).
fn joint_expect(field: &'static str, kind: JointKind) -> Expect<'static> {
    let slider = kind == JointKind::Slider;
    let (mass, length, time, example) = match (field, slider) {
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
            parent_point: zeros(),
            child_point: zeros(),
            parent_frame: Vec::new(),
            child_frame: None,
            q0: 0.0,
            u0: 0.0,
            q0_expr: None,
            u0_expr: None,
            angular_velocity0: [0.0; 3],
            velocity0: [0.0; 3],
            stiffness: None,
            rest: Expr::zero(),
            damping: None,
            coordinate: None,
            frame: None,
        };
        if let Some(axis) = self.joint_axis(decl, kind, field("axis")) {
            info.axis = axis;
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
            Some(kind @ (JointKind::Pin | JointKind::Slider)) => {
                self.lower_joint_dynamics(&mut info, kind, &field);
            }
            Some(JointKind::Ball | JointKind::Free) => self.lower_initial_rates(&mut info, &field),
            _ => {}
        }
        info
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

    fn lower_joint_dynamics<'f>(
        &mut self,
        info: &mut JointInfo,
        kind: JointKind,
        field: &dyn Fn(&str) -> Option<&'f ast::Field>,
    ) {
        let ctx = Ctx::Static("a joint property");
        let scalar = |this: &mut Self, name: &'static str| -> Option<(Expr, Span)> {
            let f = field(name)?;
            let expr = this.lower_scalar_as(&f.value, ctx, &joint_expect(name, kind))?;
            Some((expr, f.value.span))
        };
        if let Some((expr, span)) = scalar(self, "q0") {
            info.q0 = self.evaluate(&expr, span);
            info.q0_expr = Some(expr).filter(Expr::has_params);
        }
        if let Some((expr, span)) = scalar(self, "u0") {
            info.u0 = self.evaluate(&expr, span);
            info.u0_expr = Some(expr).filter(Expr::has_params);
        }
        info.stiffness = scalar(self, "stiffness");
        info.damping = scalar(self, "damping");
        if let Some((rest, _)) = scalar(self, "rest") {
            info.rest = rest;
        }
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
        let mut diagnostic = names::unknown(
            "E0208",
            "joint kind",
            "joint kinds",
            &kind.name,
            kind.span,
            &JOINT_KINDS.map(|(name, _)| name),
            "not a joint kind",
        );
        let synonym = match kind.name.as_str() {
            "revolute" | "hinge" => Some("pin"),
            "prismatic" => Some("slider"),
            "fixed" | "rigid" => Some("weld"),
            "spherical" | "socket" => Some("ball"),
            "floating" | "free_flyer" | "freejoint" | "six_dof" => Some("free"),
            _ => None,
        };
        if let Some(synonym) = synonym {
            diagnostic =
                diagnostic.with_help(format!("a {} joint is called `{synonym}` here", kind.name));
        }
        self.error(diagnostic);
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
            let (not_allowed, why) = fields_not_allowed(kind);
            if not_allowed.contains(&name) {
                let takes: Vec<&str> = JOINT_FIELDS
                    .iter()
                    .copied()
                    .filter(|f| !not_allowed.contains(f))
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
            (Some(JointKind::Pin | JointKind::Slider), None) => {
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
                let expect = Expect {
                    dim: Dimension::LENGTH,
                    what,
                    example: "[0, 5 mm, 0]",
                };
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
            _ => self.build_single(j, parent_frame),
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

    /// The frame of a `pin`, `slider` or `weld` joint: at `parent_point`, oriented by
    /// `parent_frame`, moved by the joint's one coordinate (none for a weld).
    fn build_single(&mut self, j: usize, parent_frame: Handle<ir::Frame>) -> Handle<ir::Frame> {
        let info = &self.joints[j];
        let (decl, kind) = (info.decl, info.kind.unwrap_or(JointKind::Weld));
        let coordinate = match kind {
            JointKind::Weld => None,
            _ => Some(self.model.coordinates.append(ir::Coordinate {
                name: decl.name.name.clone(),
                dimension: if kind == JointKind::Slider {
                    Dimension::LENGTH
                } else {
                    Dimension::NONE
                },
                initial: info.q0,
                initial_speed: info.u0,
                span: decl.name.span,
            })),
        };
        if let Some(coordinate) = coordinate {
            let written = [(info.q0_expr.clone(), false), (info.u0_expr.clone(), true)];
            for (expr, speed) in written {
                if let Some(expr) = expr {
                    let value = ir::InitialValue {
                        coordinate,
                        speed,
                        expr,
                    };
                    self.model.initial_values.push(value);
                }
            }
        }
        let info = &self.joints[j];
        let motion = match (kind, coordinate) {
            (JointKind::Pin, Some(coordinate)) => Motion::Revolute {
                axis: info.axis.clone(),
                coordinate,
            },
            (JointKind::Slider, Some(coordinate)) => Motion::Prismatic {
                axis: info.axis.clone(),
                coordinate,
            },
            _ => Motion::Fixed,
        };
        let joint_frame = self.model.frames.append(ir::Frame {
            name: decl.name.name.clone(),
            parent: Some(parent_frame),
            origin: info.parent_point.clone(),
            orientation: info.parent_frame.clone(),
            motion,
            span: decl.span,
        });
        self.record_joint(j, coordinate.into_iter().collect(), None, joint_frame);
        joint_frame
    }

    /// The frames of a `ball` joint (one, turned by a quaternion) or a `free` joint (slides
    /// `j.x`, `j.y`, `j.z` along the axes of the frame at `parent_point` oriented by
    /// `parent_frame`, then the ball `j`): the free joint's speeds are the velocity of the
    /// child's origin in that frame (`u = q̇`) and the child's angular velocity in its own.
    fn build_spherical(&mut self, j: usize, parent_frame: Handle<ir::Frame>) -> Handle<ir::Frame> {
        let info = &self.joints[j];
        let decl = info.decl;
        let name = decl.name.name.clone();
        let mut coordinates = Vec::new();
        let (mut parent, mut origin, mut orientation) = (
            parent_frame,
            info.parent_point.clone(),
            info.parent_frame.clone(),
        );
        if info.kind == Some(JointKind::Free) {
            let velocity0 = info.velocity0;
            for (axis, part) in ["x", "y", "z"].into_iter().enumerate() {
                let coordinate = self.model.coordinates.append(ir::Coordinate {
                    name: format!("{name}.{part}"),
                    dimension: Dimension::LENGTH,
                    initial: 0.0,
                    initial_speed: velocity0[axis],
                    span: decl.name.span,
                });
                coordinates.push(coordinate);
                let mut unit = zeros();
                unit[axis] = Expr::one();
                parent = self.model.frames.append(ir::Frame {
                    name: format!("{name}.{part}"),
                    parent: Some(parent),
                    origin: std::mem::replace(&mut origin, zeros()),
                    orientation: std::mem::take(&mut orientation),
                    motion: Motion::Prismatic {
                        axis: unit,
                        coordinate,
                    },
                    span: decl.span,
                });
            }
        }
        let info = &self.joints[j];
        let quaternion = self.model.quaternions.append(ir::Quaternion {
            name: name.clone(),
            initial_angular_velocity: info.angular_velocity0,
            span: decl.name.span,
        });
        let joint_frame = self.model.frames.append(ir::Frame {
            name,
            parent: Some(parent),
            origin,
            orientation,
            motion: Motion::Spherical { quaternion },
            span: decl.span,
        });
        self.record_joint(j, coordinates, Some(quaternion), joint_frame);
        joint_frame
    }

    /// The IR joint, and the spring and damper of a joint with one coordinate.
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
            coordinates,
            quaternion,
            span: info.decl.span,
        });
        let Some(coordinate) = coordinate else { return };
        if let Some((stiffness, span)) = info.stiffness.clone() {
            let rest = info.rest.clone();
            self.model.loads.push(ir::Load::Spring {
                coordinate,
                stiffness,
                rest,
                span,
            });
        }
        if let Some((damping, span)) = info.damping.clone() {
            self.model.loads.push(ir::Load::Damper {
                coordinate,
                damping,
                span,
            });
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
