//! `mech fit --experiment E --data D --fit NAME`: fit model parameters to measured data
//! (Levenberg–Marquardt, standard errors), with the residual before and after.
//!
//! Consumes: a diagnosis experiment file, measured data (CSV) and the parameters to fit.
//! Produces: the table on stdout, and in the output folder `fit.json` (the same facts for
//! scripts), `fit.csv` (measured, before, after per value) and one plot per measured series.

use super::Error;
use std::path::PathBuf;

use clap::Args;

use crate::diagnose::data::MeasuredData;
use crate::diagnose::experiment::{self, Experiment};
use crate::diagnose::fit::{fit, parameters, FitReport, FitRequest};
use crate::diagnose::pendulum::Screening;
use crate::experiments::leg::Leg;
use crate::output;
use crate::render::diagnosis::{fit_json, flag_kinds, overlay_plots, screening_text};

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

pub fn run(args: &FitArgs) -> Result<(), Error> {
    let experiment = experiment::load(&args.experiment)?;
    let reads = super::args::data_run_reads(&args.experiment, &experiment, &args.data);
    let known = ["fit.json", "fit.csv"].map(|name| args.out_dir.join(name));
    output::check_outputs(known.iter().map(PathBuf::as_path), &reads)?;
    let data = MeasuredData::load(&args.data)?;
    let mut leg = Leg::open_any(&experiment.model, &[])?;
    let requests = args
        .fit
        .iter()
        .map(|text| FitRequest::parse(text))
        .collect::<Result<Vec<_>, _>>()?;
    let fitted = parameters(&leg, &requests)?;
    // Checked before the screening, which reads the same columns.
    experiment.observations(&leg, &data)?;
    let screening = experiment.screen(&data)?;
    println!(
        "{}: {} rows of `{}`, fitting {}",
        experiment.title,
        data.rows,
        args.data.display(),
        requests
            .iter()
            .map(|(r, _)| r.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    );
    print!("{}", screening_text(screening.as_ref()));
    let report = fit(&experiment, &data, &mut leg, &fitted).map_err(|error| Error::Fit {
        data: args.data.clone(),
        error: Box::new(error),
    })?;
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
    write_outputs(args, &experiment, &report, screening.as_ref(), &reads)
}

fn write_outputs(
    args: &FitArgs,
    experiment: &Experiment,
    report: &FitReport,
    screening: Option<&Screening>,
    reads: &[output::Read],
) -> Result<(), Error> {
    let dir = &args.out_dir;
    let summary = fit_json(experiment, &args.data, report, screening);
    let text = serde_json::to_string_pretty(&summary)?;
    let json_path = dir.join("fit.json");
    let mut files = vec![output::File::new(&json_path, text)];

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
    files.push(output::File::csv(&csv_path, &header, &rows)?);
    let curves = [
        ("model before".to_string(), report.before.as_slice()),
        ("model after fit".to_string(), report.after.as_slice()),
    ];
    let plots = overlay_plots(dir, "fit", experiment, obs, &curves)?;
    files.extend(plots.iter().cloned());
    output::write_all(&files, reads)?;
    for plot in &plots {
        println!("wrote {}", plot.path.display());
    }
    println!("wrote {} and {}", json_path.display(), csv_path.display());
    Ok(())
}
