//! Constrained accelerations by coordinate partitioning, for loops that fall into blocks.
//!
//! Consumes: `J` (`nc × nu`, column-major), its independent rows `R` (the range-space
//! solver's choice, [`crate::ConstrainedSolver`]), `J̇u`, and a symmetric `A` (`M`, or
//! `M − γD` of a linearly implicit step). Produces: `x` of `A x = f + Jᵀλ`, `J x = −b` and
//! the multipliers `λ` on `R`.
//!
//! The speeds split into `r` dependent ones `D` (`J_RD` invertible) and `m = nu − r`
//! independent ones `I`: every `x` meeting the rows is `x = N x_I + c` with `N = [1; −J_RD⁻¹
//! J_RI]` and `c = [0; −J_RD⁻¹ b_R]` (Wehage and Haug's partitioning), so `(Nᵀ A N) x_I =
//! Nᵀ (f − A c)`, an `m × m` positive definite system, and `J_RDᵀ λ_R = (A x − f)_D`.
//!
//! Why it pays: where `J_RD` is block diagonal (each block some rows and as many dependent
//! speeds that no other block's rows touch: the legs of a walking robot, each closing its
//! own loops, coupled only through the body's speeds), its factors are a few small LUs and
//! `N` is sparse, where the range-space solve works on the full `nu × nu` factor and the
//! dense `r × r` coupling `J M⁻¹ Jᵀ`. With a single block there is nothing to gain, and
//! [`Partition::choose`] declines.
//!
//! The sparsity of `J_R` is read from one state and checked at every other
//! ([`Partition::factor`] declines where an entry outside it is not zero), so an entry that
//! happened to be zero where the partition was chosen cannot be dropped.

use crate::dense;

/// Relative size below which an LU pivot of a block counts as zero (the partition no
/// longer fits the state: choose again).
const PIVOT_TOLERANCE: f64 = 1e-9;

/// One block: rows of `R` and as many dependent speeds, and the independent speeds its rows
/// touch.
#[derive(Clone, Debug)]
struct Block {
    /// Into [`Partition::rows`] and [`Partition::dependent`] (the same range for both).
    members: std::ops::Range<usize>,
    /// Positions in [`Partition::independent`] of the independent speeds its rows touch.
    touched: Vec<usize>,
    /// Start of its `k × k` LU factor in [`Partition::lu`].
    lu_offset: usize,
}

/// A partition of the speeds into dependent and independent ones for a set of rows, and
/// the storage of its solves (allocated once).
#[derive(Clone, Debug)]
pub(crate) struct Partition {
    nu: usize,
    nc: usize,
    /// The rows `R` (rows of `J`) as given to [`Partition::choose`], and grouped by block.
    chosen_for: Vec<usize>,
    rows: Vec<usize>,
    /// The dependent speeds, grouped by block as `rows`.
    dependent: Vec<usize>,
    /// The independent speeds, increasing.
    independent: Vec<usize>,
    blocks: Vec<Block>,
    /// `allowed[k + rows.len() * c]`: whether row `rows[k]` of `J` may be nonzero at speed `c`.
    allowed: Vec<bool>,
    /// Rows of `N` that can be nonzero, per independent speed (its own row first).
    nonzeros: Vec<Vec<usize>>,
    /// Each block's LU factor of `J_RD` (partial pivoting) and its row order.
    lu: Vec<f64>,
    pivots: Vec<usize>,
    /// `N`, `nu × m` column-major.
    basis: Vec<f64>,
    /// `c` (nonzero on dependent speeds only).
    offset: Vec<f64>,
    /// `A N`, `nu × m`.
    product: Vec<f64>,
    /// `Nᵀ A N`, then its Cholesky factor, `m × m`.
    reduced: Vec<f64>,
    work: Vec<f64>,
    residual: Vec<f64>,
}

/// Whether `J[row, column]` of a column-major `nc × nu` matrix is nonzero.
fn nonzero(jacobian: &[f64], nc: usize, row: usize, column: usize) -> bool {
    jacobian[row + nc * column] != 0.0
}

/// The representative of `i` (path halving).
fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

impl Partition {
    /// Chooses the dependent speeds of `rows` (independent rows of `J`, `nc × nu`
    /// column-major) by Gaussian elimination with complete pivoting, and their blocks.
    /// `None` where the rows are found dependent, or form a single block (nothing to gain).
    pub(crate) fn choose(jacobian: &[f64], nc: usize, nu: usize, rows: &[usize]) -> Option<Self> {
        let r = rows.len();
        if r == 0 || r >= nu {
            return None;
        }
        // J_R, r × nu column-major, eliminated in place.
        let mut a: Vec<f64> = (0..nu)
            .flat_map(|c| rows.iter().map(move |&row| jacobian[row + nc * c]))
            .collect();
        if !a.iter().all(|v| v.is_finite()) {
            return None;
        }
        let (mut row_free, mut column_free) = (vec![true; r], vec![true; nu]);
        let mut dependent = Vec::with_capacity(r);
        let mut first = 0.0;
        for step in 0..r {
            let mut best = (0, 0, 0.0);
            for c in (0..nu).filter(|&c| column_free[c]) {
                for k in (0..r).filter(|&k| row_free[k]) {
                    let value = a[k + r * c].abs();
                    if value > best.2 {
                        best = (k, c, value);
                    }
                }
            }
            let (pivot_row, pivot_column, size) = best;
            if step == 0 {
                first = size;
            }
            if size <= PIVOT_TOLERANCE * first || size == 0.0 {
                return None;
            }
            row_free[pivot_row] = false;
            column_free[pivot_column] = false;
            dependent.push(pivot_column);
            let pivot = a[pivot_row + r * pivot_column];
            for k in (0..r).filter(|&k| row_free[k]) {
                let factor = a[k + r * pivot_column] / pivot;
                if factor == 0.0 {
                    continue;
                }
                for c in 0..nu {
                    a[k + r * c] -= factor * a[pivot_row + r * c];
                }
            }
        }
        // Blocks: rows joined through the dependent speeds they share.
        let mut parent: Vec<usize> = (0..r).collect();
        for &c in &dependent {
            let mut touching = (0..r).filter(|&k| nonzero(jacobian, nc, rows[k], c));
            if let Some(head) = touching.next() {
                for k in touching {
                    let (x, y) = (find(&mut parent, head), find(&mut parent, k));
                    parent[x.max(y)] = x.min(y);
                }
            }
        }
        let roots: Vec<usize> = (0..r).map(|k| find(&mut parent, k)).collect();
        let mut labels: Vec<usize> = roots.clone();
        labels.sort_unstable();
        labels.dedup();
        if labels.len() < 2 {
            return None;
        }
        let mut independent: Vec<usize> = (0..nu).filter(|&c| column_free[c]).collect();
        independent.sort_unstable();
        let (mut grouped_rows, mut grouped_dependent) = (Vec::new(), Vec::new());
        let mut blocks = Vec::new();
        let mut lu_size = 0;
        for &label in &labels {
            let members: Vec<usize> = (0..r).filter(|&k| roots[k] == label).collect();
            let columns: Vec<usize> = dependent
                .iter()
                .copied()
                .filter(|&c| {
                    (0..r)
                        .find(|&k| nonzero(jacobian, nc, rows[k], c))
                        .is_some_and(|k| roots[k] == label)
                })
                .collect();
            // An invertible J_RD has square blocks.
            if columns.len() != members.len() {
                return None;
            }
            let touched = (0..independent.len())
                .filter(|&position| {
                    members
                        .iter()
                        .any(|&k| nonzero(jacobian, nc, rows[k], independent[position]))
                })
                .collect();
            let start = grouped_rows.len();
            grouped_rows.extend(members.iter().map(|&k| rows[k]));
            grouped_dependent.extend(columns);
            blocks.push(Block {
                members: start..grouped_rows.len(),
                touched,
                lu_offset: lu_size,
            });
            lu_size += members.len() * members.len();
        }
        let m = independent.len();
        let mut allowed = vec![false; r * nu];
        let mut nonzeros: Vec<Vec<usize>> = independent.iter().map(|&c| vec![c]).collect();
        for block in &blocks {
            for k in block.members.clone() {
                for &c in &grouped_dependent[block.members.clone()] {
                    allowed[k + r * c] = true;
                }
                for &position in &block.touched {
                    allowed[k + r * independent[position]] = true;
                }
            }
            for &position in &block.touched {
                nonzeros[position].extend_from_slice(&grouped_dependent[block.members.clone()]);
            }
        }
        Some(Partition {
            nu,
            nc,
            chosen_for: rows.to_vec(),
            rows: grouped_rows,
            dependent: grouped_dependent,
            independent,
            blocks,
            allowed,
            nonzeros,
            lu: vec![0.0; lu_size],
            pivots: vec![0; r],
            basis: vec![0.0; nu * m],
            offset: vec![0.0; nu],
            product: vec![0.0; nu * m],
            reduced: vec![0.0; m * m],
            work: vec![0.0; nu],
            residual: vec![0.0; nu],
        })
    }

    /// The number of blocks (at least two).
    pub(crate) fn block_count(&self) -> usize {
        self.blocks.len()
    }

    /// Whether the partition was chosen for these rows (increasing).
    pub(crate) fn is_for(&self, rows: &[usize]) -> bool {
        self.chosen_for == rows
    }

    /// `N` and (with `bias`, `J̇u` of every row) `c` at a state's `J`: `false` where an entry
    /// of `J_R` outside the partition's pattern is not zero, or a block's pivot is too small
    /// or not finite (the partition does not fit this state).
    pub(crate) fn factor(&mut self, jacobian: &[f64], bias: Option<&[f64]>) -> bool {
        let (nu, nc, r) = (self.nu, self.nc, self.rows.len());
        for c in 0..nu {
            for (k, &row) in self.rows.iter().enumerate() {
                if !self.allowed[k + r * c] && jacobian[row + nc * c] != 0.0 {
                    return false;
                }
            }
        }
        self.basis.fill(0.0);
        self.offset.fill(0.0);
        for (position, &c) in self.independent.iter().enumerate() {
            self.basis[c + nu * position] = 1.0;
        }
        for block in &self.blocks {
            let members = block.members.clone();
            let k = members.len();
            let lu = &mut self.lu[block.lu_offset..block.lu_offset + k * k];
            for (j, &c) in self.dependent[members.clone()].iter().enumerate() {
                for (i, &row) in self.rows[members.clone()].iter().enumerate() {
                    lu[i + k * j] = jacobian[row + nc * c];
                }
            }
            let pivots = &mut self.pivots[members.clone()];
            // A pivot small against the block's entries: the dependent speeds no longer
            // suit this state (NaN fails too).
            let scale = lu.iter().fold(0.0_f64, |s, v| s.max(v.abs()));
            if !dense::lu(lu, k, pivots)
                || (0..k).any(|j| {
                    lu[j + k * j].is_nan() || lu[j + k * j].abs() <= PIVOT_TOLERANCE * scale
                })
            {
                return false;
            }
            let rhs = &mut self.work[..k];
            for &position in &block.touched {
                let c = self.independent[position];
                for (value, &row) in rhs.iter_mut().zip(&self.rows[members.clone()]) {
                    *value = jacobian[row + nc * c];
                }
                dense::lu_solve(lu, k, pivots, rhs);
                for (&d, &value) in self.dependent[members.clone()].iter().zip(rhs.iter()) {
                    self.basis[d + nu * position] = -value;
                }
            }
            if let Some(bias) = bias {
                for (value, &row) in rhs.iter_mut().zip(&self.rows[members.clone()]) {
                    *value = bias[row];
                }
                dense::lu_solve(lu, k, pivots, rhs);
                for (&d, &value) in self.dependent[members].iter().zip(rhs.iter()) {
                    self.offset[d] = -value;
                }
            }
        }
        true
    }

    /// Factors `Nᵀ A N` for a symmetric `A` (`nu × nu`, both triangles); `false` where it is
    /// not positive definite.
    pub(crate) fn reduce(&mut self, a: &[f64]) -> bool {
        let (nu, m) = (self.nu, self.independent.len());
        self.product.fill(0.0);
        for (position, rows) in self.nonzeros.iter().enumerate() {
            let target = &mut self.product[nu * position..nu * (position + 1)];
            for &i in rows {
                let weight = self.basis[i + nu * position];
                for (out, &value) in target.iter_mut().zip(&a[nu * i..nu * (i + 1)]) {
                    *out += value * weight;
                }
            }
        }
        for b in 0..m {
            for a_position in b..m {
                let column = &self.product[nu * b..nu * (b + 1)];
                self.reduced[a_position + m * b] = self.nonzeros[a_position]
                    .iter()
                    .map(|&i| self.basis[i + nu * a_position] * column[i])
                    .sum();
            }
        }
        dense::cholesky(&mut self.reduced, m)
    }

    /// `x` of `A x = f + Jᵀλ`, `J x = −b` (`b` as given to [`factor`](Self::factor); 0
    /// without it), with `A` as given to [`reduce`](Self::reduce): `f` in `x` on entry, `x`
    /// on return.
    pub(crate) fn solve(&mut self, a: &[f64], x: &mut [f64]) {
        let (nu, m) = (self.nu, self.independent.len());
        // h = f − A c.
        let h = &mut self.residual;
        h.copy_from_slice(x);
        for &d in &self.dependent {
            let c_d = self.offset[d];
            if c_d != 0.0 {
                for (out, &value) in h.iter_mut().zip(&a[nu * d..nu * (d + 1)]) {
                    *out -= value * c_d;
                }
            }
        }
        let g = &mut self.work[..m];
        for (position, rows) in self.nonzeros.iter().enumerate() {
            g[position] = rows
                .iter()
                .map(|&i| self.basis[i + nu * position] * h[i])
                .sum();
        }
        dense::cholesky_solve(&self.reduced, m, g);
        x.copy_from_slice(&self.offset);
        for (position, rows) in self.nonzeros.iter().enumerate() {
            for &i in rows {
                x[i] += self.basis[i + nu * position] * g[position];
            }
        }
    }

    /// `λ` on the partition's rows from `J_RDᵀ λ_R = (A x − f)_D` (each block apart), into
    /// `multipliers` (every row of `J`; zero off `R`), after [`solve`](Self::solve).
    pub(crate) fn multipliers(&mut self, a: &[f64], f: &[f64], x: &[f64], multipliers: &mut [f64]) {
        let nu = self.nu;
        multipliers.fill(0.0);
        for block in &self.blocks {
            let members = block.members.clone();
            let k = members.len();
            let rhs = &mut self.work[..k];
            for (value, &d) in rhs.iter_mut().zip(&self.dependent[members.clone()]) {
                // Row d of A x (A symmetric: its column d).
                let row: f64 = a[nu * d..nu * (d + 1)]
                    .iter()
                    .zip(x)
                    .map(|(a, x)| a * x)
                    .sum();
                *value = row - f[d];
            }
            let lu = &self.lu[block.lu_offset..block.lu_offset + k * k];
            dense::lu_solve_transposed(lu, k, &self.pivots[members.clone()], rhs);
            for (&row, &value) in self.rows[members].iter().zip(rhs.iter()) {
                multipliers[row] = value;
            }
        }
    }
}
