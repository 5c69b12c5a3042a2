//! Frequency responses: from a linearization (exact, complex stiffness allowed) or from a
//! simulated chirp (swept-sine estimate), and the resonances they show.
//!
//! Consumes: a [`Linearization`], sampled input/output records, or a model to drive with a
//! [`ChirpSweep`]. Produces: [`Point`]s (frequency, complex gain) and [`Resonance`]s (peak
//! frequency, gain, quality factor).

use mech_runtime::nalgebra::Complex;
use mech_runtime::{
    FlexureDamping, Linearization, Method, Model, RuntimeError, Signal, SimOptions,
};

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

/// A resonance: a local maximum of `|H|`, refined by a parabola through the three samples
/// around it (in log-frequency and dB), with the quality factor `Q = f₀ / Δf` from the
/// half-power (−3 dB) bandwidth, interpolated between samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resonance {
    pub frequency_hz: f64,
    pub peak_magnitude: f64,
    /// `None` when the −3 dB points are not both inside the sweep.
    pub quality_factor: Option<f64>,
}

/// The resonances of a sampled response, strongest first.
pub fn resonances(points: &[Point]) -> Vec<Resonance> {
    let db: Vec<f64> = points.iter().map(Point::magnitude_db).collect();
    let log_f: Vec<f64> = points.iter().map(|p| p.frequency_hz.ln()).collect();
    let mut found = Vec::new();
    for k in 1..points.len().saturating_sub(1) {
        if !(db[k] > db[k - 1] && db[k] >= db[k + 1]) {
            continue;
        }
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
        let quality_factor = match (below, above) {
            (Some(low), Some(high)) if high > low => Some(frequency_hz / (high - low)),
            _ => None,
        };
        found.push(Resonance {
            frequency_hz,
            peak_magnitude: 10f64.powf(peak_db / 20.0),
            quality_factor,
        });
    }
    found.sort_by(|a, b| b.peak_magnitude.total_cmp(&a.peak_magnitude));
    found
}

/// Swept-sine estimate from a chirp record: `H(f) = Y(f) / U(f)` with single-bin Fourier
/// transforms of the whole input and output records (trapezoid rule, rectangular window),
/// evaluated at each analysis frequency; both means are removed. No taper: in a swept sine
/// each frequency lives at one time of the record, and a window over the whole record would
/// suppress the sweep's start and end, where its lowest and highest frequencies are.
pub fn chirp_estimate(
    times: &[f64],
    input: &[f64],
    output: &[f64],
    frequencies: &[f64],
) -> Vec<Point> {
    let n = times.len();
    let mean = |values: &[f64]| values.iter().sum::<f64>() / values.len().max(1) as f64;
    let (input_mean, output_mean) = (mean(input), mean(output));
    let transform = |values: &[f64], offset: f64, omega: f64| {
        let mut sum = Complex::new(0.0, 0.0);
        for k in 1..n {
            let dt = times[k] - times[k - 1];
            let term = |j: usize| Complex::from_polar(values[j] - offset, -omega * times[j]);
            sum += (term(k) + term(k - 1)) * (0.5 * dt);
        }
        sum
    };
    frequencies
        .iter()
        .map(|&f| {
            let omega = std::f64::consts::TAU * f;
            let gain = transform(output, output_mean, omega) / transform(input, input_mean, omega);
            Point {
                frequency_hz: f,
                gain,
            }
        })
        .collect()
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
}

/// Simulates the model from `(q, u)` under `sweep` (the other inputs as `signals` give them;
/// the driven input's value at t = 0 is the chirp's offset) and estimates `H(f)` at
/// `frequencies` by [`chirp_estimate`]. Samples and steps are at most `1/(20 f_max)` apart,
/// so the highest frequency is resolved by 20 points per period.
pub fn simulated_chirp(
    model: &dyn Model,
    q: &[f64],
    u: &[f64],
    signals: &[Signal],
    sweep: &ChirpSweep,
    frequencies: &[f64],
) -> Result<Vec<Point>, RuntimeError> {
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
        ..SimOptions::default()
    };
    let run = mech_runtime::simulate(model, q, u, &signals, &options, &mut |_| {})?;
    let input: Vec<f64> = run.inputs.iter().map(|x| x[sweep.input]).collect();
    let output: Vec<f64> = run.outputs.iter().map(|x| x[sweep.output]).collect();
    Ok(chirp_estimate(&run.times, &input, &output, frequencies))
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
}
