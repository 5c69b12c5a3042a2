//! Effects written into HAMR-VI's `.mech` text by hand, independently of the model
//! transformations `mech diagnose` fits (`ir::transform::{actuator, hinge}`): the truths of
//! the diagnosis catalog's hidden-effect data.
//!
//! The hinge effects use nothing but pins, rigid revolute loops and flexure records: each
//! hinge gains two pins in series with it, about two directions ⊥ its axis through its
//! point, with flexures of their own (same loss factor). The transformation instead inserts
//! frames into the tree and, at a loop closure, springs on the closure's twist and lateral
//! angles (`ClosureKind::Revolute`'s `twist_axis`); the two agree to first order in the
//! off-axis angles, and equal stiffnesses about two ⊥ directions do not depend on which two.

use std::path::Path;

use mech::experiments::leg::Leg;

/// An effect written into HAMR-VI's text ([`hamr_vi_written`]).
#[derive(Clone, Copy, Debug)]
pub enum WrittenEffect {
    /// The lift actuator on a base body that slides along y on its own spring
    /// `k_b = k_a / c` (`k_a = F_b/δ_f`); the base weighs 1 mg (the force tests are static).
    LiftBaseCompliance(f64),
    /// This much mass (kg) added to the lift actuator's slider body.
    LiftTipMass(f64),
    /// Both actuators' slider joints moved this far (m) along their axes (+y): the springs
    /// rest there.
    Preload(f64),
    /// The lift actuator's stiffness `k_a = F_b/δ_f` times this factor, its blocked force
    /// as written (its free deflection divided by the factor).
    LiftActuatorStiffness(f64),
    /// The lift actuator's force source times this factor, its stiffness as written (blocked
    /// force and free deflection both times the factor).
    LiftActuatorForce(f64),
    /// A force along y at the foot, the parameter `side_force` (N, 0 as written), for a
    /// sensor's side load computed outside the model ([`FOOT_SIDE_FORCE`]).
    FootSideForce,
    /// Each of `hinges` (flexure, coordinate axis 0 = x, 1 = y, 2 = z) also twists about its
    /// axis with Eq. 8's stiffness `2k/(1 + ν)`, ν = 0.34, and bends about the third axis
    /// with `k/off_axis_compliance`; every other hinge is compliant off its axis,
    /// `k/off_axis_compliance` about both other coordinate axes.
    Twist {
        hinges: &'static [(&'static str, usize)],
        off_axis_compliance: f64,
    },
    /// Flexure `flexure`'s bending axis turned by `angle` (rad) about the coordinate axis
    /// `about`, and every hinge compliant off its axis (`k/off_axis_compliance` about two
    /// directions ⊥ it: the tilted hinge's turned with it).
    Tilt {
        flexure: &'static str,
        about: usize,
        angle: f64,
        off_axis_compliance: f64,
    },
}

/// The parameter of [`WrittenEffect::FootSideForce`].
pub const FOOT_SIDE_FORCE: &str = "side_force";

/// Poisson's ratio of Kapton (Doshi et al. Sec. V-A) in Eq. 8's twist stiffness.
const POISSON_RATIO: f64 = 0.34;

/// `text` with the one occurrence of `from` replaced by `to` (panics unless exactly one).
fn replace_once(text: &str, from: &str, to: &str) -> String {
    assert_eq!(text.matches(from).count(), 1, "`{from}` must occur once");
    text.replacen(from, to, 1)
}

/// HAMR-VI with `effect` written into its text, saved in `dir` and opened as a leg.
pub fn hamr_vi_written(effect: WrittenEffect, dir: &Path) -> Leg {
    let lift_joint = "joint qlact = slider(newtonian, lift_slider) {\n    axis = y;\n    \
                      parent_point = [10.504659815390 mm, 3.151779821480 mm, \
                      -0.501688531240 mm + lift_shift];\n}";
    let source = super::bundled_source("hamr_vi");
    let text = match effect {
        WrittenEffect::LiftBaseCompliance(c) => {
            let base = format!(
                "body lift_base {{ mass = 1 mg; }}\n\
                 joint qlbase = slider(newtonian, lift_base) {{\n    axis = y;\n    \
                 parent_point = [10.504659815390 mm, 3.151779821480 mm, \
                 -0.501688531240 mm + lift_shift];\n    stiffness = F_b / delta_f / {c:e};\n}}\n\
                 joint qlact = slider(lift_base, lift_slider) {{ axis = y; }}"
            );
            replace_once(&source, lift_joint, &base)
        }
        WrittenEffect::LiftTipMass(mass) => replace_once(
            &source,
            "mass = 4.5174e-3 g;",
            &format!("mass = 4.5174e-3 g + {mass:e} kg;"),
        ),
        WrittenEffect::Preload(offset) => {
            let text = replace_once(
                &source,
                "3.151779821480 mm, -0.501688531240 mm + lift_shift]",
                &format!("3.151779821480 mm + {offset:e} m, -0.501688531240 mm + lift_shift]"),
            );
            replace_once(
                &text,
                "1.456684126580 mm, -0.478250429210 mm]",
                &format!("1.456684126580 mm + {offset:e} m, -0.478250429210 mm]"),
            )
        }
        WrittenEffect::LiftActuatorStiffness(factor) => {
            lift_actuator(&source, "F_b", &format!("delta_f / {factor:e}"))
        }
        WrittenEffect::LiftActuatorForce(factor) => lift_actuator(
            &source,
            &format!("F_b * {factor:e}"),
            &format!("delta_f * {factor:e}"),
        ),
        WrittenEffect::FootSideForce => format!(
            "{source}\nparam {FOOT_SIDE_FORCE} = 0 N;\n\
             force sensor_side at leg.foot = [0, {FOOT_SIDE_FORCE}, 0] in newtonian;\n"
        ),
        WrittenEffect::Twist {
            hinges,
            off_axis_compliance,
        } => compliant_hinges(&source, off_axis_compliance, |name, axis| {
            let others = [(axis + 1) % 3, (axis + 2) % 3];
            let Some(&(_, about)) = hinges.iter().find(|(flexure, _)| *flexure == name) else {
                return HingeSprings::off_axis(axis, others);
            };
            assert!(
                others.contains(&about),
                "{name} cannot twist about its axis"
            );
            let lateral = others[0] + others[1] - about;
            let eq8 = format!("* 2 / (1 + {POISSON_RATIO})");
            HingeSprings {
                axis: unit(axis),
                springs: vec![(unit(about), eq8), (unit(lateral), String::new())],
            }
        }),
        WrittenEffect::Tilt {
            flexure,
            about,
            angle,
            off_axis_compliance,
        } => compliant_hinges(&source, off_axis_compliance, |name, axis| {
            let mut springs = HingeSprings::off_axis(axis, [(axis + 1) % 3, (axis + 2) % 3]);
            if name == flexure {
                springs.axis = rotated(springs.axis, about, angle);
                for (direction, _) in &mut springs.springs {
                    *direction = rotated(*direction, about, angle);
                }
            }
            springs
        }),
    };
    let path = dir.join("hamr_vi_written.mech");
    std::fs::write(&path, text).unwrap();
    Leg::open(&mech::session::ModelSpec {
        path,
        ..super::hamr_vi_spec()
    })
    .unwrap_or_else(|e| panic!("{effect:?}: {e}"))
}

/// `source` with the lift actuator's blocked force and free deflection written as given.
fn lift_actuator(source: &str, blocked_force: &str, free_deflection: &str) -> String {
    replace_once(
        source,
        "actuator lift on qlact {\n    blocked_force = F_b;\n    free_deflection = delta_f;",
        &format!(
            "actuator lift on qlact {{\n    blocked_force = {blocked_force};\n    \
             free_deflection = {free_deflection};"
        ),
    )
}

/// A hinge as rewritten by [`compliant_hinges`]: its bending axis, and the directions of the
/// pins added in series with it, each with its stiffness as a factor on the flexure's
/// (text appended to `k`; empty for `k/c`).
struct HingeSprings {
    axis: [f64; 3],
    springs: Vec<([f64; 3], String)>,
}

impl HingeSprings {
    /// Bending about the coordinate axis `axis`, `k/c` about the coordinate axes `others`.
    fn off_axis(axis: usize, others: [usize; 2]) -> Self {
        HingeSprings {
            axis: unit(axis),
            springs: others.map(|o| (unit(o), String::new())).to_vec(),
        }
    }
}

fn unit(axis: usize) -> [f64; 3] {
    let mut e = [0.0; 3];
    e[axis] = 1.0;
    e
}

/// `v` turned by `angle` about the coordinate axis `about` (Rodrigues:
/// `v cos α + (p × v) sin α + p (p·v)(1 − cos α)`).
fn rotated(v: [f64; 3], about: usize, angle: f64) -> [f64; 3] {
    let p = unit(about);
    let p_cross_v = [
        p[1] * v[2] - p[2] * v[1],
        p[2] * v[0] - p[0] * v[2],
        p[0] * v[1] - p[1] * v[0],
    ];
    std::array::from_fn(|i| {
        v[i] * angle.cos() + p_cross_v[i] * angle.sin() + p[i] * v[about] * (1.0 - angle.cos())
    })
}

/// `source` with every flexure's hinge (a `pin` joint or a `revolute` loop with only `axis`,
/// `parent_point` and `child_point` fields, the axis a coordinate axis) rewritten as
/// `springs(flexure, axis index)` says: massless links on pins about the spring directions
/// between the hinge's parent and the hinge, each pin a flexure of stiffness `k/c` (or `k`
/// times the given factor) with the hinge flexure's other fields.
fn compliant_hinges(source: &str, c: f64, springs: impl Fn(&str, usize) -> HingeSprings) -> String {
    let flexures: Vec<(String, String, Fields)> = source
        .lines()
        .filter_map(|line| {
            let rest = line.strip_prefix("flexure ")?;
            let (name, rest) = rest.split_once(" on ")?;
            let (joint, rest) = rest.split_once(" {")?;
            let fields = fields(rest.trim_end().strip_suffix('}').unwrap());
            Some((name.to_string(), joint.to_string(), fields))
        })
        .collect();
    assert!(flexures.len() >= 9, "HAMR-VI's nine flexures");
    let mut text = source.to_string();
    let mut added = String::new();
    for (flexure, joint, flexure_fields) in &flexures {
        let hinge = Declaration::find(&text, joint);
        let axis = match hinge.field("axis") {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            other => panic!("{joint}: axis `{other}` is not a coordinate axis"),
        };
        let rewrite = springs(flexure, axis);
        let stiffness = flexure_fields
            .iter()
            .find(|(key, _)| key == "stiffness")
            .map(|(_, value)| value.as_str())
            .unwrap();
        let mut parent = hinge.parent.clone();
        for (k, (direction, factor)) in rewrite.springs.iter().enumerate() {
            let (pin, link) = (format!("{joint}_off_{k}"), format!("{joint}_link_{k}"));
            let point = match (k, hinge.optional("parent_point")) {
                (0, Some(point)) => format!(" parent_point = {point};"),
                _ => String::new(),
            };
            let spring = match factor.as_str() {
                "" => format!("({stiffness}) / {c:e}"),
                factor => format!("({stiffness}) {factor}"),
            };
            let others: String = flexure_fields
                .iter()
                .filter(|(key, _)| key != "stiffness")
                .map(|(key, value)| format!(" {key} = {value};"))
                .collect();
            added += &format!(
                "body {link} {{ mass = 0 g; }}\n\
                 joint {pin} = pin({parent}, {link}) {{ axis = {};{point} }}\n\
                 flexure {flexure}_off_{k} on {pin} {{ stiffness = {spring};{others} }}\n",
                vector(direction)
            );
            parent = link;
        }
        let child_point = hinge
            .optional("child_point")
            .map(|point| format!(" child_point = {point};"))
            .unwrap_or_default();
        let rewritten = format!(
            "{} {joint} = {}({parent}, {}) {{ axis = {};{child_point} }}",
            hinge.keyword,
            hinge.kind,
            hinge.child,
            vector(&rewrite.axis)
        );
        text.replace_range(hinge.range, &rewritten);
    }
    text + "\n" + &added
}

fn vector(v: &[f64; 3]) -> String {
    format!("[{}, {}, {}]", v[0], v[1], v[2])
}

/// A declaration's fields, `(key, value)`.
type Fields = Vec<(String, String)>;

/// `key = value; ...` as pairs.
fn fields(text: &str) -> Fields {
    text.split(';')
        .map(str::trim)
        .filter(|field| !field.is_empty())
        .map(|field| {
            let (key, value) = field.split_once('=').unwrap();
            (key.trim().to_string(), value.trim().to_string())
        })
        .collect()
}

/// A declaration `KEYWORD NAME = KIND(PARENT, CHILD) { fields }` of a `.mech` text.
struct Declaration {
    range: std::ops::Range<usize>,
    keyword: &'static str,
    kind: String,
    parent: String,
    child: String,
    fields: Fields,
}

impl Declaration {
    /// The `pin` joint or `revolute` loop `name` of `text`; panics on anything else.
    fn find(text: &str, name: &str) -> Self {
        let (keyword, start) = ["joint", "loop"]
            .into_iter()
            .find_map(|keyword| {
                let head = format!("\n{keyword} {name} = ");
                text.find(&head).map(|at| (keyword, at + 1))
            })
            .unwrap_or_else(|| panic!("no joint or loop `{name}`"));
        let open = start + text[start..].find('{').unwrap();
        let close = open + text[open..].find('}').unwrap();
        let head = &text[start..open];
        let (_, call) = head.split_once(" = ").unwrap();
        let (kind, bodies) = call.trim().split_once('(').unwrap();
        let (parent, child) = bodies.trim_end_matches(')').split_once(", ").unwrap();
        assert!(
            ["pin", "revolute"].contains(&kind),
            "{name}: a `{kind}` hinge"
        );
        let declaration = Declaration {
            range: start..close + 1,
            keyword,
            kind: kind.to_string(),
            parent: parent.to_string(),
            child: child.to_string(),
            fields: fields(&text[open + 1..close]),
        };
        for (key, _) in &declaration.fields {
            assert!(
                ["axis", "parent_point", "child_point"].contains(&key.as_str()),
                "{name}: field `{key}` is not rewritten"
            );
        }
        declaration
    }

    fn optional(&self, key: &str) -> Option<&str> {
        self.fields
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, value)| value.as_str())
    }

    fn field(&self, key: &str) -> &str {
        self.optional(key)
            .unwrap_or_else(|| panic!("no field `{key}`"))
    }
}
