//! Nonlinear least squares by Levenberg–Marquardt, with bounds, parameter scaling, finite
//! difference Jacobians, covariance and standard errors, identifiability flags, and
//! information criteria.
//!
//! Consumes: a residual function `p ↦ r(p)` (n parameters in their own units → m residuals,
//! already divided by the measurement noise σ where it is known), and the parameters'
//! names, initial values, bounds and scales.
//! Produces: a [`FitResult`]: the parameters minimizing the cost `½‖r‖²`, their covariance
//! and standard errors, the status of each one (free, held at a bound, unidentifiable), and
//! why the iteration stopped; or an [`LmError`] when the problem cannot be started.
//!
//! # Method
//!
//! The iteration is Levenberg–Marquardt with Marquardt–Moré scaling (Moré, "The
//! Levenberg–Marquardt algorithm: implementation and theory", 1978; Nocedal & Wright,
//! *Numerical Optimization*, 2nd ed., §10.3). With `J` the Jacobian of `r`, `g = Jᵀr` the
//! gradient of the cost and `D = diag(‖J_j‖)` (the largest column norms seen so far), each
//! step solves
//!
//! ```text
//!   (JᵀJ + λ DᵀD) δ = −Jᵀr
//! ```
//!
//! through the SVD of `J D⁻¹` (one SVD per Jacobian, then every trial λ costs O(n²); rank
//! deficiency cannot make it divide by zero). The step is accepted when the gain ratio
//! `ρ = (actual reduction)/(predicted reduction)` exceeds 10⁻⁴, the predicted reduction being
//! `−(gᵀδ + ½‖Jδ‖²)`. λ is updated by Nielsen's rule (Madsen, Nielsen & Tingleff, *Methods
//! for non-linear least squares problems*, 2004, §3.2): on success `λ ← λ·max(⅓,
//! 1 − (2ρ − 1)³)`, on failure `λ ← λ·ν, ν ← 2ν`. The first λ is
//! [`LmOptions::initial_damping`] (relative to `DᵀD`).
//!
//! **Scaling.** The iteration works in `x = p / s` with `s` the parameter's scale (default:
//! its initial magnitude), rounded to a power of two so that `p ↔ x` is exact. Micro-newtons
//! and metres then mix: finite-difference steps are relative to `max(|x|, 1)` and the
//! stopping tests are scale free.
//!
//! **Bounds** are handled by projection onto the box, not by a change of variables. Each
//! iteration fixes the parameters that sit on a bound with the gradient pushing outward
//! (the active set), solves for the others, and projects the trial point onto the box; the
//! gain ratio uses the projected step. Why projection: a smooth transform (`p = lo + (hi −
//! lo)(1 + sin θ)/2`, as in MINUIT or lmfit) has a zero derivative at the bound, so an active
//! bound is approached only asymptotically and never reported as active, and the Jacobian in
//! θ distorts the covariance. With projection the parameter lands exactly on its bound, is
//! reported as [`ParameterStatus::AtLower`]/[`ParameterStatus::AtUpper`], and the
//! covariance of the others is that of the fit with it held there.
//!
//! **Stopping** (MINPACK's tests, Moré 1978 §7): the gradient test `max_j |J_jᵀ r| /
//! (‖J_j‖ ‖r‖) ≤ gtol` (cosine of the angle between `r` and each free column); the cost test
//! (actual and predicted relative reductions both `≤ ftol`); the step test `‖Dδ‖ ≤ xtol
//! (‖Dx‖ + xtol)`; a zero residual; or the iteration, evaluation or damping limits (not
//! converged).
//!
//! # Covariance
//!
//! At the solution the Jacobian is evaluated again ([`LmOptions::covariance_difference`],
//! central differences by default), and for the free parameters (not on a bound)
//!
//! ```text
//!   C = s² (JᵀJ)⁻¹,   s² = ‖r‖² / (m − rank)    (σ unknown)
//!   C = (JᵀJ)⁻¹                                 (residuals already divided by a known σ)
//! ```
//!
//! (the asymptotic covariance of nonlinear least squares, Seber & Wild, *Nonlinear
//! Regression*, 1989, §2.1; for a model linear in p it is the exact OLS covariance),
//! computed from the SVD of `J` with unit-norm columns. A singular value below
//! [`LmOptions::rank_tolerance`] times the largest one is a direction the data do not
//! determine: the parameters with a weight above 10⁻² in it are
//! [`ParameterStatus::Unidentifiable`], their standard errors are `+∞` and their covariance
//! entries NaN; the others' covariance is the pseudo-inverse's, which is exact for
//! parameters orthogonal to the null space.

use std::fmt;

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// One parameter to fit.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// Its name, for messages and reports.
    pub name: String,
    /// The starting value, in the parameter's units.
    pub initial: f64,
    /// Lower bound (`-∞` for none).
    pub lower: f64,
    /// Upper bound (`+∞` for none); `lower == upper` holds the parameter fixed.
    pub upper: f64,
    /// Typical magnitude (`None`: `|initial|`, or 1 if that is 0). Only its power of two is
    /// used.
    pub scale: Option<f64>,
}

impl Parameter {
    /// An unbounded parameter starting at `initial`.
    pub fn new(name: impl Into<String>, initial: f64) -> Parameter {
        Parameter {
            name: name.into(),
            initial,
            lower: f64::NEG_INFINITY,
            upper: f64::INFINITY,
            scale: None,
        }
    }

    /// With bounds `lower ≤ p ≤ upper` (either may be infinite).
    pub fn bounded(mut self, lower: f64, upper: f64) -> Parameter {
        self.lower = lower;
        self.upper = upper;
        self
    }

    /// With a typical magnitude (useful when the initial value is 0).
    pub fn with_scale(mut self, scale: f64) -> Parameter {
        self.scale = Some(scale);
        self
    }

    /// Held at one value (`lower == upper`), not fitted.
    pub fn is_fixed(&self) -> bool {
        self.lower == self.upper
    }
}

/// How the Jacobian is approximated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Difference {
    /// `(r(x + h) − r(x)) / h`: n evaluations, error O(h); default step `√ε ≈ 1.5e-8`.
    Forward,
    /// `(r(x + h) − r(x − h)) / 2h`: 2n evaluations, error O(h²); default step
    /// `ε^⅓ ≈ 6e-6`.
    Central,
}

impl Difference {
    /// The step relative to `max(|x|, 1)` that balances truncation and rounding error: `√ε`
    /// forward, `ε^⅓` central.
    fn default_relative_step(self) -> f64 {
        match self {
            Difference::Forward => f64::EPSILON.sqrt(),
            Difference::Central => f64::EPSILON.cbrt(),
        }
    }
}

/// Tuning of [`levenberg_marquardt`].
#[derive(Clone, Debug, PartialEq)]
pub struct LmOptions {
    /// Most Jacobian evaluations (iterations); default 200.
    pub max_iterations: usize,
    /// Most residual evaluations, Jacobians included; default 20 000.
    pub max_evaluations: usize,
    /// Relative cost reduction below which the fit has converged; default 1e-12.
    pub ftol: f64,
    /// Relative step size below which the fit has converged; default 1e-10.
    pub xtol: f64,
    /// Gradient test (cosine of the angle between `r` and the Jacobian's columns); default
    /// 1e-10.
    pub gtol: f64,
    /// Difference scheme of the Jacobian during the iteration; default forward.
    pub difference: Difference,
    /// Difference scheme of the Jacobian for the covariance (evaluated once, at the
    /// solution); default central.
    pub covariance_difference: Difference,
    /// Relative finite-difference step (of `max(|p/scale|, 1)`); `None`: the scheme's
    /// default. Raise it when the residuals are noisy (e.g. from an adaptive integrator with
    /// tolerance τ: about `√τ` forward, `τ^⅓` central).
    pub relative_step: Option<f64>,
    /// Whether the residuals are already divided by a known measurement noise σ: then the
    /// covariance is `(JᵀJ)⁻¹`; otherwise it is scaled by `s² = ‖r‖²/(m − rank)`.
    pub residuals_normalized: bool,
    /// First damping λ, relative to `DᵀD`; default 1e-3.
    pub initial_damping: f64,
    /// Relative singular value of the column-normalized Jacobian below which a direction is
    /// unidentifiable; default 1e-7. Keep it above the relative error of the Jacobian.
    pub rank_tolerance: f64,
    /// Give up on a fit the data cannot use: `None` (default) never.
    pub stall: Option<Stall>,
}

/// After `iterations` iterations, a fit whose cost is still above `cost_above` stops
/// ([`StopReason::Stalled`]). A diagnosis candidate that has not brought χ² one unit below
/// the base model's in that many steps is almost always ranked inert whatever it does next
/// (the drive example's slow crawls: 50 iterations, 170 predictions, no gain), and its crawl
/// would cost up to `max_iterations` Jacobians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stall {
    pub iterations: usize,
    pub cost_above: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            max_iterations: 200,
            max_evaluations: 20_000,
            ftol: 1e-12,
            xtol: 1e-10,
            gtol: 1e-10,
            difference: Difference::Forward,
            covariance_difference: Difference::Central,
            relative_step: None,
            residuals_normalized: false,
            initial_damping: 1e-3,
            rank_tolerance: 1e-7,
            stall: None,
        }
    }
}

/// Why the iteration stopped; in JSON by its snake_case name (`cost_reduction`, …).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The gradient is orthogonal to the residual within `gtol` (or every free parameter is
    /// held by a bound).
    Gradient,
    /// The actual and predicted relative cost reductions are below `ftol`.
    CostReduction,
    /// The step is below `xtol` relative to the parameters.
    StepSize,
    /// The residuals are exactly zero.
    ZeroResidual,
    /// `max_iterations` reached (not converged).
    MaxIterations,
    /// `max_evaluations` reached (not converged).
    MaxEvaluations,
    /// The damping grew without finding a better point: the residuals are too noisy or
    /// not smooth at this point (not converged).
    NoProgress,
    /// [`LmOptions::stall`]: the cost is still above its line after its iterations (not
    /// converged).
    Stalled,
}

impl StopReason {
    /// Whether this reason means convergence.
    pub fn converged(self) -> bool {
        matches!(
            self,
            StopReason::Gradient
                | StopReason::CostReduction
                | StopReason::StepSize
                | StopReason::ZeroResidual
        )
    }
}

impl fmt::Display for StopReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            StopReason::Gradient => "converged: gradient orthogonal to the residuals",
            StopReason::CostReduction => "converged: relative cost reduction below ftol",
            StopReason::StepSize => "converged: relative step below xtol",
            StopReason::ZeroResidual => "converged: zero residual",
            StopReason::MaxIterations => "not converged: iteration limit reached",
            StopReason::MaxEvaluations => "not converged: evaluation limit reached",
            StopReason::NoProgress => {
                "not converged: no better point found (residuals noisy or not smooth?)"
            }
            StopReason::Stalled => "not converged: stalled (no gain on the base model)",
        })
    }
}

/// What the fit says about one parameter; in JSON by its snake_case name (`at_lower`, …).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ParameterStatus {
    /// Estimated, with a finite standard error.
    Free,
    /// Held at its lower bound: standard error NaN (a boundary solution).
    AtLower,
    /// Held at its upper bound: standard error NaN.
    AtUpper,
    /// `lower == upper`: not fitted, standard error 0.
    Fixed,
    /// The data do not determine it (alone or in a combination with others): standard
    /// error `+∞`.
    Unidentifiable,
}

impl fmt::Display for ParameterStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ParameterStatus::Free => "free",
            ParameterStatus::AtLower => "at lower bound",
            ParameterStatus::AtUpper => "at upper bound",
            ParameterStatus::Fixed => "fixed",
            ParameterStatus::Unidentifiable => "unidentifiable",
        })
    }
}

/// The outcome of [`levenberg_marquardt`].
#[derive(Clone, Debug, PartialEq)]
pub struct FitResult {
    /// Parameter names, in the order given.
    pub names: Vec<String>,
    /// The best parameters found, in their units.
    pub params: Vec<f64>,
    /// `½‖r‖²` at `params`.
    pub cost: f64,
    /// `‖r‖ / √m`.
    pub residual_rms: f64,
    /// The residuals at `params`.
    pub residuals: Vec<f64>,
    /// `∂r/∂p` at `params` (m × n, parameters in their units), as used for the covariance.
    pub jacobian: DMatrix<f64>,
    /// Jacobian evaluations (iterations) of the main loop.
    pub iterations: usize,
    /// Residual evaluations, Jacobians and the final one included.
    pub evaluations: usize,
    /// Covariance of the parameters (n × n, their units squared); NaN in the rows and
    /// columns of parameters that are unidentifiable or held at a bound, 0 for fixed ones.
    pub covariance: DMatrix<f64>,
    /// `√C_ii`; `+∞` for unidentifiable parameters, NaN at a bound, 0 when fixed.
    pub standard_errors: Vec<f64>,
    /// What the fit says about each parameter.
    pub status: Vec<ParameterStatus>,
    /// Numerical rank of the Jacobian of the free parameters.
    pub rank: usize,
    /// Ratio of the largest to the smallest singular value of the column-normalized
    /// Jacobian of the free parameters (`+∞` if singular; 1 if there are none).
    pub condition_number: f64,
    /// `m − rank`.
    pub degrees_of_freedom: usize,
    /// `s²` scaling the covariance: `‖r‖²/(m − rank)`, or 1 when the residuals are
    /// normalized by a known σ (NaN if there are no degrees of freedom left).
    pub noise_variance: f64,
    /// Whether a convergence test was met.
    pub converged: bool,
    /// Why the iteration stopped.
    pub reason: StopReason,
}

impl FitResult {
    /// Number of residuals.
    pub fn residual_count(&self) -> usize {
        self.residuals.len()
    }

    /// Value and standard error of the parameter `name`.
    pub fn parameter(&self, name: &str) -> Option<(f64, f64)> {
        let i = self.names.iter().position(|n| n == name)?;
        Some((*self.params.get(i)?, *self.standard_errors.get(i)?))
    }

    /// Names of the parameters flagged unidentifiable.
    pub fn unidentifiable(&self) -> Vec<&str> {
        self.names
            .iter()
            .zip(&self.status)
            .filter(|(_, s)| **s == ParameterStatus::Unidentifiable)
            .map(|(n, _)| n.as_str())
            .collect()
    }

    /// Correlation matrix `C_ij / √(C_ii C_jj)` (NaN where undefined).
    pub fn correlation(&self) -> DMatrix<f64> {
        let c = &self.covariance;
        DMatrix::from_fn(c.nrows(), c.ncols(), |i, j| {
            let d = (c[(i, i)] * c[(j, j)]).sqrt();
            if d > 0.0 {
                c[(i, j)] / d
            } else {
                f64::NAN
            }
        })
    }

    /// AIC, AICc and BIC of this fit (see [`information_criteria`]): the number of fitted
    /// parameters is the rank of the Jacobian.
    pub fn information_criteria(&self, noise: NoiseModel) -> InformationCriteria {
        information_criteria(self.cost, self.residual_count(), self.rank, noise)
    }
}

impl fmt::Display for FitResult {
    /// A table: name, value, standard error, status; then cost, rms and the stop reason.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let width = self
            .names
            .iter()
            .map(|n| n.chars().count())
            .max()
            .unwrap_or(4);
        for ((name, value), (se, status)) in self
            .names
            .iter()
            .zip(&self.params)
            .zip(self.standard_errors.iter().zip(&self.status))
        {
            writeln!(f, "{name:<width$}  {value:>14.6e} ± {se:<12.4e} {status}")?;
        }
        write!(
            f,
            "cost {:.6e}, rms residual {:.6e}, {} residuals, {} iterations, {} evaluations; {}",
            self.cost,
            self.residual_rms,
            self.residual_count(),
            self.iterations,
            self.evaluations,
            self.reason
        )
    }
}

/// Why a fit could not be carried out.
#[derive(Clone, Debug, PartialEq)]
pub enum LmError<E> {
    /// No parameters to fit.
    NoParameters,
    /// A parameter's initial value, bounds or scale are not usable.
    InvalidParameter { name: String, reason: String },
    /// The residual function failed at the initial point or for a Jacobian (where no
    /// alternative step could be evaluated either).
    Residual { params: Vec<f64>, error: E },
    /// The residual function returned a NaN or infinity there.
    NonFiniteResidual { params: Vec<f64>, index: usize },
    /// The residual function returned no residuals.
    NoResiduals,
    /// The number of residuals changed between evaluations.
    ResidualCountChanged {
        params: Vec<f64>,
        expected: usize,
        found: usize,
    },
}

impl<E: fmt::Display> fmt::Display for LmError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LmError::NoParameters => write!(f, "nothing to fit: no parameters were given"),
            LmError::InvalidParameter { name, reason } => {
                write!(f, "parameter `{name}`: {reason}")
            }
            LmError::Residual { params, error } => write!(
                f,
                "the residuals could not be evaluated at p = {}: {error}",
                Point(params)
            ),
            LmError::NonFiniteResidual { params, index } => write!(
                f,
                "residual {index} is NaN or infinite at p = {}; check the model and the \
                 starting values",
                Point(params)
            ),
            LmError::NoResiduals => write!(f, "the residual function returned no residuals"),
            LmError::ResidualCountChanged {
                params,
                expected,
                found,
            } => write!(
                f,
                "the residual function returned {found} residuals at p = {}, but {expected} \
                 before; it must always return the same number",
                Point(params)
            ),
        }
    }
}

/// Parameter values for messages: `[1, 0.25, 2.5e-6]` (plain where that is short, else in
/// exponent form).
struct Point<'a>(&'a [f64]);

impl fmt::Display for Point<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("[")?;
        for (i, value) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            let magnitude = value.abs();
            if *value == 0.0 || !value.is_finite() || (1e-3..1e6).contains(&magnitude) {
                write!(f, "{value}")?;
            } else {
                write!(f, "{value:e}")?;
            }
        }
        f.write_str("]")
    }
}

impl<E: fmt::Debug + fmt::Display> std::error::Error for LmError<E> {}

/// The noise model behind the likelihood of [`information_criteria`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoiseModel {
    /// Gaussian noise of unknown variance σ², estimated by maximum likelihood (`‖r‖²/m`);
    /// σ² counts as one more parameter.
    UnknownVariance,
    /// The residuals are already divided by a known σ (`r_i = (y_i − f_i)/σ_i`).
    Normalized,
}

/// Information criteria of a least-squares fit under Gaussian noise; smaller is better, and
/// only differences between models fitted to the same data mean anything.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InformationCriteria {
    /// `ln L` at the fit (with the constants below).
    pub log_likelihood: f64,
    /// Number of parameters counted, `k`.
    pub parameters: usize,
    /// Akaike: `2k − 2 ln L`.
    pub aic: f64,
    /// Small-sample Akaike (Hurvich & Tsai 1989): `AIC + 2k(k + 1)/(m − k − 1)`; `+∞` when
    /// `m ≤ k + 1`.
    pub aicc: f64,
    /// Bayesian (Schwarz 1978): `k ln m − 2 ln L`.
    pub bic: f64,
}

/// AIC, AICc and BIC from the cost `½‖r‖²` of a fit with `n` fitted parameters to `m`
/// residuals, under Gaussian noise (Burnham & Anderson, *Model Selection and Multimodel
/// Inference*, 2002, §2.2):
///
/// - [`NoiseModel::UnknownVariance`]: with `RSS = 2·cost` and σ̂² = RSS/m,
///   `ln L = −(m/2)(ln(2π RSS/m) + 1)`, and `k = n + 1` (σ² is estimated too);
/// - [`NoiseModel::Normalized`]: `ln L = −(m/2) ln 2π − RSS/2` (the constant `−Σ ln σ_i` is
///   left out: it is the same for every model of the same data), and `k = n`.
///
/// A zero RSS under unknown variance gives `ln L = +∞` and AIC = BIC = −∞.
pub fn information_criteria(
    cost: f64,
    m: usize,
    n: usize,
    noise: NoiseModel,
) -> InformationCriteria {
    let rss = 2.0 * cost;
    let mf = m as f64;
    let two_pi = 2.0 * std::f64::consts::PI;
    let (log_likelihood, k) = match noise {
        NoiseModel::UnknownVariance => (-0.5 * mf * ((two_pi * rss / mf).ln() + 1.0), n + 1),
        NoiseModel::Normalized => (-0.5 * mf * two_pi.ln() - 0.5 * rss, n),
    };
    let kf = k as f64;
    let aic = 2.0 * kf - 2.0 * log_likelihood;
    let aicc = if m > k + 1 {
        aic + 2.0 * kf * (kf + 1.0) / (mf - kf - 1.0)
    } else {
        f64::INFINITY
    };
    let bic = kf * mf.ln() - 2.0 * log_likelihood;
    InformationCriteria {
        log_likelihood,
        parameters: k,
        aic,
        aicc,
        bic,
    }
}

/// Smallest gain ratio for accepting a step.
const ACCEPT_RATIO: f64 = 1e-4;
/// Damping beyond which the iteration gives up (relative to `DᵀD`).
const MAX_DAMPING: f64 = 1e16;
/// Weight in a null direction above which a parameter is flagged unidentifiable.
const NULL_WEIGHT: f64 = 1e-2;

/// Fits `parameters` so as to minimize `½‖residuals(p)‖²` (see the module documentation for
/// the method). `residuals` receives the parameters in their own units, in the order given;
/// it may fail (`Err`) or return non-finite values at a trial point, which is then rejected
/// like a poor step.
pub fn levenberg_marquardt<F, E>(
    residuals: F,
    parameters: &[Parameter],
    options: &LmOptions,
) -> Result<FitResult, LmError<E>>
where
    F: FnMut(&[f64]) -> Result<Vec<f64>, E>,
{
    let problem = Problem::new(parameters)?;
    let mut fit = Fit::start(residuals, &problem, options)?;
    let reason = fit.iterate()?;
    fit.conclude(parameters, reason)
}

/// One run of the iteration: the residual function (counting its calls), the problem in
/// scaled form, the options, and where the iteration stands.
struct Fit<'a, F> {
    eval: Evaluator<F>,
    problem: &'a Problem,
    options: &'a LmOptions,
    state: State,
}

impl<'a, F, E> Fit<'a, F>
where
    F: FnMut(&[f64]) -> Result<Vec<f64>, E>,
{
    /// The residuals at the initial point; they fix the number of residuals `m`.
    fn start(
        residuals: F,
        problem: &'a Problem,
        options: &'a LmOptions,
    ) -> Result<Self, LmError<E>> {
        let mut eval = Evaluator {
            f: residuals,
            scales: problem.scales.clone(),
            count: 0,
            m: 0,
        };
        let x = problem.x0.clone();
        let r = match eval.eval(&x) {
            Ok(r) => r,
            Err(failure) => return Err(failure.into_error(eval.params(&x))),
        };
        if r.is_empty() {
            return Err(LmError::NoResiduals);
        }
        eval.m = r.len();
        let state = State {
            cost: half_norm_squared(&r),
            lambda: options.initial_damping.max(f64::MIN_POSITIVE),
            nu: 2.0,
            d: vec![0.0f64; x.len()],
            iterations: 0,
            x,
            r,
        };
        Ok(Fit {
            eval,
            problem,
            options,
            state,
        })
    }

    /// Iterates until a stopping test is met: one Jacobian per iteration, then damped steps
    /// until one is accepted.
    fn iterate(&mut self) -> Result<StopReason, LmError<E>> {
        loop {
            if let Some(reason) = self.state.limit_reached(self.eval.count, self.options) {
                return Ok(reason);
            }
            if let Some(reason) = self.iteration()? {
                return Ok(reason);
            }
        }
    }

    /// One iteration: the Jacobian `J` and gradient `g = Jᵀr`, the active set, the gradient
    /// test, then the damped steps on the free parameters. `None`: a step was accepted.
    fn iteration(&mut self) -> Result<Option<StopReason>, LmError<E>> {
        let (options, state) = (self.options, &mut self.state);
        let jac = self.eval.jacobian(
            &state.x,
            &state.r,
            options.difference,
            options.relative_step,
            self.problem,
        )?;
        state.iterations += 1;
        let rv = DVector::from_column_slice(&state.r);
        let g = jac.tr_mul(&rv);
        let norms = column_norms(&jac);
        for (dj, nj) in state.d.iter_mut().zip(&norms) {
            *dj = dj.max(*nj);
        }
        let free = self.problem.free_parameters(&state.x, &g);
        let r_norm = (2.0 * state.cost).sqrt();
        if free.is_empty() || gradient_cosine(&free, &g, &norms, r_norm) <= options.gtol {
            return Ok(Some(StopReason::Gradient));
        }
        match ScaledSystem::new(&jac, &rv, free, &state.d) {
            Ok(system) => self.damped_steps(&jac, &g, &system),
            Err(reason) => Ok(Some(reason)),
        }
    }

    /// Trial steps of growing damping until one lowers the cost enough (`ρ > 10⁻⁴`: `None`)
    /// or a stopping test is met.
    fn damped_steps(
        &mut self,
        jac: &DMatrix<f64>,
        g: &DVector<f64>,
        system: &ScaledSystem,
    ) -> Result<Option<StopReason>, LmError<E>> {
        let (options, state) = (self.options, &mut self.state);
        let n = state.x.len();
        loop {
            let x_new = system.trial_point(&state.x, self.problem, state.lambda);
            let step = DVector::from_iterator(n, x_new.iter().zip(&state.x).map(|(a, b)| a - b));
            if step.iter().all(|s| *s == 0.0) {
                return Ok(Some(StopReason::StepSize));
            }
            // The model's reduction −(gᵀδ + ½‖Jδ‖²).
            let j_step = jac * &step;
            let predicted = -(g.dot(&step) + 0.5 * j_step.norm_squared());
            let step_norm = weighted_norm(&state.d, step.as_slice());
            let x_norm = weighted_norm(&state.d, &state.x);

            let trial = self.eval.trial(&x_new)?;
            let cost_new = trial.as_deref().map_or(f64::INFINITY, half_norm_squared);
            let actual = state.cost - cost_new;
            let rho = gain_ratio(actual, predicted);
            let accepted = rho > ACCEPT_RATIO;
            let small_reduction = predicted > 0.0
                && predicted <= options.ftol * state.cost
                && actual.abs() <= options.ftol * state.cost
                && rho <= 2.0;
            if accepted {
                state.accept(x_new, trial, cost_new, rho);
            } else {
                state.reject();
            }
            if small_reduction {
                return Ok(Some(StopReason::CostReduction));
            }
            if accepted && step_norm <= options.xtol * (x_norm + options.xtol) {
                return Ok(Some(StopReason::StepSize));
            }
            if accepted {
                return Ok(None);
            }
            if state.lambda > MAX_DAMPING || !state.lambda.is_finite() {
                return Ok(Some(StopReason::NoProgress));
            }
            if self.eval.count >= options.max_evaluations {
                return Ok(Some(StopReason::MaxEvaluations));
            }
        }
    }

    /// The result at the final point: the Jacobian again (with the covariance's difference
    /// scheme), each parameter's status, the covariance `s² (JᵀJ)⁺` and the standard errors.
    fn conclude(
        mut self,
        parameters: &[Parameter],
        reason: StopReason,
    ) -> Result<FitResult, LmError<E>> {
        let (options, state) = (self.options, self.state);
        let (m, n) = (state.r.len(), state.x.len());
        let jac_x = self.eval.jacobian(
            &state.x,
            &state.r,
            options.covariance_difference,
            options.relative_step,
            self.problem,
        )?;
        let params = self.eval.params(&state.x);
        // ∂r/∂p = ∂r/∂x / s.
        let jacobian = DMatrix::from_fn(m, n, |i, j| jac_x[(i, j)] / self.problem.scales[j]);
        let status = self.problem.bound_status(&state.x);
        let analysis = analyze(&jacobian, status, options.rank_tolerance);
        let degrees_of_freedom = m.saturating_sub(analysis.rank);
        let noise_variance = if options.residuals_normalized {
            1.0
        } else if degrees_of_freedom > 0 {
            2.0 * state.cost / degrees_of_freedom as f64
        } else {
            f64::NAN
        };
        let covariance = analysis.covariance.map(|c| c * noise_variance);
        Ok(FitResult {
            names: parameters.iter().map(|p| p.name.clone()).collect(),
            params,
            cost: state.cost,
            residual_rms: (2.0 * state.cost / m as f64).sqrt(),
            residuals: state.r,
            jacobian,
            iterations: state.iterations,
            evaluations: self.eval.count,
            standard_errors: standard_errors(&analysis.status, &covariance),
            covariance: zero_where_fixed(covariance, &analysis.status),
            status: analysis.status,
            rank: analysis.rank,
            condition_number: analysis.condition_number,
            degrees_of_freedom,
            noise_variance,
            converged: reason.converged(),
            reason,
        })
    }
}

/// Where the iteration stands: the point `x` (scaled), its residuals and cost, the damping
/// λ with Nielsen's factor ν, and the column scaling `D`.
struct State {
    x: Vec<f64>,
    r: Vec<f64>,
    /// `½‖r‖²`.
    cost: f64,
    lambda: f64,
    nu: f64,
    /// `D = diag(‖J_j‖)`, the largest column norms seen so far.
    d: Vec<f64>,
    /// Jacobian evaluations so far.
    iterations: usize,
}

impl State {
    /// A zero residual, or no room left for another Jacobian (n forward or 2n central
    /// evaluations).
    fn limit_reached(&self, evaluations: usize, options: &LmOptions) -> Option<StopReason> {
        if self.cost == 0.0 {
            Some(StopReason::ZeroResidual)
        } else if self.iterations >= options.max_iterations {
            Some(StopReason::MaxIterations)
        } else if options.stall.is_some_and(|stall| {
            self.iterations >= stall.iterations && self.cost > stall.cost_above
        }) {
            Some(StopReason::Stalled)
        } else if evaluations.saturating_add(2 * self.x.len()) > options.max_evaluations {
            Some(StopReason::MaxEvaluations)
        } else {
            None
        }
    }

    /// Moves to the trial point and relaxes the damping (Nielsen: `λ ← λ·max(⅓, 1 − (2ρ −
    /// 1)³)`, `ν ← 2`).
    fn accept(&mut self, x_new: Vec<f64>, trial: Option<Vec<f64>>, cost_new: f64, rho: f64) {
        if let Some(r_new) = trial {
            self.x = x_new;
            self.r = r_new;
            self.cost = cost_new;
        }
        self.lambda = (self.lambda * (1.0 / 3.0f64).max(1.0 - (2.0 * rho - 1.0).powi(3)))
            .max(f64::MIN_POSITIVE);
        self.nu = 2.0;
    }

    /// Stays and damps harder (Nielsen: `λ ← λ·ν`, `ν ← 2ν`).
    fn reject(&mut self) {
        self.lambda *= self.nu;
        self.nu *= 2.0;
    }
}

/// `ρ = actual / predicted` reduction; `−∞` when the model predicts no reduction.
fn gain_ratio(actual: f64, predicted: f64) -> f64 {
    if predicted > 0.0 {
        actual / predicted
    } else {
        f64::NEG_INFINITY
    }
}

/// MINPACK's gradient test: `max_j |g_j| / (‖J_j‖ ‖r‖)` over the free columns that move the
/// residuals (the cosine of the angle between `r` and each column).
fn gradient_cosine(free: &[usize], g: &DVector<f64>, norms: &[f64], r_norm: f64) -> f64 {
    free.iter()
        .filter(|&&j| norms[j] > 0.0)
        .map(|&j| g[j].abs() / (norms[j] * r_norm))
        .fold(0.0, f64::max)
}

/// `‖J_j‖` of each column.
fn column_norms(jac: &DMatrix<f64>) -> Vec<f64> {
    (0..jac.ncols()).map(|j| jac.column(j).norm()).collect()
}

/// The step equation `(JᵀJ + λ DᵀD) δ = −Jᵀr` on the free parameters, through the SVD
/// `J D⁻¹ = U Σ Vᵀ` (one per Jacobian; then every trial λ costs O(n²)).
struct ScaledSystem {
    /// The free parameters' indices.
    free: Vec<usize>,
    /// `D` of the free parameters, floored at 10⁻¹² of the largest.
    d_free: Vec<f64>,
    singular_values: DVector<f64>,
    v_t: DMatrix<f64>,
    /// `Uᵀr`.
    ur: DVector<f64>,
    /// Singular values at or below this are left out (numerically zero).
    cutoff: f64,
}

impl ScaledSystem {
    /// `Err(reason)`: no free parameter changes the residuals (a gradient stop), or the SVD
    /// failed (no progress).
    fn new(
        jac: &DMatrix<f64>,
        rv: &DVector<f64>,
        free: Vec<usize>,
        d: &[f64],
    ) -> Result<ScaledSystem, StopReason> {
        let d_max = free.iter().map(|&j| d[j]).fold(0.0, f64::max);
        if d_max == 0.0 {
            return Err(StopReason::Gradient);
        }
        let d_free: Vec<f64> = free.iter().map(|&j| d[j].max(1e-12 * d_max)).collect();
        let (m, k) = (jac.nrows(), free.len());
        let scaled = DMatrix::from_fn(m, k, |i, c| jac[(i, free[c])] / d_free[c]);
        let svd = nalgebra::SVD::try_new(scaled, true, true, f64::EPSILON, 10_000)
            .ok_or(StopReason::NoProgress)?;
        let nalgebra::SVD {
            u,
            v_t,
            singular_values,
        } = svd;
        let (Some(u), Some(v_t)) = (u, v_t) else {
            return Err(StopReason::NoProgress);
        };
        let s_max = singular_values.iter().copied().fold(0.0, f64::max);
        Ok(ScaledSystem {
            free,
            d_free,
            singular_values,
            v_t,
            ur: u.tr_mul(rv),
            cutoff: s_max * f64::EPSILON * (m.max(k) as f64),
        })
    }

    /// `x + D⁻¹ δ̃` projected onto the box, with `δ̃ = −Σ v_i σ_i (u_iᵀ r) / (σ_i² + λ)`.
    fn trial_point(&self, x: &[f64], problem: &Problem, lambda: f64) -> Vec<f64> {
        let mut step_scaled = DVector::<f64>::zeros(self.free.len());
        for (i, &s) in self.singular_values.iter().enumerate() {
            if s > self.cutoff {
                let coefficient = -s * self.ur[i] / (s * s + lambda);
                step_scaled += self.v_t.row(i).transpose() * coefficient;
            }
        }
        let mut x_new = x.to_vec();
        for (c, &j) in self.free.iter().enumerate() {
            x_new[j] =
                (x[j] + step_scaled[c] / self.d_free[c]).clamp(problem.lower[j], problem.upper[j]);
        }
        x_new
    }
}

/// `√C_jj` for a free parameter; `+∞` unidentifiable, NaN at a bound, 0 fixed.
fn standard_errors(status: &[ParameterStatus], covariance: &DMatrix<f64>) -> Vec<f64> {
    status
        .iter()
        .enumerate()
        .map(|(j, status)| match status {
            ParameterStatus::Free => covariance[(j, j)].sqrt(),
            ParameterStatus::Unidentifiable => f64::INFINITY,
            ParameterStatus::AtLower | ParameterStatus::AtUpper => f64::NAN,
            ParameterStatus::Fixed => 0.0,
        })
        .collect()
}

/// The covariance with the rows and columns of fixed parameters 0 (they do not vary).
fn zero_where_fixed(covariance: DMatrix<f64>, status: &[ParameterStatus]) -> DMatrix<f64> {
    let n = status.len();
    let held = |s: ParameterStatus| s == ParameterStatus::Fixed;
    DMatrix::from_fn(n, n, |i, j| {
        if held(status[i]) || held(status[j]) {
            0.0
        } else {
            covariance[(i, j)]
        }
    })
}

/// The parameters in scaled form: `x = p / s`, bounds likewise.
struct Problem {
    scales: Vec<f64>,
    x0: Vec<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
}

impl Problem {
    fn new<E>(parameters: &[Parameter]) -> Result<Problem, LmError<E>> {
        if parameters.is_empty() {
            return Err(LmError::NoParameters);
        }
        let mut problem = Problem {
            scales: Vec::new(),
            x0: Vec::new(),
            lower: Vec::new(),
            upper: Vec::new(),
        };
        for p in parameters {
            let invalid = |reason: String| LmError::InvalidParameter {
                name: p.name.clone(),
                reason,
            };
            if !p.initial.is_finite() {
                return Err(invalid(format!(
                    "the initial value {} is not finite",
                    p.initial
                )));
            }
            if p.lower.is_nan() || p.upper.is_nan() || p.lower > p.upper {
                return Err(invalid(format!(
                    "the bounds [{}, {}] are not an interval",
                    p.lower, p.upper
                )));
            }
            if p.initial < p.lower || p.initial > p.upper {
                return Err(invalid(format!(
                    "the initial value {} is outside the bounds [{}, {}]",
                    p.initial, p.lower, p.upper
                )));
            }
            let magnitude = match p.scale {
                Some(s) if s.is_finite() && s != 0.0 => s.abs(),
                Some(s) => {
                    return Err(invalid(format!("the scale {s} must be finite and nonzero")))
                }
                None if p.initial != 0.0 => p.initial.abs(),
                None => 1.0,
            };
            let scale = power_of_two(magnitude);
            problem.scales.push(scale);
            problem.x0.push(p.initial / scale);
            problem.lower.push(p.lower / scale);
            problem.upper.push(p.upper / scale);
        }
        Ok(problem)
    }

    /// The parameters the step may move: not fixed, and not on a bound with the gradient `g`
    /// of the cost pushing outward (the active set's complement).
    fn free_parameters(&self, x: &[f64], g: &DVector<f64>) -> Vec<usize> {
        (0..x.len())
            .filter(|&j| {
                let (lo, hi) = (self.lower[j], self.upper[j]);
                lo < hi && !(x[j] <= lo && g[j] > 0.0) && !(x[j] >= hi && g[j] < 0.0)
            })
            .collect()
    }

    /// Fixed, on a bound, or free, as `x` stands.
    fn bound_status(&self, x: &[f64]) -> Vec<ParameterStatus> {
        (0..x.len())
            .map(|j| {
                if self.lower[j] == self.upper[j] {
                    ParameterStatus::Fixed
                } else if x[j] <= self.lower[j] {
                    ParameterStatus::AtLower
                } else if x[j] >= self.upper[j] {
                    ParameterStatus::AtUpper
                } else {
                    ParameterStatus::Free
                }
            })
            .collect()
    }
}

/// The power of two nearest to `value > 0` (in the log sense), kept in the normal range.
fn power_of_two(value: f64) -> f64 {
    let exponent = value.log2().round().clamp(-1000.0, 1000.0) as i32;
    2.0f64.powi(exponent)
}

/// Why one evaluation of the residuals is unusable.
enum Failure<E> {
    Error(E),
    NonFinite { index: usize },
    Count { found: usize },
}

impl<E> Failure<E> {
    fn into_error(self, params: Vec<f64>) -> LmError<E> {
        match self {
            Failure::Error(error) => LmError::Residual { params, error },
            Failure::NonFinite { index } => LmError::NonFiniteResidual { params, index },
            Failure::Count { found } => LmError::ResidualCountChanged {
                params,
                expected: 0,
                found,
            },
        }
    }
}

/// Calls the residual function in scaled variables and counts the calls.
struct Evaluator<F> {
    f: F,
    scales: Vec<f64>,
    count: usize,
    /// Expected number of residuals (0 before the first evaluation).
    m: usize,
}

impl<F, E> Evaluator<F>
where
    F: FnMut(&[f64]) -> Result<Vec<f64>, E>,
{
    fn params(&self, x: &[f64]) -> Vec<f64> {
        x.iter().zip(&self.scales).map(|(x, s)| x * s).collect()
    }

    fn eval(&mut self, x: &[f64]) -> Result<Vec<f64>, Failure<E>> {
        let p = self.params(x);
        self.count += 1;
        let r = (self.f)(&p).map_err(Failure::Error)?;
        if self.m != 0 && r.len() != self.m {
            return Err(Failure::Count { found: r.len() });
        }
        if let Some(index) = r.iter().position(|v| !v.is_finite()) {
            return Err(Failure::NonFinite { index });
        }
        Ok(r)
    }

    /// The residuals at a trial point; `None` when they are unusable there (an error or a
    /// non-finite value: the step is rejected), an error when their number changed.
    fn trial(&mut self, x: &[f64]) -> Result<Option<Vec<f64>>, LmError<E>> {
        match self.eval(x) {
            Ok(r) => Ok(Some(r)),
            Err(Failure::Count { found }) => Err(self.count_changed(x, found)),
            Err(_) => Ok(None),
        }
    }

    fn count_changed(&self, x: &[f64], found: usize) -> LmError<E> {
        LmError::ResidualCountChanged {
            params: self.params(x),
            expected: self.m,
            found,
        }
    }

    /// `∂r/∂x` by finite differences at `x` (where the residuals are `r`). Steps stay inside
    /// the box: a central difference that would leave it becomes one-sided, a one-sided one
    /// goes the other way; a failed evaluation is retried on the other side.
    fn jacobian(
        &mut self,
        x: &[f64],
        r: &[f64],
        kind: Difference,
        relative_step: Option<f64>,
        problem: &Problem,
    ) -> Result<DMatrix<f64>, LmError<E>> {
        let m = r.len();
        let relative = relative_step
            .filter(|h| h.is_finite() && *h > 0.0)
            .unwrap_or(kind.default_relative_step());
        let mut jac = DMatrix::zeros(m, x.len());
        for j in 0..x.len() {
            let (lo, hi) = (problem.lower[j], problem.upper[j]);
            if lo == hi {
                continue;
            }
            let h = relative * x[j].abs().max(1.0);
            let (room_up, room_down) = (hi - x[j], x[j] - lo);
            let (column, last_failure) =
                if kind == Difference::Central && room_up >= h && room_down >= h {
                    self.central_column(x, r, j, h)
                } else {
                    self.one_sided_column(x, r, j, one_sided_steps(h, room_up, room_down))
                };
            match (column, last_failure) {
                (Some(column), _) => jac.set_column(j, &column),
                (None, Some(Failure::Count { found })) => return Err(self.count_changed(x, found)),
                (None, Some(failure)) => {
                    let mut at = x.to_vec();
                    at[j] += h.min(room_up.max(0.0));
                    return Err(failure.into_error(self.params(&at)));
                }
                (None, None) => {}
            }
        }
        if let Some(index) = jac.iter().position(|v| !v.is_finite()) {
            return Err(LmError::NonFiniteResidual {
                params: self.params(x),
                index: index % m.max(1),
            });
        }
        Ok(jac)
    }

    /// Column `j` by `(r(x + h) − r(x − h)) / 2h`, or one-sided where one side fails.
    fn central_column(&mut self, x: &[f64], r: &[f64], j: usize, h: f64) -> ColumnAttempt<E> {
        match (self.shifted(x, j, h), self.shifted(x, j, -h)) {
            (Ok((rp, xp)), Ok((rm, xm))) => (Some(difference(&rp, &rm, xp - xm)), None),
            (Ok((rp, xp)), Err(e)) => (Some(difference(&rp, r, xp - x[j])), Some(e)),
            (Err(e), Ok((rm, xm))) => (Some(difference(r, &rm, x[j] - xm)), Some(e)),
            (Err(e), Err(_)) => (None, Some(e)),
        }
    }

    /// Column `j` by a one-sided difference: the first of `steps` whose evaluation succeeds.
    fn one_sided_column(
        &mut self,
        x: &[f64],
        r: &[f64],
        j: usize,
        steps: [f64; 2],
    ) -> ColumnAttempt<E> {
        let mut last_failure = None;
        for step in steps {
            if step == 0.0 {
                continue;
            }
            match self.shifted(x, j, step) {
                Ok((rs, xs)) => {
                    let column = if step > 0.0 {
                        difference(&rs, r, xs - x[j])
                    } else {
                        difference(r, &rs, x[j] - xs)
                    };
                    return (Some(column), last_failure);
                }
                Err(e) => last_failure = Some(e),
            }
        }
        (None, last_failure)
    }

    /// Residuals at `x` with `x_j` moved by `step` (within the box), and the `x_j` actually
    /// used (the representable neighbour).
    fn shifted(&mut self, x: &[f64], j: usize, step: f64) -> Result<(Vec<f64>, f64), Failure<E>> {
        let mut moved = x.to_vec();
        moved[j] = x[j] + step;
        let xj = moved[j];
        self.eval(&moved).map(|r| (r, xj))
    }
}

/// A Jacobian column, if one was found, and the last evaluation that failed on the way.
type ColumnAttempt<E> = (Option<DVector<f64>>, Option<Failure<E>>);

/// The one-sided steps to try, in order: forward if there is room, else backward, else
/// whichever side has more room (a box narrower than the step); then the other side.
fn one_sided_steps(h: f64, room_up: f64, room_down: f64) -> [f64; 2] {
    let first = if room_up >= h {
        h
    } else if room_down >= h {
        -h
    } else if room_up >= room_down {
        room_up
    } else {
        -room_down
    };
    let second = if first > 0.0 {
        -h.min(room_down)
    } else {
        h.min(room_up)
    };
    [first, second]
}

/// `(a − b) / h` as a column.
fn difference(a: &[f64], b: &[f64], h: f64) -> DVector<f64> {
    DVector::from_iterator(a.len(), a.iter().zip(b).map(|(a, b)| (a - b) / h))
}

fn half_norm_squared(r: &[f64]) -> f64 {
    0.5 * r.iter().map(|v| v * v).sum::<f64>()
}

fn weighted_norm(d: &[f64], x: &[f64]) -> f64 {
    d.iter()
        .zip(x)
        .map(|(d, x)| (d * x) * (d * x))
        .sum::<f64>()
        .sqrt()
}

/// Rank, identifiability and the unscaled covariance `(JᵀJ)⁺` of the free parameters.
struct Analysis {
    status: Vec<ParameterStatus>,
    rank: usize,
    condition_number: f64,
    /// `(JᵀJ)⁺` for identifiable free parameters; NaN elsewhere (before the `s²` factor).
    covariance: DMatrix<f64>,
}

fn analyze(jacobian: &DMatrix<f64>, mut status: Vec<ParameterStatus>, tolerance: f64) -> Analysis {
    let (m, n) = jacobian.shape();
    let mut covariance = DMatrix::from_element(n, n, f64::NAN);
    let norms = column_norms(jacobian);
    // A free parameter that does not change the residuals at all.
    for j in 0..n {
        if status[j] == ParameterStatus::Free && norms[j] == 0.0 {
            status[j] = ParameterStatus::Unidentifiable;
        }
    }
    let columns: Vec<usize> = (0..n)
        .filter(|&j| status[j] == ParameterStatus::Free)
        .collect();
    let k = columns.len();
    if k == 0 {
        return Analysis {
            status,
            rank: 0,
            condition_number: 1.0,
            covariance,
        };
    }
    let normalized = DMatrix::from_fn(m, k, |i, c| jacobian[(i, columns[c])] / norms[columns[c]]);
    let svd = nalgebra::SVD::try_new(normalized, false, true, f64::EPSILON, 10_000);
    let Some((sv, v_t)) = svd.and_then(|s| Some((s.singular_values.clone(), s.v_t?))) else {
        for &j in &columns {
            status[j] = ParameterStatus::Unidentifiable;
        }
        return Analysis {
            status,
            rank: 0,
            condition_number: f64::INFINITY,
            covariance,
        };
    };
    let s_max = sv.iter().copied().fold(0.0, f64::max);
    // A wide Jacobian (m < k) has k − m more null directions than singular values.
    let s_min = if sv.len() < k {
        0.0
    } else {
        sv.iter().copied().fold(f64::INFINITY, f64::min)
    };
    let condition_number = if s_min > 0.0 {
        s_max / s_min
    } else {
        f64::INFINITY
    };
    let threshold = tolerance * s_max;
    let kept: Vec<usize> = (0..sv.len()).filter(|&i| sv[i] > threshold).collect();
    let rank = kept.len();
    // Null directions: the rows of Vᵀ below the threshold, and (for m < k) the orthogonal
    // complement of all rows, found through the projector I − VᵀV on the kept rows.
    let mut projector = DMatrix::<f64>::identity(k, k);
    for &i in &kept {
        let v = v_t.row(i).transpose();
        projector -= &v * v.transpose();
    }
    for c in 0..k {
        // Weight of parameter c in the null space: ‖P e_c‖ = √P_cc.
        if projector[(c, c)].max(0.0).sqrt() > NULL_WEIGHT {
            status[columns[c]] = ParameterStatus::Unidentifiable;
        }
    }
    // (JᵀJ)⁺ in normalized columns: Σ v vᵀ / σ², then unnormalize.
    let mut pseudo = DMatrix::<f64>::zeros(k, k);
    for &i in &kept {
        let v = v_t.row(i).transpose();
        pseudo += (&v * v.transpose()) / (sv[i] * sv[i]);
    }
    for a in 0..k {
        for b in 0..k {
            let (ja, jb) = (columns[a], columns[b]);
            if status[ja] == ParameterStatus::Free && status[jb] == ParameterStatus::Free {
                covariance[(ja, jb)] = pseudo[(a, b)] / (norms[ja] * norms[jb]);
            }
        }
    }
    Analysis {
        status,
        rank,
        condition_number,
        covariance,
    }
}

#[cfg(test)]
#[path = "lm_tests.rs"]
mod tests;
