//! `mech fit`: the command around [`super::fit`] — load the experiment file and the data,
//! fit, print the table, and write `fit.json` (the same facts for scripts), `fit.csv`
//! (measured, before, after per value) and one plot per measured series to the output folder.

use std::path::PathBuf;

use clap::Args;
use serde_json::json;

use super::data::MeasuredData;
use super::experiment::{self, Experiment};
use super::features::{features, series_rms, Feature, SeriesResidual};
use super::fit::{fit, parameters, FitReport, FitRequest};
use super::pendulum::{screen_experiment, Screening};
use crate::experiments::leg::Leg;
use crate::{output, plot};

#[derive(Args, Clone, Debug)]
pub struct FitArgs {
    /// The diagnosis experiment file (TOML, see docs/diagnose.md).
    #[arg(long)]
    pub experiment: PathBuf,
    /// The measured data (CSV with `name [unit]` headers).
    #[arg(long)]
    pub data: PathBuf,
    /// A parameter to fit: `NAME` (bounds ×/÷ 10 of a positive value) or `NAME=LO..HI UNIT`.
    /// Repeat for several.
    #[arg(long = "fit", required = true)]
    pub fit: Vec<String>,
    /// Output folder for fit.json, fit.csv and the plots (`--out` also works).
    #[arg(long, visible_alias = "out", default_value = "out/fit")]
    pub out_dir: PathBuf,
}

pub fn fit_command(args: &FitArgs) -> Result<(), String> {
    let experiment = experiment::load(&args.experiment)?;
    let data = MeasuredData::load(&args.data).map_err(|e| e.to_string())?;
    let mut leg = Leg::open_any(&experiment.model_spec(), &[])?;
    let requests = args
        .fit
        .iter()
        .map(|text| FitRequest::parse(text))
        .collect::<Result<Vec<_>, _>>()?;
    let fitted = parameters(&leg, &requests)?;
    // Checked before the screening, which reads the same columns.
    experiment.observations(&leg, &data)?;
    let screening = screen_experiment(&experiment, &data)?;
    println!(
        "{}: {} rows of `{}`, fitting {}",
        experiment.title(),
        data.rows,
        args.data.display(),
        requests
            .iter()
            .map(|(r, _)| r.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    );
    print_screening(screening.as_ref());
    let report = fit(&experiment, &data, &mut leg, &fitted)
        .map_err(|e| format!("fit to `{}`: {e}", args.data.display()))?;
    println!("\n{}", report.result);
    println!("residual RMS per series (SI units; ln|H| relative):");
    for s in &report.residuals {
        println!(
            "  {:<10} before {:.4e}  after {:.4e}  ({:+.1} %)",
            s.series,
            s.before,
            s.after,
            100.0 * (s.after / s.before - 1.0)
        );
    }
    if let Some(s) = screening.as_ref().filter(|s| !s.flags.is_empty()) {
        println!(
            "\nthe fit above is reported with {} flag(s): {}",
            s.flags.len(),
            flag_kinds(s)
        );
    }
    write_outputs(args, &experiment, &report, screening.as_ref())
}

/// The screening's summary and, prominently, its flags (nothing for unscreened kinds).
fn print_screening(screening: Option<&Screening>) {
    let Some(s) = screening else { return };
    println!("{}", s.summary());
    for flag in &s.flags {
        println!("\n  !! {}", flag.message);
    }
}

fn flag_kinds(s: &Screening) -> String {
    s.flags
        .iter()
        .map(|f| f.kind)
        .collect::<Vec<_>>()
        .join(", ")
}

/// `flags` and `screening` entries for the JSON summaries.
fn screening_json(screening: Option<&Screening>) -> (serde_json::Value, serde_json::Value) {
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

fn write_outputs(
    args: &FitArgs,
    experiment: &Experiment,
    report: &FitReport,
    screening: Option<&Screening>,
) -> Result<(), String> {
    let dir = &args.out_dir;
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let r = &report.result;
    let (flags, screened) = screening_json(screening);
    let summary = json!({
        "experiment": experiment.title(),
        "data": args.data.display().to_string(),
        "flags": flags,
        "screening": screened,
        "converged": r.converged,
        "reason": format!("{:?}", r.reason),
        "parameters": r.names.iter().enumerate().map(|(k, name)| json!({
            "name": name,
            "value": r.params[k],
            "standard_error": finite_or_null(r.standard_errors[k]),
            "status": format!("{:?}", r.status[k]),
        })).collect::<Vec<_>>(),
        "cost": r.cost,
        "degrees_of_freedom": r.degrees_of_freedom,
        "residual_rms": report.residuals.iter().map(|s| json!({
            "series": s.series, "before": s.before, "after": s.after,
        })).collect::<Vec<_>>(),
    });
    let text = serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?;
    let json_path = dir.join("fit.json");
    output::write_atomic(&json_path, text.as_bytes())
        .map_err(|e| format!("cannot write {}: {e}", json_path.display()))?;

    let obs = &report.observations;
    let names = obs.series_names();
    let rows: Vec<Vec<f64>> = (0..obs.values.len())
        .map(|k| {
            let series = names.iter().position(|s| *s == obs.series[k]).unwrap_or(0);
            vec![
                series as f64,
                obs.abscissa[k],
                obs.values[k],
                report.before[k],
                report.after[k],
            ]
        })
        .collect();
    let header: Vec<String> = ["series", "abscissa", "measured", "before", "after"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let csv_path = dir.join("fit.csv");
    output::write_csv(&csv_path, &header, &rows)
        .map_err(|e| format!("cannot write {}: {e}", csv_path.display()))?;
    let curves = [
        ("model before".to_string(), report.before.as_slice()),
        ("model after fit".to_string(), report.after.as_slice()),
    ];
    for path in overlay_plots(dir, "fit", experiment, obs, &curves)? {
        println!("wrote {}", path.display());
    }
    println!("wrote {} and {}", json_path.display(), csv_path.display());
    Ok(())
}

/// One plot per measured series (`PREFIX_SERIES.svg` in `dir`): the data and each of
/// `curves` (a label and a prediction of every observed value).
fn overlay_plots(
    dir: &std::path::Path,
    prefix: &str,
    experiment: &Experiment,
    obs: &super::experiment::Observations,
    curves: &[(String, &[f64])],
) -> Result<Vec<PathBuf>, String> {
    let log_x = matches!(experiment, Experiment::FrequencyResponse(_));
    // Axis labels and the SI → plotted unit factors.
    let (x_label, x_scale, y_unit, y_scale) = match experiment {
        Experiment::FrequencyResponse(_) => ("frequency [Hz]", 1.0, "", 1.0),
        Experiment::QuasiStatic(_) => ("data row", 1.0, " [m]", 1.0),
        Experiment::ForceDeflection(_) => ("sensor distance [µm]", 1e6, " [mN]", 1e3),
        Experiment::Pendulum(_) => ("time [s]", 1.0, " [rad]", 1.0),
    };
    let mut paths = Vec::new();
    for name in obs.series_names() {
        let pick = |values: &[f64]| -> (Vec<f64>, Vec<f64>) {
            (0..values.len().min(obs.series.len()))
                .filter(|&k| obs.series[k] == name)
                .map(|k| (obs.abscissa[k] * x_scale, values[k] * y_scale))
                .unzip()
        };
        let lines: Vec<(String, Vec<f64>, Vec<f64>)> =
            std::iter::once(("measured".to_string(), obs.values.as_slice()))
                .chain(
                    curves
                        .iter()
                        .map(|(label, values)| (label.clone(), *values)),
                )
                .map(|(label, values)| {
                    let (x, y) = pick(values);
                    (label, x, y)
                })
                .collect();
        let path = dir.join(format!("{prefix}_{}.svg", name.replace(['|', '.'], "_")));
        let title = format!("{}: {name}", experiment.title());
        let y_label = format!("{name}{y_unit}");
        plot::plot_xy(&path, &title, x_label, &y_label, &lines, log_x)
            .map_err(|e| e.to_string())?;
        paths.push(path);
    }
    Ok(paths)
}

/// `NAME = value ± σ (nominal …)` for a fitted parameter of a trial.
fn fitted_text((name, nominal, value, se): &(String, f64, f64, f64)) -> String {
    format!("{name} = {value:.4e} ± {se:.1e} (nominal {nominal:.4e})")
}

/// `; the data support equally: …` when several candidates tie with the best.
fn tied_text(d: &super::candidates::Diagnosis) -> String {
    if d.tied <= 1 {
        return String::new();
    }
    let others: Vec<String> = d.ranked[1..d.tied]
        .iter()
        .map(|t| format!("{} at {}", t.cause, t.location))
        .collect();
    format!(
        "; these data support equally well: {} (a measurement that separates them is needed)",
        others.join(", ")
    )
}

fn finite_or_null(x: f64) -> serde_json::Value {
    if x.is_finite() {
        json!(x)
    } else {
        serde_json::Value::Null
    }
}

#[derive(Args, Clone, Debug)]
pub struct DiagnoseArgs {
    /// The model (`.mech`); default: the experiment file's `model`.
    pub model: Option<PathBuf>,
    /// The diagnosis experiment file (TOML, with the measurement noise).
    #[arg(long)]
    pub experiment: PathBuf,
    /// The measured data (CSV with `name [unit]` headers).
    #[arg(long)]
    pub data: PathBuf,
    /// Parameters the user lets vary in every model (as `mech fit --fit`).
    #[arg(long = "fit")]
    pub fit: Vec<String>,
    /// Rows held out of every fit and used to rank: `every:N` (default `every:3`) or `last:P%`.
    #[arg(long, default_value = "every:3")]
    pub holdout: String,
    /// Try only the catalog causes whose name contains this (repeatable), e.g. `--cause twist
    /// --cause "loss factor"`; default: the whole catalog.
    #[arg(long = "cause")]
    pub causes: Vec<String>,
    /// Output folder for diagnosis.html, diagnosis.json and the plots (`--out` also works).
    #[arg(long, visible_alias = "out", default_value = "out/diagnose")]
    pub out_dir: PathBuf,
}

pub fn diagnose_command(args: &DiagnoseArgs) -> Result<(), String> {
    use super::candidates::{diagnose_causes, Holdout, Verdict};
    let mut experiment = experiment::load(&args.experiment)?;
    if let Some(model) = &args.model {
        experiment.set_model(model.clone());
    }
    let data = MeasuredData::load(&args.data).map_err(|e| e.to_string())?;
    let holdout = Holdout::parse(&args.holdout)?;
    let d = diagnose_causes(&experiment, &data, &args.fit, holdout, &args.causes)?;
    println!(
        "{}: {} values fitted, {} held out ({}); noise band: held-out χ²/value ≤ {:.2}",
        experiment.title(),
        d.train_values,
        d.holdout_values,
        args.holdout,
        d.noise_band
    );
    print_screening(d.screening.as_ref());
    let per = |chi2: f64| chi2 / d.holdout_values as f64;
    println!(
        "\n{:<36} {:<16} {:>12} {:>12} {:>10}  fitted",
        "cause", "where", "χ² fit", "χ²/value out", "ΔAICc"
    );
    let line = |t: &super::candidates::Trial| {
        let fitted: Vec<String> = t.parameters.iter().map(fitted_text).collect();
        println!(
            "{:<36} {:<16} {:>12.1} {:>12.2} {:>10.1}  {}",
            t.cause,
            t.location,
            t.train_chi2,
            per(t.holdout_chi2),
            t.aicc - d.base.aicc,
            fitted.join(", ")
        );
    };
    line(&d.base);
    for t in &d.ranked {
        line(t);
    }
    if !d.second_round.is_empty() {
        println!(
            "\nthe best leaves a residual above the noise; fitted together with each other candidate:"
        );
        for t in &d.second_round {
            line(t);
        }
    }
    if !d.inert.is_empty() {
        println!("\ninert (cannot change the response, or failed):");
        for t in &d.inert {
            println!(
                "  {} at {}{}",
                t.cause,
                t.location,
                t.error.as_ref().map_or(String::new(), |e| format!(": {e}"))
            );
        }
    }
    let verdict = match (&d.verdict, d.combined.as_ref().or(d.ranked.first())) {
        (Verdict::NoSignificantDiscrepancy, _) => {
            "no significant discrepancy: the model as written explains the held-out data to the noise".to_string()
        }
        (Verdict::Explained, Some(best)) => format!(
            "cause: {} at {} (held-out χ²/value {:.2} → {:.2}, {:+.0} %){}",
            best.cause,
            best.location,
            per(d.base.holdout_chi2),
            per(best.holdout_chi2),
            100.0 * (best.holdout_chi2 / d.base.holdout_chi2 - 1.0),
            tied_text(&d)
        ),
        (Verdict::PartlyExplained, Some(best)) => format!(
            "partly explained by {} at {} (held-out χ²/value {:.2} → {:.2}); an unexplained \
             residual above the noise remains",
            best.cause,
            best.location,
            per(d.base.holdout_chi2),
            per(best.holdout_chi2)
        ),
        (Verdict::Flagged, _) => format!(
            "flagged ({}): the data show what no parameter of the model can produce, so no \
             cause is named; the fits are reported with the flag{}",
            d.screening.as_ref().map_or(String::new(), flag_kinds),
            match d.ranked.first() {
                Some(best) => format!(
                    " (best fit: {} at {}, held-out χ²/value {:.2} → {:.2})",
                    best.cause,
                    best.location,
                    per(d.base.holdout_chi2),
                    per(best.holdout_chi2)
                ),
                None => String::new(),
            }
        ),
        _ => "unexplained: the residual is above the noise and no candidate explains it".to_string(),
    };
    let comparison = Comparison::new(&experiment, &d);
    comparison.print();
    println!("\nverdict: {verdict}");
    std::fs::create_dir_all(&args.out_dir)
        .map_err(|e| format!("cannot create {}: {e}", args.out_dir.display()))?;
    let trial = |t: &super::candidates::Trial| {
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
    let summary = json!({
        "experiment": experiment.title(),
        "data": args.data.display().to_string(),
        "flags": flags,
        "screening": screened,
        "holdout": args.holdout,
        "verdict": format!("{:?}", d.verdict),
        "summary": verdict,
        "tied_with_best": d.tied.saturating_sub(1),
        "base": trial(&d.base),
        "ranked": d.ranked.iter().map(trial).collect::<Vec<_>>(),
        "combined": d.combined.as_ref().map(trial),
        "second_round": d.second_round.iter().map(trial).collect::<Vec<_>>(),
        "inert": d.inert.iter().map(trial).collect::<Vec<_>>(),
        "best": comparison.best_label,
        "features": comparison.features_json(),
        "residual_rms_held_out": comparison.rms_json(),
    });
    let path = args.out_dir.join("diagnosis.json");
    let text = serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?;
    output::write_atomic(&path, text.as_bytes())
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let html = diagnosis_page(args, &experiment, &d, &verdict, &comparison, path)?;
    println!("wrote {} and its data", html.display());
    Ok(())
}

/// `diagnosis.html`, in the style of `mech report`: the verdict, the ranking, the inert
/// candidates, and per measured series the data with the base model and the best candidate.
fn diagnosis_page(
    args: &DiagnoseArgs,
    experiment: &Experiment,
    d: &super::candidates::Diagnosis,
    verdict: &str,
    comparison: &Comparison,
    json_path: PathBuf,
) -> Result<PathBuf, String> {
    use crate::experiments::{report, Outcome, Table};
    let per = |chi2: f64| chi2 / d.holdout_values as f64;
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
        source: Some(args.experiment.display().to_string()),
        title: experiment.title().to_string(),
        method: format!(
            "{} values fitted, {} held out ({}); a model explains the data to the noise when \
             its χ² per held-out value is at most {:.2}. Verdict: {verdict}.",
            d.train_values, d.holdout_values, args.holdout, d.noise_band
        ),
        tables: vec![ranking, comparison.features_table(), comparison.rms_table()],
        files: vec![args.data.clone(), json_path],
        ..Outcome::default()
    };
    if let Some(s) = &d.screening {
        // First, above the ranking: what the fits cannot be trusted for.
        let mut flags = Table::new(
            "Screening before fitting: what no parameter of the model can produce",
            &["flag", "finding"],
        );
        for flag in &s.flags {
            flags.row(vec![flag.kind.to_string(), flag.message.clone()]);
        }
        if s.flags.is_empty() {
            flags.row(vec!["none".into(), s.summary()]);
        }
        outcome.tables.insert(0, flags);
        outcome.notes.push(s.summary());
    }
    if !d.inert.is_empty() {
        let mut inert = Table::new(
            "Inert: cannot change the response beyond the noise, or the fit failed",
            &["cause", "where", "note"],
        );
        for t in &d.inert {
            inert.row(vec![
                t.cause.clone(),
                t.location.clone(),
                t.error.clone().unwrap_or_default(),
            ]);
        }
        outcome.tables.push(inert);
    }
    let mut curves = vec![("base model".to_string(), d.base.predicted.as_slice())];
    if let Some(best) = d.ranked.first() {
        let label = format!("{} at {}", best.cause, best.location);
        curves.push((label, best.predicted.as_slice()));
    }
    outcome.plots = overlay_plots(
        &args.out_dir,
        "diagnosis",
        experiment,
        &d.observations,
        &curves,
    )?;
    let page = report::render_page(
        "mech diagnose: what the model gets wrong",
        "Every candidate cause of the catalog is fitted to the rows not held out and ranked by \
         its χ² on the held-out rows (docs/diagnose.md).",
        &format!("Data: <code>{}</code>", args.data.display()),
        &[outcome],
        &args.out_dir,
    )?;
    let path = args.out_dir.join("diagnosis.html");
    output::write_atomic(&path, page.as_bytes())
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(path)
}

/// What the data show against what the base model and the best candidate predict: the
/// features of the response ([`super::features`]), each read the same way off the data and
/// off both predictions, and the residual RMS per series on the held-out values.
struct Comparison {
    /// `cause at location` of the best candidate (the combined pair when there is one).
    best_label: Option<String>,
    /// Per feature: the data's, the base model's, the best candidate's.
    features: Vec<(Feature, Feature, Option<Feature>)>,
    /// Held-out residual RMS per series: base model (`before`) and best (`after`).
    rms: Vec<SeriesResidual>,
}

impl Comparison {
    fn new(experiment: &Experiment, d: &super::candidates::Diagnosis) -> Comparison {
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
        let held_out = |k: usize| !d.train.get(k).copied().unwrap_or(true);
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
            best_label: best.map(|t| format!("{} at {}", t.cause, t.location)),
            features,
            rms,
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

    fn print(&self) {
        if self.features.is_empty() {
            return;
        }
        println!(
            "\nfeatures, read the same way off the data and each model (best: {}):",
            self.best_label.as_deref().unwrap_or("none")
        );
        println!(
            "  {:<36} {:>12} {:>22} {:>22}",
            "feature", "data", "base model", "best"
        );
        for row in self.rows() {
            println!(
                "  {:<36} {:>12} {:>22} {:>22}",
                row[0], row[1], row[2], row[3]
            );
        }
        println!("residual RMS on the held-out values (SI units; ln|H| relative):");
        for r in &self.rms {
            let [before, after, change] = Self::rms_cells(r);
            println!("  {:<36} base {before}  best {after}  ({change})", r.series);
        }
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

    fn features_json(&self) -> serde_json::Value {
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

    fn rms_json(&self) -> serde_json::Value {
        self.rms
            .iter()
            .map(|r| json!({"series": r.series, "base": r.before, "best": finite_or_null(r.after)}))
            .collect()
    }

    fn features_table(&self) -> crate::experiments::Table {
        let mut table = crate::experiments::Table::new(
            "Features, read the same way off the data and each model (deviation from the data)",
            &["feature", "data", "base model", "best candidate"],
        );
        for row in self.rows() {
            table.row(row);
        }
        table
    }

    fn rms_table(&self) -> crate::experiments::Table {
        let mut table = crate::experiments::Table::new(
            "Residual RMS on the held-out values (SI units; ln|H| relative)",
            &["series", "base model", "best candidate", "change"],
        );
        for r in &self.rms {
            let [before, after, change] = Self::rms_cells(r);
            table.row(vec![r.series.clone(), before, after, change]);
        }
        table
    }
}
