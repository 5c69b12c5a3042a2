//! pest → typed AST. The only module that sees pest `Pair`s.
//!
//! Consumes: a [`SourceFile`] and the grammar `mech.pest`.
//! Produces: an [`ast::File`] with byte spans, or one syntax diagnostic (pest stops at the
//! first error). Also guards the recursion depth of everything downstream: bracket nesting is
//! limited before pest runs, and expression depth while the AST is built.

use pest::iterators::Pair;
use pest::Parser as _;

use super::ast::{self, BinaryOp, Expr, ExprKind, Ident, MAX_SIZE};
use crate::diag::{Diagnostic, SourceFile, Span};

#[derive(pest_derive::Parser)]
#[grammar = "front/mech.pest"]
struct MechParser;

/// Deepest bracket nesting accepted (pest and `lower` recurse on it).
const MAX_BRACKET_DEPTH: usize = 64;
/// Deepest expression tree accepted (each operator of a chain adds one level).
const MAX_EXPR_DEPTH: usize = 256;

type Result<T> = std::result::Result<T, Diagnostic>;

/// Parses a whole `.mech` file.
pub fn parse_file(file: &SourceFile) -> Result<ast::File> {
    check_bracket_depth(&file.text)?;
    let mut pairs =
        MechParser::parse(Rule::file, &file.text).map_err(|e| syntax_error(&file.text, e))?;
    let root = pairs.next().ok_or_else(|| internal(Span::default()))?;
    build_file(root)
}

/// Parses a standalone quantity such as `-10 mN` into its sign, literal and unit.
pub fn parse_quantity_text(
    text: &str,
) -> std::result::Result<(bool, String, Option<ast::Unit>), String> {
    check_bracket_depth(text).map_err(|d| d.message)?;
    // The grammar's own message ("expected a declaration") speaks of a model file; a value
    // on the command line or in a data file gets the form it should have.
    let pairs = MechParser::parse(Rule::quantity_text, text).map_err(|_| {
        let finite = match text
            .trim_start_matches(['-', '+'])
            .to_ascii_lowercase()
            .as_str()
        {
            "nan" | "inf" | "infinity" => " (only finite numbers)",
            _ => "",
        };
        format!(
            "expected a number with an optional unit, such as `10 mN` or `-2.5e-3`{finite}; \
             got `{text}`"
        )
    })?;
    let mut negative = false;
    for pair in pairs.flatten() {
        match pair.as_rule() {
            Rule::neg_op => negative = true,
            Rule::quantity => {
                let (literal, unit) = build_quantity(pair).map_err(|d| d.message)?;
                return Ok((negative, literal, unit));
            }
            _ => {}
        }
    }
    Err("expected a number with an optional unit, such as `10 mN`".to_string())
}

// ---------------------------------------------------------------------------------------------
// Declarations
// ---------------------------------------------------------------------------------------------

fn build_file(root: Pair<Rule>) -> Result<ast::File> {
    let mut file = ast::File {
        docs: Vec::new(),
        model: None,
        items: Vec::new(),
    };
    for pair in root.into_inner() {
        match pair.as_rule() {
            Rule::inner_doc => file.docs.push(doc_text(pair.as_str())),
            Rule::model_decl => {
                for inner in pair.into_inner() {
                    match inner.as_rule() {
                        Rule::doc => file.docs.push(doc_text(inner.as_str())),
                        Rule::ident => file.model = Some(ident(inner)),
                        _ => {}
                    }
                }
            }
            Rule::item => file.items.push(build_item(pair)?),
            _ => {}
        }
    }
    Ok(file)
}

/// The text of a `///` or `//!` comment without the marker and one leading space.
fn doc_text(comment: &str) -> String {
    let body = comment.get(3..).unwrap_or("");
    body.strip_prefix(' ')
        .unwrap_or(body)
        .trim_end()
        .to_string()
}

fn build_item(pair: Pair<Rule>) -> Result<ast::Item> {
    let span = span_of(&pair);
    let mut docs = Vec::new();
    for inner in pair.into_inner() {
        let rule = inner.as_rule();
        if rule == Rule::doc {
            docs.push(doc_text(inner.as_str()));
            continue;
        }
        let docs = std::mem::take(&mut docs);
        return match rule {
            Rule::param_decl => Ok(ast::Item::Param(value_decl(inner, docs)?)),
            Rule::let_decl => Ok(ast::Item::Let(value_decl(inner, docs)?)),
            Rule::input_decl => Ok(ast::Item::Input(value_decl(inner, docs)?)),
            Rule::gravity_decl => gravity_decl(inner),
            Rule::newtonian_decl => newtonian_decl(inner),
            Rule::body_decl => body_decl(inner, docs),
            Rule::joint_decl => Ok(ast::Item::Joint(joint_decl(inner, docs)?)),
            Rule::loop_decl => Ok(ast::Item::Loop(joint_decl(inner, docs)?)),
            Rule::material_decl => Ok(ast::Item::Material(element_decl(inner, docs, false)?)),
            Rule::flexure_decl => Ok(ast::Item::Flexure(element_decl(inner, docs, true)?)),
            Rule::actuator_decl => Ok(ast::Item::Actuator(element_decl(inner, docs, true)?)),
            Rule::spring_decl => Ok(ast::Item::Spring(two_point_decl(inner, docs)?)),
            Rule::contact_decl => Ok(ast::Item::Contact(two_point_decl(inner, docs)?)),
            Rule::bushing_decl => Ok(ast::Item::Bushing(two_point_decl(inner, docs)?)),
            Rule::force_decl => Ok(ast::Item::Force(vector_load_decl(inner, docs)?)),
            Rule::torque_decl => Ok(ast::Item::Torque(vector_load_decl(inner, docs)?)),
            Rule::output_decl => output_decl(inner, docs),
            Rule::constraint_decl => constraint_decl(inner, docs).map(ast::Item::Constraint),
            Rule::speed_decl => constraint_decl(inner, docs).map(ast::Item::Speed),
            Rule::rolling_decl => Ok(ast::Item::Rolling(two_point_decl(inner, docs)?)),
            _ => Err(internal(span)),
        };
    }
    Err(internal(span))
}

/// The pairs of a declaration that carry content (names, expressions, blocks), in order.
struct Parts<'i> {
    pairs: std::vec::IntoIter<Pair<'i, Rule>>,
    span: Span,
}

impl<'i> Parts<'i> {
    fn of(pair: Pair<'i, Rule>) -> Parts<'i> {
        let span = span_of(&pair);
        let pairs: Vec<_> = pair
            .into_inner()
            .filter(|p| !is_punctuation(p.as_rule()))
            .collect();
        Parts {
            pairs: pairs.into_iter(),
            span,
        }
    }
    fn next(&mut self) -> Result<Pair<'i, Rule>> {
        self.pairs.next().ok_or_else(|| internal(self.span))
    }
    fn ident(&mut self) -> Result<Ident> {
        Ok(ident(self.next()?))
    }
    fn expr(&mut self) -> Result<Expr> {
        expr(self.next()?)
    }
    fn path(&mut self) -> Result<ast::Path> {
        Ok(path(self.next()?))
    }
    /// The fields of an optional `{ field; ... }` block (of a joint, loop or element).
    fn block_fields(&mut self) -> Result<Vec<ast::Field>> {
        let Some(block) = self.take(Rule::joint_block) else {
            return Ok(Vec::new());
        };
        block
            .into_inner()
            .filter(|inner| inner.as_rule() == Rule::field)
            .map(field)
            .collect()
    }
    /// The frame of an optional `in FRAME` clause.
    fn frame_clause(&mut self) -> Result<Option<ast::Path>> {
        match self.take(Rule::frame_clause) {
            Some(clause) => Ok(Some(Parts::of(clause).path()?)),
            None => Ok(None),
        }
    }
    /// The next pair if it has the given rule.
    fn take(&mut self, rule: Rule) -> Option<Pair<'i, Rule>> {
        if self
            .pairs
            .as_slice()
            .first()
            .is_some_and(|p| p.as_rule() == rule)
        {
            self.pairs.next()
        } else {
            None
        }
    }
    fn rest(self) -> std::vec::IntoIter<Pair<'i, Rule>> {
        self.pairs
    }
}

fn is_punctuation(rule: Rule) -> bool {
    use Rule::*;
    matches!(
        rule,
        semicolon
            | assign
            | comma
            | dot
            | lparen
            | rparen
            | lbracket
            | rbracket
            | lbrace
            | rbrace
            | kw_model
            | kw_param
            | kw_let
            | kw_input
            | kw_gravity
            | kw_body
            | kw_joint
            | kw_loop
            | kw_material
            | kw_flexure
            | kw_actuator
            | kw_spring
            | kw_contact
            | kw_bushing
            | kw_between
            | kw_and
            | kw_force
            | kw_torque
            | kw_constraint
            | kw_rolling
            | kw_speed
            | kw_output
            | kw_point
            | kw_frame
            | kw_on
            | kw_in
    )
}

fn value_decl(pair: Pair<Rule>, docs: Vec<String>) -> Result<ast::ValueDecl> {
    let mut parts = Parts::of(pair);
    Ok(ast::ValueDecl {
        docs,
        name: parts.ident()?,
        value: parts.expr()?,
        span: parts.span,
    })
}

fn gravity_decl(pair: Pair<Rule>) -> Result<ast::Item> {
    let mut parts = Parts::of(pair);
    Ok(ast::Item::Gravity(ast::GravityDecl {
        value: parts.expr()?,
        span: parts.span,
    }))
}

fn newtonian_decl(pair: Pair<Rule>) -> Result<ast::Item> {
    let mut parts = Parts::of(pair);
    let keyword = span_of(&parts.next()?);
    let span = parts.span;
    let members = parts.rest().map(member).collect::<Result<_>>()?;
    Ok(ast::Item::Newtonian(ast::NewtonianDecl {
        members,
        keyword,
        span,
    }))
}

fn body_decl(pair: Pair<Rule>, docs: Vec<String>) -> Result<ast::Item> {
    let mut parts = Parts::of(pair);
    let name = parts.ident()?;
    let span = parts.span;
    let members = parts.rest().map(member).collect::<Result<_>>()?;
    Ok(ast::Item::Body(ast::BodyDecl {
        docs,
        name,
        members,
        span,
    }))
}

fn member(pair: Pair<Rule>) -> Result<ast::Member> {
    let span = span_of(&pair);
    let mut docs = Vec::new();
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => docs.push(doc_text(inner.as_str())),
            Rule::field => return Ok(ast::Member::Field(field(inner)?)),
            Rule::point_decl => {
                let mut parts = Parts::of(inner);
                let name = parts.ident()?;
                let position = parts.expr()?;
                return Ok(ast::Member::Point(ast::PointDecl {
                    docs,
                    name,
                    position,
                    span: parts.span,
                }));
            }
            Rule::frame_decl => return Ok(ast::Member::Frame(frame_decl(inner, docs)?)),
            _ => return Err(internal(span)),
        }
    }
    Err(internal(span))
}

fn frame_decl(pair: Pair<Rule>, docs: Vec<String>) -> Result<ast::FrameDecl> {
    let mut parts = Parts::of(pair);
    let name = parts.ident()?;
    let span = parts.span;
    let mut rotation = None;
    let mut origin = None;
    let mut after_at = false;
    for inner in parts.rest() {
        match inner.as_rule() {
            Rule::kw_at => after_at = true,
            Rule::expr if after_at => origin = Some(expr(inner)?),
            Rule::expr => rotation = Some(expr(inner)?),
            _ => return Err(internal(span)),
        }
    }
    Ok(ast::FrameDecl {
        docs,
        name,
        rotation,
        origin,
        span,
    })
}

fn field(pair: Pair<Rule>) -> Result<ast::Field> {
    let mut parts = Parts::of(pair);
    Ok(ast::Field {
        name: parts.ident()?,
        value: parts.expr()?,
        span: parts.span,
    })
}

/// `material NAME { .. }` or `flexure|actuator NAME on TARGET { .. }`.
fn element_decl(pair: Pair<Rule>, docs: Vec<String>, has_target: bool) -> Result<ast::ElementDecl> {
    let mut parts = Parts::of(pair);
    Ok(ast::ElementDecl {
        docs,
        name: parts.ident()?,
        target: if has_target {
            Some(parts.ident()?)
        } else {
            None
        },
        fields: parts.block_fields()?,
        span: parts.span,
    })
}

/// A `joint` or `loop` declaration (they have the same shape).
fn joint_decl(pair: Pair<Rule>, docs: Vec<String>) -> Result<ast::JointDecl> {
    let mut parts = Parts::of(pair);
    Ok(ast::JointDecl {
        docs,
        name: parts.ident()?,
        kind: parts.ident()?,
        parent: parts.ident()?,
        child: parts.ident()?,
        fields: parts.block_fields()?,
        span: parts.span,
    })
}

/// `spring`, `contact` or `bushing`: `KEYWORD NAME between A and B { fields }`.
fn two_point_decl(pair: Pair<Rule>, docs: Vec<String>) -> Result<ast::SpringDecl> {
    let mut parts = Parts::of(pair);
    Ok(ast::SpringDecl {
        docs,
        name: parts.ident()?,
        ends: [parts.path()?, parts.path()?],
        fields: parts.block_fields()?,
        span: parts.span,
    })
}

/// `force NAME at POINT = VECTOR in FRAME;` or `torque NAME on BODY = VECTOR in FRAME;`.
fn vector_load_decl(pair: Pair<Rule>, docs: Vec<String>) -> Result<ast::VectorLoadDecl> {
    let mut parts = Parts::of(pair);
    let name = parts.ident()?;
    parts.take(Rule::kw_at); // a force's (a torque's `on` is punctuation)
    Ok(ast::VectorLoadDecl {
        docs,
        name,
        target: parts.path()?,
        value: parts.expr()?,
        frame: parts.frame_clause()?,
        span: parts.span,
    })
}

fn output_decl(pair: Pair<Rule>, docs: Vec<String>) -> Result<ast::Item> {
    let mut parts = Parts::of(pair);
    Ok(ast::Item::Output(ast::OutputDecl {
        docs,
        name: parts.ident()?,
        value: parts.expr()?,
        frame: parts.frame_clause()?,
        span: parts.span,
    }))
}

/// `constraint` and `speed` declarations, which share their shape.
fn constraint_decl(pair: Pair<Rule>, docs: Vec<String>) -> Result<ast::ConstraintDecl> {
    let mut parts = Parts::of(pair);
    let name = parts.ident()?;
    let value = parts.expr()?;
    let frame = parts.frame_clause()?;
    let has_block = parts
        .pairs
        .as_slice()
        .first()
        .is_some_and(|p| p.as_rule() == Rule::joint_block);
    let fields = if has_block {
        Some(parts.block_fields()?)
    } else {
        None
    };
    let head = ast::OutputDecl {
        docs,
        name,
        value,
        frame,
        span: parts.span,
    };
    Ok(ast::ConstraintDecl { head, fields })
}

fn ident(pair: Pair<Rule>) -> Ident {
    Ident {
        name: pair.as_str().to_string(),
        span: span_of(&pair),
    }
}

fn path(pair: Pair<Rule>) -> ast::Path {
    let span = span_of(&pair);
    let segments = pair
        .into_inner()
        .filter(|p| p.as_rule() == Rule::ident)
        .map(ident)
        .collect();
    ast::Path { segments, span }
}

// ---------------------------------------------------------------------------------------------
// Expressions
// ---------------------------------------------------------------------------------------------

/// Builds an expression, rejecting trees deeper than [`MAX_EXPR_DEPTH`].
fn expr(pair: Pair<Rule>) -> Result<Expr> {
    Ok(built(pair)?.0)
}

/// An expression and the depth of its tree.
type Built = (Expr, usize);

fn built(pair: Pair<Rule>) -> Result<Built> {
    let span = span_of(&pair);
    let result = match pair.as_rule() {
        Rule::expr | Rule::term => binary_chain(pair)?,
        Rule::factor | Rule::exponent => negation(pair)?,
        Rule::power => power(pair)?,
        Rule::quantity => {
            let (literal, unit) = build_quantity(pair)?;
            (
                Expr {
                    kind: ExprKind::Quantity { literal, unit },
                    span,
                },
                1,
            )
        }
        Rule::path => (
            Expr {
                kind: ExprKind::Path(path(pair)),
                span,
            },
            1,
        ),
        Rule::paren => {
            let (inner, depth) = built(Parts::of(pair).next()?)?;
            (
                Expr {
                    kind: ExprKind::Paren(Box::new(inner)),
                    span,
                },
                depth + 1,
            )
        }
        Rule::vector => {
            let (items, depth) = built_list(Parts::of(pair).rest())?;
            (
                Expr {
                    kind: ExprKind::Vector(items),
                    span,
                },
                depth + 1,
            )
        }
        Rule::call => {
            let mut parts = Parts::of(pair);
            let function = parts.ident()?;
            let (args, depth) = built_list(parts.rest())?;
            (
                Expr {
                    kind: ExprKind::Call { function, args },
                    span,
                },
                depth + 1,
            )
        }
        _ => return Err(internal(span)),
    };
    if result.1 > MAX_EXPR_DEPTH {
        return Err(too_deep(span));
    }
    Ok(result)
}

fn built_list<'i>(pairs: impl Iterator<Item = Pair<'i, Rule>>) -> Result<(Vec<Expr>, usize)> {
    let mut items = Vec::new();
    let mut depth = 0;
    for pair in pairs {
        let (item, d) = built(pair)?;
        depth = depth.max(d);
        items.push(item);
    }
    Ok((items, depth))
}

/// `a + b - c` or `a * b / c`: left associative.
fn binary_chain(pair: Pair<Rule>) -> Result<Built> {
    let span = span_of(&pair);
    let mut inner = pair.into_inner();
    let first = inner.next().ok_or_else(|| internal(span))?;
    let (mut lhs, mut depth) = built(first)?;
    while let Some(op) = inner.next() {
        let op = match op.as_str() {
            "+" => BinaryOp::Add,
            "-" => BinaryOp::Sub,
            "*" => BinaryOp::Mul,
            _ => BinaryOp::Div,
        };
        let (rhs, d) = built(inner.next().ok_or_else(|| internal(span))?)?;
        depth = depth.max(d) + 1;
        if depth > MAX_EXPR_DEPTH {
            return Err(too_deep(span));
        }
        let span = lhs.span.to(rhs.span);
        lhs = Expr {
            kind: ExprKind::Binary {
                op,
                lhs: Box::new(lhs),
                rhs: Box::new(rhs),
            },
            span,
        };
    }
    Ok((lhs, depth))
}

/// Leading minus signs: an even number cancels, an odd number is one negation.
fn negation(pair: Pair<Rule>) -> Result<Built> {
    let span = span_of(&pair);
    let mut minus_signs = 0usize;
    let mut operand = None;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::neg_op => minus_signs += 1,
            _ => operand = Some(built(inner)?),
        }
    }
    let (operand, depth) = operand.ok_or_else(|| internal(span))?;
    // The pair's span may end in whitespace; end it at the operand.
    let span = Span {
        start: span.start,
        end: operand.span.end,
    };
    match minus_signs {
        0 => Ok((operand, depth)),
        n if n % 2 == 0 => Ok((Expr { span, ..operand }, depth)),
        _ => Ok((
            Expr {
                kind: ExprKind::Neg(Box::new(operand)),
                span,
            },
            depth + 1,
        )),
    }
}

/// `a ^ b ^ c`: right associative.
fn power(pair: Pair<Rule>) -> Result<Built> {
    let span = span_of(&pair);
    let operands = pair
        .into_inner()
        .filter(|p| p.as_rule() != Rule::pow_op)
        .map(built)
        .collect::<Result<Vec<_>>>()?;
    let mut operands = operands.into_iter().rev();
    let (mut result, mut depth) = operands.next().ok_or_else(|| internal(span))?;
    for (base, d) in operands {
        depth = depth.max(d) + 1;
        if depth > MAX_EXPR_DEPTH {
            return Err(too_deep(span));
        }
        let span = base.span.to(result.span);
        result = Expr {
            kind: ExprKind::Binary {
                op: BinaryOp::Pow,
                lhs: Box::new(base),
                rhs: Box::new(result),
            },
            span,
        };
    }
    Ok((result, depth))
}

fn build_quantity(pair: Pair<Rule>) -> Result<(String, Option<ast::Unit>)> {
    let span = span_of(&pair);
    let mut literal = None;
    let mut unit = None;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::number => literal = Some(inner.as_str().to_string()),
            Rule::unit => unit = Some(build_unit(inner)),
            _ => {}
        }
    }
    Ok((literal.ok_or_else(|| internal(span))?, unit))
}

fn build_unit(pair: Pair<Rule>) -> ast::Unit {
    let span = span_of(&pair);
    let mut factors = Vec::new();
    let mut divide = false;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::unit_op => divide = inner.as_str() == "/",
            Rule::unit_factor => factors.push(build_unit_factor(inner, divide)),
            _ => {}
        }
    }
    ast::Unit { factors, span }
}

fn build_unit_factor(pair: Pair<Rule>, divide: bool) -> ast::UnitFactor {
    let span = span_of(&pair);
    let mut name = Ident {
        name: String::new(),
        span,
    };
    let mut exponent = None;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::unit_name => name = ident(inner),
            Rule::unit_exponent => exponent = Some(inner.as_str().to_string()),
            _ => {}
        }
    }
    ast::UnitFactor {
        name,
        exponent,
        divide,
        span,
    }
}

fn span_of(pair: &Pair<Rule>) -> Span {
    let span = pair.as_span();
    Span::new(span.start(), span.end())
}

fn internal(span: Span) -> Diagnostic {
    Diagnostic::error("E0100", "internal error: unexpected syntax tree shape")
        .with_label(span, "while reading this")
        .with_help("this is a bug in mech-codegen; please report it with the file")
}

fn too_deep(span: Span) -> Diagnostic {
    Diagnostic::error("E0103", "expression is nested too deeply")
        .with_label(
            span,
            format!("more than {MAX_EXPR_DEPTH} levels of operators"),
        )
        .with_help("split it with `let` definitions")
}

// ---------------------------------------------------------------------------------------------
// Syntax errors
// ---------------------------------------------------------------------------------------------

/// Rejects bracket nesting deeper than [`MAX_BRACKET_DEPTH`] (outside comments), so that
/// neither pest nor the lowering can exhaust the stack, and a statement with more than
/// [`MAX_SIZE`] operators, which the lowering would reject as too large (E0103) only after
/// pest had held the whole tree (about 150 bytes of memory per byte of text).
fn check_bracket_depth(text: &str) -> Result<()> {
    let bytes = text.as_bytes();
    let mut depth = 0usize;
    // Operators since the last `;`, `{` or `}`, and where that statement started.
    let (mut operators, mut statement) = (0usize, 0usize);
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                i += 2;
                while i < bytes.len() && !(bytes[i] == b'*' && bytes.get(i + 1) == Some(&b'/')) {
                    i += 1;
                }
                i += 1;
            }
            b'(' | b'[' | b'{' => {
                if bytes[i] == b'{' {
                    (operators, statement) = (0, i + 1);
                }
                depth += 1;
                if depth > MAX_BRACKET_DEPTH {
                    return Err(Diagnostic::error("E0103", "brackets are nested too deeply")
                        .with_label(
                            Span::new(i, i + 1),
                            format!("more than {MAX_BRACKET_DEPTH} levels"),
                        )
                        .with_help("split the expression with `let` definitions"));
                }
            }
            b')' | b']' | b'}' => {
                if bytes[i] == b'}' {
                    (operators, statement) = (0, i + 1);
                }
                depth = depth.saturating_sub(1);
            }
            b';' => (operators, statement) = (0, i + 1),
            // Units' operators count too (`kg*m^2`): an overestimate, far above real models.
            b'+' | b'-' | b'*' | b'/' | b'^' => {
                operators += 1;
                if operators > MAX_SIZE {
                    let rest = &text[statement..];
                    let statement = statement + rest.len() - rest.trim_start().len();
                    return Err(Diagnostic::error("E0103", "expression is too large")
                        .with_label(
                            Span::new(statement, statement + 1),
                            format!("a statement of more than {MAX_SIZE} operators starts here"),
                        )
                        .with_help("an expression this large is not a model of a mechanism; generate fewer terms, or split it with `let` definitions"));
                }
            }
            _ => {}
        }
        i += 1;
    }
    Ok(())
}

fn syntax_error(text: &str, error: pest::error::Error<Rule>) -> Diagnostic {
    let position = match error.location {
        pest::error::InputLocation::Pos(p) => p,
        pest::error::InputLocation::Span((start, _)) => start,
    };
    let expected = match &error.variant {
        pest::error::ErrorVariant::ParsingError { positives, .. } => expected_phrases(positives),
        pest::error::ErrorVariant::CustomError { .. } => Vec::new(),
    };
    if let Some(start) = unterminated_comment(text, position) {
        return Diagnostic::error("E0101", "unterminated block comment")
            .with_label(Span::new(start, start + 2), "this `/*` is never closed")
            .with_help("close the comment with `*/` (block comments do not nest)");
    }
    let found = found_token(text, position);
    if expected.is_empty() {
        return Diagnostic::error("E0101", format!("unexpected {found}"))
            .with_label(Span::new(position, position + 1), "not expected here");
    }
    let list = join_alternatives(&expected);
    let wants_semicolon = expected.contains(&"`;`");
    let at = if wants_semicolon {
        end_of_previous_token(text, position)
    } else {
        position
    };
    let mut diagnostic = Diagnostic::error("E0101", format!("expected {list}, found {found}"))
        .with_label(Span::new(at, at), format!("expected {list}"));
    if let Some(keyword) = keyword_before(text, position).filter(|_| expected == ["`=`"]) {
        let start = end_of_previous_token(text, position) - keyword.len();
        return diagnostic
            .with_label(
                Span::new(start, start + keyword.len()),
                "read as a field name",
            )
            .with_help(format!(
                "`{keyword}` starts a declaration: is a `}}` missing before it?"
            ));
    }
    if let Some(help) = syntax_help(&expected) {
        diagnostic = diagnostic.with_help(help);
    }
    diagnostic
}

fn syntax_help(expected: &[&str]) -> Option<&'static str> {
    if expected.contains(&"`;`") {
        Some("every declaration and field ends with `;`")
    } else if expected.contains(&"an expression") {
        Some("an expression is a number with an optional unit (`2.5 mm`), a name, a call such as `sin(x)`, or a vector `[x, y, z]`")
    } else if expected.contains(&DECLARATION) {
        Some("a model is a list of declarations: `param`, `let`, `input`, `gravity`, `newtonian`, `body`, `joint`, `force`, `torque`, `output`")
    } else {
        None
    }
}

const DECLARATION: &str = "a declaration";

/// Friendly names of the rules pest expected, deduplicated, in pest's order.
fn expected_phrases(rules: &[Rule]) -> Vec<&'static str> {
    let mut phrases = Vec::new();
    for &rule in rules {
        let phrase = describe(rule);
        if !phrases.contains(&phrase) {
            phrases.push(phrase);
        }
    }
    phrases
}

/// What a rule is called in syntax errors.
fn describe(rule: Rule) -> &'static str {
    use Rule::*;
    match rule {
        semicolon => "`;`",
        assign => "`=`",
        comma => "`,`",
        dot => "`.`",
        lparen => "`(`",
        rparen => "`)`",
        lbracket => "`[`",
        rbracket => "`]`",
        lbrace | joint_block => "`{`",
        rbrace => "`}`",
        add_op | mul_op | pow_op | unit_op => "an operator",
        expr | term | factor | power | exponent | quantity | number | call | path | paren
        | vector | neg_op => "an expression",
        ident => "a name",
        unit | unit_factor | unit_name => "a unit",
        unit_exponent => "an integer exponent",
        member | point_decl | frame_decl | field | kw_point | kw_frame => {
            "a field, `point` or `frame`"
        }
        frame_clause | kw_in => "`in`",
        kw_at => "`at`",
        kw_on => "`on`",
        kw_between => "`between`",
        kw_and => "`and`",
        EOI => "end of file",
        _ => DECLARATION,
    }
}

fn join_alternatives(phrases: &[&str]) -> String {
    match phrases {
        [] => String::new(),
        [one] => one.to_string(),
        [init @ .., last] => format!("{} or {last}", init.join(", ")),
    }
}

/// The start of a `/*` at or just before `position` that has no closing `*/`.
fn unterminated_comment(text: &str, position: usize) -> Option<usize> {
    let start = [position.saturating_sub(1), position]
        .into_iter()
        .find(|&p| text.get(p..).is_some_and(|rest| rest.starts_with("/*")))?;
    let rest = text.get(start + 2..)?;
    (!rest.contains("*/")).then_some(start)
}

/// Describes the token at `position`: a word, one character, or the end of the file.
fn found_token(text: &str, position: usize) -> String {
    let rest = text.get(position..).unwrap_or("");
    let Some(first) = rest.chars().next() else {
        return "end of file".to_string();
    };
    if first.is_alphanumeric() || first == '_' {
        let word: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == '.')
            .collect();
        let word: String = word.chars().take(30).collect();
        return format!("`{word}`");
    }
    match first {
        '\n' | '\r' => "a line break".to_string(),
        c => format!("`{c}`"),
    }
}

/// The keywords that start a top-level declaration (besides `model`).
pub(crate) const DECLARATION_KEYWORDS: [&str; 17] = [
    "param",
    "let",
    "input",
    "gravity",
    "newtonian",
    "body",
    "joint",
    "loop",
    "material",
    "flexure",
    "actuator",
    "spring",
    "contact",
    "bushing",
    "force",
    "torque",
    "output",
];

/// The top-level keyword right before `position`, if any (a field named `joint` means a `}`
/// is missing).
fn keyword_before(text: &str, position: usize) -> Option<&'static str> {
    let before = text.get(..position)?.trim_end();
    DECLARATION_KEYWORDS.into_iter().find(|k| {
        before.ends_with(k)
            && !before[..before.len() - k.len()]
                .ends_with(|c: char| c.is_ascii_alphanumeric() || c == '_')
    })
}

/// The byte offset just after the last non-whitespace character before `position`
/// (where a missing `;` belongs).
fn end_of_previous_token(text: &str, position: usize) -> usize {
    text.get(..position).unwrap_or("").trim_end().len()
}
