//! What every command does before its analysis: compile the model, apply `--set` values,
//! build the `--input` signals, and for models with loops, close them.
//!
//! Consumes: a `.mech` path and the command-line strings. Produces: a [`Session`] holding
//! the tape model, its signals, and an [`Assembled`] consistent state.

use std::fmt::Write as _;
use std::path::Path;

use mech_codegen::Compiled;
use mech_runtime::constraints::{choose_independent, complete_independent, jacobian};
use mech_runtime::{
    assemble, assemble_speeds, linearize, mobility, solve_statics, AssemblyOptions, Equilibrium,
    Fixture, Linearization, Mobility, Model, Signal, StaticsOptions,
};

use crate::signal_spec;
use crate::tape_model::TapeModel;

/// A compiled model with its run-time settings.
pub struct Session {
    pub compiled: Compiled,
    pub model: TapeModel,
    pub signals: Vec<Signal>,
}

/// A state that satisfies the loop closures.
#[derive(Clone, Debug)]
pub struct Assembled {
    pub q: Vec<f64>,
    pub u: Vec<f64>,
    /// Coordinates held at their given values while the others were solved for.
    pub independent: Vec<usize>,
    /// `None` for tree models.
    pub mobility: Option<Mobility>,
    /// Newton iterations used.
    pub iterations: usize,
}

impl Session {
    /// Compiles `path` and applies `--set NAME=VALUE` and `--input NAME=SIGNAL` strings.
    pub fn open(path: &Path, sets: &[String], inputs: &[String]) -> Result<Session, String> {
        let compiled = Compiled::from_path(path).map_err(|errors| errors.to_string())?;
        Session::from_compiled(compiled, sets, inputs)
    }

    /// As [`Session::open`], for a model already compiled (or transformed and re-derived).
    pub fn from_compiled(
        compiled: Compiled,
        sets: &[String],
        inputs: &[String],
    ) -> Result<Session, String> {
        let model = TapeModel::new(&compiled);
        let signals = mech_runtime::default_signals(&model);
        let mut session = Session {
            compiled,
            model,
            signals,
        };
        for assignment in sets {
            session.set(assignment)?;
        }
        for assignment in inputs {
            session.input(assignment)?;
        }
        Ok(session)
    }

    /// `--set m=12 g`: checks the name and the unit against the parameter's dimension.
    pub fn set(&mut self, assignment: &str) -> Result<(), String> {
        let (name, value) = signal_spec::parse_assignment(assignment)?;
        let model = &mut self.model;
        let index = model.param_index(&name).ok_or_else(|| {
            let known: Vec<&str> = (0..model.nparams()).map(|i| model.param_name(i)).collect();
            format!(
                "--set: unknown parameter `{name}`; parameters of `{}`: {}",
                model.name(),
                list(&known)
            )
        })?;
        let (si, dimension) = mech_codegen::front::units::parse_quantity(&value)
            .map_err(|e| format!("--set {name}: {e}"))?;
        let expected = self
            .compiled
            .model
            .params
            .iter()
            .nth(index)
            .map(|(_, p)| p.dimension)
            .unwrap_or_default();
        if dimension != expected {
            return Err(format!(
                "--set {name}: `{value}` has unit {dimension}, but `{name}` needs {expected}"
            ));
        }
        model.set_param(index, si);
        Ok(())
    }

    /// `--input drive=sine(...)`: checks the name and the signal's units.
    pub fn input(&mut self, assignment: &str) -> Result<(), String> {
        let (name, spec) = signal_spec::parse_assignment(assignment)?;
        let model = &self.model;
        let index = model.input_index(&name).ok_or_else(|| {
            let known: Vec<&str> = (0..model.ninputs()).map(|i| model.input_name(i)).collect();
            format!(
                "--input: unknown input `{name}`; inputs of `{}`: {}",
                model.name(),
                list(&known)
            )
        })?;
        let expected = self
            .compiled
            .model
            .inputs
            .iter()
            .nth(index)
            .map(|(_, i)| i.dimension)
            .unwrap_or_default();
        self.signals[index] = signal_spec::parse_signal(&spec, expected)
            .map_err(|e| format!("--input {name}: {e}"))?;
        Ok(())
    }

    /// Index of coordinate `name`, or an error listing the coordinates.
    pub fn coordinate_index(&self, name: &str) -> Result<usize, String> {
        let model = &self.model;
        (0..model.nq())
            .find(|&i| model.coordinate_name(i) == name)
            .ok_or_else(|| {
                let known: Vec<&str> = (0..model.nq()).map(|i| model.coordinate_name(i)).collect();
                format!(
                    "unknown coordinate `{name}`; coordinates of `{}`: {}",
                    model.name(),
                    list(&known)
                )
            })
    }

    /// The initial state of the model, with `--independent NAME[=VALUE]` coordinates held
    /// (at VALUE, or at their `q0`) and the loops closed. Without independent coordinates,
    /// they are chosen by column pivoting on `J` at `q0`.
    pub fn assemble(&self, independent: &[String]) -> Result<Assembled, String> {
        let model = &self.model;
        let mut q = vec![0.0; model.nq()];
        let mut u = vec![0.0; model.nu()];
        model.initial_state(&mut q, &mut u);
        if model.nc() == 0 {
            return Ok(Assembled {
                q,
                u,
                independent: (0..model.nq()).collect(),
                mobility: None,
                iterations: 0,
            });
        }
        let mut fixed = Vec::new();
        for item in independent {
            let (name, value) = match item.split_once('=') {
                Some((name, value)) => (name.trim(), Some(value.trim())),
                None => (item.trim(), None),
            };
            let index = self.coordinate_index(name)?;
            if let Some(value) = value {
                let (si, _) = mech_codegen::front::units::parse_quantity(value)
                    .map_err(|e| format!("--independent {name}: {e}"))?;
                q[index] = si;
            }
            fixed.push(index);
        }
        if fixed.is_empty() {
            // J has its generic rank only on the constraint manifold: close the loops first
            // (minimum-norm), choose there, then hold the chosen coordinates at their q0.
            let written = q.clone();
            assemble(model, 0.0, &mut q, &[], &AssemblyOptions::default())
                .map_err(|e| e.to_string())?;
            fixed = choose_independent(&jacobian(model, 0.0, &q));
            for &i in &fixed {
                q[i] = written[i];
            }
        }
        let iterations = assemble(model, 0.0, &mut q, &fixed, &AssemblyOptions::default())
            .map_err(|e| e.to_string())?;
        let mobility = mobility(model, 0.0, &q);
        if fixed.len() < mobility.dof() {
            // More freedom than named (e.g. a twist added by `mech diagnose`): complete the
            // list, keeping the named coordinates.
            fixed = complete_independent(&jacobian(model, 0.0, &q), &fixed);
        }
        assemble_speeds(model, 0.0, &q, &mut u, &fixed);
        let mobility = Some(mobility);
        Ok(Assembled {
            q,
            u,
            independent: fixed,
            mobility,
            iterations,
        })
    }

    /// A static equilibrium near the assembled initial state (`independent` as for
    /// [`Session::assemble`]), under constant `inputs`, with `fixtures` holding points; and
    /// the independent coordinates of the assembly.
    pub fn equilibrium(
        &self,
        independent: &[String],
        inputs: &[f64],
        fixtures: &[Fixture],
    ) -> Result<(Equilibrium, Vec<usize>), String> {
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
        .map_err(|e| format!("statics of `{}`: {e}", self.model.name()))?;
        Ok((equilibrium, state.independent))
    }

    /// The linear model about the static equilibrium under constant `inputs`, in the
    /// minimal coordinates of the assembly.
    pub fn linearization(
        &self,
        independent: &[String],
        inputs: &[f64],
    ) -> Result<Linearization, String> {
        let (equilibrium, independent) = self.equilibrium(independent, inputs, &[])?;
        linearize(&self.model, 0.0, &equilibrium.q, inputs, &independent)
            .map_err(|e| format!("linearization failed: {e}"))
    }
}

fn list(names: &[&str]) -> String {
    if names.is_empty() {
        "none".to_string()
    } else {
        names.join(", ")
    }
}

/// A readable report of an assembled state: mobility, the singular values that decided the
/// rank (with a warning when some sit near the threshold), and the coordinates.
pub fn assembly_report(model: &dyn Model, state: &Assembled) -> String {
    let mut text = String::new();
    if let Some(mobility) = &state.mobility {
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
        let mut phi = vec![0.0; model.nc()];
        model.constraints(0.0, &state.q, &mut phi);
        let worst = phi.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let _ = writeln!(
            text,
            "closed in {} Newton iteration(s), max |φ| = {worst:.1e}",
            state.iterations
        );
    }
    let _ = writeln!(text, "\n{:<20} {:>16} {:>16}  role", "coordinate", "q", "u");
    for i in 0..model.nq() {
        let role = if state.mobility.is_none() {
            "tree"
        } else if state.independent.contains(&i) {
            "independent"
        } else {
            "dependent"
        };
        let _ = writeln!(
            text,
            "{:<20} {:>16.10} {:>16.10}  {role}",
            model.coordinate_name(i),
            state.q[i],
            state.u[i]
        );
    }
    text
}
