//! The model IR: a checked, name-resolved mechanism as plain data.
//!
//! Consumes: nothing (built by `front::lower`, rewritten by later model transformations).
//! Produces: the input of `kane::derive` and of the back ends' naming.
//!
//! # Invariants (established by `front::lower`, relied on by every later phase)
//! - `frames[Model::NEWTONIAN]` is the Newtonian frame, the only frame without a parent.
//! - Every other frame's `parent` comes *before* it in the arena, so a forward scan visits
//!   parents first (the kinematic tree in topological order). A tree joint is nothing but a
//!   frame with a [`Motion`]; a body is attached to one frame; massless frames are allowed.
//! - Each coordinate is driven by exactly one frame's motion; `u_i = q̇_i`.
//! - Each quaternion (`Model::quaternions`) drives exactly one spherical or free motion. The
//!   state is laid out as `q = [coordinates…; quaternions, 4 each, scalar first…]` and
//!   `u = [coordinate speeds…; angular speeds, 3 each…]` ([`Model::quaternion_coordinate`],
//!   [`Model::angular_speed`]), so a coordinate's index addresses both `q` and `u`. Euler
//!   angles (`Model::euler_angles`, each one [`Rotation::Euler`] of a motion) follow, three
//!   coordinates and three angular speeds each ([`Model::euler_coordinate`],
//!   [`Model::euler_speed`]). The positions of free joints (`Model::translations`, each
//!   driven by one [`Motion::Free`]) come last, three coordinates and three speeds each
//!   ([`Model::translation_coordinate`], [`Model::translation_speed`]): the coordinates with
//!   `q̇ = u` are a prefix of `q`.
//! - All expressions are dimensionally consistent and in SI units (kg, m, s, rad, A).
//! - Joint axes have unit length.
//! - Loop closures (`Model::loops`) are additional constraints between two points or
//!   frames of the tree; they never change the tree itself.
//!
//! Model transformations (adding a twist axis to a hinge, say) insert frames and coordinates;
//! since derivation only ever walks frames in arena order, the result must keep parents first.

pub mod arena;
pub mod plausible;
pub mod transform;

pub use arena::{Arena, Handle};
pub use plausible::{Implausible, Requirement};

use crate::diag::Span;
use crate::sym::Number;

/// Physical dimension as integer exponents of the SI base quantities used by mechanisms.
/// Angles are dimensionless (rad = 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct Dimension {
    pub mass: i8,
    pub length: i8,
    pub time: i8,
    pub current: i8,
}

// Named like the arithmetic they mirror (dimension of a product, a quotient, a power).
#[allow(clippy::should_implement_trait)]
impl Dimension {
    pub const NONE: Dimension = Dimension {
        mass: 0,
        length: 0,
        time: 0,
        current: 0,
    };
    pub const MASS: Dimension = Dimension {
        mass: 1,
        ..Dimension::NONE
    };
    pub const LENGTH: Dimension = Dimension {
        length: 1,
        ..Dimension::NONE
    };
    pub const TIME: Dimension = Dimension {
        time: 1,
        ..Dimension::NONE
    };
    pub const CURRENT: Dimension = Dimension {
        current: 1,
        ..Dimension::NONE
    };
    /// kg·m/s²
    pub const FORCE: Dimension = Dimension {
        mass: 1,
        length: 1,
        time: -2,
        current: 0,
    };
    /// kg·m²/s² (also a torque, and a rotational stiffness N·m/rad)
    pub const TORQUE: Dimension = Dimension {
        mass: 1,
        length: 2,
        time: -2,
        current: 0,
    };
    /// kg·m²
    pub const INERTIA: Dimension = Dimension {
        mass: 1,
        length: 2,
        time: 0,
        current: 0,
    };
    pub const ACCELERATION: Dimension = Dimension {
        mass: 0,
        length: 1,
        time: -2,
        current: 0,
    };
    /// J = kg·m²/s², the dimension of a torque.
    pub const ENERGY: Dimension = Dimension::TORQUE;
    /// m/s.
    pub const VELOCITY: Dimension = Dimension {
        length: 1,
        time: -1,
        ..Dimension::NONE
    };
    /// V = kg·m²/(s³·A)
    pub const VOLTAGE: Dimension = Dimension {
        mass: 1,
        length: 2,
        time: -3,
        current: -1,
    };
    /// Hz = 1/s
    pub const FREQUENCY: Dimension = Dimension {
        time: -1,
        ..Dimension::NONE
    };
    /// Pa = kg/(m·s²), also a Young's modulus.
    pub const PRESSURE: Dimension = Dimension {
        mass: 1,
        length: -1,
        time: -2,
        current: 0,
    };

    pub fn mul(self, other: Dimension) -> Dimension {
        Dimension {
            mass: self.mass + other.mass,
            length: self.length + other.length,
            time: self.time + other.time,
            current: self.current + other.current,
        }
    }
    pub fn div(self, other: Dimension) -> Dimension {
        self.mul(other.powi(-1))
    }
    pub fn powi(self, n: i8) -> Dimension {
        Dimension {
            mass: self.mass * n,
            length: self.length * n,
            time: self.time * n,
            current: self.current * n,
        }
    }
}

impl Dimension {
    /// The conventional derived unit of this dimension where it has one (`N` rather than
    /// `kg*m/s^2`, `V` rather than `kg*m^2/s^3/A`), as the language writes it.
    pub fn conventional_unit(self) -> Option<&'static str> {
        let per = |a: Dimension, b: Dimension| a.div(b);
        let named = [
            (Dimension::FORCE, "N"),
            (Dimension::TORQUE, "N*m"),
            (Dimension::LENGTH, "m"),
            (Dimension::MASS, "kg"),
            (Dimension::TIME, "s"),
            (Dimension::CURRENT, "A"),
            (Dimension::FREQUENCY, "Hz"),
            (Dimension::ACCELERATION, "m/s^2"),
            (Dimension::VOLTAGE, "V"),
            (Dimension::PRESSURE, "Pa"),
            (Dimension::INERTIA, "kg*m^2"),
            (per(Dimension::FORCE, Dimension::LENGTH), "N/m"),
            (
                per(Dimension::FORCE.mul(Dimension::TIME), Dimension::LENGTH),
                "N*s/m",
            ),
            (Dimension::TORQUE.mul(Dimension::TIME), "N*m*s"),
            (per(Dimension::TORQUE, Dimension::TIME), "W"),
            (per(Dimension::FORCE, Dimension::VOLTAGE), "N/V"),
            (per(Dimension::LENGTH, Dimension::VOLTAGE), "m/V"),
        ];
        named
            .iter()
            .find(|(dimension, _)| *dimension == self)
            .map(|(_, unit)| *unit)
    }
}

impl std::fmt::Display for Dimension {
    /// The conventional unit where there is one (`N`, `V`, `N*m`, …), else the `kg*m/s^2`-style
    /// SI form; `1` for dimensionless.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if let Some(unit) = self.conventional_unit() {
            return write!(f, "{unit}");
        }
        let parts = [
            ("kg", self.mass),
            ("m", self.length),
            ("s", self.time),
            ("A", self.current),
        ];
        let mut numerator = Vec::new();
        let mut denominator = Vec::new();
        for (unit, exponent) in parts {
            let side = if exponent > 0 {
                &mut numerator
            } else {
                &mut denominator
            };
            match exponent.abs() {
                0 => {}
                1 => side.push(unit.to_string()),
                e => side.push(format!("{unit}^{e}")),
            }
        }
        let top = if numerator.is_empty() {
            "1".to_string()
        } else {
            numerator.join("*")
        };
        match denominator.len() {
            0 => write!(f, "{top}"),
            _ => write!(f, "{top}/{}", denominator.join("/")),
        }
    }
}

/// A scalar expression over parameters, inputs, time and (in loads and outputs) the state,
/// as written in the model (after name resolution, unit scaling and dimension checking).
/// `let` definitions are inlined.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    Number(Number),
    Param(Handle<Param>),
    Input(Handle<Input>),
    /// Simulation time `t`, in s.
    Time,
    /// A quantity of the motion; only in forces, torques and outputs (the front end checks).
    State(StateTerm),
    Pi,
    Neg(Box<Expr>),
    Add(Box<Expr>, Box<Expr>),
    Sub(Box<Expr>, Box<Expr>),
    Mul(Box<Expr>, Box<Expr>),
    Div(Box<Expr>, Box<Expr>),
    /// Power with a constant exponent (integer, or a rational such as 1/2).
    Pow(Box<Expr>, Number),
    Call(Function, Vec<Expr>),
}

impl Expr {
    pub fn number(value: Number) -> Expr {
        Expr::Number(value)
    }
    pub fn zero() -> Expr {
        Expr::Number(Number::ZERO)
    }
    pub fn one() -> Expr {
        Expr::Number(Number::ONE)
    }

    /// Whether a param appears in it.
    pub fn has_params(&self) -> bool {
        match self {
            Expr::Param(_) => true,
            Expr::Number(_) | Expr::Pi | Expr::Input(_) | Expr::Time | Expr::State(_) => false,
            Expr::Neg(a) | Expr::Pow(a, _) => a.has_params(),
            Expr::Add(a, b) | Expr::Sub(a, b) | Expr::Mul(a, b) | Expr::Div(a, b) => {
                a.has_params() || b.has_params()
            }
            Expr::Call(_, args) => args.iter().any(Expr::has_params),
        }
    }

    /// The value with the params at `params` (SI, by index); `None` if it depends on an input,
    /// time or the state.
    pub fn evaluate(&self, params: &[f64]) -> Option<f64> {
        let eval = |e: &Expr| e.evaluate(params);
        Some(match self {
            Expr::Number(n) => n.to_f64(),
            Expr::Pi => std::f64::consts::PI,
            Expr::Param(handle) => *params.get(handle.index())?,
            Expr::Input(_) | Expr::Time | Expr::State(_) => return None,
            Expr::Neg(a) => -eval(a)?,
            Expr::Add(a, b) => eval(a)? + eval(b)?,
            Expr::Sub(a, b) => eval(a)? - eval(b)?,
            Expr::Mul(a, b) => eval(a)? * eval(b)?,
            Expr::Div(a, b) => eval(a)? / eval(b)?,
            Expr::Pow(a, e) => match e.as_integer().and_then(|e| i32::try_from(e).ok()) {
                Some(e) => eval(a)?.powi(e),
                None => eval(a)?.powf(e.to_f64()),
            },
            Expr::Call(f, args) => {
                let values: Option<Vec<f64>> = args.iter().map(eval).collect();
                f.apply(&values?)
            }
        })
    }
}

/// A quantity of the motion that an expression may use (`hinge.q`, `distance(a, b)`,
/// `kinetic_energy`, …): the kinematics lowers it (`kane::lower_state_expr`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StateTerm {
    /// The coordinate `q` of a pin or slider.
    Coordinate(Handle<Coordinate>),
    /// Its speed `u = q̇`.
    Speed(Handle<Coordinate>),
    /// `L = |r_B − r_A|` of two points `[A, B]`, in m.
    Distance([Handle<Point>; 2]),
    /// `L̇ = ê·(v_B − v_A)`, `ê = (r_B − r_A)/L`, in m/s.
    DistanceRate([Handle<Point>; 2]),
    /// The total kinetic energy (outputs only).
    KineticEnergy,
    /// The potential energy as [`OutputKind::PotentialEnergy`] (outputs only).
    PotentialEnergy,
}

// Operators build the node as written, without folding constants: the closed forms of
// `crate::physics` are written once for `f64` and for `Expr` through them.
macro_rules! expr_operator {
    ($($trait:ident $method:ident $variant:ident),*) => {$(
        impl std::ops::$trait for Expr {
            type Output = Expr;
            fn $method(self, other: Expr) -> Expr {
                Expr::$variant(Box::new(self), Box::new(other))
            }
        }
    )*};
}
expr_operator!(Add add Add, Sub sub Sub, Mul mul Mul, Div div Div);

/// Elementary functions allowed in expressions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Function {
    Sin,
    Cos,
    Tan,
    Sqrt,
    Exp,
    Ln,
    Abs,
    Atan2,
}

impl Function {
    pub fn name(self) -> &'static str {
        match self {
            Function::Sin => "sin",
            Function::Cos => "cos",
            Function::Tan => "tan",
            Function::Sqrt => "sqrt",
            Function::Exp => "exp",
            Function::Ln => "ln",
            Function::Abs => "abs",
            Function::Atan2 => "atan2",
        }
    }
    /// The function at `args` (NaN for a missing argument).
    pub fn apply(self, args: &[f64]) -> f64 {
        let x = args.first().copied().unwrap_or(f64::NAN);
        match self {
            Function::Sin => x.sin(),
            Function::Cos => x.cos(),
            Function::Tan => x.tan(),
            Function::Sqrt => x.sqrt(),
            Function::Exp => x.exp(),
            Function::Ln => x.ln(),
            Function::Abs => x.abs(),
            Function::Atan2 => x.atan2(args.get(1).copied().unwrap_or(f64::NAN)),
        }
    }
    pub fn arity(self) -> usize {
        if self == Function::Atan2 {
            2
        } else {
            1
        }
    }
}

/// Components of a vector in a frame's basis: `x·frame.x + y·frame.y + z·frame.z`.
pub type Vec3 = [Expr; 3];

/// A vector together with the frame its components are expressed in.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameVector {
    pub frame: Handle<Frame>,
    pub components: Vec3,
}

/// A parameter: a named constant, settable at run time (default from the model).
#[derive(Clone, Debug, PartialEq)]
pub struct Param {
    pub name: String,
    /// Default value in SI units.
    pub value: f64,
    pub dimension: Dimension,
    pub docs: Vec<String>,
    pub span: Span,
}

/// A named time signal supplied at run time (constant, sine, chirp, CSV column, ...).
#[derive(Clone, Debug, PartialEq)]
pub struct Input {
    pub name: String,
    /// Value used when no signal is given, in SI units.
    pub default: f64,
    pub dimension: Dimension,
    pub docs: Vec<String>,
    pub span: Span,
}

/// A generalized coordinate `q_i` with its speed `u_i = q̇_i`.
#[derive(Clone, Debug, PartialEq)]
pub struct Coordinate {
    /// Name of the coordinate (by default the joint's name; `hinge` for a pin `hinge`).
    pub name: String,
    /// `Dimension::NONE` for angles (rad), `Dimension::LENGTH` for slides (m).
    pub dimension: Dimension,
    /// Initial value `q0` in SI units.
    pub initial: f64,
    /// Initial speed `u0` in SI units.
    pub initial_speed: f64,
    pub span: Span,
}

/// The orientation of a spherical motion relative to its parent: a unit quaternion
/// `e = (e₀, e₁, e₂, e₃)`, scalar first, with speeds the measure numbers of the frame's
/// angular velocity relative to the parent, in the frame's own basis, and `ė = ½ e ⊗ (0, ω)`.
/// It starts at the identity rotation.
#[derive(Clone, Debug, PartialEq)]
pub struct Quaternion {
    /// The joint's name; its coordinates are `NAME.e0` … `NAME.e3`, its speeds `NAME.wx` …
    /// `NAME.wz`.
    pub name: String,
    /// Initial angular velocity relative to the parent, in rad/s, components in the frame.
    pub initial_angular_velocity: [f64; 3],
    pub span: Span,
}

/// The angular speeds of a quaternion or a set of Euler angles: the measure numbers of the
/// frame's angular velocity along its own x, y, z.
const ANGULAR_SPEEDS: [&str; 3] = ["wx", "wy", "wz"];

/// `NAME.part` for each part: the names of a joint's coordinates or speeds.
fn member_names<const N: usize>(joint: &str, parts: [&str; N]) -> [String; N] {
    parts.map(|part| format!("{joint}.{part}"))
}

impl Quaternion {
    /// Names of the four coordinates, scalar first.
    pub fn coordinate_names(&self) -> [String; 4] {
        member_names(&self.name, ["e0", "e1", "e2", "e3"])
    }
    /// Names of the three angular speeds.
    pub fn speed_names(&self) -> [String; 3] {
        member_names(&self.name, ANGULAR_SPEEDS)
    }
}

/// The orientation of a spherical motion relative to its parent as three body-fixed
/// (intrinsic) angles, `rotation = euler(zxy)`: the frame is turned by `angle1` about the
/// sequence's first axis, then by `angle2` about the second axis of the frame so turned, then by
/// `angle3` about the third, `C = R(a₁, q₁) R(a₂, q₂) R(a₃, q₃)`. Its speeds are those of a
/// [`Quaternion`] (the angular velocity relative to the parent, in the frame's own basis), so
/// `q̇ = W(q) u` with `W` singular where the sequence is (`cos q₂ = 0` for the six sequences of
/// three different axes, `sin q₂ = 0` for the six that repeat the first).
#[derive(Clone, Debug, PartialEq)]
pub struct EulerAngles {
    /// The joint's name; its coordinates are `NAME.angle1` … `NAME.angle3`, its speeds
    /// `NAME.wx` … `NAME.wz`.
    pub name: String,
    /// The axes (0 = x) of the three turns; consecutive axes differ.
    pub sequence: [usize; 3],
    /// Initial angles, rad.
    pub initial_angles: [f64; 3],
    /// Initial angular velocity relative to the parent, in rad/s, components in the frame.
    pub initial_angular_velocity: [f64; 3],
    pub span: Span,
}

impl EulerAngles {
    /// Names of the three angles, in the order of the sequence.
    pub fn coordinate_names(&self) -> [String; 3] {
        member_names(&self.name, ["angle1", "angle2", "angle3"])
    }
    /// Names of the three angular speeds.
    pub fn speed_names(&self) -> [String; 3] {
        member_names(&self.name, ANGULAR_SPEEDS)
    }
    /// `Cᵀ v` at the initial angles: components in the turned frame of `v`, given in the
    /// frame's placement (`C = R(a₁, q₁) R(a₂, q₂) R(a₃, q₃)`, each `R` by Rodrigues' formula).
    pub fn initially_seen_from_frame(&self, v: [f64; 3]) -> [f64; 3] {
        let mut v = v;
        for (axis, angle) in self.sequence.into_iter().zip(self.initial_angles) {
            // Rᵀ(a, θ) v = v cos θ − (a × v) sin θ + a (a·v)(1 − cos θ), a a unit axis.
            let (sin, cos) = angle.sin_cos();
            let (next, after) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut turned = v.map(|x| x * cos);
            turned[axis] = v[axis];
            turned[next] += v[after] * sin;
            turned[after] -= v[next] * sin;
            v = turned;
        }
        v
    }
    /// The sequence as written: `zxy`.
    pub fn sequence_name(&self) -> String {
        self.sequence
            .iter()
            .map(|&axis| ["x", "y", "z"][axis])
            .collect()
    }
    /// Whether the sequence repeats its first axis (`zxz`: proper Euler angles, singular where
    /// `sin q₂ = 0`) rather than using three different axes (`zxy`: Tait–Bryan angles,
    /// singular where `cos q₂ = 0`).
    pub fn is_proper(&self) -> bool {
        self.sequence[0] == self.sequence[2]
    }
}

/// The position of a `free` joint's child relative to the joint frame: three coordinates
/// `NAME.x`, `NAME.y`, `NAME.z` (m), the displacement of the child's origin along the joint
/// frame's axes, and three speeds `NAME.vx`, `NAME.vy`, `NAME.vz` (m/s), the measure numbers
/// of that origin's velocity relative to the joint frame in the child's own basis (Kane's
/// choice for a floating body, Kane & Levinson §4.4; Pinocchio's free flyer). So
/// `(ẋ, ẏ, ż) = R v` with `R` the child's rotation relative to the joint frame. It starts at
/// the joint frame's origin.
#[derive(Clone, Debug, PartialEq)]
pub struct Translation {
    /// The joint's name.
    pub name: String,
    /// Initial velocity of the child's origin relative to the joint frame, m/s, components in
    /// the child's basis at its initial orientation.
    pub initial_velocity: [f64; 3],
    pub span: Span,
}

impl Translation {
    /// Names of the three coordinates, along the joint frame's x, y, z.
    pub fn coordinate_names(&self) -> [String; 3] {
        member_names(&self.name, ["x", "y", "z"])
    }
    /// Names of the three speeds, along the child's x, y, z.
    pub fn speed_names(&self) -> [String; 3] {
        member_names(&self.name, ["vx", "vy", "vz"])
    }
}

/// Rotation by `angle` about the unit vector `axis` (components in the rotating frame).
#[derive(Clone, Debug, PartialEq)]
pub struct AxisAngle {
    pub axis: Vec3,
    pub angle: Expr,
}

/// How a frame moves relative to its parent, after its constant placement.
#[derive(Clone, Debug, PartialEq)]
pub enum Motion {
    /// Fixed in the parent (a body-fixed frame, a weld, an interframe).
    Fixed,
    /// Rotation by `q` about the unit `axis` through the frame's origin (components in this
    /// frame, equal in the parent-side placement since the axis is invariant).
    Revolute {
        axis: Vec3,
        coordinate: Handle<Coordinate>,
    },
    /// Translation by `q` along the unit `axis` (components in this frame's placement).
    Prismatic {
        axis: Vec3,
        coordinate: Handle<Coordinate>,
    },
    /// Rotation about the frame's origin, by a unit quaternion or three Euler angles (a ball
    /// joint).
    Spherical { rotation: Rotation },
    /// Rotation about the frame's origin and translation of the origin by the three
    /// coordinates of `translation` along the axes of the frame's placement: `O_F = O_P +
    /// origin + C₀ (x, y, z)`, `C_{P←F} = C₀ R` (a free joint).
    Free {
        rotation: Rotation,
        translation: Handle<Translation>,
    },
}

/// The orientation of a spherical or free motion relative to its placement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rotation {
    Quaternion(Handle<Quaternion>),
    /// `rotation = euler(…)`.
    Euler(Handle<EulerAngles>),
}

impl Motion {
    pub fn coordinate(&self) -> Option<Handle<Coordinate>> {
        match self {
            Motion::Fixed | Motion::Spherical { .. } | Motion::Free { .. } => None,
            Motion::Revolute { coordinate, .. } | Motion::Prismatic { coordinate, .. } => {
                Some(*coordinate)
            }
        }
    }
}

/// A node of the kinematic tree.
///
/// Relative to its parent P, frame F is placed by
/// - origin: `O_F = O_P + origin` (components in P) `+ q·axis` for a prismatic motion
///   (axis components in F's placement, which for a prismatic motion equals F),
/// - orientation: `C_{P←F} = R(orientation[0]) · R(orientation[1]) · … · R(axis, q)`
///   where the last factor is present for a revolute motion and each `R(a, θ)` is the
///   rotation by θ about a (Rodrigues).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Qualified name: `newtonian`, `arm` (a body's frame), `arm.tilted`, or
    /// `hinge` and `hinge.child` for frames created by joint `hinge`.
    pub name: String,
    pub parent: Option<Handle<Frame>>,
    pub origin: Vec3,
    pub orientation: Vec<AxisAngle>,
    pub motion: Motion,
    pub span: Span,
}

/// Inertia tensor entries about the centre of mass, in the body frame (tensor convention:
/// off-diagonal entries are the tensor's, i.e. `I_xy = -∫ x y dm`, as in SymPy's `inertia`).
#[derive(Clone, Debug, PartialEq)]
pub struct Inertia {
    pub xx: Expr,
    pub yy: Expr,
    pub zz: Expr,
    pub xy: Expr,
    pub yz: Expr,
    pub zx: Expr,
}

impl Inertia {
    /// The six entries in the order `xx, yy, zz, xy, yz, zx`.
    pub fn entries(&self) -> [&Expr; 6] {
        [&self.xx, &self.yy, &self.zz, &self.xy, &self.yz, &self.zx]
    }

    pub fn zero() -> Inertia {
        Inertia {
            xx: Expr::zero(),
            yy: Expr::zero(),
            zz: Expr::zero(),
            xy: Expr::zero(),
            yz: Expr::zero(),
            zx: Expr::zero(),
        }
    }
}

/// A rigid body attached to one frame of the tree.
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    pub name: String,
    pub frame: Handle<Frame>,
    pub mass: Expr,
    /// Centre of mass in the body frame.
    pub center_of_mass: Vec3,
    pub inertia: Inertia,
    pub docs: Vec<String>,
    pub span: Span,
}

impl Body {
    /// A point mass at the origin of `frame`, without docs or span.
    pub fn point_mass(name: String, frame: Handle<Frame>, mass: Expr) -> Body {
        Body {
            name,
            frame,
            mass,
            center_of_mass: [Expr::zero(), Expr::zero(), Expr::zero()],
            inertia: Inertia::zero(),
            docs: Vec::new(),
            span: Span::default(),
        }
    }
}

/// A named point fixed in a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// Qualified name: `arm.tip`, or `arm` for a body's origin.
    pub name: String,
    pub frame: Handle<Frame>,
    pub position: Vec3,
    pub span: Span,
}

/// The kind of a joint, as declared (the frames it created carry the kinematics).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointKind {
    Pin,
    Slider,
    Weld,
    /// Spherical: a unit quaternion and three angular speeds.
    Ball,
    /// Six degrees of freedom (a floating base): a ball's rotation and a [`Translation`]
    /// along the joint frame's axes (speeds: the origin's velocity in the child's basis).
    Free,
    /// Two pins in series (a Cardan or Hooke joint): `angle1` about `axis`, then `angle2`
    /// about `axis2` in the frame turned by the first; `u = q̇`.
    Universal,
    /// A slide along `axis` and a turn about it: `slide`, then `angle`; `u = q̇`.
    Cylindrical,
    /// Two slides in the plane normal to `axis` and a turn about it: `slide1`, `slide2`,
    /// then `angle`; `u = q̇`.
    Planar,
}

/// A joint as declared in the model; kept for reports and diagnostics.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    pub name: String,
    pub kind: JointKind,
    /// The parent body; `None` for the Newtonian frame.
    pub parent: Option<Handle<Body>>,
    pub child: Handle<Body>,
    pub coordinates: Vec<Handle<Coordinate>>,
    /// The orientation of a `ball` or `free` joint as a quaternion (`None` with Euler
    /// angles: the [`EulerAngles`] of the joint's name).
    pub quaternion: Option<Handle<Quaternion>>,
    pub span: Span,
}

/// What a loop closure holds together.
#[derive(Clone, Debug, PartialEq)]
pub enum ClosureKind {
    /// The points coincide: the listed components (0 = x, 1 = y, 2 = z) of
    /// `child − parent`, in the basis of `frame`, are zero.
    Coincident {
        frame: Handle<Frame>,
        components: Vec<usize>,
    },
    /// A revolute closure (URDF `loop_joint` of type continuous): the points coincide and the
    /// unit `axis` (components in the parent interframe) stays aligned with the same axis in
    /// the child interframe. The interframes are given relative to each point's frame and
    /// coincide when the relative rotation about the axis is zero.
    ///
    /// With a `twist_axis` `t` (the flexure's length axis, components in the parent
    /// interframe, perpendicular to the axis) the closure is compliant: only the points are
    /// held together, and springs on its twist about `t` ([`FlexureAngle::LoopTwist`]) and its
    /// lateral bending about `a × t` ([`FlexureAngle::LoopLateral`]) hold the axes in line.
    Revolute {
        axis: Vec3,
        parent_orientation: Vec<AxisAngle>,
        child_orientation: Vec<AxisAngle>,
        twist_axis: Option<Box<Vec3>>,
    },
    /// `|child − parent| = length`.
    Distance { length: Expr },
}

/// An explicit loop closure: constraints `φ(q) = 0` between two points of the tree.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopClosure {
    pub name: String,
    pub kind: ClosureKind,
    /// Point on the parent side (fixed in the parent body's frame).
    pub parent: Handle<Point>,
    /// Point on the child side.
    pub child: Handle<Point>,
    pub span: Span,
}

/// A velocity (nonholonomic) constraint: rows `A(q) u = 0`, linear and homogeneous in the
/// speeds, with no position form (`kane::constraints` appends them to the loop rows).
#[derive(Clone, Debug, PartialEq)]
pub struct VelocityConstraint {
    pub name: String,
    pub kind: VelocityKind,
    pub span: Span,
}

/// A generalized speed chosen by a `speed` declaration: a measure number of an angular or
/// linear velocity, or a combination of the default speeds, linear and homogeneous in them.
#[derive(Clone, Debug, PartialEq)]
pub struct ChosenSpeed {
    pub name: String,
    pub kind: SpeedKind,
    /// Its dimension: an angular velocity's (1/s), a velocity's (m/s), or the combination's.
    pub dimension: Dimension,
    /// Its value at the start, `Y(q₀) ū₀` with the parameters' defaults (set by the front end).
    pub initial: f64,
    pub span: Span,
}

/// What a [`ChosenSpeed`] measures; `axis` is a unit vector in `frame`'s basis.
#[derive(Clone, Debug, PartialEq)]
pub enum SpeedKind {
    /// `ω·axis`, ω the angular velocity in N of the body whose frame is `body`.
    AngularVelocity {
        body: Handle<Frame>,
        frame: Handle<Frame>,
        axis: Box<Vec3>,
    },
    /// `v·axis`, v the velocity in N of `point`.
    PointVelocity {
        point: Handle<Point>,
        frame: Handle<Frame>,
        axis: Box<Vec3>,
    },
    /// A combination of the default speeds with coefficients of the coordinates and params:
    /// `a.u + 2 * b.u`.
    Scalar(Expr),
}

/// What a [`VelocityConstraint`] holds at zero.
#[derive(Clone, Debug, PartialEq)]
pub enum VelocityKind {
    /// The listed components (0 = x) in `frame`'s basis of the velocity in N of the material
    /// point of the body with frame `body` that is at `point` at this instant (the contact
    /// point of a wheel moves over the wheel; its material point there does not slip).
    PointVelocity {
        point: Handle<Point>,
        body: Handle<Frame>,
        frame: Handle<Frame>,
        components: Vec<usize>,
    },
    /// A scalar expression of the motion, linear and homogeneous in the speeds (checked by
    /// the front end): `a.u - 2 * b.u`.
    Scalar(Expr),
    /// A thin wheel (a disc of `radius` about `centre`, its `axle` in the basis of the frame
    /// the centre is fixed in) rolling without slip on the plane through `plane` (a Newtonian
    /// point) with unit `normal` (Newtonian basis): one loop row, the contact point's height
    /// above the plane, and two velocity rows, the wheel's material point at the contact
    /// not slipping along the plane (`kane::constraints`).
    Rolling {
        centre: Handle<Point>,
        axle: Box<Vec3>,
        radius: Expr,
        plane: Handle<Point>,
        normal: Box<Vec3>,
    },
}

/// Something that does work: contributes to the generalized active forces `F_r`.
#[derive(Clone, Debug, PartialEq)]
pub enum Load {
    /// A force applied at a point (acts on whatever the point's frame belongs to).
    Force {
        point: Handle<Point>,
        force: FrameVector,
        span: Span,
    },
    /// A couple applied to the body owning `frame`.
    Torque {
        frame: Handle<Frame>,
        torque: FrameVector,
        span: Span,
    },
    /// `−stiffness·(q − rest)` on one coordinate (joint spring); stores `½k(q−rest)²` of
    /// potential energy.
    Spring {
        coordinate: Handle<Coordinate>,
        stiffness: Expr,
        rest: Expr,
        span: Span,
    },
    /// `−damping·u` on one coordinate (joint damper).
    Damper {
        coordinate: Handle<Coordinate>,
        damping: Expr,
        span: Span,
    },
    /// Torque `−stiffness·(θ − rest)` about the axis of revolute closure `loops[closure]`,
    /// on the child (and the opposite on the parent); θ is the relative rotation of the
    /// interframes about the axis. Stores `½k(θ − rest)²` of potential energy.
    LoopSpring {
        closure: usize,
        stiffness: Expr,
        rest: Expr,
        span: Span,
    },
    /// Torque `−damping·(ω_child − ω_parent)·axis` about the axis of revolute closure
    /// `loops[closure]`.
    LoopDamper {
        closure: usize,
        damping: Expr,
        span: Span,
    },
    /// `−stiffness·(θ − rest)·∂θ/∂q` for an angle `θ(q)` that is not a coordinate (the twist
    /// of a compliant closure); stores `½k(θ − rest)²` of potential energy.
    AngleSpring {
        angle: FlexureAngle,
        stiffness: Expr,
        rest: Expr,
        span: Span,
    },
    /// `−damping·θ̇·∂θ/∂q`, `θ̇ = Σ ∂θ/∂qᵢ uᵢ`, for an angle as in [`Load::AngleSpring`].
    AngleDamper {
        angle: FlexureAngle,
        damping: Expr,
        span: Span,
    },
    /// A spring–damper along the line between two points `ends = [A, B]` (`spring NAME
    /// between A and B`): with `d = r_B − r_A`, `L = |d|`, `ê = d/L`, the tension
    /// `T = stiffness·(L − rest_length) + damping·L̇` pulls B towards A (`−T ê` on B, `+T ê`
    /// on A). Stores `½k(L − rest_length)²` of potential energy. The points are on
    /// different bodies (the front end checks it) and must not meet: `ê` is undefined at
    /// `L = 0`.
    PointSpring {
        ends: [Handle<Point>; 2],
        stiffness: Expr,
        rest_length: Expr,
        damping: Option<Expr>,
        /// A tension law of the motion (`tension = EXPR`, e.g. of `distance(A, B)`) added to
        /// `T`; its work is not in the potential energy.
        tension: Option<Expr>,
        span: Span,
    },
    /// Compliant unilateral contact (`contact NAME between P and Q`) of a sphere of `radius`
    /// centred at `point` (a point when the radius is 0) with the plane through `plane` whose
    /// unit `normal` (components in the frame `plane` is fixed in) points out of the solid.
    /// Penetration `δ = max(0, −h)`, `h = n·(r_P − r_Q) − radius`; Hunt–Crossley normal force
    /// `f_n = max(0, k δ^exponent (1 + 3/2 α δ̇))` and regularized Coulomb friction
    /// `f_t = −μ f_n v_t / √(|v_t|² + v_s²)` on the slip velocity `v_t` at the contact point
    /// `C = r_P − radius·n`, acting on `P`'s body at `C` (and the reaction on `Q`'s). Stores
    /// `k δ^(exponent+1)/(exponent+1)` of potential energy (`kane::contact`).
    Contact {
        point: Handle<Point>,
        plane: Handle<Point>,
        normal: Vec3,
        radius: Expr,
        stiffness: Expr,
        /// A positive constant (Hunt–Crossley's `n`; 3/2 for a Hertzian sphere).
        exponent: Number,
        /// α, in s/m.
        damping: Expr,
        /// μ.
        friction: Expr,
        /// `v_s` in m/s (positive).
        transition_speed: Expr,
        span: Span,
    },
    /// A bushing (`bushing NAME between A and B`): six springs and dampers on the offsets
    /// `s(q)` of frame B from frame A, components in A's basis: the position of B's origin
    /// `d = C_Aᵀ (o_B − o_A)` and the small-angle rotation `θ = vee(R − Rᵀ)/2` of
    /// `R = C_Aᵀ C_B` (`sin φ` times the axis, φ for small angles). Potential
    /// `½ Σ kᵢ sᵢ²`; generalized forces `−Σ (kᵢ sᵢ + cᵢ ṡᵢ) ∂sᵢ/∂q_r` (`q̇ = u`: the front end
    /// refuses it with quaternions). `[translational, rotational]` stiffness and damping.
    Bushing {
        frames: [Handle<Frame>; 2],
        stiffness: [Vec3; 2],
        damping: [Vec3; 2],
        span: Span,
    },
    /// A generalized force acting directly on one coordinate (an actuator's force source).
    GeneralizedForce {
        coordinate: Handle<Coordinate>,
        force: Expr,
        span: Span,
    },
}

/// The angle a flexure bends through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlexureAngle {
    /// The coordinate of a pin joint.
    Coordinate(Handle<Coordinate>),
    /// The relative rotation of revolute loop `loops[index]` about its axis.
    Loop(usize),
    /// The twist of compliant revolute loop `loops[index]` about its `twist_axis`.
    LoopTwist(usize),
    /// The lateral bending of compliant revolute loop `loops[index]`, about `axis × twist_axis`.
    LoopLateral(usize),
}

/// A compliant hinge (Doshi et al. Eqs. 2, 5): bending stiffness `k`, loss factor `η`.
/// Its spring and its time-domain damper `b = kη/ω_ref` are also in `Model::loads`; this
/// record lets frequency-domain analyses use the complex stiffness `k(1 + iη)` instead.
#[derive(Clone, Debug, PartialEq)]
pub struct Flexure {
    pub name: String,
    pub angle: FlexureAngle,
    /// Bending stiffness, N·m/rad.
    pub stiffness: Expr,
    pub loss_factor: Expr,
    /// Viscous equivalent used in the time domain, `k η / ω_ref`, N·m·s/rad.
    pub damping: Expr,
    pub span: Span,
}

/// What an output measures. Vector outputs produce three scalar outputs `name.x|y|z`.
#[derive(Clone, Debug, PartialEq)]
pub enum OutputKind {
    /// Position of `point` relative to the origin of `frame`, components in `frame`.
    Position {
        point: Handle<Point>,
        frame: Handle<Frame>,
    },
    /// Velocity of `point` in the Newtonian frame, components in `frame`.
    Velocity {
        point: Handle<Point>,
        frame: Handle<Frame>,
    },
    Coordinate(Handle<Coordinate>),
    Speed(Handle<Coordinate>),
    KineticEnergy,
    /// Gravity plus joint, closure, flexure and point-to-point springs; zero at the Newtonian
    /// origin and at springs' rest values.
    PotentialEnergy,
    /// Any scalar expression of parameters, inputs and time.
    Expr(Expr),
    /// The state of the contact `model.loads[index]` ([`Load::Contact`]): its outputs
    /// [`CONTACT_OUTPUTS`].
    Contact(usize),
}

/// The scalar outputs of a contact (`output NAME = contact(C);`), as name suffixes: the
/// penetration δ (m), the normal force `f_n` (N), the friction force in the Newtonian basis (N),
/// the power the contact dissipates (W: damping and friction, ≥ 0), and the energy it has
/// dissipated since the start of a simulation (J), the integral of the power that the
/// simulation integrates with the motion (`Equations::integrated_outputs`).
pub const CONTACT_OUTPUTS: [&str; 7] = [
    ".penetration",
    ".normal_force",
    ".friction.x",
    ".friction.y",
    ".friction.z",
    ".power",
    ".dissipated",
];

#[derive(Clone, Debug, PartialEq)]
pub struct Output {
    pub name: String,
    pub kind: OutputKind,
    pub docs: Vec<String>,
    pub span: Span,
}

/// A whole mechanism.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Model {
    /// Model name (snake_case), from `model NAME;` or the file stem.
    pub name: String,
    /// `///` comments before the `model` line (or at the top of the file).
    pub docs: Vec<String>,
    pub params: Arena<Param>,
    pub inputs: Arena<Input>,
    pub coordinates: Arena<Coordinate>,
    /// Orientations of spherical motions; their coordinates and speeds follow the
    /// coordinates' in `q` and `u`.
    pub quaternions: Arena<Quaternion>,
    /// Orientations of spherical motions as Euler angles; their coordinates and speeds follow
    /// the quaternions' in `q` and `u`.
    pub euler_angles: Arena<EulerAngles>,
    /// Positions of free joints; their coordinates and speeds follow the Euler angles'.
    pub translations: Arena<Translation>,
    /// The kinematic tree, parents first; `frames[NEWTONIAN]` is the root.
    pub frames: Arena<Frame>,
    pub bodies: Arena<Body>,
    pub points: Arena<Point>,
    pub joints: Arena<Joint>,
    pub loads: Vec<Load>,
    /// Loop closures: the only connections that are not tree joints.
    pub loops: Vec<LoopClosure>,
    /// Velocity constraints, rows appended after the loops' (no position form).
    pub velocity_constraints: Vec<VelocityConstraint>,
    /// Generalized speeds chosen by `speed` declarations, `u = Y(q) ū` of the default speeds
    /// `ū` (`q̇` of pins and sliders, a ball's ω); empty for the default `u = ū`. When not
    /// empty there are exactly [`Model::nu`] of them and `Y(q₀)` is invertible (the front end
    /// checks both); `kane::derive` writes the equations in them.
    pub speeds: Vec<ChosenSpeed>,
    /// Flexures (their springs and dampers are also in `loads`).
    pub flexures: Vec<Flexure>,
    /// Gravitational acceleration, components in the Newtonian frame.
    pub gravity: Option<Vec3>,
    pub outputs: Vec<Output>,
    /// Physical rules on masses, inertias and element dimensions, checked again when a
    /// parameter changes at run time.
    pub requirements: Vec<Requirement>,
    /// Initial values written as expressions of params (`u0 = v / r`), evaluated again when a
    /// parameter changes at run time; the coordinates' `initial` and `initial_speed` hold
    /// them at the params' defaults.
    pub initial_values: Vec<InitialValue>,
}

/// A coordinate's `q0` or `u0` that depends on params.
#[derive(Clone, Debug, PartialEq)]
pub struct InitialValue {
    pub coordinate: Handle<Coordinate>,
    /// `u0` rather than `q0`.
    pub speed: bool,
    pub expr: Expr,
}

impl InitialValue {
    /// Writes each of `values` at the params `params` into `q` or `u` (NaN where one cannot
    /// be evaluated).
    pub fn apply(values: &[InitialValue], params: &[f64], q: &mut [f64], u: &mut [f64]) {
        for value in values {
            let slot = match value.speed {
                true => u.get_mut(value.coordinate.index()),
                false => q.get_mut(value.coordinate.index()),
            };
            if let Some(slot) = slot {
                *slot = value.expr.evaluate(params).unwrap_or(f64::NAN);
            }
        }
    }
}

impl Model {
    pub const NEWTONIAN: Handle<Frame> = Handle::<Frame>::NEWTONIAN_INDEX;

    /// A model with only the Newtonian frame.
    pub fn new(name: impl Into<String>) -> Model {
        let mut model = Model {
            name: name.into(),
            ..Model::default()
        };
        model.frames.append(Frame {
            name: "newtonian".to_string(),
            parent: None,
            origin: [Expr::zero(), Expr::zero(), Expr::zero()],
            orientation: Vec::new(),
            motion: Motion::Fixed,
            span: Span::default(),
        });
        model
    }

    /// The requirements that do not hold with the parameters at `params` (SI, by index).
    pub fn implausible(&self, params: &[f64]) -> Vec<Implausible> {
        self.requirements
            .iter()
            .filter_map(|requirement| {
                let violation = requirement.check(params).err()?;
                Some(Implausible {
                    requirement: requirement.clone(),
                    violation,
                })
            })
            .collect()
    }

    /// Number of generalized coordinates: one per coordinate, four per quaternion, three per
    /// set of Euler angles or translation.
    pub fn nq(&self) -> usize {
        self.coordinates.len()
            + 4 * self.quaternions.len()
            + 3 * (self.euler_angles.len() + self.translations.len())
    }
    /// Number of generalized speeds: one per coordinate, three per quaternion, Euler angles
    /// or translation.
    pub fn nu(&self) -> usize {
        self.coordinates.len()
            + 3 * (self.quaternions.len() + self.euler_angles.len() + self.translations.len())
    }
    /// Whether `q̇ ≠ u` somewhere: the model has quaternions, Euler angles or free joints.
    pub fn has_kinematic_rates(&self) -> bool {
        !self.quaternions.is_empty()
            || !self.euler_angles.is_empty()
            || !self.translations.is_empty()
    }
    /// The dimension of `q[index]`: its coordinate's, an angle for an Euler angle, a length
    /// for a translation; `None` for a quaternion's part (a plain number, set only as a
    /// whole) or past the end.
    pub fn coordinate_dimension(&self, index: usize) -> Option<Dimension> {
        let quaternions = self.coordinates.len() + 4 * self.quaternions.len();
        let angles = quaternions + 3 * self.euler_angles.len();
        match index {
            i if i < self.coordinates.len() => Some(self.coordinates[Handle::new(i)].dimension),
            i if i < quaternions => None,
            i if i < angles => Some(Dimension::NONE),
            i if i < self.nq() => Some(Dimension::LENGTH),
            _ => None,
        }
    }
    /// The dimension of the default speed `ū[index]`: its coordinate's rate, an angular
    /// speed for a quaternion or Euler angles, a velocity for a translation.
    pub fn default_speed_dimension(&self, index: usize) -> Dimension {
        let angular =
            self.coordinates.len() + 3 * (self.quaternions.len() + self.euler_angles.len());
        let dimension = match index {
            i if i < self.coordinates.len() => self.coordinates[Handle::new(i)].dimension,
            i if i < angular => Dimension::NONE,
            _ => Dimension::LENGTH,
        };
        dimension.div(Dimension::TIME)
    }
    /// Index in `q` of coordinate `axis` (0 = x) of `translation`.
    pub fn translation_coordinate(&self, translation: Handle<Translation>, axis: usize) -> usize {
        self.coordinates.len()
            + 4 * self.quaternions.len()
            + 3 * (self.euler_angles.len() + translation.index())
            + axis
    }
    /// Index in `u` of speed `axis` (0 = along the child's x) of `translation`.
    pub fn translation_speed(&self, translation: Handle<Translation>, axis: usize) -> usize {
        self.coordinates.len()
            + 3 * (self.quaternions.len() + self.euler_angles.len() + translation.index())
            + axis
    }
    /// Index in `q` of angle `part` (0 = the first turn) of `angles`.
    pub fn euler_coordinate(&self, angles: Handle<EulerAngles>, part: usize) -> usize {
        self.coordinates.len() + 4 * self.quaternions.len() + 3 * angles.index() + part
    }
    /// Index in `u` of the angular speed about axis `axis` (0 = x) of `angles`.
    pub fn euler_speed(&self, angles: Handle<EulerAngles>, axis: usize) -> usize {
        self.coordinates.len() + 3 * self.quaternions.len() + 3 * angles.index() + axis
    }
    /// Index in `q` of part `part` (0 = scalar) of `quaternion`.
    pub fn quaternion_coordinate(&self, quaternion: Handle<Quaternion>, part: usize) -> usize {
        self.coordinates.len() + 4 * quaternion.index() + part
    }
    /// Index in `u` of the angular speed about axis `axis` (0 = x) of `quaternion`.
    pub fn angular_speed(&self, quaternion: Handle<Quaternion>, axis: usize) -> usize {
        self.coordinates.len() + 3 * quaternion.index() + axis
    }
    /// Names of `q` in order: the coordinates', each quaternion's four, each set of Euler
    /// angles' three, each translation's three.
    pub fn coordinate_names(&self) -> Vec<String> {
        let coordinates = self.coordinates.iter().map(|(_, c)| c.name.clone());
        let quaternions = self
            .quaternions
            .iter()
            .flat_map(|(_, e)| e.coordinate_names());
        let angles = self
            .euler_angles
            .iter()
            .flat_map(|(_, a)| a.coordinate_names());
        let translations = self
            .translations
            .iter()
            .flat_map(|(_, t)| t.coordinate_names());
        let all = coordinates.chain(quaternions).chain(angles);
        all.chain(translations).collect()
    }
    /// Names of `u` in order: the chosen speeds' if any, else the default speeds'.
    pub fn speed_names(&self) -> Vec<String> {
        if !self.speeds.is_empty() {
            return self.speeds.iter().map(|s| s.name.clone()).collect();
        }
        self.default_speed_names()
    }
    /// Names of the default speeds `ū`: the coordinates', then each quaternion's and each set
    /// of Euler angles' three angular speeds, then each translation's three.
    pub fn default_speed_names(&self) -> Vec<String> {
        let coordinates = self.coordinates.iter().map(|(_, c)| c.name.clone());
        let quaternions = self.quaternions.iter().flat_map(|(_, e)| e.speed_names());
        let angles = self.euler_angles.iter().flat_map(|(_, a)| a.speed_names());
        let translations = self.translations.iter().flat_map(|(_, t)| t.speed_names());
        let all = coordinates.chain(quaternions).chain(angles);
        all.chain(translations).collect()
    }
    /// Initial `q`: the coordinates' `q0`, identity rotations `(1, 0, 0, 0)`, the Euler angles'
    /// `q0`, translations at the joint frame's origin.
    pub fn initial_coordinates(&self) -> Vec<f64> {
        let coordinates = self.coordinates.iter().map(|(_, c)| c.initial);
        let quaternions = self.quaternions.iter().flat_map(|_| [1.0, 0.0, 0.0, 0.0]);
        let angles = self.euler_angles.iter().flat_map(|(_, a)| a.initial_angles);
        let translations = self.translations.iter().flat_map(|_| [0.0; 3]);
        let all = coordinates.chain(quaternions).chain(angles);
        all.chain(translations).collect()
    }
    /// Initial `u`: the chosen speeds' initial values if any, else the default speeds'.
    pub fn initial_speeds(&self) -> Vec<f64> {
        if !self.speeds.is_empty() {
            return self.speeds.iter().map(|s| s.initial).collect();
        }
        self.default_initial_speeds()
    }
    /// Initial `ū` of the default speeds (`q̇` of pins and sliders, then the angular
    /// velocities of quaternions and Euler angles, then the translations' velocities).
    pub fn default_initial_speeds(&self) -> Vec<f64> {
        let coordinates = self.coordinates.iter().map(|(_, c)| c.initial_speed);
        let quaternions = self
            .quaternions
            .iter()
            .flat_map(|(_, e)| e.initial_angular_velocity);
        let angles = self
            .euler_angles
            .iter()
            .flat_map(|(_, a)| a.initial_angular_velocity);
        let translations = self
            .translations
            .iter()
            .flat_map(|(_, t)| t.initial_velocity);
        let all = coordinates.chain(quaternions).chain(angles);
        all.chain(translations).collect()
    }

    /// The chain of frames from the root to `frame`, root first.
    pub fn frame_path(&self, frame: Handle<Frame>) -> Vec<Handle<Frame>> {
        let mut path = vec![frame];
        let mut current = frame;
        while let Some(parent) = self.frames[current].parent {
            path.push(parent);
            current = parent;
        }
        path.reverse();
        path
    }
}

impl Handle<Frame> {
    const NEWTONIAN_INDEX: Handle<Frame> = Handle::from_const(0);
}
