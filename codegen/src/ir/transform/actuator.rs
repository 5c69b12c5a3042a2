//! An actuator beyond the model as written: a compliant base in series with it, its own
//! stiffness or force off by a factor, a mass on its tip, a preload of every actuator's tip.
//! An actuator is a force source and a series spring on a slider coordinate (`actuator` in
//! the language).
//!
//! Consumes: a checked model and the actuator's slider coordinate. Produces: the model
//! changed in place, with [`BASE_COMPLIANCE`], [`STIFFNESS_FACTOR`], [`FORCE_FACTOR`],
//! [`TIP_MASS`] or [`TIP_PRELOAD`] appended.

use super::{append_param, scaled, TransformError};
use crate::ir::{Body, Dimension, Expr, Load, Model, Motion};

/// The base compliance of `Extension::BaseCompliance` (the diagnosis), per unit actuator compliance.
pub const BASE_COMPLIANCE: &str = "base_compliance";
/// The factor on one actuator's stiffness `k_a` of [`stiffness_factor`].
pub const STIFFNESS_FACTOR: &str = "actuator_stiffness_factor";
/// The factor on one actuator's force source `F_b V/V_rated` of [`force_factor`].
pub const FORCE_FACTOR: &str = "actuator_force_factor";
/// The mass (kg) of `Extension::TipMass` (the diagnosis).
pub const TIP_MASS: &str = "tip_mass";
/// The offset (m, positive along the slider axes) of `Extension::Preload` (the diagnosis).
pub const TIP_PRELOAD: &str = "tip_preload";

/// The actuator (force source and series spring) on slider coordinate `slider`: indices
/// into `model.loads` of its spring and its generalized force.
fn actuator_loads(model: &Model, slider: &str) -> Result<(usize, usize), TransformError> {
    let coordinate = model
        .coordinates
        .iter()
        .find(|(_, c)| c.name == slider)
        .map(|(handle, _)| handle)
        .ok_or_else(|| TransformError::NoCoordinate(slider.to_string()))?;
    let find = |want_force: bool| {
        model.loads.iter().position(|load| match load {
            Load::GeneralizedForce { coordinate: c, .. } => want_force && *c == coordinate,
            Load::Spring { coordinate: c, .. } => !want_force && *c == coordinate,
            _ => false,
        })
    };
    match (find(false), find(true)) {
        (Some(spring), Some(force)) => Ok((spring, force)),
        _ => Err(TransformError::NoActuator(slider.to_string())),
    }
}

/// A base spring `k_b` in series with the actuator's `k_a`, as the fitted compliance ratio
/// `c = k_a/k_b`. The node between them carries no mass, so it condenses out exactly: the
/// force on the transmission `(F_b(V) − k_a x)/(1 + c)` — force source and series stiffness
/// both scaled by `1/(1 + c)`. At c = 0 it is the base model.
pub fn base_compliance(model: &mut Model, slider: &str) -> Result<(), TransformError> {
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
    scale_loads(model, &[spring, force], &factor);
    Ok(())
}

/// The actuator's stiffness `k_a` times a fitted factor (1: the base model), its force
/// source as written: a softer or stiffer bimorph with the same blocked force, so its free
/// deflection `F_b/k_a` changes inversely.
pub fn stiffness_factor(model: &mut Model, slider: &str) -> Result<(), TransformError> {
    let (spring, _) = actuator_loads(model, slider)?;
    scale_by_new_factor(model, spring, STIFFNESS_FACTOR, "stiffness k_a");
    Ok(())
}

/// The actuator's force source times a fitted factor (1: the base model), its stiffness as
/// written: a weaker or stronger drive (piezoelectric coefficient, the voltage reaching the
/// bimorph), so blocked force and free deflection scale together.
pub fn force_factor(model: &mut Model, slider: &str) -> Result<(), TransformError> {
    let (_, force) = actuator_loads(model, slider)?;
    scale_by_new_factor(model, force, FORCE_FACTOR, "force source F_b V/V_rated");
    Ok(())
}

/// Appends the factor `name` (1 as written) and multiplies load `index` by it.
fn scale_by_new_factor(model: &mut Model, index: usize, name: &str, what: &str) {
    let factor = append_param(
        model,
        name,
        1.0,
        Dimension::NONE,
        &format!("Factor on the actuator's {what} (mech diagnose)."),
    );
    scale_loads(model, &[index], &factor);
}

/// Multiplies the stiffness of the springs and the value of the generalized forces at
/// `indices` of `model.loads` by `factor`.
fn scale_loads(model: &mut Model, indices: &[usize], factor: &Expr) {
    for &index in indices {
        match &mut model.loads[index] {
            Load::Spring {
                stiffness: value, ..
            }
            | Load::GeneralizedForce { force: value, .. } => {
                *value = scaled(factor, value);
            }
            _ => unreachable!("found as the actuator's loads"),
        }
    }
}

/// A point mass (fitted, starting at 0) on the frame of the actuator's slider.
pub fn tip_mass(model: &mut Model, slider: &str) -> Result<(), TransformError> {
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
        .ok_or_else(|| TransformError::NotASlider(slider.to_string()))?;
    let mass = append_param(
        model,
        TIP_MASS,
        0.0,
        Dimension::MASS,
        "Mass on the actuator tip (kg, mech diagnose).",
    );
    model
        .bodies
        .append(Body::point_mass(format!("{slider}_tip_mass"), frame, mass));
    Ok(())
}

/// Every actuator's series spring rests `tip_preload` further along its slider: at zero
/// voltage the spring pulls the tip there (as `rest = -preload` in `hamr_v2.mech`).
pub fn preload(model: &mut Model) -> Result<(), TransformError> {
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
        return Err(TransformError::NoActuators);
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
