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
pub mod force;
pub mod leg;
pub mod sweep;
pub mod trajectory;

use std::path::{Path, PathBuf};

use mech_codegen::ir::Dimension;
use serde::Deserialize;

pub use crate::render::report::Outcome;
pub use crate::render::table::Table;

/// One experiment file.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Experiment {
    Trajectory(trajectory::Spec),
    ForceDeflection(force::Spec),
    RatioSweep(sweep::Spec),
    Compare(compare::Spec),
    Bode(bode::Spec),
}

/// The model every experiment (or each of its series) runs on.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSpec {
    /// Path of the `.mech` file, relative to the current directory (or absolute).
    pub model: PathBuf,
    /// Parameter settings, `NAME=VALUE` as for `--set`.
    #[serde(default)]
    pub set: Vec<String>,
    /// Coordinates held independent when closing the loops (the actuators).
    #[serde(default = "default_independent")]
    pub independent: Vec<String>,
}

pub(crate) fn default_independent() -> Vec<String> {
    vec!["qsact".into(), "qlact".into()]
}

/// Reads and checks an experiment file. Errors name the file and the key.
pub fn load(path: &Path) -> Result<Experiment, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read experiment `{}`: {e}", path.display()))?;
    parse(&text).map_err(|e| format!("experiment `{}`: {e}", path.display()))
}

/// Parses an experiment from TOML text.
pub fn parse(text: &str) -> Result<Experiment, String> {
    let experiment: Experiment = toml::from_str(text).map_err(|e| {
        let message = e.to_string();
        if message.contains("missing field `kind`") {
            "missing key `kind`: expected one of \"trajectory\", \"force_deflection\", \
             \"ratio_sweep\", \"compare\", \"bode\""
                .to_string()
        } else {
            message.trim_end().to_string()
        }
    })?;
    experiment.check()?;
    Ok(experiment)
}

impl Experiment {
    pub fn title(&self) -> &str {
        match self {
            Experiment::Trajectory(s) => &s.title,
            Experiment::ForceDeflection(s) => &s.title,
            Experiment::RatioSweep(s) => &s.title,
            Experiment::Compare(s) => &s.title,
            Experiment::Bode(s) => &s.title,
        }
    }

    /// Checks the quantities (units, signs) before anything runs.
    fn check(&self) -> Result<(), String> {
        match self {
            Experiment::Trajectory(s) => s.check(),
            Experiment::ForceDeflection(s) => s.check(),
            Experiment::RatioSweep(s) => s.check(),
            Experiment::Compare(s) => s.check(),
            Experiment::Bode(s) => s.check(),
        }
    }

    /// A rough relative cost, to start the slow experiments first.
    pub fn cost(&self) -> f64 {
        match self {
            Experiment::Bode(s) => 1.0 + s.chirp.as_ref().map_or(0.0, |c| c.cost()),
            Experiment::RatioSweep(_) => 4.0,
            _ => 1.0,
        }
    }

    /// Runs the experiment, writing its files under `out_dir` (named by `name`).
    pub fn run(&self, name: &str, out_dir: &Path) -> Result<Outcome, String> {
        let mut outcome = match self {
            Experiment::Trajectory(s) => trajectory::run(s, out_dir)?,
            Experiment::ForceDeflection(s) => force::run(s, out_dir)?,
            Experiment::RatioSweep(s) => sweep::run(s, out_dir)?,
            Experiment::Compare(s) => compare::run(s, out_dir)?,
            Experiment::Bode(s) => bode::run(s, out_dir)?,
        };
        outcome.name = name.to_string();
        outcome.title = self.title().to_string();
        Ok(outcome)
    }
}

/// The experiment files of a folder, sorted by name.
pub fn experiment_files(folder: &Path) -> Result<Vec<PathBuf>, String> {
    let entries = std::fs::read_dir(folder).map_err(|e| {
        format!(
            "cannot read the experiments folder `{}`: {e}",
            folder.display()
        )
    })?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(format!(
            "no `*.toml` experiment files in `{}`",
            folder.display()
        ));
    }
    Ok(files)
}

/// Runs every file (parsed first, so a bad file fails before anything runs), the costly
/// ones first, on all cores; `progress` is called after each one finishes.
pub fn run_all(
    files: &[PathBuf],
    out_dir: &Path,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<Outcome>, String> {
    let experiments: Vec<(usize, String, Experiment)> = files
        .iter()
        .enumerate()
        .map(|(k, f)| Ok((k, stem(f), load(f)?)))
        .collect::<Result<_, String>>()?;
    let mut jobs = experiments;
    jobs.sort_by(|a, b| b.2.cost().total_cmp(&a.2.cost()));
    let results = parallel(jobs, threads(), |(k, name, experiment)| {
        let result = experiment
            .run(&name, &out_dir.join(&name))
            .map_err(|e| format!("experiment `{}`: {e}", files[k].display()));
        progress(&name);
        (k, result)
    });
    let mut results: Vec<(usize, Result<Outcome, String>)> = results;
    results.sort_by_key(|(k, _)| *k);
    results.into_iter().map(|(_, r)| r).collect()
}

/// Runs one experiment file, its outputs in `out_dir/<stem>/`.
pub fn run_file(path: &Path, out_dir: &Path) -> Result<Outcome, String> {
    let experiment = load(path)?;
    let name = stem(path);
    experiment
        .run(&name, &out_dir.join(&name))
        .map_err(|e| format!("experiment `{}`: {e}", path.display()))
}

pub(crate) fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "experiment".into())
}

// ------------------------------------------------------------------ quantities

/// V = kg·m²·s⁻³·A⁻¹.
pub const VOLTAGE: Dimension = Dimension {
    mass: 1,
    length: 2,
    time: -3,
    current: -1,
};
/// Hz = s⁻¹.
pub const FREQUENCY: Dimension = Dimension {
    mass: 0,
    length: 0,
    time: -1,
    current: 0,
};
/// J = kg·m²·s⁻².
pub const ENERGY: Dimension = Dimension::TORQUE;

fn dimension_name(d: Dimension) -> &'static str {
    match d {
        VOLTAGE => "a voltage (e.g. `225 V`)",
        FREQUENCY => "a frequency (e.g. `1 Hz`)",
        Dimension::LENGTH => "a length (e.g. `127 um`)",
        Dimension::FORCE => "a force (e.g. `17.7 mN`)",
        Dimension::TORQUE => "an energy (e.g. `38.9 uJ`)",
        Dimension::TIME => "a time (e.g. `2 s`)",
        _ => "a quantity with a unit",
    }
}

/// Parses `text` (e.g. `"225 V"`) as a quantity of dimension `expected`, in SI. `key` names
/// the TOML key in errors.
pub fn quantity(key: &str, text: &str, expected: Dimension) -> Result<f64, String> {
    let (value, dimension) = mech_codegen::front::units::parse_quantity(text)
        .map_err(|e| format!("key `{key}`: `{text}`: {e}"))?;
    if dimension != expected || !value.is_finite() {
        return Err(format!(
            "key `{key}`: expected {}, got `{text}`",
            dimension_name(expected)
        ));
    }
    Ok(value)
}

/// As [`quantity`], and positive.
pub fn positive(key: &str, text: &str, expected: Dimension) -> Result<f64, String> {
    let value = quantity(key, text, expected)?;
    if value <= 0.0 {
        return Err(format!(
            "key `{key}`: expected a positive value, got `{text}`"
        ));
    }
    Ok(value)
}

/// A paper value with its uncertainty: `"2.2 mm"` or `"2.2 +- 0.1 mm"`.
pub fn paper_value(key: &str, text: &str, expected: Dimension) -> Result<(f64, f64), String> {
    match text.split_once("+-") {
        Some((mean, rest)) => {
            // `2.2 +- 0.1 mm`: the unit follows the spread.
            let rest = rest.trim();
            let split = rest
                .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == '-'))
                .unwrap_or(rest.len());
            let (spread, unit) = rest.split_at(split);
            let mean = quantity(key, &format!("{} {unit}", mean.trim()), expected)?;
            let spread = if unit.trim().is_empty() && expected == Dimension::NONE {
                spread
                    .trim()
                    .parse::<f64>()
                    .map_err(|e| format!("key `{key}`: {e}"))?
            } else {
                quantity(key, &format!("{spread} {unit}"), expected)?
            };
            Ok((mean, spread))
        }
        None => Ok((quantity(key, text, expected)?, 0.0)),
    }
}

// ------------------------------------------------------------------ plumbing

/// Writes a CSV under `dir` and records it.
pub(crate) fn csv(
    outcome: &mut Outcome,
    dir: &Path,
    file: &str,
    header: &[&str],
    rows: &[Vec<f64>],
) -> Result<(), String> {
    let path = dir.join(file);
    let header: Vec<String> = header.iter().map(|s| s.to_string()).collect();
    crate::output::write_csv(&path, &header, rows)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
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

/// Runs `jobs` on up to `threads` threads, results in order.
pub(crate) fn parallel<T: Send, R: Send>(
    jobs: Vec<T>,
    threads: usize,
    work: impl Fn(T) -> R + Sync,
) -> Vec<R> {
    use std::sync::Mutex;
    let n = jobs.len();
    // Reversed, so that `pop` hands out the jobs in the given order.
    let queue = Mutex::new(jobs.into_iter().enumerate().rev().collect::<Vec<_>>());
    let results = Mutex::new((0..n).map(|_| None).collect::<Vec<Option<R>>>());
    let threads = threads.clamp(1, n.max(1));
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let job = queue.lock().map(|mut q| q.pop()).unwrap_or(None);
                let Some((index, job)) = job else { break };
                let result = work(job);
                if let Ok(mut slots) = results.lock() {
                    slots[index] = Some(result);
                }
            });
        }
    });
    results
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .map(|r| r.expect("every job ran"))
        .collect()
}

/// Threads to use: the machine's parallelism.
pub(crate) fn threads() -> usize {
    std::thread::available_parallelism().map_or(2, |n| n.get())
}
