//! Experiment 4, HAMR-V2.0 against HAMR-VI (seed Table IV): free deflection, blocked force,
//! `F·d` and `F·d/(F_b δ_f)` of both legs, lift and swing, and the increase of the work done
//! by the foot (the paper reports 266 %).

use std::collections::BTreeMap;

use mech_codegen::ir::Dimension;
use serde::Deserialize;

use super::force::{actuator_work, check_paper, PaperRow};
use super::leg::{Dof, ForceDeflection, ForceTest, Leg, Sensor, WarmStarts};
use super::Error;
use crate::parallel::parallel;
use crate::quantity::positive;
use crate::session::ModelSpec;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// Peak drive voltage of the model inputs (`225 V`).
    pub voltage: String,
    /// The paper's reported increase of the work done by the foot, percent (266).
    pub paper_work_increase_percent: Option<f64>,
    /// Exactly two robots: the old design first, the new one second.
    pub robot: Vec<Robot>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Robot {
    pub name: String,
    #[serde(flatten)]
    pub model: ModelSpec,
    /// Seed Table IV values, per degree of freedom.
    #[serde(default)]
    pub paper: BTreeMap<String, PaperRow>,
}

impl Spec {
    pub fn check(&self) -> Result<(), Error> {
        positive("voltage", &self.voltage, Dimension::VOLTAGE)?;
        if self.robot.len() != 2 {
            return Err(Error::Key {
                message: format!(
                    "key `robot`: expected exactly two [[robot]] tables (old, new), got {}",
                    self.robot.len()
                ),
            });
        }
        for (k, robot) in self.robot.iter().enumerate() {
            check_paper(&robot.paper, &format!("robot[{k}]."))?;
        }
        Ok(())
    }
}

/// One robot's force/deflection tests, lift then swing, and its actuator's F_b·δ_f.
pub struct RobotTests {
    pub actuator_work: f64,
    pub tests: [ForceDeflection; 2],
}

/// Runs each robot's lift and swing tests at `voltage` (one robot per thread).
pub fn compute(spec: &Spec, voltage: f64) -> Result<Vec<RobotTests>, Error> {
    let results = parallel(
        spec.robot.iter().collect(),
        2,
        |robot| -> Result<_, Error> {
            let leg = Leg::open(&robot.model)?;
            let fbdf = actuator_work(&leg)?;
            // The foot moving the way of the paper's test (the drive reversed when the
            // positive one moves it the other way: the lift test pushes the foot down).
            let tests = [Dof::Lift, Dof::Swing].map(|dof| {
                let wanted = match robot.paper.get(dof.name()) {
                    Some(row) => row.parse(&format!("paper.{}", dof.name()))?.direction,
                    None => None,
                };
                ForceTest::new(dof, voltage, Sensor::Blocked)
                    .run_toward(&leg, wanted, &mut WarmStarts::default())
                    .map_err(Error::from)
            });
            Ok((fbdf, tests))
        },
    );
    spec.robot
        .iter()
        .zip(results)
        .map(|(robot, result)| {
            let (actuator_work, [lift, swing]) =
                result.map_err(|e| e.within(format!("robot `{}`", robot.name)))?;
            let named = |dof: Dof, test: Result<ForceDeflection, Error>| {
                test.map_err(|e| e.within(format!("robot `{}` {}", robot.name, dof.name())))
            };
            Ok(RobotTests {
                actuator_work,
                tests: [named(Dof::Lift, lift)?, named(Dof::Swing, swing)?],
            })
        })
        .collect()
}
