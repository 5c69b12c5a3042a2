//! The flexure characterization experiment of the seed paper (Sec. IV.A–B), on measured or
//! simulated data: a physical pendulum hangs from the flexure under test and rings down; each
//! decay trace gives the flexure's stiffness and damping, and a set of flexures gives Young's
//! modulus and the loss factor (uncastellated) or the effective length and loss factor
//! (castellated hinges).
//!
//! - [`trace`]: one trace → ω_d (zero crossings), σ (log of the peaks), ω_n, ζ;
//! - [`rig`]: the specimen description (flexure geometry, pendulum, trace files) in TOML, and
//!   the trace files, checked (finite, increasing times, an amplitude plausible in radians);
//! - [`screen`]: one trace screened for amplitude-dependent damping and frequency, an offset
//!   or drifting baseline (also `mech diagnose`'s screening of pendulum traces);
//! - [`fit`]: Eqs. 3–4 per trace, means per specimen, Eqs. 6–7 and the castellated fits;
//!   every rejected trace listed, the good ones fitted, warnings on what looks wrong;
//! - tables, CSV and plots: [`crate::render::flexure_fit`];
//! - [`error`]: what can go wrong, as [`Error`], with messages for the user.

pub mod error;
pub mod fit;
pub mod rig;
pub mod screen;
pub mod trace;

pub use error::{Error, SpecimenError};
pub use fit::{fit_files, fit_specimens, FitOptions, FitReport};
pub use rig::{Pendulum, Specimen};
pub use trace::{analyze_trace, TraceAnalysis, TraceError, TraceOptions};
