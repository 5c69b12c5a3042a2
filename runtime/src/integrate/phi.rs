//! The matrix φ-functions `φ_0(A) = e^A`, `φ_k(A) = Σ_j A^j/(j+k)!` (k = 1…4) of a small dense
//! matrix, for the exponential integrator, without allocation.
//!
//! Scaling and squaring for φ-functions (Skaflestad & Wright, "The scaling and squaring method
//! for matrix functions related to the exponential", Appl. Numer. Math. 59, 2009): balance
//! `A` by a diagonal similarity (powers of 2, Parlett & Reinsch; the HAMR leg's Jacobian mixes
//! m and m/s, which would otherwise cost a dozen extra squarings), scale it to
//! `B = A/2^s` with `‖B‖₁ ≤ 4`, sum the Taylor series of `φ_4(B) = Σ_j B^j/(j+4)!` to degree
//! 27 (truncation `‖B‖^28/32! < 3e-19`) by Paterson & Stockmeyer (powers `B², B³, B⁴`, then
//! Horner in `B⁴` over blocks of four terms: 9 products, where Horner in `B` to degree 10 at
//! `‖B‖₁ ≤ 1/2` took 10 products and three more doublings of 5 products each), recover
//! `φ_3 … φ_0` by `φ_k(B) = B φ_{k+1}(B) + I/k!`, and double the argument `s` times with
//! `φ_k(2B) = (φ_0(B) φ_k(B) + Σ_{j=1..k} φ_j(B)/(k−j)!)/2^k`. The last doubling starts from
//! `A/2`, whose `φ_1` and `φ_2` are kept as well.

use crate::dense;

/// Highest φ-function computed.
pub(crate) const MAX_ORDER: usize = 4;
/// `‖B‖₁` bound after scaling, and the Taylor degree of `φ_4(B)` (a multiple of
/// [`BLOCK`] less one) that makes the truncation `‖B‖^(d+1)/(d+5)!` negligible.
const SCALED_NORM: f64 = 4.0;
const TAYLOR_DEGREE: usize = 27;
/// Terms per Paterson–Stockmeyer block (the highest power formed is `B^BLOCK`).
const BLOCK: usize = 4;
/// `1/k!` for `k ≤ TAYLOR_DEGREE + MAX_ORDER`.
const INVERSE_FACTORIAL: [f64; TAYLOR_DEGREE + MAX_ORDER + 1] = {
    let mut table = [1.0; TAYLOR_DEGREE + MAX_ORDER + 1];
    let mut k = 1;
    while k < table.len() {
        table[k] = table[k - 1] / k as f64;
        k += 1;
    }
    table
};

/// φ_0 … φ_4 of one `n × n` matrix (column-major), and `φ_1`, `φ_2` of half of it.
pub(crate) struct PhiFunctions {
    n: usize,
    /// `φ_k` of the balanced matrix, `k = 0..=4`.
    phi: [Vec<f64>; MAX_ORDER + 1],
    /// `φ_1` and `φ_2` of half the balanced matrix.
    half: [Vec<f64>; 2],
    /// The balancing: `A = D Ã D⁻¹` with `D = diag(scale)`.
    scale: Vec<f64>,
    /// `D⁻¹ J D` for the matrix `J` of the last [`PhiFunctions::compute_multiple`] that
    /// balanced, and its 1-norm: the balancing of `τ J` is that of `J` for every `τ`.
    balanced: Vec<f64>,
    balanced_norm: f64,
    scaled: Vec<f64>,
    next: [Vec<f64>; MAX_ORDER + 1],
    product: Vec<f64>,
    work: Vec<f64>,
}

impl PhiFunctions {
    pub(crate) fn new(n: usize) -> Self {
        let square = || vec![0.0; n * n];
        PhiFunctions {
            n,
            phi: std::array::from_fn(|_| square()),
            half: [square(), square()],
            scale: vec![1.0; n],
            balanced: square(),
            balanced_norm: f64::NAN,
            scaled: square(),
            next: std::array::from_fn(|_| square()),
            product: square(),
            work: vec![0.0; n],
        }
    }

    /// Computes the functions of `a` (`n × n`); false if `a` or a result is not finite.
    #[cfg(test)]
    pub(crate) fn compute(&mut self, a: &[f64]) -> bool {
        self.compute_multiple(a, 1.0, true)
    }

    /// Computes the functions of `τ·j` (`j` is `n × n`); false if `τ·j` or a result is not
    /// finite. With `rebalance` false, `j` must be the matrix of the last call that
    /// rebalanced (not read again): its balancing serves, which saves the balancing sweeps
    /// when one matrix is taken at several `τ` (the trial steps and the dense output of one
    /// Jacobian).
    pub(crate) fn compute_multiple(&mut self, j: &[f64], tau: f64, rebalance: bool) -> bool {
        let n = self.n;
        if rebalance {
            self.balanced_norm = f64::NAN;
            if !j[..n * n].iter().all(|v| v.is_finite()) {
                return false;
            }
            self.balanced.copy_from_slice(&j[..n * n]);
            balance(&mut self.balanced, n, &mut self.scale);
            self.balanced_norm = (0..n)
                .map(|c| {
                    self.balanced[n * c..n * (c + 1)]
                        .iter()
                        .map(|v| v.abs())
                        .sum::<f64>()
                })
                .fold(0.0, f64::max);
        }
        let norm = tau.abs() * self.balanced_norm;
        if !norm.is_finite() {
            return false;
        }
        // At least one doubling, so that φ_1(A/2) and φ_2(A/2) fall out of the chain.
        let squarings = (norm / SCALED_NORM).log2().ceil().max(1.0) as i32;
        let factor = tau * 0.5f64.powi(squarings);
        for (s, b) in self.scaled.iter_mut().zip(&self.balanced) {
            *s = factor * b;
        }
        self.taylor_phi4();
        // φ_k(B) = B φ_{k+1}(B) + I/k!.
        let [phi0, phi1, phi2, phi3, phi4] = &mut self.phi;
        dense::multiply(&self.scaled, phi4, n, phi3);
        add_identity(phi3, n, INVERSE_FACTORIAL[3]);
        dense::multiply(&self.scaled, phi3, n, phi2);
        add_identity(phi2, n, INVERSE_FACTORIAL[2]);
        dense::multiply(&self.scaled, phi2, n, phi1);
        add_identity(phi1, n, 1.0);
        dense::multiply(&self.scaled, phi1, n, phi0);
        add_identity(phi0, n, 1.0);
        for step in 0..squarings {
            if step == squarings - 1 {
                self.half[0].copy_from_slice(&self.phi[1]);
                self.half[1].copy_from_slice(&self.phi[2]);
            }
            self.double();
        }
        self.phi
            .iter()
            .chain(&self.half)
            .all(|m| m.iter().all(|v| v.is_finite()))
    }

    /// `φ_4(B) = Σ_{j ≤ TAYLOR_DEGREE} B^j/(j+4)!` into `phi[4]`, for `B` in `scaled`, by
    /// Paterson–Stockmeyer: `R ← B⁴ R + Σ_{r<4} c_{4i+r} B^r` for blocks `i` from the last
    /// down. `next` holds the powers `B^1 … B^BLOCK` meanwhile.
    fn taylor_phi4(&mut self) {
        let n = self.n;
        let [b1, b2, b3, b4, _] = &mut self.next;
        b1.copy_from_slice(&self.scaled);
        dense::multiply(b1, b1, n, b2);
        dense::multiply(b1, b2, n, b3);
        dense::multiply(b2, b2, n, b4);
        let powers = [&*b1, &*b2, &*b3];
        let coefficient = |j: usize| INVERSE_FACTORIAL[j + MAX_ORDER];
        // `out = Σ_{r<BLOCK} c_{first+r} B^r` (+ the `B⁴ R` already in `out` if `add`).
        let block = |first: usize, out: &mut [f64], add: bool| {
            if !add {
                out.fill(0.0);
            }
            for (power, r) in powers.iter().zip(1..) {
                let c = coefficient(first + r);
                for (o, p) in out.iter_mut().zip(power.iter()) {
                    *o += c * p;
                }
            }
            add_identity(out, n, coefficient(first));
        };
        let blocks = (TAYLOR_DEGREE + 1) / BLOCK;
        let phi4 = &mut self.phi[MAX_ORDER];
        block(BLOCK * (blocks - 1), phi4, false);
        for i in (0..blocks - 1).rev() {
            dense::multiply(b4, phi4, n, &mut self.product);
            block(BLOCK * i, &mut self.product, true);
            std::mem::swap(phi4, &mut self.product);
        }
    }

    /// `φ_k(2B)` from `φ_k(B)`, for all k.
    fn double(&mut self) {
        let n = self.n;
        for k in 0..=MAX_ORDER {
            dense::multiply(&self.phi[0], &self.phi[k], n, &mut self.next[k]);
            for j in 1..=k {
                let weight = INVERSE_FACTORIAL[k - j];
                for (out, v) in self.next[k].iter_mut().zip(&self.phi[j]) {
                    *out += weight * v;
                }
            }
            let halving = 0.5f64.powi(k as i32);
            for v in &mut self.next[k] {
                *v *= halving;
            }
        }
        std::mem::swap(&mut self.phi, &mut self.next);
    }

    /// `out += φ_k(A) v` (`k ≤ 4`; `v` and `out` of length `n`).
    pub(crate) fn add_apply(&mut self, k: usize, v: &[f64], out: &mut [f64]) {
        apply(&self.phi[k], &self.scale, self.n, v, out, &mut self.work);
    }

    /// `out += φ_k(A/2) v` for `k` = 1 or 2.
    pub(crate) fn add_apply_half(&mut self, k: usize, v: &[f64], out: &mut [f64]) {
        apply(
            &self.half[k - 1],
            &self.scale,
            self.n,
            v,
            out,
            &mut self.work,
        );
    }
}

/// `out += D M D⁻¹ v`.
fn apply(m: &[f64], scale: &[f64], n: usize, v: &[f64], out: &mut [f64], work: &mut [f64]) {
    for ((w, v), d) in work.iter_mut().zip(v).zip(scale) {
        *w = v / d;
    }
    for (j, column) in m.chunks_exact(n).enumerate() {
        let wj = work[j];
        for ((o, c), d) in out.iter_mut().zip(column).zip(scale) {
            *o += d * c * wj;
        }
    }
}

fn add_identity(m: &mut [f64], n: usize, value: f64) {
    for i in 0..n {
        m[i + n * i] += value;
    }
}

/// Parlett–Reinsch balancing in place (`a ← D⁻¹ a D`, `D = diag(scale)`, powers of 2, no
/// permutations), as LAPACK's `dgebal` with `job = 'S'`.
fn balance(a: &mut [f64], n: usize, scale: &mut [f64]) {
    scale.fill(1.0);
    for _sweep in 0..32 {
        let mut converged = true;
        for i in 0..n {
            let (mut c, mut r) = (0.0, 0.0);
            for j in (0..n).filter(|&j| j != i) {
                c += a[j + n * i].abs();
                r += a[i + n * j].abs();
            }
            if c == 0.0 || r == 0.0 {
                continue;
            }
            let (mut f, sum) = (1.0, c + r);
            let (mut c2, mut r2) = (c, r);
            while c2 < r2 / 2.0 {
                c2 *= 2.0;
                r2 /= 2.0;
                f *= 2.0;
            }
            while c2 >= r2 * 2.0 {
                c2 /= 2.0;
                r2 *= 2.0;
                f /= 2.0;
            }
            if c2 + r2 < 0.95 * sum {
                converged = false;
                scale[i] *= f;
                // Row i divided by f, column i multiplied by f.
                for j in 0..n {
                    a[i + n * j] /= f;
                    a[j + n * i] *= f;
                }
            }
        }
        if converged {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    /// φ_k(A) v by the exponential of the augmented matrix `[[A, v e_kᵀ…], [0, shift]]`
    /// (Al-Mohy & Higham 2011, Thm 2.1), with nalgebra's `exp`.
    fn reference(a: &DMatrix<f64>, k: usize, v: &[f64]) -> Vec<f64> {
        let n = a.nrows();
        let mut m = DMatrix::zeros(n + k, n + k);
        m.view_mut((0, 0), (n, n)).copy_from(a);
        for i in 0..n {
            m[(i, n)] = v[i];
        }
        for i in 0..k.saturating_sub(1) {
            m[(n + i, n + i + 1)] = 1.0;
        }
        let e = m.exp();
        (0..n).map(|i| e[(i, n + k - 1)]).collect()
    }

    /// A lightly damped oscillator at 100 Hz in metres and m/s plus a driven clock row: the
    /// shape (and the badly scaled entries) of the reduced HAMR Jacobian, times 20 ms.
    #[test]
    fn phi_functions_match_the_augmented_exponential() {
        let omega: f64 = 2.0 * std::f64::consts::PI * 100.0;
        let h = 0.02;
        let j = DMatrix::from_row_slice(
            3,
            3,
            &[
                0.0,
                1.0,
                0.0,
                -omega * omega,
                -0.05 * omega,
                3.0e3,
                0.0,
                0.0,
                0.0,
            ],
        );
        // Many doublings, one doubling from a Taylor sum at ‖B‖₁ near its bound, a tiny argument,
        // and zero.
        for a in [&j * h, &j * 4e-3, &j * 1e-6, DMatrix::zeros(3, 3)] {
            let mut phi = PhiFunctions::new(3);
            assert!(phi.compute(a.as_slice()));
            let v = [1.0e-4, -2.0e-2, 1.0];
            for k in 0..=MAX_ORDER {
                let mut out = vec![0.0; 3];
                phi.add_apply(k, &v, &mut out);
                let expected = if k == 0 {
                    (a.exp() * nalgebra::DVector::from_column_slice(&v))
                        .iter()
                        .copied()
                        .collect()
                } else {
                    reference(&a, k, &v)
                };
                for i in 0..3 {
                    let scale = expected[i].abs().max(1e-12);
                    assert!(
                        (out[i] - expected[i]).abs() <= 1e-10 * scale,
                        "φ_{k}: {} vs {}",
                        out[i],
                        expected[i]
                    );
                }
            }
            for k in [1, 2] {
                let mut half = vec![0.0; 3];
                phi.add_apply_half(k, &v, &mut half);
                let expected = reference(&(&a * 0.5), k, &v);
                for i in 0..3 {
                    let scale = expected[i].abs().max(1e-12);
                    assert!((half[i] - expected[i]).abs() <= 1e-10 * scale);
                }
            }
        }
    }

    /// One balancing for several multiples of a matrix gives the functions of each multiple,
    /// as a fresh computation does; a non-finite matrix fails at every multiple.
    #[test]
    fn reused_balancing_matches_a_fresh_computation() {
        let omega: f64 = 2.0 * std::f64::consts::PI * 80.0;
        let j = [0.0, -omega * omega, 1.0, -0.05 * omega];
        let mut shared = PhiFunctions::new(2);
        for (i, tau) in [0.02, 3e-3, 0.011, 1e-7, 0.0].into_iter().enumerate() {
            assert!(shared.compute_multiple(&j, tau, i == 0));
            let mut fresh = PhiFunctions::new(2);
            let scaled: Vec<f64> = j.iter().map(|v| tau * v).collect();
            assert!(fresh.compute(&scaled));
            let v = [1.0e-4, -2.0e-2];
            for k in 0..=MAX_ORDER {
                let (mut a, mut b) = ([0.0; 2], [0.0; 2]);
                shared.add_apply(k, &v, &mut a);
                fresh.add_apply(k, &v, &mut b);
                for (x, y) in a.iter().zip(&b) {
                    assert!(
                        (x - y).abs() <= 1e-13 * y.abs().max(1e-12),
                        "φ_{k}({tau}): {x} vs {y}"
                    );
                }
            }
        }
        let mut broken = PhiFunctions::new(2);
        assert!(!broken.compute_multiple(&[f64::NAN, 0.0, 1.0, 0.0], 0.01, true));
        assert!(!broken.compute_multiple(&[0.0; 4], 0.01, false));
    }

    #[test]
    fn scalar_phi_functions_have_their_closed_forms() {
        for z in [-30.0f64, -1.0, 0.05, 0.7] {
            let mut phi = PhiFunctions::new(1);
            assert!(phi.compute(&[z]));
            let exact = [
                z.exp(),
                (z.exp() - 1.0) / z,
                (z.exp() - 1.0 - z) / (z * z),
                (z.exp() - 1.0 - z - z * z / 2.0) / z.powi(3),
                (z.exp() - 1.0 - z - z * z / 2.0 - z.powi(3) / 6.0) / z.powi(4),
            ];
            for (k, e) in exact.iter().enumerate() {
                // The closed forms cancel badly for small z: compare there loosely.
                let tol = if z.abs() < 0.1 { 1e-8 } else { 1e-12 };
                let mut out = [0.0];
                phi.add_apply(k, &[1.0], &mut out);
                assert!(
                    (out[0] - e).abs() <= tol * e.abs(),
                    "φ_{k}({z}): {} vs {e}",
                    out[0]
                );
            }
        }
    }
}
