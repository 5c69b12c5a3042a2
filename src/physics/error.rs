//! Why a flexure, actuator or bimorph is not physical: each constant out of its range, with
//! the value given.
//!
//! Consumes: nothing. Produces: [`Invalid`], whose `Display` is the message users read.

use std::fmt;

#[derive(Debug, Clone, PartialEq)]
pub enum Invalid {
    /// `{part} {what}` must be positive and finite.
    NotPositive {
        part: &'static str,
        what: &'static str,
        value: f64,
    },
    /// `{part} {what}` must be finite and ≥ 0.
    Negative {
        part: &'static str,
        what: &'static str,
        value: f64,
    },
    /// An actuator's mass, when known, must be positive.
    ActuatorMass(f64),
    /// A bimorph's width ratio must lie in (0, 2).
    WidthRatio(f64),
    /// Poisson's ratio must lie in (−1, 0.5].
    PoissonRatio(f64),
    /// A castellated hinge needs 0 ≤ l_c ≤ l.
    Castellation {
        length: f64,
        castellation_length: f64,
    },
    /// A castellated hinge's effective length must lie in [l − l_c, l] (seed Sec. IV).
    EffectiveLength {
        effective_length: f64,
        lower: f64,
        length: f64,
    },
}

impl fmt::Display for Invalid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Invalid::NotPositive { part, what, value } => {
                write!(f, "{part} {what} must be positive and finite, got {value}")
            }
            Invalid::Negative { part, what, value } => {
                write!(f, "{part} {what} must be finite and ≥ 0, got {value}")
            }
            Invalid::ActuatorMass(mass) => write!(f, "actuator mass must be positive, got {mass}"),
            Invalid::WidthRatio(ratio) => write!(
                f,
                "bimorph width ratio must lie in (0, 2) (the tip width is (2 − w_r)·w_nom), got {ratio}"
            ),
            Invalid::PoissonRatio(nu) => write!(f, "Poisson's ratio must lie in (−1, 0.5], got {nu}"),
            Invalid::Castellation {
                length,
                castellation_length,
            } => write!(
                f,
                "castellated hinge: need 0 ≤ l_c ≤ l, got l = {length} m, l_c = {castellation_length} m"
            ),
            Invalid::EffectiveLength {
                effective_length,
                lower,
                length,
            } => write!(
                f,
                "castellated hinge: the effective length {effective_length} m lies outside \
                 [l − l_c, l] = [{lower}, {length}] m (seed Sec. IV)"
            ),
        }
    }
}

impl std::error::Error for Invalid {}

/// `Ok` if `value` is positive and finite.
pub(crate) fn require_positive(
    part: &'static str,
    what: &'static str,
    value: f64,
) -> Result<(), Invalid> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(Invalid::NotPositive { part, what, value })
    }
}

/// `Ok` if `value` is finite and ≥ 0.
pub(crate) fn require_non_negative(
    part: &'static str,
    what: &'static str,
    value: f64,
) -> Result<(), Invalid> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(Invalid::Negative { part, what, value })
    }
}
