//! Physical elements: materials, flexure hinges and piezoelectric actuators.
//!
//! Consumes: `material`, `flexure` and `actuator` declarations, after joints and loops.
//! Produces: springs, dampers and generalized forces in `model.loads`, flexure records in
//! `model.flexures`, and `E02xx`/`E03xx`/`E04xx` errors.
//!
//! Physics (Doshi et al., "Model driven design for flexure-based microrobots"), the closed
//! forms and the built-in materials of [`crate::physics`] (shared with the `mech` CLI):
//! - flexure bending stiffness `k = E w t³ / (12 l)` (Eq. 2), with `effective_length`
//!   replacing `length` for castellated hinges; time-domain damping `b = k η / ω_ref`
//!   (Eq. 5) with `ω_ref = 2π · reference_frequency`;
//! - `twist_axis`: the hinge also twists about its length axis with the twist stiffness
//!   `2k/(1 + ν)` (Eq. 8) and damping `2b/(1 + ν)`: on a pin joint a new coordinate, on a
//!   revolute loop a compliant closure (its lateral bending held by a stiff spring,
//!   `ir::transform::LATERAL_STIFFNESS_FACTOR · k`);
//! - actuator: a force source `F_b · V / V_rated` in parallel with the series stiffness
//!   `k_a = F_b / δ_f` along a slider.

use std::collections::BTreeMap;

use crate::diag::{Diagnostic, Span};
use crate::front::ast::{self, Ident};
use crate::ir::plausible::Rule;
use crate::ir::{self, ClosureKind, Dimension, Expr, FlexureAngle, JointKind};
use crate::physics::{self, Scalar, TaperedBimorph};
use crate::sym::Number;

use super::expr::{Ctx, Expect};
use super::{names, Lowerer};

/// A material's properties as expressions (params allowed).
#[derive(Clone, Debug)]
pub struct Material {
    pub modulus: Option<Expr>,
    pub poisson: Option<Expr>,
    pub density: Option<Expr>,
    pub loss_factor: Option<Expr>,
}

impl From<&physics::Material> for Material {
    /// The table's constants as exact decimals; an unknown (NaN) property is absent.
    fn from(material: &physics::Material) -> Material {
        let known = |value: f64| (!value.is_nan()).then(|| Expr::constant(value));
        Material {
            modulus: known(material.youngs_modulus),
            poisson: known(material.poisson_ratio),
            density: known(material.density),
            loss_factor: known(material.loss_factor),
        }
    }
}

/// Materials every model knows: `kapton` ([`physics::Material::KAPTON_HN`], the seed's
/// measured E = 2.56 GPa and η = 0.05 of uncastellated hinges). The table's other entries are
/// not language names (`kapton-datasheet` is not an identifier).
fn builtin_materials() -> BTreeMap<String, Material> {
    let kapton = &physics::Material::KAPTON_HN;
    BTreeMap::from([(kapton.name.to_string(), Material::from(kapton))])
}

const MATERIAL_FIELDS: [&str; 4] = ["modulus", "poisson", "density", "loss_factor"];
const FLEXURE_FIELDS: [&str; 10] = [
    "material",
    "width",
    "thickness",
    "length",
    "effective_length",
    "stiffness",
    "loss_factor",
    "reference_frequency",
    "rest",
    "twist_axis",
];
/// An actuator is given by (F_b, δ_f) at a rated voltage, or by its bimorph geometry.
const RATED_FIELDS: [&str; 3] = ["blocked_force", "free_deflection", "rated_voltage"];
const BIMORPH_FIELDS: [&str; 10] = [
    "pzt_thickness",
    "core_thickness",
    "length",
    "extension",
    "nominal_width",
    "width_ratio",
    "f31_blocked",
    "f31_free",
    "pzt_modulus",
    "core_modulus",
];

const PRESSURE: Dimension = Dimension {
    mass: 1,
    length: -1,
    time: -2,
    current: 0,
};
const DENSITY: Dimension = Dimension {
    mass: 1,
    length: -3,
    time: 0,
    current: 0,
};
const FREQUENCY: Dimension = Dimension {
    mass: 0,
    length: 0,
    time: -1,
    current: 0,
};
const VOLTAGE: Dimension = Dimension {
    mass: 1,
    length: 2,
    time: -3,
    current: -1,
};
/// Pa·m/V: an effective piezoelectric coefficient f31 = d31·E.
const PIEZO_COEFFICIENT: Dimension = Dimension {
    mass: 0,
    length: -2,
    time: 1,
    current: 1,
};

/// The dimension and an example for each element field.
fn expect(field: &'static str) -> Expect<'static> {
    let (dim, example) = match field {
        "modulus" => (PRESSURE, "2.5 GPa"),
        "poisson" | "loss_factor" => (Dimension::NONE, "0.05"),
        "density" => (DENSITY, "1420 kg/m^3"),
        "width" | "thickness" | "length" | "effective_length" | "free_deflection"
        | "pzt_thickness" | "core_thickness" | "extension" | "nominal_width" => {
            (Dimension::LENGTH, "25 um")
        }
        "width_ratio" => (Dimension::NONE, "1.5"),
        "f31_blocked" | "f31_free" => (PIEZO_COEFFICIENT, "24 Pa*m/V"),
        "pzt_modulus" | "core_modulus" => (PRESSURE, "40 GPa"),
        "stiffness" => (Dimension::TORQUE, "0.1 uN*m/rad"),
        "reference_frequency" => (FREQUENCY, "40 Hz"),
        "rest" => (Dimension::NONE, "0 deg"),
        "blocked_force" => (Dimension::FORCE, "320 mN"),
        "rated_voltage" | "voltage" => (VOLTAGE, "225 V"),
        _ => (Dimension::NONE, "1"),
    };
    Expect::new(dim, field, example)
}

fn mul(a: Expr, b: Expr) -> Expr {
    Expr::Mul(Box::new(a), Box::new(b))
}
fn div(a: Expr, b: Expr) -> Expr {
    Expr::Div(Box::new(a), Box::new(b))
}

impl<'a> Lowerer<'a> {
    /// Lowers materials, then flexures and actuators (call after joints and loops).
    pub(super) fn lower_elements(&mut self, items: &'a [ast::Item]) {
        let mut materials = builtin_materials();
        let mut element_names = names::Namespace::default();
        for item in items {
            let (ast::Item::Material(decl) | ast::Item::Flexure(decl) | ast::Item::Actuator(decl)) =
                item
            else {
                continue;
            };
            if let Err(diagnostic) = element_names.declare(&decl.name, "the name") {
                self.error(diagnostic);
            }
            match item {
                ast::Item::Material(decl) => {
                    let base = materials.get(&decl.name.name).cloned();
                    let material = self.lower_material(decl, base);
                    materials.insert(decl.name.name.clone(), material);
                }
                ast::Item::Flexure(decl) => self.lower_flexure(decl, &materials),
                ast::Item::Actuator(decl) => self.lower_actuator(decl),
                _ => {}
            }
        }
    }

    /// The known, non-repeated fields of an element.
    fn element_fields<'f>(
        &mut self,
        decl: &'f ast::ElementDecl,
        allowed: &[&str],
        what: &str,
    ) -> Vec<&'f ast::Field> {
        let (list, label) = (format!("fields of a {what}"), format!("not a {what} field"));
        self.known_fields(&decl.fields, allowed, &list, &label)
    }

    /// A scalar field checked against its dimension (params allowed, or inputs with `dynamic`).
    fn element_scalar(
        &mut self,
        fields: &[&ast::Field],
        name: &'static str,
        dynamic: bool,
    ) -> Option<(Expr, Span)> {
        let field = fields.iter().find(|f| f.name.name == name)?;
        let ctx = if dynamic {
            Ctx::Dynamic("an actuator's `voltage`")
        } else {
            Ctx::Static("an element property")
        };
        let expr = self.lower_scalar_as(&field.value, ctx, &expect(name))?;
        Some((expr, field.value.span))
    }

    fn lower_material(&mut self, decl: &ast::ElementDecl, base: Option<Material>) -> Material {
        let fields = self.element_fields(decl, &MATERIAL_FIELDS, "material");
        let mut material = base.unwrap_or(Material {
            modulus: None,
            poisson: None,
            density: None,
            loss_factor: None,
        });
        let set = |this: &mut Self, name: &'static str, slot: &mut Option<Expr>| {
            if let Some((expr, _)) = this.element_scalar(&fields, name, false) {
                *slot = Some(expr);
            }
        };
        set(self, "modulus", &mut material.modulus);
        set(self, "poisson", &mut material.poisson);
        set(self, "density", &mut material.density);
        set(self, "loss_factor", &mut material.loss_factor);
        material
    }

    /// Requires dimension `field` (SI `unit`) of element `kind` `decl` to be positive.
    fn require_positive(
        &mut self,
        (kind, decl): (&'static str, &ast::ElementDecl),
        field: &'static str,
        unit: &'static str,
        value: &Expr,
        span: Span,
    ) {
        let rule = Rule::Positive {
            field,
            unit,
            value: value.clone(),
        };
        self.require(kind, &decl.name.name, rule, span);
    }

    fn missing(&mut self, decl: &ast::ElementDecl, what: &str, message: &str, help: &str) {
        self.error(
            Diagnostic::error("E0402", format!("{what} `{}` {message}", decl.name.name))
                .with_label(decl.name.span, "declared here")
                .with_help(help.to_string()),
        );
    }

    /// The angle a flexure acts on: a pin joint's coordinate or a revolute loop's rotation.
    fn flexure_angle(&mut self, target: &Ident) -> Option<FlexureAngle> {
        if let Some(&j) = self.joint_index.get(&target.name) {
            let info = &self.joints[j];
            return match (info.kind, info.coordinate) {
                (Some(JointKind::Pin), Some(coordinate)) => {
                    Some(FlexureAngle::Coordinate(coordinate))
                }
                (Some(JointKind::Pin), None) => None,
                _ => {
                    self.error(
                        Diagnostic::error(
                            "E0213",
                            format!(
                                "a flexure needs a pin joint, but `{}` is not one",
                                target.name
                            ),
                        )
                        .with_label(target.span, "not a pin joint")
                        .with_help("put flexures on `pin` joints or on `revolute` loops"),
                    );
                    None
                }
            };
        }
        if let Some(index) = self.model.loops.iter().position(|l| l.name == target.name) {
            if matches!(self.model.loops[index].kind, ClosureKind::Revolute { .. }) {
                return Some(FlexureAngle::Loop(index));
            }
            self.error(
                Diagnostic::error(
                    "E0213",
                    format!(
                        "a flexure needs a revolute loop, but `{}` is not one",
                        target.name
                    ),
                )
                .with_label(target.span, "not a revolute loop")
                .with_help("declare the closure as `loop NAME = revolute(...) { axis = ...; }`"),
            );
            return None;
        }
        let mut candidates: Vec<&str> = self.joint_index.keys().map(String::as_str).collect();
        candidates.extend(self.model.loops.iter().map(|l| l.name.as_str()));
        let candidates: Vec<String> = candidates.iter().map(|s| s.to_string()).collect();
        let candidates: Vec<&str> = candidates.iter().map(String::as_str).collect();
        self.error(names::unknown(
            "E0201",
            "joint or loop",
            "joints and loops",
            &target.name,
            target.span,
            &candidates,
            "no joint or loop of that name",
        ));
        None
    }

    fn lower_flexure(&mut self, decl: &ast::ElementDecl, materials: &BTreeMap<String, Material>) {
        let fields = self.element_fields(decl, &FLEXURE_FIELDS, "flexure");
        let angle = decl
            .target
            .as_ref()
            .and_then(|target| self.flexure_angle(target));
        let material_name = fields.iter().find(|f| f.name.name == "material");
        let material = match material_name {
            None => materials.get("kapton").cloned(),
            Some(field) => match &super::expr::unparen(&field.value).kind {
                ast::ExprKind::Path(path) if path.segments.len() == 1 => {
                    let name = &path.segments[0];
                    let found = materials.get(&name.name).cloned();
                    if found.is_none() {
                        let known: Vec<&str> = materials.keys().map(String::as_str).collect();
                        self.error(names::unknown(
                            "E0204",
                            "material",
                            "materials",
                            &name.name,
                            name.span,
                            &known,
                            "not a material",
                        ));
                    }
                    found
                }
                _ => {
                    self.error(
                        Diagnostic::error("E0412", "expected a material name")
                            .with_label(field.value.span, "not a material")
                            .with_help("write e.g. `material = kapton;`"),
                    );
                    None
                }
            },
        };
        // A misspelled material is reported once; what it would have supplied is not.
        let unknown_material = material_name.is_some() && material.is_none();
        let stiffness = match self.element_scalar(&fields, "stiffness", false) {
            Some((k, _)) => Some(k),
            None if unknown_material => None,
            None => self.geometric_stiffness(decl, &fields, material.as_ref()),
        };
        let loss_factor = self
            .element_scalar(&fields, "loss_factor", false)
            .map(|(e, _)| e)
            .or_else(|| material.as_ref().and_then(|m| m.loss_factor.clone()));
        let Some(loss_factor) = loss_factor else {
            if !unknown_material {
                self.missing(
                    decl,
                    "flexure",
                    "has no `loss_factor`",
                    "give `loss_factor = 0.08;` (or use a material that has one)",
                );
            }
            return;
        };
        let frequency = self.element_scalar(&fields, "reference_frequency", false);
        if let Some((value, span)) = &frequency {
            // b = kη/ω_ref: a zero frequency gives an infinite damper.
            self.require_positive(("flexure", decl), "reference_frequency", "Hz", value, *span);
        }
        if frequency.is_none() {
            self.missing(
                decl,
                "flexure",
                "has no `reference_frequency`",
                "the time-domain damping b = kη/ω_ref needs the frequency it represents, e.g. the drive frequency: `reference_frequency = 40 Hz;`",
            );
        }
        let rest = self
            .element_scalar(&fields, "rest", false)
            .map_or_else(Expr::zero, |(e, _)| e);
        let (Some(angle), Some(stiffness), Some((frequency, _))) = (angle, stiffness, frequency)
        else {
            return;
        };
        // b = k η / ω_ref, ω_ref = 2π f_ref
        let omega = mul(mul(Expr::Number(Number::int(2)), Expr::Pi), frequency);
        let damping = physics::hysteretic_damping(stiffness.clone(), loss_factor.clone(), omega);
        let span = decl.span;
        match angle {
            FlexureAngle::Coordinate(coordinate) => {
                self.model.loads.push(ir::Load::Spring {
                    coordinate,
                    stiffness: stiffness.clone(),
                    rest,
                    span,
                });
                self.model.loads.push(ir::Load::Damper {
                    coordinate,
                    damping: damping.clone(),
                    span,
                });
            }
            FlexureAngle::Loop(closure) => {
                self.model.loads.push(ir::Load::LoopSpring {
                    closure,
                    stiffness: stiffness.clone(),
                    rest,
                    span,
                });
                self.model.loads.push(ir::Load::LoopDamper {
                    closure,
                    damping: damping.clone(),
                    span,
                });
            }
            // A flexure names a pin joint or a loop; twists are added by `apply_twists`.
            FlexureAngle::LoopTwist(_) | FlexureAngle::LoopLateral(_) => {}
        }
        if let Some(field) = fields.iter().find(|f| f.name.name == "twist_axis") {
            self.twist(
                decl,
                field,
                angle,
                material.as_ref(),
                &stiffness,
                &damping,
                &loss_factor,
            );
        }
        self.model.flexures.push(ir::Flexure {
            name: decl.name.name.clone(),
            angle,
            stiffness,
            loss_factor,
            damping,
            span,
        });
    }

    /// Records a twist for `apply_twists`: about `twist_axis`, stiffness and damping scaled
    /// by `2/(1 + ν)` (Eq. 8). On a pin joint it is a new degree of freedom; on a revolute
    /// loop the closure becomes compliant in twist.
    #[allow(clippy::too_many_arguments)]
    fn twist(
        &mut self,
        decl: &ast::ElementDecl,
        field: &ast::Field,
        angle: FlexureAngle,
        material: Option<&Material>,
        stiffness: &Expr,
        damping: &Expr,
        loss_factor: &Expr,
    ) {
        let Some(axis) = self.axis(&field.value, "a twist axis") else {
            return;
        };
        let Some(poisson) = material.and_then(|m| m.poisson.clone()) else {
            self.missing(
                decl,
                "flexure",
                "twists but its material has no `poisson`",
                "give the material a Poisson ratio: `poisson = 0.34;`",
            );
            return;
        };
        let ratio = physics::twist_ratio(poisson);
        let spring = |suffix: &str, factor: &Expr| ir::transform::HingeSpring {
            name: format!("{}_{suffix}", decl.name.name),
            stiffness: mul(factor.clone(), stiffness.clone()),
            damping: mul(factor.clone(), damping.clone()),
            loss_factor: loss_factor.clone(),
        };
        self.twists.push(super::PendingTwist {
            hinge: angle,
            axis_span: field.value.span,
            twist: ir::transform::Twist {
                axis,
                twist: spring("twist", &ratio),
                // A pin stays rigid laterally (one new coordinate); a loop closure's lateral
                // bending is held by a stiff spring.
                lateral: matches!(angle, FlexureAngle::Loop(_)).then(|| {
                    spring(
                        "lateral",
                        &Expr::Number(Number::int(ir::transform::LATERAL_STIFFNESS_FACTOR)),
                    )
                }),
                span: decl.span,
            },
        });
    }

    /// `E w t³ / (12 l)` (Eq. 2), with `effective_length` for castellated hinges.
    fn geometric_stiffness(
        &mut self,
        decl: &ast::ElementDecl,
        fields: &[&ast::Field],
        material: Option<&Material>,
    ) -> Option<Expr> {
        let width = self.element_scalar(fields, "width", false);
        let thickness = self.element_scalar(fields, "thickness", false);
        let effective_length = self.element_scalar(fields, "effective_length", false);
        let length = self.element_scalar(fields, "length", false);
        for (field, given) in [
            ("width", &width),
            ("thickness", &thickness),
            ("effective_length", &effective_length),
            ("length", &length),
        ] {
            if let Some((value, span)) = given {
                self.require_positive(("flexure", decl), field, "m", value, *span);
            }
        }
        let length = effective_length.or(length);
        let (Some((width, _)), Some((thickness, _)), Some((length, _))) =
            (width, thickness, length)
        else {
            self.missing(
                decl,
                "flexure",
                "needs either `stiffness` or `width`, `thickness` and `length` (or `effective_length`)",
                "e.g. `width = 1.23 mm; thickness = 25 um; effective_length = 66 um;`, or `stiffness = 65.4 uN*m/rad;`",
            );
            return None;
        };
        let Some(modulus) = material.and_then(|m| m.modulus.clone()) else {
            self.missing(
                decl,
                "flexure",
                "has a material without `modulus`",
                "give the material a `modulus = 2.5 GPa;`",
            );
            return None;
        };
        Some(physics::bending_stiffness(
            modulus, width, thickness, length,
        ))
    }

    fn lower_actuator(&mut self, decl: &ast::ElementDecl) {
        let allowed: Vec<&str> = RATED_FIELDS
            .iter()
            .chain(&BIMORPH_FIELDS)
            .chain(&["voltage", "rest"])
            .copied()
            .collect();
        let fields = self.element_fields(decl, &allowed, "actuator");
        let coordinate = decl
            .target
            .as_ref()
            .and_then(|target| self.slider_coordinate(target));
        let voltage = self.element_scalar(&fields, "voltage", true);
        if voltage.is_none() && !fields.iter().any(|f| f.name.name == "voltage") {
            self.missing(
                decl,
                "actuator",
                "has no `voltage`",
                "give its drive voltage, usually an input: `voltage = drive;`",
            );
        }
        let uses = |names: &[&str]| fields.iter().any(|f| names.contains(&f.name.name.as_str()));
        // Per volt: the blocked force F_b/V and the free deflection δ_f/V.
        let per_volt = match (uses(&RATED_FIELDS), uses(&BIMORPH_FIELDS)) {
            (true, true) => {
                self.missing(decl, "actuator", "mixes the two forms", "give either `blocked_force`, `free_deflection`, `rated_voltage`, or the bimorph geometry, not both");
                None
            }
            (false, true) => self.bimorph_per_volt(decl, &fields),
            _ => self.rated_per_volt(decl, &fields),
        };
        let (Some(coordinate), Some((force_per_volt, deflection_per_volt)), Some((voltage, _))) =
            (coordinate, per_volt, voltage)
        else {
            return;
        };
        // `rest`: where the tip sits at zero voltage (a preload offsets it), a length.
        let rest_expect = Expect::new(Dimension::LENGTH, "rest", "-50 um");
        let rest = fields
            .iter()
            .find(|f| f.name.name == "rest")
            .and_then(|f| {
                self.lower_scalar_as(&f.value, Ctx::Static("an element property"), &rest_expect)
            })
            .unwrap_or_else(Expr::zero);
        let span = decl.span;
        // Series stiffness k_a = F_b/δ_f (the same at every voltage), and the force source
        // F_b(V) = (F_b/V)·V.
        let stiffness = div(force_per_volt.clone(), deflection_per_volt);
        self.model.loads.push(ir::Load::Spring {
            coordinate,
            stiffness,
            rest,
            span,
        });
        self.model.loads.push(ir::Load::GeneralizedForce {
            coordinate,
            force: mul(force_per_volt, voltage),
            span,
        });
    }

    fn slider_coordinate(&mut self, target: &Ident) -> Option<ir::Handle<ir::Coordinate>> {
        let joint = self
            .joint_index
            .get(&target.name)
            .map(|&j| (self.joints[j].kind, self.joints[j].coordinate));
        match joint {
            Some((Some(JointKind::Slider), coordinate)) => coordinate,
            _ => {
                self.error(
                    Diagnostic::error("E0213", format!("an actuator acts along a slider joint, but `{}` is not one", target.name))
                        .with_label(target.span, "not a slider joint")
                        .with_help("declare `joint NAME = slider(parent, child) { axis = ...; }` and put the actuator on it"),
                );
                None
            }
        }
    }

    /// `(F_b/V_rated, δ_f/V_rated)` of the rated form.
    fn rated_per_volt(
        &mut self,
        decl: &ast::ElementDecl,
        fields: &[&ast::Field],
    ) -> Option<(Expr, Expr)> {
        let mut values = Vec::new();
        for name in RATED_FIELDS {
            match self.element_scalar(fields, name, false) {
                Some((value, _)) => values.push(value),
                None if !fields.iter().any(|f| f.name.name == name) => {
                    self.missing(decl, "actuator", &format!("has no `{name}`"), "give `blocked_force`, `free_deflection` and `rated_voltage` (F_b and δ_f at that voltage), or the bimorph geometry");
                }
                None => {}
            }
        }
        let [blocked, deflection, rated] = <[Expr; 3]>::try_from(values).ok()?;
        Some((div(blocked, rated.clone()), div(deflection, rated)))
    }

    /// `(F_b/V, δ_f/V)` of a tapered symmetric bimorph: [`TaperedBimorph`] at 1 V, with the
    /// geometry factor's limit when `width_ratio` is within [`physics::UNTAPERED_BAND`] of 1
    /// at the parameters' defaults (where the closed form is 0/0).
    fn bimorph_per_volt(
        &mut self,
        decl: &ast::ElementDecl,
        fields: &[&ast::Field],
    ) -> Option<(Expr, Expr)> {
        let mut values = BTreeMap::new();
        for name in BIMORPH_FIELDS {
            match self.element_scalar(fields, name, false) {
                Some((value, span)) => {
                    values.insert(name, (value, span));
                }
                None if !fields.iter().any(|f| f.name.name == name) => {
                    self.missing(decl, "actuator", &format!("has no `{name}`"), "a bimorph needs pzt_thickness, core_thickness, length, extension, nominal_width, width_ratio, f31_blocked, f31_free, pzt_modulus and core_modulus");
                }
                None => {}
            }
        }
        for field in ["pzt_thickness", "core_thickness", "length", "nominal_width"] {
            if let Some((value, span)) = values.get(field) {
                self.require_positive(("actuator", decl), field, "m", value, *span);
            }
        }
        if values.len() != BIMORPH_FIELDS.len() {
            return None;
        }
        let get = |name: &str| values[name].0.clone();
        let bimorph = TaperedBimorph {
            pzt_thickness: get("pzt_thickness"),
            core_thickness: get("core_thickness"),
            length: get("length"),
            extension: get("extension"),
            nominal_width: get("nominal_width"),
            width_ratio: get("width_ratio"),
            f31_blocked: get("f31_blocked"),
            f31_free: get("f31_free"),
            pzt_modulus: get("pzt_modulus"),
            core_modulus: get("core_modulus"),
        };
        let (wr_value, wr_span) = (
            self.evaluate(&bimorph.width_ratio, values["width_ratio"].1),
            values["width_ratio"].1,
        );
        if !(wr_value > 0.0 && wr_value < 2.0) {
            self.error(
                Diagnostic::error(
                    "E0302",
                    format!("`width_ratio` must lie between 0 and 2, found {wr_value}"),
                )
                .with_label(wr_span, "the tip width (2 − w_r)·w_nom must be positive")
                .with_help(
                    "a width ratio of 1.5 means a base 1.5× and a tip 0.5× the nominal width",
                ),
            );
            return None;
        }
        // The taper is chosen at the parameters' defaults: an expression cannot switch forms.
        let geometry_factor = if (wr_value - 1.0).abs() < physics::UNTAPERED_BAND {
            bimorph.untapered_geometry_factor()
        } else {
            bimorph.geometry_factor_at(bimorph.width_ratio.clone())
        };
        let force = bimorph.blocked_force_per_volt(geometry_factor);
        let deflection = bimorph.free_deflection_per_volt();
        Some((force, deflection))
    }
}
