//! Errors reported while running a model: by the integrators, the mass-matrix solve, the input
//! signals and the simulation driver.

use std::fmt;

/// Everything that can go wrong while running a model.
///
/// Times `t` are in the model's time unit (seconds for `.mech` models); step sizes `h` likewise.
/// Every message says what to try next.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum RuntimeError {
    /// `M(q)` could not be factored: it is singular (to working precision) or the solution of
    /// `M u̇ = F` was not finite although `M` and `F` were.
    SingularMassMatrix {
        /// Time at which the mass matrix was evaluated.
        t: f64,
    },
    /// The adaptive step size fell below the smallest step allowed (the `h_min` option, or
    /// ten units of roundoff of `t`): the solution is probably singular or very stiff there.
    StepSizeUnderflow {
        /// Time reached.
        t: f64,
        /// Step size that was about to be tried.
        h: f64,
    },
    /// The state or its derivative contains a NaN or an infinity.
    NonFiniteState {
        /// Last time at which the state was finite.
        t: f64,
    },
    /// The step budget (`max_steps`) was used up before the end time.
    TooManySteps {
        /// Time reached.
        t: f64,
        /// Number of steps taken (accepted and rejected).
        steps: usize,
    },
    /// A slice has the wrong length.
    LengthMismatch {
        /// What the slice holds, e.g. `"q0"` or `"signals"`.
        what: &'static str,
        /// Length required.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// An input signal is malformed (e.g. a table that is empty or not increasing in time).
    InvalidSignal(String),
    /// An option is out of range (e.g. a negative tolerance or an end time before the start).
    InvalidOptions(String),
    /// The loop closures could not be closed: `row` is the constraint row with the largest
    /// remaining residual (model units), `norm` the norm of all rows.
    AssemblyFailed {
        row: String,
        residual: f64,
        norm: f64,
    },
    /// The loop rows `rows` (names such as `link.distance`) are NaN or infinite at the
    /// coordinates the solver reached, in `φ` itself or (with `jacobian`) in `J = ∂φ/∂q`.
    NonFiniteConstraints { rows: Vec<String>, jacobian: bool },
    /// Loop row `row` is open by `residual` (model units), but no change of the free
    /// coordinates moves it: its gradient is zero there (a `distance` loop whose points
    /// coincide), so Newton steps cannot close it.
    StationaryConstraint { row: String, residual: f64 },
    /// A quantity a solver needs (`what`: "the static forces F", "the linear model", ...) is
    /// NaN or infinite.
    NonFinite { what: &'static str },
    /// The independent coordinates do not determine the others at this configuration: the
    /// loop Jacobian of the dependent coordinates is rank-deficient (reduced dynamics).
    SingularDependentJacobian {
        /// Time at which the loops were closed.
        t: f64,
    },
    /// `analysis` (statics, linearization, assembly, reduced coordinates) is written for
    /// `q̇ = u` and the model's rates are not its speeds: unit quaternions (`ball` or `free`
    /// joints: `q̇ = W(q) u`, four coordinates and three speeds each), Euler angles, or speeds
    /// chosen by `speed` declarations.
    QuaternionsUnsupported {
        /// What was asked, e.g. `"statics"`.
        analysis: &'static str,
        /// The model's name.
        model: String,
    },
    /// `analysis` (statics, linearization, reduced coordinates) works with the configuration
    /// alone and the model has velocity constraints `A(q) u = 0`, which have no position form.
    VelocityConstraintsUnsupported {
        /// What was asked, e.g. `"statics"`.
        analysis: &'static str,
        /// The model's name.
        model: String,
    },
    /// Dense output was requested outside the last step `[t_start, t_end]`.
    InterpolationOutOfRange {
        /// Requested time.
        t: f64,
        /// Start of the last step.
        t_start: f64,
        /// End of the last step.
        t_end: f64,
    },
}

impl fmt::Display for RuntimeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RuntimeError::SingularMassMatrix { t } => write!(
                f,
                "the mass matrix is singular at t = {t}: check for bodies without mass or \
                 inertia about a joint axis, and for a degenerate configuration (e.g. a lock-up)"
            ),
            RuntimeError::StepSizeUnderflow { t, h } => write!(
                f,
                "step size underflow at t = {t} (h = {h:e}): the solution is probably singular \
                 or very stiff there; check the model near this time, loosen the tolerances, \
                 or lower h_min"
            ),
            RuntimeError::NonFiniteState { t } => write!(
                f,
                "the state or its derivative became NaN or infinite after t = {t}: check the \
                 initial state, the parameters and the inputs for values that make the model \
                 blow up (divisions by zero, square roots of negative numbers)"
            ),
            RuntimeError::TooManySteps { t, steps } => write!(
                f,
                "gave up at t = {t} after {steps} steps: raise max_steps, shorten the \
                 simulation, or loosen the tolerances (a very large step count often means \
                 the model is stiff)"
            ),
            RuntimeError::LengthMismatch {
                what,
                expected,
                found,
            } => write!(
                f,
                "`{what}` has length {found} but the model needs {expected}: give one value per \
                 entry, in the model's order"
            ),
            RuntimeError::InvalidSignal(msg) => write!(f, "invalid input signal: {msg}"),
            RuntimeError::InvalidOptions(msg) => write!(f, "invalid options: {msg}"),
            RuntimeError::NonFiniteConstraints { rows, jacobian } => {
                let rows: Vec<String> = rows.iter().map(|row| format!("`{row}`")).collect();
                let (plural, what) = match (rows.len() > 1, jacobian) {
                    (false, false) => ("", "is"),
                    (true, false) => ("s", "are"),
                    (false, true) => ("", "has a Jacobian that is"),
                    (true, true) => ("s", "have Jacobians that are"),
                };
                write!(
                    f,
                    "cannot close the loops: row{plural} {} {what} not a number (NaN or \
                     infinite) at the coordinates reached; check the loops' expressions for a \
                     division by zero or a square root of a negative number at the parameters \
                     set, and start from another configuration (q0 of the joints)",
                    rows.join(", ")
                )
            }
            RuntimeError::StationaryConstraint { row, residual } => write!(
                f,
                "cannot close the loops: row `{row}` is {residual:e} away and no move of the \
                 free coordinates changes it here (its gradient is zero, as where the points \
                 of a `distance` loop coincide); start the mechanism from another \
                 configuration (q0 of the joints), where the loop's points are apart"
            ),
            RuntimeError::NonFinite { what } => write!(
                f,
                "{what} became not a number (NaN or infinite): check the parameters and \
                 inputs for values that make the model's expressions blow up (divisions by \
                 zero, square roots of negative numbers), and start from another configuration"
            ),
            RuntimeError::AssemblyFailed {
                row,
                residual,
                norm,
            } => write!(
                f,
                "cannot close the loops: row `{row}` is still {residual:e} away (|φ| = {norm:e}); \
                 start from a configuration closer to a closed one (q0 of the joints), check \
                 the loop's points, or free more coordinates"
            ),
            RuntimeError::SingularDependentJacobian { t } => write!(
                f,
                "at t = {t} the independent coordinates no longer determine the others (the \
                 loop Jacobian of the dependent coordinates is singular): choose other \
                 independent coordinates, or check the mechanism for a lock-up there"
            ),
            RuntimeError::QuaternionsUnsupported { analysis, model } => write!(
                f,
                "{analysis} of model `{model}` is not supported yet: its coordinates' rates are \
                 not its speeds (q̇ = W(q) u: a ball or free joint's unit quaternion or Euler \
                 angles, or `speed` declarations), and {analysis} is written for q̇ = u; \
                 simulate it in full coordinates (Dopri5, Dop853 or RK4), or write the joint \
                 as pins and sliders with their rates as speeds"
            ),
            RuntimeError::VelocityConstraintsUnsupported { analysis, model } => write!(
                f,
                "{analysis} of model `{model}` is not supported: it has velocity constraints \
                 (`constraint`), conditions on the speeds with no form in the coordinates, and \
                 {analysis} works with the coordinates alone; simulate it in full coordinates \
                 (Dopri5, Dop853 or RK4)"
            ),
            RuntimeError::InterpolationOutOfRange { t, t_start, t_end } => write!(
                f,
                "cannot interpolate at t = {t}: dense output only covers the last step \
                 [{t_start}, {t_end}]; interpolate after each step, before taking the next"
            ),
        }
    }
}

impl std::error::Error for RuntimeError {}
