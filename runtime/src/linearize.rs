//! Linearization about an operating point to minimal coordinates, normal modes, and the
//! frequency response of the linear model.
//!
//! Consumes: a [`Model`], a consistent operating point (usually an equilibrium from
//! [`solve_statics`](crate::solve_statics)) and the independent coordinates `z ⊂ q`.
//! Produces: a [`Linearization`] `M δz̈ + C δż + K δz = B δin`, `δy = C_q δz + C_u δż + D δin`.
//!
//! The reduced dynamics `z̈ = f(z, ż, in)` ([`Reduced`]) close the loops for each `(z, ż)` and
//! project the equations of motion onto the motions they allow, so constraint forces and
//! geometric stiffness are included. Its derivatives are central differences refined by
//! one Richardson step (error O(h⁴)). `M = Tᵀ M(q) T` with `T = ∂q/∂z` (exact, from the
//! speed map); then `K = −M ∂f/∂z`, `C = −M ∂f/∂ż`, `B = M ∂f/∂in`.

use nalgebra::{Complex, DMatrix, DVector};

use crate::constraints::AssemblyOptions;
use crate::reduced::Reduced;
use crate::signal::default_signals;
use crate::{Model, RuntimeError};

/// `M δz̈ + C δż + K δz = B δin` and `δy = C_q δz + C_u δż + D δin` about `q`, `inputs`.
#[derive(Clone, Debug, PartialEq)]
pub struct Linearization {
    /// Indices (in the model's `q`) of the minimal coordinates `z`.
    pub independent: Vec<usize>,
    pub q: Vec<f64>,
    pub inputs: Vec<f64>,
    pub mass: DMatrix<f64>,
    pub damping: DMatrix<f64>,
    pub stiffness: DMatrix<f64>,
    /// `B`: generalized force per unit input.
    pub input: DMatrix<f64>,
    pub output_position: DMatrix<f64>,
    pub output_velocity: DMatrix<f64>,
    pub output_input: DMatrix<f64>,
    /// `G = ∂θ/∂z`: each flexure's bending angle per unit minimal coordinate (`nflexures × n`).
    pub flexure_gradient: DMatrix<f64>,
    /// Each flexure's stiffness `k`, time-domain damping `b` and loss factor `η` at the
    /// operating point.
    pub flexure_stiffness: Vec<f64>,
    pub flexure_damping: Vec<f64>,
    pub flexure_loss: Vec<f64>,
}

/// How flexure losses enter a frequency response.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FlexureDamping {
    /// As the time-domain viscous dampers `b = kη/ω_ref` (already in `C`).
    Viscous,
    /// As the complex stiffness `k(1 + iη)`, exact at every frequency: `C − Gᵀ diag(b) G`
    /// and `+ i Gᵀ diag(ηk) G`.
    Hysteretic,
    /// As `Hysteretic` with a loss factor that depends on frequency as a power law,
    /// `η(ω) = η·(f/reference_hz)^exponent` (the seed, Sec. VI: η estimated at 1–10 Hz
    /// over-predicts the quality factors at the 40–150 Hz resonances).
    HystereticPowerLaw {
        /// The power of frequency (0: `Hysteretic`).
        exponent: f64,
        /// The frequency at which the flexures' `η` holds, Hz (> 0).
        reference_hz: f64,
    },
}

/// `ẋ = A x + B in`, `y = C x + D in`.
#[derive(Clone, Debug, PartialEq)]
pub struct StateSpace {
    pub a: DMatrix<f64>,
    pub b: DMatrix<f64>,
    pub c: DMatrix<f64>,
    pub d: DMatrix<f64>,
}

/// One undamped normal mode with its modal damping.
#[derive(Clone, Debug, PartialEq)]
pub struct Mode {
    /// Undamped natural frequency ω_n in rad/s (from `K v = ω² M v`); negative for an
    /// unstable mode (ω² < 0), whose growth rate is then `−natural_frequency`.
    pub natural_frequency: f64,
    /// Modal damping ratio `ζ = vᵀ C v / (2 ω_n vᵀ M v)`.
    pub damping_ratio: f64,
    /// Shape in the minimal coordinates, scaled to unit largest component.
    pub shape: Vec<f64>,
}

impl Mode {
    pub fn frequency_hz(&self) -> f64 {
        self.natural_frequency / std::f64::consts::TAU
    }
}

/// Central difference of `f` along one argument, with one Richardson refinement.
pub(crate) fn derivative(
    mut f: impl FnMut(f64) -> Result<Vec<f64>, RuntimeError>,
    h: f64,
) -> Result<Vec<f64>, RuntimeError> {
    let mut central = |h: f64| -> Result<Vec<f64>, RuntimeError> {
        let (plus, minus) = (f(h)?, f(-h)?);
        Ok(plus
            .iter()
            .zip(&minus)
            .map(|(a, b)| (a - b) / (2.0 * h))
            .collect())
    };
    let (coarse, fine) = (central(h)?, central(h / 2.0)?);
    Ok(coarse
        .iter()
        .zip(&fine)
        .map(|(c, f)| (4.0 * f - c) / 3.0)
        .collect())
}

pub(crate) fn step_for(value: f64) -> f64 {
    1e-5 * value.abs().max(1e-3)
}

/// Linearizes `model` about `(q, u = 0, inputs)` in the minimal coordinates `independent`
/// (all coordinates for a tree model). `q` must satisfy the loop closures.
pub fn linearize<M: Model + ?Sized>(
    model: &M,
    t: f64,
    q: &[f64],
    inputs: &[f64],
    independent: &[usize],
) -> Result<Linearization, RuntimeError> {
    model.require_rates_are_speeds("linearization")?;
    model.require_holonomic("linearization")?;
    let n = independent.len();
    let (ni, ny) = (model.ninputs(), model.noutputs());
    let signals = default_signals(model);
    let tolerance = AssemblyOptions::default().tolerance;
    let mut reduced = Reduced::new(model, &signals, t, q, independent, tolerance)?;
    let z0: Vec<f64> = independent.iter().map(|&i| q[i]).collect();
    let zdot0 = vec![0.0; n];
    // `[z̈; y]` at `(z, ż, in)`.
    let evaluate = |reduced: &mut Reduced<'_, M>,
                    z: &[f64],
                    zdot: &[f64],
                    inputs: &[f64]|
     -> Result<Vec<f64>, RuntimeError> {
        let mut values = vec![0.0; n + ny];
        let (zddot, y) = values.split_at_mut(n);
        reduced.accelerations(t, z, zdot, inputs, zddot)?;
        model.outputs(t, reduced.q(), reduced.u(), inputs, y);
        Ok(values)
    };

    // T = ∂q/∂z: the speed map is linear in ż, so its columns are exact.
    let mut transform = DMatrix::zeros(model.nq(), n);
    for k in 0..n {
        let mut unit = vec![0.0; n];
        unit[k] = 1.0;
        reduced.state(t, &z0, &unit)?;
        transform.column_mut(k).copy_from_slice(reduced.u());
    }
    let mut full_mass = DMatrix::zeros(model.nq(), model.nq());
    model.mass_matrix(t, q, inputs, full_mass.as_mut_slice());
    let mass = transform.transpose() * &full_mass * &transform;

    let (mut a_z, mut a_zdot, mut a_in) = (
        DMatrix::zeros(n, n),
        DMatrix::zeros(n, n),
        DMatrix::zeros(n, ni),
    );
    let (mut c_q, mut c_u, mut d) = (
        DMatrix::zeros(ny, n),
        DMatrix::zeros(ny, n),
        DMatrix::zeros(ny, ni),
    );
    // Each column: derivative of [z̈; y] with respect to one argument.
    let column =
        |reduced: &mut Reduced<'_, M>, which: usize, k: usize| -> Result<Vec<f64>, RuntimeError> {
            let base = [&z0, &zdot0, &inputs.to_vec()][which][k];
            derivative(
                |h| {
                    let (mut z, mut zdot, mut input) = (z0.clone(), zdot0.clone(), inputs.to_vec());
                    [&mut z, &mut zdot, &mut input][which][k] += h;
                    evaluate(reduced, &z, &zdot, &input)
                },
                step_for(base),
            )
        };
    for k in 0..n {
        let dz = column(&mut reduced, 0, k)?;
        a_z.column_mut(k).copy_from_slice(&dz[..n]);
        c_q.column_mut(k).copy_from_slice(&dz[n..]);
        let dzdot = column(&mut reduced, 1, k)?;
        a_zdot.column_mut(k).copy_from_slice(&dzdot[..n]);
        c_u.column_mut(k).copy_from_slice(&dzdot[n..]);
    }
    for k in 0..ni {
        let din = column(&mut reduced, 2, k)?;
        a_in.column_mut(k).copy_from_slice(&din[..n]);
        d.column_mut(k).copy_from_slice(&din[n..]);
    }
    // Flexure angles along z: G = ∂θ/∂z by the same central differences.
    let nf = model.nflexures();
    let mut values = vec![0.0; 4 * nf];
    model.flexures(t, q, &mut values);
    let mut gradient = DMatrix::zeros(nf, n);
    for k in 0..n {
        let column = derivative(
            |h| {
                let mut z = z0.clone();
                z[k] += h;
                reduced.state(t, &z, &zdot0)?;
                let mut out = vec![0.0; 4 * nf];
                model.flexures(t, reduced.q(), &mut out);
                Ok(out[..nf].to_vec())
            },
            step_for(z0[k]),
        )?;
        gradient.column_mut(k).copy_from_slice(&column);
    }
    let finite = |m: &DMatrix<f64>| m.iter().all(|x| x.is_finite());
    if ![&mass, &a_z, &a_zdot, &a_in, &c_q, &c_u, &d, &gradient]
        .into_iter()
        .all(finite)
    {
        return Err(RuntimeError::NonFinite {
            what: "the linear model (M, C, K, B or the output matrices)",
        });
    }
    Ok(Linearization {
        flexure_gradient: gradient,
        flexure_stiffness: values[nf..2 * nf].to_vec(),
        flexure_damping: values[2 * nf..3 * nf].to_vec(),
        flexure_loss: values[3 * nf..].to_vec(),
        independent: independent.to_vec(),
        q: q.to_vec(),
        inputs: inputs.to_vec(),
        stiffness: -(&mass * a_z),
        damping: -(&mass * a_zdot),
        input: &mass * a_in,
        mass,
        output_position: c_q,
        output_velocity: c_u,
        output_input: d,
    })
}

impl Linearization {
    /// First-order form `ẋ = A x + B in`, `y = C x + D in` with `x = [δz; δż]`.
    pub fn state_space(&self) -> Option<StateSpace> {
        let n = self.mass.nrows();
        if !self.is_finite() {
            return None;
        }
        let lu = self.mass.clone().lu();
        let minv_k = lu.solve(&self.stiffness)?;
        let minv_c = lu.solve(&self.damping)?;
        let minv_b = lu.solve(&self.input)?;
        let mut a = DMatrix::zeros(2 * n, 2 * n);
        a.view_mut((0, n), (n, n)).fill_with_identity();
        a.view_mut((n, 0), (n, n)).copy_from(&(-minv_k));
        a.view_mut((n, n), (n, n)).copy_from(&(-minv_c));
        let mut b = DMatrix::zeros(2 * n, self.input.ncols());
        b.view_mut((n, 0), (n, self.input.ncols()))
            .copy_from(&minv_b);
        let mut c = DMatrix::zeros(self.output_position.nrows(), 2 * n);
        c.view_mut((0, 0), (c.nrows(), n))
            .copy_from(&self.output_position);
        c.view_mut((0, n), (c.nrows(), n))
            .copy_from(&self.output_velocity);
        Some(StateSpace {
            a,
            b,
            c,
            d: self.output_input.clone(),
        })
    }

    /// Whether the matrices and flexure records are finite (a [`linearize`] result is; the
    /// fields are public), so that they may be decomposed.
    fn is_finite(&self) -> bool {
        let finite = |values: &[f64]| values.iter().all(|x| x.is_finite());
        [&self.mass, &self.damping, &self.stiffness, &self.input]
            .into_iter()
            .all(|m| finite(m.as_slice()))
            && finite(self.flexure_gradient.as_slice())
            && finite(&self.flexure_stiffness)
            && finite(&self.flexure_damping)
            && finite(&self.flexure_loss)
    }

    /// Undamped normal modes `K v = ω² M v` (K symmetrized), lowest first, with modal
    /// damping ratios. `None` if `M` is not positive definite or a matrix is not finite.
    pub fn modes(&self) -> Option<Vec<Mode>> {
        if self.mass.is_empty() {
            return Some(Vec::new());
        }
        if !self.is_finite() {
            return None;
        }
        let cholesky = self.mass.clone().cholesky()?;
        let l = cholesky.l();
        let l_inv = l.clone().try_inverse()?;
        let k_sym = (&self.stiffness + self.stiffness.transpose()) * 0.5;
        let s = &l_inv * k_sym * l_inv.transpose();
        let s = (&s + s.transpose()) * 0.5;
        // Capped: nalgebra's default iterates until convergence (symmetric matrices of
        // these sizes converge in tens of sweeps).
        let eigen = s.try_symmetric_eigen(f64::EPSILON, 10_000)?;
        let mut modes: Vec<Mode> = (0..eigen.eigenvalues.len())
            .map(|k| {
                let omega_squared = eigen.eigenvalues[k];
                let v = l_inv.transpose() * eigen.eigenvectors.column(k);
                let largest =
                    v.iter()
                        .copied()
                        .fold(0.0_f64, |m, x| if x.abs() > m.abs() { x } else { m });
                let shape: Vec<f64> = v.iter().map(|x| x / largest).collect();
                let shape_vector = DVector::from_column_slice(&shape);
                let modal_mass = shape_vector.dot(&(&self.mass * &shape_vector));
                let modal_damping = shape_vector.dot(&(&self.damping * &shape_vector));
                let natural_frequency = omega_squared.abs().sqrt();
                let damping_ratio = if natural_frequency > 0.0 {
                    modal_damping / (2.0 * natural_frequency * modal_mass)
                } else {
                    f64::NAN
                };
                let signed = if omega_squared < 0.0 {
                    -natural_frequency
                } else {
                    natural_frequency
                };
                Mode {
                    natural_frequency: signed,
                    damping_ratio,
                    shape,
                }
            })
            .collect();
        modes.sort_by(|a, b| a.natural_frequency.total_cmp(&b.natural_frequency));
        Some(modes)
    }

    /// `Gᵀ diag(w) G` over the flexures.
    fn flexure_matrix(&self, weights: impl Fn(usize) -> f64) -> DMatrix<f64> {
        let g = &self.flexure_gradient;
        let mut weighted = g.clone();
        for f in 0..g.nrows() {
            weighted.row_mut(f).scale_mut(weights(f));
        }
        g.transpose() * weighted
    }

    /// The flexures' hysteretic stiffness `K_h = Gᵀ diag(η k) G`.
    pub fn hysteretic_stiffness(&self) -> DMatrix<f64> {
        self.flexure_matrix(|f| self.flexure_loss[f] * self.flexure_stiffness[f])
    }

    /// `y/in` at angular frequency `omega` for one input and one output:
    /// `(C_q + iω C_u)(K − ω²M + iωC)⁻¹ B + D`, with the flexures' losses as chosen by
    /// `damping` (viscous as in the time domain, or the exact complex stiffness).
    pub fn frequency_response(
        &self,
        input: usize,
        output: usize,
        omega: f64,
        damping: FlexureDamping,
    ) -> Option<Complex<f64>> {
        let (viscous, hysteretic) = match damping {
            FlexureDamping::Viscous => (
                self.damping.clone(),
                DMatrix::zeros(self.mass.nrows(), self.mass.ncols()),
            ),
            FlexureDamping::Hysteretic => (
                &self.damping - self.flexure_matrix(|f| self.flexure_damping[f]),
                self.hysteretic_stiffness(),
            ),
            FlexureDamping::HystereticPowerLaw {
                exponent,
                reference_hz,
            } => {
                let scale = (omega / (2.0 * std::f64::consts::PI * reference_hz)).powf(exponent);
                (
                    &self.damping - self.flexure_matrix(|f| self.flexure_damping[f]),
                    self.hysteretic_stiffness() * scale,
                )
            }
        };
        let n = self.mass.nrows();
        if !(omega.is_finite() && self.is_finite()) {
            return None;
        }
        let i = Complex::new(0.0, 1.0);
        let dynamic = DMatrix::from_fn(n, n, |r, c| {
            Complex::new(
                self.stiffness[(r, c)] - omega * omega * self.mass[(r, c)],
                omega * viscous[(r, c)] + hysteretic[(r, c)],
            )
        });
        let b = DVector::from_fn(n, |r, _| Complex::new(self.input[(r, input)], 0.0));
        let x = dynamic.lu().solve(&b)?;
        let mut y = Complex::new(self.output_input[(output, input)], 0.0);
        for k in 0..n {
            y += (Complex::new(self.output_position[(output, k)], 0.0)
                + i * omega * self.output_velocity[(output, k)])
                * x[k];
        }
        Some(y)
    }
}
