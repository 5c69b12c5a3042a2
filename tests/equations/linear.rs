//! Statics, linearization and frequency response against closed forms and simulation.

use crate::common;

use mech::tape_model::TapeModel;
use mech_runtime::{
    linearize, solve_statics, Fixture, FlexureDamping, Linearization, Method, Model, SimOptions,
    StaticsOptions,
};
use nalgebra::{Complex, Matrix2, Vector2};

/// Asserts that `linear`'s response of `output` to input 0 at `omega` (rad/s) under `damping`
/// is `expected` to 1e-7 relative.
fn assert_response(
    linear: &Linearization,
    output: usize,
    omega: f64,
    damping: FlexureDamping,
    expected: Complex<f64>,
) {
    let ours = linear
        .frequency_response(0, output, omega, damping)
        .unwrap();
    assert!(
        (ours - expected).norm() < 1e-7 * expected.norm(),
        "ω = {omega}: {ours} vs {expected}"
    );
}

/// `models/two_mass_chain.mech`: the wall–m1 spring/damper (k1, c1) and the m1–m2 one (k2,
/// c2); a force on m2; output: the position of m2.
#[test]
fn two_mass_chain_frequency_response_matches_closed_form() {
    let model = common::tape("two_mass_chain");
    let (m1, m2, k1, k2) = TWO_MASS_CHAIN_MASSES_AND_SPRINGS;
    let linear = linearize(&model, 0.0, &[0.0, 0.0], &[0.0], &[0, 1]).unwrap();
    let output = model.output_index("x2.x").unwrap();
    for omega in [0.5, 5.0, 11.0, 13.9, 20.0, 31.6, 100.0] {
        let x2 = two_mass_chain_response(omega);
        assert_response(&linear, output, omega, FlexureDamping::Viscous, x2);
    }
    // Modes: the undamped natural frequencies of the same chain.
    let modes = linear.modes().unwrap();
    let (a, b, c) = (m1 * m2, -(m1 * k2 + m2 * (k1 + k2)), k1 * k2);
    let roots = [
        (-b - (b * b - 4.0 * a * c).sqrt()) / (2.0 * a),
        (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a),
    ];
    for (mode, omega_squared) in modes.iter().zip(roots) {
        let expected = omega_squared.sqrt();
        assert!(
            (mode.natural_frequency - expected).abs() < 1e-7 * expected,
            "{} vs {expected}",
            mode.natural_frequency
        );
    }
}

/// The four-bar hanging under gravity: the statics solution is an equilibrium (it stays at
/// rest when simulated), and the small-oscillation frequency from linearization matches the
/// one measured from a simulated free oscillation.
#[test]
fn four_bar_statics_and_small_oscillation_frequency() {
    let model = common::tape("four_bar");
    let mut q = vec![0.0; 3];
    let mut u = vec![0.0; 3];
    model.initial_state(&mut q, &mut u);
    // Start with the crank hanging down, near the stable equilibrium (the upright one is
    // an equilibrium too, an unstable one).
    q[0] = -1.5;
    mech_runtime::assemble(&model, 0.0, &mut q, &[0], &Default::default()).unwrap();
    let equilibrium =
        solve_statics(&model, 0.0, &mut q, &[], &[], &StaticsOptions::default()).unwrap();
    assert!(equilibrium.constraint_residual < 1e-12);
    let at_rest = vec![0.0; 3];
    let options = common::dopri5_options(2.0, 0.001, 1e-12, 1e-13);
    let still = mech_runtime::simulate(&model, &q, &at_rest, &[], &options, &mut |_| {}).unwrap();
    let moved = still
        .q
        .iter()
        .map(|s| (s[0] - q[0]).abs())
        .fold(0.0, f64::max);
    assert!(moved < 1e-9, "the equilibrium drifted by {moved} rad");

    let linear = linearize(&model, 0.0, &q, &[], &[0]).unwrap();
    let modes = linear.modes().unwrap();
    assert_eq!(modes.len(), 1);
    assert!(
        modes[0].natural_frequency > 0.0,
        "expected the stable equilibrium: {modes:?}"
    );
    let predicted = modes[0].natural_frequency;

    // Free oscillation from a 1 mrad crank displacement (the frequency shifts by O(amplitude²)).
    let mut start = q.clone();
    start[0] += 1e-3;
    mech_runtime::assemble(&model, 0.0, &mut start, &[0], &Default::default()).unwrap();
    let period_estimate = std::f64::consts::TAU / predicted;
    let long = SimOptions {
        t_end: 6.0 * period_estimate,
        output_interval: period_estimate / 2000.0,
        ..options
    };
    let swing = mech_runtime::simulate(&model, &start, &at_rest, &[], &long, &mut |_| {}).unwrap();
    let offset: Vec<f64> = swing.q.iter().map(|s| s[0] - q[0]).collect();
    let crossings = common::upward_crossings(&swing.times, &offset);
    assert!(crossings.len() >= 3, "too few oscillations");
    let period = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let measured = std::f64::consts::TAU / period;
    assert!(
        (measured - predicted).abs() < 1e-4 * predicted,
        "measured {measured} rad/s vs linearized {predicted} rad/s"
    );
}

/// A pendulum bob held by a fixture at the bottom of its swing carries its weight: the
/// fixture force is (0, m g, 0); held 90° out, it also carries nothing sideways.
#[test]
fn fixture_reaction_carries_the_weight() {
    let model = common::tape("pendulum");
    let (m, g, l) = (0.01, 9.81, 0.025);
    let outputs = [
        model.output_index("tip.x").unwrap(),
        model.output_index("tip.y").unwrap(),
        model.output_index("tip.z").unwrap(),
    ];
    for angle in [0.0_f64, 0.7, std::f64::consts::FRAC_PI_2] {
        let target = [l * angle.sin(), -l * angle.cos(), 0.0];
        let fixture = Fixture {
            name: "hold".into(),
            outputs,
            target,
            components: vec![0, 1],
        };
        let mut q = vec![angle + 0.05];
        let equilibrium = solve_statics(
            &model,
            0.0,
            &mut q,
            &[],
            &[fixture],
            &StaticsOptions::default(),
        )
        .unwrap();
        assert!(
            (q[0] - angle).abs() < 1e-9,
            "held at {} instead of {angle}",
            q[0]
        );
        // Only the torque about the pivot is determined: the fixture force's component along
        // the swing direction must balance gravity's: F·t = m g sin(angle) with t = (cos, sin).
        let force = equilibrium.fixture_forces[0];
        let tangential = force[0] * angle.cos() + force[1] * angle.sin();
        assert!(
            (tangential - m * g * angle.sin()).abs() < 1e-9,
            "angle {angle}: {force:?}"
        );
    }
}

/// A pendulum hanging from a flexure, driven by a torque: with the loss as complex stiffness
/// the response is exactly `1 / (k(1 + iη) + m g L − I_p ω²)`; with the loss factor a power
/// law of frequency, `η (f/f_0)^α` in place of η; with the time-domain damper it is
/// `1 / (k + m g L − I_p ω² + i ω k η/ω_ref)`.
#[test]
fn flexure_losses_as_complex_stiffness_a_power_law_or_viscous_damper() {
    let source = "
        param m = 2 g;
        param arm = 20 mm;
        input torque = 0 N*m;
        gravity = [0, -9.81 m/s^2, 0];
        body bob { mass = m; com = [0, -arm, 0]; inertia = [1e-8 kg*m^2, 0 kg*m^2, 1e-8 kg*m^2]; }
        joint hinge = pin(newtonian, bob) { axis = z; }
        flexure hinge_flexure on hinge {
            width = 2 mm; thickness = 25 um; length = 500 um;
            loss_factor = 0.08; reference_frequency = 10 Hz;
        }
        torque drive on bob = [0, 0, torque];
        output angle = hinge.q;
    ";
    let model = common::tape_from_text("flexure_pendulum", source);
    assert_eq!(
        (model.nflexures(), model.flexure_name(0)),
        (1, "hinge_flexure")
    );
    let (m, arm, g, inertia) = (2e-3, 20e-3, 9.81, 1e-8);
    // Eq. 2 with the built-in Kapton modulus, 2.56 GPa.
    let k = 2.56e9 * 2e-3 * 25e-6_f64.powi(3) / (12.0 * 500e-6);
    let (eta, omega_ref) = (0.08, std::f64::consts::TAU * 10.0);
    let pivot_inertia = inertia + m * arm * arm;
    let linear = linearize(&model, 0.0, &[0.0], &[0.0], &[0]).unwrap();
    let output = model.output_index("angle").unwrap();
    for omega in [1.0, 30.0, 62.0, 70.0, 300.0] {
        let static_stiffness = k + m * g * arm - pivot_inertia * omega * omega;
        let hysteretic = Complex::new(1.0, 0.0) / Complex::new(static_stiffness, k * eta);
        let viscous =
            Complex::new(1.0, 0.0) / Complex::new(static_stiffness, omega * k * eta / omega_ref);
        assert_response(
            &linear,
            output,
            omega,
            FlexureDamping::Hysteretic,
            hysteretic,
        );
        assert_response(&linear, output, omega, FlexureDamping::Viscous, viscous);
        let (exponent, reference_hz) = (0.3, 5.0);
        let eta_at = eta * (omega / (std::f64::consts::TAU * reference_hz)).powf(exponent);
        let power_law = Complex::new(1.0, 0.0) / Complex::new(static_stiffness, k * eta_at);
        let law = FlexureDamping::HystereticPowerLaw {
            exponent,
            reference_hz,
        };
        assert_response(&linear, output, omega, law, power_law);
    }
}

/// A 1 mg tip on a slider along y, moved by an actuator `lift` with the given `properties`
/// and the voltage of the input `drive` (0 V by default); the output `tip` is its position.
fn slider_actuator(name: &str, properties: &str) -> TapeModel {
    let source = format!(
        "
        input drive = 0 V;
        body tip {{ mass = 1 mg; }}
        joint slide = slider(newtonian, tip) {{ axis = y; }}
        actuator lift on slide {{
            {properties}
            voltage = drive;
        }}
        output tip = position(tip) in newtonian;
    "
    );
    common::tape_from_text(name, &source)
}

/// Free deflection (statics with no load) and blocked force (statics with the slider held at
/// zero by a fixture on the `tip` output) of an actuator model driven at `volts`.
fn free_and_blocked(model: &dyn Model, volts: f64) -> (f64, f64) {
    let mut q = vec![0.0];
    solve_statics(
        model,
        0.0,
        &mut q,
        &[volts],
        &[],
        &StaticsOptions::default(),
    )
    .unwrap();
    let outputs = [
        model.output_index("tip.x").unwrap(),
        model.output_index("tip.y").unwrap(),
        model.output_index("tip.z").unwrap(),
    ];
    let hold = Fixture {
        name: "wall".into(),
        outputs,
        target: [0.0; 3],
        components: vec![1],
    };
    let mut held_q = vec![0.0];
    let held = solve_statics(
        model,
        0.0,
        &mut held_q,
        &[volts],
        &[hold],
        &StaticsOptions::default(),
    )
    .unwrap();
    // The fixture holds the tip against the actuator's force.
    (q[0], -held.fixture_forces[0][1])
}

/// Asserts that the actuator model's free deflection and blocked force at `volts`
/// ([`free_and_blocked`]) are `expected` to `tol` relative; returns them.
fn assert_free_and_blocked(
    model: &dyn Model,
    volts: f64,
    (expected_free, expected_blocked): (f64, f64),
    tol: f64,
) -> (f64, f64) {
    let (free, blocked) = free_and_blocked(model, volts);
    assert!(
        (free - expected_free).abs() < tol * expected_free,
        "free deflection {free} vs {expected_free}"
    );
    assert!(
        (blocked - expected_blocked).abs() < tol * expected_blocked,
        "blocked force {blocked} vs {expected_blocked}"
    );
    (free, blocked)
}

/// A piezo actuator along a slider: free, it deflects δ_f·V/V_rated; held by a fixture at
/// zero, it pushes with F_b·V/V_rated (Doshi et al. §III: force source in parallel with
/// k_a = F_b/δ_f).
#[test]
fn actuator_free_deflection_and_blocked_force() {
    let model = slider_actuator(
        "actuator",
        "blocked_force = 320 mN; free_deflection = 300 um; rated_voltage = 225 V;",
    );
    let volts = 150.0;
    // Statics converges to 1e-10 of the initial force imbalance.
    let expected = (300e-6 * volts / 225.0, 0.320 * volts / 225.0);
    assert_free_and_blocked(&model, volts, expected, 1e-10);
}

/// A flexure with `twist_axis` gains a twist coordinate with stiffness 2k/(1 + ν) (Doshi et
/// al. Eq. 8): linearized without gravity, K = diag(k, 2k/(1 + ν)).
#[test]
fn flexure_twist_adds_a_degree_of_freedom_with_eq_8_stiffness() {
    let source = "
        body paddle { mass = 1 g; com = [0, -5 mm, 0]; inertia = [1e-9 kg*m^2, 1e-9 kg*m^2, 1e-9 kg*m^2]; }
        joint hinge = pin(newtonian, paddle) { axis = z; }
        flexure hinge_flexure on hinge {
            width = 1 mm; thickness = 25 um; length = 100 um;
            reference_frequency = 40 Hz; twist_axis = y;
        }
        output tip = position(paddle.com) in newtonian;
    ";
    let model = common::tape_from_text("twisting_flexure", source);
    assert_eq!(model.nq(), 2);
    assert_eq!(
        (model.coordinate_name(0), model.coordinate_name(1)),
        ("hinge", "hinge_flexure_twist")
    );
    let linear = linearize(&model, 0.0, &[0.0, 0.0], &[], &[0, 1]).unwrap();
    let k = 2.56e9 * 1e-3 * 25e-6_f64.powi(3) / (12.0 * 100e-6);
    let twist = 2.0 * k / (1.0 + 0.34);
    let stiffness = &linear.stiffness;
    assert!(
        (stiffness[(0, 0)] - k).abs() < 1e-6 * k,
        "bending {}",
        stiffness[(0, 0)]
    );
    assert!(
        (stiffness[(1, 1)] - twist).abs() < 1e-6 * twist,
        "twist {}",
        stiffness[(1, 1)]
    );
    assert!(stiffness[(0, 1)].abs() < 1e-6 * k && stiffness[(1, 0)].abs() < 1e-6 * k);
    assert_eq!(model.nflexures(), 2);
    // The paddle rides on the twist: M = diag(I_zz + m r², I_yy) about the pivot (its centre
    // of mass lies on the twist axis y, 5 mm from the pivot).
    let (m, r, inertia) = (1e-3, 5e-3, 1e-9);
    let expected = [inertia + m * r * r, inertia];
    for (i, want) in expected.iter().enumerate() {
        let got = linear.mass[(i, i)];
        assert!(
            (got - want).abs() < 1e-12 * want,
            "M[{i},{i}] = {got}, want {want}"
        );
    }
    assert!(linear.mass[(0, 1)].abs() < 1e-15);
}

/// An actuator given by its bimorph geometry (Table I "new geometry" with the HAMR-VI
/// coefficients) behaves like the closed form of `mech::physics` (the CLI's implementation):
/// free deflection and blocked force at 225 V.
#[test]
fn bimorph_actuator_matches_the_closed_form() {
    let model = slider_actuator(
        "bimorph",
        "pzt_thickness = 135 um; core_thickness = 55 um; length = 9.2 mm; extension = 1 mm;
        nominal_width = 3.5 mm; width_ratio = 1.5;
        f31_blocked = 24 Pa*m/V; f31_free = 32 Pa*m/V; pzt_modulus = 40 GPa; core_modulus = 340 GPa;",
    );
    let bimorph = mech::physics::actuator::Bimorph::SEED_NEW_GEOMETRY;
    let volts = 225.0;
    let expected = (bimorph.free_deflection(volts), bimorph.blocked_force(volts));
    let (free, blocked) = assert_free_and_blocked(&model, volts, expected, 1e-9);
    // Doshi et al. Table I "new geometry" model row: 300 µm and 320 mN (within 10%).
    assert!((free / 300e-6 - 1.0).abs() < 0.1 && (blocked / 0.320 - 1.0).abs() < 0.1);
}

/// A mass on a spring and damper driven by `push`: f_n = √(k/m)/2π = 10 Hz,
/// ζ = c/(2√(km)) = 0.05, Q ≈ 1/(2ζ) = 10.
const OSCILLATOR: &str = "
    input push = 0 N;
    body mass { mass = 1 kg; }
    joint x = slider(newtonian, mass) { axis = x; stiffness = 3947.8 N/m; damping = 6.2832 N*s/m; }
    force drive at mass = [push, 0, 0];
    output x = x.q;
";

/// The time-domain alternative: a simulated chirp turned into a swept-sine estimate agrees
/// with the linearization's exact response, and both give the same resonance and Q.
#[test]
fn chirp_estimate_agrees_with_the_linear_response() {
    let model = common::tape_from_text("oscillator", OSCILLATOR);
    let output = model.output_index("x").unwrap();
    let linear = linearize(&model, 0.0, &[0.0], &[0.0], &[0]).unwrap();
    let frequencies = mech::frequency::log_space(4.0, 30.0, 200);
    let exact =
        mech::frequency::linear_response(&linear, 0, output, &frequencies, FlexureDamping::Viscous)
            .unwrap();

    let (f0, f1, duration) = (2.0, 40.0, 40.0);
    let chirp = mech_runtime::Signal::Chirp {
        amplitude: 1.0,
        f0_hz: f0,
        f1_hz: f1,
        duration,
        offset: 0.0,
    };
    let options = SimOptions {
        t_end: duration,
        output_interval: 1.0 / 800.0,
        method: Method::Dopri5 {
            rtol: 1e-8,
            atol: 1e-12,
            h_max: 1.0 / 800.0,
        },
        ..SimOptions::default()
    };
    let run =
        mech_runtime::simulate(&model, &[0.0], &[0.0], &[chirp], &options, &mut |_| {}).unwrap();
    let input: Vec<f64> = run.inputs.iter().map(|u| u[0]).collect();
    let response: Vec<f64> = run.outputs.iter().map(|y| y[output]).collect();
    let estimate = mech::frequency::chirp_estimate(&run.times, &input, &response, &frequencies);
    for (a, b) in exact.iter().zip(&estimate) {
        assert!(
            (a.magnitude_db() - b.magnitude_db()).abs() < 1.0,
            "{} Hz: {} dB vs {} dB",
            a.frequency_hz,
            a.magnitude_db(),
            b.magnitude_db()
        );
    }
    let (peak, measured) = (
        mech::frequency::resonances(&exact)[0],
        mech::frequency::resonances(&estimate)[0],
    );
    assert!(
        (peak.frequency_hz - 10.0 * (1.0 - 2.0 * 0.05_f64.powi(2)).sqrt()).abs() < 0.01,
        "{peak:?}"
    );
    assert!(
        (measured.frequency_hz / peak.frequency_hz - 1.0).abs() < 0.02,
        "{measured:?} vs {peak:?}"
    );
    let (q_exact, q_chirp) = (
        peak.quality_factor.unwrap(),
        measured.quality_factor.unwrap(),
    );
    assert!(
        (q_exact - 10.0).abs() < 0.3 && (q_chirp / q_exact - 1.0).abs() < 0.15,
        "Q {q_exact} vs {q_chirp}"
    );
}

/// A chirp's resonance refined on the record's continuous estimate (`ChirpRecord::resonances`)
/// does not depend on the analysis grid, and with the ring-down after the sweep it is the
/// linear model's: a sweep that ends 1.3 bandwidths above the 10 Hz, Q = 10 mode (2 → 11.3 Hz
/// in 8 s) leaves it ringing at the end, which a record cut there misses. Seen: f_r and Q the
/// same to 1e-8 on 12, 120 and 1200 points; f_r 9.978 against 9.975 Hz, Q 9.997 against
/// 9.950 (0.5 %); with the record cut at the sweep's end, f_r 9.909 Hz and Q 15.5.
#[test]
fn chirp_resonance_is_grid_independent_and_the_linear_one() {
    let model = common::tape_from_text("oscillator", OSCILLATOR);
    let output = model.output_index("x").unwrap();
    let linear = linearize(&model, 0.0, &[0.0], &[0.0], &[0]).unwrap();
    let exact = mech::frequency::refined_resonances(
        &mech::frequency::log_space(4.0, 11.3, 50),
        mech::frequency::linear_magnitude(&linear, 0, output, FlexureDamping::Viscous),
    )
    .unwrap()[0];
    let sweep = mech::frequency::ChirpSweep {
        input: 0,
        output,
        amplitude: 1.0,
        from_hz: 2.0,
        to_hz: 11.3,
        duration: 8.0,
        rtol: 1e-9,
        max_steps: mech_runtime::SimOptions::default().max_steps,
    };
    let signals = [mech_runtime::Signal::Constant(0.0)];
    let record = mech::frequency::simulate_chirp(&model, &[0.0], &[0.0], &signals, &sweep).unwrap();
    let found: Vec<_> = [12, 120, 1200]
        .into_iter()
        .map(|points| {
            let grid = mech::frequency::log_space(4.0, 11.3, points);
            record.resonances(&record.estimate(&grid)).unwrap()[0]
        })
        .collect();
    for resonance in &found {
        let q = resonance.quality_factor.unwrap();
        println!(
            "f_r {} Hz, Q {q} (linear {exact:?})",
            resonance.frequency_hz
        );
        assert!(
            (resonance.frequency_hz / found[0].frequency_hz - 1.0).abs() < 1e-6
                && (q / found[0].quality_factor.unwrap() - 1.0).abs() < 1e-6,
            "{resonance:?} vs {:?}",
            found[0]
        );
        assert!(
            (resonance.frequency_hz / exact.frequency_hz - 1.0).abs() < 2e-3
                && (q / exact.quality_factor.unwrap() - 1.0).abs() < 0.01,
            "{resonance:?} vs the linear {exact:?}"
        );
    }
}

/// An actuator's `rest` offsets its tip: free deflection δ_f·V/V_rated + rest.
#[test]
fn actuator_rest_offsets_the_free_deflection() {
    let model = slider_actuator(
        "preloaded",
        "blocked_force = 270 mN; free_deflection = 247 um; rated_voltage = 225 V; rest = -50 um;",
    );
    let (free, _) = free_and_blocked(&model, 100.0);
    let expected = 247e-6 * 100.0 / 225.0 - 50e-6;
    assert!(
        (free - expected).abs() < 1e-10 * expected.abs(),
        "{free} vs {expected}"
    );
}

/// `models/two_mass_chain.mech`'s m1, m2 (kg), k1, k2 (N/m).
const TWO_MASS_CHAIN_MASSES_AND_SPRINGS: (f64, f64, f64, f64) = (2.0, 0.5, 300.0, 120.0);

/// `models/two_mass_chain.mech`'s response `x2/push` at `omega` (rad/s) in closed form, in
/// absolute coordinates (x1, x2): `(K − ω²M + iωC) X = [0, 1]`.
pub(crate) fn two_mass_chain_response(omega: f64) -> Complex<f64> {
    let (m1, m2, k1, k2) = TWO_MASS_CHAIN_MASSES_AND_SPRINGS;
    let (c1, c2) = (1.5, 0.4);
    let dynamic = Matrix2::new(
        Complex::new(k1 + k2 - omega * omega * m1, omega * (c1 + c2)),
        Complex::new(-k2, -omega * c2),
        Complex::new(-k2, -omega * c2),
        Complex::new(k2 - omega * omega * m2, omega * c2),
    );
    let x = dynamic
        .lu()
        .solve(&Vector2::new(
            Complex::new(0.0, 0.0),
            Complex::new(1.0, 0.0),
        ))
        .unwrap();
    x[1]
}

/// `mech linearize --matrices` writes the two-mass chain's matrices as written by hand from
/// its Lagrangian (m2 at x1 + x21: M = [[m1 + m2, m2], [m2, m2]], K = diag(k1, k2),
/// C = diag(c1, c2), the push on m2 does work through both coordinates: B = [1, 1]ᵀ), and
/// the first-order form A = [[0, I], [−M⁻¹K, −M⁻¹C]], B_s = [0; M⁻¹B], with the output x2.x
/// reading x1 + x21.
#[test]
fn linearize_matrices_are_the_chains_written_by_hand() {
    let dir = common::scratch_dir("linearize_matrices");
    let path = dir.join("chain.json");
    let args = mech::cli::linearize::LinearizeArgs {
        common: mech::cli::ModelArgs {
            model: common::bundled_path("two_mass_chain").into(),
            sets: Vec::new(),
            inputs: Vec::new(),
            independent: Vec::new(),
        },
        out: None,
        matrices: Some(path.clone()),
        motion: Default::default(),
    };
    mech::cli::linearize::run(&args).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let matrix =
        |key: &str| -> Vec<Vec<f64>> { serde_json::from_value(json[key].clone()).unwrap() };
    let (m1, m2, k1, k2) = TWO_MASS_CHAIN_MASSES_AND_SPRINGS;
    let (c1, c2) = (1.5, 0.4);
    let mass = Matrix2::new(m1 + m2, m2, m2, m2);
    let close = |got: &[Vec<f64>], want: &[&[f64]], what: &str| {
        assert_eq!(got.len(), want.len(), "{what} rows");
        for (row, want_row) in got.iter().zip(want) {
            assert_eq!(row.len(), want_row.len(), "{what} columns");
            for (g, w) in row.iter().zip(*want_row) {
                assert!(
                    (g - w).abs() <= 1e-9 * w.abs().max(1.0),
                    "{what}: {got:?} vs {want:?}"
                );
            }
        }
    };
    close(&matrix("M"), &[&[m1 + m2, m2], &[m2, m2]], "M");
    close(&matrix("K"), &[&[k1, 0.0], &[0.0, k2]], "K");
    close(&matrix("C"), &[&[c1, 0.0], &[0.0, c2]], "C");
    close(&matrix("B"), &[&[1.0], &[1.0]], "B");
    let inverse = mass.try_inverse().unwrap();
    let minv_k = -inverse * Matrix2::new(k1, 0.0, 0.0, k2);
    let minv_c = -inverse * Matrix2::new(c1, 0.0, 0.0, c2);
    let minv_b = inverse * Vector2::new(1.0, 1.0);
    close(
        &matrix("A"),
        &[
            &[0.0, 0.0, 1.0, 0.0],
            &[0.0, 0.0, 0.0, 1.0],
            &[
                minv_k[(0, 0)],
                minv_k[(0, 1)],
                minv_c[(0, 0)],
                minv_c[(0, 1)],
            ],
            &[
                minv_k[(1, 0)],
                minv_k[(1, 1)],
                minv_c[(1, 0)],
                minv_c[(1, 1)],
            ],
        ],
        "A",
    );
    close(
        &matrix("B_s"),
        &[&[0.0], &[0.0], &[minv_b[0]], &[minv_b[1]]],
        "B_s",
    );
    let outputs: Vec<String> = serde_json::from_value(json["outputs"].clone()).unwrap();
    let x2 = outputs.iter().position(|name| name == "x2.x").unwrap();
    close(
        &matrix("C_s")[x2..=x2],
        &[&[1.0, 1.0, 0.0, 0.0]],
        "C_s (x2.x)",
    );
    assert_eq!(
        json["states"],
        serde_json::json!(["q_x1", "q_x21", "u_x1", "u_x21"])
    );
    assert_eq!(json["inputs"], serde_json::json!(["push"]));
}
