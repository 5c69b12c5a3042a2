//! No data loss (issue #18): a run writes all its files or none, never over one of its
//! inputs or twice over one file, and leaves no temporary file behind.

use std::fs;
use std::path::Path;

use crate::support::{expect_errors, model, scratch};

/// The names in `dir`, sorted (hidden temporary files included).
fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn a_failed_run_leaves_the_previous_outputs_as_they_were() {
    let dir = scratch("failed_run");
    fs::write(dir.join("run.csv"), "old run").unwrap();
    // A folder for the plot cannot be made where a file is.
    fs::write(dir.join("blocker"), "keep").unwrap();
    let simulate = [
        "simulate",
        "{model:pendulum}",
        "--t-end",
        "0.1 s",
        "--out",
        "run.csv",
    ];
    // Before: run.csv was replaced, then the plot failed.
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            [&simulate[..], &["--plot", "run.txt"]].concat(),
            "cannot plot to `run.txt`",
        ),
        (
            [&simulate[..], &["--plot", "blocker/run.svg"]].concat(),
            "blocker",
        ),
    ];
    let cases: Vec<(&[&str], &str)> = cases.iter().map(|(a, e)| (a.as_slice(), *e)).collect();
    expect_errors(&dir, &cases);
    assert_eq!(fs::read_to_string(dir.join("run.csv")).unwrap(), "old run");
    assert_eq!(entries(&dir), ["blocker", "run.csv"]);
}

#[test]
fn outputs_that_would_replace_an_input_or_each_other_are_refused() {
    let dir = scratch("overwrites");
    let pendulum = dir.join("pendulum.mech");
    fs::copy(model("pendulum"), &pendulum).unwrap();
    let original = fs::read(&pendulum).unwrap();
    // `two_mass_chain` has one input, `push` (a force).
    fs::write(dir.join("drive.csv"), "t,f\n0,0\n1,1e-3\n").unwrap();
    let drive = "push=csv(drive.csv, unit=N)";
    fs::copy(model("two_mass_chain"), dir.join("chain.mech")).unwrap();
    expect_errors(
        &dir,
        &[
            (
                &[
                    "simulate",
                    "pendulum.mech",
                    "--t-end",
                    "0.1 s",
                    "--out",
                    "pendulum.mech",
                ],
                "refusing to write `pendulum.mech`: it is the model `pendulum.mech` of this run",
            ),
            (
                &[
                    "simulate",
                    "pendulum.mech",
                    "--t-end",
                    "0.1 s",
                    "--out",
                    "./pendulum.mech",
                ],
                "it is the model",
            ),
            (
                &["derive", "pendulum.mech", "--out", "pendulum.mech"],
                "it is the model",
            ),
            (
                &[
                    "simulate",
                    "chain.mech",
                    "--t-end",
                    "0.1 s",
                    "--input",
                    drive,
                    "--out",
                    "drive.csv",
                ],
                "refusing to write `drive.csv`: it is the input table `drive.csv`",
            ),
            (
                &[
                    "simulate",
                    "pendulum.mech",
                    "--t-end",
                    "0.1 s",
                    "--out",
                    "run.svg",
                    "--plot",
                    "run.svg",
                ],
                "refusing to write `",
            ),
            (
                &[
                    "linearize",
                    "pendulum.mech",
                    "--out",
                    "lin.json",
                    "--matrices",
                    "lin.json",
                ],
                "twice in one run",
            ),
        ],
    );
    assert_eq!(fs::read(&pendulum).unwrap(), original);
    assert_eq!(entries(&dir), ["chain.mech", "drive.csv", "pendulum.mech"]);
}

#[test]
fn data_inside_the_output_folder_is_not_replaced() {
    let dir = scratch("data_in_out_dir");
    let examples = root().join("docs/examples/diagnose");
    fs::create_dir(dir.join("out")).unwrap();
    // The measured data named like the fit's own CSV, inside its output folder.
    fs::copy(
        examples.join("flexure_rig_ringdown.csv"),
        dir.join("out/fit.csv"),
    )
    .unwrap();
    let data = fs::read(dir.join("out/fit.csv")).unwrap();
    let experiment = examples.join("flexure_rig_ringdown.toml");
    let experiment = experiment.to_str().unwrap();
    // A flexure trace named like the fit's output.
    let traces = dir.join("traces");
    fs::create_dir(&traces).unwrap();
    let flexures = root().join("examples/flexure_data");
    let specimen = fs::read_to_string(flexures.join("u01.toml")).unwrap();
    fs::write(
        traces.join("u01.toml"),
        specimen.replace("u01.csv", "traces.csv"),
    )
    .unwrap();
    fs::copy(flexures.join("u01.csv"), traces.join("traces.csv")).unwrap();
    let trace = fs::read(traces.join("traces.csv")).unwrap();
    expect_errors(
        &dir,
        &[
            (
                &[
                    "fit",
                    "--experiment",
                    experiment,
                    "--data",
                    "out/fit.csv",
                    "--fit",
                    "eta",
                    "--out-dir",
                    "out",
                ],
                "refusing to write `out/fit.csv`: it is the data file `out/fit.csv` of this run",
            ),
            (
                &[
                    "flexure",
                    "fit",
                    "traces",
                    "--out-dir",
                    "traces",
                    "--plots",
                    "none",
                ],
                "it is a trace",
            ),
        ],
    );
    assert_eq!(fs::read(dir.join("out/fit.csv")).unwrap(), data);
    assert_eq!(fs::read(traces.join("traces.csv")).unwrap(), trace);
    assert_eq!(entries(&traces), ["traces.csv", "u01.toml"]);
}

/// A kill during the work (the common case): nothing has been written yet. A kill inside
/// `write_all` itself (removing the staged files on SIGTERM) is too short a window to hit from
/// a test; `output`'s unit tests cover the error path that shares its clean-up.
#[cfg(unix)]
#[test]
fn a_run_killed_while_it_works_leaves_the_old_outputs_and_no_temporary_file() {
    let dir = scratch("killed");
    fs::write(dir.join("run.csv"), "old run").unwrap();
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_mech"))
        .args([
            "simulate",
            &model("pendulum"),
            "--t-end",
            "1e6 s",
            "--method",
            "rk4",
        ])
        .args(["--step", "1 us", "--out", "run.csv", "--plot", "run.svg"])
        .current_dir(&dir)
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(500));
    for signal in ["-INT", "-TERM"] {
        let _ = std::process::Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status();
    }
    let status = child.wait_with_output().unwrap().status;
    assert!(!status.success());
    assert_eq!(fs::read_to_string(dir.join("run.csv")).unwrap(), "old run");
    assert_eq!(entries(&dir), ["run.csv"]);
}

/// `mech import urdf`: the model is never written over the URDF (or the file compared), a
/// URDF with an error or a bad option leaves an earlier model as it was, and no temporary
/// file is left behind.
#[test]
fn a_urdf_import_writes_all_or_nothing_and_never_over_its_inputs() {
    let dir = scratch("urdf_import");
    let good = "<robot name=\"r\"><link name=\"base\"/><link name=\"arm\"/>\
                <joint name=\"hinge\" type=\"continuous\"><parent link=\"base\"/><child link=\"arm\"/></joint></robot>";
    fs::write(dir.join("robot.urdf"), good).unwrap();
    fs::write(dir.join("other.urdf"), good).unwrap();
    fs::write(
        dir.join("broken.urdf"),
        good.replace("child link=\"arm\"", "child link=\"leg\""),
    )
    .unwrap();
    fs::write(dir.join("old.mech"), "old model").unwrap();
    let import = |file: &'static str, out: &'static str| -> Vec<&'static str> {
        vec!["import", "urdf", file, "--out", out]
    };
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            import("robot.urdf", "robot.urdf"),
            "refusing to write `robot.urdf`: it is the URDF file `robot.urdf`",
        ),
        (
            [
                import("robot.urdf", "other.urdf"),
                vec!["--compare", "other.urdf"],
            ]
            .concat(),
            "it is the URDF file compared `other.urdf`",
        ),
        (import("broken.urdf", "old.mech"), "broken.urdf:1:"),
        (import("missing.urdf", "old.mech"), "missing.urdf"),
        (
            [import("robot.urdf", "old.mech"), vec!["--length", "g"]].concat(),
            "`g` is not a unit of length (for example m, mm, um)",
        ),
        (
            [import("robot.urdf", "old.mech"), vec!["--time", "Hz"]].concat(),
            "`Hz` is not a unit of time",
        ),
    ];
    let cases: Vec<(&[&str], &str)> = cases.iter().map(|(a, e)| (a.as_slice(), *e)).collect();
    expect_errors(&dir, &cases);
    assert_eq!(
        fs::read_to_string(dir.join("old.mech")).unwrap(),
        "old model"
    );
    assert_eq!(fs::read_to_string(dir.join("robot.urdf")).unwrap(), good);
    assert_eq!(
        entries(&dir),
        ["broken.urdf", "old.mech", "other.urdf", "robot.urdf"]
    );
    // And a good import replaces the old model.
    let run = crate::support::mech(&dir, &["import", "urdf", "robot.urdf", "--out", "old.mech"]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    assert!(fs::read_to_string(dir.join("old.mech"))
        .unwrap()
        .contains("joint hinge = pin(newtonian, arm)"));
}
