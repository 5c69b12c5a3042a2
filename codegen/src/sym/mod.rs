//! The symbolic engine (placeholder while the expression pool is written).

pub mod number;

pub use number::Number;
