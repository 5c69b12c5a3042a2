//! What an import is asked for and what it gives back: the units of the URDF's numbers
//! (checked against the `.mech` units of each quantity), whether the root link is fixed or
//! floating, `--snap` and `--compare`; and the translated robot with its warnings.
//!
//! Consumes: option text (`--length mm`). Produces: [`Options`] for `import` and `emit`
//! (its [`Units`] for `compare`), and the [`Import`] that `emit` fills.

use std::sync::Arc;

use crate::diag::{Diagnostic, SourceFile};
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
