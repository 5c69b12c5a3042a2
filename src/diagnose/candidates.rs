//! `mech diagnose` (first part): which physical cause explains what the model gets wrong.
//!
//! Consumes: a diagnosis experiment, its data, the parameters the user lets vary, and a
//! hold-out rule. Produces: a [`Diagnosis`] — the base model's residual on the data it was
//! fitted to and on the held-out data, every catalog candidate fitted the same way (its own
//! parameters plus the user's) and ranked on the held-out data, and a verdict: a named cause,
//! "no significant discrepancy", "unexplained", or "flagged" when the screening of the data
//! (pendulum traces, [`super::pendulum`]) found what no parameter can produce.
//!
//! The catalog: the parameter changes of the model as written — a flexure's stiffness off by
//! a factor (every `k_*` torsional stiffness), the loss factor (`eta`), the actuator preload
//! (`preload`), the modulus of a flexure's material (`E` of the flexure rig, standing for
//! `E w h³/l`) — a frequency-dependent loss factor `η(f) = η·(f/f_ref)^α` (in the frequency
//! response), an off-axis load at the foot (force/deflection), and the model-form extensions
//! that transform the IR ([`super::extend`]): a hinge's twist, the hinges of one loop twisting
//! together (their length axes searched first), a misaligned hinge axis, an actuator's base
//! compliance, stiffness, force, tip mass and preload. `docs/diagnose.md` has the table.
//!
//! Ranking: with measurement noise σ given, χ² = Σ((predicted − measured)/σ)². The base model
//! shows "no significant discrepancy" when its χ² per value is within `1 + 3·√(2/m)` of 1
//! (m values: all of them when the base model has nothing to fit, else the held-out ones). A candidate explains the data when it lowers the
//! training AICc by more than 10 (Burnham & Anderson's "essentially no support" for the
//! other) and brings the held-out χ² within the same noise band; a candidate that cannot move
//! the residual (its parameter unidentifiable, or no change in cost) is inert and not ranked.

use mech_codegen::ir::Dimension;

use mech_codegen::ir::transform::actuator::{
    BASE_COMPLIANCE, FORCE_FACTOR, STIFFNESS_FACTOR, TIP_MASS, TIP_PRELOAD,
};
use mech_codegen::ir::transform::hinge::{
    loop_flexures, twist_axes, twist_choice, MISALIGNMENT, OFF_AXIS_COMPLIANCE, TWIST_FACTOR,
};
use mech_codegen::ir::transform::{constant_direction, hinge_axis};
use mech_codegen::Compiled;
use serde::Serialize;

use super::data::MeasuredData;
use super::error::Error;
use super::experiment::Extensions;
use super::experiment::{Experiment, Kind};
use super::extend::Extension;
use super::fit::{fit_values, residual, Target};
use super::lm::{information_criteria, FitResult, NoiseModel, Parameter, Stall};
use crate::experiments::leg::{Leg, WarmStarts};
use mech_codegen::ir::transform::AXES;

/// Which rows are held out of the fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Holdout {
    /// Every `n`-th row (rows n−1, 2n−1, …).
    Every(usize),
    /// The last fraction of the rows (e.g. the top of a frequency band).
    Last(f64),
    /// Nothing: every value is fitted, and the ranking and the noise band use the fitted
    /// values' χ² (AICc penalizes the parameters). For a handful of summary values, such as
    /// a paper's table, where no value can be spared — the causes are then not tested on
    /// data their fit did not see.
    Nothing,
}

impl Holdout {
    /// `every:3`, `last:30%` or `none`.
    pub fn parse(text: &str) -> Result<Holdout, Error> {
        let bad = || Error::HoldoutSyntax {
            text: text.to_string(),
        };
        if text.trim() == "none" {
            return Ok(Holdout::Nothing);
        }
        match text.split_once(':') {
            Some(("every", n)) => match n.trim().parse::<usize>() {
                Ok(n) if n >= 2 => Ok(Holdout::Every(n)),
                _ => Err(bad()),
            },
            Some(("last", p)) => match p.trim().trim_end_matches('%').trim().parse::<f64>() {
                Ok(p) if p > 0.0 && p < 100.0 => Ok(Holdout::Last(p / 100.0)),
                _ => Err(bad()),
            },
            _ => Err(bad()),
        }
    }

    /// Whether data row `row` of `rows` is held out.
    pub fn holds_out(self, row: usize, rows: usize) -> bool {
        match self {
            Holdout::Every(n) => row % n == n - 1,
            Holdout::Last(fraction) => (row as f64) >= (1.0 - fraction) * rows as f64,
            Holdout::Nothing => false,
        }
    }
}

/// One candidate cause: what it is, where it acts, and the parameters it fits.
#[derive(Debug, Clone)]
pub struct Candidate {
    pub cause: String,
    pub location: String,
    pub parameters: Vec<(Target, Parameter)>,
    /// A change of the model's form, applied to its IR and re-derived before fitting (its new
    /// parameters come after the base model's, so `Target::Param` indices past the base
    /// model's refer to them).
    pub extension: Option<Extension>,
    /// How many of the last `parameters` support the cause rather than define it (e.g. the
    /// other hinges' off-axis stiffness that lets a twist act): the screen for inert
    /// candidates moves the defining ones only.
    pub supporting: usize,
    /// Whether the screen sets the supporting parameters to their upper bounds (a twist acts
    /// most where the other hinges give way most) rather than their starting values (a
    /// misalignment acts most where they are stiff).
    pub screen_at_upper: bool,
}

impl Candidate {
    fn defining(&self) -> &[(Target, Parameter)] {
        &self.parameters[..self.parameters.len() - self.supporting]
    }

    /// A change of parameters the model already has: no change of form, nothing supporting.
    fn parameter_change(
        cause: &str,
        location: String,
        parameters: Vec<(Target, Parameter)>,
    ) -> Candidate {
        Candidate {
            cause: cause.into(),
            location,
            parameters,
            extension: None,
            supporting: 0,
            screen_at_upper: false,
        }
    }

    /// A model-form extension fitted by its one new parameter alone.
    fn extended(
        cause: &str,
        location: String,
        parameter: (Target, Parameter),
        extension: Extension,
    ) -> Candidate {
        Candidate {
            extension: Some(extension),
            ..Candidate::parameter_change(cause, location, vec![parameter])
        }
    }
}

/// The catalog for `leg`'s model and the experiment (see the module comment): only causes
/// the experiment can show (a frequency-dependent loss factor needs a frequency response, an
/// off-axis load at the foot a force/deflection test).
pub fn catalog(leg: &Leg, experiment: &Experiment) -> Vec<Candidate> {
    let frequency_response = matches!(experiment.kind, Kind::FrequencyResponse(_));
    let mut out = parameter_candidates(leg, frequency_response);
    let off_axis_fraction = match &experiment.kind {
        Kind::ForceDeflection(test) => Some(test.off_axis_fraction),
        Kind::ForceDeflectionTable(table) => Some(table.off_axis_fraction),
        _ => None,
    };
    if let Some(fraction) = off_axis_fraction {
        out.push(Candidate::parameter_change(
            "unmodelled off-axis load at the foot",
            "foot (the sensor's y force)".into(),
            vec![(
                Target::OffAxisFraction,
                Parameter::new("off_axis_fraction", fraction)
                    .bounded(-1.0, 1.0)
                    .with_scale(0.1),
            )],
        ));
    }
    out.extend(modulus_candidates(leg));
    // A ring-down swings in the hinge's plane: no twist to excite.
    if !matches!(experiment.kind, Kind::Pendulum(_)) {
        out.extend(hinge_candidates(leg));
        out.extend(actuator_candidates(leg));
    }
    out
}

/// The candidates on the model's own parameters, by name: every torsional stiffness `k_*`
/// off by a factor, the loss factor `eta` (and, in a frequency response, its frequency
/// dependence), the actuator `preload`.
fn parameter_candidates(leg: &Leg, frequency_response: bool) -> Vec<Candidate> {
    let model = leg.model();
    let compiled = &leg.session.compiled.model;
    let mut out = Vec::new();
    for (index, (_, param)) in compiled.params.iter().enumerate() {
        let name = model.param_name(index);
        let value = model.param(index);
        if name.starts_with("k_") && param.dimension == Dimension::TORQUE && value > 0.0 {
            let location = format!("flexure {}", &name[2..]);
            out.push(stiffness_factor(location, index, name, value));
        } else if name == "eta" && value > 0.0 {
            out.extend(loss_factor_candidates(index, value, frequency_response));
        } else if name == "preload" {
            out.push(Candidate::parameter_change(
                "actuator tip preload",
                "both actuators".into(),
                vec![(Target::Param(index), preload(name, value))],
            ));
        }
    }
    out
}

/// A flexure's stiffness (parameter `index`, `name` = `value`) within a factor of 4 of the
/// model's.
fn stiffness_factor(location: String, index: usize, name: &str, value: f64) -> Candidate {
    Candidate::parameter_change(
        "flexure stiffness off by a factor",
        location,
        vec![(
            Target::Param(index),
            Parameter::new(name, value).bounded(value / 4.0, value * 4.0),
        )],
    )
}

/// An actuator's tip preload, up to ±200 µN.
fn preload(name: &str, value: f64) -> Parameter {
    Parameter::new(name, value)
        .bounded(-200e-6, 200e-6)
        .with_scale(50e-6)
}

/// The loss factor `eta` (parameter `index`) within a factor of 5, and in a frequency
/// response also the model-form extension η(f) = η·(f/f_ref)^α.
fn loss_factor_candidates(index: usize, value: f64, frequency_response: bool) -> Vec<Candidate> {
    let eta = Parameter::new("eta", value).bounded(value / 5.0, value * 5.0);
    let mut out = vec![Candidate::parameter_change(
        "loss factor differs",
        "all flexures".into(),
        vec![(Target::Param(index), eta.clone())],
    )];
    if frequency_response {
        out.push(Candidate::parameter_change(
            "frequency-dependent loss factor",
            "all flexures".into(),
            vec![
                (Target::Param(index), eta),
                (
                    Target::LossExponent,
                    Parameter::new("loss_exponent", 0.0)
                        .bounded(-1.5, 1.5)
                        .with_scale(1.0),
                ),
            ],
        ));
    }
    out
}

/// A flexure whose stiffness is E w h³/(12 l) of a material: the modulus stands for it.
fn modulus_candidates(leg: &Leg) -> Vec<Candidate> {
    let model = leg.model();
    super::pendulum::stiffness_moduli(leg)
        .into_iter()
        .map(|(index, flexures)| {
            let (name, value) = (model.param_name(index), model.param(index));
            let location = format!("flexure {} (modulus {name})", flexures.join(", "));
            stiffness_factor(location, index, name, value)
        })
        .collect()
}

/// Twist of each flexure hinge, and a tilt of its bending axis, about each coordinate axis of
/// its frame that is perpendicular to its bending axis (its length axis is one of them), Eq. 8's stiffness
/// times a fitted factor (`extend::Extension::Twist`). A twist in a closed loop can only act
/// as far as the other hinges give way off their axes, so their off-axis compliance (per unit
/// 1/k; `(t/w)²` for lateral bending, a geometry the model does not give) is fitted with it;
/// at its lower bound (10⁻⁶) the extension is the base model to ~0.1 % in the HAMR-VI swing
/// blocked force and ~1 % in the modes.
fn hinge_candidates(leg: &Leg) -> Vec<Candidate> {
    let model = &leg.session.compiled.model;
    let first_new = model.params.len();
    // From near the base model: a fit started where the hinges give way a lot can stall with
    // a resonance at the wrong place.
    let compliance = (
        Target::Param(first_new + 1),
        Parameter::new(OFF_AXIS_COMPLIANCE, 1e-5)
            .bounded(1e-6, 1e-2)
            .with_scale(1e-3),
    );
    let twist_factor = (
        Target::Param(first_new),
        // Eq. 8 within a factor of 2 either way: a plausible twist stiffness.
        Parameter::new(TWIST_FACTOR, 1.0).bounded(0.5, 2.0),
    );
    let mut out = Vec::new();
    // The hinges of one loop twisting together: a twist may need the loop's other hinges to
    // twist too (measured: four hinges of the spherical five-bar twisting, each about an
    // axis whose single twist the loop locks, came out "partly explained" by base compliance).
    // The trial searches their axes first ([`Trials::choose_twist_axes`]).
    let mut loops = loop_flexures(model);
    loops.sort();
    loops.dedup();
    for hinges in loops {
        let alignable = hinges.iter().all(|name| {
            model
                .flexures
                .iter()
                .find(|f| &f.name == name)
                .is_some_and(|f| twist_axes(model, f).is_some())
        });
        if hinges.len() < 2 || !alignable {
            continue;
        }
        let extension = Extension::TwistChoices(hinges);
        out.push(Candidate {
            cause: "flexure twist".into(),
            location: format!("the loop of flexures {}", extension.location()),
            parameters: vec![twist_factor.clone(), compliance.clone()],
            extension: Some(extension),
            supporting: 1,
            screen_at_upper: true,
        });
    }
    for flexure in model.flexures.iter() {
        let Some(axis) = hinge_axis(model, flexure.angle).and_then(|a| constant_direction(&a))
        else {
            continue;
        };
        for (index, name) in AXES.iter().enumerate() {
            // A coordinate axis within ~6° of perpendicular to the bending axis.
            if axis[index].abs() > 0.1 {
                continue;
            }
            out.push(Candidate {
                cause: "flexure twist".into(),
                location: format!("flexure {} about {name}", flexure.name),
                parameters: vec![twist_factor.clone(), compliance.clone()],
                extension: Some(Extension::Twist(vec![(flexure.name.clone(), index)])),
                supporting: 1,
                screen_at_upper: true,
            });
            out.push(Candidate {
                cause: "flexure axis misalignment".into(),
                location: format!("flexure {} tilted about {name}", flexure.name),
                parameters: vec![
                    (
                        Target::Param(first_new),
                        // Up to ~3° (a fabrication error of 50 µm over 1 mm). Not from 0:
                        // a tilt acts to second order (±α alike), so at 0 the fit has no
                        // gradient to follow.
                        Parameter::new(MISALIGNMENT, 0.01)
                            .bounded(-0.05, 0.05)
                            .with_scale(0.01),
                    ),
                    compliance.clone(),
                ],
                extension: Some(Extension::Misalignment {
                    flexure: flexure.name.clone(),
                    about: index,
                }),
                supporting: 1,
                screen_at_upper: false,
            });
        }
    }
    out
}

/// Per actuator (a slider coordinate with a force source): a compliant base in series (up to
/// twice the actuator's own compliance), its stiffness or its force off by a factor, and a
/// mass on its tip (up to 50 mg; a bimorph's
/// effective tip mass is about a quarter of its ~60 mg).
fn actuator_candidates(leg: &Leg) -> Vec<Candidate> {
    let model = &leg.session.compiled.model;
    let new_parameter = Target::Param(model.params.len());
    let mut out = Vec::new();
    // A model with its own `preload` parameter has that candidate already.
    let has_preload = model.params.iter().any(|(_, p)| p.name == "preload");
    let actuated = model
        .loads
        .iter()
        .any(|load| matches!(load, mech_codegen::ir::Load::GeneralizedForce { .. }));
    if actuated && !has_preload {
        out.push(Candidate::extended(
            "actuator tip preload",
            "every actuator".into(),
            (new_parameter, preload(TIP_PRELOAD, 0.0)),
            Extension::Preload,
        ));
    }
    for load in &model.loads {
        let mech_codegen::ir::Load::GeneralizedForce { coordinate, .. } = load else {
            continue;
        };
        let slider = model.coordinates[*coordinate].name.clone();
        let location = format!("actuator along {slider}");
        out.push(Candidate::extended(
            "actuator base compliance",
            location.clone(),
            (
                new_parameter,
                Parameter::new(BASE_COMPLIANCE, 0.0)
                    .bounded(0.0, 2.0)
                    .with_scale(0.1),
            ),
            Extension::BaseCompliance(slider.clone()),
        ));
        // ÷2 to ×2: a bimorph further off than that is another actuator.
        for (cause, name, extension) in [
            (
                "actuator stiffness off by a factor",
                STIFFNESS_FACTOR,
                Extension::ActuatorStiffness(slider.clone()),
            ),
            (
                "actuator force off by a factor",
                FORCE_FACTOR,
                Extension::ActuatorForce(slider.clone()),
            ),
        ] {
            out.push(Candidate::extended(
                cause,
                location.clone(),
                (
                    new_parameter,
                    Parameter::new(name, 1.0).bounded(0.5, 2.0).with_scale(0.1),
                ),
                extension,
            ));
        }
        out.push(Candidate::extended(
            "actuator tip mass",
            location,
            (
                new_parameter,
                Parameter::new(TIP_MASS, 0.0)
                    .bounded(0.0, 50e-6)
                    .with_scale(1e-5),
            ),
            Extension::TipMass(slider),
        ));
    }
    out
}

/// One fitted model (the base or a candidate) and how it does.
#[derive(Debug, Clone)]
pub struct Trial {
    pub cause: String,
    pub location: String,
    /// Fitted parameters: name, nominal, fitted value, standard error.
    pub parameters: Vec<(String, f64, f64, f64)>,
    /// χ² (or RSS without noise) on the fitted values and on the held-out ones.
    pub train_chi2: f64,
    pub holdout_chi2: f64,
    /// AICc on the training values.
    pub aicc: f64,
    /// Cannot change the response (reported, not ranked).
    pub inert: bool,
    /// The fit failed (reported, not ranked): the message of its [`Error`].
    pub error: Option<String>,
    /// The prediction of every observed value with the fitted parameters.
    pub predicted: Vec<f64>,
    /// The model-form change fitted (`None`: the model's own parameters only), to rebuild
    /// the extended model with `parameters` for other analyses.
    pub extension: Option<Extension>,
}

impl Trial {
    /// A fitted parameter ran into a bound of its plausible range (standard error NaN): the
    /// change the data ask for is outside the catalog's range, so the trial names no cause.
    pub fn at_bound(&self) -> bool {
        self.parameters.iter().any(|p| p.3.is_nan())
    }

    /// Every fitted parameter but those named in `except` is determined by the data: a
    /// finite standard error smaller than its value (two hinges in series fitted together,
    /// each `k ± 10⁵ k`, are not).
    fn determined_except(&self, except: &[&str]) -> bool {
        self.parameters
            .iter()
            .filter(|p| !except.contains(&p.0.as_str()))
            .all(|&(_, _, value, se)| se.is_finite() && se < value.abs())
    }
}

/// What `mech diagnose` concludes; in `diagnosis.json` by its snake_case name
/// (`no_significant_discrepancy`, `explained`, …).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The base model explains the held-out data to the noise.
    NoSignificantDiscrepancy,
    /// `ranked[0]` explains the data to the noise.
    Explained,
    /// `ranked[0]` helps significantly but a residual above the noise remains.
    PartlyExplained,
    /// No candidate helps significantly.
    Unexplained,
    /// Only candidates whose fit ran into a bound of its plausible range help: the cause is
    /// likely outside the catalog (or a nominal value is far off); the closest is reported,
    /// not named.
    OutsidePlausibleRange,
    /// The data show something no parameter of the model can produce (the screening's
    /// flags, e.g. a pendulum's amplitude-dependent damping): the candidates are fitted and
    /// reported, but no cause is named.
    Flagged,
}

#[derive(Debug, Clone)]
pub struct Diagnosis {
    pub base: Trial,
    /// Candidates that moved the residual, best first (lowest held-out χ²).
    pub ranked: Vec<Trial>,
    /// Two causes together, when the best alone leaves a residual above the noise and adding
    /// a second one improves significantly (the verdict then speaks of both).
    pub combined: Option<Trial>,
    /// The pairs tried for [`Diagnosis::combined`] (the best with each other ranked
    /// candidate), best first; empty when no second cause was sought.
    pub second_round: Vec<Trial>,
    /// Candidates that could not change the response, or whose fit failed.
    pub inert: Vec<Trial>,
    pub verdict: Verdict,
    /// Values held out of every fit (0 with `Holdout::Nothing`).
    pub holdout_values: usize,
    pub train_values: usize,
    /// The noise band: held-out χ² per value up to this is consistent with the noise.
    pub noise_band: f64,
    /// How many of `ranked`, from the top, the data support about equally (training AICc
    /// within 2 of the best's: Burnham & Anderson's "substantial support"), e.g. stiffness
    /// changes at flexures in series that one measurement cannot tell apart. 0 or 1: the
    /// top one stands alone.
    pub tied: usize,
    /// When the verdict names a tie: the standard tests that would tell the tied causes
    /// apart, best first ([`super::separate`]).
    pub separations: Vec<super::separate::Separation>,
    /// The measured values the trials predict.
    pub observations: super::experiment::Observations,
    /// The screening of the data before fitting (pendulum traces), with its flags.
    pub screening: Option<super::pendulum::Screening>,
    /// Per observed value: fitted (true) or held out (false).
    pub train: Vec<bool>,
}

impl Diagnosis {
    /// How many values the ranking χ² (`Trial::holdout_chi2`) is over: the held-out ones, or
    /// every fitted one when nothing is held out.
    pub fn ranking_values(&self) -> usize {
        if self.holdout_values == 0 {
            self.train_values
        } else {
            self.holdout_values
        }
    }
}

/// Runs the base model and every candidate (in parallel) on `data`.
pub fn diagnose(
    experiment: &Experiment,
    data: &MeasuredData,
    user_parameters: &[String],
    holdout: Holdout,
) -> Result<Diagnosis, Error> {
    diagnose_causes(experiment, data, user_parameters, holdout, &[])
}

/// [`diagnose`] with the catalog limited to the causes whose name contains one of `causes`
/// (`mech diagnose --cause twist`); empty: the whole catalog.
pub fn diagnose_causes(
    experiment: &Experiment,
    data: &MeasuredData,
    user_parameters: &[String],
    holdout: Holdout,
    causes: &[String],
) -> Result<Diagnosis, Error> {
    let spec = &experiment.model;
    let leg = Leg::open_any(spec, &[]).map_err(Error::leg)?;
    let observations = experiment.observations(&leg, data)?;
    let screening = experiment.screen(data)?;
    require_noise(&observations)?;
    let (train, train_values, holdout_values) = split_values(&observations, data.rows, holdout)?;
    let user = user_fit_parameters(&leg, user_parameters)?;
    let jobs = jobs(&leg, experiment, &user, causes)?;
    let mut trials = Trials {
        experiment,
        base: &leg.session.compiled,
        data,
        spec,
        user: &user,
        observations: &observations,
        train: &train,
        stall: None,
    };
    let mut jobs = jobs.into_iter();
    let base_job = jobs.next().expect("the base trial");
    let base = trials
        .fitted(&base_job)
        .map_err(|e| Error::BaseModel(Box::new(e)))?;
    // A candidate still short of one χ² unit below the base model after 10 iterations
    // stops there (it would be ranked inert: `sort_out`); the others fit to convergence.
    trials.stall = Some(Stall {
        iterations: 10,
        cost_above: 0.5 * (base.train_chi2 - 1.0),
    });
    let results = trials.run(jobs.collect()).into_iter();
    // With nothing held out, the fitted values rank and set the band.
    let band = NoiseBand::new(if holdout_values == 0 {
        train_values
    } else {
        holdout_values
    });
    let (ranked_pairs, inert) = sort_out(&base, results);
    let mut ranked_pairs = hold_undetermined(&trials, ranked_pairs);
    // A fit at a bound names no cause: those go after every other (stable: each group keeps
    // its held-out order), so the best named cause is the first.
    ranked_pairs.sort_by_key(|(_, trial)| trial.at_bound());
    // Without user parameters the base model is not fitted, so every value tests it (a
    // held-out subset alone may miss a narrow resonance).
    let base_consistent = if user.is_empty() && holdout_values > 0 {
        NoiseBand::new(train_values + holdout_values).holds_all(&base)
    } else {
        band.holds(&base)
    };
    let (second_round, combined) = if base_consistent {
        (Vec::new(), None)
    } else {
        second_cause(&trials, &band, &base, &ranked_pairs)
    };
    let flagged = screening.as_ref().is_some_and(|s| !s.flags.is_empty());
    let best = combined.as_ref().or(ranked_pairs
        .first()
        .map(|(_, t)| t)
        .filter(|t| !t.at_bound()));
    let beyond = ranked_pairs.iter().map(|(_, t)| t).find(|t| t.at_bound());
    let verdict = verdict(flagged, base_consistent, &band, &base, best, beyond);
    let tied = order_ties(&mut ranked_pairs);
    let named = matches!(verdict, Verdict::Explained | Verdict::PartlyExplained);
    let separations = if named && combined.is_none() && tied > 1 {
        trials.separations(&ranked_pairs[..tied])
    } else {
        Vec::new()
    };
    let ranked: Vec<Trial> = ranked_pairs.into_iter().map(|(_, t)| t).collect();
    Ok(Diagnosis {
        base,
        ranked,
        combined,
        second_round,
        inert,
        verdict,
        holdout_values,
        train_values,
        noise_band: band.per_value,
        tied,
        separations,
        observations,
        screening,
        train,
    })
}

/// Without noise levels no residual can be called significant.
fn require_noise(observations: &super::experiment::Observations) -> Result<(), Error> {
    match observations.sigma {
        Some(_) => Ok(()),
        None => Err(Error::NoNoise),
    }
}

/// Per observed value whether it is fitted (true) or held out, and how many of each (at
/// least 2 of each).
fn split_values(
    observations: &super::experiment::Observations,
    rows: usize,
    holdout: Holdout,
) -> Result<(Vec<bool>, usize, usize), Error> {
    let train: Vec<bool> = observations
        .row
        .iter()
        .map(|&row| !holdout.holds_out(row, rows))
        .collect();
    let holdout_values = train.iter().filter(|t| !**t).count();
    let train_values = train.len() - holdout_values;
    let too_few_held_out = holdout_values < 2 && holdout != Holdout::Nothing;
    if too_few_held_out || train_values < 2 {
        return Err(Error::HoldoutTooSmall {
            train: train_values,
            holdout: holdout_values,
        });
    }
    Ok((train, train_values, holdout_values))
}

/// The parameters the user fits with every candidate (`--fit NAME[=LO..HI UNIT]`).
fn user_fit_parameters(
    leg: &Leg,
    user_parameters: &[String],
) -> Result<Vec<(Target, Parameter)>, Error> {
    let requests = user_parameters
        .iter()
        .map(|t| super::fit::FitRequest::parse(t))
        .collect::<Result<Vec<_>, _>>()?;
    super::fit::parameters(leg, &requests)
}

/// The base model, then the catalog's candidates that `causes` asks for (all when empty)
/// and that fit no parameter the user fits already; an error names a wanted cause the
/// catalog does not have.
fn jobs(
    leg: &Leg,
    experiment: &Experiment,
    user: &[(Target, Parameter)],
    causes: &[String],
) -> Result<Vec<Candidate>, Error> {
    let mut jobs = vec![Candidate::parameter_change(
        "base model",
        "-".into(),
        Vec::new(),
    )];
    let catalog = catalog(leg, experiment);
    if let Some(unknown) = causes
        .iter()
        .find(|wanted| catalog.iter().all(|c| !c.cause.contains(wanted.as_str())))
    {
        let mut names: Vec<String> = catalog.iter().map(|c| c.cause.clone()).collect();
        names.dedup();
        return Err(Error::UnknownCause {
            cause: unknown.clone(),
            catalog: names,
        });
    }
    jobs.extend(catalog.into_iter().filter(|c| {
        // A candidate on a parameter the user already fits adds nothing.
        let fitted = c
            .parameters
            .iter()
            .any(|(i, _)| user.iter().any(|(u, _)| u == i));
        let wanted = causes.is_empty() || causes.iter().any(|w| c.cause.contains(w.as_str()));
        !fitted && wanted
    }));
    Ok(jobs)
}

/// The noise band over `m` values: a χ² per value up to `1 + 3·√(2/m)` is consistent with
/// the noise (χ²/m has mean 1 and standard deviation √(2/m)).
struct NoiseBand {
    values: f64,
    per_value: f64,
}

impl NoiseBand {
    fn new(m: usize) -> NoiseBand {
        let values = m as f64;
        NoiseBand {
            values,
            per_value: 1.0 + 3.0 * (2.0 / values).sqrt(),
        }
    }

    /// The held-out χ² of `trial` within the band.
    fn holds(&self, trial: &Trial) -> bool {
        trial.holdout_chi2 / self.values <= self.per_value
    }

    /// The χ² of `trial` on every value, fitted and held out, within the band.
    fn holds_all(&self, trial: &Trial) -> bool {
        (trial.train_chi2 + trial.holdout_chi2) / self.values <= self.per_value
    }
}

/// Significantly better than `than` (ΔAICc < −10: Burnham & Anderson's "essentially no
/// support" for the other) and better on the held-out data.
fn improves(trial: &Trial, than: &Trial) -> bool {
    than.aicc - trial.aicc > 10.0 && trial.holdout_chi2 < than.holdout_chi2
}

/// A second cause: when the best candidate improves on the base model but leaves a residual
/// above the noise, every other candidate that moved the residual is fitted together with it
/// (forward selection, one step). The pairs tried, best first, and the best pair if it
/// improves on the best alone.
fn second_cause(
    trials: &Trials,
    band: &NoiseBand,
    base: &Trial,
    ranked: &[(Candidate, Trial)],
) -> (Vec<Trial>, Option<Trial>) {
    let Some((best_candidate, best)) = ranked.first().filter(|(_, t)| !t.at_bound()) else {
        return (Vec::new(), None);
    };
    if !improves(best, base) || band.holds(best) {
        return (Vec::new(), None);
    }
    let jobs: Vec<Candidate> = ranked[1..]
        .iter()
        .filter_map(|(other, _)| combine(best_candidate, other))
        .collect();
    let (pairs, _) = sort_out(best, trials.run(jobs).into_iter());
    let second_round: Vec<Trial> = pairs.into_iter().map(|(_, t)| t).collect();
    // A second cause is a stronger claim than one: the parameters it adds must be determined
    // by the data (two hinges in series fit any split of one stiffness change). The first
    // cause's own may stay as loosely determined as they were alone (a twist's stiffness
    // factor trades off against the off-axis compliance).
    let first: Vec<&str> = best_candidate
        .parameters
        .iter()
        .map(|(_, p)| p.name.as_str())
        .collect();
    let combined = second_round
        .iter()
        .find(|t| t.determined_except(&first))
        .filter(|t| improves(t, best))
        .cloned();
    (second_round, combined)
}

/// The verdict from the screening's flags, the base model, the best trial that can name a
/// cause (a pair of causes when one was found, else the best alone) and the best whose fit
/// ran into a bound.
fn verdict(
    flagged: bool,
    base_consistent: bool,
    band: &NoiseBand,
    base: &Trial,
    best: Option<&Trial>,
    beyond: Option<&Trial>,
) -> Verdict {
    if flagged {
        Verdict::Flagged
    } else if base_consistent {
        Verdict::NoSignificantDiscrepancy
    } else {
        match best {
            Some(best) if improves(best, base) => {
                if band.holds(best) {
                    Verdict::Explained
                } else {
                    Verdict::PartlyExplained
                }
            }
            _ if beyond.is_some_and(|t| improves(t, base)) => Verdict::OutsidePlausibleRange,
            _ => Verdict::Unexplained,
        }
    }
}

/// How many candidates the data support about equally with the top of `ranked` (training
/// AICc within 2 of the best's or below it, none at a bound), moved to the front; among
/// those, on equal evidence, the simpler explanation (fewer fitted parameters) first. They
/// are gathered from the whole ranking, not only a run from the top: the held-out order of
/// candidates within the noise of each other is chance, and a worse-fitting candidate that
/// chance put second must not cut off a better one behind it.
fn order_ties(ranked: &mut [(Candidate, Trial)]) -> usize {
    let Some(best_aicc) = ranked
        .first()
        .filter(|(_, best)| !best.at_bound())
        .map(|(_, best)| best.aicc)
    else {
        return 0;
    };
    let supported =
        |t: &Trial| !t.at_bound() && ((t.aicc - best_aicc).abs() < 2.0 || t.aicc < best_aicc);
    // Stable: the tied keep their held-out order, and so do the others.
    ranked.sort_by_key(|(_, t)| !supported(t));
    let tied = ranked.iter().take_while(|(_, t)| supported(t)).count();
    // Held parameters (standard error 0) are not fitted: they do not count.
    ranked[..tied].sort_by_key(|(_, t)| t.parameters.iter().filter(|p| p.3 != 0.0).count());
    tied
}

/// A fit can run into a bound along a direction the data do not determine — two parameters
/// trading off, e.g. a twist's stiffness factor against the other hinges' off-axis
/// compliance (measured: the fb3 twist factor wandering to 0.5 or 2 at the same χ²) — rather
/// than because the data ask for a change beyond the range. Each trial at a bound that
/// would otherwise come before every trial inside its bounds (a lower AICc) is refitted
/// with its parameters at a bound held at their starting values; the refit replaces it
/// when its training χ² is less than 4 higher (the bound not supported at 2σ), the held
/// parameters then reported with standard error 0. Returned best first (held-out χ²).
fn hold_undetermined(
    trials: &Trials,
    mut ranked: Vec<(Candidate, Trial)>,
) -> Vec<(Candidate, Trial)> {
    let best_inside = ranked
        .iter()
        .filter(|(_, t)| !t.at_bound())
        .map(|(_, t)| t.aicc)
        .fold(f64::INFINITY, f64::min);
    let (indices, refits): (Vec<usize>, Vec<Candidate>) = ranked
        .iter()
        .enumerate()
        .filter(|(_, (_, t))| t.at_bound() && t.aicc < best_inside)
        .map(|(index, (candidate, trial))| (index, held_at_start(candidate, trial)))
        .unzip();
    for (index, (candidate, result)) in indices.into_iter().zip(trials.run(refits)) {
        let Ok(refit) = result else { continue };
        if !refit.inert && refit.train_chi2 - ranked[index].1.train_chi2 < 4.0 {
            ranked[index] = (candidate, refit);
        }
    }
    ranked.sort_by(|a, b| a.1.holdout_chi2.total_cmp(&b.1.holdout_chi2));
    ranked
}

/// `candidate` with the parameters `trial` left at a bound fixed at their starting values.
fn held_at_start(candidate: &Candidate, trial: &Trial) -> Candidate {
    let mut held = candidate.clone();
    for (_, parameter) in &mut held.parameters {
        let at_bound = trial
            .parameters
            .iter()
            .any(|(name, _, _, se)| *name == parameter.name && se.is_nan());
        if at_bound {
            parameter.lower = parameter.initial;
            parameter.upper = parameter.initial;
        }
    }
    held
}

/// A candidate and its trial, or why the trial failed.
type TrialResult = (Candidate, Result<Trial, Error>);

/// Splits trials into those that moved the residual (best first, lowest held-out χ²) and the
/// inert ones (no change beyond the noise, or a failed fit), compared with `reference`.
fn sort_out(
    reference: &Trial,
    trials: impl Iterator<Item = TrialResult>,
) -> (Vec<(Candidate, Trial)>, Vec<Trial>) {
    let mut ranked = Vec::new();
    let mut inert = Vec::new();
    for result in trials {
        let (candidate, trial) = result;
        let trial = trial.unwrap_or_else(|e| Trial {
            cause: candidate.cause.clone(),
            location: candidate.location.clone(),
            parameters: Vec::new(),
            train_chi2: f64::NAN,
            holdout_chi2: f64::NAN,
            aicc: f64::NAN,
            inert: true,
            error: Some(e.to_string()),
            predicted: Vec::new(),
            extension: candidate.extension.clone(),
        });
        // Fitting it must lower the training χ² by at least 1 (one σ² in total): a smaller
        // change is below what the noise (and the predictions' own ~1e-5 relative numerical
        // noise, from the finite-difference linearization) can resolve.
        let unchanged = reference.train_chi2 - trial.train_chi2 < 1.0;
        if trial.inert || trial.error.is_some() || unchanged {
            inert.push(Trial {
                inert: true,
                ..trial
            });
        } else {
            ranked.push((candidate, trial));
        }
    }
    ranked.sort_by(|a, b| a.1.holdout_chi2.total_cmp(&b.1.holdout_chi2));
    (ranked, inert)
}

/// `first` and `second` fitted together: their parameters (a target both fit counts once)
/// and the model-form extension of either. `None` when both change the model's form (their
/// new parameters would collide) or `second` adds nothing.
fn combine(first: &Candidate, second: &Candidate) -> Option<Candidate> {
    if first.extension.is_some() && second.extension.is_some() {
        return None;
    }
    let added: Vec<(Target, Parameter)> = second
        .parameters
        .iter()
        .filter(|(target, _)| first.parameters.iter().all(|(t, _)| t != target))
        .cloned()
        .collect();
    if added.is_empty() {
        return None;
    }
    let mut parameters = first.parameters.clone();
    parameters.extend(added);
    Some(Candidate {
        cause: format!("{} + {}", first.cause, second.cause),
        location: format!("{}; {}", first.location, second.location),
        parameters,
        extension: first.extension.clone().or_else(|| second.extension.clone()),
        // Combinations are not screened: each part moved the residual on its own.
        supporting: 0,
        screen_at_upper: false,
    })
}

/// What every trial of one diagnosis shares: the experiment and its data, the model spec,
/// the user's parameters, the observations and which of them are fitted.
struct Trials<'a> {
    experiment: &'a Experiment,
    /// The base model, compiled once: each candidate starts from a copy of it (a session
    /// holds a tape with scratch space, so each thread builds its own).
    base: &'a Compiled,
    data: &'a MeasuredData,
    spec: &'a crate::session::ModelSpec,
    user: &'a [(Target, Parameter)],
    observations: &'a super::experiment::Observations,
    train: &'a [bool],
    /// When a candidate's fit gives up ([`Stall`]); `None` for the base model's own fit.
    stall: Option<Stall>,
}

impl Trials<'_> {
    /// Every candidate's trial, in parallel, in the order given (`MECH_DIAGNOSE_TIMING` set:
    /// the time each took, on stderr).
    fn run(&self, jobs: Vec<Candidate>) -> Vec<TrialResult> {
        crate::parallel::parallel(jobs, crate::parallel::threads(), |candidate| {
            let started = std::time::Instant::now();
            let (candidate, trial) = self.trial(candidate);
            if std::env::var_os("MECH_DIAGNOSE_TIMING").is_some() {
                eprintln!(
                    "{:>8.2?}  {} at {}{}",
                    started.elapsed(),
                    candidate.cause,
                    candidate.location,
                    match &trial {
                        Ok(t) if t.inert && t.parameters.is_empty() => " (screened: inert)",
                        _ => "",
                    }
                );
            }
            (candidate, trial)
        })
    }

    /// `candidate` fitted with the user's parameters on the training values (or, when the
    /// screen finds it cannot move the predictions, not fitted and marked inert), and the
    /// candidate as fitted (a twist of a loop's hinges with the axes its search chose).
    fn trial(&self, candidate: Candidate) -> (Candidate, Result<Trial, Error>) {
        let candidate = match &candidate.extension {
            Some(Extension::TwistChoices(hinges)) => {
                match self.choose_twist_axes(&candidate, hinges) {
                    Ok(chosen) => chosen,
                    Err(error) => return (candidate, Err(error)),
                }
            }
            _ => candidate,
        };
        let trial = self.fitted(&candidate);
        (candidate, trial)
    }

    /// The twist of `hinges` (one loop's) about the axes that fit the training values best
    /// at the candidate's starting values: every assignment of each hinge's two possible
    /// length axes tried on one derivation ([`hinge::twist_choices`]), 2ⁿ predictions.
    fn choose_twist_axes(
        &self,
        candidate: &Candidate,
        hinges: &[String],
    ) -> Result<Candidate, Error> {
        let extension = candidate.extension.as_ref().expect("a twist search");
        let mut leg = super::extend::extend_leg(self.base, self.spec, extension)?;
        let choices: Vec<usize> = hinges
            .iter()
            .map(|name| {
                leg.model()
                    .param_index(&twist_choice(name))
                    .expect("appended by the search")
            })
            .collect();
        let mut extensions = Extensions::default();
        for (target, parameter) in self.user.iter().chain(&candidate.parameters) {
            target.apply(&mut leg, &mut extensions, parameter.initial);
        }
        let mut warm = WarmStarts::default();
        let mut best: Option<(f64, usize)> = None;
        for assignment in 0..1usize << hinges.len() {
            for (bit, &index) in choices.iter().enumerate() {
                let value = ((assignment >> bit) & 1) as f64;
                Target::Param(index).apply(&mut leg, &mut extensions, value);
            }
            let Ok(predicted) = self.experiment.predict_warm(
                &leg,
                self.data,
                self.observations,
                &extensions,
                &mut warm,
            ) else {
                continue;
            };
            let chi2 = self.chi2(&predicted, true);
            if best.is_none_or(|(lowest, _)| chi2 < lowest) {
                best = Some((chi2, assignment));
            }
        }
        let (_, assignment) = best.ok_or_else(|| Error::NoTwistAxes {
            hinges: hinges.join(", "),
        })?;
        let model = &leg.session.compiled.model;
        let twisting: Vec<(String, usize)> = hinges
            .iter()
            .enumerate()
            .map(|(bit, name)| {
                let flexure = model.flexures.iter().find(|f| &f.name == name);
                let axes = flexure
                    .and_then(|f| twist_axes(model, f))
                    .expect("checked by the catalog");
                (name.clone(), axes[(assignment >> bit) & 1])
            })
            .collect();
        let extension = Extension::Twist(twisting);
        Ok(Candidate {
            location: format!("the loop of flexures {}", extension.location()),
            extension: Some(extension),
            ..candidate.clone()
        })
    }

    /// The separations of the tied `candidates` ([`super::separate::separations`]), each
    /// model with its fitted values; empty when one cannot be built.
    fn separations(&self, tied: &[(Candidate, Trial)]) -> Vec<super::separate::Separation> {
        let legs: Option<Vec<(Leg, Extensions)>> = tied
            .iter()
            .map(|(candidate, trial)| {
                let mut leg = match &candidate.extension {
                    Some(extension) => super::extend::extend_leg(self.base, self.spec, extension),
                    None => super::extend::base_leg(self.base, self.spec),
                }
                .ok()?;
                let mut extensions = Extensions::default();
                for (target, parameter) in self.user.iter().chain(&candidate.parameters) {
                    let fitted = trial.parameters.iter().find(|p| p.0 == parameter.name);
                    let value = fitted.map_or(parameter.initial, |p| p.2);
                    target.apply(&mut leg, &mut extensions, value);
                }
                Some((leg, extensions))
            })
            .collect();
        legs.map_or_else(Vec::new, |legs| {
            super::separate::separations(self.spec, &legs)
        })
    }

    /// [`Trials::trial`] of a candidate whose model form is known.
    fn fitted(&self, candidate: &Candidate) -> Result<Trial, Error> {
        let (experiment, data, observations) = (self.experiment, self.data, self.observations);
        let mut leg = match &candidate.extension {
            Some(extension) => super::extend::extend_leg(self.base, self.spec, extension),
            None => super::extend::base_leg(self.base, self.spec),
        }?;
        let mut parameters = self.user.to_vec();
        parameters.extend(candidate.parameters.iter().cloned());
        // A candidate holding parameters fixed is a refit of one that moved the residual
        // ([`hold_undetermined`]): not screened again.
        let refit = candidate.parameters.iter().any(|(_, p)| p.is_fixed());
        let free = parameters.iter().filter(|(_, p)| !p.is_fixed()).count();
        let unmoved = if refit {
            None
        } else {
            cannot_move(
                experiment,
                data,
                &mut leg,
                candidate,
                self.user,
                observations,
            )
        };
        if let Some(predicted) = unmoved {
            let mut trial = self.judge(candidate, predicted, free);
            trial.inert = true;
            return Ok(trial);
        }
        let (predicted, fitted) = if parameters.is_empty() {
            let predicted = experiment.predict(&leg, data, observations, &Extensions::default())?;
            (predicted, None)
        } else {
            let report = fit_values(
                experiment,
                data,
                &mut leg,
                &parameters,
                observations.clone(),
                self.train,
                self.stall,
            )?;
            (report.after, Some(report.result))
        };
        let mut trial = self.judge(candidate, predicted, free);
        if let (Some(result), Some(_)) = (&fitted, std::env::var_os("MECH_DIAGNOSE_TIMING")) {
            eprintln!(
                "          fit of {} at {}: {} iterations, {} evaluations, {:?}",
                candidate.cause,
                candidate.location,
                result.iterations,
                result.evaluations,
                result.reason
            );
        }
        if let Some(result) = &fitted {
            trial.inert = all_unidentifiable(candidate, result);
            trial.parameters = parameters
                .iter()
                .filter_map(|(_, p)| {
                    result
                        .parameter(&p.name)
                        .map(|(value, se)| (p.name.clone(), p.initial, value, se))
                })
                .collect();
        }
        Ok(trial)
    }

    /// χ² of `predicted` on the fitted values (`fitted`) or on the held-out ones.
    fn chi2(&self, predicted: &[f64], fitted: bool) -> f64 {
        residual(predicted, self.observations)
            .iter()
            .zip(self.train)
            .filter(|(_, &t)| t == fitted)
            .map(|(r, _)| r * r)
            .sum()
    }

    /// The trial of `candidate` predicting `predicted` with `k` fitted parameters: χ² on the
    /// fitted and the held-out values, and the training AICc (no parameters listed yet).
    fn judge(&self, candidate: &Candidate, predicted: Vec<f64>, k: usize) -> Trial {
        let train_chi2 = self.chi2(&predicted, true);
        // Nothing held out (`Holdout::Nothing`): the fitted values rank.
        let holdout_chi2 = if self.train.iter().all(|t| *t) {
            train_chi2
        } else {
            self.chi2(&predicted, false)
        };
        let m = self.train.iter().filter(|t| **t).count();
        let aicc = information_criteria(train_chi2 / 2.0, m, k, NoiseModel::Normalized).aicc;
        Trial {
            cause: candidate.cause.clone(),
            location: candidate.location.clone(),
            parameters: Vec::new(),
            train_chi2,
            holdout_chi2,
            aicc,
            inert: false,
            error: None,
            predicted,
            extension: candidate.extension.clone(),
        }
    }
}

/// Whether the fit flagged every one of the candidate's own parameters unidentifiable (it
/// cannot move the residual).
fn all_unidentifiable(candidate: &Candidate, result: &FitResult) -> bool {
    let flagged = result.unidentifiable();
    !candidate.parameters.is_empty()
        && candidate
            .parameters
            .iter()
            .all(|(_, p)| flagged.contains(&p.name.as_str()))
}

/// Screens a candidate before fitting it: moving each of its defining parameters alone to
/// either bound (the others at their starting values, the supporting ones at their starting
/// values or, with `screen_at_upper`, their upper bounds) changes the predictions by less
/// than the noise, Σ((Δ prediction)/σ)² < 1 — it cannot change the response (e.g. a twist the other
/// hinges lock). Returns the predictions at the starting values then; `None` when the
/// candidate moves them, a prediction fails, or there is no noise level to compare with.
fn cannot_move(
    experiment: &Experiment,
    data: &MeasuredData,
    leg: &mut Leg,
    candidate: &Candidate,
    user: &[(Target, Parameter)],
    observations: &super::experiment::Observations,
) -> Option<Vec<f64>> {
    let sigma = observations.sigma.as_ref()?;
    if candidate.parameters.is_empty() {
        return None;
    }
    let supporting = &candidate.parameters[candidate.parameters.len() - candidate.supporting..];
    let mut extensions = Extensions::default();
    for (target, parameter) in user.iter().chain(&candidate.parameters) {
        target.apply(leg, &mut extensions, parameter.initial);
    }
    // Every moved prediction starts its equilibria from the reference's: for an inert
    // candidate (most of them) they hardly move.
    let mut warm = WarmStarts::default();
    let at_start = experiment
        .predict_warm(leg, data, observations, &extensions, &mut warm)
        .ok()?;
    let reference = if candidate.screen_at_upper && !supporting.is_empty() {
        for (target, parameter) in supporting {
            target.apply(leg, &mut extensions, parameter.upper);
        }
        experiment
            .predict_warm(leg, data, observations, &extensions, &mut warm)
            .ok()?
    } else {
        at_start.clone()
    };
    for (target, parameter) in candidate.defining() {
        for bound in [parameter.lower, parameter.upper] {
            if !bound.is_finite() {
                return None;
            }
            target.apply(leg, &mut extensions, bound);
            let moved = experiment
                .predict_warm(leg, data, observations, &extensions, &mut warm.clone())
                .ok()?;
            let change: f64 = moved
                .iter()
                .zip(&reference)
                .zip(sigma)
                .map(|((a, b), s)| ((a - b) / s).powi(2))
                .sum();
            if change >= 1.0 {
                return None;
            }
        }
        target.apply(leg, &mut extensions, parameter.initial);
    }
    Some(at_start)
}
