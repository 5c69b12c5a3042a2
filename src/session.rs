//! What every command does before its analysis: compile the model, apply `--set` values,
//! build the `--input` signals, and for models with loops, close them.
//!
//! Consumes: a `.mech` path and the command-line strings. Produces: a [`Session`] holding
//! the tape model, its signals, and an [`Assembled`] consistent state.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use mech_codegen::ir::{Dimension, OutputKind};
use mech_codegen::{Compiled, Diagnostic, Errors};
use mech_runtime::constraints::{
    choose_independent, complete_independent, holonomic_jacobian, independent_speeds, jacobian,
};
use mech_runtime::nalgebra::{DMatrix, DVector};
use mech_runtime::{
    assemble, assemble_along, assemble_speeds, linearize, mobility, simulate, simulate_reduced,
    solve_statics, AssemblyOptions, Equilibrium, Fixture, Linearization, Mobility, Model,
    RuntimeError, Signal, SimOptions, StaticsOptions, Trajectory,
};

use crate::signal_spec;
use crate::tape_model::TapeModel;
use serde::Deserialize;

/// A model as an experiment file names it: the `.mech` file, its parameter settings, and
/// the coordinates held independent when closing its loops. The keys `model`, `set` and
/// `independent` of every experiment file (flattened into each kind's keys).
#[derive(Debug, Clone, Deserialize)]
pub struct ModelSpec {
    /// Path of the `.mech` file, relative to the current directory (or absolute).
    #[serde(rename = "model")]
    pub path: PathBuf,
    /// Parameter settings, `NAME=VALUE` as for `--set`.
    #[serde(default)]
    pub set: Vec<String>,
    /// Coordinates held independent when closing the loops; empty: the analysis chooses
    /// (a HAMR leg holds its actuator coordinates).
    #[serde(default)]
    pub independent: Vec<String>,
}

/// What a name refers to in a model, for [`Error::UnknownName`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NameKind {
    Parameter,
    Input,
    Output,
    Coordinate,
    Speed,
}

impl NameKind {
    fn singular(self) -> &'static str {
        match self {
            NameKind::Parameter => "parameter",
            NameKind::Input => "input",
            NameKind::Output => "output",
            NameKind::Coordinate => "coordinate",
            NameKind::Speed => "speed",
        }
    }
}

/// Why the text of a setting cannot be read, from the parser that read it.
#[derive(Debug, thiserror::Error)]
pub enum SettingError {
    #[error(transparent)]
    Assignment(#[from] signal_spec::AssignmentError),
    #[error(transparent)]
    Quantity(#[from] mech_codegen::front::units::QuantityError),
    #[error(transparent)]
    Signal(#[from] signal_spec::Error),
}

/// Why a session cannot be opened, set up or analysed. Each message names the option (or
/// the model) and says what was expected.
#[derive(Debug)]
pub enum Error {
    /// The model does not compile: every diagnostic with file, line and column.
    Compile(Errors),
    /// A name the model does not have, with the names it has.
    UnknownName {
        /// The option that gave it (`--set`), if any.
        option: Option<&'static str>,
        kind: NameKind,
        name: String,
        model: String,
        known: Vec<String>,
    },
    /// A setting whose text cannot be read (not `NAME=VALUE`, a bad quantity or signal).
    Setting {
        option: &'static str,
        /// The name set, when the text got that far.
        name: Option<String>,
        /// Boxed: the parsers' errors are large, and sessions return errors often.
        error: Box<SettingError>,
    },
    /// An option's text that does not have the form it needs (`hint` says which).
    Syntax {
        option: &'static str,
        text: String,
        hint: String,
    },
    /// A quantity of the wrong dimension for what it sets.
    WrongUnit {
        option: &'static str,
        name: String,
        value: String,
        found: Dimension,
        expected: Dimension,
    },
    /// Parameter values that break a physical rule of the model (a negative mass, an
    /// impossible inertia, a flexure dimension that is not positive).
    Implausible {
        option: &'static str,
        /// The settings given, `NAME=VALUE`.
        settings: Vec<String>,
        /// The first rule broken (boxed: it holds the rule's expressions).
        broken: Box<mech_codegen::ir::Implausible>,
    },
    /// `--q0` or `--independent` on a part of a quaternion (`tip.e0`): the parts must stay
    /// a unit quaternion.
    QuaternionPart { option: &'static str, name: String },
    /// `--independent` on a coordinate the loop closure cannot hold: its rate is not a speed
    /// (an Euler angle, or any coordinate of a model with `speed` declarations).
    NotHeld { name: String, reason: &'static str },
    /// The same name set twice by one option.
    Repeated {
        option: &'static str,
        name: String,
        first: String,
        second: String,
    },
    /// The loops could not be closed. `site`: the error again, pointing at the declaration
    /// of the loop it names, when the model's text is at hand.
    Assembly {
        error: RuntimeError,
        site: Option<Box<Errors>>,
    },
    /// An analysis the model cannot have, pointing at the declaration that rules it out (a
    /// velocity constraint in statics: it has no form in the coordinates).
    Unsupported(Box<Errors>),
    /// No static equilibrium was found.
    Statics { model: String, error: RuntimeError },
    /// The linearization about the equilibrium failed.
    Linearization(RuntimeError),
    /// The simulation stopped.
    Simulation { model: String, error: RuntimeError },
}

impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Error::Compile(errors) => write!(f, "{errors}"),
            Error::UnknownName {
                option,
                kind,
                name,
                model,
                known,
            } => {
                if let Some(option) = option {
                    write!(f, "{option}: ")?;
                }
                let known: Vec<&str> = known.iter().map(String::as_str).collect();
                write!(
                    f,
                    "unknown {} `{name}`; {}s of `{model}`: {}",
                    kind.singular(),
                    kind.singular(),
                    list(&known)
                )
            }
            Error::Setting {
                option,
                name,
                error,
            } => match name {
                Some(name) => write!(f, "{option} {name}: {error}"),
                None => write!(f, "{option}: {error}"),
            },
            Error::Syntax { option, text, hint } => write!(f, "{option} `{text}`: {hint}"),
            Error::WrongUnit {
                option,
                name,
                value,
                found,
                expected,
            } => {
                // Speeds of pins are rad/s, which is 1/s (shown as Hz) to the units.
                let speed = matches!(*option, "--u0" | "--sweep");
                write!(f, "{option} {name}: `{value}` ")?;
                if *found == Dimension::NONE {
                    write!(f, "has no unit, but `{name}` needs ")?;
                } else if speed && *found == Dimension::FREQUENCY {
                    write!(f, "is an angular speed, but `{name}` needs ")?;
                } else {
                    write!(f, "has unit {found}, but `{name}` needs ")?;
                }
                if *expected == Dimension::NONE {
                    write!(f, "no unit (a plain number, or an angle such as `30 deg`)")
                } else if speed && *expected == Dimension::FREQUENCY {
                    write!(f, "an angular speed (e.g. `{name}=2 rad/s`)")
                } else {
                    write!(f, "{expected} (e.g. `{name}=2 {expected}`)")
                }
            }
            Error::QuaternionPart { option, name } if *option == "--q0" => write!(
                f,
                "--q0 {name}: a quaternion's parts cannot be set one by one (they must stay a \
                 unit quaternion); turn the joint's start with its `parent_frame`"
            ),
            Error::NotHeld { name, reason } => write!(
                f,
                "--independent {name}: {reason}, and the loop closure holds coordinates whose \
                 rate is a speed (pins and sliders of a model without `speed` declarations); \
                 let the assembly choose"
            ),
            Error::QuaternionPart { option, name } => write!(
                f,
                "{option} {name}: a quaternion's parts cannot be held one by one (they must \
                 stay a unit quaternion); hold a pin or slider coordinate, or let the assembly \
                 choose"
            ),
            Error::Repeated {
                option,
                name,
                first,
                second,
            } => write!(
                f,
                "{option} {name}: given twice (`{first}` and `{second}`); give it once"
            ),
            Error::Implausible {
                option,
                settings,
                broken,
            } => write!(f, "{option} {}: {broken}", settings.join(", ")),
            Error::Assembly {
                site: Some(site), ..
            } => write!(f, "{site}"),
            Error::Assembly { error, site: None } => write!(f, "{error}"),
            Error::Unsupported(site) => write!(f, "{site}"),
            Error::Statics { model, error } => write!(f, "statics of `{model}`: {error}"),
            Error::Linearization(error) => write!(f, "linearization failed: {error}"),
            Error::Simulation { model, error } => {
                write!(f, "simulation of `{model}` failed: {error}")
            }
        }
    }
}

impl std::error::Error for Error {}

/// An error if two of the `NAME=VALUE` `assignments` given by `option` set the same name:
/// which one was meant cannot be known.
fn refuse_repeated(option: &'static str, assignments: &[String]) -> Result<(), Error> {
    let mut seen = std::collections::BTreeMap::new();
    for text in assignments {
        let Ok((name, _)) = signal_spec::parse_assignment(text) else {
            continue; // reported with its position when it is applied
        };
        if let Some(first) = seen.insert(name.clone(), text.clone()) {
            return Err(Error::Repeated {
                option,
                name,
                first,
                second: text.clone(),
            });
        }
    }
    Ok(())
}

/// `text` (the value given to `name` by `option`) in SI, if its unit has the `expected`
/// dimension. A bare number is SI only where the dimension is none (an angle in rad).
pub fn quantity(
    option: &'static str,
    name: &str,
    text: &str,
    expected: Dimension,
) -> Result<f64, Error> {
    let (si, found) =
        mech_codegen::front::units::parse_quantity(text).map_err(|error| Error::Setting {
            option,
            name: Some(name.to_string()),
            error: Box::new(SettingError::Quantity(error)),
        })?;
    if found != expected {
        return Err(Error::WrongUnit {
            option,
            name: name.to_string(),
            value: text.to_string(),
            found,
            expected,
        });
    }
    Ok(si)
}

/// A compiled model with its run-time settings. Cloning one is cheaper than compiling the
/// text again (a diagnosis opens the same model once per candidate).
#[derive(Clone)]
pub struct Session {
    pub compiled: Compiled,
    pub model: TapeModel,
    pub signals: Vec<Signal>,
}

/// The units of a coordinate of `dimension` and of its speed: angles (dimensionless) in rad.
fn dimension_units(dimension: Dimension) -> (String, String) {
    if dimension == Dimension::NONE {
        ("rad".into(), "rad/s".into())
    } else {
        let speed = dimension.div(Dimension::TIME);
        (dimension.to_string(), speed.to_string())
    }
}

/// A state that satisfies the loop closures.
#[derive(Clone, Debug)]
pub struct Assembled {
    pub q: Vec<f64>,
    pub u: Vec<f64>,
    /// Coordinates held at their given values while the others were solved for.
    pub independent: Vec<usize>,
    /// Speeds held at their given values while the others were solved for from the
    /// constraint rows: `independent` unless the model has velocity constraints.
    pub speeds: Vec<usize>,
    /// `None` for tree models.
    pub mobility: Option<Mobility>,
    /// Newton iterations used.
    pub iterations: usize,
}

impl Session {
    /// Compiles `path` and applies `--set NAME=VALUE` and `--input NAME=SIGNAL` strings.
    pub fn open(path: &Path, sets: &[String], inputs: &[String]) -> Result<Session, Error> {
        let compiled = Compiled::from_path(path).map_err(Error::Compile)?;
        Session::from_compiled(compiled, sets, inputs)
    }

    /// As [`Session::open`], for a model already compiled (or transformed and re-derived).
    pub fn from_compiled(
        compiled: Compiled,
        sets: &[String],
        inputs: &[String],
    ) -> Result<Session, Error> {
        let model = TapeModel::new(&compiled);
        let signals = mech_runtime::default_signals(&model);
        let mut session = Session {
            compiled,
            model,
            signals,
        };
        refuse_repeated("--set", sets)?;
        refuse_repeated("--input", inputs)?;
        // Checked together: one value may only be plausible with another (`I_p` and `L_cm`
        // of the flexure rig).
        for assignment in sets {
            session.assign(assignment)?;
        }
        session.check_plausible(sets)?;
        for assignment in inputs {
            session.input(assignment)?;
        }
        Ok(session)
    }

    /// `--set m=12 g`: checks the name, the unit against the parameter's dimension, and the
    /// model's physical rules ([`Error::Implausible`], the value is then not kept).
    pub fn set(&mut self, assignment: &str) -> Result<(), Error> {
        self.keep_if_plausible(assignment, |session| session.assign(assignment))
    }

    /// Parameter `index` set to `value` in SI units (no unit check), under the model's
    /// physical rules as [`Session::set`].
    pub fn set_si(&mut self, index: usize, value: f64) -> Result<(), Error> {
        let shown = format!("{}={value}", self.model.param_name(index));
        self.keep_if_plausible(&shown, |session| {
            session.model.set_param(index, value);
            Ok(())
        })
    }

    /// Applies `change` (a setting shown as `shown`) and keeps it if the parameters then
    /// obey the model's physical rules; otherwise restores them and returns the rule broken.
    fn keep_if_plausible(
        &mut self,
        shown: &str,
        change: impl FnOnce(&mut Session) -> Result<(), Error>,
    ) -> Result<(), Error> {
        let previous: Vec<f64> = self.parameter_values();
        change(self)?;
        let checked = self.check_plausible(&[shown.to_string()]);
        if checked.is_err() {
            for (index, value) in previous.into_iter().enumerate() {
                self.model.set_param(index, value);
            }
        }
        checked
    }

    /// The parameter values, SI, by index.
    fn parameter_values(&self) -> Vec<f64> {
        (0..self.model.nparams())
            .map(|i| self.model.param(i))
            .collect()
    }

    /// The first physical rule of the model the current parameter values break, as an error
    /// naming the `--set` `settings` that led there.
    fn check_plausible(&self, settings: &[String]) -> Result<(), Error> {
        let broken = self.compiled.model.implausible(&self.parameter_values());
        match broken.into_iter().next() {
            None => Ok(()),
            Some(broken) => Err(Error::Implausible {
                option: "--set",
                settings: settings.to_vec(),
                broken: Box::new(broken),
            }),
        }
    }

    /// [`Session::set`] without the physical rules.
    fn assign(&mut self, assignment: &str) -> Result<(), Error> {
        let option = "--set";
        let (name, value, index) = self.assignment(option, NameKind::Parameter, assignment)?;
        let si = quantity(option, &name, &value, self.param_dimension(index))?;
        self.model.set_param(index, si);
        Ok(())
    }

    /// The dimension of input `index`'s values (a force, a voltage, …).
    pub fn input_dimension(&self, index: usize) -> Dimension {
        let inputs = &self.compiled.model.inputs;
        inputs
            .iter()
            .nth(index)
            .map(|(_, i)| i.dimension)
            .unwrap_or_default()
    }

    /// The units of the coordinate named `name` and of its speed: `rad` and `rad/s` for an
    /// angle, `m` and `m/s` for a slide (`None` if there is no such coordinate).
    /// A quaternion's part (`ball.e0`) is a plain number: `1` (its rate has no speed); an
    /// Euler angle (`ball.angle1`) is an angle and a free joint's position (`free.x`) a length
    /// whose rates are not one speed.
    pub fn coordinate_units(&self, name: &str) -> Option<(String, String)> {
        let model = &self.compiled.model;
        let index = model.coordinate_names().iter().position(|n| n == name)?;
        Some(match model.coordinate_dimension(index) {
            None => ("1".into(), String::new()),
            Some(dimension) if index < model.coordinates.len() => dimension_units(dimension),
            Some(dimension) => (dimension_units(dimension).0, String::new()),
        })
    }

    /// The unit of the speed named `name`: its coordinate's rate (`rad/s`, `m/s`), `rad/s` for
    /// a quaternion's or Euler angles' angular speed (`ball.wx`), `m/s` for a free joint's
    /// velocity (`free.vx`), empty for an unknown name.
    pub fn speed_unit(&self, name: &str) -> String {
        let model = &self.compiled.model;
        if let Some(speed) = model.speeds.iter().find(|s| s.name == name) {
            return dimension_units(speed.dimension.mul(Dimension::TIME)).1;
        }
        match model.default_speed_names().iter().position(|n| n == name) {
            Some(index) => {
                dimension_units(model.default_speed_dimension(index).mul(Dimension::TIME)).1
            }
            None => String::new(),
        }
    }

    /// The unit of the scalar output named `name` (`foot.x`, `energy`), `None` for an
    /// expression output (the model keeps no dimension for it) or an unknown name.
    pub fn output_unit(&self, name: &str) -> Option<String> {
        let model = &self.compiled.model;
        let output = model.outputs.iter().find(|o| {
            o.name == name
                || [".x", ".y", ".z"]
                    .iter()
                    .chain(&mech_codegen::ir::CONTACT_OUTPUTS)
                    .any(|suffix| name.strip_suffix(suffix) == Some(o.name.as_str()))
        })?;
        let coordinate = |c: &mech_codegen::ir::Handle<mech_codegen::ir::Coordinate>| {
            dimension_units(model.coordinates[*c].dimension)
        };
        Some(match &output.kind {
            OutputKind::Position { .. } => "m".into(),
            OutputKind::Velocity { .. } => "m/s".into(),
            OutputKind::Coordinate(c) => coordinate(c).0,
            OutputKind::Speed(c) => coordinate(c).1,
            OutputKind::KineticEnergy | OutputKind::PotentialEnergy => "J".into(),
            OutputKind::Expr(_) => return None,
            OutputKind::Contact(_) => {
                let suffix = name.strip_prefix(output.name.as_str())?;
                let unit = match suffix {
                    ".penetration" => "m",
                    ".power" => "W",
                    ".dissipated" => "J",
                    _ => "N",
                };
                unit.into()
            }
        })
    }

    /// `--input drive=sine(...)`: checks the name and the signal's units.
    pub fn input(&mut self, assignment: &str) -> Result<(), Error> {
        let option = "--input";
        let (name, spec, index) = self.assignment(option, NameKind::Input, assignment)?;
        let expected = self.input_dimension(index);
        self.signals[index] =
            signal_spec::parse_signal(&spec, expected).map_err(|error| Error::Setting {
                option,
                name: Some(name),
                error: Box::new(SettingError::Signal(error)),
            })?;
        Ok(())
    }

    /// `NAME=VALUE` given by `option`: the name, the value's text and the index of the
    /// `kind` it names.
    fn assignment(
        &self,
        option: &'static str,
        kind: NameKind,
        text: &str,
    ) -> Result<(String, String, usize), Error> {
        let (name, value) =
            signal_spec::parse_assignment(text).map_err(|error| Error::Setting {
                option,
                name: None,
                error: Box::new(SettingError::Assignment(error)),
            })?;
        let index = self.index_of(kind, &name, Some(option))?;
        Ok((name, value, index))
    }

    /// Index of coordinate `name`, or an error listing the coordinates.
    pub fn coordinate_index(&self, name: &str) -> Result<usize, Error> {
        self.index_of(NameKind::Coordinate, name, None)
    }

    /// Index of input `name`, or an error listing the inputs.
    pub fn input_index(&self, name: &str) -> Result<usize, Error> {
        self.index_of(NameKind::Input, name, None)
    }

    /// Index of output `name`, or an error listing the outputs.
    pub fn output_index(&self, name: &str) -> Result<usize, Error> {
        self.index_of(NameKind::Output, name, None)
    }

    /// The dimension of parameter `index`'s values.
    pub fn param_dimension(&self, index: usize) -> Dimension {
        let params = &self.compiled.model.params;
        let dimension = params.iter().nth(index).map(|(_, p)| p.dimension);
        dimension.unwrap_or_default()
    }

    /// The dimension of speed `index`: a chosen speed's own, else its coordinate's over time
    /// (a quaternion's or Euler angles' angular speeds: 1/s, as an angle's rate; a free
    /// joint's velocity: m/s).
    pub fn speed_dimension(&self, index: usize) -> Dimension {
        if let Some(speed) = self.compiled.model.speeds.get(index) {
            return speed.dimension;
        }
        self.compiled.model.default_speed_dimension(index)
    }

    /// The index of the `kind` called `name` (given by `option`, for the message).
    pub(crate) fn index_of(
        &self,
        kind: NameKind,
        name: &str,
        option: Option<&'static str>,
    ) -> Result<usize, Error> {
        let model = &self.model;
        let count = match kind {
            NameKind::Parameter => model.nparams(),
            NameKind::Input => model.ninputs(),
            NameKind::Output => model.noutputs(),
            NameKind::Coordinate => model.nq(),
            NameKind::Speed => model.nu(),
        };
        let name_of = |i: usize| match kind {
            NameKind::Parameter => model.param_name(i),
            NameKind::Input => model.input_name(i),
            NameKind::Output => model.output_name(i),
            NameKind::Coordinate => model.coordinate_name(i),
            NameKind::Speed => model.speed_name(i),
        };
        (0..count)
            .find(|&i| name_of(i) == name)
            .ok_or_else(|| Error::UnknownName {
                option,
                kind,
                name: name.to_string(),
                model: model.name().to_string(),
                known: (0..count).map(|i| name_of(i).to_string()).collect(),
            })
    }

    /// The model's `q0` and `u0` with `--q0 NAME=VALUE` and `--u0 NAME=VALUE` in place of some:
    /// each value checked for the unit of its coordinate (rad, m) or speed (rad/s, m/s). A
    /// quaternion's parts cannot be set one by one (they must stay a unit quaternion); its
    /// angular speeds can, and so can Euler angles.
    pub fn initial_state(
        &self,
        q0: &[String],
        u0: &[String],
    ) -> Result<(Vec<f64>, Vec<f64>), Error> {
        let model = &self.model;
        let mut q = vec![0.0; model.nq()];
        let mut u = vec![0.0; model.nu()];
        model.initial_state(&mut q, &mut u);
        for text in q0 {
            let (name, value, index) = self.assignment("--q0", NameKind::Coordinate, text)?;
            let dimension = self.compiled.model.coordinate_dimension(index);
            let Some(expected) = dimension else {
                return Err(Error::QuaternionPart {
                    option: "--q0",
                    name,
                });
            };
            q[index] = quantity("--q0", &name, &value, expected)?;
        }
        for text in u0 {
            let (name, value, index) = self.assignment("--u0", NameKind::Speed, text)?;
            // A pin's or slider's speed, or an angular speed of a quaternion (rad/s).
            u[index] = quantity("--u0", &name, &value, self.speed_dimension(index))?;
        }
        Ok((q, u))
    }

    /// The initial state of the model, with `--independent NAME[=VALUE]` coordinates held
    /// (at VALUE, or at their `q0`) and the loops closed. Without independent coordinates,
    /// they are chosen by column pivoting on `J` at `q0`.
    pub fn assemble(&self, independent: &[String]) -> Result<Assembled, Error> {
        self.assemble_from(independent, self.initial_state(&[], &[])?)
    }

    /// [`Session::assemble`] from `(q, u)` in place of the model's `q0`, `u0` (the
    /// starting guess of the loop closure, whose speeds are then made consistent).
    pub fn assemble_from(
        &self,
        independent: &[String],
        (mut q, mut u): (Vec<f64>, Vec<f64>),
    ) -> Result<Assembled, Error> {
        let model = &self.model;
        let q0 = q.clone();
        if model.nc() == 0 {
            return Ok(Assembled {
                q,
                u,
                independent: (0..model.nu()).collect(),
                speeds: (0..model.nu()).collect(),
                mobility: None,
                iterations: 0,
            });
        }
        let mut fixed = Vec::new();
        for item in independent {
            fixed.push(self.held_coordinate(item, &mut q)?);
        }
        let named = fixed.clone();
        if fixed.is_empty() {
            // J has its generic rank only on the constraint manifold: close the loops first
            // (minimum-norm), choose there, then hold the chosen coordinates at their q0.
            assemble(model, 0.0, &mut q, &[], &AssemblyOptions::default())
                .map_err(|error| self.assembly_error(error))?;
            fixed = choose_independent(&holonomic_jacobian(model, 0.0, &q));
            // A chosen angular speed of a quaternion holds its rotation where the minimum-norm
            // closure left it; a pin or slider goes back to its `q0`.
            for &i in fixed.iter().filter(|&&i| i < model.plain_coordinates()) {
                q[i] = q0[i];
            }
        }
        let options = AssemblyOptions::default();
        let iterations = match assemble(model, 0.0, &mut q, &fixed, &options) {
            Ok(iterations) => iterations,
            Err(direct) => {
                // From held values far from the written ones Newton can stall: close at the
                // written q0 and move the held coordinates there in steps.
                let target: Vec<f64> = fixed.iter().map(|&c| q[c]).collect();
                let mut path = q0.clone();
                let closed = assemble(model, 0.0, &mut path, &fixed, &options)
                    .map_err(|_| self.assembly_error(direct))?;
                let moved = assemble_along(model, 0.0, &mut path, &fixed, &target, &options)
                    .map_err(|error| self.assembly_error(error))?;
                q = path;
                closed + moved
            }
        };
        let mobility = mobility(model, 0.0, &q).map_err(|error| self.assembly_error(error))?;
        if fixed.len() < mobility.dof() {
            // More freedom than named (e.g. a twist added by `mech diagnose`): complete the
            // list, keeping the named coordinates.
            fixed = complete_independent(&holonomic_jacobian(model, 0.0, &q), &fixed);
        }
        // Velocity constraints free fewer speeds than coordinates: hold the independent ones.
        let speeds = match model.velocity_rows() {
            0 => fixed.clone(),
            _ => independent_speeds(&jacobian(model, 0.0, &q), &fixed, &named),
        };
        assemble_speeds(model, 0.0, &q, &mut u, &speeds)
            .map_err(|error| self.assembly_error(error))?;
        let mobility = Some(mobility);
        Ok(Assembled {
            q,
            u,
            independent: fixed,
            speeds,
            mobility,
            iterations,
        })
    }

    /// The index of the coordinate `--independent NAME[=VALUE]` holds, with `q` set to VALUE
    /// where one is given. Errors where the coordinate's rate is not one speed (a quaternion's
    /// part, a free joint's position, an Euler angle, any coordinate under chosen speeds).
    fn held_coordinate(&self, item: &str, q: &mut [f64]) -> Result<usize, Error> {
        let model = &self.model;
        let (name, value) = match item.split_once('=') {
            Some((name, value)) => (name.trim(), Some(value.trim())),
            None => (item.trim(), None),
        };
        let index = self.coordinate_index(name)?;
        if index >= model.plain_coordinates() {
            let ir = &self.compiled.model;
            let quaternion = index >= ir.coordinates.len()
                && index < ir.coordinates.len() + 4 * ir.quaternions.len();
            return Err(match (quaternion, ir.speeds.is_empty()) {
                (true, _) => Error::QuaternionPart {
                    option: "--independent",
                    name: name.to_string(),
                },
                (false, false) => Error::NotHeld {
                    name: name.to_string(),
                    reason: "the model's speeds are chosen by `speed` declarations, so no \
                         coordinate's rate is a speed",
                },
                (false, true) if index >= ir.nq() - 3 * ir.translations.len() => Error::NotHeld {
                    name: name.to_string(),
                    reason: "a free joint's position moves by its velocity speeds \
                             turned by its rotation ((ẋ, ẏ, ż) = R v), not by one speed",
                },
                (false, true) => Error::NotHeld {
                    name: name.to_string(),
                    reason: "an Euler angle's rate is not its speed (q̇ = W(q) u)",
                },
            });
        }
        if let Some(value) = value {
            let coordinates = &self.compiled.model.coordinates;
            let expected = coordinates.iter().nth(index).map(|(_, c)| c.dimension);
            let expected = expected.unwrap_or_default();
            q[index] = quantity("--independent", name, value, expected)?;
        }
        Ok(index)
    }

    /// `error` of closing the loops, pointing at the declaration of the loop whose row it
    /// names (rows are named `<loop>.<row>`), if the model's text is at hand.
    fn assembly_error(&self, error: RuntimeError) -> Error {
        let row = match &error {
            RuntimeError::AssemblyFailed { row, .. }
            | RuntimeError::StationaryConstraint { row, .. } => Some(row),
            RuntimeError::NonFiniteConstraints { rows, .. } => rows.first(),
            _ => None,
        };
        let closure = row
            .and_then(|row| row.rsplit_once('.'))
            .and_then(|(name, _)| self.compiled.model.loops.iter().find(|l| l.name == name));
        let site = match (closure, &self.compiled.source) {
            (Some(closure), Some(file)) => {
                let diagnostic = Diagnostic::error("E0601", error.to_string()).with_label(
                    closure.span,
                    format!("loop `{}` cannot be closed here", closure.name),
                );
                Some(Box::new(Errors::new(file.clone(), vec![diagnostic])))
            }
            _ => None,
        };
        Error::Assembly { error, site }
    }

    /// A static equilibrium near the assembled initial state (`independent` as for
    /// [`Session::assemble`]), under constant `inputs`, with `fixtures` holding points; and
    /// the independent coordinates of the assembly.
    pub fn equilibrium(
        &self,
        independent: &[String],
        inputs: &[f64],
        fixtures: &[Fixture],
    ) -> Result<(Equilibrium, Vec<usize>), Error> {
        let state = self.assemble(independent)?;
        let mut q = state.q.clone();
        let equilibrium = solve_statics(
            &self.model,
            0.0,
            &mut q,
            inputs,
            fixtures,
            &StaticsOptions::default(),
        )
        .map_err(|error| {
            self.unsupported(error, |error| Error::Statics {
                model: self.model.name().to_string(),
                error,
            })
        })?;
        Ok((equilibrium, state.independent))
    }

    /// The motion from an assembled `state` under the session's input signals: the reduced
    /// methods (`options.method.is_reduced()`) in the state's independent coordinates, the
    /// others in all coordinates with the loops projected. `progress` gets the time reached.
    pub fn simulate(
        &self,
        state: &Assembled,
        options: &SimOptions,
        progress: &mut dyn FnMut(f64),
    ) -> Result<Trajectory, Error> {
        let (model, signals) = (&self.model, &self.signals);
        let (q0, u0) = (&state.q, &state.u);
        if options.method.is_reduced() {
            let independent = &state.independent;
            simulate_reduced(model, q0, u0, independent, signals, options, progress)
        } else {
            simulate(model, q0, u0, signals, options, progress)
        }
        .map_err(|error| {
            self.unsupported(error, |error| Error::Simulation {
                model: model.name().to_string(),
                error,
            })
        })
    }

    /// `error` as [`Error::Unsupported`] pointing at the model's first velocity constraint
    /// when it says the analysis cannot take velocity constraints (and the text is at hand);
    /// otherwise `otherwise(error)`.
    fn unsupported(
        &self,
        error: RuntimeError,
        otherwise: impl FnOnce(RuntimeError) -> Error,
    ) -> Error {
        let constraint = self.compiled.model.velocity_constraints.first();
        match (&error, constraint, &self.compiled.source) {
            (
                RuntimeError::VelocityConstraintsUnsupported { analysis, model },
                Some(constraint),
                Some(file),
            ) => {
                let message = format!(
                    "{analysis} of model `{model}` is not possible: it has velocity constraints, \
                     and {analysis} works with the coordinates alone"
                );
                let diagnostic = Diagnostic::error("E0602", message)
                    .with_label(
                        constraint.span,
                        format!(
                            "`{}` is a condition on the speeds, with no form in the coordinates",
                            constraint.name
                        ),
                    )
                    .with_help(
                        "simulate the model in full coordinates (dopri5, dop853, rk4), or \
                         linearize it about a steady motion (`mech linearize --steady`)",
                    );
                Error::Unsupported(Box::new(Errors::new(file.clone(), vec![diagnostic])))
            }
            _ => otherwise(error),
        }
    }

    /// The linear model about the static equilibrium under constant `inputs`, in the
    /// minimal coordinates of the assembly.
    pub fn linearization(
        &self,
        independent: &[String],
        inputs: &[f64],
    ) -> Result<Linearization, Error> {
        let (equilibrium, independent) = self.equilibrium(independent, inputs, &[])?;
        linearize(&self.model, 0.0, &equilibrium.q, inputs, &independent)
            .map_err(|error| self.unsupported(error, Error::Linearization))
    }
}

/// The names of the coordinates at `indices` (as [`Model::coordinate_name`] spells them).
pub fn coordinate_names<'a>(model: &'a dyn Model, indices: &[usize]) -> Vec<&'a str> {
    indices.iter().map(|&i| model.coordinate_name(i)).collect()
}

/// The matrices of a linearization under the names `mech linearize --matrices` and Python's
/// `linearize()` give them: `M`, `C`, `K`, `B` of `M δz̈ + C δż + K δz = B δin`, then the
/// first-order `A`, `B_s`, `C_s`, `D_s` (`ẋ = A x + B_s δin`, `y = C_s x + D_s δin`,
/// `x = [δz; δż]`). `None` when `M` is singular.
pub fn named_matrices(linear: &Linearization) -> Option<[(&'static str, DMatrix<f64>); 8]> {
    let state_space = linear.state_space()?;
    Some([
        ("M", linear.mass.clone()),
        ("C", linear.damping.clone()),
        ("K", linear.stiffness.clone()),
        ("B", linear.input.clone()),
        ("A", state_space.a),
        ("B_s", state_space.b),
        ("C_s", state_space.c),
        ("D_s", state_space.d),
    ])
}

/// `names` joined by commas, or `none`.
pub(crate) fn list(names: &[&str]) -> String {
    if names.is_empty() {
        "none".to_string()
    } else {
        names.join(", ")
    }
}

/// For a model with velocity constraints, a line with the residual `max |A u|` of the
/// assembled speeds.
fn velocity_residual(model: &dyn Model, state: &Assembled, text: &mut String) {
    if model.velocity_rows() == 0 {
        return;
    }
    let rows = jacobian(model, 0.0, &state.q) * DVector::from_column_slice(&state.u);
    let worst = rows
        .rows(model.holonomic_rows(), model.velocity_rows())
        .amax();
    let _ = writeln!(text, "speeds made consistent: max |A u| = {worst:.1e}");
}

/// A readable report of an assembled state: mobility, the singular values that decided the
/// rank (with a warning when some sit near the threshold), and the coordinates.
pub fn assembly_report(model: &dyn Model, state: &Assembled) -> String {
    let mut text = String::new();
    if let Some(mobility) = state.mobility.as_ref().filter(|m| m.rows == 0) {
        // Velocity constraints alone: no loop to close, no singular values of `J` to show.
        let _ = writeln!(text, "{mobility}");
        velocity_residual(model, state, &mut text);
    } else if let Some(mobility) = &state.mobility {
        let _ = writeln!(text, "{mobility}");
        let values: Vec<String> = mobility
            .singular_values
            .iter()
            .map(|s| format!("{s:.3e}"))
            .collect();
        let _ = writeln!(
            text,
            "singular values of J: {} (rank threshold {:.1e})",
            values.join(", "),
            mobility.threshold
        );
        let near = mobility.near_threshold();
        if !near.is_empty() {
            let _ = writeln!(
                text,
                "warning: {} singular value(s) within three decades of the threshold: the rank (and the \
                 mobility) depends on the tolerance here; check that axes meant to meet really do",
                near.len()
            );
        }
        velocity_residual(model, state, &mut text);
        let mut phi = vec![0.0; model.nc()];
        model.constraints(0.0, &state.q, &mut phi);
        let worst = phi.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let _ = writeln!(
            text,
            "closed in {} Newton iteration(s), max |φ| = {worst:.1e}",
            state.iterations
        );
        if worst > AssemblyOptions::default().tolerance {
            let _ = writeln!(
                text,
                "warning: the loops close only to max |φ| = {worst:.1e} (a least-squares fit: \
                 their rows contradict each other by about this much, e.g. axes meant to meet \
                 that miss); results carry errors of this order — move the loop points onto \
                 each other to close them exactly"
            );
        }
    }
    let _ = writeln!(text, "\n{:<20} {:>16} {:>16}  role", "coordinate", "q", "u");
    // A coordinate's speed shares its index and name (`u = q̇`); a quaternion's four
    // coordinates have none, its angular speeds are listed after the coordinates.
    let own_speed = |i: usize| i < model.nu() && model.speed_name(i) == model.coordinate_name(i);
    for i in 0..model.nq() {
        let role = if state.mobility.is_none() {
            "tree"
        } else if !own_speed(i) {
            "rotation"
        } else if state.independent.contains(&i) {
            "independent"
        } else {
            "dependent"
        };
        let u = match own_speed(i) {
            true => format!("{:>16.10}", state.u[i]),
            false => format!("{:>16}", ""),
        };
        let _ = writeln!(
            text,
            "{:<20} {:>16.10} {u}  {role}",
            model.coordinate_name(i),
            state.q[i],
        );
    }
    for i in (0..model.nu()).filter(|&i| !own_speed(i)) {
        let role = match state.mobility.is_some() && state.independent.contains(&i) {
            true => "independent speed",
            false => "speed",
        };
        let _ = writeln!(
            text,
            "{:<20} {:>16} {:>16.10}  {role}",
            model.speed_name(i),
            "",
            state.u[i]
        );
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Units by kind: a slide in m, a pin in rad, their speeds per second, a position output
    /// in m per component, the energies in J; unknown names have none.
    #[test]
    fn units_of_coordinates_and_outputs() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let chain = Session::open(&root.join("models/mixed_chain.mech"), &[], &[]).unwrap();
        let units = |a: &str, b: &str| Some((a.to_string(), b.to_string()));
        assert_eq!(chain.coordinate_units("s1"), units("m", "m/s"));
        assert_eq!(chain.coordinate_units("q2"), units("rad", "rad/s"));
        assert_eq!(chain.coordinate_units("nope"), None);
        let two = Session::open(&root.join("models/two_mass_chain.mech"), &[], &[]).unwrap();
        assert_eq!(two.output_unit("x2.y").as_deref(), Some("m"));
        assert_eq!(two.output_unit("ke").as_deref(), Some("J"));
        assert_eq!(two.output_unit("nope"), None);
    }
}
