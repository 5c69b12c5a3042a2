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
    add_twist, hinge_axis, perpendicular, HingeSpring, Twist, LATERAL_STIFFNESS_FACTOR,
};
use mech_codegen::ir::{self, Dimension, Expr, Param};
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
    /// These flexures twist about a length axis (0 = x, 1 = y, 2 = z in the hinge's frame).
    Twist(Vec<(String, usize)>),
}

impl Extension {
    /// Where it acts, for reports: `s3 about x, fb3 about x`.
    pub fn location(&self) -> String {
        match self {
            Extension::Twist(hinges) => hinges
                .iter()
                .map(|(flexure, axis)| format!("{flexure} about {}", AXES[*axis]))
                .collect::<Vec<_>>()
                .join(", "),
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

/// Transforms `model` in place.
pub fn apply(model: &mut ir::Model, extension: &Extension) -> Result<(), String> {
    match extension {
        Extension::Twist(hinges) => twist(model, hinges),
    }
}

fn twist(model: &mut ir::Model, hinges: &[(String, usize)]) -> Result<(), String> {
    let factor = model.params.append(Param {
        name: TWIST_FACTOR.into(),
        value: 1.0,
        dimension: Dimension::NONE,
        docs: vec!["Factor on Eq. 8's twist stiffness 2k/(1 + ν) (mech diagnose).".into()],
        span: Default::default(),
    });
    let scaled = |factor: Expr, value: &Expr| Expr::Mul(Box::new(factor), Box::new(value.clone()));
    // Off-axis stiffness = k / compliance (compliance → 0: rigid off-axis, the base model).
    let compliance = model.params.append(Param {
        name: OFF_AXIS_COMPLIANCE.into(),
        value: 1.0 / LATERAL_STIFFNESS_FACTOR as f64,
        dimension: Dimension::NONE,
        docs: vec!["Off-axis compliance of the hinges, per unit bending compliance 1/k.".into()],
        span: Default::default(),
    });
    let stiff = Expr::Div(Box::new(Expr::one()), Box::new(Expr::Param(compliance)));
    let eq8 = Expr::Mul(
        Box::new(Expr::Param(factor)),
        Box::new(Expr::Number(Number::rational(TWIST_RATIO.0, TWIST_RATIO.1))),
    );
    let spring = |flexure: &ir::Flexure, suffix: &str, factor: &Expr| HingeSpring {
        name: format!("{}_{suffix}", flexure.name),
        stiffness: scaled(factor.clone(), &flexure.stiffness),
        damping: scaled(factor.clone(), &flexure.damping),
        loss_factor: flexure.loss_factor.clone(),
    };
    // The model's own hinges, before the springs added below get flexure records of their own.
    let named: Vec<&str> = hinges.iter().map(|(name, _)| name.as_str()).collect();
    let others: Vec<ir::Flexure> = model
        .flexures
        .iter()
        .filter(|f| !named.contains(&f.name.as_str()))
        .cloned()
        .collect();
    for (name, axis) in hinges {
        let flexure = model
            .flexures
            .iter()
            .find(|f| &f.name == name)
            .cloned()
            .ok_or_else(|| format!("no flexure `{name}` to twist"))?;
        let mut direction = [Expr::zero(), Expr::zero(), Expr::zero()];
        direction[*axis] = Expr::one();
        let twist = Twist {
            axis: direction,
            twist: spring(&flexure, "twist", &eq8),
            lateral: Some(spring(&flexure, "lateral", &stiff)),
            span: flexure.span,
        };
        add_twist(model, flexure.angle, twist)
            .map_err(|e| format!("flexure `{name}` cannot twist about {}: {e:?}", AXES[*axis]))?;
    }
    // Every other hinge: stiff in both off-axis directions, so the loops can deform.
    for flexure in others {
        let Some(axis) = hinge_axis(model, flexure.angle).and_then(|a| perpendicular(&a)) else {
            continue;
        };
        let twist = Twist {
            axis,
            twist: spring(&flexure, "off_axis", &stiff),
            lateral: Some(spring(&flexure, "lateral", &stiff)),
            span: flexure.span,
        };
        add_twist(model, flexure.angle, twist)
            .map_err(|e| format!("flexure `{}` cannot be made compliant: {e:?}", flexure.name))?;
    }
    Ok(())
}
