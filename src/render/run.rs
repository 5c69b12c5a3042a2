//! The CSV of a simulated run, as `mech simulate --out` writes it and `mech animate` reads
//! it: `t`, `q_NAME`…, `u_NAME`…, the outputs, one row per sample.
//!
//! Consumes: a model and its [`Trajectory`]. Produces: the header and rows.

use mech_runtime::{Model, Trajectory};

/// The model's coordinate names, in the order of `q`.
pub fn coordinate_names(model: &dyn Model) -> Vec<String> {
    (0..model.nq())
        .map(|i| model.coordinate_name(i).to_string())
        .collect()
}

/// The model's speed names, in the order of `u`.
pub fn speed_names(model: &dyn Model) -> Vec<String> {
    (0..model.nu())
        .map(|i| model.speed_name(i).to_string())
        .collect()
}

/// The model's output names (components as `NAME.x`), in order.
pub fn output_names(model: &dyn Model) -> Vec<String> {
    (0..model.noutputs())
        .map(|i| model.output_name(i).to_string())
        .collect()
}

/// The CSV of a run: `t`, `q_NAME`…, `u_NAME`…, the outputs; one row per sample.
pub fn trajectory_table(
    model: &dyn Model,
    trajectory: &Trajectory,
) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut header = vec!["t".to_string()];
    header.extend(coordinate_names(model).iter().map(|n| format!("q_{n}")));
    header.extend(speed_names(model).iter().map(|n| format!("u_{n}")));
    header.extend(output_names(model));
    let rows = (0..trajectory.times.len())
        .map(|k| {
            let mut row = vec![trajectory.times[k]];
            row.extend(&trajectory.q[k]);
            row.extend(&trajectory.u[k]);
            row.extend(&trajectory.outputs[k]);
            row
        })
        .collect();
    (header, rows)
}
