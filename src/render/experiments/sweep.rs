//! Rendering of `kind = "sweep"` experiment results: the tables, CSV files and plots
//! of [`crate::experiments::sweep`]'s computed data.
//!
//! Consumes: the kind's spec and what its `compute` returns. Produces: an [`Outcome`] and
//! the files it lists.

use super::shared::csv;
use crate::experiments::leg::Dof;
use crate::experiments::sweep::{compute, keys, Series, Spec, SweepPoint};
use crate::experiments::Error;
use crate::render::plot::{self, CurveStyle, Star};
use crate::render::report::Outcome;
use crate::render::table::Table;
use mech_codegen::ir::transform::AXES;
use std::path::Path;

pub fn run(spec: &Spec, dir: &Path) -> Result<Outcome, Error> {
    let sweep = compute(spec)?;
    let voltage = sweep.voltage;
    let keys = keys(&spec.series);
    let mut outcome = Outcome::with_method(method_text(spec, voltage));
    let mut chosen_table = Table::new(
        "Chosen designs (the stars of Fig. 8): the models at their own crank arms",
        &[
            "robot",
            "actuator",
            "DOF",
            "arm [mm]",
            "T model",
            "T at rest",
            "T paper",
            "lever/arm",
            "F [mN]",
            "d [mm]",
            "F·d [µJ]",
            "F·d/(F_b δ_f)",
        ],
    );
    let mut figure = Figure::default();
    for (k, (series, curve)) in spec.series.iter().zip(&sweep.curves).enumerate() {
        let key = &keys[k];
        let lever = series.lever(k)?;
        let chosen = curve
            .iter()
            .find(|p| p.chosen)
            .copied()
            .ok_or(Error::ChosenDesignMissing)?;
        chosen_table.row(vec![
            series.name.clone(),
            series.actuator.clone(),
            series.dof.name().into(),
            format!("{:.4}", chosen.arm * 1e3),
            format!("{:.2}", chosen.ratio),
            format!("{:.2}", chosen.ratio_rest),
            series.paper_ratio.map_or("–".into(), |r| format!("{r}")),
            lever_text(lever, &chosen),
            format!("{:.2}", chosen.blocked_force * 1e3),
            format!("{:.3}", chosen.free_deflection * 1e3),
            format!("{:.1}", chosen.work * 1e6),
            format!("{:.3}", chosen.normalized),
        ]);
        for (name, value) in [
            ("arm", chosen.arm),
            ("ratio", chosen.ratio),
            ("ratio_y", chosen.ratio_y),
            ("ratio_rest", chosen.ratio_rest),
            ("blocked_force", chosen.blocked_force),
            ("free_deflection", chosen.free_deflection),
            ("work", chosen.work),
            ("normalized", chosen.normalized),
        ] {
            outcome.values.insert(format!("{key}_chosen_{name}"), value);
        }
        outcome
            .values
            .insert(format!("{key}_points"), curve.len() as f64);
        outcome.notes.push(observe(series, curve));
        write_curve(&mut outcome, dir, key, lever, curve)?;
        outcome.tables.push(curve_table(series, lever, curve));
        figure.add(k, series, curve, &chosen);
    }
    outcome.tables.insert(0, chosen_table);
    let path = dir.join("ratio_sweep.svg");
    let title =
        format!("Work done by the foot (F·d) against the transmission ratio at {voltage} V");
    let plot = plot::XyPlot {
        styles: Some(&figure.styles),
        stars: &figure.stars,
        ..plot::XyPlot::new(
            &title,
            "transmission ratio T (foot per actuator displacement; lift: z, swing: x)",
            "F·d [µJ]",
            &figure.curves,
        )
    }
    .render(&path)?;
    outcome.add_plot(plot);
    if !sweep.failed.is_empty() {
        outcome.notes.push(format!(
            "Left out (no converged equilibrium): {}",
            sweep.failed.join("; ")
        ));
    }
    Ok(outcome)
}

fn method_text(spec: &Spec, voltage: f64) -> String {
    format!(
        "For each curve, the model's crank arm ({} for lift, {} for swing; the crank-slider \
         moves with the arm's input hinge, P and the leg stay, see the model headers) at {} \
         values evenly spaced in 1/arm, plus the model's own arm (the chosen design, ★). At \
         each arm: the transmission ratio T from the model's kinematics, foot displacement \
         per actuator displacement at the zero configuration (lift: foot {}, the paper's \
         T_l = s_o/l_i; swing: foot {}, T_s = s_o/s_i), and at {voltage} V the blocked \
         force F and free deflection d along that axis, by the procedure of experiments 2 \
         and 4 (foot held at its rest position along the axis by a frictionless sensor; \
         free foot), F·d and F·d/(F_b δ_f) with the model's actuator. The geometric \
         lever/arm uses the series' output lever (lift: l_o, the paper's T_l* = l_o/l_i; \
         swing: s_o).",
        Dof::Lift.arm(),
        Dof::Swing.arm(),
        spec.points,
        AXES[Dof::Lift.axis()],
        AXES[Dof::Swing.axis()],
    )
}

/// The geometric ratio lever/arm at `point` (NaN without a lever).
fn geometric_ratio(lever: Option<f64>, point: &SweepPoint) -> f64 {
    lever.map_or(f64::NAN, |l| l / point.arm)
}

fn lever_text(lever: Option<f64>, point: &SweepPoint) -> String {
    let ratio = geometric_ratio(lever, point);
    if ratio.is_finite() {
        format!("{ratio:.2}")
    } else {
        "–".into()
    }
}

/// One curve's points as a table, the chosen design starred.
fn curve_table(series: &Series, lever: Option<f64>, curve: &[SweepPoint]) -> Table {
    let mut table = Table::new(
        &format!(
            "{} ({}): work at the foot against the {} ratio",
            series.label(),
            series.actuator,
            series.dof.name()
        ),
        &[
            "arm [mm]",
            "T (kinematic)",
            "T at rest",
            "lever/arm",
            "F [mN]",
            "F·T [mN]",
            "d [mm]",
            "F·d [µJ]",
            "F·d/(F_b δ_f)",
            "",
        ],
    );
    for p in curve {
        table.row(vec![
            format!("{:.3}", p.arm * 1e3),
            format!("{:.2}", p.ratio),
            format!("{:.2}", p.ratio_rest),
            lever_text(lever, p),
            format!("{:.2}", p.blocked_force * 1e3),
            format!("{:.0}", p.blocked_force * p.ratio * 1e3),
            format!("{:.3}", p.free_deflection * 1e3),
            format!("{:.1}", p.work * 1e6),
            format!("{:.3}", p.normalized),
            if p.chosen { "★ chosen" } else { "" }.into(),
        ]);
    }
    table
}

/// `KEY.csv`: one row per point, SI units.
fn write_curve(
    outcome: &mut Outcome,
    dir: &Path,
    key: &str,
    lever: Option<f64>,
    curve: &[SweepPoint],
) -> Result<(), Error> {
    let rows: Vec<Vec<f64>> = curve
        .iter()
        .map(|p| {
            vec![
                p.arm,
                p.ratio,
                p.ratio_y,
                p.ratio_rest,
                geometric_ratio(lever, p),
                p.blocked_force,
                p.free_deflection,
                p.work,
                p.normalized,
                if p.chosen { 1.0 } else { 0.0 },
            ]
        })
        .collect();
    csv(
        outcome,
        dir,
        &format!("{key}.csv"),
        &[
            "arm",
            "ratio",
            "ratio_y",
            "ratio_rest",
            "lever_over_arm",
            "blocked_force",
            "free_deflection",
            "work",
            "normalized",
            "chosen",
        ],
        &rows,
    )
}

/// Fig. 8: work against ratio, one colour per robot (cyan first, then blue), lift dashed,
/// the chosen designs starred.
#[derive(Default)]
struct Figure {
    curves: Vec<(String, Vec<f64>, Vec<f64>)>,
    styles: Vec<CurveStyle>,
    stars: Vec<Star>,
    robots: Vec<String>,
}

impl Figure {
    fn add(&mut self, index: usize, series: &Series, curve: &[SweepPoint], chosen: &SweepPoint) {
        let robot = match self.robots.iter().position(|r| *r == series.name) {
            Some(robot) => robot,
            None => {
                self.robots.push(series.name.clone());
                self.robots.len() - 1
            }
        };
        const COLOURS: [usize; 10] = [9, 0, 1, 2, 3, 4, 5, 6, 7, 8];
        self.styles.push(CurveStyle {
            color: COLOURS[robot % COLOURS.len()],
            dashed: series.dof == Dof::Lift,
        });
        self.stars.push(Star {
            curve: index,
            x: chosen.ratio,
            y: chosen.work * 1e6,
        });
        self.curves.push((
            format!("{} ({})", series.label(), series.actuator),
            curve.iter().map(|p| p.ratio).collect(),
            curve.iter().map(|p| p.work * 1e6).collect(),
        ));
    }
}

/// What one curve shows, in the paper's terms: does the work fall as T rises; how far the
/// blocked force departs from `∝ 1/T` (`F·T` of a rigid lever is the actuator's blocked
/// force); how the free deflection grows against T.
fn observe(series: &Series, curve: &[SweepPoint]) -> String {
    let (Some(first), Some(last)) = (curve.first(), curve.last()) else {
        return format!("Model, {}: no points", series.label());
    };
    let rises: Vec<String> = curve
        .windows(2)
        .filter(|w| w[1].work > w[0].work && w[1].ratio > w[0].ratio)
        .map(|w| format!("{:.1}–{:.1}", w[0].ratio, w[1].ratio))
        .collect();
    let trend = if rises.is_empty() {
        "falls monotonically as T rises".to_string()
    } else {
        format!(
            "does NOT fall monotonically as T rises (it rises over T = {})",
            rises.join(", ")
        )
    };
    let extent = |values: &mut dyn Iterator<Item = f64>| {
        values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        })
    };
    let (ft_min, ft_max) = extent(&mut curve.iter().map(|p| p.blocked_force * p.ratio));
    let (fr_min, fr_max) = extent(&mut curve.iter().map(|p| p.blocked_force * p.ratio_rest * 1e3));
    let (n_min, n_max) = extent(&mut curve.iter().map(|p| p.normalized));
    let peak = curve
        .iter()
        .max_by(|a, b| a.free_deflection.total_cmp(&b.free_deflection))
        .map_or(f64::NAN, |p| p.ratio);
    format!(
        "Model, {}: F·d {trend}, from {:.1} µJ at T = {:.1} to {:.1} µJ at T = {:.1}. \
         Blocked force ∝ 1/T: F·T = {:.0}–{:.0} mN, and {fr_min:.1}–{fr_max:.1} mN with T at \
         the rest equilibrium (a rigid lever: the actuator's F_b V/V_rated = {:.1} mN). \
         d grows {:.2}× while T grows {:.2}× (largest d at T = {peak:.1}). \
         F·d/(F_b δ_f) = {n_min:.2}–{n_max:.2}.",
        series.label(),
        first.work * 1e6,
        first.ratio,
        last.work * 1e6,
        last.ratio,
        ft_min * 1e3,
        ft_max * 1e3,
        first.actuator_force * 1e3,
        last.free_deflection / first.free_deflection,
        last.ratio / first.ratio,
    )
}
