//! Rendering of `kind = "table_diagnosis"` results ([`crate::experiments::table_diagnosis`]):
//! per robot the verdict, the named causes with their fitted values, the paper's table beside
//! the base and the extended model, the work increase the paper headlines, and a plot.
//!
//! Consumes: the kind's spec and what its `compute` returns. Produces: an [`Outcome`] and
//! the files it lists.

use std::path::Path;

use super::compare::table_iv_plot;
use crate::diagnose::candidates::{Diagnosis, Trial, Verdict};
use crate::experiments::table_diagnosis::{compute, RobotDiagnosis, Spec};
use crate::experiments::Error;
use crate::render::diagnosis::{cause_at, fitted_text, verdict_text};
use crate::render::plot;
use crate::render::report::Outcome;
use crate::render::table::Table;

/// Work done by the foot, Σ F·d over a robot's tests: from the paper's values, from the model
/// as written, from the model as extended (if a cause is named).
type FootWork = (f64, f64, Option<f64>);

pub fn run(spec: &Spec, dir: &Path) -> Result<Outcome, Error> {
    let table = crate::experiments::load_compare(&spec.table)?;
    let robots = compute(spec, &table)?;
    let mut outcome = Outcome::with_method(method_text(spec));
    let mut causes = Table::new(
        "What the diagnosis names, per robot",
        &[
            "robot",
            "χ² base → extended (4 values)",
            "verdict",
            "fitted",
        ],
    );
    let mut values = Table::new(
        "Table IV against the model as written and as extended by the named cause (deviation in \
         s.d. of the paper's value)",
        &[
            "robot",
            "quantity",
            "paper (± s.d.)",
            "base model",
            "extended model",
        ],
    );
    let mut work = Vec::new();
    let (mut curves, mut measured) = (Vec::new(), Vec::new());
    for (r, robot) in robots.iter().enumerate() {
        let d = &robot.diagnosis;
        let extended = extended(d);
        causes.row(vec![
            robot.robot.clone(),
            format!(
                "{:.1} → {}",
                d.base.train_chi2,
                extended.map_or("–".into(), |t| format!("{:.1}", t.train_chi2))
            ),
            verdict_text(d),
            extended.map_or("–".into(), |t| {
                let fitted: Vec<String> = t.parameters.iter().map(fitted_text).collect();
                format!("{}: {}", cause_at(t), fitted.join(", "))
            }),
        ]);
        value_rows(&mut values, robot, extended);
        let key = if r == 0 { "old" } else { "new" };
        outcome
            .values
            .insert(format!("{key}_chi2_base"), d.base.train_chi2);
        if let Some(t) = extended {
            outcome
                .values
                .insert(format!("{key}_chi2_extended"), t.train_chi2);
        }
        work.push((
            foot_work(robot, &d.observations.values),
            foot_work(robot, &d.base.predicted),
            extended.map(|t| foot_work(robot, &t.predicted)),
        ));
        plot_lines(robot, extended, r, &mut curves, &mut measured);
    }
    outcome.tables.push(causes);
    if !spec.paper_causes.is_empty() {
        outcome
            .tables
            .push(paper_causes_table(&spec.paper_causes, &robots));
    }
    outcome.tables.push(values);
    let dynamics = dynamics_table(&robots, &mut outcome);
    outcome.tables.push(dynamics);
    if let [old, new] = work[..] {
        let table = work_table(old, new, &mut outcome);
        outcome.tables.push(table);
    }
    // Each robot's test: the model as written (dashed), then as extended, in one colour.
    let styles: Vec<plot::CurveStyle> = (0..curves.len())
        .map(|k| plot::CurveStyle {
            color: k / 2,
            dashed: k % 2 == 0,
        })
        .collect();
    let title = "Table IV (points, ± s.d.) against the model as written (dashed) and as extended";
    let path = dir.join("table_diagnosis.svg");
    outcome.add_plot(table_iv_plot(
        &path,
        title,
        &curves,
        &measured,
        Some(&styles),
    )?);
    Ok(outcome)
}

/// How the paper's Table IV is diagnosed: the data, the sensor's off-axis load, the catalog
/// and the rules that name a cause.
fn method_text(spec: &Spec) -> String {
    format!(
        "The paper's Table IV (from `{}`) as measured data: per robot, the free deflection \
         d and blocked force F of the lift and swing tests (mean ± s.d., n = 2; the s.d. is \
         the σ of each value) at the compare experiment's voltage, the foot driven the way \
         the paper's test moved it, the sensor pushing back along y with {:.0} % of the \
         on-axis force as the paper applied to its model (Sec. V-A). `mech diagnose` \
         (kind `force_deflection_table`, `--holdout none`: four values per robot, none to \
         spare, ranked by AICc on all of them) fits every cause of its catalog: flexure \
         stiffnesses, twist of a hinge or of a loop's hinges together (Eq. 8), axis \
         misalignments, the actuators' stiffness, force and base compliance, the \
         preload, the off-axis load itself. A cause is named when it lowers the AICc by \
         more than 10 and brings χ² per value within the noise band (explained) or not \
         (partly explained); causes within 2 of each other's AICc are a tie, and the \
         standard test that would separate them is named.",
        spec.table.display(),
        spec.off_axis_fraction * 100.0
    )
}

/// The work done by the foot (lift + swing `F·d`) of the second robot against the first's:
/// the paper's, the model's as written and as extended; the increases go into `outcome`'s
/// values.
fn work_table(old: FootWork, new: FootWork, outcome: &mut Outcome) -> Table {
    let mut table = Table::new(
        "Work done by the foot, second robot against the first (lift + swing F·d)",
        &["", "first [µJ]", "second [µJ]", "increase"],
    );
    let rows = [
        ("paper, Table IV's d·F", Some(old.0), Some(new.0)),
        ("model as written", Some(old.1), Some(new.1)),
        ("model as extended", old.2, new.2),
    ];
    for (label, first, second) in rows {
        let cell = |w: Option<f64>| w.map_or("–".into(), |w| format!("{:.1}", w * 1e6));
        let increase = match (first, second) {
            (Some(a), Some(b)) => format!("{:.0} %", 100.0 * (b / a - 1.0)),
            _ => "–".into(),
        };
        table.row(vec![label.into(), cell(first), cell(second), increase]);
    }
    outcome
        .values
        .insert("work_increase_base".into(), new.1 / old.1 - 1.0);
    if let (Some(a), Some(b)) = (old.2, new.2) {
        outcome
            .values
            .insert("work_increase_extended".into(), b / a - 1.0);
    }
    table
}

/// One row of `values` per value of Table IV of `robot`: the paper's (± s.d.), the model's as
/// written and as extended, with their deviations in s.d.
fn value_rows(values: &mut Table, robot: &RobotDiagnosis, extended: Option<&Trial>) {
    let d = &robot.diagnosis;
    let obs = &d.observations;
    let sigma = obs.sigma.as_deref().unwrap_or(&[]);
    for k in 0..obs.values.len() {
        let (scale, unit) = if obs.series[k].starts_with("free_deflection") {
            (1e3, "mm")
        } else {
            (1e3, "mN")
        };
        let model = |predicted: &[f64]| match (predicted.get(k), sigma.get(k)) {
            (Some(p), Some(s)) => {
                format!("{:.2} ({:+.1})", p * scale, (p - obs.values[k]) / s)
            }
            _ => "–".into(),
        };
        values.row(vec![
            robot.robot.clone(),
            format!("{} [{unit}]", obs.series[k].replace('_', " ")),
            format!(
                "{:.2} ± {:.2}",
                obs.values[k] * scale,
                sigma.get(k).copied().unwrap_or(f64::NAN) * scale
            ),
            model(&d.base.predicted),
            extended.map_or("–".into(), |t| model(&t.predicted)),
        ]);
    }
}

/// Per robot and cause the paper gives, the best fit (lowest χ²) of the catalog's
/// candidates of that cause, and where it stands in the diagnosis.
fn paper_causes_table(paper_causes: &[String], robots: &[RobotDiagnosis]) -> Table {
    let mut table = Table::new(
        "The paper's explanations, as fitted to the same values (the best of each kind)",
        &["robot", "cause", "χ² (4 values)", "standing", "fitted"],
    );
    for robot in robots {
        let d = &robot.diagnosis;
        for wanted in paper_causes {
            let ranked = d.ranked.iter().enumerate().map(|(k, t)| (Some(k), t));
            let inert = d.inert.iter().map(|t| (None, t));
            let best = ranked
                .chain(inert)
                .filter(|(_, t)| t.cause.contains(wanted.as_str()))
                .min_by(|a, b| {
                    let chi2 = |t: &Trial| {
                        if t.train_chi2.is_finite() {
                            t.train_chi2
                        } else {
                            f64::INFINITY
                        }
                    };
                    chi2(a.1).total_cmp(&chi2(b.1))
                });
            let Some((rank, trial)) = best else {
                table.row(vec![
                    robot.robot.clone(),
                    wanted.clone(),
                    "–".into(),
                    "not in the catalog for this experiment".into(),
                    "–".into(),
                ]);
                continue;
            };
            let named = matches!(d.verdict, Verdict::Explained | Verdict::PartlyExplained);
            let standing = match rank {
                Some(k) if named && k < d.tied.max(1) => match d.tied {
                    0 | 1 => "named".to_string(),
                    tied => format!("named, in a tie of {tied}"),
                },
                _ if trial.at_bound() => {
                    "fits only beyond its plausible range (a parameter at a bound)".into()
                }
                Some(k) => format!("ranked {} of {}", k + 1, d.ranked.len()),
                None if trial.error.is_some() => "failed".into(),
                None => "inert: cannot change these values beyond their s.d.".into(),
            };
            let fitted: Vec<String> = trial.parameters.iter().map(fitted_text).collect();
            table.row(vec![
                robot.robot.clone(),
                cause_at(trial),
                format!("{:.1}", trial.train_chi2),
                standing,
                fitted.join(", "),
            ]);
        }
    }
    table
}

/// The named causes, with their fitted values, in the dynamic regime: the largest resonance
/// of each drive as written and as extended (Fig. 10 is not data here: the paper says the
/// model predicted the lift resonance well and the swing resonance too high).
fn dynamics_table(robots: &[RobotDiagnosis], outcome: &mut Outcome) -> Table {
    let mut table = Table::new(
        "The named cause in the dynamic regime: largest resonance of each drive at rest \
         (hysteretic losses), as written and as extended. Fig. 10 (Sec. VI): the model \
         predicts the lift resonance well and the swing resonance above the measured one",
        &["robot", "DOF", "as written [Hz]", "extended [Hz]", "change"],
    );
    for (r, robot) in robots.iter().enumerate() {
        let Some(resonances) = &robot.resonances else {
            table.row(vec![
                robot.robot.clone(),
                "–".into(),
                "–".into(),
                "–".into(),
                "no cause named".into(),
            ]);
            continue;
        };
        let key = if r == 0 { "old" } else { "new" };
        for (dof, (written, extended)) in [("lift", resonances.lift), ("swing", resonances.swing)] {
            table.row(vec![
                robot.robot.clone(),
                dof.into(),
                format!("{written:.1}"),
                format!("{extended:.1}"),
                format!("{:+.1} %", 100.0 * (extended / written - 1.0)),
            ]);
            outcome.values.insert(
                format!("{key}_{dof}_resonance_change"),
                extended / written - 1.0,
            );
        }
    }
    table
}

/// The trial the verdict names (the pair when there is one, else the best, the simplest of
/// a tie); none when no cause is named.
fn extended(d: &Diagnosis) -> Option<&Trial> {
    match d.verdict {
        Verdict::Explained | Verdict::PartlyExplained => d.combined.as_ref().or(d.ranked.first()),
        _ => None,
    }
}

/// Σ d·F over the robot's tests from values laid out as its observations (each test's free
/// deflection, then each one's blocked force).
fn foot_work(robot: &RobotDiagnosis, values: &[f64]) -> f64 {
    let tests = robot.diagnosis.observations.values.len() / 2;
    (0..tests).map(|k| values[k] * values[tests + k]).sum()
}

/// Per test: the paper's two points and, dashed, the base model's and the extended model's
/// straight line from the blocked force to the free deflection.
fn plot_lines(
    robot: &RobotDiagnosis,
    extended: Option<&Trial>,
    index: usize,
    curves: &mut Vec<(String, Vec<f64>, Vec<f64>)>,
    measured: &mut Vec<plot::Measured>,
) {
    let obs = &robot.diagnosis.observations;
    let sigma = obs.sigma.as_deref().unwrap_or(&[]);
    let tests = obs.values.len() / 2;
    for k in 0..tests {
        let dof = obs.series[k].trim_start_matches("free_deflection.");
        let label = format!("{} {dof}", robot.robot);
        let color = 2 * index + k;
        let line = |values: &[f64]| {
            (
                vec![0.0, values[k] * 1e3],
                vec![values[tests + k] * 1e3, 0.0],
            )
        };
        let (x, y) = line(&robot.diagnosis.base.predicted);
        curves.push((format!("{label}: as written"), x, y));
        let (x, y) = line(extended.map_or(&robot.diagnosis.base.predicted, |t| &t.predicted));
        curves.push((format!("{label}: extended"), x, y));
        measured.push(plot::Measured {
            name: format!("{label}: Table IV (± s.d.)"),
            color,
            points: vec![
                plot::ErrorPoint {
                    x: 0.0,
                    y: obs.values[tests + k] * 1e3,
                    x_error: 0.0,
                    y_error: sigma.get(tests + k).copied().unwrap_or(0.0) * 1e3,
                },
                plot::ErrorPoint {
                    x: obs.values[k] * 1e3,
                    y: 0.0,
                    x_error: sigma.get(k).copied().unwrap_or(0.0) * 1e3,
                    y_error: 0.0,
                },
            ],
        });
    }
}
