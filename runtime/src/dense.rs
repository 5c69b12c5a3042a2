//! Small dense linear algebra on column-major slices, without allocation: Cholesky for the
//! mass matrix and a diagonally pivoted Cholesky that reveals the rank of a positive
//! semidefinite matrix (`J M⁻¹ Jᵀ` with redundant constraint rows).
//!
//! Matrices are `n × n`, column-major (`a[i + n*j]` is row i, column j), like the `Model`
//! trait's outputs.

/// Cholesky factorization `A = L Lᵀ` in place (the lower triangle receives `L`). Returns
/// false if a pivot is not positive relative to the diagonal (`A` not positive definite).
pub fn cholesky(a: &mut [f64], n: usize) -> bool {
    let scale = (0..n).map(|i| a[i + n * i].abs()).fold(0.0, f64::max);
    for j in 0..n {
        let mut diagonal = a[j + n * j];
        for k in 0..j {
            diagonal -= a[j + n * k] * a[j + n * k];
        }
        // NaN counts as not positive.
        if diagonal.is_nan() || diagonal <= scale * 1e-14 {
            return false;
        }
        let pivot = diagonal.sqrt();
        a[j + n * j] = pivot;
        for i in j + 1..n {
            let mut value = a[i + n * j];
            for k in 0..j {
                value -= a[i + n * k] * a[j + n * k];
            }
            a[i + n * j] = value / pivot;
        }
    }
    true
}

/// Solves `L Lᵀ x = b` in place, with `L` from [`cholesky`].
pub fn cholesky_solve(l: &[f64], n: usize, b: &mut [f64]) {
    for i in 0..n {
        let mut value = b[i];
        for k in 0..i {
            value -= l[i + n * k] * b[k];
        }
        b[i] = value / l[i + n * i];
    }
    for i in (0..n).rev() {
        let mut value = b[i];
        for k in i + 1..n {
            value -= l[k + n * i] * b[k];
        }
        b[i] = value / l[i + n * i];
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
    for (i, slot) in order.iter_mut().enumerate().take(n) {
        *slot = i;
    }
    let threshold = (0..n).map(|i| a[i + n * i]).fold(0.0, f64::max) * relative_tolerance;
    for j in 0..n {
        // Pivot: the largest remaining diagonal (Schur complement diagonal).
        let (best, value) = (j..n)
            .map(|i| (i, a[i + n * i]))
            .fold((j, f64::NEG_INFINITY), |m, c| if c.1 > m.1 { c } else { m });
        if value.is_nan() || value <= threshold || value <= 0.0 {
            return j;
        }
        if best != j {
            swap_symmetric(a, n, j, best);
            order.swap(j, best);
        }
        let pivot = a[j + n * j].sqrt();
        a[j + n * j] = pivot;
        for i in j + 1..n {
            a[i + n * j] /= pivot;
        }
        // Update the trailing block's lower triangle: A_ik −= L_ij L_kj.
        for k in j + 1..n {
            let l_kj = a[k + n * j];
            for i in k..n {
                a[i + n * k] -= a[i + n * j] * l_kj;
            }
        }
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
    x.iter_mut().for_each(|v| *v = 0.0);
    for i in 0..rank {
        x[order[i]] = work[i];
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
}
