//! The HAMR experiments of the reference paper (Doshi et al., "Model Driven Design for
//! Flexure-Based Microrobots", the seed), described by small TOML files under `experiments/`
//! and run by `mech experiment FILE` or all together by `mech report`.
//!
//! Consumes: an experiment file (`kind = "trajectory" | "force_deflection" | "ratio_sweep" |
//! "compare" | "bode"`, see `docs/experiments.md`) naming a `.mech` model and its settings.
//! Produces: an [`Outcome`]: CSV files and plots in an output folder, tables (model beside
//! the paper's measured values) and notes, and named key values for tests.
//!
//! Every quasi-static experiment uses static equilibria (`solve_statics`), not time
//! simulation: the paper's 0.5–1 Hz drives are far below the legs' ~65–110 Hz resonances.

pub mod bode;
pub mod compare;
pub mod error;
pub mod force;
pub mod leg;
pub mod sweep;
pub mod trajectory;

use std::path::{Path, PathBuf};

use crate::parallel::{parallel, threads};
use serde::Deserialize;

pub use error::Error;

pub use crate::render::report::Outcome;
pub use crate::render::table::Table;

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
    let experiment: Experiment = toml::from_str(text).map_err(|e| {
        let message = e.to_string();
        if message.contains("missing field `kind`") {
            Error::MissingKind
        } else if let Some((key, line)) = error::unknown_key(text, &message) {
            Error::UnknownKey { key, line }
        } else {
            Error::Toml {
                message: message.trim_end().to_string(),
            }
        }
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
        }
    }

    /// A rough relative cost, to start the slow experiments first.
    pub fn cost(&self) -> f64 {
        match &self.kind {
            Kind::Bode(s) => 1.0 + s.chirp.as_ref().map_or(0.0, |c| c.cost()),
            Kind::RatioSweep(_) => 4.0,
            _ => 1.0,
        }
    }

    /// Runs the experiment, writing its files under `out_dir` (named by `name`): the file's
    /// notes first, then what the kind observes.
    pub fn run(&self, name: &str, out_dir: &Path) -> Result<Outcome, Error> {
        let mut outcome = match &self.kind {
            Kind::Trajectory(s) => trajectory::run(s, out_dir)?,
            Kind::ForceDeflection(s) => force::run(s, out_dir)?,
            Kind::RatioSweep(s) => sweep::run(s, out_dir)?,
            Kind::Compare(s) => compare::run(s, out_dir)?,
            Kind::Bode(s) => bode::run(s, out_dir)?,
        };
        let observed = std::mem::replace(&mut outcome.notes, self.notes.clone());
        outcome.notes.extend(observed);
        outcome.name = name.to_string();
        outcome.title = self.title.clone();
        Ok(outcome)
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

/// Runs every file (parsed first, so a bad file fails before anything runs), the costly
/// ones first, on all cores; `progress` is called after each one finishes.
pub fn run_all(
    files: &[PathBuf],
    out_dir: &Path,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<Outcome>, Error> {
    let experiments: Vec<(usize, String, Experiment)> = files
        .iter()
        .enumerate()
        .map(|(k, f)| Ok((k, stem(f), load(f)?)))
        .collect::<Result<_, Error>>()?;
    let mut jobs = experiments;
    jobs.sort_by(|a, b| b.2.cost().total_cmp(&a.2.cost()));
    let results = parallel(jobs, threads(), |(k, name, experiment)| {
        let result = experiment
            .run(&name, &out_dir.join(&name))
            .map_err(|e| e.in_file(&files[k]));
        progress(&name);
        (k, result)
    });
    let mut results: Vec<(usize, Result<Outcome, Error>)> = results;
    results.sort_by_key(|(k, _)| *k);
    results.into_iter().map(|(_, r)| r).collect()
}

/// Runs one experiment file, its outputs in `out_dir/<stem>/`.
pub fn run_file(path: &Path, out_dir: &Path) -> Result<Outcome, Error> {
    let experiment = load(path)?;
    let name = stem(path);
    experiment
        .run(&name, &out_dir.join(&name))
        .map_err(|e| e.in_file(path))
}

pub(crate) fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "experiment".into())
}

// ------------------------------------------------------------------ plumbing

/// Writes a CSV under `dir` and records it.
pub(crate) fn csv(
    outcome: &mut Outcome,
    dir: &Path,
    file: &str,
    header: &[&str],
    rows: &[Vec<f64>],
) -> Result<(), Error> {
    let path = dir.join(file);
    let header: Vec<String> = header.iter().map(|s| s.to_string()).collect();
    crate::output::write_csv(&path, &header, rows).map_err(|e| Error::Write {
        path: path.clone(),
        message: e.to_string(),
    })?;
    outcome.files.push(path);
    Ok(())
}

/// `a` relative to `b` in percent, `+12 %`.
pub(crate) fn percent_diff(model: f64, paper: f64) -> String {
    if paper == 0.0 {
        return "–".into();
    }
    format!("{:+.0} %", 100.0 * (model / paper - 1.0))
}
