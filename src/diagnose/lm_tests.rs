//! Tests of [`super`]: closed-form least squares, Monte-Carlo standard errors, Rosenbrock,
//! bounds, unidentifiable parameters, a flexure-pendulum ring-down, errors, information
//! criteria.

use super::*;

/// SplitMix64 with Box–Muller normals: a seeded, dependency-free noise source.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in (0, 1].
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

type Infallible = std::convert::Infallible;

fn fit<F>(f: F, parameters: &[Parameter], options: &LmOptions) -> FitResult
where
    F: FnMut(&[f64]) -> Result<Vec<f64>, Infallible>,
{
    match levenberg_marquardt(f, parameters, options) {
        Ok(result) => result,
        Err(e) => panic!("fit failed: {e}"),
    }
}

fn relative_error(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

/// Straight-line data `y = 1.5 + 0.8 x + N(0, 0.3²)`.
fn line_data(seed: u64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = Rng(seed);
    let x: Vec<f64> = (0..30).map(|i| -2.0 + 0.37 * i as f64).collect();
    let y = x
        .iter()
        .map(|x| 1.5 + 0.8 * x + 0.3 * rng.normal())
        .collect();
    (x, y)
}

/// The line `a + b x` fitted to `(x, y)`, from `a = 0` and `b` as given (with its bounds).
fn line_fit(x: &[f64], y: &[f64], b: Parameter) -> FitResult {
    fit(
        |p| Ok(x.iter().zip(y).map(|(x, y)| p[0] + p[1] * x - y).collect()),
        &[Parameter::new("a", 0.0), b],
        &LmOptions::default(),
    )
}

#[test]
fn linear_fit_matches_closed_form_ols() {
    let (x, y) = line_data(1);
    let m = x.len() as f64;
    let x_mean = x.iter().sum::<f64>() / m;
    let y_mean = y.iter().sum::<f64>() / m;
    let sxx: f64 = x.iter().map(|x| (x - x_mean).powi(2)).sum();
    let sxy: f64 = x
        .iter()
        .zip(&y)
        .map(|(x, y)| (x - x_mean) * (y - y_mean))
        .sum();
    let b = sxy / sxx;
    let a = y_mean - b * x_mean;
    let rss: f64 = x.iter().zip(&y).map(|(x, y)| (y - a - b * x).powi(2)).sum();
    let s2 = rss / (m - 2.0);
    let se_a = (s2 * (1.0 / m + x_mean * x_mean / sxx)).sqrt();
    let se_b = (s2 / sxx).sqrt();
    let cov_ab = -s2 * x_mean / sxx;

    let result = line_fit(&x, &y, Parameter::new("b", 0.0));
    assert!(result.converged, "{result}");
    let errors = [
        relative_error(result.params[0], a),
        relative_error(result.params[1], b),
        relative_error(result.standard_errors[0], se_a),
        relative_error(result.standard_errors[1], se_b),
        relative_error(result.covariance[(0, 1)], cov_ab),
        relative_error(2.0 * result.cost, rss),
        relative_error(result.noise_variance, s2),
    ];
    println!("linear OLS relative errors: {errors:?}\n{result}");
    for e in errors {
        assert!(e < 1e-8, "{errors:?}");
    }
    assert_eq!(result.rank, 2);
    assert_eq!(result.degrees_of_freedom, 28);
    assert_eq!(result.status, vec![ParameterStatus::Free; 2]);
    assert!(result.unidentifiable().is_empty());
    let (value, se) = result.parameter("b").unwrap();
    assert_eq!((value, se), (result.params[1], result.standard_errors[1]));
    let correlation = result.correlation();
    assert!((correlation[(0, 0)] - 1.0).abs() < 1e-12);
    assert!(correlation[(0, 1)] < 0.0 && correlation[(0, 1)] > -1.0);
}

/// `y = A exp(−k t)` sampled at 51 points over 5 s.
fn decay(a: f64, k: f64) -> impl Fn(f64) -> f64 {
    move |t| a * (-k * t).exp()
}

fn decay_fit(t: &[f64], y: &[f64]) -> FitResult {
    fit(
        |p| {
            Ok(t.iter()
                .zip(y)
                .map(|(t, y)| decay(p[0], p[1])(*t) - y)
                .collect())
        },
        &[Parameter::new("A", 1.0), Parameter::new("k", 0.5)],
        &LmOptions::default(),
    )
}

#[test]
fn exponential_decay_standard_errors_agree_with_monte_carlo() {
    let (a, k, sigma) = (2.5, 1.3, 0.05);
    let t: Vec<f64> = (0..51).map(|i| 0.1 * i as f64).collect();
    let truth: Vec<f64> = t.iter().map(|t| decay(a, k)(*t)).collect();
    let mut rng = Rng(7);
    let mut noisy = || -> Vec<f64> { truth.iter().map(|y| y + sigma * rng.normal()).collect() };

    let first = decay_fit(&t, &noisy());
    assert!(first.converged, "{first}");
    let (a_hat, se_a) = (first.params[0], first.standard_errors[0]);
    let (k_hat, se_k) = (first.params[1], first.standard_errors[1]);
    println!(
        "A = {a_hat} ± {se_a} ({:.2} se off), k = {k_hat} ± {se_k} ({:.2} se off)",
        (a_hat - a) / se_a,
        (k_hat - k) / se_k
    );
    assert!((a_hat - a).abs() < 3.0 * se_a);
    assert!((k_hat - k).abs() < 3.0 * se_k);

    let replicas = 200;
    let mut fits = Vec::with_capacity(replicas);
    for _ in 0..replicas {
        let result = decay_fit(&t, &noisy());
        assert!(result.converged, "{result}");
        fits.push(result);
    }
    let n = replicas as f64;
    for (j, name) in ["A", "k"].iter().enumerate() {
        let mean = fits.iter().map(|f| f.params[j]).sum::<f64>() / n;
        let mc_sd = (fits
            .iter()
            .map(|f| (f.params[j] - mean).powi(2))
            .sum::<f64>()
            / (n - 1.0))
            .sqrt();
        let mean_se = fits.iter().map(|f| f.standard_errors[j]).sum::<f64>() / n;
        let ratio = mean_se / mc_sd;
        println!("{name}: Monte-Carlo sd {mc_sd:.4e}, mean standard error {mean_se:.4e}, ratio {ratio:.3}");
        assert!((ratio - 1.0).abs() < 0.2, "{name}: ratio {ratio}");
        // And the first fit's own estimate, which a user sees.
        let single = first.standard_errors[j] / mc_sd;
        assert!(
            (single - 1.0).abs() < 0.2,
            "{name}: single-fit ratio {single}"
        );
    }
}

#[test]
fn rosenbrock_converges_from_the_classic_start() {
    let result = fit(
        |p| Ok(vec![10.0 * (p[1] - p[0] * p[0]), 1.0 - p[0]]),
        &[Parameter::new("x", -1.2), Parameter::new("y", 1.0)],
        &LmOptions::default(),
    );
    println!("{result}");
    assert!(result.converged, "{result}");
    assert!((result.params[0] - 1.0).abs() < 1e-8, "{result}");
    assert!((result.params[1] - 1.0).abs() < 1e-8, "{result}");
    assert!(result.cost < 1e-16);
    // Zero residual, two parameters, two residuals: no degrees of freedom for s².
    assert_eq!(result.degrees_of_freedom, 0);
    assert!(result.noise_variance.is_nan());
}

/// A stall line the fit cannot reach stops it after the stated iterations (Rosenbrock's valley
/// takes longer than 3 to fall below cost 0.5); one it reaches changes nothing.
#[test]
fn a_stalled_fit_stops_and_a_reachable_line_changes_nothing() {
    let rosenbrock = |p: &[f64]| Ok(vec![10.0 * (p[1] - p[0] * p[0]), 1.0 - p[0]]);
    let start = [Parameter::new("x", -1.2), Parameter::new("y", 1.0)];
    let plain = fit(rosenbrock, &start, &LmOptions::default());
    let stalled = fit(
        rosenbrock,
        &start,
        &LmOptions {
            stall: Some(Stall {
                iterations: 3,
                cost_above: 1e-6,
            }),
            ..LmOptions::default()
        },
    );
    assert_eq!(stalled.reason, StopReason::Stalled, "{stalled}");
    assert_eq!(stalled.iterations, 3);
    assert!(!stalled.converged && stalled.cost > 1e-6);
    let reachable = fit(
        rosenbrock,
        &start,
        &LmOptions {
            stall: Some(Stall {
                iterations: 3,
                cost_above: 1e3,
            }),
            ..LmOptions::default()
        },
    );
    assert_eq!(reachable.params, plain.params);
    assert_eq!(reachable.reason, plain.reason);
}

#[test]
fn active_bound_is_respected_and_reported() {
    let (x, y) = line_data(3);
    let m = x.len() as f64;
    let upper = 0.5; // the unconstrained slope is about 0.8
    let mut highest = f64::NEG_INFINITY;
    let result = fit(
        |p| {
            highest = highest.max(p[1]);
            Ok(x.iter().zip(&y).map(|(x, y)| p[0] + p[1] * x - y).collect())
        },
        &[
            Parameter::new("a", 0.0),
            Parameter::new("b", 0.1).bounded(0.0, upper),
        ],
        &LmOptions::default(),
    );
    println!("{result}");
    assert!(result.converged, "{result}");
    assert_eq!(result.params[1], upper);
    assert!(highest <= upper, "evaluated b = {highest} above the bound");
    assert_eq!(
        result.status,
        vec![ParameterStatus::Free, ParameterStatus::AtUpper]
    );
    assert!(result.standard_errors[1].is_nan());
    // With b held at the bound, a is the mean of y − b x, with s² = RSS/(m − 1).
    let a = x.iter().zip(&y).map(|(x, y)| y - upper * x).sum::<f64>() / m;
    let rss: f64 = x
        .iter()
        .zip(&y)
        .map(|(x, y)| (y - a - upper * x).powi(2))
        .sum();
    let se_a = (rss / (m - 1.0) / m).sqrt();
    assert!(relative_error(result.params[0], a) < 1e-8, "{result}");
    assert!(
        relative_error(result.standard_errors[0], se_a) < 1e-8,
        "{result}"
    );
    assert_eq!(result.degrees_of_freedom, x.len() - 1);

    // A lower bound, on the other side, with the bound met from a start far inside.
    let result = line_fit(&x, &y, Parameter::new("b", 5.0).bounded(1.0, 10.0));
    assert_eq!(result.params[1], 1.0);
    assert_eq!(result.status[1], ParameterStatus::AtLower);

    // An inactive bound changes nothing.
    let free = line_fit(&x, &y, Parameter::new("b", 0.1).bounded(0.0, 2.0));
    assert_eq!(free.status, vec![ParameterStatus::Free; 2]);
    assert!(free.standard_errors.iter().all(|s| s.is_finite()));

    // lower == upper holds a parameter fixed.
    let fixed = line_fit(&x, &y, Parameter::new("b", 0.7).bounded(0.7, 0.7));
    assert_eq!(fixed.params[1], 0.7);
    assert_eq!(fixed.status[1], ParameterStatus::Fixed);
    assert_eq!(fixed.standard_errors[1], 0.0);
    assert!(fixed.standard_errors[0].is_finite() && fixed.standard_errors[0] > 0.0);
}

#[test]
fn duplicated_parameter_is_flagged_unidentifiable() {
    let (x, y) = line_data(5);
    let result = fit(
        |p| {
            Ok(x.iter()
                .zip(&y)
                .map(|(x, y)| (p[0] + p[1]) * x + p[2] - y)
                .collect())
        },
        &[
            Parameter::new("k1", 0.3),
            Parameter::new("k2", 0.2),
            Parameter::new("offset", 0.0),
            Parameter::new("unused", 4.0),
        ],
        &LmOptions::default(),
    );
    println!("{result}");
    assert_eq!(result.unidentifiable(), vec!["k1", "k2", "unused"]);
    assert_eq!(result.standard_errors[0], f64::INFINITY);
    assert_eq!(result.standard_errors[1], f64::INFINITY);
    assert_eq!(result.standard_errors[3], f64::INFINITY);
    assert!(result.covariance[(0, 1)].is_nan());
    assert_eq!(result.status[2], ParameterStatus::Free);
    assert!(result.standard_errors[2].is_finite());
    assert_eq!(result.rank, 2);
    assert!(result.condition_number > 1e7, "{}", result.condition_number);
    // The identifiable combination and the offset still equal the OLS line.
    let ols = line_fit(&x, &y, Parameter::new("b", 0.0));
    assert!(relative_error(result.params[0] + result.params[1], ols.params[1]) < 1e-8);
    assert!(relative_error(result.params[2], ols.params[0]) < 1e-8);
    // The offset is orthogonal to the null direction (1, −1, 0), so its standard error is
    // the OLS intercept's.
    assert!(relative_error(result.standard_errors[2], ols.standard_errors[0]) < 1e-6);
    assert!(result.to_string().contains("unidentifiable"));
}

/// The flexure pendulum's ring-down `θ(t) = A e^(−ζω_n t) sin(ω_d t + φ)`, `ω_n = 2π f_n`,
/// `ω_d = ω_n √(1 − ζ²)`.
fn ring_down(p: &[f64], t: f64) -> f64 {
    let (f_n, zeta, amplitude, phase) = (p[0], p[1], p[2], p[3]);
    let omega_n = 2.0 * std::f64::consts::PI * f_n;
    let omega_d = omega_n * (1.0 - zeta * zeta).max(0.0).sqrt();
    amplitude * (-zeta * omega_n * t).exp() * (omega_d * t + phase).sin()
}

#[test]
fn damped_sinusoid_of_the_flexure_pendulum_is_recovered() {
    // 12 Hz, ζ = 0.03, 10° release, camera at 1 kHz for 1.5 s, 0.1° noise.
    let truth = [12.0, 0.03, 10f64.to_radians(), 0.4];
    let sigma = 0.1f64.to_radians();
    let mut rng = Rng(11);
    let t: Vec<f64> = (0..1500).map(|i| i as f64 * 1e-3).collect();
    let y: Vec<f64> = t
        .iter()
        .map(|t| ring_down(&truth, *t) + sigma * rng.normal())
        .collect();
    let names = ["f_n", "zeta", "amplitude", "phase"];
    let start = [11.8, 0.05, 8f64.to_radians(), 0.2];
    let parameters: Vec<Parameter> = names
        .iter()
        .zip(start)
        .map(|(n, s)| Parameter::new(*n, s))
        .collect();
    let parameters = [
        parameters[0].clone().bounded(0.0, f64::INFINITY),
        parameters[1].clone().bounded(0.0, 1.0),
        parameters[2].clone(),
        parameters[3].clone(),
    ];
    let options = LmOptions {
        residuals_normalized: true,
        ..LmOptions::default()
    };
    let result = fit(
        |p| {
            Ok(t.iter()
                .zip(&y)
                .map(|(t, y)| (ring_down(p, *t) - y) / sigma)
                .collect())
        },
        &parameters,
        &options,
    );
    println!("{result}");
    assert!(result.converged, "{result}");
    for j in 0..4 {
        let z = (result.params[j] - truth[j]) / result.standard_errors[j];
        println!(
            "{}: {} (truth {}), {z:.2} standard errors off, relative se {:.1e}",
            names[j],
            result.params[j],
            truth[j],
            result.standard_errors[j] / truth[j]
        );
        assert!(z.abs() < 3.0, "{}: {z} standard errors off", names[j]);
    }
    assert!(relative_error(result.params[0], truth[0]) < 1e-4);
    assert!(relative_error(result.params[1], truth[1]) < 2e-2);
    // Normalized residuals: χ²/dof ≈ 1.
    let chi2_per_dof = 2.0 * result.cost / result.degrees_of_freedom as f64;
    assert!((chi2_per_dof - 1.0).abs() < 0.1, "χ²/dof = {chi2_per_dof}");
    assert_eq!(result.noise_variance, 1.0);
}

#[test]
fn parameters_of_very_different_magnitudes_mix() {
    // A force in µN and a length in m: y = F / k_stiff · x with k known, fit F and an offset
    // of 1e-6 m; scales come from the initial values.
    let x: Vec<f64> = (0..20).map(|i| i as f64).collect();
    let (force, offset) = (3.2e-6, 2.0e-6);
    let y: Vec<f64> = x.iter().map(|x| force * 1e3 * x + offset).collect();
    let result = fit(
        |p| {
            Ok(x.iter()
                .zip(&y)
                .map(|(x, y)| (p[0] * 1e3 * x + p[1] - y) / 1e-6)
                .collect())
        },
        &[
            Parameter::new("force", 1e-6),
            Parameter::new("offset", 0.0).with_scale(1e-6),
        ],
        &LmOptions::default(),
    );
    assert!(result.converged, "{result}");
    assert!(relative_error(result.params[0], force) < 1e-10, "{result}");
    assert!(relative_error(result.params[1], offset) < 1e-8, "{result}");
}

#[test]
fn failing_trial_points_are_rejected_not_fatal() {
    // The residual function refuses k > 2 (say, an integrator that diverges there); the fit
    // starts close to it with a first step that overshoots.
    let t: Vec<f64> = (0..40).map(|i| 0.1 * i as f64).collect();
    let y: Vec<f64> = t.iter().map(|t| decay(1.0, 1.9)(*t)).collect();
    let result = levenberg_marquardt(
        |p: &[f64]| {
            if p[1] > 2.0 || p[1] < 0.0 {
                return Err(format!("k = {} diverges", p[1]));
            }
            Ok(t.iter()
                .zip(&y)
                .map(|(t, y)| decay(p[0], p[1])(*t) - y)
                .collect())
        },
        &[Parameter::new("A", 3.0), Parameter::new("k", 0.2)],
        &LmOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(result.converged, "{result}");
    assert!((result.params[1] - 1.9).abs() < 1e-8, "{result}");
}

#[test]
fn unusable_problems_give_errors() {
    let options = LmOptions::default();
    let ok = |_: &[f64]| -> Result<Vec<f64>, String> { Ok(vec![1.0, 2.0]) };
    let message = |e: LmError<String>| e.to_string();

    let e = levenberg_marquardt(ok, &[], &options).unwrap_err();
    assert_eq!(e, LmError::NoParameters);
    for (parameter, expected) in [
        (Parameter::new("k", f64::NAN), "not finite"),
        (
            Parameter::new("k", 1.0).bounded(2.0, 1.0),
            "not an interval",
        ),
        (
            Parameter::new("k", 1.0).bounded(f64::NAN, 1.0),
            "not an interval",
        ),
        (
            Parameter::new("k", 3.0).bounded(0.0, 1.0),
            "outside the bounds",
        ),
        (Parameter::new("k", 1.0).with_scale(0.0), "scale"),
    ] {
        let text = message(levenberg_marquardt(ok, &[parameter], &options).unwrap_err());
        assert!(text.contains("`k`") && text.contains(expected), "{text}");
    }
    let p = [Parameter::new("k", 1.0)];
    let text = message(
        levenberg_marquardt(|_: &[f64]| Err("no model".to_string()), &p, &options).unwrap_err(),
    );
    assert!(text.contains("no model"), "{text}");
    let text = message(
        levenberg_marquardt(|_: &[f64]| Ok(vec![1.0, f64::NAN]), &p, &options).unwrap_err(),
    );
    assert!(
        text.contains("residual 1") && text.contains("NaN"),
        "{text}"
    );
    let e = levenberg_marquardt(|_: &[f64]| Ok::<_, String>(vec![]), &p, &options).unwrap_err();
    assert_eq!(e, LmError::NoResiduals);
    let mut calls = 0;
    let e = levenberg_marquardt(
        |p: &[f64]| {
            calls += 1;
            Ok(vec![p[0]; if calls == 1 { 3 } else { 2 }])
        },
        &[Parameter::new("k", 1.0)],
        &options,
    )
    .unwrap_err();
    assert!(message(e).contains("2 residuals"));
}

#[test]
fn limits_stop_the_iteration_without_convergence() {
    let options = LmOptions {
        max_iterations: 2,
        ..LmOptions::default()
    };
    let result = fit(
        |p| Ok(vec![10.0 * (p[1] - p[0] * p[0]), 1.0 - p[0]]),
        &[Parameter::new("x", -1.2), Parameter::new("y", 1.0)],
        &options,
    );
    assert_eq!(result.reason, StopReason::MaxIterations);
    assert!(!result.converged);
    assert_eq!(result.iterations, 2);
}

#[test]
fn information_criteria_follow_the_gaussian_likelihood() {
    let two_pi = 2.0 * std::f64::consts::PI;
    // RSS = 4 over m = 10 residuals, n = 2 parameters, σ unknown: k = 3.
    let ic = information_criteria(2.0, 10, 2, NoiseModel::UnknownVariance);
    let log_l = -5.0 * ((two_pi * 0.4).ln() + 1.0);
    assert_eq!(ic.parameters, 3);
    assert!((ic.log_likelihood - log_l).abs() < 1e-12);
    assert!((ic.aic - (6.0 - 2.0 * log_l)).abs() < 1e-12);
    assert!((ic.aicc - (ic.aic + 24.0 / 6.0)).abs() < 1e-12);
    assert!((ic.bic - (3.0 * 10f64.ln() - 2.0 * log_l)).abs() < 1e-12);
    // Normalized residuals: k = n, ln L = −(m/2) ln 2π − RSS/2.
    let ic = information_criteria(2.0, 10, 2, NoiseModel::Normalized);
    assert_eq!(ic.parameters, 2);
    assert!((ic.log_likelihood - (-5.0 * two_pi.ln() - 2.0)).abs() < 1e-12);
    assert!((ic.aicc - (ic.aic + 12.0 / 7.0)).abs() < 1e-12);
    // Too few residuals for AICc.
    assert_eq!(
        information_criteria(1.0, 3, 2, NoiseModel::Normalized).aicc,
        f64::INFINITY
    );

    // Model selection: quadratic data prefer the quadratic model.
    let mut rng = Rng(17);
    let x: Vec<f64> = (0..40).map(|i| -1.0 + 0.05 * i as f64).collect();
    let y: Vec<f64> = x
        .iter()
        .map(|x| 0.2 + 0.5 * x + 0.8 * x * x + 0.05 * rng.normal())
        .collect();
    let linear = line_fit(&x, &y, Parameter::new("b", 0.0));
    let quadratic = fit(
        |p| {
            Ok(x.iter()
                .zip(&y)
                .map(|(x, y)| p[0] + p[1] * x + p[2] * x * x - y)
                .collect())
        },
        &[
            Parameter::new("a", 0.0),
            Parameter::new("b", 0.0),
            Parameter::new("c", 0.0),
        ],
        &LmOptions::default(),
    );
    let (l, q) = (
        linear.information_criteria(NoiseModel::UnknownVariance),
        quadratic.information_criteria(NoiseModel::UnknownVariance),
    );
    assert!(q.aic < l.aic - 10.0 && q.bic < l.bic - 10.0 && q.aicc < l.aicc - 10.0);
}
