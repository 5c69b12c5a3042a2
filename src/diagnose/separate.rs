//! Which measurement would tell tied causes apart (`mech diagnose`'s ties).
//!
//! Consumes: the model spec and, per tied cause, a leg with its fitted values applied.
//! Produces: per probe — a standard test of a two-actuator leg (each degree of freedom's
//! force/deflection curve, the foot over a grid of drives, the frequency response of both
//! drives) — the separation of the closest two causes, χ² = Σ((a − b)/σ)² between their
//! predictions at the probe's noise, best first. A χ² above 9 (3σ) separates them; the
//! report names the best probe.
//!
//! The noise levels are typical of the reference paper's instruments, stated in each probe's
//! description (a force sensor of ~0.3 mN resolution, a foot position to ~5 µm, a transfer
//! function to 2 % and 1°); a user's own noise scales the χ² by (σ/σ_user)².

use std::path::Path;

use serde::Serialize;

use super::data::MeasuredData;
use super::experiment::{
    Experiment, Extensions, ForceDeflectionTest, FrequencyResponse, Kind, QuasiStatic,
};
use crate::experiments::leg::{Dof, Leg};
use crate::frequency::{Channel, Damping};
use crate::session::ModelSpec;

/// A χ² above this separates two causes (3σ).
pub const SEPARATES: f64 = 9.0;

/// One probe and how well it separates the closest two of the tied causes.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Separation {
    /// What to measure, with the noise assumed (`lift force/deflection at 225 V, …`).
    pub probe: String,
    /// χ² between the predictions of the two tied causes that this probe tells apart least.
    pub chi2: f64,
}

/// A standard test: the experiment, placeholder data giving its rows (drives, distances,
/// frequencies; the measured values are not read), and what it is.
struct Probe {
    description: String,
    experiment: Experiment,
    data: MeasuredData,
}

/// Drive amplitude of the probes (the paper's force tests, Sec. V-A).
const VOLTS: f64 = 225.0;

/// The probes for `spec`'s model (a leg with lift and swing drives and a foot).
fn probes(spec: &ModelSpec) -> Option<Vec<Probe>> {
    let experiment = |title: &str, kind: Kind| Experiment {
        title: title.to_string(),
        model: spec.clone(),
        kind,
    };
    let data = |csv: String| MeasuredData::parse(Path::new("(probe)"), csv.as_bytes()).ok();
    let mut probes = Vec::new();
    for dof in [Dof::Lift, Dof::Swing] {
        // The sensor every 127 µm (the paper's stage) out to 4 mm, beyond the free foot.
        let mut csv = String::from("distance [um], force [mN]\n");
        for k in 0..32 {
            csv += &format!("{}, 0\n", 127 * k);
        }
        probes.push(Probe {
            description: format!(
                "{} force/deflection at {VOLTS} V (sensor every 127 µm, 0.3 mN noise)",
                dof.name()
            ),
            experiment: experiment(
                "probe",
                Kind::ForceDeflection(ForceDeflectionTest {
                    dof,
                    voltage: format!("{VOLTS} V"),
                    off_axis_fraction: 0.0,
                    noise: Some("0.3 mN".into()),
                }),
            ),
            data: data(csv)?,
        });
    }
    let mut csv = String::from("v_lift [V], v_swing [V], foot.x [mm], foot.y [mm], foot.z [mm]\n");
    for lift in [-1.0, -0.5, 0.0, 0.5, 1.0] {
        for swing in [-1.0, -0.5, 0.0, 0.5, 1.0] {
            csv += &format!("{}, {}, 0, 0, 0\n", lift * VOLTS, swing * VOLTS);
        }
    }
    probes.push(Probe {
        description: format!(
            "the foot at 5 × 5 drives within ±{VOLTS} V on both actuators (5 µm noise)"
        ),
        experiment: experiment(
            "probe",
            Kind::QuasiStatic(QuasiStatic {
                outputs: vec!["foot.x".into(), "foot.y".into(), "foot.z".into()],
                noise: vec!["5 um".into(); 3],
            }),
        ),
        data: data(csv)?,
    });
    // 40 frequencies, log-spaced over 5–300 Hz (both resonances of a microrobot leg).
    let mut csv = String::from(
        "frequency [Hz], gain.lift [mm/V], phase.lift [deg], gain.swing [mm/V], phase.swing [deg]\n",
    );
    for k in 0..40 {
        let frequency = 5.0 * 60f64.powf(k as f64 / 39.0);
        csv += &format!("{frequency}, 1, 0, 1, 0\n");
    }
    let channel = |name: &str, input: &str, output: &str| Channel {
        name: name.into(),
        input: input.into(),
        output: output.into(),
    };
    probes.push(Probe {
        description: "the frequency response of both drives to the foot, 5–300 Hz (2 % gain, \
                      1° phase noise)"
            .into(),
        experiment: experiment(
            "probe",
            Kind::FrequencyResponse(FrequencyResponse {
                input: None,
                output: None,
                channel: vec![
                    channel("lift", "v_lift", "foot.z"),
                    channel("swing", "v_swing", "foot.x"),
                ],
                damping: Damping::default(),
                gain_noise: Some("2 %".into()),
                phase_noise: Some("1 deg".into()),
            }),
        ),
        data: data(csv)?,
    });
    Some(probes)
}

/// The probes that `legs` (one per tied cause, fitted values applied, with the extensions
/// their fits set) can all be run on, each with the separation of the closest two; best
/// first. Empty for fewer than two legs or a model that is not a two-actuator leg.
pub fn separations(spec: &ModelSpec, legs: &[(Leg, Extensions)]) -> Vec<Separation> {
    if legs.len() < 2 || legs.iter().any(|(leg, _)| leg.require_hamr().is_err()) {
        return Vec::new();
    }
    let Some(probes) = probes(spec) else {
        return Vec::new();
    };
    let mut out: Vec<Separation> = probes
        .into_iter()
        .filter_map(|probe| {
            let predictions = legs
                .iter()
                .map(|(leg, extensions)| {
                    let observations = probe.experiment.observations(leg, &probe.data).ok()?;
                    let sigma = observations.sigma.clone()?;
                    let predicted = probe
                        .experiment
                        .predict(leg, &probe.data, &observations, extensions)
                        .ok()?;
                    Some((predicted, sigma))
                })
                .collect::<Option<Vec<_>>>()?;
            let mut closest = f64::INFINITY;
            for (i, (a, sigma)) in predictions.iter().enumerate() {
                for (b, _) in &predictions[i + 1..] {
                    let chi2: f64 = a
                        .iter()
                        .zip(b)
                        .zip(sigma)
                        .map(|((a, b), s)| ((a - b) / s).powi(2))
                        .sum();
                    closest = closest.min(chi2);
                }
            }
            closest.is_finite().then_some(Separation {
                probe: probe.description,
                chi2: closest,
            })
        })
        .collect();
    out.sort_by(|a, b| b.chi2.total_cmp(&a.chi2));
    out
}
