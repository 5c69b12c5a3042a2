//! The Rosenbrock W-method ROS34PW2 of Rang & Angermann: the stages, error estimate and
//! dense output that the adaptive shell ([`AdaptiveStepper`]) steps with.
//!
//! Consumes the right-hand side and the system's own approximate Jacobian through
//! [`Ode::prepare_implicit`] (or `J` by differences, [`LinearSolve`]); produces the order-3
//! solution of each step, its scaled error norm against the embedded order-2 one, and a
//! cubic Hermite dense output.

use super::adaptive::{error_norm, AdaptiveMethod, DenseWithStep, Point, Step};
use super::rosenbrock::LinearSolve;
use super::{hermite, AdaptiveStepper, Ode};
use crate::RuntimeError;

// J. Rang and L. Angermann, "New Rosenbrock W-methods of order 3 for partial differential
// algebraic equations of index 1", BIT 45 (2005) 761–787, ROS34PW2: four stages, order 3 and
// the embedded order 2 for ANY matrix in W = I − hγJ̃ (a W-method), stiffly accurate and
// L-stable. With the stages k_i,
//   (I − hγJ̃) k_i = h f(t + α_i h, y + Σ_{j<i} α_ij k_j) + hJ̃ Σ_{j<i} γ_ij k_j,
//   y_new = y + Σ b_i k_i,  ŷ = y + Σ b̂_i k_i.
// Computed in Hairer & Wanner's variables u_i = Σ_{j≤i} γ_ij k_j (Solving ODEs II, §IV.7,
// (7.25)), which need no product J̃·k, only solves with W:
//   (I − hγJ̃) u_i = hγ f(t + α_i h, y + Σ_{j<i} a_ij u_j) + γ Σ_{j<i} c_ij u_j,
//   y_new = y + Σ m_i u_i,
// with Γ = (γ_ij) (diagonal γ), a = (α_ij) Γ⁻¹, c = diag(1/γ) − Γ⁻¹, m = bᵀ Γ⁻¹.
const STAGES: usize = 4;
/// γ.
const GAMMA: f64 = 4.358_665_215_084_59e-1;
/// α_ij, strictly lower.
const ALPHA: [[f64; STAGES]; STAGES] = [
    [0.0; STAGES],
    [8.717_330_430_169_18e-1, 0.0, 0.0, 0.0],
    [
        8.445_706_001_536_942e-1,
        -1.129_906_423_648_418_5e-1,
        0.0,
        0.0,
    ],
    [0.0, 0.0, 1.0, 0.0],
];
/// γ_ij, strictly lower (the diagonal is γ).
const GAMMA_BELOW: [[f64; STAGES]; STAGES] = [
    [0.0; STAGES],
    [-8.717_330_430_169_18e-1, 0.0, 0.0, 0.0],
    [
        -9.033_805_701_304_408e-1,
        5.418_067_238_809_533e-2,
        0.0,
        0.0,
    ],
    [
        2.421_238_070_609_534_6e-1,
        -1.223_250_583_904_514_7,
        5.452_602_553_351_021e-1,
        0.0,
    ],
];
/// b_i (order 3) and b̂_i (order 2).
const B: [f64; STAGES] = [
    2.421_238_070_609_534_6e-1,
    -1.223_250_583_904_514_7,
    1.545_260_255_335_102,
    4.358_665_215_084_59e-1,
];
const B_HAT: [f64; STAGES] = [
    3.781_090_314_581_937e-1,
    -9.604_229_221_242_318e-2,
    0.5,
    2.179_332_607_542_295e-1,
];

/// Adaptive Rosenbrock W-method ROS34PW2 (order 3, embedded order 2, L-stable, stiffly
/// accurate), with dense output.
///
/// A W-method: its order holds for any matrix `J̃` in `W = I − hγJ̃`, so a system can supply
/// only the stiff part of its Jacobian ([`Ode::prepare_implicit`]; the model's contacts for
/// [`Method::RosenbrockW`](crate::Method::RosenbrockW)) and the error estimate stays
/// consistent (unlike [`Rosenbrock`](super::Rosenbrock)'s, which assumes the exact `J`).
/// Each trial solves four systems with one `W` and evaluates the right-hand side three
/// times; an accepted step evaluates it once more at its end (the next step's first stage
/// and the dense output's slope), after the system's [`Ode::correct`]. Without the system's `J̃`, `J` is taken by differences.
pub type Ros34pw2<O> = AdaptiveStepper<O, Ros34pw2Method>;

/// The transformed coefficients (`a`, `c`, `m`, `m − m̂`) and the stage abscissae.
struct Coefficients {
    a: [[f64; STAGES]; STAGES],
    c: [[f64; STAGES]; STAGES],
    m: [f64; STAGES],
    error: [f64; STAGES],
    alpha: [f64; STAGES],
}

impl Coefficients {
    // Indexed loops: each line reads as the matrix formula it computes.
    #[allow(clippy::needless_range_loop)]
    fn new() -> Self {
        // Γ⁻¹ by forward substitution, column by column.
        let mut gamma = GAMMA_BELOW;
        for (i, row) in gamma.iter_mut().enumerate() {
            row[i] = GAMMA;
        }
        let mut inverse = [[0.0; STAGES]; STAGES];
        for column in 0..STAGES {
            for i in 0..STAGES {
                let unit = if i == column { 1.0 } else { 0.0 };
                let below: f64 = (0..i).map(|j| gamma[i][j] * inverse[j][column]).sum();
                inverse[i][column] = (unit - below) / gamma[i][i];
            }
        }
        let mut coefficients = Coefficients {
            a: [[0.0; STAGES]; STAGES],
            c: [[0.0; STAGES]; STAGES],
            m: [0.0; STAGES],
            error: [0.0; STAGES],
            alpha: [0.0; STAGES],
        };
        for i in 0..STAGES {
            coefficients.alpha[i] = ALPHA[i].iter().sum();
            for j in 0..STAGES {
                coefficients.a[i][j] = (0..STAGES).map(|k| ALPHA[i][k] * inverse[k][j]).sum();
                let diagonal = if i == j { 1.0 / GAMMA } else { 0.0 };
                coefficients.c[i][j] = diagonal - inverse[i][j];
            }
            coefficients.m[i] = (0..STAGES).map(|k| B[k] * inverse[k][i]).sum();
            let embedded: f64 = (0..STAGES).map(|k| B_HAT[k] * inverse[k][i]).sum();
            coefficients.error[i] = coefficients.m[i] - embedded;
        }
        coefficients
    }
}

/// The stages `u_i`, the stage state and derivative, the linear solve and the dense output.
pub struct Ros34pw2Method {
    coefficients: Coefficients,
    stages: [Vec<f64>; STAGES],
    x_stage: Vec<f64>,
    f_stage: Vec<f64>,
    linear: LinearSolve,
    /// Dense output of the last step: `x`, `f` at its start and end, and its length.
    start: Point,
    end_derivative: Vec<f64>,
    end: Vec<f64>,
    h: f64,
}

impl DenseWithStep for Ros34pw2Method {}

impl AdaptiveMethod for Ros34pw2Method {
    const ORDER: i32 = 3;
    const EVALUATIONS_PER_TRIAL: usize = 3;

    /// The error estimate is O(h³): exponent 1/3, less the Lund stabilisation.
    fn error_exponent(beta: f64) -> f64 {
        1.0 / 3.0 - 0.75 * beta
    }

    fn new(x0: &[f64]) -> Self {
        let n = x0.len();
        let zeros = vec![0.0; n];
        Ros34pw2Method {
            coefficients: Coefficients::new(),
            stages: std::array::from_fn(|_| zeros.clone()),
            x_stage: zeros.clone(),
            f_stage: zeros.clone(),
            linear: LinearSolve::new(n),
            start: Point {
                x: x0.to_vec(),
                f: zeros.clone(),
            },
            end_derivative: zeros.clone(),
            end: zeros,
            h: 0.0,
        }
    }

    fn derivative_refreshed(&mut self) {
        self.linear.derivative_refreshed();
    }

    /// A trial step of size `h` from `(t, x)`: `x_new` and the scaled error norm (NaN also
    /// if `W` is singular); `f(t + h, x_new)` waits for the acceptance.
    fn trial<O: Ode>(&mut self, ode: &mut O, step: Step<'_>) -> Result<f64, RuntimeError> {
        let (opts, now, t, h) = (step.opts, step.now, step.t, step.h);
        let (x, f0) = (&now.x, &now.f);
        let hg = h * GAMMA;
        if !self.linear.prepare(ode, step.stats, t, x, f0, hg)? {
            return Ok(f64::NAN);
        }
        let Coefficients { a, c, alpha, .. } = &self.coefficients;
        for i in 0..STAGES {
            let (done, rest) = self.stages.split_at_mut(i);
            let stage = &mut rest[0];
            if i == 0 {
                stage.copy_from_slice(f0);
            } else {
                self.x_stage.copy_from_slice(x);
                for (u, &a_ij) in done.iter().zip(&a[i]) {
                    for (y, u) in self.x_stage.iter_mut().zip(u) {
                        *y += a_ij * u;
                    }
                }
                ode.rhs(t + alpha[i] * h, &self.x_stage, &mut self.f_stage)?;
                stage.copy_from_slice(&self.f_stage);
            }
            // hγ f_i + γ Σ_{j<i} c_ij u_j, then W⁻¹.
            for value in stage.iter_mut() {
                *value *= hg;
            }
            for (u, &c_ij) in done.iter().zip(&c[i]) {
                for (value, u) in stage.iter_mut().zip(u) {
                    *value += GAMMA * c_ij * u;
                }
            }
            self.linear.solve(ode, stage);
        }
        let Coefficients { m, error, .. } = &self.coefficients;
        let x_new = &mut step.next.x;
        x_new.copy_from_slice(x);
        for (u, &m_i) in self.stages.iter().zip(m) {
            for (y, u) in x_new.iter_mut().zip(u) {
                *y += m_i * u;
            }
        }
        let stages = &self.stages;
        let estimate = |k: usize| (0..STAGES).map(|i| error[i] * stages[i][k]).sum::<f64>();
        // The last stage's derivative stands in for the end's in the finiteness test.
        Ok(error_norm(opts, x, x_new, &self.f_stage, estimate))
    }

    fn accept<O: Ode>(&mut self, ode: &mut O, step: Step<'_>) -> Result<(), RuntimeError> {
        let (t, h) = (step.t, step.h);
        // The system's correction (the loops' projection) before the end's derivative, so
        // that the derivative is not evaluated twice.
        ode.correct(t + h, &mut step.next.x)?;
        ode.rhs(t + h, &step.next.x, &mut step.next.f)?;
        step.stats.rhs_evaluations += 1;
        self.start.x.copy_from_slice(&step.now.x);
        self.start.f.copy_from_slice(&step.now.f);
        self.end.copy_from_slice(&step.next.x);
        self.end_derivative.copy_from_slice(&step.next.f);
        self.h = h;
        self.linear.accepted();
        Ok(())
    }

    fn interpolate(&mut self, _t: f64, theta: f64, out: &mut [f64]) -> Result<(), RuntimeError> {
        let start = (&self.start.x[..], &self.start.f[..]);
        let end = (&self.end[..], &self.end_derivative[..]);
        hermite(theta, self.h, start, end, out);
        Ok(())
    }
}
