//! Reading a URDF file: the XML tree (roxmltree) into plain data with the byte span of every
//! element and number, so later phases can point at the line and column of a problem.
//!
//! Consumes: the URDF text. Produces: a [`Robot`] (links, tree joints, Drake `loop_joint`s,
//! Drake force elements, transmissions, and every element the importer does not translate,
//! as [`Skipped`]), or [`Errors`] for malformed XML, a number that is not one, a vector of the
//! wrong length or a required attribute that is missing. Names are not resolved here
//! (`emit.rs` does that).

use std::sync::Arc;

use roxmltree::Node;

use crate::diag::{Diagnostic, Errors, SourceFile, Span};

/// A number of the file: its text as a `.mech` literal (exact, as written) and its value.
#[derive(Clone, Debug, PartialEq)]
pub struct Num {
    /// A literal the `.mech` grammar reads (`8.9854E-04`, `0.5`, `-3`); exact like the file.
    pub literal: String,
    pub value: f64,
    pub span: Span,
}

impl Num {
    fn zero(span: Span) -> Num {
        Num {
            literal: "0".to_string(),
            value: 0.0,
            span,
        }
    }
}

/// The shortest text that reads back to `value`, in the `.mech` number grammar.
pub fn float_literal(value: f64) -> String {
    let magnitude = value.abs();
    if value == 0.0 {
        "0".to_string()
    } else if (1e-4..1e6).contains(&magnitude) {
        format!("{value}")
    } else {
        format!("{value:e}")
    }
}

/// `xyz` and `rpy` of an `<origin>` (or of a loop joint's `<link1>`/`<link2>`).
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    pub xyz: [Num; 3],
    /// Roll, pitch, yaw (rad): the frame is `Rz(yaw) Ry(pitch) Rx(roll)` relative to its parent.
    pub rpy: [Num; 3],
}

impl Pose {
    fn identity(span: Span) -> Pose {
        Pose {
            xyz: [Num::zero(span), Num::zero(span), Num::zero(span)],
            rpy: [Num::zero(span), Num::zero(span), Num::zero(span)],
        }
    }

    pub fn is_rotated(&self) -> bool {
        self.rpy.iter().any(|a| a.value != 0.0)
    }
}

/// A name written in the file and where.
#[derive(Clone, Debug, PartialEq)]
pub struct Name {
    pub text: String,
    pub span: Span,
}

/// `<inertial>`: mass and inertia tensor about the centre of mass, in the frame `origin`.
#[derive(Clone, Debug, PartialEq)]
pub struct Inertial {
    pub origin: Pose,
    pub mass: Num,
    /// `ixx, iyy, izz, ixy, iyz, ixz` (URDF's are tensor entries: `ixy = −∫ x y dm`).
    pub inertia: [Num; 6],
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Collision {
    /// The `name` attribute, if any.
    pub name: Option<String>,
    pub origin: Pose,
    /// The geometry, as written (`sphere radius="0"`), for the comment.
    pub geometry: String,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Link {
    pub name: Name,
    pub inertial: Option<Inertial>,
    pub collisions: Vec<Collision>,
    pub span: Span,
}

/// A joint of the tree (`<joint>`, or Drake's `<drake:joint>`).
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    pub name: Name,
    /// `revolute`, `continuous`, `prismatic`, `fixed`, `floating`, `planar`, `ball`, …
    pub kind: Name,
    pub parent: Name,
    pub child: Name,
    pub origin: Pose,
    /// Default `1 0 0` (URDF).
    pub axis: [Num; 3],
    /// `<dynamics damping>`.
    pub damping: Option<Num>,
    pub span: Span,
}

/// Drake's `<loop_joint>`: a closure between a point and frame of `link1` and of `link2`.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopJoint {
    pub name: Name,
    pub kind: Name,
    pub axis: [Num; 3],
    pub link1: Name,
    pub pose1: Pose,
    pub link2: Name,
    pub pose2: Pose,
    pub span: Span,
}

/// A Drake `<force_element>`.
#[derive(Clone, Debug, PartialEq)]
pub enum ForceKind {
    /// `<torsional_spring stiffness rest_angle><joint name/>`.
    Torsional {
        joint: Name,
        stiffness: Num,
        rest: Option<Num>,
    },
    /// `<prismatic_spring stiffness rest_length><joint name/>`.
    Prismatic {
        joint: Name,
        stiffness: Num,
        rest: Option<Num>,
    },
    /// `<linear_spring_damper>`, boxed: much larger than the others.
    LinearSpringDamper(Box<LinearSpring>),
}

/// `<linear_spring_damper stiffness damping rest_length>` between a point of `<link1>` and one
/// of `<link2>`.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearSpring {
    pub stiffness: Num,
    pub damping: Option<Num>,
    pub rest_length: Option<Num>,
    pub link1: Name,
    pub point1: [Num; 3],
    pub link2: Name,
    pub point2: [Num; 3],
}

#[derive(Clone, Debug, PartialEq)]
pub struct ForceElement {
    pub name: Name,
    pub kind: ForceKind,
    pub span: Span,
}

/// `<transmission>`: listed as a comment (`.mech` inputs and actuators are written by hand).
#[derive(Clone, Debug, PartialEq)]
pub struct Transmission {
    pub name: String,
    pub kind: String,
    pub joints: Vec<String>,
    pub actuators: Vec<String>,
    pub reduction: Option<String>,
    pub span: Span,
}

/// Something in the file that is not translated: what it is, in a few words, and where.
#[derive(Clone, Debug, PartialEq)]
pub struct Skipped {
    /// Whose it is: a link's or joint's name, or `robot`.
    pub owner: String,
    /// The element as written, shortened (`limit lower="-pi/9" upper="pi/9"`).
    pub what: String,
    pub kind: SkippedKind,
    pub span: Span,
}

/// Why an element is not translated; the kinds are reported together (one warning each).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum SkippedKind {
    /// `<visual>`, `<material>`: display only.
    Display,
    /// `<limit>`, `<safety_controller>`: `.mech` joints have no limits.
    Limit,
    /// `<dynamics friction>`, `<mimic>`, `<calibration>` and any other element.
    Other,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    pub name: String,
    pub links: Vec<Link>,
    pub joints: Vec<Joint>,
    pub loops: Vec<LoopJoint>,
    pub forces: Vec<ForceElement>,
    pub transmissions: Vec<Transmission>,
    pub skipped: Vec<Skipped>,
    /// Where numbers were separated by commas (`xyz="-0.53, 0.12, 0.0"`), read as spaces.
    pub commas: Vec<Span>,
}

/// Reads the robot of a URDF file; every problem found is reported together.
pub fn read(file: &Arc<SourceFile>) -> Result<Robot, Errors> {
    let options = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..roxmltree::ParsingOptions::default()
    };
    let document = roxmltree::Document::parse_with_options(&file.text, options)
        .map_err(|error| Errors::new(file.clone(), vec![xml_error(&file.text, &error)]))?;
    let root = document.root_element();
    if root.tag_name().name() != "robot" {
        let span = tag_span(root);
        return Err(Errors::new(
            file.clone(),
            vec![
                Diagnostic::error("U0102", "a URDF file's root element must be `<robot>`")
                    .with_label(span, format!("`<{}>` found", root.tag_name().name()))
                    .with_help("is this a URDF file? xacro files must be expanded first"),
            ],
        ));
    }
    let mut reader = Reader {
        diagnostics: Vec::new(),
        skipped: Vec::new(),
        commas: Vec::new(),
    };
    let mut robot = Robot {
        name: root.attribute("name").unwrap_or("robot").to_string(),
        links: Vec::new(),
        joints: Vec::new(),
        loops: Vec::new(),
        forces: Vec::new(),
        transmissions: Vec::new(),
        skipped: Vec::new(),
        commas: Vec::new(),
    };
    for node in root.children().filter(Node::is_element) {
        match node.tag_name().name() {
            "link" => {
                if let Some(link) = reader.link(node) {
                    robot.links.push(link);
                }
            }
            "joint" => {
                if let Some(joint) = reader.joint(node) {
                    robot.joints.push(joint);
                }
            }
            "loop_joint" => {
                if let Some(closure) = reader.loop_joint(node) {
                    robot.loops.push(closure);
                }
            }
            "ball_constraint" => {
                let count = robot.loops.len();
                if let Some(closure) = reader.ball_constraint(node, count) {
                    robot.loops.push(closure);
                }
            }
            "force_element" => {
                if let Some(force) = reader.force_element(node) {
                    robot.forces.push(force);
                }
            }
            "transmission" => robot.transmissions.push(transmission(node)),
            "material" => reader.skip("robot", node, SkippedKind::Display),
            _ => reader.skip("robot", node, SkippedKind::Other),
        }
    }
    if !reader.diagnostics.is_empty() {
        return Err(Errors::new(file.clone(), reader.diagnostics));
    }
    robot.skipped = reader.skipped;
    robot.commas = reader.commas;
    Ok(robot)
}

/// roxmltree's error at its line and column, as a diagnostic.
fn xml_error(text: &str, error: &roxmltree::Error) -> Diagnostic {
    let position = error.pos();
    let offset = offset_of(text, position.row as usize, position.col as usize);
    let help = match error {
        roxmltree::Error::UnknownNamespace(prefix, _) if prefix == "drake" => {
            "declare Drake's prefix on the root element: `<robot name=\"...\" xmlns:drake=\"http://drake.mit.edu\">`".to_string()
        }
        roxmltree::Error::UnknownNamespace(prefix, _) => {
            format!("declare the prefix on the root element: `xmlns:{prefix}=\"...\"`")
        }
        _ => "a URDF file must be well-formed XML: every tag closed, attributes quoted".to_string(),
    };
    Diagnostic::error("U0101", "malformed XML")
        .with_label(Span::new(offset, offset + 1), error.to_string())
        .with_help(help)
}

/// The byte offset of a 1-based line and character column.
fn offset_of(text: &str, row: usize, col: usize) -> usize {
    let line_start: usize = text
        .split_inclusive('\n')
        .take(row.saturating_sub(1))
        .map(str::len)
        .sum();
    let line = &text[line_start.min(text.len())..];
    let within: usize = line
        .chars()
        .take(col.saturating_sub(1))
        .map(char::len_utf8)
        .sum();
    (line_start + within).min(text.len())
}

/// The span of an element's opening `<name` (not its whole body, which may be long).
fn tag_span(node: Node) -> Span {
    let start = node.range().start;
    Span::new(start, start + 1 + node.tag_name().name().len())
}

fn value_span(node: Node, attribute: &str) -> Span {
    node.attribute_node(attribute)
        .map(|a| {
            let range = a.range_value();
            Span::new(range.start, range.end)
        })
        .unwrap_or_else(|| tag_span(node))
}

/// The element as written, shortened for a comment: `limit lower="-pi/9" upper="pi/9"`.
fn describe(node: Node) -> String {
    let mut text = node.tag_name().name().to_string();
    for attribute in node.attributes() {
        text.push_str(&format!(" {}=\"{}\"", attribute.name(), attribute.value()));
    }
    let children: Vec<String> = node
        .children()
        .filter(Node::is_element)
        .map(describe)
        .collect();
    if !children.is_empty() {
        text.push_str(&format!(" {{ {} }}", children.join("; ")));
    } else if let Some(body) = node.text().map(str::trim).filter(|t| !t.is_empty()) {
        text.push_str(&format!(" {{ {body} }}"));
    }
    const LONGEST: usize = 160;
    if text.chars().count() > LONGEST {
        text = text.chars().take(LONGEST).collect::<String>() + " …";
    }
    text
}

fn child<'a, 'input>(node: Node<'a, 'input>, name: &str) -> Option<Node<'a, 'input>> {
    node.children()
        .find(|c| c.is_element() && c.tag_name().name() == name)
}

/// A number literal of the file made into one the `.mech` grammar reads exactly
/// (`.5` → `0.5`, `5.` → `5.0`, `+2` → `2`), or `None` if it is not a finite decimal number.
fn mech_literal(text: &str) -> Option<String> {
    let body = text.strip_prefix('+').unwrap_or(text);
    let (sign, body) = match body.strip_prefix('-') {
        Some(rest) => ("-", rest),
        None => ("", body),
    };
    let (mantissa, exponent) = match body.find(['e', 'E']) {
        Some(i) => (&body[..i], Some(&body[i + 1..])),
        None => (body, None),
    };
    let (whole, fraction) = match mantissa.split_once('.') {
        Some((w, f)) => (w, Some(f)),
        None => (mantissa, None),
    };
    let digits = |s: &str| s.bytes().all(|b| b.is_ascii_digit());
    if !digits(whole)
        || !fraction.is_none_or(digits)
        || (whole.is_empty() && fraction.is_none_or(str::is_empty))
    {
        return None;
    }
    let mut literal = format!("{sign}{}", if whole.is_empty() { "0" } else { whole });
    if let Some(fraction) = fraction {
        literal.push('.');
        literal.push_str(if fraction.is_empty() { "0" } else { fraction });
    }
    if let Some(exponent) = exponent {
        let digits_part = exponent.strip_prefix(['+', '-']).unwrap_or(exponent);
        if digits_part.is_empty() || !digits(digits_part) {
            return None;
        }
        literal.push('e');
        literal.push_str(exponent.strip_prefix('+').unwrap_or(exponent));
    }
    Some(literal)
}

struct Reader {
    diagnostics: Vec<Diagnostic>,
    skipped: Vec<Skipped>,
    commas: Vec<Span>,
}

impl Reader {
    fn skip(&mut self, owner: &str, node: Node, kind: SkippedKind) {
        self.skipped.push(Skipped {
            owner: owner.to_string(),
            what: describe(node),
            kind,
            span: tag_span(node),
        });
    }

    fn missing(&mut self, node: Node, attribute: &str, help: &str) {
        self.diagnostics.push(
            Diagnostic::error(
                "U0103",
                format!(
                    "`<{}>` needs the attribute `{attribute}`",
                    node.tag_name().name()
                ),
            )
            .with_label(tag_span(node), format!("no `{attribute}` here"))
            .with_help(help.to_string()),
        );
    }

    fn name(&mut self, node: Node, attribute: &str, help: &str) -> Option<Name> {
        match node.attribute(attribute) {
            Some(text) if !text.trim().is_empty() => Some(Name {
                text: text.trim().to_string(),
                span: value_span(node, attribute),
            }),
            _ => {
                self.missing(node, attribute, help);
                None
            }
        }
    }

    /// The numbers of an attribute (separated by spaces, or commas: some of Drake's files
    /// write `xyz="-0.53, 0.12, 0.0"`), exactly `count` of them.
    fn numbers(&mut self, node: Node, attribute: &str, count: usize) -> Option<Vec<Num>> {
        let attr = node.attribute_node(attribute)?;
        let text = attr.value();
        let value_start = attr.range_value().start;
        // Attribute values with entities (`&#45;`) would shift the offsets: point at the
        // whole value then.
        let raw_matches = attr.range_value().len() == text.len();
        let whole = value_span(node, attribute);
        if text.contains(',') {
            self.commas.push(whole);
        }
        let mut numbers = Vec::new();
        let mut bad = false;
        let mut offset = 0;
        for piece in text.split(|c: char| c.is_whitespace() || c == ',') {
            let start = offset;
            offset += piece.len() + 1;
            if piece.is_empty() {
                continue;
            }
            let span = if raw_matches {
                Span::new(value_start + start, value_start + start + piece.len())
            } else {
                whole
            };
            let parsed = mech_literal(piece).and_then(|literal| {
                let value: f64 = literal.parse().ok()?;
                value.is_finite().then_some(Num {
                    literal,
                    value,
                    span,
                })
            });
            match parsed {
                Some(number) => numbers.push(number),
                None => {
                    bad = true;
                    self.diagnostics.push(
                        Diagnostic::error("U0301", format!("`{piece}` is not a number"))
                            .with_label(span, format!("in `{attribute}` of `<{}>`", node.tag_name().name()))
                            .with_help("write a finite decimal number such as `0.5`, `-3` or `1.2e-3` (no expressions)"),
                    );
                }
            }
        }
        if bad {
            return None;
        }
        if numbers.len() != count {
            self.diagnostics.push(
                Diagnostic::error(
                    "U0302",
                    format!(
                        "`{attribute}` of `<{}>` needs {count} number{}, found {}",
                        node.tag_name().name(),
                        if count == 1 { "" } else { "s" },
                        numbers.len()
                    ),
                )
                .with_label(whole, "here")
                .with_help(if count == 3 {
                    "write three numbers separated by spaces: `x y z`"
                } else {
                    "write one number"
                }),
            );
            return None;
        }
        Some(numbers)
    }

    fn number(&mut self, node: Node, attribute: &str) -> Option<Num> {
        self.numbers(node, attribute, 1).map(|mut n| n.remove(0))
    }

    fn required_number(&mut self, node: Node, attribute: &str, help: &str) -> Option<Num> {
        if node.attribute(attribute).is_none() {
            self.missing(node, attribute, help);
            return None;
        }
        self.number(node, attribute)
    }

    fn vector(&mut self, node: Node, attribute: &str) -> Option<[Num; 3]> {
        let numbers = self.numbers(node, attribute, 3)?;
        numbers.try_into().ok()
    }

    /// `xyz`, `rpy` of `node` itself (a loop joint's `<link1>`), each default zero.
    fn pose_of(&mut self, node: Node) -> Pose {
        let mut pose = Pose::identity(tag_span(node));
        if let Some(xyz) = self.vector(node, "xyz") {
            pose.xyz = xyz;
        }
        if let Some(rpy) = self.vector(node, "rpy") {
            pose.rpy = rpy;
        }
        pose
    }

    /// The `<origin>` child of `node`, or the identity.
    fn origin(&mut self, node: Node) -> Pose {
        match child(node, "origin") {
            Some(origin) => self.pose_of(origin),
            None => Pose::identity(tag_span(node)),
        }
    }

    fn axis(&mut self, node: Node) -> [Num; 3] {
        let span = tag_span(node);
        let default = [
            Num {
                literal: "1".to_string(),
                value: 1.0,
                span,
            },
            Num::zero(span),
            Num::zero(span),
        ];
        child(node, "axis")
            .and_then(|axis| self.vector(axis, "xyz"))
            .unwrap_or(default)
    }

    fn link(&mut self, node: Node) -> Option<Link> {
        let name = self.name(
            node,
            "name",
            "every `<link>` is named: `<link name=\"base\">`",
        )?;
        let mut link = Link {
            name,
            inertial: None,
            collisions: Vec::new(),
            span: tag_span(node),
        };
        let owner = link.name.text.clone();
        for element in node.children().filter(Node::is_element) {
            match element.tag_name().name() {
                "inertial" => link.inertial = self.inertial(element),
                "collision" => {
                    let origin = self.origin(element);
                    let geometry = child(element, "geometry")
                        .and_then(|g| g.children().find(Node::is_element))
                        .map(describe)
                        .unwrap_or_else(|| "no geometry".to_string());
                    link.collisions.push(Collision {
                        name: element.attribute("name").map(str::to_string),
                        origin,
                        geometry,
                        span: tag_span(element),
                    });
                }
                "visual" => self.skip(&owner, element, SkippedKind::Display),
                _ => self.skip(&owner, element, SkippedKind::Other),
            }
        }
        Some(link)
    }

    fn inertial(&mut self, node: Node) -> Option<Inertial> {
        let origin = self.origin(node);
        let mass = match child(node, "mass") {
            Some(mass) => self.required_number(mass, "value", "`<mass value=\"0.1\"/>`")?,
            None => Num::zero(tag_span(node)),
        };
        let span = tag_span(node);
        let inertia = match child(node, "inertia") {
            Some(inertia) => {
                let mut entries = Vec::new();
                for key in ["ixx", "iyy", "izz", "ixy", "iyz", "ixz"] {
                    let entry = match inertia.attribute(key) {
                        Some(_) => self.number(inertia, key),
                        // URDF requires all six; a missing product is read as zero.
                        None => Some(Num::zero(tag_span(inertia))),
                    };
                    entries.push(entry?);
                }
                entries.try_into().ok()?
            }
            None => [0; 6].map(|_| Num::zero(span)),
        };
        Some(Inertial {
            origin,
            mass,
            inertia,
            span,
        })
    }

    fn joint(&mut self, node: Node) -> Option<Joint> {
        let name = self.name(
            node,
            "name",
            "every `<joint>` is named: `<joint name=\"hinge\" type=\"revolute\">`",
        );
        let kind = self.name(
            node,
            "type",
            "`type` is revolute, continuous, prismatic, fixed, floating or planar",
        );
        let parent = child(node, "parent")
            .map(|p| self.name(p, "link", "`<parent link=\"base\"/>`"))
            .unwrap_or_else(|| {
                self.missing_child(node, "parent", "`<parent link=\"NAME\"/>` names the link");
                None
            });
        let child_link = child(node, "child")
            .map(|c| self.name(c, "link", "`<child link=\"arm\"/>`"))
            .unwrap_or_else(|| {
                self.missing_child(node, "child", "`<child link=\"NAME\"/>` names the link");
                None
            });
        let origin = self.origin(node);
        let axis = self.axis(node);
        let owner = name
            .as_ref()
            .map_or("joint".to_string(), |n| n.text.clone());
        let mut damping = None;
        for element in node.children().filter(Node::is_element) {
            match element.tag_name().name() {
                "origin" | "parent" | "child" | "axis" => {}
                "dynamics" => {
                    if element.attribute("damping").is_some() {
                        damping = self.number(element, "damping");
                    }
                    if element
                        .attribute("friction")
                        .is_some_and(|f| f.trim().parse::<f64>().ok() != Some(0.0))
                    {
                        self.skip(&owner, element, SkippedKind::Other);
                    }
                }
                "limit" | "safety_controller" => self.skip(&owner, element, SkippedKind::Limit),
                _ => self.skip(&owner, element, SkippedKind::Other),
            }
        }
        Some(Joint {
            name: name?,
            kind: kind?,
            parent: parent?,
            child: child_link?,
            origin,
            axis,
            damping,
            span: tag_span(node),
        })
    }

    fn missing_child(&mut self, node: Node, element: &str, help: &str) {
        self.diagnostics.push(
            Diagnostic::error(
                "U0104",
                format!("`<{}>` needs a `<{element}>`", node.tag_name().name()),
            )
            .with_label(tag_span(node), format!("no `<{element}>` inside"))
            .with_help(help.to_string()),
        );
    }

    fn loop_joint(&mut self, node: Node) -> Option<LoopJoint> {
        let name = self.name(node, "name", "every `<loop_joint>` is named");
        let kind = self.name(node, "type", "`type` is continuous or revolute (or ball)");
        let axis = self.axis(node);
        let mut side = |tag: &str| -> Option<(Name, Pose)> {
            match child(node, tag) {
                Some(element) => {
                    let link = self.name(
                        element,
                        "link",
                        "`<link1 link=\"NAME\" xyz=\"x y z\" rpy=\"0 0 0\"/>`",
                    )?;
                    Some((link, self.pose_of(element)))
                }
                None => {
                    self.diagnostics.push(
                        Diagnostic::error("U0104", format!("`<loop_joint>` needs a `<{tag}>`"))
                            .with_label(tag_span(node), format!("no `<{tag}>` inside"))
                            .with_help(format!("`<{tag} link=\"NAME\" xyz=\"x y z\" rpy=\"0 0 0\"/>`: the closure's point and frame on that link")),
                    );
                    None
                }
            }
        };
        let first = side("link1");
        let second = side("link2");
        let owner = name
            .as_ref()
            .map_or("loop_joint".to_string(), |n| n.text.clone());
        for element in node.children().filter(Node::is_element) {
            if !matches!(element.tag_name().name(), "axis" | "link1" | "link2") {
                self.skip(&owner, element, SkippedKind::Other);
            }
        }
        let (link1, pose1) = first?;
        let (link2, pose2) = second?;
        Some(LoopJoint {
            name: name?,
            kind: kind?,
            axis,
            link1,
            pose1,
            link2,
            pose2,
            span: tag_span(node),
        })
    }

    /// Drake's `<drake:ball_constraint>` (body A's point P coincides with body B's point Q):
    /// a loop joint of type ball named `ball_constraint` (Drake's has no name), or
    /// `ball_constraint_N` for the closure numbered N in the file.
    fn ball_constraint(&mut self, node: Node, closures_before: usize) -> Option<LoopJoint> {
        let span = tag_span(node);
        let name = match closures_before {
            0 => "ball_constraint".to_string(),
            n => format!("ball_constraint_{}", n + 1),
        };
        let mut side = |body: &str, point: &str| -> Option<(Name, Pose)> {
            let Some(element) = child(node, body) else {
                self.missing_child(
                    node,
                    body,
                    &format!("`<drake:{body} name=\"NAME\"/>` names the link"),
                );
                return None;
            };
            let link = self.name(element, "name", "names the link: `name=\"NAME\"`")?;
            let mut pose = Pose::identity(span);
            match child(node, point) {
                Some(element) => pose.xyz = self.vector(element, "value")?,
                None => {
                    self.missing_child(
                        node,
                        point,
                        &format!("`<drake:{point} value=\"x y z\"/>`: the point on that link"),
                    );
                    return None;
                }
            }
            Some((link, pose))
        };
        let first = side("ball_constraint_body_A", "ball_constraint_p_AP");
        let second = side("ball_constraint_body_B", "ball_constraint_p_BQ");
        let (link1, pose1) = first?;
        let (link2, pose2) = second?;
        Some(LoopJoint {
            name: Name { text: name, span },
            kind: Name {
                text: "ball".to_string(),
                span,
            },
            axis: [Num::zero(span), Num::zero(span), Num::zero(span)],
            link1,
            pose1,
            link2,
            pose2,
            span,
        })
    }

    fn force_element(&mut self, node: Node) -> Option<ForceElement> {
        let name = self.name(node, "name", "every `<force_element>` is named")?;
        let Some(element) = node.children().find(Node::is_element) else {
            self.skip(&name.text, node, SkippedKind::Other);
            return None;
        };
        let joint = |reader: &mut Reader| {
            child(element, "joint").and_then(|j| {
                reader.name(
                    j,
                    "name",
                    "`<joint name=\"NAME\"/>` names the joint the spring acts on",
                )
            })
        };
        let kind = match element.tag_name().name() {
            "torsional_spring" => ForceKind::Torsional {
                stiffness: self.required_number(
                    element,
                    "stiffness",
                    "`stiffness=\"0.1\"` (torque per radian)",
                )?,
                rest: self.optional(element, "rest_angle"),
                joint: joint(self)?,
            },
            "prismatic_spring" => ForceKind::Prismatic {
                stiffness: self.required_number(
                    element,
                    "stiffness",
                    "`stiffness=\"1.5\"` (force per length)",
                )?,
                rest: self.optional(element, "rest_length"),
                joint: joint(self)?,
            },
            "linear_spring_damper" => {
                let mut side = |tag: &str| -> Option<(Name, [Num; 3])> {
                    let end = child(element, tag)?;
                    let link = self.name(end, "link", "`<link1 link=\"NAME\" xyz=\"x y z\"/>`")?;
                    Some((link, self.pose_of(end).xyz))
                };
                let first = side("link1");
                let second = side("link2");
                let (Some((link1, point1)), Some((link2, point2))) = (first, second) else {
                    self.missing_child(
                        element,
                        "link1>` and a `<link2",
                        "`<link1 link=\"NAME\" xyz=\"x y z\"/>` and `<link2 .../>`: the spring's ends",
                    );
                    return None;
                };
                ForceKind::LinearSpringDamper(Box::new(LinearSpring {
                    stiffness: self.required_number(
                        element,
                        "stiffness",
                        "`stiffness=\"1.5\"` (force per length)",
                    )?,
                    damping: self.optional(element, "damping"),
                    rest_length: self.optional(element, "rest_length"),
                    link1,
                    point1,
                    link2,
                    point2,
                }))
            }
            _ => {
                self.skip(&name.text, element, SkippedKind::Other);
                return None;
            }
        };
        Some(ForceElement {
            name,
            kind,
            span: tag_span(node),
        })
    }

    fn optional(&mut self, node: Node, attribute: &str) -> Option<Num> {
        node.attribute(attribute)?;
        self.number(node, attribute)
    }
}

fn transmission(node: Node) -> Transmission {
    let names = |tag: &str| -> Vec<String> {
        node.children()
            .filter(|c| c.is_element() && c.tag_name().name() == tag)
            .filter_map(|c| c.attribute("name").map(str::to_string))
            .collect()
    };
    let reduction = node
        .descendants()
        .find(|c| c.is_element() && c.tag_name().name() == "mechanicalReduction")
        .and_then(|c| c.text())
        .map(|t| t.trim().to_string());
    Transmission {
        name: node.attribute("name").unwrap_or("").to_string(),
        kind: node
            .attribute("type")
            .map(str::to_string)
            .or_else(|| {
                child(node, "type")
                    .and_then(|t| t.text())
                    .map(|t| t.trim().to_string())
            })
            .unwrap_or_default(),
        joints: names("joint"),
        actuators: names("actuator"),
        reduction,
        span: tag_span(node),
    }
}

#[cfg(test)]
mod tests {
    use super::mech_literal;

    #[test]
    fn literals_are_made_exact_mech_numbers() {
        assert_eq!(mech_literal("8.9854E-04").as_deref(), Some("8.9854e-04"));
        assert_eq!(mech_literal(".5").as_deref(), Some("0.5"));
        assert_eq!(mech_literal("5.").as_deref(), Some("5.0"));
        assert_eq!(mech_literal("+2e+3").as_deref(), Some("2e3"));
        assert_eq!(mech_literal("-0.53").as_deref(), Some("-0.53"));
        for bad in ["pi/9", "1..2", "e5", ".", "1e", "nan", "inf", "0x10", "1,5"] {
            assert_eq!(mech_literal(bad), None, "{bad}");
        }
    }
}
