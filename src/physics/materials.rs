//! Named materials with their elastic constants, in SI units.
//!
//! Every constant is transcribed from a cited source (the seed paper or the datasheet
//! figures collected in the project's reference notes); callers override any field by
//! building the struct with `..Material::KAPTON_HN`.

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
    /// datasheet). This is the value the seed's transmission model uses.
    pub const KAPTON_HN: Material = Material {
        name: "kapton",
        youngs_modulus: 2.56e9,
        poisson_ratio: 0.34,
        density: 1420.0,
        loss_factor: 0.05,
    };

    /// Kapton HN with the datasheet modulus E = 2.5 GPa (DuPont; seed ref. [21]).
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
