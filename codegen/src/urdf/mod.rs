//! URDF import: a robot description (URDF, with Drake's `loop_joint` and `force_element`
//! extensions) translated into `.mech` text.
//!
//! Consumes: the URDF text as a [`SourceFile`] and the [`Options`] (the units the file's
//! numbers are in, whether the root link is fixed or floating, `--snap`). Produces: an
//! [`Import`]: the `.mech` text and the warnings (spanned
//! [`Diagnostic`](crate::diag::Diagnostic)s into the URDF) for everything not translated or
//! suspicious; or [`Errors`] with file, line and column for malformed XML, a bad number, an
//! unknown link or joint, a cycle without a loop joint.
//!
//! The translation:
//! - link → `body` (mass, centre of mass, inertia about it in link axes; an inertial frame
//!   with `rpy` is turned into link axes); the root link → the Newtonian frame (default) or a
//!   body on a `free` joint; collision origins → named points (and outputs);
//! - joint → `joint`: revolute, continuous → `pin`, prismatic → `slider`, fixed → `weld`,
//!   floating → `free`, Drake's ball → `ball`; planar → two sliders and a
//!   pin through massless bodies (written before `.mech` had `planar`, whose slide directions
//!   differ; it could now use it); `<dynamics damping>` → `damping`; limits and friction → comments;
//! - Drake `loop_joint` → `loop` (`continuous`/`revolute` → `revolute`, `ball` → `coincident`),
//!   Drake's `drake:ball_constraint` → `coincident`;
//! - Drake force elements → parameters: `torsional_spring` → `stiffness`/`rest` of its pin
//!   or revolute loop, `prismatic_spring` → of its slider, `linear_spring_damper` → `spring`;
//! - transmissions → comments.
//!
//! Numbers are copied as written (exact decimals), with the units given; only computed values
//! (snapped points, turned inertias) are printed from `f64`.

mod compare;
mod emit;
mod options;
mod pose;
mod read;
mod tree;

use std::sync::Arc;

use crate::diag::{Errors, SourceFile};
pub use options::{Base, Import, Options, UnitError, Units};

/// Translates a URDF file into `.mech` text. The errors are the imported file's or, with
/// `compare`, the other file's (their [`Errors`] name the file).
pub fn import(file: Arc<SourceFile>, options: &Options) -> Result<Import, Errors> {
    let robot = read::read(&file)?;
    let differences = match &options.compare {
        Some(other_file) => {
            let other = read::read(other_file)?;
            compare::compare(&robot, &other, other_file, &options.units)
        }
        None => Vec::new(),
    };
    let mut imported = emit::emit(&file, &robot, options)?;
    imported.warnings.extend(differences);
    Ok(imported)
}
