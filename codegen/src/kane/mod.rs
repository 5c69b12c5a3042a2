//! Kane's method: from a checked model to `M(q) u̇ = F(t, q, u, inputs)` and outputs.
//!
//! Consumes: an [`ir::Model`]. Produces: [`Equations`], plain data (a pool and root ids).
//!
//! For each generalized speed r (Kane & Levinson, *Dynamics: Theory and Applications*, ch. 6),
//! `F_r + F_r* = 0` with
//! - `F_r  = Σ_points f·∂v_P/∂u_r + Σ_bodies T·∂ω/∂u_r` (applied forces, gravity, joint
//!   springs and dampers, point-to-point springs), the generalized active forces;
//! - `F_r* = −Σ_bodies [m a_G·∂v_G/∂u_r + (I α + ω × I ω)·∂ω/∂u_r]`, the generalized inertia
//!   forces.
//!
//! Splitting accelerations into their u̇ parts (`Σ_s ∂v/∂u_s u̇_s`) and the rest gives
//! `M_rs = Σ_bodies m ∂v_G/∂u_r·∂v_G/∂u_s + ∂ω/∂u_r·I ∂ω/∂u_s` and
//! `F_r = F_r + F_r*|_{u̇=0}` (SymPy's `forcing`). `M` is never inverted symbolically. The
//! bodies' sums are taken subtree by subtree (`composite.rs`: composite bodies for `M`, one
//! backward pass for their gravity and inertia forces), the other loads point by point.
//!
//! This file assembles; the folder's files compute the parts and never call back here:
//! `kinematics.rs` and `rates.rs` (frames, partial velocities, `q̇ = W(q) u`), `points.rs`
//! (point positions, relative partial velocities, spring lines), `closure.rs` (a loop
//! closure's geometry and angles), `bushing.rs`, `contact.rs`, `state.rs` (state terms of
//! expressions, the energies), `constraints.rs` (`φ`, `J`, `J̇u`), `speeds.rs` (chosen
//! speeds) and `equations.rs` (the result's data).

mod bushing;
mod closure;
mod composite;
pub mod constraints;
mod contact;
mod equations;
mod kinematics;
mod points;
mod rates;
mod speeds;
mod state;
pub mod vector;

use std::collections::BTreeMap;

use crate::ir::{self, Load, Model, OutputKind};
use crate::sym::{ExprId, ExprPool, Symbol};
use bushing::bushing_springs;
use closure::flexure_angle;
pub use equations::{Equations, FlexureRows};
pub use kinematics::{lower_expr, lower_expr_with, Kinematics};
use points::{combine_partials, point_position, relative_partials, spring_length, SpringLine};
use rates::KinematicRates;
pub use speeds::{chosen_speeds_at_start, describe as describe_speeds};
pub use state::lower_state_expr;
use state::{kinetic_energy, lower_state_vec, potential_energy};
use vector::Vec3;

/// The angle, stiffness, damping and loss factor of every flexure.
fn flexure_rows(pool: &mut ExprPool, kinematics: &mut Kinematics, model: &Model) -> FlexureRows {
    let mut rows = FlexureRows::default();
    for flexure in &model.flexures {
        let angle = flexure_angle(pool, kinematics, model, flexure.angle);
        rows.names.push(flexure.name.clone());
        rows.angles.push(angle);
        rows.stiffness.push(lower_expr(pool, &flexure.stiffness));
        rows.damping.push(lower_expr(pool, &flexure.damping));
        rows.loss_factor
            .push(lower_expr(pool, &flexure.loss_factor));
    }
    rows
}

/// Derives the equations of motion by Kane's method.
pub fn derive(model: &Model) -> Equations {
    let mut pool = ExprPool::new();
    name_symbols(model, &mut pool);
    let mut kinematics = Kinematics::new(model, &mut pool);
    let rates = KinematicRates::new(&mut pool, model);
    let nu = model.nu();

    // Terms of M_rs (r ≤ s) and F_r, summed once at the end so each sum is built once.
    let mut mass_terms: BTreeMap<(usize, usize), Vec<ExprId>> = BTreeMap::new();
    let mut forcing_terms: Vec<Vec<ExprId>> = vec![Vec::new(); nu];

    composite::add_bodies(
        &mut pool,
        &kinematics,
        model,
        &mut mass_terms,
        &mut forcing_terms,
    );
    for load in &model.loads {
        add_load(
            &mut pool,
            &mut kinematics,
            &rates,
            model,
            load,
            &mut forcing_terms,
        );
    }
    let constraints = constraints::derive(&mut pool, &mut kinematics, &rates, model);
    let flexures = flexure_rows(&mut pool, &mut kinematics, model);

    let zero = pool.zero();
    let mut mass_matrix = vec![zero; nu * nu];
    for ((r, s), terms) in mass_terms {
        let entry = pool.add_all(&terms);
        mass_matrix[r + nu * s] = entry;
        mass_matrix[s + nu * r] = entry;
    }
    let forcing: Vec<ExprId> = forcing_terms
        .iter()
        .map(|terms| pool.add_all(terms))
        .collect();
    let static_forcing =
        pool.substitute(&forcing, &|s| matches!(s, Symbol::Speed(_)).then_some(zero));
    let contact_damping = contact_damping(&mut pool, &mut kinematics, model);

    let mut outputs = Vec::new();
    let mut output_names = Vec::new();
    let mut integrated_outputs = Vec::new();
    for output in &model.outputs {
        for (suffix, id) in lower_output(&mut pool, &mut kinematics, model, &output.kind) {
            if matches!(output.kind, OutputKind::Contact(_)) && suffix == ".dissipated" {
                // The contact's `.power` is the output before it.
                integrated_outputs.push((outputs.len(), outputs.len() - 1));
            }
            output_names.push(format!("{}{suffix}", output.name));
            outputs.push(id);
        }
    }
    let kinematic_rates = rates::rates(&mut pool, model);
    let mut equations = Equations {
        pool: ExprPool::new(),
        nq: model.nq(),
        nu,
        kinematic_rates,
        mass_matrix,
        forcing,
        static_forcing,
        contact_damping,
        outputs,
        output_names,
        integrated_outputs,
        constraints,
        flexures,
    };
    if !model.speeds.is_empty() {
        speeds::change_speeds(&mut pool, &mut kinematics, model, &mut equations);
    }
    equations.pool = pool;
    equations
}

/// [`Equations::contact_damping`]: every contact's `Pᵀ K P`, summed.
fn contact_damping(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
) -> Option<Vec<ExprId>> {
    let mut terms = BTreeMap::new();
    let mut any = false;
    for load in &model.loads {
        if let Some(contact) = contact::ContactState::new(pool, kinematics, model, load) {
            contact.add_damping(pool, &mut terms);
            any = true;
        }
    }
    if !any {
        return None;
    }
    let nu = model.nu();
    let mut matrix = vec![pool.zero(); nu * nu];
    for ((r, s), entry) in terms {
        let entry = pool.add_all(&entry);
        matrix[r + nu * s] = entry;
        matrix[s + nu * r] = entry;
    }
    Some(matrix)
}

/// Display names: `q_<coordinate>`, `u_<speed>` (as [`Model::coordinate_names`] and
/// [`Model::speed_names`] spell them), parameter and input names, `t`.
fn name_symbols(model: &Model, pool: &mut ExprPool) {
    for (i, name) in model.coordinate_names().into_iter().enumerate() {
        pool.set_name(Symbol::Coordinate(i as u32), format!("q_{name}"));
    }
    for (i, name) in model.speed_names().into_iter().enumerate() {
        pool.set_name(Symbol::Speed(i as u32), format!("u_{name}"));
    }
    for (handle, param) in model.params.iter() {
        pool.set_name(Symbol::Param(handle.index() as u32), param.name.clone());
    }
    for (handle, input) in model.inputs.iter() {
        pool.set_name(Symbol::Input(handle.index() as u32), input.name.clone());
    }
}

/// `k (x − rest)`, a spring's restoring force or moment at `x`; `x` is built after `k` and
/// `rest`, the order the pool (and so the golden equations) numbers them in.
fn spring_moment(
    pool: &mut ExprPool,
    stiffness: &ir::Expr,
    rest: &ir::Expr,
    x: impl FnOnce(&mut ExprPool) -> ExprId,
) -> ExprId {
    let k = lower_expr(pool, stiffness);
    let rest = lower_expr(pool, rest);
    let x = x(pool);
    let stretch = pool.sub(x, rest);
    pool.mul(k, stretch)
}

/// `Q_r −= moment ∂θ̇/∂u_r` (`∂θ/∂q_r` where `q̇ = u`): the generalized forces of a moment
/// resisting the angle `theta`.
fn push_angle_forces(
    pool: &mut ExprPool,
    rates: &KinematicRates,
    forcing: &mut [Vec<ExprId>],
    theta: ExprId,
    moment: ExprId,
) {
    let gradient = rates.partial_rates(pool, theta);
    for (r, slope) in gradient.into_iter().enumerate() {
        let force = pool.mul(moment, slope);
        forcing[r].push(pool.neg(force));
    }
}

/// The length `L` of each point-to-point spring whose direction `ê = d/L` enters its force
/// (a rest length or a damper), at the model's initial coordinates (quaternions at the
/// identity) and the params at `params`, with the larger distance of its ends from the
/// Newtonian origin (a scale for "zero"): `(index in model.loads, L, scale)`.
pub fn spring_lengths_at_start(model: &Model, params: &[f64]) -> Vec<(usize, f64, f64)> {
    let springs: Vec<(usize, [ir::Handle<ir::Point>; 2])> = model
        .loads
        .iter()
        .enumerate()
        .filter_map(|(index, load)| match load {
            Load::PointSpring {
                rest_length: ir::Expr::Number(rest),
                damping: None,
                tension: None,
                ..
            } if rest.is_zero() => None,
            Load::PointSpring { ends, .. } => Some((index, *ends)),
            _ => None,
        })
        .collect();
    if springs.is_empty() {
        return Vec::new();
    }
    let mut pool = ExprPool::new();
    let mut kinematics = Kinematics::new(model, &mut pool);
    let mut roots = Vec::new();
    for &(_, ends) in &springs {
        let [a, b] = ends.map(|end| point_position(&mut pool, &mut kinematics, &model.points[end]));
        let d = vector::sub(&mut pool, b, a);
        let length = vector::dot(&mut pool, d, d);
        let far = [a, b].map(|r| vector::dot(&mut pool, r, r));
        roots.extend([length, far[0], far[1]]);
    }
    let q = model.initial_coordinates();
    let values = pool.eval(&roots, &|symbol| match symbol {
        Symbol::Coordinate(i) => q.get(i as usize).copied().unwrap_or(f64::NAN),
        Symbol::Param(i) => params.get(i as usize).copied().unwrap_or(f64::NAN),
        _ => 0.0,
    });
    springs
        .iter()
        .zip(values.chunks(3))
        .map(|(&(index, _), squares)| {
            let scale = squares[1].max(squares[2]).sqrt();
            (index, squares[0].sqrt(), scale)
        })
        .collect()
}

/// Contribution of one applied load to the generalized active forces `F_r`.
fn add_load(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    rates: &KinematicRates,
    model: &Model,
    load: &Load,
    forcing: &mut [Vec<ExprId>],
) {
    match load {
        Load::Force { point, force, .. } => {
            let point = &model.points[*point];
            let offset = kinematics::lower_vec(pool, &point.position);
            let f = lower_state_vec(pool, kinematics, model, &force.components);
            let f = kinematics.express(pool, f, force.frame, point.frame);
            for (r, v) in kinematics.point_partials(pool, point.frame, offset) {
                forcing[r].push(vector::dot(pool, f, v));
            }
        }
        Load::Torque { frame, torque, .. } => {
            let t = lower_state_vec(pool, kinematics, model, &torque.components);
            let t = kinematics.express(pool, t, torque.frame, *frame);
            for (r, w) in kinematics.frames[frame.index()].partial_omega.clone() {
                forcing[r].push(vector::dot(pool, t, w));
            }
        }
        Load::Spring {
            coordinate,
            stiffness,
            rest,
            ..
        } => {
            let force = spring_moment(pool, stiffness, rest, |pool| {
                pool.symbol(Symbol::Coordinate(coordinate.index() as u32))
            });
            forcing[coordinate.index()].push(pool.neg(force));
        }
        Load::Damper {
            coordinate,
            damping,
            ..
        } => {
            let c = lower_expr(pool, damping);
            let u = pool.symbol(Symbol::Speed(coordinate.index() as u32));
            let force = pool.mul(c, u);
            forcing[coordinate.index()].push(pool.neg(force));
        }
        Load::GeneralizedForce {
            coordinate, force, ..
        } => {
            let force = lower_state_expr(pool, kinematics, model, force);
            forcing[coordinate.index()].push(force);
        }
        Load::PointSpring {
            ends,
            stiffness,
            rest_length: ir::Expr::Number(rest),
            damping: None,
            tension: None,
            ..
        } if rest.is_zero() => {
            // A zero-length spring: T ê = k L ê = k d, so F_r = −k d·∂(v_B − v_A)/∂u_r, with
            // no direction to divide out: defined where the points meet.
            let k = lower_expr(pool, stiffness);
            let (d, _) = spring_length(pool, kinematics, model, *ends);
            for (r, v) in relative_partials(pool, kinematics, model, *ends) {
                let rate = vector::dot(pool, d, v);
                let force = pool.mul(k, rate);
                forcing[r].push(pool.neg(force));
            }
        }
        Load::PointSpring {
            ends,
            stiffness,
            rest_length,
            damping,
            tension: law,
            ..
        } => {
            // T = k (L − L0) + c L̇ (+ a tension law); −T ê on B and +T ê on A give
            // F_r = −T ê·(∂v_B/∂u_r − ∂v_A/∂u_r).
            let line = SpringLine::new(pool, kinematics, model, *ends);
            let mut tension = spring_moment(pool, stiffness, rest_length, |_| line.length);
            if let Some(damping) = damping {
                let c = lower_expr(pool, damping);
                let speed = line.stretch_speed(pool);
                let viscous = pool.mul(c, speed);
                tension = pool.add(tension, viscous);
            }
            if let Some(law) = law {
                let law = lower_state_expr(pool, kinematics, model, law);
                tension = pool.add(tension, law);
            }
            for &(r, rate) in &line.stretch_rates {
                let force = pool.mul(tension, rate);
                forcing[r].push(pool.neg(force));
            }
        }
        Load::Contact { .. } => {
            if let Some(contact) = contact::ContactState::new(pool, kinematics, model, load) {
                contact.add_forces(pool, forcing);
            }
        }
        Load::Bushing {
            frames,
            stiffness,
            damping,
            ..
        } => {
            // Q_r = −(k s + c ṡ) ∂ṡ/∂u_r for each offset s, as an angle spring's.
            for (s, k, c) in bushing_springs(pool, kinematics, *frames, stiffness, damping) {
                let rate = rates.rate(pool, s);
                let spring = pool.mul(k, s);
                let damper = pool.mul(c, rate);
                let moment = pool.add(spring, damper);
                push_angle_forces(pool, rates, forcing, s, moment);
            }
        }
        Load::LoopSpring {
            closure,
            stiffness,
            rest,
            ..
        } => {
            let torque =
                |pool: &mut ExprPool, _: &mut Kinematics, geometry: &closure::RevoluteGeometry| {
                    let moment = spring_moment(pool, stiffness, rest, |pool| {
                        closure::relative_angle(pool, geometry)
                    });
                    pool.neg(moment)
                };
            closure::closure_torque_forces(pool, kinematics, model, *closure, torque, forcing);
        }
        Load::AngleSpring {
            angle,
            stiffness,
            rest,
            ..
        } => {
            // Q_r = −∂V/∂q_r with V = ½k(θ − rest)².
            let k = lower_expr(pool, stiffness);
            let rest = lower_expr(pool, rest);
            let theta = flexure_angle(pool, kinematics, model, *angle);
            let stretch = pool.sub(theta, rest);
            let moment = pool.mul(k, stretch);
            push_angle_forces(pool, rates, forcing, theta, moment);
        }
        Load::AngleDamper { angle, damping, .. } => {
            // Q_r = −c θ̇ ∂θ̇/∂u_r with θ̇ = Σ ∂θ/∂q_i q̇_i.
            let c = lower_expr(pool, damping);
            let theta = flexure_angle(pool, kinematics, model, *angle);
            let rate = rates.rate(pool, theta);
            let moment = pool.mul(c, rate);
            push_angle_forces(pool, rates, forcing, theta, moment);
        }
        Load::LoopDamper {
            closure, damping, ..
        } => {
            let torque = |pool: &mut ExprPool,
                          kinematics: &mut Kinematics,
                          geometry: &closure::RevoluteGeometry| {
                let c = lower_expr(pool, damping);
                let rate = closure::relative_rate(pool, kinematics, model, *closure, geometry);
                let moment = pool.mul(c, rate);
                pool.neg(moment)
            };
            closure::closure_torque_forces(pool, kinematics, model, *closure, torque, forcing);
        }
    }
}

/// Scalar outputs of one declared output, with name suffixes (`""` or `.x`, `.y`, `.z`).
fn lower_output(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    kind: &OutputKind,
) -> Vec<(&'static str, ExprId)> {
    let vector_output = |v: Vec3| vec![(".x", v[0]), (".y", v[1]), (".z", v[2])];
    match kind {
        OutputKind::Position { point, frame } => {
            let point = &model.points[*point];
            let position = point_position(pool, kinematics, point);
            let (dcm, origin) = kinematics.to_newtonian(pool, *frame);
            let relative = vector::sub(pool, position, origin);
            vector_output(vector::mat_t_vec(pool, &dcm, relative))
        }
        OutputKind::Velocity { point, frame } => {
            let point = &model.points[*point];
            let offset = kinematics::lower_vec(pool, &point.position);
            let partials = kinematics.point_partials(pool, point.frame, offset);
            let velocity = combine_partials(pool, &partials);
            vector_output(kinematics.express(pool, velocity, point.frame, *frame))
        }
        OutputKind::Coordinate(c) => vec![("", pool.symbol(Symbol::Coordinate(c.index() as u32)))],
        OutputKind::Speed(c) => vec![("", pool.symbol(Symbol::Speed(c.index() as u32)))],
        OutputKind::KineticEnergy => vec![("", kinetic_energy(pool, kinematics, model))],
        OutputKind::PotentialEnergy => vec![("", potential_energy(pool, kinematics, model))],
        OutputKind::Expr(e) => vec![("", lower_state_expr(pool, kinematics, model, e))],
        OutputKind::Contact(index) => model
            .loads
            .get(*index)
            .and_then(|load| contact::ContactState::new(pool, kinematics, model, load))
            .map_or_else(Vec::new, |contact| {
                ir::CONTACT_OUTPUTS
                    .into_iter()
                    .zip(contact.outputs(pool))
                    .collect()
            }),
    }
}

#[cfg(test)]
mod tests;
