//! The equations and the numbers under them: SymPy cross-checks, back ends, loops, reduced dynamics, statics, linearization, the HAMR leg.
//!
//! One test binary per group, so the suite links a few binaries instead of one per file.

#[path = "../common/mod.rs"]
mod common;
#[macro_use]
#[path = "../../codegen/tests/support/golden.rs"]
mod support;
#[path = "../../codegen/tests/support/markdown.rs"]
mod markdown;

mod actuator_extensions;
mod backends;
mod bicycle;
mod bushing;
mod chosen_speeds;
mod compliant_loops;
mod compound_joints;
mod contact;
mod degenerate_loops;
mod euler_joints;
mod golden_equations;
mod hamr;
mod hamr_robot;
mod jit;
mod language_doc;
mod linear;
mod loops;
mod mass_matrix;
mod pendulum;
mod pinocchio_free_chain;
mod plausible;
mod quaternion_joints;
mod quaternion_loops;
mod reduced;
mod resonances;
mod rolling_disc;
mod simulation_outputs;
mod springs;
mod state_forces;
mod statics;
mod steady_rotation;
mod sympy_cross_check;
mod sympy_loops;
mod triple_pendulum;
mod urdf_import;
