//! Model-form extensions of `mech diagnose`: physics the base model leaves out, added by
//! transforming its IR, then re-derived and taped for one candidate.
//!
//! Consumes: a diagnosis experiment's model spec and an [`Extension`]. Produces: a [`Leg`]
//! of the extended model, whose new parameters come after the base model's (so the base
//! parameters keep their indices).
//!
//! Twist (Doshi et al. Sec. V-A, Eq. 8): a flexure hinge twists about its length axis with
//! stiffness `twist_factor · 2k/(1 + ν)`. In a rigid closed loop a single extra twist axis is
//! locked by the other hinges (and a twist at a loop closure is free only to first order), so
//! every revolute loop closure becomes compliant: its points stay together, and springs hold
//! its axis in line — the twisting hinge's own twist spring and, for the other closures,
//! stiff springs (`LATERAL_STIFFNESS_FACTOR · k`, the order of a hinge's in-plane stiffness)
//! about both off-axis directions.

use mech_codegen::ir::transform::{
    add_twist, constant_direction, hinge_axis, perpendicular, HingeSpring, Twist,
    LATERAL_STIFFNESS_FACTOR,
};
use mech_codegen::ir::{
    self, AxisAngle, ClosureKind, Dimension, Expr, FlexureAngle, Function, Load, Motion, Param,
    Vec3,
};
use mech_codegen::sym::Number;
use mech_codegen::Compiled;

use crate::experiments::leg::{Leg, AXES};
use crate::experiments::ModelSpec;
use crate::session::Session;

/// The fitted factor on Eq. 8's twist stiffness.
pub const TWIST_FACTOR: &str = "twist_factor";

/// The off-axis (lateral, and twist of the hinges not named) compliance, per unit bending
/// compliance: the inverse of the off-axis stiffness per unit k.
pub const OFF_AXIS_COMPLIANCE: &str = "off_axis_compliance";

/// Poisson's ratio of Kapton (seed Sec. V-A), in Eq. 8's `2/(1 + ν)` = 100/67.
const TWIST_RATIO: (i128, i128) = (100, 67);

/// A change of the model's form.
#[derive(Debug, Clone, PartialEq)]
pub enum Extension {
    /// These flexures twist about a length axis (0 = x, 1 = y, 2 = z in the hinge's frame),
    /// every other hinge compliant off its axis. New parameters: [`TWIST_FACTOR`],
    /// [`OFF_AXIS_COMPLIANCE`].
    Twist(Vec<(String, usize)>),
    /// A flexure's bending axis tilted by a small angle (fabrication; a rotation of the whole
    /// hinge about a coordinate axis of its frame perpendicular to it), pins and loop closures,
    /// every hinge compliant off its axis so the loops take up the misfit. New parameters: [`MISALIGNMENT`], [`OFF_AXIS_COMPLIANCE`].
    Misalignment { flexure: String, about: usize },
    /// The actuator along this slider coordinate sits on a compliant base (a spring in series
    /// with its own stiffness). New parameter: [`BASE_COMPLIANCE`].
    BaseCompliance(String),
    /// A mass rides on the tip of the actuator along this slider coordinate. New parameter:
    /// [`TIP_MASS`].
    TipMass(String),
    /// Every actuator's tip offset by the same length along its slider at zero voltage (an
    /// assembly preload, the seed's 50 µm in −y). New parameter: [`TIP_PRELOAD`].
    Preload,
}

/// The fitted misalignment angle (rad) of [`Extension::Misalignment`].
pub const MISALIGNMENT: &str = "misalignment";
/// The base compliance of [`Extension::BaseCompliance`], per unit actuator compliance.
pub const BASE_COMPLIANCE: &str = "base_compliance";
/// The mass (kg) of [`Extension::TipMass`].
pub const TIP_MASS: &str = "tip_mass";
/// The offset (m, positive along the slider axes) of [`Extension::Preload`].
pub const TIP_PRELOAD: &str = "tip_preload";

impl Extension {
    /// Where it acts, for reports: `s3 about x, fb3 about x`.
    pub fn location(&self) -> String {
        match self {
            Extension::Twist(hinges) => hinges
                .iter()
                .map(|(flexure, axis)| format!("{flexure} about {}", AXES[*axis]))
                .collect::<Vec<_>>()
                .join(", "),
            Extension::Misalignment { flexure, about } => {
                format!("{flexure} tilted about {}", AXES[*about])
            }
            Extension::BaseCompliance(slider) | Extension::TipMass(slider) => {
                format!("actuator along {slider}")
            }
            Extension::Preload => "every actuator".into(),
        }
    }
}

/// Opens `spec`'s model with `extension` applied.
pub fn open_leg(spec: &ModelSpec, extension: &Extension) -> Result<Leg, String> {
    let shown = spec.model.display();
    let base = Compiled::from_path(&spec.model).map_err(|e| format!("model `{shown}`: {e}"))?;
    let mut model = base.model;
    apply(&mut model, extension).map_err(|e| format!("model `{shown}`: {e}"))?;
    let session = Session::from_compiled(Compiled::from_model(model), &spec.set, &[])
        .map_err(|e| format!("model `{shown}` extended ({}): {e}", extension.location()))?;
    Leg::from_session(session, spec, &[])
}

/// Transforms `model` in place; the new parameters are appended in the order the variant
/// names them.
pub fn apply(model: &mut ir::Model, extension: &Extension) -> Result<(), String> {
    match extension {
        Extension::Twist(hinges) => twist(model, hinges),
        Extension::Misalignment { flexure, about } => misalign(model, flexure, *about),
        Extension::BaseCompliance(slider) => base_compliance(model, slider),
        Extension::TipMass(slider) => tip_mass(model, slider),
        Extension::Preload => preload(model),
    }
}

fn append_param(
    model: &mut ir::Model,
    name: &str,
    value: f64,
    dimension: Dimension,
    doc: &str,
) -> Expr {
    Expr::Param(model.params.append(Param {
        name: name.into(),
        value,
        dimension,
        docs: vec![doc.into()],
        span: Default::default(),
    }))
}

fn scaled(factor: &Expr, value: &Expr) -> Expr {
    Expr::Mul(Box::new(factor.clone()), Box::new(value.clone()))
}

/// A spring about one direction of `flexure`: its stiffness and damper times `factor`.
fn spring(flexure: &ir::Flexure, suffix: &str, factor: &Expr) -> HingeSpring {
    HingeSpring {
        name: format!("{}_{suffix}", flexure.name),
        stiffness: scaled(factor, &flexure.stiffness),
        damping: scaled(factor, &flexure.damping),
        loss_factor: flexure.loss_factor.clone(),
    }
}

fn find_flexure(model: &ir::Model, name: &str) -> Result<ir::Flexure, String> {
    model
        .flexures
        .iter()
        .find(|f| f.name == name)
        .cloned()
        .ok_or_else(|| format!("no flexure `{name}`"))
}

fn unit(axis: usize) -> Vec3 {
    let mut direction = [Expr::zero(), Expr::zero(), Expr::zero()];
    direction[axis] = Expr::one();
    direction
}

fn twist(model: &mut ir::Model, hinges: &[(String, usize)]) -> Result<(), String> {
    let factor = append_param(
        model,
        TWIST_FACTOR,
        1.0,
        Dimension::NONE,
        "Factor on Eq. 8's twist stiffness 2k/(1 + ν) (mech diagnose).",
    );
    let stiff = off_axis_stiffness(model);
    let eq8 = scaled(
        &factor,
        &Expr::Number(Number::rational(TWIST_RATIO.0, TWIST_RATIO.1)),
    );
    // The model's own hinges, before the springs added below get flexure records of their own.
    let named: Vec<&str> = hinges.iter().map(|(name, _)| name.as_str()).collect();
    let others: Vec<ir::Flexure> = model
        .flexures
        .iter()
        .filter(|f| !named.contains(&f.name.as_str()))
        .cloned()
        .collect();
    for (name, axis) in hinges {
        let flexure = find_flexure(model, name)?;
        let twist = Twist {
            axis: unit(*axis),
            twist: spring(&flexure, "twist", &eq8),
            lateral: Some(spring(&flexure, "lateral", &stiff)),
            span: flexure.span,
        };
        add_twist(model, flexure.angle, twist)
            .map_err(|e| format!("flexure `{name}` cannot twist about {}: {e:?}", AXES[*axis]))?;
    }
    compliant_off_axis(model, others, &stiff)
}

/// The off-axis stiffness factor `1/c` of [`OFF_AXIS_COMPLIANCE`] `c` (appended): c → 0 is
/// rigid off-axis, the base model.
fn off_axis_stiffness(model: &mut ir::Model) -> Expr {
    let compliance = append_param(
        model,
        OFF_AXIS_COMPLIANCE,
        1.0 / LATERAL_STIFFNESS_FACTOR as f64,
        Dimension::NONE,
        "Off-axis compliance of the hinges, per unit bending compliance 1/k.",
    );
    Expr::Div(Box::new(Expr::one()), Box::new(compliance))
}

/// Makes each of `flexures` stiff (`stiff`·k) in both off-axis directions, so the loops can
/// deform.
fn compliant_off_axis(
    model: &mut ir::Model,
    flexures: Vec<ir::Flexure>,
    stiff: &Expr,
) -> Result<(), String> {
    for flexure in flexures {
        let Some(axis) = hinge_axis(model, flexure.angle).and_then(|a| perpendicular(&a)) else {
            continue;
        };
        let twist = Twist {
            axis,
            twist: spring(&flexure, "off_axis", stiff),
            lateral: Some(spring(&flexure, "lateral", stiff)),
            span: flexure.span,
        };
        add_twist(model, flexure.angle, twist)
            .map_err(|e| format!("flexure `{}` cannot be made compliant: {e:?}", flexure.name))?;
    }
    Ok(())
}

/// Tilts `name`'s bending axis `a` by the fitted angle α about the coordinate axis `p` (a
/// rotation about `p`, so `a` leans towards `p × a`). At α = 0 it is the base model.
///
/// A pin's axis and its off-axis axes turn by Rodrigues' formula ([`rotate`]). A loop
/// closure's axis is read as a constant by the closure's geometry (its reference and twist
/// directions are built ⊥ it): instead both interframes turn by α about `p` (the last
/// rotation of each, so `p` is in the axis's own coordinates), which tilts the axis and every
/// direction tied to it alike and leaves the closure unstrained.
fn misalign(model: &mut ir::Model, name: &str, about: usize) -> Result<(), String> {
    let angle = append_param(
        model,
        MISALIGNMENT,
        0.0,
        Dimension::NONE,
        "Tilt of the flexure's bending axis (rad, mech diagnose).",
    );
    let stiff = off_axis_stiffness(model);
    let flexure = find_flexure(model, name)?;
    let all: Vec<ir::Flexure> = model.flexures.clone();
    compliant_off_axis(model, all, &stiff)?;
    let tiltable = |axis: &Vec3| -> Result<[f64; 3], String> {
        let a = constant_direction(axis)
            .ok_or_else(|| format!("flexure `{name}`: its axis is not a constant direction"))?;
        if a[about].abs() > 0.1 {
            return Err(format!(
                "flexure `{name}`: cannot tilt about {}, its own axis",
                AXES[about]
            ));
        }
        Ok(a)
    };
    match flexure.angle {
        FlexureAngle::Coordinate(coordinate) => {
            // The hinge's own axis and the off-axis axes `compliant_off_axis` inserted above
            // it turn together: R(Ra, q) = R·R(a, q)·Rᵀ, so the chain of the three is the
            // aligned hinge conjugated by R — the whole hinge tilted, its springs still
            // about its own (tilted) directions.
            let hinge_frames: Vec<_> = model
                .frames
                .iter()
                .filter_map(|(handle, frame)| match &frame.motion {
                    Motion::Revolute { coordinate: c, .. } => {
                        let coordinate_name = &model.coordinates[*c].name;
                        let own = *c == coordinate;
                        let off_axis = [format!("{name}_off_axis"), format!("{name}_lateral")]
                            .contains(coordinate_name);
                        (own || off_axis).then_some((handle, own))
                    }
                    _ => None,
                })
                .collect();
            if !hinge_frames.iter().any(|&(_, own)| own) {
                return Err(format!("flexure `{name}` is not on a pin joint"));
            }
            for (frame, own) in hinge_frames {
                let Motion::Revolute { axis, .. } = &mut model.frames.get_mut(frame).motion else {
                    unreachable!("found as revolute")
                };
                if own {
                    tiltable(axis)?;
                }
                rotate(axis, about, &angle).ok_or_else(|| {
                    format!("flexure `{name}`: an axis is not a constant direction")
                })?;
            }
            Ok(())
        }
        FlexureAngle::Loop(index) => match model.loops.get_mut(index).map(|c| &mut c.kind) {
            Some(ClosureKind::Revolute {
                axis,
                parent_orientation,
                child_orientation,
                ..
            }) => {
                tiltable(axis)?;
                for orientation in [parent_orientation, child_orientation] {
                    orientation.push(AxisAngle {
                        axis: unit(about),
                        angle: angle.clone(),
                    });
                }
                Ok(())
            }
            _ => Err(format!("flexure `{name}` is not on a revolute loop")),
        },
        _ => Err(format!("flexure `{name}` is not a bending hinge")),
    }
}

/// `axis` (a constant direction `a`) turned by `angle` about the coordinate axis `about`
/// (`p`), by Rodrigues' formula `a cos α + (p × a) sin α + p (p·a)(1 − cos α)`; `None` if `a`
/// is not constant.
fn rotate(axis: &mut Vec3, about: usize, angle: &Expr) -> Option<()> {
    let a = constant_direction(axis)?;
    let p = [0, 1, 2].map(|i| if i == about { 1.0 } else { 0.0 });
    let p_cross_a = [
        p[1] * a[2] - p[2] * a[1],
        p[2] * a[0] - p[0] * a[2],
        p[0] * a[1] - p[1] * a[0],
    ];
    let number = |x: f64| Expr::Number(Number::Float(x));
    let cos = Expr::Call(Function::Cos, vec![angle.clone()]);
    let sin = Expr::Call(Function::Sin, vec![angle.clone()]);
    let one_minus_cos = Expr::Sub(Box::new(Expr::one()), Box::new(cos.clone()));
    for (i, component) in axis.iter_mut().enumerate() {
        *component = Expr::Add(
            Box::new(Expr::Add(
                Box::new(scaled(&cos, &number(a[i]))),
                Box::new(scaled(&sin, &number(p_cross_a[i]))),
            )),
            Box::new(scaled(&one_minus_cos, &number(p[i] * a[about]))),
        );
    }
    Some(())
}

/// The actuator (force source and series spring) on slider coordinate `slider`: indices
/// into `model.loads` of its spring and its generalized force.
fn actuator_loads(model: &ir::Model, slider: &str) -> Result<(usize, usize), String> {
    let coordinate = model
        .coordinates
        .iter()
        .find(|(_, c)| c.name == slider)
        .map(|(handle, _)| handle)
        .ok_or_else(|| format!("no coordinate `{slider}`"))?;
    let find = |want_force: bool| {
        model.loads.iter().position(|load| match load {
            Load::GeneralizedForce { coordinate: c, .. } => want_force && *c == coordinate,
            Load::Spring { coordinate: c, .. } => !want_force && *c == coordinate,
            _ => false,
        })
    };
    match (find(false), find(true)) {
        (Some(spring), Some(force)) => Ok((spring, force)),
        _ => Err(format!("no actuator along `{slider}`")),
    }
}

/// A base spring `k_b` in series with the actuator's `k_a`, as the fitted compliance ratio
/// `c = k_a/k_b`. The node between them carries no mass, so it condenses out exactly: the
/// force on the transmission `(F_b(V) − k_a x)/(1 + c)` — force source and series stiffness
/// both scaled by `1/(1 + c)`. At c = 0 it is the base model.
fn base_compliance(model: &mut ir::Model, slider: &str) -> Result<(), String> {
    let (spring, force) = actuator_loads(model, slider)?;
    let compliance = append_param(
        model,
        BASE_COMPLIANCE,
        0.0,
        Dimension::NONE,
        "Actuator base compliance per unit actuator compliance (mech diagnose).",
    );
    let factor = Expr::Div(
        Box::new(Expr::one()),
        Box::new(Expr::Add(Box::new(Expr::one()), Box::new(compliance))),
    );
    for index in [spring, force] {
        match &mut model.loads[index] {
            Load::Spring {
                stiffness: value, ..
            }
            | Load::GeneralizedForce { force: value, .. } => {
                *value = scaled(&factor, value);
            }
            _ => unreachable!("found as the actuator's loads"),
        }
    }
    Ok(())
}

/// A point mass (fitted, starting at 0) on the frame of the actuator's slider.
fn tip_mass(model: &mut ir::Model, slider: &str) -> Result<(), String> {
    actuator_loads(model, slider)?;
    let frame = model
        .frames
        .iter()
        .find_map(|(handle, frame)| match &frame.motion {
            Motion::Prismatic { coordinate, .. }
                if model.coordinates[*coordinate].name == slider =>
            {
                Some(handle)
            }
            _ => None,
        })
        .ok_or_else(|| format!("`{slider}` is not a slider joint"))?;
    let mass = append_param(
        model,
        TIP_MASS,
        0.0,
        Dimension::MASS,
        "Mass on the actuator tip (kg, mech diagnose).",
    );
    let zero = Expr::zero;
    model.bodies.append(ir::Body {
        name: format!("{slider}_tip_mass"),
        frame,
        mass,
        center_of_mass: [zero(), zero(), zero()],
        inertia: ir::Inertia {
            xx: zero(),
            yy: zero(),
            zz: zero(),
            xy: zero(),
            yz: zero(),
            zx: zero(),
        },
        docs: Vec::new(),
        span: Default::default(),
    });
    Ok(())
}

/// Every actuator's series spring rests `tip_preload` further along its slider: at zero
/// voltage the spring pulls the tip there (as `rest = -preload` in `hamr_v2.mech`).
fn preload(model: &mut ir::Model) -> Result<(), String> {
    let offset = append_param(
        model,
        TIP_PRELOAD,
        0.0,
        Dimension::LENGTH,
        "Offset of every actuator's tip along its slider at zero voltage (m, mech diagnose).",
    );
    let actuated: Vec<_> = model
        .loads
        .iter()
        .filter_map(|load| match load {
            Load::GeneralizedForce { coordinate, .. } => Some(*coordinate),
            _ => None,
        })
        .collect();
    if actuated.is_empty() {
        return Err("no actuator to preload".into());
    }
    for load in &mut model.loads {
        if let Load::Spring {
            coordinate, rest, ..
        } = load
        {
            if actuated.contains(coordinate) {
                *rest = Expr::Add(Box::new(rest.clone()), Box::new(offset.clone()));
            }
        }
    }
    Ok(())
}
