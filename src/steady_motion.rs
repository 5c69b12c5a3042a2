//! Linearization about a steady motion, at one operating point or swept over a parameter or
//! a speed: the eigenvalues against forward speed of a bicycle, spin of a top or a disc.
//!
//! Consumes: a [`Session`], the held coordinates (`--independent`), `--q0`/`--u0` settings,
//! constant inputs and, for a sweep, `NAME=FROM..TO:N` (a parameter or a speed, with units).
//! Produces: [`SteadyLinearization`]s (`mech_runtime::steady`), one per swept value; no
//! printing, no files (`cli::linearize` renders them).

use mech_codegen::ir::Dimension;
use mech_runtime::{linearize_steady, Model, SteadyLinearization, SteadyState};

use crate::session::{quantity, Error, NameKind, Session};

/// Largest number of points of a sweep (each is a linearization: tens of model evaluations).
pub const MAX_POINTS: usize = 10_000;

/// What a sweep varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Swept {
    /// A parameter, by index: the model changes, the operating point's speeds do not.
    Parameter(usize),
    /// A speed's value at the operating point, by index (held independent).
    Speed(usize),
}

/// `NAME=FROM..TO:N`: `N` evenly spaced values from `FROM` to `TO` (SI).
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    pub name: String,
    pub swept: Swept,
    pub values: Vec<f64>,
    /// The SI unit of the values, as shown (the unit they were written in is not kept).
    pub unit: String,
}

impl Sweep {
    /// Reads `NAME=FROM..TO:N` for `session`'s model: `NAME` a parameter or a speed, the ends
    /// in its unit (`--sweep 'rear=0..30 rad/s:61'`), `2 ≤ N ≤ MAX_POINTS`.
    pub fn parse(session: &Session, text: &str) -> Result<Sweep, Error> {
        let option = "--sweep";
        let syntax = |hint: &str| Error::Syntax {
            option,
            text: text.to_string(),
            hint: format!("expected `NAME=FROM..TO:N`, e.g. `v=0..10 m/s:41`; {hint}"),
        };
        let (name, range) = text.split_once('=').ok_or_else(|| syntax("no `=`"))?;
        let name = name.trim();
        let (low, rest) = range.split_once("..").ok_or_else(|| syntax("no `..`"))?;
        let (high, count) = rest.rsplit_once(':').ok_or_else(|| syntax("no `:N`"))?;
        let count: usize = count
            .trim()
            .parse()
            .ok()
            .filter(|n| (2..=MAX_POINTS).contains(n))
            .ok_or_else(|| syntax(&format!("N is a whole number from 2 to {MAX_POINTS}")))?;
        let model = &session.model;
        let parameter = session.index_of(NameKind::Parameter, name, Some(option));
        let (swept, dimension) = if let Ok(index) = parameter {
            (Swept::Parameter(index), session.param_dimension(index))
        } else {
            let index = session
                .index_of(NameKind::Speed, name, Some(option))
                .map_err(|_| {
                    let known: Vec<&str> = (0..model.nparams())
                        .map(|i| model.param_name(i))
                        .chain((0..model.nu()).map(|i| model.speed_name(i)))
                        .collect();
                    syntax(&format!(
                        "`{name}` is neither a parameter nor a speed of `{}` ({})",
                        model.name(),
                        known.join(", ")
                    ))
                })?;
            (Swept::Speed(index), session.speed_dimension(index))
        };
        let (low, high) = (low.trim(), high.trim());
        // `0..10 m/s`: a bare number at one end takes the unit of the other.
        let unit_of = |text: &str| {
            let number = (1..=text.len())
                .rev()
                .find(|&n| text.is_char_boundary(n) && text[..n].trim().parse::<f64>().is_ok());
            number.map(|n| text[n..].trim().to_string())
        };
        let with_unit = |bare: &str, other: &str| match (bare.parse::<f64>(), unit_of(other)) {
            (Ok(_), Some(unit)) if !unit.is_empty() => format!("{bare} {unit}"),
            _ => bare.to_string(),
        };
        let (low, high) = (
            quantity(option, name, &with_unit(low, high), dimension)?,
            quantity(option, name, &with_unit(high, low), dimension)?,
        );
        let step = (high - low) / (count - 1) as f64;
        Ok(Sweep {
            name: name.to_string(),
            swept,
            values: (0..count).map(|k| low + step * k as f64).collect(),
            unit: match swept {
                Swept::Speed(_) => session.speed_unit(name),
                Swept::Parameter(_) if dimension == Dimension::NONE => "rad or 1".to_string(),
                Swept::Parameter(_) => dimension.to_string(),
            },
        })
    }
}

/// Above this `max |ẋ|` at the operating point, it is not a steady motion (reports warn).
pub const UNSTEADY: f64 = 1e-8;

/// Above this [`SteadyLinearization::cyclic_change`], the dropped coordinates are cyclic to
/// first order only (reports warn).
pub const NOT_CYCLIC: f64 = 1e-6;

/// The names of the coordinates a steady linearization dropped as cyclic.
pub fn cyclic_names<'a>(model: &'a dyn Model, linear: &SteadyLinearization) -> Vec<&'a str> {
    crate::session::coordinate_names(model, &linear.cyclic)
}

/// The names of a steady linearization's states: `q_NAME` for a coordinate, `u_NAME` for a
/// speed.
pub fn state_names(model: &dyn Model, linear: &SteadyLinearization) -> Vec<String> {
    let name = |state: &SteadyState| match *state {
        SteadyState::Coordinate(i) => format!("q_{}", model.coordinate_name(i)),
        SteadyState::Speed(i) => format!("u_{}", model.speed_name(i)),
    };
    linear.states.iter().map(name).collect()
}

/// Where a steady motion starts: the held coordinates and the `--q0`/`--u0` settings.
#[derive(Clone, Debug, Default)]
pub struct OperatingPoint {
    pub independent: Vec<String>,
    pub q0: Vec<String>,
    pub u0: Vec<String>,
}

/// The linearization about the steady motion through the assembled `point` under the
/// constant `inputs`, with speed `speed` (if given) set to a value first.
fn linearize_at(
    session: &Session,
    point: &OperatingPoint,
    inputs: &[f64],
    speed: Option<(usize, f64)>,
) -> Result<SteadyLinearization, Error> {
    let (q, mut u) = session.initial_state(&point.q0, &point.u0)?;
    let mut independent = point.independent.clone();
    if let Some((index, value)) = speed {
        u[index] = value;
        // Held, so that the assembly keeps it and solves the others from it.
        let name = session.model.speed_name(index).to_string();
        if !independent
            .iter()
            .any(|held| held.split('=').next() == Some(&name))
        {
            independent.push(name);
        }
    }
    let state = session.assemble_from(&independent, (q, u))?;
    linearize_steady(
        &session.model,
        0.0,
        (&state.q, &state.u),
        inputs,
        &state.independent,
        &state.speeds,
    )
    .map_err(Error::Linearization)
}

/// The linearization about the steady motion through the assembled initial state.
pub fn linearize(
    session: &Session,
    point: &OperatingPoint,
    inputs: &[f64],
) -> Result<SteadyLinearization, Error> {
    linearize_at(session, point, inputs, None)
}

/// One linearization per value of `sweep`, in order; a swept parameter is restored after.
pub fn sweep(
    session: &mut Session,
    point: &OperatingPoint,
    inputs: &[f64],
    sweep: &Sweep,
    mut progress: impl FnMut(usize),
) -> Result<Vec<SteadyLinearization>, Error> {
    let mut results = Vec::with_capacity(sweep.values.len());
    for (k, &value) in sweep.values.iter().enumerate() {
        let linear = match sweep.swept {
            Swept::Speed(index) => linearize_at(session, point, inputs, Some((index, value))),
            Swept::Parameter(index) => {
                let previous = session.model.param(index);
                session.set_si(index, value)?;
                let linear = linearize_at(session, point, inputs, None);
                session.model.set_param(index, previous);
                linear
            }
        }?;
        results.push(linear);
        progress(k + 1);
    }
    Ok(results)
}
