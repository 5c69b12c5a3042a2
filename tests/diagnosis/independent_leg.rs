//! HAMR-VI's front-left leg formulated a second time, independently of mech, for hidden-effect
//! data the model under diagnosis did not make (issue 17).
//!
//! Consumes the published URDFs at test time (`../shared/reference/hamr-vi-urdf/`, read by the
//! small XML reader below, not by mech and not from `models/hamr_vi.mech`); produces the
//! paper's force/deflection test (seed Sec. V-A): the foot's free deflection and the sensor
//! force at given distances, with the sensor's off-axis load; and the frequency response of
//! the foot to each actuator about the rest position (seed Sec. VI, Fig. 10).
//!
//! The formulation shares nothing with mech's: reduced coordinates are the two actuator
//! deflections `a = (a_swing, a_lift)`; the six flexure angles of the tree follow from the
//! three loop closures, solved by Gauss–Newton on the closure residual (an SVD step, Jacobian
//! by central differences); statics is the stationary point of the potential energy
//!
//!   V(a) = Σ ½ k_i θ_i² + Σ (½ k_a a_j² − F_j a_j) + g Σ m_i z_i,
//!
//! (tree and loop flexure angles θ_i, the actuators' springs k_a = F_b/δ_f and force sources
//! F_j = F_b V_j/V_rated, gravity on each link's centre of mass), its gradient by central
//! differences of V over closed configurations. A sensor holding the foot's coordinate `x_s`
//! adds the multiplier `f` (its force on the foot) and a side load `r f` along y:
//! `∂V/∂a = f (∂x_s/∂a + r ∂y_foot/∂a)`, `x_s(a) = target`. The linear dynamics about rest are
//! the 2×2 Hessian of V, the kinetic energy's mass matrix from each link's velocity and angular
//! velocity per unit actuator rate, and the flexures' hysteretic loss `η k_i` on their angles.
//!
//! The physical choices are the model header's (seed Table I actuators, the URDF's flexure
//! stiffnesses with the loop ones from `HAMRVariational_scaledV2_LB.urdf`, the leg's centre of
//! mass from `HAMR_scaledV2.urdf`, the fb2 loop points moved onto the fb2 axis through the
//! five-bar centre), restated here from the files, so the two agree only if both are right.

use std::collections::BTreeMap;

use nalgebra::{Complex, DMatrix, DVector, Matrix2, Matrix3, Rotation3, Unit, Vector2, Vector3};

/// Gravity (m/s²), as `models/hamr_vi.mech` states it.
const GRAVITY: f64 = 9.81;
/// The URDFs' units: mm, g, N·mm/rad.
const MM: f64 = 1e-3;
const GRAM: f64 = 1e-3;
/// Seed Table I, "new geometry" (PS 'b' process), HAMR-VI's actuators (Sec. V-B).
const BLOCKED_FORCE: f64 = 0.320;
const FREE_DEFLECTION: f64 = 300e-6;
const RATED_VOLTAGE: f64 = 225.0;
/// The castellated Kapton hinges' loss factor η'_m (seed Sec. IV-B).
const LOSS_FACTOR: f64 = 0.08;

// ---------------------------------------------------------------- a minimal XML reader

/// One XML element: its name, attributes and child elements (text content is not needed).
#[derive(Debug, Default)]
struct Element {
    name: String,
    attributes: Vec<(String, String)>,
    children: Vec<Element>,
}

impl Element {
    fn attribute(&self, name: &str) -> Option<&str> {
        self.attributes
            .iter()
            .find(|(key, _)| key == name)
            .map(|(_, value)| value.as_str())
    }
    fn child(&self, name: &str) -> Option<&Element> {
        self.children.iter().find(|c| c.name == name)
    }
    fn all<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Element> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }
    /// Every element named `name` anywhere below this one.
    fn descendants<'a>(&'a self, name: &str, found: &mut Vec<&'a Element>) {
        for child in &self.children {
            if child.name == name {
                found.push(child);
            }
            child.descendants(name, found);
        }
    }
}

/// The document's elements under a synthetic root. Enough XML for the URDFs: declarations and
/// comments skipped, attributes in double quotes (with blanks around `=`), no entities.
fn parse_xml(text: &str) -> Element {
    let mut stack = vec![Element::default()];
    let mut rest = text;
    while let Some(open) = rest.find('<') {
        rest = &rest[open..];
        if let Some(body) = rest.strip_prefix("<!--") {
            rest = &body[body.find("-->").expect("unclosed comment") + 3..];
            continue;
        }
        let end = rest.find('>').expect("unclosed tag");
        let tag = &rest[1..end];
        rest = &rest[end + 1..];
        if tag.starts_with('?') || tag.starts_with('!') {
            continue;
        }
        if let Some(name) = tag.strip_prefix('/') {
            let element = stack.pop().unwrap();
            assert_eq!(element.name, name.trim(), "mismatched end tag");
            stack.last_mut().unwrap().children.push(element);
            continue;
        }
        let (tag, closed) = match tag.strip_suffix('/') {
            Some(tag) => (tag, true),
            None => (tag, false),
        };
        let tag = tag.trim();
        let name_end = tag.find(char::is_whitespace).unwrap_or(tag.len());
        let mut element = Element {
            name: tag[..name_end].to_string(),
            ..Element::default()
        };
        let mut attributes = &tag[name_end..];
        while let Some(equals) = attributes.find('=') {
            let key = attributes[..equals].trim().to_string();
            let after = attributes[equals + 1..].trim_start();
            let value_start = after.find('"').expect("attribute value in quotes") + 1;
            let value_len = after[value_start..].find('"').expect("closing quote");
            let value = after[value_start..value_start + value_len].to_string();
            element.attributes.push((key, value));
            attributes = &after[value_start + value_len + 1..];
        }
        if closed {
            stack.last_mut().unwrap().children.push(element);
        } else {
            stack.push(element);
        }
    }
    assert_eq!(stack.len(), 1, "unclosed element");
    stack.pop().unwrap()
}

/// Numbers separated by blanks or commas (`"0 7.58, -11.35"` occurs in the files).
fn numbers(text: &str) -> Vec<f64> {
    text.split(|c: char| c.is_whitespace() || c == ',')
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().unwrap_or_else(|_| panic!("not a number: {s}")))
        .collect()
}

fn vector(text: &str) -> Vector3<f64> {
    let v = numbers(text);
    assert_eq!(v.len(), 3, "three numbers expected: {text}");
    Vector3::new(v[0], v[1], v[2])
}

fn read_urdf(file: &str) -> Element {
    let path = format!(
        "{}/../shared/reference/hamr-vi-urdf/{file}",
        env!("CARGO_MANIFEST_DIR")
    );
    parse_xml(&std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}")))
}

/// The torsional springs of a URDF (Drake's extension), by joint name (N·m/rad).
fn torsional_springs(robot: &Element) -> BTreeMap<String, f64> {
    let mut springs = Vec::new();
    robot.descendants("torsional_spring", &mut springs);
    springs
        .into_iter()
        .map(|s| {
            let joint = s.child("joint").unwrap().attribute("name").unwrap();
            let k: f64 = s.attribute("stiffness").unwrap().trim().parse().unwrap();
            (joint.to_string(), k * MM)
        })
        .collect()
}

// ---------------------------------------------------------------- the leg

/// A joint of the tree: the child link's frame is the parent's moved by `origin`, then turned
/// about (revolute) or slid along (prismatic) `axis` by the joint's coordinate.
#[derive(Debug, Clone)]
struct TreeJoint {
    name: String,
    parent: usize,
    child: usize,
    origin: Vector3<f64>,
    axis: Vector3<f64>,
    prismatic: bool,
    /// Flexure stiffness (N·m/rad), 0 for the actuators.
    stiffness: f64,
}

/// A loop closure: `point1` on `link1` and `point2` on `link2` coincide and the links turn
/// relative to each other about `axis` only (a revolute flexure of stiffness `stiffness`).
#[derive(Debug, Clone)]
struct LoopJoint {
    name: String,
    link1: usize,
    point1: Vector3<f64>,
    link2: usize,
    point2: Vector3<f64>,
    axis: Vector3<f64>,
    stiffness: f64,
}

/// A change to the leg as built (the hidden effect of a test).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Effect {
    /// The flexure on this joint (URDF name, e.g. `FLql2`) this many times stiffer.
    FlexureStiffness(&'static str, f64),
    /// The actuator's stiffness k_a times this factor, its force source as built (the free
    /// deflection divided by the factor).
    ActuatorStiffness(Actuator, f64),
    /// The actuator's force source times this factor.
    ActuatorForce(Actuator, f64),
    /// The actuator's base on a spring `k_a / c` in series with it (its clamp gives).
    BaseCompliance(Actuator, f64),
    /// This mass (kg) added to the actuator's slider (its tip).
    TipMass(Actuator, f64),
    /// Every flexure's loss factor this value instead of the seed's 0.08.
    LossFactor(f64),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Actuator {
    Swing = 0,
    Lift = 1,
}

/// A link's mass (kg), centre of mass in its frame (m), inertia about the centre of mass in
/// the link's axes (kg·m², tensor convention).
#[derive(Debug, Clone, Copy)]
struct Inertial {
    mass: f64,
    com: Vector3<f64>,
    inertia: Matrix3<f64>,
}

/// Link poses in the chassis frame: rotation and origin.
type Poses = Vec<(Matrix3<f64>, Vector3<f64>)>;

pub struct IndependentLeg {
    links: Vec<String>,
    /// Each link's mass (kg), centre of mass in its frame (m) and inertia about it in its
    /// axes (kg·m²).
    inertial: Vec<Inertial>,
    /// In order from the chassis (parents before children).
    joints: Vec<TreeJoint>,
    loops: Vec<LoopJoint>,
    /// The two actuators' joint indices (swing, lift).
    actuators: [usize; 2],
    foot_link: usize,
    foot: Vector3<f64>,
    /// Per actuator: stiffness, force at the rated voltage, base spring (∞: rigid).
    actuator_stiffness: [f64; 2],
    actuator_force: [f64; 2],
    base_stiffness: [f64; 2],
    /// Mass added to each actuator's slider (kg).
    tip_mass: [f64; 2],
    /// The flexures' loss factor (hysteretic damping, `k (1 + iη)`).
    loss_factor: f64,
    /// The last closed configuration: the next closure starts there.
    last_q: std::cell::RefCell<Vec<f64>>,
}

impl IndependentLeg {
    /// HAMR-VI's front-left leg from `FL_scaled.urdf` (tree, foot, tree flexures), the loop
    /// flexures from `HAMRVariational_scaledV2_LB.urdf` and the leg's centre of mass from
    /// `HAMR_scaledV2.urdf`, with `effects`.
    pub fn hamr_vi(effects: &[Effect]) -> IndependentLeg {
        let urdf = read_urdf("FL_scaled.urdf");
        let robot = urdf.child("robot").unwrap();
        let whole = read_urdf("HAMR_scaledV2.urdf");
        let whole = whole.child("robot").unwrap();
        let loop_urdf = read_urdf("HAMRVariational_scaledV2_LB.urdf");
        let mut springs = torsional_springs(robot);
        let loop_springs = torsional_springs(loop_urdf.child("robot").unwrap());

        let link_element = |robot: &'_ Element, name: &str| -> Option<Inertial> {
            let link = robot
                .all("link")
                .find(|l| l.attribute("name") == Some(name))?;
            let inertial = link.child("inertial")?;
            let mass: f64 = inertial
                .child("mass")?
                .attribute("value")?
                .trim()
                .parse()
                .ok()?;
            let com = vector(inertial.child("origin")?.attribute("xyz")?);
            let tensor = inertial.child("inertia")?;
            let moment = |key: &str| -> Option<f64> { tensor.attribute(key)?.trim().parse().ok() };
            let (xx, yy, zz) = (moment("ixx")?, moment("iyy")?, moment("izz")?);
            let (xy, xz, yz) = (moment("ixy")?, moment("ixz")?, moment("iyz")?);
            let inertia = Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz);
            Some(Inertial {
                mass: mass * GRAM,
                com: com * MM,
                inertia: inertia * GRAM * MM * MM,
            })
        };
        let links: Vec<String> = robot
            .all("link")
            .map(|l| l.attribute("name").unwrap().to_string())
            .collect();
        let inertial = links
            .iter()
            .map(|name| {
                // The leg's (FLL4) inertial data of FL_scaled.urdf put its centre of mass
                // above the five-bar although the leg hangs below it (reference/README.md):
                // the whole robot's file is used for it, as in the model, with its products
                // of inertia negated (they then match the split links of the LB file).
                if name == "FLL4" {
                    let leg = link_element(whole, name).unwrap();
                    let mut inertia = -leg.inertia;
                    inertia.set_diagonal(&leg.inertia.diagonal());
                    Inertial { inertia, ..leg }
                } else {
                    link_element(robot, name).unwrap()
                }
            })
            .collect();
        let index = |name: &str| links.iter().position(|l| l == name).unwrap();

        let mut joints = Vec::new();
        for joint in robot.all("joint") {
            let name = joint.attribute("name").unwrap().to_string();
            let kind = joint.attribute("type").unwrap();
            let stiffness = springs.remove(&name).unwrap_or(0.0);
            joints.push(TreeJoint {
                parent: index(joint.child("parent").unwrap().attribute("link").unwrap()),
                child: index(joint.child("child").unwrap().attribute("link").unwrap()),
                origin: vector(joint.child("origin").unwrap().attribute("xyz").unwrap()) * MM,
                axis: vector(joint.child("axis").unwrap().attribute("xyz").unwrap()),
                prismatic: kind == "prismatic",
                stiffness,
                name,
            });
        }
        // Parents before children.
        let mut ordered: Vec<TreeJoint> = Vec::new();
        let mut placed = vec![false; links.len()];
        placed[index("Chassis")] = true;
        while ordered.len() < joints.len() {
            let before = ordered.len();
            for joint in &joints {
                if placed[joint.parent] && !placed[joint.child] {
                    placed[joint.child] = true;
                    ordered.push(joint.clone());
                }
            }
            assert!(
                ordered.len() > before,
                "a link not reached from the chassis"
            );
        }
        assert!(springs.is_empty(), "springs on unknown joints: {springs:?}");

        let mut loops: Vec<LoopJoint> = robot
            .all("loop_joint")
            .map(|l| {
                let name = l.attribute("name").unwrap().to_string();
                let end = |tag: &str| {
                    let e = l.child(tag).unwrap();
                    (
                        index(e.attribute("link").unwrap()),
                        vector(e.attribute("xyz").unwrap()) * MM,
                    )
                };
                let ((link1, point1), (link2, point2)) = (end("link1"), end("link2"));
                LoopJoint {
                    stiffness: loop_springs[&name],
                    axis: vector(l.child("axis").unwrap().attribute("xyz").unwrap()),
                    name,
                    link1,
                    point1,
                    link2,
                    point2,
                }
            })
            .collect();

        let foot_link = index("FLL4");
        let foot = robot
            .all("link")
            .find(|l| l.attribute("name") == Some("FLL4"))
            .and_then(|l| l.child("collision"))
            .and_then(|c| c.child("origin"))
            .map(|o| vector(o.attribute("xyz").unwrap()) * MM)
            .unwrap();
        let actuators =
            ["FLqsact", "FLqlact"].map(|name| ordered.iter().position(|j| j.name == name).unwrap());
        let stiffness = BLOCKED_FORCE / FREE_DEFLECTION;
        let mut leg = IndependentLeg {
            links,
            inertial,
            joints: ordered,
            loops: Vec::new(),
            actuators,
            foot_link,
            foot,
            actuator_stiffness: [stiffness; 2],
            actuator_force: [BLOCKED_FORCE; 2],
            base_stiffness: [f64::INFINITY; 2],
            tip_mass: [0.0; 2],
            loss_factor: LOSS_FACTOR,
            last_q: Default::default(),
        };
        // The fb2 loop points of FL_scaled.urdf miss the fb2 axis through the five-bar centre
        // P by 1.44e-7 mm (reference/README.md): moved onto it, as the model does. P is where
        // the s3 and l3 loop axes (chassis-fixed) meet.
        let centre = leg.five_bar_centre(&loops);
        let poses = leg.poses(&vec![0.0; leg.joints.len()]);
        for closure in &mut loops {
            if closure.name != "FLqfb2" {
                continue;
            }
            for (link, point) in [
                (closure.link1, &mut closure.point1),
                (closure.link2, &mut closure.point2),
            ] {
                let (rotation, origin) = poses[link];
                let world = rotation * *point + origin;
                let axis = rotation * closure.axis;
                let on_axis = centre + axis * axis.dot(&(world - centre));
                *point = rotation.transpose() * (on_axis - origin);
            }
        }
        leg.loops = loops;
        *leg.last_q.borrow_mut() = vec![0.0; leg.joints.len()];
        for effect in effects {
            leg.apply(*effect);
        }
        leg
    }

    fn apply(&mut self, effect: Effect) {
        match effect {
            Effect::FlexureStiffness(joint, factor) => {
                let spring = self
                    .joints
                    .iter_mut()
                    .map(|j| (&j.name, &mut j.stiffness))
                    .chain(self.loops.iter_mut().map(|l| (&l.name, &mut l.stiffness)))
                    .find(|(name, _)| name.as_str() == joint)
                    .unwrap_or_else(|| panic!("no flexure on {joint}"));
                *spring.1 *= factor;
            }
            Effect::ActuatorStiffness(a, factor) => self.actuator_stiffness[a as usize] *= factor,
            Effect::ActuatorForce(a, factor) => self.actuator_force[a as usize] *= factor,
            Effect::BaseCompliance(a, c) => {
                self.base_stiffness[a as usize] = self.actuator_stiffness[a as usize] / c
            }
            Effect::TipMass(a, mass) => self.tip_mass[a as usize] += mass,
            Effect::LossFactor(eta) => self.loss_factor = eta,
        }
    }

    /// The point where the chassis-fixed loop axes (s3 about z, l3 about x) meet.
    fn five_bar_centre(&self, loops: &[LoopJoint]) -> Vector3<f64> {
        let chassis = self.links.iter().position(|l| l == "Chassis").unwrap();
        let fixed: Vec<&LoopJoint> = loops.iter().filter(|l| l.link1 == chassis).collect();
        assert_eq!(fixed.len(), 2, "two loops on the chassis");
        // Closest point of line 1 to line 2 (they intersect in the published geometry).
        let (p1, d1, p2, d2) = (
            fixed[0].point1,
            fixed[0].axis,
            fixed[1].point1,
            fixed[1].axis,
        );
        let w = p1 - p2;
        let (b, d, e) = (d1.dot(&d2), d1.dot(&w), d2.dot(&w));
        let s = (b * e - d2.dot(&d2) * d) / (d1.dot(&d1) * d2.dot(&d2) - b * b);
        p1 + d1 * s
    }

    /// Each link's pose in the chassis frame at joint coordinates `q` (tree order).
    fn poses(&self, q: &[f64]) -> Poses {
        let mut poses = vec![(Matrix3::identity(), Vector3::zeros()); self.links.len()];
        for (joint, &value) in self.joints.iter().zip(q) {
            let (rotation, origin) = poses[joint.parent];
            let at = origin + rotation * joint.origin;
            poses[joint.child] = if joint.prismatic {
                (rotation, at + rotation * joint.axis * value)
            } else {
                let turn = Rotation3::from_axis_angle(&Unit::new_normalize(joint.axis), value);
                (rotation * turn.matrix(), at)
            };
        }
        poses
    }

    /// The closure residual (m for the points, rad for the axes): per loop the two points'
    /// separation and the two components of link 2's axis ⊥ link 1's.
    fn residual(&self, q: &[f64]) -> DVector<f64> {
        let poses = self.poses(q);
        let mut r = Vec::with_capacity(5 * self.loops.len());
        for closure in &self.loops {
            let (r1, o1) = poses[closure.link1];
            let (r2, o2) = poses[closure.link2];
            let gap = (r1 * closure.point1 + o1) - (r2 * closure.point2 + o2);
            r.extend(gap.iter());
            let relative_axis = r1.transpose() * r2 * closure.axis;
            let (e1, e2) = perpendiculars(&closure.axis);
            r.push(e1.dot(&relative_axis));
            r.push(e2.dot(&relative_axis));
        }
        DVector::from_vec(r)
    }

    /// The tree coordinates with the actuators at `a`, the loops closed (Gauss–Newton from the
    /// last closed configuration).
    fn close(&self, a: [f64; 2]) -> Vec<f64> {
        let mut q = self.last_q.borrow().clone();
        for (k, &joint) in self.actuators.iter().enumerate() {
            q[joint] = a[k];
        }
        let free: Vec<usize> = (0..q.len())
            .filter(|i| !self.actuators.contains(i))
            .collect();
        for _ in 0..50 {
            let r = self.residual(&q);
            if r.amax() < 1e-16 {
                break;
            }
            let h = 1e-7;
            let mut jacobian = DMatrix::zeros(r.len(), free.len());
            for (column, &i) in free.iter().enumerate() {
                let mut plus = q.clone();
                plus[i] += h;
                let mut minus = q.clone();
                minus[i] -= h;
                jacobian.set_column(
                    column,
                    &((self.residual(&plus) - self.residual(&minus)) / (2.0 * h)),
                );
            }
            let step = jacobian.svd(true, true).solve(&r, 1e-12).unwrap();
            for (column, &i) in free.iter().enumerate() {
                q[i] -= step[column];
            }
            if step.amax() < 1e-15 {
                break;
            }
        }
        let r = self.residual(&q);
        assert!(r.amax() < 1e-13, "the loops do not close at {a:?}: {r}");
        *self.last_q.borrow_mut() = q.clone();
        q
    }

    /// The foot in the chassis frame (m) at closed coordinates `q`.
    fn foot_at(&self, q: &[f64]) -> Vector3<f64> {
        let (rotation, origin) = self.poses(q)[self.foot_link];
        rotation * self.foot + origin
    }

    /// The potential energy (J) with the actuators at `a` driven by `volts` (swing, lift).
    fn energy(&self, a: [f64; 2], volts: [f64; 2]) -> f64 {
        let q = self.close(a);
        let poses = self.poses(&q);
        let mut v = 0.0;
        for (stiffness, angle) in self.flexures(&q, &poses) {
            v += 0.5 * stiffness * angle * angle;
        }
        for k in 0..2 {
            // A force source F in parallel with k_a, on a base spring k_b in series: the base
            // settles where k_b b = k_a (a − b) − F, leaving the series spring's energy
            // ½ k_s (a − F/k_a)² with k_s = k_a k_b/(k_a + k_b), up to a constant.
            let force = self.actuator_force[k] * volts[k] / RATED_VOLTAGE;
            let (ka, kb) = (self.actuator_stiffness[k], self.base_stiffness[k]);
            let series = if kb.is_infinite() {
                ka
            } else {
                ka * kb / (ka + kb)
            };
            let rest = force / ka;
            v += 0.5 * series * (a[k] - rest) * (a[k] - rest);
        }
        for (link, (rotation, origin)) in self.inertial.iter().zip(&poses) {
            v += link.mass * GRAVITY * (rotation * link.com + origin).z;
        }
        v
    }

    /// Every flexure's stiffness and angle at closed coordinates `q` (tree, then loops; the
    /// loop angle is link 2's turn relative to link 1 about the loop's axis).
    fn flexures(&self, q: &[f64], poses: &Poses) -> Vec<(f64, f64)> {
        let tree = self
            .joints
            .iter()
            .zip(q)
            .filter(|(joint, _)| !joint.prismatic)
            .map(|(joint, &angle)| (joint.stiffness, angle));
        let loops = self.loops.iter().map(|closure| {
            let turn = poses[closure.link1].0.transpose() * poses[closure.link2].0;
            let (e1, e2) = perpendiculars(&closure.axis);
            let angle = (e2.dot(&(turn * e1))).atan2(e1.dot(&(turn * e1)));
            (closure.stiffness, angle)
        });
        tree.chain(loops).collect()
    }

    /// `∂f/∂a` by central differences (step 1 nm).
    fn gradient(&self, f: impl Fn([f64; 2]) -> f64, a: [f64; 2]) -> [f64; 2] {
        let h = 1e-9;
        [0, 1].map(|k| {
            let (mut plus, mut minus) = (a, a);
            plus[k] += h;
            minus[k] -= h;
            (f(plus) - f(minus)) / (2.0 * h)
        })
    }

    /// The equilibrium with the actuators driven by `volts` (swing, lift), started at `a`;
    /// with a sensor `(axis, target, r)` holding the foot's `axis` component at `target` and
    /// pushing along y with `r` times its on-axis force: the actuators' deflections and the
    /// sensor's on-axis force on the foot (N).
    fn equilibrium(
        &self,
        mut a: [f64; 2],
        volts: [f64; 2],
        sensor: Option<(usize, f64, f64)>,
    ) -> ([f64; 2], f64) {
        let mut force = 0.0;
        let equations = |a: [f64; 2], force: f64| -> Vec<f64> {
            let dv = self.gradient(|a| self.energy(a, volts), a);
            match sensor {
                None => dv.to_vec(),
                Some((axis, target, r)) => {
                    let dx = self.gradient(|a| self.foot_at(&self.close(a))[axis], a);
                    let dy = self.gradient(|a| self.foot_at(&self.close(a)).y, a);
                    let held = self.foot_at(&self.close(a))[axis] - target;
                    vec![
                        dv[0] - force * (dx[0] + r * dy[0]),
                        dv[1] - force * (dx[1] + r * dy[1]),
                        held,
                    ]
                }
            }
        };
        for iteration in 0.. {
            let e = equations(a, force);
            // Newton, the Jacobian by central differences (the equations are linear in force).
            let n = e.len();
            let h = 1e-8;
            let mut jacobian = DMatrix::zeros(n, n);
            for k in 0..n {
                let (mut ap, mut am, mut fp, mut fm) = (a, a, force, force);
                if k < 2 {
                    ap[k] += h;
                    am[k] -= h;
                } else {
                    fp += 1.0;
                    fm -= 1.0;
                }
                let (ep, em) = (equations(ap, fp), equations(am, fm));
                let width = if k < 2 { 2.0 * h } else { 2.0 };
                for row in 0..n {
                    jacobian[(row, k)] = (ep[row] - em[row]) / width;
                }
            }
            let step = jacobian.lu().solve(&DVector::from_vec(e)).unwrap();
            a[0] -= step[0];
            a[1] -= step[1];
            if n == 3 {
                force -= step[2];
            }
            // The gradient's noise (~1e-11 N against k_a ≈ 1e3 N/m) floors the step near 1e-14 m.
            if step.rows(0, 2).amax() < 1e-12 {
                break;
            }
            assert!(iteration < 40, "no equilibrium: step {step}");
        }
        (a, force)
    }

    /// The leg linearized about its rest position: the response of the foot to each
    /// actuator's voltage at `frequency` (Hz), lift (v_lift → foot z) then swing (v_swing →
    /// foot x), in m/V: `C (K + i K_η − ω² M)⁻¹ B`, with K the Hessian of the potential
    /// energy (gravity's share included), M the kinetic energy's `Σ m vᵀv + ωᵀ I ω` over the
    /// links, `K_η = η Σ k_i ∇θ_i ∇θ_iᵀ` the flexures' hysteretic loss, B the actuator forces
    /// per volt and C the foot's gradient, all differenced over closed configurations.
    pub fn frequency_response(&self, frequencies: &[f64]) -> Vec<[Complex<f64>; 2]> {
        let (rest, _) = self.equilibrium([0.0; 2], [0.0; 2], None);
        let h = 1e-7;
        let shifted = |k: usize, sign: f64| {
            let mut a = rest;
            a[k] += sign * h;
            a
        };
        let mut stiffness = Matrix2::zeros();
        for k in 0..2 {
            let plus = self.gradient(|a| self.energy(a, [0.0; 2]), shifted(k, 1.0));
            let minus = self.gradient(|a| self.energy(a, [0.0; 2]), shifted(k, -1.0));
            for j in 0..2 {
                stiffness[(j, k)] = (plus[j] - minus[j]) / (2.0 * h);
            }
        }
        let stiffness = (stiffness + stiffness.transpose()) / 2.0;

        let rest_poses = self.poses(&self.close(rest));
        // Per coordinate: each link's centre-of-mass velocity and angular velocity (chassis
        // frame) per unit rate, each flexure's angle rate, the foot's velocity.
        let mut velocities = Vec::new();
        let mut angle_rates = Vec::new();
        let mut foot_rates = Vec::new();
        for k in 0..2 {
            let (q_plus, q_minus) = (self.close(shifted(k, 1.0)), self.close(shifted(k, -1.0)));
            let (plus, minus) = (self.poses(&q_plus), self.poses(&q_minus));
            let link_rates: Vec<(Vector3<f64>, Vector3<f64>)> = (0..self.links.len())
                .map(|i| {
                    let com = |p: &Poses| p[i].0 * self.inertial[i].com + p[i].1;
                    let v = (com(&plus) - com(&minus)) / (2.0 * h);
                    // Ṙ Rᵀ = [ω]×.
                    let spin = (plus[i].0 - minus[i].0) / (2.0 * h) * rest_poses[i].0.transpose();
                    (v, Vector3::new(spin[(2, 1)], spin[(0, 2)], spin[(1, 0)]))
                })
                .collect();
            velocities.push(link_rates);
            let (fp, fm) = (
                self.flexures(&q_plus, &plus),
                self.flexures(&q_minus, &minus),
            );
            angle_rates.push(
                fp.iter()
                    .zip(&fm)
                    .map(|(p, m)| (p.1 - m.1) / (2.0 * h))
                    .collect::<Vec<f64>>(),
            );
            foot_rates.push((self.foot_at(&q_plus) - self.foot_at(&q_minus)) / (2.0 * h));
        }
        let mut mass = Matrix2::from_diagonal(&Vector2::from(self.tip_mass));
        let mut loss = Matrix2::zeros();
        let springs = self.flexures(&self.close(rest), &rest_poses);
        for j in 0..2 {
            for k in 0..2 {
                for (i, link) in self.inertial.iter().enumerate() {
                    let rotation = rest_poses[i].0;
                    let inertia = rotation * link.inertia * rotation.transpose();
                    let (vj, wj) = velocities[j][i];
                    let (vk, wk) = velocities[k][i];
                    mass[(j, k)] += link.mass * vj.dot(&vk) + wj.dot(&(inertia * wk));
                }
                for (f, (stiffness, _)) in springs.iter().enumerate() {
                    loss[(j, k)] +=
                        self.loss_factor * stiffness * angle_rates[j][f] * angle_rates[k][f];
                }
            }
        }
        // Generalized force per volt on each actuator coordinate: F_b/V_rated through the
        // base spring's share k_s/k_a (1 without a base spring).
        let per_volt = [0, 1].map(|k| {
            let (ka, kb) = (self.actuator_stiffness[k], self.base_stiffness[k]);
            let share = if kb.is_infinite() {
                1.0
            } else {
                kb / (ka + kb)
            };
            share * self.actuator_force[k] / RATED_VOLTAGE
        });
        let channels = [(Actuator::Lift as usize, 2), (Actuator::Swing as usize, 0)];
        frequencies
            .iter()
            .map(|&f| {
                let omega = 2.0 * std::f64::consts::PI * f;
                let dynamic = Matrix2::from_fn(|r, c| {
                    Complex::new(
                        stiffness[(r, c)] - omega * omega * mass[(r, c)],
                        loss[(r, c)],
                    )
                });
                let inverse = dynamic.try_inverse().expect("a regular dynamic stiffness");
                channels.map(|(input, axis)| {
                    (0..2)
                        .map(|k| foot_rates[k][axis] * inverse[(k, input)] * per_volt[input])
                        .sum()
                })
            })
            .collect()
    }

    /// The force/deflection test of the actuator `dof` at `voltage` (seed Sec. V-A, as
    /// `mech::experiments::leg::ForceTest` defines it): the foot's rest and free positions,
    /// then the sensor (a plane ⊥ `axis`) at each of `distances` from the rest position along
    /// the free motion, pushing along y with `off_axis` times its force against the free
    /// foot's y motion. Returns the free deflection (m, ≥ 0) and the force on the sensor at
    /// each distance (N; 0 beyond the free deflection).
    pub fn force_test(
        &self,
        dof: Actuator,
        axis: usize,
        voltage: f64,
        distances: &[f64],
        off_axis: f64,
    ) -> (f64, Vec<f64>) {
        let (rest_a, _) = self.equilibrium([0.0; 2], [0.0; 2], None);
        let rest = self.foot_at(&self.close(rest_a));
        let mut volts = [0.0; 2];
        volts[dof as usize] = voltage;
        let (free_a, _) = self.equilibrium(rest_a, volts, None);
        let free = self.foot_at(&self.close(free_a));
        let signed = free[axis] - rest[axis];
        let direction = if signed < 0.0 { -1.0 } else { 1.0 };
        let y_direction = if free.y < rest.y { -1.0 } else { 1.0 };
        let load = y_direction * off_axis * direction;
        let mut a = rest_a;
        let forces = distances
            .iter()
            .map(|&distance| {
                if distance > signed.abs() {
                    return 0.0;
                }
                let target = rest[axis] + direction * distance;
                let (solved, force) = self.equilibrium(a, volts, Some((axis, target, load)));
                a = solved;
                -force * direction
            })
            .collect();
        (signed.abs(), forces)
    }
}

/// Two unit vectors ⊥ `axis` and to each other, `e1 × e2 = axis` (for a coordinate axis).
fn perpendiculars(axis: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let helper = if axis.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = axis.cross(&helper).normalize();
    (e1, axis.cross(&e1))
}
