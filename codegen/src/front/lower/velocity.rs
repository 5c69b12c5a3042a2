//! Velocity (nonholonomic) constraints: `constraint NAME = velocity(P, B) in F { components }`,
//! `constraint NAME = EXPR;`, and the `rolling` wheel (`rolling NAME between CENTRE and
//! PLANE_POINT { radius; axle; normal; }`).
//!
//! Consumes: `constraint` declarations, after the tree, its points and its frames are built.
//! Produces: `model.velocity_constraints` and their errors: E0420 (not linear in the speeds),
//! E0421 (a term without a speed: the rows must be `A(q) u = 0`), and the E02xx/E04xx of
//! references, fields and clauses.
//!
//! Linearity is decided on the text, before lowering: the speeds an expression can name are
//! `joint.u` and `distance_rate(A, B)` (a `let` cannot hold the motion), so a walk of the
//! syntax tree finds every product of speeds, speed in a function, power or denominator, and
//! every term without a speed, each at its own span.

use crate::diag::{Diagnostic, Span};
use crate::front::ast::{self, BinaryOp, ExprKind};
use crate::ir::{self, Dimension};

use super::expr::{unparen, wrong_argument_count, Ctx};
use super::Lowerer;

/// Degree of an expression in the speeds: constant in them, or linear and homogeneous.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Degree {
    Zero,
    One,
}

const LINEAR_HELP: &str = "a velocity constraint is `A(q) u = 0`: a sum of terms, each one speed \
     (`joint.u`, `distance_rate(A, B)`) times a factor of the coordinates and params";

#[derive(Clone, Copy)]
/// The errors of [`Lowerer::speed_degree`]: what is not linear, and a term without a speed.
pub(super) struct DegreeErrors {
    pub not_linear: fn(Span, &str) -> Diagnostic,
    pub speed_free: fn(Span) -> Diagnostic,
}

/// How [`Lowerer::linear_scalar`] words its errors (E0403 on `in FRAME`: message, label,
/// help; E0403 on a field: message, help; E0401 on time or an input: message, help).
pub(super) struct LinearScalar {
    pub degree: DegreeErrors,
    pub frame: [&'static str; 3],
    pub fields: [&'static str; 2],
    pub varying: [&'static str; 2],
}

/// A scalar velocity constraint's errors (E0420, E0421, …).
const CONSTRAINT_RULES: LinearScalar = LinearScalar {
    degree: DegreeErrors {
        not_linear,
        speed_free,
    },
    frame: [
        "`in FRAME` is only allowed on `velocity(..)`",
        "this constraint is a scalar",
        "only `velocity(point)` has components in a frame",
    ],
    fields: [
        "a scalar constraint takes no fields",
        "write `constraint NAME = EXPR;` (EXPR = 0)",
    ],
    varying: [
        "a constraint may not depend on time or inputs",
        "its rate `Ȧ u` is taken along the motion, which knows no input's rate",
    ],
};

/// E0420 at `span`, saying what is not linear.
fn not_linear(span: Span, what: &str) -> Diagnostic {
    Diagnostic::error("E0420", "constraint is not linear in the speeds")
        .with_label(span, what.to_string())
        .with_help(LINEAR_HELP)
}

/// E0421 at `span`, a term that holds no speed.
fn speed_free(span: Span) -> Diagnostic {
    Diagnostic::error("E0421", "constraint has a term without a speed")
        .with_label(span, "no speed in this term")
        .with_help(
            "velocity constraints are homogeneous, `A(q) u = 0`: a condition on the coordinates \
             alone is a `loop`, and a prescribed speed (`A u = b`) is not supported",
        )
}

impl Lowerer<'_> {
    /// Lowers every `constraint` declaration (after the tree, points and frames are built).
    pub(super) fn lower_velocity_constraints(&mut self, items: &[ast::Item]) {
        for item in items {
            if let ast::Item::Constraint(decl) = item {
                if let Err(diagnostic) = self.structure_names.declare(&decl.head.name, "the name") {
                    self.error(diagnostic);
                }
                let kind = match &unparen(&decl.head.value).kind {
                    ExprKind::Call { function, args } if function.name == "velocity" => {
                        self.point_velocity(decl, function, args)
                    }
                    _ => self.scalar_constraint(decl),
                };
                if let Some(kind) = kind {
                    self.model
                        .velocity_constraints
                        .push(ir::VelocityConstraint {
                            name: decl.head.name.name.clone(),
                            kind,
                            span: decl.head.span,
                        });
                }
            }
            if let ast::Item::Rolling(decl) = item {
                self.lower_rolling(decl);
            }
        }
    }

    /// `velocity(P)` or `velocity(P, B)` `in F { components = [..]; }`: the velocity of B's
    /// material point at P (P's own body without B).
    fn point_velocity(
        &mut self,
        decl: &ast::ConstraintDecl,
        function: &ast::Ident,
        args: &[ast::Expr],
    ) -> Option<ir::VelocityKind> {
        let (point_arg, body_arg) = match args {
            [point] => (point, None),
            [point, body] => (point, Some(body)),
            _ => {
                self.error(
                    wrong_argument_count("velocity", "1 or 2 arguments", args.len()).with_label(
                        decl.head.value.span,
                        "expected `velocity(point)` or `velocity(point, body)`",
                    ),
                );
                return None;
            }
        };
        let point = self.point_argument(function, point_arg);
        let body = match body_arg.map(|b| &unparen(b).kind) {
            None => point.map(|p| p.owner()),
            Some(ExprKind::Path(path)) if path.segments.len() == 1 => {
                self.resolve_body(&path.segments[0])
            }
            Some(_) => {
                self.error(
                    Diagnostic::error("E0213", "expected a body in `velocity(point, body)`")
                        .with_label(args[1].span, "not a body name")
                        .with_help("name the body whose material point at `point` is meant"),
                );
                None
            }
        };
        let frame = match &decl.head.frame {
            Some(path) => self.resolve_frame(path, true),
            None => Some(super::body::FrameRef::Owner(0)),
        };
        let allowed = ["components"];
        let fields = decl.fields.as_deref().unwrap_or_default();
        let fields = self.known_fields(
            fields,
            &allowed,
            "fields of a velocity constraint",
            "not a field of a constraint",
        );
        let components = match fields.first() {
            Some(field) => self.component_list(&field.value),
            None => Some(vec![0, 1, 2]),
        };
        let point = self.point_handle(point?)?;
        let body = self.owners[body?].frame?;
        let frame = self.frame_handle(frame?)?;
        Some(ir::VelocityKind::PointVelocity {
            point,
            body,
            frame,
            components: components?,
        })
    }

    /// `constraint NAME = EXPR;`: EXPR = 0, linear and homogeneous in the speeds, of the
    /// motion and params (not of time or inputs: its rate would need theirs).
    fn scalar_constraint(&mut self, decl: &ast::ConstraintDecl) -> Option<ir::VelocityKind> {
        self.linear_scalar(decl, &CONSTRAINT_RULES)
            .map(|(expr, _)| ir::VelocityKind::Scalar(expr))
    }

    /// `NAME = EXPR;` of a `constraint` or `speed`: EXPR lowered, if it is linear and
    /// homogeneous in the speeds, not of time or inputs, with no `in FRAME` and no block
    /// (each refused as `rules` word it).
    pub(super) fn linear_scalar(
        &mut self,
        decl: &ast::ConstraintDecl,
        rules: &LinearScalar,
    ) -> Option<(ir::Expr, Dimension)> {
        let mut ok = true;
        if let Some(frame) = &decl.head.frame {
            let [message, label, help] = rules.frame;
            self.error(
                Diagnostic::error("E0403", message)
                    .with_label(frame.span, label)
                    .with_help(help),
            );
            ok = false;
        }
        if let Some(field) = decl.fields.as_ref().and_then(|f| f.first()) {
            let [message, help] = rules.fields;
            self.error(
                Diagnostic::error("E0403", message)
                    .with_label(field.name.span, "not allowed here")
                    .with_help(help),
            );
            ok = false;
        }
        let degree = self.speed_degree(&decl.head.value, &rules.degree);
        let typed = self.lower_scalar(&decl.head.value, Ctx::Load);
        match degree {
            Ok(Degree::One) => {}
            Ok(Degree::Zero) => {
                self.error((rules.degree.speed_free)(decl.head.value.span));
                ok = false;
            }
            Err(diagnostic) => {
                self.error(diagnostic);
                ok = false;
            }
        }
        let typed = typed?;
        if let Some(span) = self.time_or_input(&decl.head.value) {
            let [message, help] = rules.varying;
            self.error(
                Diagnostic::error("E0401", message)
                    .with_label(span, "time or an input")
                    .with_help(help),
            );
            ok = false;
        }
        ok.then_some((typed.expr, typed.dim))
    }

    /// Where `e` first names time, an input, or a `let` that depends on them.
    pub(super) fn time_or_input(&self, e: &ast::Expr) -> Option<Span> {
        match &e.kind {
            ExprKind::Path(path) => match path.segments.as_slice() {
                [name] if name.name == "t" => Some(e.span),
                [name] => match self.values.get(&name.name) {
                    Some(super::Value::Input(_)) => Some(e.span),
                    Some(super::Value::Let(index)) => self
                        .lets
                        .get(*index)
                        .and_then(|typed| typed.as_ref()?.varying)
                        .map(|_| e.span),
                    _ => None,
                },
                _ => None,
            },
            ExprKind::Quantity { .. } => None,
            ExprKind::Vector(items) | ExprKind::Call { args: items, .. } => {
                items.iter().find_map(|item| self.time_or_input(item))
            }
            ExprKind::Neg(inner) | ExprKind::Paren(inner) => self.time_or_input(inner),
            ExprKind::Binary { lhs, rhs, .. } => {
                self.time_or_input(lhs).or_else(|| self.time_or_input(rhs))
            }
        }
    }

    /// The degree of `e` in the speeds, or the first place where it is not linear and
    /// homogeneous (as `errors` word it).
    pub(super) fn speed_degree(
        &self,
        e: &ast::Expr,
        errors: &DegreeErrors,
    ) -> Result<Degree, Diagnostic> {
        let DegreeErrors {
            not_linear,
            speed_free,
        } = *errors;
        match &e.kind {
            ExprKind::Quantity { .. } | ExprKind::Vector(_) => Ok(Degree::Zero),
            ExprKind::Path(path) => Ok(match path.segments.as_slice() {
                [joint, which]
                    if which.name == "u" && self.joint_index.contains_key(&joint.name) =>
                {
                    Degree::One
                }
                _ => Degree::Zero,
            }),
            ExprKind::Call { function, .. } if function.name == "distance_rate" => Ok(Degree::One),
            ExprKind::Call { function, args } => {
                for arg in args {
                    if self.speed_degree(arg, errors)? == Degree::One {
                        return Err(not_linear(
                            arg.span,
                            &format!("a speed inside `{}`", function.name),
                        ));
                    }
                }
                Ok(Degree::Zero)
            }
            ExprKind::Neg(inner) | ExprKind::Paren(inner) => self.speed_degree(inner, errors),
            ExprKind::Binary { op, lhs, rhs } => {
                let (a, b) = (
                    self.speed_degree(lhs, errors)?,
                    self.speed_degree(rhs, errors)?,
                );
                match (op, a, b) {
                    (_, Degree::Zero, Degree::Zero) => Ok(Degree::Zero),
                    (BinaryOp::Add | BinaryOp::Sub, Degree::One, Degree::One) => Ok(Degree::One),
                    (BinaryOp::Add | BinaryOp::Sub, Degree::One, Degree::Zero) => {
                        Err(speed_free(rhs.span))
                    }
                    (BinaryOp::Add | BinaryOp::Sub, Degree::Zero, Degree::One) => {
                        Err(speed_free(lhs.span))
                    }
                    (BinaryOp::Mul, Degree::One, Degree::One) => {
                        Err(not_linear(e.span, "a product of speeds"))
                    }
                    (BinaryOp::Mul, _, _) | (BinaryOp::Div, Degree::One, Degree::Zero) => {
                        Ok(Degree::One)
                    }
                    (BinaryOp::Div, _, Degree::One) => {
                        Err(not_linear(rhs.span, "a speed in a denominator"))
                    }
                    (BinaryOp::Pow, _, _) => Err(not_linear(e.span, "a power of a speed")),
                }
            }
        }
    }
}

/// The fields of a `rolling` block, all required.
const ROLLING_FIELDS: [&str; 3] = ["radius", "axle", "normal"];

impl Lowerer<'_> {
    /// `rolling NAME between CENTRE and PLANE_POINT { radius; axle; normal; }`: the wheel is
    /// the body `CENTRE` is fixed in, the plane is fixed in `newtonian`.
    pub(super) fn lower_rolling(&mut self, decl: &ast::SpringDecl) {
        if let Err(diagnostic) = self.structure_names.declare(&decl.name, "the name") {
            self.error(diagnostic);
        }
        let [centre, plane] = decl.ends.each_ref().map(|path| self.resolve_point(path));
        let list = "fields of a rolling wheel";
        let known = self.known_fields(&decl.fields, &ROLLING_FIELDS, list, "not a field here");
        let field = |name: &str| known.iter().copied().find(|f| f.name.name == name);
        let expect = super::expr::Expect::mechanical("`radius`", "20 mm", [0, 1, 0]);
        let radius = field("radius")
            .and_then(|f| self.lower_scalar_as(&f.value, Ctx::Static("a wheel's radius"), &expect));
        let axle = field("axle").and_then(|f| self.axis(&f.value, "a wheel's axle"));
        let normal = field("normal").and_then(|f| self.axis(&f.value, "the plane's normal"));
        let mut ok = true;
        for (name, help) in [
            ("radius", "give the wheel's radius, e.g. `radius = 20 mm;`"),
            (
                "axle",
                "give the wheel's axle in its body's frame, e.g. `axle = y;`",
            ),
            (
                "normal",
                "give the plane's upward normal in newtonian, e.g. `normal = z;`",
            ),
        ] {
            if field(name).is_none() {
                self.error(super::body::missing_field(
                    "rolling", &decl.name, name, help,
                ));
                ok = false;
            }
        }
        if centre.is_some_and(|c| c.owner() == 0) {
            self.error(
                Diagnostic::error("E0408", "a rolling wheel's centre is fixed in `newtonian`")
                    .with_label(decl.ends[0].span, "not on a moving body")
                    .with_help("name the wheel's centre, a point of the wheel's body"),
            );
            ok = false;
        }
        if plane.is_some_and(|p| p.owner() != 0) {
            self.error(
                Diagnostic::error("E0414", "the rolling plane must be fixed in `newtonian`")
                    .with_label(decl.ends[1].span, "a point of a moving body")
                    .with_help("name a point of the ground, e.g. `newtonian.floor`"),
            );
            ok = false;
        }
        let (Some(centre), Some(plane), Some(radius), Some(axle), Some(normal), true) =
            (centre, plane, radius, axle, normal, ok)
        else {
            return;
        };
        let (Some(centre), Some(plane)) = (self.point_handle(centre), self.point_handle(plane))
        else {
            return;
        };
        self.model
            .velocity_constraints
            .push(ir::VelocityConstraint {
                name: decl.name.name.clone(),
                kind: ir::VelocityKind::Rolling {
                    centre,
                    axle: Box::new(axle),
                    radius,
                    plane,
                    normal: Box::new(normal),
                },
                span: decl.span,
            });
    }
}
