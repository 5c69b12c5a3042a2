//! Experiment 5, dynamic regime (seed Sec. VI, Fig. 10): frequency responses from drive
//! voltage to foot displacement, lift and swing, from the linearized model (hysteretic and
//! viscous flexure losses) and from a simulated linear chirp; resonances and quality factors.
//!
//! Consumes: a [`Spec`] (model, sweep, channels, optional chirp). Produces:
//! [`Responses`]: every channel's response from each source, the modes and resonances.
//! Every source's resonances are refined on its continuous response (the linear model's
//! `|H|`, the chirp record's `|Y/U|`), so they do not depend on `points`.

use mech_codegen::ir::Dimension;
use serde::Deserialize;

use super::leg::{self, Leg};
use super::Error;
use crate::frequency::{self, Channel, ChirpSweep, Point, Resonance};
use crate::parallel::{parallel, threads};
use crate::quantity::{positive, quantity};
use crate::session::ModelSpec;
use mech_runtime::Mode;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    #[serde(flatten)]
    pub model: ModelSpec,
    /// Lowest and highest frequency (`1 Hz`, `150 Hz`).
    pub from: String,
    pub to: String,
    /// Log-spaced frequencies of the linear response.
    #[serde(default = "default_points")]
    pub points: usize,
    /// Input → output pairs, e.g. `{ name = "lift", input = "v_lift", output = "foot.z" }`.
    pub channel: Vec<Channel>,
    /// A simulated linear chirp (time domain, viscous flexure dampers), if given.
    pub chirp: Option<Chirp>,
}

fn default_points() -> usize {
    300
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Chirp {
    /// Amplitude in the input's unit (`50 V`; the paper uses 50–60 V).
    pub amplitude: String,
    /// Length of the sweep (`2 s`).
    pub duration: String,
    /// Lowest frequency of the chirp estimate shown and searched for resonances (default
    /// `5 Hz`): near the sweep's start the record holds too few cycles.
    pub analysis_from: Option<String>,
}

impl Chirp {
    /// Amplitude (V), duration (s) and the lowest frequency analysed (Hz, default 5 Hz).
    fn settings(&self) -> Result<(f64, f64, f64), Error> {
        Ok((
            positive("chirp.amplitude", &self.amplitude, Dimension::VOLTAGE)?,
            positive("chirp.duration", &self.duration, Dimension::TIME)?,
            match &self.analysis_from {
                Some(t) => positive("chirp.analysis_from", t, Dimension::FREQUENCY)?,
                None => 5.0,
            },
        ))
    }

    pub fn cost(&self) -> f64 {
        quantity("chirp.duration", &self.duration, Dimension::TIME).unwrap_or(1.0) * 5.0
    }
}

impl Spec {
    pub fn check(&self) -> Result<(), Error> {
        let from = positive("from", &self.from, Dimension::FREQUENCY)?;
        let to = positive("to", &self.to, Dimension::FREQUENCY)?;
        if to <= from {
            return Err(Error::Key {
                message: format!("key `to`: {to} Hz must be above `from` ({from} Hz)"),
            });
        }
        if self.channel.is_empty() {
            return Err(Error::Key {
                message: "key `channel`: give at least one [[channel]] (name, input, output)"
                    .into(),
            });
        }
        if let Some(chirp) = &self.chirp {
            positive("chirp.amplitude", &chirp.amplitude, Dimension::VOLTAGE)?;
            positive("chirp.duration", &chirp.duration, Dimension::TIME)?;
        }
        Ok(())
    }
}

/// The responses of the model: its modes at rest and, per channel, `H(f)` from the linear
/// model (hysteretic and viscous losses) and from the chirp simulation if asked for.
pub struct Responses {
    pub model_name: String,
    pub from: f64,
    pub to: f64,
    pub frequencies: Vec<f64>,
    pub modes: Vec<Mode>,
    /// Per channel of the spec, one per source.
    pub channels: Vec<Vec<Source>>,
}

/// One source's response on the sweep's grid and its resonances, strongest first.
pub struct Source {
    pub name: &'static str,
    /// The key in [`crate::render::report::Outcome::values`] (`hysteretic`, `viscous`, `chirp`).
    pub key: &'static str,
    pub response: Vec<Point>,
    pub resonances: Vec<Resonance>,
}

/// Each channel's `(input, output)` indices in the leg's model.
fn channel_ports(spec: &Spec, leg: &Leg) -> Result<Vec<(usize, usize)>, Error> {
    spec.channel
        .iter()
        .map(|channel| {
            let input = leg.session.input_index(&channel.input);
            let output = leg.session.output_index(&channel.output);
            match (input, output) {
                (Ok(input), Ok(output)) => Ok((input, output)),
                (Err(e), _) | (_, Err(e)) => {
                    Err(Error::from(e).within(format!("channel `{}`", channel.name)))
                }
            }
        })
        .collect()
}

/// Linearizes the leg at rest and computes every channel's responses (chirps in parallel,
/// one per channel).
pub fn compute(spec: &Spec) -> Result<Responses, Error> {
    let from = positive("from", &spec.from, Dimension::FREQUENCY)?;
    let to = positive("to", &spec.to, Dimension::FREQUENCY)?;
    let leg = Leg::open(&spec.model)?;
    let model = leg.model();
    let (rest_q, linear) = leg.rest_linearization()?;
    let modes = linear.modes().ok_or(leg::Error::NoModes)?;
    let frequencies = frequency::log_space(from, to, spec.points);
    let indices = channel_ports(spec, &leg)?;
    let estimates = match &spec.chirp {
        Some(chirp) => {
            let (amplitude, duration, analysis_from) = chirp.settings()?;
            parallel(indices.clone(), threads(), |(input, output)| {
                let leg = Leg::open(&spec.model)?;
                let sweep = ChirpSweep {
                    input,
                    output,
                    amplitude,
                    from_hz: from,
                    to_hz: to,
                    duration,
                    rtol: 1e-7,
                    max_steps: mech_runtime::SimOptions::default().max_steps,
                };
                let u0 = vec![0.0; leg.model().nu()];
                let record = frequency::simulate_chirp(
                    leg.model(),
                    &rest_q,
                    &u0,
                    &leg.session.signals,
                    &sweep,
                )
                .map_err(Error::Chirp)?;
                let mut estimate = record.estimate(&frequencies);
                // Blank the start of the sweep (NaN: not drawn, not searched).
                for point in estimate
                    .iter_mut()
                    .filter(|p| p.frequency_hz < analysis_from)
                {
                    point.gain = mech_runtime::nalgebra::Complex::new(f64::NAN, f64::NAN);
                }
                let resonances = record.resonances(&estimate)?;
                Ok(Some((estimate, resonances)))
            })
            .into_iter()
            .collect::<Result<Vec<_>, Error>>()?
        }
        None => vec![None; spec.channel.len()],
    };
    let mut channels = Vec::new();
    for (&(input, output), estimate) in indices.iter().zip(estimates) {
        let linear_source = |name, key, damping| -> Result<Source, Error> {
            Ok(Source {
                name,
                key,
                response: frequency::linear_response(&linear, input, output, &frequencies, damping)
                    .ok_or(Error::SingularResponse)?,
                resonances: frequency::refined_resonances(
                    &frequencies,
                    frequency::linear_magnitude(&linear, input, output, damping),
                )?,
            })
        };
        let mut sources = vec![
            linear_source(
                "linear, hysteretic",
                "hysteretic",
                mech_runtime::FlexureDamping::Hysteretic,
            )?,
            linear_source(
                "linear, viscous",
                "viscous",
                mech_runtime::FlexureDamping::Viscous,
            )?,
        ];
        if let Some((response, resonances)) = estimate {
            sources.push(Source {
                name: "chirp simulation",
                key: "chirp",
                resonances,
                response,
            });
        }
        channels.push(sources);
    }
    Ok(Responses {
        model_name: model.name().to_string(),
        from,
        to,
        frequencies,
        modes,
        channels,
    })
}
