//! Screening of one pendulum ring-down for what a linear flexure with a constant loss factor
//! cannot produce: damping or frequency that depend on the amplitude, and an oscillation
//! centre that is off the rest angle or drifts. `mech flexure fit` screens every trace with it,
//! and so does `mech diagnose` with `kind = "pendulum"` (single traces and `--dataset`): one
//! implementation for both.
//!
//! Consumes: sample times (s, strictly increasing) and angles (rad, from the rest position),
//! optionally the pendulum's gravity share of the stiffness ([`ScreenOptions`]). Produces: a
//! [`Screening`], the fit's estimates and the [`Flag`]s, each with a kind and a message.
//!
//! It starts from the trace analysis ([`super::trace`]: zero crossings with hysteresis, one
//! least-squares half-sine amplitude `A_j` per half-cycle, the noise level from fourth
//! differences) and makes two fits.
//!
//! **Amplitudes** (Levenberg–Marquardt, weights `A_j²/σ_A²`, the inverse variance of `ln A_j`
//! under additive noise):
//!
//! ```text
//! ln A_j(measured) = ln A(τ_j) + ln g(s_j c(τ_j) / A(τ_j)),
//! ln A(τ) = a − σ₀ τ − σ₁ ∫₀^τ A dt,     c(τ) = c₀ + c₁ (τ − τ_m)
//! ```
//!
//! with `τ_j` the half-cycle's time, `s_j = ±1` its sign and `τ_m` the middle of the trace.
//! `A(τ)` decays at the rate `σ(A) = σ₀ + σ₁ A`: `σ₁ ≠ 0` is damping that depends on the
//! amplitude (air drag, friction at the clamp). `c(τ)` is the oscillation's centre: an
//! oscillation centred at `c` crosses zero early or late, so the half-cycles on the side of `c`
//! measure larger and those on the other side smaller, by the factor `g(±c/A) ≈ 1 ± (3/π)
//! c/A` (`offset_factor`, exact to all orders) — an alternation the smooth decay cannot
//! mimic. `c₁ ≠ 0` is a drifting baseline, `c₀ ≠ 0` an offset.
//!
//! **Crossing times** (weighted linear least squares, each crossing's weight the inverse
//! variance of its time, `(A ω)² m / noise²` for the `m` samples of its line fit):
//!
//! ```text
//! t_k + s_k ε_k/ω = T + Σ_{j<k} (D₀ + D₂ A_j²)(1 + σ(A_j)²/(2ω²)),    sin ε_k = c(t_k)/A(t_k)
//! ```
//!
//! The half-cycle of amplitude A lasts `π/ω_d(A)`, `ω_d² = ω_n(A)² − σ(A)²`; the first fit
//! gives `σ(A)` and `c(τ)`, whose shifts of the crossings are taken out, so what is left is
//! `ω_n(A) = π/(D₀ + D₂ A²) ≈ ω₀ (1 + γ A²)`, `γ = −D₂/D₀`. A pendulum's gravity moment
//! `m g L sin θ` softens it: its first harmonic is `m g L (1 − A²/8)`, so `γ_gravity = −g/16`
//! for a gravity share `g = m g L/(I ω_n²)`. A flexure stiffening as `k (1 + β θ²)` (first
//! harmonic `k (1 + ¾ β A²)`) adds `γ − γ_gravity = ⅜ β (1 − g)`. With the gravity share known
//! (`mech flexure fit`, from the specimen's pendulum) the excess over `γ_gravity` is tested;
//! without it (a single trace in `mech diagnose`) only what no share in [0, 1] explains:
//! `γ > 0` (stiffening) or `γ < −1/16` (softening).
//!
//! The standard errors of both fits are scaled up by `√(χ²/dof)` when the scatter exceeds the
//! noise (so a screening model that does not fit cannot produce a flag by itself), and an
//! effect is flagged beyond [`FLAG_SIGMA`] standard errors.

use std::f64::consts::PI;

use super::trace::{analyze_trace, TraceAnalysis, TraceOptions};
use crate::diagnose::lm::{levenberg_marquardt, FitResult, LmOptions, Parameter};

/// An effect is flagged when its estimate exceeds this many standard errors. Four effects
/// are tested per trace; with Gaussian noise 3.5σ gives a false flag on about 0.2 % of
/// clean traces.
pub const FLAG_SIGMA: f64 = 3.5;

/// Amplitude noise floor, relative to the first half-cycle's amplitude: effects below it
/// (noise-free synthetic traces, numerical error of the simulation) are not flagged.
const RELATIVE_NOISE_FLOOR: f64 = 1e-3;

/// Fewest half-cycles above the noise that the screening fit (5 coefficients) needs.
const MIN_HALF_CYCLES: usize = 10;

/// The largest softening a gravity share in [0, 1] can cause, `γ = −1/16` (see the module
/// documentation).
const MAX_GRAVITY_SOFTENING: f64 = 1.0 / 16.0;

/// What the screening knows about the pendulum besides the trace.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ScreenOptions {
    /// The gravity share of the small-amplitude stiffness, `m g L_cm / (I_p ω_n²)`, when the
    /// pendulum is known; `None`: anything in [0, 1].
    pub gravity_share: Option<f64>,
}

/// Something in a trace that a linear flexure with a constant loss factor cannot produce.
#[derive(Debug, Clone, PartialEq)]
pub struct Flag {
    /// `amplitude_dependent_damping`, `amplitude_stiffening`, `amplitude_softening`,
    /// `baseline_drift`, `baseline_offset` or `not_screened`.
    pub kind: &'static str,
    /// The finding with its numbers, for reports.
    pub message: String,
}

/// The screening fit's estimates (see the module documentation), SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct ScreeningFit {
    /// Half-cycles used.
    pub half_cycles: usize,
    /// First and last half-cycle amplitude (rad).
    pub amplitudes: (f64, f64),
    /// Noise level of the angle estimated from the trace (rad).
    pub noise: f64,
    /// Damped angular frequency (rad/s).
    pub omega_d: f64,
    /// Logarithmic decrement per cycle, `2π σ(A)/ω_d`, at the first and the last amplitude.
    pub decrement: (f64, f64),
    /// σ₁ in standard errors.
    pub decrement_trend_sigma: f64,
    /// Baseline at the first and the last half-cycle (rad).
    pub baseline: (f64, f64),
    /// c₁ and c₀ in standard errors.
    pub drift_sigma: f64,
    pub offset_sigma: f64,
    /// Time span of the half-cycles used (s).
    pub span: f64,
    /// `γ` of `ω_n(A) ≈ ω₀ (1 + γ A²)` (1/rad²) and its standard error.
    pub frequency_trend: (f64, f64),
    /// The gravity share used, if known.
    pub gravity_share: Option<f64>,
    /// `γ` beyond what gravity explains, in standard errors (0 within the gravity band when
    /// the share is unknown); positive: stiffening.
    pub stiffening_sigma: f64,
}

impl ScreeningFit {
    /// `γ − γ_gravity` (1/rad²): the share's, or the nearest end of [−1/16, 0].
    pub fn excess_frequency_trend(&self) -> f64 {
        let gamma = self.frequency_trend.0;
        match self.gravity_share {
            Some(g) => gamma + g / 16.0,
            None if gamma > 0.0 => gamma,
            None => (gamma + MAX_GRAVITY_SOFTENING).min(0.0),
        }
    }

    /// How much higher (relative) the natural frequency is at the first amplitude than at the
    /// last, beyond gravity.
    pub fn excess_frequency_change(&self) -> f64 {
        let (first, last) = self.amplitudes;
        self.excess_frequency_trend() * (first * first - last * last)
    }

    /// The flexure's stiffening `β A²` at the first amplitude for `k (1 + β θ²)`, when the
    /// gravity share is known.
    pub fn stiffening_at_first_amplitude(&self) -> Option<f64> {
        let g = self.gravity_share?;
        let beta = self.excess_frequency_trend() / (0.375 * (1.0 - g));
        Some(beta * self.amplitudes.0.powi(2))
    }
}

/// The result of [`screen`].
#[derive(Debug, Clone, PartialEq)]
pub struct Screening {
    /// What the trace shows that the model cannot fit (empty: nothing).
    pub flags: Vec<Flag>,
    /// The screening fit, when the trace could be analysed.
    pub fit: Option<ScreeningFit>,
}

impl Screening {
    /// One line on what was checked and found.
    pub fn summary(&self) -> String {
        let Some(f) = &self.fit else {
            return "the trace could not be screened".into();
        };
        format!(
            "screened {} half-cycles (amplitude {:.2}° → {:.2}°, noise {:.3}°, ω_d = {:.2} \
             rad/s): log decrement per cycle {:.4} → {:.4} (trend {:.1}σ), frequency {:+.3} % \
             beyond gravity ({:.1}σ), centre {:+.3}° → {:+.3}° (drift {:.1}σ, offset {:.1}σ); \
             flagged beyond {FLAG_SIGMA}σ",
            f.half_cycles,
            f.amplitudes.0.to_degrees(),
            f.amplitudes.1.to_degrees(),
            f.noise.to_degrees(),
            f.omega_d,
            f.decrement.0,
            f.decrement.1,
            f.decrement_trend_sigma,
            100.0 * f.excess_frequency_change(),
            f.stiffening_sigma,
            f.baseline.0.to_degrees(),
            f.baseline.1.to_degrees(),
            f.drift_sigma,
            f.offset_sigma
        )
    }

    /// Whether a flag of this kind was raised.
    pub fn has(&self, kind: &str) -> bool {
        self.flags.iter().any(|f| f.kind == kind)
    }
}

/// Screens one decay trace (times in s, strictly increasing; angles in rad from the rest
/// position) without knowing the pendulum: [`screen_with`] and the default options.
pub fn screen(times: &[f64], angles: &[f64]) -> Screening {
    screen_with(times, angles, &ScreenOptions::default())
}

/// Screens one decay trace for amplitude-dependent damping and frequency and a baseline
/// offset or drift.
pub fn screen_with(times: &[f64], angles: &[f64], options: &ScreenOptions) -> Screening {
    match analyze_trace(times, angles, &TraceOptions::default()) {
        Ok(analysis) => screen_analysis(times, angles, &analysis, options),
        Err(e) => not_screened(e.to_string()),
    }
}

/// [`screen_with`] on a trace already analysed (with any [`TraceOptions`]).
pub fn screen_analysis(
    times: &[f64],
    angles: &[f64],
    analysis: &TraceAnalysis,
    options: &ScreenOptions,
) -> Screening {
    if analysis.peaks.len() < MIN_HALF_CYCLES {
        return not_screened(format!(
            "only {} half-cycles above the noise (need {MIN_HALF_CYCLES})",
            analysis.peaks.len()
        ));
    }
    match screening_fit(times, angles, analysis, options) {
        Some(fit) => Screening {
            flags: flags(&fit),
            fit: Some(fit),
        },
        None => not_screened("the screening fit is singular (too short a trace?)".into()),
    }
}

fn not_screened(why: String) -> Screening {
    Screening {
        flags: vec![Flag {
            kind: "not_screened",
            message: format!(
                "not screened: {why}; amplitude-dependent damping and frequency and baseline \
                 drift could not be checked"
            ),
        }],
        fit: None,
    }
}

/// `√(χ²/dof)` when above 1: the factor by which scatter beyond the noise widens a fit's
/// standard errors.
fn inflation(result: &FitResult, values: usize) -> Option<f64> {
    let parameters = result.params.len();
    (values > parameters).then(|| {
        let chi2_dof = 2.0 * result.cost / (values - parameters) as f64;
        chi2_dof.max(1.0).sqrt()
    })
}

/// Parameter `k` in its (inflated) standard errors; 0 when that is not finite.
fn in_standard_errors(result: &FitResult, k: usize, inflation: f64) -> f64 {
    let se = result.standard_errors[k] * inflation;
    if se.is_finite() && se > 0.0 {
        result.params[k] / se
    } else {
        0.0
    }
}

fn screening_fit(
    times: &[f64],
    angles: &[f64],
    analysis: &TraceAnalysis,
    options: &ScreenOptions,
) -> Option<ScreeningFit> {
    let peaks = &analysis.peaks;
    let n = peaks.len();
    let first = peaks[0].1;
    let noise = analysis.noise.max(RELATIVE_NOISE_FLOOR * first);
    let t_first = peaks[0].0;
    let span = peaks[n - 1].0 - t_first;
    let middle = 0.5 * span;
    let half_cycles = half_cycles(times, angles, analysis, noise);
    // ln A_j(measured) = ln(A_j · g(s_j c(τ_j)/A_j)), ln A_j = a − σ₀τ_j − σ₁∫A dt.
    let residuals = |p: &[f64]| -> Result<Vec<f64>, &'static str> {
        let [a, sigma0, sigma1, c0, c1] = [p[0], p[1], p[2], p[3], p[4]];
        half_cycles
            .iter()
            .map(|h| {
                let log_true = a - sigma0 * h.tau - sigma1 * h.integral;
                let ratio = h.sign * (c0 + c1 * (h.tau - middle)) / log_true.exp();
                let factor = offset_factor(ratio).ok_or("offset beyond the amplitude")?;
                Ok((log_true + factor.ln() - h.log_amplitude) * h.root_weight)
            })
            .collect()
    };
    let scale_c = 10.0 * noise;
    let parameters = [
        Parameter::new("a", first.ln()).with_scale(1.0),
        Parameter::new("sigma0", analysis.sigma),
        Parameter::new("sigma1", 0.0).with_scale(analysis.sigma / first),
        Parameter::new("c0", 0.0).with_scale(scale_c),
        Parameter::new("c1", 0.0).with_scale(scale_c / span.max(f64::MIN_POSITIVE)),
    ];
    let lm = LmOptions {
        residuals_normalized: true,
        ..LmOptions::default()
    };
    let result = levenberg_marquardt(residuals, &parameters, &lm).ok()?;
    if result.params.iter().any(|p| !p.is_finite()) {
        return None;
    }
    let inflation_a = inflation(&result, n)?;
    let [a, sigma0, sigma1, c0, c1] = [0, 1, 2, 3, 4].map(|k| result.params[k]);
    let envelope: Vec<f64> = half_cycles
        .iter()
        .map(|h| (a - sigma0 * h.tau - sigma1 * h.integral).exp())
        .collect();
    let centre = |t: f64| c0 + c1 * (t - t_first - middle);
    let (gamma, gamma_se) = frequency_fit(
        times,
        analysis,
        noise,
        &envelope,
        &half_cycles,
        (sigma0, sigma1),
        centre,
    )?;
    let last = peaks[n - 1].1;
    let decrement = |a: f64| 2.0 * PI * (sigma0 + sigma1 * a) / analysis.omega_d;
    let mut fit = ScreeningFit {
        half_cycles: n,
        amplitudes: (first, last),
        noise: analysis.noise,
        omega_d: analysis.omega_d,
        decrement: (decrement(first), decrement(last)),
        decrement_trend_sigma: in_standard_errors(&result, 2, inflation_a),
        baseline: (c0 - c1 * middle, c0 + c1 * middle),
        drift_sigma: in_standard_errors(&result, 4, inflation_a),
        offset_sigma: in_standard_errors(&result, 3, inflation_a),
        span,
        frequency_trend: (gamma, gamma_se),
        gravity_share: options.gravity_share,
        stiffening_sigma: 0.0,
    };
    if gamma_se.is_finite() && gamma_se > 0.0 {
        fit.stiffening_sigma = fit.excess_frequency_trend() / gamma_se;
    }
    Some(fit)
}

/// Per half-cycle of `analysis`: τ, ∫A dt up to it, sign, ln A and its weight (for the
/// amplitude noise `noise`).
fn half_cycles(
    times: &[f64],
    angles: &[f64],
    analysis: &TraceAnalysis,
    noise: f64,
) -> Vec<HalfCycle> {
    let peaks = &analysis.peaks;
    let t_first = peaks[0].0;
    let mut half_cycles = Vec::with_capacity(peaks.len());
    let mut integral = 0.0;
    for (j, &(t, amplitude)) in peaks.iter().enumerate() {
        if j > 0 {
            let (t_prev, a_prev) = peaks[j - 1];
            integral += 0.5 * (a_prev + amplitude) * (t - t_prev);
        }
        // The half-cycle's sign: the sample nearest its middle.
        let k = times.partition_point(|&s| s < t).min(times.len() - 1);
        let sign = if angles[k] < 0.0 { -1.0 } else { 1.0 };
        // The least-squares half-sine amplitude over m samples has σ_A = noise·√(2/m).
        let (c0, c1) = (analysis.crossings[j], analysis.crossings[j + 1]);
        let inside = times.partition_point(|&s| s < c1) - times.partition_point(|&s| s <= c0);
        let sigma_a = noise * (2.0 / inside.max(1) as f64).sqrt();
        half_cycles.push(HalfCycle {
            tau: t - t_first,
            integral,
            sign,
            log_amplitude: amplitude.ln(),
            root_weight: amplitude / sigma_a,
        });
    }
    half_cycles
}

/// The crossing-time fit of the module documentation: `γ` and its (inflated) standard
/// error, from the crossings of `analysis`, the fitted amplitude `envelope` at each
/// half-cycle, the decay rate `σ₀ + σ₁ A` and the oscillation's `centre` at a time.
fn frequency_fit(
    times: &[f64],
    analysis: &TraceAnalysis,
    noise: f64,
    envelope: &[f64],
    half_cycles: &[HalfCycle],
    (sigma0, sigma1): (f64, f64),
    centre: impl Fn(f64) -> f64,
) -> Option<(f64, f64)> {
    let crossings = &analysis.crossings;
    let omega = analysis.omega_d;
    let half_period = PI / omega;
    let n = envelope.len();
    let decay = |a: f64| sigma0 + sigma1 * a;
    // Per crossing k: the time with the offset's shift taken out, the two regressors
    // (Σ (1 + h_j), Σ A_j² (1 + h_j) over the half-cycles before it) and the weight.
    let mut rows = Vec::with_capacity(n + 1);
    let (mut x1, mut x2) = (0.0, 0.0);
    for (k, &t) in crossings.iter().enumerate() {
        // The amplitude at the crossing, from the neighbouring half-cycles' envelope.
        let amplitude = if k == 0 {
            envelope[0] * (decay(envelope[0]) * (analysis.peaks[0].0 - t)).exp()
        } else if k == n {
            envelope[n - 1] * (-decay(envelope[n - 1]) * (t - analysis.peaks[n - 1].0)).exp()
        } else {
            (envelope[k - 1] * envelope[k]).sqrt()
        };
        // The half-cycle that starts at crossing k has sign s_k (the last one's opposite).
        let sign = if k < n {
            half_cycles[k].sign
        } else {
            -half_cycles[n - 1].sign
        };
        let epsilon = (centre(t) / amplitude).clamp(-0.5, 0.5).asin();
        let (lo, hi) = (
            times.partition_point(|&s| s < t - 0.15 * half_period),
            times.partition_point(|&s| s <= t + 0.15 * half_period),
        );
        let samples = (hi - lo).max(1) as f64;
        let sigma_t = noise / (amplitude * omega * samples.sqrt());
        rows.push((
            t - crossings[0] + sign * epsilon / omega,
            x1,
            x2,
            1.0 / sigma_t,
        ));
        if k < n {
            let a = envelope[k];
            let h = decay(a).powi(2) / (2.0 * omega * omega);
            x1 += 1.0 + h;
            x2 += a * a * (1.0 + h);
        }
    }
    let residuals = |p: &[f64]| -> Result<Vec<f64>, &'static str> {
        Ok(rows
            .iter()
            .map(|&(t, x1, x2, w)| (p[0] + p[1] * x1 + p[2] * x2 - t) * w)
            .collect())
    };
    let parameters = [
        Parameter::new("T", 0.0).with_scale(1e-3 * half_period),
        Parameter::new("D0", half_period),
        Parameter::new("D2", 0.0).with_scale(0.1 * half_period),
    ];
    let lm = LmOptions {
        residuals_normalized: true,
        ..LmOptions::default()
    };
    let result = levenberg_marquardt(residuals, &parameters, &lm).ok()?;
    let inflation = inflation(&result, rows.len())?;
    let (d0, d2) = (result.params[1], result.params[2]);
    let gamma = -d2 / d0;
    let se = result.standard_errors[2] * inflation / d0;
    (gamma.is_finite() && d0 > 0.0).then_some((gamma, se))
}

/// One half-cycle of the screening fit.
struct HalfCycle {
    /// Time of its middle from the first one's (s).
    tau: f64,
    /// ∫A dt from the first half-cycle to this one (rad·s).
    integral: f64,
    /// +1 above the rest angle, −1 below.
    sign: f64,
    log_amplitude: f64,
    /// `1/σ(ln A)` = A/σ_A.
    root_weight: f64,
}

/// `g(x)`: the least-squares half-sine amplitude, over the window between its zero
/// crossings, of `sin θ + x` (an oscillation of unit amplitude centred at `x`), so that a
/// half-cycle of amplitude `A` centred at `c` measures `A·g(s c/A)`. `g(0) = 1`,
/// `g'(0) = κ = 3/π`; the exact form matters at the end of a trace, where a drifting centre
/// is no longer small against the amplitude and the second-order term would otherwise look
/// like extra damping. `None` for `|x| ≥ 0.5` (the trace analysis drops such half-cycles).
fn offset_factor(x: f64) -> Option<f64> {
    if x.is_nan() || x.abs() >= 0.5 {
        return None;
    }
    // Crossings at θ = −ε and π + ε with sin ε = x; u ∈ [0, π] spans the window.
    let epsilon = x.asin();
    let f = |u: f64| {
        let theta = -epsilon + u * (PI + 2.0 * epsilon) / PI;
        (theta.sin() + x) * u.sin()
    };
    // Simpson's rule: the integrand is smooth, 64 intervals give ~1e-9.
    let intervals = 64;
    let h = PI / intervals as f64;
    let mut sum = f(0.0) + f(PI);
    for i in 1..intervals {
        sum += f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    Some(sum * h / 3.0 / (PI / 2.0))
}

fn flags(fit: &ScreeningFit) -> Vec<Flag> {
    let mut flags = Vec::new();
    let deg = |x: f64| x.to_degrees();
    if fit.decrement_trend_sigma.abs() > FLAG_SIGMA {
        flags.push(Flag {
            kind: "amplitude_dependent_damping",
            message: format!(
                "flagged: amplitude-dependent damping (log decrement per cycle {:.4} → {:.4} as \
                 the amplitude falls {:.2}° → {:.2}°, {:.1}σ); a constant loss factor cannot \
                 fit this trace",
                fit.decrement.0,
                fit.decrement.1,
                deg(fit.amplitudes.0),
                deg(fit.amplitudes.1),
                fit.decrement_trend_sigma.abs()
            ),
        });
    }
    if fit.stiffening_sigma.abs() > FLAG_SIGMA {
        let stiffening = fit.stiffening_sigma > 0.0;
        let gravity = match fit.gravity_share {
            Some(g) => format!("the pendulum's gravity share {g:.2}"),
            None => "any gravity share".into(),
        };
        let stiffness = match fit.stiffening_at_first_amplitude() {
            Some(rise) => format!(
                "; as k(1 + βθ²), the flexure is {:+.2} % stiffer at {:.2}°",
                100.0 * rise,
                deg(fit.amplitudes.0)
            ),
            None => String::new(),
        };
        flags.push(Flag {
            kind: if stiffening {
                "amplitude_stiffening"
            } else {
                "amplitude_softening"
            },
            message: format!(
                "flagged: amplitude {} (the natural frequency is {:+.3} % higher at {:.2}° than \
                 at {:.2}° beyond what {gravity} gives, {:.1}σ{stiffness}); a linear flexure \
                 cannot fit this trace, and its k_m is an average over the amplitudes",
                if stiffening {
                    "stiffening"
                } else {
                    "softening"
                },
                100.0 * fit.excess_frequency_change(),
                deg(fit.amplitudes.0),
                deg(fit.amplitudes.1),
                fit.stiffening_sigma.abs()
            ),
        });
    }
    if fit.drift_sigma.abs() > FLAG_SIGMA {
        flags.push(Flag {
            kind: "baseline_drift",
            message: format!(
                "flagged: drifting baseline (the oscillation's centre moves {:+.3}° → {:+.3}° \
                 over {:.2} s, {:.1}σ); the model rings down about a fixed rest angle and cannot \
                 fit this trace",
                deg(fit.baseline.0),
                deg(fit.baseline.1),
                fit.span,
                fit.drift_sigma.abs()
            ),
        });
    } else if fit.offset_sigma.abs() > FLAG_SIGMA {
        flags.push(Flag {
            kind: "baseline_offset",
            message: format!(
                "flagged: baseline offset (the oscillation is centred at {:+.3}°, {:.1}σ from \
                 the rest angle 0); the model cannot fit this trace: measure the angle from the \
                 rest position",
                deg(0.5 * (fit.baseline.0 + fit.baseline.1)),
                fit.offset_sigma.abs()
            ),
        });
    }
    flags
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `g(0) = 1` and `g'(0) = 3/π`, the first-order alternation of the module's derivation.
    #[test]
    fn offset_factor_matches_its_expansion() {
        assert!((offset_factor(0.0).unwrap() - 1.0).abs() < 1e-9);
        let h = 1e-4;
        let slope = (offset_factor(h).unwrap() - offset_factor(-h).unwrap()) / (2.0 * h);
        assert!((slope - 3.0 / PI).abs() < 1e-6, "g'(0) = {slope}");
        assert!(offset_factor(0.5).is_none() && offset_factor(f64::NAN).is_none());
    }
}
