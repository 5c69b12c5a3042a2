//! AST → IR: resolves names, evaluates units, checks dimensions, orders the joint tree, and
//! builds the [`ir::Model`].
//!
//! Consumes: an [`ast::File`] (from `front::parse`) and its source file (for the model name).
//! Produces: an [`ir::Model`] that satisfies the invariants documented in `ir/mod.rs`, or every
//! error of this phase, sorted by position.
//!
//! The work is split by topic: `expr` (scalar expressions, units, dimensions), `body` (bodies,
//! points, frames, axes, rotations), `tree` (joints, tree order, frame building), `loads`
//! (gravity, forces, torques, point-to-point springs, outputs), `loops` (loop closures),
//! `velocity` (velocity constraints), `speeds` (generalized speeds chosen by `speed`) and
//! `names` (namespaces and suggestions).

mod body;
mod elements;
mod expr;
mod loads;
mod loops;
mod names;
mod speeds;

mod tree;
mod velocity;

use std::collections::BTreeMap;
use std::sync::Arc;

use crate::diag::{Diagnostic, Errors, SourceFile, Span};
use crate::front::ast;
use crate::ir::{self, Handle};

use body::Owner;
use expr::Typed;
use loads::{PendingLoad, PendingOutput};
use names::Namespace;
use tree::JointInfo;

/// Lowers a parsed file to the IR; the model name defaults to the file stem of `file.path`.
pub fn lower(file: &Arc<SourceFile>, ast: &ast::File) -> Result<ir::Model, Errors> {
    let name = match &ast.model {
        Some(ident) => ident.name.clone(),
        None => default_model_name(&file.path),
    };
    let mut lowerer = Lowerer::new(name, ast.docs.clone());
    lowerer.run(ast);
    lowerer
        .finish()
        .map_err(|diagnostics| Errors::new(file.clone(), diagnostics))
}

/// The file stem of `path` as an identifier (`models/four-bar.mech` → `four_bar`).
pub fn default_model_name(path: &str) -> String {
    let file_name = path.rsplit(['/', '\\']).next().unwrap_or(path);
    let stem = file_name.split('.').next().unwrap_or(file_name);
    let mut name: String = stem
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if name.is_empty() {
        name.push_str("model");
    }
    if name.starts_with(|c: char| c.is_ascii_digit()) {
        name.insert(0, '_');
    }
    name
}

/// What a value name refers to.
#[derive(Clone, Copy, Debug)]
enum Value {
    Param(Handle<ir::Param>),
    Input(Handle<ir::Input>),
    Let(usize),
    /// A param or input whose value has errors (already reported): its uses lower to
    /// nothing, without errors of their own, so that one typo is reported once and not
    /// again as a dimension error at every use (as a `let` with errors is).
    Failed,
}

/// Names that may not be declared as params, lets or inputs.
const RESERVED_VALUES: &[(&str, &str)] = &[
    ("t", "the simulation time"),
    ("pi", "the constant π"),
    ("kinetic_energy", "the kinetic energy output"),
    ("potential_energy", "the potential energy output"),
];

/// The state of one lowering: the model being built plus the symbol tables.
struct Lowerer<'a> {
    diagnostics: Vec<Diagnostic>,
    model: ir::Model,
    /// params, lets and inputs
    value_names: Namespace,
    values: BTreeMap<String, Value>,
    /// Lowered `let` definitions in declaration order (`None` if it had an error).
    lets: Vec<Option<Typed>>,
    let_spans: Vec<Span>,
    /// The `let` being lowered: it may only use lets declared before it.
    current_let: Option<usize>,
    /// Default values of the params, by handle index (for evaluating `q0`, `u0`, defaults).
    param_values: Vec<f64>,
    /// Bodies and joints share one namespace (each becomes a frame of that name).
    structure_names: Namespace,
    /// `owners[0]` is the Newtonian frame; the others are bodies in declaration order.
    owners: Vec<Owner>,
    bodies: BTreeMap<String, usize>,
    joints: Vec<JointInfo<'a>>,
    joint_index: BTreeMap<String, usize>,
    loads: Vec<PendingLoad>,
    outputs: Vec<PendingOutput>,
    /// The scalar outputs lowered so far, as expressions later outputs may use.
    scalar_outputs: BTreeMap<String, Typed>,
    /// Declared contacts by name, with their index in `model.loads` once built.
    contacts: BTreeMap<String, Option<usize>>,
    /// Twist degrees of freedom of flexures, inserted into the tree once everything else
    /// refers to frames (the insertion renumbers them).
    twists: Vec<PendingTwist>,
}

/// A flexure's twist, waiting for [`Lowerer::apply_twists`].
struct PendingTwist {
    /// The flexure's hinge: a pin joint's coordinate or a revolute loop.
    hinge: ir::FlexureAngle,
    /// The `twist_axis` value, for diagnostics.
    axis_span: crate::diag::Span,
    twist: ir::transform::Twist,
}

impl<'a> Lowerer<'a> {
    fn new(name: String, docs: Vec<String>) -> Lowerer<'a> {
        let mut model = ir::Model::new(name);
        model.docs = docs;
        Lowerer {
            diagnostics: Vec::new(),
            model,
            value_names: Namespace::default(),
            values: BTreeMap::new(),
            lets: Vec::new(),
            let_spans: Vec::new(),
            current_let: None,
            param_values: Vec::new(),
            structure_names: Namespace::default(),
            owners: vec![Owner::newtonian()],
            bodies: BTreeMap::new(),
            joints: Vec::new(),
            joint_index: BTreeMap::new(),
            loads: Vec::new(),
            outputs: Vec::new(),
            scalar_outputs: BTreeMap::new(),
            contacts: BTreeMap::new(),
            twists: Vec::new(),
        }
    }

    fn error(&mut self, diagnostic: Diagnostic) {
        self.diagnostics.push(diagnostic);
    }

    /// Records a physical rule on the values of declaration `kind` `name` (kept in the model,
    /// so a run-time parameter change is checked too) and reports it if the parameters'
    /// defaults break it; `span` is the value's text.
    fn require(&mut self, kind: &'static str, name: &str, rule: ir::plausible::Rule, span: Span) {
        let requirement = ir::Requirement {
            kind,
            name: name.to_string(),
            rule,
            span,
        };
        if let Err(violation) = requirement.check(&self.param_values) {
            self.error(
                Diagnostic::error(
                    violation.code(),
                    format!("{kind} `{name}` {}", violation.message()),
                )
                .with_label(span, violation.found())
                .with_help(violation.help()),
            );
        }
        self.model.requirements.push(requirement);
    }

    /// All phases in dependency order; each collects its errors and goes on.
    fn run(&mut self, file: &'a ast::File) {
        self.lower_values(&file.items);
        self.declare_structure(&file.items);
        self.lower_owners(&file.items);
        self.lower_joints(&file.items);
        let order = self.tree_order();
        self.build_tree(&order);
        self.build_points();
        self.build_bodies();
        self.lower_loops(&file.items);
        self.lower_velocity_constraints(&file.items);
        self.lower_speeds(&file.items);
        self.lower_elements(&file.items);
        self.lower_loads_and_outputs(&file.items);
        self.build_loads();
        self.build_outputs();
        self.apply_twists();
        self.check_springs_apart();
        self.check_speeds_independent();
    }

    /// E0417: a point-to-point spring whose ends meet at the initial coordinates, where its
    /// direction `ê = d/L` (and so its force) is undefined. Checked on a complete model only
    /// (the kinematics need every frame); a zero-length undamped spring is exempt (its force
    /// `−k d` needs no direction).
    fn check_springs_apart(&mut self) {
        if !self.diagnostics.is_empty() {
            return;
        }
        let lengths = crate::kane::spring_lengths_at_start(&self.model, &self.param_values);
        for (index, length, scale) in lengths {
            if length > 1e-12 * scale {
                continue;
            }
            let Some(ir::Load::PointSpring { span, .. }) = self.model.loads.get(index) else {
                continue;
            };
            let span = *span;
            let label = if length == 0.0 {
                "its ends coincide at the initial coordinates".to_string()
            } else {
                format!("its ends are {length:.1e} m apart at the initial coordinates")
            };
            self.error(
                Diagnostic::error("E0417", "the ends of this spring meet at the start")
                    .with_label(span, label)
                    .with_help(
                        "its force acts along the line between the ends, which has no direction \
                         where they meet: start the joints (`q0`) with the ends apart, or make it \
                         a zero-length spring (`rest_length` 0, no `damping` or `tension`), whose force `−k d` \
                         is defined everywhere",
                    ),
            );
        }
    }

    /// Adds each flexure twist (`ir::transform::add_twist`) once everything else refers to
    /// frames: a pin joint's twist inserts a frame and renumbers the frames after it.
    fn apply_twists(&mut self) {
        if !self.diagnostics.is_empty() {
            return;
        }
        for pending in std::mem::take(&mut self.twists) {
            let error =
                match ir::transform::add_twist(&mut self.model, pending.hinge, pending.twist) {
                    Ok(_) => continue,
                    Err(error) => error,
                };
            let (label, help) = match error {
                ir::transform::TwistError::AlongHingeAxis => (
                    "a twist axis along the hinge axis",
                    "the twist axis is the flexure's length axis, perpendicular to its `axis`",
                ),
                ir::transform::TwistError::NotAHinge
                | ir::transform::TwistError::AlreadyTwists
                | ir::transform::TwistError::NoLateralSpring => (
                    "this hinge cannot take a twist",
                    "`twist_axis` goes on a flexure of a pin joint or of a revolute loop",
                ),
            };
            self.error(
                Diagnostic::error("E0403", "cannot add this twist axis")
                    .with_label(pending.axis_span, label)
                    .with_help(help),
            );
        }
    }

    fn finish(mut self) -> Result<ir::Model, Vec<Diagnostic>> {
        // Without bodies nothing moves and every phase accepts it (`0 = 0`). Only reported
        // alone: with other errors, those are what to fix.
        if self.diagnostics.is_empty() && self.model.bodies.is_empty() {
            self.error(
                Diagnostic::error("E0505", "the model has no bodies")
                    .with_label(Span::default(), "no `body` declared in this file")
                    .with_help("declare a body and the joint that attaches it, e.g. `body arm { mass = 10 g; }` and `joint hinge = pin(newtonian, arm) { axis = z; }`"),
            );
        }
        if self.diagnostics.is_empty() {
            return Ok(self.model);
        }
        self.diagnostics
            .sort_by_key(|d| d.labels.first().map(|l| l.span.start));
        Err(self.diagnostics)
    }

    // -----------------------------------------------------------------------------------------
    // params, lets, inputs
    // -----------------------------------------------------------------------------------------

    /// Params and inputs first (their values are constants), then lets in declaration order.
    fn lower_values(&mut self, items: &'a [ast::Item]) {
        for item in items {
            match item {
                ast::Item::Param(decl) => self.lower_param(decl),
                ast::Item::Input(decl) => self.lower_input(decl),
                ast::Item::Let(decl) => self.declare_let(decl),
                _ => {}
            }
        }
        let lets = items.iter().filter_map(|item| {
            if let ast::Item::Let(decl) = item {
                Some(decl)
            } else {
                None
            }
        });
        for (index, decl) in lets.enumerate() {
            self.current_let = Some(index);
            let value = self.lower_scalar(&decl.value, expr::Ctx::Dynamic("a `let`"));
            self.lets[index] = value;
        }
        self.current_let = None;
    }

    /// Declares a value name; `false` if it clashes (the error is recorded).
    fn declare_value(&mut self, name: &ast::Ident) -> bool {
        if let Some((_, meaning)) = RESERVED_VALUES
            .iter()
            .find(|(reserved, _)| *reserved == name.name)
        {
            self.error(names::reserved(name, meaning));
            return false;
        }
        match self.value_names.declare(name, "the name") {
            Ok(()) => true,
            Err(diagnostic) => {
                self.error(diagnostic);
                false
            }
        }
    }

    fn lower_param(&mut self, decl: &ast::ValueDecl) {
        self.lower_constant_decl(decl, "a param value", |this, value, dimension| {
            let handle = this.model.params.append(ir::Param {
                name: decl.name.name.clone(),
                value,
                dimension,
                docs: decl.docs.clone(),
                span: decl.name.span,
            });
            this.param_values.push(value);
            Value::Param(handle)
        });
    }

    fn lower_input(&mut self, decl: &ast::ValueDecl) {
        self.lower_constant_decl(
            decl,
            "an input's default value",
            |this, default, dimension| {
                Value::Input(this.model.inputs.append(ir::Input {
                    name: decl.name.name.clone(),
                    default,
                    dimension,
                    docs: decl.docs.clone(),
                    span: decl.name.span,
                }))
            },
        );
    }

    /// A param or input: its name declared, its value folded to a number (0, dimensionless,
    /// where it does not fold, so that lowering goes on), `add` puts it in the model, and the
    /// name stands for what `add` returns (a failed value where the value did not fold).
    fn lower_constant_decl(
        &mut self,
        decl: &ast::ValueDecl,
        what: &'static str,
        add: impl FnOnce(&mut Self, f64, ir::Dimension) -> Value,
    ) {
        let declared = self.declare_value(&decl.name);
        let lowered = self.lower_constant(&decl.value, expr::Ctx::Constant(what));
        let (number, dimension) = match lowered {
            Some((number, dimension)) => (number.to_f64(), dimension),
            None => (0.0, ir::Dimension::NONE),
        };
        let value = add(self, number, dimension);
        if declared {
            let value = match lowered {
                Some(_) => value,
                None => Value::Failed,
            };
            self.values.insert(decl.name.name.clone(), value);
        }
    }

    fn declare_let(&mut self, decl: &ast::ValueDecl) {
        let index = self.lets.len();
        self.lets.push(None);
        self.let_spans.push(decl.name.span);
        if self.declare_value(&decl.name) {
            self.values
                .insert(decl.name.name.clone(), Value::Let(index));
        }
    }
}
