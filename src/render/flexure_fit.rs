//! Presentation of a [`FitReport`]: readable tables for the terminal, CSV files, and plots of
//! each fit in the manner of the seed's Fig. 5 (data points and the fitted line through the
//! origin).
//!
//! Consumes: a [`FitReport`] and the output directory. Produces: a `String`, and the files
//! written (or an [`Error`] naming the file that could not be).

use std::fmt::Write as _;
use std::path::Path;

use crate::flexure_fit::error::Error;
use crate::flexure_fit::fit::{
    CastellatedFit, FitReport, LineFit, ModulusFit, SpecimenResult, LOSS_EXPONENT_RESOLUTION,
    SMALLEST_LOSS_EXPONENT,
};
use crate::flexure_fit::rig::Kind;
use crate::flexure_fit::screen::FLAG_SIGMA;
use crate::output::File;
use crate::render::plot;

fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

fn kind_name(kind: Kind) -> &'static str {
    match kind {
        Kind::Uncastellated => "uncastellated",
        Kind::Castellated => "castellated",
    }
}

/// The report as text: per-trace table, per-specimen table, the fits, the loss factor
/// against frequency and the findings.
/// The rejected traces are not in it: they are the command's error ([`FitReport::problems`]).
pub fn text_report(report: &FitReport) -> String {
    let mut s = String::new();
    write_trace_table(&mut s, report);
    write_flexure_table(&mut s, report);
    write_uncastellated_fit(&mut s, report);
    for fit in &report.castellated {
        write_castellated_fit(&mut s, fit);
    }
    s += &loss_frequency_text(report);
    if !report.rejected.is_empty() {
        let _ = writeln!(
            s,
            "\n{} of {} traces rejected, {} problem(s) in all: listed at the end (on stderr)",
            report
                .rejected
                .iter()
                .filter(|e| e.is_trace_problem())
                .count(),
            report.traces,
            report.rejected.len()
        );
    }
    s += &findings_text(report);
    s
}

/// The loss factor against frequency across the set, or why it could not be fitted or
/// resolved.
pub fn loss_frequency_text(report: &FitReport) -> String {
    let Some(fit) = &report.loss_frequency else {
        return format!(
            "\nloss factor against frequency: not fitted ({} hinges; need at least 2 more than \
             the fit's coefficients, one level per kind of hinge and the exponent)\n",
            report.specimens.len()
        );
    };
    let levels: Vec<String> = fit
        .levels
        .iter()
        .map(|(kind, eta, se)| format!("η₀ = {eta:.5} ± {se:.5} ({})", kind_name(*kind)))
        .collect();
    let mut s = format!(
        "\nloss factor against frequency, η(f) = η₀ (f/{:.2} Hz)^α over {} hinges at \
         {:.2}–{:.2} Hz:\n  α = {:.4} ± {:.4} ({:.1}σ from 0), {}; χ²/dof = {:.2}\n",
        fit.reference_frequency,
        fit.points,
        fit.frequencies.0,
        fit.frequencies.1,
        fit.exponent.0,
        fit.exponent.1,
        fit.exponent_sigma(),
        levels.join(", "),
        fit.chi2_dof
    );
    if !fit.resolved() && fit.exponent_sigma().abs() <= FLAG_SIGMA {
        let _ = writeln!(
            s,
            "  not resolved: the standard error of α exceeds {LOSS_EXPONENT_RESOLUTION:.4}, \
             which α = {SMALLEST_LOSS_EXPONENT} needs to be found at {FLAG_SIGMA}σ 9 times in \
             10; more hinges, or hinges spread over a wider range of frequencies, would resolve \
             it (the standard error falls as 1/(√n · spread of ln f))"
        );
    }
    s
}

/// The findings, each with its kind: what was fitted but deserves a look.
pub fn findings_text(report: &FitReport) -> String {
    let mut s = String::new();
    if !report.findings.is_empty() {
        let _ = writeln!(s, "\nfindings ({}):", finding_counts(report));
        for finding in &report.findings {
            let _ = writeln!(s, "  - [{}] {}", finding.kind, finding.message);
        }
    }
    s
}

/// `2 × trial_disagreement, 1 × baseline_drift`: the findings counted by kind, in order of
/// first appearance.
pub fn finding_counts(report: &FitReport) -> String {
    let mut counts: Vec<(&str, usize)> = Vec::new();
    for finding in &report.findings {
        match counts.iter_mut().find(|(kind, _)| *kind == finding.kind) {
            Some((_, n)) => *n += 1,
            None => counts.push((finding.kind, 1)),
        }
    }
    counts
        .iter()
        .map(|(kind, n)| format!("{n} × {kind}"))
        .collect::<Vec<_>>()
        .join(", ")
}

// Writing to a `String` cannot fail, hence the `let _ =` on every `writeln!` below.

fn write_trace_table(s: &mut String, report: &FitReport) {
    let _ = writeln!(s, "per trace (Eqs. 3, 4):");
    let _ = writeln!(
        s,
        "  {:<10} {:<22} {:>9} {:>8} {:>8} {:>13} {:>15} {:>5} {:>5} {:>8}",
        "specimen",
        "trace",
        "f_d [Hz]",
        "σ [1/s]",
        "ζ",
        "k_m[µN·m/rad]",
        "b_m[nN·m·s/rad]",
        "cross",
        "peaks",
        "noise[°]"
    );
    for sr in &report.specimens {
        for t in &sr.traces {
            let a = &t.analysis;
            let _ = writeln!(
                s,
                "  {:<10} {:<22} {:>9.4} {:>8.4} {:>8.5} {:>13.4} {:>15.4} {:>5} {:>5} {:>8.4}",
                sr.specimen.name,
                file_name(&t.file),
                a.omega_d / std::f64::consts::TAU,
                a.sigma,
                a.zeta,
                t.stiffness * 1e6,
                t.damping * 1e9,
                a.crossings.len(),
                a.peaks.len(),
                a.noise.to_degrees()
            );
        }
    }
}

fn write_flexure_table(s: &mut String, report: &FitReport) {
    let _ = writeln!(
        s,
        "\nper flexure (mean of its traces; Eqs. 6, 7 with the nominal length):"
    );
    let _ = writeln!(
        s,
        "  {:<10} {:<13} {:>7} {:>7} {:>8} {:>13} {:>14} {:>11} {:>11}",
        "specimen",
        "kind",
        "w [mm]",
        "t [µm]",
        "l [µm]",
        "k_m[µN·m/rad]",
        "b_m·ω_d [µN·m]",
        "y [GPa·mm]",
        "z [GPa·mm]"
    );
    for sr in &report.specimens {
        let f = &sr.specimen.flexure;
        let _ = writeln!(
            s,
            "  {:<10} {:<13} {:>7.3} {:>7.2} {:>8.1} {:>13.4} {:>14.4} {:>11.4} {:>11.5}",
            sr.specimen.name,
            kind_name(f.kind),
            f.width * 1e3,
            f.thickness * 1e6,
            f.length * 1e6,
            sr.stiffness * 1e6,
            sr.damping_times_omega * 1e6,
            sr.normalized_stiffness() * 1e-6,
            sr.normalized_damping() * 1e-6
        );
    }
}

fn write_uncastellated_fit(s: &mut String, report: &FitReport) {
    let rejected = report
        .rejected
        .iter()
        .any(|e| matches!(e, Error::ImplausibleModulus { .. }));
    if rejected {
        let _ = writeln!(
            s,
            "\nuncastellated flexures: no modulus fit (the fitted E is implausible, listed at \
             the end)"
        );
        return;
    }
    match report.uncastellated.as_ref() {
        Some(fit) => {
            let _ = writeln!(
                s,
                "\nuncastellated flexures (n = {}):\n  Eq. 6  y = E·w:    E = {:.4} GPa   R² = {:.4}\n  \
                 Eq. 7  z = η·E·w:  η = {:.4}       R² = {:.4}",
                fit.specimens.len(),
                fit.youngs_modulus * 1e-9,
                fit.stiffness_line.r_squared,
                fit.loss_factor,
                fit.damping_line.r_squared
            );
        }
        None => {
            let _ = writeln!(s, "\nuncastellated flexures: fewer than 2, no modulus fit");
        }
    }
}

fn write_castellated_fit(s: &mut String, fit: &CastellatedFit) {
    let _ = writeln!(
        s,
        "\ncastellated hinges, t = {:.1} µm, l = {:.0} µm (n = {}; E = {:.4} GPa):\n  \
         k_m = {:.4} µN·m/rad per mm of width   R² = {:.4}   → l_eff = {:.2} µm (Eq. 2)\n  \
         b_m·ω_d = {:.4} µN·m per mm            R² = {:.4}   → η' = {:.4} (Eq. 5)",
        fit.thickness * 1e6,
        fit.length * 1e6,
        fit.specimens.len(),
        fit.youngs_modulus * 1e-9,
        fit.stiffness_line.slope * 1e3,
        fit.stiffness_line.r_squared,
        fit.effective_length * 1e6,
        fit.damping_line.slope * 1e3,
        fit.damping_line.r_squared,
        fit.loss_factor
    );
}

fn text_csv(path: &Path, header: &[&str], rows: &[Vec<String>]) -> Result<File, Error> {
    let encode_failed = |message: String| Error::EncodeCsv {
        path: path.to_path_buf(),
        message,
    };
    let mut writer = csv::Writer::from_writer(Vec::new());
    writer
        .write_record(header)
        .map_err(|e| encode_failed(e.to_string()))?;
    for row in rows {
        writer
            .write_record(row)
            .map_err(|e| encode_failed(e.to_string()))?;
    }
    let bytes = writer
        .into_inner()
        .map_err(|e| encode_failed(e.to_string()))?;
    Ok(File::new(path, bytes))
}

/// `traces.csv` (one row per trace) and `flexures.csv` (one row per specimen, with the
/// normalized values) in `dir`, in SI units.
pub fn csv_files(report: &FitReport, dir: &Path) -> Result<Vec<File>, Error> {
    // `{:?}` of an f64 is the shortest text that reads back to the same number.
    let num = |v: f64| format!("{v:?}");
    let mut trace_rows = Vec::new();
    for sr in &report.specimens {
        for t in &sr.traces {
            let a = &t.analysis;
            trace_rows.push(vec![
                sr.specimen.name.clone(),
                t.file.display().to_string(),
                num(a.omega_d),
                num(a.sigma),
                num(a.omega_n),
                num(a.zeta),
                num(t.stiffness),
                num(t.damping),
                a.crossings.len().to_string(),
                a.peaks.len().to_string(),
                num(a.noise),
                num(a.log_fit_r2),
                num(a.gravity_softening),
                num(t.stiffness_se),
                num(t.damping_se),
            ]);
        }
    }
    let traces = text_csv(
        &dir.join("traces.csv"),
        &[
            "specimen",
            "trace",
            "omega_d",
            "sigma",
            "omega_n",
            "zeta",
            "k_m",
            "b_m",
            "crossings",
            "peaks",
            "noise",
            "log_fit_r2",
            "gravity_softening",
            "k_m_se",
            "b_m_se",
        ],
        &trace_rows,
    )?;
    let specimen_rows: Vec<Vec<String>> = report
        .specimens
        .iter()
        .map(|sr| {
            let f = &sr.specimen.flexure;
            vec![
                sr.specimen.name.clone(),
                kind_name(f.kind).to_string(),
                num(f.width),
                num(f.thickness),
                num(f.length),
                sr.traces.len().to_string(),
                num(sr.stiffness),
                num(sr.damping),
                num(sr.omega_d),
                num(sr.damping_times_omega),
                num(sr.normalized_stiffness()),
                num(sr.normalized_damping()),
            ]
        })
        .collect();
    let flexures = text_csv(
        &dir.join("flexures.csv"),
        &[
            "specimen",
            "kind",
            "width",
            "thickness",
            "length",
            "traces",
            "k_m",
            "b_m",
            "omega_d",
            "b_m_omega_d",
            "y",
            "z",
        ],
        &specimen_rows,
    )?;
    Ok(vec![traces, flexures])
}

/// One Fig. 5-style panel: a quantity of the fitted specimens against their width, and its
/// fitted line through the origin, all in the units of the axes.
struct Panel {
    /// File name without the extension.
    stem: String,
    title: String,
    y_label: &'static str,
    /// One value per point, in the order of the widths.
    values: Vec<f64>,
    /// The fit, its slope converted to the axes' units.
    line: LineFit,
    /// Legend of the line (its R² is appended).
    fit_label: String,
}

/// The two panels of one fit (stiffness and damping), over the same widths (mm).
struct FitPanels {
    widths_mm: Vec<f64>,
    stiffness: Panel,
    damping: Panel,
}

/// `line` with its slope multiplied by `factor`, to read in the plot's units.
fn rescaled(line: LineFit, factor: f64) -> LineFit {
    LineFit {
        slope: line.slope * factor,
        ..line
    }
}

/// `value` of each specimen `indices` names, in that order.
fn specimen_values(
    report: &FitReport,
    indices: &[usize],
    value: impl Fn(&SpecimenResult) -> f64,
) -> Vec<f64> {
    indices
        .iter()
        .map(|&i| value(&report.specimens[i]))
        .collect()
}

/// Draws `panel` against `widths_mm` as `dir/<stem>.<extension>`.
fn draw_panel(dir: &Path, extension: &str, widths_mm: &[f64], panel: Panel) -> Result<File, Error> {
    let path = dir.join(format!("{}.{extension}", panel.stem));
    let w_max = widths_mm.iter().fold(0.0_f64, |m, &w| m.max(w)) * 1.05;
    let line_x = vec![0.0, w_max];
    let line_y: Vec<f64> = line_x.iter().map(|x| panel.line.slope * x).collect();
    let curves = vec![(
        format!("{}, R² = {:.3}", panel.fit_label, panel.line.r_squared),
        line_x,
        line_y,
    )];
    // One marker per specimen (the mean over its trials), drawn over the line.
    let measured = [plot::Measured {
        name: format!(
            "measured (n = {}, mean of each specimen's trials)",
            panel.line.points
        ),
        color: 1,
        points: widths_mm
            .iter()
            .zip(&panel.values)
            .map(|(&x, &y)| plot::ErrorPoint {
                x,
                y,
                ..plot::ErrorPoint::default()
            })
            .collect(),
    }];
    plot::XyPlot {
        measured: &measured,
        ..plot::XyPlot::new(&panel.title, "width w [mm]", panel.y_label, &curves)
    }
    .render(&path)
    .map_err(|e| Error::Plot {
        path: path.clone(),
        message: e.to_string(),
    })
}

/// The plots of every fit in `dir`, with extension `extension` (`svg` or `png`).
pub fn plot_files(report: &FitReport, dir: &Path, extension: &str) -> Result<Vec<File>, Error> {
    let mut panels = Vec::new();
    if let Some(fit) = &report.uncastellated {
        panels.push(uncastellated_panels(report, fit));
    }
    for (n, fit) in report.castellated.iter().enumerate() {
        // Numbered only if there are several groups.
        let suffix = if report.castellated.len() > 1 {
            format!("_{}", n + 1)
        } else {
            String::new()
        };
        panels.push(castellated_panels(report, fit, &suffix));
    }
    let mut written = Vec::new();
    for fit in panels {
        written.push(draw_panel(dir, extension, &fit.widths_mm, fit.stiffness)?);
        written.push(draw_panel(dir, extension, &fit.widths_mm, fit.damping)?);
    }
    Ok(written)
}

/// The panels of the uncastellated fit, Eq. 6 (stiffness) and Eq. 7 (damping), in GPa·mm
/// against mm: the slopes read directly in GPa.
fn uncastellated_panels(report: &FitReport, fit: &ModulusFit) -> FitPanels {
    let widths_mm = specimen_values(report, &fit.specimens, |s| s.specimen.flexure.width * 1e3);
    let stiffness = Panel {
        stem: "fit_modulus".into(),
        title: "Uncastellated flexures: stiffness (Eq. 6)".into(),
        y_label: "y = 12 l k_m / t³ [GPa·mm]",
        values: specimen_values(report, &fit.specimens, |s| s.normalized_stiffness() * 1e-6),
        line: rescaled(fit.stiffness_line, 1e-9),
        fit_label: format!("y = E·w, E = {:.3} GPa", fit.youngs_modulus * 1e-9),
    };
    let damping = Panel {
        stem: "fit_loss_factor".into(),
        title: "Uncastellated flexures: damping (Eq. 7)".into(),
        y_label: "z = 12 l ω_d b_m / t³ [GPa·mm]",
        values: specimen_values(report, &fit.specimens, |s| s.normalized_damping() * 1e-6),
        line: rescaled(fit.damping_line, 1e-9),
        fit_label: format!("z = η·E·w, η = {:.4}", fit.loss_factor),
    };
    FitPanels {
        widths_mm,
        stiffness,
        damping,
    }
}

/// The panels of one castellated group: k_m (µN·m/rad) and b_m·ω_d (µN·m) against mm, the
/// slopes per mm of width.
fn castellated_panels(report: &FitReport, fit: &CastellatedFit, suffix: &str) -> FitPanels {
    let widths_mm = specimen_values(report, &fit.specimens, |s| s.specimen.flexure.width * 1e3);
    let group = format!(
        "t = {:.0} µm, l = {:.0} µm",
        fit.thickness * 1e6,
        fit.length * 1e6
    );
    let stiffness = Panel {
        stem: format!("fit_castellated_stiffness{suffix}"),
        title: format!("Castellated hinges ({group}): stiffness"),
        y_label: "k_m [µN·m/rad]",
        values: specimen_values(report, &fit.specimens, |s| s.stiffness * 1e6),
        line: rescaled(fit.stiffness_line, 1e3),
        fit_label: format!("l_eff = {:.1} µm", fit.effective_length * 1e6),
    };
    let damping = Panel {
        stem: format!("fit_castellated_damping{suffix}"),
        title: format!("Castellated hinges ({group}): damping"),
        y_label: "b_m·ω_d [µN·m]",
        values: specimen_values(report, &fit.specimens, |s| s.damping_times_omega * 1e6),
        line: rescaled(fit.damping_line, 1e3),
        fit_label: format!("η' = {:.4}", fit.loss_factor),
    };
    FitPanels {
        widths_mm,
        stiffness,
        damping,
    }
}
