//! Experiment 3, the transmission-ratio sweep (seed Fig. 8, Sec. V.B): the work done by the
//! foot, blocked force × free deflection exactly as in experiments 2 and 4
//! ([`ForceTest`] with the sensor at the rest position only), against the transmission
//! ratio for a given actuator. The ratio is changed through the model's crank arm (`lift_arm`
//! or `swing_arm`) and measured from the model's own kinematics at the zero configuration
//! (foot displacement per actuator displacement along the test axis: lift z, swing x).

use mech_codegen::ir::Dimension;
use serde::Deserialize;

use super::force::actuator_work;
use super::leg::{self, Dof, ForceTest, Leg, Sensor};
use super::Error;
use crate::output::file_stem;
use crate::parallel::{parallel, threads};
use crate::quantity::positive;
use crate::session::ModelSpec;

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
    pub(crate) fn label(&self) -> String {
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
    pub(crate) fn lever(&self, k: usize) -> Result<Option<f64>, Error> {
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
    let arm = leg
        .param(dof.arm())
        .ok_or_else(|| leg::Error::NoParameter {
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
pub(crate) fn keys(series: &[Series]) -> Vec<String> {
    let mut keys: Vec<String> = Vec::new();
    for (k, s) in series.iter().enumerate() {
        let key = format!(
            "{}_{}",
            file_stem(&s.model.path, "experiment"),
            s.dof.name()
        );
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
