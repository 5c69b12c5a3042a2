//! Analysis of one free-decay trace of the pendulum rig (seed Sec. IV.A): the damped
//! frequency ω_d from the mean time between zero crossings, the decay rate σ from a least
//! squares fit to the logarithm of the peak amplitudes, and `ω_n = √(σ² + ω_d²)`,
//! `ζ = σ / ω_n`.
//!
//! Consumes: sample times (s, strictly increasing) and angles (rad, measured from the rest
//! position, i.e. the vertical).
//! Produces: a [`TraceAnalysis`] (with standard errors of ω_d and σ from the scatter about
//! their fits) or a [`TraceError`] saying what is wrong with the trace, with the numbers that
//! decided it: no oscillation above the noise, fewer than about 3 periods of it, an amplitude
//! that grows or does not change. `mech diagnose` screens pendulum traces with this analysis
//! too, so these checks are made in one place.
//!
//! Robustness to measurement noise, which matters most at the end of a trace, where the
//! oscillation has decayed into the noise:
//! - the noise level is estimated from the trace itself (median absolute fourth difference,
//!   insensitive to the smooth oscillation);
//! - zero crossings are detected with hysteresis (the angle must leave a band of ±3 noise
//!   levels on the other side), so noise cannot add crossings;
//! - each crossing time is refined by a least squares line through the samples within
//!   ±0.15 half-periods of it (re-centred twice);
//! - each peak amplitude is the least squares amplitude of a half sine spanning the
//!   half-cycle between two crossings. This is linear in the data, hence unbiased under
//!   additive noise; the vertex of a parabola fitted at the maximum is not (it is biased
//!   upwards by ~var(slope)/curvature, relatively more for small peaks, which made σ, and so
//!   η, 0.4 % low on the synthetic test). The amplitude differs from the true peak by a
//!   factor that is the same for every half-cycle, which the log fit absorbs;
//! - only crossings and peaks while the envelope is above a threshold (20 noise levels, and
//!   at least 10⁻³ of the first peak) are used; the trace is cut at the first half-cycle whose
//!   peak falls below it, or whose length departs from the median half-period by more than
//!   30 % (a lost or spurious crossing).
//!
//! ω_d is `π / T½` with `T½` the slope of a least squares line through the crossing times
//! against their index: the mean time between crossings, with every crossing rather than only
//! the first and the last one contributing. The log-amplitude fit is weighted by `A²` (the
//! inverse variance of `ln A` under additive noise).

use std::f64::consts::PI;
use std::fmt;

/// Tuning of [`analyze_trace`]; the defaults suit camera-tracked decays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceOptions {
    /// Smallest peak amplitude used, in estimated noise levels (default 20).
    pub min_amplitude_over_noise: f64,
    /// Smallest peak amplitude used, relative to the first peak (default 1e-3).
    pub min_amplitude_relative: f64,
}

impl Default for TraceOptions {
    fn default() -> Self {
        TraceOptions {
            min_amplitude_over_noise: 20.0,
            min_amplitude_relative: 1e-3,
        }
    }
}

/// Why a trace cannot be analysed.
#[derive(Debug, Clone, PartialEq)]
pub enum TraceError {
    /// Fewer samples than the analysis needs.
    TooShort {
        /// Number of samples.
        samples: usize,
        /// Minimum number.
        needed: usize,
    },
    /// The time and angle columns differ in length.
    LengthMismatch {
        /// Number of times.
        times: usize,
        /// Number of angles.
        angles: usize,
    },
    /// A time or angle is NaN or infinite (0-based sample index).
    NonFinite {
        /// Sample index.
        index: usize,
        /// `"time"` or `"angle"`.
        what: &'static str,
    },
    /// Time does not increase strictly at this sample (0-based index).
    TimeNotIncreasing {
        /// Sample index.
        index: usize,
    },
    /// No oscillation stands out of the noise: the trace's amplitude is below the amplitude
    /// threshold (pure noise, or a pendulum that was not released).
    NoOscillation {
        /// The trace's amplitude, [`robust_amplitude`] (rad).
        amplitude: f64,
        /// Estimated noise level (rad).
        noise: f64,
        /// The smallest amplitude used, in noise levels.
        needed_over_noise: f64,
    },
    /// Too few usable zero crossings to measure a frequency and a decay: the recording is
    /// shorter than about 3 periods, or the oscillation sinks into the noise before that.
    TooFewCrossings {
        /// Usable crossings found.
        found: usize,
        /// Minimum needed.
        needed: usize,
        /// Period estimated from the crossings (s), if at least two were found.
        period: Option<f64>,
        /// Time span of the recording (s).
        duration: f64,
    },
    /// The amplitude grows (negative damping: a driven rig, or not a free decay).
    Growing {
        /// Fitted decay rate σ (1/s), negative.
        sigma: f64,
        /// First and last peak amplitude used (rad).
        first: f64,
        last: f64,
        /// Time span of those peaks (s).
        span: f64,
    },
    /// The amplitude does not change measurably (less than 1 % over the peaks used).
    NoDecay {
        /// Fitted decay rate σ (1/s).
        sigma: f64,
        /// Time span of the peaks used (s).
        span: f64,
    },
}

impl fmt::Display for TraceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TraceError::TooShort { samples, needed } => write!(
                f,
                "trace too short: {samples} samples, need at least {needed} (several oscillation cycles)"
            ),
            TraceError::LengthMismatch { times, angles } => write!(
                f,
                "{times} times but {angles} angles: the columns must have equal length"
            ),
            TraceError::NonFinite { index, what } => write!(
                f,
                "{what} of sample {} (data row {}) is not a finite number",
                index,
                index + 1
            ),
            TraceError::TimeNotIncreasing { index } => write!(
                f,
                "time does not increase at data row {}: times must be strictly increasing",
                index + 1
            ),
            TraceError::NoOscillation {
                amplitude,
                noise,
                needed_over_noise,
            } => write!(
                f,
                "no oscillation above the noise: amplitude {:.4}° is {:.1} noise levels \
                 (noise {:.4}°), need {needed_over_noise} for a decay; is this a ring-down \
                 trace, and the right column?",
                amplitude.to_degrees(),
                amplitude / noise,
                noise.to_degrees()
            ),
            TraceError::TooFewCrossings {
                found,
                needed,
                period: Some(period),
                duration,
            } => {
                let recorded = duration / period;
                write!(
                    f,
                    "too short: only {found} usable zero crossings (need {needed}, about 3 \
                     periods); period {period:.4} s, "
                )?;
                if recorded < 3.0 {
                    write!(
                        f,
                        "the trace lasts {duration:.4} s = {recorded:.1} periods: record at least \
                         3 periods"
                    )
                } else {
                    write!(
                        f,
                        "the trace lasts {recorded:.1} periods but the oscillation sinks into \
                         the noise after {:.1}: heavily damped, or too noisy",
                        0.5 * found.saturating_sub(1) as f64
                    )
                }
            }
            TraceError::TooFewCrossings {
                found,
                needed,
                period: None,
                duration,
            } => write!(
                f,
                "too short: only {found} usable zero crossings in {duration:.4} s (need {needed}, \
                 about 3 periods): the trace must show several oscillation cycles above the \
                 noise, about the angle 0 (the vertical)"
            ),
            TraceError::Growing {
                sigma,
                first,
                last,
                span,
            } => write!(
                f,
                "the oscillation grows (σ = {sigma:.4} 1/s: amplitude {:.3}° → {:.3}° over \
                 {span:.3} s): negative damping; is this a free decay, with the pendulum \
                 released and not driven?",
                first.to_degrees(),
                last.to_degrees()
            ),
            TraceError::NoDecay { sigma, span } => write!(
                f,
                "the oscillation does not decay (fitted decay rate σ = {sigma:.3e} 1/s, \
                 {:.2} % over {span:.3} s; need 1 %): cannot measure damping; is the trace long \
                 enough, and is the angle from the vertical?",
                100.0 * (sigma * span).abs()
            ),
        }
    }
}

impl std::error::Error for TraceError {}

/// The result of [`analyze_trace`].
#[derive(Debug, Clone, PartialEq)]
pub struct TraceAnalysis {
    /// Number of samples.
    pub samples: usize,
    /// Estimated noise standard deviation of the angle (rad).
    pub noise: f64,
    /// Amplitude threshold below which crossings and peaks were not used (rad).
    pub threshold: f64,
    /// Refined times of the zero crossings used (s).
    pub crossings: Vec<f64>,
    /// Peaks used: `(time s, amplitude rad)`, one per half-cycle between consecutive
    /// crossings, at its midpoint.
    pub peaks: Vec<(f64, f64)>,
    /// Damped angular frequency ω_d (rad/s).
    pub omega_d: f64,
    /// Standard error of ω_d from the scatter of the crossing times about their line
    /// (rad/s).
    pub omega_d_se: f64,
    /// Decay rate σ (1/s).
    pub sigma: f64,
    /// Standard error of σ from the scatter of `ln A` about its line (1/s).
    pub sigma_se: f64,
    /// Natural angular frequency `√(σ² + ω_d²)` (rad/s).
    pub omega_n: f64,
    /// Damping ratio `σ / ω_n`.
    pub zeta: f64,
    /// Weighted R² of the log-amplitude fit.
    pub log_fit_r2: f64,
    /// Mean of `2 J₁(A)/A` over the half-cycles of the ω_d fit, with the fit's weights: the
    /// factor by which a pendulum's finite amplitude A softens its gravity stiffness
    /// (`sin θ` rather than `θ`), to first order `1 − A²/8`.
    pub gravity_softening: f64,
}

/// Minimum number of samples of a trace.
pub const MIN_SAMPLES: usize = 32;
/// Minimum number of usable zero crossings: 6, the five half-cycles that a recording of
/// 3 periods released from rest shows (a decay measured over fewer cycles is mostly noise).
pub const MIN_CROSSINGS: usize = 6;

/// Analyses one decay trace. See the module documentation for the method.
pub fn analyze_trace(
    times: &[f64],
    angles: &[f64],
    options: &TraceOptions,
) -> Result<TraceAnalysis, TraceError> {
    validate(times, angles)?;
    let noise = noise_level(angles);
    let amplitude = robust_amplitude(angles);
    if amplitude < options.min_amplitude_over_noise * noise {
        return Err(TraceError::NoOscillation {
            amplitude,
            noise,
            needed_over_noise: options.min_amplitude_over_noise,
        });
    }
    let duration = times[times.len() - 1] - times[0];
    let rough = rough_crossings(times, angles, 3.0 * noise);
    if rough.len() < MIN_CROSSINGS {
        let period = (rough.len() >= 2)
            .then(|| 2.0 * (rough[rough.len() - 1] - rough[0]) / (rough.len() - 1) as f64);
        return Err(TraceError::TooFewCrossings {
            found: rough.len(),
            needed: MIN_CROSSINGS,
            period,
            duration,
        });
    }
    let mut gaps: Vec<f64> = rough.windows(2).map(|w| w[1] - w[0]).collect();
    let half_period = median(&mut gaps);

    // Refine crossings and locate the peak between each consecutive pair.
    let crossings: Vec<f64> = rough
        .iter()
        .map(|&t0| refine_crossing(times, angles, t0, 0.15 * half_period))
        .collect();
    let peaks: Vec<(f64, f64)> = crossings
        .windows(2)
        .map(|pair| half_cycle_amplitude(times, angles, pair[0], pair[1]))
        .collect();
    let first_peak = peaks.first().map_or(0.0, |p| p.1);
    let threshold =
        (options.min_amplitude_over_noise * noise).max(options.min_amplitude_relative * first_peak);
    let (crossings, peaks) = clean_half_cycles(&crossings, &peaks, threshold, half_period);
    if crossings.len() < MIN_CROSSINGS {
        return Err(TraceError::TooFewCrossings {
            found: crossings.len(),
            needed: MIN_CROSSINGS,
            period: Some(2.0 * half_period),
            duration,
        });
    }

    let (omega_d, omega_d_se) = damped_frequency(&crossings);
    let (sigma, sigma_se, log_fit_r2) = decay_rate(&peaks)?;
    let omega_n = (sigma * sigma + omega_d * omega_d).sqrt();
    Ok(TraceAnalysis {
        samples: times.len(),
        noise,
        threshold,
        gravity_softening: mean_gravity_softening(crossings.len(), &peaks),
        crossings,
        peaks,
        omega_d,
        omega_d_se,
        sigma,
        sigma_se,
        omega_n,
        zeta: sigma / omega_n,
        log_fit_r2,
    })
}

/// Rough crossing times: crossings with hysteresis (a `band` either side of zero), each at
/// the last sign change inside its bracket, interpolated.
fn rough_crossings(times: &[f64], angles: &[f64], band: f64) -> Vec<f64> {
    // (index of the last sample beyond the band on the old side, index of the first sample
    // beyond the band on the new side).
    let brackets = hysteresis_crossings(angles, band);
    brackets
        .iter()
        .map(|&(a, b)| {
            let mut k = b;
            while k > a + 1 && angles[k - 1].signum() == angles[b].signum() {
                k -= 1;
            }
            interpolate_zero(times[k - 1], angles[k - 1], times[k], angles[k])
        })
        .collect()
}

/// The leading half-cycles to use: from the start, while the peak is above `threshold` and
/// the half-cycle's length is within 30 % of `half_period` (else a crossing was lost or
/// spurious). Returns their crossings (one more than the peaks) and peaks; none if the first
/// half-cycle already fails.
fn clean_half_cycles(
    crossings: &[f64],
    peaks: &[(f64, f64)],
    threshold: f64,
    half_period: f64,
) -> (Vec<f64>, Vec<(f64, f64)>) {
    let mut used = 0; // number of half-cycles kept
    for (j, peak) in peaks.iter().enumerate() {
        let length = crossings[j + 1] - crossings[j];
        if peak.1 < threshold || (length / half_period - 1.0).abs() > 0.3 {
            break;
        }
        used = j + 1;
    }
    if used == 0 {
        (Vec::new(), Vec::new())
    } else {
        (crossings[..=used].to_vec(), peaks[..used].to_vec())
    }
}

/// ω_d = π / T½, with T½ the least squares slope of crossing time against its index, and
/// its standard error.
fn damped_frequency(crossings: &[f64]) -> (f64, f64) {
    let index: Vec<f64> = (0..crossings.len()).map(|i| i as f64).collect();
    let ones = vec![1.0; crossings.len()];
    let (slope, intercept, _) = weighted_line(&index, crossings, &ones);
    let slope_se = slope_standard_error(&index, crossings, &ones, slope, intercept);
    (PI / slope, PI / (slope * slope) * slope_se)
}

/// σ, its standard error and the fit's R² from weighted least squares on ln A (weights
/// A²); an error if the amplitude grows, or changes by less than 1 % over the peaks.
fn decay_rate(peaks: &[(f64, f64)]) -> Result<(f64, f64, f64), TraceError> {
    let peak_times: Vec<f64> = peaks.iter().map(|p| p.0).collect();
    let logs: Vec<f64> = peaks.iter().map(|p| p.1.ln()).collect();
    let weights: Vec<f64> = peaks.iter().map(|p| p.1 * p.1).collect();
    let (log_slope, intercept, log_fit_r2) = weighted_line(&peak_times, &logs, &weights);
    let sigma = -log_slope;
    let span = peak_times.last().unwrap_or(&0.0) - peak_times.first().unwrap_or(&0.0);
    // 1 % of change over the fit is the least the log fit can tell from a constant.
    if sigma * span <= -0.01 {
        return Err(TraceError::Growing {
            sigma,
            first: peaks.first().map_or(f64::NAN, |p| p.1),
            last: peaks.last().map_or(f64::NAN, |p| p.1),
            span,
        });
    }
    if sigma.is_nan() || sigma * span < 0.01 {
        return Err(TraceError::NoDecay { sigma, span });
    }
    let sigma_se = slope_standard_error(&peak_times, &logs, &weights, log_slope, intercept);
    Ok((sigma, sigma_se, log_fit_r2))
}

/// The standard error of a weighted least squares slope with the weights known only up to a
/// factor: the residual scatter sets the scale, `se² = Σw r² / ((n − 2) Σw (x − x̄)²)`.
/// Zero for two points or fewer (no scatter to measure).
fn slope_standard_error(xs: &[f64], ys: &[f64], ws: &[f64], slope: f64, intercept: f64) -> f64 {
    let n = xs.len();
    if n <= 2 {
        return 0.0;
    }
    let sw: f64 = ws.iter().sum();
    let mx = xs.iter().zip(ws).map(|(x, w)| x * w).sum::<f64>() / sw;
    let (mut residual, mut sxx) = (0.0, 0.0);
    for ((&x, &y), &w) in xs.iter().zip(ys).zip(ws) {
        residual += w * (y - slope * x - intercept).powi(2);
        sxx += w * (x - mx) * (x - mx);
    }
    (residual / ((n - 2) as f64 * sxx)).sqrt()
}

/// The amplitude of a trace robust to a few spikes: the 5th largest `|θ|` (the largest for
/// shorter traces). A ring-down's first peak spans many samples; a glitch spans one or two.
pub fn robust_amplitude(values: &[f64]) -> f64 {
    let mut magnitudes: Vec<f64> = values.iter().map(|v| v.abs()).collect();
    magnitudes.sort_by(|a, b| b.total_cmp(a));
    match magnitudes.len() {
        0 => 0.0,
        n => magnitudes[4.min(n - 1)],
    }
}

/// [`bessel_softening`] of the peaks averaged with the weights the ω_d fit gives the
/// half-cycles between `crossing_count` crossings: `j (N − j)`, j = 1..N−1.
fn mean_gravity_softening(crossing_count: usize, peaks: &[(f64, f64)]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (j, peak) in peaks.iter().enumerate() {
        let c = ((j + 1) * (crossing_count - j - 1)) as f64;
        num += c * bessel_softening(peak.1);
        den += c;
    }
    if den > 0.0 {
        num / den
    } else {
        1.0
    }
}

fn validate(times: &[f64], angles: &[f64]) -> Result<(), TraceError> {
    if times.len() != angles.len() {
        return Err(TraceError::LengthMismatch {
            times: times.len(),
            angles: angles.len(),
        });
    }
    if times.len() < MIN_SAMPLES {
        return Err(TraceError::TooShort {
            samples: times.len(),
            needed: MIN_SAMPLES,
        });
    }
    for (index, (&t, &a)) in times.iter().zip(angles).enumerate() {
        if !t.is_finite() {
            return Err(TraceError::NonFinite {
                index,
                what: "time",
            });
        }
        if !a.is_finite() {
            return Err(TraceError::NonFinite {
                index,
                what: "angle",
            });
        }
        if index > 0 && t <= times[index - 1] {
            return Err(TraceError::TimeNotIncreasing { index });
        }
    }
    Ok(())
}

/// `2 J₁(A) / A`, the first-harmonic stiffness of `sin θ` at amplitude A (series to A⁸;
/// relative error below 1e-9 for A < 0.6 rad).
pub fn bessel_softening(amplitude: f64) -> f64 {
    let a2 = amplitude * amplitude;
    1.0 - a2 / 8.0 + a2 * a2 / 192.0 - a2.powi(3) / 9216.0 + a2.powi(4) / 737_280.0
}

/// Noise standard deviation from the median absolute fourth difference
/// (`Var(Δ⁴ε) = 70 σ²` for white noise ε; `1.4826·MAD` estimates σ of a Gaussian).
pub fn noise_level(values: &[f64]) -> f64 {
    let mut d4: Vec<f64> = values
        .windows(5)
        .map(|w| (w[0] - 4.0 * w[1] + 6.0 * w[2] - 4.0 * w[3] + w[4]).abs())
        .collect();
    if d4.is_empty() {
        return 0.0;
    }
    1.4826 * median(&mut d4) / 70f64.sqrt()
}

/// Crossings of zero with hysteresis: the signal must go from beyond `+band` to beyond
/// `−band` (or back). Returns `(a, b)`: the last sample beyond the band on the old side and
/// the first beyond it on the new side.
fn hysteresis_crossings(values: &[f64], band: f64) -> Vec<(usize, usize)> {
    let band = band.max(f64::MIN_POSITIVE);
    let mut out = Vec::new();
    let mut state = 0.0_f64; // sign of the side we are on, 0 before the first excursion
    let mut last_beyond = 0usize;
    for (k, &v) in values.iter().enumerate() {
        if v.abs() <= band {
            continue;
        }
        let side = v.signum();
        if state == 0.0 || side == state {
            state = side;
            last_beyond = k;
        } else {
            out.push((last_beyond, k));
            state = side;
            last_beyond = k;
        }
    }
    out
}

fn interpolate_zero(t0: f64, v0: f64, t1: f64, v1: f64) -> f64 {
    if v1 == v0 {
        0.5 * (t0 + t1)
    } else {
        t0 + (t1 - t0) * (-v0) / (v1 - v0)
    }
}

/// Index range of the samples with `|t − center| ≤ half_width`.
fn window(times: &[f64], center: f64, half_width: f64) -> (usize, usize) {
    let lo = times.partition_point(|&t| t < center - half_width);
    let hi = times.partition_point(|&t| t <= center + half_width);
    (lo, hi)
}

/// Refines a zero crossing near `t0` by a least squares line through the samples within
/// `half_width`, re-centred twice; falls back to `t0` if too few samples or a flat fit.
fn refine_crossing(times: &[f64], angles: &[f64], t0: f64, half_width: f64) -> f64 {
    let mut center = t0;
    for _ in 0..3 {
        let (lo, hi) = window(times, center, half_width);
        if hi < lo + 3 {
            return center;
        }
        let ts: Vec<f64> = times[lo..hi].iter().map(|t| t - center).collect();
        let ones = vec![1.0; ts.len()];
        let (slope, intercept, _) = weighted_line(&ts, &angles[lo..hi], &ones);
        if slope == 0.0 || !slope.is_finite() {
            return center;
        }
        let shift = -intercept / slope;
        if shift.abs() > half_width {
            return center;
        }
        center += shift;
    }
    center
}

/// The amplitude of the half-cycle between crossings `t_a` and `t_b`: the least squares
/// amplitude `A` of `A·sin(π (t − t_a)/(t_b − t_a))` over the samples strictly between them
/// (linear in the data, so additive noise does not bias it), with the half-cycle's midpoint
/// as its time. Returns `(time, |A|)`.
fn half_cycle_amplitude(times: &[f64], angles: &[f64], t_a: f64, t_b: f64) -> (f64, f64) {
    let (lo, hi) = window(times, 0.5 * (t_a + t_b), 0.5 * (t_b - t_a));
    let (mut sxs, mut sss) = (0.0, 0.0);
    for k in lo..hi {
        let shape = (PI * (times[k] - t_a) / (t_b - t_a)).sin();
        sxs += angles[k] * shape;
        sss += shape * shape;
    }
    let amplitude = if sss > 0.0 { (sxs / sss).abs() } else { 0.0 };
    (0.5 * (t_a + t_b), amplitude)
}

/// Weighted least squares line `y = slope·x + intercept`; returns `(slope, intercept, R²)`
/// with the weighted R².
pub fn weighted_line(xs: &[f64], ys: &[f64], ws: &[f64]) -> (f64, f64, f64) {
    let sw: f64 = ws.iter().sum();
    let mx = xs.iter().zip(ws).map(|(x, w)| x * w).sum::<f64>() / sw;
    let my = ys.iter().zip(ws).map(|(y, w)| y * w).sum::<f64>() / sw;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for ((&x, &y), &w) in xs.iter().zip(ys).zip(ws) {
        sxx += w * (x - mx) * (x - mx);
        sxy += w * (x - mx) * (y - my);
        syy += w * (y - my) * (y - my);
    }
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let r2 = if syy > 0.0 {
        1.0 - (syy - slope * sxy) / syy
    } else {
        1.0
    };
    (slope, intercept, r2)
}

/// Median (sorts `values`); NaN for an empty slice.
fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(|a, b| a.total_cmp(b));
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}
