//! Loop closures: `loop NAME = coincident|revolute|distance(PARENT, CHILD) { fields }`.
//!
//! Consumes: `loop` declarations, after the tree, its points and its frames are built.
//! Produces: `model.loops` (with one IR point per side, named `<loop>.parent` and
//! `<loop>.child`), closure springs and dampers in `model.loads`, and `E02xx`/`E04xx` errors.
//!
//! A loop has the shape of a joint: `parent_point`/`child_point` as for joints, and for a
//! revolute closure `axis`, `parent_frame`, `child_frame`, `stiffness`, `rest`, `damping`
//! with the meaning they have on a pin.

use crate::diag::{Diagnostic, Span};
use crate::front::ast::{self, ExprKind};
use crate::ir::{self, AxisAngle, ClosureKind, Dimension, Expr, Vec3};

use super::body::{missing_field, zeros};
use super::expr::{unparen, Ctx, Expect};
use super::{names, Lowerer};

const LOOP_KINDS: [&str; 3] = ["coincident", "revolute", "distance"];

/// The fields each kind of loop accepts.
fn loop_fields(kind: &str) -> &'static [&'static str] {
    match kind {
        "coincident" => &["parent_point", "child_point", "components", "frame"],
        "revolute" => &[
            "parent_point",
            "child_point",
            "axis",
            "parent_frame",
            "child_frame",
            "stiffness",
            "rest",
            "damping",
        ],
        _ => &["parent_point", "child_point", "length"],
    }
}

/// The dimension of a revolute closure's scalar fields (as on a pin).
fn closure_expect(field: &'static str) -> Expect<'static> {
    let (dim, what, example) = match field {
        "stiffness" => (Dimension::TORQUE, "`stiffness`", "0.1 uN*m/rad"),
        "damping" => (
            Dimension {
                mass: 1,
                length: 2,
                time: -1,
                current: 0,
            },
            "`damping`",
            "1e-9 N*m*s/rad",
        ),
        "rest" => (Dimension::NONE, "`rest`", "0 deg"),
        _ => (Dimension::LENGTH, "`length`", "5 mm"),
    };
    Expect::new(dim, what, example)
}

impl<'a> Lowerer<'a> {
    /// Lowers every `loop` declaration (call after the tree, points and frames are built).
    pub(super) fn lower_loops(&mut self, items: &'a [ast::Item]) {
        for item in items {
            if let ast::Item::Loop(decl) = item {
                if let Err(diagnostic) = self.structure_names.declare(&decl.name, "the name") {
                    self.error(diagnostic);
                }
                self.lower_loop(decl);
            }
        }
    }

    fn lower_loop(&mut self, decl: &'a ast::JointDecl) {
        let kind = self.loop_kind(&decl.kind);
        let parent = self.resolve_owner(&decl.parent);
        let child = self.resolve_owner(&decl.child);
        self.check_distinct_ends("loop", decl, parent, child);
        let fields = self.loop_field_list(decl, kind);
        let field = |name: &str| fields.iter().copied().find(|f| f.name.name == name);

        let parent_point = match field("parent_point") {
            Some(f) => self.joint_point(f, parent, "`parent_point`", "parent"),
            None => Some(zeros()),
        };
        let child_point = match field("child_point") {
            Some(f) => self.joint_point(f, child, "`child_point`", "child"),
            None => Some(zeros()),
        };
        let closure = match kind {
            Some("coincident") => self.coincident(field("components"), field("frame")),
            Some("revolute") => self.revolute(decl, parent, child, &field),
            Some(_) => self.distance(decl, field("length")),
            None => None,
        };
        let (Some(parent), Some(child), Some(parent_point), Some(child_point), Some(closure)) =
            (parent, child, parent_point, child_point, closure)
        else {
            return;
        };
        let (Some(parent_frame), Some(child_frame)) =
            (self.owners[parent].frame, self.owners[child].frame)
        else {
            return;
        };
        let name = decl.name.name.clone();
        let parent_handle = self.model.points.append(ir::Point {
            name: format!("{name}.parent"),
            frame: parent_frame,
            position: parent_point,
            span: decl.parent.span,
        });
        let child_handle = self.model.points.append(ir::Point {
            name: format!("{name}.child"),
            frame: child_frame,
            position: child_point,
            span: decl.child.span,
        });
        let index = self.model.loops.len();
        self.model.loops.push(ir::LoopClosure {
            name,
            kind: closure,
            parent: parent_handle,
            child: child_handle,
            span: decl.span,
        });
        if kind == Some("revolute") {
            self.closure_loads(index, &field);
        }
    }

    fn loop_kind(&mut self, kind: &ast::Ident) -> Option<&'static str> {
        if let Some(&known) = LOOP_KINDS.iter().find(|&&k| k == kind.name) {
            return Some(known);
        }
        let synonym = match kind.name.as_str() {
            "pin" | "hinge" | "continuous" => Some("revolute"),
            "point" | "spherical" | "ball" => Some("coincident"),
            _ => None,
        };
        self.error(names::unknown_kind(
            "loop",
            "closure",
            kind,
            &LOOP_KINDS,
            synonym,
        ));
        None
    }

    /// The known, non-repeated fields of a loop (all of them are checked, even if the kind
    /// is unknown, against the union of the kinds' fields).
    fn loop_field_list<'f>(
        &mut self,
        decl: &'f ast::JointDecl,
        kind: Option<&str>,
    ) -> Vec<&'f ast::Field> {
        let allowed: Vec<&str> = match kind {
            Some(kind) => loop_fields(kind).to_vec(),
            None => LOOP_KINDS
                .iter()
                .flat_map(|k| loop_fields(k).iter().copied())
                .collect(),
        };
        let list = format!("fields of a {} loop", kind.unwrap_or("loop"));
        self.known_fields(&decl.fields, &allowed, &list, "not a field of this loop")
    }

    /// `components = [x, y];` (default all three) in `frame = F;` (default newtonian).
    fn coincident(
        &mut self,
        components: Option<&ast::Field>,
        frame: Option<&ast::Field>,
    ) -> Option<ClosureKind> {
        let components = match components {
            None => vec![0, 1, 2],
            Some(field) => self.component_list(&field.value)?,
        };
        let frame = match frame {
            None => Some(ir::Model::NEWTONIAN),
            Some(field) => match &unparen(&field.value).kind {
                ExprKind::Path(path) => {
                    let frame = self.resolve_frame(path, true)?;
                    self.frame_handle(frame)
                }
                _ => {
                    self.error(
                        Diagnostic::error("E0412", "expected a frame for `frame`")
                            .with_label(field.value.span, "not a frame")
                            .with_help("name a frame, such as `newtonian`, a body or `body.frame`"),
                    );
                    None
                }
            },
        }?;
        Some(ClosureKind::Coincident { frame, components })
    }

    /// `[x, z]` → `[0, 2]`: distinct axis names.
    pub(super) fn component_list(&mut self, value: &ast::Expr) -> Option<Vec<usize>> {
        let value = unparen(value);
        let items = match &value.kind {
            ExprKind::Vector(items) if !items.is_empty() => items.clone(),
            ExprKind::Path(_) => vec![value.clone()],
            _ => {
                self.error(
                    Diagnostic::error("E0412", "expected a list of components")
                        .with_label(value.span, "not a list of axes")
                        .with_help("write e.g. `components = [x, y];`"),
                );
                return None;
            }
        };
        let mut components = Vec::new();
        for item in &items {
            let index = match &unparen(item).kind {
                ExprKind::Path(path) if path.segments.len() == 1 => ["x", "y", "z"]
                    .iter()
                    .position(|axis| *axis == path.segments[0].name),
                _ => None,
            };
            match index {
                Some(index) if !components.contains(&index) => components.push(index),
                Some(_) => {
                    self.error(
                        Diagnostic::error("E0211", "component listed twice")
                            .with_label(item.span, "already listed")
                            .with_help("list each of `x`, `y`, `z` at most once"),
                    );
                    return None;
                }
                None => {
                    self.error(
                        Diagnostic::error("E0412", "expected `x`, `y` or `z`")
                            .with_label(item.span, "not a component")
                            .with_help("components are the axes `x`, `y`, `z` of `frame`"),
                    );
                    return None;
                }
            }
        }
        components.sort_unstable();
        Some(components)
    }

    fn revolute<'f>(
        &mut self,
        decl: &ast::JointDecl,
        parent: Option<usize>,
        child: Option<usize>,
        field: &dyn Fn(&str) -> Option<&'f ast::Field>,
    ) -> Option<ClosureKind> {
        let axis: Option<Vec3> = match field("axis") {
            Some(f) => self.axis(&f.value, "a loop axis"),
            None => {
                let help =
                    "add `axis = z;` (or `x`, `y`, `[ax, ay, az]`), in the parent interframe";
                self.error(missing_field("revolute loop", &decl.name, "axis", help));
                None
            }
        };
        let parent_orientation = self.interframe(field("parent_frame"), parent, "parent")?;
        let child_orientation = self.interframe(field("child_frame"), child, "child")?;
        Some(ClosureKind::Revolute {
            axis: axis?,
            parent_orientation,
            child_orientation,
            twist_axis: None,
        })
    }

    /// The rotation of an interframe relative to its body frame (empty for the body frame).
    fn interframe(
        &mut self,
        field: Option<&ast::Field>,
        owner: Option<usize>,
        side: &str,
    ) -> Option<Vec<AxisAngle>> {
        match field {
            None => Some(Vec::new()),
            Some(f) => Some(self.joint_frame(f, owner, side)?.unwrap_or_default()),
        }
    }

    fn distance(
        &mut self,
        decl: &ast::JointDecl,
        length: Option<&ast::Field>,
    ) -> Option<ClosureKind> {
        let Some(length) = length else {
            let help = "add the distance between the two points, e.g. `length = 5 mm;`";
            self.error(missing_field("distance loop", &decl.name, "length", help));
            return None;
        };
        let span = length.value.span;
        let length = self.lower_scalar_as(
            &length.value,
            Ctx::Static("a loop length"),
            &closure_expect("length"),
        )?;
        // The closure divides by the length (kane::constraints), and at zero length the
        // points' direction, which the row constrains, is undefined.
        let value = self.evaluate(&length, span);
        if value <= 0.0 {
            self.error(
                Diagnostic::error(
                    "E0415",
                    format!("a distance loop's `length` must be positive, found {value} m"),
                )
                .with_label(span, "not a positive length")
                .with_help(format!(
                    "to hold the two points together, use `loop {} = coincident(...)` (or \
                     `revolute`) instead",
                    decl.name.name
                )),
            );
            return None;
        }
        Some(ClosureKind::Distance { length })
    }

    /// `stiffness`/`rest`/`damping` of a revolute closure → closure springs and dampers.
    fn closure_loads<'f>(
        &mut self,
        closure: usize,
        field: &dyn Fn(&str) -> Option<&'f ast::Field>,
    ) {
        let ctx = Ctx::Static("a loop property");
        let scalar = |this: &mut Self, name: &'static str| -> Option<(Expr, Span)> {
            let f = field(name)?;
            let expr = this.lower_scalar_as(&f.value, ctx, &closure_expect(name))?;
            Some((expr, f.value.span))
        };
        let rest = scalar(self, "rest").map_or_else(Expr::zero, |(rest, _)| rest);
        if let Some((stiffness, span)) = scalar(self, "stiffness") {
            self.model.loads.push(ir::Load::LoopSpring {
                closure,
                stiffness,
                rest,
                span,
            });
        }
        if let Some((damping, span)) = scalar(self, "damping") {
            self.model.loads.push(ir::Load::LoopDamper {
                closure,
                damping,
                span,
            });
        }
    }
}
