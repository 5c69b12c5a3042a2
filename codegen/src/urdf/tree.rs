//! The URDF's structure: link names resolved, the tree of joints checked (one root, no link
//! with two parent joints, no cycle) and the zero pose (every coordinate zero) computed.
//!
//! Consumes: a read [`Robot`]. Produces: a [`Tree`] (each joint's parent and child links,
//! the links in `.mech` coordinate order, each link's frame at the zero pose) or [`Errors`]
//! for unknown or repeated names and for structures that are not a tree.

use std::collections::HashMap;
use std::sync::Arc;

use super::pose::{self, Frame, Vec3};
use super::read::{Name, Num, Pose, Robot};
use crate::diag::{self, Diagnostic, Errors, SourceFile, Span};

/// The links by name.
pub struct Links {
    index: HashMap<String, usize>,
    names: Vec<String>,
}

impl Links {
    /// The index of the link `name` names. A name that matches one link only when case is
    /// ignored (`chassis` for `Chassis`, in one of the HAMR files) is read as that link, with
    /// a warning; an unknown name is an error with the closest name or the list.
    pub fn resolve(
        &self,
        name: &Name,
        errors: &mut Vec<Diagnostic>,
        warnings: &mut Vec<Diagnostic>,
    ) -> Option<usize> {
        if let Some(&i) = self.index.get(&name.text) {
            return Some(i);
        }
        let folded: Vec<usize> = (0..self.names.len())
            .filter(|&i| self.names[i].eq_ignore_ascii_case(&name.text))
            .collect();
        if let [only] = folded[..] {
            warnings.push(
                Diagnostic::warning(
                    "U0601",
                    format!("no link `{}`: read as `{}`", name.text, self.names[only]),
                )
                .with_label(name.span, "names differ only in case")
                .with_help("URDF names are case-sensitive; correct the file to silence this"),
            );
            return Some(only);
        }
        let names: Vec<&str> = self.names.iter().map(String::as_str).collect();
        let error = Diagnostic::error("U0201", format!("unknown link `{}`", name.text))
            .with_label(name.span, "no `<link>` has this name");
        errors.push(match diag::closest(&name.text, &names) {
            Some(close) => error.with_help(format!("did you mean `{close}`?")),
            None => error.with_help(format!("the links of this file: {}", listing(&names))),
        });
        None
    }
}

/// The tree of a robot at its zero pose.
pub struct Tree {
    pub links: Links,
    /// Each joint's (parent, child) links.
    pub ends: Vec<(usize, usize)>,
    /// Each link's parent joint (`None` for the root).
    pub parent_joint: Vec<Option<usize>>,
    /// The joints by name.
    pub joint_index: HashMap<String, usize>,
    pub root: usize,
    /// The links depth first from the root, siblings in the file's order: the order of
    /// `.mech` coordinates.
    pub order: Vec<usize>,
    /// Each link's frame at the zero pose, in the root link's frame.
    pub world: Vec<Frame>,
    /// The farthest link origin from the root's (at least the smallest positive number): the
    /// scale of "round-off" for loop misses.
    pub size: f64,
}

impl Tree {
    /// The child of the root whose subtree holds `link` (the root for itself): one leg of a
    /// robot whose legs hang from the root.
    pub fn branch(&self, link: usize) -> usize {
        let mut link = link;
        while let Some(joint) = self.parent_joint[link] {
            let parent = self.ends[joint].0;
            if parent == self.root {
                return link;
            }
            link = parent;
        }
        link
    }

    pub fn build(
        file: &Arc<SourceFile>,
        robot: &Robot,
        warnings: &mut Vec<Diagnostic>,
    ) -> Result<Tree, Errors> {
        let fail = |diagnostics: Vec<Diagnostic>| Err(Errors::new(file.clone(), diagnostics));
        let mut errors = Vec::new();
        let mut index: HashMap<String, usize> = HashMap::new();
        for (i, link) in robot.links.iter().enumerate() {
            match index.get(&link.name.text) {
                Some(&first) => {
                    errors.push(duplicate("link", &link.name, robot.links[first].name.span))
                }
                None => {
                    index.insert(link.name.text.clone(), i);
                }
            }
        }
        let links = Links {
            index,
            names: robot.links.iter().map(|l| l.name.text.clone()).collect(),
        };
        let mut parent_joint: Vec<Option<usize>> = vec![None; robot.links.len()];
        let mut ends = Vec::new();
        let mut joint_index: HashMap<String, usize> = HashMap::new();
        for (j, joint) in robot.joints.iter().enumerate() {
            match joint_index.get(&joint.name.text) {
                Some(&first) => errors.push(duplicate(
                    "joint",
                    &joint.name,
                    robot.joints[first].name.span,
                )),
                None => {
                    joint_index.insert(joint.name.text.clone(), j);
                }
            }
            let parent = links.resolve(&joint.parent, &mut errors, warnings);
            let child = links.resolve(&joint.child, &mut errors, warnings);
            ends.push(parent.zip(child).unwrap_or((0, 0)));
            let Some(child) = child else { continue };
            match parent_joint[child] {
                Some(first) => errors.push(two_parents(robot, child, first, j)),
                None => parent_joint[child] = Some(j),
            }
        }
        if !errors.is_empty() {
            return fail(errors);
        }
        let roots: Vec<usize> = (0..robot.links.len())
            .filter(|&i| parent_joint[i].is_none())
            .collect();
        let root = match roots[..] {
            [root] => root,
            [] if robot.links.is_empty() => {
                return fail(vec![Diagnostic::error("U0402", "the robot has no links")
                    .with_label(Span::new(0, 1), "no `<link>` in this file")
                    .with_help("a URDF robot has at least one `<link name=\"...\">`")])
            }
            [] => {
                return fail(vec![Diagnostic::error(
                "U0401",
                "every link has a parent joint: the joints form a cycle and the tree has no root",
            )
            .with_label(robot.joints[0].span, "one joint of the cycle")
            .with_help(CLOSE_THE_CYCLE)])
            }
            _ => {
                let mut error = Diagnostic::error(
                    "U0403",
                    format!(
                        "{} links have no parent joint; a URDF tree has one root",
                        roots.len()
                    ),
                );
                for &r in &roots {
                    error = error.with_label(
                        robot.links[r].name.span,
                        "no joint has this link as its child",
                    );
                }
                return fail(vec![error.with_help(
                    "join the extra roots to the tree with a `<joint>` (type fixed to weld them)",
                )]);
            }
        };
        // Depth first from the root, siblings in the file's order; a link not reached from
        // the root sits on a cycle.
        let mut world: Vec<Option<Frame>> = vec![None; robot.links.len()];
        world[root] = Some(Frame::ROOT);
        let mut order = Vec::new();
        let mut stack = vec![root];
        while let Some(parent) = stack.pop() {
            order.push(parent);
            let frame = world[parent].unwrap_or(Frame::ROOT);
            let mut children = Vec::new();
            for (joint, &(p, c)) in robot.joints.iter().zip(&ends) {
                if p == parent && world[c].is_none() {
                    world[c] =
                        Some(frame.then(values(&joint.origin.xyz), &rotation(&joint.origin)));
                    children.push(c);
                }
            }
            stack.extend(children.into_iter().rev());
        }
        if let Some(lost) = (0..robot.links.len()).find(|&i| world[i].is_none()) {
            let joint = &robot.joints[parent_joint[lost].unwrap_or(0)];
            return fail(vec![Diagnostic::error(
                "U0401",
                format!(
                    "link `{}` is on a cycle of joints not connected to the root `{}`",
                    robot.links[lost].name.text, robot.links[root].name.text
                ),
            )
            .with_label(joint.span, "a joint of the cycle")
            .with_help(CLOSE_THE_CYCLE)]);
        }
        let world: Vec<Frame> = world
            .into_iter()
            .map(|f| f.unwrap_or(Frame::ROOT))
            .collect();
        let size = world
            .iter()
            .map(|f| pose::norm(f.origin))
            .fold(0.0_f64, f64::max)
            .max(f64::MIN_POSITIVE);
        Ok(Tree {
            links,
            ends,
            parent_joint,
            joint_index,
            root,
            order,
            world,
            size,
        })
    }
}

const CLOSE_THE_CYCLE: &str =
    "make one joint of the cycle a Drake `<loop_joint>` (axis, link1, link2)";

fn two_parents(robot: &Robot, child: usize, first: usize, second: usize) -> Diagnostic {
    let (first, second) = (&robot.joints[first], &robot.joints[second]);
    Diagnostic::error(
        "U0401",
        format!(
            "link `{}` has two parent joints, `{}` and `{}`: a kinematic cycle",
            robot.links[child].name.text, first.name.text, second.name.text
        ),
    )
    .with_label(second.child.span, "second parent joint")
    .with_label(first.child.span, "first parent joint")
    .with_help(format!(
        "a URDF tree gives each link one parent; close the cycle with Drake's `<loop_joint name=\"{}\" type=\"continuous\">` (axis, link1, link2) instead of this `<joint>`",
        second.name.text
    ))
}

fn duplicate(what: &str, name: &Name, first: Span) -> Diagnostic {
    Diagnostic::error("U0203", format!("two {what}s are named `{}`", name.text))
        .with_label(name.span, "second")
        .with_label(first, "first")
        .with_help(format!("{what} names must be unique; rename one"))
}

/// Names for a help line: the first ten, then how many more.
pub fn listing(names: &[&str]) -> String {
    const SHOWN: usize = 10;
    let mut text = names
        .iter()
        .take(SHOWN)
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > SHOWN {
        text.push_str(&format!(" and {} more", names.len() - SHOWN));
    }
    text
}

pub fn values(numbers: &[Num; 3]) -> Vec3 {
    [numbers[0].value, numbers[1].value, numbers[2].value]
}

pub fn rotation(pose: &Pose) -> pose::Mat3 {
    pose::rpy_matrix(values(&pose.rpy))
}
