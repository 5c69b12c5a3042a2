//! Scalar expressions: name resolution, units, dimension checking and constant folding.
//!
//! Consumes: [`ast::Expr`] trees and a [`Ctx`] saying what they may refer to.
//! Produces: [`Typed`] IR expressions (SI, `let`s inlined, numeric subtrees folded exactly
//! where possible) with their dimension; `E02xx`/`E03xx`/`E04xx` diagnostics.

use crate::diag::{Diagnostic, Span};
use crate::front::ast::{self, BinaryOp, ExprKind, MAX_SIZE};
use crate::front::units::{self, describe, dim_div, dim_mul, dim_pow, UnitError};
use crate::ir::{self, Dimension, Expr, Function};
use crate::sym::Number;

use super::{names, Lowerer, Value};

/// Deepest expression tree accepted after inlining `let`s (the largest: [`MAX_SIZE`]).
const MAX_DEPTH: usize = 400;

/// E0404: a call with the wrong number of arguments; `takes` is what it takes (`2 arguments`,
/// `1 or 2 arguments`). The caller labels the call with what a right one looks like.
pub(super) fn wrong_argument_count(name: &str, takes: &str, found: usize) -> Diagnostic {
    Diagnostic::error("E0404", format!("`{name}` takes {takes}, found {found}"))
}

/// What an expression may refer to.
#[derive(Clone, Copy, Debug)]
pub enum Ctx {
    /// Numbers, units and `pi` only (param values, axes, exponents); names what is being lowered.
    Constant(&'static str),
    /// Also params and `let`s of params (body properties, initial values); not time or inputs.
    Static(&'static str),
    /// Also inputs and time `t` (`let`s, an actuator's voltage); names what is being lowered.
    Dynamic(&'static str),
    /// Also the motion: `joint.q`, `joint.u`, `distance(A, B)`, `distance_rate(A, B)` (forces
    /// and torques).
    Load,
    /// Also the energies and the scalar outputs declared above (outputs).
    Output,
}

impl Ctx {
    /// What is being lowered, for messages (`None` where the state is allowed).
    fn what(self) -> Option<&'static str> {
        match self {
            Ctx::Constant(what) | Ctx::Static(what) | Ctx::Dynamic(what) => Some(what),
            Ctx::Load | Ctx::Output => None,
        }
    }
}

/// A lowered scalar expression with its dimension.
#[derive(Clone, Debug)]
pub struct Typed {
    pub expr: Expr,
    pub dim: Dimension,
    /// Where the expression first depends on time or an input, if it does.
    pub varying: Option<Span>,
    size: usize,
    depth: usize,
}

impl Typed {
    pub(super) fn leaf(expr: Expr, dim: Dimension, varying: Option<Span>) -> Typed {
        Typed {
            expr,
            dim,
            varying,
            size: 1,
            depth: 1,
        }
    }
    /// A node built from `parts`, inheriting their size, depth and time dependence.
    fn node(expr: Expr, dim: Dimension, parts: &[&Typed]) -> Typed {
        let size = parts.iter().map(|p| p.size).sum::<usize>() + 1;
        let depth = parts.iter().map(|p| p.depth).max().unwrap_or(0) + 1;
        let varying = parts.iter().find_map(|p| p.varying);
        Typed {
            expr,
            dim,
            varying,
            size,
            depth,
        }
    }
    /// A plain zero (`0`, `-0`, `0.0`) fits any dimension.
    pub fn is_plain_zero(&self) -> bool {
        self.dim == Dimension::NONE && matches!(self.expr, Expr::Number(n) if n.is_zero())
    }
}

/// The dimension an expression must have, for messages: `what` names the place (`` `mass` ``)
/// and `example` shows a correct value (`10 g`).
pub struct Expect<'w> {
    pub dim: Dimension,
    pub what: &'w str,
    pub example: &'static str,
}

impl<'w> Expect<'w> {
    pub fn new(dim: Dimension, what: &'w str, example: &'static str) -> Self {
        Expect { dim, what, example }
    }

    /// A mechanical quantity (no current) of dimension mass^m · length^l · time^t.
    pub fn mechanical(what: &'w str, example: &'static str, [mass, length, time]: [i8; 3]) -> Self {
        let dim = Dimension {
            mass,
            length,
            time,
            current: 0,
        };
        Expect::new(dim, what, example)
    }
}

impl Lowerer<'_> {
    /// Lowers a scalar expression.
    pub(super) fn lower_scalar(&mut self, e: &ast::Expr, ctx: Ctx) -> Option<Typed> {
        let typed = match &e.kind {
            ExprKind::Quantity { literal, unit } => {
                self.quantity(literal, unit.as_ref(), e.span)?
            }
            ExprKind::Path(path) => self.path_value(path, ctx)?,
            ExprKind::Vector(_) => {
                self.error(
                    Diagnostic::error("E0411", "expected a scalar, found a vector")
                        .with_label(e.span, "a vector is not allowed here")
                        .with_help("vectors `[x, y, z]` are only used where a position, axis, force or torque is expected"),
                );
                return None;
            }
            ExprKind::Call { function, args } => self.call(function, args, e.span, ctx)?,
            ExprKind::Neg(operand) => {
                let operand = self.lower_scalar(operand, ctx)?;
                Typed::node(neg(operand.expr.clone()), operand.dim, &[&operand])
            }
            ExprKind::Binary { op, lhs, rhs } => self.binary(*op, lhs, rhs, ctx)?,
            ExprKind::Paren(inner) => self.lower_scalar(inner, ctx)?,
        };
        self.check_size(typed, e.span)
    }

    /// Lowers a scalar and checks its dimension against `expect`.
    pub(super) fn lower_scalar_as(
        &mut self,
        e: &ast::Expr,
        ctx: Ctx,
        expect: &Expect,
    ) -> Option<Expr> {
        let typed = self.lower_scalar(e, ctx)?;
        self.check_dimension(&typed, expect, e.span)
            .then_some(typed.expr)
    }

    /// Lowers `[x, y, z]` with each component of the expected dimension.
    pub(super) fn lower_vector_as(
        &mut self,
        e: &ast::Expr,
        ctx: Ctx,
        expect: &Expect,
    ) -> Option<ir::Vec3> {
        let items = self.vector_items(e, expect.what, 3)?;
        let components: Vec<Option<Expr>> = items
            .iter()
            .map(|item| self.lower_scalar_as(item, ctx, expect))
            .collect();
        let mut components = components.into_iter();
        let mut next = || components.next().flatten();
        Some([next()?, next()?, next()?])
    }

    /// The components of a vector expression, which must have `count` entries (`0` = any
    /// number). A vector may be scaled: `[1, 2, 3] * 1 mm`, `2 * v`, `[..] / 2`, `-[..]`.
    pub(super) fn vector_items(
        &mut self,
        e: &ast::Expr,
        what: &str,
        count: usize,
    ) -> Option<Vec<ast::Expr>> {
        let Some(items) = vector_components(e) else {
            self.error(
                Diagnostic::error("E0411", format!("{what} must be a vector"))
                    .with_label(e.span, "expected a vector `[x, y, z]`")
                    .with_help("write the components in brackets, e.g. `[0, -1 mm, 0]`"),
            );
            return None;
        };
        if count != 0 && items.len() != count {
            self.error(
                Diagnostic::error(
                    "E0404",
                    format!("{what} needs {count} components, found {}", items.len()),
                )
                .with_label(e.span, format!("expected {count} components"))
                .with_help("a vector is written `[x, y, z]`"),
            );
            return None;
        }
        Some(items)
    }

    /// Lowers a constant expression (numbers, units, `pi`) and folds it to a number.
    pub(super) fn lower_constant(
        &mut self,
        e: &ast::Expr,
        ctx: Ctx,
    ) -> Option<(Number, Dimension)> {
        let typed = self.lower_scalar(e, ctx)?;
        let number = fold(&typed.expr)?;
        if !number.to_f64().is_finite() {
            self.error(not_finite(e.span));
            return None;
        }
        Some((number, typed.dim))
    }

    /// Evaluates a static expression at the params' default values.
    pub(super) fn evaluate(&mut self, expr: &Expr, span: Span) -> f64 {
        match expr.evaluate(&self.param_values) {
            Some(value) if value.is_finite() => value,
            _ => {
                self.error(not_finite(span));
                0.0
            }
        }
    }

    /// `true` if `typed` has the expected dimension; records the error otherwise.
    pub(super) fn check_dimension(&mut self, typed: &Typed, expect: &Expect, span: Span) -> bool {
        if typed.dim == expect.dim || typed.is_plain_zero() {
            return true;
        }
        let found = describe(typed.dim);
        let help = if typed.dim == Dimension::NONE {
            format!(
                "plain numbers and angles are dimensionless; write a unit, for example `{}`",
                expect.example
            )
        } else {
            format!("for example `{}`", expect.example)
        };
        self.error(
            Diagnostic::error(
                "E0302",
                format!(
                    "{} must be {}, found {found}",
                    expect.what,
                    article(expect.dim)
                ),
            )
            .with_label(span, format!("this is {found}"))
            .with_help(help),
        );
        false
    }

    fn check_size(&mut self, typed: Typed, span: Span) -> Option<Typed> {
        if typed.size <= MAX_SIZE && typed.depth <= MAX_DEPTH {
            return Some(typed);
        }
        self.error(
            Diagnostic::error("E0103", "expression is too large")
                .with_label(span, format!("more than {MAX_SIZE} operations or {MAX_DEPTH} levels after inlining `let`s"))
                .with_help("`let` definitions are copied where they are used; use fewer nested `let`s"),
        );
        None
    }

    fn quantity(&mut self, literal: &str, unit: Option<&ast::Unit>, span: Span) -> Option<Typed> {
        let Some(number) = units::parse_literal(literal) else {
            self.error(
                Diagnostic::error("E0102", format!("number `{literal}` is out of range"))
                    .with_label(span, "too large for a 64-bit float")
                    .with_help("use a unit with a prefix, such as `GPa` or `um`"),
            );
            return None;
        };
        let Some(unit) = unit else {
            return Some(Typed::leaf(Expr::Number(number), Dimension::NONE, None));
        };
        let unit_value = match units::evaluate(unit) {
            Ok(value) => value,
            Err(error) => {
                self.unit_error(literal, unit, error);
                return None;
            }
        };
        let value = number.mul(unit_value.scale);
        if !value.to_f64().is_finite() {
            self.error(not_finite(span));
            return None;
        }
        Some(Typed::leaf(Expr::Number(value), unit_value.dimension, None))
    }

    fn unit_error(&mut self, literal: &str, unit: &ast::Unit, error: UnitError) {
        let diagnostic = match error {
            UnitError::Unknown(index) => {
                let Some(factor) = unit.factors.get(index) else {
                    return;
                };
                unknown_unit(literal, unit, factor)
            }
            UnitError::BadExponent(index) => {
                let span = unit.factors.get(index).map_or(unit.span, |f| f.span);
                Diagnostic::error("E0304", "unit exponent out of range").with_label(
                    span,
                    format!(
                        "expected an integer between -{0} and {0}",
                        units::MAX_EXPONENT
                    ),
                )
            }
            UnitError::Overflow => Diagnostic::error("E0304", "dimension out of range").with_label(
                unit.span,
                format!(
                    "an exponent of kg, m, s or A exceeds {}",
                    units::MAX_EXPONENT
                ),
            ),
        };
        self.error(diagnostic);
    }

    fn path_value(&mut self, path: &ast::Path, ctx: Ctx) -> Option<Typed> {
        let [name] = path.segments.as_slice() else {
            return self.joint_state(path, ctx);
        };
        match name.name.as_str() {
            "t" => return self.time(name.span, ctx),
            "pi" => return Some(Typed::leaf(Expr::Pi, Dimension::NONE, None)),
            "kinetic_energy" | "potential_energy" => return self.energy(name, ctx),
            _ => {}
        }
        let Some(&value) = self.values.get(&name.name) else {
            if let (Ctx::Output, Some(output)) = (ctx, self.scalar_outputs.get(&name.name)) {
                return Some(output.clone());
            }
            self.unknown_value(name, ctx);
            return None;
        };
        match value {
            Value::Param(handle) => {
                if let Ctx::Constant(what) = ctx {
                    self.error(not_constant(what, name, "a param"));
                    return None;
                }
                Some(Typed::leaf(
                    Expr::Param(handle),
                    self.model.params[handle].dimension,
                    None,
                ))
            }
            Value::Input(handle) => {
                if let Ctx::Constant(what) | Ctx::Static(what) = ctx {
                    self.error(varying(what, ctx, name, "an input", None));
                    return None;
                }
                Some(Typed::leaf(
                    Expr::Input(handle),
                    self.model.inputs[handle].dimension,
                    Some(name.span),
                ))
            }
            Value::Let(index) => self.let_value(index, name, ctx),
            Value::Failed => None,
        }
    }

    /// `joint.q` or `joint.u` of a pin or slider, where the motion may be used.
    fn joint_state(&mut self, path: &ast::Path, ctx: Ctx) -> Option<Typed> {
        let [joint, which] = path.segments.as_slice() else {
            self.not_a_number(path);
            return None;
        };
        if !matches!(which.name.as_str(), "q" | "u") {
            self.not_a_number(path);
            return None;
        }
        // Before the joints are known (a `let`), any `NAME.q` reads as a coordinate.
        self.allow_state(ctx, path.span, "a joint's coordinate or speed")?;
        if !self.joint_index.contains_key(&joint.name) {
            self.not_a_number(path);
            return None;
        }
        let index = self.single_coordinate_joint(joint, path.span)?;
        let coordinate = self.joints.get(index).and_then(|info| info.coordinate)?;
        let angle_or_length = self.model.coordinates[coordinate].dimension;
        let (term, dim) = if which.name == "q" {
            (ir::StateTerm::Coordinate(coordinate), angle_or_length)
        } else {
            let rate = dim_div(angle_or_length, Dimension::TIME)?;
            (ir::StateTerm::Speed(coordinate), rate)
        };
        Some(Typed::leaf(Expr::State(term), dim, Some(path.span)))
    }

    /// `kinetic_energy` or `potential_energy`: in outputs only.
    fn energy(&mut self, name: &ast::Ident, ctx: Ctx) -> Option<Typed> {
        if !matches!(ctx, Ctx::Output) {
            let place = ctx.what().unwrap_or("a force or torque");
            self.error(
                Diagnostic::error(
                    "E0213",
                    format!("`{}` is only allowed in an output", name.name),
                )
                .with_label(name.span, format!("used in {place}"))
                .with_help(
                    "the energies are outputs of the motion (`output total = kinetic_energy \
                         + potential_energy;`); a load uses the motion through `joint.q`, \
                         `joint.u`, `distance(A, B)` and `distance_rate(A, B)`",
                ),
            );
            return None;
        }
        let term = if name.name == "kinetic_energy" {
            ir::StateTerm::KineticEnergy
        } else {
            ir::StateTerm::PotentialEnergy
        };
        Some(Typed::leaf(
            Expr::State(term),
            Dimension::ENERGY,
            Some(name.span),
        ))
    }

    /// `distance(A, B)` (m) or `distance_rate(A, B)` (m/s) of two points.
    fn point_distance(
        &mut self,
        function: &ast::Ident,
        args: &[ast::Expr],
        span: Span,
        ctx: Ctx,
    ) -> Option<Typed> {
        self.allow_state(ctx, function.span, "a distance between points")?;
        let [a, b] = args else {
            self.error(
                wrong_argument_count(&function.name, "2 arguments", args.len()).with_label(
                    span,
                    format!("expected `{}(A, B)` of two points", function.name),
                ),
            );
            return None;
        };
        let ends = [a, b].map(|arg| self.point_argument(function, arg));
        let [a, b] = ends;
        let ends = [self.point_handle(a?)?, self.point_handle(b?)?];
        let (term, dim) = if function.name == "distance" {
            (ir::StateTerm::Distance(ends), Dimension::LENGTH)
        } else {
            (ir::StateTerm::DistanceRate(ends), Dimension::VELOCITY)
        };
        Some(Typed::leaf(Expr::State(term), dim, Some(span)))
    }

    /// E0401 where an expression may not use the motion.
    fn allow_state(&mut self, ctx: Ctx, span: Span, kind: &str) -> Option<()> {
        let Some(what) = ctx.what() else {
            return Some(());
        };
        self.error(
            Diagnostic::error("E0401", format!("{what} cannot depend on the motion"))
                .with_label(span, format!("{kind} changes as the model moves"))
                .with_help(
                    "only `force`, `torque` and `output` expressions may use `joint.q`, `joint.u`, \
                     `distance(A, B)` and `distance_rate(A, B)`; write the expression there",
                ),
        );
        None
    }

    fn time(&mut self, span: Span, ctx: Ctx) -> Option<Typed> {
        if let Ctx::Constant(what) | Ctx::Static(what) = ctx {
            let name = ast::Ident {
                name: "t".to_string(),
                span,
            };
            self.error(varying(what, ctx, &name, "the simulation time", None));
            return None;
        }
        Some(Typed::leaf(Expr::Time, Dimension::TIME, Some(span)))
    }

    fn let_value(&mut self, index: usize, name: &ast::Ident, ctx: Ctx) -> Option<Typed> {
        if let Ctx::Constant(what) = ctx {
            self.error(not_constant(what, name, "a `let`"));
            return None;
        }
        if self.current_let.is_some_and(|current| index >= current) {
            let definition = self.let_spans.get(index).copied().unwrap_or(name.span);
            self.error(
                Diagnostic::error(
                    "E0214",
                    format!("`{}` is used before its definition", name.name),
                )
                .with_label(name.span, "used here")
                .with_label(definition, "defined here")
                .with_help(
                    "a `let` may only use `let`s declared above it; reorder the definitions",
                ),
            );
            return None;
        }
        let typed = self.lets.get(index)?.clone()?;
        if let (Ctx::Static(what), Some(source)) = (ctx, typed.varying) {
            self.error(varying(
                what,
                ctx,
                name,
                "a `let` that depends on time or an input",
                Some(source),
            ));
            return None;
        }
        Some(typed)
    }

    fn not_a_number(&mut self, path: &ast::Path) {
        let text = path
            .segments
            .iter()
            .map(|s| s.name.as_str())
            .collect::<Vec<_>>()
            .join(".");
        let is_coordinate = match path.segments.as_slice() {
            [joint, q] => {
                self.joint_index.contains_key(&joint.name) && (q.name == "q" || q.name == "u")
            }
            _ => false,
        };
        let help = if is_coordinate {
            format!("`{text}` is not a pin's or slider's coordinate or speed")
        } else {
            "points and frames can only be used where a point or frame is expected".to_string()
        };
        self.error(
            Diagnostic::error("E0213", format!("`{text}` cannot be used in an expression"))
                .with_label(path.span, "not a number")
                .with_help(help),
        );
    }

    fn unknown_value(&mut self, name: &ast::Ident, ctx: Ctx) {
        let mut candidates: Vec<&str> = self.value_names.names().collect();
        candidates.extend(["t", "pi"]);
        if let Ctx::Output = ctx {
            candidates.extend(self.scalar_outputs.keys().map(String::as_str));
        }
        let mut diagnostic = names::unknown(
            "E0204",
            "name",
            "params, lets and inputs in scope",
            &name.name,
            name.span,
            &candidates,
            names::NOT_DECLARED,
        );
        if units::lookup(&name.name).is_some() && diagnostic.help.is_none() {
            diagnostic = diagnostic.with_help(format!(
                "`{0}` is a unit; a unit follows a number, as in `1 {0}`",
                name.name
            ));
        }
        self.error(diagnostic);
    }

    fn call(
        &mut self,
        function: &ast::Ident,
        args: &[ast::Expr],
        span: Span,
        ctx: Ctx,
    ) -> Option<Typed> {
        if matches!(function.name.as_str(), "distance" | "distance_rate") {
            return self.point_distance(function, args, span, ctx);
        }
        let Some(f) = function_named(&function.name) else {
            self.unknown_function(function);
            return None;
        };
        if args.len() != f.arity() {
            let plural = if f.arity() == 1 {
                "argument"
            } else {
                "arguments"
            };
            let takes = format!("{} {plural}", f.arity());
            self.error(
                wrong_argument_count(f.name(), &takes, args.len())
                    .with_label(span, format!("expected {takes}")),
            );
            return None;
        }
        let lowered: Vec<Option<Typed>> =
            args.iter().map(|arg| self.lower_scalar(arg, ctx)).collect();
        let lowered: Vec<Typed> = lowered.into_iter().collect::<Option<_>>()?;
        let dim = self.call_dimension(f, &lowered, args)?;
        let parts: Vec<&Typed> = lowered.iter().collect();
        let exprs: Vec<Expr> = lowered.iter().map(|t| t.expr.clone()).collect();
        let expr = fold_call(f, exprs);
        self.check_finite(&expr, span)?;
        Some(Typed::node(expr, dim, &parts))
    }

    /// The dimension of a call's result; `sqrt` halves even exponents, `abs` keeps them,
    /// `atan2` takes two arguments of one dimension, the others need dimensionless arguments.
    fn call_dimension(
        &mut self,
        f: Function,
        args: &[Typed],
        spans: &[ast::Expr],
    ) -> Option<Dimension> {
        let (first, first_span) = (args.first()?, spans.first()?.span);
        match f {
            Function::Abs => Some(first.dim),
            Function::Sqrt => {
                let dim = dim_pow(first.dim, 1, 2);
                if dim.is_none() {
                    self.error(argument_error(
                        f,
                        first_span,
                        &describe(first.dim),
                        "the square root of this dimension is not a whole unit",
                    ));
                }
                dim
            }
            Function::Atan2 => {
                let second = args.get(1)?;
                let same =
                    first.dim == second.dim || first.is_plain_zero() || second.is_plain_zero();
                if !same {
                    let span = spans.get(1).map_or(first_span, |e| e.span);
                    self.error(
                        Diagnostic::error(
                            "E0303",
                            format!(
                                "the arguments of `atan2` must have one dimension, found {} and {}",
                                describe(first.dim),
                                describe(second.dim)
                            ),
                        )
                        .with_label(first_span, describe(first.dim))
                        .with_label(span, describe(second.dim)),
                    );
                    return None;
                }
                Some(Dimension::NONE)
            }
            _ if first.dim != Dimension::NONE => {
                self.error(argument_error(
                    f,
                    first_span,
                    &describe(first.dim),
                    "angles are dimensionless (rad); divide by a reference value to get a ratio",
                ));
                None
            }
            _ => Some(Dimension::NONE),
        }
    }

    fn unknown_function(&mut self, function: &ast::Ident) {
        let candidates = [
            "sin",
            "cos",
            "tan",
            "sqrt",
            "exp",
            "ln",
            "abs",
            "atan2",
            "distance",
            "distance_rate",
        ];
        let mut diagnostic = names::unknown(
            "E0207",
            "function",
            "functions",
            &function.name,
            function.span,
            &candidates,
            "not a known function",
        );
        diagnostic = match function.name.as_str() {
            "rotate" => {
                diagnostic.with_help("`rotate(axis, angle)` is only used in `frame` declarations")
            }
            "position" | "velocity" => diagnostic.with_help(format!(
                "`{}(point)` is only used on its own in an `output`",
                function.name
            )),
            _ => diagnostic,
        };
        self.error(diagnostic);
    }

    fn binary(
        &mut self,
        op: BinaryOp,
        lhs: &ast::Expr,
        rhs: &ast::Expr,
        ctx: Ctx,
    ) -> Option<Typed> {
        let span = lhs.span.to(rhs.span);
        if op == BinaryOp::Pow {
            return self.power(lhs, rhs, ctx);
        }
        let a = self.lower_scalar(lhs, ctx);
        let b = self.lower_scalar(rhs, ctx);
        let (a, b) = (a?, b?);
        let dim = match op {
            BinaryOp::Add | BinaryOp::Sub => self.sum_dimension(op, &a, &b, lhs.span, rhs.span)?,
            BinaryOp::Mul => self.checked_dim(dim_mul(a.dim, b.dim), span)?,
            _ => self.checked_dim(dim_div(a.dim, b.dim), span)?,
        };
        let expr = match op {
            BinaryOp::Add => add(a.expr.clone(), b.expr.clone()),
            BinaryOp::Sub => sub(a.expr.clone(), b.expr.clone()),
            BinaryOp::Mul => mul(a.expr.clone(), b.expr.clone()),
            _ => div(a.expr.clone(), b.expr.clone()),
        };
        self.check_finite(&expr, span)?;
        Some(Typed::node(expr, dim, &[&a, &b]))
    }

    fn sum_dimension(
        &mut self,
        op: BinaryOp,
        a: &Typed,
        b: &Typed,
        a_span: Span,
        b_span: Span,
    ) -> Option<Dimension> {
        if a.dim == b.dim || b.is_plain_zero() {
            return Some(a.dim);
        }
        if a.is_plain_zero() {
            return Some(b.dim);
        }
        let (left, right) = (describe(a.dim), describe(b.dim));
        let message = match op {
            BinaryOp::Add => format!("cannot add {left} and {right}"),
            _ => format!("cannot subtract {right} from {left}"),
        };
        let help = if a.dim == Dimension::NONE || b.dim == Dimension::NONE {
            "a plain number is dimensionless; write its unit, e.g. `2 mm`".to_string()
        } else {
            format!(
                "both sides of `{}` must have the same dimension; check the units",
                op.symbol()
            )
        };
        self.error(
            Diagnostic::error("E0301", message)
                .with_label(a_span, format!("this is {left}"))
                .with_label(b_span, format!("this is {right}"))
                .with_help(help),
        );
        None
    }

    fn power(&mut self, lhs: &ast::Expr, rhs: &ast::Expr, ctx: Ctx) -> Option<Typed> {
        let base = self.lower_scalar(lhs, ctx);
        let exponent = self.exponent(rhs);
        let (base, exponent) = (base?, exponent?);
        let span = lhs.span.to(rhs.span);
        let dim = match exponent_ratio(exponent) {
            _ if base.dim == Dimension::NONE => Some(Dimension::NONE),
            Some((num, den)) => dim_pow(base.dim, num, den),
            None => None,
        };
        let Some(dim) = dim else {
            self.error(
                Diagnostic::error(
                    "E0304",
                    format!("`^ {exponent}` gives a non-integer or out-of-range dimension"),
                )
                .with_label(lhs.span, format!("this is {}", describe(base.dim)))
                .with_label(rhs.span, "exponent")
                .with_help("the exponents of kg, m, s and A must stay whole numbers"),
            );
            return None;
        };
        let expr = pow(base.expr.clone(), exponent);
        self.check_finite(&expr, span)?;
        Some(Typed::node(expr, dim, &[&base]))
    }

    /// An exponent: a dimensionless constant.
    fn exponent(&mut self, e: &ast::Expr) -> Option<Number> {
        let (number, dim) = self.lower_constant(e, Ctx::Constant("an exponent"))?;
        if dim != Dimension::NONE {
            self.error(
                Diagnostic::error(
                    "E0305",
                    format!("an exponent must be dimensionless, found {}", describe(dim)),
                )
                .with_label(e.span, "has a unit"),
            );
            return None;
        }
        Some(number)
    }

    fn checked_dim(&mut self, dim: Option<Dimension>, span: Span) -> Option<Dimension> {
        if dim.is_none() {
            self.error(
                Diagnostic::error("E0304", "dimension out of range").with_label(
                    span,
                    format!(
                        "an exponent of kg, m, s or A exceeds {}",
                        units::MAX_EXPONENT
                    ),
                ),
            );
        }
        dim
    }

    fn check_finite(&mut self, expr: &Expr, span: Span) -> Option<()> {
        match expr {
            Expr::Number(n) if !n.to_f64().is_finite() => {
                self.error(not_finite(span));
                None
            }
            _ => Some(()),
        }
    }
}

/// The components of a vector literal, distributing scalar factors, divisors and negation
/// over them; `None` if `e` is not a vector.
fn vector_components(e: &ast::Expr) -> Option<Vec<ast::Expr>> {
    let scaled = |items: Vec<ast::Expr>, f: &dyn Fn(ast::Expr) -> ExprKind| {
        items
            .into_iter()
            .map(|item| ast::Expr {
                span: item.span.to(e.span),
                kind: f(item),
            })
            .collect()
    };
    let binary = |op, lhs: ast::Expr, rhs: ast::Expr| ExprKind::Binary {
        op,
        lhs: Box::new(lhs),
        rhs: Box::new(rhs),
    };
    match &unparen(e).kind {
        ExprKind::Vector(items) => Some(items.clone()),
        ExprKind::Neg(inner) => Some(scaled(vector_components(inner)?, &|item| {
            ExprKind::Neg(Box::new(item))
        })),
        ExprKind::Binary {
            op: BinaryOp::Mul,
            lhs,
            rhs,
        } => match vector_components(lhs) {
            Some(items) => Some(scaled(items, &|item| {
                binary(BinaryOp::Mul, item, (**rhs).clone())
            })),
            None => Some(scaled(vector_components(rhs)?, &|item| {
                binary(BinaryOp::Mul, (**lhs).clone(), item)
            })),
        },
        ExprKind::Binary {
            op: BinaryOp::Div,
            lhs,
            rhs,
        } => Some(scaled(vector_components(lhs)?, &|item| {
            binary(BinaryOp::Div, item, (**rhs).clone())
        })),
        _ => None,
    }
}

/// `true` if `e` is a vector expression (a literal, possibly scaled).
pub(super) fn is_vector(e: &ast::Expr) -> bool {
    vector_components(e).is_some()
}

/// The expression inside any parentheses.
pub(super) fn unparen(mut e: &ast::Expr) -> &ast::Expr {
    while let ExprKind::Paren(inner) = &e.kind {
        e = inner;
    }
    e
}

/// "a mass (kg)"-style description of a dimension for messages.
fn article(dim: Dimension) -> String {
    let name = match (dim.mass, dim.length, dim.time, dim.current) {
        (0, 0, 0, 0) => return "dimensionless".to_string(),
        (1, 0, 0, 0) => "a mass",
        (0, 1, 0, 0) => "a length",
        (1, 1, -2, 0) => "a force",
        (1, 2, -2, 0) => "a torque",
        (1, 2, 0, 0) => "a moment of inertia",
        (0, 1, -2, 0) => "an acceleration",
        (0, 1, -1, 0) => "a velocity",
        (0, 0, -1, 0) => "an angular velocity",
        _ => return format!("in {dim}"),
    };
    format!("{name} ({dim})")
}

fn unknown_unit(literal: &str, unit: &ast::Unit, factor: &ast::UnitFactor) -> Diagnostic {
    let name = &factor.name.name;
    let all = units::all_unit_names();
    let candidates: Vec<&str> = all.iter().map(String::as_str).collect();
    let mut diagnostic = Diagnostic::error("E0206", format!("unknown unit `{name}`"))
        .with_label(factor.name.span, "not a unit");
    if let Some(best) = crate::diag::closest(name, &candidates) {
        diagnostic = diagnostic.with_note(format!("did you mean `{best}`?"));
    }
    if unit.factors.len() == 1 && factor.exponent.is_none() {
        diagnostic.with_help(format!(
            "if you meant multiplication, write `{literal} * {name}`"
        ))
    } else {
        diagnostic.with_help("units are m, g, s, Hz, N, J, W, Pa, V, A, C, F, rad and deg, with the prefixes G, M, k, c, m, u (µ), n, p")
    }
}

fn not_constant(what: &str, name: &ast::Ident, kind: &str) -> Diagnostic {
    let help = if what == "a param value" {
        "a param's value is a number with a unit, such as `10 g`; use `let` for quantities derived from params".to_string()
    } else {
        format!("{what} is fixed when the model is compiled; write a number with a unit")
    };
    Diagnostic::error("E0401", format!("{what} must be a constant"))
        .with_label(name.span, format!("`{}` is {kind}", name.name))
        .with_help(help)
}

fn varying(
    what: &str,
    ctx: Ctx,
    name: &ast::Ident,
    kind: &str,
    source: Option<Span>,
) -> Diagnostic {
    if let Ctx::Constant(_) = ctx {
        return not_constant(what, name, kind);
    }
    let mut diagnostic =
        Diagnostic::error("E0401", format!("{what} cannot depend on time or inputs"))
            .with_label(name.span, format!("`{}` is {kind}", name.name));
    if let Some(source) = source {
        diagnostic = diagnostic.with_label(source, "varies with time here");
    }
    diagnostic
        .with_help("only loads (`force`, `torque`), `let`s and `output`s may use inputs and `t`")
}

fn argument_error(f: Function, span: Span, found: &str, help: &str) -> Diagnostic {
    Diagnostic::error(
        "E0303",
        format!("invalid argument of `{}`: found {found}", f.name()),
    )
    .with_label(span, format!("this is {found}"))
    .with_help(help.to_string())
}

fn not_finite(span: Span) -> Diagnostic {
    Diagnostic::error("E0413", "this constant is not a finite number")
        .with_label(span, "evaluates to infinity or NaN")
        .with_help("check for a division by zero, a logarithm of zero, or an overflow")
}

fn function_named(name: &str) -> Option<Function> {
    Some(match name {
        "sin" => Function::Sin,
        "cos" => Function::Cos,
        "tan" => Function::Tan,
        "sqrt" => Function::Sqrt,
        "exp" => Function::Exp,
        "ln" => Function::Ln,
        "abs" => Function::Abs,
        "atan2" => Function::Atan2,
        _ => return None,
    })
}

/// `p/q` of an exponent usable on a dimension: exact, or a float with an integer value.
fn exponent_ratio(exponent: Number) -> Option<(i64, i64)> {
    match exponent {
        Number::Rational(num, den) => Some((num, den)),
        Number::Float(x) if x.fract() == 0.0 && x.abs() <= units::MAX_EXPONENT as f64 => {
            Some((x as i64, 1))
        }
        Number::Float(_) => None,
    }
}

// ---------------------------------------------------------------------------------------------
// Folding constructors: numeric operands are combined exactly (Number arithmetic).
// ---------------------------------------------------------------------------------------------

/// `a op b`, folded to a number where both are numbers.
fn binary(
    a: Expr,
    b: Expr,
    number: fn(Number, Number) -> Number,
    node: fn(Box<Expr>, Box<Expr>) -> Expr,
) -> Expr {
    match (&a, &b) {
        (Expr::Number(x), Expr::Number(y)) => Expr::Number(number(*x, *y)),
        _ => node(Box::new(a), Box::new(b)),
    }
}

pub fn neg(a: Expr) -> Expr {
    match a {
        Expr::Number(n) => Expr::Number(n.neg()),
        Expr::Neg(inner) => *inner,
        other => Expr::Neg(Box::new(other)),
    }
}

pub fn add(a: Expr, b: Expr) -> Expr {
    binary(a, b, Number::add, Expr::Add)
}

pub fn sub(a: Expr, b: Expr) -> Expr {
    binary(a, b, Number::sub, Expr::Sub)
}

pub fn mul(a: Expr, b: Expr) -> Expr {
    binary(a, b, Number::mul, Expr::Mul)
}

pub fn div(a: Expr, b: Expr) -> Expr {
    binary(a, b, Number::div, Expr::Div)
}

pub fn pow(base: Expr, exponent: Number) -> Expr {
    match (&base, exponent.as_integer()) {
        (Expr::Number(x), Some(e)) => Expr::Number(x.powi(e)),
        (Expr::Number(x), None) => Expr::Number(Number::Float(x.to_f64().powf(exponent.to_f64()))),
        _ => Expr::Pow(Box::new(base), exponent),
    }
}

fn fold_call(f: Function, args: Vec<Expr>) -> Expr {
    let values: Option<Vec<f64>> = args
        .iter()
        .map(|a| {
            if let Expr::Number(n) = a {
                Some(n.to_f64())
            } else {
                None
            }
        })
        .collect();
    match values {
        Some(values) => Expr::Number(Number::Float(f.apply(&values))),
        None => Expr::Call(f, args),
    }
}

/// Folds a constant expression (numbers, `pi`, calls) to a number; `None` if it refers to a
/// param, input or time.
pub fn fold(expr: &Expr) -> Option<Number> {
    let float = |x: f64| Some(Number::Float(x));
    match expr {
        Expr::Number(n) => Some(*n),
        Expr::Pi => float(std::f64::consts::PI),
        Expr::Param(_) | Expr::Input(_) | Expr::Time | Expr::State(_) => None,
        Expr::Neg(a) => Some(fold(a)?.neg()),
        Expr::Add(a, b) => Some(fold(a)?.add(fold(b)?)),
        Expr::Sub(a, b) => Some(fold(a)?.sub(fold(b)?)),
        Expr::Mul(a, b) => Some(fold(a)?.mul(fold(b)?)),
        Expr::Div(a, b) => Some(fold(a)?.div(fold(b)?)),
        Expr::Pow(a, e) => match pow(Expr::Number(fold(a)?), *e) {
            Expr::Number(n) => Some(n),
            _ => None,
        },
        Expr::Call(f, args) => {
            let values: Option<Vec<f64>> =
                args.iter().map(|a| fold(a).map(Number::to_f64)).collect();
            float(f.apply(&values?))
        }
    }
}
