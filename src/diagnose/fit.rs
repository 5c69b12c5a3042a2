//! `mech fit`: the parameters a user allows, fitted to measured data.
//!
//! Consumes: an opened leg (the model), a diagnosis [`Experiment`], its [`MeasuredData`] and
//! the parameters to fit ([`FitRequest`]: a name and optional bounds). Produces: a
//! [`FitReport`] — the Levenberg–Marquardt result (values, standard errors, status), the
//! residual before and after per measured series, and both predictions for plots.
//!
//! The residual is `(predicted − measured)/σ` when the experiment file gives the noise σ
//! (then the covariance is `(JᵀJ)⁻¹` and χ²/dof near 1 means the model explains the data to
//! the noise), and `predicted − measured` otherwise (covariance scaled by the residual
//! variance).

use mech_codegen::ir::Dimension;
use mech_runtime::Model;

use super::data::MeasuredData;
use super::error::Error;
use super::experiment::{Experiment, Extensions, Observations};
use super::features::series_rms;
pub use super::features::SeriesResidual;
use super::lm::{levenberg_marquardt, Difference, FitResult, LmOptions, Parameter, Stall};
use crate::experiments::leg::{Leg, WarmStarts};

/// What a fitted value sets: a model parameter (by index) or an extension's setting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    Param(usize),
    LossExponent,
    OffAxisFraction,
}

impl Target {
    pub(crate) fn apply(self, leg: &mut Leg, extensions: &mut Extensions, value: f64) {
        match self {
            Target::Param(index) => leg.session.model.set_param(index, value),
            Target::LossExponent => extensions.loss_exponent = Some(value),
            Target::OffAxisFraction => extensions.off_axis_fraction = Some(value),
        }
    }
}

/// A parameter to fit: `NAME` (bounds: a factor of 10 either side of a positive value, none
/// otherwise) or `NAME=LO..HI` with units (`k_s3=10..100 uN*m/rad`).
#[derive(Debug, Clone, PartialEq)]
pub struct FitRequest {
    pub name: String,
    pub bounds: Option<(f64, f64)>,
}

impl FitRequest {
    /// Parses `NAME` or `NAME=LO..HI UNIT`; the unit applies to both bounds and is checked
    /// against the parameter's dimension by [`parameters`].
    pub fn parse(text: &str) -> Result<(FitRequest, Option<Dimension>), Error> {
        let Some((name, range)) = text.split_once('=') else {
            return Ok((
                FitRequest {
                    name: text.trim().to_string(),
                    bounds: None,
                },
                None,
            ));
        };
        let (lo, hi) = range.split_once("..").ok_or_else(|| Error::FitSyntax {
            text: text.to_string(),
        })?;
        // `10..100 uN*m/rad`: the unit follows the upper bound and applies to both.
        let hi = hi.trim();
        let split = hi
            .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | 'e' | 'E' | '-' | '+')))
            .unwrap_or(hi.len());
        let (hi_number, unit) = hi.split_at(split);
        let parse = |number: &str| {
            mech_codegen::front::units::parse_quantity(&format!("{} {unit}", number.trim()))
                .map_err(|message| Error::FitBound {
                    text: text.to_string(),
                    message,
                })
        };
        let ((lo, dimension), (hi, _)) = (parse(lo)?, parse(hi_number)?);
        if lo >= hi || lo.is_nan() || hi.is_nan() {
            return Err(Error::FitBoundsOrder {
                text: text.to_string(),
            });
        }
        Ok((
            FitRequest {
                name: name.trim().to_string(),
                bounds: Some((lo, hi)),
            },
            Some(dimension),
        ))
    }
}

/// The LM parameters for `requests`, starting at the model's current values; errors name an
/// unknown parameter (listing the known ones) or a bound with the wrong unit.
pub fn parameters(
    leg: &Leg,
    requests: &[(FitRequest, Option<Dimension>)],
) -> Result<Vec<(Target, Parameter)>, Error> {
    let model = leg.model();
    let compiled = &leg.session.compiled.model;
    requests
        .iter()
        .map(|(request, dimension)| {
            let index =
                model
                    .param_index(&request.name)
                    .ok_or_else(|| Error::UnknownParameter {
                        name: request.name.clone(),
                        model: model.name().to_string(),
                        known: (0..model.nparams())
                            .map(|i| model.param_name(i).to_string())
                            .collect(),
                    })?;
            let expected = compiled
                .params
                .iter()
                .nth(index)
                .map(|(_, p)| p.dimension)
                .unwrap_or_default();
            if let Some(d) = dimension {
                if *d != expected {
                    return Err(Error::BoundUnit {
                        name: request.name.clone(),
                        found: *d,
                        expected,
                    });
                }
            }
            let initial = model.param(index);
            let parameter = Parameter::new(&request.name, initial);
            let parameter = match request.bounds {
                Some((lo, hi)) => parameter.bounded(lo, hi),
                None if initial > 0.0 => parameter.bounded(initial / 10.0, initial * 10.0),
                None => parameter,
            };
            Ok((Target::Param(index), parameter))
        })
        .collect()
}

/// Everything `mech fit` reports.
#[derive(Debug, Clone)]
pub struct FitReport {
    pub title: String,
    pub observations: Observations,
    pub before: Vec<f64>,
    pub after: Vec<f64>,
    pub residuals: Vec<SeriesResidual>,
    pub result: FitResult,
}

/// Fits the parameters `fitted` (model parameter index, LM parameter) of `leg` to `data`.
/// On return the leg holds the fitted values.
pub fn fit(
    experiment: &Experiment,
    data: &MeasuredData,
    leg: &mut Leg,
    fitted: &[(Target, Parameter)],
) -> Result<FitReport, Error> {
    let observations = experiment.observations(leg, data)?;
    let train = vec![true; observations.values.len()];
    fit_values(experiment, data, leg, fitted, observations, &train, None)
}

/// As [`fit`] with the observations already built, fitting only the values marked in
/// `train` (the rest are held out: predicted, not fitted), giving up as `stall` says.
pub fn fit_values(
    experiment: &Experiment,
    data: &MeasuredData,
    leg: &mut Leg,
    fitted: &[(Target, Parameter)],
    observations: Observations,
    train: &[bool],
    stall: Option<Stall>,
) -> Result<FitReport, Error> {
    let mut extensions = Extensions::default();
    for (target, parameter) in fitted {
        target.apply(leg, &mut extensions, parameter.initial);
    }
    // Each evaluation starts its equilibria from the last one's (the parameters move little).
    let mut warm = WarmStarts::default();
    let before = experiment.predict_warm(leg, data, &observations, &extensions, &mut warm)?;
    let sigma = observations.sigma.clone();
    let parameters: Vec<Parameter> = fitted.iter().map(|(_, p)| p.clone()).collect();
    let options = LmOptions {
        // The predictions come from Newton solves and finite-difference linearizations
        // (relative accuracy ~1e-7): steps well above that noise.
        relative_step: Some(1e-4),
        // Forward differences while iterating (half the predictions); the covariance at the
        // solution still uses central ones. A relative change of χ² below 1e-8 is far below
        // what the noise resolves (χ² changes of order 1).
        difference: Difference::Forward,
        covariance_difference: Difference::Central,
        ftol: 1e-8,
        xtol: 1e-8,
        // A fit that has not converged in 50 iterations will not rank well anyway; the cap
        // bounds the cost of a candidate whose predictions are slow (IR extensions).
        max_iterations: 50,
        residuals_normalized: sigma.is_some(),
        stall,
        ..LmOptions::default()
    };
    let result = {
        let mut residuals = |p: &[f64]| -> Result<Vec<f64>, Error> {
            for (&(target, _), &value) in fitted.iter().zip(p) {
                target.apply(leg, &mut extensions, value);
            }
            let predicted =
                experiment.predict_warm(leg, data, &observations, &extensions, &mut warm)?;
            let all = residual(&predicted, &observations);
            Ok(all
                .into_iter()
                .zip(train)
                .filter(|(_, &t)| t)
                .map(|(r, _)| r)
                .collect())
        };
        levenberg_marquardt(&mut residuals, &parameters, &options)?
    };
    for (&(target, _), &value) in fitted.iter().zip(&result.params) {
        target.apply(leg, &mut extensions, value);
    }
    let after = experiment.predict_warm(leg, data, &observations, &extensions, &mut warm)?;
    let residuals = series_rms(&observations, &before, &after, &|_| true);
    Ok(FitReport {
        title: experiment.title.to_string(),
        observations,
        before,
        after,
        residuals,
        result,
    })
}

/// `(predicted − measured)/σ`, or `predicted − measured` without noise levels.
pub fn residual(predicted: &[f64], observations: &Observations) -> Vec<f64> {
    let difference = predicted
        .iter()
        .zip(&observations.values)
        .map(|(p, m)| p - m);
    match &observations.sigma {
        Some(sigma) => difference.zip(sigma).map(|(d, s)| d / s).collect(),
        None => difference.collect(),
    }
}
