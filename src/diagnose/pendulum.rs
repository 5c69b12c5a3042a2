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
//!   parameter of the model can produce — damping or frequency that depend on the amplitude
//!   (the model's loss factor gives a constant logarithmic decrement, its linear flexure a
//!   frequency that only gravity's `sin θ` moves) and an oscillation centre that is not at the
//!   rest angle or drifts. `mech fit` and `mech diagnose` report the flags prominently, and
//!   `mech diagnose` names no cause for a flagged trace.
//!
//! The screening is `mech flexure fit`'s ([`crate::flexure_fit::screen`], re-exported here),
//! so both commands screen a trace the same way. A single trace comes without the pendulum's
//! gravity share, so the frequency is flagged only where no share explains it.

use mech_codegen::ir::{Dimension, Expr};
use mech_runtime::integrate::{AdaptiveOptions, Dop853, Stepper};
use mech_runtime::{Reduced, RuntimeError};
use serde::Deserialize;

use super::data::MeasuredData;
use super::error::{Error, KeyError};
use super::observations::{key_quantity, noise_value, Observations};
use crate::experiments::leg::Leg;
use crate::flexure_fit::trace::{analyze_trace, TraceOptions};

pub use crate::flexure_fit::screen::{screen, Flag, Screening, ScreeningFit, FLAG_SIGMA};

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
        let noise = self
            .noise
            .as_ref()
            .map(|text| noise_value("noise", text, Dimension::NONE))
            .transpose()?;
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
    key_quantity("release", text, Dimension::NONE, |key, text| {
        KeyError::NotAngle { key, text }
    })
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
        Expr::Number(_) | Expr::Input(_) | Expr::Time | Expr::State(_) | Expr::Pi => {}
        Expr::Neg(a) | Expr::Pow(a, _) => collect_params(a, out),
        Expr::Add(a, b) | Expr::Sub(a, b) | Expr::Mul(a, b) | Expr::Div(a, b) => {
            collect_params(a, out);
            collect_params(b, out);
        }
        Expr::Call(_, args) => args.iter().for_each(|a| collect_params(a, out)),
    }
}
