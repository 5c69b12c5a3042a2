//! Piezoelectric bending actuators (seed Sec. II–III): a force source `F_b(V)`, linear in
//! the drive voltage, in parallel with a series stiffness `k_a = F_b / δ_f`, so that the tip
//! force at deflection δ is `F = F_b(V) − k_a δ`. The pair `(F_b, δ_f)` is given at a rated
//! voltage, or computed from a symmetric tapered bimorph's geometry by the closed form of
//! Wood, Steltz & Fearing (2005) with the refinements of Jafferis, Smith & Wood (2015).
//!
//! Units: N, m, V, kg; energy density in J/kg. The bimorph closed form is
//! [`mech_codegen::physics::TaperedBimorph`], shared with the language's `actuator` lowering.

use super::error::{require_non_negative, require_positive, Invalid};
use mech_codegen::physics::{Material, TaperedBimorph, UNTAPERED_BAND};

/// Energy density of Eq. 1: `D_u = δ_f F_b / (2 m_a)` (J/kg): the area under the linear
/// force–deflection curve per unit actuator mass (a quarter of the convention of the
/// earlier papers, see seed Sec. III).
pub fn energy_density(free_deflection: f64, blocked_force: f64, mass: f64) -> f64 {
    free_deflection * blocked_force / (2.0 * mass)
}

/// A linear actuator model: blocked force and free deflection at `rated_voltage`, both
/// proportional to the voltage (seed Sec. III: linear in 50–225 V).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Actuator {
    /// Blocked force F_b at the rated voltage (N, peak one-way).
    pub blocked_force: f64,
    /// Free deflection δ_f at the rated voltage (m, peak one-way).
    pub free_deflection: f64,
    /// Voltage at which `blocked_force` and `free_deflection` hold (V).
    pub rated_voltage: f64,
    /// Actuator mass m_a (kg); NaN if unknown (then `energy_density` is NaN).
    pub mass: f64,
}

impl Actuator {
    /// Series stiffness `k_a = F_b / δ_f` (N/m), independent of voltage.
    pub fn stiffness(&self) -> f64 {
        self.blocked_force / self.free_deflection
    }

    /// Blocked force at drive voltage `voltage` (N): `F_b · V / V_rated`.
    pub fn blocked_force_at(&self, voltage: f64) -> f64 {
        self.blocked_force * voltage / self.rated_voltage
    }

    /// Free deflection at drive voltage `voltage` (m).
    pub fn free_deflection_at(&self, voltage: f64) -> f64 {
        self.free_deflection * voltage / self.rated_voltage
    }

    /// Tip force at voltage `voltage` and tip deflection `deflection`: `F_b(V) − k_a δ` (N).
    pub fn tip_force(&self, voltage: f64, deflection: f64) -> f64 {
        self.blocked_force_at(voltage) - self.stiffness() * deflection
    }

    /// Energy density at the rated voltage, Eq. 1 (J/kg).
    pub fn energy_density(&self) -> f64 {
        energy_density(self.free_deflection, self.blocked_force, self.mass)
    }

    /// The same actuator re-rated at `voltage`.
    pub fn at_voltage(&self, voltage: f64) -> Actuator {
        Actuator {
            blocked_force: self.blocked_force_at(voltage),
            free_deflection: self.free_deflection_at(voltage),
            rated_voltage: voltage,
            mass: self.mass,
        }
    }

    /// Checks that the constants are finite and positive (the mass may be NaN: unknown).
    pub fn validate(&self) -> Result<(), Invalid> {
        for (what, value) in [
            ("blocked force", self.blocked_force),
            ("free deflection", self.free_deflection),
            ("rated voltage", self.rated_voltage),
        ] {
            require_positive("actuator", what, value)?;
        }
        if !(self.mass.is_nan() || (self.mass.is_finite() && self.mass > 0.0)) {
            return Err(Invalid::ActuatorMass(self.mass));
        }
        Ok(())
    }
}

/// Effective material coefficients of the bimorph closed form.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PiezoCoefficients {
    /// Effective f31 = d31·E_p for the blocked force (Pa·m/V).
    pub f31_blocked: f64,
    /// Effective f31 for the free deflection (Pa·m/V).
    pub f31_free: f64,
    /// PZT modulus E_p (Pa).
    pub pzt_modulus: f64,
    /// Core (carbon fibre) modulus E_cf (Pa).
    pub core_modulus: f64,
}

impl PiezoCoefficients {
    /// Coefficients used for HAMR-VI's actuators (Jafferis, Smith & Wood 2015, as collected in
    /// the project's reference notes): f31 = 24 Pa·m/V (blocked force), 32 Pa·m/V (free
    /// deflection), E_p = 40 GPa, E_cf = 340 GPa.
    pub const HAMR_VI: PiezoCoefficients = PiezoCoefficients {
        f31_blocked: 24.0,
        f31_free: 32.0,
        pzt_modulus: Material::PZT.youngs_modulus,
        core_modulus: Material::CARBON_FIBRE.youngs_modulus,
    };
}

/// A symmetric tapered bimorph: two PZT plates of thickness `t_p` on a carbon-fibre core
/// `t_cf`, active length `L`, rigid extension `l_ext`, nominal width `w_nom`, width ratio
/// `w_r` (base `w_r·w_nom`, tip `(2 − w_r)·w_nom`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bimorph {
    /// PZT plate thickness t_p (m).
    pub pzt_thickness: f64,
    /// Core thickness t_cf (m).
    pub core_thickness: f64,
    /// Active (PZT) length L (m).
    pub length: f64,
    /// Rigid extension length l_ext (m).
    pub extension_length: f64,
    /// Nominal width w_nom (m).
    pub nominal_width: f64,
    /// Width ratio w_r (0 < w_r < 2).
    pub width_ratio: f64,
    /// Material coefficients.
    pub coefficients: PiezoCoefficients,
}

impl Bimorph {
    /// Seed Table I, "new geometry": t_p = 135 µm, t_cf = 55 µm, L = 9.2 mm, l_ext = 1 mm,
    /// w_nom = 3.5 mm, w_r = 1.5, with the HAMR-VI coefficients.
    pub const SEED_NEW_GEOMETRY: Bimorph = Bimorph {
        pzt_thickness: 135e-6,
        core_thickness: 55e-6,
        length: 9.2e-3,
        extension_length: 1.0e-3,
        nominal_width: 3.5e-3,
        width_ratio: 1.5,
        coefficients: PiezoCoefficients::HAMR_VI,
    };

    /// Seed Table I, "old geometry": t_p = 135 µm, t_cf = 110 µm, L = 8.8 mm, l_ext = 0.8 mm,
    /// w_nom = 4.2 mm, w_r = 1.5, with the HAMR-VI coefficients.
    pub const SEED_OLD_GEOMETRY: Bimorph = Bimorph {
        pzt_thickness: 135e-6,
        core_thickness: 110e-6,
        length: 8.8e-3,
        extension_length: 0.8e-3,
        nominal_width: 4.2e-3,
        width_ratio: 1.5,
        coefficients: PiezoCoefficients::HAMR_VI,
    };

    /// Checks that the geometry is positive and finite and `0 < w_r < 2`.
    pub fn validate(&self) -> Result<(), Invalid> {
        let c = &self.coefficients;
        for (what, value) in [
            ("PZT thickness", self.pzt_thickness),
            ("core thickness", self.core_thickness),
            ("length", self.length),
            ("nominal width", self.nominal_width),
            ("f31 (blocked force)", c.f31_blocked),
            ("f31 (free deflection)", c.f31_free),
            ("PZT modulus", c.pzt_modulus),
            ("core modulus", c.core_modulus),
        ] {
            require_positive("bimorph", what, value)?;
        }
        require_non_negative("bimorph", "extension length", self.extension_length)?;
        if !(self.width_ratio > 0.0 && self.width_ratio < 2.0) {
            return Err(Invalid::WidthRatio(self.width_ratio));
        }
        Ok(())
    }

    /// The closed form of this geometry.
    fn closed_form(&self) -> TaperedBimorph<f64> {
        let c = &self.coefficients;
        TaperedBimorph {
            pzt_thickness: self.pzt_thickness,
            core_thickness: self.core_thickness,
            length: self.length,
            extension: self.extension_length,
            nominal_width: self.nominal_width,
            width_ratio: self.width_ratio,
            f31_blocked: c.f31_blocked,
            f31_free: c.f31_free,
            pzt_modulus: c.pzt_modulus,
            core_modulus: c.core_modulus,
        }
    }

    /// Extension ratio l_r = l_ext / L.
    pub fn extension_ratio(&self) -> f64 {
        self.closed_form().extension_ratio()
    }

    /// Flexural rigidity per unit width (N·m):
    /// `D = ⅓ E_p t_p (1.5 t_cf² + 3 t_cf t_p + 2 t_p²) + E_cf t_cf³ / 12`.
    pub fn rigidity_per_width(&self) -> f64 {
        self.closed_form().rigidity_per_width()
    }

    /// Geometry factor GF of the taper and extension (→ 1 for w_r → 1 and l_r = 0), see
    /// [`TaperedBimorph::geometry_factor_at`].
    ///
    /// Near `w_r = 1` the expression is 0/0; its limit there is
    /// `4(1 + 2l_r) / (3(1 + 2l_r)² + 1)`, and within 0.01 of 1 the value is interpolated
    /// linearly between that limit and the formula at `1 ± 0.01` (error below 1e-5). (The
    /// language, which cannot interpolate an expression, takes the limit in that band.)
    pub fn geometry_factor(&self) -> f64 {
        let form = self.closed_form();
        let wr = self.width_ratio;
        let e = wr - 1.0;
        if e.abs() >= UNTAPERED_BAND {
            return form.geometry_factor_at(wr);
        }
        let limit = form.untapered_geometry_factor();
        let edge = form.geometry_factor_at(1.0 + UNTAPERED_BAND.copysign(e));
        limit + (edge - limit) * e.abs() / UNTAPERED_BAND
    }

    /// Free deflection at drive amplitude `voltage` (m):
    /// `δ_f = ¼ (1 + 2l_r) f31 (V/t_p) t_p (t_p + t_cf) L² / D`.
    pub fn free_deflection(&self, voltage: f64) -> f64 {
        self.closed_form().free_deflection_per_volt() * voltage
    }

    /// Blocked force at drive amplitude `voltage` (N):
    /// `F_b = ¾ f31 V w_nom (t_p + t_cf) GF / L`.
    pub fn blocked_force(&self, voltage: f64) -> f64 {
        self.closed_form()
            .blocked_force_per_volt(self.geometry_factor())
            * voltage
    }

    /// The linear actuator model at `voltage`, with mass `mass` (kg, NaN if unknown).
    pub fn actuator(&self, voltage: f64, mass: f64) -> Actuator {
        Actuator {
            blocked_force: self.blocked_force(voltage),
            free_deflection: self.free_deflection(voltage),
            rated_voltage: voltage,
            mass,
        }
    }
}

/// One row of the seed's Table II ("Summary of actuator performance metrics"), peak one-way
/// values at 225 V.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TableIIRow {
    /// Actuator as named in the table.
    pub name: &'static str,
    /// Mass m_a (kg).
    pub mass: f64,
    /// Free deflection δ_f (m).
    pub free_deflection: f64,
    /// Blocked force F_b (N).
    pub blocked_force: f64,
    /// Energy density as printed (J/kg).
    pub energy_density: f64,
}

/// The seed's Table II, transcribed (mg, µm, mN in the paper; SI here).
pub const SEED_TABLE_II: [TableIIRow; 5] = [
    TableIIRow {
        name: "PNP from [13]",
        mass: 96e-6,
        free_deflection: 200e-6,
        blocked_force: 0.200,
        energy_density: 0.21,
    },
    TableIIRow {
        name: "PNP 'a'",
        mass: 100e-6,
        free_deflection: 234e-6,
        blocked_force: 0.259,
        energy_density: 0.32,
    },
    TableIIRow {
        name: "PS 'a'",
        mass: 100e-6,
        free_deflection: 247e-6,
        blocked_force: 0.270,
        energy_density: 0.35,
    },
    TableIIRow {
        name: "PS 'b'",
        mass: 109e-6,
        free_deflection: 219e-6,
        blocked_force: 0.500,
        energy_density: 0.5,
    },
    TableIIRow {
        name: "Model from [16]",
        mass: 109e-6,
        free_deflection: 184e-6,
        blocked_force: 0.549,
        energy_density: 0.46,
    },
];

/// Seed Table I, model values (from \[16\]) at 225 V: old geometry δ_f = 184 µm, F_b = 549 mN;
/// new geometry δ_f = 300 µm, F_b = 320 mN. Pairs `(δ_f m, F_b N)`.
pub const SEED_TABLE_I_MODEL: [(&str, f64, f64); 2] = [
    ("old geometry", 184e-6, 0.549),
    ("new geometry", 300e-6, 0.320),
];

/// Drive amplitude of the seed's actuator measurements (V): 225 V.
pub const SEED_DRIVE_VOLTAGE: f64 = 225.0;
