//! Bodies and the Newtonian block: fields, points, frames; axes, rotations, and references to
//! points and frames.
//!
//! Consumes: `body` and `newtonian` declarations.
//! Produces: one [`Owner`] per body (plus the Newtonian one) holding lowered properties, and
//! resolvers for `body.point` / `body.frame` references used by joints, loads and outputs.

use crate::diag::{Diagnostic, Span};
use crate::front::ast::{self, ExprKind, Ident};
use crate::ir::plausible::Rule;
use crate::ir::{self, AxisAngle, Dimension, Expr, Handle, Vec3};
use crate::sym::Number;

use super::expr::{is_vector, unparen, wrong_argument_count, Ctx, Expect};
use super::names::{self, Namespace};
use super::Lowerer;

/// Something points and frames can be fixed in: the Newtonian frame or a body.
pub struct Owner {
    pub name: String,
    pub name_span: Span,
    /// `None` for the Newtonian frame.
    pub body: Option<BodyProps>,
    pub points: Vec<PointInfo>,
    pub frames: Vec<FrameInfo>,
    /// Points and frames share one namespace per owner.
    pub members: Namespace,
    /// Filled when the tree is built.
    pub frame: Option<Handle<ir::Frame>>,
    pub frame_handles: Vec<Option<Handle<ir::Frame>>>,
    pub origin_point: Option<Handle<ir::Point>>,
    pub com_point: Option<Handle<ir::Point>>,
    pub point_handles: Vec<Option<Handle<ir::Point>>>,
}

pub struct BodyProps {
    pub mass: Expr,
    pub com: Vec3,
    pub inertia: ir::Inertia,
    pub docs: Vec<String>,
    pub span: Span,
}

pub struct PointInfo {
    pub name: Ident,
    pub position: Vec3,
}

pub struct FrameInfo {
    pub name: Ident,
    pub rotation: Vec<AxisAngle>,
    pub origin: Vec3,
}

/// A reference to a point: a body's origin, its centre of mass, or a named point.
#[derive(Clone, Copy, Debug)]
pub enum PointRef {
    Origin(usize),
    Com(usize),
    Named(usize, usize),
}

impl PointRef {
    /// The index in `owners` of the body (or `newtonian`, 0) the point is fixed in.
    pub fn owner(self) -> usize {
        match self {
            PointRef::Origin(owner) | PointRef::Com(owner) | PointRef::Named(owner, _) => owner,
        }
    }
}

/// A reference to a frame: a body's (or the Newtonian) frame, a named frame, or a joint's frame.
#[derive(Clone, Copy, Debug)]
pub enum FrameRef {
    Owner(usize),
    Named(usize, usize),
    Joint(usize),
}

pub fn zeros() -> Vec3 {
    [Expr::zero(), Expr::zero(), Expr::zero()]
}

impl Owner {
    pub fn newtonian() -> Owner {
        Owner::new("newtonian".to_string(), Span::default(), None)
    }
    fn new(name: String, name_span: Span, body: Option<BodyProps>) -> Owner {
        Owner {
            name,
            name_span,
            body,
            points: Vec::new(),
            frames: Vec::new(),
            members: Namespace::default(),
            frame: None,
            frame_handles: Vec::new(),
            origin_point: None,
            com_point: None,
            point_handles: Vec::new(),
        }
    }
    fn point_named(&self, name: &str) -> Option<usize> {
        self.points.iter().position(|p| p.name.name == name)
    }
    fn frame_named(&self, name: &str) -> Option<usize> {
        self.frames.iter().position(|f| f.name.name == name)
    }
}

const LENGTH: Dimension = Dimension::LENGTH;
const BODY_FIELDS: [&str; 3] = ["mass", "com", "inertia"];

impl<'a> Lowerer<'a> {
    /// Declares body and joint names (one namespace) and registers the bodies.
    pub(super) fn declare_structure(&mut self, items: &'a [ast::Item]) {
        for item in items {
            let name = match item {
                ast::Item::Body(body) => &body.name,
                ast::Item::Joint(joint) => &joint.name,
                _ => continue,
            };
            if name.name == "newtonian" {
                self.error(names::reserved(name, "the Newtonian (inertial) frame"));
                continue;
            }
            if let Err(diagnostic) = self.structure_names.declare(name, "the body or joint name") {
                self.error(diagnostic);
                continue;
            }
            if let ast::Item::Body(body) = item {
                self.bodies
                    .insert(body.name.name.clone(), self.owners.len());
                self.owners
                    .push(Owner::new(body.name.name.clone(), body.name.span, None));
            }
        }
    }

    /// Lowers the contents of every `body` and `newtonian` block.
    pub(super) fn lower_owners(&mut self, items: &'a [ast::Item]) {
        let mut newtonian_block: Option<Span> = None;
        for item in items {
            match item {
                ast::Item::Body(body) => {
                    if let Some(&owner) = self.bodies.get(&body.name.name) {
                        if self.owners[owner].name_span == body.name.span {
                            self.lower_body(owner, body);
                        }
                    }
                }
                ast::Item::Newtonian(block) => {
                    if let Some(previous) = newtonian_block {
                        let keyword = Ident {
                            name: "newtonian".to_string(),
                            span: block.keyword,
                        };
                        self.error(names::redefinition(&keyword, previous, "the block"));
                        continue;
                    }
                    newtonian_block = Some(block.keyword);
                    self.lower_members(0, &block.members);
                }
                _ => {}
            }
        }
    }

    fn lower_body(&mut self, owner: usize, body: &ast::BodyDecl) {
        let fields = self.lower_members(owner, &body.members);
        let static_ctx = Ctx::Static("a body property");
        let mass = match fields.iter().find(|f| f.name.name == "mass") {
            Some(field) => {
                let expect = Expect::new(Dimension::MASS, "`mass`", "10 g");
                match self.lower_scalar_as(&field.value, static_ctx, &expect) {
                    Some(mass) => {
                        let rule = Rule::Mass(mass.clone());
                        self.require("body", &body.name.name, rule, field.value.span);
                        mass
                    }
                    None => Expr::zero(),
                }
            }
            None => {
                let help = "every body needs a mass, e.g. `mass = 10 g;`";
                self.error(missing_field("body", &body.name, "mass", help));
                Expr::zero()
            }
        };
        let com = match fields.iter().find(|f| f.name.name == "com") {
            Some(field) => {
                let expect = Expect::new(LENGTH, "`com`", "[0, -5 mm, 0]");
                self.lower_vector_as(&field.value, static_ctx, &expect)
                    .unwrap_or_else(zeros)
            }
            None => zeros(),
        };
        let inertia = match fields.iter().find(|f| f.name.name == "inertia") {
            Some(field) => match self.inertia(&field.value) {
                Some(inertia) => {
                    let rule = Rule::Inertia(inertia.clone());
                    self.require("body", &body.name.name, rule, field.value.span);
                    inertia
                }
                None => ir::Inertia::zero(),
            },
            None => ir::Inertia::zero(),
        };
        self.owners[owner].body = Some(BodyProps {
            mass,
            com,
            inertia,
            docs: body.docs.clone(),
            span: body.span,
        });
    }

    /// `[Ixx, Iyy, Izz]` or `[Ixx, Iyy, Izz, Ixy, Iyz, Izx]`.
    fn inertia(&mut self, e: &ast::Expr) -> Option<ir::Inertia> {
        let items = self.vector_items(e, "`inertia`", 0)?;
        if items.len() != 3 && items.len() != 6 {
            self.error(
                Diagnostic::error("E0404", format!("`inertia` needs 3 or 6 entries, found {}", items.len()))
                    .with_label(e.span, "expected 3 or 6 entries")
                    .with_help("write `[Ixx, Iyy, Izz]` for principal axes or `[Ixx, Iyy, Izz, Ixy, Iyz, Izx]`"),
            );
            return None;
        }
        let expect = Expect::new(Dimension::INERTIA, "`inertia`", "[1, 1, 2] * 1e-12 kg*m^2");
        let ctx = Ctx::Static("a body property");
        let entries: Vec<Option<Expr>> = items
            .iter()
            .map(|item| self.lower_scalar_as(item, ctx, &expect))
            .collect();
        let mut entries = entries.into_iter().collect::<Option<Vec<_>>>()?.into_iter();
        let mut next = || entries.next().unwrap_or_else(Expr::zero);
        Some(ir::Inertia {
            xx: next(),
            yy: next(),
            zz: next(),
            xy: next(),
            yz: next(),
            zx: next(),
        })
    }

    /// Lowers points and frames; returns the fields (checked for duplicates and unknown names).
    fn lower_members<'m>(
        &mut self,
        owner: usize,
        members: &'m [ast::Member],
    ) -> Vec<&'m ast::Field> {
        let mut fields: Vec<&ast::Field> = Vec::new();
        for member in members {
            match member {
                ast::Member::Field(field) => {
                    if self.check_body_field(owner, field, &fields) {
                        fields.push(field);
                    }
                }
                ast::Member::Point(point) => self.lower_point(owner, point),
                ast::Member::Frame(frame) => self.lower_frame(owner, frame),
            }
        }
        fields
    }

    fn check_body_field(&mut self, owner: usize, field: &ast::Field, seen: &[&ast::Field]) -> bool {
        if owner == 0 {
            self.error(
                Diagnostic::error(
                    "E0209",
                    format!(
                        "unknown field `{}` in the `newtonian` block",
                        field.name.name
                    ),
                )
                .with_label(field.name.span, "the Newtonian frame has no fields")
                .with_help("a `newtonian` block only holds `point` and `frame` declarations"),
            );
            return false;
        }
        let (list, label) = ("fields of a body", "not a body field");
        self.check_field(field, seen, &BODY_FIELDS, list, label)
    }

    /// The fields of a declaration that are known and not repeated, in order (see
    /// [`check_field`](Self::check_field)).
    pub(super) fn known_fields<'f>(
        &mut self,
        fields: &'f [ast::Field],
        allowed: &[&str],
        list: &str,
        label: &str,
    ) -> Vec<&'f ast::Field> {
        let mut known: Vec<&ast::Field> = Vec::new();
        for field in fields {
            if self.check_field(field, &known, allowed, list, label) {
                known.push(field);
            }
        }
        known
    }

    /// Whether `field` is one of `allowed` (E0209 otherwise: the field `label`led, the allowed
    /// ones listed as `list`) and not among the fields `seen` before it (E0211).
    pub(super) fn check_field(
        &mut self,
        field: &ast::Field,
        seen: &[&ast::Field],
        allowed: &[&str],
        list: &str,
        label: &str,
    ) -> bool {
        let name = &field.name;
        if !allowed.contains(&name.name.as_str()) {
            let unknown = names::unknown(
                "E0209", "field", list, &name.name, name.span, allowed, label,
            );
            self.error(unknown);
            return false;
        }
        let Some(previous) = seen.iter().find(|f| f.name.name == field.name.name) else {
            return true;
        };
        self.error(
            Diagnostic::error(
                "E0211",
                format!("field `{}` is given more than once", field.name.name),
            )
            .with_label(field.name.span, "given again here")
            .with_label(previous.name.span, "first given here")
            .with_help("remove one of them"),
        );
        false
    }

    fn declare_member(&mut self, owner: usize, name: &Ident, what: &str) -> bool {
        if name.name == "com" && owner != 0 {
            self.error(names::reserved(name, "the body's centre of mass point"));
            return false;
        }
        match self.owners[owner].members.declare(name, what) {
            Ok(()) => true,
            Err(diagnostic) => {
                self.error(diagnostic);
                false
            }
        }
    }

    fn lower_point(&mut self, owner: usize, point: &ast::PointDecl) {
        let declared = self.declare_member(owner, &point.name, "the point or frame");
        let expect = Expect::new(LENGTH, "a point position", "[0, -25 mm, 0]");
        let position =
            self.lower_vector_as(&point.position, Ctx::Static("a point position"), &expect);
        if declared {
            let position = position.unwrap_or_else(zeros);
            self.owners[owner].points.push(PointInfo {
                name: point.name.clone(),
                position,
            });
        }
    }

    fn lower_frame(&mut self, owner: usize, frame: &ast::FrameDecl) {
        let declared = self.declare_member(owner, &frame.name, "the point or frame");
        let rotation = match &frame.rotation {
            Some(e) => self.rotation(e).unwrap_or_default(),
            None => Vec::new(),
        };
        let origin = match &frame.origin {
            Some(e) => {
                let expect = Expect::new(LENGTH, "a frame origin", "[0, -25 mm, 0]");
                self.lower_vector_as(e, Ctx::Static("a frame origin"), &expect)
                    .unwrap_or_else(zeros)
            }
            None => zeros(),
        };
        if declared {
            self.owners[owner].frames.push(FrameInfo {
                name: frame.name.clone(),
                rotation,
                origin,
            });
        }
    }

    /// `rotate(a, θ) * rotate(b, φ) * ...`: body-fixed rotations applied left to right.
    pub(super) fn rotation(&mut self, e: &ast::Expr) -> Option<Vec<AxisAngle>> {
        let mut factors = Vec::new();
        collect_product(e, &mut factors);
        let lowered: Vec<Option<AxisAngle>> = factors.iter().map(|f| self.rotate_call(f)).collect();
        lowered.into_iter().collect()
    }

    fn rotate_call(&mut self, e: &ast::Expr) -> Option<AxisAngle> {
        let ExprKind::Call { function, args } = &e.kind else {
            self.error(not_a_rotation(e.span));
            return None;
        };
        if function.name != "rotate" {
            self.error(not_a_rotation(e.span));
            return None;
        }
        let [axis, angle] = args.as_slice() else {
            self.error(
                wrong_argument_count("rotate", "2 arguments", args.len())
                    .with_label(e.span, "expected `rotate(axis, angle)`"),
            );
            return None;
        };
        let axis = self.axis(axis, "a rotation axis");
        let expect = Expect::new(Dimension::NONE, "a rotation angle", "30 deg");
        let angle = self.lower_scalar_as(angle, Ctx::Static("a rotation angle"), &expect);
        Some(AxisAngle {
            axis: axis?,
            angle: angle?,
        })
    }

    /// `x`, `y`, `z`, `-x`, `-y`, `-z`, or a constant `[ax, ay, az]`, normalized.
    pub(super) fn axis(&mut self, e: &ast::Expr, what: &'static str) -> Option<Vec3> {
        let e = unparen(e);
        if let Some(axis) = named_axis(e) {
            return Some(axis);
        }
        if !is_vector(e) {
            self.error(
                Diagnostic::error("E0412", format!("expected an axis for {what}"))
                    .with_label(e.span, "not an axis")
                    .with_help(
                        "write `x`, `y`, `z`, `-x`, `-y`, `-z` or a constant vector `[ax, ay, az]`",
                    ),
            );
            return None;
        }
        let items = self.vector_items(e, what, 3)?;
        let components: Vec<Option<Number>> = items
            .iter()
            .map(|item| self.axis_component(item, what))
            .collect();
        let components: Vec<Number> = components.into_iter().collect::<Option<_>>()?;
        match normalize(&components) {
            Some(axis) => Some(axis),
            None => {
                self.error(
                    Diagnostic::error("E0405", "an axis must be a nonzero vector")
                        .with_label(e.span, "this has length zero (or is out of range)")
                        .with_help("give a direction, e.g. `[0, 0, 1]`"),
                );
                None
            }
        }
    }

    fn axis_component(&mut self, e: &ast::Expr, what: &'static str) -> Option<Number> {
        let (number, dim) = self.lower_constant(e, Ctx::Constant(what))?;
        let typed_dim_ok = dim == Dimension::NONE;
        if !typed_dim_ok {
            self.error(
                Diagnostic::error(
                    "E0302",
                    format!(
                        "{what} must be dimensionless, found {}",
                        crate::front::units::describe(dim)
                    ),
                )
                .with_label(e.span, "has a unit")
                .with_help("an axis is a direction: write plain numbers such as `[1, 1, 0]`"),
            );
            return None;
        }
        Some(number)
    }

    /// Resolves `body`, `body.com`, `body.point` or `newtonian.point`.
    pub(super) fn resolve_point(&mut self, path: &ast::Path) -> Option<PointRef> {
        match path.segments.as_slice() {
            [owner] => {
                if owner.name == "newtonian" {
                    self.error(
                        Diagnostic::error("E0213", "`newtonian` is a frame, not a point")
                            .with_label(owner.span, "expected a point")
                            .with_help("declare a point: `newtonian { point anchor = [0, 0, 0]; }` and use `newtonian.anchor`"),
                    );
                    return None;
                }
                Some(PointRef::Origin(self.resolve_body(owner)?))
            }
            [owner_name, point] => {
                let owner = self.resolve_owner(owner_name)?;
                if point.name == "com" && owner != 0 {
                    return Some(PointRef::Com(owner));
                }
                if let Some(index) = self.owners[owner].point_named(&point.name) {
                    return Some(PointRef::Named(owner, index));
                }
                self.unknown_member(owner, point, path, "point");
                None
            }
            _ => {
                self.error(
                    Diagnostic::error("E0202", "expected a point")
                        .with_label(path.span, "not a point reference")
                        .with_help("write `body` (its origin), `body.com`, `body.point` or `newtonian.point`"),
                );
                None
            }
        }
    }

    /// Resolves `newtonian`, `body`, `body.frame`, `newtonian.frame`, and (if allowed) a joint.
    pub(super) fn resolve_frame(
        &mut self,
        path: &ast::Path,
        allow_joints: bool,
    ) -> Option<FrameRef> {
        match path.segments.as_slice() {
            [name] => {
                if name.name == "newtonian" {
                    return Some(FrameRef::Owner(0));
                }
                if let Some(&owner) = self.bodies.get(&name.name) {
                    return Some(FrameRef::Owner(owner));
                }
                if let (true, Some(&joint)) = (allow_joints, self.joint_index.get(&name.name)) {
                    return Some(FrameRef::Joint(joint));
                }
                let mut candidates = vec!["newtonian"];
                candidates.extend(self.owners.iter().skip(1).map(|o| o.name.as_str()));
                if allow_joints {
                    candidates.extend(self.joints.iter().map(|j| j.decl.name.name.as_str()));
                }
                self.error(names::unknown(
                    "E0203",
                    "frame",
                    "frames in scope",
                    &name.name,
                    name.span,
                    &candidates,
                    names::NOT_DECLARED,
                ));
                None
            }
            [owner_name, frame] => {
                let owner = self.resolve_owner(owner_name)?;
                if let Some(index) = self.owners[owner].frame_named(&frame.name) {
                    return Some(FrameRef::Named(owner, index));
                }
                self.unknown_member(owner, frame, path, "frame");
                None
            }
            _ => {
                self.error(
                    Diagnostic::error("E0203", "expected a frame")
                        .with_label(path.span, "not a frame reference")
                        .with_help("write `newtonian`, `body`, `body.frame` or `newtonian.frame`"),
                );
                None
            }
        }
    }

    fn unknown_member(&mut self, owner: usize, name: &Ident, path: &ast::Path, kind: &str) {
        let owner_name = self.owners[owner].name.clone();
        let full = format!("{owner_name}.{}", name.name);
        let (is_point, is_frame) = (
            self.owners[owner].point_named(&name.name).is_some(),
            self.owners[owner].frame_named(&name.name).is_some(),
        );
        if is_point || is_frame {
            let actual = if is_point { "point" } else { "frame" };
            self.error(
                Diagnostic::error("E0213", format!("`{full}` is a {actual}, not a {kind}"))
                    .with_label(path.span, format!("expected a {kind}")),
            );
            return;
        }
        let (code, candidates): (&'static str, Vec<&str>) = if kind == "point" {
            let mut points: Vec<&str> = self.owners[owner]
                .points
                .iter()
                .map(|p| p.name.name.as_str())
                .collect();
            if owner != 0 {
                points.push("com");
            }
            ("E0202", points)
        } else {
            (
                "E0203",
                self.owners[owner]
                    .frames
                    .iter()
                    .map(|f| f.name.name.as_str())
                    .collect(),
            )
        };
        let plural = format!("{kind}s of `{owner_name}`");
        let mut diagnostic = names::unknown(
            code,
            kind,
            &plural,
            &full,
            name.span,
            &candidates,
            names::NOT_DECLARED,
        );
        if let Some(best) = crate::diag::closest(&name.name, &candidates) {
            diagnostic = diagnostic.with_help(format!("did you mean `{owner_name}.{best}`?"));
        }
        self.error(diagnostic);
    }

    /// `newtonian` or a body name → owner index.
    pub(super) fn resolve_owner(&mut self, name: &Ident) -> Option<usize> {
        if name.name == "newtonian" {
            return Some(0);
        }
        self.resolve_body(name)
    }

    /// A body name (not `newtonian`) → owner index, or an "unknown body" error.
    pub(super) fn resolve_body(&mut self, name: &Ident) -> Option<usize> {
        if let Some(&owner) = self.bodies.get(&name.name) {
            return Some(owner);
        }
        let candidates: Vec<&str> = self
            .owners
            .iter()
            .skip(1)
            .map(|o| o.name.as_str())
            .collect();
        let mut diagnostic = names::unknown(
            "E0201",
            "body",
            "bodies in scope",
            &name.name,
            name.span,
            &candidates,
            names::NOT_DECLARED,
        );
        if self.joint_index.contains_key(&name.name) {
            diagnostic =
                diagnostic.with_help(format!("`{}` is a joint; name a body here", name.name));
        }
        self.error(diagnostic);
        None
    }

    /// The position of a referenced point in its owner's frame.
    pub(super) fn point_position(&self, point: PointRef) -> Vec3 {
        match point {
            PointRef::Origin(_) => zeros(),
            PointRef::Com(owner) => self.owners[owner]
                .body
                .as_ref()
                .map_or_else(zeros, |b| b.com.clone()),
            PointRef::Named(owner, index) => self.owners[owner].points[index].position.clone(),
        }
    }

    pub(super) fn point_owner(point: PointRef) -> usize {
        match point {
            PointRef::Origin(owner) | PointRef::Com(owner) | PointRef::Named(owner, _) => owner,
        }
    }
}

/// E0402: `<what> `name`` lacks its required `field`.
pub(super) fn missing_field(what: &str, name: &Ident, field: &str, help: &str) -> Diagnostic {
    Diagnostic::error("E0402", format!("{what} `{}` has no `{field}`", name.name))
        .with_label(name.span, format!("missing `{field} = ...;`"))
        .with_help(help)
}

/// Flattens `a * b * c` (through parentheses) into its factors, left to right.
fn collect_product<'e>(e: &'e ast::Expr, out: &mut Vec<&'e ast::Expr>) {
    match &unparen(e).kind {
        ExprKind::Binary {
            op: ast::BinaryOp::Mul,
            lhs,
            rhs,
        } => {
            collect_product(lhs, out);
            collect_product(rhs, out);
        }
        _ => out.push(unparen(e)),
    }
}

fn not_a_rotation(span: Span) -> Diagnostic {
    Diagnostic::error("E0412", "expected a rotation")
        .with_label(span, "not a rotation")
        .with_help("write `rotate(axis, angle)`, or a product `rotate(x, 10 deg) * rotate(z, a)` applied left to right")
}

/// `x`, `-y`, ... as a unit vector.
fn named_axis(e: &ast::Expr) -> Option<Vec3> {
    let (path, sign) = match &e.kind {
        ExprKind::Path(path) => (path, 1),
        ExprKind::Neg(inner) => match &unparen(inner).kind {
            ExprKind::Path(path) => (path, -1),
            _ => return None,
        },
        _ => return None,
    };
    let [name] = path.segments.as_slice() else {
        return None;
    };
    let index = ["x", "y", "z"].iter().position(|axis| *axis == name.name)?;
    let mut axis = zeros();
    axis[index] = Expr::Number(Number::int(sign));
    Some(axis)
}

/// Scales `v` to unit length, exactly if its length is rational; `None` if zero or not finite.
pub fn normalize(v: &[Number]) -> Option<Vec3> {
    let [x, y, z] = v else { return None };
    let norm2 = x.mul(*x).add(y.mul(*y)).add(z.mul(*z));
    let value = norm2.to_f64();
    if value == 0.0 || !value.is_finite() {
        return None;
    }
    let norm = exact_sqrt(norm2).unwrap_or(Number::Float(value.sqrt()));
    let unit = |c: &Number| {
        let q = match norm {
            Number::Rational(..) => c.div(norm),
            Number::Float(n) => Number::Float(c.to_f64() / n),
        };
        Expr::Number(q)
    };
    Some([unit(x), unit(y), unit(z)])
}

fn exact_sqrt(n: Number) -> Option<Number> {
    let Number::Rational(num, den) = n else {
        return None;
    };
    Some(Number::rational(
        integer_sqrt(num)? as i128,
        integer_sqrt(den)? as i128,
    ))
}

fn integer_sqrt(n: i64) -> Option<i64> {
    if n < 0 {
        return None;
    }
    let guess = (n as f64).sqrt() as i64;
    (guess.saturating_sub(1)..=guess.saturating_add(1)).find(|r| r.checked_mul(*r) == Some(n))
}
