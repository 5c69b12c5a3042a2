//! One-line tests of the symbolic engine in s-expression form (egg's `test_fn!` style).

use std::collections::HashMap;

use super::*;
use crate::back::tape::Program;

/// Parsing `input` through the canonicalizing constructors prints as `expected`.
fn check(input: &str, expected: &str) {
    let mut pool = ExprPool::new();
    let id = pool.parse_sexpr(input).unwrap();
    assert_eq!(pool.sexpr(id), expected, "simplifying {input}");
}

/// `d input / d symbol` prints as `expected`.
fn check_diff(input: &str, symbol: &str, expected: &str) {
    let mut pool = ExprPool::new();
    let id = pool.parse_sexpr(input).unwrap();
    let symbol_id = pool.parse_sexpr(symbol).unwrap();
    let Node::Symbol(s) = *pool.node(symbol_id) else {
        panic!("{symbol} is not a symbol")
    };
    let d = pool.diff(id, s);
    assert_eq!(pool.sexpr(d), expected, "d/d{symbol} {input}");
}

#[test]
fn constants_fold_exactly() {
    check("(+ 1/3 1/3 1/3)", "1");
    check("(* 2 0.5)", "1");
    check("(/ 3 6)", "1/2");
    check("(^ 2/3 -2)", "9/4");
    check("(sin 0)", "0");
    check("(cos 0)", "1");
}

#[test]
fn sums_collect_like_terms() {
    check("(+ x x)", "(* 2 x)");
    check("(- x x)", "0");
    check("(+ x 0)", "x");
    check("(+ (* 2 x y) (* -2 y x))", "0");
    check("(+ (+ a b) (- a) 3)", "(+ 3 b)");
}

#[test]
fn products_collect_powers() {
    check("(* x x)", "(^ x 2)");
    check("(* x (/ 1 x))", "1");
    check("(* 0 x)", "0");
    check("(* 1 x)", "x");
    check("(* (^ x 2) (^ x -1/2))", "(^ x 3/2)");
    check("(* 2 (+ a b))", "(+ (* 2 a) (* 2 b))");
}

#[test]
fn pythagorean_identity() {
    check("(+ (^ (sin q0) 2) (^ (cos q0) 2))", "1");
    check("(+ (* m (^ (sin q0) 2)) (* m (^ (cos q0) 2)))", "m");
    check(
        "(+ x (* 3 l (^ (sin q0) 2)) (* 3 l (^ (cos q0) 2)))",
        "(+ x (* 3 l))",
    );
}

#[test]
fn odd_and_even_functions() {
    check("(sin (- q0))", "(* -1 (sin q0))");
    check("(cos (- q0))", "(cos q0)");
}

#[test]
fn derivatives() {
    check_diff("(sin q0)", "q0", "(cos q0)");
    check_diff("(cos q0)", "q0", "(* -1 (sin q0))");
    check_diff("(* m (^ l 2) q0)", "q0", "(* m (^ l 2))");
    check_diff("(^ q0 3)", "q0", "(* 3 (^ q0 2))");
    check_diff("(* q0 (sin q0))", "q0", "(+ (sin q0) (* q0 (cos q0)))");
    check_diff("(sqrt q0)", "q0", "(* 1/2 (^ q0 -1/2))");
    check_diff("(ln q0)", "q0", "(^ q0 -1)");
    check_diff("(sin u0)", "q0", "0");
}

#[test]
fn hash_consing_shares_equal_expressions() {
    let mut pool = ExprPool::new();
    let a = pool.parse_sexpr("(+ (sin q0) (* 2 x))").unwrap();
    let b = pool.parse_sexpr("(+ (* x 2) (sin q0))").unwrap();
    assert_eq!(a, b);
}

#[test]
fn evaluation_matches_closed_form() {
    let mut pool = ExprPool::new();
    let e = pool
        .parse_sexpr("(+ (* 3 (^ q0 2)) (sqrt q0) (atan2 q0 1) (exp q0))")
        .unwrap();
    let q = 0.7_f64;
    let value = pool.eval(&[e], &|_| q)[0];
    let exact = 3.0 * q * q + q.sqrt() + q.atan2(1.0) + q.exp();
    assert!((value - exact).abs() < 1e-15, "{value} vs {exact}");
}

#[test]
fn derivative_agrees_with_finite_difference() {
    let mut pool = ExprPool::new();
    let e = pool
        .parse_sexpr(
            "(* (sin (* 2 q0)) (^ (+ 1 (^ q0 2)) -1/2) (atan2 q0 (+ 2 q0)) (tan q0) (abs q0))",
        )
        .unwrap();
    let d = pool.diff(e, Symbol::Coordinate(0));
    let at = |x: f64| pool.eval(&[e], &|_| x)[0];
    let x = 0.37;
    let h = 1e-6;
    let fd = (at(x + h) - at(x - h)) / (2.0 * h);
    let exact = pool.eval(&[d], &|_| x)[0];
    assert!((fd - exact).abs() < 1e-8, "{fd} vs {exact}");
}

/// `derivative_along` (one forward pass) equals the sum of the partials times the rates,
/// at a point, and for a second rate (`J̇u` from `φ`) is smaller than that sum's DAG.
#[test]
fn directional_derivative_is_the_sum_of_partials_times_rates() {
    let mut pool = ExprPool::new();
    let phi = pool
        .parse_sexpr("(+ (* (cos q0) (sin (+ q0 q1))) (* q2 (cos (+ q1 q2))) (atan2 q0 q2))")
        .unwrap();
    let symbols = [0, 1, 2].map(Symbol::Coordinate);
    let rates: HashMap<Symbol, ExprId> = symbols
        .iter()
        .enumerate()
        .map(|(i, &q)| (q, pool.symbol(Symbol::Speed(i as u32))))
        .collect();
    let summed = |pool: &mut ExprPool, f: ExprId| {
        let terms: Vec<ExprId> = symbols
            .iter()
            .map(|&q| {
                let partial = pool.diff(f, q);
                pool.mul(partial, rates[&q])
            })
            .collect();
        pool.add_all(&terms)
    };
    let velocity = pool.derivative_along(phi, &rates);
    let bias = pool.derivative_along(velocity, &rates);
    let velocity_summed = summed(&mut pool, phi);
    let bias_summed = summed(&mut pool, velocity_summed);
    let state = |s: Symbol| match s {
        Symbol::Coordinate(i) => [0.3, -1.1, 0.8][i as usize],
        Symbol::Speed(i) => [2.0, 0.5, -1.5][i as usize],
        _ => 0.0,
    };
    let values = pool.eval(&[velocity, velocity_summed, bias, bias_summed], &state);
    assert!((values[0] - values[1]).abs() < 1e-14, "{values:?}");
    assert!((values[2] - values[3]).abs() < 1e-13, "{values:?}");
    let size = |pool: &ExprPool, root| Program::compile(pool, &[root]).operation_count();
    assert!(size(&pool, bias) < size(&pool, bias_summed));
}

/// Reading `input` fails, saying `expected`.
fn check_error(input: &str, expected: &str) {
    let error = ExprPool::new().parse_sexpr(input).unwrap_err();
    assert_eq!(error.to_string(), expected, "reading {input}");
}

#[test]
fn parse_errors_are_reported() {
    check_error("(+ 1", "missing `)`");
    check_error("(frob 1)", "unknown operator `frob`");
    check_error(")", "unexpected `)`");
    check_error("(- a b c)", "`-` takes one or two arguments");
    check_error("(/ a)", "`/` takes two arguments");
    check_error("(^ a b)", "the exponent of `^` must be a number");
    check_error("(atan2 y)", "`atan2` takes two arguments");
    check_error("(sqrt a b)", "`sqrt` takes one argument");
    check_error("(sin a b)", "`sin` takes one argument");
}

#[test]
fn identity_search_respects_its_limit() {
    let text = "(+ (^ (sin q0) 2) (^ (cos q0) 2) a b c)";
    let mut limited = ExprPool::with_limits(Limits {
        identity_search_terms: 4,
    });
    let id = limited.parse_sexpr(text).unwrap();
    assert_eq!(limited.sexpr(id), "(+ (^ (sin q0) 2) (^ (cos q0) 2) a b c)");
    check(text, "(+ 1 a b c)");
}

/// `input` with every speed `u_i` set to zero prints as `expected` (`None`: no value there).
fn check_at_rest(input: &str, expected: Option<&str>) {
    let mut pool = ExprPool::new();
    let id = pool.parse_sexpr(input).unwrap();
    let zero = pool.zero();
    let rebuilt = pool.substitute(&[id], &|s| matches!(s, Symbol::Speed(_)).then_some(zero));
    assert_eq!(
        rebuilt.map(|r| pool.sexpr(r[0])).as_deref(),
        expected,
        "{input} at u = 0"
    );
}

#[test]
fn substitution_drops_vanishing_terms() {
    check_at_rest(
        "(+ (* m u0 u1 (sin q0)) (* k q0) 3)",
        Some("(+ 3 (* q0 k))"),
    );
    check_at_rest("(* c (+ u0 (cos u1)))", Some("c"));
    check_at_rest("(+ (sin q0) (atan2 u0 1))", Some("(sin q0)"));
    check_at_rest("(* q0 (^ u0 -1))", None);
}

/// Each s-expression of `texts`, parsed into `pool`.
fn parsed(pool: &mut ExprPool, texts: &[&str]) -> Vec<ExprId> {
    texts
        .iter()
        .map(|text| pool.parse_sexpr(text).unwrap())
        .collect()
}

/// Every token of the printout but the brackets.
fn printed_tokens(text: &str) -> u64 {
    text.replace(['(', ')'], " ").split_whitespace().count() as u64
}

#[test]
fn printed_size_counts_the_printout_without_making_it() {
    let mut pool = ExprPool::new();
    let roots = parsed(
        &mut pool,
        &[
            "(+ 1 (* 2 x) (* 3 (^ x 2) y) (sin q0))",
            "(* -1/2 (cos q0) (^ u0 2) m)",
            "(atan2 (* 2 q0) (- x))",
            "(/ (+ x 1) (^ (+ y 2) 3))",
            "x",
        ],
    );
    for &root in &roots {
        let text = pool.sexpr(root);
        assert_eq!(pool.printed_size(&[root]), printed_tokens(&text), "{text}");
    }
    let all: u64 = roots.iter().map(|&r| printed_tokens(&pool.sexpr(r))).sum();
    assert_eq!(pool.printed_size(&roots), all);

    // Sharing: e_{k+1} = sin(e_k) · cos(e_k) holds e_k twice, so its printout doubles with k
    // while the pool grows by a few nodes; 64 levels would print 2^64 tokens.
    let mut e = pool.parse_sexpr("q0").unwrap();
    let mut sizes = Vec::new();
    for _ in 0..64 {
        let (sin, cos) = (pool.call(Func::Sin, e), pool.call(Func::Cos, e));
        e = pool.mul(sin, cos);
        if sizes.len() < 4 {
            assert_eq!(pool.printed_size(&[e]), printed_tokens(&pool.sexpr(e)));
        }
        sizes.push(pool.printed_size(&[e]));
    }
    assert_eq!(&sizes[..3], [5, 13, 29]);
    assert_eq!(sizes[63], u64::MAX, "saturates instead of overflowing");
}

/// `ramp = max(0, x)` and its derivative `step` (Heaviside, 0 at the kink): values at and on
/// both sides of the kink, NaN kept, exact zeros folded, the chain rule, and the s-expression
/// round trip.
#[test]
fn ramp_and_step() {
    for (x, ramp, step) in [(-2.0, 0.0, 0.0), (0.0, 0.0, 0.0), (3.5, 3.5, 1.0)] {
        assert_eq!(Func::Ramp.apply(x), ramp);
        assert_eq!(Func::Step.apply(x), step);
    }
    assert!(Func::Ramp.apply(f64::NAN).is_nan() && Func::Step.apply(f64::NAN).is_nan());
    let mut pool = ExprPool::new();
    let zero = pool.zero();
    assert_eq!(pool.call(Func::Ramp, zero), zero);
    assert_eq!(pool.call(Func::Step, zero), zero);
    check_diff("(ramp (* 2 x))", "x", "(* 2 (step (* 2 x)))");
    check_diff("(step x)", "x", "0");
    check("(ramp (+ 1 x))", "(ramp (+ 1 x))");
}

/// `Func::ALL` holds every function once, in declaration order (the JIT indexes its shims by
/// `f as usize`): the match fails to compile when a function is added, pointing here.
#[test]
fn func_all_lists_every_function_in_declaration_order() {
    for (i, &f) in Func::ALL.iter().enumerate() {
        let declared = match f {
            Func::Sin => 0,
            Func::Cos => 1,
            Func::Tan => 2,
            Func::Exp => 3,
            Func::Ln => 4,
            Func::Abs => 5,
            Func::Ramp => 6,
            Func::Step => 7,
        };
        assert_eq!((i, f as usize), (declared, declared), "{}", f.name());
    }
}

/// A program restricted to some of its results keeps only what they need and computes
/// them to the same bits, in the order asked.
#[test]
fn restricted_programs_compute_the_same_bits() {
    let mut pool = ExprPool::new();
    let roots = parsed(
        &mut pool,
        &[
            "(* (sin q0) (+ u0 (cos q1)))",
            "(+ (^ (sin q0) 3) (sqrt (+ 2 (* q1 q1))))",
            "(atan2 (- u1 q0) (+ 1 (^ (cos q1) 2)))",
        ],
    );
    let program = Program::compile(&pool, &roots);
    let env = crate::back::tape::Env {
        t: 0.0,
        q: &[0.3, -1.1],
        u: &[2.0, 0.5],
        params: &[],
        inputs: &[],
    };
    let mut registers = Vec::new();
    let mut all = [0.0; 3];
    program.eval(&env, &mut registers, &mut all);
    for picked in [vec![0], vec![2, 1], vec![1]] {
        let part = program.restricted(&picked);
        assert!(part.ops.len() < program.ops.len(), "{picked:?}");
        let mut values = vec![0.0; picked.len()];
        part.eval(&env, &mut registers, &mut values);
        let expected: Vec<u64> = picked.iter().map(|&k| all[k].to_bits()).collect();
        let got: Vec<u64> = values.iter().map(|v| v.to_bits()).collect();
        assert_eq!(got, expected, "{picked:?}");
    }
    // The first root alone does not need the atan2 or the square root.
    let first = program.restricted(&[0]);
    assert!(!first.ops.iter().any(|op| matches!(
        op,
        crate::back::tape::Op::Atan2(..) | crate::back::tape::Op::Sqrt(_)
    )));
}
