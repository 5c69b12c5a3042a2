//! The typed syntax tree of a `.mech` file, with byte spans on every node.
//!
//! Consumes: nothing (built by `front::parse` from pest pairs).
//! Produces: the input of `front::lower`. Names are unresolved strings; numbers keep their
//! literal text and unit, so that `lower` can keep them exact.

use crate::diag::Span;

/// Largest expression (in nodes) accepted after inlining `let`s: a limit of the language the
/// parser checks on a statement's operators and the lowering on the inlined expression.
pub const MAX_SIZE: usize = 100_000;

/// An identifier with its place in the source.
#[derive(Clone, Debug, PartialEq)]
pub struct Ident {
    pub name: String,
    pub span: Span,
}

/// A name or a dotted reference: `m`, `arm.tip`, `newtonian.anchor`, `hinge.q`.
#[derive(Clone, Debug, PartialEq)]
pub struct Path {
    pub segments: Vec<Ident>,
    pub span: Span,
}

/// A whole file.
#[derive(Clone, Debug, PartialEq)]
pub struct File {
    /// `//!` lines at the top of the file, and `///` lines before `model`.
    pub docs: Vec<String>,
    pub model: Option<Ident>,
    pub items: Vec<Item>,
}

/// A top-level declaration.
#[derive(Clone, Debug, PartialEq)]
pub enum Item {
    Param(ValueDecl),
    Let(ValueDecl),
    Input(ValueDecl),
    Gravity(GravityDecl),
    Newtonian(NewtonianDecl),
    Body(BodyDecl),
    Joint(JointDecl),
    /// `loop NAME = KIND(PARENT, CHILD) { fields }`: same shape as a joint.
    Loop(JointDecl),
    /// `material NAME { fields }` (no target).
    Material(ElementDecl),
    /// `flexure NAME on TARGET { fields }`.
    Flexure(ElementDecl),
    /// `actuator NAME on TARGET { fields }`.
    Actuator(ElementDecl),
    Spring(SpringDecl),
    /// `contact NAME between POINT and PLANE_POINT { fields }`: same shape as a spring.
    Contact(SpringDecl),
    /// `bushing NAME between FRAME and FRAME { fields }`: same shape as a spring.
    Bushing(SpringDecl),
    Force(VectorLoadDecl),
    Torque(VectorLoadDecl),
    Output(OutputDecl),
    Constraint(ConstraintDecl),
    /// `rolling NAME between CENTRE and PLANE_POINT { fields }`: same shape as a spring.
    Rolling(SpringDecl),
    /// `speed NAME = WHAT in FRAME { axis }` or `speed NAME = EXPR;`: same shape as a
    /// constraint.
    Speed(ConstraintDecl),
}

/// `param`, `let` or `input`: a name bound to an expression.
#[derive(Clone, Debug, PartialEq)]
pub struct ValueDecl {
    pub docs: Vec<String>,
    pub name: Ident,
    pub value: Expr,
    pub span: Span,
}

/// `gravity = [gx, gy, gz];`
#[derive(Clone, Debug, PartialEq)]
pub struct GravityDecl {
    pub value: Expr,
    pub span: Span,
}

/// `newtonian { ... }`
#[derive(Clone, Debug, PartialEq)]
pub struct NewtonianDecl {
    pub members: Vec<Member>,
    /// The `newtonian` keyword.
    pub keyword: Span,
    pub span: Span,
}

/// `body NAME { ... }`
#[derive(Clone, Debug, PartialEq)]
pub struct BodyDecl {
    pub docs: Vec<String>,
    pub name: Ident,
    pub members: Vec<Member>,
    pub span: Span,
}

/// A declaration inside a `body` or `newtonian` block.
#[derive(Clone, Debug, PartialEq)]
pub enum Member {
    Field(Field),
    Point(PointDecl),
    Frame(FrameDecl),
}

/// `NAME = EXPR;` inside a block.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub name: Ident,
    pub value: Expr,
    pub span: Span,
}

/// `point NAME = [x, y, z];`
#[derive(Clone, Debug, PartialEq)]
pub struct PointDecl {
    pub docs: Vec<String>,
    pub name: Ident,
    pub position: Expr,
    pub span: Span,
}

/// `frame NAME = ROTATION at ORIGIN;`
#[derive(Clone, Debug, PartialEq)]
pub struct FrameDecl {
    pub docs: Vec<String>,
    pub name: Ident,
    pub rotation: Option<Expr>,
    pub origin: Option<Expr>,
    pub span: Span,
}

/// `joint NAME = KIND(PARENT, CHILD) { fields }`
#[derive(Clone, Debug, PartialEq)]
pub struct JointDecl {
    pub docs: Vec<String>,
    pub name: Ident,
    pub kind: Ident,
    pub parent: Ident,
    pub child: Ident,
    pub fields: Vec<Field>,
    pub span: Span,
}

/// A named block of fields, optionally attached to a joint or loop:
/// `material NAME { ... }`, `flexure NAME on TARGET { ... }`, `actuator NAME on TARGET { ... }`.
#[derive(Clone, Debug, PartialEq)]
pub struct ElementDecl {
    pub docs: Vec<String>,
    pub name: Ident,
    pub target: Option<Ident>,
    pub fields: Vec<Field>,
    pub span: Span,
}

/// `spring NAME between POINT and POINT { fields }` (and `contact`, of the same shape)
#[derive(Clone, Debug, PartialEq)]
pub struct SpringDecl {
    pub docs: Vec<String>,
    pub name: Ident,
    /// The two points the spring connects, as written (`A` and `B` of the docs).
    pub ends: [Path; 2],
    pub fields: Vec<Field>,
    pub span: Span,
}

/// `force NAME at POINT = VECTOR in FRAME;` (and `torque NAME on BODY = VECTOR in FRAME;`,
/// of the same shape)
#[derive(Clone, Debug, PartialEq)]
pub struct VectorLoadDecl {
    pub docs: Vec<String>,
    pub name: Ident,
    /// The point a force acts at, or the body a torque acts on, as written.
    pub target: Path,
    pub value: Expr,
    pub frame: Option<Path>,
    pub span: Span,
}

/// `output NAME = WHAT in FRAME;`
#[derive(Clone, Debug, PartialEq)]
pub struct OutputDecl {
    pub docs: Vec<String>,
    pub name: Ident,
    pub value: Expr,
    pub frame: Option<Path>,
    pub span: Span,
}

/// `constraint NAME = WHAT in FRAME { fields }` (the block and the frame only with a velocity).
#[derive(Clone, Debug, PartialEq)]
pub struct ConstraintDecl {
    /// `NAME = WHAT in FRAME`, as an output's.
    pub head: OutputDecl,
    /// `None` without a block (`... ;`).
    pub fields: Option<Vec<Field>>,
}

/// An expression with its span.
#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    pub kind: ExprKind,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ExprKind {
    /// A number literal (its text, e.g. `2.5e-3`) with an optional unit.
    Quantity {
        literal: String,
        unit: Option<Unit>,
    },
    Path(Path),
    Vector(Vec<Expr>),
    Call {
        function: Ident,
        args: Vec<Expr>,
    },
    Neg(Box<Expr>),
    Binary {
        op: BinaryOp,
        lhs: Box<Expr>,
        rhs: Box<Expr>,
    },
    /// A parenthesized expression (kept so that spans and diagnostics follow the source).
    Paren(Box<Expr>),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinaryOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
}

impl BinaryOp {
    pub fn symbol(self) -> &'static str {
        match self {
            BinaryOp::Add => "+",
            BinaryOp::Sub => "-",
            BinaryOp::Mul => "*",
            BinaryOp::Div => "/",
            BinaryOp::Pow => "^",
        }
    }
}

/// A unit written after a number: `N*m/rad`.
#[derive(Clone, Debug, PartialEq)]
pub struct Unit {
    pub factors: Vec<UnitFactor>,
    pub span: Span,
}

/// One factor of a unit: `s^2` in `m/s^2` (`divide` is true for factors after `/`).
#[derive(Clone, Debug, PartialEq)]
pub struct UnitFactor {
    pub name: Ident,
    /// The exponent as written (`2`, `-1`), if any.
    pub exponent: Option<String>,
    pub divide: bool,
    pub span: Span,
}
