//! The experiment files (`experiments/*.toml`, `mech experiment`, `mech report`): every kind
//! runs on the bundled HAMR models and gives physically consistent, checkable numbers. The
//! specs are the bundled ones, thinned (fewer points, no chirp) to keep debug builds fast.

use std::path::PathBuf;

use mech::experiments::{self, force, leg, trajectory, Experiment, Kind};
use mech::render;
use mech::toml_file::TomlError;

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

/// `hamr_vi_trajectory.toml` with 8 points instead of 72.
fn thinned_trajectory() -> Experiment {
    bundled("hamr_vi_trajectory.toml", &[("points = 72", "points = 8")])
}

/// `hamr_vi_force.toml` with the sensor every 1000 µm instead of every 127 µm.
fn thinned_force() -> Experiment {
    bundled("hamr_vi_force.toml", &[("\"127 um\"", "\"1000 um\"")])
}

fn out(name: &str) -> PathBuf {
    std::env::temp_dir()
        .join(format!("mech-experiments-test-{}", std::process::id()))
        .join(name)
}

fn close(a: f64, b: f64, tolerance: f64) -> bool {
    (a / b - 1.0).abs() < tolerance
}

/// The leg of an experiment's `model` as written (without its `set` overrides) and its lift
/// force test at 225 V against a blocked sensor: the independent check of the experiment's
/// numbers.
fn lift_test_as_written(model: &mech::session::ModelSpec) -> (leg::Leg, leg::ForceDeflection) {
    let leg = leg::Leg::open(&mech::session::ModelSpec {
        set: vec![],
        ..model.clone()
    })
    .unwrap();
    let test = leg::ForceTest::new(leg::Dof::Lift, 225.0, leg::Sensor::Blocked)
        .run(&leg)
        .unwrap();
    (leg, test)
}

/// Every experiment file parses, and every `mech sweep` study of `experiments/studies/`
/// (experiment 7's) is ready to run against its models.
#[test]
fn every_bundled_experiment_file_parses() {
    for entry in std::fs::read_dir(root().join("experiments")).unwrap() {
        let path = entry.unwrap().path();
        if !path.is_dir() {
            experiments::load(&path).unwrap_or_else(|e| panic!("{e}"));
            continue;
        }
        for study in std::fs::read_dir(&path).unwrap() {
            let study = study.unwrap().path();
            mech::sweep::load_in(&study, Some(&root())).unwrap_or_else(|e| panic!("{e}"));
        }
    }
}

#[test]
fn bad_experiment_files_give_clear_errors() {
    let missing_kind = experiments::parse("title = \"x\"").unwrap_err();
    assert!(
        matches!(missing_kind, experiments::Error::MissingKind)
            && missing_kind.to_string().contains("kind"),
        "{missing_kind}"
    );
    let unknown = experiments::parse("kind = \"trajectory\"\ntitle = \"t\"\nmodel = \"m.mech\"\namplitude = \"225 V\"\nfrequency = \"1 Hz\"\nvolts = 3").unwrap_err();
    assert!(
        matches!(&unknown, experiments::Error::Toml(TomlError::UnknownKey { key, line: 6, .. }) if key == "volts")
            && unknown.to_string().contains("docs/experiments.md"),
        "{unknown}"
    );
    // The model keys are shared by every kind; a missing one is still named.
    let no_model = experiments::parse(
        "kind = \"trajectory\"\ntitle = \"t\"\namplitude = \"225 V\"\nfrequency = \"1 Hz\"",
    )
    .unwrap_err();
    assert!(no_model.to_string().contains("`model`"), "{no_model}");
    let unit = experiments::parse("kind = \"trajectory\"\ntitle = \"t\"\nmodel = \"m.mech\"\namplitude = \"225 mm\"\nfrequency = \"1 Hz\"").unwrap_err();
    let unit = unit.to_string();
    assert!(
        unit.contains("amplitude") && unit.contains("voltage"),
        "{unit}"
    );
}

#[test]
fn trajectory_peak_equals_the_statics_deflection_at_the_peak_voltage() {
    let spec = thinned_trajectory();
    let outcome = run_and_write(&spec, "trajectory", &out("trajectory")).unwrap();
    println!("{:?}", outcome.values);
    // The statics of the free leg at +225 V on the lift, independently.
    let Kind::Trajectory(t) = &spec.kind else {
        panic!()
    };
    let (_, test) = lift_test_as_written(&t.model);
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

/// `trajectory::compute` returns the cycles without writing anything: each drive case comes
/// back to its start after one period (the lift and swing cases start at rest), and its peak
/// is the quarter-period sample, where the lift (or the swing alone) is at +225 V.
#[test]
fn trajectory_compute_returns_closed_cycles_from_rest() {
    let spec = thinned_trajectory();
    let Kind::Trajectory(t) = &spec.kind else {
        panic!()
    };
    let trajectories = trajectory::compute(t).unwrap();
    assert_eq!(
        (trajectories.amplitude, trajectories.frequency),
        (225.0, 1.0)
    );
    let names: Vec<&str> = trajectories.cycles.iter().map(|(n, _)| *n).collect();
    assert_eq!(names, ["lift", "swing", "both"]);
    for (name, cycle) in &trajectories.cycles {
        assert_eq!(cycle.rows.len(), 9, "{name}");
        let (first, last) = (&cycle.rows[0], &cycle.rows[8]);
        // Every drive starts at 0 V but the swing of `both`, 90° ahead of the lift.
        let starts_at_rest = first[1] == 0.0 && first[2] == 0.0;
        assert_eq!(starts_at_rest, *name != "both", "{name}: {first:?}");
        for axis in 0..3 {
            assert!(
                !starts_at_rest || first[6 + axis].abs() < 1e-12,
                "{name}: {first:?}"
            );
            assert!(
                (last[6 + axis] - first[6 + axis]).abs() < 1e-9,
                "{name}: {last:?}"
            );
        }
        let quarter = &cycle.rows[2];
        assert_eq!(
            cycle.at_peak,
            [quarter[6], quarter[7], quarter[8]],
            "{name}"
        );
        let drive = if *name == "swing" {
            quarter[2]
        } else {
            quarter[1]
        };
        assert!(close(drive, 225.0, 1e-12), "{name}: {quarter:?}");
    }
}

/// `force::compute` returns the tests without writing anything: per DOF the on-axis test and
/// the 30 % off-axis one; the sensor points (what `force_DOF.csv` lists) at 0, 1, 2, 3 mm
/// with the force falling to the last one, all short of the free deflection.
#[test]
fn force_compute_returns_the_sensor_points() {
    let spec = thinned_force();
    let Kind::ForceDeflection(f) = &spec.kind else {
        panic!()
    };
    let results = force::compute(f).unwrap();
    assert!(close(results.actuator_work, 0.320 * 300e-6, 1e-9));
    let dofs: Vec<leg::Dof> = results.dofs.iter().map(|(d, _)| *d).collect();
    assert_eq!(dofs, [leg::Dof::Lift, leg::Dof::Swing]);
    for (dof, cases) in &results.dofs {
        let labels: Vec<&str> = cases.iter().map(|(l, _)| *l).collect();
        assert_eq!(
            labels,
            [
                "on-axis only",
                "on-axis only, reversed drive",
                "30 % off-axis"
            ],
            "{dof:?}"
        );
        // The reversed drive moves the foot the other way.
        assert_eq!(cases[1].1.direction, -cases[0].1.direction, "{dof:?}");
        assert_eq!(cases[2].1.off_axis_fraction, 0.3);
    }
    let lift = &results.dofs[0].1[0].1;
    let distances: Vec<f64> = lift.points.iter().map(|p| p.distance).collect();
    assert_eq!(distances.len(), 4);
    for (k, d) in distances.iter().enumerate() {
        assert!((d - k as f64 * 1e-3).abs() < 1e-12, "{distances:?}");
    }
    assert!(lift.free_deflection > distances[3]);
    assert!(lift.points.windows(2).all(|w| w[1].force < w[0].force));
    assert!(lift.points[3].force > 0.0);
}

#[test]
fn force_deflection_blocked_force_and_work() {
    let spec = thinned_force();
    let outcome = run_and_write(&spec, "force", &out("force")).unwrap();
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
    let Kind::ForceDeflection(f) = &spec.kind else {
        panic!()
    };
    let (leg, test) = lift_test_as_written(&f.model);
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
    let outcome = run_and_write(&spec, "compare", &out("compare")).unwrap();
    // Table IV on the figure: F_b and d of 2 robots × 2 DOFs, each a marker (filled, then
    // outlined) with an error bar, and one legend marker each; the model as lines.
    let plot = outcome
        .rendered
        .iter()
        .find(|f| f.path.ends_with("compare.svg"))
        .expect("compare.svg");
    let svg = String::from_utf8_lossy(&plot.bytes);
    assert_eq!(svg.matches("<circle").count(), 2 * (2 * 4 + 4), "{svg}");
    assert_eq!(
        svg.matches("Table IV, F_b and d (± s.d., n = 2)").count(),
        4
    );
    let v = &outcome.values;
    println!("{v:?}");
    let ratio =
        (v["new_lift_work"] + v["new_swing_work"]) / (v["old_lift_work"] + v["old_swing_work"]);
    assert!(close(v["work_ratio"], ratio, 1e-12));
    // The redesign increases the work of both DOFs in the model too.
    assert!(v["new_lift_work"] > v["old_lift_work"] && v["new_swing_work"] > v["old_swing_work"]);
    // The model's own numbers, not the paper's 266 % (which the report prints from the
    // experiment file): the F·d of docs/experiments.md's sample table (HAMR-V2.0 22.4 +
    // 35.0 µJ, HAMR-VI 44.0 + 68.8 µJ; lift the paper's way, the foot pushed down, since
    // 2026-11-26: 45.8 and 85.6 µJ up) and their ratio 1.97 (a 97 % increase), pinned to the
    // values measured on this model (`cargo test --test analyses
    // compare_work_ratio_is_consistent -- --nocapture` prints them) within 1e-4 relative:
    // the statics converge to ~1e-12, so only a change of the model or of the procedure
    // moves them.
    for (key, micro_joules) in [
        ("old_lift_work", 22.3797),
        ("old_swing_work", 34.9811),
        ("new_lift_work", 44.0104),
        ("new_swing_work", 68.8174),
    ] {
        assert!(
            close(v[key] * 1e6, micro_joules, 1e-4),
            "{key} = {} µJ, pinned {micro_joules} µJ",
            v[key] * 1e6
        );
    }
    assert!(
        close(v["work_ratio"], 1.96699, 1e-4),
        "work ratio {}, pinned 1.96699",
        v["work_ratio"]
    );
}

#[test]
fn bode_resonances_match_the_linearized_modes() {
    let mut spec = bundled("hamr_vi_bode.toml", &[("points = 300", "points = 200")]);
    let Kind::Bode(b) = &mut spec.kind else {
        panic!()
    };
    b.chirp = None;
    let outcome = run_and_write(&spec, "bode", &out("bode")).unwrap();
    let v = &outcome.values;
    println!("{v:?}");
    // Lift is the first mode, swing the second: the modes of tests/equations/hamr.rs
    // (78.9053 Hz, 106.3285 Hz, within 1e-4 relative), and both the hysteretic and the
    // viscous resonances within 1 % of them (measured: lift 78.89 / 78.82 Hz, swing 106.33 /
    // 106.29 Hz; ζ ≈ 0.02–0.03 moves a peak by ~ζ²).
    for (key, hz) in [("mode1_hz", 78.9053), ("mode2_hz", 106.3285)] {
        assert!(close(v[key], hz, 1e-4), "{key} = {}, pinned {hz}", v[key]);
    }
    for (dof, mode) in [("lift", "mode1_hz"), ("swing", "mode2_hz")] {
        for loss in ["hysteretic", "viscous"] {
            let key = format!("{dof}_{loss}_resonance_hz");
            assert!(
                close(v[&key], v[mode], 0.01),
                "{key} = {}, {mode} = {}",
                v[&key],
                v[mode]
            );
        }
    }
    assert!(v["lift_hysteretic_q"] > v["lift_viscous_q"]);
}

/// The phases a CSV holds are the plotted ones, unwrapped along frequency: `mech bode --out`
/// on a two-mass chain driven at its free end and observed at the other mass (two modes and
/// no antiresonance between them: the phase goes from 0 to −360°) has no step of 180° or
/// more between neighbouring rows and reaches below −300° (wrapped, it jumped by 360° at
/// −180°). The experiments' `bode_NAME.csv` go through the same `unwrapped_phases`.
#[test]
fn bode_csv_phases_are_unwrapped() {
    let dir = out("bode_csv");
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("chain.mech");
    std::fs::write(
        &model,
        "model chain;\ninput push = 0 N;\nbody first { mass = 2 kg; }\n\
         body second { mass = 0.5 kg; }\n\
         joint x1 = slider(newtonian, first) { axis = x; stiffness = 300 N/m; damping = 1.5 N*s/m; }\n\
         joint x21 = slider(first, second) { axis = x; stiffness = 120 N/m; damping = 0.4 N*s/m; }\n\
         force drive at second = [push, 0, 0];\n\
         output x1 = position(first) in newtonian;\n",
    )
    .unwrap();
    let csv = dir.join("chain.csv");
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_mech"))
        .arg("bode")
        .arg(&model)
        .args(["--drive", "push", "--output", "x1.x"])
        .args(["--from", "0.5Hz", "--to", "20Hz", "--out"])
        .arg(&csv)
        .output()
        .unwrap();
    assert!(output.status.success(), "{output:?}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let phases: Vec<f64> = text
        .lines()
        .skip(1)
        .map(|line| line.split(',').nth(2).unwrap().trim().parse().unwrap())
        .collect();
    for pair in phases.windows(2) {
        assert!((pair[1] - pair[0]).abs() < 180.0, "a step {pair:?}");
    }
    let lowest = phases.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(lowest < -300.0, "lowest phase {lowest}°");
}

/// The linear model's resonances are refined on its continuous response, so a 50-point grid
/// (a sample every 11 %, wider than the 2–6 % half-power bands) gives the same f_r and Q as
/// a 2000-point one, within 1e-4 (measured: 6e-8). Read off the grid (the code before
/// refinement), Q at 50 points was 34–75 % low (swing hysteretic 11.9 against 47.1), and
/// the swing's hysteretic Q 26 % low at the bundled 300 points (34.8). The converged values are pinned (1e-4 relative): measured with
/// the refinement and by the grid-only reading at 20 000 points (47.1185, 41.9616, 17.7662,
/// 21.2478).
#[test]
fn bode_resonances_do_not_depend_on_the_grid() {
    let resonances = |points: usize| {
        let mut spec = bundled(
            "hamr_vi_bode.toml",
            &[("points = 300", &format!("points = {points}"))],
        );
        let Kind::Bode(b) = &mut spec.kind else {
            panic!()
        };
        b.chirp = None;
        let responses = experiments::bode::compute(b).unwrap();
        responses
            .channels
            .iter()
            .flatten()
            .map(|source| source.resonances[0])
            .collect::<Vec<_>>()
    };
    let (coarse, fine) = (resonances(50), resonances(2000));
    // Channels lift, swing; sources hysteretic, viscous.
    let converged = [41.9617, 21.2477, 47.1185, 17.7662];
    assert_eq!(coarse.len(), converged.len());
    for ((c, f), q) in coarse.iter().zip(&fine).zip(converged) {
        println!("50 points: {c:?}\n2000 points: {f:?}");
        assert!(
            close(c.frequency_hz, f.frequency_hz, 1e-4),
            "{c:?} vs {f:?}"
        );
        let (qc, qf) = (c.quality_factor.unwrap(), f.quality_factor.unwrap());
        assert!(close(qc, qf, 1e-4), "Q {qc} (50 points) vs {qf} (2000)");
        assert!(close(qf, q, 1e-4), "Q {qf}, pinned {q}");
    }
}

/// The chirp's resonances (HAMR-VI, the bundled 2 V, 2 s sweep) are solved on its estimate's
/// continuous `|Y/U|` with the record's free decay after the sweep: on 50 and 2000 points
/// they agree within 1e-4, and their Q with the viscous linear model's converged values
/// (the same losses) within 1 % (seen: lift 21.250 vs 21.248, swing 17.727 vs 17.766). Read off
/// the grid of a record cut at the sweep's end, the swing's was 8.8 and 20.6 on these grids.
#[test]
fn chirp_resonances_do_not_depend_on_the_grid() {
    let resonances = |points: usize| {
        let spec = bundled(
            "hamr_vi_bode.toml",
            &[("points = 300", &format!("points = {points}"))],
        );
        let Kind::Bode(b) = &spec.kind else { panic!() };
        let responses = experiments::bode::compute(b).unwrap();
        responses
            .channels
            .iter()
            .map(|sources| {
                let chirp = sources.iter().find(|s| s.key == "chirp").unwrap();
                chirp.resonances[0]
            })
            .collect::<Vec<_>>()
    };
    let (coarse, fine) = (resonances(50), resonances(2000));
    // Lift, swing: the viscous linear model's converged Q (above).
    for ((c, f), q) in coarse.iter().zip(&fine).zip([21.2477, 17.7662]) {
        println!("50 points: {c:?}\n2000 points: {f:?}");
        let (qc, qf) = (c.quality_factor.unwrap(), f.quality_factor.unwrap());
        assert!(
            close(c.frequency_hz, f.frequency_hz, 1e-4) && close(qc, qf, 1e-4),
            "{c:?} vs {f:?}"
        );
        assert!(close(qf, q, 0.01), "chirp Q {qf} vs the viscous linear {q}");
    }
}

#[test]
fn report_renders_tables_and_inline_plots() {
    let spec = bundled("hamr_v2_vs_vi.toml", &[]);
    let outcome = run_and_write(&spec, "compare", &out("report").join("compare")).unwrap();
    let html =
        mech::render::report::render_html(std::slice::from_ref(&outcome), &out("report"), 0.1)
            .unwrap();
    assert!(html.starts_with("<!DOCTYPE html>") && html.contains("<table>"));
    // The model's row of the work table, formatted as the report formats it from the model's
    // own works and ratio (old µJ, new µJ, ratio new/old, increase; "57.4, 112.8, 1.97, 97 %"
    // today), and the model's increase next to the paper's reported one: neither can come
    // from the experiment file's 266 %.
    let v = &outcome.values;
    let (old, new) = (
        v["old_lift_work"] + v["old_swing_work"],
        v["new_lift_work"] + v["new_swing_work"],
    );
    let ratio = v["work_ratio"];
    let cells = [
        "model".to_string(),
        format!("{:.1}", old * 1e6),
        format!("{:.1}", new * 1e6),
        format!("{ratio:.2}"),
        format!("{:.0} %", 100.0 * (ratio - 1.0)),
    ];
    assert_eq!(cells[1..], ["57.4", "112.8", "1.97", "97 %"]);
    let html_row = format!("<tr><td>{}</td></tr>", cells.join("</td><td>"));
    assert!(html.contains(&html_row), "no `{html_row}` in the HTML");
    let reported = format!("266 % (model {:.0} %)", 100.0 * (ratio - 1.0));
    assert!(html.contains(&reported), "no `{reported}` in the HTML");
    let md_row = format!("| {} |", cells.join(" | "));
    let md = mech::render::report::render_markdown(&[outcome], &out("report"), 0.1);
    assert!(md.contains("| HAMR-VI | lift |"), "{md}");
    assert!(md.contains(&md_row), "no `{md_row}` in {md}");
    assert!(md.contains(&reported), "no `{reported}` in {md}");
}

/// Runs an experiment and writes its files, as `mech experiment` does.
fn run_and_write(
    spec: &mech::experiments::Experiment,
    name: &str,
    dir: &std::path::Path,
) -> Result<mech::render::report::Outcome, mech::experiments::Error> {
    let outcome = render::experiments::run(spec, name, dir)?;
    mech::output::write_all(&outcome.rendered, &[]).unwrap();
    Ok(outcome)
}

/// The rows of a CSV written by an experiment, by column name.
fn csv_columns(path: &std::path::Path) -> std::collections::BTreeMap<String, Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(|s| s.trim().to_string())
        .collect();
    let mut columns: std::collections::BTreeMap<String, Vec<f64>> =
        header.iter().map(|h| (h.clone(), Vec::new())).collect();
    for line in lines.filter(|l| !l.trim().is_empty()) {
        for (name, cell) in header.iter().zip(line.split(',')) {
            columns
                .get_mut(name)
                .unwrap()
                .push(cell.trim().parse().unwrap());
        }
    }
    columns
}

#[test]
fn ratio_sweep_matches_the_force_experiments_and_the_papers_trend() {
    let spec = bundled("hamr_ratio_sweep.toml", &[("points = 16", "points = 5")]);
    let outcome = run_and_write(&spec, "sweep", &out("sweep")).unwrap();
    let v = &outcome.values;
    println!("{v:?}");

    // At the model's own arm the sweep runs the procedure of experiments 2 and 4: the same
    // blocked force, free deflection and work as the force/deflection experiment (HAMR-VI)
    // and the comparison (HAMR-V2.0).
    let force_spec = thinned_force();
    let force = run_and_write(&force_spec, "force", &out("sweep_force")).unwrap();
    let compare_spec = bundled("hamr_v2_vs_vi.toml", &[]);
    let compare = run_and_write(&compare_spec, "compare", &out("sweep_compare")).unwrap();
    for dof in ["lift", "swing"] {
        for quantity in ["blocked_force", "free_deflection", "work", "normalized"] {
            let sweep = v[&format!("hamr_vi_{dof}_chosen_{quantity}")];
            let experiment = force.values[&format!("{dof}_{quantity}")];
            assert!(
                close(sweep, experiment, 1e-9),
                "HAMR-VI {dof} {quantity}: sweep {sweep}, force experiment {experiment}"
            );
            // The comparison tests the lift the paper's way (the foot pushed down: the
            // drive reversed), the sweep at the positive drive: compared for swing.
            if dof == "lift" {
                continue;
            }
            let sweep = v[&format!("hamr_v2_{dof}_chosen_{quantity}")];
            let experiment = compare.values[&format!("old_{dof}_{quantity}")];
            assert!(
                close(sweep, experiment, 1e-9),
                "HAMR-V2.0 {dof} {quantity}: sweep {sweep}, comparison {experiment}"
            );
        }
    }

    // The ratio at the model's own arm is the small-motion ratio of tests/hamr.rs.
    assert!(close(v["hamr_vi_lift_chosen_ratio"], 7.58 / 0.58, 1e-4));
    assert!(close(v["hamr_vi_lift_chosen_ratio_y"], 13.0 / 0.58, 1e-4));
    assert!(close(v["hamr_vi_swing_chosen_ratio"], 7.58 / 0.53, 1e-4));
    assert!(close(
        v["hamr_v2_lift_chosen_ratio"],
        7.58 * 30.8 / 13.0,
        1e-3
    ));
    assert!(close(v["hamr_v2_lift_chosen_ratio_y"], 30.8, 0.01));
    assert!(close(
        v["hamr_v2_swing_chosen_ratio"],
        7.58 * 20.5 / (0.53 * 13.0),
        1e-3
    ));

    let csvs: Vec<_> = outcome
        .files
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    assert_eq!(csvs.len(), 4);
    for path in csvs {
        let c = csv_columns(path);
        let n = c["ratio"].len();
        // The 5 swept arms (range ends included) and the chosen design.
        assert_eq!(n, 6, "{}", path.display());
        assert_eq!(c["chosen"].iter().filter(|&&x| x == 1.0).count(), 1);
        let arms = &c["arm"];
        let (low, high) = arms
            .iter()
            .fold((f64::INFINITY, 0.0_f64), |(a, b), &x| (a.min(x), b.max(x)));
        assert!(close(low, 0.25e-3, 1e-12) && close(high, 1.2e-3, 1e-12));
        let f_b = if path.to_string_lossy().contains("hamr_v2") {
            0.270
        } else {
            0.320
        };
        for k in 0..n {
            // The ratio is the kinematic lever: geometric s_o/arm on the plotted axis (swing
            // s_o = 7.58 mm; lift z the same s_o), up to the leg's small cross terms.
            assert!(
                close(c["ratio"][k], 7.58e-3 / arms[k], 1e-3),
                "{}: T = {} at arm {}",
                path.display(),
                c["ratio"][k],
                arms[k]
            );
            // A rigid lever at the blocked (rest) position: F = F_b / T_rest.
            let lever_force = c["blocked_force"][k] * c["ratio_rest"][k];
            assert!(
                close(lever_force, f_b, 1e-3),
                "{}: F·T_rest = {lever_force} at arm {}",
                path.display(),
                arms[k]
            );
            assert!(close(
                c["work"][k],
                c["blocked_force"][k] * c["free_deflection"][k],
                1e-12
            ));
        }
        // The paper's Fig. 8: the work rises as the ratio falls, over the whole range; the
        // free deflection grows less than the ratio (the transmission stiffens as T²).
        for k in 1..n {
            assert!(c["ratio"][k] > c["ratio"][k - 1], "sorted by ratio");
            assert!(
                c["work"][k] < c["work"][k - 1],
                "{}: work rises from T = {} to {}",
                path.display(),
                c["ratio"][k - 1],
                c["ratio"][k]
            );
        }
        let grows = c["free_deflection"][n - 1] / c["free_deflection"][0];
        assert!(grows < 0.5 * c["ratio"][n - 1] / c["ratio"][0], "{grows}");
    }
    assert_eq!(outcome.plots.len(), 1);
    assert!(outcome.plots[0].exists());
}

#[test]
fn bad_ratio_sweeps_give_clear_errors() {
    let sweep = |series: &str| {
        experiments::parse(&format!(
            "kind = \"ratio_sweep\"\ntitle = \"t\"\nvoltage = \"225 V\"\n[[series]]\nname = \"r\"\n\
             actuator = \"a\"\nmodel = \"m.mech\"\ndof = \"lift\"\n{series}"
        ))
    };
    assert!(sweep("arm = [\"0.3 mm\", \"1 mm\"]").is_ok());
    let one = sweep("arm = [\"0.3 mm\"]").unwrap_err().to_string();
    assert!(
        one.contains("series[0].arm") && one.contains("two"),
        "{one}"
    );
    let unit = sweep("arm = [\"0.3 V\", \"1 mm\"]")
        .unwrap_err()
        .to_string();
    assert!(
        unit.contains("series[0].arm") && unit.contains("length"),
        "{unit}"
    );
    let lever = sweep("arm = [\"0.3 mm\", \"1 mm\"]\nlever = \"-1 mm\"")
        .unwrap_err()
        .to_string();
    assert!(lever.contains("series[0].lever"), "{lever}");
}

/// Experiment 6 (Table IV diagnosed): the base model's χ² of each robot is the one computed
/// here from the compare file's `paper` rows and the leg's own force tests (the data's units,
/// the paper's test directions and the off-axis load reach the diagnosis intact), and the
/// cause the diagnosis names brings each robot's χ² down. Slow (two whole-catalog
/// diagnoses in a debug build): run by .ci/run.
#[test]
#[ignore = "slow: two whole-catalog diagnoses, run by .ci/run"]
fn what_the_model_gets_wrong_diagnoses_table_iv() {
    let table = root().join("experiments/hamr_v2_vs_vi.toml");
    let spec = bundled(
        "hamr_what_the_model_gets_wrong.toml",
        &[(
            "\"experiments/hamr_v2_vs_vi.toml\"",
            &format!("\"{}\"", table.display()),
        )],
    );
    let outcome = run_and_write(&spec, "what", &out("what")).unwrap();
    let Kind::Compare(compare) = bundled("hamr_v2_vs_vi.toml", &[]).kind else {
        panic!("experiment 4 is a compare file")
    };
    for (key, robot) in ["old", "new"].iter().zip(&compare.robot) {
        let leg = leg::Leg::open(&robot.model).unwrap();
        let mut chi2 = 0.0;
        for dof in [leg::Dof::Lift, leg::Dof::Swing] {
            let paper = robot.paper[dof.name()].parse(dof.name()).unwrap();
            let test = leg::ForceTest::new(dof, 225.0, leg::Sensor::Blocked)
                .off_axis(0.3)
                .run_toward(&leg, paper.direction, &mut leg::WarmStarts::default())
                .unwrap();
            chi2 += ((test.free_deflection - paper.d.0) / paper.d.1).powi(2);
            chi2 += ((test.blocked_force() - paper.force.0) / paper.force.1).powi(2);
        }
        let (base, extended) = (
            outcome.values[&format!("{key}_chi2_base")],
            outcome.values[&format!("{key}_chi2_extended")],
        );
        assert!(
            close(base, chi2, 1e-6),
            "{}: χ² {base} vs {chi2}",
            robot.name
        );
        assert!(
            extended < 0.5 * base,
            "{}: χ² {base} → {extended}",
            robot.name
        );
    }
}
