//! The flexure pendulum as a diagnosis experiment (`kind = "pendulum"`; seed Sec. IV.A): a
//! physical pendulum hangs from the flexure under test, is released from rest and rings
//! down; a camera measures its angle.
//!
//! Consumes: the experiment file's `[pendulum]` keys ([`Pendulum`]), the opened model (a
//! [`Leg`] without HAMR ports) and the measured trace (columns `time [s]` and the measured
//! angle, `angle [deg]` or `[rad]`, angles from the rest position). Produces:
//! - the observations (one angle per data row, abscissa the time) and the model's prediction
//!   of them: the ring-down simulated by the runtime (DOP853 on the reduced dynamics) from
//!   rest at the release angle, sampled at the data times by dense output
//!   ([`Pendulum::predict`]);
//! - a [`Screening`] of the trace before anything is fitted ([`screen`]): flags for what no
//!   parameter of the model can produce — damping that depends on the amplitude (the
//!   model's loss factor gives a constant logarithmic decrement) and an oscillation centre
//!   that is not at the rest angle or drifts. `mech fit` and `mech diagnose` report the flags
//!   prominently, and `mech diagnose` names no cause for a flagged trace.
//!
//! The screening reuses `mech flexure fit`'s trace analysis (zero crossings with hysteresis,
//! one least-squares half-sine amplitude `A_j` per half-cycle, the noise level from fourth
//! differences) and fits (Levenberg–Marquardt, weights `A_j²/σ_A²`, the inverse variance of
//! `ln A_j` under additive noise)
//!
//! ```text
//! ln A_j(measured) = ln A(τ_j) + ln g(s_j c(τ_j) / A(τ_j)),
//! ln A(τ) = a − σ₀ τ − σ₁ ∫₀^τ A dt,     c(τ) = c₀ + c₁ (τ − τ_m)
//! ```
//!
//! with `τ_j` the half-cycle's time, `s_j = ±1` its sign and `τ_m` the middle of the trace.
//! `A(τ)` decays at the rate `σ(A) = σ₀ + σ₁ A` (`d ln A/dt = −σ(A)`, integrated with the
//! measured amplitudes): `σ₁ ≠ 0` is damping that depends on the amplitude. `c(τ)` is the
//! oscillation's centre: an oscillation centred at `c` crosses zero early or late, so the
//! half-cycles on the side of `c` measure larger and those on the other side smaller, by the
//! factor `g(±c/A) ≈ 1 ± (3/π) c/A` ([`offset_factor`], exact to all orders) — an alternation
//! the smooth decay cannot mimic. `c₁ ≠ 0` is a drifting baseline, `c₀ ≠ 0` an offset. The
//! standard errors come from the fit, scaled up by `√(χ²/dof)` when the scatter exceeds the
//! noise (so a screening model that does not fit cannot produce a flag by itself), and an
//! effect is flagged beyond [`FLAG_SIGMA`] standard errors.

use std::f64::consts::PI;

use mech_codegen::ir::{Dimension, Expr};
use mech_runtime::integrate::{AdaptiveOptions, Dop853, Stepper};
use mech_runtime::{Reduced, RuntimeError};
use serde::Deserialize;

use super::data::MeasuredData;
use super::error::{Error, KeyError};
use super::lm::{levenberg_marquardt, LmOptions, Parameter};
use super::observations::{noise_value, Observations};
use crate::experiments::leg::Leg;
use crate::flexure_fit::trace::{analyze_trace, TraceAnalysis, TraceOptions};

/// An effect is flagged when its estimate exceeds this many standard errors. Three effects
/// are tested per trace; with Gaussian noise 3.5σ gives a false flag on about 0.14 % of
/// clean traces.
pub const FLAG_SIGMA: f64 = 3.5;

/// Amplitude noise floor, relative to the first half-cycle's amplitude: effects below it
/// (noise-free synthetic traces, numerical error of the simulation) are not flagged.
const RELATIVE_NOISE_FLOOR: f64 = 1e-3;

/// Fewest half-cycles above the noise that the screening fit (5 coefficients) needs.
const MIN_HALF_CYCLES: usize = 10;

/// Tolerances of the ring-down simulation: far below any camera's noise, and smooth in the
/// parameters at the fit's finite-difference steps (relative 1e-4).
const RTOL: f64 = 1e-10;
const ATOL: f64 = 1e-12;

/// A `kind = "pendulum"` experiment file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pendulum {
    /// The measured angle: a model output or coordinate, and the data column of that name
    /// (default `angle`, the rig's output).
    #[serde(default = "default_angle")]
    pub angle: String,
    /// The coordinate released from the release angle (default: the model's only degree of
    /// freedom).
    #[serde(default)]
    pub coordinate: Option<String>,
    /// The release angle, e.g. `"10 deg"`; omitted: estimated from the data (the trace must
    /// start at the release).
    #[serde(default)]
    pub release: Option<String>,
    /// Measurement noise of the angle (one standard deviation), e.g. `"0.05 deg"`.
    #[serde(default)]
    pub noise: Option<String>,
}

fn default_angle() -> String {
    "angle".into()
}

/// Data column of the sample times.
pub const TIME: &str = "time";

/// What the measured angle is in the model.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Measured {
    Output(usize),
    Coordinate(usize),
}

impl Pendulum {
    /// Checks the keys that do not need the model.
    pub fn check(&self) -> Result<(), KeyError> {
        if let Some(text) = &self.noise {
            noise_value("noise", text, Dimension::NONE)?;
        }
        if let Some(text) = &self.release {
            release_value(text)?;
        }
        Ok(())
    }

    fn measured(&self, leg: &Leg) -> Result<Measured, KeyError> {
        let model = leg.model();
        if let Some(index) = model.output_index(&self.angle) {
            return Ok(Measured::Output(index));
        }
        if let Ok(index) = leg.session.coordinate_index(&self.angle) {
            return Ok(Measured::Coordinate(index));
        }
        Err(KeyError::UnknownAngle {
            angle: self.angle.clone(),
            outputs: (0..model.noutputs())
                .map(|i| model.output_name(i).to_string())
                .collect(),
        })
    }

    /// The released coordinate (an independent one).
    fn coordinate(&self, leg: &Leg) -> Result<usize, KeyError> {
        let index = match &self.coordinate {
            Some(name) => leg
                .session
                .coordinate_index(name)
                .map_err(|error| KeyError::UnknownCoordinate(Box::new(error)))?,
            None => match leg.independent.as_slice() {
                [only] => *only,
                several => {
                    return Err(KeyError::CoordinateAmbiguous {
                        model: leg.model().name().to_string(),
                        dofs: several.len(),
                    })
                }
            },
        };
        if !leg.independent.contains(&index) {
            return Err(KeyError::CoordinateNotIndependent {
                coordinate: leg.model().coordinate_name(index).to_string(),
            });
        }
        Ok(index)
    }

    /// The sample times and measured angles (SI), checked: errors name the data file, the
    /// line and the column.
    pub fn trace<'a>(&self, data: &'a MeasuredData) -> Result<(&'a [f64], &'a [f64]), Error> {
        let times = data.require(TIME, Dimension::TIME)?;
        data.check_time_monotonic(TIME)?;
        // The unit first: a length or a bare number is no angle (and `require` alone would
        // accept any dimensionless column, a percentage too).
        if let Some((index, column)) = data
            .columns
            .iter()
            .enumerate()
            .find(|(_, c)| c.name == self.angle)
        {
            if !is_angle_unit(&column.unit_text) {
                return Err(Error::NotAngleUnit {
                    path: data.path.clone(),
                    index: index + 1,
                    column: column.name.clone(),
                    unit_text: column.unit_text.clone(),
                });
            }
        }
        let angles = data.require(&self.angle, Dimension::NONE)?;
        Ok((times, angles))
    }

    /// The measured angles, one per row, with the time as abscissa.
    pub fn observations(&self, leg: &Leg, data: &MeasuredData) -> Result<Observations, Error> {
        self.measured(leg)?;
        self.coordinate(leg)?;
        let (times, angles) = self.trace(data)?;
        if data.rows < 2 {
            return Err(Error::TooFewSamples {
                path: data.path.clone(),
            });
        }
        let noise = match &self.noise {
            Some(text) => Some(noise_value("noise", text, Dimension::NONE)?),
            None => None,
        };
        Ok(Observations {
            values: angles.to_vec(),
            sigma: noise.map(|s| vec![s; angles.len()]),
            series: vec![self.angle.clone(); angles.len()],
            abscissa: times.to_vec(),
            row: (0..angles.len()).collect(),
        })
    }

    /// The release angle (rad): the file's, or the data's estimate ([`estimated_release`]).
    pub fn release_angle(&self, data: &MeasuredData) -> Result<f64, Error> {
        match &self.release {
            Some(text) => Ok(release_value(text)?),
            None => {
                let (times, angles) = self.trace(data)?;
                Ok(estimated_release(times, angles))
            }
        }
    }

    /// The model's ring-down at the data times, from rest at the release angle.
    pub fn predict(&self, leg: &Leg, data: &MeasuredData) -> Result<Vec<f64>, Error> {
        let measured = self.measured(leg)?;
        let coordinate = self.coordinate(leg)?;
        let release = self.release_angle(data)?;
        let (times, _) = self.trace(data)?;
        ring_down(leg, coordinate, release, times, measured).map_err(|error| Error::RingDown {
            model: leg.model().name().to_string(),
            error,
        })
    }
}

fn is_angle_unit(unit: &str) -> bool {
    matches!(
        unit.trim(),
        "deg" | "rad" | "mrad" | "urad" | "degree" | "degrees"
    )
}

fn release_value(text: &str) -> Result<f64, KeyError> {
    let key = "release";
    let (value, dimension) =
        mech_codegen::front::units::parse_quantity(text).map_err(|message| KeyError::Quantity {
            key,
            text: text.to_string(),
            message,
        })?;
    if dimension != Dimension::NONE || !value.is_finite() {
        return Err(KeyError::NotAngle {
            key,
            text: text.to_string(),
        });
    }
    Ok(value)
}

/// The release angle from a trace that starts at the release: the least-squares amplitude
/// `θ₀` of the free decay from rest, `θ₀ e^{−στ}(cos ω_d τ + (σ/ω_d) sin ω_d τ)`, over the
/// samples before the first zero crossing (ω_d, σ from the trace analysis). Uses every
/// sample of the first quarter period rather than the first one alone, whose noise would
/// scale the whole prediction. Falls back to the first sample when the trace cannot be
/// analysed.
pub fn estimated_release(times: &[f64], angles: &[f64]) -> f64 {
    let first = angles.first().copied().unwrap_or(0.0);
    let Ok(analysis) = analyze_trace(times, angles, &TraceOptions::default()) else {
        return first;
    };
    let (t0, end) = (times[0], analysis.crossings[0]);
    let (wd, sigma) = (analysis.omega_d, analysis.sigma);
    let (mut num, mut den) = (0.0, 0.0);
    for (&t, &a) in times.iter().zip(angles).take_while(|(&t, _)| t < end) {
        let tau = t - t0;
        let shape = (-sigma * tau).exp() * ((wd * tau).cos() + sigma / wd * (wd * tau).sin());
        num += a * shape;
        den += shape * shape;
    }
    if den > 0.0 {
        num / den
    } else {
        first
    }
}

/// Simulates the free decay from rest with `coordinate` at `release` (the other coordinates
/// at the assembled state, loops closed) and samples the measured angle at `times`.
fn ring_down(
    leg: &Leg,
    coordinate: usize,
    release: f64,
    times: &[f64],
    measured: Measured,
) -> Result<Vec<f64>, RuntimeError> {
    let model = leg.model();
    let (t0, t1) = (times[0], times[times.len() - 1]);
    let mut q = leg.q0.clone();
    q[coordinate] = release;
    let signals = &leg.session.signals;
    let independent = &leg.independent;
    let tolerance = 1e-12;
    let ode = Reduced::new(model, signals, t0, &q, independent, tolerance)?;
    // A second instance maps each sample's (z, ż) back to (q, u).
    let mut sampler = Reduced::new(model, signals, t0, &q, independent, tolerance)?;
    let nz = independent.len();
    let mut x0: Vec<f64> = independent.iter().map(|&i| q[i]).collect();
    x0.resize(2 * nz, 0.0);
    let options = AdaptiveOptions {
        rtol: RTOL,
        atol: ATOL,
        ..AdaptiveOptions::dop853()
    };
    let mut stepper = Dop853::new(ode, t0, &x0, t1, options)?;
    let mut x = x0.clone();
    let mut inputs = vec![0.0; model.ninputs()];
    let mut y = vec![0.0; model.noutputs()];
    let mut out = Vec::with_capacity(times.len());
    for &t in times {
        while stepper.t() < t {
            stepper.step()?;
        }
        if t == t0 {
            x.copy_from_slice(&x0);
        } else {
            stepper.interpolate(t, &mut x)?;
        }
        let (z, zdot) = x.split_at(nz);
        sampler.state(t, z, zdot)?;
        out.push(match measured {
            Measured::Coordinate(i) => sampler.q()[i],
            Measured::Output(i) => {
                for (v, s) in inputs.iter_mut().zip(signals) {
                    *v = s.value(t);
                }
                model.outputs(t, sampler.q(), sampler.u(), &inputs, &mut y);
                y[i]
            }
        });
    }
    Ok(out)
}

/// Something in a trace that the model cannot produce with any parameter values.
#[derive(Debug, Clone, PartialEq)]
pub struct Flag {
    /// `amplitude_dependent_damping`, `baseline_drift`, `baseline_offset` or `not_screened`.
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
             rad/s): log decrement per cycle {:.4} → {:.4} (trend {:.1}σ), centre {:+.3}° → \
             {:+.3}° (drift {:.1}σ, offset {:.1}σ); flagged beyond {FLAG_SIGMA}σ",
            f.half_cycles,
            f.amplitudes.0.to_degrees(),
            f.amplitudes.1.to_degrees(),
            f.noise.to_degrees(),
            f.omega_d,
            f.decrement.0,
            f.decrement.1,
            f.decrement_trend_sigma,
            f.baseline.0.to_degrees(),
            f.baseline.1.to_degrees(),
            f.drift_sigma,
            f.offset_sigma
        )
    }
}

/// Screens one decay trace (times in s, strictly increasing; angles in rad from the rest
/// position) for amplitude-dependent damping and a baseline offset or drift.
pub fn screen(times: &[f64], angles: &[f64]) -> Screening {
    let not_screened = |why: String| Screening {
        flags: vec![Flag {
            kind: "not_screened",
            message: format!(
                "not screened: {why}; amplitude-dependent damping and baseline drift could not \
                 be checked"
            ),
        }],
        fit: None,
    };
    let analysis = match analyze_trace(times, angles, &TraceOptions::default()) {
        Ok(a) => a,
        Err(e) => return not_screened(e.to_string()),
    };
    if analysis.peaks.len() < MIN_HALF_CYCLES {
        return not_screened(format!(
            "only {} half-cycles above the noise (need {MIN_HALF_CYCLES})",
            analysis.peaks.len()
        ));
    }
    match screening_fit(times, angles, &analysis) {
        Some(fit) => Screening {
            flags: flags(&fit),
            fit: Some(fit),
        },
        None => not_screened("the screening fit is singular (too short a trace?)".into()),
    }
}

fn screening_fit(times: &[f64], angles: &[f64], analysis: &TraceAnalysis) -> Option<ScreeningFit> {
    let peaks = &analysis.peaks;
    let n = peaks.len();
    let first = peaks[0].1;
    let noise = analysis.noise.max(RELATIVE_NOISE_FLOOR * first);
    let t_first = peaks[0].0;
    let span = peaks[n - 1].0 - t_first;
    let middle = 0.5 * span;
    // Per half-cycle: τ, ∫A dt up to it, sign, ln A and its weight.
    let mut half_cycles = Vec::with_capacity(n);
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
    let options = LmOptions {
        residuals_normalized: true,
        ..LmOptions::default()
    };
    let result = levenberg_marquardt(residuals, &parameters, &options).ok()?;
    if n <= parameters.len() || result.params.iter().any(|p| !p.is_finite()) {
        return None;
    }
    // Scatter beyond the noise (a screening model that does not fit) widens the errors.
    let chi2_dof = 2.0 * result.cost / (n - parameters.len()) as f64;
    let inflation = chi2_dof.max(1.0).sqrt();
    let z = |k: usize| {
        let se = result.standard_errors[k] * inflation;
        if se.is_finite() && se > 0.0 {
            result.params[k] / se
        } else {
            0.0
        }
    };
    let [_, sigma0, sigma1, c0, c1] = [0, 1, 2, 3, 4].map(|k| result.params[k]);
    let last = peaks[n - 1].1;
    let decrement = |a: f64| 2.0 * PI * (sigma0 + sigma1 * a) / analysis.omega_d;
    Some(ScreeningFit {
        half_cycles: n,
        amplitudes: (first, last),
        noise: analysis.noise,
        omega_d: analysis.omega_d,
        decrement: (decrement(first), decrement(last)),
        decrement_trend_sigma: z(2),
        baseline: (c0 - c1 * middle, c0 + c1 * middle),
        drift_sigma: z(4),
        offset_sigma: z(3),
        span,
    })
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

/// The model parameters that stand for a flexure's stiffness when it is not a parameter of
/// its own (`k_*`): a flexure made of a material with modulus `E` has stiffness
/// `E w h³/(12 l)`, in which `E`, `w`, `h` and `l` act only through that product — the modulus
/// (a parameter of pressure dimension in the stiffness) is the one to fit; the geometry is
/// measured. Returns (parameter index, flexures it stiffens).
pub fn stiffness_moduli(leg: &Leg) -> Vec<(usize, Vec<String>)> {
    const PRESSURE: Dimension = Dimension {
        mass: 1,
        length: -1,
        time: -2,
        current: 0,
    };
    let compiled = &leg.session.compiled.model;
    let mut out: Vec<(usize, Vec<String>)> = Vec::new();
    for flexure in &compiled.flexures {
        let mut params = Vec::new();
        collect_params(&flexure.stiffness, &mut params);
        for index in params {
            let Some((_, param)) = compiled.params.iter().nth(index) else {
                continue;
            };
            if param.dimension != PRESSURE || leg.model().param(index) <= 0.0 {
                continue;
            }
            match out.iter_mut().find(|(i, _)| *i == index) {
                Some((_, names)) => names.push(flexure.name.clone()),
                None => out.push((index, vec![flexure.name.clone()])),
            }
        }
    }
    out
}

fn collect_params(expr: &Expr, out: &mut Vec<usize>) {
    match expr {
        Expr::Param(handle) => {
            if !out.contains(&handle.index()) {
                out.push(handle.index());
            }
        }
        Expr::Number(_) | Expr::Input(_) | Expr::Time | Expr::Pi => {}
        Expr::Neg(a) | Expr::Pow(a, _) => collect_params(a, out),
        Expr::Add(a, b) | Expr::Sub(a, b) | Expr::Mul(a, b) | Expr::Div(a, b) => {
            collect_params(a, out);
            collect_params(b, out);
        }
        Expr::Call(_, args) => args.iter().for_each(|a| collect_params(a, out)),
    }
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
