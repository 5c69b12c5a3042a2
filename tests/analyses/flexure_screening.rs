//! `mech flexure fit` on a data set with bad traces: every bad trace is rejected with a
//! reason naming its file (and line and column where there is one), all problems are
//! reported together, and the good hinges are still fitted to their known k and η.
//!
//! The traces are written by this test from the closed-form free decay of the linearized rig,
//! `I_p θ̈ + b θ̇ + (k + m g L_cm) θ = 0` released from rest, plus Gaussian noise; not from
//! mech's own model or integrator. Being linear, they are fitted with Eq. 4 literally
//! (`small_angle`), which is exact for them.

use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;
use std::path::Path;

use crate::common::{self, Rng};

use mech::flexure_fit::error::Error;
use mech::flexure_fit::fit::{fit_files, FitOptions, FitReport};
use mech::flexure_fit::rig::specimen_files;
use mech::flexure_fit::TraceError;

const E: f64 = 2.56e9;
const ETA: f64 = 0.05;
const THICKNESS: f64 = 25e-6;
/// Angle noise: 0.05°, as a camera tracker.
const NOISE: f64 = 0.05 * PI / 180.0;
/// The pendulum: 0.2 g, centre of mass 3 mm below the pivot, a rod for the inertia.
const MASS: f64 = 0.2e-3;
const L_CM: f64 = 3e-3;
const G: f64 = 9.81;

fn inertia() -> f64 {
    MASS * L_CM * L_CM * (1.0 + 1.0 / 3.0)
}

/// A hinge of width `w` and length `l` (m): its stiffness k (Eq. 2), and the decay rate σ
/// and damped frequency ω_d of the rig with damping `b = kη/ω_d` (Eq. 5 at the seed's
/// ω = ω_d, by fixed-point iteration).
struct Oscillator {
    k: f64,
    sigma: f64,
    omega_d: f64,
}

fn oscillator(w: f64, l: f64) -> Oscillator {
    let k = E * w * THICKNESS.powi(3) / (12.0 * l);
    let omega_n = ((k + MASS * G * L_CM) / inertia()).sqrt();
    let mut omega_d = omega_n;
    let mut sigma = 0.0;
    for _ in 0..50 {
        sigma = k * ETA / omega_d / (2.0 * inertia());
        omega_d = (omega_n * omega_n - sigma * sigma).sqrt();
    }
    Oscillator { k, sigma, omega_d }
}

/// `θ₀ e^{−σt} (cos ω_d t + (σ/ω_d) sin ω_d t)` (rad) at 40 samples per period for
/// `periods` periods, plus noise of `noise` rad.
fn decay(osc: &Oscillator, theta0: f64, periods: f64, noise: f64, rng: &mut Rng) -> Trace {
    let dt = TAU / osc.omega_d / 40.0;
    let n = (periods * 40.0) as usize;
    let times: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
    let angles = times
        .iter()
        .map(|&t| {
            let (s, c) = (osc.omega_d * t).sin_cos();
            let clean = theta0 * (-osc.sigma * t).exp() * (c + osc.sigma / osc.omega_d * s);
            clean + noise * common::box_muller(rng.uniform_open(), rng.uniform_open())
        })
        .collect();
    Trace { times, angles }
}

struct Trace {
    times: Vec<f64>,
    angles: Vec<f64>,
}

impl Trace {
    /// CSV text with one comment line first, so that data row `i` is on file line `i + 3`.
    fn csv(&self, scale: f64) -> String {
        let mut s = String::from("# synthetic ring-down\nt,angle\n");
        for (t, a) in self.times.iter().zip(&self.angles) {
            let _ = writeln!(s, "{t:?},{:?}", a * scale);
        }
        s
    }
}

/// Replaces field `column` (0-based) of data row `row` with `text`.
fn corrupt(csv: &str, row: usize, column: usize, text: &str) -> String {
    let mut lines: Vec<String> = csv.lines().map(str::to_string).collect();
    let mut fields: Vec<&str> = lines[row + 2].split(',').collect();
    fields[column] = text;
    lines[row + 2] = fields.join(",");
    lines.join("\n") + "\n"
}

fn specimen_toml(name: &str, traces: &[&str], w: f64, l: f64, extra: &str) -> String {
    let list: Vec<String> = traces.iter().map(|t| format!("\"{t}\"")).collect();
    format!(
        "name = \"{name}\"\ntraces = [{}]\n{extra}\n[flexure]\nwidth = {w:e}\nthickness = \
         {THICKNESS:e}\nlength = {l:e}\n[pendulum]\nmass = {MASS:e}\ninertia = {:e}\n\
         com_distance = {L_CM:e}\n",
        list.join(", "),
        inertia()
    )
}

fn write(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join(name), text).unwrap();
}

fn fit(dir: &Path) -> FitReport {
    let files = specimen_files(&[dir.to_path_buf()]).unwrap();
    let options = FitOptions {
        small_angle: true,
        ..FitOptions::default()
    };
    fit_files(&files, &options)
}

/// The good hinges: (name, width, length); each recorded twice, from 10° and 6°.
const GOOD: [(&str, f64, f64); 3] = [
    ("g1", 1e-3, 300e-6),
    ("g2", 2e-3, 500e-6),
    ("g3", 3e-3, 1000e-6),
];

/// Writes the good hinges into `dir`; `g3`'s second trial has `nan` as the angle of data
/// row 700 (one bad trial of a good hinge).
fn write_good_hinges(dir: &Path, rng: &mut Rng) {
    for (name, w, l) in GOOD {
        let osc = oscillator(w, l);
        let periods = 6.0 * osc.omega_d / osc.sigma / TAU;
        for (trial, theta0) in [("a", 10f64), ("b", 6.0)] {
            let mut csv = decay(&osc, theta0.to_radians(), periods, NOISE, rng).csv(1.0);
            if name == "g3" && trial == "b" {
                csv = corrupt(&csv, 700, 1, "nan");
            }
            write(dir, &format!("{name}_{trial}.csv"), &csv);
        }
        let traces = [format!("{name}_a.csv"), format!("{name}_b.csv")];
        let traces: Vec<&str> = traces.iter().map(String::as_str).collect();
        write(
            dir,
            &format!("{name}.toml"),
            &specimen_toml(name, &traces, w, l, ""),
        );
    }
}

fn problem_for<'a>(report: &'a FitReport, file: &str) -> &'a Error {
    let matching: Vec<&Error> = report
        .rejected
        .iter()
        .filter(|e| e.to_string().contains(file))
        .collect();
    assert_eq!(
        matching.len(),
        1,
        "one problem naming `{file}`: {matching:?}"
    );
    matching[0]
}

#[test]
fn bad_traces_are_rejected_together_and_good_hinges_still_fitted() {
    let dir = common::scratch_dir("flexure_screening_mixed");
    let mut rng = Rng::new(17);
    write_good_hinges(&dir, &mut rng);
    let osc = oscillator(2e-3, 500e-6);
    let long = 6.0 * osc.omega_d / osc.sigma / TAU;
    let clean = |rng: &mut Rng| decay(&osc, 10f64.to_radians(), long, NOISE, rng);
    let single = |name: &str, extra: &str| {
        specimen_toml(name, &[&format!("{name}.csv")], 2e-3, 500e-6, extra)
    };

    // Degrees written, radians declared (angle_unit omitted): the user's E = −15.4 GPa.
    write(&dir, "deg.csv", &clean(&mut rng).csv(180.0 / PI));
    write(&dir, "deg.toml", &single("deg", ""));
    // `inf` as the time of data row 40 (file line 43).
    write(
        &dir,
        "inf.csv",
        &corrupt(&clean(&mut rng).csv(1.0), 40, 0, "inf"),
    );
    write(&dir, "inf.toml", &single("inf", ""));
    // 2.2 periods recorded.
    write(
        &dir,
        "short.csv",
        &decay(&osc, 0.17, 2.2, NOISE, &mut rng).csv(1.0),
    );
    write(&dir, "short.toml", &single("short", ""));
    // Negative damping: the amplitude grows e-fold over the trace.
    let growing = Oscillator {
        sigma: -osc.sigma / 6.0,
        ..oscillator(2e-3, 500e-6)
    };
    write(
        &dir,
        "grow.csv",
        &decay(&growing, 0.05, long, NOISE, &mut rng).csv(1.0),
    );
    write(&dir, "grow.toml", &single("grow", ""));
    // Noise only: the camera recorded a pendulum at rest.
    write(
        &dir,
        "noise.csv",
        &decay(&osc, 0.0, long, NOISE, &mut rng).csv(1.0),
    );
    write(&dir, "noise.toml", &single("noise", ""));

    let report = fit(&dir);

    // Every problem at once, each with its numbers.
    assert_eq!(report.rejected.len(), 6, "{:#?}", report.rejected);
    assert_eq!(report.traces, 11);
    match problem_for(&report, "deg.csv") {
        Error::AngleAmplitude {
            column: 2,
            name,
            amplitude,
            unit: "rad",
            ..
        } if name == "angle" && *amplitude > 8.0 && *amplitude <= 10.0 => {}
        other => panic!("deg.csv: {other:?}"),
    }
    let text = problem_for(&report, "deg.csv").to_string();
    assert!(
        text.contains("look like degrees")
            && text.contains("angle_unit = \"deg\"")
            && text.contains("deg.toml"),
        "{text}"
    );
    match problem_for(&report, "g3_b.csv") {
        Error::NotFinite {
            line: 703,
            column: 2,
            name,
            value,
            count: 1,
            ..
        } if name == "angle" && value.is_nan() => {}
        other => panic!("g3_b.csv: {other:?}"),
    }
    match problem_for(&report, "inf.csv") {
        Error::NotFinite {
            line: 43,
            column: 1,
            name,
            value,
            ..
        } if name == "t" && value.is_infinite() => {}
        other => panic!("inf.csv: {other:?}"),
    }
    let text = problem_for(&report, "inf.csv").to_string();
    assert!(text.contains("line 43, column 1 (`t`)"), "{text}");
    match problem_for(&report, "short.csv") {
        Error::Trace {
            error:
                TraceError::TooFewCrossings {
                    found,
                    period: Some(period),
                    duration,
                    ..
                },
            ..
        } => {
            assert!(*found < 6, "{found} crossings");
            let periods = duration / period;
            assert!((periods - 2.2).abs() < 0.1, "{periods} periods");
        }
        other => panic!("short.csv: {other:?}"),
    }
    assert!(problem_for(&report, "short.csv")
        .to_string()
        .contains("record at least 3 periods"));
    match problem_for(&report, "grow.csv") {
        Error::Trace {
            error: TraceError::Growing {
                sigma, first, last, ..
            },
            ..
        } => {
            assert!(
                common::relative_error(*sigma, growing.sigma).abs() < 0.05,
                "σ {sigma}"
            );
            assert!(last > first);
        }
        other => panic!("grow.csv: {other:?}"),
    }
    match problem_for(&report, "noise.csv") {
        Error::Trace {
            error: TraceError::NoOscillation {
                amplitude, noise, ..
            },
            ..
        } => {
            assert!(
                common::relative_error(*noise, NOISE).abs() < 0.1,
                "noise {noise}"
            );
            assert!(*amplitude < 5.0 * noise);
        }
        other => panic!("noise.csv: {other:?}"),
    }

    // The good hinges, g3 from its good trial alone, are fitted to their known k and η.
    let names: Vec<&str> = report
        .specimens
        .iter()
        .map(|s| s.specimen.name.as_str())
        .collect();
    assert_eq!(names, ["g1", "g2", "g3"]);
    for (sr, (_, w, l)) in report.specimens.iter().zip(GOOD) {
        let k = oscillator(w, l).k;
        assert_eq!(
            sr.traces.len(),
            if sr.specimen.name == "g3" { 1 } else { 2 }
        );
        for t in &sr.traces {
            let error = common::relative_error(t.stiffness, k);
            assert!(
                error.abs() < 1e-3,
                "{}: k_m {:+.4} %",
                t.file.display(),
                100.0 * error
            );
            // The standard error is honest: the error is within 4 of it.
            assert!(
                (t.stiffness - k).abs() < 4.0 * t.stiffness_se,
                "{} ± {}",
                t.stiffness,
                t.stiffness_se
            );
        }
    }
    let fit = report.uncastellated.as_ref().expect("three good hinges");
    let worst = report
        .specimens
        .iter()
        .zip(GOOD)
        .flat_map(|(sr, (_, w, l))| {
            let k = oscillator(w, l).k;
            sr.traces
                .iter()
                .map(move |t| common::relative_error(t.stiffness, k).abs())
        })
        .fold(0.0_f64, f64::max);
    println!(
        "good hinges: worst k_m error {:.4} %, E {:+.4} %, η {:+.3} %",
        100.0 * worst,
        100.0 * common::relative_error(fit.youngs_modulus, E),
        100.0 * common::relative_error(fit.loss_factor, ETA)
    );
    common::assert_close("E", fit.youngs_modulus, E, 1e-3, 0.0);
    common::assert_close("η", fit.loss_factor, ETA, 0.01, 0.0);
    // Clean trials agree within their uncertainties: no false warning.
    assert!(report.findings.is_empty(), "{:#?}", report.findings);

    // The summary lists them all and says the rest was fitted.
    let summary = report.problems().unwrap_err().to_string();
    assert!(
        summary.starts_with("6 problems in the data set (6 of 11 traces rejected"),
        "{summary}"
    );
    for file in [
        "deg.csv",
        "g3_b.csv",
        "inf.csv",
        "short.csv",
        "grow.csv",
        "noise.csv",
    ] {
        assert!(summary.contains(file), "{file} in {summary}");
    }
}

#[test]
fn an_implausible_modulus_is_rejected_not_reported() {
    // The good hinges with their thickness a decade off (2.5 µm for 25 µm): as it enters
    // cubed, E comes out a thousand times too large.
    let dir = common::scratch_dir("flexure_screening_modulus");
    let mut rng = Rng::new(5);
    write_good_hinges(&dir, &mut rng);
    for (name, _, _) in GOOD {
        let path = dir.join(format!("{name}.toml"));
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::write(
            &path,
            text.replace("thickness = 2.5e-5", "thickness = 2.5e-6"),
        )
        .unwrap();
    }
    let report = fit(&dir);
    assert!(report.uncastellated.is_none());
    let modulus = report
        .rejected
        .iter()
        .find_map(|e| match e {
            Error::ImplausibleModulus { modulus, .. } => Some(*modulus),
            _ => None,
        })
        .expect("the modulus is rejected");
    assert!(
        common::relative_error(modulus, 1000.0 * E).abs() < 0.01,
        "{modulus}"
    );
    let text = mech::render::flexure_fit::text_report(&report);
    assert!(
        text.contains("no modulus fit") && !text.contains("E = "),
        "{text}"
    );
}

#[test]
fn stiffness_below_gravity_and_disagreeing_trials() {
    let dir = common::scratch_dir("flexure_screening_stiffness");
    let mut rng = Rng::new(9);
    // A soft hinge (k below a third of m g L_cm) whose file declares the point-mass inertia
    // m L_cm², 3/4 of the true one: I_p ω_n² − m g L_cm < 0.
    let soft = oscillator(0.5e-3, 2e-3);
    assert!(soft.k < MASS * G * L_CM / 3.0);
    let periods = 6.0 * soft.omega_d / soft.sigma / TAU;
    write(
        &dir,
        "soft.csv",
        &decay(&soft, 0.17, periods, NOISE, &mut rng).csv(1.0),
    );
    let toml = specimen_toml("soft", &["soft.csv"], 0.5e-3, 2e-3, "").replace(
        &format!("inertia = {:e}", inertia()),
        &format!("inertia = {:e}", MASS * L_CM * L_CM),
    );
    write(&dir, "soft.toml", &toml);
    // Two trials of one hinge whose second is 3 % stiffer (a re-clamped flexure).
    let osc = oscillator(2e-3, 500e-6);
    let stiffer = oscillator(2e-3 * 1.03, 500e-6);
    let periods = 6.0 * osc.omega_d / osc.sigma / TAU;
    write(
        &dir,
        "pair_a.csv",
        &decay(&osc, 0.17, periods, NOISE, &mut rng).csv(1.0),
    );
    write(
        &dir,
        "pair_b.csv",
        &decay(&stiffer, 0.17, periods, NOISE, &mut rng).csv(1.0),
    );
    write(
        &dir,
        "pair.toml",
        &specimen_toml("pair", &["pair_a.csv", "pair_b.csv"], 2e-3, 500e-6, ""),
    );

    let report = fit(&dir);
    assert_eq!(report.rejected.len(), 1, "{:#?}", report.rejected);
    match &report.rejected[0] {
        Error::NonPositiveStiffness {
            path,
            total,
            gravity,
        } => {
            assert!(path.ends_with("soft.csv") && total < gravity);
        }
        other => panic!("{other:?}"),
    }
    assert!(report.rejected[0].to_string().contains("pendulum.inertia"));
    assert_eq!(report.specimens.len(), 1);
    // b_m = kη/ω_d is 2.4 % larger too.
    let [finding] = &report.findings[..] else {
        panic!("{:#?}", report.findings);
    };
    assert!(
        finding.kind == "trial_disagreement"
            && finding.message.starts_with("pair: trials")
            && finding.message.contains("on k_m")
            && finding.message.contains(" and b_m"),
        "{finding:?}"
    );
}
