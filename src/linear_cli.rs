//! `mech statics`, `mech linearize` and `mech bode`: equilibria, linear models, modes and
//! frequency responses from the command line, as readable tables, CSV and plots.
//!
//! Consumes: command-line arguments. Produces: text on stdout and files written atomically.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::Args;
use mech_runtime::{
    linearize, solve_statics, Equilibrium, Fixture, Linearization, Model, StaticsOptions,
};

use crate::frequency::{self, Point};
use crate::session::Session;
use crate::{output, plot};

/// What every linear-analysis command takes.
#[derive(Args, Clone, Debug)]
pub struct ModelArgs {
    /// The `.mech` file.
    pub model: PathBuf,
    /// Set a parameter: `--set 'm=12 g'` (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub sets: Vec<String>,
    /// Hold an input at a value: `--input 'drive=2 mN'` (a constant; repeatable).
    #[arg(long = "input", value_name = "NAME=VALUE")]
    pub inputs: Vec<String>,
    /// For models with loops: a coordinate kept independent (`NAME` or `NAME=VALUE` for the
    /// starting guess); default: chosen by pivoting.
    #[arg(long = "independent", value_name = "NAME[=VALUE]")]
    pub independent: Vec<String>,
}

#[derive(Args, Clone, Debug)]
pub struct StaticsArgs {
    #[command(flatten)]
    pub common: ModelArgs,
    /// Hold a point at a place: `--fixture 'foot=[1 mm, 2 mm, 0]'` where `foot` is a
    /// `position(...)` output of the model (Newtonian components; repeatable). Append
    /// `:xz` to hold only some components.
    #[arg(long = "fixture", value_name = "OUTPUT=[x, y, z][:COMPONENTS]")]
    pub fixtures: Vec<String>,
    /// CSV file for the equilibrium.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

#[derive(Args, Clone, Debug)]
pub struct LinearizeArgs {
    #[command(flatten)]
    pub common: ModelArgs,
    /// CSV file for the modes (frequency, damping ratio, shape).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

#[derive(Args, Clone, Debug)]
pub struct BodeArgs {
    #[command(flatten)]
    pub common: ModelArgs,
    /// Input driving the response.
    #[arg(long = "from-input", alias = "drive", value_name = "INPUT")]
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
    #[arg(long, default_value_t = 400)]
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
    /// CSV file (frequency, magnitude, phase, and the chirp estimate if any).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Bode plot (`.svg` or `.png`): magnitude and phase panels.
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// `--damping` of `mech bode`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Damping {
    Hysteretic,
    Viscous,
}

/// Opens the model with constant inputs, and returns it with the input values.
fn open(args: &ModelArgs) -> Result<(Session, Vec<f64>), String> {
    let session = Session::open(&args.model, &args.sets, &args.inputs)?;
    let inputs: Vec<f64> = session.signals.iter().map(|s| s.value(0.0)).collect();
    Ok((session, inputs))
}

/// A static equilibrium near the assembled initial state.
fn equilibrium(
    session: &Session,
    args: &ModelArgs,
    inputs: &[f64],
    fixtures: &[Fixture],
) -> Result<(Equilibrium, Vec<usize>), String> {
    let state = session.assemble(&args.independent)?;
    let mut q = state.q.clone();
    let equilibrium = solve_statics(
        &session.model,
        0.0,
        &mut q,
        inputs,
        fixtures,
        &StaticsOptions::default(),
    )
    .map_err(|e| format!("statics of `{}`: {e}", session.model.name()))?;
    Ok((equilibrium, state.independent))
}

/// `foot=[1 mm, 2 mm, 0]:xz` → a fixture on the position output `foot`.
fn parse_fixture(model: &dyn Model, text: &str) -> Result<Fixture, String> {
    let (name, rest) = text
        .split_once('=')
        .ok_or_else(|| format!("--fixture `{text}`: expected OUTPUT=[x, y, z]"))?;
    let name = name.trim();
    let (vector, components) = match rest.rsplit_once(':') {
        Some((vector, components)) if !components.contains(']') => (vector, components.trim()),
        _ => (rest, "xyz"),
    };
    let components: Vec<usize> = components
        .chars()
        .map(|c| {
            "xyz"
                .find(c)
                .ok_or_else(|| format!("--fixture {name}: `{c}` is not a component; use x, y, z"))
        })
        .collect::<Result<_, _>>()?;
    let mut outputs = [0; 3];
    for (axis, slot) in ["x", "y", "z"].iter().zip(outputs.iter_mut()) {
        *slot = model.output_index(&format!("{name}.{axis}")).ok_or_else(|| {
            format!("--fixture: the model has no position output `{name}`; declare `output {name} = position(body.point);`")
        })?;
    }
    let inner = vector
        .trim()
        .strip_prefix('[')
        .and_then(|v| v.strip_suffix(']'))
        .ok_or_else(|| {
            format!(
                "--fixture {name}: expected a position `[x, y, z]` with units, e.g. `[1 mm, 0, 0]`"
            )
        })?;
    let values: Vec<f64> = inner
        .split(',')
        .map(|part| {
            let (value, dimension) = mech_codegen::front::units::parse_quantity(part.trim())
                .map_err(|e| format!("--fixture {name}: {e}"))?;
            if dimension != mech_codegen::ir::Dimension::LENGTH
                && !(dimension == mech_codegen::ir::Dimension::NONE && value == 0.0)
            {
                return Err(format!(
                    "--fixture {name}: `{}` is not a length",
                    part.trim()
                ));
            }
            Ok(value)
        })
        .collect::<Result<_, _>>()?;
    let target: [f64; 3] = values
        .try_into()
        .map_err(|_| format!("--fixture {name}: give three components"))?;
    Ok(Fixture {
        name: name.to_string(),
        outputs,
        target,
        components,
    })
}

pub fn statics(args: &StaticsArgs) -> Result<(), String> {
    let (session, inputs) = open(&args.common)?;
    let model = &session.model;
    let fixtures: Vec<Fixture> = args
        .fixtures
        .iter()
        .map(|f| parse_fixture(model, f))
        .collect::<Result<_, _>>()?;
    let (equilibrium, _) = equilibrium(&session, &args.common, &inputs, &fixtures)?;
    let mut text = format!(
        "static equilibrium of `{}` in {} Newton iteration(s): max |F + Jᵀλ| = {:.1e}, max |φ| = {:.1e}\n",
        model.name(),
        equilibrium.iterations,
        equilibrium.force_residual,
        equilibrium.constraint_residual
    );
    let _ = writeln!(text, "\n{:<20} {:>18}", "coordinate", "q");
    for i in 0..model.nq() {
        let _ = writeln!(
            text,
            "{:<20} {:>18.10e}",
            model.coordinate_name(i),
            equilibrium.q[i]
        );
    }
    if model.nc() > 0 {
        let _ = writeln!(text, "\n{:<20} {:>18}", "loop row", "λ (reaction)");
        for (i, lambda) in equilibrium.loop_multipliers.iter().enumerate() {
            let _ = writeln!(text, "{:<20} {:>18.6e}", model.constraint_name(i), lambda);
        }
    }
    for (fixture, force) in fixtures.iter().zip(&equilibrium.fixture_forces) {
        let _ = writeln!(
            text,
            "\nforce of fixture `{}` on the model [N]: x {:.6e}, y {:.6e}, z {:.6e} (|F| = {:.6e})",
            fixture.name,
            force[0],
            force[1],
            force[2],
            (force[0] * force[0] + force[1] * force[1] + force[2] * force[2]).sqrt()
        );
    }
    print!("{text}");
    if let Some(out) = &args.out {
        let mut header: Vec<String> = (0..model.nq())
            .map(|i| format!("q_{}", model.coordinate_name(i)))
            .collect();
        let mut row = equilibrium.q.clone();
        for (fixture, force) in fixtures.iter().zip(&equilibrium.fixture_forces) {
            for (axis, value) in ["x", "y", "z"].iter().zip(force) {
                header.push(format!("{}.force_{axis}", fixture.name));
                row.push(*value);
            }
        }
        output::write_csv(out, &header, &[row])
            .map_err(|e| format!("cannot write {}: {e}", out.display()))?;
        println!("written to {}", out.display());
    }
    Ok(())
}

/// Linearizes about the static equilibrium.
fn linear_model(
    session: &Session,
    args: &ModelArgs,
    inputs: &[f64],
) -> Result<Linearization, String> {
    let (equilibrium, independent) = equilibrium(session, args, inputs, &[])?;
    linearize(&session.model, 0.0, &equilibrium.q, inputs, &independent)
        .map_err(|e| format!("linearization failed: {e}"))
}

fn matrix_text(name: &str, matrix: &mech_runtime::nalgebra::DMatrix<f64>) -> String {
    let mut text = format!("{name} =\n");
    for r in 0..matrix.nrows() {
        let row: Vec<String> = (0..matrix.ncols())
            .map(|c| format!("{:>13.5e}", matrix[(r, c)]))
            .collect();
        let _ = writeln!(text, "  [{}]", row.join(" "));
    }
    text
}

pub fn linearize_command(args: &LinearizeArgs) -> Result<(), String> {
    let (session, inputs) = open(&args.common)?;
    let model = &session.model;
    let linear = linear_model(&session, &args.common, &inputs)?;
    let names: Vec<&str> = linear
        .independent
        .iter()
        .map(|&i| model.coordinate_name(i))
        .collect();
    let mut text = format!(
        "`{}` linearized about its static equilibrium, in the minimal coordinates [{}]:\n\
         M δz̈ + C δż + K δz = B δin (SI units)\n\n",
        model.name(),
        names.join(", ")
    );
    text += &matrix_text("M", &linear.mass);
    text += &matrix_text("C", &linear.damping);
    text += &matrix_text("K", &linear.stiffness);
    if linear.input.ncols() > 0 {
        let inputs: Vec<&str> = (0..model.ninputs()).map(|i| model.input_name(i)).collect();
        text += &matrix_text(&format!("B (inputs {})", inputs.join(", ")), &linear.input);
    }
    let modes = linear
        .modes()
        .ok_or("the reduced mass matrix is not positive definite")?;
    let _ = writeln!(
        text,
        "\n{:>4} {:>14} {:>14} {:>12}  shape",
        "mode", "f [Hz]", "ω_n [rad/s]", "ζ"
    );
    let mut rows = Vec::new();
    for (k, mode) in modes.iter().enumerate() {
        let shape: Vec<String> = mode.shape.iter().map(|x| format!("{x:+.4}")).collect();
        let unstable = if mode.natural_frequency < 0.0 {
            "  (unstable: growth rate −ω_n)"
        } else {
            ""
        };
        let _ = writeln!(
            text,
            "{:>4} {:>14.6} {:>14.6} {:>12.4e}  [{}]{unstable}",
            k + 1,
            mode.frequency_hz(),
            mode.natural_frequency,
            mode.damping_ratio,
            shape.join(", ")
        );
        let mut row = vec![
            mode.frequency_hz(),
            mode.natural_frequency,
            mode.damping_ratio,
        ];
        row.extend(&mode.shape);
        rows.push(row);
    }
    print!("{text}");
    if let Some(out) = &args.out {
        let mut header = vec![
            "frequency_hz".to_string(),
            "omega_rad_s".to_string(),
            "damping_ratio".to_string(),
        ];
        header.extend(names.iter().map(|n| format!("shape_{n}")));
        output::write_csv(out, &header, &rows)
            .map_err(|e| format!("cannot write {}: {e}", out.display()))?;
        println!("written to {}", out.display());
    }
    Ok(())
}

fn frequency_value(what: &str, text: &str) -> Result<f64, String> {
    let (value, dimension) =
        mech_codegen::front::units::parse_quantity(text).map_err(|e| format!("{what}: {e}"))?;
    let hertz = mech_codegen::ir::Dimension {
        time: -1,
        ..mech_codegen::ir::Dimension::NONE
    };
    if (dimension != hertz && dimension != mech_codegen::ir::Dimension::NONE)
        || value.is_nan()
        || value <= 0.0
    {
        return Err(format!(
            "{what}: expected a positive frequency such as `10 Hz`, got `{text}`"
        ));
    }
    Ok(value)
}

pub fn bode(args: &BodeArgs) -> Result<(), String> {
    let (session, inputs) = open(&args.common)?;
    let model = &session.model;
    let input = model.input_index(&args.drive).ok_or_else(|| {
        let known: Vec<&str> = (0..model.ninputs()).map(|i| model.input_name(i)).collect();
        format!(
            "unknown input `{}`; inputs of `{}`: {}",
            args.drive,
            model.name(),
            known.join(", ")
        )
    })?;
    let output = model.output_index(&args.output).ok_or_else(|| {
        let known: Vec<&str> = (0..model.noutputs())
            .map(|i| model.output_name(i))
            .collect();
        format!(
            "unknown output `{}`; outputs of `{}`: {}",
            args.output,
            model.name(),
            known.join(", ")
        )
    })?;
    let (from, to) = (
        frequency_value("--from", &args.from)?,
        frequency_value("--to", &args.to)?,
    );
    if to <= from {
        return Err(format!("--to ({to} Hz) must be above --from ({from} Hz)"));
    }
    let linear = linear_model(&session, &args.common, &inputs)?;
    let frequencies = frequency::log_space(from, to, args.points);
    let damping = match args.damping {
        Damping::Hysteretic => mech_runtime::FlexureDamping::Hysteretic,
        Damping::Viscous => mech_runtime::FlexureDamping::Viscous,
    };
    let response = frequency::linear_response(&linear, input, output, &frequencies, damping)
        .ok_or("the linear model is singular at some frequency")?;
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
    let found = frequency::resonances(&response);
    if found.is_empty() {
        text += "no resonance peak inside the sweep\n";
    }
    for resonance in &found {
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
    let chirp = if args.chirp {
        Some(chirp_response(
            &session,
            args,
            input,
            output,
            from,
            to,
            &frequencies,
        )?)
    } else {
        None
    };
    print!("{text}");

    let mut header = vec![
        "frequency_hz".to_string(),
        "magnitude_db".to_string(),
        "phase_deg".to_string(),
    ];
    if chirp.is_some() {
        header.extend([
            "chirp_magnitude_db".to_string(),
            "chirp_phase_deg".to_string(),
        ]);
    }
    let rows: Vec<Vec<f64>> = response
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let mut row = vec![p.frequency_hz, p.magnitude_db(), p.phase_deg()];
            if let Some(estimate) = &chirp {
                row.extend([estimate[k].magnitude_db(), estimate[k].phase_deg()]);
            }
            row
        })
        .collect();
    if let Some(out) = &args.out {
        output::write_csv(out, &header, &rows)
            .map_err(|e| format!("cannot write {}: {e}", out.display()))?;
        println!("written to {}", out.display());
    }
    if let Some(path) = &args.plot {
        bode_plot(
            path,
            &format!("{}: {} → {}", model.name(), args.drive, args.output),
            &response,
            chirp.as_deref(),
        )?;
        println!("plot written to {}", path.display());
    }
    Ok(())
}

/// Simulates a chirp on `input` (from the equilibrium) and estimates the response.
fn chirp_response(
    session: &Session,
    args: &BodeArgs,
    input: usize,
    output: usize,
    from: f64,
    to: f64,
    frequencies: &[f64],
) -> Result<Vec<Point>, String> {
    let model = &session.model;
    let amplitude = match &args.chirp_amplitude {
        Some(text) => {
            mech_codegen::front::units::parse_quantity(text)
                .map_err(|e| format!("--chirp-amplitude: {e}"))?
                .0
        }
        None => 1.0,
    };
    // Sweep slowly enough to pass each resonance in many cycles: 200 periods of the lowest
    // frequency, at least 2 s.
    let duration = (200.0 / from).max(2.0);
    let mut signals = session.signals.clone();
    let offset = signals[input].value(0.0);
    signals[input] = mech_runtime::Signal::Chirp {
        amplitude,
        f0_hz: from,
        f1_hz: to,
        duration,
        offset,
    };
    let state = session.assemble(&args.common.independent)?;
    let options = mech_runtime::SimOptions {
        t_end: duration,
        output_interval: 1.0 / (20.0 * to),
        method: mech_runtime::Method::Dopri5 {
            rtol: 1e-8,
            atol: 1e-12,
            h_max: 1.0 / (20.0 * to),
        },
        ..mech_runtime::SimOptions::default()
    };
    let run = mech_runtime::simulate(model, &state.q, &state.u, &signals, &options, &mut |_| {})
        .map_err(|e| format!("chirp simulation failed: {e}"))?;
    let u: Vec<f64> = run.inputs.iter().map(|x| x[input]).collect();
    let y: Vec<f64> = run.outputs.iter().map(|x| x[output]).collect();
    Ok(frequency::chirp_estimate(&run.times, &u, &y, frequencies))
}

fn bode_plot(
    path: &Path,
    title: &str,
    response: &[Point],
    chirp: Option<&[Point]>,
) -> Result<(), String> {
    let frequencies: Vec<f64> = response.iter().map(|p| p.frequency_hz).collect();
    let mut magnitude = vec![(
        "linear model".to_string(),
        frequencies.clone(),
        response.iter().map(Point::magnitude_db).collect(),
    )];
    let mut phase = vec![(
        "linear model".to_string(),
        frequencies.clone(),
        response.iter().map(Point::phase_deg).collect(),
    )];
    if let Some(chirp) = chirp {
        magnitude.push((
            "chirp estimate".to_string(),
            frequencies.clone(),
            chirp.iter().map(Point::magnitude_db).collect(),
        ));
        phase.push((
            "chirp estimate".to_string(),
            frequencies.clone(),
            chirp.iter().map(Point::phase_deg).collect(),
        ));
    }
    plot::plot_bode(path, title, &magnitude, &phase).map_err(|e| format!("cannot plot: {e}"))
}
