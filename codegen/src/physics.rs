//! The physics of compliant parts, written once for the language and the analysis layer:
//! the named materials and the closed forms of flexure hinges and piezoelectric bimorphs.
//!
//! Consumes: constants in SI units (m, Pa, kg/m³, V), as `f64` (the `mech` CLI's numbers) or
//! as model expressions ([`crate::ir::Expr`], the front end's `material`, `flexure` and `actuator`
//! lowering, where any value may be a `param`). Produces: the same quantities in either form,
//! through [`Scalar`]. Both evaluate the arithmetic as written here, in this order (the
//! expressions are the trees the language has always built, so generated code is unchanged).
//!
//! Equation numbers refer to Doshi et al., "Model driven design for flexure-based
//! microrobots" (IROS 2015); the bimorph closed form is Wood, Steltz & Fearing (2005) as
//! refined by Jafferis, Smith & Wood (2015).

use std::ops::{Add, Div, Mul, Sub};

use crate::ir::{Expr, Function};
use crate::sym::Number;

/// The arithmetic of the closed forms: `f64`, or [`Expr`] trees built as written.
pub trait Scalar:
    Clone + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// A constant (for `Expr`, the exact decimal that `value` prints as).
    fn constant(value: f64) -> Self;
    fn powi(self, exponent: i32) -> Self;
    fn ln(self) -> Self;
}

impl Scalar for f64 {
    fn constant(value: f64) -> f64 {
        value
    }
    fn powi(self, exponent: i32) -> f64 {
        f64::powi(self, exponent)
    }
    fn ln(self) -> f64 {
        f64::ln(self)
    }
}

impl Scalar for Expr {
    fn constant(value: f64) -> Expr {
        // Through the shortest decimal, so 0.34 is the rational 17/50 as if written in a model.
        Expr::Number(Number::parse_decimal(&value.to_string()).unwrap_or(Number::Float(value)))
    }
    fn powi(self, exponent: i32) -> Expr {
        Expr::Pow(Box::new(self), Number::int(i64::from(exponent)))
    }
    fn ln(self) -> Expr {
        Expr::Call(Function::Ln, vec![self])
    }
}

/// An isotropic material. `loss_factor` is the loss tangent η of Eq. 5 (dimensionless), if
/// one has been measured for it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Short name, as accepted by [`Material::by_name`].
    pub name: &'static str,
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio ν (dimensionless).
    pub poisson_ratio: f64,
    /// Density ρ (kg/m³); NaN if unknown.
    pub density: f64,
    /// Loss tangent η (dimensionless); NaN if unknown.
    pub loss_factor: f64,
}

impl Material {
    /// Kapton HN polyimide film as measured in the seed paper (Sec. IV.B): E = 2.56 GPa from
    /// the pendulum experiment (2.3 % above the datasheet), η = 0.05 for uncastellated hinges;
    /// ν = 0.34 (seed Sec. V.A, from DuPont's datasheet) and ρ = 1.42 g/cm³ (DuPont Kapton HN
    /// datasheet). This is the value the seed's transmission model uses, and the language's
    /// built-in `kapton`.
    pub const KAPTON_HN: Material = Material {
        name: "kapton",
        youngs_modulus: 2.56e9,
        poisson_ratio: 0.34,
        density: 1420.0,
        loss_factor: 0.05,
    };

    /// Kapton HN with the datasheet modulus E = 2.5 GPa (DuPont; seed ref. \[21\]).
    pub const KAPTON_HN_DATASHEET: Material = Material {
        name: "kapton-datasheet",
        youngs_modulus: 2.5e9,
        ..Material::KAPTON_HN
    };

    /// Effective PZT-5H of HAMR-VI's bimorphs: E_p = 40 GPa (Jafferis, Smith & Wood 2015, as
    /// collected in the project's reference notes). ν, ρ and η are not given there.
    pub const PZT: Material = Material {
        name: "pzt",
        youngs_modulus: 40e9,
        poisson_ratio: f64::NAN,
        density: f64::NAN,
        loss_factor: f64::NAN,
    };

    /// High-modulus carbon-fibre composite core of HAMR-VI's bimorphs: E_cf = 340 GPa
    /// (same source as [`Material::PZT`]).
    pub const CARBON_FIBRE: Material = Material {
        name: "carbon-fibre",
        youngs_modulus: 340e9,
        poisson_ratio: f64::NAN,
        density: f64::NAN,
        loss_factor: f64::NAN,
    };

    /// Every named material.
    pub const ALL: [Material; 4] = [
        Material::KAPTON_HN,
        Material::KAPTON_HN_DATASHEET,
        Material::PZT,
        Material::CARBON_FIBRE,
    ];

    /// Looks a material up by name, case-insensitively; `kapton-hn` is an alias of `kapton`.
    pub fn by_name(name: &str) -> Option<Material> {
        let name = name.trim().to_ascii_lowercase();
        let name = match name.as_str() {
            "kapton-hn" | "kapton_hn" => "kapton",
            "carbon-fiber" => "carbon-fibre",
            other => other,
        };
        Material::ALL.into_iter().find(|m| m.name == name)
    }

    /// The names accepted by [`Material::by_name`], for error messages.
    pub fn names() -> Vec<&'static str> {
        Material::ALL.iter().map(|m| m.name).collect()
    }
}

/// Bending stiffness of a rectangular flexure, Eq. 2: `k = E w t³ / (12 l)` (N·m/rad).
/// For castellated hinges `l` is the effective length `l_eff`.
pub fn bending_stiffness<T: Scalar>(youngs_modulus: T, width: T, thickness: T, length: T) -> T {
    youngs_modulus * width * thickness.powi(3) / (T::constant(12.0) * length)
}

/// Equivalent viscous damping of a hysteretic hinge at angular frequency `omega`, Eq. 5:
/// `b = k η / ω` (N·m·s/rad).
pub fn hysteretic_damping<T: Scalar>(stiffness: T, loss_factor: T, omega: T) -> T {
    stiffness * loss_factor / omega
}

/// Ratio of twist to bending stiffness of a compliant flexure, Eq. 8: `2 / (1 + ν)`
/// (≈ 1.49 for Kapton, ν = 0.34).
pub fn twist_ratio<T: Scalar>(poisson_ratio: T) -> T {
    T::constant(2.0) / (T::constant(1.0) + poisson_ratio)
}

/// Within this distance of `w_r = 1` the taper's geometry factor is 0/0 in closed form; the
/// callers use its limit there ([`TaperedBimorph::untapered_geometry_factor`]).
pub const UNTAPERED_BAND: f64 = 0.01;

/// The closed form of a symmetric tapered bimorph: two PZT plates of thickness `t_p` on a
/// carbon-fibre core `t_cf`, active length `L`, rigid extension `l_ext`, nominal width
/// `w_nom`, width ratio `w_r` (base `w_r·w_nom`, tip `(2 − w_r)·w_nom`), effective
/// coefficients f31 (Pa·m/V) and moduli (Pa).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TaperedBimorph<T> {
    pub pzt_thickness: T,
    pub core_thickness: T,
    pub length: T,
    pub extension: T,
    pub nominal_width: T,
    pub width_ratio: T,
    /// f31 of the blocked force.
    pub f31_blocked: T,
    /// f31 of the free deflection.
    pub f31_free: T,
    pub pzt_modulus: T,
    pub core_modulus: T,
}

impl<T: Scalar> TaperedBimorph<T> {
    /// Extension ratio `l_r = l_ext / L`.
    pub fn extension_ratio(&self) -> T {
        self.extension.clone() / self.length.clone()
    }

    /// Flexural rigidity per unit width (N·m):
    /// `D = ⅓ E_p t_p (1.5 t_cf² + 3 t_cf t_p + 2 t_p²) + E_cf t_cf³ / 12`.
    pub fn rigidity_per_width(&self) -> T {
        let k = T::constant;
        let (tp, tcf) = (self.pzt_thickness.clone(), self.core_thickness.clone());
        let bracket = k(1.5) * tcf.clone().powi(2)
            + k(3.0) * tcf.clone() * tp.clone()
            + k(2.0) * tp.clone().powi(2);
        self.pzt_modulus.clone() * tp * bracket / k(3.0)
            + self.core_modulus.clone() * tcf.powi(3) / k(12.0)
    }

    /// Geometry factor GF of the taper and extension at width ratio `wr` (→ 1 for w_r → 1
    /// and l_r = 0): `8(1 − w_r)³(1 + 2l_r) / [−6(w_r − 1)(−3 + 4l_r(w_r − 1) + 2w_r)
    ///  + 3(−2 + 2l_r(w_r − 1) + w_r)² ln((2 − w_r)/w_r)]`; 0/0 at `w_r = 1`.
    pub fn geometry_factor_at(&self, wr: T) -> T {
        let k = T::constant;
        let lr = self.extension_ratio();
        let numerator = k(8.0) * (k(1.0) - wr.clone()).powi(3) * (k(1.0) + k(2.0) * lr.clone());
        let denominator = k(-6.0)
            * (wr.clone() - k(1.0))
            * (k(-3.0) + k(4.0) * lr.clone() * (wr.clone() - k(1.0)) + k(2.0) * wr.clone())
            + k(3.0)
                * (k(-2.0) + k(2.0) * lr * (wr.clone() - k(1.0)) + wr.clone()).powi(2)
                * ((k(2.0) - wr.clone()) / wr).ln();
        numerator / denominator
    }

    /// The limit of [`geometry_factor_at`](Self::geometry_factor_at) at `w_r = 1`:
    /// `4(1 + 2l_r) / (3(1 + 2l_r)² + 1)`.
    pub fn untapered_geometry_factor(&self) -> T {
        let k = T::constant;
        let a = k(1.0) + k(2.0) * self.extension_ratio();
        k(4.0) * a.clone() / (k(3.0) * a.powi(2) + k(1.0))
    }

    /// Free deflection per volt of drive amplitude (m/V):
    /// `δ_f/V = ¼ (1 + 2l_r) f31 (t_p + t_cf) L² / D` (the field V/t_p times t_p).
    pub fn free_deflection_per_volt(&self) -> T {
        let k = T::constant;
        k(0.25)
            * (k(1.0) + k(2.0) * self.extension_ratio())
            * self.f31_free.clone()
            * (self.pzt_thickness.clone() + self.core_thickness.clone())
            * self.length.clone().powi(2)
            / self.rigidity_per_width()
    }

    /// Blocked force per volt of drive amplitude (N/V), given the geometry factor:
    /// `F_b/V = ¾ f31 w_nom (t_p + t_cf) GF / L`.
    pub fn blocked_force_per_volt(&self, geometry_factor: T) -> T {
        T::constant(0.75)
            * self.f31_blocked.clone()
            * self.nominal_width.clone()
            * (self.pzt_thickness.clone() + self.core_thickness.clone())
            * geometry_factor
            / self.length.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expression_constants_are_the_decimals_as_written() {
        for (value, text) in [
            (0.34, "0.34"),
            (2.56e9, "2.56e9"),
            (-6.0, "-6"),
            (0.25, "0.25"),
        ] {
            assert_eq!(
                Expr::constant(value),
                Expr::Number(Number::parse_decimal(text).unwrap())
            );
        }
    }

    #[test]
    fn kapton_is_the_measured_kapton_hn() {
        let kapton = Material::by_name("Kapton-HN").unwrap();
        assert_eq!(kapton, Material::KAPTON_HN);
        assert_eq!(
            bending_stiffness(2.56e9, 1e-3, 25e-6, 66e-6),
            2.56e9 * 1e-3 * 25e-6f64.powi(3) / (12.0 * 66e-6)
        );
        assert_eq!(twist_ratio(kapton.poisson_ratio), 2.0 / 1.34);
    }
}
