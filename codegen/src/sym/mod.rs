//! The symbolic engine: exact numbers, a hash-consed expression DAG with canonical sums and
//! products, differentiation, evaluation and an s-expression text form.
//!
//! Consumes: constructor calls from Kane's method (`kane`). Produces: [`ExprPool`] + root
//! [`ExprId`]s that the back ends (`back::tape`, `back::rust`) schedule and emit.

mod diff;
mod eval;
mod expr;
pub mod number;
mod sexpr;
mod subst;
#[cfg(test)]
mod tests;

pub use eval::power;
pub use expr::{children, ExprId, ExprPool, Func, Limits, Node, Symbol};
pub use number::Number;
