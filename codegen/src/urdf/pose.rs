//! The robot at its zero pose (every joint coordinate zero): where each link's frame is, how
//! far the two points of each loop closure miss each other there, and the `--snap` fix that
//! moves such points onto the closure's axis where the other hinge axes meet it.
//!
//! Consumes: the links' world poses composed from the tree joints' origins (`emit.rs`), and
//! the loop closures. Produces: plain numbers ([`Frame`], [`Miss`], [`Snap`]); no text.

/// A 3-vector.
pub type Vec3 = [f64; 3];

/// A rotation matrix, rows first.
pub type Mat3 = [[f64; 3]; 3];

pub const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// A frame in the root link's frame: origin and orientation (columns: its axes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub origin: Vec3,
    pub rotation: Mat3,
}

impl Frame {
    pub const ROOT: Frame = Frame {
        origin: [0.0; 3],
        rotation: IDENTITY,
    };

    /// The frame at `xyz`, turned by `rotation`, relative to this one.
    pub fn then(&self, xyz: Vec3, rotation: &Mat3) -> Frame {
        Frame {
            origin: add(self.origin, mul_vec(&self.rotation, xyz)),
            rotation: mul(&self.rotation, rotation),
        }
    }

    /// A point given in this frame, in the root frame.
    pub fn point(&self, local: Vec3) -> Vec3 {
        add(self.origin, mul_vec(&self.rotation, local))
    }

    /// A root-frame point in this frame's coordinates.
    pub fn local(&self, point: Vec3) -> Vec3 {
        mul_vec(&transpose(&self.rotation), sub(point, self.origin))
    }

    pub fn direction(&self, local: Vec3) -> Vec3 {
        mul_vec(&self.rotation, local)
    }
}

/// URDF's `rpy`: `Rz(yaw) Ry(pitch) Rx(roll)`.
pub fn rpy_matrix([roll, pitch, yaw]: Vec3) -> Mat3 {
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sy, cy) = yaw.sin_cos();
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

pub fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub fn scale(a: Vec3, s: f64) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

pub fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub fn norm(a: Vec3) -> f64 {
    dot(a, a).sqrt()
}

pub fn unit(a: Vec3) -> Option<Vec3> {
    let n = norm(a);
    (n > 0.0).then(|| scale(a, 1.0 / n))
}

pub fn mul_vec(m: &Mat3, v: Vec3) -> Vec3 {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

pub fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let bt = transpose(b);
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| dot(a[i], bt[j])))
}

pub fn transpose(m: &Mat3) -> Mat3 {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| m[j][i]))
}

/// A line through `point` along the unit vector `direction`: a hinge axis at the zero pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// The joint or closure it belongs to.
    pub name: String,
    pub point: Vec3,
    pub direction: Vec3,
}

/// The distance between two lines (zero where they cross), `None` if they are parallel.
fn crossing_distance(a: &Axis, b: &Axis) -> Option<f64> {
    let normal = cross(a.direction, b.direction);
    let n = norm(normal);
    (n > 1e-9).then(|| dot(sub(b.point, a.point), normal).abs() / n)
}

/// The point nearest to all `axes` in the least-squares sense, `None` when their directions
/// do not span at least a plane (parallel lines meet nowhere in particular).
fn nearest_point(axes: &[&Axis]) -> Option<Vec3> {
    let mut a = [[0.0; 3]; 3];
    let mut b = [0.0; 3];
    for axis in axes {
        let d = axis.direction;
        for i in 0..3 {
            for j in 0..3 {
                let projector = if i == j { 1.0 } else { 0.0 } - d[i] * d[j];
                a[i][j] += projector;
                b[i] += projector * axis.point[j];
            }
        }
    }
    let det = dot(a[0], cross(a[1], a[2]));
    let trace = a[0][0] + a[1][1] + a[2][2];
    if det.abs() <= 1e-9 * trace.powi(3) {
        return None;
    }
    // Cramer's rule on the 3×3 normal equations.
    let column = |k: usize| -> f64 {
        let mut m = a;
        for (row, value) in m.iter_mut().zip(b) {
            row[k] = value;
        }
        dot(m[0], cross(m[1], m[2])) / det
    };
    Some([column(0), column(1), column(2)])
}

/// How far a loop closure's two points are apart at the zero pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Miss {
    /// `link2`'s point minus `link1`'s, in the root frame.
    pub gap: Vec3,
    pub distance: f64,
}

pub fn miss(first: Vec3, second: Vec3) -> Miss {
    let gap = sub(second, first);
    Miss {
        gap,
        distance: norm(gap),
    }
}

/// The `--snap` fix of one revolute closure: both points moved onto the closure's axis line
/// through `centre`.
#[derive(Clone, Debug, PartialEq)]
pub struct Snap {
    /// Where the axes that cross this closure's axis meet (least squares); or, when no two
    /// of them fix a point, the midpoint of the two points.
    pub centre: Vec3,
    /// The hinges whose axes meet there (empty for the midpoint).
    pub through: Vec<String>,
    /// The new points, in the root frame.
    pub first: Vec3,
    pub second: Vec3,
}

/// Snaps a revolute closure whose points (`first`, `second`, root frame) miss each other:
/// the axes among `others` that cross its axis within `tolerance` define the centre (as for
/// a spherical linkage, whose axes must all meet in one point); each point is moved to its
/// nearest point on the closure's axis through that centre.
pub fn snap(direction: Vec3, first: Vec3, second: Vec3, others: &[Axis], tolerance: f64) -> Snap {
    let midpoint = scale(add(first, second), 0.5);
    let own = Axis {
        name: String::new(),
        point: midpoint,
        direction,
    };
    let crossing: Vec<&Axis> = others
        .iter()
        .filter(|axis| crossing_distance(&own, axis).is_some_and(|d| d <= tolerance))
        .collect();
    let (centre, through) = match nearest_point(&crossing) {
        Some(centre) => (centre, crossing.iter().map(|a| a.name.clone()).collect()),
        None => (midpoint, Vec::new()),
    };
    let onto_axis = |p: Vec3| add(centre, scale(direction, dot(sub(p, centre), direction)));
    Snap {
        centre,
        through,
        first: onto_axis(first),
        second: onto_axis(second),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rpy_turns_roll_then_pitch_then_yaw_about_fixed_axes() {
        let quarter = std::f64::consts::FRAC_PI_2;
        // Yaw alone turns x into y.
        let r = rpy_matrix([0.0, 0.0, quarter]);
        let x = mul_vec(&r, [1.0, 0.0, 0.0]);
        assert!(norm(sub(x, [0.0, 1.0, 0.0])) < 1e-15);
        // Roll then yaw: z → −y (roll about x) → x (yaw about z).
        let r = rpy_matrix([quarter, 0.0, quarter]);
        let z = mul_vec(&r, [0.0, 0.0, 1.0]);
        assert!(norm(sub(z, [1.0, 0.0, 0.0])) < 1e-15, "{z:?}");
    }

    #[test]
    fn snapping_moves_both_points_onto_the_axis_through_the_common_point() {
        let centre = [1.0, 2.0, 3.0];
        let others = [
            Axis {
                name: "a".into(),
                point: add(centre, [0.0, 0.0, 5.0]),
                direction: [0.0, 0.0, 1.0],
            },
            Axis {
                name: "b".into(),
                point: add(centre, [-4.0, 0.0, 0.0]),
                direction: [1.0, 0.0, 0.0],
            },
            // Far from the closure's axis: not one of the spherical linkage's.
            Axis {
                name: "far".into(),
                point: [10.0, 0.0, 0.0],
                direction: [0.0, 0.0, 1.0],
            },
        ];
        let first = add(centre, [1e-7, 6.0, 0.0]);
        let second = add(centre, [0.0, 6.0, -1e-7]);
        let fixed = snap([0.0, 1.0, 0.0], first, second, &others, 1e-5);
        assert_eq!(fixed.through, ["a", "b"]);
        assert!(norm(sub(fixed.centre, centre)) < 1e-14);
        assert!(norm(sub(fixed.first, add(centre, [0.0, 6.0, 0.0]))) < 1e-14);
        assert!(norm(sub(fixed.second, fixed.first)) < 1e-14);
    }
}
