//! Physical plausibility: the rules a body's mass and inertia and an element's dimensions
//! obey, kept in the model with the expressions they constrain, so that they are checked at
//! the parameters' defaults when the model is read (`E05xx`) and again whenever a parameter
//! changes at run time (`mech --set`, Python's `Model.set`).
//!
//! Consumes: [`Requirement`]s recorded by `front::lower`, parameter values (SI).
//! Produces: the [`Implausible`] values, each a requirement and how it is violated.

use std::fmt;

use super::{Expr, Inertia};
use crate::diag::Span;

/// Relative slack of the inertia checks, against the largest principal moment: measured
/// tensors are written to 4–5 digits, and a thin plate meets `I1 + I2 = I3` exactly.
const INERTIA_SLACK: f64 = 1e-6;

/// A rule on values of one declaration, with the place it was written.
#[derive(Clone, Debug, PartialEq)]
pub struct Requirement {
    /// `body`, `flexure`, `actuator`.
    pub kind: &'static str,
    /// The declaration's name.
    pub name: String,
    pub rule: Rule,
    /// The value's text (the field's right-hand side).
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Rule {
    /// A body's mass: zero (a massless link) or positive.
    Mass(Expr),
    /// A body's inertia tensor about its centre of mass: positive semidefinite, and its
    /// principal moments obey the triangle inequality `I1 + I2 ≥ I3` (every real mass
    /// distribution does; zero for a massless body or a point mass).
    Inertia(Inertia),
    /// A length or frequency of an element that must be greater than zero (`width`, …);
    /// `unit` is its SI unit, for messages.
    Positive {
        field: &'static str,
        unit: &'static str,
        value: Expr,
    },
    /// A contact's property (`kind` is `contact`): greater than zero where `positive` (its
    /// stiffness and transition speed: the friction law divides by `√(|v_t|² + v_s²)`), zero
    /// or greater otherwise (its radius, damping and friction coefficient).
    ContactProperty {
        field: &'static str,
        unit: &'static str,
        value: Expr,
        positive: bool,
    },
}

/// How a requirement is violated, with the values found.
#[derive(Clone, Debug, PartialEq)]
pub enum Violation {
    NegativeMass(f64),
    /// Principal moments, ascending; the first is negative.
    NegativeMoment([f64; 3]),
    /// Principal moments, ascending; `I1 + I2 < I3`.
    Triangle([f64; 3]),
    NotPositive {
        field: &'static str,
        unit: &'static str,
        value: f64,
    },
    /// A contact's property below its range (see [`Rule::ContactProperty`]).
    ContactOutOfRange {
        field: &'static str,
        unit: &'static str,
        value: f64,
        positive: bool,
    },
}

/// A requirement that does not hold.
#[derive(Clone, Debug, PartialEq)]
pub struct Implausible {
    pub requirement: Requirement,
    pub violation: Violation,
}

impl Requirement {
    /// Checks the rule with the parameters at `params` (SI, by parameter index). Values that
    /// cannot be evaluated (not finite) are left to the errors that report them.
    pub fn check(&self, params: &[f64]) -> Result<(), Violation> {
        let value = |e: &Expr| e.evaluate(params).filter(|v| v.is_finite());
        match &self.rule {
            Rule::Mass(mass) => match value(mass) {
                Some(m) if m < 0.0 => Err(Violation::NegativeMass(m)),
                _ => Ok(()),
            },
            Rule::Positive {
                field,
                unit,
                value: e,
            } => match value(e) {
                Some(v) if v <= 0.0 => Err(Violation::NotPositive {
                    field,
                    unit,
                    value: v,
                }),
                _ => Ok(()),
            },
            &Rule::ContactProperty {
                field,
                unit,
                value: ref e,
                positive,
            } => match value(e) {
                Some(v) if v < 0.0 || (positive && v == 0.0) => Err(Violation::ContactOutOfRange {
                    field,
                    unit,
                    value: v,
                    positive,
                }),
                _ => Ok(()),
            },
            Rule::Inertia(inertia) => {
                let mut values = [0.0; 6];
                for (slot, entry) in values.iter_mut().zip(inertia.entries()) {
                    let Some(v) = value(entry) else {
                        return Ok(());
                    };
                    *slot = v;
                }
                let [xx, yy, zz, xy, yz, zx] = values;
                let moments = symmetric_eigenvalues([[xx, xy, zx], [xy, yy, yz], [zx, yz, zz]]);
                let slack = INERTIA_SLACK * moments.iter().fold(0.0_f64, |a, m| a.max(m.abs()));
                if moments[0] < -slack {
                    Err(Violation::NegativeMoment(moments))
                } else if moments[0] + moments[1] < moments[2] - slack {
                    Err(Violation::Triangle(moments))
                } else {
                    Ok(())
                }
            }
        }
    }
}

impl Violation {
    /// The diagnostic code of this kind of violation.
    pub fn code(&self) -> &'static str {
        match self {
            Violation::NegativeMass(_) => "E0501",
            Violation::NegativeMoment(_) => "E0502",
            Violation::Triangle(_) => "E0503",
            Violation::NotPositive { .. } => "E0504",
            Violation::ContactOutOfRange { .. } => "E0506",
        }
    }

    /// What is wrong, after the declaration (`body `arm` …`).
    pub fn message(&self) -> String {
        match self {
            Violation::NegativeMass(_) => "has a negative mass".to_string(),
            Violation::NegativeMoment(_) => {
                "has an inertia tensor with a negative principal moment".to_string()
            }
            Violation::Triangle(_) => {
                "has principal moments of inertia that break the triangle inequality".to_string()
            }
            Violation::NotPositive { field, .. }
            | Violation::ContactOutOfRange {
                field,
                positive: true,
                ..
            } => format!("has a `{field}` that is not positive"),
            Violation::ContactOutOfRange { field, .. } => format!("has a negative `{field}`"),
        }
    }

    /// The values found (SI).
    pub fn found(&self) -> String {
        match self {
            Violation::NegativeMass(m) => format!("mass = {m} kg"),
            Violation::NegativeMoment([a, b, c]) | Violation::Triangle([a, b, c]) => {
                format!("principal moments {a:.3e}, {b:.3e}, {c:.3e} kg*m^2")
            }
            Violation::NotPositive { field, unit, value }
            | Violation::ContactOutOfRange {
                field, unit, value, ..
            } => format!("{field} = {value} {unit}").trim_end().to_string(),
        }
    }

    /// What a plausible value looks like.
    pub fn help(&self) -> &'static str {
        match self {
            Violation::NegativeMass(_) => {
                "a mass is zero (a massless link) or positive, e.g. `mass = 10 g;`"
            }
            Violation::NegativeMoment(_) => {
                "an inertia tensor has no negative principal moment; check the moments and the signs of the products of inertia (tensor convention: Ixy = -∫ x y dm)"
            }
            Violation::Triangle(_) => {
                "every mass distribution has I1 + I2 ≥ I3 for its principal moments; a thin rod along x has [0, I, I], a planar plate in x-y [Ixx, Iyy, Ixx + Iyy]"
            }
            Violation::NotPositive { .. } => "lengths, thicknesses and frequencies are greater than zero",
            Violation::ContactOutOfRange { .. } => {
                "a contact's `stiffness`, `reference_depth`, `transition_speed` and `exponent` are greater than zero; its `radius`, `damping` and `friction` are zero or greater"
            }
        }
    }
}

impl fmt::Display for Implausible {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Requirement { kind, name, .. } = &self.requirement;
        let v = &self.violation;
        write!(
            f,
            "{kind} `{name}` {} ({}): {}",
            v.message(),
            v.found(),
            v.help()
        )
    }
}

/// Eigenvalues of a symmetric 3×3 matrix, ascending (the trigonometric closed form).
fn symmetric_eigenvalues(a: [[f64; 3]; 3]) -> [f64; 3] {
    let off = a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2);
    let mut eig = if off == 0.0 {
        [a[0][0], a[1][1], a[2][2]]
    } else {
        let q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
        let p2 = (a[0][0] - q).powi(2) + (a[1][1] - q).powi(2) + (a[2][2] - q).powi(2) + 2.0 * off;
        let p = (p2 / 6.0).sqrt();
        let b = |i: usize, j: usize| (a[i][j] - if i == j { q } else { 0.0 }) / p;
        let det = b(0, 0) * (b(1, 1) * b(2, 2) - b(1, 2) * b(2, 1))
            - b(0, 1) * (b(1, 0) * b(2, 2) - b(1, 2) * b(2, 0))
            + b(0, 2) * (b(1, 0) * b(2, 1) - b(1, 1) * b(2, 0));
        let phi = (det / 2.0).clamp(-1.0, 1.0).acos() / 3.0;
        let largest = q + 2.0 * p * phi.cos();
        let smallest = q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos();
        [smallest, 3.0 * q - largest - smallest, largest]
    };
    eig.sort_by(f64::total_cmp);
    eig
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sym::Number;

    fn inertia(values: [f64; 6]) -> Requirement {
        let e = |v: f64| Expr::Number(Number::Float(v));
        let [xx, yy, zz, xy, yz, zx] = values.map(e);
        Requirement {
            kind: "body",
            name: "b".to_string(),
            rule: Rule::Inertia(Inertia {
                xx,
                yy,
                zz,
                xy,
                yz,
                zx,
            }),
            span: Span::default(),
        }
    }

    #[test]
    fn eigenvalues_of_a_full_tensor_match_its_invariants() {
        let a = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.25], [0.5, 0.25, 2.0]];
        let [l1, l2, l3] = symmetric_eigenvalues(a);
        let trace = 9.0;
        let det = 4.0 * (6.0 - 0.0625) - 1.0 * (2.0 - 0.125) + 0.5 * (0.25 - 1.5);
        assert!((l1 + l2 + l3 - trace).abs() < 1e-12);
        assert!((l1 * l2 * l3 - det).abs() < 1e-12);
        assert!(l1 <= l2 && l2 <= l3);
    }

    #[test]
    fn inertia_rules() {
        // A point mass, a thin rod along x, a plate: plausible.
        for ok in [
            [0.0; 6],
            [0.0, 1.0, 1.0, 0.0, 0.0, 0.0],
            [1.0, 2.0, 3.0, 0.0, 0.0, 0.0],
        ] {
            assert_eq!(inertia(ok).check(&[]), Ok(()), "{ok:?}");
        }
        // A planar-only moment: I1 + I2 = 0 < I3.
        assert!(matches!(
            inertia([0.0, 0.0, 1.0, 0.0, 0.0, 0.0]).check(&[]),
            Err(Violation::Triangle(_))
        ));
        // Diagonal fine, products too large: eigenvalues 3 ± 4 and 3, one negative.
        assert!(matches!(
            inertia([3.0, 3.0, 3.0, 4.0, 0.0, 0.0]).check(&[]),
            Err(Violation::NegativeMoment(m)) if (m[0] + 1.0).abs() < 1e-12
        ));
        // Products that only tilt the axes: eigenvalues 3 ± 1 and 3, plausible.
        assert_eq!(inertia([3.0, 3.0, 3.0, 1.0, 0.0, 0.0]).check(&[]), Ok(()));
    }
}
