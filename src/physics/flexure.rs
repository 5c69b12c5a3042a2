//! Kapton flexure hinges modelled as small-length flexural pivots in pure bending
//! (seed Sec. IV): a torsional spring `k` (Eq. 2), hysteretic damping `b = kη/ω` (Eq. 5) or
//! the complex stiffness `k(1 + iη)`, and the twist-to-bending stiffness ratio (Eq. 8).
//!
//! Units: lengths in m, moduli in Pa, stiffness in N·m/rad, damping in N·m·s/rad, angular
//! frequencies in rad/s.
//!
//! **Time-domain damping convention.** Hysteretic (structural) damping dissipates per cycle
//! an energy independent of frequency; a viscous damper matches it only at one frequency. In
//! the time domain [`Flexure::damping`] takes that reference angular frequency `ω_ref`; the
//! seed uses the oscillation frequency, `ω = ω_d` of its pendulum (Eq. 5), and its
//! transmission model a drive frequency. In the frequency domain use
//! [`Flexure::complex_stiffness`], which is exact at every frequency.

use super::error::{require_non_negative, require_positive, Invalid};
use nalgebra::Complex;

use super::materials::Material;

// Eq. 2 `k = E w t³ / (12 l)`, Eq. 5 `b = k η / ω` and Eq. 8 `2 / (1 + ν)`, shared with the
// language's `flexure` lowering.
pub use mech_codegen::physics::{bending_stiffness, hysteretic_damping, twist_ratio};

/// Seed Sec. IV.B: HAMR's mirrored-castellated hinges are 25 µm thick (m).
pub const HAMR_HINGE_THICKNESS: f64 = 25e-6;
/// Seed Sec. IV.B: ... 120 µm long (m) ...
pub const HAMR_HINGE_LENGTH: f64 = 120e-6;
/// Seed Sec. IV.B: ... with 100 µm long castellations (m).
pub const HAMR_HINGE_CASTELLATION: f64 = 100e-6;
/// Seed Sec. IV.B: effective length of those hinges from the pendulum fit, 66 µm (m).
pub const HAMR_HINGE_EFFECTIVE_LENGTH: f64 = 66e-6;
/// Seed Sec. IV.B: loss factor η' of those hinges (at ~31 rad/s), 0.08.
pub const HAMR_HINGE_LOSS_FACTOR: f64 = 0.08;

/// One row of the seed's Table III ("Flexure values used in model").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TableIIIRow {
    /// Hinge name(s) as printed.
    pub hinge: &'static str,
    /// Width w (m).
    pub width: f64,
    /// Listed stiffness k_m (N·m/rad).
    pub stiffness: f64,
    /// Listed damping times frequency b_m·ω_d (N·m).
    pub damping_times_omega: f64,
}

/// The seed's Table III, transcribed (w in mm, k_m in µN·m/rad and b_m·ω_d in µN·m in the
/// paper; converted to SI here). The table says its values come from Eqs. 2 and 5 with
/// l_eff = 66 µm and η' = 0.08, yet they scatter by up to ±27 % around Eq. 2 (S2 and L2 share
/// w = 0.80 mm but list 35.0 and 31.9): they are reproduced as published, not adjusted.
pub const SEED_TABLE_III: [TableIIIRow; 7] = [
    TableIIIRow {
        hinge: "S1",
        width: 1.74e-3,
        stiffness: 88.4e-6,
        damping_times_omega: 6.8e-6,
    },
    TableIIIRow {
        hinge: "S2",
        width: 0.80e-3,
        stiffness: 35.0e-6,
        damping_times_omega: 3.2e-6,
    },
    TableIIIRow {
        hinge: "S3, FB3",
        width: 0.64e-3,
        stiffness: 33.3e-6,
        damping_times_omega: 2.5e-6,
    },
    TableIIIRow {
        hinge: "L1",
        width: 1.64e-3,
        stiffness: 89.8e-6,
        damping_times_omega: 6.8e-6,
    },
    TableIIIRow {
        hinge: "L2",
        width: 0.80e-3,
        stiffness: 31.9e-6,
        damping_times_omega: 2.7e-6,
    },
    TableIIIRow {
        hinge: "L3, FB1",
        width: 1.23e-3,
        stiffness: 65.4e-6,
        damping_times_omega: 5.2e-6,
    },
    TableIIIRow {
        hinge: "FB2",
        width: 2.00e-3,
        stiffness: 115.0e-6,
        damping_times_omega: 8.9e-6,
    },
];

/// The geometry class of a hinge (seed Fig. 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HingeKind {
    /// A plain rectangular flexure: Eq. 2 with its own length.
    Uncastellated,
    /// A (mirrored-)castellated hinge of nominal length `length` with castellations of length
    /// `castellation_length`; Eq. 2 holds with an effective length
    /// `l − l_c ≤ l_eff ≤ l` (seed Sec. IV).
    Castellated {
        /// Nominal flexure length l (m).
        length: f64,
        /// Castellation length l_c (m).
        castellation_length: f64,
    },
}

/// A flexure hinge: geometry, material and loss factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Flexure {
    /// Width w (m).
    pub width: f64,
    /// Film thickness t (m).
    pub thickness: f64,
    /// Length entering Eq. 2 (m): the length itself for uncastellated hinges, `l_eff` for
    /// castellated ones.
    pub effective_length: f64,
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio ν.
    pub poisson_ratio: f64,
    /// Loss factor η of Eq. 5.
    pub loss_factor: f64,
    /// Geometry class.
    pub kind: HingeKind,
}

impl Flexure {
    /// An uncastellated flexure of `material` (its E, ν and η).
    pub fn uncastellated(material: &Material, width: f64, thickness: f64, length: f64) -> Flexure {
        Flexure {
            width,
            thickness,
            effective_length: length,
            youngs_modulus: material.youngs_modulus,
            poisson_ratio: material.poisson_ratio,
            loss_factor: material.loss_factor,
            kind: HingeKind::Uncastellated,
        }
    }

    /// A castellated hinge with a known effective length; checks
    /// `l − l_c ≤ l_eff ≤ l` (seed Sec. IV) and returns an error otherwise.
    pub fn castellated(
        material: &Material,
        width: f64,
        thickness: f64,
        length: f64,
        castellation_length: f64,
        effective_length: f64,
        loss_factor: f64,
    ) -> Result<Flexure, Invalid> {
        let flexure = Flexure {
            width,
            thickness,
            effective_length,
            youngs_modulus: material.youngs_modulus,
            poisson_ratio: material.poisson_ratio,
            loss_factor,
            kind: HingeKind::Castellated {
                length,
                castellation_length,
            },
        };
        flexure.validate()?;
        Ok(flexure)
    }

    /// One of HAMR's mirrored-castellated Kapton hinges (seed Sec. IV.B and Table III):
    /// 25 µm thick, 120 µm long, 100 µm castellations, l_eff = 66 µm, E = 2.56 GPa, η' = 0.08.
    pub fn hamr_castellated(width: f64) -> Flexure {
        Flexure {
            width,
            thickness: HAMR_HINGE_THICKNESS,
            effective_length: HAMR_HINGE_EFFECTIVE_LENGTH,
            youngs_modulus: Material::KAPTON_HN.youngs_modulus,
            poisson_ratio: Material::KAPTON_HN.poisson_ratio,
            loss_factor: HAMR_HINGE_LOSS_FACTOR,
            kind: HingeKind::Castellated {
                length: HAMR_HINGE_LENGTH,
                castellation_length: HAMR_HINGE_CASTELLATION,
            },
        }
    }

    /// Checks that every dimension and constant is finite and positive (η ≥ 0, −1 < ν ≤ 0.5)
    /// and, for castellated hinges, that `l − l_c ≤ l_eff ≤ l`.
    pub fn validate(&self) -> Result<(), Invalid> {
        let positive = [
            ("width", self.width),
            ("thickness", self.thickness),
            ("length", self.effective_length),
            ("Young's modulus", self.youngs_modulus),
        ];
        for (what, value) in positive {
            require_positive("flexure", what, value)?;
        }
        require_non_negative("flexure", "loss factor", self.loss_factor)?;
        if !(self.poisson_ratio > -1.0 && self.poisson_ratio <= 0.5) {
            return Err(Invalid::PoissonRatio(self.poisson_ratio));
        }
        if let HingeKind::Castellated {
            length,
            castellation_length,
        } = self.kind
        {
            let l_eff = self.effective_length;
            let lower = length - castellation_length;
            // Allow for rounding of values given in µm.
            let slack = 1e-9 * length.abs();
            if !(length > 0.0 && castellation_length >= 0.0 && castellation_length <= length) {
                return Err(Invalid::Castellation {
                    length,
                    castellation_length,
                });
            }
            if l_eff < lower - slack || l_eff > length + slack {
                return Err(Invalid::EffectiveLength {
                    effective_length: l_eff,
                    lower,
                    length,
                });
            }
        }
        Ok(())
    }

    /// Bending stiffness k (N·m/rad), Eq. 2.
    pub fn stiffness(&self) -> f64 {
        bending_stiffness(
            self.youngs_modulus,
            self.width,
            self.thickness,
            self.effective_length,
        )
    }

    /// Equivalent viscous damping at the reference angular frequency `omega` (rad/s), Eq. 5:
    /// `b = k η / ω` (N·m·s/rad).
    pub fn damping(&self, omega: f64) -> f64 {
        hysteretic_damping(self.stiffness(), self.loss_factor, omega)
    }

    /// `b·ω = k η` (N·m), the frequency-independent product the seed's Table III lists.
    pub fn damping_times_omega(&self) -> f64 {
        self.stiffness() * self.loss_factor
    }

    /// Complex (hysteretic) stiffness `k (1 + iη)` for frequency-domain analyses.
    pub fn complex_stiffness(&self) -> Complex<f64> {
        let k = self.stiffness();
        Complex::new(k, k * self.loss_factor)
    }

    /// Twist stiffness about the hinge's long axis (N·m/rad), Eq. 8: `k · 2/(1 + ν)`.
    pub fn twist_stiffness(&self) -> f64 {
        self.stiffness() * twist_ratio(self.poisson_ratio)
    }
}
