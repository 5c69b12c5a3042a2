//! Compliant unilateral contact between a sphere (or a point) and a plane.
//!
//! Consumes: an [`ir::Load::Contact`] and the kinematics. Produces: [`ContactState`], the
//! contact's penetration, forces, dissipated power and stored energy as pool expressions, with
//! the relative partial velocities of the contact point that turn its force into generalized
//! forces (`kane::add_load`), its outputs (`kane::lower_output`) and its potential energy.
//!
//! With `n` the plane's unit normal (out of the solid), `r_P` the sphere's centre, `r_Q` a
//! point of the plane and `ρ` the radius: the gap `h = n·(r_P − r_Q) − ρ`, the penetration
//! `δ = max(0, −h)`, the contact point `C = r_P − ρ n`, and `v = v_C|body − v_C|plane` the
//! velocity of the body's material point at C relative to the plane's. Then `δ̇ = −n·v` (the
//! `ω × ρn` terms have no normal component), and (Hunt & Crossley 1975, in the form of
//! Marhefka & Orin 1999, IEEE Trans. SMC-A 29(6), Eq. 5 with `λ = 3/2 α k`)
//!
//! `f_n = max(0, k δ^e (1 + 3/2 α δ̇))`, `f_t = −μ f_n v_t / √(|v_t|² + v_s²)`,
//! `v_t = v − (n·v) n`,
//!
//! acting as `f = f_n n + f_t` on the body at C and `−f` on the plane's body at C:
//! `F_r = f·∂v/∂u_r`. The clamp never lets the contact pull (a fast separation would make
//! the damping term exceed the elastic one). `max(0, x)` is the pool's [`Func::Ramp`] (its
//! derivative Heaviside's [`Func::Step`]), exactly 0 below the kink in every back end: not
//! `(x + |x|)/2`, whose two halves the pool expands apart, so that rounding leaves a tiny
//! negative penetration whose power `δ^e` is NaN.
//! The elastic part `k δ^e` is conservative, with the potential `V = k δ^(e+1)/(e+1)`; the
//! contact's dissipated power is what its force takes from the motion beyond `−V̇`:
//! `D = −f·v − V̇ = (f_n − k δ^e) δ̇ − f_t·v_t ≥ 0`.

use std::collections::BTreeMap;

use super::kinematics::{self, Kinematics, Partials};
use super::points::{combine_partials, point_position, relative_partials_at};
use super::vector::{self, Vec3};
use crate::ir::{self, Model};
use crate::sym::{ExprId, ExprPool, Func, Number};

/// One contact's quantities in N's basis (see the module docs).
pub struct ContactState {
    pub penetration: ExprId,
    pub normal_force: ExprId,
    pub friction: Vec3,
    /// `D`, the power the contact dissipates (damping and friction).
    pub power: ExprId,
    /// `V = k δ^(e+1)/(e+1)`.
    pub energy: ExprId,
    /// `f = f_n n + f_t`, on the body at C.
    pub force: Vec3,
    /// `∂v/∂u_r` of the contact point, body relative to plane.
    pub partials: Partials,
    /// The plane's unit normal `n` and the slip velocity `v_t`, in N's basis.
    normal: Vec3,
    slip: Vec3,
    /// The coefficients of [`ContactState::add_damping`]'s `K`: `c = ∂f_n/∂δ̇`,
    /// `g = μ f_n / s` and `g / s²`, with `s = √(|v_t|² + v_s²)`.
    normal_damping: ExprId,
    friction_rate: ExprId,
    friction_curvature: ExprId,
}

/// `max(0, x)`.
fn ramp(pool: &mut ExprPool, x: ExprId) -> ExprId {
    pool.call(Func::Ramp, x)
}

impl ContactState {
    /// The state of `load`, which must be a [`ir::Load::Contact`] (`None` otherwise).
    pub fn new(
        pool: &mut ExprPool,
        kinematics: &mut Kinematics,
        model: &Model,
        load: &ir::Load,
    ) -> Option<ContactState> {
        let ir::Load::Contact {
            point,
            plane,
            normal,
            radius,
            stiffness,
            exponent,
            damping,
            friction,
            transition_speed,
            ..
        } = load
        else {
            return None;
        };
        let (body_point, plane_point) = (&model.points[*point], &model.points[*plane]);
        let radius = kinematics::lower_expr(pool, radius);
        let normal_local = kinematics::lower_vec(pool, normal);
        let (plane_dcm, _) = kinematics.to_newtonian(pool, plane_point.frame);
        let n = vector::mat_vec(pool, &plane_dcm, normal_local);
        let centre = point_position(pool, kinematics, body_point);
        let anchor = point_position(pool, kinematics, plane_point);
        let apart = vector::sub(pool, centre, anchor);
        let height = vector::dot(pool, n, apart);
        let gap = pool.sub(height, radius);
        let minus_gap = pool.neg(gap);
        let penetration = ramp(pool, minus_gap);

        // C as an offset in each body's basis: r_P − ρn on the sphere's body, and
        // r_Q + (r_P − r_Q) − ρn on the plane's.
        let n_in_body = kinematics.express(pool, normal_local, plane_point.frame, body_point.frame);
        let inward = vector::scale(pool, n_in_body, radius);
        let body_offset = kinematics::lower_vec(pool, &body_point.position);
        let body_offset = vector::sub(pool, body_offset, inward);
        let apart_in_plane = vector::mat_t_vec(pool, &plane_dcm, apart);
        let inward = vector::scale(pool, normal_local, radius);
        let plane_offset = kinematics::lower_vec(pool, &plane_point.position);
        let plane_offset = vector::add(pool, plane_offset, apart_in_plane);
        let plane_offset = vector::sub(pool, plane_offset, inward);
        let ends = [
            (plane_point.frame, plane_offset),
            (body_point.frame, body_offset),
        ];
        let partials = relative_partials_at(pool, kinematics, |_, end| ends[end]);
        let v = combine_partials(pool, &partials);
        let normal_speed = vector::dot(pool, n, v);
        let rate = pool.neg(normal_speed);

        // f_n = max(0, k δ^e (1 + 3/2 α δ̇)).
        let k = kinematics::lower_expr(pool, stiffness);
        let power_law = pool.pow(penetration, *exponent);
        let elastic = pool.mul(k, power_law);
        let alpha = kinematics::lower_expr(pool, damping);
        let alpha_rate = pool.mul(alpha, rate);
        let damping_term = pool.scale(alpha_rate, Number::rational(3, 2));
        let one = pool.one();
        let factor = pool.add(one, damping_term);
        let unclamped = pool.mul(elastic, factor);
        let normal_force = ramp(pool, unclamped);
        // c = ∂f_n/∂δ̇ = 3/2 α k δ^e where the clamp is open.
        let open = pool.call(Func::Step, unclamped);
        let viscous = pool.mul(elastic, alpha);
        let viscous = pool.scale(viscous, Number::rational(3, 2));
        let normal_damping = pool.mul(open, viscous);

        // f_t = −μ f_n v_t / √(|v_t|² + v_s²).
        let along = vector::scale(pool, n, normal_speed);
        let slip = vector::sub(pool, v, along);
        let slip_square = vector::dot(pool, slip, slip);
        let v_s = kinematics::lower_expr(pool, transition_speed);
        let v_s_square = pool.pow(v_s, Number::int(2));
        let regularized = pool.add(slip_square, v_s_square);
        let inverse = pool.pow(regularized, Number::rational(-1, 2));
        let mu = kinematics::lower_expr(pool, friction);
        let mu_normal = pool.mul(mu, normal_force);
        let magnitude = pool.mul(mu_normal, inverse);
        let friction_rate = magnitude;
        let magnitude = pool.neg(magnitude);
        let friction = vector::scale(pool, slip, magnitude);
        let inverse_square = pool.pow(regularized, Number::int(-1));
        let friction_curvature = pool.mul(friction_rate, inverse_square);

        let normal_part = vector::scale(pool, n, normal_force);
        let force = vector::add(pool, normal_part, friction);

        // D = (f_n − k δ^e) δ̇ − f_t·v_t.
        let excess = pool.sub(normal_force, elastic);
        let damping_power = pool.mul(excess, rate);
        let friction_power = vector::dot(pool, friction, slip);
        let power = pool.sub(damping_power, friction_power);

        // V = k δ^(e+1)/(e+1).
        let raised = exponent.add(Number::ONE);
        let stored = pool.pow(penetration, raised);
        let stored = pool.mul(k, stored);
        let energy = pool.scale(stored, raised.recip());
        Some(ContactState {
            penetration,
            normal_force,
            friction,
            power,
            energy,
            force,
            partials,
            normal: n,
            slip,
            normal_damping,
            friction_rate,
            friction_curvature,
        })
    }

    /// Adds the contact's damping `Pᵀ K P` to `damping[(r, s)]` (`r ≤ s`; the matrix is
    /// symmetric), `P` the partial velocities `∂v/∂u` and `K ≈ ∂f/∂v` the contact force's
    /// slope in the slip velocity at fixed `q`: `K = −c n nᵀ − g (I − n nᵀ) + (g/s²) v_t v_tᵀ`
    /// (from `f_n` in `δ̇ = −n·v`, and `f_t = −μ f_n v_t/s` at fixed `f_n`). The term in which
    /// `f_t` follows `f_n` through `δ̇`, `μ c (v_t/s) nᵀ`, is left out: it is not symmetric,
    /// and without it `K` is symmetric negative semidefinite (`1/s ≥ |v_t|²/s³`), so that a
    /// linearly implicit integrator's `M − γ Pᵀ K P` stays positive definite. It is the part
    /// of `∂F/∂u` that is stiff: on a light foot the regularized friction is a damper of
    /// microseconds.
    pub fn add_damping(
        &self,
        pool: &mut ExprPool,
        damping: &mut BTreeMap<(usize, usize), Vec<ExprId>>,
    ) {
        // a_r = n·p_r, b_r = v_t·p_r; K's quadratic form on (p_r, p_s) is
        // (g − c) a_r a_s − g p_r·p_s + (g/s²) b_r b_s.
        let along: Vec<(ExprId, ExprId)> = self
            .partials
            .iter()
            .map(|&(_, p)| {
                (
                    vector::dot(pool, self.normal, p),
                    vector::dot(pool, self.slip, p),
                )
            })
            .collect();
        let normal_weight = pool.sub(self.friction_rate, self.normal_damping);
        let plane_weight = pool.neg(self.friction_rate);
        for (i, &(r, p_r)) in self.partials.iter().enumerate() {
            for (j, &(s, p_s)) in self.partials.iter().enumerate().skip(i) {
                let (a_r, b_r) = along[i];
                let (a_s, b_s) = along[j];
                let normal = pool.mul_all(&[normal_weight, a_r, a_s]);
                let dot = vector::dot(pool, p_r, p_s);
                let plane = pool.mul(plane_weight, dot);
                let slip = pool.mul_all(&[self.friction_curvature, b_r, b_s]);
                damping
                    .entry((r.min(s), r.max(s)))
                    .or_default()
                    .extend([normal, plane, slip]);
            }
        }
    }

    /// `F_r += f·∂v/∂u_r`.
    pub fn add_forces(&self, pool: &mut ExprPool, forcing: &mut [Vec<ExprId>]) {
        for &(r, partial) in &self.partials {
            forcing[r].push(vector::dot(pool, self.force, partial));
        }
    }

    /// The outputs in [`ir::CONTACT_OUTPUTS`] order; the last, the dissipated energy, is 0
    /// here: a simulation integrates it from the power (`Equations::integrated_outputs`).
    pub fn outputs(&self, pool: &mut ExprPool) -> [ExprId; 7] {
        let [fx, fy, fz] = self.friction;
        let (penetration, normal_force, power) = (self.penetration, self.normal_force, self.power);
        [penetration, normal_force, fx, fy, fz, power, pool.zero()]
    }
}
