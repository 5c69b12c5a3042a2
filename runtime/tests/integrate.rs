//! Integrator tests against exact solutions and against Hairer's Fortran DOPRI5.

// Reference values are copied verbatim from their sources.
#![allow(clippy::excessive_precision)]

use mech_runtime::integrate::{AdaptiveOptions, Dop853, Dopri5, Ode, Rk4, Stepper};
use mech_runtime::RuntimeError;

mod common;
use common::{run_to_end, worst_dense_error};

/// y' = -y, y(0) = 1.
struct Decay;
impl Ode for Decay {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), RuntimeError> {
        dxdt[0] = -x[0];
        Ok(())
    }
}

/// x'' = -x as [x, v]; exact solution from (1, 0) is (cos t, -sin t).
struct Oscillator;
impl Ode for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), RuntimeError> {
        dxdt[0] = x[1];
        dxdt[1] = -x[0];
        Ok(())
    }
}

/// Restricted three-body problem (Hairer, Nørsett & Wanner I, §II.0).
struct Arenstorf;
const MU: f64 = 0.012277471;
const ARENSTORF_X0: [f64; 4] = [0.994, 0.0, 0.0, -2.00158510637908252240537862224];
const ARENSTORF_PERIOD: f64 = 17.0652165601579625588917206249;
impl Ode for Arenstorf {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&mut self, _t: f64, y: &[f64], f: &mut [f64]) -> Result<(), RuntimeError> {
        let mup = 1.0 - MU;
        let r1 = (y[0] + MU).powi(2) + y[1].powi(2);
        let r1 = r1 * r1.sqrt();
        let r2 = (y[0] - mup).powi(2) + y[1].powi(2);
        let r2 = r2 * r2.sqrt();
        f[0] = y[2];
        f[1] = y[3];
        f[2] = y[0] + 2.0 * y[3] - mup * (y[0] + MU) / r1 - MU * (y[0] - mup) / r2;
        f[3] = y[1] - 2.0 * y[2] - mup * y[1] / r1 - MU * y[1] / r2;
        Ok(())
    }
}

/// y' = y², y(0) = 1: y = 1/(1 - t) blows up at t = 1.
struct BlowUp;
impl Ode for BlowUp {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), RuntimeError> {
        dxdt[0] = x[0] * x[0];
        Ok(())
    }
}

fn tol(rtol: f64, atol: f64) -> AdaptiveOptions {
    AdaptiveOptions {
        rtol,
        atol,
        ..Default::default()
    }
}

/// Global error of DOPRI5 on the oscillator over [0, 20].
fn oscillator_error(rtol: f64) -> f64 {
    let t_end = 20.0;
    let mut s = Dopri5::new(Oscillator, 0.0, &[1.0, 0.0], t_end, tol(rtol, rtol)).unwrap();
    run_to_end(&mut s);
    assert_eq!(s.t(), t_end);
    let x = s.state();
    (x[0] - t_end.cos()).abs().max((x[1] + t_end.sin()).abs())
}

#[test]
fn dopri5_decay_global_error() {
    let mut s = Dopri5::new(Decay, 0.0, &[1.0], 10.0, tol(1e-10, 1e-14)).unwrap();
    run_to_end(&mut s);
    let exact = (-10.0f64).exp();
    let rel = (s.state()[0] - exact).abs() / exact;
    assert!(rel < 1e-8, "relative error {rel:e}");
    // A loose tolerance must give a visibly worse answer (the test can fail).
    let mut loose = Dopri5::new(Decay, 0.0, &[1.0], 10.0, tol(1e-4, 1e-14)).unwrap();
    run_to_end(&mut loose);
    let rel_loose = (loose.state()[0] - exact).abs() / exact;
    assert!(rel_loose > 100.0 * rel, "{rel_loose:e} vs {rel:e}");
}

#[test]
fn dopri5_oscillator_error_decreases_with_tolerance() {
    let errors: Vec<f64> = [1e-4, 1e-6, 1e-8, 1e-10]
        .iter()
        .map(|&r| oscillator_error(r))
        .collect();
    assert!(errors[3] < 1e-8, "error at rtol 1e-10: {:e}", errors[3]);
    for w in errors.windows(2) {
        // Tolerance 100× tighter: error at least 10× smaller (DOPRI5's error is roughly
        // proportional to the tolerance).
        assert!(w[1] < w[0] / 10.0, "errors {errors:?}");
    }
}

#[test]
fn dopri5_dense_output_matches_exact_solution() {
    let mut s = Dopri5::new(Oscillator, 0.0, &[1.0, 0.0], 20.0, tol(1e-10, 1e-10)).unwrap();
    let mut out = [0.0; 2];
    let mut worst: f64 = 0.0;
    let mut checked = 0;
    while !s.is_finished() {
        s.step().unwrap();
        let (a, b) = (s.t_prev(), s.t());
        for k in 1..10 {
            let t = a + (b - a) * k as f64 / 10.0;
            s.interpolate(t, &mut out).unwrap();
            worst = worst.max((out[0] - t.cos()).abs().max((out[1] + t.sin()).abs()));
            checked += 1;
        }
        // End points are the step's own states.
        s.interpolate(b, &mut out).unwrap();
        assert_eq!(out, [s.state()[0], s.state()[1]]);
    }
    assert!(checked > 100);
    assert!(worst < 1e-8, "worst dense-output error {worst:e}");
    // Outside the last step: an error, not an extrapolation.
    let t_prev = s.t_prev();
    assert!(matches!(
        s.interpolate(t_prev - 1e-3, &mut out),
        Err(RuntimeError::InterpolationOutOfRange { .. })
    ));
}

/// Hairer's DOPRI5 (Fortran) on the Arenstorf orbit with rtol = atol = 1e-7 and a first step of
/// 1e-4 (driver `dopri5_aren.f` of github.com/cpmech/hwode, output
/// `russell_ode/data/fortran_dopri5_arenstorf.txt` of github.com/cpmech/russell): 217 accepted
/// and 21 rejected steps, and the final state below. Our transcription must take the same steps.
#[test]
fn dopri5_reproduces_hairer_fortran_on_arenstorf() {
    let opts = AdaptiveOptions {
        h_init: Some(1e-4),
        ..tol(1e-7, 1e-7)
    };
    let mut s = Dopri5::new(Arenstorf, 0.0, &ARENSTORF_X0, ARENSTORF_PERIOD, opts).unwrap();
    // Dense output at t = 1, 2, ... as printed by the Fortran SOLOUT.
    let fortran_dense: [(f64, [f64; 4]); 3] = [
        (
            1.0,
            [
                3.132838429324978E-01,
                3.480091155210374E-01,
                -1.042618215839560E+00,
                6.733839248384575E-01,
            ],
        ),
        (
            10.0,
            [
                -8.398073586249510E-01,
                4.468300944741782E-01,
                3.737429154752904E-01,
                -1.496700318777275E-01,
            ],
        ),
        (
            17.0,
            [
                9.413011551544933E-01,
                3.531669084568508E-02,
                6.983649876011137E-01,
                -1.853067154749635E-01,
            ],
        ),
    ];
    let mut out = [0.0; 4];
    let mut next = 0;
    while !s.is_finished() {
        s.step().unwrap();
        while next < fortran_dense.len() && fortran_dense[next].0 <= s.t() {
            let (t, want) = fortran_dense[next];
            s.interpolate(t, &mut out).unwrap();
            for i in 0..4 {
                assert!(
                    (out[i] - want[i]).abs() < 1e-12,
                    "t = {t}: {out:?} vs {want:?}"
                );
            }
            next += 1;
        }
    }
    assert_eq!(next, fortran_dense.len());
    let st = s.stats();
    assert_eq!(st.accepted_steps, 217);
    assert_eq!(st.rejected_steps, 21);
    // Fortran counts 2 evaluations at the start even when H is given; we count 1.
    assert_eq!(st.rhs_evaluations, 1 + 6 * 238);
    let fortran_end = [
        9.940021704030663E-01,
        9.040891036151961E-06,
        1.459758305600828E-03,
        -2.001245515834718E+00,
    ];
    for i in 0..4 {
        assert!(
            (s.state()[i] - fortran_end[i]).abs() < 1e-12,
            "{:?} vs {fortran_end:?}",
            s.state()
        );
    }
}

#[test]
fn dopri5_arenstorf_closes_after_one_period_at_tight_tolerance() {
    let mut s = Dopri5::new(
        Arenstorf,
        0.0,
        &ARENSTORF_X0,
        ARENSTORF_PERIOD,
        tol(1e-12, 1e-12),
    )
    .unwrap();
    run_to_end(&mut s);
    let gap = s
        .state()
        .iter()
        .zip(ARENSTORF_X0)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(gap < 1e-5, "orbit misses its start by {gap:e}");
    // The automatic initial step size works too (no h_init given) and the count is sane.
    let st = s.stats();
    assert!(
        st.accepted_steps > 500 && st.accepted_steps < 5000,
        "{st:?}"
    );
}

#[test]
fn dopri5_state_modification_recomputes_the_derivative() {
    // Integrate y' = -y to t = 1, double the state, continue to t = 2:
    // y(2) = 2·e⁻¹·e⁻¹.
    let mut s = Dopri5::new(Decay, 0.0, &[1.0], 1.0, tol(1e-12, 1e-14)).unwrap();
    run_to_end(&mut s);
    s.state_mut()[0] *= 2.0;
    s.set_t_end(2.0).unwrap();
    run_to_end(&mut s);
    let exact = 2.0 * (-2.0f64).exp();
    assert!(
        (s.state()[0] - exact).abs() < 1e-11,
        "{} vs {exact}",
        s.state()[0]
    );
    // reset() is the explicit form, and counts one evaluation.
    let before = s.stats().rhs_evaluations;
    s.state_mut()[0] = 1.0;
    s.reset().unwrap();
    assert_eq!(s.stats().rhs_evaluations, before + 1);
    assert_eq!(s.derivative(), &[-1.0]);
}

#[test]
fn dopri5_blow_up_is_an_error_not_a_hang() {
    let mut s = Dopri5::new(BlowUp, 0.0, &[1.0], 2.0, tol(1e-8, 1e-10)).unwrap();
    let err = loop {
        match s.step() {
            Ok(()) => assert!(!s.is_finished(), "integrated through a singularity"),
            Err(e) => break e,
        }
    };
    match err {
        RuntimeError::StepSizeUnderflow { t, .. } | RuntimeError::NonFiniteState { t } => {
            // The numerical singularity lags the exact one by about the tolerance.
            assert!(t > 0.99 && t < 1.0 + 1e-6, "stopped at t = {t}")
        }
        other => panic!("unexpected error {other:?}"),
    }
}

#[test]
fn dopri5_step_budget_and_h_min() {
    let opts = AdaptiveOptions {
        max_steps: 10,
        ..tol(1e-10, 1e-10)
    };
    let mut s = Dopri5::new(Oscillator, 0.0, &[1.0, 0.0], 100.0, opts).unwrap();
    let err = loop {
        if let Err(e) = s.step() {
            break e;
        }
    };
    assert!(
        matches!(err, RuntimeError::TooManySteps { steps: 10, .. }),
        "{err:?}"
    );

    let opts = AdaptiveOptions {
        h_min: 1.0,
        ..tol(1e-10, 1e-10)
    };
    let mut s = Dopri5::new(Oscillator, 0.0, &[1.0, 0.0], 100.0, opts).unwrap();
    assert!(matches!(
        s.step(),
        Err(RuntimeError::StepSizeUnderflow { .. })
    ));
}

#[test]
fn dopri5_rejects_bad_options_and_inputs() {
    for opts in [
        tol(-1.0, 1e-6),
        tol(1e-6, 0.0),
        tol(f64::NAN, 1e-6),
        AdaptiveOptions {
            h_max: 0.0,
            ..Default::default()
        },
        AdaptiveOptions {
            h_init: Some(-1.0),
            ..Default::default()
        },
    ] {
        assert!(matches!(
            Dopri5::new(Decay, 0.0, &[1.0], 1.0, opts),
            Err(RuntimeError::InvalidOptions(_))
        ));
    }
    assert!(matches!(
        Dopri5::new(Decay, 0.0, &[1.0, 2.0], 1.0, AdaptiveOptions::default()),
        Err(RuntimeError::LengthMismatch {
            expected: 1,
            found: 2,
            ..
        })
    ));
    assert!(matches!(
        Dopri5::new(Decay, 1.0, &[1.0], 0.0, AdaptiveOptions::default()),
        Err(RuntimeError::InvalidOptions(_))
    ));
    assert!(matches!(
        Dopri5::new(Decay, 0.0, &[f64::NAN], 1.0, AdaptiveOptions::default()),
        Err(RuntimeError::NonFiniteState { t: 0.0 })
    ));
}

/// Error of RK4 with step h on the oscillator at t = 10.
fn rk4_error(h: f64) -> f64 {
    let mut s = Rk4::new(Oscillator, 0.0, &[1.0, 0.0], 10.0, h).unwrap();
    run_to_end(&mut s);
    assert_eq!(s.t(), 10.0);
    let x = s.state();
    (x[0] - 10f64.cos()).hypot(x[1] + 10f64.sin())
}

#[test]
fn rk4_is_fourth_order() {
    let e = [rk4_error(0.1), rk4_error(0.05), rk4_error(0.025)];
    for w in e.windows(2) {
        let ratio = w[0] / w[1];
        assert!((15.0..17.0).contains(&ratio), "errors {e:?}, ratio {ratio}");
    }
}

#[test]
fn rk4_steps_land_on_the_end_time_and_count_evaluations() {
    // 1.0 / 0.3: three full steps and a shortened one.
    let mut s = Rk4::new(Decay, 0.0, &[1.0], 1.0, 0.3).unwrap();
    let mut times = vec![];
    while !s.is_finished() {
        s.step().unwrap();
        times.push(s.t());
    }
    assert_eq!(times.len(), 4);
    assert_eq!(times[3], 1.0);
    assert!((times[2] - 0.9).abs() < 1e-15);
    assert_eq!(s.stats().rhs_evaluations, 1 + 4 * 4);
    // 0.1 does not divide 1.0 exactly in binary; still exactly 10 steps ending at 1.0.
    let mut s = Rk4::new(Decay, 0.0, &[1.0], 1.0, 0.1).unwrap();
    run_to_end(&mut s);
    assert_eq!(s.stats().accepted_steps, 10);
    assert_eq!(s.t(), 1.0);
}

#[test]
fn rk4_dense_output_is_accurate() {
    let h = 0.01;
    let mut s = Rk4::new(Oscillator, 0.0, &[1.0, 0.0], 1.0, h).unwrap();
    let mut out = [0.0; 2];
    let mut worst: f64 = 0.0;
    while !s.is_finished() {
        s.step().unwrap();
        let t = 0.5 * (s.t_prev() + s.t());
        s.interpolate(t, &mut out).unwrap();
        worst = worst.max((out[0] - t.cos()).abs());
    }
    // Cubic Hermite: local error ~ h⁴/384.
    assert!(worst < 1e-9, "worst {worst:e}");
}

#[test]
fn rk4_non_finite_state_is_an_error() {
    let mut s = Rk4::new(BlowUp, 0.0, &[1.0], 2.0, 0.25).unwrap();
    let err = loop {
        if let Err(e) = s.step() {
            break e;
        }
        assert!(!s.is_finished());
    };
    assert!(
        matches!(err, RuntimeError::NonFiniteState { .. }),
        "{err:?}"
    );
}

/// Van der Pol's equation `y1' = y2`, `y2' = ((1 − y1²) y2 − y1)/ε` with ε = 1e-3.
struct VanDerPol;
impl Ode for VanDerPol {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], f: &mut [f64]) -> Result<(), RuntimeError> {
        f[0] = y[1];
        f[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) / 1e-3;
        Ok(())
    }
}

/// Hairer's DOP853 (Fortran) on van der Pol (ε = 1e-3, y(0) = (2, 0), t ∈ [0, 2]) with
/// rtol = atol = 1e-9 and a first step of 1e-6 (driver `examples/dop853_vdp.f` of
/// github.com/cpmech/hwode, output `russell_ode/data/logs/fortran_dop853_van_der_pol.txt` of
/// github.com/cpmech/russell): 1348 accepted and 121 rejected steps, the dense output at
/// t = 0.1, 0.2, … and the final state below. Our transcription must take the same steps.
#[test]
fn dop853_reproduces_hairer_fortran_on_van_der_pol() {
    let opts = AdaptiveOptions {
        h_init: Some(1e-6),
        ..AdaptiveOptions::dop853().with_tolerances(1e-9, 1e-9)
    };
    let mut s = Dop853::new(VanDerPol, 0.0, &[2.0, 0.0], 2.0, opts).unwrap();
    // (t, accepted steps so far, y) as printed by the Fortran SOLOUT (a selection).
    let fortran_dense: [(f64, usize, [f64; 2]); 5] = [
        (0.1, 75, [1.931611417501184E+00, -7.070951240604973E-01]),
        (0.8, 525, [1.102733648413240E+00, -4.482889108091831E+00]),
        (0.9, 631, [-1.959570969570627E+00, 6.898639929483857E-01]),
        (1.6, 1085, [-1.227570508060995E+00, 2.379082947865465E+00]),
        (1.9, 1298, [1.843292936171062E+00, -7.685214701753735E-01]),
    ];
    let mut out = [0.0; 2];
    let mut next = 0;
    while !s.is_finished() {
        s.step().unwrap();
        while next < fortran_dense.len() && fortran_dense[next].0 <= s.t() {
            let (t, steps, want) = fortran_dense[next];
            assert_eq!(s.stats().accepted_steps, steps, "accepted steps at t = {t}");
            s.interpolate(t, &mut out).unwrap();
            for i in 0..2 {
                assert!(
                    (out[i] - want[i]).abs() < 1e-12 * want[i].abs().max(1.0),
                    "y{i}({t}) = {:.15e}, Fortran {:.15e}",
                    out[i],
                    want[i]
                );
            }
            next += 1;
        }
    }
    assert_eq!(next, fortran_dense.len());
    let stats = s.stats();
    assert_eq!((stats.accepted_steps, stats.rejected_steps), (1348, 121));
    let want = [1.763234540172087E+00, -8.356886819301910E-01];
    for (i, (got, want)) in s.state().iter().zip(want).enumerate() {
        assert!(
            (got - want).abs() < 1e-12,
            "y{i}(2) = {got:.15e}, Fortran {want:.15e}"
        );
    }
    // 11 evaluations per trial step, 1 per accepted step (FSAL), 3 per interpolated step.
    assert_eq!(
        stats.rhs_evaluations,
        1 + 11 * (1348 + 121) + 1348 + 3 * fortran_dense.len()
    );
}

/// DOP853 is 8th order: on the harmonic oscillator, tightening the tolerance by 10⁴ shrinks
/// the global error by about 10⁴ while the step count grows by about 10^(4/8) = 3.2; its
/// dense output is accurate to the tolerance everywhere.
#[test]
fn dop853_converges_and_interpolates() {
    let run = |tol: f64| {
        let opts = AdaptiveOptions::dop853().with_tolerances(tol, tol);
        let mut s = Dop853::new(Oscillator, 0.0, &[1.0, 0.0], 20.0, opts).unwrap();
        let worst_dense =
            worst_dense_error(&mut s, &[0.25, 0.5, 0.75], |t, x| (x[0] - t.cos()).abs());
        let error = (s.state()[0] - 20f64.cos()).abs();
        (error, s.stats().accepted_steps, worst_dense)
    };
    let (e1, n1, d1) = run(1e-7);
    let (e2, n2, d2) = run(1e-11);
    assert!(e1 < 1e-6 && e2 < 1e-10, "errors {e1:e}, {e2:e}");
    let error_ratio = e1 / e2;
    assert!(
        (1e3..1e5).contains(&error_ratio),
        "error ratio {error_ratio}"
    );
    let step_ratio = n2 as f64 / n1 as f64;
    assert!((2.0..5.0).contains(&step_ratio), "step ratio {step_ratio}");
    assert!(d1 < 1e-6 && d2 < 1e-10, "dense errors {d1:e}, {d2:e}");
}
