//! Rendering of `kind = "trajectory"` experiment results: the tables, CSV files and plots
//! of [`crate::experiments::trajectory`]'s computed data.
//!
//! Consumes: the kind's spec and what its `compute` returns. Produces: an [`Outcome`] and
//! the files it lists.

use super::shared::csv;
use crate::experiments::trajectory::{compute, peak_to_peak, Spec};
use crate::experiments::Error;
use crate::render::plot;
use crate::render::report::Outcome;
use crate::render::table::Table;
use mech_codegen::ir::transform::AXES;
use std::path::Path;

pub fn run(spec: &Spec, dir: &Path) -> Result<Outcome, Error> {
    let trajectories = compute(spec)?;
    let (amplitude, frequency) = (trajectories.amplitude, trajectories.frequency);
    let mut outcome = Outcome::with_method(method_text(spec, amplitude, frequency));
    let mut table = Table::new(
        "Foot trajectory: peak-to-peak range and the foot at the peak drive (mm)",
        &[
            "drive",
            "Δx p-p",
            "Δy p-p",
            "Δz p-p",
            "foot at +peak (x, y, z)",
        ],
    );
    let mut sagittal = Vec::new();
    let mut frontal = Vec::new();
    for (name, cycle) in &trajectories.cycles {
        let name = *name;
        csv(
            &mut outcome,
            dir,
            &format!("trajectory_{name}.csv"),
            &[
                "t", "v_lift", "v_swing", "foot_x", "foot_y", "foot_z", "dx", "dy", "dz",
            ],
            &cycle.rows,
        )?;
        let [xs, ys, zs] = [0, 1, 2].map(|axis| cycle.displacement_mm(axis));
        let ranges = [&xs, &ys, &zs].map(|v| peak_to_peak(v));
        for (axis, r) in AXES.iter().zip(ranges) {
            outcome.values.insert(format!("{name}_pp_{axis}"), r * 1e-3);
        }
        for (axis, v) in AXES.iter().zip(cycle.at_peak) {
            outcome.values.insert(format!("{name}_peak_d{axis}"), v);
        }
        let at_peak = cycle.at_peak;
        table.row(vec![
            name.to_string(),
            format!("{:.3}", ranges[0]),
            format!("{:.3}", ranges[1]),
            format!("{:.3}", ranges[2]),
            format!(
                "({:+.3}, {:+.3}, {:+.3})",
                at_peak[0] * 1e3,
                at_peak[1] * 1e3,
                at_peak[2] * 1e3
            ),
        ]);
        let label = format!(
            "{name} ({})",
            match name {
                "both" => format!("swing {:+.0}° ahead", spec.phase_deg),
                _ => "alone".into(),
            }
        );
        sagittal.push((label.clone(), xs, zs.clone()));
        frontal.push((label, ys, zs));
    }
    outcome.tables.push(table);
    plot_planes(
        &mut outcome,
        dir,
        &trajectories.model_name,
        &sagittal,
        &frontal,
    )?;
    Ok(outcome)
}

type Curve = (String, Vec<f64>, Vec<f64>);

/// `sagittal.svg` (x–z) and `frontal.svg` (y–z): the foot's path in each plane, one curve
/// per drive case.
fn plot_planes(
    outcome: &mut Outcome,
    dir: &Path,
    model_name: &str,
    sagittal: &[Curve],
    frontal: &[Curve],
) -> Result<(), Error> {
    for (file, title, x_label, curves) in [
        (
            "sagittal.svg",
            "sagittal plane (x–z)",
            "foot Δx [mm] (forward)",
            sagittal,
        ),
        (
            "frontal.svg",
            "frontal plane (y–z)",
            "foot Δy [mm] (lateral)",
            frontal,
        ),
    ] {
        let path = dir.join(file);
        let title = format!("{model_name}: quasi-static foot trajectory, {title}");
        // Equal scale: the path's shape (the step's height against its length) as it is.
        let plot = plot::XyPlot {
            equal_scale: true,
            ..plot::XyPlot::new(&title, x_label, "foot Δz [mm] (up)", curves)
        }
        .render(&path)?;
        outcome.add_plot(plot);
    }
    Ok(())
}

fn method_text(spec: &Spec, amplitude: f64, frequency: f64) -> String {
    format!(
        "Quasi-static: {} static equilibria per cycle of a {frequency} Hz sinusoid of \
         amplitude {amplitude} V on the model's drive inputs (the paper's 225 V \
         peak-to-peak drive, which moves each actuator tip ± its peak one-way \
         deflection), continuation from the previous phase; no time integration, since \
         the drive is far below the first resonance. Model `{}`{}. Foot displacement \
         from its rest position under gravity, chassis frame (x forward, y lateral, z up).",
        spec.points,
        spec.model.path.display(),
        if spec.model.set.is_empty() {
            String::new()
        } else {
            format!(" with {}", spec.model.set.join(", "))
        }
    )
}
