//! Model-form extensions of `mech diagnose`: physics the base model leaves out, added by
//! codegen's IR transforms ([`hinge`], [`actuator`]), then re-derived and taped for one
//! candidate.
//!
//! Consumes: a diagnosis experiment's model spec and an [`Extension`]. Produces: a [`Leg`]
//! of the extended model, whose new parameters come after the base model's (so the base
//! parameters keep their indices).

use mech_codegen::ir;
use mech_codegen::ir::transform::{actuator, hinge, TransformError, AXES};
use mech_codegen::Compiled;

use super::error::Error;
use crate::experiments::leg::Leg;
use crate::session::ModelSpec;
use crate::session::Session;

/// A change of the model's form.
#[derive(Debug, Clone, PartialEq)]
pub enum Extension {
    /// These flexures twist about a length axis (0 = x, 1 = y, 2 = z in the hinge's frame),
    /// every other hinge compliant off its axis. New parameters: [`hinge::TWIST_FACTOR`],
    /// [`hinge::OFF_AXIS_COMPLIANCE`].
    Twist(Vec<(String, usize)>),
    /// These flexures (the hinges of one loop) twist together, each about one of the two
    /// coordinate axes ⊥ its bending axis, picked by a parameter per hinge
    /// ([`hinge::twist_choice`]): the model on which `mech diagnose` searches the axes before
    /// fitting the [`Extension::Twist`] it finds. New parameters as for
    /// [`Extension::Twist`], then the choices.
    TwistChoices(Vec<String>),
    /// A flexure's bending axis tilted by a small angle (fabrication; a rotation of the whole
    /// hinge about a coordinate axis of its frame perpendicular to it), pins and loop closures,
    /// every hinge compliant off its axis so the loops take up the misfit. New parameters:
    /// [`hinge::MISALIGNMENT`], [`hinge::OFF_AXIS_COMPLIANCE`].
    Misalignment { flexure: String, about: usize },
    /// The actuator along this slider coordinate sits on a compliant base (a spring in series
    /// with its own stiffness). New parameter: [`actuator::BASE_COMPLIANCE`].
    BaseCompliance(String),
    /// The actuator along this slider coordinate is stiffer or softer than written, its
    /// blocked force as written. New parameter: [`actuator::STIFFNESS_FACTOR`].
    ActuatorStiffness(String),
    /// The actuator along this slider coordinate pushes harder or weaker than written, its
    /// stiffness as written. New parameter: [`actuator::FORCE_FACTOR`].
    ActuatorForce(String),
    /// A mass rides on the tip of the actuator along this slider coordinate. New parameter:
    /// [`actuator::TIP_MASS`].
    TipMass(String),
    /// Every actuator's tip offset by the same length along its slider at zero voltage (an
    /// assembly preload, the seed's 50 µm in −y). New parameter: [`actuator::TIP_PRELOAD`].
    Preload,
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
            Extension::TwistChoices(hinges) => hinges.join(", "),
            Extension::Misalignment { flexure, about } => {
                format!("{flexure} tilted about {}", AXES[*about])
            }
            Extension::BaseCompliance(slider)
            | Extension::ActuatorStiffness(slider)
            | Extension::ActuatorForce(slider)
            | Extension::TipMass(slider) => {
                format!("actuator along {slider}")
            }
            Extension::Preload => "every actuator".into(),
        }
    }
}

/// Opens `spec`'s model with `extension` applied.
pub fn open_leg(spec: &ModelSpec, extension: &Extension) -> Result<Leg, Error> {
    let base = Compiled::from_path(&spec.path).map_err(|errors| Error::Compile {
        model: spec.path.clone(),
        errors,
    })?;
    extend_leg(&base, spec, extension)
}

/// `base` (`spec`'s model, compiled once) as it is, without reading the text again.
pub fn base_leg(base: &Compiled, spec: &ModelSpec) -> Result<Leg, Error> {
    let session = Session::from_compiled(base.clone(), &spec.set, &[])
        .map_err(|error| Error::leg(error.into()))?;
    Leg::from_session(session, spec, &[]).map_err(Error::leg)
}

/// `base` (`spec`'s model, compiled once) with `extension` applied to a copy of its IR,
/// re-derived without reading the text again.
pub fn extend_leg(base: &Compiled, spec: &ModelSpec, extension: &Extension) -> Result<Leg, Error> {
    let path = || spec.path.clone();
    let mut model = base.model.clone();
    apply(&mut model, extension).map_err(|error| Error::Transform {
        model: path(),
        error,
    })?;
    let session =
        Session::from_compiled(Compiled::from_model(model), &spec.set, &[]).map_err(|error| {
            Error::ExtendedSession {
                model: path(),
                location: extension.location(),
                error: Box::new(error),
            }
        })?;
    let mut leg = Leg::from_session(session, spec, &[]).map_err(Error::leg)?;
    // The base model's rest is a start its extension's Newton reaches (`Leg::rest_start`).
    let base = base_leg(base, spec)?;
    if let Ok(rest) = base.equilibrium(&base.q0, &base.inputs(0.0, 0.0), &[]) {
        leg.start_rest_at(&base, &rest.q);
    }
    Ok(leg)
}

/// Transforms `model` in place by the IR transform of [`hinge`] or [`actuator`]; the new
/// parameters are appended in the order the variant names them.
pub fn apply(model: &mut ir::Model, extension: &Extension) -> Result<(), TransformError> {
    match extension {
        Extension::Twist(hinges) => hinge::twist(model, hinges),
        Extension::TwistChoices(hinges) => hinge::twist_choices(model, hinges).map(|_| ()),
        Extension::Misalignment { flexure, about } => hinge::misalign(model, flexure, *about),
        Extension::BaseCompliance(slider) => actuator::base_compliance(model, slider),
        Extension::ActuatorStiffness(slider) => actuator::stiffness_factor(model, slider),
        Extension::ActuatorForce(slider) => actuator::force_factor(model, slider),
        Extension::TipMass(slider) => actuator::tip_mass(model, slider),
        Extension::Preload => actuator::preload(model),
    }
}
