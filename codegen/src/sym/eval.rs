//! Numeric evaluation of pool expressions and the reachable-node schedule shared by the
//! evaluator, the tape and the Rust emitter.
//!
//! Consumes: root expressions and symbol values. Produces: `f64` values, or the list of
//! nodes reachable from the roots in topological (id) order.

use super::expr::{children, ExprId, ExprPool, Node, Symbol};
use super::Number;

impl ExprPool {
    /// Ids of all nodes reachable from `roots`, ascending (operands before users).
    pub fn reachable(&self, roots: &[ExprId]) -> Vec<ExprId> {
        let Some(max) = roots.iter().max() else {
            return Vec::new();
        };
        let mut seen = vec![false; max.index() + 1];
        let mut stack: Vec<ExprId> = roots.to_vec();
        while let Some(id) = stack.pop() {
            if std::mem::replace(&mut seen[id.index()], true) {
                continue;
            }
            stack.extend(children(self.node(id)));
        }
        (0..seen.len())
            .filter(|&i| seen[i])
            .map(|i| ExprId(i as u32))
            .collect()
    }

    /// Evaluates `roots` with symbol values from `value_of`.
    pub fn eval(&self, roots: &[ExprId], value_of: &dyn Fn(Symbol) -> f64) -> Vec<f64> {
        let order = self.reachable(roots);
        let mut values = vec![f64::NAN; order.last().map_or(0, |id| id.index() + 1)];
        for id in order {
            values[id.index()] = self.eval_node(self.node(id), &values, value_of);
        }
        roots.iter().map(|id| values[id.index()]).collect()
    }

    fn eval_node(&self, node: &Node, values: &[f64], value_of: &dyn Fn(Symbol) -> f64) -> f64 {
        match node {
            Node::Number(n) => n.to_f64(),
            Node::Symbol(s) => value_of(*s),
            Node::Add { constant, terms } => {
                terms.iter().fold(constant.to_f64(), |acc, &(t, c)| {
                    acc + c.to_f64() * values[t.index()]
                })
            }
            Node::Mul {
                coefficient,
                factors,
            } => factors.iter().fold(coefficient.to_f64(), |acc, &(b, e)| {
                acc * power(values[b.index()], e)
            }),
            Node::Call(func, x) => func.apply(values[x.index()]),
            Node::Atan2(y, x) => values[y.index()].atan2(values[x.index()]),
        }
    }
}

/// `x^e` with the cheapest exact-enough method for the exponent.
pub fn power(x: f64, e: Number) -> f64 {
    match e {
        Number::Rational(n, 1) if n.unsigned_abs() <= i32::MAX as u64 => x.powi(n as i32),
        Number::Rational(1, 2) => x.sqrt(),
        Number::Rational(-1, 2) => 1.0 / x.sqrt(),
        _ => x.powf(e.to_f64()),
    }
}
