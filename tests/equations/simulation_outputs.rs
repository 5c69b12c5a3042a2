//! What `mech simulate --accelerations` adds to a run, `mech_runtime::accelerations_along`:
//! the accelerations `u̇` and the multipliers `λ` of `M u̇ = F + Jᵀλ`, against physics the
//! library does not compute: a pendulum written as a point mass on two sliders held at its
//! length by a `distance` loop, whose rod tension is `T = m g cos θ + m v²/l` (the radial
//! balance of the bob), and whose `u̇` is the slope of the run's own speeds.
//!
//! Consumes: a model text written here. Produces: tests only.

use crate::common;

use mech_runtime::{accelerations_along, default_signals, Model};

/// The bob at (x, y) on sliders, the rod a `distance` loop from the pivot: with
/// `φ = (|r|² − l²)/(2l)`, `Jᵀλ = λ r/l` is the rod's force on the bob, `−T r̂`, so `λ = −T`.
#[test]
fn the_multiplier_of_a_rod_is_its_tension() {
    let (m, l, g): (f64, f64, f64) = (0.02, 0.1, 9.81);
    let text = format!(
        "
gravity = [0, -{g} m/s^2, 0];
body carriage {{ mass = 0 kg; }}
body bob {{ mass = {m} kg; }}
joint x = slider(newtonian, carriage) {{ axis = x; q0 = 50 mm; }}
joint y = slider(carriage, bob) {{ axis = y; q0 = -86.60254037844386 mm; }}
loop rod = distance(newtonian, bob) {{ length = {l} m; }}
"
    );
    let model = common::tape_from_text("rod", &text);
    let (mut q0, mut u0) = (vec![0.0; 2], vec![0.0; 2]);
    model.initial_state(&mut q0, &mut u0);
    let options = common::dopri5_options(0.5, 1e-4, 1e-11, 1e-14);
    let run = common::simulate_at_default_inputs(&model, &q0, &u0, &options);
    let signals = default_signals(&model);
    let sampled = accelerations_along(&model, &signals, &run).unwrap();
    assert_eq!(model.nc(), 1);
    let mut worst_tension = 0.0_f64;
    for ((q, u), lambda) in run.q.iter().zip(&run.u).zip(&sampled.multipliers) {
        let cos_theta = -q[1] / q[0].hypot(q[1]);
        let tension = m * g * cos_theta + m * (u[0] * u[0] + u[1] * u[1]) / l;
        worst_tension = worst_tension.max((lambda[0] + tension).abs() / (m * g));
    }
    eprintln!("rod: largest |λ + T| / (m g) over 0.5 s {worst_tension:.2e}");
    assert!(worst_tension < 1e-8, "{worst_tension:e}");
    // u̇ is the slope of the run's own speeds (central differences of the 0.1 ms samples).
    let h = run.times[1] - run.times[0];
    let mut worst_slope = 0.0_f64;
    for (window, udot) in run.u.windows(3).zip(&sampled.udot[1..]) {
        for (i, a) in udot.iter().enumerate() {
            let slope = (window[2][i] - window[0][i]) / (2.0 * h);
            worst_slope = worst_slope.max((a - slope).abs() / g);
        }
    }
    eprintln!("rod: largest |u̇ − Δu/Δt| / g {worst_slope:.2e}");
    assert!(worst_slope < 1e-6, "{worst_slope:e}");
}
