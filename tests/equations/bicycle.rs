//! The Whipple bicycle benchmark (Meijaard, Papadopoulos, Ruina & Schwab, Proc. R. Soc. A 463,
//! 2007): `models/benchmarks/whipple_bicycle.mech`, linearized about upright straight running by
//! `linearize_steady`, against the paper's published matrices (eq. (A 24), given there to 14
//! digits) and its weave and capsize speeds (Table 2). The model is written in mech's own
//! general language (pins, sliders, a velocity constraint and a `rolling` element): none of
//! the paper's equations is in it, so agreement checks the derivation of nonholonomic
//! equations, the closure of the front contact and the steady-motion linearization at once.

use mech_runtime::nalgebra::{Complex, DMatrix};
use mech_runtime::{assemble_speeds, linearize_steady, Model, SteadyLinearization, SteadyState};

use crate::common;

/// Under `models/benchmarks/`: a reference model, not compiled to Rust with the bundled ones
/// (its generated code is the largest of all; the tape serves the tests).
const BICYCLE: &str = "benchmarks/whipple_bicycle";
const G: f64 = 9.81;
const REAR_RADIUS: f64 = 0.3;

/// Published: M, C1, K0, K2 of `M q̈ + v C1 q̇ + (g K0 + v² K2) q = f`, q = (φ, δ).
const M: [[f64; 2]; 2] = [
    [80.81722, 2.31941332208709],
    [2.31941332208709, 0.29784188199686],
];
const C1: [[f64; 2]; 2] = [
    [0.0, 33.86641391492494],
    [-0.85035641456978, 1.68540397397560],
];
const K0: [[f64; 2]; 2] = [
    [-80.95, -2.59951685249872],
    [-2.59951685249872, -0.80329488458618],
];
const K2: [[f64; 2]; 2] = [[0.0, 76.59734589573222], [0.0, 2.65431523794604]];
/// Table 2: the weave and capsize speeds, m/s.
const WEAVE_SPEED: f64 = 4.292_382_536_341_11;
const CAPSIZE_SPEED: f64 = 6.024_262_015_388_37;

fn index(model: &dyn Model, name: &str) -> usize {
    (0..model.nq())
        .find(|&i| model.coordinate_name(i) == name)
        .unwrap_or_else(|| panic!("no coordinate {name}"))
}

/// Upright straight running at forward speed `v`.
fn linearized(model: &dyn Model, v: f64) -> SteadyLinearization {
    let (q, mut u) = common::initial_state(model);
    let names = ["roll", "rear", "steer"];
    let speeds: Vec<usize> = names.iter().map(|name| index(model, name)).collect();
    u.iter_mut().for_each(|x| *x = 0.0);
    u[index(model, "rear")] = v / REAR_RADIUS;
    assemble_speeds(model, 0.0, &q, &mut u, &speeds).unwrap();
    let pitch = index(model, "pitch");
    let coordinates: Vec<usize> = (0..model.nq()).filter(|&i| i != pitch).collect();
    let inputs = common::default_inputs(model);
    linearize_steady(model, 0.0, (&q, &u), &inputs, &coordinates, &speeds).unwrap()
}

/// `M`, `C`, `K` over (roll, steer) at speed `v`.
fn second_order(model: &dyn Model, v: f64) -> [DMatrix<f64>; 3] {
    let linear = linearized(model, v);
    let form = linear
        .second_order()
        .expect("roll and steer are independent speeds");
    let names: Vec<&str> = form
        .coordinates
        .iter()
        .map(|&i| model.coordinate_name(i))
        .collect();
    assert_eq!(names, ["roll", "steer"]);
    [form.mass, form.damping, form.stiffness]
}

fn assert_matrix(what: &str, ours: &DMatrix<f64>, published: [[f64; 2]; 2], tolerance: f64) {
    for r in 0..2 {
        for c in 0..2 {
            let error = (ours[(r, c)] - published[r][c]).abs();
            assert!(
                error <= tolerance * published[r][c].abs().max(1.0),
                "{what}[{r}][{c}] = {} vs published {}",
                ours[(r, c)],
                published[r][c]
            );
        }
    }
}

fn largest_error(ours: &DMatrix<f64>, published: [[f64; 2]; 2]) -> f64 {
    let mut worst = 0.0_f64;
    for r in 0..2 {
        for c in 0..2 {
            worst =
                worst.max((ours[(r, c)] - published[r][c]).abs() / published[r][c].abs().max(1.0));
        }
    }
    worst
}

#[test]
fn whipple_bicycle_matches_the_published_linearized_equations() {
    let model = common::tape(BICYCLE);
    let linear = linearized(&model, 5.0);
    let cyclic: Vec<&str> = linear
        .cyclic
        .iter()
        .map(|&i| model.coordinate_name(i))
        .collect();
    assert_eq!(cyclic, ["x", "y", "yaw", "rear", "front"]);
    assert!(linear.unsteadiness() < 1e-12, "{}", linear.unsteadiness());
    // A symmetry: the place, heading and wheel angles moved on, A is the same to the central
    // differences' noise (measured 2.8e-8; `mech linearize` warns above 1e-6).
    assert!(linear.cyclic_change < 1e-6, "{}", linear.cyclic_change);
    let [mass, _, stiffness_0] = second_order(&model, 0.0);
    let [_, damping_a, stiffness_a] = second_order(&model, 3.0);
    let [_, damping_b, stiffness_b] = second_order(&model, 5.0);
    let k0 = stiffness_0 / G;
    let c1 = damping_b.clone() / 5.0;
    let k2 = (stiffness_b.clone() - stiffness_a.clone()) / (25.0 - 9.0);
    let c1_at_3 = damping_a / 3.0;
    println!(
        "Whipple bicycle vs Meijaard et al. (2007), largest relative difference: M {:.1e}, \
         C1 {:.1e}, K0 {:.1e}, K2 {:.1e}",
        largest_error(&mass, M),
        largest_error(&c1, C1),
        largest_error(&k0, K0),
        largest_error(&k2, K2)
    );
    // Measured 5e-15 to 2e-14; the central differences' noise is allowed for.
    assert_matrix("M", &mass, M, 1e-12);
    assert_matrix("C1", &c1, C1, 1e-10);
    assert_matrix("C1 (at 3 m/s)", &c1_at_3, C1, 1e-10);
    assert_matrix("K0", &k0, K0, 1e-10);
    assert_matrix("K2", &k2, K2, 1e-10);
}

/// The eigenvalues of the published equations at speed `v` (first-order form on
/// `[φ, δ, φ̇, δ̇]`), sorted as `SteadyLinearization::eigenvalues`.
fn published_eigenvalues(v: f64) -> Vec<Complex<f64>> {
    let matrix = |m: [[f64; 2]; 2]| DMatrix::from_fn(2, 2, |r, c| m[r][c]);
    let mass_inverse = matrix(M).try_inverse().unwrap();
    let stiffness = matrix(K0) * G + matrix(K2) * (v * v);
    let damping = matrix(C1) * v;
    let mut a = DMatrix::zeros(4, 4);
    a.view_mut((0, 2), (2, 2)).fill_with_identity();
    a.view_mut((2, 0), (2, 2))
        .copy_from(&(-&mass_inverse * stiffness));
    a.view_mut((2, 2), (2, 2))
        .copy_from(&(-&mass_inverse * damping));
    let mut values: Vec<Complex<f64>> = a.complex_eigenvalues().iter().copied().collect();
    values.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
    values
}

/// The eigenvalues of mech's linearization but the forward speed's (the rear wheel's spin
/// is a state of its own, which the linear motion leaves constant: an eigenvalue 0 whose
/// eigenvector is that state alone).
fn lateral_eigenvalues(model: &dyn Model, v: f64) -> Vec<Complex<f64>> {
    let linear = linearized(model, v);
    let rear = linear
        .states
        .iter()
        .position(|s| *s == SteadyState::Speed(index(model, "rear")))
        .unwrap();
    let scale = linear.a.amax();
    assert!(
        linear.a.row(rear).amax() <= 1e-9 * scale,
        "the spin is not constant"
    );
    assert!(
        linear.a.column(rear).amax() <= 1e-9 * scale,
        "the spin is felt"
    );
    let kept: Vec<usize> = (0..linear.states.len()).filter(|&k| k != rear).collect();
    let lateral = SteadyLinearization {
        a: linear.a.select_rows(&kept).select_columns(&kept),
        ..linear
    };
    lateral.eigenvalues()
}

/// Meijaard et al.'s Table 2: the eigenvalues from 0 to 10 m/s against those of the published
/// matrices, and the weave speed (where the oscillating pair's real part crosses zero) and
/// the capsize speed (where the real one does) to the digits given.
#[test]
fn whipple_bicycle_eigenvalues_and_stable_speed_range() {
    let model = common::tape(BICYCLE);
    let mut worst = 0.0_f64;
    for step in 0..=20 {
        let v = 0.5 * step as f64;
        let ours = lateral_eigenvalues(&model, v);
        let theirs = published_eigenvalues(v);
        for (a, b) in ours.iter().zip(&theirs) {
            worst = worst.max((a - b).norm() / b.norm().max(1.0));
        }
    }
    println!("eigenvalues at 0, 0.5, …, 10 m/s: largest difference {worst:.1e}");
    // Measured 2.9e-14; the central differences of the rates allow more, not five decades.
    assert!(worst < 1e-11, "{worst:e}");
    let weave = |v: f64| {
        lateral_eigenvalues(&model, v)
            .iter()
            .filter(|z| z.im.abs() > 1e-9)
            .map(|z| z.re)
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let capsize = |v: f64| {
        lateral_eigenvalues(&model, v)
            .iter()
            .filter(|z| z.im.abs() <= 1e-9)
            .map(|z| z.re)
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let crossing = |f: &dyn Fn(f64) -> f64, mut low: f64, mut high: f64| {
        assert!(f(low) * f(high) < 0.0);
        while high - low > 1e-12 {
            let middle = 0.5 * (low + high);
            if f(middle) * f(low) > 0.0 {
                low = middle;
            } else {
                high = middle;
            }
        }
        0.5 * (low + high)
    };
    let weave_speed = crossing(&weave, 4.0, 4.5);
    let capsize_speed = crossing(&capsize, 5.5, 6.5);
    println!(
        "weave speed {weave_speed:.12} m/s (published {WEAVE_SPEED}, {:.1e} off), capsize speed \
         {capsize_speed:.12} m/s (published {CAPSIZE_SPEED}, {:.1e} off)",
        weave_speed - WEAVE_SPEED,
        capsize_speed - CAPSIZE_SPEED
    );
    // Bisection to 1e-12 on eigenvalues good to ~1e-14: the published 14 digits, to 1e-11.
    assert!((weave_speed - WEAVE_SPEED).abs() < 1e-11, "{weave_speed}");
    assert!(
        (capsize_speed - CAPSIZE_SPEED).abs() < 1e-11,
        "{capsize_speed}"
    );
}

/// The rear wheel's `u0 = v / rR` is an expression of params: it follows a changed `v` (and
/// `rR`) in the tape model, so a sweep over `v` moves the operating point.
#[test]
fn initial_speeds_written_with_params_follow_them() {
    use mech_runtime::Model as _;
    let mut model = common::tape(BICYCLE);
    let param = |model: &dyn Model, name: &str| {
        (0..model.nparams())
            .find(|&i| model.param_name(i) == name)
            .unwrap()
    };
    let (v, radius) = (param(&model, "v"), param(&model, "rR"));
    let rear = index(&model, "rear");
    let (_, u) = common::initial_state(&model);
    assert_eq!(u[rear], 5.0 / 0.3);
    model.set_param(v, 2.0);
    model.set_param(radius, 0.25);
    let (_, u) = common::initial_state(&model);
    assert_eq!(u[rear], 2.0 / 0.25);
}
