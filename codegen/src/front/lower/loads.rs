//! Gravity, forces, torques, point-to-point springs and outputs.
//!
//! Consumes: `gravity`, `force`, `torque`, `spring` and `output` declarations.
//! Produces: `model.gravity`, force, torque and point-spring [`ir::Load`]s and
//! [`ir::Output`]s. References are resolved first (collecting every error) and turned into
//! handles once the tree is built.

use crate::diag::{Diagnostic, Span};
use crate::front::ast::{self, ExprKind, Ident};
use crate::ir::{self, Dimension, Expr, Handle, JointKind, Vec3};

use super::body::{missing_field, FrameRef, PointRef};
use super::expr::{unparen, wrong_argument_count, Ctx, Expect, Typed};
use super::names::Namespace;
use super::Lowerer;

pub enum PendingLoad {
    Force {
        point: PointRef,
        frame: FrameRef,
        components: Vec3,
        span: Span,
    },
    Torque {
        body: usize,
        frame: FrameRef,
        components: Vec3,
        span: Span,
    },
    Spring {
        ends: [PointRef; 2],
        stiffness: Expr,
        rest_length: Expr,
        damping: Option<Expr>,
        tension: Option<Expr>,
        span: Span,
    },
    Bushing {
        frames: [FrameRef; 2],
        /// `([translational, rotational] stiffness, [translational, rotational] damping)`.
        law: Box<([Vec3; 2], [Vec3; 2])>,
        span: Span,
    },
    Contact {
        name: String,
        point: PointRef,
        plane: PointRef,
        law: Box<ContactLaw>,
        span: Span,
    },
}

/// The fields of a `bushing` block.
const BUSHING_FIELDS: [&str; 4] = [
    "stiffness",
    "damping",
    "rotational_stiffness",
    "rotational_damping",
];

/// The dimension of a bushing field: N/m, N·s/m, N·m/rad, N·m·s/rad (vectors in A's axes).
fn bushing_expect(field: &str) -> Expect<'static> {
    match field {
        "stiffness" => Expect::mechanical("`stiffness`", "[10, 10, 20] * 1 N/m", [1, 0, -2]),
        "damping" => Expect::mechanical("`damping`", "[1, 1, 1] * 0.01 N*s/m", [1, 0, -1]),
        "rotational_stiffness" => Expect::mechanical(
            "`rotational_stiffness`",
            "[1, 1, 2] * 1 uN*m/rad",
            [1, 2, -2],
        ),
        _ => Expect::mechanical(
            "`rotational_damping`",
            "[1, 1, 1] * 1 nN*m*s/rad",
            [1, 2, -1],
        ),
    }
}

/// The fields of a `contact` block.
const CONTACT_FIELDS: [&str; 8] = [
    "normal",
    "radius",
    "stiffness",
    "exponent",
    "reference_depth",
    "damping",
    "friction",
    "transition_speed",
];

/// A contact's law as [`ir::Load::Contact`] holds it.
pub struct ContactLaw {
    normal: Vec3,
    radius: Expr,
    stiffness: Expr,
    exponent: crate::sym::Number,
    damping: Expr,
    friction: Expr,
    transition_speed: Expr,
}

/// The dimension of a contact field: N/m, m, s/m, m/s or none.
fn contact_expect(field: &str) -> Expect<'static> {
    match field {
        "stiffness" => Expect::mechanical("`stiffness`", "1e4 N/m", [1, 0, -2]),
        "damping" => Expect::mechanical("`damping`", "0.5 s/m", [0, -1, 1]),
        "transition_speed" => Expect::mechanical("`transition_speed`", "1 mm/s", [0, 1, -1]),
        "friction" => Expect::mechanical("`friction`", "0.5", [0, 0, 0]),
        "reference_depth" => Expect::mechanical("`reference_depth`", "0.1 mm", [0, 1, 0]),
        _ => Expect::mechanical("`radius`", "2 mm", [0, 1, 0]),
    }
}

/// The fields of a `spring` block.
const SPRING_FIELDS: [&str; 4] = ["stiffness", "rest_length", "damping", "tension"];

/// The dimension of a spring field: N/m, m, N·s/m, N.
fn spring_expect(field: &str) -> Expect<'static> {
    match field {
        "stiffness" => Expect::mechanical("`stiffness`", "10 N/m", [1, 0, -2]),
        "damping" => Expect::mechanical("`damping`", "0.01 N*s/m", [1, 0, -1]),
        "tension" => Expect::mechanical("`tension`", "2 mN", [1, 1, -2]),
        _ => Expect::mechanical("`rest_length`", "5 mm", [0, 1, 0]),
    }
}

pub struct PendingOutput {
    name: String,
    docs: Vec<String>,
    span: Span,
    kind: PendingKind,
}

enum PendingKind {
    Position(PointRef, FrameRef),
    Velocity(PointRef, FrameRef),
    Coordinate(usize),
    Speed(usize),
    KineticEnergy,
    PotentialEnergy,
    Expr(Expr),
    /// `contact(NAME)`.
    Contact(String),
}

impl Lowerer<'_> {
    pub(super) fn lower_loads_and_outputs(&mut self, items: &[ast::Item]) {
        let mut load_names = Namespace::default();
        let mut output_names = Namespace::default();
        let mut gravity: Option<Span> = None;
        for item in items {
            if let ast::Item::Contact(decl) = item {
                self.contacts.entry(decl.name.name.clone()).or_insert(None);
            }
        }
        for item in items {
            // Every kind of load is named in one namespace, declared before it is lowered.
            let load_name = match item {
                ast::Item::Force(decl) | ast::Item::Torque(decl) => Some(&decl.name),
                ast::Item::Spring(decl) | ast::Item::Contact(decl) | ast::Item::Bushing(decl) => {
                    Some(&decl.name)
                }
                _ => None,
            };
            if let Some(name) = load_name {
                self.declare_in(&mut load_names, name, "the load");
            }
            match item {
                ast::Item::Gravity(decl) => {
                    if let Some(previous) = gravity {
                        let name = Ident {
                            name: "gravity".to_string(),
                            span: decl.span,
                        };
                        self.error(super::names::redefinition(
                            &name,
                            previous,
                            "the declaration",
                        ));
                        continue;
                    }
                    gravity = Some(decl.span);
                    self.lower_gravity(decl);
                }
                ast::Item::Force(decl) => self.lower_force(decl),
                ast::Item::Torque(decl) => self.lower_torque(decl),
                ast::Item::Spring(decl) => self.lower_spring(decl),
                ast::Item::Contact(decl) => self.lower_contact(decl),
                ast::Item::Bushing(decl) => self.lower_bushing(decl),
                ast::Item::Output(decl)
                    if self.declare_in(&mut output_names, &decl.name, "the output") =>
                {
                    self.lower_output(decl);
                }
                _ => {}
            }
        }
    }

    fn declare_in(&mut self, namespace: &mut Namespace, name: &Ident, what: &str) -> bool {
        match namespace.declare(name, what) {
            Ok(()) => true,
            Err(diagnostic) => {
                self.error(diagnostic);
                false
            }
        }
    }

    fn lower_gravity(&mut self, decl: &ast::GravityDecl) {
        let expect = Expect::new(Dimension::ACCELERATION, "`gravity`", "[0, -9.81 m/s^2, 0]");
        self.model.gravity = self.lower_vector_as(&decl.value, Ctx::Static("gravity"), &expect);
    }

    fn lower_force(&mut self, decl: &ast::VectorLoadDecl) {
        let point = self.resolve_point(&decl.target);
        let expect = Expect::new(Dimension::FORCE, "a force", "[0, 1 mN, 0]");
        let vector = self.load_vector(&decl.value, decl.frame.as_ref(), &expect);
        if let (Some(point), Some((components, frame))) = (point, vector) {
            self.loads.push(PendingLoad::Force {
                point,
                frame,
                components,
                span: decl.span,
            });
        }
    }

    fn lower_torque(&mut self, decl: &ast::VectorLoadDecl) {
        let body = match decl.target.segments.as_slice() {
            [name] if name.name != "newtonian" => self.resolve_body(name),
            _ => {
                self.error(
                    Diagnostic::error("E0213", "a torque acts on a body")
                        .with_label(decl.target.span, "expected a body name")
                        .with_help("write `torque NAME on BODY = [tx, ty, tz] in FRAME;`"),
                );
                None
            }
        };
        let expect = Expect::new(Dimension::TORQUE, "a torque", "[0, 0, 1 uN*m]");
        let vector = self.load_vector(&decl.value, decl.frame.as_ref(), &expect);
        if let (Some(body), Some((components, frame))) = (body, vector) {
            self.loads.push(PendingLoad::Torque {
                body,
                frame,
                components,
                span: decl.span,
            });
        }
    }

    /// `spring NAME between A and B { stiffness; rest_length; damping; tension; }`: `stiffness`
    /// is required unless a `tension` law is given (a pure damper writes `stiffness = 0 N/m;`
    /// on purpose), `rest_length` defaults to 0, `damping` and `tension` to none; the ends are
    /// on two different bodies. `tension` may use the motion (as a force may).
    fn lower_spring(&mut self, decl: &ast::SpringDecl) {
        let ends = decl.ends.each_ref().map(|path| self.resolve_point(path));
        let fields = self.known_fields(
            &decl.fields,
            &SPRING_FIELDS,
            "fields of a spring",
            "not a field of a spring",
        );
        let ctx = Ctx::Static("a spring property");
        let scalar = |this: &mut Self, name: &str| {
            let field = fields.iter().find(|f| f.name.name == name)?;
            Some(this.lower_scalar_as(&field.value, ctx, &spring_expect(name)))
        };
        let stiffness = scalar(self, "stiffness");
        let rest_length = scalar(self, "rest_length");
        let damping = scalar(self, "damping");
        let tension = fields
            .iter()
            .find(|f| f.name.name == "tension")
            .map(|field| self.lower_scalar_as(&field.value, Ctx::Load, &spring_expect("tension")));
        if stiffness.is_none() && tension.is_none() {
            let help =
                "add the spring's stiffness along its line, e.g. `stiffness = 10 N/m;`, or a \
                    tension law, e.g. `tension = 1e4 N/m^3 * (distance(A, B) - 5 mm)^3;`";
            self.error(missing_field("spring", &decl.name, "stiffness", help));
        }
        if let [Some(a), Some(b)] = ends {
            self.check_spring_ends(decl, a, b);
        }
        // Each `Some(None)` is a field whose error is already reported.
        let stiffness = match stiffness {
            None => Expr::zero(),
            Some(Some(stiffness)) => stiffness,
            Some(None) => return,
        };
        let [Some(a), Some(b)] = ends else {
            return;
        };
        let tension = match tension {
            None => None,
            Some(Some(tension)) => Some(tension),
            Some(None) => return,
        };
        let rest_length = match rest_length {
            None => Expr::zero(),
            Some(Some(rest_length)) => rest_length,
            Some(None) => return,
        };
        let damping = match damping {
            None => None,
            Some(Some(damping)) => Some(damping),
            Some(None) => return,
        };
        self.loads.push(PendingLoad::Spring {
            ends: [a, b],
            stiffness,
            rest_length,
            damping,
            tension,
            span: decl.span,
        });
    }

    /// E0408 if both ends of a spring are on one body (or both fixed in `newtonian`): its
    /// length could not change, so it would do nothing (its forces on the body cancel).
    fn check_spring_ends(&mut self, decl: &ast::SpringDecl, a: PointRef, b: PointRef) {
        let help = "a spring acts between points of two different bodies (or a body and \
                    `newtonian`); between two points of one rigid body its length never changes";
        self.check_two_bodies("spring", decl, [a, b], help);
    }

    /// E0408 if both points of a two-point declaration (`what`: spring, contact) are on one
    /// body (or both fixed in `newtonian`).
    fn check_two_bodies(
        &mut self,
        what: &str,
        decl: &ast::SpringDecl,
        [a, b]: [PointRef; 2],
        help: &str,
    ) {
        if a.owner() != b.owner() {
            return;
        }
        let owner = self.owners[a.owner()].name.clone();
        self.error(
            Diagnostic::error(
                "E0408",
                format!("{what} `{}` connects `{owner}` to itself", decl.name.name),
            )
            .with_label(decl.ends[1].span, "this point")
            .with_label(decl.ends[0].span, format!("is on `{owner}` too"))
            .with_help(help.to_string()),
        );
    }

    /// `contact NAME between P and Q { normal; stiffness; … }` (see [`ir::Load::Contact`]):
    /// `normal` (an axis in the frame Q is fixed in) and `stiffness` are required; `radius`,
    /// `damping` and `friction` default to 0; `exponent` to 3/2 with a radius and 1 without;
    /// an exponent other than 1 needs `reference_depth` δ₀, with which the elastic force is
    /// `k δ₀ (δ/δ₀)^e` (N for `k` in N/m at any exponent); `friction` needs
    /// `transition_speed`. The properties may use params (checked by E0506 at run time too).
    fn lower_contact(&mut self, decl: &ast::SpringDecl) {
        let ends = decl.ends.each_ref().map(|path| self.resolve_point(path));
        let fields = self.known_fields(
            &decl.fields,
            &CONTACT_FIELDS,
            "fields of a contact",
            "not a field of a contact",
        );
        let field = |name: &str| fields.iter().find(|f| f.name.name == name).copied();
        let ctx = Ctx::Static("a contact property");
        let mut failed = false;
        let mut property = |this: &mut Self, name: &'static str, positive: bool| {
            let field = field(name)?;
            let value = this.lower_scalar_as(&field.value, ctx, &contact_expect(name));
            if let Some(value) = &value {
                let (unit, rule_value) = (contact_expect(name).example, value.clone());
                let unit = unit.split_once(' ').map_or("", |(_, unit)| unit);
                let rule = ir::plausible::Rule::ContactProperty {
                    field: name,
                    unit,
                    value: rule_value,
                    positive,
                };
                this.require("contact", &decl.name.name, rule, field.value.span);
            }
            failed |= value.is_none();
            value
        };
        let radius = property(self, "radius", false);
        let stiffness = property(self, "stiffness", true);
        let depth = property(self, "reference_depth", true);
        let damping = property(self, "damping", false);
        let friction = property(self, "friction", false);
        let transition_speed = property(self, "transition_speed", true);
        let normal = field("normal").and_then(|f| self.axis(&f.value, "a contact's normal"));
        let exponent = match field("exponent") {
            None if radius.is_some() => Some(crate::sym::Number::rational(3, 2)),
            None => Some(crate::sym::Number::ONE),
            Some(f) => self.contact_exponent(&decl.name.name, &f.value),
        };
        for (name, present, help) in [
            (
                "normal",
                field("normal").is_some(),
                "give the plane's outward normal in the frame of its point, e.g. `normal = y;`",
            ),
            (
                "stiffness",
                field("stiffness").is_some(),
                "give the contact's stiffness, e.g. `stiffness = 1e4 N/m;`",
            ),
        ] {
            if !present {
                self.error(missing_field("contact", &decl.name, name, help));
            }
        }
        let nonlinear = exponent.is_some_and(|e| !e.is_one());
        if nonlinear && field("reference_depth").is_none() {
            let help = "with an exponent e other than 1 the elastic force is `k δ₀ (δ/δ₀)^e`: \
                        give the depth δ₀ at which it is `k δ₀`, e.g. `reference_depth = 0.1 mm;` \
                        (or write `exponent = 1;`)";
            self.error(missing_field(
                "contact",
                &decl.name,
                "reference_depth",
                help,
            ));
        }
        if field("friction").is_some() && field("transition_speed").is_none() {
            let help = "friction is regularized below a slip speed v_s: give it, e.g. \
                        `transition_speed = 1 mm/s;`";
            self.error(missing_field(
                "contact",
                &decl.name,
                "transition_speed",
                help,
            ));
        }
        if let [Some(a), Some(b)] = ends {
            let help = "a contact acts between a point of one body and a plane fixed in \
                        another body (or in `newtonian`)";
            self.check_two_bodies("contact", decl, [a, b], help);
        }
        let (Some(stiffness), Some(normal), Some(exponent), [Some(point), Some(plane)], false) =
            (stiffness, normal, exponent, ends, failed)
        else {
            return;
        };
        // k δ₀ (δ/δ₀)^e = k δ₀^(1−e) δ^e.
        let stiffness = match depth {
            Some(depth) if nonlinear => {
                stiffness * Expr::Pow(Box::new(depth), crate::sym::Number::ONE.sub(exponent))
            }
            _ => stiffness,
        };
        let law = ContactLaw {
            normal,
            radius: radius.unwrap_or_else(Expr::zero),
            stiffness,
            exponent,
            damping: damping.unwrap_or_else(Expr::zero),
            friction: friction.unwrap_or_else(Expr::zero),
            transition_speed: transition_speed.unwrap_or(Expr::Number(crate::sym::Number::ONE)),
        };
        self.loads.push(PendingLoad::Contact {
            name: decl.name.name.clone(),
            point,
            plane,
            law: Box::new(law),
            span: decl.span,
        });
    }

    /// `bushing NAME between A and B { stiffness; damping; rotational_stiffness;
    /// rotational_damping; }` (see [`ir::Load::Bushing`]): A and B are body or Newtonian
    /// frames of two different bodies (E0408); each field is a vector in A's axes, default
    /// zero, of params.
    fn lower_bushing(&mut self, decl: &ast::SpringDecl) {
        let frames = decl
            .ends
            .each_ref()
            .map(|path| self.resolve_frame(path, false));
        let fields = self.known_fields(
            &decl.fields,
            &BUSHING_FIELDS,
            "fields of a bushing",
            "not a field of a bushing",
        );
        let ctx = Ctx::Static("a bushing property");
        let mut values: Vec<Option<Vec3>> = Vec::new();
        for name in BUSHING_FIELDS {
            let value = match fields.iter().find(|f| f.name.name == name) {
                Some(field) => self.lower_vector_as(&field.value, ctx, &bushing_expect(name)),
                None => Some([Expr::zero(), Expr::zero(), Expr::zero()]),
            };
            values.push(value);
        }
        let owner = |frame: FrameRef| match frame {
            FrameRef::Owner(owner) | FrameRef::Named(owner, _) => Some(owner),
            FrameRef::Joint(_) => None,
        };
        if let [Some(a), Some(b)] = frames {
            if owner(a).is_some() && owner(a) == owner(b) {
                let name = self.owners[owner(a).unwrap_or(0)].name.clone();
                self.error(
                    Diagnostic::error(
                        "E0408",
                        format!("bushing `{}` connects `{name}` to itself", decl.name.name),
                    )
                    .with_label(decl.ends[1].span, "this frame")
                    .with_label(decl.ends[0].span, format!("is on `{name}` too"))
                    .with_help(
                        "a bushing couples frames of two different bodies (or a body and \
                         `newtonian`)",
                    ),
                );
                return;
            }
        }
        let ([Some(a), Some(b)], [Some(k), Some(c), Some(k_r), Some(c_r)]) = (
            frames,
            <[Option<Vec3>; 4]>::try_from(values).unwrap_or_default(),
        ) else {
            return;
        };
        self.loads.push(PendingLoad::Bushing {
            frames: [a, b],
            law: Box::new(([k, k_r], [c, c_r])),
            span: decl.span,
        });
    }

    /// A contact's `exponent`: a positive dimensionless constant.
    fn contact_exponent(&mut self, name: &str, e: &ast::Expr) -> Option<crate::sym::Number> {
        let (number, dim) = self.lower_constant(e, Ctx::Constant("a contact's exponent"))?;
        if dim != Dimension::NONE {
            self.error(
                Diagnostic::error("E0302", "a contact's `exponent` must be dimensionless")
                    .with_label(e.span, "has a unit")
                    .with_help("write a plain number, e.g. `exponent = 1.5;`"),
            );
            return None;
        }
        let rule = ir::plausible::Rule::ContactProperty {
            field: "exponent",
            unit: "",
            value: Expr::Number(number),
            positive: true,
        };
        let before = self.diagnostics.len();
        self.require("contact", name, rule, e.span);
        (self.diagnostics.len() == before).then_some(number)
    }

    /// The components of a force or torque and the frame they are given in.
    fn load_vector(
        &mut self,
        value: &ast::Expr,
        frame: Option<&ast::Path>,
        expect: &Expect,
    ) -> Option<(Vec3, FrameRef)> {
        let components = self.lower_vector_as(value, Ctx::Load, expect);
        let frame = self.frame_clause(frame);
        Some((components?, frame?))
    }

    /// `in FRAME`, defaulting to the Newtonian frame.
    fn frame_clause(&mut self, path: Option<&ast::Path>) -> Option<FrameRef> {
        match path {
            Some(path) => self.resolve_frame(path, true),
            None => Some(FrameRef::Owner(0)),
        }
    }

    fn lower_output(&mut self, decl: &ast::OutputDecl) {
        let value = unparen(&decl.value);
        let kind = match &value.kind {
            ExprKind::Call { function, args }
                if function.name == "position" || function.name == "velocity" =>
            {
                self.vector_output(function, args, value.span, decl.frame.as_ref())
            }
            ExprKind::Call { function, args } if function.name == "contact" => {
                self.contact_output(args, value.span, decl)
            }
            ExprKind::Path(path) => self.path_output(path, decl),
            _ => self.expr_output(decl),
        };
        if let Some(kind) = kind {
            let output = PendingOutput {
                name: decl.name.name.clone(),
                docs: decl.docs.clone(),
                span: decl.span,
                kind,
            };
            self.outputs.push(output);
        }
    }

    fn vector_output(
        &mut self,
        function: &Ident,
        args: &[ast::Expr],
        span: Span,
        frame: Option<&ast::Path>,
    ) -> Option<PendingKind> {
        let [arg] = args else {
            self.error(
                wrong_argument_count(&function.name, "1 argument", args.len())
                    .with_label(span, format!("expected `{}(point)`", function.name)),
            );
            return None;
        };
        let point = self.point_argument(function, arg);
        let frame = self.frame_clause(frame);
        let (point, frame) = (point?, frame?);
        Some(match function.name.as_str() {
            "position" => PendingKind::Position(point, frame),
            _ => PendingKind::Velocity(point, frame),
        })
    }

    /// `contact(NAME)`: the outputs of a declared contact ([`ir::CONTACT_OUTPUTS`]).
    fn contact_output(
        &mut self,
        args: &[ast::Expr],
        span: Span,
        decl: &ast::OutputDecl,
    ) -> Option<PendingKind> {
        let name = match args {
            [arg] => match &unparen(arg).kind {
                ExprKind::Path(path) => match path.segments.as_slice() {
                    [name] => Some(name),
                    _ => None,
                },
                _ => None,
            },
            _ => None,
        };
        let Some(name) = name else {
            self.error(
                Diagnostic::error("E0404", "`contact` takes the name of one contact")
                    .with_label(span, "expected `contact(NAME)`"),
            );
            return None;
        };
        self.reject_frame_clause(decl)?;
        if !self.contacts.contains_key(&name.name) {
            let known: Vec<&str> = self.contacts.keys().map(String::as_str).collect();
            self.error(super::names::unknown(
                "E0418",
                "contact",
                "contacts",
                &name.name,
                name.span,
                &known,
                "not a contact",
            ));
            return None;
        }
        Some(PendingKind::Contact(name.name.clone()))
    }

    fn path_output(&mut self, path: &ast::Path, decl: &ast::OutputDecl) -> Option<PendingKind> {
        let kind = match path.segments.as_slice() {
            [name] if name.name == "kinetic_energy" => PendingKind::KineticEnergy,
            [name] if name.name == "potential_energy" => PendingKind::PotentialEnergy,
            [joint, which]
                if self.joint_index.contains_key(&joint.name)
                    && (which.name == "q" || which.name == "u") =>
            {
                let j = self.single_coordinate_joint(joint, path.span)?;
                if which.name == "q" {
                    PendingKind::Coordinate(j)
                } else {
                    PendingKind::Speed(j)
                }
            }
            _ => return self.expr_output(decl),
        };
        self.reject_frame_clause(decl)?;
        if let Some(value) = self.output_value(&kind, path.span) {
            self.scalar_outputs.insert(decl.name.name.clone(), value);
        }
        Some(kind)
    }

    /// A scalar output as an expression later outputs may use.
    fn output_value(&self, kind: &PendingKind, span: Span) -> Option<Typed> {
        let (term, dim) = match *kind {
            PendingKind::KineticEnergy => (ir::StateTerm::KineticEnergy, Dimension::ENERGY),
            PendingKind::PotentialEnergy => (ir::StateTerm::PotentialEnergy, Dimension::ENERGY),
            PendingKind::Coordinate(j) | PendingKind::Speed(j) => {
                let coordinate = self.joints.get(j)?.coordinate?;
                let dim = self.model.coordinates[coordinate].dimension;
                if let PendingKind::Coordinate(_) = kind {
                    (ir::StateTerm::Coordinate(coordinate), dim)
                } else {
                    let rate = crate::front::units::dim_div(dim, Dimension::TIME)?;
                    (ir::StateTerm::Speed(coordinate), rate)
                }
            }
            _ => return None,
        };
        Some(Typed::leaf(Expr::State(term), dim, Some(span)))
    }

    /// A point given as an argument of `function` (`position(arm.tip)`, `distance(A, B)`).
    pub(super) fn point_argument(&mut self, function: &Ident, arg: &ast::Expr) -> Option<PointRef> {
        let ExprKind::Path(path) = &unparen(arg).kind else {
            self.error(
                Diagnostic::error("E0412", format!("expected a point in `{}`", function.name))
                    .with_label(arg.span, "not a point")
                    .with_help(
                        "write a point such as `arm.tip`, `arm.com`, `arm` or `newtonian.anchor`",
                    ),
            );
            return None;
        };
        self.resolve_point(path)
    }

    /// The index of `joint` if it has one coordinate (a pin or slider); E0213 for a weld (none)
    /// and for `ball` and `free` (a quaternion).
    /// E0213 for `joint.q` or `joint.u` of a joint with several coordinates.
    fn several_coordinates(&mut self, joint: &Ident, span: Span, what: &str, why: &str) {
        self.error(
            Diagnostic::error(
                "E0213",
                format!("{what} joint `{}` has no single coordinate", joint.name),
            )
            .with_label(span, why)
            .with_help(
                "use the motion of a point of the child body, \
                 `position(body.point)` or `velocity(body.point)` as outputs, \
                 `distance(A, B)` in a load",
            ),
        );
    }

    pub(super) fn single_coordinate_joint(&mut self, joint: &Ident, span: Span) -> Option<usize> {
        let j = *self.joint_index.get(&joint.name)?;
        match self.joints.get(j).and_then(|info| info.kind) {
            Some(JointKind::Weld) => {
                self.error(
                    Diagnostic::error(
                        "E0213",
                        format!("weld joint `{}` has no coordinate", joint.name),
                    )
                    .with_label(span, "a weld has no degree of freedom"),
                );
                None
            }
            Some(kind @ (JointKind::Ball | JointKind::Free)) => {
                let what = if kind == JointKind::Ball {
                    "ball"
                } else {
                    "free"
                };
                self.several_coordinates(joint, span, what, "its orientation is a unit quaternion");
                None
            }
            Some(kind @ (JointKind::Universal | JointKind::Cylindrical | JointKind::Planar)) => {
                let what = match kind {
                    JointKind::Universal => "universal",
                    JointKind::Cylindrical => "cylindrical",
                    _ => "planar",
                };
                self.several_coordinates(joint, span, what, "it has a coordinate per freedom");
                None
            }
            _ => Some(j),
        }
    }

    fn expr_output(&mut self, decl: &ast::OutputDecl) -> Option<PendingKind> {
        let typed = self.lower_scalar(&decl.value, Ctx::Output);
        self.reject_frame_clause(decl)?;
        let typed = typed?;
        self.scalar_outputs
            .insert(decl.name.name.clone(), typed.clone());
        Some(PendingKind::Expr(typed.expr))
    }

    fn reject_frame_clause(&mut self, decl: &ast::OutputDecl) -> Option<()> {
        let Some(frame) = &decl.frame else {
            return Some(());
        };
        self.error(
            Diagnostic::error("E0403", "`in FRAME` is only allowed on vector outputs")
                .with_label(frame.span, "this output is a scalar")
                .with_help(
                    "only `position(point)` and `velocity(point)` have components in a frame",
                ),
        );
        None
    }

    // -----------------------------------------------------------------------------------------
    // Handles
    // -----------------------------------------------------------------------------------------

    pub(super) fn point_handle(&self, point: PointRef) -> Option<Handle<ir::Point>> {
        match point {
            PointRef::Origin(owner) => self.owners[owner].origin_point,
            PointRef::Com(owner) => self.owners[owner].com_point,
            PointRef::Named(owner, index) => self.owners[owner]
                .point_handles
                .get(index)
                .copied()
                .flatten(),
        }
    }

    pub(super) fn frame_handle(&self, frame: FrameRef) -> Option<Handle<ir::Frame>> {
        match frame {
            FrameRef::Owner(owner) => self.owners[owner].frame,
            FrameRef::Named(owner, index) => self.owners[owner]
                .frame_handles
                .get(index)
                .copied()
                .flatten(),
            FrameRef::Joint(joint) => self.joints.get(joint).and_then(|j| j.frame),
        }
    }

    /// Records an internal error if a reference could not be mapped although no error explains it.
    fn unresolved(&mut self, span: Span) {
        if self.diagnostics.is_empty() {
            self.error(
                Diagnostic::error("E0100", "internal error: a reference was not resolved")
                    .with_label(span, "here")
                    .with_help("this is a bug in mech-codegen; please report it with the file"),
            );
        }
    }

    pub(super) fn build_loads(&mut self) {
        for load in std::mem::take(&mut self.loads) {
            let built = match &load {
                PendingLoad::Force {
                    point,
                    frame,
                    components,
                    span,
                } => {
                    let handles = self.point_handle(*point).zip(self.frame_handle(*frame));
                    handles.map(|(point, frame)| ir::Load::Force {
                        point,
                        force: ir::FrameVector {
                            frame,
                            components: components.clone(),
                        },
                        span: *span,
                    })
                }
                PendingLoad::Torque {
                    body,
                    frame,
                    components,
                    span,
                } => {
                    let handles = self.owners[*body].frame.zip(self.frame_handle(*frame));
                    handles.map(|(body_frame, frame)| ir::Load::Torque {
                        frame: body_frame,
                        torque: ir::FrameVector {
                            frame,
                            components: components.clone(),
                        },
                        span: *span,
                    })
                }
                PendingLoad::Spring {
                    ends,
                    stiffness,
                    rest_length,
                    damping,
                    tension,
                    span,
                } => {
                    let handles = self.point_handle(ends[0]).zip(self.point_handle(ends[1]));
                    handles.map(|(a, b)| ir::Load::PointSpring {
                        ends: [a, b],
                        stiffness: stiffness.clone(),
                        rest_length: rest_length.clone(),
                        damping: damping.clone(),
                        tension: tension.clone(),
                        span: *span,
                    })
                }
                PendingLoad::Bushing { frames, law, span } => {
                    let handles = self
                        .frame_handle(frames[0])
                        .zip(self.frame_handle(frames[1]));
                    handles.map(|(a, b)| ir::Load::Bushing {
                        frames: [a, b],
                        stiffness: law.0.clone(),
                        damping: law.1.clone(),
                        span: *span,
                    })
                }
                PendingLoad::Contact {
                    name,
                    point,
                    plane,
                    law,
                    span,
                } => {
                    let handles = self.point_handle(*point).zip(self.point_handle(*plane));
                    if handles.is_some() {
                        self.contacts
                            .insert(name.clone(), Some(self.model.loads.len()));
                    }
                    handles.map(|(point, plane)| ir::Load::Contact {
                        point,
                        plane,
                        normal: law.normal.clone(),
                        radius: law.radius.clone(),
                        stiffness: law.stiffness.clone(),
                        exponent: law.exponent,
                        damping: law.damping.clone(),
                        friction: law.friction.clone(),
                        transition_speed: law.transition_speed.clone(),
                        span: *span,
                    })
                }
            };
            match built {
                Some(load) => self.model.loads.push(load),
                None => self.unresolved(load_span(&load)),
            }
        }
    }

    pub(super) fn build_outputs(&mut self) {
        for output in std::mem::take(&mut self.outputs) {
            let kind = match output.kind {
                PendingKind::Position(point, frame) => self
                    .point_handle(point)
                    .zip(self.frame_handle(frame))
                    .map(|(point, frame)| ir::OutputKind::Position { point, frame }),
                PendingKind::Velocity(point, frame) => self
                    .point_handle(point)
                    .zip(self.frame_handle(frame))
                    .map(|(point, frame)| ir::OutputKind::Velocity { point, frame }),
                PendingKind::Coordinate(j) => self
                    .joints
                    .get(j)
                    .and_then(|j| j.coordinate)
                    .map(ir::OutputKind::Coordinate),
                PendingKind::Speed(j) => self
                    .joints
                    .get(j)
                    .and_then(|j| j.coordinate)
                    .map(ir::OutputKind::Speed),
                PendingKind::KineticEnergy => Some(ir::OutputKind::KineticEnergy),
                PendingKind::PotentialEnergy => Some(ir::OutputKind::PotentialEnergy),
                PendingKind::Expr(expr) => Some(ir::OutputKind::Expr(expr)),
                // A contact with errors has none here (already reported).
                PendingKind::Contact(name) => match self.contacts.get(&name) {
                    Some(Some(index)) => Some(ir::OutputKind::Contact(*index)),
                    _ if !self.diagnostics.is_empty() => continue,
                    _ => None,
                },
            };
            match kind {
                Some(kind) => self.model.outputs.push(ir::Output {
                    name: output.name,
                    kind,
                    docs: output.docs,
                    span: output.span,
                }),
                None => self.unresolved(output.span),
            }
        }
    }
}

fn load_span(load: &PendingLoad) -> Span {
    match load {
        PendingLoad::Force { span, .. }
        | PendingLoad::Torque { span, .. }
        | PendingLoad::Spring { span, .. }
        | PendingLoad::Bushing { span, .. }
        | PendingLoad::Contact { span, .. } => *span,
    }
}
