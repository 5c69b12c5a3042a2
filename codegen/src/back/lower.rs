//! Lowering of one DAG node to a small operator tree, shared by both back ends.
//!
//! Consumes: a node of the pool. Produces: a [`Lowered`] tree whose leaves are constants,
//! symbols or *other nodes* (which the back ends have already given a register or a `let`).
//! The tape flattens the tree into instructions; the Rust emitter prints it as one
//! expression. Both follow the same operation order, so they agree to rounding.
//!
//! Sums become a left-to-right chain that starts with a positive term when there is one
//! (`a − b` instead of `−b + a`); products put positive powers first and divide once by the
//! product of the negative powers; coefficients ±1 become signs.

use crate::sym::{ExprId, ExprPool, Func, Node, Number, Symbol};

/// A leaf of a lowered tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Operand {
    /// A non-leaf node computed earlier (a register / a `let`).
    Node(ExprId),
    /// A non-negative finite constant, or a non-finite one.
    Const(f64),
    Symbol(Symbol),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Binary {
    Add,
    Sub,
    Mul,
    Div,
    Atan2,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unary {
    Neg,
    Sqrt,
    Call(Func),
}

/// An operator tree over [`Operand`]s.
#[derive(Clone, Debug, PartialEq)]
pub enum Lowered {
    Operand(Operand),
    Binary(Binary, Box<Lowered>, Box<Lowered>),
    Unary(Unary, Box<Lowered>),
    Powi(Box<Lowered>, i32),
    Powf(Box<Lowered>, f64),
}

impl Lowered {
    fn binary(op: Binary, a: Lowered, b: Lowered) -> Lowered {
        Lowered::Binary(op, Box::new(a), Box::new(b))
    }
    fn unary(op: Unary, a: Lowered) -> Lowered {
        Lowered::Unary(op, Box::new(a))
    }
}

/// A leaf node as an operand, anything else as a reference to its register.
pub fn operand(pool: &ExprPool, id: ExprId) -> Operand {
    match pool.node(id) {
        Node::Number(n) => Operand::Const(n.to_f64()),
        Node::Symbol(s) => Operand::Symbol(*s),
        _ => Operand::Node(id),
    }
}

/// True for nodes that need no register (inlined as operands).
pub fn is_leaf(pool: &ExprPool, id: ExprId) -> bool {
    matches!(pool.node(id), Node::Number(_) | Node::Symbol(_))
}

/// The operator tree computing node `id` from its operands.
pub fn lower_node(pool: &ExprPool, id: ExprId) -> Lowered {
    match pool.node(id) {
        Node::Number(n) => constant(n.to_f64()),
        Node::Symbol(s) => Lowered::Operand(Operand::Symbol(*s)),
        Node::Add { constant: k, terms } => {
            let mut signed: Vec<(bool, Lowered)> = terms
                .iter()
                .map(|&(t, c)| scaled(pool, c, Lowered::Operand(operand(pool, t))))
                .collect();
            if !k.is_zero() {
                signed.push((k.is_negative(), constant(k.to_f64().abs())));
            }
            chain_sum(signed)
        }
        Node::Mul {
            coefficient,
            factors,
        } => {
            let power =
                |&(base, e): &(ExprId, Number)| raise(Lowered::Operand(operand(pool, base)), e);
            let numerator: Vec<Lowered> = factors
                .iter()
                .filter(|f| !f.1.is_negative())
                .map(power)
                .collect();
            let denominator: Vec<Lowered> = factors
                .iter()
                .filter(|f| f.1.is_negative())
                .map(|&(b, e)| power(&(b, e.neg())))
                .collect();
            let magnitude = coefficient.to_f64().abs();
            let mut product = numerator
                .into_iter()
                .reduce(|a, b| Lowered::binary(Binary::Mul, a, b));
            if magnitude != 1.0 {
                let c = constant(magnitude);
                product = Some(match product {
                    Some(p) => Lowered::binary(Binary::Mul, c, p),
                    None => c,
                });
            }
            let mut result = product.unwrap_or(constant(1.0));
            if let Some(d) = denominator
                .into_iter()
                .reduce(|a, b| Lowered::binary(Binary::Mul, a, b))
            {
                result = Lowered::binary(Binary::Div, result, d);
            }
            if coefficient.is_negative() {
                result = Lowered::unary(Unary::Neg, result);
            }
            result
        }
        Node::Call(func, x) => {
            Lowered::unary(Unary::Call(*func), Lowered::Operand(operand(pool, *x)))
        }
        Node::Atan2(y, x) => Lowered::binary(
            Binary::Atan2,
            Lowered::Operand(operand(pool, *y)),
            Lowered::Operand(operand(pool, *x)),
        ),
    }
}

fn constant(value: f64) -> Lowered {
    Lowered::Operand(Operand::Const(value))
}

/// `c·x` as (is negative, |c|·x).
fn scaled(_pool: &ExprPool, c: Number, x: Lowered) -> (bool, Lowered) {
    let magnitude = c.to_f64().abs();
    let term = if magnitude == 1.0 {
        x
    } else {
        Lowered::binary(Binary::Mul, constant(magnitude), x)
    };
    (c.is_negative(), term)
}

/// Left-to-right `±a ± b ± …`, starting from the first positive term if any.
fn chain_sum(mut signed: Vec<(bool, Lowered)>) -> Lowered {
    if let Some(first_positive) = signed.iter().position(|(negative, _)| !negative) {
        let first = signed.remove(first_positive);
        signed.insert(0, first);
    }
    let mut items = signed.into_iter();
    let Some((negative, first)) = items.next() else {
        return constant(0.0);
    };
    let mut acc = if negative {
        Lowered::unary(Unary::Neg, first)
    } else {
        first
    };
    for (negative, term) in items {
        acc = Lowered::binary(if negative { Binary::Sub } else { Binary::Add }, acc, term);
    }
    acc
}

/// `x^e` for a positive exponent.
fn raise(x: Lowered, e: Number) -> Lowered {
    match e {
        Number::Rational(1, 1) => x,
        Number::Rational(1, 2) => Lowered::unary(Unary::Sqrt, x),
        Number::Rational(n, 1) if n <= i32::MAX as i64 => Lowered::Powi(Box::new(x), n as i32),
        _ => Lowered::Powf(Box::new(x), e.to_f64()),
    }
}

/// The nodes that need a register or a `let` to compute `roots`, operands first.
pub fn schedule(pool: &ExprPool, roots: &[ExprId]) -> Vec<ExprId> {
    pool.reachable(roots)
        .into_iter()
        .filter(|&id| !is_leaf(pool, id))
        .collect()
}
