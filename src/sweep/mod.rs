//! `mech sweep`: parameter grids and Monte-Carlo tolerance studies over one model or several
//! robots under the same parameter values (docs/sweep.md).
//!
//! Consumes: a study file (TOML: the model or `[[robot]]`s, `[[parameter]]`s with units and
//! a distribution or grid values, the seed, the sample count, the outputs). Produces: a
//! [`Table`] of samples × (parameter values, outputs), with every failed sample's error kept
//! beside it, and from a table its [`stats`] (summaries, Spearman sensitivity ranking). No
//! printing, no files: `cli/sweep.rs` renders and writes.
//!
//! A sample's values depend only on the seed and its index ([`sample`]), and each sample is
//! evaluated on a fresh copy of the compiled model, so a table is the same on any number of
//! threads, and a study split into index chunks (Python's Dask workers) gives the same rows.

pub mod error;
pub mod features;
pub mod sample;
pub mod stats;
pub mod study;

use std::path::Path;
use std::sync::{Mutex, MutexGuard};

use mech_codegen::ir::Dimension;

use crate::experiments::leg::{self, Leg};
use crate::parallel::parallel;
use crate::session::{ModelSpec, Session};
pub use error::{Error, SampleError};
use features::{Feature, Settings};
use sample::{Dist, Source};
use study::{line_of, ParameterFile, StudyFile, Value};

/// The most samples a study may have (a grid's product included): a table of this size
/// holds tens of megabytes, and its run takes hours even for the smallest models.
pub const MAX_SAMPLES: usize = 1_000_000;

/// Points of the frequency grid searched for resonances (refined between them).
const FREQUENCY_POINTS: usize = 200;

/// A study ready to run: its models compiled, its parameters checked against them.
pub struct Study {
    pub title: Option<String>,
    pub notes: Vec<String>,
    pub seed: u64,
    /// Samples: the file's `samples` (Monte-Carlo) or the grid's size.
    pub samples: usize,
    pub parameters: Vec<Parameter>,
    pub robots: Vec<Robot>,
    pub features: Vec<Feature>,
    pub settings: Settings,
}

/// One parameter: its name in the models, whether its values are factors of each model's
/// own value, and where they come from.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    pub name: String,
    pub relative: bool,
    pub source: Source,
    /// The unit of its column (SI, `""` for a factor or a plain number).
    pub unit: String,
}

/// A model of the study, compiled once; every sample copies it.
pub struct Robot {
    /// `None` for a study of one `model`.
    pub name: Option<String>,
    pub spec: ModelSpec,
    /// Behind a mutex: the tape's registers are not shared-safe; each sample takes a copy.
    session: Mutex<Session>,
    /// Per parameter of the study, its index in this model and its own value (SI).
    pub parameters: Vec<(usize, f64)>,
}

/// The samples run: one row per sample index.
#[derive(Debug)]
pub struct Table {
    pub parameters: Vec<String>,
    pub parameter_units: Vec<String>,
    /// Output columns: the feature's name, `ROBOT/feature` for a study of robots.
    pub outputs: Vec<String>,
    pub output_units: Vec<String>,
    pub rows: Vec<Row>,
}

/// One sample: its parameter values (NaN if they could not be drawn), its outputs (NaN where
/// a model failed) and the failures.
#[derive(Debug)]
pub struct Row {
    pub index: usize,
    pub parameters: Vec<f64>,
    pub outputs: Vec<f64>,
    pub failures: Vec<Failure>,
}

/// Why a sample has no outputs for a robot (or for any robot, when its values could not be
/// drawn).
#[derive(Debug)]
pub struct Failure {
    pub robot: Option<String>,
    pub error: SampleError,
}

/// Reads a study file and prepares it ([`prepare`]); errors name the file. Model paths are
/// relative to the current directory.
pub fn load(path: &Path) -> Result<Study, Error> {
    load_in(path, None)
}

/// [`load`] with relative model paths taken from `base` (a cluster's worker runs where the
/// client's current directory is not).
pub fn load_in(path: &Path, base: Option<&Path>) -> Result<Study, Error> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::Read {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    study::parse(&text)
        .map(|mut file| {
            if let Some(base) = base {
                file.model = file.model.map(|m| base.join(m));
                for robot in &mut file.robot {
                    robot.model.path = base.join(&robot.model.path);
                }
            }
            file
        })
        .and_then(|file| prepare(&file, &text))
        .map_err(|e| e.in_file(path))
}

/// Checks a parsed study against its models (names, units, distributions, outputs) and
/// compiles them. `text` is the file's text, for the lines of errors.
pub fn prepare(file: &StudyFile, text: &str) -> Result<Study, Error> {
    let robots = open_robots(file)?;
    let features = parse_features(file, text)?;
    let hamr = features.iter().any(|f| f.is_hamr());
    for robot in &robots {
        let leg = Leg::from_session(robot.session().clone(), &robot.spec, &[])
            .map_err(|e| Error::Model(Box::new(e)))?;
        if hamr {
            leg.require_hamr()
                .map_err(|e| Error::Model(Box::new(e)).within(robot.name.as_deref()))?;
        }
    }
    let settings = settings(file, text, &features)?;
    let mut parameters = Vec::new();
    let mut robots = robots;
    let mut sources: Vec<Source> = Vec::new();
    for (k, p) in file.parameter.iter().enumerate() {
        if let Some(first) = parameters
            .iter()
            .position(|q: &Parameter| q.name == *p.name.get_ref())
        {
            return Err(Error::key(
                &format!("parameter[{}].name", k + 1),
                line_of(text, p.name.span().start),
                format!(
                    "`{}` is already parameter[{}]; give each parameter once",
                    p.name.get_ref(),
                    first + 1
                ),
            ));
        }
        let parameter = parameter(k, p, text, &mut robots)?;
        sources.push(parameter.source.clone());
        parameters.push(parameter);
        // Checked as the grid grows, so that no more than the cap's values are ever held.
        if sample::grid_size(&sources).is_none_or(|n| n > MAX_SAMPLES) {
            return Err(Error::TooManySamples {
                key: format!("parameter[{}]", k + 1),
                line: Some(line_of(text, p.name.span().start)),
                max: MAX_SAMPLES,
            });
        }
    }
    let samples = sample_count(file, text, &sources)?;
    Ok(Study {
        title: file.title.clone(),
        notes: file.notes.clone(),
        seed: file.seed,
        samples,
        parameters,
        robots,
        features,
        settings,
    })
}

/// The study's models, each compiled with its `set` values.
fn open_robots(file: &StudyFile) -> Result<Vec<Robot>, Error> {
    let specs: Vec<(Option<String>, ModelSpec)> = match (&file.model, file.robot.is_empty()) {
        (Some(path), true) => vec![(
            None,
            ModelSpec {
                path: path.clone(),
                set: file.set.clone(),
                independent: file.independent.clone(),
            },
        )],
        (None, false) => file
            .robot
            .iter()
            .map(|r| (Some(r.name.clone()), r.model.clone()))
            .collect(),
        _ => return Err(Error::ModelOrRobots),
    };
    specs
        .into_iter()
        .map(|(name, spec)| {
            let session = Session::open(&spec.path, &spec.set, &[]).map_err(|error| {
                Error::Model(Box::new(leg::Error::Model {
                    model: spec.path.clone(),
                    error: Box::new(error),
                }))
                .within(name.as_deref())
            })?;
            Ok(Robot {
                name,
                spec,
                session: Mutex::new(session),
                parameters: Vec::new(),
            })
        })
        .collect()
}

fn parse_features(file: &StudyFile, text: &str) -> Result<Vec<Feature>, Error> {
    let line = line_of(text, file.outputs.span().start);
    if file.outputs.get_ref().is_empty() {
        return Err(Error::key("outputs", line, "give at least one output"));
    }
    file.outputs
        .get_ref()
        .iter()
        .map(|name| {
            Feature::parse(name).ok_or_else(|| {
                Error::key(
                    "outputs",
                    line,
                    format!(
                        "unknown output `{name}`; the outputs are {}",
                        features::NAMES
                    ),
                )
            })
        })
        .collect()
}

/// The voltage and frequency range, required by the outputs that use them.
fn settings(file: &StudyFile, text: &str, features: &[Feature]) -> Result<Settings, Error> {
    let mut settings = Settings::default();
    let needs = |f: fn(&Feature) -> bool| features.iter().find(|x| f(x)).map(|x| x.name());
    use Feature::*;
    match (
        &file.voltage,
        needs(|f| matches!(f, FreeStroke(_) | BlockedForce(_) | Work(_))),
    ) {
        (Some(v), _) => {
            let line = line_of(text, v.span().start);
            settings.voltage = Some(
                crate::quantity::positive("voltage", v.get_ref(), Dimension::VOLTAGE)
                    .map_err(|error| Error::Quantity { line, error })?,
            );
        }
        (None, Some(output)) => {
            return Err(Error::Missing {
                key: "voltage",
                output,
            })
        }
        (None, None) => {}
    }
    match (
        &file.frequencies,
        needs(|f| matches!(f, Resonance(_) | QualityFactor(_))),
    ) {
        (Some(range), _) => {
            let line = line_of(text, range.span().start);
            let [from, to] = range.get_ref().as_slice() else {
                return Err(Error::key(
                    "frequencies",
                    line,
                    "expected two frequencies, e.g. [\"10 Hz\", \"300 Hz\"]",
                ));
            };
            let hz = |t: &str| crate::quantity::positive("frequencies", t, Dimension::FREQUENCY);
            let (from, to) = (hz(from), hz(to));
            let (from, to) = (from, to);
            let (from, to) = match (from, to) {
                (Ok(a), Ok(b)) if a < b => (a, b),
                (Ok(_), Ok(_)) => {
                    return Err(Error::key(
                        "frequencies",
                        line,
                        "the first must be the lower",
                    ))
                }
                (Err(error), _) | (_, Err(error)) => return Err(Error::Quantity { line, error }),
            };
            settings.frequencies = Some(crate::frequency::log_space(from, to, FREQUENCY_POINTS));
        }
        (None, Some(output)) => {
            return Err(Error::Missing {
                key: "frequencies",
                output,
            })
        }
        (None, None) => {}
    }
    Ok(settings)
}

/// `[[parameter]]` number `k`, checked against every robot (which records the parameter's
/// index and own value).
fn parameter(
    k: usize,
    p: &ParameterFile,
    text: &str,
    robots: &mut [Robot],
) -> Result<Parameter, Error> {
    let name = p.name.get_ref().clone();
    let key = |field: &str| format!("parameter[{}].{field}", k + 1);
    let mut dimension = None;
    for robot in robots.iter_mut() {
        let session = robot.session().clone();
        let model = &session.model;
        let index = mech_runtime::Model::param_index(model, &name).ok_or_else(|| {
            let error = leg::Error::NoParameter {
                model: robot.spec.path.display().to_string(),
                name: name.clone(),
                purpose: None,
            };
            Error::Key {
                key: key("name"),
                line: line_of(text, p.name.span().start),
                message: error.to_string(),
            }
        })?;
        let own = session.compiled.model.params.iter().nth(index);
        let found = own.map(|(_, p)| p.dimension).unwrap_or_default();
        if dimension.is_some_and(|d| d != found) {
            return Err(Error::key(
                &key("name"),
                line_of(text, p.name.span().start),
                "the models give this parameter different units",
            ));
        }
        dimension = Some(found);
        let value = mech_runtime::Model::param(model, index);
        robot.parameters.push((index, value));
    }
    let dimension = match p.relative {
        true => Dimension::NONE,
        false => dimension.unwrap_or_default(),
    };
    let read = |field: &str, value: &toml::Spanned<Value>| {
        error::quantity(
            &key(field),
            line_of(text, value.span().start),
            &value.get_ref().text(),
            dimension,
            &name,
        )
    };
    let source = source(k, p, text, &read)?;
    Ok(Parameter {
        name,
        relative: p.relative,
        source,
        unit: match (p.relative, dimension == Dimension::NONE) {
            (true, _) | (_, true) => String::new(),
            _ => dimension.to_string(),
        },
    })
}

/// Reads a parameter's value at a key (`mean`, `values`, …) in SI or as a factor.
type ValueReader<'a> = &'a dyn Fn(&str, &toml::Spanned<Value>) -> Result<f64, Error>;

/// Where `[[parameter]]` `k`'s values come from: its distribution's keys, or its grid.
fn source(k: usize, p: &ParameterFile, text: &str, read: ValueReader<'_>) -> Result<Source, Error> {
    let key = |field: &str| format!("parameter[{}].{field}", k + 1);
    let line = line_of(text, p.name.span().start);
    let given = |field: &'static str, v: &Option<toml::Spanned<Value>>| {
        v.as_ref()
            .ok_or_else(|| Error::key(&key(field), line, "missing for this distribution"))
            .and_then(|v| read(field, v))
    };
    match (&p.distribution, &p.values, &p.range) {
        (Some(d), None, None) => {
            let dline = line_of(text, d.span().start);
            let dist = match d.get_ref().as_str() {
                "normal" => Dist::Normal {
                    mean: given("mean", &p.mean)?,
                    sd: error::spread(&key("sd"), line, given("sd", &p.sd)?)?,
                },
                "uniform" => {
                    let (low, high) = (given("low", &p.low)?, given("high", &p.high)?);
                    error::ordered(&key("high"), line, low, high)?;
                    Dist::Uniform { low, high }
                }
                "truncated_normal" => {
                    let (low, high) = (given("low", &p.low)?, given("high", &p.high)?);
                    error::ordered(&key("high"), line, low, high)?;
                    Dist::TruncatedNormal {
                        mean: given("mean", &p.mean)?,
                        sd: error::spread(&key("sd"), line, given("sd", &p.sd)?)?,
                        low,
                        high,
                    }
                }
                other => {
                    return Err(Error::key(
                        &key("distribution"),
                        dline,
                        format!(
                            "unknown distribution `{other}`; expected normal, uniform or \
                             truncated_normal"
                        ),
                    ))
                }
            };
            Ok(Source::Draw(dist))
        }
        (None, Some(values), None) => {
            let vline = line_of(text, values.span().start);
            if values.get_ref().is_empty() {
                return Err(Error::key(&key("values"), vline, "give at least one value"));
            }
            let spanned = |v: &Value| toml::Spanned::new(values.span(), v.clone());
            let points = values.get_ref().iter().map(|v| read("values", &spanned(v)));
            Ok(Source::Grid(points.collect::<Result<_, _>>()?))
        }
        (None, None, Some(range)) => {
            let rline = line_of(text, range.span().start);
            let (low, high, n) = parse_range(&key("range"), rline, range.get_ref())?;
            let value = |t: &str| {
                read(
                    "range",
                    &toml::Spanned::new(range.span(), Value::Text(t.into())),
                )
            };
            let (low, high) = (value(&low)?, value(&high)?);
            let points = (0..n)
                .map(|i| match n {
                    1 => low,
                    _ => low + (high - low) * i as f64 / (n - 1) as f64,
                })
                .collect();
            Ok(Source::Grid(points))
        }
        _ => Err(Error::key(
            &key("name"),
            line,
            "give exactly one of `distribution` (Monte-Carlo), `values` or `range` (a grid)",
        )),
    }
}

/// `"LOW .. HIGH : N"`: the two ends' text and the count (1 to the sample cap).
fn parse_range(key: &str, line: usize, text: &str) -> Result<(String, String, usize), Error> {
    let bad = || {
        Error::key(
            key,
            line,
            format!("`{text}`: expected `LOW .. HIGH : N`, e.g. `\"0.5 mm .. 0.7 mm : 5\"`"),
        )
    };
    let (low, rest) = text.split_once("..").ok_or_else(bad)?;
    let (high, count) = rest.rsplit_once(':').ok_or_else(bad)?;
    let count: usize = count.trim().parse().map_err(|_| bad())?;
    if !(1..=MAX_SAMPLES).contains(&count) {
        return Err(bad());
    }
    Ok((low.trim().to_string(), high.trim().to_string(), count))
}

/// The number of samples: the grid's size, or `samples` for a Monte-Carlo study; capped.
fn sample_count(file: &StudyFile, text: &str, sources: &[Source]) -> Result<usize, Error> {
    let draws = sources.iter().any(|s| matches!(s, Source::Draw(_)));
    let grid = sources.iter().any(|s| matches!(s, Source::Grid(_)));
    let line = |s: &toml::Spanned<i64>| line_of(text, s.span().start);
    match (&file.samples, draws, grid) {
        (_, true, true) => Err(Error::key(
            "parameter",
            line_of(text, file.outputs.span().start),
            "a study is a grid (every parameter `values` or `range`) or Monte-Carlo (every \
             parameter a `distribution`), not both",
        )),
        (Some(s), false, true) => Err(Error::key(
            "samples",
            line(s),
            "a grid has as many samples as points; remove `samples`",
        )),
        // Within the cap: checked as the parameters were read.
        (_, false, _) => Ok(sample::grid_size(sources).unwrap_or(MAX_SAMPLES)),
        (None, true, false) => Err(Error::key(
            "samples",
            1,
            "a Monte-Carlo study needs `samples` (how many draws)",
        )),
        (Some(s), true, false) => check_count("samples", Some(line(s)), *s.get_ref()),
    }
}

/// A sample count given by `key` (a study's `samples`, `--samples`), between 1 and
/// [`MAX_SAMPLES`].
pub fn check_count(key: &str, line: Option<usize>, count: i64) -> Result<usize, Error> {
    match usize::try_from(count) {
        Ok(n) if (1..=MAX_SAMPLES).contains(&n) => Ok(n),
        Ok(0) | Err(_) => Err(Error::Key {
            key: key.into(),
            line: line.unwrap_or(0),
            message: format!("expected at least one sample, got {count}"),
        }),
        Ok(_) => Err(Error::TooManySamples {
            key: key.into(),
            line,
            max: MAX_SAMPLES,
        }),
    }
}

impl Study {
    /// The study with `samples` Monte-Carlo samples in place of the file's (refused for a
    /// grid, whose size is its points').
    pub fn with_samples(mut self, samples: usize) -> Result<Study, Error> {
        if self
            .parameters
            .iter()
            .any(|p| matches!(p.source, Source::Grid(_)))
        {
            return Err(Error::GridSamples);
        }
        self.samples = check_count("--samples", None, samples as i64)?;
        Ok(self)
    }

    /// The output columns' names and units.
    pub fn output_columns(&self) -> (Vec<String>, Vec<String>) {
        let mut names = Vec::new();
        let mut units = Vec::new();
        for robot in &self.robots {
            for feature in &self.features {
                names.push(match &robot.name {
                    Some(name) => format!("{name}/{}", feature.name()),
                    None => feature.name(),
                });
                units.push(feature.unit().to_string());
            }
        }
        (names, units)
    }

    /// Sample `index`: its parameter values and every robot's outputs.
    pub fn sample(&self, index: usize) -> Row {
        let names: Vec<String> = self.parameters.iter().map(|p| p.name.clone()).collect();
        let sources: Vec<Source> = self.parameters.iter().map(|p| p.source.clone()).collect();
        let outputs = self.robots.len() * self.features.len();
        let mut row = Row {
            index,
            parameters: vec![f64::NAN; names.len()],
            outputs: vec![f64::NAN; outputs],
            failures: Vec::new(),
        };
        match sample::values(&names, &sources, self.seed, index) {
            Ok(values) => row.parameters = values,
            Err(error) => {
                row.failures.push(Failure {
                    robot: None,
                    error: SampleError::Draw(error),
                });
                return row;
            }
        }
        for (r, robot) in self.robots.iter().enumerate() {
            let n = self.features.len();
            match self.evaluate(robot, &row.parameters) {
                Ok(values) => row.outputs[r * n..(r + 1) * n].copy_from_slice(&values),
                Err(error) => row.failures.push(Failure {
                    robot: robot.name.clone(),
                    error,
                }),
            }
        }
        row
    }

    /// `robot`'s outputs with the study's parameters at `values`.
    fn evaluate(&self, robot: &Robot, values: &[f64]) -> Result<Vec<f64>, SampleError> {
        let mut session = robot.session().clone();
        for ((parameter, &(index, own)), &value) in
            self.parameters.iter().zip(&robot.parameters).zip(values)
        {
            let si = if parameter.relative {
                own * value
            } else {
                value
            };
            session
                .set_si(index, si)
                .map_err(|e| SampleError::Setting(Box::new(e)))?;
        }
        let leg = Leg::from_session(session, &robot.spec, &[])?;
        features::evaluate(&leg, &self.features, &self.settings)
    }

    /// Runs the samples `indices` on `threads` threads (each index below `samples`);
    /// `progress` is called after each sample. Rows in the order of `indices`.
    pub fn run(
        &self,
        indices: &[usize],
        threads: usize,
        progress: &(dyn Fn() + Sync),
    ) -> Result<Table, Error> {
        if let Some(&index) = indices.iter().find(|&&i| i >= self.samples) {
            return Err(Error::IndexOutOfRange {
                index,
                samples: self.samples,
            });
        }
        let rows = parallel(indices.to_vec(), threads, |index| {
            let row = self.sample(index);
            progress();
            row
        });
        let (outputs, output_units) = self.output_columns();
        Ok(Table {
            parameters: self.parameters.iter().map(|p| p.name.clone()).collect(),
            parameter_units: self.parameters.iter().map(|p| p.unit.clone()).collect(),
            outputs,
            output_units,
            rows,
        })
    }

    /// Every sample, `0..samples`.
    pub fn run_all(&self, threads: usize, progress: &(dyn Fn() + Sync)) -> Result<Table, Error> {
        let indices: Vec<usize> = (0..self.samples).collect();
        self.run(&indices, threads, progress)
    }
}

impl Robot {
    /// The compiled model, locked (a panic elsewhere leaves it usable: samples only copy it).
    pub fn session(&self) -> MutexGuard<'_, Session> {
        self.session
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

impl Table {
    /// Parameter column `k` over the rows.
    pub fn parameter_column(&self, k: usize) -> Vec<f64> {
        self.rows.iter().map(|r| r.parameters[k]).collect()
    }

    /// Output column `k` over the rows.
    pub fn output_column(&self, k: usize) -> Vec<f64> {
        self.rows.iter().map(|r| r.outputs[k]).collect()
    }

    /// Samples with at least one failure.
    pub fn failed(&self) -> usize {
        self.rows.iter().filter(|r| !r.failures.is_empty()).count()
    }

    /// Per output, its summary over the samples where it was computed.
    pub fn summaries(&self) -> Vec<stats::Summary> {
        (0..self.outputs.len())
            .map(|k| stats::summary(&self.output_column(k)))
            .collect()
    }

    /// Per output, every parameter by |Spearman ρ|, largest first.
    pub fn ranking(&self) -> Vec<Vec<stats::Correlation>> {
        let parameters: Vec<Vec<f64>> = (0..self.parameters.len())
            .map(|k| self.parameter_column(k))
            .collect();
        let outputs: Vec<Vec<f64>> = (0..self.outputs.len())
            .map(|k| self.output_column(k))
            .collect();
        stats::ranking(&parameters, &outputs)
    }
}
