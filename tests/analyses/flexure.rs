//! The flexure characterization experiment (seed Sec. IV) on synthetic data: decay traces of
//! the pendulum rig `models/flexure_rig.mech`, simulated with the project's own tape model and
//! integrator for 25 uncastellated flexures spanning the seed's ranges (w 0.8–6 mm,
//! l 30 µm–2 mm, t 7.5–50 µm) and 7 castellated hinges, with Gaussian angle noise; the fits
//! must recover the modulus, the loss factors, each trace's stiffness and l_eff.
//! Plus the flexure formulas (Eqs. 2, 5, 8), Table III, and errors on bad traces.

use std::f64::consts::{PI, TAU};
use std::path::PathBuf;

use crate::common::{self, Rng};

use mech::flexure_fit::fit::{
    analyze_specimen_trace, fit_results, specimen_result, FitOptions, SpecimenResult,
};
use mech::flexure_fit::rig::{FlexureGeometry, Kind, Pendulum, Specimen};
use mech::flexure_fit::{analyze_trace, TraceError, TraceOptions};
use mech::physics::flexure::{bending_stiffness, twist_ratio, SEED_TABLE_III};
use mech::physics::{Flexure, Material};
use mech::tape_model::TapeModel;
use mech_runtime::{Model, SimOptions};

/// The "true" material of the synthetic experiment.
const E_TRUE: f64 = 2.56e9;
const ETA_TRUE: f64 = 0.05;
/// Castellated family: seed Sec. IV.B.
const ETA_CASTELLATED: f64 = 0.08;
const L_EFF_TRUE: f64 = 66e-6;
/// Angle noise: 0.05° standard deviation.
const NOISE: f64 = 0.05 * PI / 180.0;

/// Deterministic Gaussian noise: Box–Muller on two open uniforms (this file's draw, not
/// `Rng::normal`, so that the synthetic data stay those the tolerances were set on).
fn gaussian(rng: &mut Rng) -> f64 {
    let (u1, u2) = (rng.uniform_open(), rng.uniform_open());
    common::box_muller(u1, u2)
}

/// Pendulums of the rig, from light to heavy: a bob on a light arm (mass m, centre of mass
/// L_cm below the pivot, a rod of length 2 L_cm for the inertia about the centre of mass).
fn rigs() -> Vec<Pendulum> {
    [
        (0.05e-3, 2e-3),
        (0.2e-3, 3e-3),
        (1e-3, 5e-3),
        (5e-3, 8e-3),
        (20e-3, 12e-3),
    ]
    .into_iter()
    .map(|(m, l): (f64, f64)| Pendulum {
        mass: m,
        inertia: m * l * l + m * (2.0 * l).powi(2) / 12.0,
        com_distance: l,
        gravity: 9.81,
    })
    .collect()
}

/// The rig for a flexure of stiffness `k`: gravity stiffness closest to k/2 (in log), as an
/// experimenter would swap pendulums so that the flexure dominates.
fn choose_rig(k: f64) -> Pendulum {
    rigs()
        .into_iter()
        .min_by(|a, b| {
            let da = (a.gravity_stiffness() / (0.5 * k)).ln().abs();
            let db = (b.gravity_stiffness() / (0.5 * k)).ln().abs();
            da.total_cmp(&db)
        })
        .unwrap()
}

/// Damped frequency of the linearized rig, and the damping `b = kη/ω_d` at that frequency
/// (Eq. 5 with the seed's ω = ω_d), found by fixed-point iteration.
fn damping_at_own_frequency(k: f64, eta: f64, rig: &Pendulum) -> (f64, f64) {
    let omega_n = ((k + rig.gravity_stiffness()) / rig.inertia).sqrt();
    let mut omega_d = omega_n;
    let mut b = 0.0;
    for _ in 0..50 {
        b = k * eta / omega_d;
        let zeta = b / (2.0 * rig.inertia * omega_n);
        omega_d = omega_n * (1.0 - zeta * zeta).sqrt();
    }
    (omega_d, b)
}

fn rig_model() -> TapeModel {
    common::tape("flexure_rig")
}

fn set(model: &mut TapeModel, name: &str, value: f64) {
    let index = model
        .param_index(name)
        .unwrap_or_else(|| panic!("rig has no parameter `{name}`"));
    model.set_param(index, value);
}

/// One synthetic specimen: true stiffness, and its traces.
struct Synthetic {
    specimen: Specimen,
    k_true: f64,
    traces: Vec<(Vec<f64>, Vec<f64>)>,
}

/// Simulates the rig for a flexure (w, t, l_eq) where `l_eq` is the length entering Eq. 2,
/// released from each of `angles`, `t_end_decays` e-folding times long, with noise.
#[allow(clippy::too_many_arguments)]
fn simulate_specimen(
    model: &mut TapeModel,
    name: &str,
    geometry: FlexureGeometry,
    l_eq: f64,
    eta: f64,
    angles: &[f64],
    t_end_decays: f64,
    rng: &mut Rng,
) -> Synthetic {
    let k = bending_stiffness(E_TRUE, geometry.width, geometry.thickness, l_eq);
    let rig = choose_rig(k);
    let (omega_d, b) = damping_at_own_frequency(k, eta, &rig);
    for (p, v) in [
        ("m", rig.mass),
        ("I_p", rig.inertia),
        ("L_cm", rig.com_distance),
        ("g", rig.gravity),
        ("E", E_TRUE),
        ("w", geometry.width),
        ("h", geometry.thickness),
        ("l", l_eq),
        ("eta", eta),
        ("omega_ref", omega_d),
    ] {
        set(model, p, v);
    }
    // The model's own outputs confirm Eqs. 2 and 5.
    let mut y = vec![0.0; model.noutputs()];
    model.outputs(0.0, &[0.0], &[0.0], &[], &mut y);
    let out = |n: &str| y[model.output_index(n).unwrap()];
    assert!((out("stiffness") - k).abs() <= 1e-12 * k);
    assert!((out("damping") - b).abs() <= 1e-12 * b);

    let sigma = b / (2.0 * rig.inertia);
    let period = TAU / omega_d;
    let options = SimOptions {
        max_steps: 5_000_000,
        ..common::dopri5_options(
            t_end_decays / sigma,
            (1e-3_f64).min(period / 40.0),
            1e-10,
            1e-13,
        )
    };
    let signals = mech_runtime::default_signals(model);
    let traces = angles
        .iter()
        .map(|&theta0| {
            let run =
                mech_runtime::simulate(model, &[theta0], &[0.0], &signals, &options, &mut |_| {})
                    .unwrap_or_else(|e| panic!("{name}: {e}"));
            let angle_index = model.output_index("angle").unwrap();
            let noisy: Vec<f64> = run
                .outputs
                .iter()
                .map(|o| o[angle_index] + NOISE * gaussian(rng))
                .collect();
            (run.times, noisy)
        })
        .collect();
    Synthetic {
        specimen: Specimen {
            name: name.to_string(),
            source: PathBuf::from(format!("{name}.toml")),
            flexure: geometry,
            pendulum: rig,
            traces: Vec::new(),
            angle_scale: Some(1.0),
            angle_column: None,
        },
        k_true: k,
        traces,
    }
}

/// The 25 uncastellated geometries (w mm, l µm, t µm), spanning the seed's ranges.
const GEOMETRIES: [(f64, f64, f64); 25] = [
    (0.8, 30.0, 7.5),
    (2.0, 30.0, 7.5),
    (4.0, 50.0, 7.5),
    (6.0, 40.0, 7.5),
    (3.0, 100.0, 7.5),
    (1.0, 50.0, 12.0),
    (2.5, 200.0, 12.0),
    (6.0, 500.0, 12.0),
    (4.0, 100.0, 12.0),
    (1.5, 30.0, 12.0),
    (5.0, 1000.0, 12.0),
    (2.0, 1000.0, 25.0),
    (6.0, 2000.0, 25.0),
    (1.0, 100.0, 25.0),
    (3.0, 300.0, 25.0),
    (5.0, 60.0, 25.0),
    (0.8, 30.0, 25.0),
    (4.5, 700.0, 25.0),
    (0.8, 2000.0, 50.0),
    (2.0, 500.0, 50.0),
    (4.0, 1000.0, 50.0),
    (6.0, 200.0, 50.0),
    (1.2, 60.0, 50.0),
    (3.0, 30.0, 50.0),
    (6.0, 30.0, 50.0),
];

/// Release angle of trial `j` of specimen `i`: 5°–15°.
fn release_angles(i: usize) -> [f64; 2] {
    let a = 5.0 + 10.0 * (i as f64) / 24.0;
    let b = 15.0 - 10.0 * (i as f64) / 24.0;
    [a.to_radians(), b.to_radians()]
}

fn analyse(synthetic: &Synthetic, options: &FitOptions) -> SpecimenResult {
    let traces = synthetic
        .traces
        .iter()
        .enumerate()
        .map(|(j, (t, a))| {
            analyze_specimen_trace(
                t,
                a,
                &synthetic.specimen.pendulum,
                PathBuf::from(format!("{}_{j}.csv", synthetic.specimen.name)),
                options,
            )
            .unwrap_or_else(|e| panic!("{e}"))
        })
        .collect();
    specimen_result(synthetic.specimen.clone(), traces)
}

fn uncastellated_set(rng: &mut Rng) -> Vec<Synthetic> {
    let mut model = rig_model();
    GEOMETRIES
        .iter()
        .enumerate()
        .map(|(i, &(w, l, t))| {
            let geometry = FlexureGeometry {
                kind: Kind::Uncastellated,
                width: w * 1e-3,
                thickness: t * 1e-6,
                length: l * 1e-6,
                castellation_length: f64::NAN,
            };
            simulate_specimen(
                &mut model,
                &format!("U{:02}", i + 1),
                geometry,
                geometry.length,
                ETA_TRUE,
                &release_angles(i),
                6.0,
                rng,
            )
        })
        .collect()
}

#[test]
fn pendulum_fit_recovers_modulus_loss_factor_and_stiffness() {
    let mut rng = Rng::new(20_150_928);
    let set = uncastellated_set(&mut rng);
    let frequencies: Vec<f64> = set
        .iter()
        .map(|s| {
            let (omega_d, _) = damping_at_own_frequency(s.k_true, ETA_TRUE, &s.specimen.pendulum);
            omega_d / TAU
        })
        .collect();
    let (f_lo, f_hi) = frequencies
        .iter()
        .fold((f64::INFINITY, 0.0_f64), |(lo, hi), &f| {
            (lo.min(f), hi.max(f))
        });
    println!("rig frequencies {f_lo:.2}–{f_hi:.2} Hz");
    assert!(
        f_lo > 2.0 && f_hi < 60.0,
        "rig frequencies {f_lo}–{f_hi} Hz"
    );

    // Per branch (finite amplitude, then Eq. 4 literal): each trace's relative k_m error and
    // number of crossings used, and the fitted (E, η).
    let mut per_trace: Vec<Vec<(f64, usize)>> = Vec::new();
    let mut fitted: Vec<(f64, f64)> = Vec::new();
    for small_angle in [false, true] {
        let options = FitOptions {
            small_angle,
            ..FitOptions::default()
        };
        let results: Vec<SpecimenResult> = set.iter().map(|s| analyse(s, &options)).collect();
        per_trace.push(
            set.iter()
                .zip(&results)
                .flat_map(|(s, r)| {
                    r.traces.iter().map(|t| {
                        (
                            common::relative_error(t.stiffness, s.k_true),
                            t.analysis.crossings.len(),
                        )
                    })
                })
                .collect(),
        );
        let mut worst_k = 0.0_f64;
        for (s, r) in set.iter().zip(&results) {
            for t in &r.traces {
                let error = common::relative_error(t.stiffness, s.k_true);
                worst_k = worst_k.max(error.abs());
                if !small_angle {
                    assert!(
                        error.abs() < 0.01,
                        "{}: k_m {} vs {} ({:+.3} %)",
                        s.specimen.name,
                        t.stiffness,
                        s.k_true,
                        100.0 * error
                    );
                    assert!(t.analysis.crossings.len() >= 10);
                }
            }
        }
        let report = fit_results(results, &options);
        // The trials of a flexure agree within their standard errors once the finite
        // amplitude is corrected for (no false warning over 25 flexures). Eq. 4 literally is
        // biased by the release amplitude, differently for the two trials (5°–15°): the
        // check must see it on some flexures (4 here, 4.2–5.3 standard errors), and on k_m
        // only, which is what the bias moves.
        if small_angle {
            assert!(!report.findings.is_empty());
            for finding in &report.findings {
                assert!(
                    finding.kind == "trial_disagreement"
                        && finding.message.contains("on k_m")
                        && !finding.message.contains("b_m"),
                    "{finding:?}"
                );
            }
        } else {
            assert!(report.findings.is_empty(), "{:#?}", report.findings);
        }
        let fit = report.uncastellated.expect("25 uncastellated specimens");
        let e_error = common::relative_error(fit.youngs_modulus, E_TRUE);
        let eta_error = common::relative_error(fit.loss_factor, ETA_TRUE);
        println!(
            "{}: E = {:.5} GPa ({:+.4} %), η = {:.5} ({:+.3} %), R² = {:.6} / {:.6}, \
             worst per-trace k_m error {:.4} %",
            if small_angle {
                "Eq. 4 literal"
            } else {
                "finite-amplitude gravity"
            },
            fit.youngs_modulus * 1e-9,
            100.0 * e_error,
            fit.loss_factor,
            100.0 * eta_error,
            fit.stiffness_line.r_squared,
            fit.damping_line.r_squared,
            100.0 * worst_k
        );
        fitted.push((fit.youngs_modulus, fit.loss_factor));
        if !small_angle {
            assert!(e_error.abs() < 0.01, "E error {e_error}");
            assert!(eta_error.abs() < 0.05, "η error {eta_error}");
            assert!(fit.stiffness_line.r_squared > 0.99);
            assert!(fit.damping_line.r_squared > 0.99);
            // A careful analysis does much better than the required 1 % / 5 %.
            assert!(worst_k < 2e-3, "worst k_m error {worst_k}");
            assert!(eta_error.abs() < 0.01, "η error {eta_error}");
        }
    }

    // Eq. 4 literal is biased low by the pendulum's finite amplitude, by the closed form:
    // I θ̈ + b θ̇ + k θ + G sin θ = 0 (G = m g L_cm); at amplitude A the first harmonic of
    // sin(A cos ωt) is (2 J₁(A)/A)·A cos ωt, so I ω² = k + G (1 − A²/8 + O(A⁴)), and
    // k_m = I ω² − G = k − G A²/8: a relative error −(G/k) A²/8 (the flexure is linear).
    // The amplitude decays, A_h = A₀ e^(−σ (h+1) π/ω_d) at the peak of half-cycle h (released
    // at rest from A₀, the first crossing a quarter period later), σ = b/(2 I_p) and ω_d of
    // the simulation. ω_d is π over the least squares slope of crossing time t_i against
    // index i = 0..N−1, and that slope is Σ c_h τ_h / Σ c_h over the half-cycle lengths
    // τ_h = t_(h+1) − t_h with c_h = Σ_(i>h) (i − ī) ∝ (h+1)(N−1−h); each τ_h is π/ω(A_h), so
    // to first order the bias is −(G/k) Σ c_h A_h²/8 / Σ c_h. Both branches analyse the same
    // traces, so the literal k_m minus the finite-amplitude one is that bias alone: within
    // 2 % of it per trace (the neglected A⁴/192 term is A²/24 ≤ 0.3 % of it at 15°, the rest
    // the envelope's O(ζ) offsets; measured 0.995–1.002 of it). A code that dropped, doubled
    // or sign-flipped the finite-amplitude correction, or mis-read the peak amplitudes,
    // fails here.
    let mut trace = 0;
    let (mut weighted_bias, mut width_squares) = (0.0, 0.0);
    for (i, s) in set.iter().enumerate() {
        let rig = &s.specimen.pendulum;
        let gravity = rig.mass * rig.gravity * rig.com_distance;
        let (omega_d, b) = damping_at_own_frequency(s.k_true, ETA_TRUE, rig);
        let sigma = b / (2.0 * rig.inertia);
        let mut specimen_bias = 0.0;
        for (j, &a0) in release_angles(i).iter().enumerate() {
            let ((finite, n), (literal, n_literal)) = (per_trace[0][trace], per_trace[1][trace]);
            assert_eq!(n, n_literal);
            let (mut sum, mut weights) = (0.0, 0.0);
            for h in 0..n - 1 {
                let c = ((h + 1) * (n - 1 - h)) as f64;
                let a = a0 * (-sigma * (h + 1) as f64 * PI / omega_d).exp();
                sum += c * a * a / 8.0;
                weights += c;
            }
            let bias = -gravity / s.k_true * sum / weights;
            let shift = literal - finite;
            assert!(
                (shift / bias - 1.0).abs() < 0.02,
                "{} trace {j}: Eq. 4 literal k_m error {literal:+.4e}, finite-amplitude \
                 {finite:+.4e}: shift {shift:.4e} against the closed form's {bias:.4e}",
                s.specimen.name
            );
            specimen_bias += bias / 2.0;
            trace += 1;
        }
        // E is the slope of y = 12 l k_m/t³ ≈ E w through the origin: Σ w y / Σ w², so a
        // relative error e_i of specimen i's mean k_m moves E by Σ w_i² e_i / Σ w_i².
        let w = s.specimen.flexure.width;
        weighted_bias += w * w * specimen_bias;
        width_squares += w * w;
    }
    assert_eq!(trace, per_trace[1].len());
    // So the literal fit's E is low by the width²-weighted bias (−3.35e-4 here), within 2 %,
    // and its η (damping slope over stiffness slope; b_m does not use the gravity term) is
    // high by exactly the inverse factor.
    let ((e_finite, eta_finite), (e_literal, eta_literal)) = (fitted[0], fitted[1]);
    let e_shift = e_literal / e_finite - 1.0;
    let e_bias = weighted_bias / width_squares;
    assert!(
        (e_shift / e_bias - 1.0).abs() < 0.02,
        "Eq. 4 literal E is {e_shift:+.4e} off the finite-amplitude E, closed form {e_bias:+.4e}"
    );
    assert!(
        ((eta_literal / eta_finite) * (e_literal / e_finite) - 1.0).abs() < 1e-9,
        "η {eta_literal} / {eta_finite}, E {e_literal} / {e_finite}"
    );
}

#[test]
fn castellated_fit_recovers_effective_length_and_loss_factor() {
    let mut rng = Rng::new(66);
    let mut model = rig_model();
    // The widths of seed Table III, 25 µm thick, 120 µm long, 100 µm castellations.
    let set: Vec<Synthetic> = SEED_TABLE_III
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let geometry = FlexureGeometry {
                kind: Kind::Castellated,
                width: row.width,
                thickness: 25e-6,
                length: 120e-6,
                castellation_length: 100e-6,
            };
            simulate_specimen(
                &mut model,
                &format!("C{}", i + 1),
                geometry,
                L_EFF_TRUE,
                ETA_CASTELLATED,
                &[
                    (6.0 + 1.3 * i as f64).to_radians(),
                    (14.0 - i as f64).to_radians(),
                ],
                6.0,
                &mut rng,
            )
        })
        .collect();
    let options = FitOptions {
        modulus: Some(E_TRUE),
        ..FitOptions::default()
    };
    let results: Vec<SpecimenResult> = set.iter().map(|s| analyse(s, &options)).collect();
    for (s, r) in set.iter().zip(&results) {
        for t in &r.traces {
            assert!(common::relative_error(t.stiffness, s.k_true).abs() < 0.01);
        }
    }
    let report = fit_results(results, &options);
    assert!(report.uncastellated.is_none());
    assert_eq!(report.castellated.len(), 1);
    let fit = &report.castellated[0];
    let l_error = common::relative_error(fit.effective_length, L_EFF_TRUE);
    let eta_error = common::relative_error(fit.loss_factor, ETA_CASTELLATED);
    println!(
        "castellated: l_eff = {:.3} µm ({:+.4} %), η' = {:.5} ({:+.3} %), R² = {:.6} / {:.6}",
        fit.effective_length * 1e6,
        100.0 * l_error,
        fit.loss_factor,
        100.0 * eta_error,
        fit.stiffness_line.r_squared,
        fit.damping_line.r_squared
    );
    assert!(l_error.abs() < 0.02, "l_eff error {l_error}");
    assert!(eta_error.abs() < 0.05, "η' error {eta_error}");
    assert!(fit.stiffness_line.r_squared > 0.99 && fit.damping_line.r_squared > 0.99);
}

#[test]
fn a_long_noisy_tail_does_not_bias_the_frequency() {
    // The same flexure recorded for 6 and for 20 e-folding times: the longer trace ends in
    // many noise-only "crossings", which must not change ω_d or σ.
    let geometry = FlexureGeometry {
        kind: Kind::Uncastellated,
        width: 2e-3,
        thickness: 25e-6,
        length: 500e-6,
        castellation_length: f64::NAN,
    };
    let mut model = rig_model();
    let mut run = |decays: f64| {
        let mut rng = Rng::new(7);
        let s = simulate_specimen(
            &mut model,
            "tail",
            geometry,
            geometry.length,
            ETA_TRUE,
            &[10f64.to_radians()],
            decays,
            &mut rng,
        );
        let (t, a) = &s.traces[0];
        (analyze_trace(t, a, &TraceOptions::default()).unwrap(), s)
    };
    let (short, s) = run(6.0);
    let (long, _) = run(20.0);
    let (omega_d, b) = damping_at_own_frequency(s.k_true, ETA_TRUE, &s.specimen.pendulum);
    let sigma = b / (2.0 * s.specimen.pendulum.inertia);
    for a in [&short, &long] {
        common::assert_close("ω_d", a.omega_d, omega_d, 2e-4, 0.0);
        common::assert_close("σ", a.sigma, sigma, 0.01, 0.0);
    }
    assert!((long.omega_d - short.omega_d).abs() < 1e-4 * omega_d);
    // The noise estimate is right to 10 %.
    assert!(
        common::relative_error(long.noise, NOISE).abs() < 0.1,
        "noise {}",
        long.noise
    );
}

#[test]
fn gravity_stiffens_the_hanging_rig() {
    // Linearized, the rig obeys I_p θ̈ + b θ̇ + (k + m g L_cm) θ = 0: at 0.5° the simulated
    // frequency must match ω_n = √((k + m g L_cm)/I_p) (not k − m g L_cm).
    let mut model = rig_model();
    set(&mut model, "eta", 0.0);
    let idx = |n: &str| model.param_index(n).unwrap();
    let p = |n: &str| model.param(idx(n));
    let k = bending_stiffness(p("E"), p("w"), p("h"), p("l"));
    let omega = ((k + p("m") * p("g") * p("L_cm")) / p("I_p")).sqrt();
    let options = common::dopri5_options(20.0 * TAU / omega, TAU / omega / 200.0, 1e-11, 1e-14);
    let run = common::simulate_at_default_inputs(&model, &[0.5f64.to_radians()], &[0.0], &options);
    let angle: Vec<f64> = run.q.iter().map(|q| q[0]).collect();
    let up = common::upward_crossings(&run.times, &angle);
    let period = (up[up.len() - 1] - up[0]) / (up.len() - 1) as f64;
    assert!(((TAU / period - omega) / omega).abs() < 1e-4);
}

fn damped_sine(n: usize, sigma: f64) -> (Vec<f64>, Vec<f64>) {
    let times: Vec<f64> = (0..n).map(|i| i as f64 * 1e-3).collect();
    let angles = times
        .iter()
        .map(|t| 0.1 * (-sigma * t).exp() * (TAU * 10.0 * t).cos())
        .collect();
    (times, angles)
}

#[test]
fn bad_traces_get_clear_errors() {
    let options = TraceOptions::default();
    let (t, a) = damped_sine(10, 1.0);
    let e = analyze_trace(&t, &a, &options).unwrap_err();
    assert!(matches!(e, TraceError::TooShort { samples: 10, .. }), "{e}");
    assert!(e.to_string().contains("too short"));

    let (mut t, a) = damped_sine(2000, 1.0);
    t[100] = t[98];
    let e = analyze_trace(&t, &a, &options).unwrap_err();
    assert_eq!(e, TraceError::TimeNotIncreasing { index: 100 });
    assert!(e.to_string().contains("data row 101"), "{e}");

    let (t, mut a) = damped_sine(2000, 1.0);
    a[500] = f64::NAN;
    let e = analyze_trace(&t, &a, &options).unwrap_err();
    assert_eq!(
        e,
        TraceError::NonFinite {
            index: 500,
            what: "angle"
        }
    );
    assert!(e.to_string().contains("not a finite number"));

    let (t, a) = damped_sine(2000, 0.0);
    let e = analyze_trace(&t, &a, &options).unwrap_err();
    assert!(matches!(e, TraceError::NoDecay { .. }), "{e}");
    assert!(e.to_string().contains("does not decay"));

    // Growing oscillation, with the rate that decided it.
    let (t, a) = damped_sine(2000, -1.0);
    let e = analyze_trace(&t, &a, &options).unwrap_err();
    assert!(
        matches!(e, TraceError::Growing { sigma, .. } if (sigma + 1.0).abs() < 1e-3),
        "{e}"
    );
    assert!(e.to_string().contains("grows"), "{e}");

    // Only one and a half cycles, then two and a half (< 3 periods: 5 crossings).
    for (n, crossings) in [(150, 3), (250, 5)] {
        let (t, a) = damped_sine(n, 1.0);
        let e = analyze_trace(&t, &a, &options).unwrap_err();
        assert!(
            matches!(e, TraceError::TooFewCrossings { found, period: Some(p), .. }
                if found == crossings && (p - 0.1).abs() < 1e-3),
            "{e}"
        );
        assert!(e.to_string().contains("record at least 3 periods"), "{e}");
    }
    let (t, a) = damped_sine(300, 1.0);
    assert!(analyze_trace(&t, &a, &options).is_ok());

    // Noise only.
    let mut rng = Rng::new(3);
    let t: Vec<f64> = (0..2000).map(|i| i as f64 * 1e-3).collect();
    let a: Vec<f64> = t.iter().map(|_| 1e-3 * gaussian(&mut rng)).collect();
    let e = analyze_trace(&t, &a, &options).unwrap_err();
    assert!(matches!(e, TraceError::NoOscillation { .. }), "{e}");
    assert!(
        e.to_string().contains("no oscillation above the noise"),
        "{e}"
    );

    let e = analyze_trace(&t, &a[..1999], &options).unwrap_err();
    assert!(matches!(e, TraceError::LengthMismatch { .. }));
}

#[test]
fn clean_damped_sine_is_analysed_exactly() {
    // θ = A e^{−σt} cos(ω_d t): zero crossings are exactly π/ω_d apart.
    let (t, a) = damped_sine(3000, 1.5);
    let r = analyze_trace(&t, &a, &TraceOptions::default()).unwrap();
    assert!(
        (r.omega_d - TAU * 10.0).abs() < 1e-6 * TAU * 10.0,
        "{}",
        r.omega_d
    );
    assert!((r.sigma - 1.5).abs() < 1e-4, "{}", r.sigma);
    assert!((r.omega_n - (1.5f64.powi(2) + (TAU * 10.0).powi(2)).sqrt()).abs() < 1e-4);
}

#[test]
fn flexure_formulas() {
    let kapton = Material::by_name("Kapton").unwrap();
    assert_eq!(kapton, Material::KAPTON_HN);
    assert_eq!(kapton.youngs_modulus, 2.56e9);
    assert_eq!(
        Material::by_name("kapton-datasheet")
            .unwrap()
            .youngs_modulus,
        2.5e9
    );
    let f = Flexure::uncastellated(&kapton, 2e-3, 25e-6, 500e-6);
    let k = 2.56e9 * 2e-3 * (25e-6_f64).powi(3) / (12.0 * 500e-6);
    assert!((f.stiffness() - k).abs() < 1e-15 * k.abs().max(1.0));
    assert!((f.damping(40.0) - k * 0.05 / 40.0).abs() < 1e-18);
    let c = f.complex_stiffness();
    assert_eq!((c.re, c.im), (f.stiffness(), 0.05 * f.stiffness()));
    assert!((twist_ratio(0.34) - 2.0 / 1.34).abs() < 1e-15);
    assert!((f.twist_stiffness() / f.stiffness() - 1.4925).abs() < 1e-4);
    // Overridable: a stiffer film.
    let stiff = Material {
        youngs_modulus: 3e9,
        ..Material::KAPTON_HN
    };
    assert!(Flexure::uncastellated(&stiff, 2e-3, 25e-6, 500e-6).stiffness() > f.stiffness());
    // Castellated: l − l_c ≤ l_eff ≤ l.
    assert!(Flexure::castellated(&kapton, 1e-3, 25e-6, 120e-6, 100e-6, 66e-6, 0.08).is_ok());
    let e = Flexure::castellated(&kapton, 1e-3, 25e-6, 120e-6, 100e-6, 130e-6, 0.08).unwrap_err();
    assert!(
        matches!(e, mech::physics::Invalid::EffectiveLength { .. })
            && e.to_string().contains("outside"),
        "{e}"
    );
    assert!(Flexure::uncastellated(&kapton, -1e-3, 25e-6, 1e-4)
        .validate()
        .is_err());
}

#[test]
fn table_iii_beside_eq_2() {
    // Eq. 2 with l_eff = 66 µm, E = 2.56 GPa, t = 25 µm: 50.505 µN·m/rad per mm of width.
    let mut worst = 0.0_f64;
    for row in SEED_TABLE_III {
        let f = Flexure::hamr_castellated(row.width);
        let k = f.stiffness();
        assert!((k / row.width - 2.56e9 * 25e-6_f64.powi(3) / (12.0 * 66e-6)).abs() < 1e-9);
        assert!((f.damping_times_omega() - 0.08 * k).abs() < 1e-18);
        worst = worst.max(common::relative_error(row.stiffness, k).abs());
    }
    // The table scatters around Eq. 2: L2 lists 31.9 where Eq. 2 gives 40.4, 21 % below it
    // (Eq. 2 is 27 % above the listed value). Reproduced as published, nothing tuned.
    assert!(worst > 0.2 && worst < 0.28, "worst {worst}");
    let text = mech::cli::flexure::seed_table_iii();
    assert!(text.contains("L2") && text.contains("40.4"), "{text}");
}

#[test]
fn specimen_files_are_read_and_checked() {
    use mech::flexure_fit::rig::parse_specimen;
    use mech::flexure_fit::{Error, SpecimenError};
    let path = std::path::Path::new("/data/u01.toml");
    let text = r#"
        name = "U01"
        traces = ["u01_a.csv"]
        angle_unit = "deg"
        [flexure]
        width = "2 mm"
        thickness = "25 um"
        length = 5e-4
        [pendulum]
        mass = "0.2 g"
        inertia = "2.4e-9 kg*m^2"
        com_distance = "3 mm"
    "#;
    let s = parse_specimen(path, text).unwrap();
    assert_eq!(s.name, "U01");
    assert_eq!(s.traces, vec![PathBuf::from("/data/u01_a.csv")]);
    assert!((s.flexure.width - 2e-3).abs() < 1e-15 && s.flexure.length == 5e-4);
    assert!((s.angle_scale.unwrap() - PI / 180.0).abs() < 1e-15);
    assert_eq!(s.pendulum.gravity, 9.81);

    let bad_unit = text.replace("\"3 mm\"", "\"3 g\"");
    let e = parse_specimen(path, &bad_unit).unwrap_err();
    assert!(
        matches!(
            &e,
            Error::Specimen {
                error: SpecimenError::Quantity(mech::quantity::Error {
                    subject: mech::quantity::Subject::Plain(key),
                    ..
                }),
                ..
            } if key == "pendulum.com_distance"
        ),
        "{e}"
    );
    let e = e.to_string();
    assert!(
        e.contains("pendulum.com_distance") && e.contains("u01.toml"),
        "{e}"
    );
    let inertia_about_com = text.replace("2.4e-9", "1e-9");
    let e = parse_specimen(path, &inertia_about_com).unwrap_err();
    assert!(
        matches!(
            &e,
            Error::Specimen {
                error: SpecimenError::InertiaBelowPointMass { .. },
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("about the pivot"), "{e}");
    let typo = text.replace("com_distance", "com_distanse");
    assert!(parse_specimen(path, &typo).is_err());
}

#[test]
fn example_data_fit_end_to_end() {
    // The small example set under examples/flexure_data/ goes through the whole pipeline:
    // TOML + CSV → tables, CSV files and plots.
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/flexure_data");
    let files = mech::flexure_fit::rig::specimen_files(std::slice::from_ref(&dir)).unwrap();
    assert!(files.len() >= 3);
    let specimens = files
        .iter()
        .map(|f| mech::flexure_fit::rig::read_specimen(f).unwrap())
        .collect();
    let report = mech::flexure_fit::fit_specimens(specimens, &FitOptions::default());
    assert!(report.rejected.is_empty(), "{:#?}", report.rejected);
    assert!(report.findings.is_empty(), "{:#?}", report.findings);
    let fit = report.uncastellated.as_ref().unwrap();
    common::assert_close("E", fit.youngs_modulus, E_TRUE, 0.01, 0.0);
    common::assert_close("η", fit.loss_factor, ETA_TRUE, 0.05, 0.0);
    let out = std::env::temp_dir().join(format!("mech_flexure_fit_{}", std::process::id()));
    let mut written = mech::render::flexure_fit::csv_files(&report, &out).unwrap();
    written.extend(mech::render::flexure_fit::plot_files(&report, &out, "svg").unwrap());
    mech::output::write_all(&written, &[]).unwrap();
    for f in &written {
        let size = std::fs::metadata(&f.path).unwrap().len();
        assert!(
            size > 100 && size == f.bytes.len() as u64,
            "{}",
            f.path.display()
        );
    }
    let text = mech::render::flexure_fit::text_report(&report);
    assert!(text.contains("Eq. 6") && text.contains("R²"), "{text}");
    let _ = std::fs::remove_dir_all(&out);
}
