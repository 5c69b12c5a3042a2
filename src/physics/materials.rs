//! Named materials with their elastic constants, in SI units: the one table of
//! [`mech_codegen::physics::Material`], which also gives the language its built-in `kapton`.
//!
//! Every constant is transcribed from a cited source (the seed paper or the datasheet
//! figures collected in the project's reference notes); callers override any field by
//! building the struct with `..Material::KAPTON_HN`.

pub use mech_codegen::physics::Material;
