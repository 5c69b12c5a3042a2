//! Runtime for mech models.
//!
//! Symbols used throughout (defined once here): `q` generalized coordinates, `u = q̇`
//! generalized speeds, `M(q)` the mass matrix, `F(t, q, u, inputs)` the forcing, so that the
//! equations of motion are `M u̇ = F`.

pub mod model;

pub use model::Model;
pub use nalgebra;
