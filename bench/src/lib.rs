//! The benchmark of `docs/benchmarks.md`: mech on the N-link 3D chain of
//! `../shared/peers/`, measured beside SymPy and Pinocchio by `bench/run.sh`.
//!
//! * [`chain_source`]: the `.mech` text of the N-link chain (the models `build.rs` compiles).
//! * [`chains`]: the chains compiled to Rust at build time (dogfooding `mech_codegen::Builder`).
//! * [`cholesky_solve`]: an allocation-free in-place Cholesky solve for `M u̇ = F`.
//! * [`loops`]: the four-bar and the spherical five-bar (assembly, constrained `u̇`, 1 s of
//!   motion).
//! * [`timing`]: medians of batched tight loops, and of repeated one-shot runs.

pub mod chains;
pub mod loops;
pub mod source;
pub mod timing;

pub use source::{
    chain_source, chain_source_per_link, floating_chain_source, FLOATING_SIZES, SIZES,
};

use mech_codegen::Compiled;

/// Solves `A x = b` in place for a symmetric positive definite `n × n` matrix `a`
/// (column-major; only the lower triangle is read, and it is overwritten by the Cholesky
/// factor `L`, `A = L Lᵀ`); `b` becomes `x`. Returns `false`, with `a` and `b` partly
/// overwritten, when `A` is not positive definite. Never allocates.
#[inline(always)]
pub fn cholesky_solve(a: &mut [f64], b: &mut [f64], n: usize) -> bool {
    assert!(a.len() >= n * n && b.len() >= n);
    // Right-looking factorization: column j of L, then the trailing lower triangle updated
    // column by column (contiguous in column-major storage).
    for j in 0..n {
        let pivot = a[j + n * j];
        if pivot <= 0.0 || pivot.is_nan() {
            return false;
        }
        let d = pivot.sqrt();
        let inv = 1.0 / d;
        a[j + n * j] = d;
        for i in j + 1..n {
            a[i + n * j] *= inv;
        }
        for c in j + 1..n {
            let l_cj = a[c + n * j];
            for i in c..n {
                a[i + n * c] -= a[i + n * j] * l_cj;
            }
        }
    }
    // L y = b (column oriented), then Lᵀ x = y (dot products down the columns of L).
    for j in 0..n {
        b[j] /= a[j + n * j];
        let y = b[j];
        for i in j + 1..n {
            b[i] -= a[i + n * j] * y;
        }
    }
    for j in (0..n).rev() {
        let mut sum = b[j];
        for i in j + 1..n {
            sum -= a[i + n * j] * b[i];
        }
        b[j] = sum / a[j + n * j];
    }
    true
}

/// The fixed-size form of [`cholesky_solve`]: `m` is overwritten by its factor, `f` by `u̇`.
#[inline(always)]
pub fn cholesky_solve_fixed<const N: usize>(
    m: &mut nalgebra::SMatrix<f64, N, N>,
    f: &mut nalgebra::SVector<f64, N>,
) -> bool {
    cholesky_solve(m.as_mut_slice(), f.as_mut_slice(), N)
}

/// The speeds at which every evaluation is timed: the non-zero `v` of the Pinocchio C++
/// peer (`peers/native/pinocchio_bench.cpp`), `u_i = 0.3 ((i mod 3) − 1) + 0.1 i`.
pub fn bench_speeds(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| 0.3 * ((i % 3) as f64 - 1.0) + 0.1 * i as f64)
        .collect()
}

/// Values of a compiled model's parameters, in index order (the defaults in the source).
pub fn param_values(compiled: &Compiled) -> Vec<f64> {
    compiled.model.params.iter().map(|(_, p)| p.value).collect()
}

/// `(M, F)` of a compiled model at `(q, u)` (time 0, no inputs), evaluated on its
/// expression pool; `M` column-major.
pub fn eval_equations(compiled: &Compiled, q: &[f64], u: &[f64]) -> (Vec<f64>, Vec<f64>) {
    use mech_codegen::sym::Symbol;
    let params = param_values(compiled);
    let value_of = |symbol: Symbol| match symbol {
        Symbol::Coordinate(i) => q[i as usize],
        Symbol::Speed(i) => u[i as usize],
        Symbol::Param(i) => params[i as usize],
        Symbol::Time => 0.0,
        Symbol::Input(_) | Symbol::Acceleration(_) => f64::NAN,
    };
    let equations = &compiled.equations;
    (
        equations.pool.eval(&equations.mass_matrix, &value_of),
        equations.pool.eval(&equations.forcing, &value_of),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use mech_codegen::SourceFile;

    fn compile(name: &str, text: String) -> Compiled {
        Compiled::from_source(SourceFile::new(name, text))
            .unwrap_or_else(|errors| panic!("{name}: {errors:?}"))
    }

    /// A deterministic pseudo-random state (xorshift), in [-1.5, 1.5).
    fn random_state(n: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
        let mut x = seed;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64 * 3.0 - 1.5
        };
        let q = (0..n).map(|_| next()).collect();
        let u = (0..n).map(|_| next()).collect();
        (q, u)
    }

    /// `M` and `F` of two compilations agree at the state `(q, u)`.
    fn assert_same_equations(a: &Compiled, b: &Compiled, q: &[f64], u: &[f64]) {
        let (m1, f1) = eval_equations(a, q, u);
        let (m2, f2) = eval_equations(b, q, u);
        assert_close(&m1, &m2, "M");
        assert_close(&f1, &f2, "F");
    }

    fn assert_close(a: &[f64], b: &[f64], what: &str) {
        assert_eq!(a.len(), b.len(), "{what}: lengths");
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            assert!(
                (x - y).abs() <= 1e-12 * (1.0 + x.abs().max(y.abs())),
                "{what}[{i}]: {x} vs {y}"
            );
        }
    }

    #[test]
    fn chain4_source_is_the_bundled_model() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/chain4.mech");
        let bundled = std::fs::read_to_string(path).expect("models/chain4.mech");
        assert_eq!(chain_source(4), bundled);
    }

    #[test]
    fn chain4_source_compiles_to_the_bundled_equations() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/chain4.mech");
        let bundled = Compiled::from_path(path).expect("models/chain4.mech compiles");
        let generated = compile("chain4.mech", chain_source(4));
        assert_eq!(generated.equations.nu, 4);
        for seed in [1, 2, 3] {
            let (q, u) = random_state(4, 0x9E37_79B9_7F4A_7C15 ^ seed);
            assert_same_equations(&bundled, &generated, &q, &u);
        }
    }

    #[test]
    fn per_link_parameters_give_the_same_equations() {
        for n in [1, 3, 6] {
            let shared = compile("shared.mech", chain_source(n));
            let per_link = compile("per_link.mech", chain_source_per_link(n));
            assert_eq!(per_link.model.params.len(), 9 * n + 1);
            let (q, u) = random_state(n, 7 + n as u64);
            assert_same_equations(&shared, &per_link, &q, &u);
        }
    }

    #[test]
    fn cholesky_solves_a_mass_matrix() {
        let compiled = compile("chain6.mech", chain_source(6));
        let (q, u) = random_state(6, 11);
        let (m, f) = eval_equations(&compiled, &q, &u);
        let (mut a, mut x) = (m.clone(), f.clone());
        assert!(cholesky_solve(&mut a, &mut x, 6));
        let reference = nalgebra::DMatrix::from_column_slice(6, 6, &m)
            .lu()
            .solve(&nalgebra::DVector::from_column_slice(&f))
            .expect("M is invertible");
        assert_close(&x, reference.as_slice(), "u̇");
        let mut not_spd = [1.0, 2.0, 2.0, 1.0];
        assert!(!cholesky_solve(&mut not_spd, &mut [1.0, 1.0], 2));
    }

    #[test]
    fn generated_chain_matches_its_equations() {
        let compiled = compile("chain4.mech", chain_source(4));
        let model = chains::chain4::Chain4::new();
        let (q, u) = random_state(4, 5);
        let qv = nalgebra::SVector::<f64, 4>::from_column_slice(&q);
        let uv = nalgebra::SVector::<f64, 4>::from_column_slice(&u);
        let inputs = nalgebra::SVector::<f64, 0>::zeros();
        let (m, f) = eval_equations(&compiled, &q, &u);
        assert_close(
            model.mass_matrix_fixed(0.0, &qv, &inputs).as_slice(),
            &m,
            "generated M",
        );
        assert_close(
            model.forcing_fixed(0.0, &qv, &uv, &inputs).as_slice(),
            &f,
            "generated F",
        );
    }
}
