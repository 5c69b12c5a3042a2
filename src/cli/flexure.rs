//! `mech flexure stiffness|fit|seed-table`: the flexure hinge model (seed Eqs. 2, 5, 8) and
//! the pendulum characterization fit (Sec. IV.A).
//!
//! Consumes: quantities with units from the command line, specimen files. Produces: text on
//! stdout; `fit` also writes CSV files and plots through [`crate::render::flexure_fit`].

use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::PathBuf;

use clap::{Args, Subcommand};
use mech_codegen::ir::Dimension;

use super::args::{angular_frequency, length, positive};
use super::Error;
use crate::flexure_fit::fit::{fit_files, FitOptions, FitReport, PLAUSIBLE_MODULUS};
use crate::flexure_fit::rig::specimen_files;
use crate::output;
use crate::physics::flexure::{
    twist_ratio, HAMR_HINGE_EFFECTIVE_LENGTH, HAMR_HINGE_LOSS_FACTOR, HAMR_HINGE_THICKNESS,
    SEED_TABLE_III,
};
use crate::physics::{Flexure, HingeKind, Material};
use crate::quantity::parse_si;
use crate::render::flexure_fit as report;

/// `mech flexure ...`
#[derive(Subcommand)]
pub enum FlexureCommand {
    /// Stiffness (Eq. 2), damping at a frequency (Eq. 5) and twist stiffness (Eq. 8) of a flexure.
    Stiffness(StiffnessArgs),
    /// Fit stiffness, damping, modulus and loss factor to pendulum decay traces (Sec. IV.A).
    Fit(FitArgs),
    /// The seed's Table III beside Eq. 2 with l_eff = 66 µm, E = 2.56 GPa and η' = 0.08.
    SeedTable,
}

/// Options of `mech flexure stiffness`.
#[derive(Args)]
pub struct StiffnessArgs {
    /// Named material (kapton, kapton-datasheet).
    #[arg(long, default_value = "kapton")]
    pub material: String,
    /// Flexure width, e.g. `2 mm`.
    #[arg(long)]
    pub width: String,
    /// Film thickness, e.g. `25 um`.
    #[arg(long)]
    pub thickness: String,
    /// Flexure length, e.g. `500 um` (the nominal length of a castellated hinge).
    #[arg(long)]
    pub length: String,
    /// Effective length of a castellated hinge (used in Eq. 2 instead of the length).
    #[arg(long)]
    pub effective_length: Option<String>,
    /// Castellation length l_c of a castellated hinge (checks l − l_c ≤ l_eff ≤ l).
    #[arg(long)]
    pub castellation_length: Option<String>,
    /// Override Young's modulus, e.g. `2.5 GPa`.
    #[arg(long)]
    pub modulus: Option<String>,
    /// Override Poisson's ratio.
    #[arg(long, value_parser = super::args::poisson_ratio)]
    pub poisson: Option<f64>,
    /// Override the loss factor η.
    #[arg(long, value_parser = super::args::non_negative_number)]
    pub loss_factor: Option<f64>,
    /// Reference frequency of the time-domain damping b = kη/ω: `40 Hz`, or `250 rad/s`.
    #[arg(long, default_value = "40 Hz")]
    pub frequency: String,
}

/// Options of `mech flexure fit`.
#[derive(Args)]
pub struct FitArgs {
    /// Specimen files (`.toml`, naming their CSV traces) or directories of them.
    #[arg(required = true)]
    pub data: Vec<PathBuf>,
    /// Directory for traces.csv, flexures.csv and the plots.
    #[arg(long, default_value = "out/flexure_fit")]
    pub out_dir: PathBuf,
    /// Young's modulus for the castellated fits (default: the uncastellated fit's).
    #[arg(long)]
    pub modulus: Option<String>,
    /// Use Eq. 4 literally, without the finite-amplitude correction of the gravity stiffness
    /// (the screening then does not assume gravity's softening either).
    #[arg(long)]
    pub small_angle: bool,
    /// Plausible Young's modulus, MIN and MAX: an uncastellated fit outside is rejected
    /// (default 0.256 GPa and 25.6 GPa, a factor 10 either side of Kapton's).
    #[arg(long, num_args = 2, value_names = ["MIN", "MAX"])]
    pub modulus_range: Option<Vec<String>>,
    /// Plot format: `svg` or `png`; `none` for no plots.
    #[arg(long, default_value = "svg")]
    pub plots: String,
}

/// Runs a `mech flexure` subcommand.
pub fn run(command: FlexureCommand) -> Result<(), Error> {
    match command {
        FlexureCommand::Stiffness(args) => stiffness(&args),
        FlexureCommand::Fit(args) => fit(&args),
        FlexureCommand::SeedTable => {
            print!("{}", seed_table_iii());
            Ok(())
        }
    }
}

fn stiffness(args: &StiffnessArgs) -> Result<(), Error> {
    let mut material = Material::by_name(&args.material).ok_or_else(|| {
        Error::Usage(format!(
            "--material: unknown material `{}`; known: {}",
            args.material,
            Material::names().join(", ")
        ))
    })?;
    if let Some(text) = &args.modulus {
        material.youngs_modulus = positive(
            "--modulus",
            parse_si("--modulus", text, Dimension::PRESSURE, false)?,
        )?;
    }
    if let Some(nu) = args.poisson {
        material.poisson_ratio = nu;
    }
    if let Some(eta) = args.loss_factor {
        material.loss_factor = eta;
    }
    let width = length("--width", &args.width)?;
    let thickness = length("--thickness", &args.thickness)?;
    let nominal = length("--length", &args.length)?;
    let flexure = match &args.effective_length {
        Some(text) => {
            let l_eff = length("--effective-length", text)?;
            let l_c = match &args.castellation_length {
                Some(text) => parse_si("--castellation-length", text, Dimension::LENGTH, false)?,
                None => nominal, // no check of the lower bound
            };
            Flexure::castellated(
                &material,
                width,
                thickness,
                nominal,
                l_c,
                l_eff,
                material.loss_factor,
            )?
        }
        None => {
            if args.castellation_length.is_some() {
                return Err(Error::Usage("--castellation-length needs --effective-length (Eq. 2 uses l_eff for castellated hinges)".into()));
            }
            Flexure::uncastellated(&material, width, thickness, nominal)
        }
    };
    flexure.validate()?;
    let omega = angular_frequency("--frequency", &args.frequency)?;
    print!("{}", stiffness_text(&material, &flexure, omega));
    Ok(())
}

pub fn stiffness_text(material: &Material, flexure: &Flexure, omega: f64) -> String {
    let mut s = String::new();
    let k = flexure.stiffness();
    let _ = writeln!(
        s,
        "flexure of {}: E = {} GPa, ν = {}, η = {}",
        material.name,
        flexure.youngs_modulus * 1e-9,
        flexure.poisson_ratio,
        flexure.loss_factor
    );
    let _ = write!(
        s,
        "  w = {} mm, t = {} µm, ",
        flexure.width * 1e3,
        flexure.thickness * 1e6
    );
    match flexure.kind {
        HingeKind::Uncastellated => {
            let _ = writeln!(s, "l = {} µm", flexure.effective_length * 1e6);
        }
        HingeKind::Castellated { length, .. } => {
            let _ = writeln!(
                s,
                "l = {} µm, castellated: l_eff = {} µm",
                length * 1e6,
                flexure.effective_length * 1e6
            );
        }
    }
    let _ = writeln!(
        s,
        "  k   = E w t³/(12 l)   = {k:.6e} N·m/rad   ({:.4} µN·m/rad)   [Eq. 2]",
        k * 1e6
    );
    let _ = writeln!(
        s,
        "  b·ω = k η             = {:.6e} N·m       ({:.4} µN·m)",
        flexure.damping_times_omega(),
        flexure.damping_times_omega() * 1e6
    );
    let _ = writeln!(
        s,
        "  b   = k η / ω         = {:.6e} N·m·s/rad at ω = {:.4} rad/s ({:.4} Hz)   [Eq. 5]",
        flexure.damping(omega),
        omega,
        omega / TAU
    );
    let c = flexure.complex_stiffness();
    let _ = writeln!(
        s,
        "  k(1 + iη)             = {:.6e} + {:.6e}i N·m/rad   (frequency domain)",
        c.re, c.im
    );
    let _ = writeln!(
        s,
        "  k_twist = 2k/(1 + ν)  = {:.6e} N·m/rad   (ratio {:.4})   [Eq. 8]",
        flexure.twist_stiffness(),
        twist_ratio(flexure.poisson_ratio)
    );
    s
}

pub fn seed_table_iii() -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Seed Table III against Eq. 2 (E = 2.56 GPa, t = 25 µm, l_eff = 66 µm) and Eq. 5 (η' = 0.08):"
    );
    let _ = writeln!(
        s,
        "  {:<8} {:>6} | {:>10} {:>9} {:>7} | {:>9} {:>9} {:>7}",
        "hinge", "w [mm]", "k table", "k Eq. 2", "diff", "bω table", "bω Eq.5", "diff"
    );
    let _ = writeln!(
        s,
        "  {:<8} {:>6} | {:>10} {:>9} {:>7} | {:>9} {:>9} {:>7}",
        "", "", "[µN·m/rad]", "", "", "[µN·m]", "", ""
    );
    for row in SEED_TABLE_III {
        let f = Flexure::hamr_castellated(row.width);
        debug_assert_eq!(f.thickness, HAMR_HINGE_THICKNESS);
        debug_assert_eq!(f.effective_length, HAMR_HINGE_EFFECTIVE_LENGTH);
        debug_assert_eq!(f.loss_factor, HAMR_HINGE_LOSS_FACTOR);
        let k = f.stiffness();
        let bw = f.damping_times_omega();
        let _ = writeln!(
            s,
            "  {:<8} {:>6.2} | {:>10.1} {:>9.1} {:>+6.1}% | {:>9.1} {:>9.2} {:>+6.1}%",
            row.hinge,
            row.width * 1e3,
            row.stiffness * 1e6,
            k * 1e6,
            100.0 * (row.stiffness - k) / k,
            row.damping_times_omega * 1e6,
            bw * 1e6,
            100.0 * (row.damping_times_omega - bw) / bw
        );
    }
    let _ = writeln!(
        s,
        "(diff = (table − Eq.) / Eq. The table scatters around Eq. 2: S2 and L2 share w = 0.80 mm \
         but list 35.0 and 31.9.)"
    );
    s
}

/// Fits every specimen it can; prints the report and writes its files even when some traces
/// were rejected, then fails (exit code 1) listing every rejected trace.
fn fit(args: &FitArgs) -> Result<(), Error> {
    let files = specimen_files(&args.data)?;
    let modulus_range = match args.modulus_range.as_deref() {
        Some([min, max]) => {
            let value = |text: &str| {
                positive(
                    "--modulus-range",
                    parse_si("--modulus-range", text, Dimension::PRESSURE, false)?,
                )
            };
            let range = (value(min)?, value(max)?);
            if range.0 >= range.1 {
                return Err(Error::Usage(format!(
                    "--modulus-range: MIN `{min}` must be below MAX `{max}`"
                )));
            }
            range
        }
        _ => PLAUSIBLE_MODULUS,
    };
    let modulus = match &args.modulus {
        Some(text) => Some(positive(
            "--modulus",
            parse_si("--modulus", text, Dimension::PRESSURE, false)?,
        )?),
        None => None,
    };
    let options = FitOptions {
        small_angle: args.small_angle,
        modulus,
        modulus_range,
        ..FitOptions::default()
    };
    let plots = args.plots.to_ascii_lowercase();
    if !matches!(plots.as_str(), "svg" | "png" | "none") {
        return Err(Error::Usage(format!(
            "--plots: expected `svg`, `png` or `none`, got `{}`",
            args.plots
        )));
    }
    let fit_report = fit_files(&files, &options);
    print!("{}", report::text_report(&fit_report));
    let mut written = report::csv_files(&fit_report, &args.out_dir)?;
    if plots != "none" {
        written.extend(report::plot_files(&fit_report, &args.out_dir, &plots)?);
    }
    output::write_all(&written, &data_set_reads(&files, &fit_report))?;
    println!(
        "\nwritten: {}",
        written
            .iter()
            .map(|file| file.path.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(fit_report.problems()?)
}

/// The files a data set's run read: its specimen files and their traces (outputs may not
/// overwrite them).
pub(super) fn data_set_reads(files: &[PathBuf], report: &FitReport) -> Vec<output::Read> {
    let traces = report.specimens.iter().flat_map(|s| &s.traces);
    (files.iter().map(|path| (path, "a specimen file")))
        .chain(traces.map(|trace| (&trace.file, "a trace")))
        .map(|(path, what)| output::Read {
            path: path.clone(),
            what,
        })
        .collect()
}
