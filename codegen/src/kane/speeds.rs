//! Generalized speeds chosen by `speed` declarations: `u = Y(q) ū`, ū the default speeds
//! (`q̇` of pins and sliders, a ball's ω), and Kane's equations rewritten in them.
//!
//! Consumes: a model with [`ir::Model::speeds`] and the equations derived in the default
//! speeds. Produces: the same equations in the chosen speeds, and `q̇ = W(q) u`.
//!
//! `Y_rs = ∂u_r/∂ū_s` is exact: each chosen speed is lowered with the default speeds as
//! symbols (a measure number of a velocity is `Σ_s (∂v/∂ū_s · n) ū_s`, from the partial
//! velocities) and differentiated. `W = Y⁻¹` is built symbolically by Gauss–Jordan
//! elimination, each pivot the entry of largest magnitude at the initial coordinates (the
//! front end refuses a `Y(q₀)` that is singular, E0441). Then, with `ū = W u`:
//! - the partial velocities in the new speeds are `∂v/∂u_r = Σ_s ∂v/∂ū_s W_sr`, so Kane's
//!   `F̃_r + F̃*_r = Σ_s W_sr (F_s + F*_s)`, i.e. `Wᵀ (M ū̇ − F) = 0`;
//! - `ū̇ = W u̇ + Ẇ u`, so `M̃ = Wᵀ M W` and `F̃ = Wᵀ (F(q, W u) − M Ẇ u)`;
//! - a constraint row `J ū̇ + b(ū)` becomes `(J W) u̇ + b(W u) + J Ẇ u`;
//! - `q̇ = W u` for pins and sliders (a quaternion's `ė = ½ e ⊗ (0, ω)` with `ω = (W u)`);
//! - outputs are rewritten with `ū = W u`.
//!
//! `Ẇ u = Σ_k ∂(W u)/∂q_k q̇_k` at fixed u.

use super::equations::Equations;
use super::kinematics::{self, Kinematics};
use super::points::combine_partials;
use super::state::lower_state_expr;
use super::vector;
use crate::ir::{self, Model, SpeedKind};
use crate::sym::{ExprId, ExprPool, Symbol};

/// A square matrix of expressions, by rows.
type Matrix = Vec<Vec<ExprId>>;

/// The chosen speeds' values at the initial coordinates and speeds, `Y(q₀) ū₀`; or the
/// index of the first speed that is a combination of those before it at `q₀` (`Y(q₀)`
/// singular).
pub fn chosen_speeds_at_start(model: &Model, params: &[f64]) -> Result<Vec<f64>, usize> {
    let mut pool = ExprPool::new();
    let mut kinematics = Kinematics::new(model, &mut pool);
    let y = speed_matrix(&mut pool, &mut kinematics, model);
    let values = at_start(&pool, model, params, &y);
    let reduced = independent_rows(&values)?;
    debug_assert_eq!(reduced, values.len());
    let u0 = model.default_initial_speeds();
    Ok(values
        .iter()
        .map(|row| row.iter().zip(&u0).map(|(y, u)| y * u).sum())
        .collect())
}

/// `Y(q)`, `Y_rs = ∂u_r/∂ū_s`, one row per chosen speed.
fn speed_matrix(pool: &mut ExprPool, kinematics: &mut Kinematics, model: &Model) -> Matrix {
    let nu = model.nu();
    model
        .speeds
        .iter()
        .map(|speed| {
            let value = speed_value(pool, kinematics, model, &speed.kind);
            (0..nu)
                .map(|s| pool.diff(value, Symbol::Speed(s as u32)))
                .collect()
        })
        .collect()
}

/// A chosen speed in terms of the default speeds `ū` (the `Speed` symbols).
fn speed_value(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    kind: &SpeedKind,
) -> ExprId {
    let (velocity, from, frame, axis) = match kind {
        SpeedKind::Scalar(expr) => return lower_state_expr(pool, kinematics, model, expr),
        SpeedKind::AngularVelocity { body, frame, axis } => {
            (kinematics.frames[body.index()].omega, *body, frame, axis)
        }
        SpeedKind::PointVelocity { point, frame, axis } => {
            let point = &model.points[*point];
            let offset = kinematics::lower_vec(pool, &point.position);
            let partials = kinematics.point_partials(pool, point.frame, offset);
            (combine_partials(pool, &partials), point.frame, frame, axis)
        }
    };
    let velocity = kinematics.express(pool, velocity, from, *frame);
    let axis = kinematics::lower_vec(pool, axis);
    vector::dot(pool, velocity, axis)
}

/// The entries of `matrix` at the initial coordinates and the parameters `params`.
fn at_start(pool: &ExprPool, model: &Model, params: &[f64], matrix: &Matrix) -> Vec<Vec<f64>> {
    let q0 = model.initial_coordinates();
    let flat: Vec<ExprId> = matrix.iter().flatten().copied().collect();
    let values = pool.eval(&flat, &|symbol| match symbol {
        Symbol::Coordinate(i) => q0.get(i as usize).copied().unwrap_or(f64::NAN),
        Symbol::Param(i) => params.get(i as usize).copied().unwrap_or(f64::NAN),
        _ => 0.0,
    });
    let width = matrix.first().map_or(1, Vec::len).max(1);
    values.chunks(width).map(<[f64]>::to_vec).collect()
}

/// The number of rows, if each row is independent of those before it; else the index of
/// the first that is not (its remainder after elimination below `1e-9` of its size).
fn independent_rows(rows: &[Vec<f64>]) -> Result<usize, usize> {
    let mut basis: Vec<(usize, Vec<f64>)> = Vec::new();
    for (index, row) in rows.iter().enumerate() {
        let size = row.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let mut rest = row.clone();
        for (pivot, base) in &basis {
            let factor = rest[*pivot] / base[*pivot];
            rest.iter_mut()
                .zip(base)
                .for_each(|(x, b)| *x -= factor * b);
        }
        let (pivot, largest) =
            rest.iter()
                .enumerate()
                .fold((0, 0.0_f64), |best, (i, x)| match x.abs() > best.1 {
                    true => (i, x.abs()),
                    false => best,
                });
        if largest.is_nan() || largest <= 1e-9 * size {
            return Err(index);
        }
        basis.push((pivot, rest));
    }
    Ok(rows.len())
}

/// `Y⁻¹` by Gauss–Jordan elimination, each pivot the entry of largest magnitude at the start.
fn invert(pool: &mut ExprPool, model: &Model, y: Matrix) -> Matrix {
    let n = y.len();
    let params: Vec<f64> = model.params.iter().map(|(_, p)| p.value).collect();
    let mut a = y;
    let (zero, one) = (pool.zero(), pool.one());
    let mut inverse: Matrix = (0..n)
        .map(|i| (0..n).map(|j| if i == j { one } else { zero }).collect())
        .collect();
    for k in 0..n {
        let column: Matrix = a[k..].iter().map(|row| vec![row[k]]).collect();
        let values = at_start(pool, model, &params, &column);
        let pivot_row = (0..values.len())
            .max_by(|&i, &j| values[i][0].abs().total_cmp(&values[j][0].abs()))
            .map_or(k, |i| k + i);
        a.swap(k, pivot_row);
        inverse.swap(k, pivot_row);
        let pivot = a[k][k];
        for entry in a[k].iter_mut().chain(inverse[k].iter_mut()) {
            *entry = pool.div(*entry, pivot);
        }
        for i in (0..n).filter(|&i| i != k) {
            let factor = a[i][k];
            if pool.is_zero(factor) {
                continue;
            }
            for j in 0..n {
                let (reduce_a, reduce_inverse) =
                    (pool.mul(factor, a[k][j]), pool.mul(factor, inverse[k][j]));
                a[i][j] = pool.sub(a[i][j], reduce_a);
                inverse[i][j] = pool.sub(inverse[i][j], reduce_inverse);
            }
        }
    }
    inverse
}

/// `Σ_j m_j v_j` over the nonzero coefficients.
/// `Wᵀ A W` of a symmetric `nu × nu` matrix `A` (column-major), `W` given by its columns.
fn congruence(pool: &mut ExprPool, matrix: &[ExprId], w_columns: &[Vec<ExprId>]) -> Vec<ExprId> {
    let nu = w_columns.len();
    // (A W) column s, then (Wᵀ A W)[r, s] = w_rᵀ (A W)_s.
    let times_w: Matrix = (0..nu)
        .map(|i| {
            let row: Vec<ExprId> = (0..nu).map(|j| matrix[i + nu * j]).collect();
            w_columns
                .iter()
                .map(|c| combination(pool, &row, c))
                .collect()
        })
        .collect();
    let mut out = vec![pool.zero(); nu * nu];
    for s in 0..nu {
        let column: Vec<ExprId> = times_w.iter().map(|row| row[s]).collect();
        for r in 0..=s {
            let entry = combination(pool, &w_columns[r], &column);
            out[r + nu * s] = entry;
            out[s + nu * r] = entry;
        }
    }
    out
}

fn combination(pool: &mut ExprPool, coefficients: &[ExprId], values: &[ExprId]) -> ExprId {
    let mut terms = Vec::with_capacity(values.len());
    for (&c, &v) in coefficients.iter().zip(values) {
        if !pool.is_zero(c) {
            terms.push(pool.mul(c, v));
        }
    }
    pool.add_all(&terms)
}

/// Rewrites `equations`, derived in the default speeds, in the model's chosen speeds (see the
/// module docs). `equations.kinematic_rates` becomes `q̇ = W(q) u`.
pub(super) fn change_speeds(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    equations: &mut Equations,
) {
    let (nq, nu) = (equations.nq, equations.nu);
    assert_eq!(
        model.speeds.len(),
        nu,
        "one `speed` per default speed (the front end checks it; an IR transform that adds a \
         coordinate to a model with chosen speeds must add its speed)"
    );
    let y = speed_matrix(pool, kinematics, model);
    let w = invert(pool, model, y);
    let speeds: Vec<ExprId> = (0..nu)
        .map(|r| pool.symbol(Symbol::Speed(r as u32)))
        .collect();
    // ū = W u, and the default speeds' symbols replaced by it everywhere.
    let defaults: Vec<ExprId> = w
        .iter()
        .map(|row| combination(pool, row, &speeds))
        .collect();
    let in_new_speeds = |pool: &mut ExprPool, roots: &[ExprId]| -> Vec<ExprId> {
        let replacement = |symbol| match symbol {
            Symbol::Speed(i) => defaults.get(i as usize).copied(),
            _ => None,
        };
        pool.substitute(roots, &replacement)
            .expect("a linear substitution puts no zero under a negative power")
    };
    let rates = match equations.kinematic_rates.take() {
        Some(rates) => in_new_speeds(pool, &rates),
        None => defaults.clone(),
    };
    // Ẇu = Σ_k ∂(W u)/∂q_k q̇_k.
    let w_dot_u: Vec<ExprId> = defaults
        .iter()
        .map(|&default| {
            let slopes: Vec<ExprId> = (0..nq)
                .map(|k| pool.diff(default, Symbol::Coordinate(k as u32)))
                .collect();
            combination(pool, &slopes, &rates)
        })
        .collect();
    let column = |w: &Matrix, r: usize| -> Vec<ExprId> { w.iter().map(|row| row[r]).collect() };
    let w_columns: Vec<Vec<ExprId>> = (0..nu).map(|r| column(&w, r)).collect();

    // M̃ = Wᵀ M W, F̃ = Wᵀ (F(q, W u) − M Ẇ u).
    let mass_rows: Matrix = (0..nu)
        .map(|i| (0..nu).map(|j| equations.mass_matrix[i + nu * j]).collect())
        .collect();
    let mass_matrix = congruence(pool, &equations.mass_matrix, &w_columns);
    let forcing = in_new_speeds(pool, &equations.forcing);
    let transport: Vec<ExprId> = mass_rows
        .iter()
        .map(|row| combination(pool, row, &w_dot_u))
        .collect();
    let net: Vec<ExprId> = forcing
        .iter()
        .zip(&transport)
        .map(|(&f, &m)| pool.sub(f, m))
        .collect();
    equations.forcing = w_columns
        .iter()
        .map(|c| combination(pool, c, &net))
        .collect();
    equations.mass_matrix = mass_matrix;
    // D̃ = Wᵀ D(q, W u) W, as M̃ (D is the slope of F in u).
    equations.contact_damping = equations.contact_damping.take().map(|damping| {
        let damping = in_new_speeds(pool, &damping);
        congruence(pool, &damping, &w_columns)
    });
    // At rest Ẇu = 0 and F(q, 0) is the default speeds' static forcing.
    equations.static_forcing = equations.static_forcing.take().map(|rest| {
        w_columns
            .iter()
            .map(|c| combination(pool, c, &rest))
            .collect()
    });

    // Constraint rows: J̃ = J W, b̃ = b(q, W u) + J Ẇ u.
    let rows = &mut equations.constraints;
    let nc = rows.residual.len();
    let jacobian_rows: Matrix = (0..nc)
        .map(|row| (0..nu).map(|i| rows.jacobian[row + nc * i]).collect())
        .collect();
    let bias = in_new_speeds(pool, &rows.bias);
    for (row, j_row) in jacobian_rows.iter().enumerate() {
        for (r, w_column) in w_columns.iter().enumerate() {
            rows.jacobian[row + nc * r] = combination(pool, j_row, w_column);
        }
        let transport = combination(pool, j_row, &w_dot_u);
        rows.bias[row] = pool.add(bias[row], transport);
    }
    equations.outputs = in_new_speeds(pool, &equations.outputs);
    equations.kinematic_rates = Some(rates);
}

/// The speeds' names for `mech check`: `name = what`, in declaration order.
pub fn describe(model: &Model) -> Vec<String> {
    let frame_name = |f: ir::Handle<ir::Frame>| model.frames[f].name.clone();
    model
        .speeds
        .iter()
        .map(|speed| {
            let what = match &speed.kind {
                SpeedKind::AngularVelocity { body, frame, .. } => format!(
                    "angular velocity of `{}` along an axis of `{}`",
                    frame_name(*body),
                    frame_name(*frame)
                ),
                SpeedKind::PointVelocity { point, frame, .. } => format!(
                    "velocity of point `{}` along an axis of `{}`",
                    model.points[*point].name,
                    frame_name(*frame)
                ),
                SpeedKind::Scalar(_) => "a combination of joint speeds".to_string(),
            };
            format!("{} = {what}", speed.name)
        })
        .collect()
}
