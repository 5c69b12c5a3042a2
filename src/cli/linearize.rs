//! `mech linearize MODEL`: `M δz̈ + C δż + K δz = B δin` about the static equilibrium, in
//! minimal coordinates, and the normal modes.
//!
//! Consumes: [`ModelArgs`]. Produces: the matrices and modes on stdout; with `--out` the
//! modes as CSV, with `--matrices` the matrices and the first-order (state-space) form as
//! JSON, each row and column named.

use super::Error;
use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;
use mech_runtime::nalgebra::DMatrix;
use mech_runtime::{Linearization, Model};

use super::ModelArgs;
use crate::output;

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
    #[arg(long)]
    pub matrices: Option<PathBuf>,
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
    let outputs = [args.out.as_deref(), args.matrices.as_deref()];
    let reads = args.common.check_outputs(&outputs, None)?;
    let (session, inputs) = args.common.open("linearize")?;
    let model = &session.model;
    let linear = session.linearization(&args.common.independent, &inputs)?;
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
    output::write_all(&files, &reads)?;
    for file in &files {
        println!("written to {}", file.path.display());
    }
    Ok(())
}
