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

    /// The number of atoms and operators (every token but the brackets) of the s-expressions
    /// of `roots` (`sexpr`, which repeats a shared subexpression at each use), computed on the
    /// DAG in time linear in its size, saturating: how large a printout is before making it.
    pub fn printed_size(&self, roots: &[ExprId]) -> u64 {
        let order = self.reachable(roots);
        let len = order.last().map_or(0, |id| id.index() + 1);
        // The whole s-expression, and the factors alone (`write_factors`).
        let (mut whole, mut factors) = (vec![0u64; len], vec![0u64; len]);
        let add = |a: u64, b: u64| a.saturating_add(b);
        for id in order {
            let i = id.index();
            let (w, f) = match self.node(id) {
                Node::Number(_) | Node::Symbol(_) => (1, 1),
                Node::Add { constant, terms } => {
                    let mut size = 1 + u64::from(!constant.is_zero());
                    for &(term, c) in terms.iter() {
                        size = add(
                            size,
                            if c.is_one() {
                                whole[term.index()]
                            } else {
                                add(2, factors[term.index()])
                            },
                        );
                    }
                    (size, size)
                }
                Node::Mul {
                    coefficient,
                    factors: items,
                } => {
                    let mut f = 0u64;
                    for &(base, e) in items.iter() {
                        f = add(
                            f,
                            if e.is_one() {
                                whole[base.index()]
                            } else {
                                add(2, whole[base.index()])
                            },
                        );
                    }
                    let w = if coefficient.is_one() && items.len() == 1 {
                        f
                    } else {
                        add(f, 1 + u64::from(!coefficient.is_one()))
                    };
                    (w, f)
                }
                Node::Call(_, x) => {
                    let w = add(1, whole[x.index()]);
                    (w, w)
                }
                Node::Atan2(y, x) => {
                    let w = add(1, add(whole[y.index()], whole[x.index()]));
                    (w, w)
                }
            };
            (whole[i], factors[i]) = (w, f);
        }
        roots.iter().fold(0, |acc, id| add(acc, whole[id.index()]))
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
