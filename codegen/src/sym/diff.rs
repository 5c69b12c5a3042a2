//! Differentiation of pool expressions.
//!
//! Consumes: an expression and a [`Symbol`] (or the rates of several). Produces: the partial
//! derivative, or the directional derivative `Σ_s ∂f/∂s · ṡ` (forward mode), built with the
//! canonicalizing constructors. Memoized per call, so the cost is linear in the size of the
//! DAG below the root (shared subexpressions are differentiated once).

use rustc_hash::FxHashMap;
use std::collections::HashMap;
use std::hash::BuildHasher;

use super::expr::{ExprId, ExprPool, Func, Node, Symbol};
use super::Number;

impl ExprPool {
    /// `∂root/∂symbol`.
    pub fn diff(&mut self, root: ExprId, symbol: Symbol) -> ExprId {
        let one = self.one();
        self.derivative_along(root, &HashMap::from([(symbol, one)]))
    }

    /// `Σ_s ∂root/∂s · rates[s]` over the symbols with a rate (the others held), in one
    /// forward pass: each node's rate is built once from its operands' rates. Summing the
    /// partials `∂root/∂s` one symbol at a time gives the same value, but each partial
    /// repeats the product rule's terms through the whole DAG, and the sum of them (the
    /// loop bias `J̇u` of a four-legged robot: 47k operations) shares little.
    pub fn derivative_along<S: BuildHasher>(
        &mut self,
        root: ExprId,
        rates: &HashMap<Symbol, ExprId, S>,
    ) -> ExprId {
        let mut memo = FxHashMap::default();
        self.diff_memo(root, rates, &mut memo)
    }

    /// Total time derivative with `q̇ = u`, `u̇ = Acceleration`, explicit `t` (inputs are
    /// treated as constants here: callers that need input rates must add them).
    pub fn time_derivative(&mut self, root: ExprId) -> ExprId {
        let mut rates = FxHashMap::default();
        for symbol in self.free_symbols(root) {
            let rate = match symbol {
                Symbol::Coordinate(i) => self.symbol(Symbol::Speed(i)),
                Symbol::Speed(i) => self.symbol(Symbol::Acceleration(i)),
                Symbol::Time => self.one(),
                Symbol::Acceleration(_) | Symbol::Param(_) | Symbol::Input(_) => continue,
            };
            rates.insert(symbol, rate);
        }
        self.derivative_along(root, &rates)
    }

    fn diff_memo<S: BuildHasher>(
        &mut self,
        id: ExprId,
        rates: &HashMap<Symbol, ExprId, S>,
        memo: &mut FxHashMap<ExprId, ExprId>,
    ) -> ExprId {
        if let Some(&d) = memo.get(&id) {
            return d;
        }
        let result = match self.node(id).clone() {
            Node::Number(_) => self.zero(),
            Node::Symbol(s) => match rates.get(&s) {
                Some(&rate) => rate,
                None => self.zero(),
            },
            Node::Add { terms, .. } => {
                let mut items = Vec::with_capacity(terms.len());
                for &(term, c) in terms.iter() {
                    items.push((self.diff_memo(term, rates, memo), c));
                }
                self.sum(&items)
            }
            Node::Mul {
                coefficient,
                factors,
            } => {
                // Product rule: Σᵢ c·eᵢ·bᵢ^(eᵢ−1)·∂bᵢ·Π_{j≠i} bⱼ^eⱼ
                let mut items = Vec::new();
                for (i, &(base, exponent)) in factors.iter().enumerate() {
                    let d_base = self.diff_memo(base, rates, memo);
                    if self.is_zero(d_base) {
                        continue;
                    }
                    let mut rest: Vec<(ExprId, Number)> = factors.to_vec();
                    rest[i].1 = exponent.sub(Number::ONE);
                    rest.push((d_base, Number::ONE));
                    items.push((self.product(coefficient.mul(exponent), &rest), Number::ONE));
                }
                self.sum(&items)
            }
            Node::Call(func, x) => {
                let dx = self.diff_memo(x, rates, memo);
                if self.is_zero(dx) {
                    self.zero()
                } else {
                    let outer = self.derivative_of_call(func, x, id);
                    self.mul(outer, dx)
                }
            }
            Node::Atan2(y, x) => {
                // d atan2(y, x) = (x dy − y dx) / (x² + y²)
                let dy = self.diff_memo(y, rates, memo);
                let dx = self.diff_memo(x, rates, memo);
                let x_dy = self.mul(x, dy);
                let y_dx = self.mul(y, dx);
                let numerator = self.sub(x_dy, y_dx);
                let x2 = self.pow(x, Number::int(2));
                let y2 = self.pow(y, Number::int(2));
                let denominator = self.add(x2, y2);
                self.div(numerator, denominator)
            }
        };
        memo.insert(id, result);
        result
    }

    /// `f'(x)` for `call = f(x)`.
    fn derivative_of_call(&mut self, func: Func, x: ExprId, call: ExprId) -> ExprId {
        match func {
            Func::Sin => self.cos(x),
            Func::Cos => {
                let s = self.sin(x);
                self.neg(s)
            }
            Func::Tan => {
                // 1 + tan²x
                let square = self.pow(call, Number::int(2));
                let one = self.one();
                self.add(one, square)
            }
            Func::Exp => call,
            Func::Ln => self.pow(x, Number::MINUS_ONE),
            Func::Abs => self.div(x, call),
            Func::Ramp => self.call(Func::Step, x),
            Func::Step => self.zero(),
        }
    }
}
