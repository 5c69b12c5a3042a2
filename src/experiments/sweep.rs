//! Experiment 3, the transmission-ratio sweep (seed Fig. 8, Sec. V.B): the work done by the
//! foot, blocked force × free deflection exactly as in experiments 2 and 4
//! ([`force_deflection`] with the sensor at the rest position only), against the transmission
//! ratio for a given actuator. The ratio is changed through the model's crank arm (`lift_arm`
//! or `swing_arm`) and measured from the model's own kinematics at the zero configuration
//! (foot displacement per actuator displacement along the test axis: lift z, swing x).

use std::path::Path;

use mech_codegen::ir::Dimension;
use serde::Deserialize;

use super::force::actuator_work;
use super::leg::{Dof, ForceTest, Leg, Sensor};
use super::Error;
use super::{csv, Outcome, Table};
use crate::parallel::{parallel, threads};
use crate::quantity::positive;
use crate::render::plot::{self, CurveStyle, Star};
use crate::session::ModelSpec;
use mech_codegen::ir::transform::AXES;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// Peak drive voltage of the model input (`225 V`).
    pub voltage: String,
    /// Arm values per series, evenly spaced in 1/arm (so roughly evenly in ratio); the
    /// chosen design (the model's own arm) is added to them.
    #[serde(default = "default_points")]
    pub points: usize,
    /// The curves: one robot, actuator and degree of freedom each.
    pub series: Vec<Series>,
}

/// One curve of the sweep.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Series {
    /// The robot, e.g. `HAMR-V2.0` (curves of one robot share a colour in the plot).
    pub name: String,
    /// The actuator label, e.g. `PS 'a' (270 mN, 247 um)`; the values are the model's.
    pub actuator: String,
    #[serde(flatten)]
    pub model: ModelSpec,
    /// `lift` (arm `lift_arm`, foot z) or `swing` (arm `swing_arm`, foot x).
    pub dof: Dof,
    /// The swept crank arm, `["0.25 mm", "1.2 mm"]` (either order).
    pub arm: Vec<String>,
    /// The output lever of the geometric ratio `lever/arm` printed beside the measured one
    /// (lift: l_o, the paper's T_l* = l_o/l_i; swing: s_o, T_s = s_o/s_i).
    pub lever: Option<String>,
    /// The paper's chosen ratio for this curve (its star), e.g. 16.5, for the table.
    pub paper_ratio: Option<f64>,
}

fn default_points() -> usize {
    16
}

impl Series {
    fn label(&self) -> String {
        format!("{} {}", self.name, self.dof.name())
    }
    /// The swept arm range `(low, high)` in SI, checked.
    fn arm_range(&self, k: usize) -> Result<(f64, f64), Error> {
        let key = format!("series[{k}].arm");
        let [a, b] = self.arm.as_slice() else {
            return Err(Error::Key {
                message: format!(
                "key `{key}`: expected two lengths, e.g. [\"0.25 mm\", \"1.2 mm\"], got {} values",
                self.arm.len()
            ),
            });
        };
        let (a, b) = (
            positive(&key, a, Dimension::LENGTH)?,
            positive(&key, b, Dimension::LENGTH)?,
        );
        if a == b {
            return Err(Error::Key {
                message: format!("key `{key}`: the two ends are equal"),
            });
        }
        Ok((a.min(b), a.max(b)))
    }
    fn lever(&self, k: usize) -> Result<Option<f64>, Error> {
        self.lever
            .as_deref()
            .map(|l| positive(&format!("series[{k}].lever"), l, Dimension::LENGTH))
            .transpose()
            .map_err(Error::from)
    }
}

impl Spec {
    pub fn check(&self) -> Result<(), Error> {
        positive("voltage", &self.voltage, Dimension::VOLTAGE)?;
        if !(2..=200).contains(&self.points) {
            return Err(Error::Key {
                message: format!(
                    "key `points`: expected 2 to 200 arm values per series, got {}",
                    self.points
                ),
            });
        }
        if self.series.is_empty() {
            return Err(Error::Key {
                message: "key `series`: expected at least one [[series]] table".into(),
            });
        }
        for (k, series) in self.series.iter().enumerate() {
            series.arm_range(k)?;
            series.lever(k)?;
            if let Some(r) = series.paper_ratio {
                if !(r.is_finite() && r > 0.0) {
                    return Err(Error::Key {
                        message: format!(
                            "key `series[{k}].paper_ratio`: expected a positive ratio, got {r}"
                        ),
                    });
                }
            }
        }
        Ok(())
    }
}

/// The leg at one crank arm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepPoint {
    /// The crank arm (m).
    pub arm: f64,
    /// Foot displacement along the test axis per actuator displacement, magnitude, at the
    /// zero configuration (lift: the paper's T_l, foot z; swing: T_s, foot x).
    pub ratio: f64,
    /// The same for foot y (lift: the paper's T_l* = l_o/l_i).
    pub ratio_y: f64,
    /// As `ratio`, at the rest equilibrium (gravity, HAMR-V2.0's actuator preload), where
    /// the blocked force is measured.
    pub ratio_rest: f64,
    /// The actuator's blocked force at the drive, `F_b V/V_rated` (N; NaN if the model has
    /// no `F_b`, `V_rated`): `F·T` of a rigid lever.
    pub actuator_force: f64,
    pub blocked_force: f64,
    pub free_deflection: f64,
    /// `F·d`, as [`super::leg::ForceDeflection::work`].
    pub work: f64,
    /// `F·d/(F_b δ_f)` with the model's actuator.
    pub normalized: f64,
    /// The model's own arm (no arm set).
    pub chosen: bool,
}

/// The leg of `series` with the crank arm at `arm` (`None`: the model's own) at `voltage`:
/// the ratio from the kinematics and the blocked force and free deflection of experiment 2.
pub fn sweep_point(series: &Series, voltage: f64, arm: Option<f64>) -> Result<SweepPoint, Error> {
    let dof = series.dof;
    let set: Vec<(&str, f64)> = arm.map(|a| (dof.arm(), a)).into_iter().collect();
    let leg = Leg::open_with(&series.model, &set)?;
    let arm = leg.param(dof.arm()).ok_or_else(|| Error::NoParameter {
        model: series.model.path.display().to_string(),
        name: dof.arm().to_string(),
        purpose: Some(format!("the crank arm that sets the {} ratio", dof.name())),
    })?;
    let ratio = leg.kinematic_ratio(&leg.q0, dof, dof.axis())?.abs();
    let ratio_y = leg.kinematic_ratio(&leg.q0, dof, 1)?.abs();
    let test = ForceTest::new(dof, voltage, Sensor::Blocked).run(&leg)?;
    let ratio_rest = leg.kinematic_ratio(&test.rest_q, dof, dof.axis())?.abs();
    let actuator_force = match (leg.param("F_b"), leg.param("V_rated")) {
        (Some(f), Some(v)) => f * voltage / v,
        _ => f64::NAN,
    };
    Ok(SweepPoint {
        arm,
        ratio,
        ratio_y,
        ratio_rest,
        actuator_force,
        blocked_force: test.blocked_force(),
        free_deflection: test.free_deflection,
        work: test.work(),
        normalized: test.work() / actuator_work(&leg)?,
        chosen: set.is_empty(),
    })
}

/// `n` arms from `low` to `high`, evenly spaced in 1/arm.
fn arms(low: f64, high: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| {
            let t = k as f64 / (n - 1) as f64;
            1.0 / (1.0 / high + t * (1.0 / low - 1.0 / high))
        })
        .collect()
}

/// Short names of the series for values and files: `{model stem}_{dof}`, numbered on repeats.
fn keys(series: &[Series]) -> Vec<String> {
    let mut keys: Vec<String> = Vec::new();
    for (k, s) in series.iter().enumerate() {
        let key = format!("{}_{}", super::stem(&s.model.path), s.dof.name());
        let key = if keys.contains(&key) {
            format!("{key}_{}", k + 1)
        } else {
            key
        };
        keys.push(key);
    }
    keys
}

/// The sweep's results: per series its points (sorted by ratio, the chosen design among
/// them), and the points left out because their equilibrium did not converge.
pub struct Sweep {
    pub voltage: f64,
    pub curves: Vec<Vec<SweepPoint>>,
    pub failed: Vec<String>,
}

/// Runs every (series, arm) point on all cores. The model is compiled per point
/// (milliseconds), so that the points are independent.
pub fn compute(spec: &Spec) -> Result<Sweep, Error> {
    let voltage = positive("voltage", &spec.voltage, Dimension::VOLTAGE)?;
    let mut jobs = Vec::new();
    for (k, series) in spec.series.iter().enumerate() {
        let (low, high) = series.arm_range(k)?;
        jobs.push((k, None));
        jobs.extend(
            arms(low, high, spec.points)
                .into_iter()
                .map(|a| (k, Some(a))),
        );
    }
    let results = parallel(jobs, threads(), |(k, arm)| {
        (k, arm, sweep_point(&spec.series[k], voltage, arm))
    });
    let mut curves: Vec<Vec<SweepPoint>> = vec![Vec::new(); spec.series.len()];
    let mut failed: Vec<String> = Vec::new();
    for (k, arm, result) in results {
        let series = &spec.series[k];
        match (result, arm) {
            (Ok(point), _) => curves[k].push(point),
            (Err(e), None) => {
                return Err(Error::Key {
                    message: format!("series `{}` at the model's own arm: {e}", series.label()),
                })
            }
            // A sweep point that does not converge is left out and reported, not fatal: the
            // range may reach arms where the leg folds over.
            (Err(e), Some(a)) => failed.push(format!(
                "{} at {} = {:.3} mm: {e}",
                series.label(),
                series.dof.arm(),
                a * 1e3
            )),
        }
    }
    for curve in &mut curves {
        curve.sort_by(|a, b| a.ratio.total_cmp(&b.ratio));
    }
    Ok(Sweep {
        voltage,
        curves,
        failed,
    })
}

pub fn run(spec: &Spec, dir: &Path) -> Result<Outcome, Error> {
    let sweep = compute(spec)?;
    let voltage = sweep.voltage;
    let keys = keys(&spec.series);
    let mut outcome = Outcome {
        method: method_text(spec, voltage),
        ..Outcome::default()
    };
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
    plot::plot_xy_styled(
        &path,
        &format!("Work done by the foot (F·d) against the transmission ratio at {voltage} V"),
        "transmission ratio T (foot per actuator displacement; lift: z, swing: x)",
        "F·d [µJ]",
        &figure.curves,
        &figure.styles,
        &figure.stars,
    )?;
    outcome.plots.push(path);
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
