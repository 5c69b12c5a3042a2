//! Small symbolic 3-vectors and 3×3 direction cosine matrices over an [`ExprPool`].
//!
//! A `Vec3` holds components in one frame's basis; a `Mat3` `C_{A←B}` maps components in B
//! to components in A (rows indexed by A's axes). Constant vectors go to and from numbers
//! (`constant_vector`, `number_vector`) where directions are built numerically
//! (`perpendiculars` of a loop's axis or a plane's normal).

use crate::sym::{ExprId, ExprPool, Number};

pub type Vec3 = [ExprId; 3];
pub type Mat3 = [[ExprId; 3]; 3];

pub fn zero(pool: &mut ExprPool) -> Vec3 {
    let z = pool.zero();
    [z, z, z]
}

pub fn identity(pool: &mut ExprPool) -> Mat3 {
    let (z, o) = (pool.zero(), pool.one());
    [[o, z, z], [z, o, z], [z, z, o]]
}

pub fn add(pool: &mut ExprPool, a: Vec3, b: Vec3) -> Vec3 {
    [
        pool.add(a[0], b[0]),
        pool.add(a[1], b[1]),
        pool.add(a[2], b[2]),
    ]
}

pub fn sub(pool: &mut ExprPool, a: Vec3, b: Vec3) -> Vec3 {
    [
        pool.sub(a[0], b[0]),
        pool.sub(a[1], b[1]),
        pool.sub(a[2], b[2]),
    ]
}

/// `s·a` for a scalar expression `s`.
pub fn scale(pool: &mut ExprPool, a: Vec3, s: ExprId) -> Vec3 {
    [pool.mul(a[0], s), pool.mul(a[1], s), pool.mul(a[2], s)]
}

pub fn scale_number(pool: &mut ExprPool, a: Vec3, c: Number) -> Vec3 {
    [
        pool.scale(a[0], c),
        pool.scale(a[1], c),
        pool.scale(a[2], c),
    ]
}

pub fn dot(pool: &mut ExprPool, a: Vec3, b: Vec3) -> ExprId {
    let products = [
        pool.mul(a[0], b[0]),
        pool.mul(a[1], b[1]),
        pool.mul(a[2], b[2]),
    ];
    pool.add_all(&products)
}

pub fn cross(pool: &mut ExprPool, a: Vec3, b: Vec3) -> Vec3 {
    let component = |pool: &mut ExprPool, i: usize, j: usize| {
        let left = pool.mul(a[i], b[j]);
        let right = pool.mul(a[j], b[i]);
        pool.sub(left, right)
    };
    [
        component(pool, 1, 2),
        component(pool, 2, 0),
        component(pool, 0, 1),
    ]
}

/// `C·v`.
pub fn mat_vec(pool: &mut ExprPool, c: &Mat3, v: Vec3) -> Vec3 {
    [dot(pool, c[0], v), dot(pool, c[1], v), dot(pool, c[2], v)]
}

/// `Cᵀ·v` (for a DCM: the inverse map).
pub fn mat_t_vec(pool: &mut ExprPool, c: &Mat3, v: Vec3) -> Vec3 {
    let column = |i: usize| [c[0][i], c[1][i], c[2][i]];
    [
        dot(pool, column(0), v),
        dot(pool, column(1), v),
        dot(pool, column(2), v),
    ]
}

/// `A·B`.
pub fn mat_mul(pool: &mut ExprPool, a: &Mat3, b: &Mat3) -> Mat3 {
    let mut out = [[pool.zero(); 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, entry) in row.iter_mut().enumerate() {
            *entry = dot(pool, a[i], [b[0][j], b[1][j], b[2][j]]);
        }
    }
    out
}

/// Rotation by `angle` about the unit `axis` (Rodrigues): `C_{P←F} = cosθ·I + sinθ·[a]× +
/// (1 − cosθ)·a aᵀ`, the DCM of a frame F obtained by rotating P.
pub fn rotation(pool: &mut ExprPool, axis: Vec3, angle: ExprId) -> Mat3 {
    let c = pool.cos(angle);
    let s = pool.sin(angle);
    let one = pool.one();
    let versine = pool.sub(one, c);
    let mut out = [[pool.zero(); 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, entry) in row.iter_mut().enumerate() {
            let outer = pool.mul_all(&[versine, axis[i], axis[j]]);
            // [a]× entry (i, j) = −ε_ijk a_k
            let skew = match (i, j) {
                (0, 1) => pool.neg(axis[2]),
                (0, 2) => axis[1],
                (1, 0) => axis[2],
                (1, 2) => pool.neg(axis[0]),
                (2, 0) => pool.neg(axis[1]),
                (2, 1) => axis[0],
                _ => pool.zero(),
            };
            let skew = pool.mul(s, skew);
            let diagonal = if i == j { c } else { pool.zero() };
            *entry = pool.add_all(&[diagonal, skew, outer]);
        }
    }
    out
}

/// The DCM `C_{P←F}` of the unit quaternion `e = (e₀, ε)`, scalar first, that turns P into F
/// (Euler parameters; Kane, Likins & Levinson, *Spacecraft Dynamics*, §1.3):
/// `C = (e₀² − ε·ε) I + 2 ε εᵀ + 2 e₀ [ε]×`, a rotation where `|e| = 1` only: the back ends
/// evaluate every function of `q` at its quaternions scaled to unit norm
/// (`mech_runtime::__codegen::unit_quaternions`, `TapeModel::with_env`), so an integrator's
/// stage slightly off the unit sphere still sees a rigid motion. (Dividing by `|e|²` here
/// would do the same symbolically, but `J = ∂φ/∂q` through it costs the HAMR robot 1.8× in
/// run time.)
pub fn quaternion_rotation(pool: &mut ExprPool, e: [ExprId; 4]) -> Mat3 {
    let [e0, e1, e2, e3] = e;
    let vector = [e1, e2, e3];
    let squares = e.map(|part| pool.pow(part, Number::int(2)));
    let mut out = [[pool.zero(); 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, entry) in row.iter_mut().enumerate() {
            *entry = if i == j {
                // e₀² + εᵢ² − the other two squares.
                let others: Vec<usize> = (1..4).filter(|&k| k != i + 1).collect();
                let plus = pool.add(squares[0], squares[i + 1]);
                let minus = pool.add(squares[others[0]], squares[others[1]]);
                pool.sub(plus, minus)
            } else {
                // 2 (εᵢ εⱼ − ε_ijk e₀ εₖ): the skew part has the sign of (i, j, k) cyclic.
                let k = 3 - i - j;
                let outer = pool.mul(vector[i], vector[j]);
                let skew = pool.mul(e0, vector[k]);
                let cyclic = (j + 3 - i) % 3 == 1;
                let sum = if cyclic {
                    pool.sub(outer, skew)
                } else {
                    pool.add(outer, skew)
                };
                pool.scale(sum, Number::int(2))
            };
        }
    }
    out
}

/// `ė = ½ e ⊗ (0, ω)` for `ω` in F's basis: `ė₀ = −½ ε·ω`, `ε̇ = ½ (e₀ ω + ε × ω)` (the
/// kinematic differential equations of Euler parameters, Kane, Likins & Levinson §1.13).
pub fn quaternion_rates(pool: &mut ExprPool, e: [ExprId; 4], omega: Vec3) -> [ExprId; 4] {
    let vector = [e[1], e[2], e[3]];
    let half = Number::rational(1, 2);
    let projection = dot(pool, vector, omega);
    let scalar = pool.scale(projection, Number::rational(-1, 2));
    let along = scale(pool, omega, e[0]);
    let across = cross(pool, vector, omega);
    let rate = add(pool, along, across);
    let rate = scale_number(pool, rate, half);
    [scalar, rate[0], rate[1], rate[2]]
}

/// The unit vector along axis `index` (0 = x).
fn unit(pool: &mut ExprPool, index: usize) -> Vec3 {
    identity(pool)[index]
}

/// `C = R(a₁, q₁) R(a₂, q₂) R(a₃, q₃)` of body-fixed Euler angles `q` about the axes
/// `sequence` (0 = x).
pub fn euler_rotation(pool: &mut ExprPool, sequence: [usize; 3], q: [ExprId; 3]) -> Mat3 {
    let mut dcm = identity(pool);
    for (axis, angle) in sequence.into_iter().zip(q) {
        let axis = unit(pool, axis);
        let turn = rotation(pool, axis, angle);
        dcm = mat_mul(pool, &dcm, &turn);
    }
    dcm
}

/// `q̇ = W(q) ω` of body-fixed Euler angles, `ω` the frame's angular velocity in its own basis.
/// In the frame after the second turn `ω₂ = R(a₃, q₃) ω = R(a₂, q₂)ᵀ a₁ q̇₁ + a₂ q̇₂ + a₃ q̇₃`,
/// and `R(a₂, q₂)ᵀ a₁ = cos q₂ a₁ + s sin q₂ k` with `a₁ × a₂ = s k` (k the axis that is
/// neither, s = ±1). Three different axes (k = a₃): `q̇₁ = ω₂·a₁ / cos q₂`, `q̇₂ = ω₂·a₂`,
/// `q̇₃ = ω₂·a₃ − s tan q₂ ω₂·a₁`. A repeated first axis (a₃ = a₁): `q̇₁ = s ω₂·k / sin q₂`,
/// `q̇₂ = ω₂·a₂`, `q̇₃ = ω₂·a₁ − cos q₂ q̇₁`.
pub fn euler_rates(
    pool: &mut ExprPool,
    sequence: [usize; 3],
    q: [ExprId; 3],
    omega: Vec3,
) -> [ExprId; 3] {
    let [first, second, third] = sequence;
    let third_axis = unit(pool, third);
    let last_turn = rotation(pool, third_axis, q[2]);
    let omega2 = mat_vec(pool, &last_turn, omega);
    let other = 3 - first - second;
    // a₁ × a₂ = +k when (first, second, other) is a cyclic order of (x, y, z).
    let sign = if (first + 1) % 3 == second { 1 } else { -1 };
    let (cos2, sin2) = (pool.cos(q[1]), pool.sin(q[1]));
    let signed = |pool: &mut ExprPool, x: ExprId| match sign {
        1 => x,
        _ => pool.neg(x),
    };
    let middle = omega2[second];
    if first == third {
        let numerator = signed(pool, omega2[other]);
        let rate1 = pool.div(numerator, sin2);
        let along = pool.mul(cos2, rate1);
        let rate3 = pool.sub(omega2[first], along);
        [rate1, middle, rate3]
    } else {
        let rate1 = pool.div(omega2[first], cos2);
        let along = pool.mul(sin2, rate1);
        let along = signed(pool, along);
        let rate3 = pool.sub(omega2[third], along);
        [rate1, middle, rate3]
    }
}

/// Two unit vectors perpendicular to the unit `axis` and to each other (`e₂ = a × e₁`),
/// built from the coordinate axis least aligned with `a`.
pub(super) fn perpendiculars(axis: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let least = (0..3)
        .min_by(|&i, &j| axis[i].abs().total_cmp(&axis[j].abs()))
        .unwrap_or(0);
    let mut helper = [0.0; 3];
    helper[least] = 1.0;
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let e1 = cross(axis, helper);
    let norm = (e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]).sqrt();
    let e1 = [e1[0] / norm, e1[1] / norm, e1[2] / norm];
    (e1, cross(axis, e1))
}

/// Numeric values of a constant vector (loop axes are constants after lowering).
pub(super) fn constant_vector(pool: &ExprPool, v: Vec3) -> [f64; 3] {
    let value = |id| pool.as_number(id).map_or(f64::NAN, Number::to_f64);
    [value(v[0]), value(v[1]), value(v[2])]
}

/// A vector of numbers as pool constants (exact zeros kept as zero).
pub(super) fn number_vector(pool: &mut ExprPool, v: [f64; 3]) -> Vec3 {
    let number = |pool: &mut ExprPool, x: f64| if x == 0.0 { pool.zero() } else { pool.float(x) };
    [number(pool, v[0]), number(pool, v[1]), number(pool, v[2])]
}
