//! Input signal tests.

use mech_runtime::{RuntimeError, Signal};
use std::f64::consts::{PI, TAU};

/// Zero crossings of `s` in [a, b], by scanning with step `dt` and bisecting.
fn zero_crossings(s: &Signal, a: f64, b: f64, dt: f64) -> Vec<f64> {
    let mut roots = vec![];
    let mut t = a;
    while t < b {
        let (mut lo, mut hi) = (t, (t + dt).min(b));
        if s.value(lo) == 0.0 {
            roots.push(lo);
        } else if s.value(lo).signum() != s.value(hi).signum() && s.value(hi) != 0.0 {
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if s.value(lo).signum() == s.value(mid).signum() {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            roots.push(0.5 * (lo + hi));
        }
        t += dt;
    }
    roots
}

#[test]
fn constant_and_sine_values() {
    assert_eq!(Signal::Constant(2.5).value(-3.0), 2.5);
    let s = Signal::Sine {
        amplitude: 2.0,
        frequency_hz: 5.0,
        phase_rad: PI / 2.0,
        offset: 1.0,
    };
    assert!((s.value(0.0) - 3.0).abs() < 1e-15);
    assert!((s.value(0.1) - 1.0 - 2.0 * (TAU * 0.5 + PI / 2.0).sin()).abs() < 1e-15);
    assert_eq!(s.frequency_hz(123.0), Some(5.0));
    assert_eq!(Signal::Constant(1.0).frequency_hz(0.0), None);
}

#[test]
fn sine_zero_crossings_are_half_a_period_apart() {
    let s = Signal::Sine {
        amplitude: 1.0,
        frequency_hz: 7.0,
        phase_rad: 0.3,
        offset: 0.0,
    };
    let roots = zero_crossings(&s, 0.0, 1.0, 1e-3);
    assert_eq!(roots.len(), 14);
    for w in roots.windows(2) {
        assert!((w[1] - w[0] - 1.0 / 14.0).abs() < 1e-12);
    }
}

#[test]
fn chirp_instantaneous_frequency_rises_linearly_then_holds() {
    let (f0, f1, d) = (2.0, 12.0, 5.0);
    let s = Signal::Chirp {
        amplitude: 3.0,
        f0_hz: f0,
        f1_hz: f1,
        duration: d,
        offset: 0.0,
    };
    s.validate().unwrap();
    assert_eq!(s.value(0.0), 0.0);
    assert_eq!(s.frequency_hz(-1.0), Some(f0));
    assert_eq!(s.frequency_hz(2.5), Some(7.0));
    assert_eq!(s.frequency_hz(9.0), Some(f1));

    // Zero crossings are where the phase 2π(f0 t + (f1 - f0) t²/(2d)) is a multiple of π.
    let roots = zero_crossings(&s, 0.0, d - 1e-2, 1e-3);
    for (k, &t) in roots.iter().enumerate().skip(1) {
        // Solve (f1-f0)/(2d) t² + f0 t - k/2 = 0.
        let a = (f1 - f0) / (2.0 * d);
        let exact = (-f0 + (f0 * f0 + 2.0 * a * k as f64).sqrt()) / (2.0 * a);
        assert!((t - exact).abs() < 1e-10, "crossing {k}: {t} vs {exact}");
    }
    // Total phase over the sweep: 2π (f0 + f1)/2 · d = 2π·35: crossings k = 0..=70, the last
    // one at t = d (outside the scanned range).
    assert_eq!(roots.len(), 70);
    // Spacing between crossings is 1/(2 f(t)) locally.
    for w in roots.windows(2) {
        let mid = 0.5 * (w[0] + w[1]);
        let f = s.frequency_hz(mid).unwrap();
        assert!(((w[1] - w[0]) * 2.0 * f - 1.0).abs() < 1e-2);
    }
    // After the sweep: f1 with continuous phase (the crossing at t = d continues the series).
    let after = zero_crossings(&s, d - 1e-2, d + 1.0, 1e-3);
    assert!((after[0] - d).abs() < 1e-9, "{}", after[0]);
    for w in after.windows(2) {
        assert!((w[1] - w[0] - 1.0 / (2.0 * f1)).abs() < 1e-10);
    }
    // Continuity at the end of the sweep.
    assert!((s.value(d - 1e-9) - s.value(d + 1e-9)).abs() < 1e-6);
}

#[test]
fn table_interpolates_linearly_and_holds_outside() {
    let s = Signal::table(vec![0.0, 1.0, 3.0], vec![1.0, 3.0, -1.0]).unwrap();
    assert_eq!(s.value(-5.0), 1.0);
    assert_eq!(s.value(0.0), 1.0);
    assert_eq!(s.value(0.25), 1.5);
    assert_eq!(s.value(1.0), 3.0);
    assert_eq!(s.value(2.0), 1.0);
    assert_eq!(s.value(3.0), -1.0);
    assert_eq!(s.value(10.0), -1.0);
    let one = Signal::table(vec![2.0], vec![4.0]).unwrap();
    assert_eq!(one.value(0.0), 4.0);
    assert_eq!(one.value(5.0), 4.0);
}

#[test]
fn table_validation() {
    let err = |t: Vec<f64>, v: Vec<f64>| match Signal::table(t, v) {
        Err(RuntimeError::InvalidSignal(msg)) => msg,
        other => panic!("expected InvalidSignal, got {other:?}"),
    };
    assert!(err(vec![], vec![]).contains("empty"));
    assert!(err(vec![0.0, 1.0], vec![1.0]).contains("2 times but 1 values"));
    assert!(err(vec![0.0, 1.0, 1.0], vec![1.0, 2.0, 3.0]).contains("increase strictly"));
    assert!(err(vec![0.0, 2.0, 1.0], vec![1.0, 2.0, 3.0]).contains("increase strictly"));
    assert!(err(vec![0.0, f64::NAN], vec![1.0, 2.0]).contains("not finite"));
    assert!(err(vec![0.0, 1.0], vec![1.0, f64::INFINITY]).contains("not finite"));
}

#[test]
fn parameter_validation() {
    let chirp = |duration: f64, f0_hz: f64| Signal::Chirp {
        amplitude: 1.0,
        f0_hz,
        f1_hz: 2.0,
        duration,
        offset: 0.0,
    };
    assert!(chirp(1.0, 1.0).validate().is_ok());
    assert!(matches!(
        chirp(0.0, 1.0).validate(),
        Err(RuntimeError::InvalidSignal(_))
    ));
    assert!(matches!(
        chirp(1.0, -1.0).validate(),
        Err(RuntimeError::InvalidSignal(_))
    ));
    assert!(matches!(
        Signal::Constant(f64::NAN).validate(),
        Err(RuntimeError::InvalidSignal(_))
    ));
}
