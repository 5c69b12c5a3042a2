//! Kane's method on hand-built IR models with closed-form equations of motion.

use super::*;
use crate::diag::Span;
use crate::ir::{Body, Coordinate, Dimension, Expr, Frame, Handle, Motion, Param};

fn param(model: &mut Model, name: &str, value: f64) -> Expr {
    let handle = model.params.append(Param {
        name: name.to_string(),
        value,
        dimension: Dimension::NONE,
        docs: Vec::new(),
        span: Span::default(),
    });
    Expr::Param(handle)
}

fn zero3() -> [Expr; 3] {
    [Expr::zero(), Expr::zero(), Expr::zero()]
}

fn axis(i: usize) -> [Expr; 3] {
    let mut a = zero3();
    a[i] = Expr::one();
    a
}

fn coordinate(model: &mut Model, name: &str) -> Handle<Coordinate> {
    model.coordinates.append(Coordinate {
        name: name.to_string(),
        dimension: Dimension::NONE,
        initial: 0.0,
        initial_speed: 0.0,
        span: Span::default(),
    })
}

fn frame(
    model: &mut Model,
    name: &str,
    parent: Handle<Frame>,
    origin: [Expr; 3],
    motion: Motion,
) -> Handle<Frame> {
    model.frames.append(Frame {
        name: name.to_string(),
        parent: Some(parent),
        origin,
        orientation: Vec::new(),
        motion,
        span: Span::default(),
    })
}

fn point_mass(model: &mut Model, name: &str, frame: Handle<Frame>, mass: Expr) {
    model
        .bodies
        .append(Body::point_mass(name.to_string(), frame, mass));
}

/// Hangs a bob of mass `m` on a massless rod of length `l` from a pin about z in `parent` (its
/// coordinate and frame both named `pin`), under gravity −g y.
fn hang_bob(model: &mut Model, parent: Handle<Frame>, pin: &str, m: Expr, l: Expr, g: Expr) {
    let q = coordinate(model, pin);
    let revolute = Motion::Revolute {
        axis: axis(2),
        coordinate: q,
    };
    let pin = frame(model, pin, parent, zero3(), revolute);
    let rod = [Expr::zero(), Expr::Neg(Box::new(l)), Expr::zero()];
    let bob = frame(model, "bob", pin, rod, Motion::Fixed);
    point_mass(model, "bob", bob, m);
    model.gravity = Some([Expr::zero(), Expr::Neg(Box::new(g)), Expr::zero()]);
}

/// A bob of mass m on a massless rod of length l, pinned about z, gravity −g y.
fn pendulum() -> Model {
    let mut model = Model::new("pendulum");
    let m = param(&mut model, "m", 1.0);
    let l = param(&mut model, "l", 1.0);
    let g = param(&mut model, "g", 9.81);
    hang_bob(&mut model, Model::NEWTONIAN, "hinge", m, l, g);
    model
}

/// `id` is the expression `expected` (hash-consing makes structural equality an id comparison).
fn assert_is(pool: &mut ExprPool, id: ExprId, expected: &str) {
    let expected_id = pool.parse_sexpr(expected).unwrap();
    assert_eq!(id, expected_id, "{} is not {expected}", pool.sexpr(id));
}

#[test]
fn simple_pendulum_is_exact() {
    let mut eqs = derive(&pendulum());
    assert_is(&mut eqs.pool, eqs.mass_matrix[0], "(* m (^ l 2))");
    assert_is(&mut eqs.pool, eqs.forcing[0], "(* -1 m g l (sin q_hinge))");
}

/// A cart (mass M) on a slider along x carrying a pendulum bob (mass m, length l):
/// M = [[M + m, m l cos θ], [m l cos θ, m l²]], F = [m l θ̇² sin θ, −m g l sin θ].
#[test]
fn cart_pendulum_matches_closed_form() {
    let mut model = Model::new("cart_pendulum");
    let cart_mass = param(&mut model, "M", 2.0);
    let m = param(&mut model, "m", 0.5);
    let l = param(&mut model, "l", 0.8);
    let g = param(&mut model, "g", 9.81);
    let x = coordinate(&mut model, "x");
    let cart = frame(
        &mut model,
        "cart",
        Model::NEWTONIAN,
        zero3(),
        Motion::Prismatic {
            axis: axis(0),
            coordinate: x,
        },
    );
    point_mass(&mut model, "cart", cart, cart_mass);
    hang_bob(&mut model, cart, "theta", m, l, g);
    let eqs = derive(&model);

    let (q, u) = ([0.3, -0.7], [0.4, 1.3]);
    let value_of = |s: Symbol| match s {
        Symbol::Coordinate(i) => q[i as usize],
        Symbol::Speed(i) => u[i as usize],
        Symbol::Param(i) => [2.0, 0.5, 0.8, 9.81][i as usize],
        _ => f64::NAN,
    };
    let mm = eqs.pool.eval(&eqs.mass_matrix, &value_of);
    let f = eqs.pool.eval(&eqs.forcing, &value_of);
    let (big_m, m, l, g, th, thd) = (2.0, 0.5, 0.8, 9.81_f64, -0.7_f64, 1.3_f64);
    let expected_m = [big_m + m, m * l * th.cos(), m * l * th.cos(), m * l * l];
    let expected_f = [m * l * thd * thd * th.sin(), -m * g * l * th.sin()];
    for (a, b) in mm.iter().zip(expected_m) {
        assert!((a - b).abs() < 1e-14, "M: {mm:?} vs {expected_m:?}");
    }
    for (a, b) in f.iter().zip(expected_f) {
        assert!((a - b).abs() < 1e-14, "F: {f:?} vs {expected_f:?}");
    }
}
