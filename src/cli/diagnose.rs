//! `mech diagnose [MODEL] --experiment E --data D`: find what the model gets wrong — fit
//! every catalog cause, rank on held-out data, and name the cause (or say there is none, or
//! that none explains it).
//!
//! Consumes: a diagnosis experiment file, measured data (CSV), optional extra parameters and
//! cause filters. Produces: the ranking and verdict on stdout, and `diagnosis.json`,
//! `diagnosis.html` and plots in the output folder.

use super::Error;
use std::path::PathBuf;

use clap::Args;
use serde_json::json;

use crate::diagnose::candidates::{diagnose_causes, Diagnosis, Holdout, Trial};
use crate::diagnose::data::MeasuredData;
use crate::diagnose::experiment::{self, Experiment};
use crate::output;
use crate::render::diagnosis::{
    diagnosis_page, finite_or_null, ranking_text, screening_json, screening_text, verdict_text,
    Comparison, PageSources,
};

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

pub fn run(args: &DiagnoseArgs) -> Result<(), Error> {
    let mut experiment = experiment::load(&args.experiment)?;
    if let Some(model) = &args.model {
        experiment.set_model(model.clone());
    }
    let reads = super::data_run_reads(&args.experiment, &experiment, &args.data);
    let known = ["diagnosis.json", "diagnosis.html"].map(|name| args.out_dir.join(name));
    output::check_outputs(known.iter().map(PathBuf::as_path), &reads)?;
    let data = MeasuredData::load(&args.data)?;
    let holdout = Holdout::parse(&args.holdout)?;
    let d = diagnose_causes(&experiment, &data, &args.fit, holdout, &args.causes)?;
    println!(
        "{}: {} values fitted, {} held out ({}); noise band: held-out χ²/value ≤ {:.2}",
        experiment.title, d.train_values, d.holdout_values, args.holdout, d.noise_band
    );
    print!("{}", screening_text(d.screening.as_ref()));
    print!("{}", ranking_text(&d));
    let verdict = verdict_text(&d);
    let comparison = Comparison::new(&experiment, &d);
    print!("{}", comparison.text());
    println!("\nverdict: {verdict}");
    let summary = summary_json(args, &experiment, &d, &verdict, &comparison);
    let path = args.out_dir.join("diagnosis.json");
    let text = serde_json::to_string_pretty(&summary)?;
    let json = output::File::new(&path, text);
    let sources = PageSources {
        experiment: &args.experiment,
        data: &args.data,
        holdout: &args.holdout,
        out_dir: &args.out_dir,
    };
    let mut files = diagnosis_page(&sources, &experiment, &d, &verdict, &comparison, path)?;
    let html = files
        .last()
        .map(|page| page.path.clone())
        .unwrap_or_default();
    files.push(json);
    output::write_all(&files, &reads)?;
    println!("wrote {} and its data", html.display());
    Ok(())
}

/// `diagnosis.json`: every trial with its fitted values, the verdict, the features and the
/// held-out residuals — the facts of the terminal text, for scripts.
fn summary_json(
    args: &DiagnoseArgs,
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
        "data": args.data.display().to_string(),
        "flags": flags,
        "screening": screened,
        "holdout": args.holdout,
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
