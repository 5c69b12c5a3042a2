//! mech: the command-line tool and analysis layer of the mech compiler.
//!
//! Runs any `.mech` model through the tape evaluator ([`tape_model`]), or the bundled models
//! through the Rust code that `build.rs` generated for them ([`models`]).
//!
//! Symbols: `q` generalized coordinates, `u = q̇` generalized speeds, `M(q) u̇ = F`.

pub mod animation;
pub mod cli;
pub mod describe;
pub mod diagnose;
pub mod experiments;
pub mod flexure_fit;
pub mod frequency;
pub mod helper_thread;
pub mod output;
pub mod parallel;
pub mod physics;
pub mod quantity;
pub mod render;
pub mod session;
pub mod signal_spec;
pub mod steady_motion;
pub mod sweep;
pub mod tape_model;
pub mod toml_file;

/// The models of `models/`, compiled to Rust by `build.rs` through the public build API.
pub mod models {
    include!(concat!(env!("OUT_DIR"), "/bundled_models.rs"));
}
