//! An actuator off from its data sheet, in data the candidates did not make: the lift
//! actuator's stiffness or force written into HAMR-VI's text (`common::WrittenEffect`), lift
//! force/deflection data at 225 V with 0.3 mN noise. The case that asked for it: with the
//! lift actuator 20 % softer and no actuator-stiffness entry in the catalog, flexures l3 and
//! fb1 softened to their ÷4 bound were reported as the explanation.

use crate::common;
use crate::diagnose_catalog::{diagnose_data, force_case, summary, top};

use common::{Rng, WrittenEffect};
use mech::diagnose::candidates::{diagnose_causes, Holdout, Verdict};
use mech::experiments::leg::Dof;
use mech_codegen::ir::transform::actuator::{FORCE_FACTOR, STIFFNESS_FACTOR};

/// Lift force data from HAMR-VI with `effect` written in (drawing with `rng` after the
/// effect's size), diagnosed with the whole catalog: the top cause must be `cause` at the lift
/// actuator, its `parameter` within 3σ and 2 % of `truth`.
fn actuator_case(
    name: &str,
    effect: WrittenEffect,
    truth: f64,
    (cause, parameter): (&str, &str),
    rng: &mut Rng,
) {
    let dir = common::scratch_dir(name);
    let leg = common::hamr_vi_written(effect, &dir);
    let (experiment, text) = force_case(&dir, &leg, Dof::Lift, 0.0, 0.0, rng);
    let d = diagnose_data(&dir, &experiment, &text);
    let fitted = top(&d, cause, "actuator along qlact", parameter);
    let se = d.ranked[0].parameters[0].3;
    assert!(
        (fitted - truth).abs() < 3.0 * se && (fitted / truth - 1.0).abs() < 0.02,
        "{parameter} {fitted} ± {se} vs {truth}\n{}",
        summary(&d)
    );
}

/// The lift actuator's stiffness ×U(0.7, 0.85), its blocked force as written.
fn softer_lift_actuator(seed: u64) {
    let mut rng = Rng::new(seed);
    let factor = rng.uniform(0.7, 0.85);
    actuator_case(
        &format!("softer_lift_actuator_{seed}"),
        WrittenEffect::LiftActuatorStiffness(factor),
        factor,
        ("actuator stiffness off by a factor", STIFFNESS_FACTOR),
        &mut rng,
    );
}

#[test]
fn hidden_effect_softer_lift_actuator_seed_1() {
    softer_lift_actuator(1)
}

#[test]
#[ignore = "slow: the second and third seeds, run by .ci/run"]
fn hidden_effect_softer_lift_actuator_seed_2() {
    softer_lift_actuator(2)
}

#[test]
#[ignore = "slow: the second and third seeds, run by .ci/run"]
fn hidden_effect_softer_lift_actuator_seed_3() {
    softer_lift_actuator(3)
}

/// The lift actuator's force ×U(0.8, 0.9), its stiffness as written (a weaker piezoelectric
/// drive). Slow (a whole-catalog diagnosis): run by .ci/run with the ignored seeds.
#[test]
#[ignore = "slow: a second whole-catalog diagnosis of this file, run by .ci/run"]
fn hidden_effect_weaker_lift_actuator() {
    let mut rng = Rng::new(7);
    let factor = rng.uniform(0.8, 0.9);
    actuator_case(
        "weaker_lift_actuator",
        WrittenEffect::LiftActuatorForce(factor),
        factor,
        ("actuator force off by a factor", FORCE_FACTOR),
        &mut rng,
    );
}

/// The case, with the catalog limited to flexure stiffness changes (`--cause`): the
/// softer actuator's data are fitted best by flexures at their ÷4 bound, which must not be
/// named — the verdict says no cause lies within the plausible ranges, and no pair of causes
/// is offered.
#[test]
fn a_fit_at_its_bound_names_no_cause() {
    let mut rng = Rng::new(1);
    let dir = common::scratch_dir("fit_at_bound");
    let truth = common::hamr_vi_written(WrittenEffect::LiftActuatorStiffness(0.8), &dir);
    let (experiment, text) = force_case(&dir, &truth, Dof::Lift, 0.0, 0.0, &mut rng);
    let data = common::measured_data(&dir, &text);
    let d = diagnose_causes(
        &experiment,
        &data,
        &[],
        Holdout::Every(3),
        &["flexure stiffness".to_string()],
    )
    .unwrap();
    assert!(
        d.ranked.iter().any(|t| t.at_bound()),
        "a fit at its bound\n{}",
        summary(&d)
    );
    assert_eq!(d.verdict, Verdict::OutsidePlausibleRange, "{}", summary(&d));
    assert!(d.combined.is_none(), "{}", summary(&d));
    let text = mech::render::diagnosis::verdict_text(&d);
    assert!(
        text.starts_with("no cause within the catalog's plausible ranges: the closest, flexure stiffness off by a factor at flexure"),
        "{text}"
    );
}
