//! URDF import: a robot description (URDF, with Drake's `loop_joint` and `force_element`
//! extensions) translated into `.mech` text.
//!
//! Consumes: the URDF text as a [`SourceFile`] and the [`Options`] (the units the file's
//! numbers are in, whether the root link is fixed or floating, `--snap`). Produces: an
//! [`Import`]: the `.mech` text and the warnings (spanned [`Diagnostic`]s into the URDF) for
//! everything not translated or suspicious; or [`Errors`] with file, line and column for
//! malformed XML, a bad number, an unknown link or joint, a cycle without a loop joint.
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
mod pose;
mod read;
mod tree;

use std::sync::Arc;

use crate::diag::{Diagnostic, Errors, SourceFile};
use crate::front::units;
use crate::ir::Dimension;

/// The units of the URDF's numbers (`--length mm --mass g --time ms` for the HAMR files).
/// URDF itself is SI: m, kg, s, the default.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Units {
    pub length: String,
    pub mass: String,
    pub time: String,
}

impl Default for Units {
    fn default() -> Units {
        Units {
            length: "m".to_string(),
            mass: "kg".to_string(),
            time: "s".to_string(),
        }
    }
}

/// A unit that is not one of the `.mech` units of its quantity.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnitError {
    /// `length`, `mass` or `time`.
    pub quantity: &'static str,
    pub unit: String,
}

impl std::fmt::Display for UnitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let examples = match self.quantity {
            "length" => "m, mm, um",
            "mass" => "kg, g, mg",
            _ => "s, ms, us",
        };
        write!(
            f,
            "`{}` is not a unit of {} (for example {examples})",
            self.unit, self.quantity
        )
    }
}

impl std::error::Error for UnitError {}

impl Units {
    /// Checks each unit against its dimension (`mm` a length, `g` a mass, `ms` a time).
    pub fn new(length: &str, mass: &str, time: &str) -> Result<Units, UnitError> {
        for (quantity, unit, dimension) in [
            ("length", length, Dimension::LENGTH),
            ("mass", mass, Dimension::MASS),
            ("time", time, Dimension::TIME),
        ] {
            if units::lookup(unit).is_none_or(|u| u.dimension != dimension) {
                return Err(UnitError {
                    quantity,
                    unit: unit.to_string(),
                });
            }
        }
        Ok(Units {
            length: length.to_string(),
            mass: mass.to_string(),
            time: time.to_string(),
        })
    }
}

/// What the root link becomes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Base {
    /// The Newtonian frame: held fixed, as a leg on a test bench (default).
    #[default]
    Fixed,
    /// A body on a `free` joint: a walking robot.
    Floating,
}

#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Options {
    pub units: Units,
    pub base: Base,
    /// Move loop points that miss each other at the zero pose by round-off onto the
    /// closure's axis where the other hinge axes meet it (see `pose::snap`).
    pub snap: bool,
    /// Another URDF of the same robot (`--compare`): the links both have are compared and
    /// every disagreement of their inertial data is a warning with both files' numbers.
    pub compare: Option<Arc<SourceFile>>,
}

/// A translated robot.
#[derive(Clone, Debug)]
pub struct Import {
    /// The URDF file, for rendering the warnings.
    pub file: Arc<SourceFile>,
    /// The `.mech` model.
    pub text: String,
    /// Everything not translated or suspicious, each pointing into the URDF.
    pub warnings: Vec<Diagnostic>,
    pub bodies: usize,
    pub joints: usize,
    pub loops: usize,
}

impl Import {
    /// The warnings as text (codespan style, with the URDF's line and column).
    pub fn render_warnings(&self) -> String {
        self.warnings
            .iter()
            .map(|w| w.render(&self.file))
            .collect::<Vec<_>>()
            .join("\n")
    }
}

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
