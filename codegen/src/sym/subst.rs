//! Substitution of symbols in pool expressions.
//!
//! Consumes: root expressions and a replacement for some symbols. Produces: the roots with
//! those symbols replaced, rebuilt bottom-up with the canonicalizing constructors, so terms
//! that vanish (a product with a speed set to zero) are dropped rather than evaluated.
//! Used for the statics' forcing `F(t, q, 0, inputs)`, where every velocity term of Kane's
//! `F_r*` and every damper drops out.

use super::expr::{ExprId, ExprPool, Node, Symbol};

impl ExprPool {
    /// `roots` with each symbol `s` for which `replacement(s)` is `Some(e)` replaced by `e`.
    /// `None` when a replacement puts a zero under a negative power (the expression has no
    /// value there, so no rebuilt form can stand for it).
    pub fn substitute(
        &mut self,
        roots: &[ExprId],
        replacement: &dyn Fn(Symbol) -> Option<ExprId>,
    ) -> Option<Vec<ExprId>> {
        let order = self.reachable(roots);
        let mut rebuilt = vec![ExprId(0); order.last().map_or(0, |id| id.index() + 1)];
        for id in order {
            let new = match self.node(id).clone() {
                Node::Number(_) => id,
                Node::Symbol(s) => replacement(s).unwrap_or(id),
                Node::Add { constant, terms } => {
                    let k = self.number(constant);
                    let mut items: Vec<_> = terms
                        .iter()
                        .map(|&(t, c)| (rebuilt[t.index()], c))
                        .collect();
                    items.push((k, super::Number::ONE));
                    self.sum(&items)
                }
                Node::Mul {
                    coefficient,
                    factors,
                } => {
                    let items: Vec<_> = factors
                        .iter()
                        .map(|&(b, e)| (rebuilt[b.index()], e))
                        .collect();
                    if items
                        .iter()
                        .any(|&(b, e)| e.is_negative() && self.is_zero(b))
                    {
                        return None;
                    }
                    self.product(coefficient, &items)
                }
                Node::Call(func, x) => self.call(func, rebuilt[x.index()]),
                Node::Atan2(y, x) => self.atan2(rebuilt[y.index()], rebuilt[x.index()]),
            };
            rebuilt[id.index()] = new;
        }
        Some(roots.iter().map(|r| rebuilt[r.index()]).collect())
    }
}
