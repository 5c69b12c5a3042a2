//! Input signals: scalar functions of time that drive a model's inputs during a simulation.
//!
//! Consumes the signal definitions (and, to check them against it, the [`Model`] they drive);
//! produces their values at a time. Everything about signals is here: the [`Signal`] and
//! [`Table`] types, their validation, the defaults of a model's inputs ([`default_signals`])
//! and the evaluation of one signal per input that the dynamics call at every time.
//!
//! Times are in seconds (the model's time unit), frequencies in hertz, phases in radians; the
//! value has the unit of the input it drives.

use crate::integrate::check_len;
use crate::{Model, RuntimeError};
use std::f64::consts::TAU;

/// A scalar input signal `s(t)`.
///
/// Build tables with [`Signal::table`], which validates them. Use [`Signal::validate`] to check
/// the parameters of the other variants ([`crate::simulate()`] does so).
#[derive(Debug, Clone, PartialEq)]
pub enum Signal {
    /// `s(t) = value`.
    Constant(f64),
    /// `s(t) = amplitude·sin(2π·frequency_hz·t + phase_rad) + offset`.
    Sine {
        /// Peak amplitude.
        amplitude: f64,
        /// Frequency in Hz (≥ 0).
        frequency_hz: f64,
        /// Phase at `t = 0`, in radians.
        phase_rad: f64,
        /// Value added to the sinusoid.
        offset: f64,
    },
    /// Linear chirp (frequency sweep) from `f0_hz` at `t = 0` to `f1_hz` at `t = duration`:
    /// `s(t) = amplitude·sin(φ(t)) + offset` with
    ///
    /// * `φ(t) = 2π·(f0·t + (f1 − f0)·t²/(2·duration))` for `0 ≤ t ≤ duration`, so the
    ///   instantaneous frequency `φ'(t)/2π` rises linearly from `f0` to `f1`;
    /// * after `duration` the frequency **holds at `f1`** with continuous phase:
    ///   `φ(t) = φ(duration) + 2π·f1·(t − duration)`. Holding (rather than stopping or
    ///   wrapping) keeps the excitation smooth, so a simulation that runs past the sweep does
    ///   not see a jump;
    /// * before `t = 0` the frequency is `f0`: `φ(t) = 2π·f0·t`.
    ///
    /// The sine starts at phase 0, so `s(0) = offset`.
    Chirp {
        /// Peak amplitude.
        amplitude: f64,
        /// Start frequency in Hz (≥ 0).
        f0_hz: f64,
        /// End frequency in Hz (≥ 0).
        f1_hz: f64,
        /// Length of the sweep in seconds (> 0).
        duration: f64,
        /// Value added to the sinusoid.
        offset: f64,
    },
    /// Piecewise-linear interpolation of samples, held constant outside their time range.
    Table(Table),
}

/// Samples `(times[i], values[i])` of a [`Signal::Table`]: non-empty, finite, with strictly
/// increasing times. Construct with [`Table::new`] or [`Signal::table`].
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    times: Vec<f64>,
    values: Vec<f64>,
}

impl Table {
    /// Validates and wraps the samples: same lengths, at least one sample, all values finite,
    /// times strictly increasing.
    pub fn new(times: Vec<f64>, values: Vec<f64>) -> Result<Table, RuntimeError> {
        let bad = |msg: String| Err(RuntimeError::InvalidSignal(msg));
        if times.len() != values.len() {
            return bad(format!(
                "table has {} times but {} values: give one value per time",
                times.len(),
                values.len()
            ));
        }
        if times.is_empty() {
            return bad("table is empty: give at least one (time, value) sample".into());
        }
        if let Some(i) = times.iter().position(|t| !t.is_finite()) {
            return bad(format!("table time #{i} is {} (not finite)", times[i]));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return bad(format!("table value #{i} is {} (not finite)", values[i]));
        }
        if let Some(i) = times.windows(2).position(|w| w[1] <= w[0]) {
            return bad(format!(
                "table times must increase strictly, but time #{} ({}) follows {}: \
                 sort the samples and remove duplicate times",
                i + 1,
                times[i + 1],
                times[i]
            ));
        }
        Ok(Table { times, values })
    }

    /// Sample times, strictly increasing.
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// Sample values.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Linear interpolation at `t`; the first (last) value before (after) the samples.
    pub fn value(&self, t: f64) -> f64 {
        let (ts, vs) = (&self.times, &self.values);
        let n = ts.len();
        if t <= ts[0] {
            return vs[0];
        }
        if t >= ts[n - 1] {
            return vs[n - 1];
        }
        // ts[0] < t < ts[n-1]: the first index with ts[i] > t is in 1..n.
        let i = ts.partition_point(|&ti| ti <= t);
        let (t0, t1, v0, v1) = (ts[i - 1], ts[i], vs[i - 1], vs[i]);
        let w = (t - t0) / (t1 - t0);
        v0 + w * (v1 - v0)
    }
}

impl Signal {
    /// A validated [`Signal::Table`]; see [`Table::new`].
    pub fn table(times: Vec<f64>, values: Vec<f64>) -> Result<Signal, RuntimeError> {
        Table::new(times, values).map(Signal::Table)
    }

    /// Value at time `t` (seconds).
    pub fn value(&self, t: f64) -> f64 {
        match self {
            Signal::Constant(v) => *v,
            Signal::Sine {
                amplitude,
                frequency_hz,
                phase_rad,
                offset,
            } => amplitude * (TAU * frequency_hz * t + phase_rad).sin() + offset,
            Signal::Chirp {
                amplitude, offset, ..
            } => amplitude * self.chirp_phase(t).sin() + offset,
            Signal::Table(table) => table.value(t),
        }
    }

    /// Instantaneous frequency in Hz at time `t` for [`Signal::Sine`] and [`Signal::Chirp`]
    /// (the derivative of the phase divided by 2π); `None` for the other variants.
    pub fn frequency_hz(&self, t: f64) -> Option<f64> {
        match self {
            Signal::Sine { frequency_hz, .. } => Some(*frequency_hz),
            Signal::Chirp {
                f0_hz,
                f1_hz,
                duration,
                ..
            } => Some(if t <= 0.0 {
                *f0_hz
            } else if t >= *duration {
                *f1_hz
            } else {
                f0_hz + (f1_hz - f0_hz) * t / duration
            }),
            Signal::Constant(_) | Signal::Table(_) => None,
        }
    }

    /// Phase `φ(t)` of a chirp, in radians (see [`Signal::Chirp`]); 0 for other variants.
    fn chirp_phase(&self, t: f64) -> f64 {
        let Signal::Chirp {
            f0_hz,
            f1_hz,
            duration,
            ..
        } = *self
        else {
            return 0.0;
        };
        let sweep = |t: f64| TAU * (f0_hz * t + (f1_hz - f0_hz) * t * t / (2.0 * duration));
        if t <= 0.0 {
            TAU * f0_hz * t
        } else if t <= duration {
            sweep(t)
        } else {
            sweep(duration) + TAU * f1_hz * (t - duration)
        }
    }

    /// Checks the parameters: finite numbers, frequencies ≥ 0, chirp duration > 0. (Tables are
    /// validated when built.)
    pub fn validate(&self) -> Result<(), RuntimeError> {
        let finite = |name: &str, v: f64| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(RuntimeError::InvalidSignal(format!(
                    "{name} is {v} (not finite)"
                )))
            }
        };
        let frequency = |name: &str, v: f64| {
            finite(name, v)?;
            if v < 0.0 {
                return Err(RuntimeError::InvalidSignal(format!(
                    "{name} is {v}: frequencies must be >= 0 (use phase_rad or a negative \
                     amplitude to invert the signal)"
                )));
            }
            Ok(())
        };
        match *self {
            Signal::Constant(v) => finite("constant value", v),
            Signal::Sine {
                amplitude,
                frequency_hz,
                phase_rad,
                offset,
            } => {
                finite("sine amplitude", amplitude)?;
                frequency("sine frequency_hz", frequency_hz)?;
                finite("sine phase_rad", phase_rad)?;
                finite("sine offset", offset)
            }
            Signal::Chirp {
                amplitude,
                f0_hz,
                f1_hz,
                duration,
                offset,
            } => {
                finite("chirp amplitude", amplitude)?;
                frequency("chirp f0_hz", f0_hz)?;
                frequency("chirp f1_hz", f1_hz)?;
                finite("chirp offset", offset)?;
                finite("chirp duration", duration)?;
                if duration <= 0.0 {
                    return Err(RuntimeError::InvalidSignal(format!(
                        "chirp duration is {duration}: it must be > 0 (use a sine for a fixed \
                         frequency)"
                    )));
                }
                Ok(())
            }
            Signal::Table(_) => Ok(()),
        }
    }
}

/// One [`Signal::Constant`] per model input, at the input's default value.
pub fn default_signals<M: Model + ?Sized>(model: &M) -> Vec<Signal> {
    (0..model.ninputs())
        .map(|i| Signal::Constant(model.input_default(i)))
        .collect()
}

/// Checks that `signals` can drive `model`: one per input, each valid.
pub(crate) fn check_inputs<M: Model + ?Sized>(
    model: &M,
    signals: &[Signal],
) -> Result<(), RuntimeError> {
    check_len("signals", model.ninputs(), signals.len())?;
    signals.iter().try_for_each(Signal::validate)
}

/// The value of each signal at `t` into `values` (one per signal).
pub(crate) fn values_at(signals: &[Signal], t: f64, values: &mut [f64]) {
    for (value, signal) in values.iter_mut().zip(signals) {
        *value = signal.value(t);
    }
}
