//! The rendering shared by `mech fit` and `mech diagnose`: the screening's flags, the
//! overlay plots of data and models, the comparison of features and residuals, the
//! self-contained `diagnosis.html`, and the summary of `mech diagnose --dataset`.
//!
//! Consumes: a [`crate::diagnose`] experiment, its observations and predictions, a
//! [`Diagnosis`]; for `--dataset`, a flexure [`FitReport`]. Produces: text, JSON values, SVG
//! plots and the HTML page (written atomically).

use std::path::{Path, PathBuf};

use serde_json::json;

use crate::diagnose::candidates::{Diagnosis, Trial, Verdict};
use crate::diagnose::experiment::{Experiment, Kind, Observations};
use crate::diagnose::features::{features, series_rms, Feature, SeriesResidual};
use crate::diagnose::pendulum::{Screening, FLAG_SIGMA};
use crate::diagnose::separate::SEPARATES;
use crate::flexure_fit::fit::{FitReport, AGREEMENT_SIGMA};
use crate::output::File;
use crate::render::plot;
use crate::render::report::{render_page, Outcome};
use crate::render::table::Table;
use crate::render::Error;

/// The screening's summary and, prominently, its flags (empty for unscreened kinds).
pub fn screening_text(screening: Option<&Screening>) -> String {
    let Some(s) = screening else {
        return String::new();
    };
    let mut text = format!("{}\n", s.summary());
    for flag in &s.flags {
        text += &format!("\n  !! {}\n", flag.message);
    }
    text
}

/// `mech diagnose --dataset`: one line per trace with its screening (the effects in standard
/// errors, the flags by kind), then the set's findings: the loss factor against frequency,
/// trial disagreement, and every finding with its message.
pub fn dataset_text(report: &FitReport) -> String {
    let rejected = report
        .rejected
        .iter()
        .filter(|e| e.is_trace_problem())
        .count();
    let mut s = format!(
        "{} traces of {} specimens screened as pendulum ring-downs (each with its specimen's \
         pendulum); effects in standard errors, flagged beyond {FLAG_SIGMA}σ\n\n",
        report.traces,
        report.specimens.len(),
    );
    s += &format!(
        "  {:<10} {:<18} {:>8} {:>15} {:>8} {:>8} {:>6} {:>6}  flags\n",
        "specimen", "trace", "f_d [Hz]", "amplitude [°]", "damping", "stiffen", "drift", "offset"
    );
    for specimen in &report.specimens {
        for t in &specimen.traces {
            let name = t.file.file_name().map_or_else(
                || t.file.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
            let flags = if t.screening.flags.is_empty() {
                "-".to_string()
            } else {
                flag_kinds(&t.screening)
            };
            let numbers = match &t.screening.fit {
                Some(f) => format!(
                    "{:>6.2} → {:<6.2} {:>7.1}σ {:>7.1}σ {:>5.1}σ {:>5.1}σ",
                    f.amplitudes.0.to_degrees(),
                    f.amplitudes.1.to_degrees(),
                    f.decrement_trend_sigma,
                    f.stiffening_sigma,
                    f.drift_sigma,
                    f.offset_sigma
                ),
                None => format!("{:>48}", "not screened"),
            };
            s += &format!(
                "  {:<10} {:<18} {:>8.3} {numbers}  {flags}\n",
                specimen.specimen.name,
                name,
                t.analysis.omega_d / std::f64::consts::TAU
            );
        }
    }
    if rejected > 0 {
        s += &format!(
            "  ({rejected} of {} traces rejected: listed at the end, on stderr)\n",
            report.traces
        );
    }
    s += &crate::render::flexure_fit::loss_frequency_text(report);
    let pairs: usize = report
        .specimens
        .iter()
        .map(|sp| sp.traces.len() * sp.traces.len().saturating_sub(1) / 2)
        .sum();
    let disagreeing = report
        .findings
        .iter()
        .filter(|f| f.kind == "trial_disagreement")
        .count();
    s += &format!(
        "\ntrial disagreement: {disagreeing} of {pairs} pairs of trials differ by more than \
         {AGREEMENT_SIGMA} standard errors in k_m or b_m\n"
    );
    let findings = crate::render::flexure_fit::findings_text(report);
    if findings.is_empty() {
        s += "\nfindings: none\n";
    } else {
        s += &findings;
    }
    s
}

/// The kinds of the screening's flags, comma-separated.
pub fn flag_kinds(s: &Screening) -> String {
    s.flags
        .iter()
        .map(|f| f.kind)
        .collect::<Vec<_>>()
        .join(", ")
}

/// `flags` and `screening` entries for the JSON summaries.
pub fn screening_json(screening: Option<&Screening>) -> (serde_json::Value, serde_json::Value) {
    match screening {
        Some(s) => (
            json!(s
                .flags
                .iter()
                .map(|f| json!({"kind": f.kind, "message": f.message}))
                .collect::<Vec<_>>()),
            json!(s.summary()),
        ),
        None => (json!([]), serde_json::Value::Null),
    }
}

/// One plot per measured series (`PREFIX_SERIES.svg` in `dir`): the data as markers with
/// ±σ error bars (none where the experiment file gives no noise, and the legend says so) and
/// each of `curves` (a label and a prediction of every observed value) as a line.
pub fn overlay_plots(
    dir: &Path,
    prefix: &str,
    experiment: &Experiment,
    obs: &Observations,
    curves: &[(String, &[f64])],
) -> Result<Vec<File>, Error> {
    let log_x = matches!(experiment.kind, Kind::FrequencyResponse(_));
    // Axis labels and the SI → plotted unit factors.
    let (x_label, x_scale, y_unit, y_scale) = match experiment.kind {
        Kind::FrequencyResponse(_) => ("frequency [Hz]", 1.0, "", 1.0),
        Kind::QuasiStatic(_) => ("data row", 1.0, " [m]", 1.0),
        Kind::ForceDeflection(_) => ("sensor distance [µm]", 1e6, " [mN]", 1e3),
        // One value per series: the features table shows them beside the models.
        Kind::ForceDeflectionTable(_) => return Ok(Vec::new()),
        Kind::Pendulum(_) => ("time [s]", 1.0, " [rad]", 1.0),
    };
    // The models in the palette's colours after the data's (0).
    let styles: Vec<plot::CurveStyle> = (1..=curves.len())
        .map(|color| plot::CurveStyle {
            color,
            dashed: false,
        })
        .collect();
    let mut plots = Vec::new();
    for name in obs.series_names() {
        let in_series: Vec<usize> = (0..obs.values.len().min(obs.series.len()))
            .filter(|&k| obs.series[k] == name)
            .collect();
        let lines: Vec<(String, Vec<f64>, Vec<f64>)> = curves
            .iter()
            .map(|(label, values)| {
                let (x, y) = in_series
                    .iter()
                    .filter(|&&k| k < values.len())
                    .map(|&k| (obs.abscissa[k] * x_scale, values[k] * y_scale))
                    .unzip();
                (label.clone(), x, y)
            })
            .collect();
        let measured = [plot::Measured {
            name: match obs.sigma {
                Some(_) => "measured (± σ, the file's noise)".into(),
                None => "measured (no noise given: no bars)".into(),
            },
            color: 0,
            points: in_series
                .iter()
                .map(|&k| plot::ErrorPoint {
                    x: obs.abscissa[k] * x_scale,
                    y: obs.values[k] * y_scale,
                    x_error: 0.0,
                    y_error: obs.sigma.as_ref().map_or(0.0, |s| s[k] * y_scale),
                })
                .collect(),
        }];
        let path = dir.join(format!("{prefix}_{}.svg", name.replace(['|', '.'], "_")));
        let title = format!("{}: {name}", experiment.title);
        let y_label = format!("{name}{y_unit}");
        let plot = plot::XyPlot {
            log_x,
            styles: Some(&styles),
            measured: &measured,
            ..plot::XyPlot::new(&title, x_label, &y_label, &lines)
        };
        plots.push(plot.render(&path)?);
    }
    Ok(plots)
}

/// The ranking as terminal text: the base model, the candidates best first, the second
/// round and the inert candidates, each with its χ² and fitted values.
pub fn ranking_text(d: &Diagnosis) -> String {
    let per = |chi2: f64| chi2 / d.ranking_values() as f64;
    let mut text = format!(
        "\n{:<36} {:<16} {:>12} {:>12} {:>10}  fitted\n",
        "cause", "where", "χ² fit", "χ²/value out", "ΔAICc"
    );
    let line = |t: &Trial| {
        let fitted: Vec<String> = t.parameters.iter().map(fitted_text).collect();
        format!(
            "{:<36} {:<16} {:>12.1} {:>12.2} {:>10.1}  {}\n",
            t.cause,
            t.location,
            t.train_chi2,
            per(t.holdout_chi2),
            t.aicc - d.base.aicc,
            fitted.join(", ")
        )
    };
    text += &line(&d.base);
    for t in &d.ranked {
        text += &line(t);
    }
    if !d.second_round.is_empty() {
        text += "\nthe best leaves a residual above the noise; fitted together with each other \
                 candidate:\n";
        for t in &d.second_round {
            text += &line(t);
        }
    }
    let (failed, inert) = inert_and_failed(d);
    if !inert.is_empty() {
        text += "\ninert (cannot change the response beyond the noise):\n";
        for t in inert {
            text += &format!("  {}\n", cause_at(t));
        }
    }
    if !failed.is_empty() {
        text += "\nfailed (the fit stopped with an error):\n";
        for t in failed {
            let error = t.error.as_deref().unwrap_or_default();
            text += &format!("  {}: {error}\n", cause_at(t));
        }
    }
    text
}

/// The values the ranking χ² is over: `held-out`, or `fitted` when nothing is held out.
pub fn ranked_on(d: &Diagnosis) -> &'static str {
    if d.holdout_values == 0 {
        "fitted"
    } else {
        "held-out"
    }
}

/// The trials set aside, split: those whose fit failed (with the error), and the inert.
fn inert_and_failed(d: &Diagnosis) -> (Vec<&Trial>, Vec<&Trial>) {
    d.inert.iter().partition(|t| t.error.is_some())
}

/// The verdict in one sentence: the cause with its held-out gain, a tie, a flag, or none.
pub fn verdict_text(d: &Diagnosis) -> String {
    let per = |chi2: f64| chi2 / d.ranking_values() as f64;
    let gain = |t: &Trial| {
        format!(
            "{} χ²/value {:.2} → {:.2}",
            ranked_on(d),
            per(d.base.holdout_chi2),
            per(t.holdout_chi2)
        )
    };
    let named = d.combined.as_ref().or(d.ranked.first());
    match (&d.verdict, named) {
        (Verdict::NoSignificantDiscrepancy, _) => {
            format!("no significant discrepancy: the model as written explains the {} data to the noise", ranked_on(d))
        }
        (Verdict::Explained, Some(best)) => format!(
            "cause: {} ({}, {:+.0} %)",
            named_cause(d, best),
            gain(best),
            100.0 * (best.holdout_chi2 / d.base.holdout_chi2 - 1.0),
        ),
        (Verdict::PartlyExplained, Some(best)) => format!(
            "partly explained by {} ({}); an unexplained residual above the noise remains",
            named_cause(d, best),
            gain(best)
        ),
        (Verdict::OutsidePlausibleRange, _) => match d.ranked.iter().find(|t| t.at_bound()) {
            Some(closest) => format!(
                "no cause within the catalog's plausible ranges: the closest, {}, needs {} ({}); \
                 the effect is likely outside the catalog, or a nominal value of the model is \
                 far off",
                cause_at(closest),
                closest
                    .parameters
                    .iter()
                    .filter(|p| p.3.is_nan())
                    .map(fitted_text)
                    .collect::<Vec<_>>()
                    .join(", "),
                gain(closest)
            ),
            None => "no cause within the catalog's plausible ranges".to_string(),
        },
        (Verdict::Flagged, _) => format!(
            "flagged ({}): the data show what no parameter of the model can produce, so no \
             cause is named; the fits are reported with the flag{}",
            d.screening.as_ref().map_or(String::new(), flag_kinds),
            match d.ranked.first() {
                Some(best) => format!(" (best fit: {}, {})", cause_at(best), gain(best)),
                None => String::new(),
            }
        ),
        _ => {
            "unexplained: the residual is above the noise and no candidate explains it".to_string()
        }
    }
}

/// `CAUSE at LOCATION`; a pair of causes (`A + B` at `a; b`) as `A at a, and B at b`, or
/// `A at a and at b` when both are the same cause.
pub fn cause_at(t: &Trial) -> String {
    let causes: Vec<&str> = t.cause.split(" + ").collect();
    let locations: Vec<&str> = t.location.split("; ").collect();
    if causes.len() != locations.len() || causes.len() == 1 {
        return format!("{} at {}", t.cause, t.location);
    }
    if causes.iter().all(|c| *c == causes[0]) {
        return format!("{} at {}", causes[0], locations.join(" and at "));
    }
    causes
        .iter()
        .zip(&locations)
        .map(|(cause, location)| format!("{cause} at {location}"))
        .collect::<Vec<_>>()
        .join(", and ")
}

/// The named cause: `best` alone, or, when the data support several about equally, all of
/// them as a tie (`X at one of a, b, c`), the simplest first.
fn named_cause(d: &Diagnosis, best: &Trial) -> String {
    // A pair of causes is named as it is; the tie is among single causes.
    if d.tied <= 1 || d.combined.is_some() {
        return cause_at(best);
    }
    let tied = &d.ranked[..d.tied];
    let alternatives = if tied.iter().all(|t| t.cause == best.cause) {
        let places: Vec<&str> = tied.iter().map(|t| t.location.as_str()).collect();
        format!("{} at one of {}", best.cause, places.join(", "))
    } else {
        let each: Vec<String> = tied.iter().map(cause_at).collect();
        format!("one of {}", each.join("; "))
    };
    let separating = match d.separations.first() {
        Some(best) if best.chi2 >= SEPARATES => format!(
            "data that would separate them: {} (χ² {:.0} between the closest two)",
            best.probe, best.chi2
        ),
        Some(best) => format!(
            "no standard test separates them at its usual noise (the best, {}, gives χ² {:.1} \
             between the closest two)",
            best.probe, best.chi2
        ),
        None => "a measurement that tells them apart is needed: another output, drive or \
                 frequency band"
            .to_string(),
    };
    format!("{alternatives} — not separable by these data; {separating}")
}

/// `NAME = value ± σ (nominal …)` for a fitted parameter of a trial; a fit that ran into a
/// bound has no standard error (NaN), and says where it stopped instead; a parameter held
/// fixed (standard error 0: the data do not determine it) says so.
pub fn fitted_text((name, nominal, value, se): &(String, f64, f64, f64)) -> String {
    if *se == 0.0 {
        format!("{name} held at its starting value {value:.4e} (not determined by these data)")
    } else if se.is_nan() {
        format!(
            "{name} = {value:.4e} at a bound of its plausible range, no standard error \
             (nominal {nominal:.4e})"
        )
    } else {
        format!("{name} = {value:.4e} ± {se:.1e} (nominal {nominal:.4e})")
    }
}

/// `diagnosis.json` (and the Python package's `diagnose`): every trial with its fitted values,
/// the verdict, the features and the held-out residuals — the facts of the terminal text, for
/// scripts.
pub fn diagnosis_json(
    holdout: &str,
    data: &Path,
    experiment: &Experiment,
    d: &Diagnosis,
    verdict: &str,
    comparison: &Comparison,
) -> serde_json::Value {
    let trial = |t: &Trial| {
        json!({
            "cause": t.cause, "location": t.location,
            "train_chi2": t.train_chi2, "holdout_chi2": finite_or_null(t.holdout_chi2),
            "delta_aicc": finite_or_null(t.aicc - d.base.aicc),
            "parameters": t.parameters.iter().map(|(n, nominal, v, se)| json!({
                "name": n, "nominal": nominal, "value": v, "standard_error": finite_or_null(*se),
            })).collect::<Vec<_>>(),
            "error": t.error,
        })
    };
    let (flags, screened) = screening_json(d.screening.as_ref());
    json!({
        "experiment": experiment.title,
        "data": data.display().to_string(),
        "flags": flags,
        "screening": screened,
        "holdout": holdout,
        "verdict": d.verdict,
        "summary": verdict,
        "tied_with_best": d.tied.saturating_sub(1),
        "separations": d.separations,
        "base": trial(&d.base),
        "ranked": d.ranked.iter().map(trial).collect::<Vec<_>>(),
        "combined": d.combined.as_ref().map(trial),
        "second_round": d.second_round.iter().map(trial).collect::<Vec<_>>(),
        "inert": d.inert.iter().map(trial).collect::<Vec<_>>(),
        "best": comparison.best_label,
        "features": comparison.features_json(),
        "residual_rms_held_out": comparison.rms_json(),
    })
}

/// `fit.json` (and the Python package's `fit`): the fitted parameters with their standard
/// errors and status, the stop reason, the cost and the residual RMS per series before and
/// after, and the screening's flags.
pub fn fit_json(
    experiment: &Experiment,
    data: &Path,
    report: &crate::diagnose::fit::FitReport,
    screening: Option<&Screening>,
) -> serde_json::Value {
    let r = &report.result;
    let (flags, screened) = screening_json(screening);
    json!({
        "experiment": experiment.title,
        "data": data.display().to_string(),
        "flags": flags,
        "screening": screened,
        "converged": r.converged,
        "reason": r.reason,
        "parameters": r.names.iter().enumerate().map(|(k, name)| json!({
            "name": name,
            "value": r.params[k],
            "standard_error": finite_or_null(r.standard_errors[k]),
            "status": r.status[k],
        })).collect::<Vec<_>>(),
        "cost": r.cost,
        "degrees_of_freedom": r.degrees_of_freedom,
        "residual_rms": report.residuals.iter().map(|s| json!({
            "series": s.series, "before": s.before, "after": s.after,
        })).collect::<Vec<_>>(),
    })
}

/// A JSON number, or `null` for NaN and infinities (which JSON cannot hold).
pub fn finite_or_null(x: f64) -> serde_json::Value {
    if x.is_finite() {
        json!(x)
    } else {
        serde_json::Value::Null
    }
}

/// Where a diagnosis came from and where its page goes.
pub struct PageSources<'a> {
    pub experiment: &'a Path,
    pub data: &'a Path,
    /// The hold-out rule as the user wrote it (`every:3`).
    pub holdout: &'a str,
    pub out_dir: &'a Path,
}

/// `diagnosis.html`, in the style of `mech report`: the verdict, the ranking, the inert
/// candidates, and per measured series the data with the base model and the best candidate.
/// Returns the page's files, the page last (the plots first).
pub fn diagnosis_page(
    sources: &PageSources,
    experiment: &Experiment,
    d: &Diagnosis,
    verdict: &str,
    comparison: &Comparison,
    json_path: PathBuf,
) -> Result<Vec<File>, Error> {
    let per = |chi2: f64| chi2 / d.ranking_values() as f64;
    let mut ranking = Table::new(
        "Candidates, best first (χ² on the fitted values; χ² per value on the held-out ones)",
        &[
            "cause",
            "where",
            "χ² fit",
            "χ²/value held out",
            "ΔAICc",
            "fitted",
        ],
    );
    for t in std::iter::once(&d.base)
        .chain(&d.ranked)
        .chain(&d.second_round)
    {
        let fitted: Vec<String> = t.parameters.iter().map(fitted_text).collect();
        ranking.row(vec![
            t.cause.clone(),
            t.location.clone(),
            format!("{:.1}", t.train_chi2),
            format!("{:.2}", per(t.holdout_chi2)),
            format!("{:.1}", t.aicc - d.base.aicc),
            fitted.join(", "),
        ]);
    }
    let mut outcome = Outcome {
        name: "diagnosis".into(),
        source: Some(sources.experiment.display().to_string()),
        title: experiment.title.to_string(),
        method: format!(
            "{} values fitted, {} held out ({}); a model explains the data to the noise when \
             its χ² per held-out value is at most {:.2}. Verdict: {verdict}.",
            d.train_values, d.holdout_values, sources.holdout, d.noise_band
        ),
        tables: vec![ranking, comparison.features_table(), comparison.rms_table()],
        files: vec![sources.data.to_path_buf(), json_path],
        ..Outcome::default()
    };
    if !d.separations.is_empty() {
        // Right after the ranking, whose tie it is about.
        outcome.tables.insert(1, separations_table(d));
    }
    if let Some(screening) = &d.screening {
        // First, above the ranking: what the fits cannot be trusted for.
        outcome.tables.insert(0, flags_table(screening));
        outcome.notes.push(screening.summary());
    }
    if !d.inert.is_empty() {
        outcome.tables.extend(inert_tables(d));
    }
    let mut curves = vec![("base model".to_string(), d.base.predicted.as_slice())];
    if let Some(best) = d.ranked.first() {
        let label = cause_at(best);
        curves.push((label, best.predicted.as_slice()));
    }
    let plots = overlay_plots(
        sources.out_dir,
        "diagnosis",
        experiment,
        &d.observations,
        &curves,
    )?;
    for plot in plots {
        outcome.add_plot(plot);
    }
    let page = render_page(
        "mech diagnose: what the model gets wrong",
        "Every candidate cause of the catalog is fitted to the rows not held out and ranked by \
         its χ² on the held-out rows (docs/diagnose.md).",
        &format!("Data: <code>{}</code>", sources.data.display()),
        std::slice::from_ref(&outcome),
        sources.out_dir,
    )?;
    let path = sources.out_dir.join("diagnosis.html");
    outcome.rendered.push(File::new(path, page));
    Ok(outcome.rendered)
}

/// The screening's flags, or its summary when nothing was flagged.
fn flags_table(screening: &Screening) -> Table {
    let mut flags = Table::new(
        "Screening before fitting: what no parameter of the model can produce",
        &["flag", "finding"],
    );
    for flag in &screening.flags {
        flags.row(vec![flag.kind.to_string(), flag.message.clone()]);
    }
    if screening.flags.is_empty() {
        flags.row(vec!["none".into(), screening.summary()]);
    }
    flags
}

/// The standard tests scored on how well they would tell the tied causes apart, best first
/// ([`crate::diagnose::separate`]).
fn separations_table(d: &Diagnosis) -> Table {
    let mut table = Table::new(
        &format!(
            "Tests that would tell the {} tied causes apart (χ² between the predictions of the \
             closest two; at least {SEPARATES:.0} separates them)",
            d.tied
        ),
        &["test (noise assumed)", "χ² closest two", "separates"],
    );
    for s in &d.separations {
        table.row(vec![
            s.probe.clone(),
            format!("{:.1}", s.chi2),
            if s.chi2 >= SEPARATES { "yes" } else { "no" }.into(),
        ]);
    }
    table
}

/// The candidates that could not change the response, and those whose fit failed (each
/// table only if it has rows).
fn inert_tables(d: &Diagnosis) -> Vec<Table> {
    let (failed, inert) = inert_and_failed(d);
    let mut tables = Vec::new();
    if !inert.is_empty() {
        let mut table = Table::new(
            "Inert: cannot change the response beyond the noise",
            &["cause", "where"],
        );
        for t in inert {
            table.row(vec![t.cause.clone(), t.location.clone()]);
        }
        tables.push(table);
    }
    if !failed.is_empty() {
        let mut table = Table::new(
            "Failed: the fit stopped with an error",
            &["cause", "where", "error"],
        );
        for t in failed {
            let error = t.error.clone().unwrap_or_default();
            table.row(vec![t.cause.clone(), t.location.clone(), error]);
        }
        tables.push(table);
    }
    tables
}

/// What the data show against what the base model and the best candidate predict: the
/// features of the response ([`crate::diagnose::features`]), each read the same way off the
/// data and off both predictions, and the residual RMS per series on the held-out values.
pub struct Comparison {
    /// `cause at location` of the best candidate (the combined pair when there is one).
    pub best_label: Option<String>,
    /// Per feature: the data's, the base model's, the best candidate's.
    features: Vec<(Feature, Feature, Option<Feature>)>,
    /// Residual RMS per series on the ranking values: base model (`before`) and best
    /// (`after`).
    rms: Vec<SeriesResidual>,
    /// The values the RMS is over ([`ranked_on`]).
    rms_on: &'static str,
}

impl Comparison {
    pub fn new(experiment: &Experiment, d: &Diagnosis) -> Comparison {
        let best = d
            .combined
            .as_ref()
            .or(d.ranked.first())
            .filter(|t| t.predicted.len() == d.observations.values.len());
        let of = |values: &[f64]| features(experiment, &d.observations, values);
        let (data, base) = (of(&d.observations.values), of(&d.base.predicted));
        let best_features = best.map(|t| of(&t.predicted));
        let features = data
            .into_iter()
            .zip(base)
            .enumerate()
            .map(|(k, (data, base))| {
                let best = best_features.as_ref().and_then(|f| f.get(k).cloned());
                (data, base, best)
            })
            .collect();
        // The values that rank: the held-out ones, or all when nothing is held out.
        let held_out = |k: usize| d.holdout_values == 0 || !d.train.get(k).copied().unwrap_or(true);
        let rms = match best {
            Some(best) => series_rms(
                &d.observations,
                &d.base.predicted,
                &best.predicted,
                &held_out,
            ),
            // No candidate: the base model's RMS alone (`after` NaN, shown as `-`).
            None => series_rms(
                &d.observations,
                &d.base.predicted,
                &d.base.predicted,
                &held_out,
            )
            .into_iter()
            .map(|r| SeriesResidual {
                after: f64::NAN,
                ..r
            })
            .collect(),
        };
        Comparison {
            best_label: best.map(cause_at),
            features,
            rms,
            rms_on: ranked_on(d),
        }
    }

    /// `value (+x.x %)`: a model's feature and its deviation from the data's.
    fn against(model: &Feature, data: &Feature) -> String {
        match (model.value, data.value) {
            (Some(m), Some(v)) if v != 0.0 => {
                format!("{} ({:+.1} %)", model.display(), 100.0 * (m / v - 1.0))
            }
            _ => model.display(),
        }
    }

    fn rows(&self) -> Vec<Vec<String>> {
        self.features
            .iter()
            .map(|(data, base, best)| {
                vec![
                    data.label(),
                    data.display(),
                    Self::against(base, data),
                    best.as_ref()
                        .map_or("-".into(), |best| Self::against(best, data)),
                ]
            })
            .collect()
    }

    /// The comparison as terminal text (empty without features).
    pub fn text(&self) -> String {
        if self.features.is_empty() {
            return String::new();
        }
        let mut text = format!(
            "\nfeatures, read the same way off the data and each model (best: {}):\n",
            self.best_label.as_deref().unwrap_or("none")
        );
        text += &format!(
            "  {:<36} {:>12} {:>22} {:>22}\n",
            "feature", "data", "base model", "best"
        );
        for row in self.rows() {
            text += &format!(
                "  {:<36} {:>12} {:>22} {:>22}\n",
                row[0], row[1], row[2], row[3]
            );
        }
        text += &format!(
            "residual RMS on the {} values (SI units; ln|H| relative):\n",
            self.rms_on
        );
        for r in &self.rms {
            let [before, after, change] = Self::rms_cells(r);
            text += &format!(
                "  {:<36} base {before}  best {after}  ({change})\n",
                r.series
            );
        }
        text
    }

    /// Base RMS, best RMS and the change, as shown (`-` without a best candidate).
    fn rms_cells(r: &SeriesResidual) -> [String; 3] {
        if r.after.is_nan() {
            return [format!("{:.4e}", r.before), "-".into(), "-".into()];
        }
        [
            format!("{:.4e}", r.before),
            format!("{:.4e}", r.after),
            format!("{:+.1} %", 100.0 * (r.after / r.before - 1.0)),
        ]
    }

    pub fn features_json(&self) -> serde_json::Value {
        let value = |f: &Feature| f.value.map_or(serde_json::Value::Null, |v| json!(v));
        self.features
            .iter()
            .map(|(data, base, best)| {
                json!({
                    "name": data.name,
                    "display_unit": data.unit,
                    "display_scale": data.scale,
                    "data": value(data),
                    "base": value(base),
                    "best": best.as_ref().map_or(serde_json::Value::Null, value),
                })
            })
            .collect()
    }

    pub fn rms_json(&self) -> serde_json::Value {
        self.rms
            .iter()
            .map(|r| json!({"series": r.series, "base": r.before, "best": finite_or_null(r.after)}))
            .collect()
    }

    fn features_table(&self) -> Table {
        let mut table = Table::new(
            "Features, read the same way off the data and each model (deviation from the data)",
            &["feature", "data", "base model", "best candidate"],
        );
        for row in self.rows() {
            table.row(row);
        }
        table
    }

    fn rms_table(&self) -> Table {
        let title = format!(
            "Residual RMS on the {} values (SI units; ln|H| relative)",
            self.rms_on
        );
        let mut table = Table::new(
            &title,
            &["series", "base model", "best candidate", "change"],
        );
        for r in &self.rms {
            let [before, after, change] = Self::rms_cells(r);
            table.row(vec![r.series.clone(), before, after, change]);
        }
        table
    }
}

#[cfg(test)]
mod tests {
    use super::fitted_text;

    #[test]
    fn a_parameter_at_a_bound_has_no_standard_error_in_the_text() {
        let fitted = ("k".to_string(), 1.0, 4.0, f64::NAN);
        assert_eq!(
            fitted_text(&fitted),
            "k = 4.0000e0 at a bound of its plausible range, no standard error (nominal 1.0000e0)"
        );
        let fitted = ("k".to_string(), 1.0, 1.2, 0.05);
        assert_eq!(
            fitted_text(&fitted),
            "k = 1.2000e0 ± 5.0e-2 (nominal 1.0000e0)"
        );
    }
}
