//! The experiment files (`experiments/*.toml`, `mech experiment`, `mech report`): every kind
//! runs on the bundled HAMR models and gives physically consistent, checkable numbers. The
//! specs are the bundled ones, thinned (fewer points, no chirp) to keep debug builds fast.

use std::path::PathBuf;

use mech::experiments::{self, leg, Experiment};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A bundled experiment file with its model path made absolute and some keys replaced.
fn bundled(file: &str, replace: &[(&str, &str)]) -> Experiment {
    let mut text = std::fs::read_to_string(root().join("experiments").join(file)).unwrap();
    text = text.replace("\"models/", &format!("\"{}/models/", root().display()));
    for (from, to) in replace {
        assert!(text.contains(from), "{file}: no `{from}`");
        text = text.replace(from, to);
    }
    experiments::parse(&text).unwrap_or_else(|e| panic!("{file}: {e}"))
}

fn out(name: &str) -> PathBuf {
    std::env::temp_dir()
        .join(format!("mech-experiments-test-{}", std::process::id()))
        .join(name)
}

fn close(a: f64, b: f64, tolerance: f64) -> bool {
    (a / b - 1.0).abs() < tolerance
}

#[test]
fn every_bundled_experiment_file_parses() {
    for entry in std::fs::read_dir(root().join("experiments")).unwrap() {
        let path = entry.unwrap().path();
        experiments::load(&path).unwrap_or_else(|e| panic!("{e}"));
    }
}

#[test]
fn bad_experiment_files_give_clear_errors() {
    let missing_kind = experiments::parse("title = \"x\"").unwrap_err();
    assert!(missing_kind.contains("kind"), "{missing_kind}");
    let unknown = experiments::parse("kind = \"trajectory\"\ntitle = \"t\"\nmodel = \"m.mech\"\namplitude = \"225 V\"\nfrequency = \"1 Hz\"\nvolts = 3").unwrap_err();
    assert!(unknown.contains("volts"), "{unknown}");
    let unit = experiments::parse("kind = \"trajectory\"\ntitle = \"t\"\nmodel = \"m.mech\"\namplitude = \"225 mm\"\nfrequency = \"1 Hz\"").unwrap_err();
    assert!(
        unit.contains("amplitude") && unit.contains("voltage"),
        "{unit}"
    );
}

#[test]
fn trajectory_peak_equals_the_statics_deflection_at_the_peak_voltage() {
    let spec = bundled("hamr_vi_trajectory.toml", &[("points = 72", "points = 8")]);
    let outcome = spec.run("trajectory", &out("trajectory")).unwrap();
    println!("{:?}", outcome.values);
    // The statics of the free leg at +225 V on the lift, independently.
    let Experiment::Trajectory(t) = &spec else {
        panic!()
    };
    let leg = leg::Leg::open(&experiments::ModelSpec {
        model: t.model.clone(),
        set: vec![],
        independent: t.independent.clone(),
    })
    .unwrap();
    let test = leg::force_deflection(&leg, leg::Dof::Lift, 2, 225.0, None, 0.0).unwrap();
    let dz = test.free[2] - test.rest[2];
    assert!(
        close(outcome.values["lift_peak_dz"], dz, 1e-9),
        "{} vs {dz}",
        outcome.values["lift_peak_dz"]
    );
    // Lift moves the foot up (z) and sideways (y), barely in x; swing moves it in x.
    assert!(
        outcome.values["lift_pp_z"] > 1e-3
            && outcome.values["lift_pp_x"] < 0.01 * outcome.values["lift_pp_z"]
    );
    assert!(
        outcome.values["swing_pp_x"] > 1e-3
            && outcome.values["swing_pp_z"] < 0.01 * outcome.values["swing_pp_x"]
    );
    assert_eq!(outcome.plots.len(), 2);
    assert!(outcome.plots.iter().all(|p| p.exists()));
}

#[test]
fn force_deflection_blocked_force_and_work() {
    let spec = bundled("hamr_vi_force.toml", &[("\"127 um\"", "\"1000 um\"")]);
    let outcome = spec.run("force", &out("force")).unwrap();
    let v = &outcome.values;
    println!("{v:?}");
    // Blocked force ≈ F_b / T at small motion (T = 13.1 lift → z, 14.3 swing → x), and
    // equals the runtime's fixture reaction where its KKT solver converges.
    assert!(
        close(v["lift_blocked_force"], 0.320 / 13.07, 0.05),
        "{}",
        v["lift_blocked_force"]
    );
    assert!(
        close(v["swing_blocked_force"], 0.320 / 14.3, 0.05),
        "{}",
        v["swing_blocked_force"]
    );
    assert!(close(
        v["lift_work"],
        v["lift_blocked_force"] * v["lift_free_deflection"],
        1e-12
    ));
    assert!(close(
        v["lift_normalized"],
        v["lift_work"] / (0.320 * 300e-6),
        1e-9
    ));
    // Force falls with distance: the sensor at 1 mm, 2 mm, 3 mm: 4 points below 3.48 mm.
    assert_eq!(v["lift_points"], 4.0);
    // The 30 % off-axis load: F_y = 0.3 F on the sensor.
    assert!(close(
        v["lift_offaxis_blocked_force_y"].abs(),
        0.3 * v["lift_offaxis_blocked_force"],
        1e-9
    ));
    let Experiment::ForceDeflection(f) = &spec else {
        panic!()
    };
    let leg = leg::Leg::open(&experiments::ModelSpec {
        model: f.model.clone(),
        set: vec![],
        independent: f.independent.clone(),
    })
    .unwrap();
    let test = leg::force_deflection(&leg, leg::Dof::Lift, 2, 225.0, None, 0.0).unwrap();
    let inputs = leg.drive(leg::Dof::Lift, 225.0);
    let rest_q = leg
        .equilibrium(&leg.q0, &leg.inputs(0.0, 0.0), &[])
        .unwrap()
        .q;
    let fixture = leg.fixture(test.rest, vec![2]);
    let mut q = rest_q.clone();
    if let Ok(eq) = mech_runtime::solve_statics(
        leg.model(),
        0.0,
        &mut q,
        &inputs,
        &[fixture],
        &Default::default(),
    ) {
        assert!(close(-eq.fixture_forces[0][2], test.blocked_force(), 1e-6));
    }
}

#[test]
fn compare_work_ratio_is_consistent() {
    let spec = bundled("hamr_v2_vs_vi.toml", &[]);
    let outcome = spec.run("compare", &out("compare")).unwrap();
    let v = &outcome.values;
    let ratio =
        (v["new_lift_work"] + v["new_swing_work"]) / (v["old_lift_work"] + v["old_swing_work"]);
    assert!(close(v["work_ratio"], ratio, 1e-12));
    // The redesign increases the work of both DOFs in the model too.
    assert!(v["new_lift_work"] > v["old_lift_work"] && v["new_swing_work"] > v["old_swing_work"]);
    assert!(v["work_ratio"] > 1.0);
}

#[test]
fn bode_resonances_match_the_linearized_modes() {
    let spec = bundled("hamr_vi_bode.toml", &[("points = 300", "points = 200")]);
    let Experiment::Bode(mut b) = spec else {
        panic!()
    };
    b.chirp = None;
    let outcome = Experiment::Bode(b).run("bode", &out("bode")).unwrap();
    let v = &outcome.values;
    println!("{v:?}");
    // Lift is the first mode, swing the second (tests/hamr.rs: 78.9 Hz, 106.3 Hz).
    assert!(close(
        v["lift_hysteretic_resonance_hz"],
        v["mode1_hz"],
        0.01
    ));
    assert!(close(
        v["swing_hysteretic_resonance_hz"],
        v["mode2_hz"],
        0.01
    ));
    for key in ["lift_viscous_resonance_hz", "swing_viscous_resonance_hz"] {
        assert!(v[key] > 40.0 && v[key] < 150.0, "{key} = {}", v[key]);
    }
    assert!(v["lift_hysteretic_q"] > v["lift_viscous_q"]);
}

#[test]
fn report_renders_tables_and_inline_plots() {
    let spec = bundled("hamr_v2_vs_vi.toml", &[]);
    let outcome = spec.run("compare", &out("report").join("compare")).unwrap();
    let html =
        experiments::report::render_html(std::slice::from_ref(&outcome), &out("report"), 0.1)
            .unwrap();
    assert!(
        html.starts_with("<!DOCTYPE html>") && html.contains("<table>") && html.contains("266")
    );
    let md = experiments::report::render_markdown(&[outcome], &out("report"), 0.1);
    assert!(md.contains("| HAMR-VI | lift |"), "{md}");
}
