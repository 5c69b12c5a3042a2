//! The bodies' share of `M` and `F` by composite bodies: Kane's sums regrouped over subtrees.
//!
//! Consumes: the [`Kinematics`] of the frame tree and the IR bodies. Produces: the terms of
//! `M_rs` and of `F_r` that the bodies give (inertia and gravity), added to the caller's lists.
//!
//! Kane's `M_rs = Σ_bodies m v_r·v_s + ω_r·I ω_s` costs a dot product per body per pair of
//! speeds, and every entry of a chain's `M` then carries every link below both joints. A
//! speed `u_s` that enters at frame i moves the whole subtree of i as one rigid body, with
//! `(a_s, v_s)` = `(∂ω/∂u_s, ∂v_O/∂u_s)` at i's origin O (`joint_partials`). So the bodies of
//! that subtree can be lumped first (Featherstone's composite-rigid-body algorithm,
//! *Rigid Body Dynamics Algorithms* §6.2): with the subtree's mass `m`, first moment `h` and
//! inertia `J` about O,
//! ```text
//! L = m v_s + a_s × h            (momentum of the subtree moving with u_s alone)
//! H = J a_s + h × v_s            (its moment about O)
//! M_rs = a_r·H + v_r·L           (r entering at i or at an ancestor j of i, with L, H moved
//!                                 to j: L' = C L, H' = C H + d × L' at each step up)
//! ```
//! and `M_rs = 0` when neither frame is an ancestor of the other. The same lumping of the
//! bodies' gravity and u̇-free inertia forces (force `f` and moment `n` about O, summed up
//! the tree as in the backward pass of Newton–Euler) gives `F_r ∋ a_r·n + v_r·f` in one
//! pass. The composites are shared subexpressions, so `M` costs O(N·depth) and `F` O(N)
//! operations instead of O(N·depth²) and O(N·depth).

use std::collections::BTreeMap;

use super::kinematics::{inertia_matrix, lower_expr, lower_vec, Kinematics};
use super::vector::{self, Mat3, Vec3};
use crate::ir::Model;
use crate::sym::{ExprId, ExprPool, Number};

/// The bodies of one subtree, in the basis of its root frame, about that frame's origin.
#[derive(Clone, Copy)]
struct Composite {
    mass: ExprId,
    /// `Σ m ρ_G`, ρ from the frame's origin.
    first_moment: Vec3,
    /// `Σ I_G + m (|ρ|² 1 − ρ ρᵀ)`.
    inertia: Mat3,
    /// `Σ m (g − a_G|u̇=0)`: gravity less the u̇-free inertia force.
    force: Vec3,
    /// Moment of those forces about the origin, with the bodies' `−(I α + ω × I ω)`.
    moment: Vec3,
}

/// Adds the bodies' `M_rs` (keys `r ≤ s`) and `F_r` terms (see the module docs).
pub(super) fn add_bodies(
    pool: &mut ExprPool,
    kinematics: &Kinematics,
    model: &Model,
    mass_terms: &mut BTreeMap<(usize, usize), Vec<ExprId>>,
    forcing_terms: &mut [Vec<ExprId>],
) {
    let frames = &kinematics.frames;
    let mut composites: Vec<Option<Composite>> = vec![None; frames.len()];
    for (_, body) in model.bodies.iter() {
        let own = body_composite(pool, kinematics, body);
        gather(pool, &mut composites[body.frame.index()], own);
    }
    // Children have larger indices than their parents (an IR invariant): one backward sweep.
    for k in (0..frames.len()).rev() {
        let (Some(parent), Some(child)) = (frames[k].parent, composites[k]) else {
            continue;
        };
        let moved = to_parent(pool, child, &frames[k].to_parent, frames[k].offset);
        gather(pool, &mut composites[parent.index()], moved);
    }

    // Whether some frame above k (k excluded) has speeds of its own: how far to carry L, H.
    let mut speeds_above = vec![false; frames.len()];
    for k in 0..frames.len() {
        if let Some(parent) = frames[k].parent {
            let p = parent.index();
            speeds_above[k] = speeds_above[p] || !frames[p].joint_partials.is_empty();
        }
    }

    for (i, frame) in frames.iter().enumerate() {
        let Some(composite) = composites[i] else {
            continue;
        };
        for &(r, a_r, v_r) in &frame.joint_partials {
            let on_moment = vector::dot(pool, a_r, composite.moment);
            let on_force = vector::dot(pool, v_r, composite.force);
            forcing_terms[r].extend([on_moment, on_force]);
        }
        for (n, &(s, a_s, v_s)) in frame.joint_partials.iter().enumerate() {
            let (mut momentum, mut moment) = momenta(pool, &composite, a_s, v_s);
            for &(r, a_r, v_r) in &frame.joint_partials[..=n] {
                let entry = generalized_momentum(pool, a_r, v_r, moment, momentum);
                mass_terms.entry((r, s)).or_default().push(entry);
            }
            let mut j = i;
            while speeds_above[j] {
                let step = &frames[j];
                (momentum, moment) =
                    carry_to_parent(pool, &step.to_parent, step.offset, momentum, moment);
                j = step
                    .parent
                    .expect("a frame with speeds above has a parent")
                    .index();
                for &(r, a_r, v_r) in &frames[j].joint_partials {
                    let entry = generalized_momentum(pool, a_r, v_r, moment, momentum);
                    mass_terms
                        .entry((r.min(s), r.max(s)))
                        .or_default()
                        .push(entry);
                }
            }
        }
    }
}

/// `a·H + v·L`.
fn generalized_momentum(
    pool: &mut ExprPool,
    a: Vec3,
    v: Vec3,
    moment: Vec3,
    momentum: Vec3,
) -> ExprId {
    let angular = vector::dot(pool, a, moment);
    let linear = vector::dot(pool, v, momentum);
    pool.add(angular, linear)
}

/// `(L, H)` of the composite moving with `(a, v)` at its origin (module docs).
fn momenta(pool: &mut ExprPool, composite: &Composite, a: Vec3, v: Vec3) -> (Vec3, Vec3) {
    let translation = vector::scale(pool, v, composite.mass);
    let turn = vector::cross(pool, a, composite.first_moment);
    let momentum = vector::add(pool, translation, turn);
    let spin = vector::mat_vec(pool, &composite.inertia, a);
    let carried = vector::cross(pool, composite.first_moment, v);
    (momentum, vector::add(pool, spin, carried))
}

/// One body as a composite of its own frame.
fn body_composite(
    pool: &mut ExprPool,
    kinematics: &Kinematics,
    body: &crate::ir::Body,
) -> Composite {
    let frame = &kinematics.frames[body.frame.index()];
    let mass = lower_expr(pool, &body.mass);
    let com = lower_vec(pool, &body.center_of_mass);
    let central = inertia_matrix(pool, &body.inertia);

    let accel = kinematics.point_accel_rest(pool, body.frame, com);
    let net = vector::sub(pool, frame.gravity, accel);
    let force = vector::scale(pool, net, mass);
    let i_alpha = vector::mat_vec(pool, &central, frame.alpha_rest);
    let i_omega = vector::mat_vec(pool, &central, frame.omega);
    let gyroscopic = vector::cross(pool, frame.omega, i_omega);
    let inertia_torque = vector::add(pool, i_alpha, gyroscopic);
    let lever = vector::cross(pool, com, force);
    let moment = vector::sub(pool, lever, inertia_torque);

    let first_moment = vector::scale(pool, com, mass);
    // The parallel-axis term m (|ρ|² 1 − ρ ρᵀ): the shift below with no first moment.
    let zero = vector::zero(pool);
    let parallel = shifted_inertia(pool, mass, com, zero);
    let inertia = add_mat(pool, &central, &parallel);
    Composite {
        mass,
        first_moment,
        inertia,
        force,
        moment,
    }
}

/// A child's composite in its parent's basis about the parent's origin; `c` = C_{p←k},
/// `d` = O_k − O_p in p.
fn to_parent(pool: &mut ExprPool, child: Composite, c: &Mat3, d: Vec3) -> Composite {
    let turned_first_moment = vector::mat_vec(pool, c, child.first_moment);
    let shift = vector::scale(pool, d, child.mass);
    let first_moment = vector::add(pool, turned_first_moment, shift);
    // C J Cᵀ + the shift by d of a body with first moment h' = C h about O_k:
    // m (|d|² 1 − d dᵀ) + 2 (d·h') 1 − d h'ᵀ − h' dᵀ.
    let turned = rotate_symmetric(pool, c, &child.inertia);
    let shifted = shifted_inertia(pool, child.mass, d, turned_first_moment);
    let inertia = add_mat(pool, &turned, &shifted);
    let (force, moment) = carry_to_parent(pool, c, d, child.force, child.moment);
    Composite {
        mass: child.mass,
        first_moment,
        inertia,
        force,
        moment,
    }
}

/// A vector and its moment about O_k (a force and its moment, or a momentum and its angular
/// momentum) in the parent's basis about O_p: `(C f, C n + d × C f)`.
fn carry_to_parent(
    pool: &mut ExprPool,
    c: &Mat3,
    d: Vec3,
    linear: Vec3,
    moment: Vec3,
) -> (Vec3, Vec3) {
    let turned = vector::mat_vec(pool, c, linear);
    let turned_moment = vector::mat_vec(pool, c, moment);
    let lever = vector::cross(pool, d, turned);
    (turned, vector::add(pool, turned_moment, lever))
}

/// Adds `composite` into the frame's `slot` (the first fills it).
fn gather(pool: &mut ExprPool, slot: &mut Option<Composite>, composite: Composite) {
    *slot = Some(match *slot {
        Some(other) => sum(pool, other, composite),
        None => composite,
    });
}

/// The sum of two composites of the same frame.
fn sum(pool: &mut ExprPool, a: Composite, b: Composite) -> Composite {
    Composite {
        mass: pool.add(a.mass, b.mass),
        first_moment: vector::add(pool, a.first_moment, b.first_moment),
        inertia: add_mat(pool, &a.inertia, &b.inertia),
        force: vector::add(pool, a.force, b.force),
        moment: vector::add(pool, a.moment, b.moment),
    }
}

/// `m (|d|² 1 − d dᵀ) + 2 (d·h) 1 − d hᵀ − h dᵀ`: the inertia about a point moved by −d of
/// a body with mass `m` and first moment `h` about its old point (module docs).
fn shifted_inertia(pool: &mut ExprPool, mass: ExprId, d: Vec3, h: Vec3) -> Mat3 {
    let d_d = vector::dot(pool, d, d);
    let d_h = vector::dot(pool, d, h);
    let d_h2 = pool.scale(d_h, Number::int(2));
    let m_dd = pool.mul(mass, d_d);
    let diagonal = pool.add(m_dd, d_h2);
    let mut out = zero_mat(pool);
    for i in 0..3 {
        for j in i..3 {
            let dd = pool.mul(d[i], d[j]);
            let m_dd = pool.mul(mass, dd);
            let dh = pool.mul(d[i], h[j]);
            let hd = pool.mul(h[i], d[j]);
            let cross = pool.add_all(&[m_dd, dh, hd]);
            let off = pool.neg(cross);
            out[i][j] = if i == j { pool.add(diagonal, off) } else { off };
            out[j][i] = out[i][j];
        }
    }
    out
}

/// `C J Cᵀ` of a symmetric `J`, the six distinct entries computed once.
fn rotate_symmetric(pool: &mut ExprPool, c: &Mat3, j: &Mat3) -> Mat3 {
    let jct: [Vec3; 3] = std::array::from_fn(|col| vector::mat_vec(pool, j, c[col]));
    let mut out = zero_mat(pool);
    for row in 0..3 {
        for col in row..3 {
            out[row][col] = vector::dot(pool, c[row], jct[col]);
            out[col][row] = out[row][col];
        }
    }
    out
}

fn add_mat(pool: &mut ExprPool, a: &Mat3, b: &Mat3) -> Mat3 {
    std::array::from_fn(|i| vector::add(pool, a[i], b[i]))
}

fn zero_mat(pool: &mut ExprPool) -> Mat3 {
    let zero = pool.zero();
    [[zero; 3]; 3]
}
