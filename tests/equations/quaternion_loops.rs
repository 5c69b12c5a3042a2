//! Loop closures in models with a `ball` or `free` joint, whose rows' Jacobian is taken
//! along the speeds (`φ̇ = J u`, `J = ∂φ/∂q W(q)`; `J` and `J̇u` against finite differences
//! are in `loops.rs`, with every bundled loop model). Checked here against what the code does
//! not compute:
//! - a floating four-bar (`models/floating_four_bar.mech`) without gravity conserves energy,
//!   linear momentum, and angular momentum about the origin, with its loop closed;
//! - a spatial linkage through a ball joint moves as the same linkage with the ball written
//!   as three pins on massless frames (another coordinate set, no quaternion).

use crate::common;

use mech_runtime::{Method, Model, SimOptions};

fn options(t_end: f64) -> SimOptions {
    SimOptions {
        t_start: 0.0,
        t_end,
        output_interval: t_end / 200.0,
        method: Method::Dop853 {
            rtol: 1e-11,
            atol: 1e-13,
            h_max: f64::INFINITY,
        },
        ..SimOptions::default()
    }
}

/// The model's `q0`, `u0` with the loop closed holding the crank (angle and speed) and the
/// base's speeds: the coupler's and rocker's speeds follow from `J u = 0` (two free columns
/// of full rank, so the state is the same whatever the coordinates).
fn closed_start(model: &dyn Model) -> (Vec<f64>, Vec<f64>) {
    let mut q = vec![0.0; model.nq()];
    let mut u = vec![0.0; model.nu()];
    model.initial_state(&mut q, &mut u);
    let dependent =
        ["coupler_angle", "rocker_angle"].map(|name| model.coordinate_index(name).unwrap());
    let held: Vec<usize> = (0..model.nu()).filter(|i| !dependent.contains(i)).collect();
    mech_runtime::assemble(model, 0.0, &mut q, &held, &Default::default()).unwrap();
    mech_runtime::assemble_speeds(model, 0.0, &q, &mut u, &held).unwrap();
    (q, u)
}

/// `R(e)`, the chassis axes in N as columns, of the unit quaternion `e` (scalar first):
/// `R = (e₀² − ε·ε) I + 2 ε εᵀ + 2 e₀ [ε]×`.
fn rotation(e: &[f64]) -> [[f64; 3]; 3] {
    let (e0, v) = (e[0], [e[1], e[2], e[3]]);
    let vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    let skew = [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]];
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let identity = if i == j { e0 * e0 - vv } else { 0.0 };
            r[i][j] = identity + 2.0 * v[i] * v[j] + 2.0 * e0 * skew[i][j];
        }
    }
    r
}

/// Without gravity nothing acts on the floating four-bar from outside: its energy, its linear
/// momentum `p` and its angular momentum about N's origin `H = r_b × p + R (∂T/∂ω)` stay
/// constant. `p` and `∂T/∂ω` (the angular momentum about the chassis origin), both in the
/// chassis basis, are rows of `M u`: the free joint's speeds are the origin's velocity and the
/// chassis's angular velocity, both in the chassis's own basis. The loop's reactions are internal: a wrong
/// `J` or `J̇u` pushes on the chassis and breaks the balance.
#[test]
fn a_floating_four_bar_conserves_energy_and_momentum() {
    let model = common::tape("floating_four_bar");
    let (q0, u0) = closed_start(&model);
    let run = common::simulate_at_default_inputs(&model, &q0, &u0, &options(2.0));
    let nu = model.nu();
    let base = ["base.x", "base.y", "base.z"].map(|name| model.coordinate_index(name).unwrap());
    let spin = model.unit_quaternions()[0];
    let speed = |name: &str| (0..nu).find(|&i| model.speed_name(i) == name).unwrap();
    let (omega, velocity) = (speed("base.wx"), speed("base.vx"));
    let momenta = |q: &[f64], u: &[f64]| {
        let m = common::mass_matrix(&model, q);
        let generalized: Vec<f64> = (0..nu)
            .map(|r| (0..nu).map(|s| m[r][s] * u[s]).sum())
            .collect();
        let r = rotation(&q[spin..spin + 4]);
        let in_n = |own: [f64; 3]| [0, 1, 2].map(|i| (0..3).map(|j| r[i][j] * own[j]).sum::<f64>());
        let p = in_n([0, 1, 2].map(|k| generalized[velocity + k]));
        let turned = in_n([0, 1, 2].map(|k| generalized[omega + k]));
        let origin = base.map(|i| q[i]);
        let moment = [
            origin[1] * p[2] - origin[2] * p[1],
            origin[2] * p[0] - origin[0] * p[2],
            origin[0] * p[1] - origin[1] * p[0],
        ];
        (p, [0, 1, 2].map(|k| moment[k] + turned[k]))
    };
    let (p0, h0) = momenta(&run.q[0], &run.u[0]);
    let (p_scale, h_scale) = (
        p0.iter().fold(0.0_f64, |m, v| m.max(v.abs())),
        h0.iter().fold(0.0_f64, |m, v| m.max(v.abs())),
    );
    let (mut p_drift, mut h_drift, mut phi_max) = (0.0_f64, 0.0_f64, 0.0_f64);
    for (q, u) in run.q.iter().zip(&run.u) {
        let (p, h) = momenta(q, u);
        for k in 0..3 {
            p_drift = p_drift.max((p[k] - p0[k]).abs() / p_scale);
            h_drift = h_drift.max((h[k] - h0[k]).abs() / h_scale);
        }
        let mut phi = vec![0.0; model.nc()];
        model.constraints(0.0, q, &mut phi);
        phi_max = phi.iter().fold(phi_max, |m, v| m.max(v.abs()));
    }
    let (_, energy_drift) = common::energy_drift(&model, &run);
    println!("floating four-bar over 2 s: energy {energy_drift:.1e}, p {p_drift:.1e}, H {h_drift:.1e}, max |φ| {phi_max:.1e} m");
    assert!(energy_drift < 1e-8, "energy drift {energy_drift:e}");
    assert!(p_drift < 1e-9, "linear momentum drift {p_drift:e}");
    assert!(h_drift < 1e-9, "angular momentum drift {h_drift:e}");
    assert!(phi_max < 1e-11, "loop open by {phi_max:e} m");
    // The four-bar moved: the crank turned by more than a radian.
    let crank = model.coordinate_index("crank_angle").unwrap();
    let swing = run
        .q
        .iter()
        .map(|q| (q[crank] - q0[crank]).abs())
        .fold(0.0, f64::max);
    assert!(swing > 1.0, "crank swing {swing}");
}

/// The loop closes within the floating body's four-bar, so its rows are measured in the
/// chassis (the nearest body both sides hang from): `φ`, `J` and `J̇u` must not change when
/// only the base's pose and speeds do, and `J`'s base columns must be zero. Checked off the
/// constraint (`q` not assembled, so `φ ≠ 0`): rows measured in N would turn with the base.
#[test]
fn loop_rows_hold_nothing_of_the_floating_base() {
    let model = common::tape("floating_four_bar");
    let (nq, nu, nc) = (model.nq(), model.nu(), model.nc());
    let (mut q, mut u) = (vec![0.0; nq], vec![0.0; nu]);
    model.initial_state(&mut q, &mut u);
    let mut moved = (q.clone(), u.clone());
    let spin = model.unit_quaternions()[0];
    let turned = [0.3_f64, -0.5, 0.7, 0.4];
    let norm = turned.iter().map(|e| e * e).sum::<f64>().sqrt();
    for (k, e) in turned.iter().enumerate() {
        moved.0[spin + k] = e / norm;
    }
    for (name, value) in [("base.x", 0.02), ("base.y", -0.01), ("base.z", 0.05)] {
        moved.0[model.coordinate_index(name).unwrap()] = value;
    }
    let base_speeds: Vec<usize> = (0..nu)
        .filter(|&i| model.speed_name(i).starts_with("base."))
        .collect();
    assert_eq!(base_speeds.len(), 6);
    for (k, &i) in base_speeds.iter().enumerate() {
        moved.1[i] = 1.5 - 0.7 * k as f64;
    }
    let rows = |q: &[f64], u: &[f64]| {
        let (mut phi, mut jacobian, mut bias) = (vec![0.0; nc], vec![0.0; nc * nu], vec![0.0; nc]);
        model.constraints(0.0, q, &mut phi);
        model.constraint_jacobian(0.0, q, &mut jacobian);
        model.constraint_bias(0.0, q, u, &mut bias);
        (phi, jacobian, bias)
    };
    let (phi, jacobian, bias) = rows(&q, &u);
    let (phi_moved, jacobian_moved, bias_moved) = rows(&moved.0, &moved.1);
    assert!(
        phi.iter().any(|v| v.abs() > 1e-6),
        "the start is off the loop: {phi:?}"
    );
    assert_eq!(phi, phi_moved);
    assert_eq!(jacobian, jacobian_moved);
    assert_eq!(bias, bias_moved);
    for &i in &base_speeds {
        assert!(jacobian[i * nc..(i + 1) * nc].iter().all(|&v| v == 0.0));
    }
}

/// A spring and a damper on the loop itself (`stiffness` and `damping` of `loop tip`: torques
/// about its axis whose rate and vectors are taken in the loop's frame) on the tumbling
/// floating four-bar without gravity: the energy lost equals `∫ c θ̇² dt`, with `θ̇` written
/// independently as `u_rocker − u_crank − u_coupler` (every axis of this four-bar is the
/// chassis's z), to 1e-4 of the loss. A torque or a rate taken in another basis than the
/// loop's geometry breaks the balance once the base has turned.
#[test]
fn a_loop_spring_and_damper_balance_energy_on_a_tumbling_base() {
    let damping = 2e-6;
    let spring_and_damper =
        format!("    stiffness = 1e-3 N*m/rad;\n    damping = {damping:e} N*m*s/rad;\n");
    let source = common::bundled_source("floating_four_bar").replace(
        "    axis = z;\n}\nflexure tip_hinge",
        &format!("    axis = z;\n{spring_and_damper}}}\nflexure tip_hinge"),
    );
    assert!(
        source.contains(&spring_and_damper),
        "the loop's block changed"
    );
    let model = common::tape_from_text("floating_four_bar", &source);
    let (q0, u0) = closed_start(&model);
    let mut options = options(0.5);
    options.output_interval = 0.5 / 4000.0;
    let run = common::simulate_at_default_inputs(&model, &q0, &u0, &options);
    let (ke, pe) = (
        model.output_index("ke").unwrap(),
        model.output_index("pe").unwrap(),
    );
    let speed = |name: &str| {
        (0..model.nu())
            .find(|&i| model.speed_name(i) == name)
            .unwrap()
    };
    let [crank, coupler, rocker] = ["crank_angle", "coupler_angle", "rocker_angle"].map(speed);
    let power: Vec<f64> = run
        .u
        .iter()
        .map(|u| damping * (u[rocker] - u[crank] - u[coupler]).powi(2))
        .collect();
    let energy = |k: usize| run.outputs[k][ke] + run.outputs[k][pe];
    let (mut dissipated, mut imbalance) = (0.0, 0.0_f64);
    for k in 1..run.times.len() {
        let step = run.times[k] - run.times[k - 1];
        dissipated += 0.5 * (power[k] + power[k - 1]) * step;
        imbalance = imbalance.max((energy(k) + dissipated - energy(0)).abs());
    }
    println!(
        "loop damper over 0.5 s: dissipated {dissipated:.4e} J of {:.4e} J, imbalance {imbalance:.1e} J",
        energy(0)
    );
    assert!(
        dissipated > 1e-3 * energy(0),
        "too little dissipated to test"
    );
    assert!(imbalance < 1e-4 * dissipated, "imbalance {imbalance:e} J");
}

/// The chassis on three sliders and three pins (z, then y, then x: Euler angles, all zero at
/// the start, where the chassis's angular velocity in its basis is the pins' rates in the
/// order x, y, z) in place of the free joint: another set of coordinates and speeds, no
/// quaternion, the loop rows `∂φ/∂q` as before. Both start from the same state and must
/// follow the same motion (the Euler angles stay away from their singularity at pitch ±90°).
#[test]
fn a_loop_through_a_free_joint_moves_as_through_six_scalar_joints() {
    let source = common::bundled_source("floating_four_bar");
    let free_joint = &source
        [source.find("joint base = free").unwrap()..source.find("joint crank_angle").unwrap()];
    let euler = source.replace(
        free_joint,
        "body s1 { mass = 0 kg; }\nbody s2 { mass = 0 kg; }\nbody s3 { mass = 0 kg; }\n\
         body r1 { mass = 0 kg; }\nbody r2 { mass = 0 kg; }\n\
         joint bx = slider(newtonian, s1) { axis = x; u0 = 0.1 m/s; }\n\
         joint by = slider(s1, s2) { axis = y; }\n\
         joint bz = slider(s2, s3) { axis = z; u0 = 0.2 m/s; }\n\
         joint yaw = pin(s3, r1) { axis = z; u0 = 3 rad/s; }\n\
         joint pitch = pin(r1, r2) { axis = y; u0 = -1 rad/s; }\n\
         joint roll = pin(r2, chassis) { axis = x; u0 = 2 rad/s; }\n",
    );
    assert!(
        free_joint.contains("u0 = [2 rad/s, -1 rad/s, 3 rad/s]")
            && free_joint.contains("v0 = [0.1 m/s, 0, 0.2 m/s]")
    );
    let quaternion = common::tape("floating_four_bar");
    let angles = common::tape_from_text("floating_four_bar_euler", &euler);
    let t_end = 1.0;
    let runs = [&quaternion, &angles].map(|model| {
        let (q0, u0) = closed_start(model);
        common::simulate_at_default_inputs(model, &q0, &u0, &options(t_end))
    });
    let compare = |what: &str| {
        let [a, b] = [&quaternion, &angles].map(|model| model.output_index(what).unwrap());
        let mut worst = 0.0_f64;
        let scale = runs[0]
            .outputs
            .iter()
            .fold(1e-3_f64, |m, y| m.max(y[a].abs()));
        for (x, y) in runs[0].outputs.iter().zip(&runs[1].outputs) {
            worst = worst.max((x[a] - y[b]).abs() / scale);
        }
        worst
    };
    let crank = |model: &dyn Model, run: &mech_runtime::Trajectory| {
        let i = model.coordinate_index("crank_angle").unwrap();
        run.q.iter().map(|q| q[i]).collect::<Vec<f64>>()
    };
    let (crank_a, crank_b) = (crank(&quaternion, &runs[0]), crank(&angles, &runs[1]));
    let crank_error = crank_a
        .iter()
        .zip(&crank_b)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let position_error = [
        "chassis_position.x",
        "chassis_position.y",
        "chassis_position.z",
    ]
    .map(compare)
    .into_iter()
    .fold(0.0, f64::max);
    let energy_error = compare("ke");
    println!("free joint vs six scalar joints over {t_end} s: crank {crank_error:.1e} rad, chassis {position_error:.1e}, kinetic energy {energy_error:.1e} (relative)");
    assert!(
        crank_error < 1e-7,
        "crank angle differs by {crank_error:e} rad"
    );
    assert!(
        position_error < 1e-7,
        "chassis position differs by {position_error:e}"
    );
    assert!(
        energy_error < 1e-7,
        "kinetic energy differs by {energy_error:e}"
    );
}
