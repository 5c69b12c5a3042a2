//! `mech diagnose [MODEL] --experiment E --data D`: find what the model gets wrong — fit
//! every catalog cause, rank on held-out data, and name the cause (or say there is none, or
//! that none explains it). `mech diagnose --dataset DIR`: screen every ring-down of a flexure
//! data set (the layout `mech flexure fit` reads) as the pendulum kind does, and the set for a
//! loss factor that depends on frequency and for trials that disagree, in one summary.
//!
//! Consumes: a diagnosis experiment file, measured data (CSV), optional extra parameters and
//! cause filters; or a flexure data set. Produces: the ranking and verdict on stdout, and
//! `diagnosis.json`, `diagnosis.html` and plots in the output folder; for a data set the
//! summary on stdout and `dataset.json`.

use super::Error;
use std::path::{Path, PathBuf};

use clap::Args;
use serde_json::json;

use crate::diagnose::candidates::{diagnose_causes, Holdout};
use crate::diagnose::data::MeasuredData;
use crate::diagnose::experiment;
use crate::flexure_fit::fit::{fit_files, FitOptions, FitReport};
use crate::flexure_fit::rig::specimen_files;
use crate::output;
use crate::render::diagnosis::{
    dataset_text, diagnosis_json, diagnosis_page, ranked_on, ranking_text, screening_json,
    screening_text, verdict_text, Comparison, PageSources,
};

#[derive(Args, Clone, Debug)]
pub struct DiagnoseArgs {
    /// The model (`.mech`); default: the experiment file's `model`.
    pub model: Option<PathBuf>,
    /// The diagnosis experiment file (TOML, with the measurement noise).
    #[arg(long, required_unless_present = "dataset")]
    pub experiment: Option<PathBuf>,
    /// The measured data (CSV with `name [unit]` headers).
    #[arg(long, required_unless_present = "dataset")]
    pub data: Option<PathBuf>,
    /// A flexure data set (specimen `.toml` files naming their ring-down traces, as `mech
    /// flexure fit` reads): every trace screened as the pendulum kind, and the set for a
    /// frequency-dependent loss factor and disagreeing trials, in one summary. Exit code 0
    /// when traces are flagged, 1 when some cannot be read or analysed (all listed).
    #[arg(long, conflicts_with_all = ["experiment", "data", "model", "fit", "causes"])]
    pub dataset: Option<PathBuf>,
    /// Parameters the user lets vary in every model (as `mech fit --fit`).
    #[arg(long = "fit")]
    pub fit: Vec<String>,
    /// Rows held out of every fit and used to rank: `every:N` (default `every:3`), `last:P%`,
    /// or `none` (a few summary values, e.g. a paper's table: the fitted values rank).
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
    if let Some(dir) = &args.dataset {
        return dataset(dir, &args.out_dir);
    }
    let (Some(experiment_path), Some(data_path)) = (&args.experiment, &args.data) else {
        return Err(Error::Usage(
            "give --experiment and --data, or --dataset".into(),
        ));
    };
    let mut experiment = experiment::load(experiment_path)?;
    if let Some(model) = &args.model {
        experiment.set_model(model.clone());
    }
    let reads = super::args::data_run_reads(experiment_path, &experiment, data_path);
    let known = ["diagnosis.json", "diagnosis.html"].map(|name| args.out_dir.join(name));
    output::check_outputs(known.iter().map(PathBuf::as_path), &reads)?;
    let data = MeasuredData::load(data_path)?;
    let holdout = Holdout::parse(&args.holdout)?;
    let d = diagnose_causes(&experiment, &data, &args.fit, holdout, &args.causes)?;
    println!(
        "{}: {} values fitted, {} held out ({}); noise band: {} χ²/value ≤ {:.2}",
        experiment.title,
        d.train_values,
        d.holdout_values,
        args.holdout,
        ranked_on(&d),
        d.noise_band
    );
    print!("{}", screening_text(d.screening.as_ref()));
    print!("{}", ranking_text(&d));
    let verdict = verdict_text(&d);
    let comparison = Comparison::new(&experiment, &d);
    print!("{}", comparison.text());
    println!("\nverdict: {verdict}");
    let summary = diagnosis_json(
        &args.holdout,
        data_path,
        &experiment,
        &d,
        &verdict,
        &comparison,
    );
    let path = args.out_dir.join("diagnosis.json");
    let text = serde_json::to_string_pretty(&summary)?;
    let json = output::File::new(&path, text);
    let sources = PageSources {
        experiment: experiment_path,
        data: data_path,
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

/// `mech diagnose --dataset DIR`: the summary on stdout and `dataset.json`; then every trace
/// or file that could not be used, as the error (exit code 1), while flags alone leave it 0.
fn dataset(dir: &Path, out_dir: &Path) -> Result<(), Error> {
    let files = specimen_files(&[dir.to_path_buf()])?;
    let path = out_dir.join("dataset.json");
    let report = fit_files(&files, &FitOptions::default());
    let reads = super::flexure::data_set_reads(&files, &report);
    output::check_outputs([path.as_path()], &reads)?;
    print!("{}", dataset_text(&report));
    let text = serde_json::to_string_pretty(&dataset_json(&report))?;
    output::write_all(&[output::File::new(&path, text)], &reads)?;
    println!("\nwrote {}", path.display());
    Ok(report.problems()?)
}

/// `dataset.json`: each trace's flags and screening, the loss factor against frequency, the
/// findings and the rejected traces — the facts of the summary, for scripts.
fn dataset_json(report: &FitReport) -> serde_json::Value {
    let traces: Vec<serde_json::Value> = report
        .specimens
        .iter()
        .flat_map(|s| s.traces.iter().map(move |t| (s, t)))
        .map(|(s, t)| {
            let (flags, screening) = screening_json(Some(&t.screening));
            json!({
                "specimen": s.specimen.name,
                "trace": t.file.display().to_string(),
                "frequency_hz": t.analysis.omega_d / std::f64::consts::TAU,
                "loss_factor": t.loss_factor().0,
                "flags": flags,
                "screening": screening,
            })
        })
        .collect();
    let loss = report.loss_frequency.as_ref().map(|f| {
        json!({
            "exponent": f.exponent.0,
            "exponent_standard_error": f.exponent.1,
            "resolved": f.resolved(),
            "reference_frequency_hz": f.reference_frequency,
            "frequencies_hz": [f.frequencies.0, f.frequencies.1],
            "hinges": f.points,
            "chi2_dof": f.chi2_dof,
        })
    });
    json!({
        "traces": traces,
        "loss_frequency": loss,
        "findings": report.findings.iter().map(|f| json!({"kind": f.kind, "message": f.message})).collect::<Vec<_>>(),
        "rejected": report.rejected.iter().map(|e| e.to_string()).collect::<Vec<_>>(),
    })
}
