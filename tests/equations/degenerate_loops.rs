//! Models the numerics cannot solve end in a typed error, never a panic or a hang (#18): a
//! `distance` loop whose points coincide at `q0` (it used to give NaN Newton steps, and
//! nalgebra's SVD of them panicked with "Singular value was NaN" or never returned), a loop
//! length set to zero at run time, forces that are NaN, and a linear model that is not finite.
//! Also the `distance` row itself, `(|d|² − L²)/2L`, against its closed form.

use crate::common;

use mech::session::{Error, Session};
use mech_runtime::constraints::{jacobian, residual, solve_least_squares};
use mech_runtime::nalgebra::{DMatrix, DVector};
use mech_runtime::{mobility, FlexureDamping, Model, RuntimeError};

fn session(name: &str, text: &str) -> Session {
    Session::from_compiled(common::compile_text(name, text), &[], &[]).unwrap()
}

/// The row and residual of a stationary-row assembly error, and its rendered location.
fn stationary(error: Error) -> (String, f64, String) {
    let text = error.to_string();
    match error {
        Error::Assembly {
            error: RuntimeError::StationaryConstraint { row, residual },
            site: Some(_),
        } => (row, residual, text),
        other => panic!("expected a located stationary row, got {other:?}: {other}"),
    }
}

/// Both sliders start at the origin, where both loops' points coincide (the model of the
/// panic: the first Newton step was NaN).
const TWO_DISTANCES: &str = "
body a { mass = 1 g; }
body b { mass = 1 g; }
joint sa = slider(newtonian, a) { axis = x; }
joint sb = slider(newtonian, b) { axis = y; }
loop da = distance(newtonian, a) { length = 1 mm; }
loop db = distance(newtonian, b) { length = 1 mm; }
";

#[test]
fn distance_loops_starting_at_coincident_points_are_a_located_error() {
    let session = session("two_distances", TWO_DISTANCES);
    let (row, residual, text) = stationary(session.assemble(&[]).unwrap_err());
    // Both rows are −L/2 at d = 0; the last of the largest is reported.
    assert_eq!(row, "db.distance");
    assert_eq!(residual, -0.5e-3);
    assert!(
        text.contains("two_distances.mech:7:1") && text.contains("coincide"),
        "{text}"
    );
    // `mech statics` and `mech linearize` assemble first and stop there, with the same error.
    let statics = session.equilibrium(&[], &[], &[]).unwrap_err();
    assert_eq!(stationary(statics).0, "db.distance");
    let linear = session.linearization(&[], &[]).unwrap_err();
    assert_eq!(stationary(linear).0, "db.distance");
}

/// The model of the hang: one `distance` loop at coincident points beside a revolute loop
/// on other bodies.
#[test]
fn a_distance_loop_at_coincident_points_beside_another_loop_is_a_located_error() {
    let text = "
body crank { mass = 1 mg; com = [0, 0.3 mm, 0]; inertia = [1e-15 kg*m^2, 1e-15 kg*m^2, 1e-15 kg*m^2]; }
body slider { mass = 0.5 mg; }
body arm { mass = 1 mg; com = [1 mm, 0, 0]; inertia = [1e-15 kg*m^2, 1e-15 kg*m^2, 1e-15 kg*m^2]; }
body rocker { mass = 1 mg; com = [1 mm, 0, 0]; inertia = [1e-15 kg*m^2, 1e-15 kg*m^2, 1e-15 kg*m^2]; }
joint crank_angle = pin(newtonian, crank) { axis = z; }
joint stroke = slider(newtonian, slider) { axis = x; parent_point = [0, 0.5 mm, 0]; }
joint arm_angle = pin(newtonian, arm) { axis = z; parent_point = [5 mm, 0, 0]; q0 = 90 deg; }
joint rocker_angle = pin(arm, rocker) { axis = z; parent_point = [2 mm, 0, 0]; q0 = -90 deg; }
loop link = distance(crank, slider) { parent_point = [0, 0.5 mm, 0]; length = 0.1 mm; }
loop tip = revolute(rocker, newtonian) { parent_point = [2 mm, 0, 0]; child_point = [7 mm, 2 mm, 0]; axis = z; }
";
    let session = session("beside", text);
    let (row, residual, rendered) = stationary(session.assemble(&[]).unwrap_err());
    assert_eq!((row.as_str(), residual), ("link.distance", -0.05e-3));
    assert!(rendered.contains("beside.mech:10:1"), "{rendered}");
}

/// A slider whose origin is 1 mm from the Newtonian origin, tied there by `length = gap`.
const TIE: &str = "
param gap = 1 mm;
body a { mass = 1 g; }
joint slide = slider(newtonian, a) { axis = x; q0 = 1 mm; }
loop tie = distance(newtonian, a) { length = gap; }
";

#[test]
fn a_loop_length_set_to_zero_is_a_non_finite_error_naming_the_row() {
    let mut session = session("tie", TIE);
    assert!(session.assemble(&[]).is_ok());
    // The front end rejects a written zero length (E0415); `--set` can still give one.
    session.set("gap=0 mm").unwrap();
    match session.assemble(&[]).unwrap_err() {
        Error::Assembly {
            error: RuntimeError::NonFiniteConstraints { rows, jacobian },
            site: Some(site),
        } => {
            assert_eq!((rows, jacobian), (vec!["tie.distance".to_string()], false));
            assert!(site.to_string().contains("tie.mech:5:1"), "{site}");
        }
        other => panic!("{other:?}"),
    }
    // The rank decision refuses the NaN Jacobian rather than decomposing it.
    let q = [1e-3];
    match mobility(&session.model, 0.0, &q).unwrap_err() {
        RuntimeError::NonFiniteConstraints { rows, jacobian } => {
            assert_eq!((rows, jacobian), (vec!["tie.distance".to_string()], true));
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn least_squares_refuses_input_that_is_not_finite() {
    let a = DMatrix::from_row_slice(2, 2, &[2.0, 0.0, 0.0, 4.0]);
    let b = DVector::from_column_slice(&[2.0, 2.0]);
    assert_eq!(
        solve_least_squares(&a, &b),
        Some(DVector::from_column_slice(&[1.0, 0.5]))
    );
    let mut nan_a = a.clone();
    nan_a[(1, 0)] = f64::NAN;
    assert_eq!(solve_least_squares(&nan_a, &b), None);
    let infinite_b = DVector::from_column_slice(&[2.0, f64::INFINITY]);
    assert_eq!(solve_least_squares(&a, &infinite_b), None);
}

/// A force infinite at `q0` (`1/q` at q = 0): `F` is not finite, and the statics say so
/// instead of iterating on it (they used to run their 60 iterations and report "no static
/// equilibrium found"). This test used a spring whose ends meet at `q0`, now error E0417.
#[test]
fn statics_with_forces_that_are_not_finite_is_a_typed_error() {
    let text = "
body bob { mass = 20 g; }
joint x = slider(newtonian, bob) { axis = x; }
force repulsion at bob = [1 mN * 1 mm / x.q, 0, 0];
";
    let session = session("force_infinite_at_the_start", text);
    match session.equilibrium(&[], &[], &[]).unwrap_err() {
        Error::Statics {
            error: RuntimeError::NonFinite { what },
            ..
        } => assert!(what.contains("generalized forces"), "{what}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_linear_model_that_is_not_finite_has_no_modes_state_space_or_response() {
    let session = Session::from_compiled(common::compile_bundled("pendulum"), &[], &[]).unwrap();
    let mut linear = session.linearization(&[], &[]).unwrap();
    assert!(linear.modes().is_some() && linear.state_space().is_some());
    linear.stiffness[(0, 0)] = f64::NAN;
    assert!(linear.modes().is_none());
    assert!(linear.state_space().is_none());
    assert!(linear
        .frequency_response(0, 0, 1.0, FlexureDamping::Viscous)
        .is_none());
}

/// The slider-crank with its rod as a `distance` loop from the crank pin to the slider: the
/// row is `(|d|² − L²)/2L` (d = (x − r cos θ, −r sin θ)) and, where the loop is closed, its
/// gradient is that of `|d|`, `dᵀ∂d/∂q / |d|`, so `λ` is the rod's tension.
#[test]
fn the_distance_row_and_its_gradient_against_the_closed_form() {
    let text = "
param r = 5 mm;
param rod = 15 mm;
body crank { mass = 2 g; com = [r / 2, 0, 0]; inertia = [0 kg*m^2, 1e-9 kg*m^2, 1e-9 kg*m^2]; }
body slider { mass = 3 g; }
joint crank_angle = pin(newtonian, crank) { axis = z; q0 = 60 deg; }
joint slide = slider(newtonian, slider) { axis = x; q0 = 17 mm; }
loop rod_link = distance(crank, slider) { parent_point = [r, 0, 0]; length = rod; }
";
    let session = session("rod", text);
    let (r, rod) = (5e-3, 15e-3);
    let d = |q: &[f64]| [q[1] - r * q[0].cos(), -r * q[0].sin()];
    // Off the loop, at the written q0.
    let q0 = [60f64.to_radians(), 17e-3];
    let [dx, dy] = d(&q0);
    let phi = residual(&session.model, 0.0, &q0)[0];
    let expected = (dx * dx + dy * dy - rod * rod) / (2.0 * rod);
    assert!((phi - expected).abs() <= 1e-15 * rod, "{phi} vs {expected}");
    // On it: ∂|d|/∂θ = x r sin θ / |d|, ∂|d|/∂x = (x − r cos θ) / |d|.
    let state = session.assemble(&["crank_angle".to_string()]).unwrap();
    let q = &state.q;
    let [dx, dy] = d(q);
    assert!(((dx * dx + dy * dy).sqrt() - rod).abs() < 1e-15);
    let j = jacobian(&session.model, 0.0, q);
    let gradient = [q[1] * r * q[0].sin() / rod, dx / rod];
    for (value, expected) in j.iter().zip(gradient) {
        assert!(
            (value - expected).abs() <= 1e-13 * expected.abs(),
            "{value} vs {expected}"
        );
    }
    assert_eq!(session.model.nc(), 1);
}

/// Two distance loops that contradict each other by `miss`: a slider 1 mm from the origin
/// and 1 mm + `miss` from it at once.
fn contradicting(miss: &str) -> String {
    format!(
        "body a {{ mass = 1 g; }}
joint s = slider(newtonian, a) {{ axis = x; q0 = 0.9 mm; }}
loop near = distance(newtonian, a) {{ length = 1 mm; }}
loop far = distance(newtonian, a) {{ length = 1 mm + {miss}; }}
"
    )
}

/// Loop rows that contradict each other by a little (HAMR-VI's published five-bar points miss
/// by 1.4e-10 m) close to their least-squares fit with a warning; by more than a nanometre,
/// they are an error naming a loop. The fit is the midpoint: each row off by half the miss.
#[test]
fn loops_that_contradict_by_a_little_close_with_a_warning() {
    let small = session("contradicting", &contradicting("2e-10 m"));
    let assembled = small.assemble(&[]).unwrap();
    let mut phi = vec![0.0; 2];
    small.model.constraints(0.0, &assembled.q, &mut phi);
    assert!(
        (assembled.q[0] - (1e-3 + 1e-10)).abs() < 1e-15 && (phi[0].abs() - 1e-10).abs() < 1e-14,
        "q {:e}, φ {phi:?}",
        assembled.q[0]
    );
    let report = mech::session::assembly_report(&small.model, &assembled);
    assert!(
        report.contains("warning: the loops close only to max |φ| = 1.0e-10"),
        "{report}"
    );
    let large = session("contradicting", &contradicting("1e-8 m"));
    let error = large.assemble(&[]).unwrap_err().to_string();
    assert!(error.contains("cannot close the loops"), "{error}");
}
