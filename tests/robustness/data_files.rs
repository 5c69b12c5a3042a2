//! Bad data and experiment files: each gets an error naming the file, the line or key, and
//! the expected form; nothing is silently read in the wrong unit.

use std::fs;
use std::path::Path;

use crate::support::{expect_errors, mech, scratch};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The ring-down example's experiment and data, copied into `dir` with the experiment's
/// model path made absolute; returns the data's text.
fn ring_down(dir: &Path) -> String {
    let examples = root().join("docs/examples/diagnose");
    let experiment = fs::read_to_string(examples.join("flexure_rig_ringdown.toml")).unwrap();
    let model = root().join("models/flexure_rig.mech");
    let experiment = experiment.replace("models/flexure_rig.mech", model.to_str().unwrap());
    fs::write(dir.join("ringdown.toml"), &experiment).unwrap();
    let data = fs::read_to_string(examples.join("flexure_rig_ringdown.csv")).unwrap();
    fs::write(dir.join("ringdown.csv"), &data).unwrap();
    data
}

fn fit(data: &str, experiment: &'static str) -> [&'static str; 9] {
    let data: &'static str = Box::leak(data.to_string().into_boxed_str());
    [
        "fit",
        "--experiment",
        experiment,
        "--data",
        data,
        "--fit",
        "eta",
        "--out-dir",
        "out",
    ]
}

#[test]
fn data_files_in_another_encoding_are_named_as_such() {
    let dir = scratch("encodings");
    let data = ring_down(&dir);
    let utf16: Vec<u8> = [0xFF, 0xFE]
        .into_iter()
        .chain(data.encode_utf16().flat_map(u16::to_le_bytes))
        .collect();
    fs::write(dir.join("utf16.csv"), utf16).unwrap();
    let mut latin1 = data.clone().into_bytes();
    latin1.splice(0..0, b"# \xE9t\xE9\n".iter().copied());
    fs::write(dir.join("latin1.csv"), latin1).unwrap();
    fs::write(dir.join("binary.csv"), b"t,x\n\x00\x01\x02").unwrap();
    fs::write(dir.join("table.csv"), b"\xFF\xFEt\x00").unwrap();
    expect_errors(
        &dir,
        &[
            // Were reported as rows with the wrong number of fields.
            (&fit("utf16.csv", "ringdown.toml"), "`utf16.csv`: it is UTF-16 text (it starts with a UTF-16 byte-order mark); save it as CSV in UTF-8"),
            (&fit("latin1.csv", "ringdown.toml"), "`latin1.csv`: line 1: it is not valid UTF-8"),
            (&fit("binary.csv", "ringdown.toml"), "line 2: it holds NUL bytes"),
            (&["simulate", "{model:two_mass_chain}", "--t-end", "1 s", "--input", "push=csv(table.csv, unit=N)", "--out", "run.csv"], "--input push: cannot read `table.csv`: it is UTF-16 text"),
        ],
    );
}

#[test]
fn a_stray_huge_value_is_blamed_on_the_data_not_the_model() {
    let dir = scratch("outlier");
    let data = ring_down(&dir);
    let mut lines: Vec<String> = data.lines().map(str::to_string).collect();
    let row = lines.iter().position(|l| l.starts_with("0.007")).unwrap();
    lines[row] = format!("{},1e300", lines[row].split(',').next().unwrap());
    fs::write(dir.join("huge.csv"), lines.join("\n")).unwrap();
    // Was "the state or its derivative became NaN": the fit chased the value.
    expect_errors(
        &dir,
        &[(&fit("huge.csv", "ringdown.toml"), &format!("`huge.csv`, line {}, column 2 (`angle`): `1e300` is more than 1e6 times the column's median magnitude", row + 1))],
    );
}

#[test]
fn experiment_keys_with_the_wrong_unit_or_type_are_named() {
    let dir = scratch("experiment_keys");
    ring_down(&dir);
    let experiment = fs::read_to_string(dir.join("ringdown.toml")).unwrap();
    let line = 1 + experiment
        .lines()
        .position(|l| l.starts_with("noise"))
        .unwrap();
    let with = |noise: &str| experiment.replace("noise = \"0.05 deg\"", noise);
    fs::write(dir.join("length.toml"), with("noise = \"0.05 mm\"")).unwrap();
    fs::write(dir.join("number.toml"), with("noise = 0.05")).unwrap();
    let number = format!("line {line}: key `noise`: invalid type: floating point `0.05`, expected a string\n  hint: quantities are strings with a unit");
    expect_errors(
        &dir,
        &[
            // Was read as 0.05 rad.
            (
                &fit("ringdown.csv", "length.toml"),
                "key `noise`: `0.05 mm` has unit m, but this noise needs an angle",
            ),
            // Was reported at line 1, column 1, without the key.
            (&fit("ringdown.csv", "number.toml"), &number),
        ],
    );
}

#[test]
fn flexure_specimens_read_units_from_their_traces_and_refuse_unit_slips() {
    let dir = scratch("specimens");
    let flexures = root().join("examples/flexure_data");
    let specimen = fs::read_to_string(flexures.join("u01.toml")).unwrap();
    let trace = fs::read_to_string(flexures.join("u01.csv")).unwrap();
    assert!(trace.starts_with("t,angle\n") && !specimen.contains("angle_unit"));
    let write = |name: &str, specimen: &str, trace: &str| {
        fs::create_dir_all(dir.join(name)).unwrap();
        fs::write(dir.join(name).join("u01.toml"), specimen).unwrap();
        fs::write(dir.join(name).join("u01.csv"), trace).unwrap();
    };
    // The same trace in ms and degrees, said so by its header only.
    let mut converted = String::from("time [ms], angle [deg]\n");
    for line in trace.lines().skip(1) {
        let (t, a) = line.split_once(',').unwrap();
        let (t, a): (f64, f64) = (t.parse().unwrap(), a.parse().unwrap());
        converted += &format!("{:e},{:e}\n", t * 1e3, a.to_degrees());
    }
    write("header_units", &specimen, &converted);
    let width = specimen.lines().find(|l| l.starts_with("width")).unwrap();
    write("plain_width", &specimen.replace(width, "width = 1"), &trace);
    let declared = specimen.replace("[flexure]", "angle_unit = \"rad\"\n\n[flexure]");
    write("conflict", &declared, &converted);
    expect_errors(
        &dir,
        &[
            // Was read as 1 m.
            (&["flexure", "fit", "plain_width", "--out-dir", "out", "--plots", "none"], "flexure.width = 1 is 1 m (plain numbers are SI), too large for a flexure rig; give the unit, e.g. `width = \"1 mm\"`"),
            (&["flexure", "fit", "conflict", "--out-dir", "out", "--plots", "none"], "column 2 (`angle [deg]`): the header's unit disagrees with the specimen's `angle_unit` (rad)"),
        ],
    );
    // Was read as radians and seconds.
    let fitted = |folder: &str| {
        let run = mech(
            &dir,
            &[
                "flexure",
                "fit",
                folder,
                "--out-dir",
                folder,
                "--plots",
                "none",
            ],
        );
        let row = run
            .stdout
            .lines()
            .find(|l| l.contains("u01.csv"))
            .map(str::to_string);
        row.unwrap_or_else(|| panic!("{}\n{}", run.stdout, run.stderr))
    };
    write("plain", &specimen, &trace);
    let (plain, converted) = (fitted("plain"), fitted("header_units"));
    let numbers = |row: &str| -> Vec<f64> {
        row.split_whitespace()
            .filter_map(|w| w.parse().ok())
            .take(4)
            .collect()
    };
    let (a, b) = (numbers(&plain), numbers(&converted));
    assert_eq!(a.len(), 4, "{plain}");
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() <= 1e-4 * x.abs(), "{plain}\n{converted}");
    }
}
