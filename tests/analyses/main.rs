//! The analyses of the application crate: the paper's experiments, flexure and actuator physics, the README.
//!
//! One test binary per group, so the suite links a few binaries instead of one per file.

#[path = "../common/mod.rs"]
mod common;
#[path = "../../codegen/tests/support/markdown.rs"]
mod markdown;

mod actuator;
mod animate;
mod docs_commands;
mod experiments;
mod flexure;
mod flexure_effects;
mod flexure_screening;
mod locomotion;
mod readme;
mod sweep;
