//! Experiment 1, quasi-static foot trajectory (seed Fig. 6 c–e, h–j): sinusoidal drive of the
//! lift alone, the swing alone, and both 90° out of phase; the foot's path in the sagittal
//! (x–z) and frontal (y–z) planes. Quasi-static: a static equilibrium at each drive phase
//! (continuation from the previous one), valid far below the first resonance.

use mech_codegen::ir::Dimension;
use serde::Deserialize;

use super::leg::Leg;
use super::Error;
use crate::quantity::positive;
use crate::session::ModelSpec;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    #[serde(flatten)]
    pub model: ModelSpec,
    /// Amplitude of the model's drive input (`225 V`: the paper's 225 V peak-to-peak drive
    /// moves a bimorph tip ± its peak one-way deflection, i.e. ±V_rated in the model).
    pub amplitude: String,
    /// Drive frequency (`1 Hz`; only the time axis of the CSV depends on it).
    pub frequency: String,
    /// Phase of the swing drive ahead of the lift drive when both run, degrees.
    #[serde(default = "default_phase")]
    pub phase_deg: f64,
    /// Equilibria per cycle (a multiple of 4 hits the peaks exactly).
    #[serde(default = "default_points")]
    pub points: usize,
}

fn default_phase() -> f64 {
    90.0
}
fn default_points() -> usize {
    72
}

impl Spec {
    pub fn check(&self) -> Result<(), Error> {
        positive("amplitude", &self.amplitude, Dimension::VOLTAGE)?;
        positive("frequency", &self.frequency, Dimension::FREQUENCY)?;
        if self.points < 4 {
            return Err(Error::Key {
                message: "key `points`: expected at least 4 equilibria per cycle".into(),
            });
        }
        Ok(())
    }
}

/// One drive case: which actuators run.
const CASES: [(&str, bool, bool); 3] = [
    ("lift", true, false),
    ("swing", false, true),
    ("both", true, true),
];

/// The foot over one drive cycle of one case.
pub struct Cycle {
    /// Per sample: t, v_lift, v_swing, foot x, y, z, displacement dx, dy, dz (SI).
    pub rows: Vec<Vec<f64>>,
    /// Displacement from rest at the +peak of the drive (a quarter period in).
    pub at_peak: [f64; 3],
}

impl Cycle {
    /// The displacement along `axis` (0 = x) at every sample, in mm.
    pub(crate) fn displacement_mm(&self, axis: usize) -> Vec<f64> {
        self.rows.iter().map(|row| row[6 + axis] * 1e3).collect()
    }
}

/// The drive case's cycle by continuation: each phase's equilibrium starts from the
/// previous one's.
fn cycle(
    spec: &Spec,
    leg: &Leg,
    (lift_on, swing_on): (bool, bool),
    (amplitude, frequency): (f64, f64),
    rest_q: &[f64],
) -> Result<Cycle, Error> {
    let rest = leg.foot_at(rest_q, &leg.inputs(0.0, 0.0));
    let phase = spec.phase_deg.to_radians();
    let mut q = rest_q.to_vec();
    let mut rows = Vec::new();
    let mut at_peak = [0.0; 3];
    for k in 0..=spec.points {
        let t = k as f64 / (spec.points as f64 * frequency);
        let angle = std::f64::consts::TAU * frequency * t;
        let lift = if lift_on {
            amplitude * angle.sin()
        } else {
            0.0
        };
        let swing = match (lift_on, swing_on) {
            (true, true) => amplitude * (angle + phase).sin(),
            (false, true) => amplitude * angle.sin(),
            _ => 0.0,
        };
        let inputs = leg.inputs(lift, swing);
        q = leg
            .equilibrium(&q, &inputs, &[])
            .map_err(|e| {
                Error::from(e).within(format!("v_lift = {lift:.1} V, v_swing = {swing:.1} V"))
            })?
            .q;
        let foot = leg.foot_at(&q, &inputs);
        let d = [0, 1, 2].map(|i| foot[i] - rest[i]);
        if 4 * k == spec.points {
            at_peak = d;
        }
        rows.push(vec![
            t, lift, swing, foot[0], foot[1], foot[2], d[0], d[1], d[2],
        ]);
    }
    Ok(Cycle { rows, at_peak })
}

pub(crate) fn peak_to_peak(values: &[f64]) -> f64 {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    hi - lo
}

/// The foot over one drive cycle of each case (lift alone, swing alone, both), from the
/// rest equilibrium under gravity.
pub struct Trajectories {
    pub model_name: String,
    /// Drive amplitude (V) and frequency (Hz).
    pub amplitude: f64,
    pub frequency: f64,
    /// Per drive case (`lift`, `swing`, `both`): its name and cycle.
    pub cycles: Vec<(&'static str, Cycle)>,
}

/// Finds the rest equilibrium, then each drive case's cycle by continuation from it.
pub fn compute(spec: &Spec) -> Result<Trajectories, Error> {
    let amplitude = positive("amplitude", &spec.amplitude, Dimension::VOLTAGE)?;
    let frequency = positive("frequency", &spec.frequency, Dimension::FREQUENCY)?;
    let leg = Leg::open(&spec.model)?;
    let rest_q = leg.equilibrium(&leg.q0, &leg.inputs(0.0, 0.0), &[])?.q;
    let cycles = CASES
        .into_iter()
        .map(|(name, lift_on, swing_on)| {
            cycle(
                spec,
                &leg,
                (lift_on, swing_on),
                (amplitude, frequency),
                &rest_q,
            )
            .map(|cycle| (name, cycle))
            .map_err(|e| e.within(format!("{name} drive")))
        })
        .collect::<Result<_, Error>>()?;
    Ok(Trajectories {
        model_name: leg.model().name().to_string(),
        amplitude,
        frequency,
        cycles,
    })
}
