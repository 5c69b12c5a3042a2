//! Physics of the compliant parts of a flexure-based microrobot: Kapton flexure hinges and
//! piezoelectric bending actuators, as plain functions and structs in SI units.
//!
//! Consumes: geometry and material constants (SI: m, Pa, kg/m³, V).
//! Produces: the lumped parameters a `.mech` model needs (a hinge's stiffness `k` and
//! damping `b`, an actuator's blocked force `F_b(V)` and series stiffness `k_a`) and the
//! figures of merit the reference paper reports (energy density `D_u`, twist ratio).
//!
//! Equation numbers refer to the reference paper, Doshi et al., "Model driven design for
//! flexure-based microrobots" (IROS 2015), sections III and IV; the bimorph closed form is
//! Wood, Steltz & Fearing (2005) as refined by Jafferis, Smith & Wood (2015). See
//! `docs/flexure-and-actuator.md`.

pub mod actuator;
pub mod error;
pub mod flexure;
pub mod materials;

pub use actuator::{Actuator, Bimorph, PiezoCoefficients};
pub use error::Invalid;
pub use flexure::{Flexure, HingeKind};
pub use materials::Material;
