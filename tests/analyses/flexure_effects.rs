//! Issue #17's characterization targets: the screening of `mech flexure fit` (and of `mech
//! diagnose`'s pendulum kind) must flag and name air drag, amplitude stiffening, baseline drift,
//! a frequency-dependent loss factor and trial disagreement on at least 90 % of affected
//! traces or data sets, with at most 1 % false flags on clean traces.
//!
//! The traces come from an independent formulation written here, not from mech's model: the
//! pendulum's equation of motion with the effects,
//!
//! ```text
//! I θ̈ = −m g L sin θ − k (1 + β θ²) θ − b θ̇ − c |θ̇| θ̇,    b = k η(f)/ω_d,
//! η(f) = η_kind (f/10 Hz)^α,    measured angle = θ + d·t/T + noise,
//! ```
//!
//! integrated by RK4 at 4 kHz, sampled at 1 kHz, with 0.05° of Gaussian noise (a camera
//! tracker). The effect sizes, drawn per trace or data set:
//! - air drag: `c` such that the drag's equivalent viscous damping `(8/3π) c A ω` is 25–100 %
//!   of the flexure's at the release angle;
//! - amplitude stiffening: `β θ₀² ` = 2–6 % (the flexure 2–6 % stiffer at the release angle);
//! - baseline drift: `|d|` = 0.1–0.5° over the trace;
//! - frequency-dependent loss: `|α|` = 0.1–0.25 over six hinges at 5–25 Hz;
//! - trial disagreement: one hinge's second trial 1–4 % stiffer or softer (remounted).
//!
//! Releases are 5–15°, hinges 5–25 Hz with gravity 20–40 % of the stiffness. The default test
//! runs a few cases in seconds; the counts are `#[ignore]`d (see `docs/diagnose.md`):
//! `cargo test --release --test analyses flexure_effects -- --ignored --nocapture`.

use std::f64::consts::{PI, TAU};
use std::path::PathBuf;

use crate::common::{self, Rng};

use mech::flexure_fit::fit::{
    analyze_specimen_trace, fit_results, specimen_result, FitOptions, FitReport,
    LOSS_EXPONENT_RESOLUTION,
};
use mech::flexure_fit::rig::{FlexureGeometry, Kind, Pendulum, Specimen};
use mech::flexure_fit::screen::{screen, Screening};

const E: f64 = 2.56e9;
const THICKNESS: f64 = 25e-6;
const ETA: f64 = 0.05;
const ETA_CASTELLATED: f64 = 0.08;
const L_EFF: f64 = 66e-6;
const NOISE: f64 = 0.05 * PI / 180.0;
const RATE: f64 = 1000.0;
const G: f64 = 9.81;

/// One hinge on its pendulum.
#[derive(Clone, Copy, Debug)]
struct Hinge {
    geometry: FlexureGeometry,
    pendulum: Pendulum,
    /// Small-amplitude flexure stiffness (N·m/rad).
    k: f64,
    /// Loss factor at this hinge's frequency.
    eta: f64,
}

/// What a trace has besides the linear flexure with a constant loss factor.
#[derive(Clone, Copy, Debug, Default)]
struct Effects {
    /// Drag's equivalent damping over the flexure's, at the release angle.
    drag: f64,
    /// `β θ₀²`.
    stiffening: f64,
    /// Baseline drift over the trace (rad).
    drift: f64,
    /// Factor on k (a remounted flexure).
    stiffness_factor: Option<f64>,
}

/// A hinge of `kind` at about `frequency` Hz, gravity share `share`: the width from the
/// frequency's pendulum, the pendulum a bob on an arm with `I = 2 m L²`.
fn hinge(kind: Kind, frequency: f64, share: f64, rng: &mut Rng) -> Hinge {
    let width = rng.uniform(0.8e-3, 3e-3);
    let (length, l_bending) = match kind {
        Kind::Uncastellated => {
            let l = rng.uniform(100e-6, 500e-6);
            (l, l)
        }
        Kind::Castellated => (120e-6, L_EFF),
    };
    let k = E * width * THICKNESS.powi(3) / (12.0 * l_bending);
    let omega = TAU * frequency;
    let mgl = k * share / (1.0 - share);
    let inertia = (k + mgl) / (omega * omega);
    // I = 2 m L² and m g L = mgl: L = I g / (2 mgl).
    let com = inertia * G / (2.0 * mgl);
    let pendulum = Pendulum {
        mass: mgl / (G * com),
        inertia,
        com_distance: com,
        gravity: G,
    };
    let eta = match kind {
        Kind::Uncastellated => ETA,
        Kind::Castellated => ETA_CASTELLATED,
    };
    Hinge {
        geometry: FlexureGeometry {
            kind,
            width,
            thickness: THICKNESS,
            length,
            castellation_length: f64::NAN,
        },
        pendulum,
        k,
        eta,
    }
}

/// The damped frequency of the linearized hinge and its damping `b = k η/ω_d` (Eq. 5 at the
/// seed's ω = ω_d), by fixed-point iteration.
fn damping(h: &Hinge, k: f64) -> (f64, f64) {
    let p = &h.pendulum;
    let omega_n = ((k + p.gravity_stiffness()) / p.inertia).sqrt();
    let (mut omega_d, mut b) = (omega_n, 0.0);
    for _ in 0..50 {
        b = k * h.eta / omega_d;
        let sigma = b / (2.0 * p.inertia);
        omega_d = (omega_n * omega_n - sigma * sigma).sqrt();
    }
    (omega_d, b)
}

/// The ring-down from rest at `release` (rad): the module's equation by RK4, sampled at
/// 1 kHz until the linear envelope falls to e⁻³ (2–8 s), plus noise.
fn ring_down(h: &Hinge, release: f64, e: Effects, rng: &mut Rng) -> (Vec<f64>, Vec<f64>) {
    let p = h.pendulum;
    let k = h.k * e.stiffness_factor.unwrap_or(1.0);
    let (omega_d, b) = damping(h, k);
    let beta = e.stiffening / (release * release);
    let c = e.drag * b * 3.0 * PI / (8.0 * release * omega_d);
    let accel = |theta: f64, omega: f64| {
        -(p.gravity_stiffness() * theta.sin()
            + k * (1.0 + beta * theta * theta) * theta
            + b * omega
            + c * omega.abs() * omega)
            / p.inertia
    };
    let sigma = b / (2.0 * p.inertia);
    let duration = (3.0 / sigma).clamp(2.0, 8.0);
    let samples = (duration * RATE) as usize;
    let steps = 4;
    let dt = 1.0 / (RATE * steps as f64);
    let (mut theta, mut omega) = (release, 0.0);
    let (mut times, mut angles) = (Vec::with_capacity(samples), Vec::with_capacity(samples));
    for n in 0..samples {
        let t = n as f64 / RATE;
        times.push(t);
        angles.push(theta + e.drift * t / duration + NOISE * rng.normal());
        for _ in 0..steps {
            (theta, omega) = common::rk4_step((theta, omega), dt, accel);
        }
    }
    (times, angles)
}

fn release(rng: &mut Rng) -> f64 {
    rng.uniform(5.0, 15.0).to_radians()
}

/// A random hinge at 5–25 Hz (log-uniform), gravity share 0.2–0.4.
fn random_hinge(rng: &mut Rng) -> Hinge {
    let frequency = rng.uniform(5f64.ln(), 25f64.ln()).exp();
    let share = rng.uniform(0.2, 0.4);
    let kind = if rng.uniform(0.0, 1.0) < 0.3 {
        Kind::Castellated
    } else {
        Kind::Uncastellated
    };
    hinge(kind, frequency, share, rng)
}

/// One trace with `effects`, screened as `mech flexure fit` does (the pendulum known) and as
/// `mech diagnose` does a single trace (the pendulum unknown).
fn screened_trace(seed: u64, effects: Effects) -> (Screening, Screening) {
    let mut rng = Rng::new(seed);
    let h = random_hinge(&mut rng);
    let theta0 = release(&mut rng);
    let (times, angles) = ring_down(&h, theta0, effects, &mut rng);
    let result = analyze_specimen_trace(
        &times,
        &angles,
        &h.pendulum,
        PathBuf::from(format!("trace_{seed}.csv")),
        &FitOptions::default(),
    )
    .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
    (result.screening, screen(&times, &angles))
}

/// The effects drawn for a trace of `kind` (`clean`, `drag`, `stiffening`, `drift`).
fn trace_effects(kind: &str, rng: &mut Rng) -> Effects {
    let sign = if rng.uniform(0.0, 1.0) < 0.5 {
        -1.0
    } else {
        1.0
    };
    match kind {
        "clean" => Effects::default(),
        "drag" => Effects {
            drag: rng.uniform(0.25, 1.0),
            ..Effects::default()
        },
        "stiffening" => Effects {
            stiffening: rng.uniform(0.02, 0.06),
            ..Effects::default()
        },
        "drift" => Effects {
            drift: sign * rng.uniform(0.1, 0.5).to_radians(),
            ..Effects::default()
        },
        other => panic!("no effect `{other}`"),
    }
}

/// A data set of six hinges (four uncastellated, two castellated) at 5–25 Hz (`span` = (5,
/// 25)) each released twice; `alpha` makes the loss factor frequency dependent, and
/// `disagreement` makes one hinge's second trial that much stiffer, `scatter` gives each hinge
/// its own loss factor (log-normal, that relative standard deviation).
fn data_set(seed: u64, span: (f64, f64), alpha: f64, disagreement: f64, scatter: f64) -> FitReport {
    let mut rng = Rng::new(seed);
    let n = 6;
    let odd = rng.index(n);
    let mut results = Vec::new();
    for i in 0..n {
        // Spread evenly in ln f, jittered, so every set spans the range.
        let (lo, hi) = (span.0.ln(), span.1.ln());
        let u = (i as f64 + rng.uniform(0.0, 1.0)) / n as f64;
        let frequency = (lo + u * (hi - lo)).exp();
        let kind = if i % 3 == 2 {
            Kind::Castellated
        } else {
            Kind::Uncastellated
        };
        let mut h = hinge(kind, frequency, rng.uniform(0.2, 0.4), &mut rng);
        h.eta *= (frequency / 10.0).powf(alpha) * (scatter * rng.normal()).exp();
        let specimen = Specimen {
            name: format!("H{i}"),
            source: PathBuf::from(format!("h{i}.toml")),
            flexure: h.geometry,
            pendulum: h.pendulum,
            traces: Vec::new(),
            angle_scale: None,
            angle_column: None,
        };
        let traces = (0..2)
            .map(|trial| {
                let effects = Effects {
                    stiffness_factor: (i == odd && trial == 1).then_some(1.0 + disagreement),
                    ..Effects::default()
                };
                let theta0 = release(&mut rng);
                let (times, angles) = ring_down(&h, theta0, effects, &mut rng);
                let file = PathBuf::from(format!("h{i}_{trial}.csv"));
                analyze_specimen_trace(&times, &angles, &h.pendulum, file, &FitOptions::default())
                    .unwrap_or_else(|e| panic!("seed {seed}: {e}"))
            })
            .collect();
        results.push(specimen_result(specimen, traces));
    }
    fit_results(results, &FitOptions::default())
}

fn kinds(report: &FitReport) -> Vec<&'static str> {
    let mut kinds: Vec<&'static str> = report.findings.iter().map(|f| f.kind).collect();
    kinds.sort();
    kinds.dedup();
    kinds
}

fn trace_kinds(s: &Screening) -> Vec<&'static str> {
    s.flags.iter().map(|f| f.kind).collect()
}

/// The name each effect must get.
fn expected(kind: &str) -> &'static str {
    match kind {
        "drag" => "amplitude_dependent_damping",
        "stiffening" => "amplitude_stiffening",
        "drift" => "baseline_drift",
        _ => unreachable!(),
    }
}

/// A few cases of each effect, and clean traces and sets, in seconds: each effect named
/// alone, nothing on clean data; the η(f) exponent within 3σ of the truth; a set whose
/// hinges scatter says it does not resolve α.
#[test]
fn each_effect_is_named_on_a_few_cases() {
    for seed in 0..3 {
        let (known, unknown) = screened_trace(seed, Effects::default());
        assert!(known.flags.is_empty(), "clean {seed}: {:?}", known.flags);
        assert!(
            unknown.flags.is_empty(),
            "clean {seed}: {:?}",
            unknown.flags
        );
    }
    for kind in ["drag", "stiffening", "drift"] {
        for seed in 100..102 {
            let mut rng = Rng::new(seed + 7);
            let effects = trace_effects(kind, &mut rng);
            let (known, _) = screened_trace(seed, effects);
            assert_eq!(
                trace_kinds(&known),
                [expected(kind)],
                "{kind} {seed}: {known:?}"
            );
        }
    }
    let clean = data_set(200, (5.0, 25.0), 0.0, 0.0, 0.0);
    assert!(clean.findings.is_empty(), "{:#?}", clean.findings);
    let fit = clean.loss_frequency.as_ref().unwrap();
    assert!(
        fit.resolved() && fit.exponent_sigma().abs() < 3.0,
        "{fit:?}"
    );

    let alpha = 0.15;
    let lossy = data_set(201, (5.0, 25.0), alpha, 0.0, 0.0);
    assert_eq!(
        kinds(&lossy),
        ["frequency_dependent_loss"],
        "{:#?}",
        lossy.findings
    );
    let fit = lossy.loss_frequency.as_ref().unwrap();
    assert!(
        (fit.exponent.0 - alpha).abs() < 3.0 * fit.exponent.1,
        "{fit:?}"
    );

    let remounted = data_set(202, (5.0, 25.0), 0.0, 0.02, 0.0);
    assert_eq!(
        kinds(&remounted),
        ["trial_disagreement"],
        "{:#?}",
        remounted.findings
    );

    // Hinges whose loss factors scatter by 5 % (as real ones do, seed Fig. 5: R² 0.83–0.97):
    // six at 5–25 Hz cannot resolve α (se ≈ 0.05/(√6 · 0.46) ≈ 0.044), and say so.
    let scattered = data_set(203, (5.0, 25.0), 0.0, 0.0, 0.05);
    let fit = scattered.loss_frequency.as_ref().unwrap();
    assert!(
        fit.exponent.1 > LOSS_EXPONENT_RESOLUTION && !fit.resolved(),
        "{fit:?}"
    );
    assert!(fit.chi2_dof > 100.0, "{fit:?}");
    assert!(scattered.findings.is_empty(), "{:#?}", scattered.findings);
    assert!(mech::render::flexure_fit::loss_frequency_text(&scattered).contains("not resolved"));
}

/// Counts of `(flagged with the right name alone, flagged with the right name among others,
/// cases)`.
#[derive(Default, Debug)]
struct Tally {
    alone: usize,
    named: usize,
    cases: usize,
    /// The other names given, counted.
    others: std::collections::BTreeMap<String, usize>,
}

impl Tally {
    fn add(&mut self, kinds: &[&str], expected: &str) {
        self.cases += 1;
        if kinds.contains(&expected) {
            self.named += 1;
            if kinds.len() == 1 {
                self.alone += 1;
            }
        }
        for kind in kinds.iter().filter(|k| **k != expected) {
            *self.others.entry(kind.to_string()).or_default() += 1;
        }
    }
    fn rate(&self) -> f64 {
        self.named as f64 / self.cases as f64
    }
}

/// Evaluation seeds start here; the thresholds were looked at on seeds from
/// [`CALIBRATION_SEEDS`] only.
const EVALUATION_SEEDS: u64 = 1;
const CALIBRATION_SEEDS: u64 = 1_000_000;

/// The rates of issue #17's targets, on seeds not used to look at the thresholds.
/// `MECH_FLEXURE_EFFECT_SEEDS=calibration` runs the calibration seeds instead.
#[test]
#[ignore = "counts over 1000+ traces; run with --release --ignored (docs/diagnose.md)"]
fn rates_of_issue_17_targets() {
    let base = match std::env::var("MECH_FLEXURE_EFFECT_SEEDS").as_deref() {
        Ok("calibration") => CALIBRATION_SEEDS,
        _ => EVALUATION_SEEDS,
    };
    let (clean_traces, per_effect, clean_sets) = (200, 60, 60);
    let mut report = String::new();
    // Clean traces: any flag is false.
    let (mut false_known, mut false_unknown) = (0, 0);
    for i in 0..clean_traces {
        let (known, unknown) = screened_trace(base + i, Effects::default());
        false_known += usize::from(!known.flags.is_empty());
        false_unknown += usize::from(!unknown.flags.is_empty());
    }
    // Clean data sets: their 12 traces each count as clean traces too.
    let (mut set_false, mut set_traces, mut set_trace_false) = (0, 0, 0);
    for i in 0..clean_sets {
        let set = data_set(base + 10_000 + i, (5.0, 25.0), 0.0, 0.0, 0.0);
        let false_findings: Vec<_> = set
            .findings
            .iter()
            .filter(|f| matches!(f.kind, "frequency_dependent_loss" | "trial_disagreement"))
            .collect();
        if !false_findings.is_empty() {
            set_false += 1;
            println!("clean set {}: {false_findings:#?}", base + 10_000 + i);
        }
        for s in &set.specimens {
            for t in &s.traces {
                set_traces += 1;
                set_trace_false += usize::from(!t.screening.flags.is_empty());
            }
        }
    }
    report += &format!(
        "clean traces, pendulum known: {false_known}/{clean_traces} flagged; in clean sets \
         {set_trace_false}/{set_traces}\nclean traces, single-trace screening (pendulum \
         unknown): {false_unknown}/{clean_traces} flagged\nclean data sets: {set_false}/\
         {clean_sets} with a set finding\n"
    );
    let mut tallies = Vec::new();
    for (e, kind) in ["drag", "stiffening", "drift"].into_iter().enumerate() {
        let (mut known, mut unknown) = (Tally::default(), Tally::default());
        for i in 0..per_effect {
            let seed = base + 20_000 + 1000 * e as u64 + i;
            let mut rng = Rng::new(seed ^ 0x5eed);
            let effects = trace_effects(kind, &mut rng);
            let (k, u) = screened_trace(seed, effects);
            known.add(&trace_kinds(&k), expected(kind));
            unknown.add(&trace_kinds(&u), expected(kind));
        }
        report += &format!(
            "{kind}: pendulum known {}/{} named ({} alone, others {:?}); single trace {}/{} ({} \
             alone, others {:?})\n",
            known.named,
            known.cases,
            known.alone,
            known.others,
            unknown.named,
            unknown.cases,
            unknown.alone,
            unknown.others
        );
        tallies.push((kind, known));
    }
    let mut loss = Tally::default();
    let mut trials = Tally::default();
    for i in 0..per_effect {
        let mut rng = Rng::new(base + 40_000 + i);
        let sign = if rng.uniform(0.0, 1.0) < 0.5 {
            -1.0
        } else {
            1.0
        };
        let alpha = sign * rng.uniform(0.1, 0.25);
        let set = data_set(base + 50_000 + i, (5.0, 25.0), alpha, 0.0, 0.0);
        loss.add(&kinds(&set), "frequency_dependent_loss");
        let disagreement = sign * rng.uniform(0.01, 0.04);
        let set = data_set(base + 60_000 + i, (5.0, 25.0), 0.0, disagreement, 0.0);
        trials.add(&kinds(&set), "trial_disagreement");
    }
    report += &format!(
        "frequency-dependent loss: {}/{} sets named ({} alone, others {:?})\ntrial \
         disagreement: {}/{} sets named ({} alone, others {:?})\n",
        loss.named,
        loss.cases,
        loss.alone,
        loss.others,
        trials.named,
        trials.cases,
        trials.alone,
        trials.others
    );
    println!("{report}");
    tallies.push(("frequency-dependent loss", loss));
    tallies.push(("trial disagreement", trials));
    let clean_rate = (false_known + set_trace_false) as f64 / (clean_traces + set_traces) as f64;
    assert!(
        clean_rate <= 0.01,
        "false flags on clean traces: {clean_rate}\n{report}"
    );
    for (kind, tally) in &tallies {
        assert!(tally.rate() >= 0.9, "{kind}: {tally:?}\n{report}");
    }
}

/// A specimen file for `h` naming `traces`.
fn specimen_toml(name: &str, h: &Hinge, traces: &[String]) -> String {
    let list: Vec<String> = traces.iter().map(|t| format!("\"{t}\"")).collect();
    let (g, p) = (&h.geometry, &h.pendulum);
    format!(
        "name = \"{name}\"\ntraces = [{}]\n[flexure]\nwidth = {:e}\nthickness = {:e}\nlength = \
         {:e}\n[pendulum]\nmass = {:e}\ninertia = {:e}\ncom_distance = {:e}\n",
        list.join(", "),
        g.width,
        g.thickness,
        g.length,
        p.mass,
        p.inertia,
        p.com_distance
    )
}

/// `mech diagnose --dataset` on a set with air drag in one trace, a drifting baseline in
/// another and `nan` in a third: one summary naming each flag at its trace, the bad trace
/// listed with its line and column and exit code 1; without the bad trace, exit code 0 though
/// traces are flagged, and `dataset.json` with the flags.
#[test]
fn diagnose_dataset_summarizes_flags_and_lists_bad_traces() {
    let dir = common::scratch_dir("diagnose_dataset");
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::create_dir(&dir).unwrap();
    let mut rng = Rng::new(17);
    let effects = [
        Effects {
            drag: 0.6,
            ..Effects::default()
        },
        Effects {
            drift: 0.3f64.to_radians(),
            ..Effects::default()
        },
        Effects::default(),
    ];
    for (i, effect) in effects.iter().enumerate() {
        let h = hinge(Kind::Uncastellated, 8.0 + 5.0 * i as f64, 0.3, &mut rng);
        let names: Vec<String> = (0..2).map(|trial| format!("h{i}_{trial}.csv")).collect();
        for (trial, name) in names.iter().enumerate() {
            let e = if trial == 1 {
                *effect
            } else {
                Effects::default()
            };
            let (times, angles) = ring_down(&h, 10f64.to_radians(), e, &mut rng);
            let mut csv = String::from("t,angle\n");
            for (k, (t, a)) in times.iter().zip(&angles).enumerate() {
                // Data row 100 of the third hinge's second trial: a dropped frame.
                let a = if i == 2 && trial == 1 && k == 100 {
                    "nan".to_string()
                } else {
                    format!("{a:?}")
                };
                csv += &format!("{t:?},{a}\n");
            }
            std::fs::write(dir.join(name), csv).unwrap();
        }
        let toml = specimen_toml(&format!("H{i}"), &h, &names);
        std::fs::write(dir.join(format!("h{i}.toml")), toml).unwrap();
    }
    let out = dir.join("out");
    let run = || {
        std::process::Command::new(env!("CARGO_BIN_EXE_mech"))
            .args(["diagnose", "--dataset"])
            .arg(&dir)
            .arg("--out-dir")
            .arg(&out)
            .output()
            .unwrap()
    };
    let output = run();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr),
    );
    assert_eq!(output.status.code(), Some(1), "{stdout}\n{stderr}");
    let row = |trace: &str| {
        stdout
            .lines()
            .find(|l| l.contains(trace))
            .unwrap_or_else(|| panic!("no row for {trace}:\n{stdout}"))
            .to_string()
    };
    assert!(
        row("h0_1.csv").ends_with("amplitude_dependent_damping"),
        "{stdout}"
    );
    assert!(row("h1_1.csv").ends_with("baseline_drift"), "{stdout}");
    for clean in ["h0_0.csv", "h1_0.csv", "h2_0.csv"] {
        assert!(row(clean).ends_with(" -"), "{stdout}");
    }
    assert!(stdout.contains("1 of 6 traces rejected"), "{stdout}");
    // Air drag adds damping at the larger amplitudes only, so H0's trials disagree on b_m.
    assert!(
        stdout.contains("trial disagreement: 1 of 2 pairs"),
        "{stdout}"
    );
    assert!(stdout.contains("[trial_disagreement] H0: "), "{stdout}");
    assert!(
        stderr.contains("h2_1.csv") && stderr.contains("line 102, column 2"),
        "{stderr}"
    );

    // Without the bad trace: flags alone leave the exit code 0.
    let h2 = std::fs::read_to_string(dir.join("h2.toml")).unwrap();
    std::fs::write(dir.join("h2.toml"), h2.replace(", \"h2_1.csv\"", "")).unwrap();
    let output = run();
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(0), "{stdout}");
    assert!(
        stdout.contains(
            "findings (1 × amplitude_dependent_damping, 1 × trial_disagreement, 1 × baseline_drift"
        ),
        "{stdout}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("dataset.json")).unwrap()).unwrap();
    let flagged: Vec<&str> = json["findings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["kind"].as_str().unwrap())
        .collect();
    assert_eq!(
        flagged[..3],
        [
            "amplitude_dependent_damping",
            "trial_disagreement",
            "baseline_drift"
        ]
    );
}
