//! Rendering of `kind = "bode"` experiment results: the tables, CSV files and plots
//! of [`crate::experiments::bode`]'s computed data.
//!
//! Consumes: the kind's spec and what its `compute` returns. Produces: an [`Outcome`] and
//! the files it lists.

use super::shared::csv;
use crate::experiments::bode::{compute, Source, Spec};
use crate::experiments::Error;
use crate::frequency::{self, Channel, Point};
use crate::render::plot;
use crate::render::report::Outcome;
use crate::render::table::Table;
use mech_runtime::Mode;
use std::path::Path;

pub fn run(spec: &Spec, dir: &Path) -> Result<Outcome, Error> {
    let responses = compute(spec)?;
    let (from, to, name) = (responses.from, responses.to, &responses.model_name);
    let mut outcome = Outcome::with_method(method_text(spec, from, to));
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
                q,
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
            "{linear} Chirp rows: the same search on the swept-sine estimate's continuous \
             |Y(f)/U(f)| (the record's Fourier transforms at any frequency) within the band \
             the sweep excited, so they do not depend on the grid either; they keep the \
             estimate's own error (sweep rate, record length): compare them with the viscous \
             linear row, the same losses."
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
                 of {} from {from} to {to} Hz over {}, then {:.0} % of that again with the \
                 drive at rest (the free decay belongs to the response), one input at a time; \
                 H estimated by single-bin Fourier transforms of the whole record (rectangular \
                 window; viscous \
                 losses, as in the time domain), not shown where the sweep hardly excited the \
                 frequency: input spectrum |U(f)| below {:.0} % of the sweep's in-band level \
                 A/(2√r) (−6 dB, the level at the sweep's own first and last frequency; one \
                 noise-free record has no coherence to compute). Magnitudes in dB re 1 µm/V; \
                 phases unwrapped along frequency.",
                c.amplitude,
                c.duration,
                100.0 * frequency::CHIRP_RING_DOWN,
                100.0 * frequency::CHIRP_INPUT_FLOOR
            ),
            None => "Magnitudes in dB re 1 µm/V; phases unwrapped along frequency.".into(),
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

/// `bode_NAME.csv` (magnitude in m/V, phase unwrapped as plotted) and `bode_NAME.svg` (dB re
/// 1 µm/V) of one channel, every source side by side.
fn write_channel(
    outcome: &mut Outcome,
    dir: &Path,
    name: &str,
    channel: &Channel,
    frequencies: &[f64],
    sources: &[Source],
) -> Result<(), Error> {
    let db = |p: &Point| 20.0 * (p.gain.norm() * 1e6).log10();
    let curve = |s: &Source, values: Vec<f64>| (s.name.to_string(), frequencies.to_vec(), values);
    let magnitude: Vec<_> = sources
        .iter()
        .map(|s| curve(s, s.response.iter().map(db).collect()))
        .collect();
    let responses: Vec<&[Point]> = sources.iter().map(|s| s.response.as_slice()).collect();
    let phase: Vec<_> = sources
        .iter()
        .zip(frequency::unwrapped_phases(&responses))
        .map(|(s, values)| curve(s, values))
        .collect();
    // The phases as plotted (unwrapped along frequency, the curves on one branch).
    let rows: Vec<Vec<f64>> = (0..frequencies.len())
        .map(|k| {
            let mut row = vec![frequencies[k]];
            for (s, (_, _, phase)) in sources.iter().zip(&phase) {
                row.extend([s.response[k].gain.norm(), phase[k]]);
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
    let plot = plot::plot_bode(
        &path,
        &format!("{name}: {} → {}", channel.input, channel.output),
        "magnitude [dB re 1 µm/V]",
        &magnitude,
        &phase,
    )?;
    outcome.add_plot(plot);
    Ok(())
}

fn q_text(q: Option<f64>) -> String {
    q.map_or("n/a".into(), |q| format!("{q:.1}"))
}
