//! The outputs a study can ask for: scalar features of the existing analyses, computed by
//! them on one perturbed model — the HAMR force/deflection test of experiments 2 and 4 (free
//! stroke, blocked force, `F·d`), the resonance and Q of the linear model's response (the
//! Bode experiment's), and the undamped natural frequencies of the linearization.
//!
//! Consumes: a [`Leg`] with the sample's parameter values and the study's [`Settings`].
//! Produces: one number per [`Feature`] (SI units), or the analysis's error.

use mech_runtime::FlexureDamping;

use super::SampleError;
use crate::experiments::leg::{self, Dof, ForceDeflection, ForceTest, Leg, Sensor};
use crate::frequency;

/// One output of a study.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feature {
    /// The foot's free travel along the dof's axis at the drive voltage (m).
    FreeStroke(Dof),
    /// The on-axis force with the sensor at the foot's rest position (N).
    BlockedForce(Dof),
    /// Blocked force × free stroke, Table IV's `F·d` (J).
    Work(Dof),
    /// The strongest resonance of drive → foot (lift: foot z, swing: foot x), linear model
    /// with hysteretic flexure losses (Hz).
    Resonance(Dof),
    /// Its quality factor (NaN when a −3 dB point lies outside the frequency range).
    QualityFactor(Dof),
    /// The `k`-th (1-based) undamped natural frequency of the linearization at rest (Hz).
    NaturalFrequency(usize),
}

/// What the features need besides the model.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Settings {
    /// Drive voltage of the force tests (V).
    pub voltage: Option<f64>,
    /// The frequency grid searched for resonances (Hz).
    pub frequencies: Option<Vec<f64>>,
}

/// The names a study writes, for messages.
pub const NAMES: &str = "free_stroke.DOF, blocked_force.DOF, work.DOF, resonance.DOF, \
                         quality_factor.DOF (DOF lift or swing), natural_frequency.K (K = 1, 2, …)";

impl Feature {
    /// `free_stroke.lift`, `natural_frequency.2`, …; `None` for any other text.
    pub fn parse(text: &str) -> Option<Feature> {
        let (kind, which) = text.trim().split_once('.')?;
        let dof = match which {
            "lift" => Some(Dof::Lift),
            "swing" => Some(Dof::Swing),
            _ => None,
        };
        Some(match (kind, dof) {
            ("free_stroke", Some(d)) => Feature::FreeStroke(d),
            ("blocked_force", Some(d)) => Feature::BlockedForce(d),
            ("work", Some(d)) => Feature::Work(d),
            ("resonance", Some(d)) => Feature::Resonance(d),
            ("quality_factor", Some(d)) => Feature::QualityFactor(d),
            ("natural_frequency", None) => match which.parse::<usize>() {
                Ok(k) if k >= 1 => Feature::NaturalFrequency(k),
                _ => return None,
            },
            _ => return None,
        })
    }

    pub fn name(self) -> String {
        match self {
            Feature::FreeStroke(d) => format!("free_stroke.{}", d.name()),
            Feature::BlockedForce(d) => format!("blocked_force.{}", d.name()),
            Feature::Work(d) => format!("work.{}", d.name()),
            Feature::Resonance(d) => format!("resonance.{}", d.name()),
            Feature::QualityFactor(d) => format!("quality_factor.{}", d.name()),
            Feature::NaturalFrequency(k) => format!("natural_frequency.{k}"),
        }
    }

    /// The SI unit of its values (`""`: a plain number).
    pub fn unit(self) -> &'static str {
        match self {
            Feature::FreeStroke(_) => "m",
            Feature::BlockedForce(_) => "N",
            Feature::Work(_) => "J",
            Feature::Resonance(_) | Feature::NaturalFrequency(_) => "Hz",
            Feature::QualityFactor(_) => "",
        }
    }

    /// Whether it drives a HAMR leg's ports (`v_lift`, `v_swing`, `foot`).
    pub fn is_hamr(self) -> bool {
        !matches!(self, Feature::NaturalFrequency(_))
    }

    /// The force test it reads, if any.
    fn force_dof(self) -> Option<Dof> {
        match self {
            Feature::FreeStroke(d) | Feature::BlockedForce(d) | Feature::Work(d) => Some(d),
            _ => None,
        }
    }
}

/// Every feature of `features` on `leg`, in order. Each force test and the linearization are
/// run once however many features read them.
pub fn evaluate(
    leg: &Leg,
    features: &[Feature],
    settings: &Settings,
) -> Result<Vec<f64>, SampleError> {
    let mut tests: Vec<(Dof, ForceDeflection)> = Vec::new();
    for dof in features.iter().filter_map(|f| f.force_dof()) {
        if !tests.iter().any(|(d, _)| *d == dof) {
            let voltage = settings.voltage.unwrap_or(0.0);
            tests.push((dof, ForceTest::new(dof, voltage, Sensor::Blocked).run(leg)?));
        }
    }
    let test = |dof: Dof| tests.iter().find(|(d, _)| *d == dof).map(|(_, t)| t);
    let linear = match features.iter().any(|f| f.force_dof().is_none()) {
        true => Some(leg.rest_linearization()?.1),
        false => None,
    };
    features
        .iter()
        .map(|&feature| {
            Ok(match (feature, &linear) {
                (Feature::FreeStroke(d), _) => test(d).map_or(f64::NAN, |t| t.free_deflection),
                (Feature::BlockedForce(d), _) => test(d).map_or(f64::NAN, |t| t.blocked_force()),
                (Feature::Work(d), _) => test(d).map_or(f64::NAN, |t| t.work()),
                (Feature::NaturalFrequency(k), Some(linear)) => {
                    let modes = linear.modes().ok_or(leg::Error::NoModes)?;
                    modes.get(k - 1).map_or(f64::NAN, |m| m.frequency_hz())
                }
                (Feature::Resonance(d) | Feature::QualityFactor(d), Some(linear)) => {
                    let grid = settings.frequencies.as_deref().unwrap_or_default();
                    let output = leg.foot()[d.axis()];
                    let input = match d {
                        Dof::Lift => leg.v_lift(),
                        Dof::Swing => leg.v_swing(),
                    };
                    let magnitude = frequency::linear_magnitude(
                        linear,
                        input,
                        output,
                        FlexureDamping::Hysteretic,
                    );
                    let strongest = frequency::refined_resonances(grid, magnitude)?
                        .into_iter()
                        .next();
                    match (feature, strongest) {
                        (Feature::Resonance(_), Some(r)) => r.frequency_hz,
                        (_, Some(r)) => r.quality_factor.unwrap_or(f64::NAN),
                        (_, None) => f64::NAN,
                    }
                }
                (_, None) => f64::NAN,
            })
        })
        .collect()
}
