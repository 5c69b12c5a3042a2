//! The HAMR experiments of the reference paper (Doshi et al., "Model Driven Design for
//! Flexure-Based Microrobots", the seed), described by small TOML files under `experiments/`
//! and run by `mech experiment FILE` or all together by `mech report`.
//!
//! Consumes: an experiment file (`kind = "trajectory" | "force_deflection" | "ratio_sweep" |
//! "compare" | "bode" | "table_diagnosis" | "tolerance" | "locomotion"`, see `docs/experiments.md`) naming a `.mech` model and its settings.
//! Produces: each kind's `compute` returns its results as plain data (equilibria, forces,
//! sweeps, responses); [`crate::render::experiments`] turns them into an `Outcome` (tables
//! of the model beside the paper's measured values, notes, CSV files and plots, named key
//! values for tests).
//!
//! Every quasi-static experiment uses static equilibria (`solve_statics`), not time
//! simulation: the paper's 0.5–1 Hz drives are far below the legs' ~65–110 Hz resonances.

pub mod bode;
pub mod compare;
pub mod error;
pub mod force;
pub mod leg;
pub mod locomotion;
pub mod sweep;
pub mod table_diagnosis;
pub mod tolerance;
pub mod trajectory;

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::toml_file::{self, TomlError};

pub use error::Error;

/// One experiment file: what every kind has (a title, notes on the comparison with the
/// paper, printed in the report), then the kind's own keys.
#[derive(Debug, Clone, Deserialize)]
pub struct Experiment {
    pub title: String,
    #[serde(default)]
    pub notes: Vec<String>,
    #[serde(flatten)]
    pub kind: Kind,
}

/// The experiment kinds, by the file's `kind` key.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Kind {
    Trajectory(trajectory::Spec),
    ForceDeflection(force::Spec),
    RatioSweep(sweep::Spec),
    Compare(compare::Spec),
    Bode(bode::Spec),
    TableDiagnosis(table_diagnosis::Spec),
    Tolerance(tolerance::Spec),
    Locomotion(locomotion::Spec),
}

/// Reads and checks an experiment file. Errors name the file and the key.
pub fn load(path: &Path) -> Result<Experiment, Error> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::Read {
        what: "experiment",
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    parse(&text).map_err(|e| e.in_file(path))
}

/// Parses an experiment from TOML text.
pub fn parse(text: &str) -> Result<Experiment, Error> {
    let hint = "docs/experiments.md lists the keys of each kind";
    let experiment: Experiment = toml_file::parse(text, hint).map_err(|error| match error {
        TomlError::Other { message } if message.contains("missing field `kind`") => {
            Error::MissingKind
        }
        error => Error::Toml(error),
    })?;
    experiment.check()?;
    Ok(experiment)
}

impl Experiment {
    pub fn title(&self) -> &str {
        &self.title
    }

    /// Checks the quantities (units, signs) before anything runs.
    fn check(&self) -> Result<(), Error> {
        match &self.kind {
            Kind::Trajectory(s) => s.check(),
            Kind::ForceDeflection(s) => s.check(),
            Kind::RatioSweep(s) => s.check(),
            Kind::Compare(s) => s.check(),
            Kind::Bode(s) => s.check(),
            Kind::TableDiagnosis(s) => s.check(),
            Kind::Tolerance(s) => s.check(),
            Kind::Locomotion(s) => s.check(),
        }
    }

    /// A rough relative cost, to start the slow experiments first.
    pub fn cost(&self) -> f64 {
        match &self.kind {
            Kind::Bode(s) => 1.0 + s.chirp.as_ref().map_or(0.0, |c| c.cost()),
            Kind::RatioSweep(_) => 4.0,
            // Two diagnoses over the whole catalog, ~1 min each.
            Kind::TableDiagnosis(_) => 8.0,
            Kind::Locomotion(s) => s.cost(),
            _ => 1.0,
        }
    }
}

/// The `compare` experiment at `path` (the table a `table_diagnosis` experiment diagnoses).
pub fn load_compare(path: &Path) -> Result<compare::Spec, Error> {
    match load(path)?.kind {
        Kind::Compare(compare) => Ok(compare),
        _ => Err(Error::Key {
            message: format!(
                "key `table`: `{}` is not a `compare` experiment (the one with the robots and \
                 their `paper` rows)",
                path.display()
            ),
        }),
    }
}

/// The experiment files of a folder, sorted by name.
pub fn experiment_files(folder: &Path) -> Result<Vec<PathBuf>, Error> {
    let entries = std::fs::read_dir(folder).map_err(|e| Error::Read {
        what: "the experiments folder",
        path: folder.to_path_buf(),
        message: e.to_string(),
    })?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(Error::NoExperimentFiles {
            folder: folder.to_path_buf(),
        });
    }
    Ok(files)
}
