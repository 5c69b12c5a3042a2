//! Experiment 6, "What the model gets wrong, and why": the paper's Table IV taken as measured
//! data and diagnosed. For each robot of a `compare` experiment file, its rows (free
//! deflection d and blocked force F of the lift and swing tests, mean ± s.d., n = 2) become
//! a diagnosis experiment of kind `force_deflection_table` (the sensor's ~30 % off-axis load
//! as the paper applied it to its model curves, Sec. V-A), and `mech diagnose` runs its whole
//! catalog on them with nothing held out (four values per robot: none to spare). The result
//! is each robot's verdict, the named causes with their fitted values and uncertainties, and
//! the extended models' predictions of the table beside the base model's and the paper's.
//!
//! The one experiment kind that calls [`crate::diagnose`] (which itself uses only
//! [`super::leg`] of this module).
//!
//! Consumes: the kind's keys and the `compare` file they name. Produces: per robot a
//! [`RobotDiagnosis`] (plain data; `render::experiments::table_diagnosis` renders it).

use std::path::PathBuf;

use serde::Deserialize;

use mech_codegen::Compiled;
use mech_runtime::FlexureDamping;

use super::compare;
use super::leg::{self, Dof, Leg, WarmStarts};
use super::Error;
use crate::diagnose::candidates::{diagnose, Diagnosis, Holdout, Trial, Verdict};
use crate::diagnose::data::MeasuredData;
use crate::diagnose::experiment::{self as diagnosis, ForceDeflectionTable, TableTest};
use crate::diagnose::extend;
use crate::frequency;
use crate::parallel::parallel;
use crate::session::ModelSpec;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// The `compare` experiment file whose robots (models) and `paper` rows are the data,
    /// relative to the working directory (as every experiment's `model`).
    pub table: PathBuf,
    /// The sensor's y force as a fraction of the on-axis force in every test (the paper's
    /// ~0.3, Sec. V-A).
    #[serde(default)]
    pub off_axis_fraction: f64,
    /// The causes the paper gives, as parts of catalog cause names (`"flexure twist"`): each
    /// shown with its best fit, whether the diagnosis names it or not.
    #[serde(default)]
    pub paper_causes: Vec<String>,
}

impl Spec {
    pub fn check(&self) -> Result<(), Error> {
        if !(self.off_axis_fraction.is_finite() && self.off_axis_fraction.abs() <= 1.0) {
            return Err(Error::Key {
                message: format!(
                    "key `off_axis_fraction`: expected a fraction between -1 and 1, got {}",
                    self.off_axis_fraction
                ),
            });
        }
        Ok(())
    }
}

/// One robot's table, as diagnosed.
pub struct RobotDiagnosis {
    pub robot: String,
    /// The diagnosis experiment built from the robot's model and the table's tests.
    pub experiment: diagnosis::Experiment,
    /// The robot's rows of the table as measured data (one row per test).
    pub data: MeasuredData,
    pub diagnosis: Diagnosis,
    /// The dynamic regime (Fig. 10) of the model as written and as extended by the named
    /// cause with its fitted values; `None` when no cause is named.
    pub resonances: Option<Resonances>,
}

/// The largest resonance of each drive's own response (lift: `v_lift` → `foot.z`, swing:
/// `v_swing` → `foot.x`; hysteretic losses, refined on the continuous response), Hz: per
/// dof, (as written, as extended).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Resonances {
    pub lift: (f64, f64),
    pub swing: (f64, f64),
}

/// The band searched for [`Resonances`] (Hz): Fig. 10's 1–150 Hz and beyond, where the
/// legs' modes are (65–110 Hz).
const RESONANCE_BAND: (f64, f64, usize) = (10.0, 400.0, 200);

/// The robots of `compare` (the `compare` file `spec.table` names, read by
/// [`super::load_compare`]), each diagnosed on its rows of the paper's table (one robot per
/// thread; each diagnosis runs its candidates on the cores it gets).
pub fn compute(spec: &Spec, compare: &compare::Spec) -> Result<Vec<RobotDiagnosis>, Error> {
    let cases = compare
        .robot
        .iter()
        .map(|robot| case(spec, compare, robot))
        .collect::<Result<Vec<_>, Error>>()?;
    let results = parallel(cases, 2, |(robot, experiment, data)| {
        let result = diagnose(&experiment, &data, &[], Holdout::Nothing);
        (robot, experiment, data, result)
    });
    results
        .into_iter()
        .map(|(robot, experiment, data, result)| {
            let diagnosis = result.map_err(|error| Error::In {
                part: format!("robot `{robot}`"),
                error: Box::new(Error::Diagnosis(Box::new(error))),
            })?;
            let named = match diagnosis.verdict {
                Verdict::Explained | Verdict::PartlyExplained => {
                    diagnosis.combined.as_ref().or(diagnosis.ranked.first())
                }
                _ => None,
            };
            let resonances = named
                .map(|trial| resonances(&experiment.model, trial))
                .transpose()
                .map_err(|error| Error::In {
                    part: format!("robot `{robot}`, the dynamic regime"),
                    error: Box::new(error),
                })?;
            Ok(RobotDiagnosis {
                robot,
                experiment,
                data,
                diagnosis,
                resonances,
            })
        })
        .collect()
}

/// The diagnosis experiment and data of one robot: its lift and swing rows, in that order.
fn case(
    spec: &Spec,
    compare: &compare::Spec,
    robot: &compare::Robot,
) -> Result<(String, diagnosis::Experiment, MeasuredData), Error> {
    let mut tests = Vec::new();
    let mut csv = String::from(
        "free_deflection [mm], free_deflection_sd [mm], blocked_force [mN], blocked_force_sd [mN]\n",
    );
    for dof in [Dof::Lift, Dof::Swing] {
        let Some(row) = robot.paper.get(dof.name()) else {
            continue;
        };
        let paper = row.parse(&format!("robot `{}` paper.{}", robot.name, dof.name()))?;
        csv += &format!(
            "{}, {}, {}, {}\n",
            paper.d.0 * 1e3,
            paper.d.1 * 1e3,
            paper.force.0 * 1e3,
            paper.force.1 * 1e3
        );
        tests.push(TableTest {
            dof,
            direction: row.direction.clone(),
        });
    }
    let source = PathBuf::from(format!("{} (robot `{}`)", spec.table.display(), robot.name));
    let data = MeasuredData::parse(&source, csv.as_bytes()).map_err(|errors| Error::Key {
        message: format!("the paper's rows of robot `{}`: {errors}", robot.name),
    })?;
    let experiment = diagnosis::Experiment {
        title: format!("{}: the paper's Table IV", robot.name),
        model: robot.model.clone(),
        kind: diagnosis::Kind::ForceDeflectionTable(ForceDeflectionTable {
            voltage: compare.voltage.clone(),
            off_axis_fraction: spec.off_axis_fraction,
            test: tests,
        }),
    };
    Ok((robot.name.clone(), experiment, data))
}

/// [`Resonances`] of `spec`'s model as written and as `trial` extends it (its model-form
/// change, its fitted values of the model's parameters; a fitted value that is no model
/// parameter, such as the sensor's off-axis load, plays no part in the dynamics).
fn resonances(spec: &ModelSpec, trial: &Trial) -> Result<Resonances, Error> {
    let compiled = Compiled::from_path(&spec.path).map_err(|errors| {
        Error::Diagnosis(Box::new(crate::diagnose::Error::Compile {
            model: spec.path.clone(),
            errors,
        }))
    })?;
    let diagnosis_error = |error| Error::Diagnosis(Box::new(error));
    let base = extend::base_leg(&compiled, spec).map_err(diagnosis_error)?;
    let mut extended = match &trial.extension {
        Some(extension) => extend::extend_leg(&compiled, spec, extension),
        None => extend::base_leg(&compiled, spec),
    }
    .map_err(diagnosis_error)?;
    for (name, _, value, _) in &trial.parameters {
        if let Some(index) = extended.model().param_index(name) {
            extended.session.set_si(index, *value)?;
        }
    }
    let [base_lift, base_swing] = largest_resonances(&base)?;
    let [lift, swing] = largest_resonances(&extended)?;
    Ok(Resonances {
        lift: (base_lift, lift),
        swing: (base_swing, swing),
    })
}

/// The largest resonance of the lift and of the swing drive's own response at rest, Hz
/// (NaN where the band holds none).
fn largest_resonances(leg: &Leg) -> Result<[f64; 2], Error> {
    let inputs = leg.inputs(0.0, 0.0);
    let rest = leg.warm_rest(&mut WarmStarts::default(), 0, &inputs)?.q;
    let linear = mech_runtime::linearize(leg.model(), 0.0, &rest, &inputs, &leg.independent)
        .map_err(leg::Error::Linearization)?;
    let (from, to, points) = RESONANCE_BAND;
    let grid = frequency::log_space(from, to, points);
    let foot = leg.foot();
    let mut found = [f64::NAN; 2];
    for (slot, (input, output)) in found
        .iter_mut()
        .zip([(leg.v_lift(), foot[2]), (leg.v_swing(), foot[0])])
    {
        let magnitude =
            frequency::linear_magnitude(&linear, input, output, FlexureDamping::Hysteretic);
        *slot = frequency::refined_resonances(&grid, magnitude)?
            .into_iter()
            .max_by(|a, b| a.peak_magnitude.total_cmp(&b.peak_magnitude))
            .map_or(f64::NAN, |r| r.frequency_hz);
    }
    Ok(found)
}
