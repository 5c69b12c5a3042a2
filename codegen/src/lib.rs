//! mech-codegen: the build-time compiler for `.mech` models.

pub mod diag;
pub mod ir;
pub mod sym;
