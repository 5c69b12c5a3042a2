//! The description of one specimen of the flexure characterization experiment, read from a
//! small TOML file: the flexure's geometry, the pendulum hanging from it, and the decay
//! traces (CSV files) recorded with it.
//!
//! ```toml
//! name = "U07"                    # optional; default: the file stem
//! traces = ["u07_a.csv", "u07_b.csv"]   # relative to this file; columns: time [s], angle
//! angle_unit = "deg"              # "rad" (default) or "deg"
//! angle_column = "angle"          # optional; default: the second column
//!
//! [flexure]
//! kind = "uncastellated"          # or "castellated"
//! width = "2 mm"
//! thickness = "25 um"
//! length = "500 um"               # nominal length l
//! castellation_length = "100 um"  # castellated hinges only (optional)
//!
//! [pendulum]
//! mass = "0.2 g"                  # m
//! inertia = "2.4e-9 kg*m^2"       # I_p, about the pivot (the flexure's centre)
//! com_distance = "3 mm"           # L_cm, pivot to centre of mass
//! gravity = "9.81 m/s^2"          # optional, default 9.81 m/s²
//! ```
//!
//! Quantities are strings with a unit (any unit of the `.mech` language) or plain numbers in SI
//! (a plain length of 0.1 m or more, mass of 0.1 kg or more, is refused as a unit slip).
//! A trace's header may give the units of its columns (`time [ms], angle [deg]`); they are
//! used, and must agree with `angle_unit` when both are given.
//!
//! Consumes: the command line's DATA paths, the TOML text, the trace CSV files. Produces:
//! [`Specimen`]s and `(times, angles)` in SI, or an [`Error`] naming the file and the key.

use std::path::{Path, PathBuf};

use mech_codegen::ir::Dimension;
use serde::Deserialize;

use super::error::{Error, SpecimenError};
use crate::quantity::parse_si;

/// The pendulum of the rig (seed Sec. IV.A, Eqs. 3–4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pendulum {
    /// Mass m (kg).
    pub mass: f64,
    /// Inertia about the pivot I_p (kg·m²).
    pub inertia: f64,
    /// Pivot to centre of mass L_cm (m), positive below the pivot (hanging).
    pub com_distance: f64,
    /// Gravitational acceleration g (m/s²).
    pub gravity: f64,
}

impl Pendulum {
    /// Gravity stiffness of the hanging pendulum at small angles, `m g L_cm` (N·m/rad).
    pub fn gravity_stiffness(&self) -> f64 {
        self.mass * self.gravity * self.com_distance
    }
}

/// Geometry class of the flexure under test.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Kind {
    /// Plain rectangular flexure.
    Uncastellated,
    /// (Mirrored-)castellated hinge.
    Castellated,
}

/// Geometry of the flexure under test (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlexureGeometry {
    /// Geometry class.
    pub kind: Kind,
    /// Width w.
    pub width: f64,
    /// Thickness t.
    pub thickness: f64,
    /// Nominal length l.
    pub length: f64,
    /// Castellation length l_c (NaN if not given).
    pub castellation_length: f64,
}

/// One specimen: a flexure, its pendulum, and its traces.
#[derive(Debug, Clone, PartialEq)]
pub struct Specimen {
    /// Name for tables and plots.
    pub name: String,
    /// The file it was read from.
    pub source: PathBuf,
    /// The flexure.
    pub flexure: FlexureGeometry,
    /// The pendulum.
    pub pendulum: Pendulum,
    /// Trace files (resolved against the TOML's directory).
    pub traces: Vec<PathBuf>,
    /// Factor from the CSV's angle unit to radians, if `angle_unit` is given (else a unit in
    /// the trace's header, else rad).
    pub angle_scale: Option<f64>,
    /// Column of the angle (None: the second column).
    pub angle_column: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SpecimenFile {
    name: Option<String>,
    traces: Vec<String>,
    angle_unit: Option<String>,
    angle_column: Option<String>,
    flexure: FlexureFile,
    pendulum: PendulumFile,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FlexureFile {
    kind: Option<String>,
    width: Quantity,
    thickness: Quantity,
    length: Quantity,
    castellation_length: Option<Quantity>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PendulumFile {
    mass: Quantity,
    inertia: Quantity,
    com_distance: Quantity,
    gravity: Option<Quantity>,
}

/// A TOML quantity: a number in SI, or a string with a unit.
#[derive(Deserialize, Clone)]
#[serde(untagged)]
enum Quantity {
    Number(f64),
    Text(String),
}

/// Plain numbers are SI, which suits a flexure rig badly (`width = 1` is a metre): a plain
/// number at or above this for a length, a mass or an inertia of the rig is refused as a
/// number meant in another unit.
fn implausible_in_si(expected: Dimension) -> Option<f64> {
    if expected == Dimension::LENGTH || expected == Dimension::MASS {
        // m: flexures are µm–mm, the pendulum's arm mm–cm; kg: its mass grams at most.
        Some(0.1)
    } else if expected == Dimension::INERTIA {
        Some(1e-3) // kg·m²: a 0.1 kg mass at 0.1 m
    } else {
        None
    }
}

fn quantity(key: &'static str, q: &Quantity, expected: Dimension) -> Result<f64, SpecimenError> {
    let value = match q {
        Quantity::Number(v)
            if implausible_in_si(expected).is_some_and(|limit| v.abs() >= limit) =>
        {
            return Err(SpecimenError::PlainNumberTooLarge {
                key,
                value: *v,
                unit: expected,
            })
        }
        Quantity::Number(v) => *v,
        Quantity::Text(text) => {
            parse_si(key, text, expected, true).map_err(SpecimenError::Quantity)?
        }
    };
    if !(value.is_finite() && value > 0.0) {
        return Err(SpecimenError::NotPositive { key, value });
    }
    Ok(value)
}

/// Reads a specimen description. Errors name the file.
pub fn read_specimen(path: &Path) -> Result<Specimen, Error> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::ReadSpecimen {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    parse_specimen(path, &text)
}

/// Parses a specimen description given as text; `path` names it and anchors relative trace
/// paths.
pub fn parse_specimen(path: &Path, text: &str) -> Result<Specimen, Error> {
    parse_specimen_text(path, text).map_err(|error| Error::Specimen {
        path: path.to_path_buf(),
        error,
    })
}

fn parse_specimen_text(path: &Path, text: &str) -> Result<Specimen, SpecimenError> {
    let raw: SpecimenFile = toml::from_str(text).map_err(|e| SpecimenError::Toml {
        message: e.to_string(),
    })?;
    let flexure = flexure_geometry(&raw.flexure)?;
    let pendulum = pendulum(&raw.pendulum)?;
    let angle_scale = match raw.angle_unit.as_deref() {
        None => None,
        Some("rad") => Some(1.0),
        Some("deg") => Some(std::f64::consts::PI / 180.0),
        Some(other) => {
            return Err(SpecimenError::UnknownAngleUnit {
                unit: other.to_string(),
            })
        }
    };
    if raw.traces.is_empty() {
        return Err(SpecimenError::NoTraces);
    }
    let dir = path.parent().unwrap_or(Path::new(""));
    let traces = raw.traces.iter().map(|t| dir.join(t)).collect();
    let name = raw
        .name
        .unwrap_or_else(|| crate::output::file_stem(path, "specimen"));
    Ok(Specimen {
        name,
        source: path.to_path_buf(),
        flexure,
        pendulum,
        traces,
        angle_scale,
        angle_column: raw.angle_column,
    })
}

fn flexure_geometry(raw: &FlexureFile) -> Result<FlexureGeometry, SpecimenError> {
    let kind = match raw.kind.as_deref().map(str::to_ascii_lowercase).as_deref() {
        None | Some("uncastellated") => Kind::Uncastellated,
        Some("castellated") | Some("mirrored-castellated") => Kind::Castellated,
        Some(other) => {
            return Err(SpecimenError::UnknownKind {
                kind: other.to_string(),
            })
        }
    };
    let l = Dimension::LENGTH;
    Ok(FlexureGeometry {
        kind,
        width: quantity("flexure.width", &raw.width, l)?,
        thickness: quantity("flexure.thickness", &raw.thickness, l)?,
        length: quantity("flexure.length", &raw.length, l)?,
        castellation_length: match &raw.castellation_length {
            Some(q) => quantity("flexure.castellation_length", q, l)?,
            None => f64::NAN,
        },
    })
}

fn pendulum(raw: &PendulumFile) -> Result<Pendulum, SpecimenError> {
    let pendulum = Pendulum {
        mass: quantity("pendulum.mass", &raw.mass, Dimension::MASS)?,
        inertia: quantity("pendulum.inertia", &raw.inertia, Dimension::INERTIA)?,
        com_distance: quantity(
            "pendulum.com_distance",
            &raw.com_distance,
            Dimension::LENGTH,
        )?,
        gravity: match &raw.gravity {
            Some(q) => quantity("pendulum.gravity", q, Dimension::ACCELERATION)?,
            None => 9.81,
        },
    };
    // A common slip: the inertia about the centre of mass, which Eq. 4 does not want.
    let point_mass_inertia = pendulum.mass * pendulum.com_distance.powi(2);
    if pendulum.inertia < point_mass_inertia * (1.0 - 1e-9) {
        return Err(SpecimenError::InertiaBelowPointMass {
            inertia: pendulum.inertia,
            point_mass_inertia,
        });
    }
    Ok(pendulum)
}

/// Expands the command line's DATA arguments: `.toml` files as given, directories to the
/// `.toml` files they contain (sorted).
pub fn specimen_files(arguments: &[PathBuf]) -> Result<Vec<PathBuf>, Error> {
    let mut files = Vec::new();
    for argument in arguments {
        if argument.is_dir() {
            let mut found: Vec<PathBuf> = std::fs::read_dir(argument)
                .map_err(|e| Error::ReadDirectory {
                    path: argument.clone(),
                    message: e.to_string(),
                })?
                .filter_map(|entry| entry.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "toml"))
                .collect();
            if found.is_empty() {
                return Err(Error::NoSpecimenFiles {
                    path: argument.clone(),
                });
            }
            found.sort();
            files.extend(found);
        } else if argument.extension().is_some_and(|e| e == "toml") {
            files.push(argument.clone());
        } else {
            return Err(Error::NotSpecimenFile {
                path: argument.clone(),
            });
        }
    }
    Ok(files)
}

/// The largest amplitude (rad) a trace may have: the rig is released from 5–15°, and a
/// release of 1° written in degrees but read as radians already exceeds it. Beyond it the
/// hanging pendulum is far from the small angles Eq. 4 linearizes about.
pub const MAX_AMPLITUDE: f64 = 1.0;

/// A trace as read from its CSV file, checked: times finite and strictly increasing, angles
/// finite and of a plausible amplitude.
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    /// Sample times (s).
    pub times: Vec<f64>,
    /// Angles (rad).
    pub angles: Vec<f64>,
}

/// The SI factor of the unit in brackets at the end of column `index`'s header
/// (`time [ms]` → 1e-3), which must have dimension `expected`; `None` without brackets.
fn header_unit(
    path: &Path,
    header: &[String],
    index: usize,
    expected: Dimension,
) -> Result<Option<f64>, Error> {
    let name = &header[index];
    let Some(unit) = name
        .trim_end()
        .strip_suffix(']')
        .and_then(|rest| rest.rsplit_once('[').map(|(_, unit)| unit.trim()))
    else {
        return Ok(None);
    };
    let error = |message: String| Error::TraceUnit {
        path: path.to_path_buf(),
        column: index + 1,
        name: name.clone(),
        message,
    };
    let (scale, found) = mech_codegen::front::units::parse_quantity(&format!("1 {unit}"))
        .map_err(|e| error(format!("unit `{unit}`: {e}")))?;
    if found != expected {
        let what = if expected == Dimension::TIME {
            "a time (`s`, `ms`)"
        } else {
            "an angle (`rad`, `deg`)"
        };
        return Err(error(format!(
            "unit `{unit}` is {found}, but the column needs {what}"
        )));
    }
    Ok(Some(scale))
}

/// Reads the angle trace `path` of `specimen`; errors name the file, the line and the column.
pub fn read_trace(specimen: &Specimen, path: &Path) -> Result<Trace, Error> {
    let table = crate::output::read_csv_table(path).map_err(|error| Error::ReadTrace {
        path: path.to_path_buf(),
        message: error.to_string(),
    })?;
    let index = match &specimen.angle_column {
        Some(column) => table
            .column_index(column)
            .ok_or_else(|| Error::MissingAngleColumn {
                path: path.to_path_buf(),
                column: column.clone(),
                columns: table.header.clone(),
            })?,
        None => {
            if table.columns.len() < 2 {
                return Err(Error::NoAngleColumn {
                    path: path.to_path_buf(),
                });
            }
            1
        }
    };
    for j in [0, index] {
        let column = &table.columns[j];
        if let Some(row) = column.iter().position(|v| !v.is_finite()) {
            return Err(Error::NotFinite {
                path: path.to_path_buf(),
                line: table.lines[row],
                column: j + 1,
                name: table.header[j].clone(),
                value: column[row],
                count: column.iter().filter(|v| !v.is_finite()).count(),
            });
        }
    }
    let time_scale = header_unit(path, &table.header, 0, Dimension::TIME)?.unwrap_or(1.0);
    let angle_scale = match (
        header_unit(path, &table.header, index, Dimension::NONE)?,
        specimen.angle_scale,
    ) {
        (Some(header), Some(declared)) if (header / declared - 1.0).abs() > 1e-12 => {
            return Err(Error::TraceUnit {
                path: path.to_path_buf(),
                column: index + 1,
                name: table.header[index].clone(),
                message: format!(
                    "the header's unit disagrees with the specimen's `angle_unit` ({})",
                    if declared == 1.0 { "rad" } else { "deg" }
                ),
            })
        }
        (Some(scale), _) | (None, Some(scale)) => scale,
        (None, None) => 1.0,
    };
    let times: Vec<f64> = table.columns[0].iter().map(|t| t * time_scale).collect();
    if let Some(row) = (1..times.len()).find(|&i| times[i] <= times[i - 1]) {
        return Err(Error::TimeNotIncreasing {
            path: path.to_path_buf(),
            line: table.lines[row],
            column: 1,
            name: table.header[0].clone(),
            previous: times[row - 1],
            time: times[row],
        });
    }
    let angles: Vec<f64> = table.columns[index]
        .iter()
        .map(|a| a * angle_scale)
        .collect();
    let amplitude = super::trace::robust_amplitude(&angles);
    if amplitude > MAX_AMPLITUDE {
        return Err(Error::AngleAmplitude {
            path: path.to_path_buf(),
            column: index + 1,
            name: table.header[index].clone(),
            amplitude: amplitude / angle_scale,
            unit: if angle_scale == 1.0 { "rad" } else { "deg" },
            specimen: specimen.source.clone(),
            limit: MAX_AMPLITUDE,
        });
    }
    Ok(Trace {
        times: times.clone(),
        angles,
    })
}
