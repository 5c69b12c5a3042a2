//! From analysed traces to flexure constants (seed Sec. IV.A–B): per trace the measured
//! stiffness and damping (Eqs. 3–4), per specimen the mean over its trials, and across a set
//! of uncastellated flexures the normalized fits for Young's modulus (Eq. 6) and the loss
//! factor (Eq. 7); for castellated hinges of one thickness and length, the effective length
//! and their own loss factor.
//!
//! Consumes: specimen files, [`Specimen`]s (and reads their traces) or analysed traces.
//! Produces: a [`FitReport`] of the good traces and specimens, each trace screened
//! ([`super::screen`]), with every rejected trace or file (an [`Error`] naming it), the loss
//! factor's frequency dependence across the set ([`LossFrequencyFit`]) and the findings, each
//! named by its kind: the traces' screening flags, a poor decay fit, trials that disagree
//! beyond their uncertainties, a loss factor that depends on frequency, a poor line across
//! flexures. One bad trace does not stop the others.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::error::Error;
use super::rig::{Kind, Pendulum, Specimen};
use super::screen::{screen_analysis, Flag, ScreenOptions, Screening, FLAG_SIGMA};
use super::trace::{analyze_trace, TraceAnalysis, TraceOptions};
use crate::diagnose::lm::{levenberg_marquardt, LmOptions, Parameter};

/// Options of the fits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// Trace analysis options.
    pub trace: TraceOptions,
    /// Use Eq. 4 literally (`k_m = I_p ω_n² − m g L_cm`), without the finite-amplitude
    /// correction of the gravity stiffness (see [`measured_stiffness`]); the screening then
    /// allows the frequency any gravity softening from none to the largest.
    pub small_angle: bool,
    /// Young's modulus for the castellated fits (Pa); default: the uncastellated fit's, or
    /// Kapton's 2.56 GPa if there are no uncastellated specimens.
    pub modulus: Option<f64>,
    /// Plausible Young's modulus (Pa): an uncastellated fit outside it is rejected. Default
    /// [`PLAUSIBLE_MODULUS`].
    pub modulus_range: (f64, f64),
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            trace: TraceOptions::default(),
            small_angle: false,
            modulus: None,
            modulus_range: PLAUSIBLE_MODULUS,
        }
    }
}

/// A factor 10 either side of Kapton's 2.56 GPa: polymer films (2–10 GPa) pass; a
/// thickness in the wrong unit (it enters cubed) or degrees read as radians do not.
pub const PLAUSIBLE_MODULUS: (f64, f64) = (0.256e9, 25.6e9);

/// Below this weighted R² of its `ln A` fit a trace's decay is not exponential (the R² of
/// the test's synthetic traces with 0.05° noise is above 0.9999).
pub const POOR_DECAY_R2: f64 = 0.99;

/// Two trials of a flexure disagree when their k_m or b_m differ by more than this many
/// combined standard errors.
pub const AGREEMENT_SIGMA: f64 = 4.0;

/// Below this R² a line across flexures is reported as poor (the seed's real data gave
/// 0.83–0.97).
pub const POOR_LINE_R2: f64 = 0.8;

/// The smallest exponent α of `η(f) = η₀ (f/f₀)^α` worth finding: η changing by 26 % per
/// decade of frequency (HAMR's hinges work from 1 to 150 Hz, over which it would change by
/// 65 %).
pub const SMALLEST_LOSS_EXPONENT: f64 = 0.1;

/// A data set resolves the loss factor's frequency dependence when the standard error of α
/// is at most this: α = [`SMALLEST_LOSS_EXPONENT`] then lies 4.78σ from 0, so it is flagged
/// beyond [`FLAG_SIGMA`] with 90 % probability (3.5σ + 1.28σ, the normal 90 % quantile).
pub const LOSS_EXPONENT_RESOLUTION: f64 = SMALLEST_LOSS_EXPONENT / (FLAG_SIGMA + 1.2816);
/// Eq. 3: `b_m = 2 ζ ω_n I_p` (= 2 σ I_p), N·m·s/rad.
pub fn measured_damping(analysis: &TraceAnalysis, pendulum: &Pendulum) -> f64 {
    2.0 * analysis.zeta * analysis.omega_n * pendulum.inertia
}

/// Eq. 4: `k_m = I_p ω_n² − m g L_cm`, N·m/rad. The hanging pendulum's gravity stiffness
/// `m g L_cm` is subtracted: linearized, `I_p θ̈ + b θ̇ + (k + m g L_cm) θ = 0`.
///
/// Unless `small_angle`, the gravity term is multiplied by the trace's
/// [`TraceAnalysis::gravity_softening`] `⟨2J₁(A)/A⟩ ≈ 1 − ⟨A²⟩/8`: at amplitude A the
/// pendulum's `m g L_cm sin θ` is softer than `m g L_cm θ`, which lowers ω_d by up to 0.4 %
/// of the gravity share at 15°. The flexure's own stiffness is linear.
pub fn measured_stiffness(analysis: &TraceAnalysis, pendulum: &Pendulum, small_angle: bool) -> f64 {
    let softening = if small_angle {
        1.0
    } else {
        analysis.gravity_softening
    };
    pendulum.inertia * analysis.omega_n.powi(2) - pendulum.gravity_stiffness() * softening
}

/// One analysed trace.
#[derive(Debug, Clone, PartialEq)]
pub struct TraceResult {
    /// The CSV file.
    pub file: PathBuf,
    /// Frequency and decay.
    pub analysis: TraceAnalysis,
    /// Measured stiffness k_m (N·m/rad), Eq. 4.
    pub stiffness: f64,
    /// Measured damping b_m (N·m·s/rad), Eq. 3.
    pub damping: f64,
    /// Standard errors of k_m and b_m from those of ω_d and σ (N·m/rad, N·m·s/rad).
    pub stiffness_se: f64,
    pub damping_se: f64,
    /// The screening for amplitude-dependent damping and frequency, offset and drift, with
    /// the pendulum's gravity share known.
    pub screening: Screening,
}

impl TraceResult {
    /// The loss factor `η = b_m ω_d / k_m` (Eq. 5 at the trace's frequency) and its standard
    /// error.
    pub fn loss_factor(&self) -> (f64, f64) {
        let eta = self.damping * self.analysis.omega_d / self.stiffness;
        let relative = ((self.damping_se / self.damping).powi(2)
            + (self.stiffness_se / self.stiffness).powi(2))
        .sqrt();
        (eta, eta * relative)
    }
}

/// One specimen: its traces and their means (the seed averages the trials of a flexure).
#[derive(Debug, Clone, PartialEq)]
pub struct SpecimenResult {
    /// The specimen description.
    pub specimen: Specimen,
    /// Its traces.
    pub traces: Vec<TraceResult>,
    /// Mean k_m (N·m/rad).
    pub stiffness: f64,
    /// Mean b_m (N·m·s/rad).
    pub damping: f64,
    /// Mean ω_d (rad/s).
    pub omega_d: f64,
    /// Mean of b_m·ω_d (N·m).
    pub damping_times_omega: f64,
}

impl SpecimenResult {
    /// Eq. 6: `y = 12 l k_m / t³` (N/m = Pa·m), with the nominal length.
    pub fn normalized_stiffness(&self) -> f64 {
        let f = &self.specimen.flexure;
        12.0 * f.length * self.stiffness / f.thickness.powi(3)
    }

    /// Eq. 7: `z = 12 l ω_d b_m / t³` (Pa·m), with the nominal length.
    pub fn normalized_damping(&self) -> f64 {
        let f = &self.specimen.flexure;
        12.0 * f.length * self.damping_times_omega / f.thickness.powi(3)
    }
}

/// A least squares line through the origin, `y = slope · x`, with
/// `R² = 1 − Σ(y − slope·x)² / Σ(y − ȳ)²`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineFit {
    /// Fitted slope.
    pub slope: f64,
    /// Coefficient of determination.
    pub r_squared: f64,
    /// Number of points.
    pub points: usize,
}

/// Fits `y = slope · x` by least squares.
pub fn fit_through_origin(xs: &[f64], ys: &[f64]) -> LineFit {
    let sxx: f64 = xs.iter().map(|x| x * x).sum();
    let sxy: f64 = xs.iter().zip(ys).map(|(x, y)| x * y).sum();
    let slope = sxy / sxx;
    let n = ys.len() as f64;
    let mean = ys.iter().sum::<f64>() / n;
    let ss_tot: f64 = ys.iter().map(|y| (y - mean).powi(2)).sum();
    let ss_res: f64 = xs
        .iter()
        .zip(ys)
        .map(|(x, y)| (y - slope * x).powi(2))
        .sum();
    let r_squared = if ss_tot > 0.0 {
        1.0 - ss_res / ss_tot
    } else if ss_res == 0.0 {
        1.0
    } else {
        f64::NAN
    };
    LineFit {
        slope,
        r_squared,
        points: ys.len(),
    }
}

/// The fits across uncastellated flexures (seed Fig. 5 a, b).
#[derive(Debug, Clone, PartialEq)]
pub struct ModulusFit {
    /// Eq. 6 data against width: slope = Young's modulus (Pa).
    pub stiffness_line: LineFit,
    /// Eq. 7 data against width: slope = η E (Pa).
    pub damping_line: LineFit,
    /// Young's modulus (E_k)_m (Pa).
    pub youngs_modulus: f64,
    /// Loss factor η_m = slope of Eq. 7 / (E_k)_m.
    pub loss_factor: f64,
    /// Indices (into the specimen results) of the specimens used.
    pub specimens: Vec<usize>,
}

/// The fits for castellated hinges of one thickness and nominal length (seed Fig. 5 c, d).
#[derive(Debug, Clone, PartialEq)]
pub struct CastellatedFit {
    /// Thickness t (m).
    pub thickness: f64,
    /// Nominal length l (m).
    pub length: f64,
    /// k_m against width: slope = E t³ / (12 l_eff) (N·m/rad per m).
    pub stiffness_line: LineFit,
    /// b_m ω_d against width: slope = η' E t³ / (12 l_eff) (N·m per m).
    pub damping_line: LineFit,
    /// Modulus used to convert the slope to a length (Pa).
    pub youngs_modulus: f64,
    /// Effective length l_eff = E t³ / (12 · slope) (m), Eq. 2.
    pub effective_length: f64,
    /// Loss factor η' = damping slope / stiffness slope, Eq. 5.
    pub loss_factor: f64,
    /// Indices of the specimens used.
    pub specimens: Vec<usize>,
}

/// Everything `mech flexure fit` computes.
#[derive(Debug, Clone, PartialEq)]
pub struct FitReport {
    /// Per specimen (and per trace) results, in input order.
    pub specimens: Vec<SpecimenResult>,
    /// The uncastellated fit, if there are at least two uncastellated specimens.
    pub uncastellated: Option<ModulusFit>,
    /// One fit per (thickness, length) group of castellated specimens with ≥ 2 members.
    pub castellated: Vec<CastellatedFit>,
    /// The loss factor against frequency across the set, if it has enough hinges.
    pub loss_frequency: Option<LossFrequencyFit>,
    /// Every trace, specimen file or fit rejected, each naming its file.
    pub rejected: Vec<Error>,
    /// What was fitted but deserves a look, each with its kind and naming its files: the
    /// traces' screening flags, `poor_decay_fit`, `trial_disagreement`,
    /// `frequency_dependent_loss`, `poor_line_fit`.
    pub findings: Vec<Flag>,
    /// Traces read (accepted and rejected).
    pub traces: usize,
}

impl FitReport {
    /// `Err` listing every problem if anything was rejected (the fits of the rest stand).
    pub fn problems(&self) -> Result<(), Error> {
        if self.rejected.is_empty() {
            Ok(())
        } else {
            Err(Error::Rejected {
                problems: self.rejected.clone(),
                traces: self.traces,
            })
        }
    }
}

/// Analyses one trace of `specimen`.
pub fn analyze_specimen_trace(
    times: &[f64],
    angles: &[f64],
    pendulum: &Pendulum,
    file: PathBuf,
    options: &FitOptions,
) -> Result<TraceResult, Error> {
    let analysis = match analyze_trace(times, angles, &options.trace) {
        Ok(analysis) => analysis,
        Err(error) => return Err(Error::Trace { path: file, error }),
    };
    let stiffness = measured_stiffness(&analysis, pendulum, options.small_angle);
    if stiffness.is_nan() || stiffness <= 0.0 {
        let total = pendulum.inertia * analysis.omega_n.powi(2);
        return Err(Error::NonPositiveStiffness {
            path: file,
            total,
            gravity: total - stiffness,
        });
    }
    // With `small_angle` the traces are taken as those of the linearized rig, whose gravity
    // does not soften: the screening then allows any share, linear gravity (0) included.
    let gravity_share =
        pendulum.gravity_stiffness() / (pendulum.inertia * analysis.omega_n.powi(2));
    let screen_options = ScreenOptions {
        gravity_share: (!options.small_angle).then_some(gravity_share),
    };
    let screening = screen_analysis(times, angles, &analysis, &screen_options);
    // k_m = I_p (σ² + ω_d²) − …, b_m = 2 I_p σ; ω_d and σ come from separate fits.
    let i2 = 2.0 * pendulum.inertia;
    let stiffness_se = i2
        * ((analysis.sigma * analysis.sigma_se).powi(2)
            + (analysis.omega_d * analysis.omega_d_se).powi(2))
        .sqrt();
    Ok(TraceResult {
        stiffness,
        damping: measured_damping(&analysis, pendulum),
        stiffness_se,
        damping_se: i2 * analysis.sigma_se,
        screening,
        file,
        analysis,
    })
}

/// Averages a specimen's trace results.
pub fn specimen_result(specimen: Specimen, traces: Vec<TraceResult>) -> SpecimenResult {
    let n = traces.len() as f64;
    let mean = |f: &dyn Fn(&TraceResult) -> f64| traces.iter().map(f).sum::<f64>() / n;
    SpecimenResult {
        stiffness: mean(&|t| t.stiffness),
        damping: mean(&|t| t.damping),
        omega_d: mean(&|t| t.analysis.omega_d),
        damping_times_omega: mean(&|t| t.damping * t.analysis.omega_d),
        specimen,
        traces,
    }
}

/// Reads every specimen file and fits its traces ([`fit_specimens`]); a file that cannot be
/// read is listed among the rejected, before the traces' problems.
pub fn fit_files(files: &[PathBuf], options: &FitOptions) -> FitReport {
    let mut rejected = Vec::new();
    let mut specimens = Vec::new();
    for file in files {
        match super::rig::read_specimen(file) {
            Ok(specimen) => specimens.push(specimen),
            Err(error) => rejected.push(error),
        }
    }
    let mut report = fit_specimens(specimens, options);
    rejected.append(&mut report.rejected);
    report.rejected = rejected;
    report
}

/// Reads and analyses every trace of `specimens` and fits across them. A trace that cannot
/// be used is listed in [`FitReport::rejected`]; a specimen is fitted from its good traces,
/// and left out if it has none.
pub fn fit_specimens(specimens: Vec<Specimen>, options: &FitOptions) -> FitReport {
    let mut rejected = Vec::new();
    let mut results = Vec::new();
    let mut count = 0;
    for specimen in specimens {
        let mut traces = Vec::new();
        for file in &specimen.traces {
            count += 1;
            match analyze_file(&specimen, file, options) {
                Ok(trace) => traces.push(trace),
                Err(error) => rejected.push(error),
            }
        }
        if !traces.is_empty() {
            results.push(specimen_result(specimen, traces));
        }
    }
    let mut report = fit_results(results, options);
    rejected.append(&mut report.rejected);
    report.rejected = rejected;
    report.traces = count;
    report
}

fn analyze_file(
    specimen: &Specimen,
    file: &Path,
    options: &FitOptions,
) -> Result<TraceResult, Error> {
    let trace = super::rig::read_trace(specimen, file)?;
    analyze_specimen_trace(
        &trace.times,
        &trace.angles,
        &specimen.pendulum,
        file.to_path_buf(),
        options,
    )
}

/// Findings on the analysed traces: their screening flags, a poor decay fit, and trials of
/// one specimen that disagree beyond their standard errors.
fn trace_findings(specimens: &[SpecimenResult]) -> Vec<Flag> {
    let mut findings = Vec::new();
    for sr in specimens {
        for t in &sr.traces {
            findings.extend(t.screening.flags.iter().map(|flag| Flag {
                kind: flag.kind,
                message: format!("`{}`: {}", t.file.display(), flag.message),
            }));
            if t.analysis.log_fit_r2 < POOR_DECAY_R2 {
                findings.push(Flag {
                    kind: "poor_decay_fit",
                    message: format!(
                        "`{}`: the decay is not exponential (R² of ln A against time {:.4} < \
                         {POOR_DECAY_R2}, {} peaks): damping that depends on the amplitude, a \
                         drifting baseline or a disturbance",
                        t.file.display(),
                        t.analysis.log_fit_r2,
                        t.analysis.peaks.len()
                    ),
                });
            }
        }
        for (i, a) in sr.traces.iter().enumerate() {
            for b in &sr.traces[i + 1..] {
                if let Some(finding) = trial_disagreement(&sr.specimen.name, a, b) {
                    findings.push(finding);
                }
            }
        }
    }
    findings
}

/// Two trials of one flexure whose k_m or b_m differ by more than [`AGREEMENT_SIGMA`]
/// combined standard errors (each from its trace's scatter, so the noise sets the scale).
fn trial_disagreement(specimen: &str, a: &TraceResult, b: &TraceResult) -> Option<Flag> {
    let quantities = [
        (
            "k_m",
            a.stiffness,
            a.stiffness_se,
            b.stiffness,
            b.stiffness_se,
            1e6,
            "µN·m/rad",
        ),
        (
            "b_m",
            a.damping,
            a.damping_se,
            b.damping,
            b.damping_se,
            1e9,
            "nN·m·s/rad",
        ),
    ];
    let parts: Vec<String> = quantities
        .into_iter()
        .filter_map(|(name, va, sa, vb, sb, scale, unit)| {
            let z = (va - vb).abs() / (sa * sa + sb * sb).sqrt();
            (z > AGREEMENT_SIGMA).then(|| {
                format!(
                    "{name} {:.4} ± {:.4} and {:.4} ± {:.4} {unit} ({:+.2} %, {z:.1} standard \
                     errors apart)",
                    va * scale,
                    sa * scale,
                    vb * scale,
                    sb * scale,
                    100.0 * (vb - va) / va
                )
            })
        })
        .collect();
    (!parts.is_empty()).then(|| Flag {
        kind: "trial_disagreement",
        message: format!(
            "{specimen}: trials `{}` and `{}` disagree beyond their noise (more than \
             {AGREEMENT_SIGMA} standard errors) on {}; the mean hides it: the flexure or its \
             clamp changed between them",
            a.file.display(),
            b.file.display(),
            parts.join(" and ")
        ),
    })
}

/// The loss factor against frequency across a data set, `ln η_i = ln η₀,c + α ln(f_i/f₀)`:
/// one exponent α for the set, one level per kind of hinge (castellated hinges lose more,
/// seed Sec. IV.B), weighted least squares on the hinges' `ln η` (the mean of their trials)
/// with their standard errors, which the scatter widens when it exceeds them.
#[derive(Debug, Clone, PartialEq)]
pub struct LossFrequencyFit {
    /// α and its standard error.
    pub exponent: (f64, f64),
    /// η₀ of each kind present at f₀, with its standard error.
    pub levels: Vec<(Kind, f64, f64)>,
    /// f₀, the geometric mean of the hinges' frequencies (Hz).
    pub reference_frequency: f64,
    /// Lowest and highest hinge frequency (Hz).
    pub frequencies: (f64, f64),
    /// Hinges used.
    pub points: usize,
    /// `χ²/dof` of the fit with the hinges' own standard errors.
    pub chi2_dof: f64,
}

impl LossFrequencyFit {
    /// Whether the set resolves α: its standard error is at most
    /// [`LOSS_EXPONENT_RESOLUTION`].
    pub fn resolved(&self) -> bool {
        self.exponent.1 <= LOSS_EXPONENT_RESOLUTION
    }

    /// α in standard errors.
    pub fn exponent_sigma(&self) -> f64 {
        self.exponent.0 / self.exponent.1
    }
}

/// Fits [`LossFrequencyFit`] to the specimens; `None` with fewer than two hinges beyond the
/// fit's coefficients (its scatter could not be measured).
pub fn fit_loss_frequency(specimens: &[SpecimenResult]) -> Option<LossFrequencyFit> {
    let mut kinds: Vec<Kind> = specimens.iter().map(|s| s.specimen.flexure.kind).collect();
    kinds.sort_by_key(|k| *k == Kind::Castellated);
    kinds.dedup();
    // Per hinge: ln f, ln η, its standard error, its kind's index.
    let hinges: Vec<(f64, f64, f64, usize)> = specimens
        .iter()
        .map(|s| {
            let n = s.traces.len() as f64;
            let (mut eta, mut variance) = (0.0, 0.0);
            for t in &s.traces {
                let (e, se) = t.loss_factor();
                eta += e / n;
                variance += (se / n).powi(2);
            }
            let kind = kinds.iter().position(|k| *k == s.specimen.flexure.kind);
            let frequency = s.omega_d / (2.0 * std::f64::consts::PI);
            (
                frequency.ln(),
                eta.ln(),
                variance.sqrt() / eta,
                kind.unwrap_or(0),
            )
        })
        .filter(|h| h.1.is_finite() && h.2.is_finite() && h.2 > 0.0)
        .collect();
    let coefficients = kinds.len() + 1;
    if hinges.len() < coefficients + 2 {
        return None;
    }
    let log_f0 = hinges.iter().map(|h| h.0).sum::<f64>() / hinges.len() as f64;
    let residuals = |p: &[f64]| -> Result<Vec<f64>, &'static str> {
        Ok(hinges
            .iter()
            .map(|&(lf, le, se, c)| (p[c] + p[kinds.len()] * (lf - log_f0) - le) / se)
            .collect())
    };
    let mut parameters: Vec<Parameter> = kinds
        .iter()
        .enumerate()
        .map(|(c, _)| {
            let mean = hinges.iter().filter(|h| h.3 == c).map(|h| h.1).sum::<f64>()
                / hinges.iter().filter(|h| h.3 == c).count() as f64;
            Parameter::new(format!("ln_eta{c}"), mean).with_scale(1.0)
        })
        .collect();
    parameters.push(Parameter::new("alpha", 0.0).with_scale(0.1));
    let lm = LmOptions {
        residuals_normalized: true,
        ..LmOptions::default()
    };
    let result = levenberg_marquardt(residuals, &parameters, &lm).ok()?;
    let chi2_dof = 2.0 * result.cost / (hinges.len() - coefficients) as f64;
    let inflation = chi2_dof.max(1.0).sqrt();
    let se = |k: usize| result.standard_errors[k] * inflation;
    let frequencies = hinges.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), h| {
        (lo.min(h.0.exp()), hi.max(h.0.exp()))
    });
    let alpha = (result.params[kinds.len()], se(kinds.len()));
    (alpha.0.is_finite() && alpha.1.is_finite()).then(|| LossFrequencyFit {
        exponent: alpha,
        levels: kinds
            .iter()
            .enumerate()
            .map(|(c, &kind)| {
                let eta0 = result.params[c].exp();
                (kind, eta0, eta0 * se(c))
            })
            .collect(),
        reference_frequency: log_f0.exp(),
        frequencies,
        points: hinges.len(),
        chi2_dof,
    })
}

/// The finding of a loss factor that depends on frequency: α beyond [`FLAG_SIGMA`] standard
/// errors (whether or not the set resolves the smallest α worth finding).
fn loss_frequency_finding(fit: &LossFrequencyFit) -> Option<Flag> {
    (fit.exponent_sigma().abs() > FLAG_SIGMA).then(|| Flag {
        kind: "frequency_dependent_loss",
        message: format!(
            "the loss factor depends on frequency: η(f) = η₀ (f/{:.2} Hz)^α with α = {:.3} ± \
             {:.3} ({:.1}σ) over {} hinges at {:.2}–{:.2} Hz; the constant η of Eq. 7 (and of \
             the time-domain b = kη/ω_ref) is an average over these frequencies",
            fit.reference_frequency,
            fit.exponent.0,
            fit.exponent.1,
            fit.exponent_sigma().abs(),
            fit.points,
            fit.frequencies.0,
            fit.frequencies.1
        ),
    })
}

/// The fits across already analysed specimens.
pub fn fit_results(specimens: Vec<SpecimenResult>, options: &FitOptions) -> FitReport {
    let unc: Vec<usize> = (0..specimens.len())
        .filter(|&i| specimens[i].specimen.flexure.kind == Kind::Uncastellated)
        .collect();
    let mut rejected = Vec::new();
    let mut findings = trace_findings(&specimens);
    let loss_frequency = fit_loss_frequency(&specimens);
    findings.extend(loss_frequency.as_ref().and_then(loss_frequency_finding));
    let uncastellated = (unc.len() >= 2).then(|| {
        let (stiffness_line, damping_line) = width_lines(
            &specimens,
            &unc,
            SpecimenResult::normalized_stiffness,
            SpecimenResult::normalized_damping,
        );
        ModulusFit {
            youngs_modulus: stiffness_line.slope,
            loss_factor: damping_line.slope / stiffness_line.slope,
            stiffness_line,
            damping_line,
            specimens: unc,
        }
    });
    // A modulus outside the plausible range is not a result: it is reported as a problem and
    // the castellated fits fall back to the default modulus.
    let uncastellated = uncastellated.and_then(|fit| {
        let (lo, hi) = options.modulus_range;
        if fit.youngs_modulus >= lo && fit.youngs_modulus <= hi {
            return Some(fit);
        }
        rejected.push(Error::ImplausibleModulus {
            modulus: fit.youngs_modulus,
            range: options.modulus_range,
            specimens: fit
                .specimens
                .iter()
                .map(|&i| specimens[i].specimen.name.clone())
                .collect(),
        });
        None
    });
    if let Some(fit) = &uncastellated {
        for (what, line) in [("Eq. 6", &fit.stiffness_line), ("Eq. 7", &fit.damping_line)] {
            if line.r_squared < POOR_LINE_R2 {
                findings.push(line_finding(&format!("uncastellated {what}"), line));
            }
        }
    }
    let modulus = options
        .modulus
        .or(uncastellated.as_ref().map(|f| f.youngs_modulus))
        .unwrap_or(crate::physics::Material::KAPTON_HN.youngs_modulus);

    let castellated = castellated_fits(&specimens, modulus);
    for fit in &castellated {
        for (what, line) in [("k_m", &fit.stiffness_line), ("b_m·ω_d", &fit.damping_line)] {
            if line.r_squared < POOR_LINE_R2 {
                let group = format!(
                    "castellated (t = {:.1} µm, l = {:.0} µm) {what}",
                    fit.thickness * 1e6,
                    fit.length * 1e6
                );
                findings.push(line_finding(&group, line));
            }
        }
    }
    let traces = specimens.iter().map(|s| s.traces.len()).sum();
    FitReport {
        specimens,
        uncastellated,
        castellated,
        loss_frequency,
        rejected,
        findings,
        traces,
    }
}

/// Eq. 2's effective length and the loss factor of each group of castellated hinges of one
/// thickness and length (two specimens or more), under Young's modulus `modulus`.
fn castellated_fits(specimens: &[SpecimenResult], modulus: f64) -> Vec<CastellatedFit> {
    // Group castellated hinges by (thickness, length), to 1 nm.
    let mut groups: BTreeMap<(i64, i64), Vec<usize>> = BTreeMap::new();
    for (i, s) in specimens.iter().enumerate() {
        let f = &s.specimen.flexure;
        if f.kind == Kind::Castellated {
            let key = (
                (f.thickness * 1e9).round() as i64,
                (f.length * 1e9).round() as i64,
            );
            groups.entry(key).or_default().push(i);
        }
    }
    groups
        .into_values()
        .filter(|members| members.len() >= 2)
        .map(|members| {
            let f = specimens[members[0]].specimen.flexure;
            let (stiffness_line, damping_line) = width_lines(
                specimens,
                &members,
                |s| s.stiffness,
                |s| s.damping_times_omega,
            );
            CastellatedFit {
                thickness: f.thickness,
                length: f.length,
                youngs_modulus: modulus,
                effective_length: modulus * f.thickness.powi(3) / (12.0 * stiffness_line.slope),
                loss_factor: damping_line.slope / stiffness_line.slope,
                stiffness_line,
                damping_line,
                specimens: members,
            }
        })
        .collect()
}

/// The stiffness and the damping of the specimens `members`, each fitted by a line through
/// the origin against their widths.
fn width_lines(
    specimens: &[SpecimenResult],
    members: &[usize],
    stiffness: impl Fn(&SpecimenResult) -> f64,
    damping: impl Fn(&SpecimenResult) -> f64,
) -> (LineFit, LineFit) {
    let widths: Vec<f64> = members
        .iter()
        .map(|&i| specimens[i].specimen.flexure.width)
        .collect();
    let line = |value: &dyn Fn(&SpecimenResult) -> f64| {
        let values: Vec<f64> = members.iter().map(|&i| value(&specimens[i])).collect();
        fit_through_origin(&widths, &values)
    };
    (line(&stiffness), line(&damping))
}

fn line_finding(what: &str, line: &LineFit) -> Flag {
    Flag {
        kind: "poor_line_fit",
        message: format!(
            "{what} against width: R² = {:.3} < {POOR_LINE_R2} over {} flexures; the \
             flexures scatter about the line (the seed's real data gave 0.83–0.97): check their \
             geometry, or a loss factor that depends on frequency",
            line.r_squared, line.points
        ),
    }
}
