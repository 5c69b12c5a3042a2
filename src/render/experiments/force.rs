//! Rendering of `kind = "force_deflection"` experiment results: the tables, CSV files and plots
//! of [`crate::experiments::force`]'s computed data.
//!
//! Consumes: the kind's spec and what its `compute` returns. Produces: an [`Outcome`] and
//! the files it lists.

use super::shared::{csv, percent_diff};
use crate::experiments::force::{compute, ForceDeflections, Paper, PaperRow, Spec};
use crate::experiments::leg::{Dof, ForceDeflection};
use crate::experiments::Error;
use crate::render::plot;
use crate::render::report::Outcome;
use crate::render::table::Table;
use mech_codegen::ir::transform::AXES;
use std::collections::BTreeMap;
use std::path::Path;

pub fn run(spec: &Spec, dir: &Path) -> Result<Outcome, Error> {
    let results = compute(spec)?;
    let (voltage, fbdf, model_name) = (results.voltage, results.actuator_work, &results.model_name);
    let mut outcome = Outcome::with_method(method_text(spec, voltage, results.step));
    let mut summary = Table::new(
        &format!("{model_name}: blocked force, free deflection and work at the foot"),
        &[
            "DOF",
            "load",
            "F_b foot [mN]",
            "F_y [mN]",
            "δ_free [mm]",
            "F·d [µJ]",
            "F·d/(F_b δ_f)",
        ],
    );
    let mut curves = Vec::new();
    let mut measured = Vec::new();
    for (dof, cases) in &results.dofs {
        let dof = *dof;
        outcome.tables.push(points_table(model_name, dof, cases));
        if let Some(row) = spec.paper.get(dof.name()) {
            // In the colour of the on-axis curve of the paper's way, drawn next.
            let paper = row.parse(&format!("paper.{}", dof.name()))?;
            let paper_way = compared_test(&results, dof);
            let compared = cases
                .iter()
                .position(|(_, test)| Some(test) == paper_way)
                .unwrap_or(0);
            measured.push(table_iv_points(dof.name(), &paper, curves.len() + compared));
        }
        for (label, test) in cases {
            record(&mut outcome, &mut summary, dof, label, test, fbdf);
            let rows = write_test(&mut outcome, dir, dof, test)?;
            let (xs, ys): (Vec<f64>, Vec<f64>) =
                rows.iter().map(|r| (r[0] * 1e3, r[1] * 1e3)).unzip();
            curves.push((format!("{} ({label})", dof.name()), xs, ys));
        }
    }
    outcome.tables.insert(0, summary);
    if !spec.paper.is_empty() {
        outcome
            .tables
            .push(paper_table(&results, &spec.paper, &outcome)?);
    }
    let path = dir.join("force_deflection.svg");
    let title = format!("{model_name}: force on the sensor against its distance at {voltage} V");
    let plot = plot::XyPlot {
        measured: &measured,
        ..plot::XyPlot::new(
            &title,
            "sensor distance from the foot's rest position [mm]",
            "on-axis force [mN]",
            &curves,
        )
    }
    .render(&path)?;
    outcome.add_plot(plot);
    Ok(outcome)
}

/// Table IV's measurements of one DOF as points on a force/distance plot (mm, mN, bars
/// ±1 s.d.): the blocked force at distance 0 and the free deflection at force 0, in palette
/// colour `color`.
pub(crate) fn table_iv_points(dof: &str, paper: &Paper, color: usize) -> plot::Measured {
    let ((d, d_sd), (force, force_sd)) = (paper.d, paper.force);
    plot::Measured {
        name: format!("{dof}: Table IV, F_b and d (± s.d., n = 2)"),
        color,
        points: vec![
            plot::ErrorPoint {
                x: 0.0,
                y: force * 1e3,
                x_error: 0.0,
                y_error: force_sd * 1e3,
            },
            plot::ErrorPoint {
                x: d * 1e3,
                y: 0.0,
                x_error: d_sd * 1e3,
                y_error: 0.0,
            },
        ],
    }
}

fn method_text(spec: &Spec, voltage: f64, step: f64) -> String {
    format!(
        "Static equilibria of `{}` at {voltage} V on one actuator, the foot against a \
         frictionless plane sensor normal to the test axis (lift: z, swing: x) held by a \
         fixture at 0, {:.0} µm, … from the foot's rest position along its free motion, \
         until the free foot no longer reaches it. Force = the fixture's reaction on the \
         sensor. Blocked force = force at distance 0; free deflection = the foot's one-way \
         displacement at {voltage} V; F·d as in Table IV. {}",
        spec.model.path.display(),
        step * 1e6,
        match spec.off_axis_fraction {
            Some(c) => format!(
                "Repeated with an off-axis load: the sensor also pushes the foot along y \
                 with {:.0} % of the on-axis force, opposing the foot's free y motion \
                 (the paper's ~30 %, Sec. V.A; direction assumed).",
                c * 100.0
            ),
            None => String::new(),
        }
    )
}

/// The force on the sensor against its distance, with the off-axis case beside if any.
fn points_table(model_name: &str, dof: Dof, cases: &[(&str, ForceDeflection)]) -> Table {
    let mut points = Table::new(
        &format!(
            "{model_name} {}: force on the sensor along {} against sensor distance",
            dof.name(),
            AXES[dof.axis()]
        ),
        &[
            "distance [µm]",
            "F [mN]",
            "F_y [mN]",
            "F, off-axis load [mN]",
            "F_y, off-axis load [mN]",
        ],
    );
    let offaxis = cases.iter().find(|(_, t)| t.off_axis_fraction > 0.0);
    for (k, p) in cases[0].1.points.iter().enumerate() {
        let loaded = offaxis.and_then(|(_, t)| t.points.get(k));
        points.row(vec![
            format!("{:.0}", p.distance * 1e6),
            format!("{:.2}", p.force * 1e3),
            format!("{:+.2}", p.force_y * 1e3),
            loaded.map_or("–".into(), |l| format!("{:.2}", l.force * 1e3)),
            loaded.map_or("–".into(), |l| format!("{:+.2}", l.force_y * 1e3)),
        ]);
    }
    points
}

/// `_offaxis` for the test with the off-axis load, `_reversed` for the reversed drive, `""`
/// for the on-axis test at the positive drive: the suffix of its CSV file and values.
fn test_tag(test: &ForceDeflection) -> &'static str {
    if test.off_axis_fraction > 0.0 {
        "_offaxis"
    } else if test.voltage < 0.0 {
        "_reversed"
    } else {
        ""
    }
}

/// The on-axis test of `dof` that moves the foot the paper's way (the compared one).
fn compared_test(results: &ForceDeflections, dof: Dof) -> Option<&ForceDeflection> {
    let (_, direction, _) = results.limits.iter().find(|(d, _, _)| *d == dof)?;
    results.on_axis(dof, *direction)
}

/// `force_DOF[_reversed|_offaxis].csv`: the sensor points and, last, the free foot; returns
/// the rows.
fn write_test(
    outcome: &mut Outcome,
    dir: &Path,
    dof: Dof,
    test: &ForceDeflection,
) -> Result<Vec<Vec<f64>>, Error> {
    let tag = test_tag(test);
    let rows: Vec<Vec<f64>> = test
        .points
        .iter()
        .map(|p| vec![p.distance, p.force, p.force_y, p.foot_y])
        .chain(std::iter::once(vec![
            test.free_deflection,
            0.0,
            0.0,
            test.free[1] - test.rest[1],
        ]))
        .collect();
    csv(
        outcome,
        dir,
        &format!("force_{}{tag}.csv", dof.name()),
        &["distance", "force", "force_y", "foot_dy"],
        &rows,
    )?;
    Ok(rows)
}

/// Adds a summary row and the key values `{dof}[_reversed|_offaxis]_{blocked_force, free_deflection,
/// work, normalized, blocked_force_y}`.
fn record(
    outcome: &mut Outcome,
    table: &mut Table,
    dof: Dof,
    label: &str,
    test: &ForceDeflection,
    fbdf: f64,
) {
    let blocked = test.points.first().copied();
    let force_y = blocked.map_or(0.0, |p| p.force_y);
    let tag = test_tag(test);
    let name = dof.name();
    for (key, value) in [
        ("blocked_force", test.blocked_force()),
        ("blocked_force_y", force_y),
        ("free_deflection", test.free_deflection),
        ("work", test.work()),
        ("normalized", test.work() / fbdf),
        ("points", test.points.len() as f64),
    ] {
        outcome.values.insert(format!("{name}{tag}_{key}"), value);
    }
    table.row(vec![
        name.to_string(),
        label.to_string(),
        format!("{:.2}", test.blocked_force() * 1e3),
        format!("{:+.2}", force_y * 1e3),
        format!("{:.3}", test.free_deflection * 1e3),
        format!("{:.1}", test.work() * 1e6),
        format!("{:.3}", test.work() / fbdf),
    ]);
}

/// Model (on-axis load only, the foot moving the paper's way) beside the paper's Table IV
/// values, and the kinematic limit of the foot's travel that way.
fn paper_table(
    results: &ForceDeflections,
    paper: &BTreeMap<String, PaperRow>,
    outcome: &Outcome,
) -> Result<Table, Error> {
    let mut table = Table::new(
        &format!(
            "{}: model against the paper's measurements (seed Table IV, mean ± s.d., n = 2; \
             the foot moving the way of the paper's test)",
            results.model_name
        ),
        &["DOF", "quantity", "model", "paper", "model vs paper"],
    );
    for (dof, row) in paper {
        let p = row.parse(&format!("paper.{dof}"))?;
        let tested = results
            .dofs
            .iter()
            .map(|(d, _)| *d)
            .find(|d| d.name() == dof);
        let tag = tested
            .and_then(|d| compared_test(results, d))
            .map_or("", test_tag);
        let value = |key: &str| {
            outcome
                .values
                .get(&format!("{dof}{tag}_{key}"))
                .copied()
                .unwrap_or(f64::NAN)
        };
        let limit = results
            .limits
            .iter()
            .find(|(d, _, _)| Some(*d) == tested)
            .and_then(|(d, direction, limit)| limit.map(|l| (*d, *direction, l)));
        if let Some((tested, direction, limit)) = limit {
            let sign = if direction > 0.0 { "+" } else { "−" };
            let way = format!("{sign}{}", AXES[tested.axis()]);
            table.row(vec![
                dof.clone(),
                format!("d limit, loop kinematics ({way}) [mm]"),
                format!("{:.2}", limit.foot * 1e3),
                format!("{:.2} ± {:.2}", p.d.0 * 1e3, p.d.1 * 1e3),
                if p.d.0 > limit.foot {
                    format!(
                        "measured beyond the model's reach by {:.1} s.d.",
                        (p.d.0 - limit.foot) / p.d.1
                    )
                } else {
                    percent_diff(limit.foot, p.d.0)
                },
            ]);
        }
        for (label, model, (mean, sd), scale, digits) in [
            (
                "d (free deflection) [mm]",
                value("free_deflection"),
                p.d,
                1e3,
                2,
            ),
            (
                "F (blocked force) [mN]",
                value("blocked_force"),
                p.force,
                1e3,
                1,
            ),
            ("F·d [µJ]", value("work"), p.work, 1e6, 1),
            ("F·d/(F_b δ_f)", value("normalized"), p.normalized, 1.0, 2),
        ] {
            table.row(vec![
                dof.clone(),
                label.to_string(),
                format!("{:.*}", digits, model * scale),
                format!("{:.*} ± {:.*}", digits, mean * scale, digits, sd * scale),
                percent_diff(model, mean),
            ]);
        }
    }
    Ok(table)
}
