//! The stiff integrators against closed forms: order of convergence (and the W-method
//! property of `Rosenbrock`), L-stability, following a lightly damped fast mode over steps
//! longer than its period (`ExpRosenbrock`), dense output, and adaptive accuracy.

use mech_runtime::integrate::{AdaptiveOptions, ExpRosenbrock, Ode, Ros34pw2, Rosenbrock, Stepper};
use mech_runtime::nalgebra::Matrix3;
use mech_runtime::RuntimeError;

mod common;
use common::{run_to_end, worst_dense_error};

/// `y' = −2t·y²` (`y = 1/(1 + t²)`) and `x'' = −x` (`x = cos t`): nonlinear, time-dependent.
struct Smooth;

impl Ode for Smooth {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&mut self, t: f64, y: &[f64], f: &mut [f64]) -> Result<(), RuntimeError> {
        f[0] = -2.0 * t * y[0] * y[0];
        f[1] = y[2];
        f[2] = -y[1];
        Ok(())
    }
}

fn smooth_exact(t: f64) -> [f64; 3] {
    [1.0 / (1.0 + t * t), t.cos(), -t.sin()]
}

/// `x'' + 2ζω x' + ω² x = ω² sin t` from rest: a 100 Hz mode with ζ = 0.02 under a slow drive,
/// the shape of a flexure leg driven quasi-statically.
struct Resonator;

const OMEGA: f64 = 2.0 * std::f64::consts::PI * 100.0;
const ZETA: f64 = 0.02;

impl Ode for Resonator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, t: f64, y: &[f64], f: &mut [f64]) -> Result<(), RuntimeError> {
        f[0] = y[1];
        f[1] = OMEGA * OMEGA * (t.sin() - y[0]) - 2.0 * ZETA * OMEGA * y[1];
        Ok(())
    }
}

/// The closed form of [`Resonator`] from `x = x' = 0`, and the amplitude of its transient.
fn resonator_exact(t: f64) -> (f64, f64) {
    let w2 = OMEGA * OMEGA;
    let c = 2.0 * ZETA * OMEGA;
    let det = (w2 - 1.0).powi(2) + c * c;
    let (a, b) = (w2 * (w2 - 1.0) / det, -w2 * c / det);
    let wd = OMEGA * (1.0 - ZETA * ZETA).sqrt();
    let (cc, dd) = (-b, (-a + ZETA * OMEGA * -b) / wd);
    let decay = (-ZETA * OMEGA * t).exp();
    let x = a * t.sin() + b * t.cos() + decay * (cc * (wd * t).cos() + dd * (wd * t).sin());
    (x, cc.hypot(dd))
}

/// Every step of size `h`: a huge tolerance accepts all, `h_max` stops growth.
fn fixed(h: f64) -> AdaptiveOptions {
    AdaptiveOptions {
        rtol: 1e6,
        atol: 1e6,
        h_init: Some(h),
        h_max: h,
        ..AdaptiveOptions::rosenbrock()
    }
}

fn smooth_error(stepper: &mut dyn Stepper) -> f64 {
    run_to_end(stepper);
    let exact = smooth_exact(stepper.t());
    (0..3)
        .map(|i| (stepper.state()[i] - exact[i]).abs())
        .fold(0.0, f64::max)
}

/// `log2(e(h)/e(h/2))` over three halvings, from the errors at `t = 2`.
fn observed_orders(mut error: impl FnMut(f64) -> f64) -> Vec<f64> {
    let errors: Vec<f64> = [0.1, 0.05, 0.025, 0.0125].map(&mut error).to_vec();
    errors.windows(2).map(|e| (e[0] / e[1]).log2()).collect()
}

#[test]
fn rosenbrock_is_second_order_even_with_a_frozen_jacobian() {
    let y0 = smooth_exact(0.0);
    for reuse in [0, usize::MAX] {
        let orders = observed_orders(|h| {
            let mut s = Rosenbrock::new(Smooth, 0.0, &y0, 2.0, fixed(h)).unwrap();
            // usize::MAX: the Jacobian of t = 0 serves the whole run (a W-method keeps its
            // order for any matrix).
            s.reuse_jacobian(reuse);
            smooth_error(&mut s)
        });
        println!("Rosenbrock, Jacobian reused {reuse} steps: observed orders {orders:.3?}");
        for order in orders {
            assert!((order - 2.0).abs() < 0.25, "order {order}");
        }
    }
}

/// [`Smooth`] with its own `W = I − γ J̃` for the W-methods ([`Ode::prepare_implicit`]), `J̃`
/// a fixed matrix that is not its Jacobian.
struct SmoothWithW {
    approximation: Matrix3<f64>,
    inverse: Matrix3<f64>,
}

impl Ode for SmoothWithW {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&mut self, t: f64, y: &[f64], f: &mut [f64]) -> Result<(), RuntimeError> {
        Smooth.rhs(t, y, f)
    }
    fn prepare_implicit(
        &mut self,
        _t: f64,
        _x: &[f64],
        gamma: f64,
    ) -> Option<Result<bool, RuntimeError>> {
        let w = Matrix3::identity() - self.approximation * gamma;
        Some(Ok(match w.try_inverse() {
            Some(inverse) => {
                self.inverse = inverse;
                true
            }
            None => false,
        }))
    }
    fn solve_implicit(&mut self, r: &mut [f64]) {
        let k = self.inverse * mech_runtime::nalgebra::Vector3::new(r[0], r[1], r[2]);
        r.copy_from_slice(k.as_slice());
    }
}

/// ROS34PW2 (the coefficients transcribed from Rang & Angermann) converges at order 3 with
/// the Jacobian by differences, and with a `J̃` that is not the Jacobian at all (the
/// W-method property that [`Method::RosenbrockW`](mech_runtime::Method::RosenbrockW) rests
/// on: the robot's `J̃` is its contacts' damping only).
#[test]
fn ros34pw2_is_third_order_with_any_w() {
    let y0 = smooth_exact(0.0);
    let differences = observed_orders(|h| {
        smooth_error(&mut Ros34pw2::new(Smooth, 0.0, &y0, 2.0, fixed(h)).unwrap())
    });
    let approximation = Matrix3::new(-1.0, 0.0, 0.5, 0.0, 0.0, 1.0, 0.5, -1.0, -0.5);
    let supplied = observed_orders(|h| {
        let ode = SmoothWithW {
            approximation,
            inverse: Matrix3::zeros(),
        };
        smooth_error(&mut Ros34pw2::new(ode, 0.0, &y0, 2.0, fixed(h)).unwrap())
    });
    println!("ROS34PW2: observed orders {differences:.3?} (J by differences), {supplied:.3?} (a wrong J̃)");
    for order in differences.into_iter().chain(supplied) {
        assert!((order - 3.0).abs() < 0.3, "order {order}");
    }
}

#[test]
fn exp_rosenbrock_is_fourth_order() {
    let y0 = smooth_exact(0.0);
    let orders = observed_orders(|h| {
        smooth_error(&mut ExpRosenbrock::new(Smooth, 0.0, &y0, 2.0, fixed(h)).unwrap())
    });
    println!("ExpRosenbrock: observed orders {orders:.3?}");
    for order in orders {
        assert!((order - 4.0).abs() < 0.4, "order {order}");
    }
}

/// `y' = λ(y − 1)` from `y = 0`: one step gives `1 − R(hλ)`, `R` the stability function.
/// L-stability is `R(hλ) → 0` as `hλ → −∞`; an A-stable method that is not L-stable (the
/// trapezoidal rule) keeps `|R| → 1` and the stiff deviation with it.
#[test]
fn rosenbrocks_are_l_stable() {
    struct Relaxation(f64);
    impl Ode for Relaxation {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, y: &[f64], f: &mut [f64]) -> Result<(), RuntimeError> {
            f[0] = self.0 * (y[0] - 1.0);
            Ok(())
        }
    }
    let h = 0.1;
    // 1 − y after one step from 0, at hλ = −1e2, −1e4, −1e6.
    let stability = |stepper: &mut dyn Stepper| {
        run_to_end(stepper);
        1.0 - stepper.state()[0]
    };
    let lambdas = [-1e3, -1e5, -1e7];
    // |R| below 0.05 and 1e-3 at the first two, below `stiffest` at hλ = −1e6.
    let check = |method: &str, r: [f64; 3], stiffest: f64| {
        println!("{method}: R(hλ) at hλ = −1e2, −1e4, −1e6: {r:?}");
        assert!(
            r[0].abs() < 0.05 && r[1].abs() < 1e-3 && r[2].abs() < stiffest,
            "{method}: {r:?}"
        );
    };
    let r = lambdas.map(|lambda| {
        stability(&mut Rosenbrock::new(Relaxation(lambda), 0.0, &[0.0], h, fixed(h)).unwrap())
    });
    check("Rosenbrock", r, 1e-6);
    // ROS34PW2 is stiffly accurate: R(hλ) = O(1/hλ) as hλ → −∞.
    let r = lambdas.map(|lambda| {
        stability(&mut Ros34pw2::new(Relaxation(lambda), 0.0, &[0.0], h, fixed(h)).unwrap())
    });
    check("ROS34PW2", r, 1e-5);
}

/// Steps of 20 ms, twice the 100 Hz period: the exponential method follows the lightly damped
/// transient (at the ends of the steps and, through its dense output, inside them), while the
/// L-stable method damps it within a step: the two behaviours that decide which one fits a
/// flexure mechanism driven through its resonances.
#[test]
fn exp_rosenbrock_follows_a_fast_mode_over_long_steps() {
    let (h, t_end) = (0.02, 0.5);
    let (_, transient) = resonator_exact(0.0);
    let mut exp = ExpRosenbrock::new(Resonator, 0.0, &[0.0, 0.0], t_end, fixed(h)).unwrap();
    let worst = worst_dense_error(&mut exp, &[0.13, 0.5, 0.77, 1.0], |t, x| {
        (x[0] - resonator_exact(t).0).abs()
    });
    println!(
        "ExpRosenbrock at ωh = {:.1}: worst error {worst:e} (transient {transient:e})",
        OMEGA * h
    );
    assert!(worst < 1e-3 * transient, "worst error {worst:e}");

    // A quarter period past ten: the transient at its largest.
    let t = 0.1025;
    let mut damped = Rosenbrock::new(Resonator, 0.0, &[0.0, 0.0], t, fixed(h)).unwrap();
    run_to_end(&mut damped);
    let lost = (damped.state()[0] - resonator_exact(t).0).abs();
    let left = transient * (-ZETA * OMEGA * t).exp();
    println!("Rosenbrock at {t} s: error {lost:e} (transient left {left:e})");
    assert!(lost > 0.5 * left, "error {lost:e}");
}

#[test]
fn rosenbrock_dense_output_is_third_order_accurate() {
    let y0 = smooth_exact(0.0);
    let error = |h: f64| {
        let mut s = Rosenbrock::new(Smooth, 0.0, &y0, 1.0, fixed(h)).unwrap();
        let mut out = [0.0; 3];
        let mut worst: f64 = 0.0;
        // The first step only: the interpolation error of one step, O(h³).
        s.step().unwrap();
        for theta in [0.25, 0.5, 0.75] {
            let t = theta * s.t();
            s.interpolate(t, &mut out).unwrap();
            let exact = smooth_exact(t);
            for i in 0..3 {
                worst = worst.max((out[i] - exact[i]).abs());
            }
        }
        worst
    };
    let ratio = error(0.1) / error(0.05);
    println!("Rosenbrock dense output: error ratio for halved h {ratio:.2}");
    assert!(ratio > 6.0, "ratio {ratio}");
}

/// Adaptive runs on the smooth problem: the global error falls with the tolerance, as
/// `tol^(2/3)` for the order-2 method controlled on its O(h³) local error and `tol^(3/4)` for
/// the order-4 one (controlled on its order-3 estimate), and stays within a modest multiple
/// of it.
#[test]
fn adaptive_runs_meet_their_tolerance() {
    let y0 = smooth_exact(0.0);
    let error = |exp: bool, tol: f64| {
        let opts = AdaptiveOptions::rosenbrock().with_tolerances(tol, tol);
        let mut stepper: Box<dyn Stepper> = if exp {
            Box::new(ExpRosenbrock::new(Smooth, 0.0, &y0, 2.0, opts).unwrap())
        } else {
            Box::new(Rosenbrock::new(Smooth, 0.0, &y0, 2.0, opts).unwrap())
        };
        let error = smooth_error(stepper.as_mut());
        let stats = stepper.stats();
        assert!(stats.jacobian_evaluations >= stats.accepted_steps);
        (error, stats.accepted_steps)
    };
    for exp in [false, true] {
        let (loose, tight) = (error(exp, 1e-6), error(exp, 1e-9));
        println!(
            "exp {exp}: tol 1e-6: error {:e} in {} steps; tol 1e-9: {:e} in {}",
            loose.0, loose.1, tight.0, tight.1
        );
        assert!(tight.0 < 1e3 * 1e-9 && loose.0 < 1e3 * 1e-6);
        assert!(
            loose.0 / tight.0 > 30.0,
            "error ratio {}",
            loose.0 / tight.0
        );
    }

    // The resonator adaptively (its transient is exact up to the Jacobian's accuracy).
    let opts = AdaptiveOptions::rosenbrock().with_tolerances(1e-6, 1e-9);
    let mut exp = ExpRosenbrock::new(Resonator, 0.0, &[0.0, 0.0], 1.0, opts).unwrap();
    run_to_end(&mut exp);
    let error = (exp.state()[0] - resonator_exact(1.0).0).abs();
    println!(
        "ExpRosenbrock on the resonator: error {error:e}, {:?}",
        exp.stats()
    );
    assert!(error < 1e-6, "error {error:e}");
}

#[test]
fn state_changes_and_bad_options_are_handled() {
    let y0 = smooth_exact(0.0);
    let mut s = Rosenbrock::new(Smooth, 0.0, &y0, 1.0, AdaptiveOptions::rosenbrock()).unwrap();
    s.step().unwrap();
    let before = s.stats().rhs_evaluations;
    s.state_mut()[0] *= 1.0;
    s.reset().unwrap();
    assert_eq!(s.stats().rhs_evaluations, before + 1);
    run_to_end(&mut s);
    assert!((s.state()[0] - 0.5).abs() < 1e-6);

    let bad = AdaptiveOptions {
        rtol: -1.0,
        ..AdaptiveOptions::rosenbrock()
    };
    assert!(ExpRosenbrock::new(Smooth, 0.0, &y0, 1.0, bad).is_err());
    assert!(Rosenbrock::new(Smooth, 0.0, &[1.0], 1.0, AdaptiveOptions::rosenbrock()).is_err());
}

/// Prothero–Robinson `y' = λ(y − cos t) − sin t` with `λ = −10⁴`, on its smooth solution
/// `y = cos t`: convergence in the stiff regime (`hλ` from −1000 to −125). The Rosenbrock
/// method keeps its order 2; the exponential one shows order ≈ 3 here (the forcing `−λ cos t`
/// has time derivatives of size λ, which its error constants carry).
#[test]
fn convergence_on_a_stiff_problem() {
    struct ProtheroRobinson;
    impl Ode for ProtheroRobinson {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, t: f64, y: &[f64], f: &mut [f64]) -> Result<(), RuntimeError> {
            f[0] = -1e4 * (y[0] - t.cos()) - t.sin();
            Ok(())
        }
    }
    let error = |exp: bool, h: f64| {
        let mut stepper: Box<dyn Stepper> = if exp {
            Box::new(ExpRosenbrock::new(ProtheroRobinson, 0.0, &[1.0], 1.0, fixed(h)).unwrap())
        } else {
            Box::new(Rosenbrock::new(ProtheroRobinson, 0.0, &[1.0], 1.0, fixed(h)).unwrap())
        };
        run_to_end(stepper.as_mut());
        (stepper.state()[0] - 1f64.cos()).abs()
    };
    let orders = |exp: bool| -> Vec<f64> {
        let errors: Vec<f64> = [0.1, 0.05, 0.025, 0.0125].map(|h| error(exp, h)).to_vec();
        errors.windows(2).map(|e| (e[0] / e[1]).log2()).collect()
    };
    let (rosenbrock, exp) = (orders(false), orders(true));
    println!("Prothero–Robinson, λ = −1e4: observed orders {rosenbrock:.3?} (ode23s), {exp:.3?} (exprb43)");
    for order in rosenbrock {
        assert!((order - 2.0).abs() < 0.2, "ode23s order {order}");
    }
    for order in exp {
        assert!(order > 2.5, "exprb43 order {order}");
    }
    assert!(error(true, 0.1) < 1e-8);
}
