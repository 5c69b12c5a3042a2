//! Diagnosis: measured data, fits, the candidate catalog on hidden effects, the pendulum kind.
//!
//! One test binary per group, so the suite links a few binaries instead of one per file.

#[path = "../common/mod.rs"]
mod common;

mod actuator_causes;
mod diagnose;
mod diagnose_catalog;
mod independent;
mod independent_leg;
mod pendulum_diagnose;
mod separation;
mod table;
