//! The actuator extensions `mech diagnose` fits (base compliance, tip mass, preload) against
//! closed forms on one actuator driving one slider, and against the same effect written into
//! `.mech` text: a base body on its own spring, a heavier tip, actuators moved along their
//! sliders. The diagnosis catalog's hidden-effect data come from those written models, so a
//! wrong transform cannot fit its own data perfectly.

use crate::common;

use common::WrittenEffect;
use mech::diagnose::extend::{apply, open_leg, Extension};
use mech::experiments::leg::{Dof, ForceTest, Leg, Sensor};
use mech::tape_model::TapeModel;
use mech_codegen::ir::transform::actuator::{BASE_COMPLIANCE, TIP_MASS, TIP_PRELOAD};
use mech_codegen::Compiled;
use mech_runtime::Model;

/// One bimorph on a slider: force source `F_b v / V_rated` in parallel with
/// `k_a = F_b / δ_f` (seed Eq. 3), tip mass 5 mg, no gravity along the slider.
const SLIDER: &str = "
    param F_b = 300 mN;
    param delta_f = 250 um;
    param V_rated = 200 V;
    input v = 0 V;
    body tip { mass = 5 mg; }
    joint x = slider(newtonian, tip) { axis = y; }
    actuator drive on x {
        blocked_force = F_b; free_deflection = delta_f; rated_voltage = V_rated; voltage = v;
    }
";

const F_B: f64 = 0.3;
const DELTA_F: f64 = 250e-6;
const K_A: f64 = F_B / DELTA_F;
const TIP: f64 = 5e-6;

/// The slider model with `extension` applied and its new parameter set to `value`.
fn extended(extension: &Extension, parameter: &str, value: f64) -> TapeModel {
    let mut model = common::compile_text("slider", SLIDER).model;
    apply(&mut model, extension).unwrap();
    let mut tape = TapeModel::new(&Compiled::from_model(model));
    let index = tape.param_index(parameter).unwrap();
    tape.set_param(index, value);
    tape
}

/// The generalized force at (q, u = 0) under drive voltage `volts`.
fn force(model: &dyn Model, q: f64, volts: f64) -> f64 {
    let mut f = [0.0];
    model.forcing(0.0, &[q], &[0.0], &[volts], &mut f);
    f[0]
}

fn assert_close(value: f64, expected: f64, what: &str) {
    common::assert_close(what, value, expected, 1e-12, 1e-12);
}

/// A base spring `k_b = k_a / c` in series: the tip force `(F_b V/V_r − k_a x)/(1 + c)`,
/// so the blocked force falls by `1/(1 + c)` and the free deflection stays `δ_f`.
#[test]
fn base_compliance_scales_force_and_stiffness_by_one_over_one_plus_c() {
    let c = 0.35;
    let model = extended(&Extension::BaseCompliance("x".into()), BASE_COMPLIANCE, c);
    for (q, volts) in [(0.0, 200.0), (1e-4, 150.0), (-3e-5, 0.0)] {
        let expected = (F_B * volts / 200.0 - K_A * q) / (1.0 + c);
        assert_close(force(&model, q, volts), expected, "tip force");
    }
    // Free deflection unchanged: zero force at δ_f under the rated voltage.
    assert!(force(&model, DELTA_F, 200.0).abs() < 1e-12);
}

/// A mass on the tip adds to the slider's mass: `M = m + Δm`.
#[test]
fn tip_mass_adds_to_the_sliders_mass() {
    let added = 12e-6;
    let model = extended(&Extension::TipMass("x".into()), TIP_MASS, added);
    let mut m = [0.0];
    model.mass_matrix(0.0, &[1e-4], &[0.0], &mut m);
    assert_close(m[0], TIP + added, "mass");
}

/// A preload `p` moves the spring's rest: `F = −k_a (x − p)` at zero voltage.
#[test]
fn preload_moves_the_springs_rest_along_the_slider() {
    let p = -50e-6;
    let model = extended(&Extension::Preload, TIP_PRELOAD, p);
    for q in [0.0, 2e-5, -7e-5] {
        assert_close(force(&model, q, 0.0), -K_A * (q - p), "spring force");
    }
}

// ---------------------------------------------------------------- on HAMR-VI, against text

/// HAMR-VI with `extension` (its parameter at `value`), as `mech diagnose` builds it.
fn transformed(extension: Extension, parameter: &str, value: f64) -> Leg {
    let mut leg = open_leg(&common::hamr_vi_spec(), &extension).unwrap();
    common::set_leg_param(&mut leg, parameter, value);
    leg
}

/// The seed's 50 µm preload in −y: the transform's spring rest against the actuators' joints
/// moved in the text. The feet agree to 1 nm (Newton's tolerance; the preload moves them by
/// micrometres).
#[test]
fn preload_equals_the_actuators_moved_in_the_text() {
    let feet = common::feet_at_rest_and_225_volts;
    let dir = common::scratch_dir("written_preload");
    let offset = -50e-6;
    let written = feet(&common::hamr_vi_written(
        WrittenEffect::Preload(offset),
        &dir,
    ));
    let fitted = feet(&transformed(Extension::Preload, TIP_PRELOAD, offset));
    let base = feet(&Leg::open(&common::hamr_vi_spec()).unwrap());
    for ((w, f), b) in written.iter().zip(&fitted).zip(&base) {
        for axis in 0..3 {
            assert!((w[axis] - f[axis]).abs() < 1e-9, "{w:?} vs {f:?}");
        }
        assert!(
            (w[1] - b[1]).abs() > 1e-6,
            "the preload moves the foot: {w:?} vs {b:?}"
        );
    }
}

/// A compliant lift-actuator base: the transform's condensed series spring against a base
/// body on its own spring in the text. Blocked force and free deflection agree to 1e-8.
#[test]
fn base_compliance_equals_a_base_body_on_its_own_spring() {
    let dir = common::scratch_dir("written_base_compliance");
    let c = 0.35;
    let test = ForceTest::new(Dof::Lift, 225.0, Sensor::Blocked);
    let written = test
        .run(&common::hamr_vi_written(
            WrittenEffect::LiftBaseCompliance(c),
            &dir,
        ))
        .unwrap();
    let fitted = test
        .run(&transformed(
            Extension::BaseCompliance("qlact".into()),
            BASE_COMPLIANCE,
            c,
        ))
        .unwrap();
    let base = test
        .run(&Leg::open(&common::hamr_vi_spec()).unwrap())
        .unwrap();
    common::assert_close(
        "blocked force",
        written.blocked_force(),
        fitted.blocked_force(),
        1e-8,
        0.0,
    );
    common::assert_close(
        "free deflection",
        written.free_deflection,
        fitted.free_deflection,
        1e-8,
        0.0,
    );
    assert!(written.blocked_force() < 0.9 * base.blocked_force());
}

/// A 15 mg lift tip mass: the transform's point mass against the slider's mass raised in
/// the text. The two modes agree to 1e-9 relative.
#[test]
fn tip_mass_equals_a_heavier_slider_in_the_text() {
    let dir = common::scratch_dir("written_tip_mass");
    let mass = 15e-6;
    let modes = |leg: &Leg| -> Vec<f64> {
        let rest_inputs = leg.inputs(0.0, 0.0);
        let rest = leg.equilibrium(&leg.q0, &rest_inputs, &[]).unwrap().q;
        let linear =
            mech_runtime::linearize(leg.model(), 0.0, &rest, &rest_inputs, &leg.independent)
                .unwrap();
        linear
            .modes()
            .unwrap()
            .iter()
            .map(|m| m.frequency_hz())
            .collect()
    };
    let written = modes(&common::hamr_vi_written(
        WrittenEffect::LiftTipMass(mass),
        &dir,
    ));
    let fitted = modes(&transformed(
        Extension::TipMass("qlact".into()),
        TIP_MASS,
        mass,
    ));
    let base = modes(&Leg::open(&common::hamr_vi_spec()).unwrap());
    assert_eq!(written.len(), 2);
    for ((w, f), b) in written.iter().zip(&fitted).zip(&base) {
        common::assert_close("mode (Hz)", *w, *f, 1e-9, 0.0);
        println!("mode {b:.3} Hz → {w:.3} Hz with the tip mass");
    }
}
