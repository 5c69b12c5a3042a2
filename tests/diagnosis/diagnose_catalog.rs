//! An effect hidden in the data (issue 7's test): "measured" data made with mech's own
//! simulator from the HAMR-VI model plus one hidden effect of the catalog, written into the
//! model's text by hand (`common::WrittenEffect`) or a runtime setting (the flexure
//! parameters, damping laws), never by the candidates' own transformations — the entry drawn
//! by a seeded random choice ([`draw`]), then its size, location and the noise from the same
//! generator. Only the data and the base model go to `diagnose`; the top-ranked candidate
//! must name the effect and where it acts, recover its parameter within a stated tolerance,
//! and show a held-out gain (each entry's case states its own checks). The seeds run every
//! entry (checked); clean data and an effect no entry covers are in `tests/diagnose.rs`; the
//! paper's story closes the file.

use crate::common;

use std::path::Path;

use common::{Rng, WrittenEffect, FOOT_SIDE_FORCE};
use mech::diagnose::candidates::{diagnose, Diagnosis, Holdout, Trial, Verdict};
use mech::diagnose::experiment::Experiment;
use mech::diagnose::features::features;
use mech::diagnose::separate::SEPARATES;
use mech::experiments::leg::{Dof, ForceTest, Leg, Sensor};
use mech_codegen::ir::transform::actuator::{BASE_COMPLIANCE, TIP_MASS, TIP_PRELOAD};
use mech_codegen::ir::transform::hinge::{MISALIGNMENT, OFF_AXIS_COMPLIANCE};

/// Runs the diagnosis of `text` (CSV) under `experiment` with the default hold-out.
pub(crate) fn diagnose_data(dir: &Path, experiment: &Experiment, text: &str) -> Diagnosis {
    let data = common::measured_data(dir, text);
    diagnose(experiment, &data, &[], Holdout::Every(3)).unwrap()
}

/// Everything a failed assertion needs to show.
pub(crate) fn summary(d: &Diagnosis) -> String {
    let mut text = format!(
        "verdict {:?}; base χ² {:.1}/{:.1}\n",
        d.verdict, d.base.train_chi2, d.base.holdout_chi2
    );
    let line = |t: &Trial| {
        format!(
            "  {} at {}: χ² {:.1}/{:.1} AICc {:.1} {:?}\n",
            t.cause, t.location, t.train_chi2, t.holdout_chi2, t.aicc, t.parameters
        )
    };
    for t in &d.ranked {
        text += &line(t);
    }
    if !d.second_round.is_empty() {
        text += "second round:\n";
        for t in &d.second_round {
            text += &line(t);
        }
    }
    text += &format!("{} inert\n", d.inert.len());
    text
}

// ---------------------------------------------------------------- force/deflection

/// Noise of the force sensor (one standard deviation).
const FORCE_NOISE: f64 = 0.3e-3;
/// The paper's sensor step (seed Sec. V-A).
const SENSOR_STEP: f64 = 127e-6;

/// The force/deflection test of `dof` (swing along x, lift along z) at 225 V with the
/// sensor's y load `true_fraction` of the on-axis force: the on-axis force at every 127 µm
/// from the rest position until the free foot no longer reaches the sensor, from `truth`,
/// with noise; and the experiment file that reads it (stating `file_fraction`).
pub(crate) fn force_case(
    dir: &Path,
    truth: &Leg,
    dof: Dof,
    true_fraction: f64,
    file_fraction: f64,
    rng: &mut Rng,
) -> (Experiment, String) {
    let test = ForceTest::new(dof, 225.0, Sensor::Steps(SENSOR_STEP))
        .off_axis(true_fraction)
        .run(truth)
        .unwrap();
    let mut text = String::from("distance [um], force [mN]\n");
    for point in &test.points {
        let force = point.force + FORCE_NOISE * rng.normal();
        text += &format!("{}, {}\n", point.distance * 1e6, force * 1e3);
    }
    let name = dof.name();
    let experiment = common::hamr_vi_experiment_in(
        dir,
        &format!(
            "kind = \"force_deflection\"\ntitle = \"{name} force\"\ndof = \"{name}\"\n\
             voltage = \"225 V\"\noff_axis_fraction = {file_fraction}\nnoise = \"0.3 mN\"\n"
        ),
    );
    (experiment, text)
}

fn blocked_swing_force(leg: &Leg) -> f64 {
    ForceTest::new(Dof::Swing, 225.0, Sensor::Blocked)
        .off_axis(0.3)
        .run(leg)
        .unwrap()
        .blocked_force()
}

/// HAMR-VI with flexure fb3 twisting about y (Eq. 8's stiffness) and the other hinges
/// compliant off their axes by `compliance`, written by hand in `dir`, and the fraction of the
/// blocked swing force that this removes.
fn fb3_twisting(dir: &Path, compliance: f64) -> (Leg, f64) {
    let base = blocked_swing_force(&Leg::open(&common::hamr_vi_spec()).unwrap());
    let effect = WrittenEffect::Twist {
        hinges: &[("fb3", 1)],
        off_axis_compliance: compliance,
    };
    let truth = common::hamr_vi_written(effect, dir);
    let loss = 1.0 - blocked_swing_force(&truth) / base;
    (truth, loss)
}

/// Twist that removes 30–50 % of the swing force (the seed's finding, Sec. V-A): flexure fb3
/// twists about y with Eq. 8's stiffness, the other hinges' off-axis compliance drawn so that
/// the blocked swing force falls by 30–50 %. The diagnosis must name the twist of fb3 about y
/// and recover the off-axis compliance within 30 %.
fn twist_case(dir: &Path, rng: &mut Rng) {
    let compliance = 10f64.powf(rng.uniform(-3.6, -3.2));
    let (truth, loss) = fb3_twisting(dir, compliance);
    assert!(
        (0.3..=0.5).contains(&loss),
        "the generator's twist removes {loss}"
    );
    let (experiment, text) = force_case(dir, &truth, Dof::Swing, 0.3, 0.3, rng);
    let d = diagnose_data(dir, &experiment, &text);
    let best = d.ranked.first().expect("a ranked candidate");
    assert_eq!(
        (best.cause.as_str(), best.location.as_str()),
        ("flexure twist", "flexure fb3 about y"),
        "{}",
        summary(&d)
    );
    assert_eq!(d.verdict, Verdict::Explained, "{}", summary(&d));
    let fitted = best
        .parameters
        .iter()
        .find(|p| p.0 == OFF_AXIS_COMPLIANCE)
        .unwrap();
    assert!(
        (fitted.2 / compliance - 1.0).abs() < 0.3,
        "compliance {} vs {compliance}\n{}",
        fitted.2,
        summary(&d)
    );
    assert!(
        best.holdout_chi2 < 0.2 * d.base.holdout_chi2,
        "{}",
        summary(&d)
    );
    // The gain in the features a designer reads (seed Table IV): the base model's blocked
    // force is off by the twist's 30–50 % (relative to the data: +40 % or more), the best
    // candidate's within 5 %.
    let blocked = |values: &[f64]| {
        features(&experiment, &d.observations, values)
            .into_iter()
            .find(|f| f.name == "blocked force")
            .and_then(|f| f.value)
            .unwrap()
    };
    let data = blocked(&d.observations.values);
    let (base, fitted) = (blocked(&d.base.predicted), blocked(&best.predicted));
    assert!(
        base / data - 1.0 > 0.4 && (fitted / data - 1.0).abs() < 0.05,
        "blocked force: data {data}, base {base}, best {fitted}"
    );
}

/// Twist at four hinges of the spherical five-bar together (s3 about x, fb1 about z, fb2
/// about z, fb3 about x: each a twist its loop locks when alone), the other hinges stiff off
/// their axes: it unlocks the loop and removes ~43 % of the swing force whatever the
/// off-axis compliance. The diagnosis must name the twist of that loop with those axes (alone
/// or tied with an explanation the force curve cannot tell from it), Eq. 8's stiffness within
/// 3σ, and no single hinge's twist among the best. Before the loop candidates: "partly
/// explained: actuator base compliance".
#[test]
#[ignore = "slow: run by .ci/run with the catalog's seeds"]
fn hidden_effect_twist_of_one_loop() {
    let dir = common::scratch_dir("hidden_effect_loop_twist");
    let effect = WrittenEffect::Twist {
        hinges: &[("s3", 0), ("fb1", 2), ("fb2", 2), ("fb3", 0)],
        off_axis_compliance: 1e-4,
    };
    let truth = common::hamr_vi_written(effect, &dir);
    let mut rng = Rng::new(5);
    let (experiment, text) = force_case(&dir, &truth, Dof::Swing, 0.3, 0.3, &mut rng);
    let d = diagnose_data(&dir, &experiment, &text);
    assert_eq!(d.verdict, Verdict::Explained, "{}", summary(&d));
    let best = &d.ranked[..d.tied.max(1)];
    let truth_found = best.iter().find(|t| {
        t.cause == "flexure twist"
            && ["s3 about x", "fb1 about z", "fb2 about z", "fb3 about x"]
                .iter()
                .all(|hinge| t.location.contains(hinge))
    });
    let found = truth_found.unwrap_or_else(|| panic!("{}", summary(&d)));
    assert!(
        best.iter().all(|t| !t.location.starts_with("flexure ")),
        "a single hinge's twist among the best\n{}",
        summary(&d)
    );
    let (_, _, factor, se) = found.parameters[0].clone();
    assert!(
        se > 0.0 && se < 0.2 && (factor - 1.0).abs() < 3.0 * se,
        "twist factor {factor} ± {se}\n{}",
        summary(&d)
    );
    assert_holdout_gain(&d, found);
    // The force curve may not tell this loop's twist from the swing crank-slider's (seen:
    // ΔAICc 1.9, a tie): a tie names a standard test that tells them apart.
    assert!(
        d.tied <= 1 || d.separations.first().is_some_and(|s| s.chi2 >= SEPARATES),
        "{:?}\n{}",
        d.separations,
        summary(&d)
    );
}

/// The held-out values, which no fit saw, are outside the noise band under the base model
/// and inside it under `trial`.
fn assert_holdout_gain(d: &Diagnosis, trial: &Trial) {
    let band = d.noise_band * d.holdout_values as f64;
    assert!(
        d.base.holdout_chi2 > band && trial.holdout_chi2 <= band,
        "held-out χ² {:.1} → {:.1}, noise band {band:.1}\n{}",
        d.base.holdout_chi2,
        trial.holdout_chi2,
        summary(d)
    );
}

/// Checks the top of `d`: the cause and where it acts, the verdict, the held-out gain, and
/// returns the fitted value of `parameter`.
pub(crate) fn top(d: &Diagnosis, cause: &str, location: &str, parameter: &str) -> f64 {
    let best = d
        .combined
        .as_ref()
        .or(d.ranked.first())
        .expect("a ranked candidate");
    assert_eq!(
        (best.cause.as_str(), best.location.as_str()),
        (cause, location),
        "{}",
        summary(d)
    );
    assert_eq!(d.verdict, Verdict::Explained, "{}", summary(d));
    assert!(
        best.holdout_chi2 < 0.5 * d.base.holdout_chi2,
        "{}",
        summary(d)
    );
    best.parameters
        .iter()
        .find(|p| p.0 == parameter)
        .unwrap_or_else(|| panic!("no {parameter}\n{}", summary(d)))
        .2
}

/// The on-axis sensor force at each 127 µm step of `dof`'s force test at 225 V, the sensor
/// also pushing on the foot along y with `fraction` of that force, opposing the free foot's
/// y motion — computed without the statics' side-load code ([`ForceTest::off_axis`]): the
/// y force is a plain force at the foot written into the model (`side_force`), applied only
/// while the sensor holds the foot (rest and free deflection are unloaded), and iterated to
/// the fixed point `F_y = −sign(free y motion)·fraction·F` at each sensor position.
fn side_loaded_forces(dir: &Path, dof: Dof, fraction: f64) -> Vec<(f64, f64)> {
    let mut leg = common::hamr_vi_written(WrittenEffect::FootSideForce, dir);
    let unloaded = ForceTest::new(dof, 225.0, Sensor::Steps(SENSOR_STEP))
        .run(&leg)
        .unwrap();
    let y_direction = (unloaded.free[1] - unloaded.rest[1]).signum();
    let (axis, inputs) = (dof.axis(), leg.drive(dof, 225.0));
    let mut q = unloaded.rest_q.clone();
    unloaded
        .points
        .iter()
        .map(|point| {
            if point.force == 0.0 {
                return (point.distance, 0.0); // beyond the free foot's reach
            }
            let mut target = unloaded.rest;
            target[axis] += unloaded.direction * point.distance;
            let (mut side, mut force) = (0.0, 0.0);
            for _ in 0..100 {
                common::set_leg_param(&mut leg, FOOT_SIDE_FORCE, side);
                let fixture = leg.fixture(target, vec![axis]);
                let equilibrium = leg.equilibrium(&q, &inputs, &[fixture]).unwrap();
                force = -equilibrium.fixture_forces[0][axis] * unloaded.direction;
                q = equilibrium.q;
                let next = -y_direction * fraction * force;
                if (next - side).abs() < 1e-13 {
                    break;
                }
                side = next;
            }
            (point.distance, force)
        })
        .collect()
}

/// The two formulations of the sensor's side load agree: the statics' side load of the
/// fixture ([`ForceTest::off_axis`]) and a plain foot force iterated to its fixed point,
/// to 1e-8 of the blocked force (each equilibrium converges to 1e-10 of the model's force
/// scale; seen: 1.1e-9).
#[test]
fn the_side_load_equals_a_foot_force_at_its_fixed_point() {
    let dir = common::scratch_dir("side_load_fixed_point");
    let written = side_loaded_forces(&dir, Dof::Lift, 0.3);
    let statics = ForceTest::new(Dof::Lift, 225.0, Sensor::Steps(SENSOR_STEP))
        .off_axis(0.3)
        .run(&Leg::open(&common::hamr_vi_spec()).unwrap())
        .unwrap();
    let unloaded = ForceTest::new(Dof::Lift, 225.0, Sensor::Blocked)
        .run(&Leg::open(&common::hamr_vi_spec()).unwrap())
        .unwrap();
    assert_eq!(written.len(), statics.points.len());
    for ((distance, force), point) in written.iter().zip(&statics.points) {
        assert_eq!(*distance, point.distance);
        assert!(
            (force - point.force).abs() < 1e-8 * unloaded.blocked_force(),
            "at {distance}: {force} vs {}",
            point.force
        );
    }
    let blocked = written[0].1;
    assert!(
        (blocked / unloaded.blocked_force() - 1.0).abs() > 1e-3,
        "the side load changes the blocked force: {blocked} vs {}",
        unloaded.blocked_force()
    );
}

/// An unmodelled off-axis load: the sensor pushes on the foot along y with 20–40 % of the
/// on-axis force (the seed's ~30 %), the experiment file says none. Lift force data made by
/// [`side_loaded_forces`], not by the side-load code the candidate fits with; the fraction
/// recovered within 0.05.
fn off_axis_load_case(dir: &Path, rng: &mut Rng) {
    let fraction = rng.uniform(0.2, 0.4);
    let mut text = String::from("distance [um], force [mN]\n");
    for (distance, force) in side_loaded_forces(dir, Dof::Lift, fraction) {
        let force = force + FORCE_NOISE * rng.normal();
        text += &format!("{}, {}\n", distance * 1e6, force * 1e3);
    }
    let experiment = common::hamr_vi_experiment_in(
        dir,
        "kind = \"force_deflection\"\ntitle = \"lift force\"\ndof = \"lift\"\n\
         voltage = \"225 V\"\noff_axis_fraction = 0\nnoise = \"0.3 mN\"\n",
    );
    let d = diagnose_data(dir, &experiment, &text);
    let fitted = top(
        &d,
        "unmodelled off-axis load at the foot",
        "foot (the sensor's y force)",
        "off_axis_fraction",
    );
    assert!((fitted - fraction).abs() < 0.05, "{fitted} vs {fraction}");
}

/// A compliant actuator base: the lift actuator's base compliance 0.2–0.5 of its own (force
/// and stroke fall by 1/(1 + c)). Lift force data; c recovered within 15 %.
fn base_compliance_case(dir: &Path, rng: &mut Rng) {
    let compliance = rng.uniform(0.2, 0.5);
    let truth = common::hamr_vi_written(WrittenEffect::LiftBaseCompliance(compliance), dir);
    let (experiment, text) = force_case(dir, &truth, Dof::Lift, 0.0, 0.0, rng);
    let d = diagnose_data(dir, &experiment, &text);
    let fitted = top(
        &d,
        "actuator base compliance",
        "actuator along qlact",
        BASE_COMPLIANCE,
    );
    assert!(
        (fitted / compliance - 1.0).abs() < 0.15,
        "{fitted} vs {compliance}"
    );
}

/// A misaligned hinge: l2's bending axis tilted 1–2° about y, the hinges' off-axis
/// compliance 1e-4 of their bending compliance (`(t/w)²` for w = 2.5 mm, t = 25 µm). It
/// stiffens the lift transmission (the seed's lift stroke loss, Sec. V-A). 17 quasi-static
/// points of a lift sweep to 225 V, foot z with 2 µm noise
/// (its sign is not observable: a tilt acts to second order); the assertions say what these
/// data can and cannot tell.
fn misalignment_case(dir: &Path, rng: &mut Rng) {
    let angle = rng.uniform(1.0, 2.0).to_radians();
    let effect = WrittenEffect::Tilt {
        flexure: "l2",
        about: 1,
        angle,
        off_axis_compliance: 1e-4,
    };
    let truth = common::hamr_vi_written(effect, dir);
    let experiment = common::hamr_vi_experiment_in(
        dir,
        "kind = \"quasi_static\"\ntitle = \"lift sweep\"\n\
         outputs = [\"foot.z\"]\nnoise = [\"2 um\"]\n",
    );
    let mut text = String::from("v_lift [V], foot.z [mm]\n");
    let mut q = truth.q0.clone();
    for k in 0..17 {
        let volts = 225.0 * k as f64 / 16.0;
        let inputs = truth.inputs(volts, 0.0);
        q = truth.equilibrium(&q, &inputs, &[]).unwrap().q;
        let z = truth.foot_at(&q, &inputs)[2] + 2e-6 * rng.normal();
        text += &format!("{volts}, {}\n", z * 1e3);
    }
    let d = diagnose_data(dir, &experiment, &text);
    // Measured: a tilt about y or about z of l2 fit these data equally (AICc within 2: the
    // diagnosis reports them tied), and so, for some noise draws (seed 7), does l2 simply
    // stiffer: a lift sweep sees the tilted hinge only through its extra stiffness, which
    // grows as α²·k/c (the bending forced about an axis α off, against the off-axis
    // stiffness k/c). So α and c are not recovered alone, but α²/c is. Asserted: every
    // supported cause acts at l2, the true tilt among them, the held-out gain, and α²/c of
    // the true tilt's fit within 20 %.
    assert_eq!(d.verdict, Verdict::Explained, "{}", summary(&d));
    let supported = &d.ranked[..d.tied.max(1)];
    assert!(
        supported
            .iter()
            .all(|t| t.location.starts_with("flexure l2")),
        "{}",
        summary(&d)
    );
    let tilt = supported
        .iter()
        .find(|t| t.location == "flexure l2 tilted about y")
        .unwrap_or_else(|| panic!("the true tilt is not supported\n{}", summary(&d)));
    assert!(
        d.ranked[0].holdout_chi2 < 1e-3 * d.base.holdout_chi2,
        "{}",
        summary(&d)
    );
    let value = |name: &str| tilt.parameters.iter().find(|p| p.0 == name).unwrap().2;
    let (alpha, compliance) = (value(MISALIGNMENT), value(OFF_AXIS_COMPLIANCE));
    let (fitted, true_value) = (alpha.powi(2) / compliance, angle.powi(2) / 1e-4);
    eprintln!("misalignment: α²/c = {fitted:.3} vs {true_value:.3}");
    assert!(
        (fitted / true_value - 1.0).abs() < 0.2,
        "α²/c = {fitted} (α {alpha}, c {compliance}) vs {true_value} (α {angle}, c 1e-4)\n{}",
        summary(&d)
    );
}

/// The Bode experiment's frequencies: 30 log-spaced from 1 to 150 Hz.
pub(crate) fn bode_frequencies() -> impl Iterator<Item = f64> {
    (0..30).map(|k| 150.0f64.powf(k as f64 / 29.0))
}

/// Noise-free lift and swing responses of `leg` at [`bode_frequencies`] with `damping`:
/// per frequency, `[gain, phase (deg)]` of lift (v_lift → foot.z), then swing
/// (v_swing → foot.x).
pub(crate) fn bode_responses(
    leg: &Leg,
    damping: mech_runtime::FlexureDamping,
) -> Vec<[[f64; 2]; 2]> {
    let rest_inputs = leg.inputs(0.0, 0.0);
    let rest = leg.equilibrium(&leg.q0, &rest_inputs, &[]).unwrap().q;
    let linear =
        mech_runtime::linearize(leg.model(), 0.0, &rest, &rest_inputs, &leg.independent).unwrap();
    let channels = [
        (leg.v_lift(), leg.foot()[2]),
        (leg.v_swing(), leg.foot()[0]),
    ];
    bode_frequencies()
        .map(|f| {
            let omega = 2.0 * std::f64::consts::PI * f;
            channels.map(|(input, output)| {
                let h = linear
                    .frequency_response(input, output, omega, damping)
                    .unwrap();
                [h.norm(), h.arg().to_degrees()]
            })
        })
        .collect()
}

/// Noise of the Bode data: relative gain, phase (deg).
const GAIN_NOISE: f64 = 0.02;
const PHASE_NOISE: f64 = 1.0;

/// Lift and swing Bode curves of `truth` (1–150 Hz, 30 points, 2 % gain and 1° phase noise)
/// with `damping` for the flexure losses, and the two-channel experiment that reads them.
fn bode_case(
    dir: &Path,
    truth: &Leg,
    damping: mech_runtime::FlexureDamping,
    rng: &mut Rng,
) -> (Experiment, String) {
    bode_data(dir, &bode_responses(truth, damping), rng)
}

/// [`bode_case`] from noise-free `responses` at [`bode_frequencies`] (`[gain, phase (deg)]`
/// of lift, then swing).
pub(crate) fn bode_data(
    dir: &Path,
    responses: &[[[f64; 2]; 2]],
    rng: &mut Rng,
) -> (Experiment, String) {
    let experiment = common::hamr_vi_experiment_in(
        dir,
        "kind = \"frequency_response\"\ntitle = \"lift and swing\"\n\
         gain_noise = \"2 %\"\nphase_noise = \"1 deg\"\n\
         [[channel]]\nname = \"lift\"\ninput = \"v_lift\"\noutput = \"foot.z\"\n\
         [[channel]]\nname = \"swing\"\ninput = \"v_swing\"\noutput = \"foot.x\"\n",
    );
    let mut text = String::from(
        "frequency [Hz], gain.lift [mm/V], phase.lift [deg], gain.swing [mm/V], phase.swing [deg]\n",
    );
    for (f, channels) in bode_frequencies().zip(responses) {
        text += &format!("{f}");
        for [gain, phase] in channels {
            let gain = gain * (1.0 + GAIN_NOISE * rng.normal());
            let phase = phase + PHASE_NOISE * rng.normal();
            text += &format!(", {}, {phase}", gain * 1e3);
        }
        text += "\n";
    }
    (experiment, text)
}

/// The χ² that separates two noise-free Bode responses at the data's noise (gain residuals
/// on ln |H|, as the diagnosis takes them): below 1, no data set of this design tells them
/// apart.
fn separation_chi2(a: &[[[f64; 2]; 2]], b: &[[[f64; 2]; 2]]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(a, b)| a.iter().zip(b))
        .map(|(a, b)| {
            ((a[0] / b[0]).ln() / GAIN_NOISE).powi(2) + ((a[1] - b[1]) / PHASE_NOISE).powi(2)
        })
        .sum()
}

/// A mass on the lift actuator's tip, 10–20 mg (a bimorph's effective tip mass is about a
/// quarter of its ~60 mg), in Bode data of both channels (2 %, 1°), the truth written into
/// the model text. The leg's inertia reflected through the transmission dominates the
/// actuator's mass: 15 mg moves the modes 78.905 → 78.828 Hz and 106.329 → 106.287 Hz
/// (`tests/equations/actuator_extensions.rs`), which the phase near the resonances shows
/// (separation χ² between truth and base 14.5 at 17.8 mg, ∝ mass²: 4.6–18 over the
/// drawn range, on 120 values — one parameter's worth, which the base model's total χ²
/// may or may not lift out of its noise band: seen both verdicts). Asserted: (1) the
/// separation, computed from the two noise-free responses; (2) no cause other than the tip
/// mass stands alone; (3) the tip-mass candidate recovers the mass within 3σ, with σ what
/// the sensitivity predicts, `mass/√χ²_sep`, within 30 % — a fit that failed, or reported
/// an uncertainty the data do not give, fails here.
fn tip_mass_case(dir: &Path, rng: &mut Rng) {
    let mass = rng.uniform(10e-6, 20e-6);
    let truth = common::hamr_vi_written(WrittenEffect::LiftTipMass(mass), dir);
    let damping = mech_runtime::FlexureDamping::Hysteretic;
    let base = Leg::open(&common::hamr_vi_spec()).unwrap();
    let separation = separation_chi2(
        &bode_responses(&truth, damping),
        &bode_responses(&base, damping),
    );
    assert!(
        (4.0..40.0).contains(&separation),
        "mass {mass}: separation χ² {separation}"
    );
    let (experiment, text) = bode_case(dir, &truth, damping, rng);
    let d = diagnose_data(dir, &experiment, &text);
    let is_tip_mass =
        |t: &&Trial| t.cause == "actuator tip mass" && t.location == "actuator along qlact";
    if d.verdict != Verdict::NoSignificantDiscrepancy {
        assert!(
            d.ranked[..d.tied.max(1)].iter().any(|t| is_tip_mass(&t)),
            "a cause other than the tip mass stands alone (mass {mass})\n{}",
            summary(&d)
        );
    }
    let trial = d
        .ranked
        .iter()
        .chain(&d.inert)
        .find(is_tip_mass)
        .expect("the tip-mass candidate");
    let (_, _, fitted, se) = trial
        .parameters
        .iter()
        .find(|p| p.0 == TIP_MASS)
        .cloned()
        .unwrap_or_else(|| panic!("not fitted\n{}", summary(&d)));
    let predicted = mass / separation.sqrt();
    eprintln!(
        "tip mass {mass:e}: separation χ² {separation:.1}, fitted {fitted:e} ± {se:e} \
         (σ predicted {predicted:e}), verdict {:?}",
        d.verdict
    );
    assert!(
        (fitted - mass).abs() < 3.0 * se && (se / predicted - 1.0).abs() < 0.3,
        "m = {fitted} ± {se} (σ predicted {predicted}) vs {mass}\n{}",
        summary(&d)
    );
}

/// The seed's 50 µm actuator preload in −y (Sec. V-A; HAMR-VI's model has none), hidden in
/// 8 quasi-static points of the
/// paper's 1 Hz, 225 V drive (swing 90° ahead of lift), foot x, y, z with 2 µm noise; the
/// preload recovered within 10 µm.
fn preload_case(dir: &Path, rng: &mut Rng) {
    let preload = -50e-6;
    let truth = common::hamr_vi_written(WrittenEffect::Preload(preload), dir);
    let experiment = common::hamr_vi_experiment_in(
        dir,
        "kind = \"quasi_static\"\ntitle = \"1 Hz trajectory\"\n\
         outputs = [\"foot.x\", \"foot.y\", \"foot.z\"]\nnoise = [\"2 um\", \"2 um\", \"2 um\"]\n",
    );
    let mut text = String::from("v_lift [V], v_swing [V], foot.x [mm], foot.y [mm], foot.z [mm]\n");
    for (lift, swing, foot) in common::feet_along_the_drive(&truth) {
        let noisy: Vec<String> = foot
            .iter()
            .map(|x| format!("{}", (x + 2e-6 * rng.normal()) * 1e3))
            .collect();
        text += &format!("{lift}, {swing}, {}\n", noisy.join(", "));
    }
    let d = diagnose_data(dir, &experiment, &text);
    let fitted = top(&d, "actuator tip preload", "every actuator", TIP_PRELOAD);
    assert!((fitted - preload).abs() < 10e-6, "{fitted} vs {preload}");
}

/// A flexure's stiffness 20 % off (the size): a flexure drawn by the generator made
/// 20 % stiffer, in Bode data of both channels. How well such data see it is computed, not
/// assumed: the separation χ² between the truth's and the base model's noise-free
/// responses. The true flexure's own candidate must recover the factor within 4σ whatever
/// the verdict (unless the change cannot act: separation below 1, candidate inert); a change
/// the data clearly resolve (separation over 60, about what lifts the base model's χ² out
/// of its noise band) must be found, with the true flexure at the top or among the causes the
/// data support equally; on top, the factor within 5 %.
fn stiffness_case(dir: &Path, rng: &mut Rng) {
    let flexures = ["s1", "s2", "s3", "l1", "l2", "l3", "fb1", "fb2", "fb3"];
    let pick = flexures[rng.index(flexures.len())];
    let name = format!("k_{pick}");
    let mut truth = Leg::open(&common::hamr_vi_spec()).unwrap();
    let nominal = truth.param(&name).unwrap();
    common::set_leg_param(&mut truth, &name, 1.2 * nominal);
    let damping = mech_runtime::FlexureDamping::Hysteretic;
    let base = Leg::open(&common::hamr_vi_spec()).unwrap();
    let separation = separation_chi2(
        &bode_responses(&truth, damping),
        &bode_responses(&base, damping),
    );
    let (experiment, text) = bode_case(dir, &truth, damping, rng);
    let d = diagnose_data(dir, &experiment, &text);
    let location = format!("flexure {pick}");
    let is_true =
        |t: &&Trial| t.location == location && t.cause == "flexure stiffness off by a factor";
    eprintln!(
        "{name}: separation χ² {separation:.1}, verdict {:?}",
        d.verdict
    );
    let Some(own) = d.ranked.iter().find(is_true) else {
        assert!(
            separation < 1.0 && d.inert.iter().any(|t| is_true(&t)),
            "{name}: no fit of the true flexure (separation {separation})\n{}",
            summary(&d)
        );
        return;
    };
    let (_, nominal, value, se) = own.parameters[0];
    assert!(
        (value - 1.2 * nominal).abs() < 4.0 * se,
        "{name}: factor {} ± {} vs 1.2\n{}",
        value / nominal,
        se / nominal,
        summary(&d)
    );
    if separation > 60.0 {
        assert_ne!(
            d.verdict,
            Verdict::NoSignificantDiscrepancy,
            "{name}\n{}",
            summary(&d)
        );
        assert!(
            d.ranked[..d.tied.max(1)].iter().any(|t| is_true(&t)),
            "{name}\n{}",
            summary(&d)
        );
    }
    if d.ranked[0].location == location {
        assert!(
            (value / nominal - 1.2).abs() < 0.05,
            "{name}: factor {} ± {}",
            value / nominal,
            se / nominal
        );
    }
}

/// A loss factor that lowers the resonance Q by 27–38 % (the 30 %; Q ∝ 1/η): η drawn
/// from 0.11–0.13 instead of the model's 0.08, in Bode data of both channels. The diagnosis
/// must put a loss-factor cause on top (the frequency-dependent one nests the constant one:
/// they may tie), recover η within 0.01 and 3σ, and show the held-out gain.
fn loss_factor_case(dir: &Path, rng: &mut Rng) {
    let eta = rng.uniform(0.11, 0.13);
    let mut truth = Leg::open(&common::hamr_vi_spec()).unwrap();
    common::set_leg_param(&mut truth, "eta", eta);
    let damping = mech_runtime::FlexureDamping::Hysteretic;
    let (experiment, text) = bode_case(dir, &truth, damping, rng);
    let d = diagnose_data(dir, &experiment, &text);
    let constant = loss_factor_named(&d, eta);
    // With every third frequency held out, the rows near the resonances (where the loss
    // factor shows) fall mostly in the training set, so the held-out gain is modest (seen:
    // 76 → 42); it must still carry the held-out data from outside the noise band to inside.
    assert_holdout_gain(&d, constant);
}

/// The diagnosis explains the data by a loss factor: only loss-factor causes on top (the
/// frequency-dependent one nests the constant one: they may tie), the constant η among them
/// within 3σ and 0.01 of `eta`. Returns that trial.
pub(crate) fn loss_factor_named(d: &Diagnosis, eta: f64) -> &Trial {
    assert_eq!(d.verdict, Verdict::Explained, "{}", summary(d));
    let supported = &d.ranked[..d.tied.max(1)];
    assert!(
        supported.iter().all(|t| t.cause.contains("loss factor")),
        "{}",
        summary(d)
    );
    let constant = supported
        .iter()
        .find(|t| t.cause == "loss factor differs" && t.location == "all flexures")
        .unwrap_or_else(|| panic!("the constant loss factor is not supported\n{}", summary(d)));
    let (_, _, value, se) = constant.parameters[0];
    assert!(
        (value - eta).abs() < 3.0 * se && (value - eta).abs() < 0.01,
        "η = {value} ± {se} vs {eta}\n{}",
        summary(d)
    );
    constant
}

/// The loss factor grows with frequency, η(f) = 0.08·(f/10 Hz)^α with α drawn from
/// 0.12–0.22 (the seed: η measured at 1–10 Hz; at the ~80 Hz lift resonance α = 0.17 lowers
/// Q by about 30 %), Bode data of both channels from 1 to 150 Hz. The diagnosis must prefer
/// the frequency-dependent loss factor to a constant one and recover the exponent within 3σ
/// (σ at least 0.01).
fn frequency_dependent_loss_case(dir: &Path, rng: &mut Rng) {
    let exponent = rng.uniform(0.12, 0.22);
    let truth = Leg::open(&common::hamr_vi_spec()).unwrap();
    let damping = mech_runtime::FlexureDamping::HystereticPowerLaw {
        exponent,
        reference_hz: 10.0,
    };
    let (experiment, text) = bode_case(dir, &truth, damping, rng);
    let d = diagnose_data(dir, &experiment, &text);
    assert_eq!(d.verdict, Verdict::Explained, "{}", summary(&d));
    let best = &d.ranked[0];
    assert_eq!(
        (best.cause.as_str(), best.location.as_str()),
        ("frequency-dependent loss factor", "all flexures"),
        "{}",
        summary(&d)
    );
    // A held-out gain, modest for the reason the loss-factor case gives (seen: 72 → 51).
    assert_holdout_gain(&d, best);
    let (_, _, fitted, se) = best
        .parameters
        .iter()
        .find(|p| p.0 == "loss_exponent")
        .cloned()
        .unwrap();
    assert!(
        (fitted - exponent).abs() < 3.0 * se.max(0.01),
        "α = {fitted} ± {se} vs {exponent}"
    );
}

// ---------------------------------------------------------------- the generator

/// The catalog's entries, each shown by the experiment its case builds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Entry {
    Twist,
    OffAxisLoad,
    BaseCompliance,
    Misalignment,
    TipMass,
    Preload,
    Stiffness,
    LossFactor,
    FrequencyDependentLoss,
}

const CATALOG: [Entry; 9] = [
    Entry::Twist,
    Entry::OffAxisLoad,
    Entry::BaseCompliance,
    Entry::Misalignment,
    Entry::TipMass,
    Entry::Preload,
    Entry::Stiffness,
    Entry::LossFactor,
    Entry::FrequencyDependentLoss,
];

/// The generator's choice: the entry is a seeded random choice from the catalog; the same
/// generator then draws the effect's size (and its location, where the entry has several)
/// and the noise.
fn draw(seed: u64) -> (Entry, Rng) {
    let mut rng = Rng::new(seed);
    let entry = CATALOG[rng.index(CATALOG.len())];
    (entry, rng)
}

/// Builds the data with the effect `seed` draws, hides everything but the CSV and the base
/// model, diagnoses, and checks what the entry's case says.
fn hidden_effect(seed: u64) {
    let (entry, mut rng) = draw(seed);
    eprintln!("seed {seed}: {entry:?}");
    let dir = common::scratch_dir(&format!("hidden_effect_{seed}"));
    let case = match entry {
        Entry::Twist => twist_case,
        Entry::OffAxisLoad => off_axis_load_case,
        Entry::BaseCompliance => base_compliance_case,
        Entry::Misalignment => misalignment_case,
        Entry::TipMass => tip_mass_case,
        Entry::Preload => preload_case,
        Entry::Stiffness => stiffness_case,
        Entry::LossFactor => loss_factor_case,
        Entry::FrequencyDependentLoss => frequency_dependent_loss_case,
    };
    case(&dir, &mut rng);
}

/// One test per seed, and `SEEDS` for the coverage check; the seeds after `slow:` are
/// ignored by `cargo test` and run by `.ci/run` (`-- --ignored`).
macro_rules! hidden_effect_tests {
    ($($name:ident: $seed:literal),* ; slow: $($slow:ident: $slow_seed:literal),* $(,)?) => {
        const SEEDS: &[u64] = &[$($seed),*, $($slow_seed),*];
        $(
            #[test]
            fn $name() {
                hidden_effect($seed)
            }
        )*
        $(
            #[test]
            #[ignore = "slow: the catalog's second and third seeds, run by .ci/run"]
            fn $slow() {
                hidden_effect($slow_seed)
            }
        )*
    };
}

// The first three seeds, counting from 1, that draw each entry: preload 1, 2, 8; off-axis
// load 3, 20, 33; misalignment 4, 5, 7; stiffness 6, 9, 13; twist 10, 18, 21; base
// compliance 11, 35, 61; tip mass 15, 17, 34; loss factor 22, 31, 37; frequency-dependent
// loss factor 23, 32, 36.
hidden_effect_tests!(
    hidden_effect_seed_1: 1,
    hidden_effect_seed_3: 3,
    hidden_effect_seed_4: 4,
    hidden_effect_seed_6: 6,
    hidden_effect_seed_10: 10,
    hidden_effect_seed_11: 11,
    hidden_effect_seed_15: 15,
    hidden_effect_seed_22: 22,
    hidden_effect_seed_23: 23;
    slow:
    hidden_effect_seed_2: 2,
    hidden_effect_seed_5: 5,
    hidden_effect_seed_7: 7,
    hidden_effect_seed_8: 8,
    hidden_effect_seed_9: 9,
    hidden_effect_seed_13: 13,
    hidden_effect_seed_17: 17,
    hidden_effect_seed_18: 18,
    hidden_effect_seed_20: 20,
    hidden_effect_seed_21: 21,
    hidden_effect_seed_31: 31,
    hidden_effect_seed_32: 32,
    hidden_effect_seed_33: 33,
    hidden_effect_seed_34: 34,
    hidden_effect_seed_35: 35,
    hidden_effect_seed_36: 36,
    hidden_effect_seed_37: 37,
    hidden_effect_seed_61: 61,
);

/// The seeds above run every entry of the catalog three times (a change of the generator
/// that leaves one out fails here, not silently).
#[test]
fn the_seeds_draw_every_catalog_entry() {
    let drawn: Vec<Entry> = SEEDS.iter().map(|&seed| draw(seed).0).collect();
    for entry in CATALOG {
        let count = drawn.iter().filter(|&&e| e == entry).count();
        assert_eq!(
            count, 3,
            "{entry:?} is drawn {count} times by {SEEDS:?}: {drawn:?}"
        );
    }
}

// ---------------------------------------------------------------- the paper's story

/// The seed's story for HAMR-VI (Sec. V-A, VI): the swing force almost 50 % below the model
/// (the sensor's ~30 % off-axis load twists s3 and fb3, Eq. 8), the swing resonance below
/// the model's, and quality factors over-estimated because the loss factor, measured at
/// 1–10 Hz, grows with frequency.
///
/// From the paper: the ~30 % off-axis load, the ~50 % swing force loss, the 1–140 Hz chirp
/// band, η measured at 1–10 Hz, twist stiffness 2k/(1 + ν) with ν = 0.34 (Eq. 8).
/// Chosen here: the twist acts at fb3 about y (our model's s3 twist is inert: the five-bar
/// locks it — the diagnosis lists it so); the other hinges' off-axis compliance
/// 6.25e-4 of their bending compliance, `(t/w)²` for 25 µm Kapton 1 mm wide (the width Eq. 2
/// gives for k_fb3 with a ~100 µm hinge); η(f) = 0.08·(f/5 Hz)^0.3; noise 0.3 mN, 2 %, 1°.
///
/// The finding about the paper: with Eq. 8's stiffness and that geometry estimate, the twist
/// of fb3 removes 45–60 % of the swing force (asserted below) — as much as the paper reports.
#[test]
fn the_papers_story_twist_and_a_frequency_dependent_loss_factor() {
    let dir = common::scratch_dir("paper_story");
    let mut rng = Rng::new(2024);
    let (truth, loss) = fb3_twisting(&dir, 6.25e-4);
    assert!(
        (0.45..=0.6).contains(&loss),
        "Eq. 8 twist at fb3 removes {:.0} % of the swing force",
        100.0 * loss
    );

    // Force/deflection: the swing force, ~50 % low → twist of fb3.
    let (experiment, text) = force_case(&dir, &truth, Dof::Swing, 0.3, 0.3, &mut rng);
    let d = diagnose_data(&dir, &experiment, &text);
    top(
        &d,
        "flexure twist",
        "flexure fb3 about y",
        OFF_AXIS_COMPLIANCE,
    );
    assert!(
        d.inert
            .iter()
            .any(|t| t.location.starts_with("flexure s3 about")),
        "s3's twist should be reported inert\n{}",
        summary(&d)
    );

    // The chirp: swing resonance low and Q over-estimated → twist and η(f), together.
    let bode_dir = common::scratch_dir("paper_story_bode");
    let damping = mech_runtime::FlexureDamping::HystereticPowerLaw {
        exponent: 0.3,
        reference_hz: 5.0,
    };
    let (experiment, text) = bode_case(&bode_dir, &truth, damping, &mut rng);
    let d = diagnose_data(&bode_dir, &experiment, &text);
    let both = d
        .combined
        .as_ref()
        .unwrap_or_else(|| panic!("no second cause\n{}", summary(&d)));
    assert!(
        both.cause.contains("flexure twist")
            && both.cause.contains("frequency-dependent loss factor")
            && both.location.contains("fb3 about y"),
        "{}: {}\n{}",
        both.cause,
        both.location,
        summary(&d)
    );
    assert_eq!(d.verdict, Verdict::Explained, "{}", summary(&d));
    let exponent = both
        .parameters
        .iter()
        .find(|p| p.0 == "loss_exponent")
        .unwrap()
        .2;
    assert!((exponent - 0.3).abs() < 0.1, "loss exponent {exponent}");
}
