//! Rendering of `kind = "compare"` experiment results: the tables, CSV files and plots
//! of [`crate::experiments::compare`]'s computed data.
//!
//! Consumes: the kind's spec and what its `compute` returns. Produces: an [`Outcome`] and
//! the files it lists.

use super::force::table_iv_points;
use super::shared::csv;
use crate::experiments::compare::{compute, Spec};
use crate::experiments::leg::Dof;
use crate::experiments::Error;
use crate::output::File;
use crate::quantity::positive;
use crate::render::plot::{self, PlotError};
use crate::render::report::Outcome;
use crate::render::table::Table;
use mech_codegen::ir::Dimension;
use std::path::Path;

pub fn run(spec: &Spec, dir: &Path) -> Result<Outcome, Error> {
    let voltage = positive("voltage", &spec.voltage, Dimension::VOLTAGE)?;
    let robots = compute(spec, voltage)?;
    let mut outcome = Outcome::with_method(format!(
        "For each robot and degree of freedom, at {voltage} V: the free deflection d of the \
         foot along the test axis (lift: z, swing: x; one way from rest) and the blocked \
         force F (foot held at its rest position along that axis, frictionless), as in \
         experiment 2 without off-axis load; F·d and F·d/(F_b δ_f) with the model's \
         actuator F_b and δ_f, as in Table IV."
    ));
    let mut table = Table::new(
        "Model against the paper's Table IV (measured mean ± s.d., n = 2)",
        &[
            "robot",
            "DOF",
            "d model [mm]",
            "d paper",
            "F model [mN]",
            "F paper",
            "F·d model [µJ]",
            "F·d paper",
            "F·d/(F_b δ_f) model",
            "paper",
        ],
    );
    let mut work = [[0.0; 2]; 2];
    let mut paper_work = [[f64::NAN; 2]; 2];
    let mut rows = Vec::new();
    let (mut lines, mut measured) = (Vec::new(), Vec::new());
    for (r, (robot, tests)) in spec.robot.iter().zip(&robots).enumerate() {
        let fbdf = tests.actuator_work;
        for (k, (dof, test)) in [Dof::Lift, Dof::Swing].iter().zip(&tests.tests).enumerate() {
            let paper = robot
                .paper
                .get(dof.name())
                .map(|p| p.parse(dof.name()))
                .transpose()?;
            let (d, f, w) = (test.free_deflection, test.blocked_force(), test.work());
            work[r][k] = w;
            let label = format!("{} {}", robot.name, dof.name());
            if let Some(p) = &paper {
                paper_work[r][k] = p.work.0;
                measured.push(table_iv_points(&label, p, lines.len()));
            }
            // The model's blocked force and free deflection, joined straight.
            lines.push((
                format!("{label}: model, F_b to d"),
                vec![0.0, d * 1e3],
                vec![f * 1e3, 0.0],
            ));
            table.row(vec![
                robot.name.clone(),
                dof.name().into(),
                format!("{:.2}", d * 1e3),
                paper_text(paper.map(|p| p.d), 1e3, 1),
                format!("{:.1}", f * 1e3),
                paper_text(paper.map(|p| p.force), 1e3, 1),
                format!("{:.1}", w * 1e6),
                paper_text(paper.map(|p| p.work), 1e6, 1),
                format!("{:.2}", w / fbdf),
                paper_text(paper.map(|p| p.normalized), 1.0, 2),
            ]);
            let key = format!("{}_{}", if r == 0 { "old" } else { "new" }, dof.name());
            for (name, value) in [
                ("free_deflection", d),
                ("blocked_force", f),
                ("work", w),
                ("normalized", w / fbdf),
            ] {
                outcome.values.insert(format!("{key}_{name}"), value);
            }
            rows.push(vec![r as f64, k as f64, d, f, w, w / fbdf]);
        }
    }
    csv(
        &mut outcome,
        dir,
        "compare.csv",
        &[
            "robot",
            "dof_lift0_swing1",
            "free_deflection",
            "blocked_force",
            "work",
            "normalized",
        ],
        &rows,
    )?;
    outcome.tables.push(table);
    let title = format!("Blocked force and free deflection at {voltage} V: model against Table IV");
    let path = dir.join("compare.svg");
    outcome.add_plot(table_iv_plot(&path, &title, &lines, &measured, None)?);
    let (increase, model_ratio) = increase_table(spec, work, paper_work);
    outcome.values.insert("work_ratio".into(), model_ratio);
    outcome.tables.push(increase);
    Ok(outcome)
}

/// Model lines of force against the foot's distance from rest along the test axis (mm, mN)
/// under Table IV's points (± s.d.), written to `path`; `styles` as [`plot::XyPlot::styles`].
pub(crate) fn table_iv_plot(
    path: &Path,
    title: &str,
    lines: &[(String, Vec<f64>, Vec<f64>)],
    measured: &[plot::Measured],
    styles: Option<&[plot::CurveStyle]>,
) -> Result<File, PlotError> {
    plot::XyPlot {
        measured,
        styles,
        ..plot::XyPlot::new(
            title,
            "foot distance from rest along the test axis [mm]",
            "force [mN]",
            lines,
        )
    }
    .render(path)
}

/// `mean ± s.d.` of a paper value in display units, or `–`.
fn paper_text(value: Option<(f64, f64)>, scale: f64, digits: usize) -> String {
    value.map_or("–".to_string(), |(m, s)| {
        format!("{:.*} ± {:.*}", digits, m * scale, digits, s * scale)
    })
}

/// The work increase of the second robot over the first (lift + swing F·d), model against
/// the paper's Table IV and its reported figure; and the model's ratio.
fn increase_table(spec: &Spec, work: [[f64; 2]; 2], paper_work: [[f64; 2]; 2]) -> (Table, f64) {
    let total = |w: [f64; 2]| w[0] + w[1];
    let model_ratio = total(work[1]) / total(work[0]);
    let table_ratio = total(paper_work[1]) / total(paper_work[0]);
    let mut increase = Table::new(
        &format!(
            "Work done by the foot, {} against {} (lift + swing F·d)",
            spec.robot[1].name, spec.robot[0].name
        ),
        &["", "old [µJ]", "new [µJ]", "ratio new/old", "increase"],
    );
    let row = |label: &str, work: [[f64; 2]; 2], ratio: f64| {
        vec![
            label.to_string(),
            format!("{:.1}", total(work[0]) * 1e6),
            format!("{:.1}", total(work[1]) * 1e6),
            format!("{ratio:.2}"),
            format!("{:.0} %", 100.0 * (ratio - 1.0)),
        ]
    };
    increase.row(row("model", work, model_ratio));
    if table_ratio.is_finite() {
        increase.row(row("paper, from Table IV", paper_work, table_ratio));
    }
    if let Some(p) = spec.paper_work_increase_percent {
        increase.row(vec![
            "paper, reported (abstract)".into(),
            "–".into(),
            "–".into(),
            format!("{:.2}", 1.0 + p / 100.0),
            format!("{p:.0} % (model {:.0} %)", 100.0 * (model_ratio - 1.0)),
        ]);
    }
    (increase, model_ratio)
}
