//! `mech report`: run every experiment in a folder in parallel (progress bar) and write
//! `report.html` (self-contained) and `report.md`.
//!
//! Consumes: the experiments folder. Produces: text on stdout, the two report files and each
//! experiment's files, written all or none.

use super::Error;
use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use crate::experiments::experiment_files;
use crate::output;
use crate::render::experiments::run_all;
use crate::render::report::{experiment_reads, outcome_text, Report};

#[derive(Args, Clone, Debug)]
pub struct ReportArgs {
    /// Folder of experiment files (every `*.toml` in it is run).
    #[arg(long, default_value = "experiments")]
    pub experiments: PathBuf,
    /// Output folder: `report.html`, `report.md`, and one subfolder per experiment.
    #[arg(long, default_value = "out/report")]
    pub out_dir: PathBuf,
}

pub fn run(args: &ReportArgs) -> Result<(), Error> {
    let start = Instant::now();
    let experiment_files = experiment_files(&args.experiments)?;
    let bar = super::progress::progress_bar(
        experiment_files.len() as u64,
        "experiments {bar:40} {pos}/{len} {msg} [{elapsed}]",
    );
    bar.tick();
    let outcomes = run_all(&experiment_files, &args.out_dir, &|name| {
        bar.inc(1);
        bar.set_message(format!("done: {name}"));
    });
    bar.finish_and_clear();
    let elapsed = start.elapsed().as_secs_f64();
    let report = Report::new(outcomes?, &args.out_dir, elapsed)?;
    for outcome in &report.outcomes {
        println!("{}", outcome_text(outcome));
    }
    let (html, markdown) = (report.html.path.clone(), report.markdown.path.clone());
    let count = report.outcomes.len();
    output::write_all(&report.into_files(), &experiment_reads(&experiment_files))?;
    println!(
        "{count} experiments in {elapsed:.1} s; report written to {} and {}",
        html.display(),
        markdown.display()
    );
    Ok(())
}
