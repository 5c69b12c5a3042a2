//! Hidden effects in data from a second formulation of the leg (issue 17: "tests that cannot
//! pass by construction"): force/deflection data made by [`IndependentLeg`] — the published
//! URDFs read at test time, reduced coordinates, statics by energy — with an effect built in,
//! diagnosed against `models/hamr_vi.mech`. First the two formulations are checked to agree
//! on the leg as built, so that what the diagnosis finds is the effect, not a difference of
//! formulations.

use crate::common;
use crate::diagnose_catalog::{
    bode_data, bode_frequencies, bode_responses, diagnose_data, loss_factor_named, summary,
};
use crate::independent_leg::{Actuator, Effect, IndependentLeg};

use common::{Rng, WrittenEffect};
use mech::diagnose::candidates::{Diagnosis, Verdict};
use mech::experiments::leg::{Dof, ForceTest, Leg, Sensor};
use mech_codegen::ir::transform::actuator::{BASE_COMPLIANCE, STIFFNESS_FACTOR};

/// Noise of the force sensor (one standard deviation) and the paper's sensor step.
const FORCE_NOISE: f64 = 0.3e-3;
const SENSOR_STEP: f64 = 127e-6;

fn actuator(dof: Dof) -> Actuator {
    match dof {
        Dof::Lift => Actuator::Lift,
        Dof::Swing => Actuator::Swing,
    }
}

/// `test` run by mech on `leg` and by `independent`: free deflection and the sensor force at
/// each of mech's sensor positions must agree to `1e-8` of the free deflection and of the
/// blocked force (seen: 3e-10).
fn assert_same_test(what: &str, test: &ForceTest, leg: &Leg, independent: &IndependentLeg) {
    let by_mech = test.run(leg).unwrap();
    let distances: Vec<f64> = by_mech.points.iter().map(|p| p.distance).collect();
    let (free, forces) = independent.force_test(
        actuator(test.dof),
        test.dof.axis(),
        test.voltage,
        &distances,
        test.off_axis_fraction,
    );
    let blocked = by_mech.blocked_force();
    assert!(
        (free / by_mech.free_deflection - 1.0).abs() < 1e-8,
        "{what}: free deflection {free} (independent) vs {} (mech)",
        by_mech.free_deflection
    );
    for (point, force) in by_mech.points.iter().zip(&forces) {
        assert!(
            (force - point.force).abs() < 1e-8 * blocked,
            "{what} at {} m: force {force} (independent) vs {} (mech)",
            point.distance,
            point.force
        );
    }
    println!(
        "{what}: free {free:.10e} vs {:.10e}; blocked {:.10e} vs {blocked:.10e}; {} points",
        by_mech.free_deflection,
        forces[0],
        forces.len()
    );
}

/// The same tests run by mech on `models/hamr_vi.mech` and by the independent leg: free
/// deflection and the sensor force at 0, 127, 254, … µm with the paper's 30 % off-axis load,
/// for lift (both ways) and swing. The formulations differ (Kane's method with symbolic
/// derivatives and the runtime's statics against energy and finite differences; the `.mech`
/// transcription against the URDF read at run time); their results agree to round-off and
/// difference steps.
#[test]
fn independent_leg_agrees_with_mech() {
    let leg = Leg::open(&common::hamr_vi_spec()).unwrap();
    let independent = IndependentLeg::hamr_vi(&[]);
    for (dof, voltage) in [(Dof::Lift, 225.0), (Dof::Lift, -225.0), (Dof::Swing, 225.0)] {
        let test = ForceTest::new(dof, voltage, Sensor::Steps(SENSOR_STEP)).off_axis(0.3);
        assert_same_test(&format!("{dof:?} {voltage} V"), &test, &leg, &independent);
    }
}

/// The effects the other hidden-effect tests write into the model's text
/// (`common::WrittenEffect`) or set as parameters, against the same effects built into the
/// independent leg: each pair must give the same tests, so those tests' truths are the
/// physical effects they claim.
#[test]
fn written_effects_agree_with_the_independent_leg() {
    let dir = common::scratch_dir("written_effects_agree");
    let lift = ForceTest::new(Dof::Lift, 225.0, Sensor::Steps(2.0 * SENSOR_STEP)).off_axis(0.3);
    let cases = [
        (
            WrittenEffect::LiftActuatorStiffness(0.8),
            Effect::ActuatorStiffness(Actuator::Lift, 0.8),
        ),
        (
            WrittenEffect::LiftActuatorForce(0.85),
            Effect::ActuatorForce(Actuator::Lift, 0.85),
        ),
        (
            WrittenEffect::LiftBaseCompliance(0.4),
            Effect::BaseCompliance(Actuator::Lift, 0.4),
        ),
    ];
    for (written, built) in cases {
        let leg = common::hamr_vi_written(written, &dir);
        let independent = IndependentLeg::hamr_vi(&[built]);
        assert_same_test(&format!("{written:?}"), &lift, &leg, &independent);
    }
    // A flexure's stiffness, a parameter of the model (`k_l2`) and a spring of the URDF.
    let mut leg = Leg::open(&common::hamr_vi_spec()).unwrap();
    let k_l2 = leg.param("k_l2").unwrap();
    common::set_leg_param(&mut leg, "k_l2", 2.5 * k_l2);
    let independent = IndependentLeg::hamr_vi(&[Effect::FlexureStiffness("FLql2", 2.5)]);
    assert_same_test("k_l2 × 2.5", &lift, &leg, &independent);
}

/// Force/deflection data of `dof` at 225 V from the independent leg with `effects` (no
/// off-axis load, as the catalog's force cases), 0.3 mN noise, diagnosed with the whole
/// catalog against the model as written.
fn independent_case(name: &str, effects: &[Effect], dof: Dof, rng: &mut Rng) -> Diagnosis {
    let dir = common::scratch_dir(name);
    let truth = IndependentLeg::hamr_vi(effects);
    // The sensor positions: every 127 µm until the free foot no longer reaches it.
    let (free, _) = truth.force_test(actuator(dof), dof.axis(), 225.0, &[], 0.0);
    let distances: Vec<f64> = (0..)
        .map(|k| k as f64 * SENSOR_STEP)
        .take_while(|&d| d < free)
        .collect();
    let (_, forces) = truth.force_test(actuator(dof), dof.axis(), 225.0, &distances, 0.0);
    let mut text = String::from("distance [um], force [mN]\n");
    for (distance, force) in distances.iter().zip(&forces) {
        let force = force + FORCE_NOISE * rng.normal();
        text += &format!("{}, {}\n", distance * 1e6, force * 1e3);
    }
    let dof_name = dof.name();
    let experiment = common::hamr_vi_experiment_in(
        &dir,
        &format!(
            "kind = \"force_deflection\"\ntitle = \"{dof_name} force\"\ndof = \"{dof_name}\"\n\
             voltage = \"225 V\"\noff_axis_fraction = 0\nnoise = \"0.3 mN\"\n"
        ),
    );
    diagnose_data(&dir, &experiment, &text)
}

/// Asserts that `d` found nothing to explain: no cause fits the data significantly better
/// than the model as written.
fn assert_nothing_to_explain(d: &Diagnosis) {
    assert_eq!(
        d.verdict,
        Verdict::NoSignificantDiscrepancy,
        "{}",
        summary(d)
    );
}

/// The named candidate's fitted `parameter` (value, standard error), the top cause or one of
/// a tie the verdict states.
fn named(d: &Diagnosis, cause: &str, location: &str, parameter: &str) -> (f64, f64) {
    println!("{}", summary(d));
    let named = &d.ranked[..d.tied.max(1)];
    let trial = named
        .iter()
        .find(|t| t.cause == cause && t.location == location)
        .unwrap_or_else(|| panic!("{cause} at {location} not named\n{}", summary(d)));
    let (_, _, value, se) = trial
        .parameters
        .iter()
        .find(|p| p.0 == parameter)
        .cloned()
        .unwrap_or_else(|| panic!("no {parameter}\n{}", summary(d)));
    (value, se)
}

/// Asserts that `d` explains the data and names the candidate with its fitted `parameter`
/// within 3σ of `truth`; returns (value, standard error).
fn explained_within_3_sigma(
    d: &Diagnosis,
    cause: &str,
    location: &str,
    parameter: &str,
    truth: f64,
) -> (f64, f64) {
    assert_eq!(d.verdict, Verdict::Explained, "{}", summary(d));
    let (value, se) = named(d, cause, location, parameter);
    assert!(
        (value - truth).abs() < 3.0 * se,
        "{parameter} {value} ± {se} vs {truth}\n{}",
        summary(d)
    );
    (value, se)
}

/// The leg as built, lift and swing data: nothing to explain.
#[test]
#[ignore = "slow: two whole-catalog diagnoses, run by .ci/run's `hidden_effect` filter"]
fn hidden_effect_independent_clean_data() {
    let mut rng = Rng::new(21);
    for dof in [Dof::Lift, Dof::Swing] {
        let d = independent_case(&format!("independent_clean_{dof:?}"), &[], dof, &mut rng);
        assert_nothing_to_explain(&d);
    }
}

/// The issue's own case, in data mech did not make: the lift actuator 20 % softer than its
/// data sheet (its blocked force as written). The actuator's stiffness is named at the lift
/// actuator, its factor within 3σ of 0.8 and pinned by the data to σ < 0.02 (seen: 0.784 ±
/// 0.008; a bound of 2 % as `actuator_causes.rs` has would be 2σ at this noise).
#[test]
#[ignore = "slow: a whole-catalog diagnosis, run by .ci/run's `hidden_effect` filter"]
fn hidden_effect_independent_softer_lift_actuator() {
    let d = independent_case(
        "independent_softer_lift_actuator",
        &[Effect::ActuatorStiffness(Actuator::Lift, 0.8)],
        Dof::Lift,
        &mut Rng::new(22),
    );
    let (value, se) = explained_within_3_sigma(
        &d,
        "actuator stiffness off by a factor",
        "actuator along qlact",
        STIFFNESS_FACTOR,
        0.8,
    );
    assert!(
        se < 0.02,
        "{STIFFNESS_FACTOR} {value} ± {se} vs 0.8\n{}",
        summary(&d)
    );
}

/// The swing actuator's clamp gives: a base spring k_a/0.5 in series. Named as the swing
/// actuator's base compliance (alone or in a tie the verdict states), within 3σ of 0.5.
#[test]
#[ignore = "slow: a whole-catalog diagnosis, run by .ci/run's `hidden_effect` filter"]
fn hidden_effect_independent_swing_base_compliance() {
    let d = independent_case(
        "independent_swing_base_compliance",
        &[Effect::BaseCompliance(Actuator::Swing, 0.5)],
        Dof::Swing,
        &mut Rng::new(23),
    );
    explained_within_3_sigma(
        &d,
        "actuator base compliance",
        "actuator along qsact",
        BASE_COMPLIANCE,
        0.5,
    );
}

/// `[gain (m/V), phase (deg)]` of the independent leg's lift and swing responses at the Bode
/// experiment's frequencies.
fn independent_bode(leg: &IndependentLeg) -> Vec<[[f64; 2]; 2]> {
    let frequencies: Vec<f64> = bode_frequencies().collect();
    leg.frequency_response(&frequencies)
        .into_iter()
        .map(|channels| channels.map(|h| [h.norm(), h.arg().to_degrees()]))
        .collect()
}

/// The largest relative gain and phase (deg) differences of two sets of Bode responses.
fn bode_difference(a: &[[[f64; 2]; 2]], b: &[[[f64; 2]; 2]]) -> (f64, f64) {
    let pairs = a.iter().zip(b).flat_map(|(a, b)| a.iter().zip(b));
    pairs.fold((0.0f64, 0.0f64), |(gain, phase), (a, b)| {
        (
            gain.max((a[0] / b[0] - 1.0).abs()),
            phase.max((a[1] - b[1]).abs()),
        )
    })
}

/// mech's linearization (`models/hamr_vi.mech`, hysteretic flexures) against the independent
/// leg's, as built and with 15 mg on the lift actuator's tip (written into the model's text):
/// the lift and swing Bode responses from 1 to 150 Hz, through both resonances. Seen: gain
/// within 8.9e-6 (largest beside the 79 Hz mode; 6e-7 static for lift, 4e-9 for swing), phase
/// within 6.2e-4°: both linearizations difference their energies or forces, mech with steps
/// of 1e-5 of the coordinate (floor 1e-8) and one Richardson step, this one nested central
/// differences. Asserted: 3e-5 and 3e-3°, a thousandth of the Bode data's 2 % and 1° noise.
#[test]
fn independent_frequency_response_agrees_with_mech() {
    let damping = mech_runtime::FlexureDamping::Hysteretic;
    let dir = common::scratch_dir("independent_bode");
    let cases = [
        (Leg::open(&common::hamr_vi_spec()).unwrap(), Vec::new()),
        (
            common::hamr_vi_written(WrittenEffect::LiftTipMass(15e-6), &dir),
            vec![Effect::TipMass(Actuator::Lift, 15e-6)],
        ),
    ];
    for (leg, effects) in cases {
        let (gain, phase) = bode_difference(
            &independent_bode(&IndependentLeg::hamr_vi(&effects)),
            &bode_responses(&leg, damping),
        );
        println!("{effects:?}: gain within {gain:.2e}, phase within {phase:.2e}°");
        assert!(gain < 3e-5 && phase < 3e-3, "{effects:?}: {gain}, {phase}°");
    }
}

/// Lift and swing Bode data (2 %, 1°) from the independent leg with `effects`, noise drawn
/// from `seed`, diagnosed with the whole catalog against the model as written.
fn independent_bode_case(name: &str, effects: &[Effect], seed: u64) -> Diagnosis {
    let dir = common::scratch_dir(name);
    let responses = independent_bode(&IndependentLeg::hamr_vi(effects));
    let (experiment, text) = bode_data(&dir, &responses, &mut Rng::new(seed));
    diagnose_data(&dir, &experiment, &text)
}

/// The leg as built, lift and swing Bode data (2 %, 1°): nothing to explain.
#[test]
#[ignore = "slow: a whole-catalog diagnosis, run by .ci/run's `hidden_effect` filter"]
fn hidden_effect_independent_clean_bode() {
    assert_nothing_to_explain(&independent_bode_case("independent_clean_bode", &[], 24));
}

/// Every flexure's loss factor 0.12 instead of 0.08 (the resonances' Q a third lower), lift
/// and swing Bode data: a loss-factor cause on top (the frequency-dependent one nests the
/// constant one: they may tie), the constant η within 3σ and 0.01 of 0.12.
#[test]
#[ignore = "slow: a whole-catalog diagnosis, run by .ci/run's `hidden_effect` filter"]
fn hidden_effect_independent_loss_factor() {
    let effects = [Effect::LossFactor(0.12)];
    loss_factor_named(
        &independent_bode_case("independent_loss_factor", &effects, 25),
        0.12,
    );
}
