//! Resonances refined on the continuous response (`mech::frequency::refined_resonances`)
//! against closed forms: the peak and both half-power frequencies of a one-degree-of-freedom
//! oscillator with viscous or hysteretic loss, on a coarse and a fine grid; and the two peaks
//! of a two-mode chain against a dense grid.

use std::f64::consts::TAU;

use mech::frequency::{self, log_space, refined_resonances, Resonance};
use mech_runtime::{FlexureDamping, Linearization};
use nalgebra::{Complex, DMatrix};

fn close(a: f64, b: f64, tolerance: f64) -> bool {
    (a / b - 1.0).abs() < tolerance
}

/// `m ẍ + c ẋ + k x = in`, `y = x`, with one flexure along `x` (stiffness `k`, time-domain
/// damper `c`, loss factor `η`), written directly: the viscous response is
/// `1/(k − mω² + icω)`, the hysteretic one `1/(k(1 + iη) − mω²)`, with no finite differences.
fn oscillator(m: f64, k: f64, c: f64, eta: f64) -> Linearization {
    let one = |x: f64| DMatrix::from_element(1, 1, x);
    Linearization {
        independent: vec![0],
        q: vec![0.0],
        inputs: vec![0.0],
        mass: one(m),
        damping: one(c),
        stiffness: one(k),
        input: one(1.0),
        output_position: one(1.0),
        output_velocity: one(0.0),
        output_input: one(0.0),
        flexure_gradient: one(1.0),
        flexure_stiffness: vec![k],
        flexure_damping: vec![c],
        flexure_loss: vec![eta],
    }
}

/// The one resonance of `linear` on `points` log-spaced frequencies, 10–1000 Hz.
fn refined(linear: &Linearization, damping: FlexureDamping, points: usize) -> Resonance {
    let found = refined_resonances(
        &log_space(10.0, 1000.0, points),
        frequency::linear_magnitude(linear, 0, 0, damping),
    )
    .unwrap();
    assert_eq!(found.len(), 1, "{found:?}");
    found[0]
}

/// Viscous: `|H|² = 1/D(s)`, `D(s) = (k − ms)² + c²s`, `s = ω²`. The peak is where
/// `D′(s) = 0`, `s_p = k/m − c²/(2m²)`; the half-power points solve `D(s) = 2D(s_p)`, the
/// quadratic in `s` (the quartic in ω) `m²s² + (c² − 2km)s + k² − 2D(s_p) = 0`.
/// Hysteretic: `|H|² = 1/((k − ms)² + (ηk)²)`: the peak at `s = k/m`, the half-power points
/// at `s = k(1 ± η)/m`. Both on a 20-point grid (a sample every 27 %, the half-power band is
/// 4 % wide) and a 2000-point one, to 1e-6 relative.
#[test]
fn one_mode_peak_and_half_power_points_match_the_closed_forms() {
    let (m, f_n, zeta, eta) = (2e-3, 100.0, 0.02, 0.03);
    let k = m * (TAU * f_n).powi(2);
    let c = 2.0 * zeta * (k * m).sqrt();
    let linear = oscillator(m, k, c, eta);
    let hz = |s: f64| s.sqrt() / TAU;

    let d = |s: f64| (k - m * s).powi(2) + c * c * s;
    let s_peak = k / m - c * c / (2.0 * m * m);
    let (a, b, cc) = (m * m, c * c - 2.0 * k * m, k * k - 2.0 * d(s_peak));
    // The larger root first (−b > 0: no cancellation), the smaller from the product a·s₁s₂ = cc.
    let s_high = (-b + (b * b - 4.0 * a * cc).sqrt()) / (2.0 * a);
    let s_low = cc / (a * s_high);
    let viscous = (hz(s_peak), 1.0 / d(s_peak).sqrt(), hz(s_low), hz(s_high));
    let hysteretic = (
        hz(k / m),
        1.0 / (eta * k),
        hz(k * (1.0 - eta) / m),
        hz(k * (1.0 + eta) / m),
    );

    for (damping, (peak_hz, peak, low_hz, high_hz)) in [
        (FlexureDamping::Viscous, viscous),
        (FlexureDamping::Hysteretic, hysteretic),
    ] {
        let q = peak_hz / (high_hz - low_hz);
        for points in [20, 2000] {
            let found = refined(&linear, damping, points);
            println!("{damping:?}, {points} points: {found:?}; exact Q {q}");
            assert!(
                close(found.frequency_hz, peak_hz, 1e-6),
                "{damping:?} {points}: peak {} Hz, exact {peak_hz} Hz",
                found.frequency_hz
            );
            assert!(close(found.peak_magnitude, peak, 1e-9), "{found:?}");
            let found_q = found.quality_factor.unwrap();
            assert!(
                close(found_q, q, 1e-6),
                "{damping:?} {points}: Q {found_q}, exact {q}"
            );
        }
        // The grid-only reading on the coarse grid is far off: what the refinement is for.
        let sampled: Vec<_> = log_space(10.0, 1000.0, 20)
            .into_iter()
            .map(|f| frequency::Point {
                frequency_hz: f,
                gain: linear.frequency_response(0, 0, TAU * f, damping).unwrap(),
            })
            .collect();
        let grid_q = frequency::resonances(&sampled)[0].quality_factor;
        assert!(
            grid_q.is_none_or(|grid_q| !close(grid_q, q, 0.1)),
            "{grid_q:?}"
        );
    }
}

/// `models/two_mass_chain.mech`'s |x2/push| at `f` (Hz), in closed form.
fn two_mass_chain(f: f64) -> f64 {
    crate::linear::two_mass_chain_response(TAU * f).norm()
}

/// Two modes (1.62 and 2.96 Hz, Q ≈ 21 and 15): refined on a 20-point grid (0.5–20 Hz, a
/// sample every 21 %), both peaks and both Q agree to 1e-6 with the grid-only reading of a
/// 400 000-point grid (its interpolation error ~1e-8), and with a 2000-point refinement.
#[test]
fn two_modes_refined_on_a_coarse_grid_match_a_dense_grid() {
    let dense: Vec<_> = log_space(0.5, 20.0, 400_000)
        .into_iter()
        .map(|f| frequency::Point {
            frequency_hz: f,
            gain: Complex::new(two_mass_chain(f), 0.0),
        })
        .collect();
    let reference = frequency::resonances(&dense);
    assert_eq!(reference.len(), 2, "{reference:?}");
    for points in [20, 2000] {
        let found = refined_resonances(&log_space(0.5, 20.0, points), two_mass_chain).unwrap();
        println!("{points} points: {found:?}\nreference: {reference:?}");
        assert_eq!(found.len(), 2, "{found:?}");
        for (ours, dense) in found.iter().zip(&reference) {
            assert!(close(ours.frequency_hz, dense.frequency_hz, 1e-6));
            assert!(close(ours.peak_magnitude, dense.peak_magnitude, 1e-6));
            let (q, q_dense) = (ours.quality_factor.unwrap(), dense.quality_factor.unwrap());
            assert!(close(q, q_dense, 1e-6), "Q {q} vs {q_dense}");
        }
    }
}
