//! Small dense linear algebra on column-major slices, without allocation: Cholesky for the
//! mass matrix and a diagonally pivoted Cholesky that reveals the rank of a positive
//! semidefinite matrix (`J M⁻¹ Jᵀ` with redundant constraint rows), plus the products the
//! constrained solver needs (`Zᵀ Z`, `Zᵀ w`, `Z λ`), and the inverse from a Cholesky factor
//! (for the reduced dynamics' many solves with one factor); LU with partial pivoting for general
//! square systems (a mass matrix that is not symmetric, the Rosenbrock iteration matrix);
//! Householder QR for the least-squares
//! solves of the reduced dynamics (the tall loop Jacobian of the dependent coordinates).
//!
//! Matrices are `n × n` (or `n × m`), column-major (`a[i + n*j]` is row i, column j), like the
//! `Model` trait's outputs.
//!
//! Multibody models are small (a few coordinates, a few loop rows), where loop and
//! bounds-check overhead costs more than the arithmetic. So every kernel is written once,
//! generic over a `Dim`, and the public functions dispatch: sizes 1 to [`UNROLLED`] get a
//! copy with the size known at compile time (loops fully unrolled, no bounds checks), larger
//! ones the same code with the size at run time.

/// Sizes up to this one are compiled with the size known (fully unrolled kernels).
pub const UNROLLED: usize = 6;

/// A dimension: known at compile time ([`Fixed`]) or at run time ([`Dynamic`]).
trait Dim: Copy {
    /// Whether kernels look for the runs of zeros in a column ([`Runs`]): not for the
    /// unrolled sizes, where the scan would cost more than the arithmetic it saves.
    const SCANS: bool;
    fn get(self) -> usize;
}

#[derive(Clone, Copy)]
struct Fixed<const N: usize>;

impl<const N: usize> Dim for Fixed<N> {
    const SCANS: bool = false;
    #[inline(always)]
    fn get(self) -> usize {
        N
    }
}

#[derive(Clone, Copy)]
struct Dynamic(usize);

impl Dim for Dynamic {
    const SCANS: bool = true;
    #[inline(always)]
    fn get(self) -> usize {
        self.0
    }
}

/// Runs `$body` with `$d` bound to a [`Dim`] of value `$n`: `Fixed` for the sizes 1 to
/// [`UNROLLED`] (listed in the first rule), `Dynamic` above.
macro_rules! by_size {
    ($n:expr, |$d:ident| $body:expr) => {
        by_size!($n, |$d| $body, fixed: 1 2 3 4 5 6)
    };
    ($n:expr, |$d:ident| $body:expr, fixed: $($size:literal)+) => {
        match $n {
            $($size => {
                let $d = Fixed::<$size>;
                $body
            })+
            n => {
                let $d = Dynamic(n);
                $body
            }
        }
    };
}

/// Cholesky factorization `A = L Lᵀ` in place (the lower triangle receives `L`; the strict
/// upper triangle is left as it was). Returns false if a pivot is not positive relative to the
/// diagonal (`A` not positive definite).
pub fn cholesky(a: &mut [f64], n: usize) -> bool {
    by_size!(n, |d| cholesky_in(a, d))
}

#[inline(always)]
fn cholesky_in<D: Dim>(a: &mut [f64], d: D) -> bool {
    let n = d.get();
    let a = &mut a[..n * n];
    let mut scale = 0.0;
    for i in 0..n {
        scale = f64::max(scale, a[i + n * i].abs());
    }
    let floor = scale * 1e-14;
    for j in 0..n {
        // The Schur-complement diagonal; NaN counts as not positive.
        let diagonal = a[j + n * j];
        if diagonal.is_nan() || diagonal <= floor {
            return false;
        }
        cholesky_column(a, n, j);
    }
    true
}

/// One right-looking step of the Cholesky factorizations, at a positive diagonal `A_jj`:
/// column `j` of `L` (`L_jj = √A_jj`, `L_ij = A_ij / L_jj`), then the update of the trailing
/// lower triangle, `A_ik −= L_ij L_kj` for `j < k ≤ i` (skipped where `L_kj` is zero: a
/// sparse `A` that fills in little costs less, as the mass matrix of a floating robot whose
/// base's speeds come last, its legs' blocks coupled only through them). The update runs over
/// every row below `k`, zeros of column `j` included: on HAMR-VI's robot (38 speeds) skipping
/// those too ([`Runs`]) took twice as long, two short loops for one that vectorizes.
#[inline(always)]
fn cholesky_column(a: &mut [f64], n: usize, j: usize) {
    let pivot = a[j + n * j].sqrt();
    a[j + n * j] = pivot;
    for i in j + 1..n {
        a[i + n * j] /= pivot;
    }
    // Column j as a slice apart from the columns it updates: no bounds checks in the loop.
    let (before, after) = a.split_at_mut(n * (j + 1));
    let column_j = &before[n * j..];
    for (k, column_k) in (j + 1..n).zip(after.chunks_exact_mut(n)) {
        let l_kj = column_j[k];
        if l_kj == 0.0 {
            continue;
        }
        for (a_ik, &l_ij) in column_k[k..].iter_mut().zip(&column_j[k..]) {
            *a_ik -= l_ij * l_kj;
        }
    }
}

/// The rows at and below `from` where a column can be nonzero: `[start, end)` and
/// `[resume, n)`, exact zeros elsewhere (in a floating robot's mass matrix, a leg's column
/// holds its own leg's rows, zeros through the other legs', then the base's). Other zeros fall
/// inside the two ranges. NaN and infinities count as nonzero.
#[derive(Clone, Copy)]
struct Runs {
    start: usize,
    end: usize,
    resume: usize,
    n: usize,
}

impl Runs {
    /// The runs of `column` (length `n`) from row `from`; every row from `from` for the
    /// unrolled sizes (`D::SCANS`).
    #[inline(always)]
    fn of<D: Dim>(d: D, column: &[f64], from: usize) -> Runs {
        let n = d.get();
        let from = from.min(n);
        if !D::SCANS {
            return Runs {
                start: from,
                end: n,
                resume: n,
                n,
            };
        }
        let column = &column[..n];
        let after = |from: usize, nonzero: bool| {
            column[from..]
                .iter()
                .position(|&v| (v != 0.0) == nonzero)
                .map_or(n, |offset| from + offset)
        };
        let start = after(from, true);
        let end = after(start, false);
        let resume = after(end, true);
        Runs {
            start,
            end,
            resume,
            n,
        }
    }

    /// The two ranges of rows at and below `row`.
    #[inline(always)]
    fn from(self, row: usize) -> [std::ops::Range<usize>; 2] {
        let clip = |lo: usize, hi: usize| lo.max(row).min(hi)..hi;
        [clip(self.start, self.end), clip(self.resume, self.n)]
    }
}

/// Solves `L y = b` in place (forward substitution), with `L` from [`cholesky`].
pub fn forward_substitute(l: &[f64], n: usize, b: &mut [f64]) {
    by_size!(n, |d| forward_in(l, d, b))
}

#[inline(always)]
fn forward_in<D: Dim>(l: &[f64], d: D, b: &mut [f64]) {
    let n = d.get();
    let (l, b) = (&l[..n * n], &mut b[..n]);
    for j in 0..n {
        let y = b[j] / l[j + n * j];
        b[j] = y;
        // A zero leaves the rest as it is (a constraint row's few speeds, a sparse `L`).
        if y == 0.0 {
            continue;
        }
        let column = &l[n * j + j + 1..n * (j + 1)];
        for (b_i, &l_ij) in b[j + 1..].iter_mut().zip(column) {
            *b_i -= l_ij * y;
        }
    }
}

/// Solves `Lᵀ x = y` in place (back substitution), with `L` from [`cholesky`].
pub fn back_substitute(l: &[f64], n: usize, b: &mut [f64]) {
    by_size!(n, |d| back_in(l, d, b))
}

#[inline(always)]
fn back_in<D: Dim>(l: &[f64], d: D, b: &mut [f64]) {
    let n = d.get();
    let (l, b) = (&l[..n * n], &mut b[..n]);
    for j in (0..n).rev() {
        let column = &l[n * j + j + 1..n * (j + 1)];
        b[j] = (b[j] - dot(column, &b[j + 1..])) / l[j + n * j];
    }
}

/// Solves `L Lᵀ x = b` in place, with `L` from [`cholesky`].
pub fn cholesky_solve(l: &[f64], n: usize, b: &mut [f64]) {
    by_size!(n, |d| {
        forward_in(l, d, b);
        back_in(l, d, b);
    })
}

/// `A⁻¹` (`n × n`, both triangles) into `out`, from the factor `L` of `A = L Lᵀ` by
/// [`cholesky`]: `A⁻¹ = L⁻ᵀ L⁻¹`. For a well-conditioned `A` solved many times: a product with
/// `A⁻¹` has no divisions on its critical path, where [`cholesky_solve`] has `2n` in a chain.
pub fn cholesky_inverse(l: &[f64], n: usize, out: &mut [f64]) {
    by_size!(n, |d| cholesky_inverse_in(l, d, out))
}

#[inline(always)]
fn cholesky_inverse_in<D: Dim>(l: &[f64], d: D, out: &mut [f64]) {
    let n = d.get();
    let (l, out) = (&l[..n * n], &mut out[..n * n]);
    // X = L⁻¹ (lower triangular) into the lower triangle of `out`: X_jj = 1/L_jj (independent
    // divisions, first), then column by column X_ij = −(Σ_{j≤k<i} L_ik X_kj)·X_ii.
    for j in 0..n {
        out[j + n * j] = 1.0 / l[j + n * j];
    }
    for j in 0..n {
        for i in j + 1..n {
            let mut sum = 0.0;
            for k in j..i {
                sum += l[i + n * k] * out[k + n * j];
            }
            out[i + n * j] = -sum * out[i + n * i];
        }
    }
    // A⁻¹ = XᵀX: entry (i, j), i ≥ j, is Σ_{k≥i} X_ki X_kj; in place, since entry (i, j)
    // reads only rows k ≥ i of columns i and j, and the rows are done from the top.
    for i in 0..n {
        for j in 0..=i {
            let mut sum = 0.0;
            for k in i..n {
                sum += out[k + n * i] * out[k + n * j];
            }
            out[j + n * i] = sum;
        }
    }
    for j in 0..n {
        for i in j + 1..n {
            out[i + n * j] = out[j + n * i];
        }
    }
}

/// Solves `L Y = B` in place for the `m` columns of the `n × m` matrix `b`: column by column
/// of `L`, each applied to every column of `B` over its nonzero rows (`Runs`, found once for
/// all of them). The same operations in the same order as [`forward_substitute`] on each
/// column, less those with an exact zero. On a synthetic arrowhead like HAMR-VI's robot's
/// `M` (four 8-speed legs, 6 base speeds) and 24 constraint rows: 3.9 → 2.5 µs against the
/// columns one at a time over every row (a scratch benchmark, minima).
pub fn forward_substitute_columns(l: &[f64], n: usize, b: &mut [f64], m: usize) {
    if n == 0 {
        return;
    }
    by_size!(n, |d| forward_columns_in(l, d, b, m))
}

#[inline(always)]
fn forward_columns_in<D: Dim>(l: &[f64], d: D, b: &mut [f64], m: usize) {
    let n = d.get();
    let (l, b) = (&l[..n * n], &mut b[..n * m]);
    for (j, column) in l.chunks_exact(n).enumerate() {
        let runs = Runs::of(d, column, j + 1);
        for rhs in b.chunks_exact_mut(n) {
            let y = rhs[j] / column[j];
            rhs[j] = y;
            if y == 0.0 {
                continue;
            }
            for range in runs.from(j + 1) {
                for (b_i, &l_ij) in rhs[range.clone()].iter_mut().zip(&column[range]) {
                    *b_i -= l_ij * y;
                }
            }
        }
    }
}

/// The lower triangle of `Zᵀ Z` (`m × m`) into `out`, for the `n × m` matrix `z`.
pub fn gram_lower(z: &[f64], n: usize, m: usize, out: &mut [f64]) {
    by_size!(n, |dn| by_size!(m, |dm| gram_in(z, dn, dm, out)))
}

#[inline(always)]
fn gram_in<D: Dim, E: Dim>(z: &[f64], dn: D, dm: E, out: &mut [f64]) {
    let (n, m) = (dn.get(), dm.get());
    let (z, out) = (&z[..n * m], &mut out[..m * m]);
    if n == 0 {
        out.fill(0.0);
        return;
    }
    // Each product starts at the later of the two columns' first nonzero entries: the rest
    // of the shorter one is zeros. Constraint rows touch few speeds, and `L⁻¹` keeps a
    // column's leading zeros, so `L⁻¹Jᵀ` of a robot's leg rows starts at that leg's speeds
    // (HAMR-VI's robot at its assembled state: 50.5 % of the multiplications of its 24 rows
    // over 38 speeds remain). Not for the unrolled sizes (`D::SCANS`), and up to
    // `LEADING_ZEROS_UP_TO` columns (a stack array; more start at 0).
    let mut starts = [0usize; LEADING_ZEROS_UP_TO];
    if D::SCANS && m <= LEADING_ZEROS_UP_TO {
        for (start, column) in starts.iter_mut().zip(z.chunks_exact(n)) {
            *start = column.iter().position(|&v| v != 0.0).unwrap_or(n);
        }
    }
    // Columns as slices: no bounds checks in the inner loop when `n` is only known at run time.
    for (r, zr) in z.chunks_exact(n).enumerate() {
        let start_r = starts.get(r).copied().unwrap_or(0);
        for (s, zs) in z.chunks_exact(n).take(r + 1).enumerate() {
            let start = start_r.max(starts.get(s).copied().unwrap_or(0));
            out[r + m * s] = dot(&zr[start..], &zs[start..]);
        }
    }
}

/// Columns up to which [`gram_lower`] skips their leading zeros.
const LEADING_ZEROS_UP_TO: usize = 64;

/// `Σ a_k b_k` in four partial sums (`k mod 4`), added at the end: four independent chains
/// of additions, which the processor overlaps (and the compiler vectorizes), where one sum in
/// order waits for each addition before the next.
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let length = a.len().min(b.len());
    let (a, b) = (&a[..length], &b[..length]);
    let mut sums = [0.0; 4];
    let (a_lanes, b_lanes) = (a.chunks_exact(4), b.chunks_exact(4));
    let (a_rest, b_rest) = (a_lanes.remainder(), b_lanes.remainder());
    for (x, y) in a_lanes.zip(b_lanes) {
        for lane in 0..4 {
            sums[lane] += x[lane] * y[lane];
        }
    }
    for (lane, (x, y)) in a_rest.iter().zip(b_rest).enumerate() {
        sums[lane] += x * y;
    }
    (sums[0] + sums[1]) + (sums[2] + sums[3])
}

/// `out = Zᵀ w` (length `m`) for the `n × m` matrix `z`.
pub fn transpose_times(z: &[f64], n: usize, m: usize, w: &[f64], out: &mut [f64]) {
    by_size!(n, |dn| by_size!(m, |dm| transpose_times_in(
        z, dn, dm, w, out
    )))
}

#[inline(always)]
fn transpose_times_in<D: Dim, E: Dim>(z: &[f64], dn: D, dm: E, w: &[f64], out: &mut [f64]) {
    let (n, m) = (dn.get(), dm.get());
    let (z, w, out) = (&z[..n * m], &w[..n], &mut out[..m]);
    if n == 0 {
        out.fill(0.0);
        return;
    }
    for (o, column) in out.iter_mut().zip(z.chunks_exact(n)) {
        *o = dot(column, w);
    }
}

/// `out += Z x` (length `n`) for the `n × m` matrix `z`.
pub fn add_times(z: &[f64], n: usize, m: usize, x: &[f64], out: &mut [f64]) {
    by_size!(n, |dn| by_size!(m, |dm| add_times_in(z, dn, dm, x, out)))
}

#[inline(always)]
fn add_times_in<D: Dim, E: Dim>(z: &[f64], dn: D, dm: E, x: &[f64], out: &mut [f64]) {
    let (n, m) = (dn.get(), dm.get());
    let (z, x, out) = (&z[..n * m], &x[..m], &mut out[..n]);
    if n == 0 {
        return;
    }
    for (column, &x_r) in z.chunks_exact(n).zip(x) {
        for (o, z) in out.iter_mut().zip(column) {
            *o += z * x_r;
        }
    }
}

/// `out = A B` for `n × n` matrices.
pub fn multiply(a: &[f64], b: &[f64], n: usize, out: &mut [f64]) {
    by_size!(n, |d| multiply_in(a, b, d, out))
}

#[inline(always)]
fn multiply_in<D: Dim>(a: &[f64], b: &[f64], d: D, out: &mut [f64]) {
    let n = d.get();
    let (a, b, out) = (&a[..n * n], &b[..n * n], &mut out[..n * n]);
    for j in 0..n {
        for i in 0..n {
            let mut sum = 0.0;
            for k in 0..n {
                sum += a[i + n * k] * b[k + n * j];
            }
            out[i + n * j] = sum;
        }
    }
}

/// Diagonally pivoted Cholesky of a positive semidefinite `A` in place: `P A Pᵀ = L Lᵀ` on the
/// first `rank` pivots, stopping when the largest remaining diagonal falls below
/// `relative_tolerance` times the largest initial diagonal. `order` receives the pivot order.
/// Returns the rank.
pub fn pivoted_cholesky(
    a: &mut [f64],
    n: usize,
    relative_tolerance: f64,
    order: &mut [usize],
) -> usize {
    by_size!(n, |d| pivoted_cholesky_in(a, d, relative_tolerance, order))
}

#[inline(always)]
fn pivoted_cholesky_in<D: Dim>(
    a: &mut [f64],
    d: D,
    relative_tolerance: f64,
    order: &mut [usize],
) -> usize {
    let n = d.get();
    let (a, order) = (&mut a[..n * n], &mut order[..n]);
    let mut largest = 0.0;
    for (i, slot) in order.iter_mut().enumerate() {
        *slot = i;
        largest = f64::max(largest, a[i + n * i]);
    }
    let threshold = largest * relative_tolerance;
    for j in 0..n {
        // Pivot: the largest remaining diagonal (Schur complement diagonal).
        let (mut best, mut value) = (j, f64::NEG_INFINITY);
        for i in j..n {
            let candidate = a[i + n * i];
            if candidate > value {
                (best, value) = (i, candidate);
            }
        }
        if value.is_nan() || value <= threshold || value <= 0.0 {
            return j;
        }
        if best != j {
            swap_symmetric(a, n, j, best);
            order.swap(j, best);
        }
        cholesky_column(a, n, j);
    }
    n
}

/// Swaps rows and columns `p < q` of a symmetric matrix stored in its lower triangle
/// (entries already factored, columns `< p`, are swapped as rows only).
fn swap_symmetric(a: &mut [f64], n: usize, p: usize, q: usize) {
    let (p, q) = (p.min(q), p.max(q));
    for k in 0..p {
        a.swap(p + n * k, q + n * k);
    }
    a.swap(p + n * p, q + n * q);
    for i in p + 1..q {
        a.swap(i + n * p, q + n * i);
    }
    for i in q + 1..n {
        a.swap(i + n * p, i + n * q);
    }
}

/// Solves `A x = b` for the pivoted factor of rank `rank`: the pivot rows are solved exactly,
/// the others get `x = 0` (a solution whenever the system is consistent, as it is for
/// redundant constraint rows). `work` needs length `n`.
pub fn pivoted_solve(
    l: &[f64],
    n: usize,
    rank: usize,
    order: &[usize],
    b: &[f64],
    x: &mut [f64],
    work: &mut [f64],
) {
    by_size!(n, |d| pivoted_solve_in(l, d, rank, order, b, x, work))
}

#[inline(always)]
fn pivoted_solve_in<D: Dim>(
    l: &[f64],
    d: D,
    rank: usize,
    order: &[usize],
    b: &[f64],
    x: &mut [f64],
    work: &mut [f64],
) {
    let n = d.get();
    let rank = rank.min(n);
    let (l, order, x, work) = (&l[..n * n], &order[..n], &mut x[..n], &mut work[..n]);
    // L y = P b, then Lᵀ z = y, on the first `rank` pivots.
    for i in 0..rank {
        let mut value = b[order[i]];
        for k in 0..i {
            value -= l[i + n * k] * work[k];
        }
        work[i] = value / l[i + n * i];
    }
    for i in (0..rank).rev() {
        let mut value = work[i];
        for k in i + 1..rank {
            value -= l[k + n * i] * work[k];
        }
        work[i] = value / l[i + n * i];
    }
    x.fill(0.0);
    for i in 0..rank {
        x[order[i]] = work[i];
    }
}

/// LU factorization with partial pivoting, `P A = L U`, in place (`L` unit lower, below the
/// diagonal; `U` on and above it); `pivots[k]` is the row swapped with row `k` at step `k`.
/// Returns false if a pivot is at most `n·ε·max|a_ij|` (singular to working precision).
pub fn lu(a: &mut [f64], n: usize, pivots: &mut [usize]) -> bool {
    let a = &mut a[..n * n];
    let tol = n as f64 * f64::EPSILON * a.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
    for k in 0..n {
        let mut p = k;
        for i in k + 1..n {
            if a[i + n * k].abs() > a[p + n * k].abs() {
                p = i;
            }
        }
        pivots[k] = p;
        let size = a[p + n * k].abs();
        if size.is_nan() || size <= tol {
            return false;
        }
        if p != k {
            for j in 0..n {
                a.swap(k + n * j, p + n * j);
            }
        }
        let pivot = a[k + n * k];
        for i in k + 1..n {
            a[i + n * k] /= pivot;
        }
        for j in k + 1..n {
            let akj = a[k + n * j];
            if akj != 0.0 {
                for i in k + 1..n {
                    a[i + n * j] -= a[i + n * k] * akj;
                }
            }
        }
    }
    true
}

/// Solves `A x = b` in place with the factor and pivots from [`lu`].
pub fn lu_solve(lu: &[f64], n: usize, pivots: &[usize], b: &mut [f64]) {
    let (a, b) = (&lu[..n * n], &mut b[..n]);
    for (k, &p) in pivots[..n].iter().enumerate() {
        b.swap(k, p);
    }
    for i in 0..n {
        let mut s = b[i];
        for j in 0..i {
            s -= a[i + n * j] * b[j];
        }
        b[i] = s;
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for j in i + 1..n {
            s -= a[i + n * j] * b[j];
        }
        b[i] = s / a[i + n * i];
    }
}

/// Solves `Aᵀ y = b` in place with the factor and pivots from [`lu`] (`Aᵀ = Uᵀ Lᵀ P`).
pub fn lu_solve_transposed(lu: &[f64], n: usize, pivots: &[usize], b: &mut [f64]) {
    // Uᵀ z = b (forward), then Lᵀ w = z (backward), then y = Pᵀ w.
    for j in 0..n {
        let sum: f64 = (0..j).map(|i| lu[i + n * j] * b[i]).sum();
        b[j] = (b[j] - sum) / lu[j + n * j];
    }
    for j in (0..n).rev() {
        let sum: f64 = (j + 1..n).map(|i| lu[i + n * j] * b[i]).sum();
        b[j] -= sum;
    }
    for j in (0..n).rev() {
        b.swap(j, pivots[j]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_solves_a_positive_definite_system() {
        let mut a = vec![4.0, 2.0, 0.4, 2.0, 5.0, 1.0, 0.4, 1.0, 3.0];
        let original = a.clone();
        assert!(cholesky(&mut a, 3));
        let mut x = vec![1.0, -2.0, 0.5];
        let b = x.clone();
        cholesky_solve(&a, 3, &mut x);
        for i in 0..3 {
            let ax: f64 = (0..3).map(|j| original[i + 3 * j] * x[j]).sum();
            assert!((ax - b[i]).abs() < 1e-14);
        }
        let mut singular = vec![1.0, 1.0, 1.0, 1.0];
        assert!(!cholesky(&mut singular, 2));
    }

    #[test]
    fn cholesky_inverse_inverts_a_positive_definite_matrix() {
        for n in [1, 3, 7] {
            // A = B Bᵀ + n I for a fixed B with entries of both signs.
            let mut a = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    a[i + n * j] = (0..n)
                        .map(|k| ((i * 7 + k * 3) % 5) as f64 - 2.0)
                        .zip((0..n).map(|k| ((j * 7 + k * 3) % 5) as f64 - 2.0))
                        .map(|(x, y)| x * y)
                        .sum::<f64>()
                        + if i == j { n as f64 } else { 0.0 };
                }
            }
            let mut l = a.clone();
            assert!(cholesky(&mut l, n));
            let mut inverse = vec![f64::NAN; n * n];
            cholesky_inverse(&l, n, &mut inverse);
            for i in 0..n {
                for j in 0..n {
                    let product: f64 = (0..n).map(|k| a[i + n * k] * inverse[k + n * j]).sum();
                    let expected = if i == j { 1.0 } else { 0.0 };
                    assert!((product - expected).abs() < 1e-13, "n = {n}: ({i}, {j})");
                    assert_eq!(inverse[i + n * j], inverse[j + n * i]);
                }
            }
        }
    }

    /// A rank-2 3×3 matrix (third row = first + second): the pivoted factor finds rank 2 and
    /// solves a consistent right-hand side.
    #[test]
    fn pivoted_cholesky_reveals_rank_and_solves_consistent_systems() {
        let rows = [[1.0, 2.0, 0.5], [0.0, 1.0, -1.0]];
        let j = [
            rows[0],
            rows[1],
            [
                rows[0][0] + rows[1][0],
                rows[0][1] + rows[1][1],
                rows[0][2] + rows[1][2],
            ],
        ];
        let mut a = vec![0.0; 9];
        for r in 0..3 {
            for c in 0..3 {
                a[r + 3 * c] = (0..3).map(|k| j[r][k] * j[c][k]).sum();
            }
        }
        let original = a.clone();
        let mut order = [0; 3];
        let rank = pivoted_cholesky(&mut a, 3, 1e-12, &mut order);
        assert_eq!(rank, 2);
        let y = [0.3, -0.7, 1.1];
        let b: Vec<f64> = (0..3)
            .map(|i| (0..3).map(|k| original[i + 3 * k] * y[k]).sum())
            .collect();
        let (mut x, mut work) = (vec![0.0; 3], vec![0.0; 3]);
        pivoted_solve(&a, 3, rank, &order, &b, &mut x, &mut work);
        for i in 0..3 {
            let ax: f64 = (0..3).map(|k| original[i + 3 * k] * x[k]).sum();
            assert!((ax - b[i]).abs() < 1e-12, "{ax} vs {}", b[i]);
        }
    }

    /// Values uniform in [−0.5, 0.5) from `seed` (xorshift64), the same on every run.
    /// `A x = b` and `Aᵀ y = b` by one partially pivoted LU, against the products.
    #[test]
    fn lu_solves_and_transposed_solves_meet_the_products() {
        let mut next = uniform(7);
        let n = 5;
        let a: Vec<f64> = (0..n * n).map(|_| next()).collect();
        let mut factor = a.clone();
        let mut pivots = vec![0; n];
        assert!(lu(&mut factor, n, &mut pivots));
        assert!(
            pivots.iter().enumerate().any(|(k, &p)| p != k),
            "no row swapped"
        );
        let b: Vec<f64> = (0..n).map(|_| next()).collect();
        let mut x = b.clone();
        lu_solve(&factor, n, &pivots, &mut x);
        for i in 0..n {
            let row: f64 = (0..n).map(|j| a[i + n * j] * x[j]).sum();
            assert!((row - b[i]).abs() < 1e-12, "A x: {row} vs {}", b[i]);
        }
        let mut y = b.clone();
        lu_solve_transposed(&factor, n, &pivots, &mut y);
        for j in 0..n {
            let column: f64 = (0..n).map(|i| a[i + n * j] * y[i]).sum();
            assert!((column - b[j]).abs() < 1e-12, "Aᵀ y: {column} vs {}", b[j]);
        }
    }

    fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    /// A floating robot's pattern (four 4-speed legs coupled only through 6 base speeds,
    /// declared last): the factor (skipping zero multipliers) and `L⁻¹B` (skipping zero runs)
    /// equal the textbook right-looking Cholesky and forward substitution that multiply every
    /// zero.
    #[test]
    fn skipping_the_zero_runs_changes_no_value() {
        let mut next = uniform(0x9E37_79B9_7F4A_7C15);
        let (legs, leg, base) = (4, 4, 6);
        let n = legs * leg + base;
        let group = |i: usize| if i < legs * leg { i / leg } else { legs };
        let mut a = vec![0.0; n * n];
        for j in 0..n {
            for i in j + 1..n {
                if group(i) == group(j) || group(i) == legs || group(j) == legs {
                    let v = next();
                    a[i + n * j] = v;
                    a[j + n * i] = v;
                }
            }
        }
        for i in 0..n {
            // Diagonally dominant: positive definite.
            a[i + n * i] = 1.0 + (0..n).map(|k| a[i + n * k].abs()).sum::<f64>();
        }
        let mut reference = a.clone();
        for j in 0..n {
            let pivot = reference[j + n * j].sqrt();
            reference[j + n * j] = pivot;
            for i in j + 1..n {
                reference[i + n * j] /= pivot;
            }
            for k in j + 1..n {
                for i in k..n {
                    reference[i + n * k] -= reference[i + n * j] * reference[k + n * j];
                }
            }
        }
        let mut factor = a.clone();
        assert!(cholesky(&mut factor, n));
        for j in 0..n {
            for i in j..n {
                assert_eq!(factor[i + n * j], reference[i + n * j], "L[{i}, {j}]");
            }
        }
        // Right-hand sides like constraint rows: one leg's speeds and the base's.
        let m = 5;
        let mut b = vec![0.0; n * m];
        for (c, column) in b.chunks_exact_mut(n).enumerate() {
            for (i, value) in column.iter_mut().enumerate() {
                if group(i) == c % legs || group(i) == legs {
                    *value = next();
                }
            }
        }
        let mut expected = b.clone();
        for column in expected.chunks_exact_mut(n) {
            for j in 0..n {
                column[j] /= reference[j + n * j];
                for i in j + 1..n {
                    column[i] -= reference[i + n * j] * column[j];
                }
            }
        }
        forward_substitute_columns(&factor, n, &mut b, m);
        assert_eq!(b, expected);
    }

    /// The unrolled sizes (1 to `UNROLLED`) and the run-time-size code agree, and solve.
    #[test]
    fn every_size_solves_and_the_products_agree() {
        let mut next = uniform(0x2545_F491_4F6C_DD1D);
        for n in 1..=UNROLLED + 3 {
            let m = 1 + n % 4;
            // A = B Bᵀ + n I, symmetric positive definite.
            let b: Vec<f64> = (0..n * n).map(|_| next()).collect();
            let mut a = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    a[i + n * j] = (0..n).map(|k| b[i + n * k] * b[j + n * k]).sum::<f64>()
                        + if i == j { n as f64 } else { 0.0 };
                }
            }
            let original = a.clone();
            assert!(cholesky(&mut a, n));
            let rhs: Vec<f64> = (0..n).map(|_| next()).collect();
            let mut x = rhs.clone();
            cholesky_solve(&a, n, &mut x);
            for i in 0..n {
                let ax: f64 = (0..n).map(|j| original[i + n * j] * x[j]).sum();
                assert!((ax - rhs[i]).abs() < 1e-12, "n = {n}: {ax} vs {}", rhs[i]);
            }
            // Z = L⁻¹ C column by column; ZᵀZ = Cᵀ A⁻¹ C; Zᵀw and Z x against plain loops.
            // Column r of C starts with `r mod n` zeros (a constraint row on later speeds):
            // `gram_lower` skips them.
            let c: Vec<f64> = (0..n * m)
                .map(|i| if i % n < (i / n) % n { 0.0 } else { next() })
                .collect();
            let mut z = c.clone();
            forward_substitute_columns(&a, n, &mut z, m);
            let mut gram = vec![0.0; m * m];
            gram_lower(&z, n, m, &mut gram);
            for r in 0..m {
                let mut y: Vec<f64> = c[n * r..n * (r + 1)].to_vec();
                cholesky_solve(&a, n, &mut y);
                for s in 0..=r {
                    let expected: f64 = (0..n).map(|k| c[k + n * s] * y[k]).sum();
                    assert!((gram[r + m * s] - expected).abs() < 1e-12, "n = {n}, gram");
                }
            }
            let w: Vec<f64> = (0..n).map(|_| next()).collect();
            let mut zw = vec![0.0; m];
            transpose_times(&z, n, m, &w, &mut zw);
            let lambda: Vec<f64> = (0..m).map(|_| next()).collect();
            let mut zl = vec![0.5; n];
            add_times(&z, n, m, &lambda, &mut zl);
            for r in 0..m {
                let expected: f64 = (0..n).map(|k| z[k + n * r] * w[k]).sum();
                assert!((zw[r] - expected).abs() < 1e-14);
            }
            for k in 0..n {
                let expected: f64 = 0.5 + (0..m).map(|r| z[k + n * r] * lambda[r]).sum::<f64>();
                assert!((zl[k] - expected).abs() < 1e-14);
            }
        }
    }
}
