//! What measured data came from, and the model's prediction of the same measurements.
//!
//! Consumes: a diagnosis experiment file (TOML, `docs/diagnose.md` §"Experiment files") and
//! the [`MeasuredData`] it describes. Produces: an [`Observations`] (the measured values in
//! one flat vector, with their noise σ and labels) and, for any parameter values of the
//! model, the predicted values in the same order ([`Experiment::predict`]) — the two sides of
//! every residual that `fit` and `diagnose` minimize.
//!
//! Kinds:
//! - `quasi_static`: each row holds the drive voltages (columns named as the model's inputs;
//!   a missing input column means 0 V) and measured outputs (columns named as the model's
//!   outputs, e.g. `foot.x`); the model's static equilibrium under each row's inputs
//!   (continuation from the previous row) predicts them. The paper's 1 Hz trajectories.
//! - `frequency_response`: columns `frequency [Hz]`, `gain [m/V]` (magnitude of output over
//!   input, any unit of that dimension) and `phase [deg]`; the model linearized about its rest
//!   equilibrium predicts them, with the flexure losses as complex stiffness (hysteretic,
//!   default) or viscous dampers. Gain residuals are taken on `ln |H|`, so σ is relative.
//! - `force_deflection`: columns `distance [um]` (the sensor's distance from the foot's rest
//!   position along the driven motion) and `force [mN]` (the on-axis force on the sensor);
//!   the leg driven at `voltage` on `dof` against a sensor at each distance predicts them,
//!   with the file's off-axis (y) load fraction (seed Sec. V-A, Fig. 6 a, b). A sensor that
//!   the free foot no longer reaches reads 0.
//! - `force_deflection_table`: the two numbers a paper's table gives for each force/deflection
//!   test (seed Table IV), one data row per `[[test]]`: `free_deflection [mm]` (the free
//!   foot's travel from rest along the test's axis) and `blocked_force [mN]` (the force with
//!   the sensor at the foot's rest position), each with its standard deviation
//!   (`free_deflection_sd`, `blocked_force_sd`, the σ of the fit); the same leg test predicts
//!   them, driven the way the test's `direction` says.
//! - `pendulum`: columns `time [s]` and the measured angle (`angle [deg]`): a ring-down of a
//!   model without HAMR ports (the flexure rig), simulated from rest at the release angle
//!   ([`super::pendulum`], which also screens the trace for what no parameter can fit).

use std::path::{Path, PathBuf};

use mech_codegen::ir::Dimension;
use mech_runtime::FlexureDamping;
use serde::Deserialize;

use super::data::MeasuredData;
use super::error::{Error, KeyError};
pub use super::observations::Observations;
use super::observations::{key_quantity, noise_value};
use super::pendulum::{self, Pendulum, Screening};
use crate::experiments::leg::{Dof, ForceTest, Leg, Sensor, WarmStarts};
use crate::frequency::{Channel, Damping};
use crate::session::ModelSpec;
use crate::toml_file;

/// One diagnosis experiment file: the keys every kind has (a title, the model), then the
/// kind's own keys.
#[derive(Debug, Clone, Deserialize)]
pub struct Experiment {
    pub title: String,
    #[serde(flatten)]
    pub model: ModelSpec,
    #[serde(flatten)]
    pub kind: Kind,
}

/// The diagnosis experiment kinds, by the file's `kind` key.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Kind {
    QuasiStatic(QuasiStatic),
    FrequencyResponse(FrequencyResponse),
    ForceDeflection(ForceDeflectionTest),
    ForceDeflectionTable(ForceDeflectionTable),
    Pendulum(Pendulum),
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceDeflectionTable {
    /// Drive voltage of every test, e.g. `"225 V"`.
    pub voltage: String,
    /// As [`ForceDeflectionTest::off_axis_fraction`], for every test's blocked force.
    #[serde(default)]
    pub off_axis_fraction: f64,
    /// The tests, one per data row, in order.
    pub test: Vec<TableTest>,
}

/// One test of a [`ForceDeflectionTable`].
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TableTest {
    pub dof: Dof,
    /// The way the foot moved along the test's axis, `"+z"`/`"-z"` (lift) or `"+x"`/`"-x"`
    /// (swing); omitted: the way the positive drive moves it.
    #[serde(default)]
    pub direction: Option<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceDeflectionTest {
    /// The driven degree of freedom: `lift` (force along z) or `swing` (along x).
    pub dof: Dof,
    /// Drive voltage of the model input, e.g. `"225 V"`.
    pub voltage: String,
    /// The sensor's y force on the foot as a fraction of the on-axis force (the paper's
    /// ~0.3), opposing the free foot's y motion; 0 by default.
    #[serde(default)]
    pub off_axis_fraction: f64,
    /// Measurement noise of the force (one standard deviation), e.g. `"0.5 mN"`.
    #[serde(default)]
    pub noise: Option<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QuasiStatic {
    /// The measured outputs (model output names = data column names).
    pub outputs: Vec<String>,
    /// Measurement noise (one standard deviation) of each output, e.g. `"5 um"`; omitted: the
    /// noise is estimated from the fit's residual.
    #[serde(default)]
    pub noise: Vec<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrequencyResponse {
    /// One transfer function: model input and output, e.g. `v_lift` → `foot.z` (data
    /// columns `gain`, `phase`). Or several as `[[channel]]` tables below.
    #[serde(default)]
    pub input: Option<String>,
    #[serde(default)]
    pub output: Option<String>,
    /// Several transfer functions measured at the same frequencies, each with a `name`: data
    /// columns `gain.NAME` and `phase.NAME`.
    #[serde(default)]
    pub channel: Vec<Channel>,
    /// `hysteretic` (complex stiffness k(1 + iη), default) or `viscous`.
    #[serde(default)]
    pub damping: Damping,
    /// Relative noise of the gain (e.g. `"5 %"`) and noise of the phase (e.g. `"3 deg"`).
    #[serde(default)]
    pub gain_noise: Option<String>,
    #[serde(default)]
    pub phase_noise: Option<String>,
}

impl FrequencyResponse {
    /// The channels with their data-column suffix (`""` for the single-channel form).
    fn channels(&self) -> Vec<(String, String, String)> {
        match (&self.input, &self.output) {
            (Some(i), Some(o)) => vec![(String::new(), i.clone(), o.clone())],
            _ => self
                .channel
                .iter()
                .map(|c| (format!(".{}", c.name), c.input.clone(), c.output.clone()))
                .collect(),
        }
    }
}

/// Model-form extensions that act in the prediction rather than through a model parameter.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Extensions {
    /// A frequency-dependent loss factor `η(f) = η·(f/f_ref)^exponent`, with `f_ref` the
    /// geometric mean of the measured frequencies (so `η` and the exponent are nearly
    /// uncorrelated). Frequency responses only; inert for static data.
    pub loss_exponent: Option<f64>,
    /// An off-axis (y) load at the foot, as a fraction of the on-axis sensor force, in place
    /// of the experiment file's (force/deflection only).
    pub off_axis_fraction: Option<f64>,
}

impl Extensions {
    /// The sensor's off-axis load fraction: the extension's, in place of the file's `written`.
    fn off_axis(&self, written: f64) -> f64 {
        self.off_axis_fraction.unwrap_or(written)
    }
}

/// Reads and checks a diagnosis experiment file.
pub fn load(path: &Path) -> Result<Experiment, Error> {
    let text = std::fs::read_to_string(path).map_err(|error| Error::ReadExperiment {
        path: path.to_path_buf(),
        error,
    })?;
    parse(path, &text)
}

/// Parses and checks a diagnosis experiment from TOML `text`; `path` only names the file in
/// messages (the model path in the text stays as written).
pub fn parse(path: &Path, text: &str) -> Result<Experiment, Error> {
    let path_buf = || path.to_path_buf();
    let hint = "docs/diagnose.md lists the keys of each kind";
    let experiment: Experiment =
        toml_file::parse(text, hint).map_err(|error| Error::ExperimentToml {
            path: path_buf(),
            error,
        })?;
    experiment.check().map_err(|error| Error::Experiment {
        path: path_buf(),
        error,
    })?;
    Ok(experiment)
}

impl Experiment {
    /// The screening of a pendulum experiment's trace (nothing for the other kinds): see
    /// [`pendulum`]. Errors only for unreadable data (missing column, bad unit, time not
    /// increasing), which the observations report too.
    pub fn screen(&self, data: &MeasuredData) -> Result<Option<Screening>, Error> {
        match &self.kind {
            Kind::Pendulum(e) => {
                let (times, angles) = e.trace(data)?;
                Ok(Some(pendulum::screen(times, angles)))
            }
            _ => Ok(None),
        }
    }

    /// The same experiment on another model file (`mech diagnose MODEL …`).
    pub fn set_model(&mut self, path: PathBuf) {
        self.model.path = path;
    }

    /// The keys that do not need the model or the data.
    fn check(&self) -> Result<(), KeyError> {
        match &self.kind {
            Kind::QuasiStatic(e) => {
                if e.outputs.is_empty() {
                    return Err(KeyError::NoOutputs);
                }
                if !e.noise.is_empty() && e.noise.len() != e.outputs.len() {
                    return Err(KeyError::NoiseCount {
                        values: e.noise.len(),
                        outputs: e.outputs.len(),
                    });
                }
                for text in &e.noise {
                    noise_value("noise", text, Dimension::LENGTH)?;
                }
            }
            Kind::FrequencyResponse(e) => {
                let single = e.input.is_some() || e.output.is_some();
                if single && (e.input.is_none() || e.output.is_none() || !e.channel.is_empty()) {
                    return Err(KeyError::ChannelForms);
                }
                if !single && e.channel.is_empty() {
                    return Err(KeyError::NoChannels);
                }
                if let Some(text) = &e.gain_noise {
                    noise_value("gain_noise", text, Dimension::NONE)?;
                }
                if let Some(text) = &e.phase_noise {
                    noise_value("phase_noise", text, Dimension::NONE)?;
                }
            }
            Kind::ForceDeflection(e) => {
                volts(&e.voltage)?;
                if let Some(text) = &e.noise {
                    noise_value("noise", text, Dimension::FORCE)?;
                }
                check_off_axis(e.off_axis_fraction)?;
            }
            Kind::ForceDeflectionTable(e) => {
                volts(&e.voltage)?;
                check_off_axis(e.off_axis_fraction)?;
                if e.test.is_empty() {
                    return Err(KeyError::NoTests);
                }
                e.directions()?;
            }
            Kind::Pendulum(e) => e.check()?,
        }
        Ok(())
    }

    /// The measured values this experiment compares, in the order of [`Experiment::predict`].
    /// Errors name the data file and the column.
    pub fn observations(&self, leg: &Leg, data: &MeasuredData) -> Result<Observations, Error> {
        match &self.kind {
            Kind::QuasiStatic(e) => e.observations(leg, data),
            Kind::FrequencyResponse(e) => e.observations(leg, data),
            Kind::ForceDeflection(e) => e.observations(leg, data),
            Kind::ForceDeflectionTable(e) => e.observations(leg, data),
            Kind::Pendulum(e) => e.observations(leg, data),
        }
    }

    /// The model's prediction of [`Experiment::observations`] with the leg's current
    /// parameter values. `data` supplies the drive (quasi-static) or the frequencies.
    pub fn predict(
        &self,
        leg: &Leg,
        data: &MeasuredData,
        measured: &Observations,
        extensions: &Extensions,
    ) -> Result<Vec<f64>, Error> {
        self.predict_warm(leg, data, measured, extensions, &mut WarmStarts::default())
    }

    /// [`Experiment::predict`] with its equilibria started from those of the last prediction
    /// `warm` recorded (a fit's previous evaluation), and recorded there in turn.
    pub fn predict_warm(
        &self,
        leg: &Leg,
        data: &MeasuredData,
        measured: &Observations,
        extensions: &Extensions,
        warm: &mut WarmStarts,
    ) -> Result<Vec<f64>, Error> {
        match &self.kind {
            Kind::QuasiStatic(e) => e.predict_warm(leg, data, warm),
            Kind::FrequencyResponse(e) => e.predict_warm(leg, data, measured, extensions, warm),
            Kind::ForceDeflection(e) => e.predict_warm(leg, measured, extensions, warm),
            Kind::ForceDeflectionTable(e) => e.predict_warm(leg, extensions, warm),
            // A frequency-dependent loss factor has no meaning at the one frequency of a
            // ring-down (the catalog leaves it out for every kind but frequency responses).
            Kind::Pendulum(e) => e.predict(leg, data),
        }
    }
}

impl QuasiStatic {
    /// The output columns, row by row, one series per output.
    fn observations(&self, leg: &Leg, data: &MeasuredData) -> Result<Observations, Error> {
        let model = leg.model();
        let mut obs = Observations::default();
        leg.require_hamr().map_err(Error::leg)?;
        let mut sigma = Vec::new();
        for (k, name) in self.outputs.iter().enumerate() {
            model
                .output_index(name)
                .ok_or_else(|| KeyError::UnknownOutput { name: name.clone() })?;
            let values = data.require(name, Dimension::LENGTH)?;
            let noise = self
                .noise
                .get(k)
                .map(|text| noise_value("noise", text, Dimension::LENGTH))
                .transpose()?;
            for (row, &v) in values.iter().enumerate() {
                obs.push(v, name, row as f64, row);
                sigma.push(noise.unwrap_or(f64::NAN));
            }
        }
        obs.sigma = (!self.noise.is_empty()).then_some(sigma);
        Ok(obs)
    }

    /// The outputs at the static equilibrium under each row's drive voltages.
    fn predict_warm(
        &self,
        leg: &Leg,
        data: &MeasuredData,
        warm: &mut WarmStarts,
    ) -> Result<Vec<f64>, Error> {
        let model = leg.model();
        leg.require_hamr().map_err(Error::leg)?;
        let rows = data.rows;
        let column = |name: &str| data.column(name);
        let v_lift = column(model.input_name(leg.v_lift()));
        let v_swing = column(model.input_name(leg.v_swing()));
        let outputs: Vec<usize> = self
            .outputs
            .iter()
            .map(|name| model.output_index(name).expect("checked by observations"))
            .collect();
        let mut per_output = vec![Vec::with_capacity(rows); outputs.len()];
        let mut q = leg.q0.clone();
        let mut y = vec![0.0; model.noutputs()];
        let u = vec![0.0; model.nu()];
        for row in 0..rows {
            let inputs = leg.inputs(
                v_lift.map_or(0.0, |c| c[row]),
                v_swing.map_or(0.0, |c| c[row]),
            );
            q = leg
                .warm_equilibrium(warm, row, &q, &inputs, &[], &[])
                .map_err(|error| Error::Equilibrium {
                    line: data.line(row),
                    error: Box::new(error),
                })?
                .q;
            model.outputs(0.0, &q, &u, &inputs, &mut y);
            for (series, &o) in per_output.iter_mut().zip(&outputs) {
                series.push(y[o]);
            }
        }
        Ok(per_output.concat())
    }
}

impl FrequencyResponse {
    /// Per channel, `ln|H|` then the phase at every frequency of the data.
    fn observations(&self, leg: &Leg, data: &MeasuredData) -> Result<Observations, Error> {
        let model = leg.model();
        let mut obs = Observations::default();
        leg.require_hamr().map_err(Error::leg)?;
        let frequency = data.require("frequency", Dimension::FREQUENCY)?;
        let gain_sigma = self
            .gain_noise
            .as_ref()
            .map(|t| noise_value("gain_noise", t, Dimension::NONE))
            .transpose()?;
        let phase_sigma = self
            .phase_noise
            .as_ref()
            .map(|t| noise_value("phase_noise", t, Dimension::NONE))
            .transpose()?;
        let mut sigma = Vec::new();
        for (suffix, input, output) in self.channels() {
            let unknown = |port: &'static str, name: &str| KeyError::UnknownChannelPort {
                channel: suffix.strip_prefix('.').map(str::to_string),
                port,
                name: name.to_string(),
            };
            model
                .input_index(&input)
                .ok_or_else(|| unknown("input", &input))?;
            model
                .output_index(&output)
                .ok_or_else(|| unknown("output", &output))?;
            let gain = data.require(&format!("gain{suffix}"), GAIN)?;
            let phase = data.require(&format!("phase{suffix}"), Dimension::NONE)?;
            if let Some(bad) = gain.iter().position(|&g| g <= 0.0) {
                return Err(Error::GainNotPositive {
                    path: data.path.clone(),
                    line: data.line(bad),
                });
            }
            for (row, (&f, &g)) in frequency.iter().zip(gain).enumerate() {
                obs.push(g.ln(), format!("ln|H|{suffix}"), f, row);
                // A relative gain noise σ_g is σ_g on ln|H| to first order.
                sigma.push(gain_sigma.unwrap_or(f64::NAN));
            }
            for (row, (&f, &p)) in frequency.iter().zip(phase).enumerate() {
                obs.push(p, format!("phase{suffix}"), f, row);
                sigma.push(phase_sigma.unwrap_or(f64::NAN));
            }
        }
        obs.sigma = (gain_sigma.is_some() && phase_sigma.is_some()).then_some(sigma);
        Ok(obs)
    }

    /// `ln|H|` and the phase (on the measured phase's branch) of the linear model at rest.
    fn predict_warm(
        &self,
        leg: &Leg,
        data: &MeasuredData,
        measured: &Observations,
        extensions: &Extensions,
        warm: &mut WarmStarts,
    ) -> Result<Vec<f64>, Error> {
        let model = leg.model();
        leg.require_hamr().map_err(Error::leg)?;
        let rest_inputs = leg.inputs(0.0, 0.0);
        let rest = leg.warm_rest(warm, 0, &rest_inputs).map_err(Error::leg)?.q;
        let linear = mech_runtime::linearize(model, 0.0, &rest, &rest_inputs, &leg.independent)
            .map_err(Error::Linearization)?;
        let rows = data.rows;
        let frequencies = &measured.abscissa[..rows];
        let damping = match (extensions.loss_exponent, self.damping) {
            (Some(exponent), _) => FlexureDamping::HystereticPowerLaw {
                exponent,
                reference_hz: geometric_mean(frequencies),
            },
            (None, damping) => damping.into(),
        };
        // Per channel: `rows` values of ln|H|, then `rows` phases (as observed).
        let mut predicted = Vec::with_capacity(measured.values.len());
        for (c, (_, input, output)) in self.channels().iter().enumerate() {
            let (input, output) = (
                model.input_index(input).expect("checked"),
                model.output_index(output).expect("checked"),
            );
            let offset = 2 * rows * c;
            let mut phase = Vec::with_capacity(rows);
            for (k, &f) in frequencies.iter().enumerate() {
                let omega = 2.0 * std::f64::consts::PI * f;
                let h = linear
                    .frequency_response(input, output, omega, damping)
                    .ok_or(Error::Singular { frequency: f })?;
                predicted.push(h.norm().ln());
                // The measured phase picks the branch: model phase within ±π of it.
                phase.push(wrap_near(h.arg(), measured.values[offset + rows + k]));
            }
            predicted.extend(phase);
        }
        Ok(predicted)
    }
}

impl ForceDeflectionTest {
    /// The sensor force at each measured distance.
    fn observations(&self, leg: &Leg, data: &MeasuredData) -> Result<Observations, Error> {
        let mut obs = Observations::default();
        leg.require_hamr().map_err(Error::leg)?;
        let distance = data.require("distance", Dimension::LENGTH)?;
        let force = data.require("force", Dimension::FORCE)?;
        if let Some(bad) = distance.iter().position(|&d| d < 0.0) {
            return Err(Error::NegativeDistance {
                path: data.path.clone(),
                line: data.line(bad),
            });
        }
        let noise = self
            .noise
            .as_ref()
            .map(|text| noise_value("noise", text, Dimension::FORCE))
            .transpose()?;
        for (row, (&d, &f)) in distance.iter().zip(force).enumerate() {
            obs.push(f, "force", d, row);
        }
        obs.sigma = noise.map(|sigma| vec![sigma; obs.values.len()]);
        Ok(obs)
    }

    /// The sensor force at the measured distances, warm-started along the sweep.
    fn predict_warm(
        &self,
        leg: &Leg,
        measured: &Observations,
        extensions: &Extensions,
        warm: &mut WarmStarts,
    ) -> Result<Vec<f64>, Error> {
        leg.require_hamr().map_err(Error::leg)?;
        let fraction = extensions.off_axis(self.off_axis_fraction);
        let distances = measured.abscissa.clone();
        let test = ForceTest::new(self.dof, volts(&self.voltage)?, Sensor::At(distances))
            .off_axis(fraction)
            .run_warm(leg, warm)
            .map_err(Error::leg)?;
        // A sensor beyond the free foot's reach is not touched: it reads 0.
        Ok(test.points.iter().map(|p| p.force.max(0.0)).collect())
    }
}

/// The sensor's y load fraction of a force/deflection test, within [-1, 1].
fn check_off_axis(fraction: f64) -> Result<(), KeyError> {
    if fraction.is_finite() && fraction.abs() <= 1.0 {
        Ok(())
    } else {
        Err(KeyError::OffAxisFraction { value: fraction })
    }
}

/// The key `voltage` of a force/deflection kind, in volts.
fn volts(text: &str) -> Result<f64, KeyError> {
    key_quantity("voltage", text, Dimension::VOLTAGE, |key, text| {
        KeyError::NotVoltage { key, text }
    })
}

impl ForceDeflectionTable {
    /// Each test's `direction` as ±1 (`None`: as the positive drive moves the foot).
    fn directions(&self) -> Result<Vec<Option<f64>>, KeyError> {
        self.test
            .iter()
            .enumerate()
            .map(|(k, test)| match &test.direction {
                None => Ok(None),
                Some(text) => {
                    test.dof
                        .direction(text)
                        .map(Some)
                        .ok_or_else(|| KeyError::TestDirection {
                            index: k + 1,
                            dof: test.dof.name(),
                            text: text.clone(),
                        })
                }
            })
            .collect()
    }

    /// Per test (data row), the free deflection, then per test the blocked force, each with
    /// the σ of its `_sd` column.
    fn observations(&self, leg: &Leg, data: &MeasuredData) -> Result<Observations, Error> {
        leg.require_hamr().map_err(Error::leg)?;
        if data.rows != self.test.len() {
            return Err(Error::TableRows {
                path: data.path.clone(),
                rows: data.rows,
                tests: self.test.len(),
            });
        }
        let mut obs = Observations::default();
        let mut sigma = Vec::new();
        for (column, dimension) in [
            ("free_deflection", Dimension::LENGTH),
            ("blocked_force", Dimension::FORCE),
        ] {
            let values = data.require(column, dimension)?;
            let sd_column = if column == "free_deflection" {
                "free_deflection_sd"
            } else {
                "blocked_force_sd"
            };
            let spreads = data.require(sd_column, dimension)?;
            for (row, (&value, &sd)) in values.iter().zip(spreads).enumerate() {
                if sd <= 0.0 {
                    return Err(Error::SpreadNotPositive {
                        path: data.path.clone(),
                        line: data.line(row),
                        column: sd_column,
                    });
                }
                obs.push(
                    value,
                    format!("{column}.{}", self.test[row].dof.name()),
                    row as f64,
                    row,
                );
                sigma.push(sd);
            }
        }
        obs.sigma = Some(sigma);
        Ok(obs)
    }

    /// Each test's free deflection, then each one's blocked force (with the off-axis load),
    /// the foot driven the way the test's direction says.
    fn predict_warm(
        &self,
        leg: &Leg,
        extensions: &Extensions,
        warm: &mut WarmStarts,
    ) -> Result<Vec<f64>, Error> {
        leg.require_hamr().map_err(Error::leg)?;
        let fraction = extensions.off_axis(self.off_axis_fraction);
        let voltage = volts(&self.voltage)?;
        let mut deflections = Vec::with_capacity(self.test.len());
        let mut forces = Vec::with_capacity(self.test.len());
        for ((k, test), direction) in self.test.iter().enumerate().zip(self.directions()?) {
            let result = ForceTest::new(test.dof, voltage, Sensor::Blocked)
                .off_axis(fraction)
                .run_toward(leg, direction, warm.part(k))
                .map_err(Error::leg)?;
            deflections.push(result.free_deflection);
            forces.push(result.blocked_force());
        }
        deflections.extend(forces);
        Ok(deflections)
    }
}

/// A gain of foot position per drive voltage, m/V = A·s³·kg⁻¹·m⁻¹.
const GAIN: Dimension = Dimension {
    mass: -1,
    length: -1,
    time: 3,
    current: 1,
};

fn geometric_mean(values: &[f64]) -> f64 {
    (values.iter().map(|v| v.ln()).sum::<f64>() / values.len().max(1) as f64).exp()
}

/// `angle + 2πk` closest to `reference`.
fn wrap_near(angle: f64, reference: f64) -> f64 {
    let two_pi = 2.0 * std::f64::consts::PI;
    angle + two_pi * ((reference - angle) / two_pi).round()
}
