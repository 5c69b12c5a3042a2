//! `mech actuator`: the piezo bending actuator — blocked force, free deflection, series
//! stiffness and energy density, from the datasheet values or the bimorph geometry.
//!
//! Consumes: quantities with units from the command line. Produces: text on stdout.

use std::fmt::Write as _;

use clap::Args;
use mech_codegen::ir::Dimension;

use super::args::{length, positive, voltage};
use super::Error;
use crate::physics::actuator::{
    energy_density, SEED_DRIVE_VOLTAGE, SEED_TABLE_II, SEED_TABLE_I_MODEL,
};
use crate::physics::{Actuator, Bimorph};
use crate::quantity::parse_si;

/// Options of `mech actuator`.
#[derive(Args)]
pub struct ActuatorArgs {
    /// Blocked force at the rated voltage, e.g. `320 mN`.
    #[arg(long)]
    pub blocked_force: Option<String>,
    /// Free deflection at the rated voltage, e.g. `300 um`.
    #[arg(long)]
    pub free_deflection: Option<String>,
    /// Bimorph geometry preset: `new-geometry` or `old-geometry` (seed Table I); the geometry
    /// options below override its fields.
    #[arg(long)]
    pub bimorph: Option<String>,
    /// PZT plate thickness t_p.
    #[arg(long)]
    pub pzt_thickness: Option<String>,
    /// Carbon-fibre core thickness t_cf.
    #[arg(long)]
    pub core_thickness: Option<String>,
    /// Active PZT length L.
    #[arg(long)]
    pub length: Option<String>,
    /// Rigid extension length l_ext.
    #[arg(long)]
    pub extension: Option<String>,
    /// Nominal width w_nom.
    #[arg(long)]
    pub width: Option<String>,
    /// Width ratio w_r (base w_r·w_nom, tip (2 − w_r)·w_nom).
    #[arg(long)]
    pub width_ratio: Option<f64>,
    /// Drive voltage (amplitude across one plate); default: the rated voltage.
    #[arg(long)]
    pub voltage: Option<String>,
    /// Voltage at which --blocked-force and --free-deflection hold (default 225 V).
    #[arg(long, default_value = "225 V")]
    pub rated_voltage: String,
    /// Actuator mass m_a, for the energy density, e.g. `100 mg`.
    #[arg(long)]
    pub mass: Option<String>,
    /// Print the seed's Tables I and II beside this model instead.
    #[arg(long)]
    pub seed_tables: bool,
}

pub fn run(args: &ActuatorArgs) -> Result<(), Error> {
    if args.seed_tables {
        print!("{}", seed_tables_i_ii());
        return Ok(());
    }
    let mass = match &args.mass {
        Some(text) => positive("--mass", parse_si("--mass", text, Dimension::MASS, false)?)?,
        None => f64::NAN,
    };
    let geometry_given = args.pzt_thickness.is_some()
        || args.core_thickness.is_some()
        || args.length.is_some()
        || args.extension.is_some()
        || args.width.is_some()
        || args.width_ratio.is_some();
    let direct = args.blocked_force.is_some() || args.free_deflection.is_some();
    let mut text = String::new();
    let actuator = if direct {
        if args.bimorph.is_some() || geometry_given {
            return Err(Error::Usage("give either --blocked-force and --free-deflection, or a bimorph geometry (--bimorph ...), not both".into()));
        }
        from_datasheet(args, mass, &mut text)?
    } else {
        from_bimorph(args, geometry_given, mass, &mut text)?
    };
    actuator.validate()?;
    print!("{text}{}", actuator_text(&actuator));
    Ok(())
}

/// The actuator from `--blocked-force` and `--free-deflection` at the rated voltage, scaled
/// to `--voltage`; describes it in `text`.
fn from_datasheet(args: &ActuatorArgs, mass: f64, text: &mut String) -> Result<Actuator, Error> {
    let (Some(force), Some(deflection)) = (&args.blocked_force, &args.free_deflection) else {
        return Err(Error::Usage(
            "--blocked-force and --free-deflection must be given together".into(),
        ));
    };
    let rated = voltage("--rated-voltage", &args.rated_voltage)?;
    let base = Actuator {
        blocked_force: positive(
            "--blocked-force",
            parse_si("--blocked-force", force, Dimension::FORCE, false)?,
        )?,
        free_deflection: length("--free-deflection", deflection)?,
        rated_voltage: rated,
        mass,
    };
    let _ = writeln!(
        text,
        "actuator: F_b = {force}, δ_f = {deflection} at {} V (linear in voltage)",
        rated
    );
    Ok(match &args.voltage {
        Some(v) => base.at_voltage(voltage("--voltage", v)?),
        None => base,
    })
}

/// The actuator from a bimorph preset with the geometry overrides (seed Table I), at
/// `--voltage`; describes the bimorph in `text`.
fn from_bimorph(
    args: &ActuatorArgs,
    geometry_given: bool,
    mass: f64,
    text: &mut String,
) -> Result<Actuator, Error> {
    let preset =
        args.bimorph
            .as_deref()
            .unwrap_or(if geometry_given { "new-geometry" } else { "" });
    let mut bimorph = match preset {
        "new-geometry" | "new" => Bimorph::SEED_NEW_GEOMETRY,
        "old-geometry" | "old" => Bimorph::SEED_OLD_GEOMETRY,
        "" => {
            return Err(Error::Usage("give --blocked-force and --free-deflection, or --bimorph new-geometry|old-geometry (optionally with geometry overrides), or --seed-tables".into()))
        }
        other => return Err(Error::Usage(format!("--bimorph: unknown preset `{other}`; known: new-geometry, old-geometry (seed Table I)"))),
    };
    if let Some(t) = &args.pzt_thickness {
        bimorph.pzt_thickness = length("--pzt-thickness", t)?;
    }
    if let Some(t) = &args.core_thickness {
        bimorph.core_thickness = length("--core-thickness", t)?;
    }
    if let Some(t) = &args.length {
        bimorph.length = length("--length", t)?;
    }
    if let Some(t) = &args.extension {
        bimorph.extension_length = parse_si("--extension", t, Dimension::LENGTH, false)?;
    }
    if let Some(t) = &args.width {
        bimorph.nominal_width = length("--width", t)?;
    }
    if let Some(r) = args.width_ratio {
        bimorph.width_ratio = r;
    }
    bimorph.validate()?;
    let v = match &args.voltage {
        Some(v) => voltage("--voltage", v)?,
        None => voltage("--rated-voltage", &args.rated_voltage)?,
    };
    let c = &bimorph.coefficients;
    let _ = writeln!(
        text,
        "bimorph ({preset}): t_p = {} µm, t_cf = {} µm, L = {} mm, l_ext = {} mm, w_nom = {} mm, w_r = {}\n  \
         coefficients: f31 = {} / {} Pa·m/V (force / deflection), E_p = {} GPa, E_cf = {} GPa\n  \
         D = {:.6e} N·m (rigidity per width), GF = {:.5}",
        bimorph.pzt_thickness * 1e6,
        bimorph.core_thickness * 1e6,
        bimorph.length * 1e3,
        bimorph.extension_length * 1e3,
        bimorph.nominal_width * 1e3,
        bimorph.width_ratio,
        c.f31_blocked,
        c.f31_free,
        c.pzt_modulus * 1e-9,
        c.core_modulus * 1e-9,
        bimorph.rigidity_per_width(),
        bimorph.geometry_factor()
    );
    Ok(bimorph.actuator(v, mass))
}

pub fn actuator_text(a: &Actuator) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "at V = {} V:", a.rated_voltage);
    let _ = writeln!(
        s,
        "  F_b = {:.6e} N   ({:.2} mN, blocked force)",
        a.blocked_force,
        a.blocked_force * 1e3
    );
    let _ = writeln!(
        s,
        "  δ_f = {:.6e} m   ({:.2} µm, free deflection)",
        a.free_deflection,
        a.free_deflection * 1e6
    );
    let _ = writeln!(
        s,
        "  k_a = F_b/δ_f = {:.6e} N/m   ({:.4} N/mm, series stiffness)",
        a.stiffness(),
        a.stiffness() * 1e-3
    );
    if a.mass.is_nan() {
        let _ = writeln!(
            s,
            "  D_u = δ_f F_b/(2 m_a): give --mass for the energy density [Eq. 1]"
        );
    } else {
        let _ = writeln!(
            s,
            "  D_u = δ_f F_b/(2 m_a) = {:.4} J/kg with m_a = {:.2} mg   [Eq. 1]",
            a.energy_density(),
            a.mass * 1e6
        );
    }
    s
}

pub fn seed_tables_i_ii() -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Seed Table II: D_u from Eq. 1 with the table's own m_a, δ_f, F_b:"
    );
    let _ = writeln!(
        s,
        "  {:<16} {:>7} {:>8} {:>8} | {:>9} {:>9} {:>7}",
        "actuator", "m_a[mg]", "δ_f[µm]", "F_b[mN]", "D_u table", "D_u Eq.1", "diff"
    );
    for row in SEED_TABLE_II {
        let du = energy_density(row.free_deflection, row.blocked_force, row.mass);
        let _ = writeln!(
            s,
            "  {:<16} {:>7.0} {:>8.0} {:>8.0} | {:>9.2} {:>9.3} {:>+7.3}",
            row.name,
            row.mass * 1e6,
            row.free_deflection * 1e6,
            row.blocked_force * 1e3,
            row.energy_density,
            du,
            row.energy_density - du
        );
    }
    let _ = writeln!(
        s,
        "\nSeed Table I model rows against the bimorph closed form (HAMR-VI coefficients, {SEED_DRIVE_VOLTAGE} V):"
    );
    let _ = writeln!(
        s,
        "  {:<13} {:>10} {:>10} {:>7} | {:>10} {:>10} {:>7} | {:>10}",
        "geometry",
        "δ_f table",
        "δ_f model",
        "diff",
        "F_b table",
        "F_b model",
        "diff",
        "k_a [N/mm]"
    );
    for ((name, deflection, force), bimorph) in SEED_TABLE_I_MODEL
        .into_iter()
        .zip([Bimorph::SEED_OLD_GEOMETRY, Bimorph::SEED_NEW_GEOMETRY])
    {
        let a = bimorph.actuator(SEED_DRIVE_VOLTAGE, f64::NAN);
        let _ = writeln!(
            s,
            "  {:<13} {:>7.0} µm {:>7.1} µm {:>+6.1}% | {:>7.0} mN {:>7.1} mN {:>+6.1}% | {:>10.4}",
            name,
            deflection * 1e6,
            a.free_deflection * 1e6,
            100.0 * (a.free_deflection - deflection) / deflection,
            force * 1e3,
            a.blocked_force * 1e3,
            100.0 * (a.blocked_force - force) / force,
            a.stiffness() * 1e-3
        );
    }
    s
}
