//! Experiment 5, dynamic regime (seed Sec. VI, Fig. 10): frequency responses from drive
//! voltage to foot displacement, lift and swing, from the linearized model (hysteretic and
//! viscous flexure losses) and from a simulated linear chirp; resonances and quality factors.
//!
//! Consumes: a [`Spec`] (model, sweep, channels, optional chirp). Produces: an [`Outcome`]
//! with the resonance and mode tables, one CSV and Bode plot per channel, and key values.
//! The linear model's resonances are refined on its continuous response (independent of
//! `points`); the chirp's are read off the grid of its estimate, and say so.

use std::path::Path;

use mech_codegen::ir::Dimension;
use serde::Deserialize;

use super::leg::Leg;
use super::Error;
use super::{csv, Outcome, Table};
use crate::frequency::{self, Channel, ChirpSweep, Point, Resonance};
use crate::parallel::{parallel, threads};
use crate::quantity::{positive, quantity};
use crate::render::plot;
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

fn q_text(q: Option<f64>) -> String {
    q.map_or("n/a".into(), |q| format!("{q:.1}"))
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
    /// The key in [`Outcome::values`] (`hysteretic`, `viscous`, `chirp`).
    pub key: &'static str,
    pub response: Vec<Point>,
    pub resonances: Vec<Resonance>,
    /// Refined on the continuous response (the linear model), or read off the grid (chirp).
    pub refined: bool,
}

/// Linearizes the leg at rest and computes every channel's responses (chirps in parallel,
/// one per channel).
pub fn compute(spec: &Spec) -> Result<Responses, Error> {
    let from = positive("from", &spec.from, Dimension::FREQUENCY)?;
    let to = positive("to", &spec.to, Dimension::FREQUENCY)?;
    let leg = Leg::open(&spec.model)?;
    let model = leg.model();
    let rest_inputs = leg.inputs(0.0, 0.0);
    let rest_q = leg.equilibrium(&leg.q0, &rest_inputs, &[])?.q;
    let linear = mech_runtime::linearize(model, 0.0, &rest_q, &rest_inputs, &leg.independent)
        .map_err(Error::Linearization)?;
    let modes = linear.modes().ok_or(Error::NoModes)?;
    let frequencies = frequency::log_space(from, to, spec.points);
    let indices = spec
        .channel
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
        .collect::<Result<Vec<_>, Error>>()?;
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
                };
                let u0 = vec![0.0; leg.model().nu()];
                let mut estimate = frequency::simulated_chirp(
                    leg.model(),
                    &rest_q,
                    &u0,
                    &leg.session.signals,
                    &sweep,
                    &frequencies,
                )
                .map_err(Error::Chirp)?;
                // Blank the start of the sweep (NaN: not drawn, not searched).
                for point in estimate
                    .iter_mut()
                    .filter(|p| p.frequency_hz < analysis_from)
                {
                    point.gain = mech_runtime::nalgebra::Complex::new(f64::NAN, f64::NAN);
                }
                Ok(Some(estimate))
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
                refined: true,
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
        if let Some(e) = estimate {
            sources.push(Source {
                name: "chirp simulation",
                key: "chirp",
                resonances: frequency::resonances(&e),
                response: e,
                refined: false,
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

pub fn run(spec: &Spec, dir: &Path) -> Result<Outcome, Error> {
    let responses = compute(spec)?;
    let (from, to, name) = (responses.from, responses.to, &responses.model_name);
    let mut outcome = Outcome {
        method: method_text(spec, from, to),
        ..Outcome::default()
    };
    for (k, mode) in responses.modes.iter().enumerate() {
        outcome
            .values
            .insert(format!("mode{}_hz", k + 1), mode.frequency_hz());
    }
    let mut table = Table::new(
        &format!("{name}: resonances and quality factors, {from}–{to} Hz"),
        &[
            "channel",
            "source",
            "f_r [Hz]",
            "Q (−3 dB)",
            "gain at f_r [µm/V]",
            "lowest-f gain [µm/V]",
        ],
    );
    for (channel, sources) in spec.channel.iter().zip(&responses.channels) {
        for source in sources {
            let peak = source.resonances.first();
            let low = source
                .response
                .iter()
                .map(|p| p.gain.norm())
                .find(|g| g.is_finite())
                .unwrap_or(f64::NAN);
            let key = source.key;
            if let Some(r) = peak {
                outcome.values.insert(
                    format!("{}_{key}_resonance_hz", channel.name),
                    r.frequency_hz,
                );
                if let Some(q) = r.quality_factor {
                    outcome
                        .values
                        .insert(format!("{}_{key}_q", channel.name), q);
                }
            }
            let q = q_text(peak.and_then(|r| r.quality_factor));
            table.row(vec![
                channel.name.clone(),
                source.name.to_string(),
                peak.map_or("–".into(), |r| format!("{:.1}", r.frequency_hz)),
                // A grid-read Q is low by an amount that depends on `points`: marked.
                if source.refined || q == "n/a" {
                    q
                } else {
                    format!("{q} (grid)")
                },
                peak.map_or("–".into(), |r| format!("{:.2}", r.peak_magnitude * 1e6)),
                format!("{:.2}", low * 1e6),
            ]);
        }
        write_channel(
            &mut outcome,
            dir,
            name,
            channel,
            &responses.frequencies,
            sources,
        )?;
    }
    outcome.tables.push(table);
    outcome.tables.push(modes_table(name, &responses.modes));
    outcome.notes.push(q_note(spec));
    Ok(outcome)
}

/// How the table's f_r and Q were obtained, and what limits the chirp's.
fn q_note(spec: &Spec) -> String {
    let linear = "Resonances of the linear model: the peak of |H| and both −3 dB points \
                  solved on its continuous response (Brent's method), so f_r and Q do not \
                  depend on the frequency grid.";
    match spec.chirp {
        Some(_) => format!(
            "{linear} Chirp rows, marked (grid): read off the {}-point grid of the swept-sine \
             estimate (parabola through the peak's samples, −3 dB points interpolated \
             between samples), so their Q depends on that grid and on the estimate's \
             ripple (sweep rate, record length) and can read low or high: compare it with \
             the viscous linear row, the same losses.",
            spec.points
        ),
        None => linear.to_string(),
    }
}

fn method_text(spec: &Spec, from: f64, to: f64) -> String {
    format!(
        "Linearized about the rest equilibrium under gravity (minimal coordinates: the \
         actuators), H = foot displacement / drive voltage, {from}–{to} Hz: with the \
         flexure losses as complex stiffness k(1 + iη) (exact at every frequency) and as \
         the time-domain viscous dampers b = kη/ω_ref (ω_ref = 2π·40 Hz). {}",
        match &spec.chirp {
            Some(c) => format!(
                "Chirp: the nonlinear model simulated (DOPRI5) from rest under a linear chirp \
                 of {} from {from} to {to} Hz over {}, one input at a time; H estimated by \
                 single-bin Fourier transforms of the whole record (rectangular window; viscous \
                 losses, as in the time domain). Magnitudes in dB re 1 µm/V.",
                c.amplitude, c.duration
            ),
            None => "Magnitudes in dB re 1 µm/V.".into(),
        }
    )
}

fn modes_table(name: &str, modes: &[Mode]) -> Table {
    let mut table = Table::new(
        &format!("{name}: normal modes of the linearized model"),
        &[
            "mode",
            "f [Hz]",
            "ζ (viscous)",
            "Q ≈ 1/(2ζ)",
            "shape (qsact, qlact)",
        ],
    );
    for (k, mode) in modes.iter().enumerate() {
        table.row(vec![
            format!("{}", k + 1),
            format!("{:.1}", mode.frequency_hz()),
            format!("{:.4}", mode.damping_ratio),
            format!("{:.1}", 1.0 / (2.0 * mode.damping_ratio)),
            format!(
                "[{}]",
                mode.shape
                    .iter()
                    .map(|x| format!("{x:+.3}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ]);
    }
    table
}

/// `bode_NAME.csv` (magnitude in m/V, phase) and `bode_NAME.svg` (dB re 1 µm/V) of one
/// channel, every source side by side.
fn write_channel(
    outcome: &mut Outcome,
    dir: &Path,
    name: &str,
    channel: &Channel,
    frequencies: &[f64],
    sources: &[Source],
) -> Result<(), Error> {
    let db = |p: &Point| 20.0 * (p.gain.norm() * 1e6).log10();
    let curves = |value: &dyn Fn(&Point) -> f64| -> Vec<(String, Vec<f64>, Vec<f64>)> {
        sources
            .iter()
            .map(|s| {
                (
                    s.name.to_string(),
                    frequencies.to_vec(),
                    s.response.iter().map(value).collect(),
                )
            })
            .collect()
    };
    let (magnitude, phase) = (curves(&db), curves(&Point::phase_deg));
    let rows: Vec<Vec<f64>> = (0..frequencies.len())
        .map(|k| {
            let mut row = vec![frequencies[k]];
            for s in sources {
                row.extend([s.response[k].gain.norm(), s.response[k].phase_deg()]);
            }
            row
        })
        .collect();
    let mut header = vec!["frequency_hz".to_string()];
    for s in sources {
        let s = s.name.replace([',', ' '], "_").replace("__", "_");
        header.extend([format!("{s}_magnitude_m_per_v"), format!("{s}_phase_deg")]);
    }
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    csv(
        outcome,
        dir,
        &format!("bode_{}.csv", channel.name),
        &header,
        &rows,
    )?;
    let path = dir.join(format!("bode_{}.svg", channel.name));
    plot::plot_bode(
        &path,
        &format!(
            "{name}: {} → {} (dB re 1 µm/V)",
            channel.input, channel.output
        ),
        &magnitude,
        &phase,
    )?;
    outcome.plots.push(path);
    Ok(())
}
