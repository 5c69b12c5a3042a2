//! Piezo bending actuators against the seed paper: Eq. 1 on Table II's own numbers, the
//! bimorph closed form (HAMR-VI coefficients) against Table I's model rows, and the linear
//! actuator model (force source in parallel with k_a = F_b/δ_f).

use crate::common;

use mech::physics::actuator::{
    energy_density, SEED_DRIVE_VOLTAGE, SEED_TABLE_II, SEED_TABLE_I_MODEL,
};
use mech::physics::{Actuator, Bimorph};

#[test]
fn table_ii_energy_density_from_its_own_columns() {
    // D_u = δ_f F_b / (2 m_a), Eq. 1; the table prints two decimals and its PNP 'a' and PS 'a'
    // rows are 0.017 J/kg above Eq. 1 (0.303 vs 0.32, 0.333 vs 0.35).
    let mut worst = 0.0_f64;
    for row in SEED_TABLE_II {
        let du = energy_density(row.free_deflection, row.blocked_force, row.mass);
        let difference = (du - row.energy_density).abs();
        println!(
            "{:<16} D_u = {du:.4} J/kg (table {})",
            row.name, row.energy_density
        );
        assert!(
            difference <= 0.02,
            "{}: {du} vs {}",
            row.name,
            row.energy_density
        );
        worst = worst.max(difference);
    }
    assert!(
        worst > 0.015,
        "the two 0.017 rows are reproduced, not hidden"
    );
    // Exact arithmetic on one row: PS 'b', 219 µm · 500 mN / (2 · 109 mg).
    let du = energy_density(219e-6, 0.5, 109e-6);
    assert!((du - 219e-6 * 0.5 / 218e-6).abs() < 1e-15);
}

#[test]
fn table_i_new_geometry_from_the_bimorph_formulas() {
    let a = Bimorph::SEED_NEW_GEOMETRY.actuator(SEED_DRIVE_VOLTAGE, f64::NAN);
    let (_, deflection, force) = SEED_TABLE_I_MODEL[1];
    let e_d = common::relative_error(a.free_deflection, deflection);
    let e_f = common::relative_error(a.blocked_force, force);
    println!(
        "new geometry: δ_f = {:.1} µm ({:+.1} %), F_b = {:.1} mN ({:+.1} %), k_a = {:.4} N/mm",
        a.free_deflection * 1e6,
        100.0 * e_d,
        a.blocked_force * 1e3,
        100.0 * e_f,
        a.stiffness() * 1e-3
    );
    assert!(e_d.abs() < 0.10 && e_f.abs() < 0.10);
    // The reference notes: 281–297 µm and 308–324 mN for t_cf = 65–55 µm.
    assert!((a.free_deflection - 297.2e-6).abs() < 0.5e-6);
    assert!((a.blocked_force - 0.3081).abs() < 0.5e-3);
    let thick = Bimorph {
        core_thickness: 65e-6,
        ..Bimorph::SEED_NEW_GEOMETRY
    }
    .actuator(SEED_DRIVE_VOLTAGE, f64::NAN);
    assert!((thick.free_deflection - 280.6e-6).abs() < 0.5e-6);
    assert!((thick.blocked_force - 0.3243).abs() < 0.5e-3);

    // The old geometry's model row (184 µm, 549 mN) is within 10 % as well.
    let old = Bimorph::SEED_OLD_GEOMETRY.actuator(SEED_DRIVE_VOLTAGE, f64::NAN);
    let (_, deflection, force) = SEED_TABLE_I_MODEL[0];
    println!(
        "old geometry: δ_f = {:.1} µm, F_b = {:.1} mN",
        old.free_deflection * 1e6,
        old.blocked_force * 1e3
    );
    assert!(common::relative_error(old.free_deflection, deflection).abs() < 0.10);
    assert!(common::relative_error(old.blocked_force, force).abs() < 0.10);
}

#[test]
fn geometry_factor_is_continuous_through_the_untapered_limit() {
    let at = |wr: f64, lr: f64| {
        Bimorph {
            width_ratio: wr,
            extension_length: lr * 9.2e-3,
            ..Bimorph::SEED_NEW_GEOMETRY
        }
        .geometry_factor()
    };
    assert!((at(1.0, 0.0) - 1.0).abs() < 1e-12);
    for lr in [0.0, 0.1087, 0.3] {
        let limit = at(1.0, lr);
        for e in [1e-7, 1e-4, 5e-3, 0.0099, 0.0101, 0.02] {
            for wr in [1.0 - e, 1.0 + e] {
                let gf = at(wr, lr);
                assert!(
                    (gf - limit).abs() < 2.0 * e,
                    "GF({wr}, {lr}) = {gf} vs {limit}"
                );
                assert!(gf.is_finite() && gf > 0.0);
            }
        }
    }
    assert!(Bimorph {
        width_ratio: 2.0,
        ..Bimorph::SEED_NEW_GEOMETRY
    }
    .validate()
    .is_err());
}

#[test]
fn linear_actuator_model() {
    let a = Actuator {
        blocked_force: 0.32,
        free_deflection: 300e-6,
        rated_voltage: 225.0,
        mass: 92e-6,
    };
    assert!((a.stiffness() - 0.32 / 300e-6).abs() < 1e-9);
    assert!((a.blocked_force_at(112.5) - 0.16).abs() < 1e-15);
    // Force source in parallel with k_a: zero force at the free deflection.
    assert!(a.tip_force(225.0, 300e-6).abs() < 1e-15);
    assert!((a.tip_force(225.0, 0.0) - 0.32).abs() < 1e-15);
    let half = a.at_voltage(112.5);
    assert!((half.stiffness() - a.stiffness()).abs() < 1e-9);
    assert!((a.energy_density() - 300e-6 * 0.32 / (2.0 * 92e-6)).abs() < 1e-12);
    assert!(Actuator { mass: -1.0, ..a }.validate().is_err());
    assert!(Actuator {
        mass: f64::NAN,
        ..a
    }
    .validate()
    .is_ok());
    // The bimorph's k_a does not depend on voltage.
    let b = Bimorph::SEED_NEW_GEOMETRY;
    let k1 = b.actuator(100.0, f64::NAN).stiffness();
    let k2 = b.actuator(225.0, f64::NAN).stiffness();
    assert!((k1 - k2).abs() < 1e-9 * k1);
}

#[test]
fn seed_tables_text() {
    let text = mech::cli::actuator::seed_tables_i_ii();
    assert!(
        text.contains("PS 'b'") && text.contains("new geometry"),
        "{text}"
    );
}
