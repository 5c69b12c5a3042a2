//! The expression pool: a hash-consed DAG of canonical sums and products.
//!
//! Consumes: constructor calls (`add`, `mul`, `pow`, `sin`, ...) from the derivation.
//! Produces: [`ExprId`]s. Structurally equal expressions get the same id (hash-consing), and
//! every node's operands have smaller ids than the node itself, so a forward scan over ids is
//! a topological order (evaluation, CSE and emission are linear scans).
//!
//! Canonical forms, maintained by the constructors:
//! - `Add { constant, terms }`: `constant + Σ coefficient·term`, terms sorted by id, no term is
//!   a number, a sum, or a product with a coefficient other than 1; coefficients are nonzero;
//!   never a single term with coefficient 1 and zero constant (that is just the term).
//! - `Mul { coefficient, factors }`: `coefficient · Π base^exponent`, bases sorted by id, no
//!   base is a number or (for integer exponents) a product; exponents nonzero. A numeric
//!   coefficient times a sum is distributed into the sum.
//! - `sin(x)²·m + cos(x)²·m` with equal coefficients collapses to `m` when a sum is built.
//!
//! Simplification is local to construction (bounded work per node), so a big model gets a
//! bigger answer, never a hang.

use rustc_hash::FxHashMap;
use std::collections::HashMap;

use super::Number;

/// Handle to a node of an [`ExprPool`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ExprId(pub(crate) u32);

impl ExprId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// The free variables of the equations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Symbol {
    /// Generalized coordinate `q[i]`.
    Coordinate(u32),
    /// Generalized speed `u[i]`.
    Speed(u32),
    /// Time derivative of a generalized speed `u̇[i]` (only inside Kane's `F_r*`).
    Acceleration(u32),
    Param(u32),
    Input(u32),
    Time,
}

/// Unary functions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Func {
    Sin,
    Cos,
    Tan,
    Exp,
    Ln,
    Abs,
    /// `max(0, x)` (the positive part; NaN stays NaN).
    Ramp,
    /// Heaviside's step `H(x)`: 1 for `x > 0`, 0 for `x ≤ 0` (NaN stays NaN), the
    /// derivative of [`Func::Ramp`] (taken as 0 at the kink).
    Step,
}

impl Func {
    /// Every function, in declaration order.
    pub const ALL: [Func; 8] = [
        Func::Sin,
        Func::Cos,
        Func::Tan,
        Func::Exp,
        Func::Ln,
        Func::Abs,
        Func::Ramp,
        Func::Step,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Exp => "exp",
            Func::Ln => "ln",
            Func::Abs => "abs",
            Func::Ramp => "ramp",
            Func::Step => "step",
        }
    }
    pub fn apply(self, x: f64) -> f64 {
        match self {
            Func::Sin => x.sin(),
            Func::Cos => x.cos(),
            Func::Tan => x.tan(),
            Func::Exp => x.exp(),
            Func::Ln => x.ln(),
            Func::Abs => x.abs(),
            Func::Ramp if x > 0.0 => x,
            Func::Step if x > 0.0 => 1.0,
            Func::Ramp | Func::Step if x.is_nan() => x,
            Func::Ramp | Func::Step => 0.0,
        }
    }
}

/// One node of the DAG. See the module docs for the canonical-form invariants.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Node {
    Number(Number),
    Symbol(Symbol),
    Add {
        constant: Number,
        terms: Box<[(ExprId, Number)]>,
    },
    Mul {
        coefficient: Number,
        factors: Box<[(ExprId, Number)]>,
    },
    Call(Func, ExprId),
    Atan2(ExprId, ExprId),
}

/// Bounds on the work simplification may do per constructed node. Larger models get less
/// simplified (bigger) expressions, never a hang.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Sums with more terms than this skip the `sin² + cos² = 1` pair search, which is
    /// quadratic in the number of terms.
    pub identity_search_terms: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            identity_search_terms: 48,
        }
    }
}

/// Hash-consed expression storage with names for symbols (used by `Display` and emitters).
#[derive(Clone, Debug, Default)]
pub struct ExprPool {
    nodes: Vec<Node>,
    memo: FxHashMap<Node, ExprId>,
    names: HashMap<Symbol, String>,
    limits: Limits,
}

impl ExprPool {
    pub fn new() -> ExprPool {
        ExprPool::default()
    }

    pub fn with_limits(limits: Limits) -> ExprPool {
        ExprPool {
            limits,
            ..ExprPool::default()
        }
    }

    pub fn limits(&self) -> Limits {
        self.limits
    }

    pub fn len(&self) -> usize {
        self.nodes.len()
    }
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
    pub fn node(&self, id: ExprId) -> &Node {
        &self.nodes[id.index()]
    }

    /// Interns a node that is already in canonical form.
    fn intern(&mut self, node: Node) -> ExprId {
        if let Some(&id) = self.memo.get(&node) {
            return id;
        }
        let id = ExprId(self.nodes.len() as u32);
        self.nodes.push(node.clone());
        self.memo.insert(node, id);
        id
    }

    // ----- leaves -----

    pub fn number(&mut self, value: Number) -> ExprId {
        self.intern(Node::Number(value))
    }
    pub fn int(&mut self, value: i64) -> ExprId {
        self.number(Number::int(value))
    }
    pub fn zero(&mut self) -> ExprId {
        self.number(Number::ZERO)
    }
    pub fn one(&mut self) -> ExprId {
        self.number(Number::ONE)
    }
    pub fn float(&mut self, value: f64) -> ExprId {
        self.number(Number::Float(value))
    }
    pub fn symbol(&mut self, symbol: Symbol) -> ExprId {
        self.intern(Node::Symbol(symbol))
    }
    /// Gives `symbol` a display name (used by `Display`, s-expressions and emitters).
    pub fn set_name(&mut self, symbol: Symbol, name: impl Into<String>) {
        self.names.insert(symbol, name.into());
    }
    pub fn symbol_name(&self, symbol: Symbol) -> String {
        if let Some(name) = self.names.get(&symbol) {
            return name.clone();
        }
        match symbol {
            Symbol::Coordinate(i) => format!("q{i}"),
            Symbol::Speed(i) => format!("u{i}"),
            Symbol::Acceleration(i) => format!("ud{i}"),
            Symbol::Param(i) => format!("p{i}"),
            Symbol::Input(i) => format!("in{i}"),
            Symbol::Time => "t".to_string(),
        }
    }
    pub(crate) fn symbol_by_name(&self, name: &str) -> Option<Symbol> {
        self.names
            .iter()
            .find(|(_, n)| n.as_str() == name)
            .map(|(s, _)| *s)
    }

    pub fn as_number(&self, id: ExprId) -> Option<Number> {
        match self.node(id) {
            Node::Number(n) => Some(*n),
            _ => None,
        }
    }
    pub fn is_zero(&self, id: ExprId) -> bool {
        self.as_number(id).is_some_and(Number::is_zero)
    }

    // ----- sums -----

    /// `a + b`.
    pub fn add(&mut self, a: ExprId, b: ExprId) -> ExprId {
        self.sum(&[(a, Number::ONE), (b, Number::ONE)])
    }
    /// `a − b`.
    pub fn sub(&mut self, a: ExprId, b: ExprId) -> ExprId {
        self.sum(&[(a, Number::ONE), (b, Number::MINUS_ONE)])
    }
    /// `−a`.
    pub fn neg(&mut self, a: ExprId) -> ExprId {
        self.scale(a, Number::MINUS_ONE)
    }
    /// `c·a`.
    pub fn scale(&mut self, a: ExprId, c: Number) -> ExprId {
        self.sum(&[(a, c)])
    }
    /// `Σ items` for any number of operands.
    pub fn add_all(&mut self, items: &[ExprId]) -> ExprId {
        let terms: Vec<(ExprId, Number)> = items.iter().map(|&id| (id, Number::ONE)).collect();
        self.sum(&terms)
    }

    /// `Σ cᵢ·eᵢ` in canonical form.
    pub fn sum(&mut self, items: &[(ExprId, Number)]) -> ExprId {
        let mut constant = Number::ZERO;
        let mut collected: Vec<(ExprId, Number)> = Vec::with_capacity(items.len());
        let mut pending: Vec<(ExprId, Number)> = items.to_vec();
        while let Some((id, c)) = pending.pop() {
            if c.is_zero() {
                continue;
            }
            match self.node(id) {
                Node::Number(n) => constant = constant.add(n.mul(c)),
                Node::Add { constant: k, terms } => {
                    constant = constant.add(k.mul(c));
                    pending.extend(terms.iter().map(|&(t, tc)| (t, tc.mul(c))));
                }
                Node::Mul {
                    coefficient,
                    factors,
                } if !coefficient.is_one() => {
                    let (coefficient, factors) = (*coefficient, factors.clone());
                    let monomial = self.intern_mul(Number::ONE, factors);
                    collected.push((monomial, coefficient.mul(c)));
                }
                _ => collected.push((id, c)),
            }
        }
        let terms = combine_like(collected, Number::add);
        if let Some((i, j, rest, c)) = self.pythagorean_pair(&terms) {
            // Rebuild without the pair; each rebuild removes one sin², so this terminates.
            let mut items: Vec<(ExprId, Number)> = terms
                .iter()
                .enumerate()
                .filter(|&(k, _)| k != i && k != j)
                .map(|(_, &t)| t)
                .collect();
            items.push((rest, c));
            let k = self.number(constant);
            items.push((k, Number::ONE));
            return self.sum(&items);
        }
        match (terms.len(), constant.is_zero()) {
            (0, _) => self.number(constant),
            (1, true) if terms[0].1.is_one() => terms[0].0,
            (1, true) => {
                let (id, c) = terms[0];
                match self.node(id).clone() {
                    Node::Mul { factors, .. } => self.intern_mul(c, factors),
                    _ => self.intern_mul(c, vec![(id, Number::ONE)].into()),
                }
            }
            _ => self.intern(Node::Add {
                constant,
                terms: terms.into(),
            }),
        }
    }

    /// Finds terms `c·m·sin(x)²` and `c·m·cos(x)²` (same c and m): returns their positions,
    /// `m` and `c`, since the pair equals `c·m`.
    fn pythagorean_pair(
        &mut self,
        terms: &[(ExprId, Number)],
    ) -> Option<(usize, usize, ExprId, Number)> {
        if terms.len() > self.limits.identity_search_terms {
            return None;
        }
        for (i, &(term, coefficient)) in terms.iter().enumerate() {
            let Some((rest, cos_square)) = self.split_sin_square(term) else {
                continue;
            };
            if let Some(j) = terms
                .iter()
                .position(|&(t, c)| t == cos_square && c == coefficient)
            {
                return Some((i, j, rest, coefficient));
            }
        }
        None
    }

    /// For a monomial containing `sin(x)^2`, returns (monomial without it, same monomial with
    /// `cos(x)^2` in its place).
    fn split_sin_square(&mut self, term: ExprId) -> Option<(ExprId, ExprId)> {
        let factors: Vec<(ExprId, Number)> = match self.node(term) {
            Node::Mul {
                coefficient,
                factors,
            } if coefficient.is_one() => factors.to_vec(),
            _ => return None,
        };
        let two = Number::int(2);
        let (position, argument) =
            factors
                .iter()
                .enumerate()
                .find_map(|(k, &(base, e))| match self.node(base) {
                    Node::Call(Func::Sin, x) if e == two => Some((k, *x)),
                    _ => None,
                })?;
        let mut rest = factors.clone();
        rest.remove(position);
        let cos = self.call(Func::Cos, argument);
        let rest_id = self.product(Number::ONE, &rest);
        let mut with_cos = rest;
        with_cos.push((cos, two));
        let cos_id = self.product(Number::ONE, &with_cos);
        Some((rest_id, cos_id))
    }

    // ----- products -----

    /// `a · b`.
    pub fn mul(&mut self, a: ExprId, b: ExprId) -> ExprId {
        self.product(Number::ONE, &[(a, Number::ONE), (b, Number::ONE)])
    }
    /// `Π items`.
    pub fn mul_all(&mut self, items: &[ExprId]) -> ExprId {
        let factors: Vec<(ExprId, Number)> = items.iter().map(|&id| (id, Number::ONE)).collect();
        self.product(Number::ONE, &factors)
    }
    /// `a / b`.
    pub fn div(&mut self, a: ExprId, b: ExprId) -> ExprId {
        self.product(Number::ONE, &[(a, Number::ONE), (b, Number::MINUS_ONE)])
    }
    /// `a^exponent`.
    pub fn pow(&mut self, a: ExprId, exponent: Number) -> ExprId {
        self.product(Number::ONE, &[(a, exponent)])
    }
    pub fn sqrt(&mut self, a: ExprId) -> ExprId {
        self.pow(a, Number::rational(1, 2))
    }

    /// `coefficient · Π baseᵢ^eᵢ` in canonical form.
    pub fn product(&mut self, coefficient: Number, items: &[(ExprId, Number)]) -> ExprId {
        let mut coefficient = coefficient;
        let mut collected: Vec<(ExprId, Number)> = Vec::with_capacity(items.len());
        let mut pending: Vec<(ExprId, Number)> = items.to_vec();
        while let Some((id, e)) = pending.pop() {
            if e.is_zero() {
                continue;
            }
            match self.node(id) {
                Node::Number(n) => match e.as_integer() {
                    Some(k) => coefficient = coefficient.mul(n.powi(k)),
                    None => {
                        coefficient = coefficient.mul(Number::Float(n.to_f64().powf(e.to_f64())))
                    }
                },
                Node::Mul {
                    coefficient: c,
                    factors,
                } if e.as_integer().is_some() => {
                    let k = e.as_integer().unwrap_or(1);
                    coefficient = coefficient.mul(c.powi(k));
                    pending.extend(factors.iter().map(|&(b, fe)| (b, fe.mul(e))));
                }
                _ => collected.push((id, e)),
            }
        }
        if coefficient.is_zero() {
            return self.zero();
        }
        let factors = combine_like(collected, Number::add);
        match factors.len() {
            0 => self.number(coefficient),
            1 if factors[0].1.is_one() => {
                let base = factors[0].0;
                if coefficient.is_one() {
                    base
                } else {
                    // c·(a + b) is distributed so that scaled sums stay canonical.
                    self.scale_canonical(base, coefficient)
                }
            }
            _ => self.intern_mul(coefficient, factors.into()),
        }
    }

    /// `c·x` for an `x` that is not a product: a scaled sum, or a one-factor product.
    fn scale_canonical(&mut self, base: ExprId, coefficient: Number) -> ExprId {
        match self.node(base) {
            Node::Add { .. } => self.sum(&[(base, coefficient)]),
            _ => self.intern_mul(coefficient, vec![(base, Number::ONE)].into()),
        }
    }

    fn intern_mul(&mut self, coefficient: Number, factors: Box<[(ExprId, Number)]>) -> ExprId {
        if factors.len() == 1 && factors[0].1.is_one() && coefficient.is_one() {
            return factors[0].0;
        }
        self.intern(Node::Mul {
            coefficient,
            factors,
        })
    }

    // ----- functions -----

    /// `f(x)`, folding constants and the odd/even symmetries of sin, cos, tan.
    pub fn call(&mut self, func: Func, x: ExprId) -> ExprId {
        if let Some(n) = self.as_number(x) {
            if n.is_zero()
                && matches!(
                    func,
                    Func::Sin | Func::Tan | Func::Abs | Func::Ramp | Func::Step
                )
            {
                return self.zero();
            }
            if n.is_zero() && matches!(func, Func::Cos | Func::Exp) {
                return self.one();
            }
            return self.float(func.apply(n.to_f64()));
        }
        if let Some(positive) = self.negated(x) {
            match func {
                Func::Sin | Func::Tan => {
                    let f = self.call(func, positive);
                    return self.neg(f);
                }
                Func::Cos | Func::Abs => return self.call(func, positive),
                Func::Exp | Func::Ln | Func::Ramp | Func::Step => {}
            }
        }
        self.intern(Node::Call(func, x))
    }
    pub fn sin(&mut self, x: ExprId) -> ExprId {
        self.call(Func::Sin, x)
    }
    pub fn cos(&mut self, x: ExprId) -> ExprId {
        self.call(Func::Cos, x)
    }
    pub fn atan2(&mut self, y: ExprId, x: ExprId) -> ExprId {
        match (self.as_number(y), self.as_number(x)) {
            (Some(a), Some(b)) => self.float(a.to_f64().atan2(b.to_f64())),
            _ => self.intern(Node::Atan2(y, x)),
        }
    }

    /// If `x` is `−y` for a product with negative coefficient, returns `y`.
    fn negated(&mut self, x: ExprId) -> Option<ExprId> {
        match self.node(x) {
            Node::Mul {
                coefficient,
                factors,
            } if coefficient.is_negative() => {
                let (c, f) = (coefficient.neg(), factors.clone());
                Some(self.product(c, &f))
            }
            _ => None,
        }
    }

    /// The symbols an expression depends on, sorted.
    pub fn free_symbols(&self, root: ExprId) -> Vec<Symbol> {
        let mut seen = vec![false; root.index() + 1];
        let mut stack = vec![root];
        let mut symbols = Vec::new();
        while let Some(id) = stack.pop() {
            if std::mem::replace(&mut seen[id.index()], true) {
                continue;
            }
            match self.node(id) {
                Node::Symbol(s) => symbols.push(*s),
                other => stack.extend(children(other)),
            }
        }
        symbols.sort();
        symbols.dedup();
        symbols
    }
}

/// Operands of a node, in order.
pub fn children(node: &Node) -> Vec<ExprId> {
    match node {
        Node::Number(_) | Node::Symbol(_) => Vec::new(),
        Node::Add { terms, .. } => terms.iter().map(|&(t, _)| t).collect(),
        Node::Mul { factors, .. } => factors.iter().map(|&(b, _)| b).collect(),
        Node::Call(_, x) => vec![*x],
        Node::Atan2(y, x) => vec![*y, *x],
    }
}

/// Sorts by id and merges equal ids with `merge`, dropping zero results.
fn combine_like(
    mut items: Vec<(ExprId, Number)>,
    merge: fn(Number, Number) -> Number,
) -> Vec<(ExprId, Number)> {
    items.sort_by_key(|&(id, _)| id);
    let mut out: Vec<(ExprId, Number)> = Vec::with_capacity(items.len());
    for (id, value) in items {
        match out.last_mut() {
            Some((last, acc)) if *last == id => *acc = merge(*acc, value),
            _ => out.push((id, value)),
        }
    }
    out.retain(|&(_, value)| !value.is_zero());
    out
}
