//! Generalized speeds chosen by the user: `speed NAME = angular_velocity(BODY) in FRAME
//! { axis = z; }`, `speed NAME = velocity(POINT) in FRAME { axis = x; }` and
//! `speed NAME = EXPR;` (a combination of `joint.u`, coefficients of the coordinates).
//!
//! Consumes: `speed` declarations, after the tree, its points and its frames are built.
//! Produces: `model.speeds` and their errors: E0440 (not as many speeds as the model's
//! default speeds), E0441 (the speeds are not independent at the start: `Y(q₀)` singular),
//! E0442 (a combination that is not linear in the speeds), E0443 (a term without a speed:
//! `u = Y(q) ū`, no `Z(q)`), and the E02xx/E04xx of references, fields and clauses.
//!
//! Every speed is linear and homogeneous in the default speeds `ū` (`q̇` of pins and sliders,
//! a ball's ω) by construction: measure numbers of velocities are, and a combination is
//! checked on the text as a velocity constraint is (`velocity.rs`). `kane::derive` writes
//! the equations in the chosen speeds; the initial values are `Y(q₀) ū₀`.

use crate::diag::{Diagnostic, Span};
use crate::front::ast::{self, ExprKind};
use crate::ir::{self, Dimension};

use super::expr::{unparen, wrong_argument_count};
use super::velocity::{DegreeErrors, LinearScalar};
use super::Lowerer;

const SPEED_HELP: &str = "a speed is `u = Y(q) ū`: a sum of terms, each one joint speed \
     (`joint.u`) times a factor of the coordinates and params";

/// A combination's errors: the speeds' versions of E0420/E0421 (E0442, E0443), …
const SPEED_RULES: LinearScalar = LinearScalar {
    degree: DegreeErrors {
        not_linear: |span, what| {
            Diagnostic::error("E0442", "speed is not linear in the joint speeds")
                .with_label(span, what.to_string())
                .with_help(SPEED_HELP)
        },
        speed_free: |span| {
            Diagnostic::error("E0443", "speed has a term without a joint speed")
                .with_label(span, "no joint speed in this term")
                .with_help("a speed is `u = Y(q) ū` with no term of the coordinates alone")
        },
    },
    frame: [
        "`in FRAME` is only allowed on a velocity",
        "this speed is a combination of joint speeds",
        "only `angular_velocity(body)` and `velocity(point)` have a frame",
    ],
    fields: [
        "a combination of joint speeds takes no fields",
        "write `speed NAME = EXPR;`",
    ],
    varying: [
        "a speed may not depend on time or inputs",
        "a speed is `u = Y(q) ū`, of the coordinates and params only",
    ],
};

impl Lowerer<'_> {
    /// Lowers every `speed` declaration (after the tree, points and frames are built).
    pub(super) fn lower_speeds(&mut self, items: &[ast::Item]) {
        let decls: Vec<&ast::ConstraintDecl> = items
            .iter()
            .filter_map(|item| match item {
                ast::Item::Speed(decl) => Some(decl),
                _ => None,
            })
            .collect();
        for decl in &decls {
            if let Err(diagnostic) = self.structure_names.declare(&decl.head.name, "the name") {
                self.error(diagnostic);
            }
            let kind = match &unparen(&decl.head.value).kind {
                ExprKind::Call { function, args }
                    if function.name == "angular_velocity" || function.name == "velocity" =>
                {
                    self.measure_number(decl, function, args).map(|kind| {
                        let dimension = match kind {
                            ir::SpeedKind::PointVelocity { .. } => Dimension::LENGTH,
                            _ => Dimension::NONE,
                        };
                        (kind, dimension.div(Dimension::TIME))
                    })
                }
                _ => self.speed_combination(decl),
            };
            if let Some((kind, dimension)) = kind {
                self.model.speeds.push(ir::ChosenSpeed {
                    name: decl.head.name.name.clone(),
                    kind,
                    dimension,
                    initial: 0.0,
                    span: decl.head.span,
                });
            }
        }
    }

    /// E0440 unless the model declares no speed or exactly one per default speed (counted
    /// on the complete model: a flexure's twist adds a coordinate). Whether an error was
    /// reported.
    fn check_speed_count(&mut self) -> bool {
        let expected = self.model.nu();
        let speeds = &self.model.speeds;
        let (Some(last), true) = (speeds.last(), speeds.len() != expected) else {
            return false;
        };
        let (span, label) = match speeds.get(expected) {
            Some(first_extra) => (
                first_extra.span,
                format!("one speed too many: the model has {expected}"),
            ),
            None => (
                last.span,
                format!("the last of {}: the model has {expected}", speeds.len()),
            ),
        };
        let defaults = self.model.default_speed_names().join(", ");
        self.error(
            Diagnostic::error(
                "E0440",
                format!(
                    "{} `speed` declared for a model with {expected} speeds",
                    speeds.len()
                ),
            )
            .with_label(span, label)
            .with_help(format!(
                "declare no `speed` (the default speeds: {defaults}) or exactly one per default speed"
            )),
        );
        true
    }

    /// `angular_velocity(BODY) in FRAME { axis }` or `velocity(POINT) in FRAME { axis }`.
    fn measure_number(
        &mut self,
        decl: &ast::ConstraintDecl,
        function: &ast::Ident,
        args: &[ast::Expr],
    ) -> Option<ir::SpeedKind> {
        let angular = function.name == "angular_velocity";
        let [arg] = args else {
            let expected = match angular {
                true => "expected `angular_velocity(body)`",
                false => "expected `velocity(point)`",
            };
            self.error(
                wrong_argument_count(&function.name, "1 argument", args.len())
                    .with_label(decl.head.value.span, expected),
            );
            return None;
        };
        let body = angular.then(|| self.body_argument(arg)).flatten();
        let point = (!angular)
            .then(|| self.point_argument(function, arg))
            .flatten();
        let frame = match &decl.head.frame {
            Some(path) => self.resolve_frame(path, true),
            None => Some(super::body::FrameRef::Owner(0)),
        };
        let fields = decl.fields.as_deref().unwrap_or_default();
        let fields = self.known_fields(fields, &["axis"], "fields of a speed", "not a field here");
        let axis = match fields.first() {
            Some(field) => self.axis(&field.value, "a speed's axis"),
            None => {
                self.error(super::body::missing_field(
                    "speed",
                    &decl.head.name,
                    "axis",
                    "give the axis of the measure number in the frame after `in`, e.g. \
                     `{ axis = z; }`",
                ));
                None
            }
        };
        let frame = self.frame_handle(frame?)?;
        let axis = Box::new(axis?);
        match angular {
            true => Some(ir::SpeedKind::AngularVelocity {
                body: self.owners[body?].frame?,
                frame,
                axis,
            }),
            false => Some(ir::SpeedKind::PointVelocity {
                point: self.point_handle(point?)?,
                frame,
                axis,
            }),
        }
    }

    /// The body named by `angular_velocity(BODY)`'s argument.
    fn body_argument(&mut self, arg: &ast::Expr) -> Option<usize> {
        match &unparen(arg).kind {
            ExprKind::Path(path) if path.segments.len() == 1 => {
                self.resolve_body(&path.segments[0])
            }
            _ => {
                self.error(
                    Diagnostic::error("E0213", "expected a body in `angular_velocity(body)`")
                        .with_label(arg.span, "not a body name")
                        .with_help("name the body whose angular velocity is meant"),
                );
                None
            }
        }
    }

    /// `speed NAME = EXPR;`: linear and homogeneous in the joint speeds, of the coordinates
    /// and params (not of time or inputs).
    fn speed_combination(
        &mut self,
        decl: &ast::ConstraintDecl,
    ) -> Option<(ir::SpeedKind, Dimension)> {
        self.linear_scalar(decl, &SPEED_RULES)
            .map(|(expr, dimension)| (ir::SpeedKind::Scalar(expr), dimension))
    }

    /// E0440 (their count), else E0441 where the chosen speeds are not independent at the
    /// initial coordinates (`Y(q₀)` singular); else sets each speed's initial value
    /// `Y(q₀) ū₀`. On a complete model only.
    pub(super) fn check_speeds_independent(&mut self) {
        if !self.diagnostics.is_empty() || self.check_speed_count() {
            return;
        }
        if self.model.speeds.is_empty() {
            return;
        }
        match crate::kane::chosen_speeds_at_start(&self.model, &self.param_values) {
            Ok(initial) => {
                for (speed, value) in self.model.speeds.iter_mut().zip(initial) {
                    speed.initial = value;
                }
            }
            Err(dependent) => {
                let span: Span = self.model.speeds[dependent].span;
                self.error(
                    Diagnostic::error(
                        "E0441",
                        "the speeds are not independent at the initial coordinates",
                    )
                    .with_label(span, "a combination of the other speeds at `q0`")
                    .with_help(
                        "the joints' rates must follow from the speeds (`Y(q)` invertible): \
                         choose a speed that measures a motion the others miss, or start the \
                         joints (`q0`) away from the singular pose",
                    ),
                );
            }
        }
    }
}
