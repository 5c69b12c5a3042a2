//! Kinematics of the frame tree, the first half of Kane's method.
//!
//! Consumes: the IR frames (parents first) and the pool. Produces, for every frame k, in k's
//! own basis (vectors are kept in the frame where they are simplest; Kane & Levinson §2):
//! - `to_parent` = C_{p←k}, the direction cosine matrix to the parent frame;
//! - `omega` = ω of k in N and its partial angular velocities `partial_omega` = ∂ω/∂u_r;
//! - `partial_velocity` = ∂v_O/∂u_r of k's origin O;
//! - `alpha_rest`, `accel_rest`: the angular acceleration of k and the acceleration of O with
//!   every u̇ set to zero (the u̇ parts are `Σ partial·u̇_r`);
//! - `gravity`: the gravitational acceleration in k's basis.
//!
//! The recursion, for frame k with parent p, C = C_{p←k} and d = O_k − O_p (in p):
//! ```text
//! ω_k   = Cᵀ ω_p + a u_j                                  (revolute about a, speed u_j)
//!       = Cᵀ ω_p + Σ_i n_i u_i                            (spherical: C = C₀ C(e) or C₀ C(q₁, q₂, q₃), n_i = k's axes)
//! W_k,r = Cᵀ W_p,r  (+ a for r = j, revolute; + n_i for r = i, spherical)
//! V_k,r = Cᵀ (V_p,r + W_p,r × d)  (+ a for r = j, prismatic; + n_i for r = i, free)
//! α_k   = Cᵀ α_p + (Cᵀ ω_p) × a u_j                       (u̇-free part; Σ n_i u_i if spherical)
//! a_O,k = Cᵀ (a_O,p + α_p × d + ω_p × (ω_p × d) + 2 ω_p × a_p u_j)   (last term prismatic)
//!       + (Cᵀ ω_p + ω_k) × v                              (free: v = Σ n_i u_i, d = d₀ + C₀ (x, y, z))
//! ```

use super::vector::{self, Mat3, Vec3};
use crate::ir::{self, Handle, Model, Motion};
use crate::sym::{ExprId, ExprPool, Number, Symbol};

/// A sparse list of partials: `(speed index r, ∂(vector)/∂u_r)`, sorted by r.
pub type Partials = Vec<(usize, Vec3)>;

/// Kinematic quantities of one frame (see the module docs).
#[derive(Clone, Debug)]
pub struct FrameKinematics {
    pub parent: Option<Handle<ir::Frame>>,
    pub to_parent: Mat3,
    /// O_k − O_p in the parent's basis.
    pub offset: Vec3,
    pub omega: Vec3,
    pub partial_omega: Partials,
    pub partial_velocity: Partials,
    /// The speeds that enter at this frame (its joint's): `(r, ∂ω/∂u_r, ∂v_O/∂u_r)` in k's
    /// basis, sorted by r. Every frame below k moves with u_r as one rigid body with k.
    pub joint_partials: Vec<(usize, Vec3, Vec3)>,
    pub alpha_rest: Vec3,
    pub accel_rest: Vec3,
    pub gravity: Vec3,
}

/// Kinematics of every frame, plus lazily built quantities relative to the Newtonian frame.
pub struct Kinematics {
    pub frames: Vec<FrameKinematics>,
    to_newtonian: Vec<Option<(Mat3, Vec3)>>,
}

/// Lowers an IR scalar expression into the pool. A coordinate or speed becomes its symbol;
/// the terms that need the kinematics (distances, energies) only occur in loads and outputs,
/// which lower through `kane::lower_state_expr` (elsewhere they would be NaN).
pub fn lower_expr(pool: &mut ExprPool, expr: &ir::Expr) -> ExprId {
    lower_expr_with(pool, expr, &mut |pool, term| match term {
        ir::StateTerm::Coordinate(c) => pool.symbol(Symbol::Coordinate(c.index() as u32)),
        ir::StateTerm::Speed(c) => pool.symbol(Symbol::Speed(c.index() as u32)),
        _ => pool.float(f64::NAN),
    })
}

/// Lowers an IR scalar expression, each [`ir::StateTerm`] through `state`.
pub fn lower_expr_with(
    pool: &mut ExprPool,
    expr: &ir::Expr,
    state: &mut dyn FnMut(&mut ExprPool, ir::StateTerm) -> ExprId,
) -> ExprId {
    use ir::{Expr, Function};
    let mut lower_expr = |pool: &mut ExprPool, e: &ir::Expr| lower_expr_with(pool, e, state);
    match expr {
        Expr::Number(n) => pool.number(*n),
        Expr::Param(p) => pool.symbol(Symbol::Param(p.index() as u32)),
        Expr::Input(i) => pool.symbol(Symbol::Input(i.index() as u32)),
        Expr::Time => pool.symbol(Symbol::Time),
        Expr::State(term) => state(pool, *term),
        Expr::Pi => pool.float(std::f64::consts::PI),
        Expr::Neg(a) => {
            let a = lower_expr(pool, a);
            pool.neg(a)
        }
        Expr::Add(a, b) | Expr::Sub(a, b) | Expr::Mul(a, b) | Expr::Div(a, b) => {
            let x = lower_expr(pool, a);
            let y = lower_expr(pool, b);
            match expr {
                Expr::Add(..) => pool.add(x, y),
                Expr::Sub(..) => pool.sub(x, y),
                Expr::Mul(..) => pool.mul(x, y),
                _ => pool.div(x, y),
            }
        }
        Expr::Pow(a, e) => {
            let a = lower_expr(pool, a);
            pool.pow(a, *e)
        }
        Expr::Call(function, args) => {
            let args: Vec<ExprId> = args.iter().map(|a| lower_expr(pool, a)).collect();
            let unary = |f| (f, args.first().copied());
            use crate::sym::Func;
            let (func, x) = match function {
                Function::Sin => unary(Func::Sin),
                Function::Cos => unary(Func::Cos),
                Function::Tan => unary(Func::Tan),
                Function::Exp => unary(Func::Exp),
                Function::Ln => unary(Func::Ln),
                Function::Abs => unary(Func::Abs),
                Function::Sqrt => {
                    return match args.first() {
                        Some(&x) => pool.sqrt(x),
                        None => pool.zero(),
                    }
                }
                Function::Atan2 => {
                    return match args[..] {
                        [y, x] => pool.atan2(y, x),
                        _ => pool.zero(),
                    }
                }
            };
            match x {
                Some(x) => pool.call(func, x),
                None => pool.zero(),
            }
        }
    }
}

pub fn lower_vec(pool: &mut ExprPool, v: &ir::Vec3) -> Vec3 {
    [
        lower_expr(pool, &v[0]),
        lower_expr(pool, &v[1]),
        lower_expr(pool, &v[2]),
    ]
}

/// The symmetric inertia matrix from tensor entries.
pub fn inertia_matrix(pool: &mut ExprPool, inertia: &ir::Inertia) -> [[ExprId; 3]; 3] {
    let [xx, yy, zz, xy, yz, zx] = inertia.entries().map(|e| lower_expr(pool, e));
    [[xx, xy, zx], [xy, yy, yz], [zx, yz, zz]]
}

/// `C_{p←F0}` of a constant orientation sequence `R(a₀,θ₀)·R(a₁,θ₁)·…`.
pub(crate) fn orientation(pool: &mut ExprPool, sequence: &[ir::AxisAngle]) -> Mat3 {
    let mut dcm = vector::identity(pool);
    for step in sequence {
        let axis = lower_vec(pool, &step.axis);
        let angle = lower_expr(pool, &step.angle);
        let rotation = vector::rotation(pool, axis, angle);
        dcm = vector::mat_mul(pool, &dcm, &rotation);
    }
    dcm
}

impl Kinematics {
    /// Runs the recursion over all frames (parents first, an IR invariant).
    pub fn new(model: &Model, pool: &mut ExprPool) -> Kinematics {
        let mut frames: Vec<FrameKinematics> = Vec::with_capacity(model.frames.len());
        for (handle, frame) in model.frames.iter() {
            let kinematics = match frame.parent {
                None => root(model, pool),
                Some(parent) => child(pool, model, frame, &frames[parent.index()]),
            };
            debug_assert_eq!(frames.len(), handle.index());
            frames.push(kinematics);
        }
        let count = frames.len();
        Kinematics {
            frames,
            to_newtonian: vec![None; count],
        }
    }

    /// `(C_{N←k}, r_O)`: orientation and origin position of frame k, both in N's basis.
    pub fn to_newtonian(&mut self, pool: &mut ExprPool, frame: Handle<ir::Frame>) -> (Mat3, Vec3) {
        if let Some(known) = self.to_newtonian[frame.index()] {
            return known;
        }
        let kinematics = &self.frames[frame.index()];
        let (to_parent, offset) = (kinematics.to_parent, kinematics.offset);
        let result = match kinematics.parent {
            None => (vector::identity(pool), vector::zero(pool)),
            Some(parent) => {
                let (parent_dcm, parent_origin) = self.to_newtonian(pool, parent);
                let dcm = vector::mat_mul(pool, &parent_dcm, &to_parent);
                let step = vector::mat_vec(pool, &parent_dcm, offset);
                (dcm, vector::add(pool, parent_origin, step))
            }
        };
        self.to_newtonian[frame.index()] = Some(result);
        result
    }

    /// `(C_{A←k}, r)`: the orientation of frame k and the position of its origin relative to
    /// its ancestor A, both in A's basis; [`Kinematics::to_newtonian`] when A is the root.
    /// Loop closures are measured here from the nearest common ancestor of their two frames,
    /// so their rows hold no coordinate above it (on a floating robot, not the base's pose).
    pub fn relative_to(
        &mut self,
        pool: &mut ExprPool,
        frame: Handle<ir::Frame>,
        ancestor: Handle<ir::Frame>,
    ) -> (Mat3, Vec3) {
        if self.frames[ancestor.index()].parent.is_none() {
            return self.to_newtonian(pool, frame);
        }
        let chain = self.ancestors(frame);
        let below = chain
            .iter()
            .position(|&f| f == ancestor)
            .expect("relative_to an ancestor of the frame");
        let (mut dcm, mut origin) = (vector::identity(pool), vector::zero(pool));
        for &step in chain[..below].iter().rev() {
            let kinematics = &self.frames[step.index()];
            let (to_parent, offset) = (kinematics.to_parent, kinematics.offset);
            let shift = vector::mat_vec(pool, &dcm, offset);
            origin = vector::add(pool, origin, shift);
            dcm = vector::mat_mul(pool, &dcm, &to_parent);
        }
        (dcm, origin)
    }

    /// The nearest frame that is an ancestor of both `a` and `b` (either one itself).
    pub fn common_ancestor(&self, a: Handle<ir::Frame>, b: Handle<ir::Frame>) -> Handle<ir::Frame> {
        let ancestors_of_a = self.ancestors(a);
        let mut current = b;
        while !ancestors_of_a.contains(&current) {
            current = self.frames[current.index()]
                .parent
                .expect("the root is an ancestor of every frame");
        }
        current
    }

    /// Re-expresses `v` (components in `from`) in the basis of `to`, walking up to the
    /// common ancestor and down again, so only the DCMs on that path are used.
    pub fn express(
        &self,
        pool: &mut ExprPool,
        v: Vec3,
        from: Handle<ir::Frame>,
        to: Handle<ir::Frame>,
    ) -> Vec3 {
        let meeting = self.common_ancestor(from, to);
        let mut v = v;
        let mut current = from;
        while current != meeting {
            let kinematics = &self.frames[current.index()];
            v = vector::mat_vec(pool, &kinematics.to_parent, v);
            current = kinematics.parent.expect("below the common ancestor");
        }
        let ancestors_of_to = self.ancestors(to);
        let position = ancestors_of_to
            .iter()
            .position(|&f| f == meeting)
            .expect("the common ancestor is an ancestor of `to`");
        for &frame in ancestors_of_to[..position].iter().rev() {
            v = vector::mat_t_vec(pool, &self.frames[frame.index()].to_parent, v);
        }
        v
    }

    /// `frame`, its parent, …, the root.
    fn ancestors(&self, frame: Handle<ir::Frame>) -> Vec<Handle<ir::Frame>> {
        let mut chain = vec![frame];
        while let Some(parent) = self.frames[chain[chain.len() - 1].index()].parent {
            chain.push(parent);
        }
        chain
    }

    /// Partial velocities of the point at `offset` (basis of `frame`) fixed in `frame`:
    /// `V_r + W_r × offset`.
    pub fn point_partials(
        &self,
        pool: &mut ExprPool,
        frame: Handle<ir::Frame>,
        offset: Vec3,
    ) -> Partials {
        let kinematics = &self.frames[frame.index()];
        let rotational: Partials = kinematics
            .partial_omega
            .iter()
            .map(|&(r, w)| (r, vector::cross(pool, w, offset)))
            .collect();
        merge(pool, &kinematics.partial_velocity, &rotational)
    }

    /// Acceleration (u̇-free part) of the point at `offset` fixed in `frame`:
    /// `a_O + α × r + ω × (ω × r)`.
    pub fn point_accel_rest(
        &self,
        pool: &mut ExprPool,
        frame: Handle<ir::Frame>,
        offset: Vec3,
    ) -> Vec3 {
        let kinematics = &self.frames[frame.index()];
        accel_of_point(
            pool,
            kinematics.accel_rest,
            kinematics.alpha_rest,
            kinematics.omega,
            offset,
        )
    }
}

/// The Newtonian frame: at rest; gravity from the model.
fn root(model: &Model, pool: &mut ExprPool) -> FrameKinematics {
    let zero = vector::zero(pool);
    let gravity = match &model.gravity {
        Some(g) => lower_vec(pool, g),
        None => zero,
    };
    FrameKinematics {
        parent: None,
        to_parent: vector::identity(pool),
        offset: zero,
        omega: zero,
        partial_omega: Vec::new(),
        partial_velocity: Vec::new(),
        joint_partials: Vec::new(),
        alpha_rest: zero,
        accel_rest: zero,
        gravity,
    }
}

/// The symbols of `N` consecutive coordinates from index `first` (a quaternion's `e₀ … e₃`
/// from `model.quaternion_coordinate(q, 0)`, a set of Euler angles' `q₁ … q₃`).
pub fn coordinate_run<const N: usize>(pool: &mut ExprPool, first: usize) -> [ExprId; N] {
    std::array::from_fn(|part| pool.symbol(Symbol::Coordinate((first + part) as u32)))
}

/// The symbols of three consecutive speeds from index `first`, with their indices (the
/// angular speeds of a quaternion or a set of Euler angles).
pub fn speed_run(pool: &mut ExprPool, first: usize) -> [(usize, ExprId); 3] {
    [0, 1, 2].map(|axis| {
        (
            first + axis,
            pool.symbol(Symbol::Speed((first + axis) as u32)),
        )
    })
}

/// `R`, the rotation of a spherical or free motion relative to its placement: `C(e)` of a
/// quaternion, `R(a₁, q₁) R(a₂, q₂) R(a₃, q₃)` of Euler angles.
pub fn joint_rotation(pool: &mut ExprPool, model: &Model, rotation: ir::Rotation) -> Mat3 {
    match rotation {
        ir::Rotation::Quaternion(quaternion) => {
            let e = coordinate_run(pool, model.quaternion_coordinate(quaternion, 0));
            vector::quaternion_rotation(pool, e)
        }
        ir::Rotation::Euler(angles) => {
            let q = coordinate_run(pool, model.euler_coordinate(angles, 0));
            vector::euler_rotation(pool, model.euler_angles[angles].sequence, q)
        }
    }
}

/// The symbols of the three angular speeds of a rotation, with their indices.
pub fn rotation_speed_symbols(
    pool: &mut ExprPool,
    model: &Model,
    rotation: ir::Rotation,
) -> [(usize, ExprId); 3] {
    match rotation {
        ir::Rotation::Quaternion(quaternion) => speed_run(pool, model.angular_speed(quaternion, 0)),
        ir::Rotation::Euler(angles) => speed_run(pool, model.euler_speed(angles, 0)),
    }
}

/// The spins of a spherical motion: each angular speed (from `speeds`, built after the axes
/// so that the pool numbers its symbols as it always has) about its own axis of the frame.
fn spins_about_own_axes(
    pool: &mut ExprPool,
    speeds: impl FnOnce(&mut ExprPool) -> [(usize, ExprId); 3],
) -> Vec<(usize, Vec3, ExprId)> {
    let axes = vector::identity(pool);
    speeds(pool)
        .into_iter()
        .zip(axes)
        .map(|((r, u), axis)| (r, axis, u))
        .collect()
}

/// One step of the recursion in the module docs.
fn child(
    pool: &mut ExprPool,
    model: &Model,
    frame: &ir::Frame,
    parent: &FrameKinematics,
) -> FrameKinematics {
    let placement = orientation(pool, &frame.orientation);
    let origin = lower_vec(pool, &frame.origin);
    let speed_symbol = |pool: &mut ExprPool, c: Handle<ir::Coordinate>| {
        (
            pool.symbol(Symbol::Coordinate(c.index() as u32)),
            pool.symbol(Symbol::Speed(c.index() as u32)),
        )
    };

    // A free motion's velocity speeds `v = Σ u_i k_i`: the origin's velocity relative to the
    // placement, in k's own basis.
    let mut free_velocity = None;
    let (to_parent, offset, own_rotation, own_translation) = match &frame.motion {
        Motion::Fixed => (placement, origin, Vec::new(), None),
        Motion::Revolute { axis, coordinate } => {
            let axis = lower_vec(pool, axis);
            let (q, u) = speed_symbol(pool, *coordinate);
            let rotation = vector::rotation(pool, axis, q);
            let dcm = vector::mat_mul(pool, &placement, &rotation);
            (dcm, origin, vec![(coordinate.index(), axis, u)], None)
        }
        Motion::Spherical { rotation } => {
            let turn = joint_rotation(pool, model, *rotation);
            let dcm = vector::mat_mul(pool, &placement, &turn);
            let speeds = |pool: &mut ExprPool| rotation_speed_symbols(pool, model, *rotation);
            (dcm, origin, spins_about_own_axes(pool, speeds), None)
        }
        Motion::Free {
            rotation,
            translation,
        } => {
            let first = model.translation_coordinate(*translation, 0);
            let position = coordinate_run(pool, first);
            let displacement = vector::mat_vec(pool, &placement, position);
            let offset = vector::add(pool, origin, displacement);
            let turn = joint_rotation(pool, model, *rotation);
            let dcm = vector::mat_mul(pool, &placement, &turn);
            let speeds = |pool: &mut ExprPool| rotation_speed_symbols(pool, model, *rotation);
            let spins = spins_about_own_axes(pool, speeds);
            let first = model.translation_speed(*translation, 0);
            free_velocity = Some(speed_run(pool, first));
            (dcm, offset, spins, None)
        }
        Motion::Prismatic { axis, coordinate } => {
            let axis = lower_vec(pool, axis);
            let (q, u) = speed_symbol(pool, *coordinate);
            let axis_in_parent = vector::mat_vec(pool, &placement, axis);
            let slide = vector::scale(pool, axis_in_parent, q);
            let offset = vector::add(pool, origin, slide);
            (
                placement,
                offset,
                Vec::new(),
                Some((coordinate.index(), axis, axis_in_parent, u)),
            )
        }
    };
    let c = to_parent;
    let to_child = |pool: &mut ExprPool, v: Vec3| vector::mat_t_vec(pool, &c, v);

    // Angular velocity and its partials.
    let parent_omega_here = to_child(pool, parent.omega);
    let mut partial_omega: Partials = parent
        .partial_omega
        .iter()
        .map(|&(r, w)| (r, to_child(pool, w)))
        .collect();
    let mut omega = parent_omega_here;
    let mut alpha_rest = to_child(pool, parent.alpha_rest);
    let mut spins = Vec::with_capacity(own_rotation.len());
    let zero = vector::zero(pool);
    let mut joint_partials = Vec::new();
    for (r, axis, u) in own_rotation {
        partial_omega.push((r, axis));
        joint_partials.push((r, axis, zero));
        spins.push(vector::scale(pool, axis, u));
    }
    if let Some(spin) = spins.into_iter().reduce(|a, b| vector::add(pool, a, b)) {
        omega = vector::add(pool, omega, spin);
        let transport = vector::cross(pool, parent_omega_here, spin);
        alpha_rest = vector::add(pool, alpha_rest, transport);
    }

    // Origin velocity partials: Cᵀ (V_p,r + W_p,r × d), plus the slide axis.
    let lever: Partials = parent
        .partial_omega
        .iter()
        .map(|&(r, w)| (r, vector::cross(pool, w, offset)))
        .collect();
    let mut partial_velocity: Partials = merge(pool, &parent.partial_velocity, &lever)
        .into_iter()
        .map(|(r, v)| (r, to_child(pool, v)))
        .collect();

    // Origin acceleration without u̇: Cᵀ (a_p + α_p × d + ω_p × (ω_p × d) + 2 ω_p × a_p u).
    let mut accel = accel_of_point(
        pool,
        parent.accel_rest,
        parent.alpha_rest,
        parent.omega,
        offset,
    );
    if let Some((r, axis, axis_in_parent, u)) = own_translation {
        partial_velocity.push((r, axis));
        joint_partials.push((r, zero, axis));
        let slide_rate = vector::scale(pool, axis_in_parent, u);
        let coriolis = vector::cross(pool, parent.omega, slide_rate);
        let coriolis = vector::scale_number(pool, coriolis, Number::int(2));
        accel = vector::add(pool, accel, coriolis);
    }
    let mut accel_rest = to_child(pool, accel);
    if let Some(speeds) = free_velocity {
        // d/dt in N of C v: Cᵀ ω_p × v (parent) + ω_k × v (k turning under v) + v̇.
        let axes = vector::identity(pool);
        for ((r, _), axis) in speeds.into_iter().zip(axes) {
            partial_velocity.push((r, axis));
            joint_partials.push((r, zero, axis));
        }
        let velocity = speeds.map(|(_, u)| u);
        let turning = vector::add(pool, parent_omega_here, omega);
        let transport = vector::cross(pool, turning, velocity);
        accel_rest = vector::add(pool, accel_rest, transport);
    }
    partial_velocity.sort_by_key(|&(r, _)| r);
    partial_omega.sort_by_key(|&(r, _)| r);
    joint_partials.sort_by_key(|&(r, _, _)| r);
    let gravity = to_child(pool, parent.gravity);

    FrameKinematics {
        parent: frame.parent,
        to_parent: c,
        offset,
        omega,
        partial_omega,
        partial_velocity,
        joint_partials,
        alpha_rest,
        accel_rest,
        gravity,
    }
}

/// Acceleration of a point fixed in a frame at `r`: `a_O + α × r + ω × (ω × r)`.
fn accel_of_point(pool: &mut ExprPool, accel: Vec3, alpha: Vec3, omega: Vec3, r: Vec3) -> Vec3 {
    let tangential = vector::cross(pool, alpha, r);
    let omega_r = vector::cross(pool, omega, r);
    let centripetal = vector::cross(pool, omega, omega_r);
    let sum = vector::add(pool, accel, tangential);
    vector::add(pool, sum, centripetal)
}

/// Sum of two sparse partial lists (sorted by speed index).
pub fn merge(pool: &mut ExprPool, a: &Partials, b: &Partials) -> Partials {
    let mut out: Partials = Vec::with_capacity(a.len().max(b.len()));
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        match (a.get(i), b.get(j)) {
            (Some(&(ra, va)), Some(&(rb, vb))) if ra == rb => {
                out.push((ra, vector::add(pool, va, vb)));
                i += 1;
                j += 1;
            }
            (Some(&(ra, va)), Some(&(rb, _))) if ra < rb => {
                out.push((ra, va));
                i += 1;
            }
            (Some(&(ra, va)), None) => {
                out.push((ra, va));
                i += 1;
            }
            (_, Some(&(rb, vb))) => {
                out.push((rb, vb));
                j += 1;
            }
            (None, None) => break,
        }
    }
    out
}
