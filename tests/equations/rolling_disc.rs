//! The rolling disc (`models/rolling_disc.mech`): a velocity constraint (`constraint roll =
//! velocity(tilt, disc) in newtonian { components = [x, y]; }`) against SymPy's own rolling
//! disc (`test_rolling_disc` of sympy.physics.mechanics, which builds no slip into its
//! coordinates; fixture `tests/peers/fixture.json`), and the physics of the motion: energy,
//! the constraint rows along a run, steady turning at the classical lean–speed relation, and
//! the rows themselves against their closed form and the bias against finite differences.

use crate::common;

use common::{assert_close, json_numbers, sympy_fixture};
use mech_runtime::constraints::jacobian;
use mech_runtime::{ConstrainedSolver, Model, RuntimeError};

const R: f64 = 0.5;
const G: f64 = 9.81;

/// `u̇` of the constrained equations `M u̇ = F + Jᵀλ`, `J u̇ = −J̇u` at `(q, u)`.
fn udot(model: &dyn Model, q: &[f64], u: &[f64]) -> Vec<f64> {
    let mut solver = ConstrainedSolver::for_model(model);
    let mut out = vec![0.0; model.nu()];
    let inputs = common::default_inputs(model);
    solver
        .accelerations(model, 0.0, q, u, &inputs, &mut out)
        .unwrap();
    out
}

/// The same disc with the no-slip rows written as scalar expressions of the speeds (the
/// contact point moves along the heading at `r` times the spin rate).
fn scalar_form() -> String {
    let text = common::bundled_source("rolling_disc");
    let vector = "constraint roll = velocity(tilt, disc) in newtonian { components = [x, y]; }";
    assert!(text.contains(vector));
    text.replace(
        vector,
        "constraint roll_x = x.u - r * cos(yaw.q) * spin.u;\n\
         constraint roll_y = y.u - r * sin(yaw.q) * spin.u;",
    )
}

/// At SymPy's states, `u̇` (all five: the contact's path from the no-slip rows) and the
/// energies agree to 1e-12, in both back ends and with the rows written either way.
#[test]
fn rolling_disc_matches_sympy() {
    let fixture = sympy_fixture();
    let reference = &fixture["models"]["rolling_disc"];
    let tape = common::tape("rolling_disc");
    let compiled = mech::models::compiled("rolling_disc").unwrap();
    let scalar = common::tape_from_text("rolling_disc", &scalar_form());
    let mut worst: f64 = 0.0;
    for model in [&tape as &dyn Model, compiled.as_ref(), &scalar] {
        assert_eq!(model.velocity_rows(), 2);
        for (k, state) in reference["states"].as_array().unwrap().iter().enumerate() {
            let (q, u) = (json_numbers(&state["q"]), json_numbers(&state["u"]));
            let expected = json_numbers(&state["udot"]);
            let ours = udot(model, &q, &u);
            let floor = expected.iter().fold(0.0_f64, |a, b| a.max(b.abs()));
            for (i, (a, b)) in ours.iter().zip(&expected).enumerate() {
                worst = worst.max((a - b).abs() / floor);
                assert_close(&format!("state {k} u̇[{i}]"), *a, *b, 1e-12, floor);
            }
            for (output, key) in [("ke", "kinetic_energy"), ("pe", "potential_energy")] {
                let value = state[key].as_f64().unwrap();
                let ours = common::output(model, output, &q, &u);
                assert_close(&format!("state {k} {output}"), ours, value, 1e-12, 1.0);
            }
        }
    }
    println!("rolling disc: max |Δu̇| / max |u̇| against SymPy = {worst:.1e}");
}

/// `A(q)` is the closed form `[1, 0, 0, 0, −r cos yaw; 0, 1, 0, 0, −r sin yaw]` (`φ` is 0
/// there), and the bias `Ȧu` is the central difference of `A(q + h u) u` along the motion.
#[test]
fn rolling_disc_constraint_rows() {
    let mut rng = common::Rng::new(15);
    let tape = common::tape("rolling_disc");
    let compiled = mech::models::compiled("rolling_disc").unwrap();
    for model in [&tape as &dyn Model, compiled.as_ref()] {
        assert_eq!((model.nc(), model.holonomic_rows()), (2, 0));
        for _ in 0..5 {
            let q = rng.vector(5, -3.0, 3.0);
            let u = rng.vector(5, -2.0, 2.0);
            let j = jacobian(model, 0.0, &q);
            let (c, s) = (q[2].cos(), q[2].sin());
            let closed = [[1.0, 0.0, 0.0, 0.0, -R * c], [0.0, 1.0, 0.0, 0.0, -R * s]];
            for (row, expected) in closed.iter().enumerate() {
                for (col, e) in expected.iter().enumerate() {
                    assert!((j[(row, col)] - e).abs() < 1e-15, "A[{row},{col}]");
                }
            }
            let mut phi = vec![1.0; 2];
            model.constraints(0.0, &q, &mut phi);
            assert_eq!(phi, [0.0, 0.0]);
            let mut bias = vec![0.0; 2];
            model.constraint_bias(0.0, &q, &u, &mut bias);
            let h = 1e-6;
            let shifted = |sign: f64| {
                let q: Vec<f64> = q.iter().zip(&u).map(|(a, b)| a + sign * h * b).collect();
                jacobian(model, 0.0, &q) * mech_runtime::nalgebra::DVector::from_vec(u.clone())
            };
            let difference = (shifted(1.0) - shifted(-1.0)) / (2.0 * h);
            for r in 0..2 {
                assert_close(&format!("Ȧu[{r}]"), bias[r], difference[r], 1e-8, 1.0);
            }
        }
    }
}

/// Ten seconds of rolling from an upright-ish start (lean 0.1 rad, 4 rad/s of spin):
/// energy is conserved (no damping; the contact does no work), and the no-slip rows stay
/// satisfied through the projection after every step.
#[test]
fn rolling_disc_conserves_energy_and_keeps_rolling() {
    let tape = common::tape("rolling_disc");
    let session = mech::session::Session::open(
        std::path::Path::new(&common::bundled_path("rolling_disc")),
        &[],
        &[],
    )
    .unwrap();
    let state = session.assemble(&[]).unwrap();
    // u_x, u_y made consistent from the spin (declared later: the base's speeds are dependent).
    assert_eq!(state.u, [R * 4.0, 0.0, 0.0, 0.0, 4.0]);
    let options = common::dopri5_options(10.0, 0.01, 1e-10, 1e-12);
    let run = common::simulate_at_default_inputs(&tape, &state.q, &state.u, &options);
    let (scale, drift) = common::energy_drift(&tape, &run);
    let mut slip: f64 = 0.0;
    for (q, u) in run.q.iter().zip(&run.u) {
        let rows = jacobian(&tape, 0.0, q) * mech_runtime::nalgebra::DVector::from_vec(u.clone());
        slip = slip.max(rows.amax());
    }
    println!(
        "rolling disc, 10 s: energy drift {drift:.1e} of the largest kinetic energy \
         ({scale:.3} J), max |A u| = {slip:.1e} m/s, {} steps",
        run.stats.accepted_steps
    );
    assert!(drift < 1e-8, "energy drift {drift:e}");
    // The projection corrects `u` when `max |A u|` exceeds its tolerance (1e-12 m/s).
    assert!(slip <= 1e-12, "slip {slip:e}");
    // The disc went somewhere: it rolled (not a trivial run).
    let last = run.q.last().unwrap();
    assert!(last[0].hypot(last[1]) > 1.0, "{last:?}");
}

/// Steady turning: lean θ, heading rate Ω, the disc's angular velocity along its axle
/// `ω₂ = Ω sin θ + ψ̇` (ψ̇ the spin rate). Euler's equations about the centre, with the
/// contact force from `m a_G` (`a_G = r ω₂ Ω` towards the turn), give the classical
/// condition for a thin uniform disc (I = m r²/4, m r²/4, m r²/2):
/// `g sin θ = (r/4) Ω² sin θ cos θ − (3/2) r ω₂ Ω cos θ`.
/// At such a state every speed but the path's direction is constant: the angles'
/// accelerations are zero, and a run holds the lean.
#[test]
fn rolling_disc_steady_turning() {
    let tape = common::tape("rolling_disc");
    let (theta, omega) = (0.1_f64, 0.5_f64);
    let (s, c) = theta.sin_cos();
    let axle = ((R / 4.0) * omega * omega * s * c - G * s) / (1.5 * R * omega * c);
    let spin = axle - omega * s;
    let q = [0.0, 0.0, 0.0, theta, 0.0];
    let u = [R * spin, 0.0, omega, 0.0, spin];
    let accelerations = udot(&tape, &q, &u);
    // ẍ, ÿ turn the path's direction: ẍ = 0, ÿ = r ψ̇ Ω at yaw 0.
    let expected = [0.0, R * spin * omega, 0.0, 0.0, 0.0];
    for (i, (a, e)) in accelerations.iter().zip(expected).enumerate() {
        assert!((a - e).abs() < 1e-12, "u̇[{i}] = {a:e}, expected {e:e}");
    }
    // The same relation with the point-mass factor 1 in place of 3/2 is not steady.
    let wrong_axle = ((R / 4.0) * omega * omega * s * c - G * s) / (R * omega * c);
    let wrong = [
        R * (wrong_axle - omega * s),
        0.0,
        omega,
        0.0,
        wrong_axle - omega * s,
    ];
    assert!(udot(&tape, &q, &wrong)[3].abs() > 0.1);
    let options = common::dopri5_options(5.0, 0.01, 1e-11, 1e-13);
    let run = common::simulate_at_default_inputs(&tape, &q, &u, &options);
    let lean = run
        .q
        .iter()
        .map(|q| (q[3] - theta).abs())
        .fold(0.0, f64::max);
    let rates = run
        .u
        .iter()
        .map(|u| (u[2] - omega).abs().max((u[4] - spin).abs()))
        .fold(0.0, f64::max);
    println!(
        "steady turning θ = {theta}, Ω = {omega} rad/s, ψ̇ = {spin:.6} rad/s (centre at \
         {:.4} m/s on a circle of radius {:.4} m): over 5 s max |Δθ| = {lean:.1e} rad, \
         max |Δ rates| = {rates:.1e} rad/s",
        (R * axle).abs(),
        (R * axle / omega).abs()
    );
    assert!(lean < 1e-8, "lean drifts by {lean:e}");
    assert!(rates < 1e-8, "rates drift by {rates:e}");
}

/// Analyses that work on the configuration alone refuse a model with velocity constraints.
#[test]
fn rolling_disc_statics_and_linearization_are_refused() {
    let tape = common::tape("rolling_disc");
    let q = [0.0, 0.0, 0.0, 0.1, 0.0];
    let inputs = common::default_inputs(&tape);
    let error = mech_runtime::linearize(&tape, 0.0, &q, &inputs, &[0, 1, 2, 3, 4]).unwrap_err();
    assert!(
        matches!(
            error,
            RuntimeError::VelocityConstraintsUnsupported {
                analysis: "linearization",
                ..
            }
        ),
        "{error}"
    );
}

/// The disc again, with the built-in `rolling` element: its centre on three sliders (no
/// height built in), the element's height row closing the contact with the floor, and its
/// two no-slip rows. At SymPy's states (the centre placed over the contact, the angles'
/// rates kept and the centre's velocity solved from the rows) the angles' accelerations are
/// SymPy's to 1e-12.
#[test]
fn rolling_element_matches_sympy() {
    let text = "param r = 0.5 m;\nparam m = 1.5 kg;\ngravity = [0, 0, -9.81 m/s^2];\n\
        newtonian { point floor = [0, 0, 0]; }\n\
        body carriage { mass = 0 kg; }\nbody slide { mass = 0 kg; }\nbody lift { mass = 0 kg; }\n\
        body heading { mass = 0 kg; }\nbody tilt { mass = 0 kg; }\n\
        body disc { mass = m; inertia = [m * r^2 / 4, m * r^2 / 2, m * r^2 / 4]; }\n\
        joint x = slider(newtonian, carriage) { axis = x; }\n\
        joint y = slider(carriage, slide) { axis = y; }\n\
        joint z = slider(slide, lift) { axis = z; q0 = 0.5 m; }\n\
        joint yaw = pin(lift, heading) { axis = z; }\n\
        joint lean = pin(heading, tilt) { axis = x; }\n\
        joint spin = pin(tilt, disc) { axis = y; }\n\
        rolling wheel between disc and newtonian.floor { radius = r; axle = y; normal = z; }\n\
        output ke = kinetic_energy;\noutput pe = potential_energy;\n";
    let model = common::tape_from_text("rolling_wheel", text);
    assert_eq!((model.nc(), model.velocity_rows()), (3, 2));
    let fixture = sympy_fixture();
    let reference = &fixture["models"]["rolling_disc"];
    for (k, state) in reference["states"].as_array().unwrap().iter().enumerate() {
        let (q5, u5) = (json_numbers(&state["q"]), json_numbers(&state["u"]));
        let (yaw, lean) = (q5[2], q5[3]);
        // The centre is r L.z above the contact, L.z = (sin ψ sin θ, −cos ψ sin θ, cos θ).
        let q = [
            q5[0] + R * yaw.sin() * lean.sin(),
            q5[1] - R * yaw.cos() * lean.sin(),
            R * lean.cos(),
            yaw,
            lean,
            q5[4],
        ];
        let mut phi = [1.0; 3];
        model.constraints(0.0, &q, &mut phi);
        assert!(phi[0].abs() < 1e-15, "height {}", phi[0]);
        let mut u = [0.0, 0.0, 0.0, u5[2], u5[3], u5[4]];
        mech_runtime::assemble_speeds(&model, 0.0, &q, &mut u, &[3, 4, 5]).unwrap();
        let ours = udot(&model, &q, &u);
        let expected = json_numbers(&state["udot"]);
        let floor = expected.iter().fold(0.0_f64, |a, b| a.max(b.abs()));
        for i in 0..3 {
            assert_close(
                &format!("state {k} u̇ of angle {i}"),
                ours[3 + i],
                expected[2 + i],
                1e-12,
                floor,
            );
        }
        let ke = state["kinetic_energy"].as_f64().unwrap();
        assert_close("KE", common::output(&model, "ke", &q, &u), ke, 1e-12, 1.0);
    }
    let mobility = mech_runtime::mobility(&model, 0.0, &[0.0, 0.0, R, 0.0, 0.3, 0.0]).unwrap();
    assert_eq!(
        mobility.to_string(),
        "6 coordinates, 1 constraint rows, rank 1; 2 velocity rows, rank 2: \
         5 degrees of freedom in the configuration, 3 in the motion"
    );
}

/// A disc on a `free` joint (a unit quaternion, `q̇ = W(q) u`) held to the floor by the
/// `rolling` element alone, started leaning 0.1 rad with spin and a turn: assembled (the
/// height closed along the joint's z, the centre's velocity solved from the rows), then 5 s
/// of motion conserve energy and keep the height and no-slip rows.
#[test]
fn rolling_element_on_a_free_joint_conserves_energy() {
    let text = "param r = 0.5 m;\nparam m = 1.5 kg;\ngravity = [0, 0, -9.81 m/s^2];\n\
        newtonian { point floor = [0, 0, 0]; frame tilted = rotate(x, 0.1 rad); }\n\
        body disc { mass = m; inertia = [m * r^2 / 4, m * r^2 / 2, m * r^2 / 4]; }\n\
        joint throw = free(newtonian, disc) {\n\
            parent_frame = newtonian.tilted; parent_point = [0, 0, 0.5 m];\n\
            u0 = [0, 4 rad/s, 0.5 rad/s];\n\
        }\n\
        rolling wheel between disc and newtonian.floor { radius = r; axle = y; normal = z; }\n\
        output ke = kinetic_energy;\noutput pe = potential_energy;\n";
    let model = common::tape_from_text("free_wheel", text);
    let (mut q, mut u) = common::initial_state(&model);
    let options = mech_runtime::AssemblyOptions::default();
    // u = [ω; v], both in the disc's frame: the loops close along v_z alone; ω independent,
    // v from the rolling.
    mech_runtime::assemble(&model, 0.0, &mut q, &[0, 1, 2, 3, 4], &options).unwrap();
    mech_runtime::assemble_speeds(&model, 0.0, &q, &mut u, &[0, 1, 2]).unwrap();
    let run = common::simulate_at_default_inputs(
        &model,
        &q,
        &u,
        &common::dopri5_options(5.0, 0.01, 1e-10, 1e-12),
    );
    let (scale, drift) = common::energy_drift(&model, &run);
    let (mut height, mut slip): (f64, f64) = (0.0, 0.0);
    for (q, u) in run.q.iter().zip(&run.u) {
        let mut phi = vec![0.0; 3];
        model.constraints(0.0, q, &mut phi);
        height = height.max(phi[0].abs());
        let rows = jacobian(&model, 0.0, q) * mech_runtime::nalgebra::DVector::from_vec(u.clone());
        slip = slip.max(rows.amax());
    }
    println!(
        "free disc on `rolling`, 5 s: energy drift {drift:.1e} of {scale:.3} J, \
         max |height| = {height:.1e} m, max |J u| = {slip:.1e}"
    );
    assert!(drift < 1e-8, "energy drift {drift:e}");
    assert!(height <= 1e-12 && slip <= 1e-12, "{height:e} {slip:e}");
}

/// Our nonzero eigenvalues `[re, im]` at spin `spin` are SymPy's, in the same order, each
/// part within `tolerance`.
fn assert_matches_sympy(spin: f64, ours: &[[f64; 2]], expected: &[Vec<f64>], tolerance: f64) {
    assert_eq!(
        ours.len(),
        expected.len(),
        "ψ̇ = {spin}: {ours:?} vs SymPy {expected:?}"
    );
    for (a, b) in ours.iter().zip(expected) {
        for k in 0..2 {
            assert!(
                (a[k] - b[k]).abs() < tolerance,
                "ψ̇ = {spin}: {a:?} vs SymPy {b:?}"
            );
        }
    }
}

/// The eigenvalues `[re, im]` SymPy gives for one case of the fixture's upright rolling.
fn sympy_eigenvalues(case: &serde_json::Value) -> Vec<Vec<f64>> {
    let values = case["eigenvalues"].as_array().unwrap();
    values.iter().map(json_numbers).collect()
}

/// Upright rolling (q = 0, spin ψ̇, rolling at r ψ̇): the eigenvalues of the linearized motion
/// (central differences of `ẋ = [u; u̇(q, u)]`, all 10 states) against those of SymPy's
/// `KanesMethod.linearize` of its rolling disc, at 1.1 and 0.9 times the critical spin
/// `√(g / 3r)`: a pair on the imaginary axis above it, a real pair below (the disc falls),
/// every other eigenvalue zero (the cyclic coordinates; the directions off `A u = 0`, which
/// the multiplier form keeps constant). At the critical spin all are zero (SymPy's own test).
#[test]
fn upright_rolling_eigenvalues_match_sympy() {
    use mech_runtime::nalgebra::DMatrix;
    let tape = common::tape("rolling_disc");
    let rhs = |x: &[f64]| {
        let (q, u) = x.split_at(5);
        let mut out = u.to_vec();
        out.extend(udot(&tape, q, u));
        out
    };
    let eigenvalues = |spin: f64| {
        let x = [0.0, 0.0, 0.0, 0.0, 0.0, R * spin, 0.0, 0.0, 0.0, spin];
        let h = 1e-6;
        let mut jacobian = DMatrix::zeros(10, 10);
        for c in 0..10 {
            let (mut plus, mut minus) = (x, x);
            plus[c] += h;
            minus[c] -= h;
            let (a, b) = (rhs(&plus), rhs(&minus));
            for r in 0..10 {
                jacobian[(r, c)] = (a[r] - b[r]) / (2.0 * h);
            }
        }
        let mut values: Vec<[f64; 2]> = jacobian
            .complex_eigenvalues()
            .iter()
            .map(|z| [z.re, z.im])
            .collect();
        values.sort_by(|a, b| a[1].total_cmp(&b[1]).then(a[0].total_cmp(&b[0])));
        values
    };
    let fixture = sympy_fixture();
    for case in fixture["models"]["rolling_disc"]["upright"]
        .as_array()
        .unwrap()
    {
        let spin = case["spin"].as_f64().unwrap();
        let expected = sympy_eigenvalues(case);
        let all = eigenvalues(spin);
        let nonzero: Vec<[f64; 2]> = all
            .iter()
            .copied()
            .filter(|z| z[0].hypot(z[1]) > 1e-3)
            .collect();
        assert_matches_sympy(spin, &nonzero, &expected, 1e-7);
        let zeros = all.iter().map(|z| z[0].hypot(z[1])).filter(|&m| m <= 1e-3);
        println!(
            "upright rolling at ψ̇ = {spin:.6} rad/s: eigenvalues {nonzero:?} (SymPy \
             {expected:?}), the other 8 within {:.1e} of 0",
            zeros.fold(0.0, f64::max)
        );
    }
    let critical = (G / (3.0 * R)).sqrt();
    let largest = eigenvalues(critical)
        .iter()
        .map(|z| z[0].hypot(z[1]))
        .fold(0.0, f64::max);
    println!("at the critical spin {critical:.6} rad/s: max |λ| = {largest:.1e}");
    assert!(largest < 1e-3, "{largest:e}");
}

/// The same upright rolling through `linearize_steady`, which finds the cyclic coordinates
/// itself (the place, the heading and the spin angle) and keeps the lean and the independent
/// speeds (turning, leaning, spinning): four states, whose eigenvalues are SymPy's pair and
/// two zeros (the turning and spinning rates that the linear motion leaves unchanged), to
/// 1e-10 (measured 1e-14).
#[test]
fn steady_linearization_of_upright_rolling_matches_sympy() {
    use mech_runtime::nalgebra::Complex;
    use mech_runtime::{assemble_speeds, linearize_steady, SteadyState};
    let tape = common::tape("rolling_disc");
    let index = |name: &str| {
        (0..tape.nq())
            .find(|&i| tape.coordinate_name(i) == name)
            .unwrap()
    };
    let speeds: Vec<usize> = ["yaw", "lean", "spin"].iter().map(|n| index(n)).collect();
    let fixture = sympy_fixture();
    for case in fixture["models"]["rolling_disc"]["upright"]
        .as_array()
        .unwrap()
    {
        let spin = case["spin"].as_f64().unwrap();
        let q = vec![0.0; 5];
        let mut u = vec![0.0; 5];
        u[index("spin")] = spin;
        assemble_speeds(&tape, 0.0, &q, &mut u, &speeds).unwrap();
        let inputs = common::default_inputs(&tape);
        let coordinates: Vec<usize> = (0..5).collect();
        let linear =
            linearize_steady(&tape, 0.0, (&q, &u), &inputs, &coordinates, &speeds).unwrap();
        let cyclic: Vec<&str> = linear
            .cyclic
            .iter()
            .map(|&i| tape.coordinate_name(i))
            .collect();
        assert_eq!(cyclic, ["x", "y", "yaw", "spin"]);
        assert_eq!(linear.states[0], SteadyState::Coordinate(index("lean")));
        let expected = sympy_eigenvalues(case);
        let values = linear.eigenvalues();
        let scale = values.iter().fold(0.0_f64, |m, z| m.max(z.norm()));
        let (zeros, nonzero): (Vec<&Complex<f64>>, Vec<&Complex<f64>>) =
            values.iter().partition(|z| z.norm() <= 1e-9 * scale);
        assert_eq!(zeros.len(), 2, "{values:?}");
        let mut ours: Vec<[f64; 2]> = nonzero.iter().map(|z| [z.re, z.im]).collect();
        ours.sort_by(|a, b| a[1].total_cmp(&b[1]).then(a[0].total_cmp(&b[0])));
        assert_matches_sympy(spin, &ours, &expected, 1e-10);
        println!("steady upright rolling at ψ̇ = {spin}: {ours:?} (SymPy {expected:?})");
    }
}
