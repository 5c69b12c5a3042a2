//! Rendering of the HAMR experiments' results ([`crate::experiments`]): each kind's tables,
//! CSV files and plots, one module per kind, and the runs of one file or a whole folder.
//!
//! Consumes: parsed experiment files. Produces: [`Outcome`]s, with the files they list
//! written under the output folder.

mod shared;

pub mod bode;
pub mod compare;
pub mod force;
pub mod locomotion;
pub mod sweep;
pub mod table_diagnosis;
pub mod tolerance;
pub mod trajectory;

use std::path::{Path, PathBuf};

use crate::experiments::{load, Error, Experiment, Kind};
use crate::output::file_stem;
use crate::parallel::{parallel, threads};
use crate::render::report::Outcome;
pub use shared::Progress;

/// Runs the experiment, writing its files under `out_dir` (named by `name`): the file's
/// notes first, then what the kind observes.
pub fn run(experiment: &Experiment, name: &str, out_dir: &Path) -> Result<Outcome, Error> {
    run_with_progress(experiment, name, out_dir, &|_, _| {})
}

/// [`run`], telling `progress` as the experiment's parts finish.
pub fn run_with_progress(
    experiment: &Experiment,
    name: &str,
    out_dir: &Path,
    progress: Progress<'_>,
) -> Result<Outcome, Error> {
    let mut outcome = match &experiment.kind {
        Kind::Trajectory(s) => trajectory::run(s, out_dir)?,
        Kind::ForceDeflection(s) => force::run(s, out_dir)?,
        Kind::RatioSweep(s) => sweep::run(s, out_dir)?,
        Kind::Compare(s) => compare::run(s, out_dir)?,
        Kind::Bode(s) => bode::run(s, out_dir)?,
        Kind::TableDiagnosis(s) => table_diagnosis::run(s, out_dir)?,
        Kind::Tolerance(s) => tolerance::run(s, out_dir)?,
        Kind::Locomotion(s) => locomotion::run(s, out_dir, progress)?,
    };
    let observed = std::mem::replace(&mut outcome.notes, experiment.notes.clone());
    outcome.notes.extend(observed);
    outcome.name = name.to_string();
    outcome.title = experiment.title.clone();
    Ok(outcome)
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
        .map(|(k, f)| Ok((k, file_stem(f, "experiment"), load(f)?)))
        .collect::<Result<_, Error>>()?;
    let mut jobs = experiments;
    jobs.sort_by(|a, b| b.2.cost().total_cmp(&a.2.cost()));
    let results = parallel(jobs, threads(), |(k, name, experiment)| {
        let result =
            run(&experiment, &name, &out_dir.join(&name)).map_err(|e| e.in_file(&files[k]));
        progress(&name);
        (k, result)
    });
    let mut results: Vec<(usize, Result<Outcome, Error>)> = results;
    results.sort_by_key(|(k, _)| *k);
    results.into_iter().map(|(_, r)| r).collect()
}

/// Runs one experiment file, its outputs in `out_dir/<stem>/`.
pub fn run_file(path: &Path, out_dir: &Path) -> Result<Outcome, Error> {
    run_file_with_progress(path, out_dir, &|_, _| {})
}

/// [`run_file`], telling `progress` as the experiment's parts finish.
pub fn run_file_with_progress(
    path: &Path,
    out_dir: &Path,
    progress: Progress<'_>,
) -> Result<Outcome, Error> {
    let experiment = load(path)?;
    let name = file_stem(path, "experiment");
    run_with_progress(&experiment, &name, &out_dir.join(&name), progress)
        .map_err(|e| e.in_file(path))
}
