//! `ball` and `free` joints (unit quaternions, scalar first; speeds the angular velocity in
//! the child frame, and for `free` the origin's velocity in the joint frame) against closed
//! forms and an independent formulation written here:
//! - a torque-free rigid body with three distinct principal inertias conserves its kinetic
//!   energy and its angular momentum in N, and flips about its intermediate axis
//!   (Dzhanibekov); its quaternion stays at unit norm;
//! - a heavy symmetric top precesses steadily at the closed-form rate;
//! - a free body under gravity: its centre of mass falls on the closed-form parabola;
//! - the ball double pendulum (`models/ball_double_pendulum.mech`): `M` symmetric positive
//!   definite, `M`, `F` and `q̇ = W(q) u` against Newton–Euler written here from its own
//!   kinematics (finite differences of velocities in N for the accelerations), generated Rust
//!   and tape alike; energy and the vertical angular momentum conserved;
//! - the language reference's `ball` and `free` examples (with a quaternion or Euler angles)
//!   simulate and conserve energy.

use crate::common;
use crate::language_doc::language_reference_examples;

use common::Rng;
use mech::tape_model::TapeModel;
use mech_runtime::{simulate, Method, Model, SimOptions, Trajectory};

type V3 = [f64; 3];
type M3 = [[f64; 3]; 3];

fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn mat_vec(m: &M3, v: V3) -> V3 {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}
pub(crate) fn mat_mul(a: &M3, b: &M3) -> M3 {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, entry) in row.iter_mut().enumerate() {
            *entry = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    out
}
fn transpose(a: &M3) -> M3 {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, entry) in row.iter_mut().enumerate() {
            *entry = a[j][i];
        }
    }
    out
}

/// The rotation of the quaternion `e` (scalar first) as `R = I + 2 e₀ [ε]× + 2 [ε]×²`
/// (written differently from the code generator's `(e₀² − ε·ε) I + 2 ε εᵀ + 2 e₀ [ε]×`),
/// the columns the rotated frame's axes in the fixed one.
fn rotation(e: &[f64]) -> M3 {
    let (e0, v) = (e[0], [e[1], e[2], e[3]]);
    let skew = [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]];
    let skew2 = mat_mul(&skew, &skew);
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let identity = if i == j { 1.0 } else { 0.0 };
            r[i][j] = identity + 2.0 * e0 * skew[i][j] + 2.0 * skew2[i][j];
        }
    }
    r
}

/// `ė` from `ė = ½ e ⊗ (0, ω)` with the Hamilton product written out.
fn quaternion_rate(e: &[f64], w: V3) -> [f64; 4] {
    let p = [0.0, w[0], w[1], w[2]];
    [
        0.5 * (e[0] * p[0] - e[1] * p[1] - e[2] * p[2] - e[3] * p[3]),
        0.5 * (e[0] * p[1] + e[1] * p[0] + e[2] * p[3] - e[3] * p[2]),
        0.5 * (e[0] * p[2] - e[1] * p[3] + e[2] * p[0] + e[3] * p[1]),
        0.5 * (e[0] * p[3] + e[1] * p[2] - e[2] * p[1] + e[3] * p[0]),
    ]
}

fn random_unit_quaternion(rng: &mut Rng) -> [f64; 4] {
    let e = [rng.normal(), rng.normal(), rng.normal(), rng.normal()];
    let norm = e.iter().map(|x| x * x).sum::<f64>().sqrt();
    e.map(|x| x / norm)
}

pub(crate) fn dop853(t_end: f64, output_interval: f64, rtol: f64, atol: f64) -> SimOptions {
    SimOptions {
        t_end,
        output_interval,
        method: Method::Dop853 {
            rtol,
            atol,
            h_max: f64::INFINITY,
        },
        max_steps: 10_000_000,
        ..SimOptions::default()
    }
}

pub(crate) fn run(model: &dyn Model, q0: &[f64], u0: &[f64], options: &SimOptions) -> Trajectory {
    let signals = mech_runtime::default_signals(model);
    simulate(model, q0, u0, &signals, options, &mut |_| {}).unwrap()
}

/// The energy drift ([`common::energy_drift`]) of `model` over 1 s from its written state,
/// DOP853 at rtol 1e-11, atol 1e-13, sampled every 10 ms.
pub(crate) fn energy_drift_over_one_second(model: &dyn Model) -> f64 {
    let (q0, u0) = common::initial_state(model);
    let trajectory = run(model, &q0, &u0, &dop853(1.0, 0.01, 1e-11, 1e-13));
    common::energy_drift(model, &trajectory).1
}

const TORQUE_FREE: &str = "
    body brick { mass = 2 kg; inertia = [1, 2, 3] * 1 kg*m^2; }
    joint float = free(newtonian, brick) { u0 = [0.01 rad/s, 1 rad/s, 0.01 rad/s]; v0 = [0.3 m/s, 0, 0]; }
    output ke = kinetic_energy;
";

/// 100 s of a torque-free body spinning near its intermediate axis: kinetic energy and the
/// angular momentum `H = R (I ω)` in N to 1e-10 relative, the spin about the intermediate
/// axis reverses (and comes back), `|e| = 1` to 1e-12 at every sample; and without the
/// projection after each step (the ODE alone) the norm drifts, by an amount printed.
#[test]
fn torque_free_body_conserves_energy_and_momentum_and_flips() {
    let model = common::tape_from_text("torque_free", TORQUE_FREE);
    assert_eq!((model.nq(), model.nu()), (7, 6));
    // q = [e0…e3; x, y, z], u = [ω in the body; v in the body].
    assert_eq!(model.unit_quaternions(), &[0]);
    let inertia = [1.0, 2.0, 3.0];
    let (q0, u0) = common::initial_state(&model);
    assert_eq!(
        &q0[0..4],
        &[1.0, 0.0, 0.0, 0.0],
        "identity rotation at start"
    );
    let options = dop853(100.0, 0.01, 1e-13, 1e-15);
    let trajectory = run(&model, &q0, &u0, &options);

    let momentum = |q: &[f64], u: &[f64]| {
        let w = [u[0], u[1], u[2]];
        mat_vec(&rotation(&q[0..4]), [0, 1, 2].map(|i| inertia[i] * w[i]))
    };
    let energy = |u: &[f64]| {
        let rotational: f64 = (0..3).map(|i| inertia[i] * u[i] * u[i]).sum();
        0.5 * (2.0 * dot([u[3], u[4], u[5]], [u[3], u[4], u[5]]) + rotational)
    };
    let (h0, t0) = (momentum(&q0, &u0), energy(&u0));
    let h_scale = dot(h0, h0).sqrt();
    let (mut worst_h, mut worst_t, mut worst_norm) = (0.0_f64, 0.0_f64, 0.0_f64);
    let ke = model.output_index("ke").unwrap();
    for k in 0..trajectory.len() {
        let (q, u) = (&trajectory.q[k], &trajectory.u[k]);
        let h = momentum(q, u);
        worst_h = worst_h.max(dot(sub(h, h0), sub(h, h0)).sqrt() / h_scale);
        worst_t = worst_t.max((energy(u) - t0).abs() / t0);
        let norm = q[0..4].iter().map(|x| x * x).sum::<f64>().sqrt();
        worst_norm = worst_norm.max((norm - 1.0).abs());
        common::assert_close(
            "kinetic_energy output",
            trajectory.outputs[k][ke],
            energy(u),
            1e-12,
            0.0,
        );
    }
    eprintln!(
        "torque-free body, 100 s (DOP853, rtol 1e-13): max |ΔH|/|H| = {worst_h:.2e}, \
         max |ΔT|/T = {worst_t:.2e}, max ||e| − 1| = {worst_norm:.2e}, {} steps",
        trajectory.stats.accepted_steps
    );
    assert!(worst_h < 1e-10, "angular momentum drifts by {worst_h:e}");
    assert!(worst_t < 1e-10, "kinetic energy drifts by {worst_t:e}");
    assert!(worst_norm < 1e-12, "quaternion norm off by {worst_norm:e}");

    // The intermediate axis (y) is unstable: ω_y goes from +1 rad/s to about −1 and back.
    let wy: Vec<f64> = trajectory.u.iter().map(|u| u[1]).collect();
    let low = wy.iter().copied().fold(f64::INFINITY, f64::min);
    let sign_changes = wy
        .windows(2)
        .filter(|w| w[0].signum() != w[1].signum())
        .count();
    assert!(low < -0.99, "no flip: min ω_y = {low}");
    assert!(sign_changes >= 2, "ω_y changes sign {sign_changes} times");
    // The origin drifts at v0 in N (the mass centre is at the origin, no force), while the
    // body turns under the velocity speeds: |v| stays, its measure numbers do not.
    let last = trajectory.q.last().unwrap();
    common::assert_close("x(100 s)", last[4], 30.0, 1e-12, 0.0);

    // The ODE alone (no projection): the norm drifts by the integrator's error.
    let drift = unprojected_norm_drift(&model, &q0, &u0, 100.0);
    eprintln!("without the projection: max ||e| − 1| = {drift:.2e} over 100 s");
    assert!(
        drift > worst_norm && drift < 1e-8,
        "unprojected drift {drift:e}"
    );
}

/// `max ||e| − 1|` over `t_end` integrating `ẋ = [W(q) u; M⁻¹F]` with DOP853's stepper,
/// nothing done between steps.
fn unprojected_norm_drift(model: &dyn Model, q0: &[f64], u0: &[f64], t_end: f64) -> f64 {
    use mech_runtime::{AdaptiveOptions, Dop853, ModelOde, Stepper};
    let signals = mech_runtime::default_signals(model);
    let ode = ModelOde::new(model, &signals).unwrap();
    let x0: Vec<f64> = q0.iter().chain(u0).copied().collect();
    let options = AdaptiveOptions {
        rtol: 1e-13,
        atol: 1e-15,
        max_steps: 10_000_000,
        ..AdaptiveOptions::dop853()
    };
    let mut stepper = Dop853::new(ode, 0.0, &x0, t_end, options).unwrap();
    let start = model.unit_quaternions()[0];
    let mut worst = 0.0_f64;
    while !stepper.is_finished() {
        stepper.step().unwrap();
        let e = &stepper.state()[start..start + 4];
        worst = worst.max((e.iter().map(|x| x * x).sum::<f64>().sqrt() - 1.0).abs());
    }
    worst
}

/// The heavy symmetric top of the tests here (`joint_fields` on its ball joint), its tilt θ,
/// spin ω₃ and the slow steady-precession rate `φ̇` of `m g l = φ̇ (C ω₃ − A φ̇ cos θ)`.
pub(crate) fn heavy_top(name: &str, joint_fields: &str) -> (TapeModel, f64, f64, f64) {
    let (m, l, g, a_com, c) = (0.5, 0.04, 9.81, 2e-4, 3e-4);
    let text = format!(
        "gravity = [0, 0, -{g} m/s^2];
         body top {{ mass = {m} kg; com = [0, 0, {l} m]; inertia = [{a_com}, {a_com}, {c}] * 1 kg*m^2; }}
         joint tip = ball(newtonian, top) {{ {joint_fields} }}
         output ke = kinetic_energy; output pe = potential_energy;"
    );
    let model = common::tape_from_text(name, &text);
    let a = a_com + m * l * l;
    let (theta, spin): (f64, f64) = (0.5, 200.0);
    let discriminant = (c * spin).powi(2) - 4.0 * a * theta.cos() * m * g * l;
    let rate = (c * spin - discriminant.sqrt()) / (2.0 * a * theta.cos());
    (model, theta, spin, rate)
}

/// A heavy symmetric top on a ball joint at its tip, tilted by θ from the vertical and
/// spinning at ω₃ about its axis, started with the angular velocity of steady precession:
/// the precession rate `φ̇` solves `m g l = φ̇ (C ω₃ − A φ̇ cos θ)` (Goldstein, Poole & Safko,
/// *Classical Mechanics*, 3rd ed., §5.7, Eq. 5.76; A the transverse moment about the pivot,
/// C the axial one), the slow root. Over 2 s the nutation angle stays at θ and the axis turns
/// about the vertical at that rate.
#[test]
fn heavy_symmetric_top_precesses_at_the_closed_form_rate() {
    let (model, theta, spin, rate) = heavy_top("top", "");
    // Tilted by θ about x; ω = φ̇ ẑ_N + ψ̇ ẑ_body, in the body: (0, φ̇ sin θ, ω₃).
    let q0 = [(theta / 2.0).cos(), (theta / 2.0).sin(), 0.0, 0.0];
    let u0 = [0.0, rate * theta.sin(), spin];
    let t_end = 2.0;
    let trajectory = run(&model, &q0, &u0, &dop853(t_end, 1e-3, 1e-12, 1e-14));
    let mut azimuth_unwrapped = 0.0;
    let mut previous = None::<f64>;
    let mut worst_tilt = 0.0_f64;
    for q in &trajectory.q {
        let r = rotation(q);
        let axis = [r[0][2], r[1][2], r[2][2]];
        worst_tilt = worst_tilt.max((axis[2].acos() - theta).abs());
        let azimuth = axis[1].atan2(axis[0]);
        if let Some(last) = previous {
            let mut step: f64 = azimuth - last;
            step -= (step / std::f64::consts::TAU).round() * std::f64::consts::TAU;
            azimuth_unwrapped += step;
        }
        previous = Some(azimuth);
    }
    let measured = azimuth_unwrapped / t_end;
    eprintln!(
        "heavy top: φ̇ = {measured:.12} rad/s simulated, {rate:.12} rad/s closed form \
         (relative {:.1e}); max |θ − θ₀| = {worst_tilt:.1e} rad",
        (measured - rate).abs() / rate
    );
    assert!(worst_tilt < 1e-9, "the top nutates by {worst_tilt:e} rad");
    common::assert_close("precession rate", measured, rate, 1e-9, 0.0);
    let (_, drift) = common::energy_drift(&model, &trajectory);
    assert!(drift < 1e-10, "energy drift {drift:e}");
}

/// A free body whose mass centre is off its origin, thrown spinning under gravity: the mass
/// centre follows `r_G(t) = r_G0 + v_G0 t + ½ g t²` with `v_G0 = v0 + ω × r_G0`, and the
/// angular velocity (torque-free about G, spun about a principal axis through G) stays.
#[test]
fn free_body_under_gravity_falls_on_a_parabola() {
    let text = "
        gravity = [0, 0, -9.81 m/s^2];
        body stone { mass = 0.2 kg; com = [0.1 m, 0, 0]; inertia = [1e-3, 2e-3, 3e-3] * 1 kg*m^2; }
        joint throw = free(newtonian, stone) { u0 = [0, 0, 2 rad/s]; v0 = [1 m/s, 0, 3 m/s]; }
        output centre = position(stone.com);
        output ke = kinetic_energy; output pe = potential_energy;
    ";
    let model = common::tape_from_text("throw", text);
    let (q0, u0) = common::initial_state(&model);
    assert_eq!(model.speed_name(0), "throw.wx");
    assert_eq!(model.speed_name(3), "throw.vx");
    assert_eq!(model.coordinate_name(0), "throw.e0");
    assert_eq!(model.coordinate_name(4), "throw.x");
    let trajectory = run(&model, &q0, &u0, &dop853(2.0, 0.01, 1e-12, 1e-14));
    let r0 = [0.1, 0.0, 0.0];
    let v0 = add([1.0, 0.0, 3.0], cross([0.0, 0.0, 2.0], r0));
    let centre = model.output_index("centre.x").unwrap();
    let mut worst = 0.0_f64;
    for (k, &t) in trajectory.times.iter().enumerate() {
        let expected = add(add(r0, scale(v0, t)), [0.0, 0.0, -0.5 * 9.81 * t * t]);
        let y = &trajectory.outputs[k][centre..centre + 3];
        worst = worst.max(
            dot(
                sub([y[0], y[1], y[2]], expected),
                sub([y[0], y[1], y[2]], expected),
            )
            .sqrt(),
        );
        for (i, &w) in [0.0, 0.0, 2.0].iter().enumerate() {
            let found = trajectory.u[k][i];
            assert!((found - w).abs() < 1e-10, "ω[{i}] at t = {t}: {found}");
        }
    }
    eprintln!("free body: max |r_G − parabola| = {worst:.1e} m over 2 s");
    assert!(
        worst < 1e-9,
        "the mass centre leaves the parabola by {worst:e} m"
    );
}

/// The ball double pendulum as written in `models/ball_double_pendulum.mech`.
struct DoublePendulum {
    masses: [f64; 2],
    /// Mass centres in the body frames.
    centres: [V3; 2],
    inertias: [V3; 2],
    /// The elbow in the upper link's frame.
    elbow: V3,
    gravity: V3,
}

const PENDULUM: DoublePendulum = DoublePendulum {
    masses: [1.0, 0.5],
    centres: [[0.0, 0.0, -0.15], [0.02, 0.0, -0.1]],
    inertias: [[0.02, 0.015, 0.01], [0.004, 0.003, 0.002]],
    elbow: [0.0, 0.0, -0.3],
    gravity: [0.0, 0.0, -9.81],
};

/// Velocities in N of both links at `(q, u)`: `(R_b, ω_b, r_G, v_G)` per link.
type LinkState = (M3, V3, V3, V3);

impl DoublePendulum {
    /// Kinematics in N written directly: `R₁ = R(e₁)`, `R₂ = R₁ R(e₂)`, `ω₁ = R₁ w₁`,
    /// `ω₂ = ω₁ + R₂ w₂`, `r_G1 = R₁ c₁`, `r_E = R₁ p`, `r_G2 = r_E + R₂ c₂`,
    /// `v_G1 = ω₁ × R₁ c₁`, `v_G2 = ω₁ × r_E + ω₂ × R₂ c₂`.
    fn links(&self, q: &[f64], u: &[f64]) -> [LinkState; 2] {
        let r1 = rotation(&q[0..4]);
        let r2 = mat_mul(&r1, &rotation(&q[4..8]));
        let w1 = mat_vec(&r1, [u[0], u[1], u[2]]);
        let w2 = add(w1, mat_vec(&r2, [u[3], u[4], u[5]]));
        let g1 = mat_vec(&r1, self.centres[0]);
        let elbow = mat_vec(&r1, self.elbow);
        let arm2 = mat_vec(&r2, self.centres[1]);
        let v1 = cross(w1, g1);
        let v2 = add(cross(w1, elbow), cross(w2, arm2));
        [(r1, w1, g1, v1), (r2, w2, add(elbow, arm2), v2)]
    }

    /// `I_N = R I Rᵀ` of link `b`.
    fn inertia_in_n(&self, b: usize, r: &M3) -> M3 {
        let i = self.inertias[b];
        let body = [[i[0], 0.0, 0.0], [0.0, i[1], 0.0], [0.0, 0.0, i[2]]];
        mat_mul(&mat_mul(r, &body), &transpose(r))
    }

    /// `(∂v_G/∂u_r, ∂ω/∂u_r)` of each link: the velocities at `u = e_r` (they are linear in u).
    fn partials(&self, q: &[f64]) -> Vec<[(V3, V3); 2]> {
        (0..6)
            .map(|r| {
                let mut unit = [0.0; 6];
                unit[r] = 1.0;
                self.links(q, &unit).map(|(_, w, _, v)| (v, w))
            })
            .collect()
    }

    /// `M_rs = Σ m v_r·v_s + ω_r·I_N ω_s`.
    fn mass_matrix(&self, q: &[f64]) -> Vec<Vec<f64>> {
        let partials = self.partials(q);
        let links = self.links(q, &[0.0; 6]);
        (0..6)
            .map(|r| {
                (0..6)
                    .map(|s| {
                        (0..2)
                            .map(|b| {
                                let inertia = self.inertia_in_n(b, &links[b].0);
                                let (vr, wr) = partials[r][b];
                                let (vs, ws) = partials[s][b];
                                self.masses[b] * dot(vr, vs) + dot(wr, mat_vec(&inertia, ws))
                            })
                            .sum()
                    })
                    .collect()
            })
            .collect()
    }

    /// `q̇` from the hand-written `ė = ½ e ⊗ (0, w)` of each joint.
    fn rates(q: &[f64], u: &[f64]) -> Vec<f64> {
        let mut qdot = quaternion_rate(&q[0..4], [u[0], u[1], u[2]]).to_vec();
        qdot.extend(quaternion_rate(&q[4..8], [u[3], u[4], u[5]]));
        qdot
    }

    /// Newton–Euler in Kane's form with accelerations from central differences along
    /// `q̇ = W(q) u` at fixed u (the u̇-free parts): `F_r = Σ m (g − a_G)·v_r −
    /// (I_N α + ω × I_N ω)·ω_r`.
    fn forcing(&self, q: &[f64], u: &[f64]) -> Vec<f64> {
        let h = 1e-6;
        let qdot = Self::rates(q, u);
        let shifted = |sign: f64| -> Vec<f64> {
            q.iter().zip(&qdot).map(|(x, d)| x + sign * h * d).collect()
        };
        let (ahead, behind) = (self.links(&shifted(1.0), u), self.links(&shifted(-1.0), u));
        let now = self.links(q, u);
        let partials = self.partials(q);
        (0..6)
            .map(|r| {
                (0..2)
                    .map(|b| {
                        let accel = scale(sub(ahead[b].3, behind[b].3), 0.5 / h);
                        let alpha = scale(sub(ahead[b].1, behind[b].1), 0.5 / h);
                        let (rotation, omega) = (now[b].0, now[b].1);
                        let inertia = self.inertia_in_n(b, &rotation);
                        let force = scale(sub(self.gravity, accel), self.masses[b]);
                        let torque = add(
                            mat_vec(&inertia, alpha),
                            cross(omega, mat_vec(&inertia, omega)),
                        );
                        let (vr, wr) = partials[r][b];
                        dot(force, vr) - dot(torque, wr)
                    })
                    .sum()
            })
            .collect()
    }
}

fn random_pendulum_state(rng: &mut Rng) -> (Vec<f64>, Vec<f64>) {
    let mut q = random_unit_quaternion(rng).to_vec();
    q.extend(random_unit_quaternion(rng));
    (q, rng.vector(6, -3.0, 3.0))
}

/// Both back ends of `models/ball_double_pendulum.mech` (the generated Rust of build.rs and
/// the tape) against [`DoublePendulum`]: `M` to 1e-12, `q̇ = W(q)u` to 1e-14, `F` to 1e-7
/// (the finite differences' error) relative to its largest entry, at random states; `M`
/// symmetric and positive definite there.
#[test]
fn ball_double_pendulum_matches_newton_euler() {
    let tape = common::tape("ball_double_pendulum");
    let generated = mech::models::compiled("ball_double_pendulum").unwrap();
    let mut rng = Rng::new(1515);
    for model in [&tape as &dyn Model, generated.as_ref()] {
        assert_eq!((model.nq(), model.nu()), (8, 6));
        assert_eq!(model.unit_quaternions(), &[0, 4]);
        for _ in 0..20 {
            let (q, u) = random_pendulum_state(&mut rng);
            let m = common::mass_matrix(model, &q);
            let expected = PENDULUM.mass_matrix(&q);
            let scale = m.iter().flatten().fold(0.0_f64, |s, x| s.max(x.abs()));
            for r in 0..6 {
                for s in 0..6 {
                    assert!(
                        (m[r][s] - expected[r][s]).abs() <= 1e-12 * scale,
                        "M[{r}][{s}]: {} vs {}",
                        m[r][s],
                        expected[r][s]
                    );
                    assert_eq!(m[r][s], m[s][r], "M not symmetric");
                }
            }
            let matrix = mech_runtime::nalgebra::DMatrix::from_fn(6, 6, |r, s| m[r][s]);
            let eigenvalues = matrix.symmetric_eigenvalues();
            assert!(
                eigenvalues.min() > 1e-6 * eigenvalues.max(),
                "M not positive definite: {eigenvalues}"
            );

            let f = common::forcing(model, &q, &u);
            let expected = PENDULUM.forcing(&q, &u);
            let scale = expected.iter().fold(0.0_f64, |s, x| s.max(x.abs()));
            for r in 0..6 {
                assert!(
                    (f[r] - expected[r]).abs() <= 1e-7 * scale,
                    "F[{r}]: {} vs {}",
                    f[r],
                    expected[r]
                );
            }

            let mut qdot = vec![0.0; 8];
            model.kinematic_rates(0.0, &q, &u, &mut qdot);
            for (i, (a, b)) in qdot.iter().zip(DoublePendulum::rates(&q, &u)).enumerate() {
                assert!((a - b).abs() <= 1e-14 * 4.0, "q̇[{i}]: {a} vs {b}");
            }
        }
    }
}

/// 20 s of the ball double pendulum from its written state: energy to 1e-10 of the largest
/// kinetic energy, and the angular momentum about the vertical through the fixed pivot
/// (gravity has no moment about it) to 1e-10 of its scale.
#[test]
fn ball_double_pendulum_conserves_energy_and_vertical_momentum() {
    let model = common::tape("ball_double_pendulum");
    let (q0, u0) = common::initial_state(&model);
    let trajectory = run(&model, &q0, &u0, &dop853(20.0, 0.01, 1e-12, 1e-14));
    let (_, energy_drift) = common::energy_drift(&model, &trajectory);
    let vertical_momentum = |q: &[f64], u: &[f64]| -> (f64, f64) {
        let links = PENDULUM.links(q, u);
        let mut total = [0.0; 3];
        let mut size = 0.0_f64;
        for (b, (rotation, omega, centre, velocity)) in links.into_iter().enumerate() {
            let spin = mat_vec(&PENDULUM.inertia_in_n(b, &rotation), omega);
            let orbit = scale(cross(centre, velocity), PENDULUM.masses[b]);
            size = size
                .max(dot(spin, spin).sqrt())
                .max(dot(orbit, orbit).sqrt());
            total = add(total, add(spin, orbit));
        }
        (total[2], size)
    };
    let (h0, _) = vertical_momentum(&q0, &u0);
    let mut scale_h = 0.0_f64;
    let mut worst = 0.0_f64;
    for (q, u) in trajectory.q.iter().zip(&trajectory.u) {
        let (h, size) = vertical_momentum(q, u);
        scale_h = scale_h.max(size);
        worst = worst.max((h - h0).abs());
    }
    eprintln!(
        "ball double pendulum, 20 s: energy drift {energy_drift:.1e}, H_z drift {:.1e} (relative)",
        worst / scale_h
    );
    assert!(energy_drift < 1e-10, "energy drift {energy_drift:e}");
    assert!(
        worst < 1e-10 * scale_h,
        "H_z drifts by {worst:e} (scale {scale_h:e})"
    );
}

/// The `ball` and `free` examples of `docs/mech-language.md` load, simulate 1 s from their
/// written state and keep their energy (to 1e-9 of the largest kinetic energy).
#[test]
fn language_reference_quaternion_examples_simulate() {
    let mut checked = 0;
    for (name, text) in language_reference_examples() {
        if !(text.contains("= ball(") || text.contains("= free(")) {
            continue;
        }
        checked += 1;
        let model = common::tape_from_text(&name, &text);
        let euler = text.contains("rotation = euler(");
        assert!(euler || !model.unit_quaternions().is_empty(), "{name}");
        let drift = energy_drift_over_one_second(&model);
        assert!(drift < 1e-9, "{name}: energy drift {drift:e}");
    }
    assert!(
        checked >= 2,
        "only {checked} examples with ball or free joints"
    );
}

/// `q̇ = W(q) u` of the tape as native code (Cranelift) and through the interpreter: the same
/// bits, as for `M`, `F` and the outputs (`jit.rs`).
#[test]
fn kinematic_rates_native_code_matches_the_interpreter() {
    use mech::tape_model::{Backend, TapeModel};
    let compiled = common::compile_bundled("ball_double_pendulum");
    let native = TapeModel::with_backend(&compiled, Backend::Native);
    let interpreted = TapeModel::with_backend(&compiled, Backend::Interpreter);
    let programs = native.compile_native();
    assert!(programs >= 4, "{programs} programs native");
    let mut rng = Rng::new(16);
    for _ in 0..10 {
        let (q, u) = random_pendulum_state(&mut rng);
        let (mut a, mut b) = (vec![0.0; 8], vec![0.0; 8]);
        native.kinematic_rates(0.0, &q, &u, &mut a);
        interpreted.kinematic_rates(0.0, &q, &u, &mut b);
        let bits = |values: &[f64]| values.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a), bits(&b));
    }
}

/// A stone thrown off a spinning turntable on a `free` joint (its speeds the velocity and
/// angular velocity in the stone's own frame, the joint frame tilted on the moving table)
/// against the same stone on three sliders and a `ball` (speeds the slides' rates in the joint
/// frame: the prismatic recursion, checked against SymPy, and no transport term of the free
/// motion's): over 1 s the mass centre and the table's angle agree to 1e-9, so the free
/// motion's Coriolis and turning terms `(Cᵀ ω_p + ω_k) × v` are right under a moving parent.
#[test]
fn free_joint_on_a_moving_parent_matches_sliders_and_a_ball() {
    let common = "gravity = [0, 0, -9.81 m/s^2];
        body table { mass = 1 kg; com = [0.1 m, 0, 0]; inertia = [0.01, 0.02, 0.03] * 1 kg*m^2;
                     point seat = [0.2 m, 0, 0.1 m]; frame tilted = rotate(x, 0.3 rad); }
        body stone { mass = 0.3 kg; com = [20 mm, 10 mm, 0];
                     inertia = [1e-3, 2e-3, 3e-3] * 1 kg*m^2; }
        joint spin = pin(newtonian, table) { axis = z; u0 = 2 rad/s; stiffness = 0.5 N*m/rad; }
        output at = position(stone.com);";
    let free = format!(
        "{common}
        joint throw = free(table, stone) {{ parent_point = table.seat; parent_frame = table.tilted;
            u0 = [0.4 rad/s, -1 rad/s, 3 rad/s]; v0 = [0.5 m/s, 0.2 m/s, 1 m/s]; }}"
    );
    let sliders = format!(
        "{common}
        body c1 {{ mass = 0 kg; }} body c2 {{ mass = 0 kg; }} body c3 {{ mass = 0 kg; }}
        joint sx = slider(table, c1) {{ axis = x; parent_point = table.seat;
            parent_frame = table.tilted; u0 = 0.5 m/s; }}
        joint sy = slider(c1, c2) {{ axis = y; u0 = 0.2 m/s; }}
        joint sz = slider(c2, c3) {{ axis = z; u0 = 1 m/s; }}
        joint throw = ball(c3, stone) {{ u0 = [0.4 rad/s, -1 rad/s, 3 rad/s]; }}"
    );
    let free = common::tape_from_text("thrown_free", &free);
    let sliders = common::tape_from_text("thrown_sliders", &sliders);
    let options = dop853(1.0, 0.01, 1e-12, 1e-14);
    let (qf, uf) = common::initial_state(&free);
    let (qs, us) = common::initial_state(&sliders);
    let (on_free, on_sliders) = (
        run(&free, &qf, &uf, &options),
        run(&sliders, &qs, &us, &options),
    );
    let (at_f, at_s) = (
        free.output_index("at.x").unwrap(),
        sliders.output_index("at.x").unwrap(),
    );
    let spin_f = free.coordinate_index("spin").unwrap();
    let spin_s = sliders.coordinate_index("spin").unwrap();
    let (mut worst, mut travel) = (0.0_f64, 0.0_f64);
    for k in 0..on_free.len() {
        for c in 0..3 {
            let (a, b) = (
                on_free.outputs[k][at_f + c],
                on_sliders.outputs[k][at_s + c],
            );
            worst = worst.max((a - b).abs());
            travel = travel.max((a - on_free.outputs[0][at_f + c]).abs());
        }
        worst = worst.max((on_free.q[k][spin_f] - on_sliders.q[k][spin_s]).abs());
    }
    eprintln!("free joint vs sliders and a ball on a spinning table, 1 s: max |Δ| = {worst:.1e} (the stone travels {travel:.2} m)");
    assert!(travel > 0.5, "the stone hardly moved: {travel}");
    assert!(worst < 1e-9, "free joint and sliders differ by {worst:e}");
}
