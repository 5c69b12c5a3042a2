//! `mech linearize MODEL`: `M δz̈ + C δż + K δz = B δin` about the static equilibrium, in
//! minimal coordinates, and the normal modes; with `--steady`, `δẋ = A δx` about the steady
//! motion through the initial state and its eigenvalues, optionally swept (`--sweep`).
//!
//! Consumes: [`ModelArgs`]. Produces: the matrices and modes (eigenvalues) on stdout; with
//! `--out` the modes (eigenvalues, per swept value) as CSV, with `--matrices` the matrices
//! and the first-order (state-space) form as JSON, each row and column named; with `--plot`
//! the swept eigenvalues' real and imaginary parts.

use super::Error;
use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;
use mech_runtime::nalgebra::{Complex, DMatrix};
use mech_runtime::{Linearization, Model, SteadyLinearization};

use super::args::ModelArgs;
use crate::output;
use crate::render::plot::{CurveStyle, XyPlot};
use crate::session::list;
use crate::steady_motion::{self, OperatingPoint, Sweep};

#[derive(Args, Clone, Debug)]
pub struct LinearizeArgs {
    #[command(flatten)]
    pub common: ModelArgs,
    /// CSV file for the modes (frequency, damping ratio, shape).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// JSON file for the matrices M, C, K, B and the state-space form ẋ = A x + B_s in,
    /// y = C_s x + D_s in with x = [δz; δż] (rows as arrays, with the names of the
    /// coordinates, inputs, states and outputs).
    #[arg(long, conflicts_with = "steady")]
    pub matrices: Option<PathBuf>,
    #[command(flatten)]
    pub motion: SteadyArgs,
}

/// The options of `--steady`: the operating point and the sweep.
#[derive(Args, Clone, Debug, Default)]
pub struct SteadyArgs {
    /// Linearize about the steady motion through the initial state (`q0`, `u0`, `--q0`,
    /// `--u0`; loops closed, dependent speeds solved) instead of the static equilibrium: the
    /// coordinates the motion does not depend on (cyclic) are dropped; the state is the other
    /// independent coordinates and the independent speeds (`--independent` names some).
    #[arg(long)]
    pub steady: bool,
    /// With `--steady`: start a coordinate at VALUE: `--q0 'lean=5 deg'` (repeatable).
    #[arg(long = "q0", value_name = "NAME=VALUE", requires = "steady")]
    pub q0: Vec<String>,
    /// With `--steady`: a speed's value in the steady motion: `--u0 'spin=10 rad/s'`.
    #[arg(long = "u0", value_name = "NAME=VALUE", requires = "steady")]
    pub u0: Vec<String>,
    /// With `--steady`: the eigenvalues for N values of a parameter or a speed (held at each
    /// value): `--sweep 'rear=0..33 rad/s:34'`.
    #[arg(long, value_name = "NAME=FROM..TO:N", requires = "steady")]
    pub sweep: Option<String>,
    /// With `--sweep`: the eigenvalues' real parts (solid) and imaginary parts' sizes (dashed)
    /// against the swept value (`.svg` or `.png`).
    #[arg(long, requires = "sweep")]
    pub plot: Option<PathBuf>,
}

/// A matrix as JSON: an array of rows.
fn matrix_json(matrix: &DMatrix<f64>) -> serde_json::Value {
    (0..matrix.nrows())
        .map(|r| (0..matrix.ncols()).map(|c| matrix[(r, c)]).collect())
        .collect::<Vec<Vec<f64>>>()
        .into()
}

/// The `--matrices` document: the second-order matrices in the minimal coordinates and the
/// first-order form, with the names that label their rows and columns.
fn matrices_json(
    model: &dyn Model,
    linear: &Linearization,
    coordinates: &[&str],
) -> Result<serde_json::Value, Error> {
    let matrices = crate::session::named_matrices(linear).ok_or(Error::NoModes)?;
    let inputs: Vec<&str> = (0..model.ninputs()).map(|i| model.input_name(i)).collect();
    let outputs: Vec<&str> = (0..model.noutputs())
        .map(|i| model.output_name(i))
        .collect();
    let states: Vec<String> = ["q", "u"]
        .iter()
        .flat_map(|kind| coordinates.iter().map(move |name| format!("{kind}_{name}")))
        .collect();
    let mut json = serde_json::json!({
        "model": model.name(),
        "form": "M δz̈ + C δż + K δz = B δin; ẋ = A x + B_s δin, y = C_s x + D_s δin, x = [δz; δż] (SI units)",
        "coordinates": coordinates,
        "inputs": inputs,
        "outputs": outputs,
        "states": states,
    });
    for (name, matrix) in &matrices {
        json[*name] = matrix_json(matrix);
    }
    Ok(json)
}

fn matrix_text(name: &str, matrix: &DMatrix<f64>) -> String {
    let mut text = format!("{name} =\n");
    for r in 0..matrix.nrows() {
        let row: Vec<String> = (0..matrix.ncols())
            .map(|c| format!("{:>13.5e}", matrix[(r, c)]))
            .collect();
        let _ = writeln!(text, "  [{}]", row.join(" "));
    }
    text
}

pub fn run(args: &LinearizeArgs) -> Result<(), Error> {
    if args.motion.steady {
        return run_steady(args);
    }
    let outputs = [args.out.as_deref(), args.matrices.as_deref()];
    let reads = args.common.check_outputs(&outputs, None)?;
    let (session, inputs) = args.common.open("linearize")?;
    let model = &session.model;
    let linear = session.linearization(&args.common.independent, &inputs)?;
    let names = crate::session::coordinate_names(model, &linear.independent);
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
    let modes = linear.modes().ok_or(Error::NoModes)?;
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
    let mut files = Vec::new();
    if let Some(out) = &args.out {
        let mut header = vec![
            "frequency_hz".to_string(),
            "omega_rad_s".to_string(),
            "damping_ratio".to_string(),
        ];
        header.extend(names.iter().map(|n| format!("shape_{n}")));
        files.push(output::File::csv(out, &header, &rows)?);
    }
    if let Some(path) = &args.matrices {
        let json = matrices_json(model, &linear, &names)?;
        let text = serde_json::to_string_pretty(&json).map_err(|e| Error::write(path, e))?;
        files.push(output::File::new(path, text));
    }
    write_files(&files, &reads)
}

/// Writes `files` all or nothing (none replaces one of `reads`) and names each.
fn write_files(files: &[output::File], reads: &[output::Read]) -> Result<(), Error> {
    output::write_all(files, reads)?;
    for file in files {
        println!("written to {}", file.path.display());
    }
    Ok(())
}

/// The eigenvalues of `linear` with parts below 1e-10 of the largest eigenvalue shown as
/// zero (the central differences' round-off on a zero eigenvalue has no sign worth showing).
fn shown_eigenvalues(linear: &SteadyLinearization) -> Vec<Complex<f64>> {
    let values = linear.eigenvalues();
    let largest = values.iter().fold(0.0_f64, |m, z| m.max(z.norm()));
    let clean = |x: f64| if x.abs() <= 1e-10 * largest { 0.0 } else { x };
    values
        .iter()
        .map(|z| Complex::new(clean(z.re), clean(z.im)))
        .collect()
}

/// One eigenvalue as `re ± im i` with its frequency and damping ratio (oscillating ones).
fn eigenvalue_text(value: &Complex<f64>) -> String {
    if value.im == 0.0 {
        return format!("{:>13.6}", value.re);
    }
    let omega = value.norm();
    format!(
        "{:>13.6} {:>+13.6}i   f = {:.6} Hz, ζ = {:.4}",
        value.re,
        value.im,
        value.im.abs() / std::f64::consts::TAU,
        -value.re / omega
    )
}

/// `mech linearize --steady`: one operating point, or the eigenvalues along `--sweep`.
fn run_steady(args: &LinearizeArgs) -> Result<(), Error> {
    let outputs = [args.out.as_deref()];
    let reads = args
        .common
        .check_outputs(&outputs, args.motion.plot.as_deref())?;
    let (mut session, inputs) = args.common.open("linearize")?;
    let point = OperatingPoint {
        independent: args.common.independent.clone(),
        q0: args.motion.q0.clone(),
        u0: args.motion.u0.clone(),
    };
    let Some(text) = &args.motion.sweep else {
        let linear = steady_motion::linearize(&session, &point, &inputs)?;
        print!("{}", steady_text(&session.model, &linear));
        let mut files = Vec::new();
        if let Some(out) = &args.out {
            let header = ["re_per_s".to_string(), "im_rad_s".to_string()];
            let rows: Vec<Vec<f64>> = linear
                .eigenvalues()
                .iter()
                .map(|z| vec![z.re, z.im])
                .collect();
            files.push(output::File::csv(out, &header, &rows)?);
        }
        return write_files(&files, &reads);
    };
    let sweep = Sweep::parse(&session, text)?;
    let bar = super::progress::progress_bar(
        sweep.values.len() as u64,
        "linearizing {bar:30} {pos}/{len} values",
    );
    let results = steady_motion::sweep(&mut session, &point, &inputs, &sweep, |done| {
        bar.set_position(done as u64)
    })?;
    bar.finish_and_clear();
    let model = &session.model;
    let first = &results[0];
    let names = steady_motion::state_names(model, first);
    let cyclic = steady_motion::cyclic_names(model, first);
    let mut text = format!(
        "`{}` linearized about its steady motion for {} = {} .. {} {} ({} values): state [{}], \
         cyclic coordinates dropped: {}\n\n{:>12}  eigenvalues (re ± im i, 1/s)\n",
        model.name(),
        sweep.name,
        sweep.values[0],
        sweep.values[sweep.values.len() - 1],
        sweep.unit,
        sweep.values.len(),
        names.join(", "),
        list(&cyclic),
        sweep.name,
    );
    let mut rows = Vec::new();
    let width = first.states.len();
    for (value, linear) in sweep.values.iter().zip(&results) {
        let values = shown_eigenvalues(linear);
        let shown: Vec<String> = values
            .iter()
            .map(|z| match z.im {
                0.0 => format!("{:.4}", z.re),
                im => format!("{:.4}{:+.4}i", z.re, im),
            })
            .collect();
        let _ = writeln!(text, "{value:>12.6}  {}", shown.join("  "));
        // The files get the values as computed; only the table rounds round-off to zero.
        let mut row = vec![*value];
        row.extend(linear.eigenvalues().iter().flat_map(|z| [z.re, z.im]));
        row.resize(1 + 2 * width, f64::NAN);
        rows.push(row);
    }
    if let Some(worst) = results
        .iter()
        .max_by(|a, b| a.cyclic_change.total_cmp(&b.cyclic_change))
    {
        text += &cyclic_warning(model, worst);
    }
    if let Some(worst) = results
        .iter()
        .max_by(|a, b| a.unsteadiness().total_cmp(&b.unsteadiness()))
    {
        if worst.unsteadiness() > steady_motion::UNSTEADY {
            let _ = writeln!(
                text,
                "warning: max |ẋ| = {:.1e} at one operating point: not a steady motion there",
                worst.unsteadiness()
            );
        }
    }
    print!("{text}");
    let mut files = Vec::new();
    if let Some(out) = &args.out {
        let mut header = vec![sweep.name.clone()];
        header.extend((1..=width).flat_map(|k| [format!("re_{k}"), format!("im_{k}")]));
        files.push(output::File::csv(out, &header, &rows)?);
    }
    if let Some(path) = &args.motion.plot {
        files.push(eigenvalue_plot(path, &sweep, &rows, width)?);
    }
    write_files(&files, &reads)
}

/// A line warning that the dropped coordinates are cyclic to first order only (empty if they
/// are a symmetry: `A` the same, to `NOT_CYCLIC`, when they move on).
fn cyclic_warning(model: &dyn Model, linear: &SteadyLinearization) -> String {
    if linear.cyclic_change <= steady_motion::NOT_CYCLIC {
        return String::new();
    }
    let cyclic = steady_motion::cyclic_names(model, linear);
    format!(
        "warning: A changes by {:.1e} of its largest entry when {} move on: they are cyclic \
         to first order only here, and the eigenvalues hold at this instant (a periodic motion \
         needs Floquet analysis, or coordinates in which it is steady)\n",
        linear.cyclic_change,
        cyclic.join(", ")
    )
}

/// The report of one steady linearization.
fn steady_text(model: &dyn Model, linear: &SteadyLinearization) -> String {
    let names = steady_motion::state_names(model, linear);
    let cyclic = steady_motion::cyclic_names(model, linear);
    let fastest = linear.u.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let moving: Vec<String> = (0..model.nu())
        .filter(|&i| linear.u[i].abs() > 1e-12 * fastest)
        .map(|i| format!("{} = {:.6}", model.speed_name(i), linear.u[i]))
        .collect();
    let mut text = format!(
        "`{}` linearized about its steady motion (SI units): δẋ = A δx\n\
         speeds: {} (the others zero)\n\
         cyclic coordinates (the motion does not depend on them; dropped): {}\n\
         state x = [{}]\n\
         max |ẋ| at the operating point: {:.1e}{}\n{}\n",
        model.name(),
        if moving.is_empty() {
            "all zero".to_string()
        } else {
            moving.join(", ")
        },
        list(&cyclic),
        names.join(", "),
        linear.unsteadiness(),
        if linear.unsteadiness() > steady_motion::UNSTEADY {
            "  (warning: not a steady motion; the linearization is about a passing state)"
        } else {
            ""
        },
        cyclic_warning(model, linear),
    );
    text += &matrix_text("A", &linear.a);
    if let Some(form) = linear.second_order() {
        let coordinates = crate::session::coordinate_names(model, &form.coordinates);
        let _ = writeln!(
            text,
            "\nsecond-order form in [{}], the other speeds held: M δz̈ + C δż + K δz = 0",
            coordinates.join(", ")
        );
        text += &matrix_text("M", &form.mass);
        text += &matrix_text("C", &form.damping);
        text += &matrix_text("K", &form.stiffness);
    }
    let _ = writeln!(text, "\neigenvalues (1/s):");
    for value in shown_eigenvalues(linear) {
        let _ = writeln!(text, "  {}", eigenvalue_text(&value));
    }
    text
}

/// Real parts solid, imaginary parts' sizes (a conjugate pair's are one) dashed in the same
/// colour, against the swept value. The eigenvalues of each row are sorted by real part, so
/// each real-part curve is continuous; an imaginary part follows its eigenvalue's rank and
/// may pass to another colour where real parts cross.
fn eigenvalue_plot(
    path: &std::path::Path,
    sweep: &Sweep,
    rows: &[Vec<f64>],
    width: usize,
) -> Result<output::File, Error> {
    let xs: Vec<f64> = rows.iter().map(|row| row[0]).collect();
    let mut curves = Vec::new();
    let mut styles = Vec::new();
    for k in 0..width {
        let part = |offset: usize| rows.iter().map(|row| row[1 + 2 * k + offset]).collect();
        curves.push((format!("Re λ{}", k + 1), xs.clone(), part(0)));
        styles.push(CurveStyle {
            color: k,
            dashed: false,
        });
        let imaginary: Vec<f64> = part(1);
        if imaginary.iter().any(|&im| im != 0.0) {
            let magnitude = imaginary.iter().map(|im| im.abs()).collect();
            curves.push((format!("|Im λ{}|", k + 1), xs.clone(), magnitude));
            styles.push(CurveStyle {
                color: k,
                dashed: true,
            });
        }
    }
    let x_label = format!("{} [{}]", sweep.name, sweep.unit);
    let plot = XyPlot {
        styles: Some(&styles),
        ..XyPlot::new(
            "Eigenvalues of the steady motion",
            &x_label,
            "λ [1/s]",
            &curves,
        )
    };
    Ok(plot.render(path)?)
}
