//! Frequency responses: from a linearization (exact, complex stiffness allowed) or from a
//! simulated chirp (swept-sine estimate), and the resonances they show.
//!
//! Consumes: a [`Linearization`], sampled input/output records, or a model to drive with a
//! [`ChirpSweep`]. Produces: [`Point`]s (frequency, complex gain) and [`Resonance`]s (peak
//! frequency, gain, quality factor).
//!
//! Resonances come two ways. [`resonances`] reads them off samples alone (measured data, a
//! chirp estimate): the peak and the −3 dB points are interpolated between samples, so a
//! sharp peak is cut short and Q comes out low unless the grid is much finer than the
//! bandwidth (HAMR-VI swing: 34.8 at 300 points, 47.1 converged). [`refined_resonances`]
//! takes `|H|` as a function it can evaluate at any frequency (the linear model:
//! [`linear_magnitude`]) and, from the peaks the grid shows, solves for the maximum and for
//! both half-power crossings on the continuous response, so Q is exact to the solver's
//! tolerance on any grid that shows the peak, coarse or fine. The 1-D searches are Brent's (argmin's
//! `BrentOpt` and `BrentRoot`: maintained, and no rand with default features off).

use argmin::core::{CostFunction, Executor, IterState, Solver, State, TerminationReason};
use argmin::solver::brent::{BrentOpt, BrentRoot};
use mech_runtime::nalgebra::Complex;
use mech_runtime::{
    FlexureDamping, Linearization, Method, Model, RuntimeError, Signal, SimOptions,
};

/// One transfer function an experiment file names: a model input driven, a model output
/// read, and the channel's name (its data columns and output files are suffixed with it).
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Channel {
    pub name: String,
    pub input: String,
    pub output: String,
}

/// How the flexures' losses enter a frequency response, as an experiment file
/// (`damping = "viscous"`) or `mech bode --damping` names it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Damping {
    // Plain comments: `mech bode --help` says what each is in the option's own text.
    // The complex stiffness `k(1 + iη)`, exact at every frequency.
    #[default]
    Hysteretic,
    // The viscous dampers `b = kη/ω_ref` of the time-domain model.
    Viscous,
}

impl From<Damping> for FlexureDamping {
    fn from(damping: Damping) -> FlexureDamping {
        match damping {
            Damping::Hysteretic => FlexureDamping::Hysteretic,
            Damping::Viscous => FlexureDamping::Viscous,
        }
    }
}

/// One point of a frequency response.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    pub frequency_hz: f64,
    pub gain: Complex<f64>,
}

impl Point {
    pub fn magnitude_db(&self) -> f64 {
        20.0 * self.gain.norm().log10()
    }
    pub fn phase_deg(&self) -> f64 {
        self.gain.arg().to_degrees()
    }
}

/// `count` frequencies log-spaced from `from` to `to` (Hz), both included.
pub fn log_space(from: f64, to: f64, count: usize) -> Vec<f64> {
    let count = count.max(2);
    let (a, b) = (from.ln(), to.ln());
    (0..count)
        .map(|k| (a + (b - a) * k as f64 / (count - 1) as f64).exp())
        .collect()
}

/// The linear model's response from input `input` to output `output` at `frequencies` (Hz),
/// with the flexures' losses as chosen by `damping`.
pub fn linear_response(
    linear: &Linearization,
    input: usize,
    output: usize,
    frequencies: &[f64],
    damping: FlexureDamping,
) -> Option<Vec<Point>> {
    frequencies
        .iter()
        .map(|&f| {
            let gain =
                linear.frequency_response(input, output, std::f64::consts::TAU * f, damping)?;
            Some(Point {
                frequency_hz: f,
                gain,
            })
        })
        .collect()
}

/// `|H(f)|` of the linear model from `input` to `output`, for [`refined_resonances`]: NaN
/// where the model is singular (reported there as [`RefineError::NotFinite`]).
pub fn linear_magnitude(
    linear: &Linearization,
    input: usize,
    output: usize,
    damping: FlexureDamping,
) -> impl Fn(f64) -> f64 + '_ {
    move |f| {
        linear
            .frequency_response(input, output, std::f64::consts::TAU * f, damping)
            .map_or(f64::NAN, |gain| gain.norm())
    }
}

/// A resonance: a local maximum of `|H|` with the quality factor `Q = f₀ / Δf` of its
/// half-power (−3 dB) bandwidth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resonance {
    pub frequency_hz: f64,
    pub peak_magnitude: f64,
    /// `None` when the −3 dB points are not both inside the sweep.
    pub quality_factor: Option<f64>,
}

/// Why [`refined_resonances`] could not refine a response.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RefineError {
    /// The frequencies are not positive, finite and strictly increasing.
    #[error(
        "the sweep's frequencies must be positive, finite and increasing (at {frequency_hz} Hz)"
    )]
    Grid { frequency_hz: f64 },
    /// `|H|` was not a finite number (a singular linear model).
    #[error("|H| is not finite at {frequency_hz} Hz (is the linear model singular there?)")]
    NotFinite { frequency_hz: f64 },
    /// A 1-D search stopped without converging (argmin's message).
    #[error("the {search} near {frequency_hz} Hz did not converge: {message}")]
    Search {
        search: &'static str,
        frequency_hz: f64,
        message: String,
    },
}

/// The indices of the samples that are local maxima of `magnitudes` (NaN is never one, nor
/// next to one).
fn sampled_peaks(magnitudes: &[f64]) -> impl Iterator<Item = usize> + '_ {
    (1..magnitudes.len().saturating_sub(1))
        .filter(move |&k| magnitudes[k] > magnitudes[k - 1] && magnitudes[k] >= magnitudes[k + 1])
}

/// The resonances of a sampled response alone, strongest first: for measured data or a chirp
/// estimate, where there is no continuous `|H|` to refine on (else use
/// [`refined_resonances`]). The peak is the vertex of the parabola through its three samples
/// (in log-frequency and dB) and the −3 dB points are interpolated between samples, so the
/// result is limited by the grid: a peak a few samples wide is cut short and its Q is low.
pub fn resonances(points: &[Point]) -> Vec<Resonance> {
    let magnitudes: Vec<f64> = points.iter().map(|p| p.gain.norm()).collect();
    let db: Vec<f64> = points.iter().map(Point::magnitude_db).collect();
    let log_f: Vec<f64> = points.iter().map(|p| p.frequency_hz.ln()).collect();
    let mut found = Vec::new();
    for k in sampled_peaks(&magnitudes) {
        // Vertex of the parabola through (log f, dB) at k−1, k, k+1.
        let (x0, x1, x2) = (log_f[k - 1], log_f[k], log_f[k + 1]);
        let (y0, y1, y2) = (db[k - 1], db[k], db[k + 1]);
        let denominator = (x0 - x1) * (x0 - x2) * (x1 - x2);
        let a = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / denominator;
        let b = (x2 * x2 * (y0 - y1) + x1 * x1 * (y2 - y0) + x0 * x0 * (y1 - y2)) / denominator;
        let (peak_log_f, peak_db) = if a < 0.0 {
            let x = -b / (2.0 * a);
            (
                x,
                y1 + a * (x - x1) * (x - x1) + (2.0 * a * x1 + b) * (x - x1),
            )
        } else {
            (x1, y1)
        };
        let half_power = peak_db - 10.0 * 2.0_f64.log10();
        let crossing = |range: &mut dyn Iterator<Item = usize>| -> Option<f64> {
            for j in range {
                let (a, b) = (j, if j > k { j - 1 } else { j + 1 });
                if db[a] <= half_power && db[b] > half_power {
                    let fraction = (half_power - db[a]) / (db[b] - db[a]);
                    return Some((log_f[a] + fraction * (log_f[b] - log_f[a])).exp());
                }
            }
            None
        };
        let below = crossing(&mut (0..k).rev());
        let above = crossing(&mut (k + 1..points.len()));
        let frequency_hz = peak_log_f.exp();
        found.push(Resonance {
            frequency_hz,
            peak_magnitude: 10f64.powf(peak_db / 20.0),
            quality_factor: quality_factor(frequency_hz, below, above),
        });
    }
    found.sort_by(|a, b| b.peak_magnitude.total_cmp(&a.peak_magnitude));
    found
}

fn quality_factor(peak_hz: f64, below: Option<f64>, above: Option<f64>) -> Option<f64> {
    match (below, above) {
        (Some(low), Some(high)) if high > low => Some(peak_hz / (high - low)),
        _ => None,
    }
}

/// The resonances of a response known at every frequency, strongest first: `magnitude(f)`
/// is `|H|` at `f` Hz (e.g. [`linear_magnitude`]), sampled at `frequencies` (increasing) to
/// find the peaks. Each sampled peak is refined on the continuous `|H|`: its maximum between
/// the neighbouring samples (Brent's minimizer in log-frequency), then each half-power point
/// (the first crossing of `peak/√2` going out from the peak, bracketed by a march and solved
/// by Brent's root finder). The grid only has to show the peak (a sample above both its
/// neighbours); f_r and Q are then exact to ~1e-9 relative (the closed-form tests).
/// `quality_factor` is `None` when a crossing is outside the sweep, as for [`resonances`].
pub fn refined_resonances(
    frequencies: &[f64],
    magnitude: impl Fn(f64) -> f64,
) -> Result<Vec<Resonance>, RefineError> {
    for (k, &f) in frequencies.iter().enumerate() {
        if !(f.is_finite() && f > 0.0) || (k > 0 && f <= frequencies[k - 1]) {
            return Err(RefineError::Grid { frequency_hz: f });
        }
    }
    let search = LogFrequency {
        magnitude: &magnitude,
        scale: 1.0,
        level: 0.0,
    };
    let sampled = frequencies
        .iter()
        .map(|&f| search.at(f.ln()))
        .collect::<Result<Vec<f64>, RefineError>>()?;
    let log_f: Vec<f64> = frequencies.iter().map(|f| f.ln()).collect();
    let mut found = Vec::new();
    for k in sampled_peaks(&sampled) {
        let near_hz = frequencies[k];
        // Maximum of |H| (scaled by the sample so the cost is of order 1) between the
        // neighbouring samples, which are both below the middle one.
        let peak_search = LogFrequency {
            scale: -1.0 / sampled[k],
            ..search
        };
        let solver =
            BrentOpt::new(log_f[k - 1], log_f[k + 1]).set_tolerance(f64::EPSILON.sqrt(), 1e-12);
        let x = peak_search.solve("peak search", near_hz, solver)?;
        // Brent returns its best point; the middle sample is a fallback, never better.
        let (mut peak_x, mut peak) = (x, search.at(x)?);
        if sampled[k] > peak {
            (peak_x, peak) = (log_f[k], sampled[k]);
        }
        let level = peak / std::f64::consts::SQRT_2;
        // The march starts at a quarter of the sample spacing around the peak.
        let step = (log_f[k + 1] - log_f[k - 1]) / 8.0;
        let below = search.half_power(peak_x, level, step, log_f[0], near_hz)?;
        let above = search.half_power(peak_x, level, step, log_f[log_f.len() - 1], near_hz)?;
        let frequency_hz = peak_x.exp();
        found.push(Resonance {
            frequency_hz,
            peak_magnitude: peak,
            quality_factor: quality_factor(frequency_hz, below, above),
        });
    }
    found.sort_by(|a, b| b.peak_magnitude.total_cmp(&a.peak_magnitude));
    Ok(found)
}

/// `scale·(|H(e^x)| − level)` as an argmin cost of `x = ln f`.
struct LogFrequency<'a, M> {
    magnitude: &'a M,
    scale: f64,
    level: f64,
}

// Not derived: that would ask `M: Clone`, and only the reference is copied.
impl<M> Clone for LogFrequency<'_, M> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<M> Copy for LogFrequency<'_, M> {}

impl<M: Fn(f64) -> f64> LogFrequency<'_, M> {
    fn at(&self, x: f64) -> Result<f64, RefineError> {
        let frequency_hz = x.exp();
        let value = (self.magnitude)(frequency_hz);
        if value.is_finite() {
            Ok(value)
        } else {
            Err(RefineError::NotFinite { frequency_hz })
        }
    }

    /// Runs one Brent search on this cost and returns its best `x`.
    fn solve<S>(&self, search: &'static str, near_hz: f64, solver: S) -> Result<f64, RefineError>
    where
        S: Solver<Self, IterState<f64, (), (), (), (), f64>>,
    {
        let failed = |message: String| RefineError::Search {
            search,
            frequency_hz: near_hz,
            message,
        };
        let result = Executor::new(*self, solver)
            .configure(|state| state.max_iters(200))
            .run()
            // argmin's errors are untyped: ours (a non-finite |H|) come back out as they went in.
            .map_err(|error| match error.downcast::<RefineError>() {
                Ok(ours) => ours,
                Err(other) => failed(other.to_string()),
            })?;
        let state = result.state();
        match (state.get_termination_reason(), state.get_best_param()) {
            (Some(TerminationReason::SolverConverged), Some(&x)) => Ok(x),
            (reason, _) => Err(failed(
                reason.map_or("no result".into(), |r| r.text().to_string()),
            )),
        }
    }

    /// The first crossing of `level` by `|H|` going from the peak at `peak_x` towards `limit`
    /// (log-frequency), `None` if `|H|` stays above it up to `limit`. Marched in steps of
    /// `step`, growing to a quarter of the distance covered (near the peak the march cannot
    /// step over a stretch below the level wider than `step`; far from it, it stays short),
    /// then solved between the last point above the level and the first at or below it.
    fn half_power(
        &self,
        peak_x: f64,
        level: f64,
        step: f64,
        limit: f64,
        near_hz: f64,
    ) -> Result<Option<f64>, RefineError> {
        let direction = (limit - peak_x).signum();
        let mut inside = peak_x;
        loop {
            let stride = step.max((inside - peak_x).abs() / 4.0);
            let next = if direction > 0.0 {
                (inside + stride).min(limit)
            } else {
                (inside - stride).max(limit)
            };
            if self.at(next)? <= level {
                let crossing = LogFrequency {
                    scale: 1.0 / level,
                    level,
                    ..*self
                };
                let solver = BrentRoot::new(inside, next, 4.0 * f64::EPSILON);
                return Ok(Some(
                    crossing.solve("half-power search", near_hz, solver)?.exp(),
                ));
            }
            if next == limit {
                return Ok(None);
            }
            inside = next;
        }
    }
}

impl<M: Fn(f64) -> f64> CostFunction for LogFrequency<'_, M> {
    type Param = f64;
    type Output = f64;

    fn cost(&self, x: &f64) -> Result<f64, argmin::core::Error> {
        let value = self.at(*x)?;
        Ok(self.scale * (value - self.level))
    }
}

/// Swept-sine estimate from a chirp record: `H(f) = Y(f) / U(f)` with single-bin Fourier
/// transforms of the whole input and output records (`single_bin`), evaluated at each
/// analysis frequency; both means are removed. No taper: in a swept sine each frequency lives
/// at one time of the record, and a window over the whole record would suppress the sweep's
/// start and end, where its lowest and highest frequencies are.
pub fn chirp_estimate(
    times: &[f64],
    input: &[f64],
    output: &[f64],
    frequencies: &[f64],
) -> Vec<Point> {
    frequencies
        .iter()
        .map(|&f| Point {
            frequency_hz: f,
            gain: single_bin(times, output, f) / single_bin(times, input, f),
        })
        .collect()
}

/// The Fourier transform of the record `values(times)` at `frequency_hz` alone (trapezoid
/// rule, rectangular window, the record's mean removed).
fn single_bin(times: &[f64], values: &[f64], frequency_hz: f64) -> Complex<f64> {
    let omega = std::f64::consts::TAU * frequency_hz;
    let mean = values.iter().sum::<f64>() / values.len().max(1) as f64;
    let term = |j: usize| Complex::from_polar(values[j] - mean, -omega * times[j]);
    (1..times.len().min(values.len()))
        .map(|k| (term(k) + term(k - 1)) * (0.5 * (times[k] - times[k - 1])))
        .sum()
}

/// The fraction of a linear chirp's in-band input spectrum below which its estimate is not
/// trusted: half (−6 dB). A sweep of amplitude `A` at rate `r` (Hz/s) has
/// `|U(f)| ≈ A / (2√r)` inside its band (stationary phase), with a Fresnel ripple of about
/// ±2 dB that falls to exactly half at its first and last frequencies. Below half the sweep has
/// hardly excited `f`, and `Y/U` divides what the output holds there anyway (the start-up
/// transient, the ringing cut off at the record's end) by almost nothing. A single simulated
/// record has no coherence to compute (one record, no noise, `γ² = 1` by construction): the
/// input's power is the measure of trust it has.
pub const CHIRP_INPUT_FLOOR: f64 = 0.5;

/// Blanks (NaN: not drawn, not searched for resonances) the points of a chirp estimate
/// whose input spectrum `|U(f)|` over `times` is below [`CHIRP_INPUT_FLOOR`] of the
/// in-band level of a linear sweep of `amplitude` at `rate_hz_per_s`. Returns how many.
pub fn mask_weak_input(
    points: &mut [Point],
    times: &[f64],
    input: &[f64],
    amplitude: f64,
    rate_hz_per_s: f64,
) -> usize {
    let floor = CHIRP_INPUT_FLOOR * amplitude / (2.0 * rate_hz_per_s.sqrt());
    let mut masked = 0;
    for point in points {
        if single_bin(times, input, point.frequency_hz).norm() < floor {
            point.gain = Complex::new(f64::NAN, f64::NAN);
            masked += 1;
        }
    }
    masked
}

/// Phases in degrees along increasing frequency, unwrapped: each finite sample moved by the
/// multiple of 360° that brings it within 180° of the finite sample before it, and the first
/// finite one within 180° of `start` (another curve's phase there, so that curves drawn
/// together share a branch; the sample itself for none). NaN stays NaN, a gap bridged.
pub fn unwrap_phase_deg(phases: &[f64], start: f64) -> Vec<f64> {
    let mut previous = start;
    phases
        .iter()
        .map(|&phase| {
            if !phase.is_finite() {
                return phase;
            }
            let reference = if previous.is_finite() {
                previous
            } else {
                phase
            };
            let unwrapped = phase - 360.0 * ((phase - reference) / 360.0).round();
            previous = unwrapped;
            unwrapped
        })
        .collect()
}

/// The phases (degrees) of responses on one frequency grid, each unwrapped
/// ([`unwrap_phase_deg`]), the first from its own first sample and every other one on the
/// branch of the first at its own first finite sample: drawn together, the curves do not sit
/// 360° apart.
pub fn unwrapped_phases(responses: &[&[Point]]) -> Vec<Vec<f64>> {
    let mut phases: Vec<Vec<f64>> = Vec::new();
    for response in responses {
        let raw: Vec<f64> = response.iter().map(Point::phase_deg).collect();
        let first = raw.iter().position(|p| p.is_finite());
        let start = match (phases.first(), first) {
            (Some(reference), Some(k)) => reference.get(k).copied().unwrap_or(raw[k]),
            (None, Some(k)) => raw[k],
            (_, None) => f64::NAN,
        };
        phases.push(unwrap_phase_deg(&raw, start));
    }
    phases
}

/// A linear chirp on one input, and the output it is read from.
#[derive(Clone, Copy, Debug)]
pub struct ChirpSweep {
    pub input: usize,
    pub output: usize,
    /// In the input's SI unit.
    pub amplitude: f64,
    pub from_hz: f64,
    pub to_hz: f64,
    /// Seconds from `from_hz` to `to_hz`.
    pub duration: f64,
    /// Relative tolerance of the DOPRI5 simulation (absolute: 1e-12).
    pub rtol: f64,
    /// Budget of integration steps (`SimOptions::max_steps`).
    pub max_steps: usize,
}

/// A simulated chirp ([`simulate_chirp`]): the record of the driven input and the output, and
/// the sweep's amplitude and rate (what [`mask_weak_input`] needs).
#[derive(Clone, Debug, PartialEq)]
pub struct ChirpRecord {
    pub times: Vec<f64>,
    pub input: Vec<f64>,
    pub output: Vec<f64>,
    amplitude: f64,
    rate_hz_per_s: f64,
}

impl ChirpRecord {
    /// The swept-sine estimate at `frequencies` ([`chirp_estimate`]), blanked where the sweep
    /// did not excite `f` ([`mask_weak_input`]).
    pub fn estimate(&self, frequencies: &[f64]) -> Vec<Point> {
        let mut estimate = chirp_estimate(&self.times, &self.input, &self.output, frequencies);
        mask_weak_input(
            &mut estimate,
            &self.times,
            &self.input,
            self.amplitude,
            self.rate_hz_per_s,
        );
        estimate
    }

    /// The resonances of `estimate` (this record's, possibly blanked further) refined on the
    /// continuous estimate `|Y(f)/U(f)|`, which the record gives at any frequency
    /// ([`refined_resonances`] over the longest run of `estimate`'s finite points, the band
    /// the sweep excited): the grid only has to show each peak, so f_r and Q do not depend
    /// on it. They remain the estimate's: its error (sweep rate, record length) is theirs.
    pub fn resonances(&self, estimate: &[Point]) -> Result<Vec<Resonance>, RefineError> {
        let mut best = 0..0;
        let mut run_start = 0;
        for (k, point) in estimate.iter().enumerate() {
            if !point.gain.norm().is_finite() {
                run_start = k + 1;
            } else if k + 1 - run_start > best.len() {
                best = run_start..k + 1;
            }
        }
        let frequencies: Vec<f64> = estimate[best].iter().map(|p| p.frequency_hz).collect();
        refined_resonances(&frequencies, |f| {
            (single_bin(&self.times, &self.output, f) / single_bin(&self.times, &self.input, f))
                .norm()
        })
    }
}

/// How long the record runs on after the sweep, as a fraction of the sweep's duration.
pub const CHIRP_RING_DOWN: f64 = 0.25;

/// Simulates the model from `(q, u)` under `sweep` (the other inputs as `signals` give them;
/// the driven input's value at t = 0 is the chirp's offset), then for
/// [`CHIRP_RING_DOWN`] of its duration more with the input back at the offset. `Y = H U` holds
/// for the transforms of whole records only when the output's record holds the whole
/// response: cut at the sweep's end, it loses the free decay of what the sweep left ringing,
/// which near a resonance is a tenth of `Y` (HAMR-VI's swing Q read 17 % high). Samples
/// and steps are at most `1/(20 f_max)` apart, so the highest frequency is resolved by 20
/// points per period.
pub fn simulate_chirp(
    model: &dyn Model,
    q: &[f64],
    u: &[f64],
    signals: &[Signal],
    sweep: &ChirpSweep,
) -> Result<ChirpRecord, RuntimeError> {
    let mut signals = signals.to_vec();
    let offset = signals[sweep.input].value(0.0);
    signals[sweep.input] = Signal::Chirp {
        amplitude: sweep.amplitude,
        f0_hz: sweep.from_hz,
        f1_hz: sweep.to_hz,
        duration: sweep.duration,
        offset,
    };
    let sample = 1.0 / (20.0 * sweep.to_hz);
    let options = SimOptions {
        t_end: sweep.duration,
        output_interval: sample,
        method: Method::Dopri5 {
            rtol: sweep.rtol,
            atol: 1e-12,
            h_max: sample,
        },
        max_steps: sweep.max_steps,
        ..SimOptions::default()
    };
    let mut run = mech_runtime::simulate(model, q, u, &signals, &options, &mut |_| {})?;
    let (last_q, last_u) = (run.q.last().unwrap().clone(), run.u.last().unwrap().clone());
    signals[sweep.input] = Signal::Constant(offset);
    let ring_down = mech_runtime::simulate(
        model,
        &last_q,
        &last_u,
        &signals,
        &SimOptions {
            t_start: sweep.duration,
            t_end: sweep.duration * (1.0 + CHIRP_RING_DOWN),
            ..options
        },
        &mut |_| {},
    )?;
    // The ring-down's first sample is the sweep's last (at the sweep's end): skipped.
    run.times.extend_from_slice(&ring_down.times[1..]);
    run.inputs.extend_from_slice(&ring_down.inputs[1..]);
    run.outputs.extend_from_slice(&ring_down.outputs[1..]);
    Ok(ChirpRecord {
        input: run.inputs.iter().map(|x| x[sweep.input]).collect(),
        output: run.outputs.iter().map(|x| x[sweep.output]).collect(),
        times: run.times,
        amplitude: sweep.amplitude,
        rate_hz_per_s: (sweep.to_hz - sweep.from_hz).abs() / sweep.duration,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A single-degree-of-freedom oscillator: H = 1/(k − mω² + icω).
    fn oscillator(f: f64) -> Point {
        let (m, k, c) = (1.0, (std::f64::consts::TAU * 10.0_f64).powi(2), 2.0);
        let omega = std::f64::consts::TAU * f;
        Point {
            frequency_hz: f,
            gain: Complex::new(1.0, 0.0) / Complex::new(k - m * omega * omega, c * omega),
        }
    }

    #[test]
    fn resonance_and_quality_factor_of_a_single_oscillator() {
        let points: Vec<Point> = log_space(1.0, 100.0, 2000)
            .into_iter()
            .map(oscillator)
            .collect();
        let found = resonances(&points);
        let (omega_n, zeta) = (
            std::f64::consts::TAU * 10.0,
            2.0 / (2.0 * std::f64::consts::TAU * 10.0),
        );
        // Peak of |H| at ω_n √(1 − 2ζ²); Q of the half-power bandwidth ≈ 1/(2ζ) for light damping.
        let peak = omega_n * (1.0 - 2.0 * zeta * zeta).sqrt() / std::f64::consts::TAU;
        assert!(
            (found[0].frequency_hz - peak).abs() < 1e-4 * peak,
            "{found:?}"
        );
        let q = found[0].quality_factor.unwrap();
        assert!((q - 1.0 / (2.0 * zeta)).abs() < 0.02 * q, "Q = {q}");
    }

    fn magnitude(f: f64) -> f64 {
        oscillator(f).gain.norm()
    }

    /// A −3 dB point outside the sweep gives no Q (as on the grid), not a wrong one; the peak
    /// is still refined. The sweep stops between the peak (9.9975 Hz) and the upper crossing
    /// (~10.16 Hz).
    #[test]
    fn refined_q_needs_both_half_power_points_inside_the_sweep() {
        let found = refined_resonances(&log_space(5.0, 10.1, 50), magnitude).unwrap();
        assert_eq!(found.len(), 1);
        assert!((found[0].frequency_hz / 9.997466649515706 - 1.0).abs() < 1e-7);
        assert_eq!(found[0].quality_factor, None);
        assert!(resonances(
            &log_space(5.0, 10.1, 50)
                .into_iter()
                .map(oscillator)
                .collect::<Vec<_>>()
        )[0]
        .quality_factor
        .is_none());
    }

    /// A linear phase that leaves (−180°, 180°] four times comes back as the straight line,
    /// across a NaN gap, and on the branch of `start`.
    #[test]
    fn unwrap_restores_a_linear_phase() {
        let line: Vec<f64> = (0..60).map(|k| 170.0 - 13.0 * k as f64).collect();
        let mut wrapped: Vec<f64> = line
            .iter()
            .map(|p| p - 360.0 * ((p - 1e-9) / 360.0).round())
            .collect();
        assert!(wrapped.iter().all(|p| (-180.0..=180.0).contains(p)));
        wrapped[20] = f64::NAN;
        let unwrapped = unwrap_phase_deg(&wrapped, wrapped[0]);
        for (k, (a, b)) in line.iter().zip(&unwrapped).enumerate() {
            if k == 20 {
                assert!(b.is_nan());
            } else {
                assert!((a - b).abs() < 1e-9, "sample {k}: {b} for {a}");
            }
        }
        // A phase near ±180° flipping sign (the comb) is one branch; `start` picks which.
        let comb = [179.0, -179.5, 179.8, -178.0];
        assert_eq!(
            unwrap_phase_deg(&comb, 180.0),
            vec![179.0, 180.5, 179.8, 182.0]
        );
        assert_eq!(
            unwrap_phase_deg(&comb, -180.0),
            vec![-181.0, -179.5, -180.2, -178.0]
        );
    }

    /// Outside a 10–50 Hz sweep (and at its Fresnel edges) the estimate is blanked; inside it
    /// is kept, and there `H` of the identity is 1.
    #[test]
    fn chirp_estimate_is_blanked_where_the_sweep_did_not_reach() {
        let (amplitude, f0, f1, duration, dt) = (2.0, 10.0, 50.0, 4.0, 1e-3);
        let rate = (f1 - f0) / duration;
        let times: Vec<f64> = (0..=(duration / dt) as usize)
            .map(|k| k as f64 * dt)
            .collect();
        let input: Vec<f64> = times
            .iter()
            .map(|t| amplitude * (std::f64::consts::TAU * (f0 * t + 0.5 * rate * t * t)).sin())
            .collect();
        let frequencies = log_space(2.0, 100.0, 120);
        let mut points = chirp_estimate(&times, &input, &input, &frequencies);
        let masked = mask_weak_input(&mut points, &times, &input, amplitude, rate);
        assert!(masked > 0 && masked < points.len());
        for point in &points {
            let f = point.frequency_hz;
            if !(7.0..=53.0).contains(&f) {
                assert!(point.gain.re.is_nan(), "{f} Hz kept: {}", point.gain);
            }
            if (13.0..=47.0).contains(&f) {
                assert!(
                    (point.gain.norm() - 1.0).abs() < 1e-9,
                    "{f} Hz: {}",
                    point.gain
                );
            }
        }
    }

    /// Bad grids and a response that is not a number are typed errors, not panics or loops.
    #[test]
    fn refine_errors_are_typed() {
        for grid in [
            vec![1.0, 2.0, 2.0, 3.0],
            vec![0.0, 1.0, 2.0],
            vec![1.0, f64::NAN],
        ] {
            assert!(
                matches!(
                    refined_resonances(&grid, magnitude),
                    Err(RefineError::Grid { .. })
                ),
                "{grid:?}"
            );
        }
        // Singular between two samples: found by the searches, reported with its frequency.
        let singular = |f: f64| {
            if (9.99..10.01).contains(&f) {
                f64::NAN
            } else {
                magnitude(f)
            }
        };
        let error = refined_resonances(&log_space(1.0, 100.0, 30), singular).unwrap_err();
        assert!(
            matches!(error, RefineError::NotFinite { frequency_hz } if (9.99..10.01).contains(&frequency_hz)),
            "{error:?}"
        );
        assert!(error.to_string().contains("not finite"), "{error}");
        assert_eq!(refined_resonances(&[], magnitude), Ok(Vec::new()));
    }
}
