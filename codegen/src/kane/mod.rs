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

mod composite;
pub mod constraints;
mod contact;
mod kinematics;
mod rates;
mod speeds;
pub mod vector;

use std::collections::BTreeMap;

use crate::ir::{self, Load, Model, OutputKind};
use crate::sym::{ExprId, ExprPool, Number, Symbol};
pub use kinematics::{lower_expr, lower_expr_with, Kinematics};
use rates::KinematicRates;
pub use speeds::{chosen_speeds_at_start, describe as describe_speeds};
use vector::Vec3;

/// The equations of motion of a model, ready for the back ends.
#[derive(Clone, Debug)]
pub struct Equations {
    pub pool: ExprPool,
    /// Number of generalized coordinates and speeds (equal without quaternions).
    pub nq: usize,
    pub nu: usize,
    /// The kinematic differential equations `q̇ = W(q) u`, length `nq`, where they are not
    /// `q̇ = u`: `None` for models without quaternions or Euler angles.
    pub kinematic_rates: Option<Vec<ExprId>>,
    /// `M(q)`, `nu × nu`, column-major; symmetric (`M[r + nu*s] == M[s + nu*r]`, same id).
    pub mass_matrix: Vec<ExprId>,
    /// `F(t, q, u, inputs)`, length `nu`.
    pub forcing: Vec<ExprId>,
    /// `F(t, q, 0, inputs)`: the forcing at rest, for statics (no velocity term of `F_r*`, no
    /// damper); `None` where a speed sits under a negative power (no value at `u = 0`).
    pub static_forcing: Option<Vec<ExprId>>,
    /// The contacts' damping `D ≈ ∂F/∂u` (`nu × nu`, column-major, symmetric negative
    /// semidefinite; [`contact::ContactState::add_damping`]): the stiff part of `F` that a
    /// linearly implicit integrator takes implicitly. `None` for models without contacts.
    pub contact_damping: Option<Vec<ExprId>>,
    /// Scalar outputs in declaration order (vector outputs expanded to `.x`, `.y`, `.z`).
    pub outputs: Vec<ExprId>,
    pub output_names: Vec<String>,
    /// Outputs that a simulation integrates, as `(target, rate)` indices into `outputs`: the
    /// target (0 in `outputs`) is sampled as `∫ rate dt` from the start of the run (a
    /// contact's dissipated energy; `Model::integrated_outputs` in the runtime).
    pub integrated_outputs: Vec<(usize, usize)>,
    /// Loop-closure rows: `φ(q)`, `J = ∂φ/∂q` (`nc × nq`, column-major) and `J̇u`; the
    /// velocity constraints' rows `A(q) u = 0` last (`φ` = 0, `J` rows `A`, bias `Ȧu`).
    pub constraints: constraints::Constraints,
    /// Flexures: their angles `θ(q)`, stiffness `k`, time-domain damping `b` and loss factor
    /// `η`, for frequency-domain analyses (complex stiffness `k(1 + iη)`).
    pub flexures: FlexureRows,
}

/// Per-flexure expressions, in `Model::flexures` order.
#[derive(Clone, Debug, Default)]
pub struct FlexureRows {
    pub names: Vec<String>,
    pub angles: Vec<ExprId>,
    pub stiffness: Vec<ExprId>,
    pub damping: Vec<ExprId>,
    pub loss_factor: Vec<ExprId>,
}

impl FlexureRows {
    /// `[θ…, k…, b…, η…]`, the layout of the generated `flexures` function.
    pub fn all(&self) -> Vec<ExprId> {
        [
            &self.angles,
            &self.stiffness,
            &self.damping,
            &self.loss_factor,
        ]
        .into_iter()
        .flatten()
        .copied()
        .collect()
    }
}

/// The angle, stiffness, damping and loss factor of every flexure.
fn flexure_rows(pool: &mut ExprPool, kinematics: &mut Kinematics, model: &Model) -> FlexureRows {
    let mut rows = FlexureRows::default();
    for flexure in &model.flexures {
        let angle = match flexure.angle {
            ir::FlexureAngle::Coordinate(c) => pool.symbol(Symbol::Coordinate(c.index() as u32)),
            angle => flexure_angle(pool, kinematics, model, angle),
        };
        rows.names.push(flexure.name.clone());
        rows.angles.push(angle);
        rows.stiffness.push(lower_expr(pool, &flexure.stiffness));
        rows.damping.push(lower_expr(pool, &flexure.damping));
        rows.loss_factor
            .push(lower_expr(pool, &flexure.loss_factor));
    }
    rows
}

/// `θ(q)` of a flexure angle.
fn flexure_angle(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    angle: ir::FlexureAngle,
) -> ExprId {
    use ir::FlexureAngle::{Coordinate, Loop, LoopLateral, LoopTwist};
    let closure = match angle {
        Coordinate(c) => return pool.symbol(Symbol::Coordinate(c.index() as u32)),
        Loop(closure) | LoopTwist(closure) | LoopLateral(closure) => closure,
    };
    let Some(geometry) = constraints::closure_geometry(pool, kinematics, model, closure) else {
        return pool.zero();
    };
    match angle {
        LoopTwist(_) => constraints::off_axis_angle(pool, &geometry, false),
        LoopLateral(_) => constraints::off_axis_angle(pool, &geometry, true),
        _ => constraints::relative_angle(pool, &geometry),
    }
}

/// The six offsets `s(q)` of a bushing's frame B from its frame A ([`Load::Bushing`]), in
/// A's basis: `d = C_Aᵀ (o_B − o_A)`, then `θ = vee(R − Rᵀ)/2` of `R = C_Aᵀ C_B`
/// (`R_ij = (column i of C_A)·(column j of C_B)`).
fn bushing_offsets(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    frames: [ir::Handle<ir::Frame>; 2],
) -> [ExprId; 6] {
    let (dcm_a, origin_a) = kinematics.to_newtonian(pool, frames[0]);
    let (dcm_b, origin_b) = kinematics.to_newtonian(pool, frames[1]);
    let apart = vector::sub(pool, origin_b, origin_a);
    let [dx, dy, dz] = vector::mat_t_vec(pool, &dcm_a, apart);
    let column = |c: &vector::Mat3, i: usize| [c[0][i], c[1][i], c[2][i]];
    let mut r = |i: usize, j: usize| vector::dot(pool, column(&dcm_a, i), column(&dcm_b, j));
    let pairs = [((2, 1), (1, 2)), ((0, 2), (2, 0)), ((1, 0), (0, 1))];
    let [tx, ty, tz] = pairs.map(|((i, j), (k, l))| (r(i, j), r(k, l)));
    let half = |pool: &mut ExprPool, (a, b): (ExprId, ExprId)| {
        let difference = pool.sub(a, b);
        pool.scale(difference, Number::rational(1, 2))
    };
    let (tx, ty, tz) = (half(pool, tx), half(pool, ty), half(pool, tz));
    [dx, dy, dz, tx, ty, tz]
}

/// A bushing's six springs: each offset `s` ([`bushing_offsets`]) with its stiffness `k` and
/// damping `c`. The laws are lowered before the offsets: the order fixes the pool's
/// numbering, and with it the generated code.
fn bushing_springs(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    frames: [ir::Handle<ir::Frame>; 2],
    stiffness: &[ir::Vec3; 2],
    damping: &[ir::Vec3; 2],
) -> [(ExprId, ExprId, ExprId); 6] {
    let six = |pool: &mut ExprPool, v: &[ir::Vec3; 2]| {
        let [a, b, c] = kinematics::lower_vec(pool, &v[0]);
        let [d, e, f] = kinematics::lower_vec(pool, &v[1]);
        [a, b, c, d, e, f]
    };
    let (k, c) = (six(pool, stiffness), six(pool, damping));
    let s = bushing_offsets(pool, kinematics, frames);
    std::array::from_fn(|i| (s[i], k[i], c[i]))
}

impl Equations {
    /// Number of constraint rows `NC` (redundant rows and velocity rows included).
    pub fn nc(&self) -> usize {
        self.constraints.residual.len()
    }
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

/// The symmetric inertia matrix from tensor entries.
fn inertia_matrix(pool: &mut ExprPool, inertia: &ir::Inertia) -> [[ExprId; 3]; 3] {
    let [xx, yy, zz, xy, yz, zx] = inertia.entries().map(|e| lower_expr(pool, e));
    [[xx, xy, zx], [xy, yy, yz], [zx, yz, zz]]
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

/// The line of a point-to-point spring between `ends = [A, B]`, in N's basis.
struct SpringLine {
    /// `L = |r_B − r_A|`.
    length: ExprId,
    /// `ê·∂(v_B − v_A)/∂u_r = ∂L/∂q_r` for every speed r that moves an end (`ê = d/L`).
    stretch_rates: Vec<(usize, ExprId)>,
}

/// `d = r_B − r_A` and `L = |d|` of a spring's ends, in N (positions from [`point_position`]).
fn spring_length(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    ends: [ir::Handle<ir::Point>; 2],
) -> (Vec3, ExprId) {
    let [a, b] = ends.map(|end| point_position(pool, kinematics, &model.points[end]));
    let d = vector::sub(pool, b, a);
    let square = vector::dot(pool, d, d);
    (d, pool.sqrt(square))
}

/// `∂(v_B − v_A)/∂u_r` of two points `ends = [A, B]`, in N's basis ([`relative_partials_at`]).
fn relative_partials(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    ends: [ir::Handle<ir::Point>; 2],
) -> kinematics::Partials {
    relative_partials_at(pool, kinematics, |pool, end| {
        let point = &model.points[ends[end]];
        (point.frame, kinematics::lower_vec(pool, &point.position))
    })
}

/// `∂(v_B − v_A)/∂u_r` of two points A (`end(pool, 0)`) and B (`end(pool, 1)`), each given by
/// the frame it is fixed in and its offset in that frame's basis, in N's basis: the partial
/// velocities of each end (B with `+`, A with `−`, each from [`Kinematics::point_partials`]
/// re-expressed in N). Each end is built when its turn comes (B first), the order the pool
/// numbers them in.
fn relative_partials_at(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    mut end: impl FnMut(&mut ExprPool, usize) -> (ir::Handle<ir::Frame>, Vec3),
) -> kinematics::Partials {
    let mut relative: kinematics::Partials = Vec::new();
    for (index, sign) in [(1, Number::ONE), (0, Number::MINUS_ONE)] {
        let (frame, offset) = end(pool, index);
        let partials: kinematics::Partials = kinematics
            .point_partials(pool, frame, offset)
            .into_iter()
            .map(|(r, v)| {
                let v = kinematics.express(pool, v, frame, Model::NEWTONIAN);
                (r, vector::scale_number(pool, v, sign))
            })
            .collect();
        relative = kinematics::merge(pool, &relative, &partials);
    }
    relative
}

impl SpringLine {
    /// `ê` from the ends' positions, and the ends' relative partial velocities projected on it.
    fn new(
        pool: &mut ExprPool,
        kinematics: &mut Kinematics,
        model: &Model,
        ends: [ir::Handle<ir::Point>; 2],
    ) -> SpringLine {
        let (d, length) = spring_length(pool, kinematics, model, ends);
        let inverse = pool.pow(length, Number::MINUS_ONE);
        let direction = vector::scale(pool, d, inverse);
        let relative = relative_partials(pool, kinematics, model, ends);
        let stretch_rates = relative
            .into_iter()
            .map(|(r, v)| (r, vector::dot(pool, direction, v)))
            .collect();
        SpringLine {
            length,
            stretch_rates,
        }
    }

    /// `L̇ = ê·(v_B − v_A) = Σ_r (ê·∂(v_B − v_A)/∂u_r) u_r`.
    fn stretch_speed(&self, pool: &mut ExprPool) -> ExprId {
        let terms: Vec<ExprId> = self
            .stretch_rates
            .iter()
            .map(|&(r, rate)| {
                let u = pool.symbol(Symbol::Speed(r as u32));
                pool.mul(rate, u)
            })
            .collect();
        pool.add_all(&terms)
    }
}

/// Lowers an expression of a load or output: its [`ir::StateTerm`]s become the coordinate
/// and speed symbols, a distance `L = |r_B − r_A|`, its rate `L̇ = ê·(v_B − v_A)`, or the
/// energies, from the kinematics.
pub fn lower_state_expr(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    expr: &ir::Expr,
) -> ExprId {
    lower_expr_with(pool, expr, &mut |pool, term| match term {
        ir::StateTerm::Coordinate(c) => pool.symbol(Symbol::Coordinate(c.index() as u32)),
        ir::StateTerm::Speed(c) => pool.symbol(Symbol::Speed(c.index() as u32)),
        ir::StateTerm::Distance(ends) => spring_length(pool, kinematics, model, ends).1,
        ir::StateTerm::DistanceRate(ends) => {
            SpringLine::new(pool, kinematics, model, ends).stretch_speed(pool)
        }
        ir::StateTerm::KineticEnergy => kinetic_energy(pool, kinematics, model),
        ir::StateTerm::PotentialEnergy => potential_energy(pool, kinematics, model),
    })
}

/// [`lower_state_expr`] of each component.
fn lower_state_vec(
    pool: &mut ExprPool,
    kinematics: &mut Kinematics,
    model: &Model,
    v: &ir::Vec3,
) -> Vec3 {
    [
        lower_state_expr(pool, kinematics, model, &v[0]),
        lower_state_expr(pool, kinematics, model, &v[1]),
        lower_state_expr(pool, kinematics, model, &v[2]),
    ]
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
            let torque = |pool: &mut ExprPool,
                          _: &mut Kinematics,
                          geometry: &constraints::RevoluteGeometry| {
                let moment = spring_moment(pool, stiffness, rest, |pool| {
                    constraints::relative_angle(pool, geometry)
                });
                pool.neg(moment)
            };
            constraints::closure_torque_forces(pool, kinematics, model, *closure, torque, forcing);
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
                          geometry: &constraints::RevoluteGeometry| {
                let c = lower_expr(pool, damping);
                let rate = constraints::relative_rate(pool, kinematics, model, *closure, geometry);
                let moment = pool.mul(c, rate);
                pool.neg(moment)
            };
            constraints::closure_torque_forces(pool, kinematics, model, *closure, torque, forcing);
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

/// Position of a point from the Newtonian origin, in N's basis.
fn point_position(pool: &mut ExprPool, kinematics: &mut Kinematics, point: &ir::Point) -> Vec3 {
    let (dcm, origin) = kinematics.to_newtonian(pool, point.frame);
    let offset = kinematics::lower_vec(pool, &point.position);
    let offset = vector::mat_vec(pool, &dcm, offset);
    vector::add(pool, origin, offset)
}

/// `Σ_r partial_r · u_r`.
fn combine_partials(pool: &mut ExprPool, partials: &kinematics::Partials) -> Vec3 {
    let mut total = vector::zero(pool);
    for &(r, v) in partials {
        let u = pool.symbol(Symbol::Speed(r as u32));
        let term = vector::scale(pool, v, u);
        total = vector::add(pool, total, term);
    }
    total
}

/// `½ Σ_bodies (m v_G·v_G + ω·I ω)`.
fn kinetic_energy(pool: &mut ExprPool, kinematics: &Kinematics, model: &Model) -> ExprId {
    let mut terms = Vec::new();
    for (_, body) in model.bodies.iter() {
        let mass = lower_expr(pool, &body.mass);
        let com = kinematics::lower_vec(pool, &body.center_of_mass);
        let partials = kinematics.point_partials(pool, body.frame, com);
        let v = combine_partials(pool, &partials);
        let omega = kinematics.frames[body.frame.index()].omega;
        let inertia = inertia_matrix(pool, &body.inertia);
        let i_omega = vector::mat_vec(pool, &inertia, omega);
        let v2 = vector::dot(pool, v, v);
        terms.push(pool.mul(mass, v2));
        terms.push(vector::dot(pool, omega, i_omega));
    }
    let twice = pool.add_all(&terms);
    pool.scale(twice, Number::rational(1, 2))
}

/// `−Σ_bodies m g·r_G + Σ_springs ½ k (x − rest)²`, x a joint coordinate, a closure or
/// flexure angle, or a point-to-point spring's length, plus each contact's
/// `k δ^(e+1)/(e+1)` and each bushing's `½ Σ k s²`.
fn potential_energy(pool: &mut ExprPool, kinematics: &mut Kinematics, model: &Model) -> ExprId {
    let mut terms = Vec::new();
    let gravity = kinematics.frames[ir::Model::NEWTONIAN.index()].gravity;
    for (_, body) in model.bodies.iter() {
        let mass = lower_expr(pool, &body.mass);
        let (dcm, origin) = kinematics.to_newtonian(pool, body.frame);
        let com = kinematics::lower_vec(pool, &body.center_of_mass);
        let com = vector::mat_vec(pool, &dcm, com);
        let position = vector::add(pool, origin, com);
        let height_work = vector::dot(pool, gravity, position);
        let work = pool.mul(mass, height_work);
        terms.push(pool.neg(work));
    }
    for load in &model.loads {
        // ½ k (x − rest)² for joint springs (x = q), closure and angle springs (x = θ),
        // point-to-point springs (x = L).
        let (stiffness, rest, stretched) = match load {
            Load::Spring {
                coordinate,
                stiffness,
                rest,
                ..
            } => (
                stiffness,
                rest,
                pool.symbol(Symbol::Coordinate(coordinate.index() as u32)),
            ),
            Load::LoopSpring {
                closure,
                stiffness,
                rest,
                ..
            } => {
                let Some(geometry) =
                    constraints::closure_geometry(pool, kinematics, model, *closure)
                else {
                    continue;
                };
                (
                    stiffness,
                    rest,
                    constraints::relative_angle(pool, &geometry),
                )
            }
            Load::AngleSpring {
                angle,
                stiffness,
                rest,
                ..
            } => (
                stiffness,
                rest,
                flexure_angle(pool, kinematics, model, *angle),
            ),
            Load::PointSpring {
                ends,
                stiffness,
                rest_length,
                ..
            } => (
                stiffness,
                rest_length,
                spring_length(pool, kinematics, model, *ends).1,
            ),
            Load::Contact { .. } => {
                if let Some(contact) = contact::ContactState::new(pool, kinematics, model, load) {
                    terms.push(contact.energy);
                }
                continue;
            }
            Load::Bushing {
                frames,
                stiffness,
                damping,
                ..
            } => {
                // ½ Σ k s².
                for (s, k, _) in bushing_springs(pool, kinematics, *frames, stiffness, damping) {
                    let square = pool.pow(s, Number::int(2));
                    let energy = pool.mul(k, square);
                    terms.push(pool.scale(energy, Number::rational(1, 2)));
                }
                continue;
            }
            _ => continue,
        };
        let k = lower_expr(pool, stiffness);
        let rest = lower_expr(pool, rest);
        let stretch = pool.sub(stretched, rest);
        let square = pool.pow(stretch, Number::int(2));
        let energy = pool.mul(k, square);
        terms.push(pool.scale(energy, Number::rational(1, 2)));
    }
    pool.add_all(&terms)
}

#[cfg(test)]
mod tests;
