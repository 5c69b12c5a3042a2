//! Back ends: from [`Equations`](crate::kane::Equations) to Rust source or to a tape.
//!
//! `lower` turns one expression node into an operator tree; `tape` flattens those trees into
//! register instructions; `rust` prints them as Rust expressions. Sharing the lowering keeps
//! the two back ends' arithmetic identical. `include` lists the models of one build as
//! modules of a single file.

pub mod include;
pub mod lower;
pub mod rust;
pub mod tape;
