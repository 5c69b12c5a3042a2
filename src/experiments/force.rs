//! Experiment 2, force/deflection (seed Fig. 6 a, b, f, g; Sec. V.A, Fig. 7): the foot
//! pushed against a force sensor at increasing distances (127 µm steps) until no force; the
//! on-axis force at each distance with the off-axis (y) force, optionally with the paper's
//! ~30 % off-axis load; blocked force and free deflection; `F·d` and `F·d/(F_b δ_f)`.

use std::collections::BTreeMap;

use mech_codegen::ir::Dimension;
use serde::Deserialize;

use super::leg::{Dof, ForceDeflection, ForceTest, Leg, Sensor, StrokeLimit};
use super::Error;
use crate::quantity::{paper_value, positive};
use crate::session::ModelSpec;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    #[serde(flatten)]
    pub model: ModelSpec,
    /// Peak drive voltage of the model input (`225 V`).
    pub voltage: String,
    /// Step of the sensor position (`127 um`).
    pub sensor_step: String,
    /// Degrees of freedom tested (`["lift", "swing"]`); lift pushes along z, swing along x.
    #[serde(default = "default_dofs")]
    pub dofs: Vec<Dof>,
    /// If set, the test is repeated with this fraction of the on-axis force applied along y.
    pub off_axis_fraction: Option<f64>,
    /// The paper's measured values for this robot (Table IV), per degree of freedom.
    #[serde(default)]
    pub paper: BTreeMap<String, PaperRow>,
}

/// One row of the paper's Table IV: `"2.2 +- 0.1 mm"` etc.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PaperRow {
    /// Maximum one-way foot displacement.
    pub d: String,
    /// Maximum force.
    pub force: String,
    /// `F·d`.
    pub work: String,
    /// `F·d/(F_b δ_f)`, e.g. `"0.38 +- 0.04"`.
    pub normalized: String,
    /// The way the foot moved in the paper's test, along the DOF's axis: `"+z"` or `"-z"`
    /// for lift (`"-z"`: the foot pushed down onto a sensor under the leg, Fig. 7b), `"+x"`
    /// or `"-x"` for swing; omitted: the way the positive drive moves it.
    #[serde(default)]
    pub direction: Option<String>,
}

/// A parsed [`PaperRow`], SI means and spreads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Paper {
    pub d: (f64, f64),
    pub force: (f64, f64),
    pub work: (f64, f64),
    pub normalized: (f64, f64),
    /// +1 or −1 along the DOF's axis ([`PaperRow::direction`]); `None`: the positive drive's.
    pub direction: Option<f64>,
}

impl PaperRow {
    pub fn parse(&self, key: &str) -> Result<Paper, Error> {
        Ok(Paper {
            d: paper_value(&format!("{key}.d"), &self.d, Dimension::LENGTH)?,
            force: paper_value(&format!("{key}.force"), &self.force, Dimension::FORCE)?,
            work: paper_value(&format!("{key}.work"), &self.work, Dimension::ENERGY)?,
            normalized: paper_value(
                &format!("{key}.normalized"),
                &self.normalized,
                Dimension::NONE,
            )?,
            direction: self
                .direction
                .as_deref()
                .map(|text| parse_direction(key, text))
                .transpose()?,
        })
    }
}

/// `"+z"` → +1 for the key `….lift` (the lift axis is z; swing's is x).
fn parse_direction(key: &str, text: &str) -> Result<f64, Error> {
    let dof = if key.ends_with("lift") {
        Dof::Lift
    } else {
        Dof::Swing
    };
    dof.direction(text).ok_or_else(|| {
        let axis = if dof == Dof::Lift { 'z' } else { 'x' };
        Error::Key {
            message: format!(
                "key `{key}.direction`: expected `+{axis}` or `-{axis}` (the way the foot moved \
                 along the test's axis), got `{text}`"
            ),
        }
    })
}

pub(crate) fn check_paper(paper: &BTreeMap<String, PaperRow>, prefix: &str) -> Result<(), Error> {
    for (key, row) in paper {
        if key != "lift" && key != "swing" {
            return Err(Error::Key {
                message: format!("key `{prefix}paper.{key}`: expected `lift` or `swing`"),
            });
        }
        row.parse(&format!("{prefix}paper.{key}"))?;
    }
    Ok(())
}

fn default_dofs() -> Vec<Dof> {
    vec![Dof::Lift, Dof::Swing]
}

impl Spec {
    pub fn check(&self) -> Result<(), Error> {
        positive("voltage", &self.voltage, Dimension::VOLTAGE)?;
        positive("sensor_step", &self.sensor_step, Dimension::LENGTH)?;
        if let Some(c) = self.off_axis_fraction {
            if !(0.0..=2.0).contains(&c) {
                return Err(Error::Key {
                    message: format!(
                        "key `off_axis_fraction`: expected a fraction between 0 and 2, got {c}"
                    ),
                });
            }
        }
        check_paper(&self.paper, "")
    }
}

/// `F_b δ_f` of the model's actuator (parameters `F_b`, `delta_f`).
pub(crate) fn actuator_work(leg: &Leg) -> Result<f64, Error> {
    match (leg.param("F_b"), leg.param("delta_f")) {
        (Some(f), Some(d)) => Ok(f * d),
        _ => Err(Error::Key {
 message: format!(
            "model `{}` has no parameters `F_b` and `delta_f` (the actuator's blocked force and free deflection)",
            leg.model().name()
        ),
 }),
    }
}

/// The force/deflection tests of one degree of freedom: on-axis only, then with the
/// off-axis load if the spec asks for one; each with its label.
fn tests(
    spec: &Spec,
    leg: &Leg,
    dof: Dof,
    voltage: f64,
    step: f64,
) -> Result<Vec<(&'static str, ForceDeflection)>, Error> {
    let test = ForceTest::new(dof, voltage, Sensor::Steps(step));
    // Both ways: the paper's lift test pushes the foot down (Fig. 7b), the way a negative
    // drive moves HAMR's foot.
    let reversed = ForceTest::new(dof, -voltage, Sensor::Steps(step));
    let mut cases = vec![
        ("on-axis only", test.run(leg)?),
        ("on-axis only, reversed drive", reversed.run(leg)?),
    ];
    if let Some(c) = spec.off_axis_fraction {
        if c > 0.0 {
            let label = if (c - 0.3).abs() < 1e-12 {
                "30 % off-axis"
            } else {
                "off-axis"
            };
            cases.push((label, test.clone().off_axis(c).run(leg)?));
        }
    }
    Ok(cases)
}

/// The force/deflection tests of the model at the drive voltage: per degree of freedom of
/// the spec, its tests (on-axis only, then with the off-axis load if asked for).
pub struct ForceDeflections {
    pub model_name: String,
    /// Drive voltage (V) and sensor step (m).
    pub voltage: f64,
    pub step: f64,
    /// `F_b δ_f` of the model's actuator.
    pub actuator_work: f64,
    /// Per degree of freedom of the spec, its tests, each with its label (`on-axis only`,
    /// the same with the drive reversed, then the off-axis load's).
    pub dofs: Vec<(Dof, Vec<(&'static str, ForceDeflection)>)>,
    /// Per degree of freedom, the way of the paper's test (±1 along its axis: the
    /// [`PaperRow::direction`], else the positive drive's) and the kinematic limit of the
    /// foot's travel that way ([`Leg::stroke_limit`], over 2 mm of actuator travel).
    pub limits: Vec<(Dof, f64, Option<StrokeLimit>)>,
}

impl ForceDeflections {
    /// The on-axis test of `dof` whose foot moves `direction` (±1) along the axis.
    pub fn on_axis(&self, dof: Dof, direction: f64) -> Option<&ForceDeflection> {
        let (_, cases) = self.dofs.iter().find(|(d, _)| *d == dof)?;
        cases
            .iter()
            .map(|(_, test)| test)
            .find(|test| test.off_axis_fraction == 0.0 && test.direction == direction)
    }
}

/// Opens the leg and runs each degree of freedom's tests, in the spec's order.
pub fn compute(spec: &Spec) -> Result<ForceDeflections, Error> {
    let voltage = positive("voltage", &spec.voltage, Dimension::VOLTAGE)?;
    let step = positive("sensor_step", &spec.sensor_step, Dimension::LENGTH)?;
    let leg = Leg::open(&spec.model)?;
    let actuator_work = actuator_work(&leg)?;
    let dofs: Vec<(Dof, Vec<(&'static str, ForceDeflection)>)> = spec
        .dofs
        .iter()
        .map(|&dof| Ok((dof, tests(spec, &leg, dof, voltage, step)?)))
        .collect::<Result<_, Error>>()?;
    let mut limits = Vec::new();
    for (dof, cases) in &dofs {
        let paper = match spec.paper.get(dof.name()) {
            Some(row) => row.parse(&format!("paper.{}", dof.name()))?.direction,
            None => None,
        };
        let direction = paper.unwrap_or(cases[0].1.direction);
        limits.push((*dof, direction, leg.stroke_limit(*dof, direction, 2e-3)?));
    }
    Ok(ForceDeflections {
        model_name: leg.model().name().to_string(),
        voltage,
        step,
        actuator_work,
        dofs,
        limits,
    })
}
