//! `mech bode MODEL --drive IN --output OUT --from F1 --to F2`: the frequency response
//! of the linear model (and optionally of a simulated chirp), its resonances and Q.
//!
//! Consumes: [`ModelArgs`] and the sweep settings. Produces: text on stdout (resonances
//! refined on the linear model's continuous response, so independent of `--points`), and
//! with `--out`/`--plot` a CSV and a Bode plot.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::Args;
use mech_runtime::Model;

use super::args::{frequency_value, ModelArgs};
use super::Error;
use crate::frequency::{self, ChirpSweep, Damping, Point};
use crate::output;
use crate::render::plot;

#[derive(Args, Clone, Debug)]
pub struct BodeArgs {
    #[command(flatten)]
    pub common: ModelArgs,
    /// Input driving the response (`--from-input` is an older spelling of the same option).
    #[arg(long = "drive", alias = "from-input", value_name = "INPUT")]
    pub drive: String,
    /// Output observed.
    #[arg(long, value_name = "OUTPUT")]
    pub output: String,
    /// Lowest frequency, with a unit (`1 Hz`) or in Hz.
    #[arg(long)]
    pub from: String,
    /// Highest frequency.
    #[arg(long)]
    pub to: String,
    /// Number of log-spaced frequencies.
    #[arg(long, default_value_t = 400, value_parser = super::args::point_count)]
    pub points: usize,
    /// How flexure losses enter: `hysteretic` (complex stiffness k(1 + iη), exact at every
    /// frequency) or `viscous` (the time-domain dampers b = kη/ω_ref, as a simulation sees them).
    #[arg(long, value_enum, default_value_t = Damping::Hysteretic)]
    pub damping: Damping,
    /// Also simulate a linear chirp from `from` to `to` and overlay its swept-sine estimate.
    #[arg(long)]
    pub chirp: bool,
    /// Chirp amplitude (with the input's unit; default: 1 in SI units).
    #[arg(long)]
    pub chirp_amplitude: Option<String>,
    /// Budget of the chirp simulation's integration steps, accepted and rejected.
    #[arg(long, default_value_t = mech_runtime::SimOptions::default().max_steps, value_parser = super::args::positive_count)]
    pub max_steps: usize,
    /// CSV file (frequency, magnitude, phase, and the chirp estimate if any).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Bode plot (`.svg` or `.png`): magnitude and phase panels.
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

pub fn run(args: &BodeArgs) -> Result<(), Error> {
    let reads = (args.common).check_outputs(&[args.out.as_deref()], args.plot.as_deref())?;
    let (session, inputs) = args.common.open("bode")?;
    let model = &session.model;
    let input = session.input_index(&args.drive)?;
    let output = session.output_index(&args.output)?;
    let (from, to) = (
        frequency_value("--from", &args.from)?,
        frequency_value("--to", &args.to)?,
    );
    if to <= from {
        return Err(Error::Usage(format!(
            "--to ({to} Hz) must be above --from ({from} Hz)"
        )));
    }
    let linear = session.linearization(&args.common.independent, &inputs)?;
    let frequencies = frequency::log_space(from, to, args.points);
    let damping = args.damping.into();
    let response = frequency::linear_response(&linear, input, output, &frequencies, damping)
        .ok_or(Error::SingularResponse)?;
    let chirp = if args.chirp {
        let sweep = ChirpSweep {
            input,
            output,
            amplitude: match &args.chirp_amplitude {
                Some(text) => {
                    let expected = session.input_dimension(input);
                    crate::session::quantity("--chirp-amplitude", &args.drive, text, expected)?
                }
                None => 1.0,
            },
            from_hz: from,
            to_hz: to,
            // Slow enough to pass each resonance in many cycles: 200 periods of the lowest
            // frequency, at least 2 s.
            duration: (200.0 / from).max(2.0),
            rtol: 1e-8,
            max_steps: args.max_steps,
        };
        let state = session.assemble(&args.common.independent)?;
        let estimate =
            frequency::simulate_chirp(model, &state.q, &state.u, &session.signals, &sweep)
                .map_err(Error::Chirp)?
                .estimate(&frequencies);
        Some(estimate)
    } else {
        None
    };
    let found = frequency::refined_resonances(
        &frequencies,
        frequency::linear_magnitude(&linear, input, output, damping),
    )?;
    print!("{}", resonances_text(args, model, (from, to), &found));

    let mut files = Vec::new();
    if let Some(out) = &args.out {
        let (header, rows) = response_table(&response, chirp.as_deref());
        files.push(output::File::csv(out, &header, &rows)?);
    }
    if let Some(path) = &args.plot {
        let title = format!("{}: {} → {}", model.name(), args.drive, args.output);
        // The reference of the dB: 1 output unit per input unit.
        let output_unit = session.output_unit(&args.output);
        let reference = format!(
            "{}/{}",
            output_unit.as_deref().unwrap_or("(output unit)"),
            session.input_dimension(input)
        );
        let label = format!("magnitude [dB re 1 {reference}]");
        files.push(bode_plot(
            path,
            &title,
            &label,
            &response,
            chirp.as_deref(),
        )?);
    }
    output::write_all(&files, &reads)?;
    if let Some(out) = &args.out {
        println!("written to {}", out.display());
    }
    if let Some(path) = &args.plot {
        println!("plot written to {}", path.display());
    }
    Ok(())
}

/// The sweep, how losses enter, and each resonance with its peak gain and Q.
fn resonances_text(
    args: &BodeArgs,
    model: &dyn Model,
    (from, to): (f64, f64),
    found: &[frequency::Resonance],
) -> String {
    let losses = if model.nflexures() == 0 {
        "no flexures"
    } else if args.damping == Damping::Hysteretic {
        "flexure losses as complex stiffness k(1 + iη)"
    } else {
        "flexure losses as viscous dampers b = kη/ω_ref"
    };
    let mut text = format!(
        "frequency response of `{}` from `{}` to `{}`, {from} – {to} Hz ({losses})\n",
        model.name(),
        args.drive,
        args.output
    );
    if found.is_empty() {
        text += "no resonance peak inside the sweep\n";
    } else {
        // Said because a grid-read Q (the `mech report` chirp rows, measured data) differs.
        text += "peaks and −3 dB points solved on the continuous response, not read off the grid\n";
    }
    for resonance in found {
        let q = resonance
            .quality_factor
            .map_or("n/a (−3 dB points outside the sweep)".to_string(), |q| {
                format!("{q:.4}")
            });
        let _ = writeln!(
            text,
            "resonance at {:.6} Hz, peak gain {:.6e}, Q = {q}",
            resonance.frequency_hz, resonance.peak_magnitude
        );
    }
    text
}

/// The CSV of `--out`: frequency, magnitude and phase, and the chirp estimate's if any; the
/// phases unwrapped along frequency, as plotted.
fn response_table(response: &[Point], chirp: Option<&[Point]>) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut header: Vec<String> = ["frequency_hz", "magnitude_db", "phase_deg"]
        .map(String::from)
        .to_vec();
    if chirp.is_some() {
        header.extend(["chirp_magnitude_db", "chirp_phase_deg"].map(String::from));
    }
    let responses: Vec<&[Point]> = std::iter::once(response).chain(chirp).collect();
    let phases = frequency::unwrapped_phases(&responses);
    let rows = response
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let mut row = vec![p.frequency_hz, p.magnitude_db(), phases[0][k]];
            if let Some(estimate) = chirp {
                row.extend([estimate[k].magnitude_db(), phases[1][k]]);
            }
            row
        })
        .collect();
    (header, rows)
}

fn bode_plot(
    path: &Path,
    title: &str,
    magnitude_label: &str,
    response: &[Point],
    chirp: Option<&[Point]>,
) -> Result<output::File, Error> {
    let frequencies: Vec<f64> = response.iter().map(|p| p.frequency_hz).collect();
    let named: Vec<(&str, &[Point])> = std::iter::once(("linear model", response))
        .chain(chirp.map(|c| ("chirp estimate", c)))
        .collect();
    let responses: Vec<&[Point]> = named.iter().map(|(_, r)| *r).collect();
    let magnitude: Vec<_> = named
        .iter()
        .map(|(name, r)| {
            let db = r.iter().map(Point::magnitude_db).collect();
            (name.to_string(), frequencies.clone(), db)
        })
        .collect();
    let phase: Vec<_> = named
        .iter()
        .zip(frequency::unwrapped_phases(&responses))
        .map(|((name, _), phase)| (name.to_string(), frequencies.clone(), phase))
        .collect();
    Ok(plot::plot_bode(
        path,
        title,
        magnitude_label,
        &magnitude,
        &phase,
    )?)
}
