//! `mech sweep STUDY.toml`: run a parameter grid or Monte-Carlo tolerance study on all cores
//! (progress bar), print its summary, sensitivity ranking and failed samples, and write the
//! samples' CSV, histograms and scatter plots.
//!
//! Consumes: the study file and the options. Produces: text on stdout, the study's files
//! under `--out` (written all or none).

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use super::Error;
use crate::output;
use crate::parallel::threads;
use crate::render::report::outcome_text;
use crate::sweep;

#[derive(Args, Clone, Debug)]
pub struct SweepArgs {
    /// The study file (TOML), e.g. `experiments/studies/hamr_tolerance.toml`.
    pub study: PathBuf,
    /// Folder for `samples.csv`, `failures.csv` and the plots (default
    /// `out/sweep/<study stem>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Monte-Carlo samples, in place of the study's `samples`.
    #[arg(long)]
    pub samples: Option<u64>,
    /// Seed of the draws, in place of the study's `seed`.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Threads (default: all cores); the results do not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
}

pub fn run(args: &SweepArgs) -> Result<(), Error> {
    let start = Instant::now();
    let mut study = sweep::load(&args.study)?;
    if let Some(samples) = args.samples {
        let samples = i64::try_from(samples).unwrap_or(i64::MAX);
        let samples = sweep::check_count("--samples", None, samples)?;
        study = study.with_samples(samples)?;
    }
    if let Some(seed) = args.seed {
        study.seed = seed;
    }
    let out = args.out.clone().unwrap_or_else(|| {
        PathBuf::from("out/sweep").join(output::file_stem(&args.study, "experiment"))
    });
    let bar = super::progress::progress_bar(
        study.samples as u64,
        "samples {bar:40} {pos}/{len} [{elapsed} < {eta}]",
    );
    let threads = args.threads.map_or_else(threads, |t| t as usize);
    let table = study.run_all(threads, &|| bar.inc(1))?;
    bar.finish_and_clear();
    let mut outcome = crate::render::sweep::render(&study, &table, &out)?;
    outcome.name = output::file_stem(&args.study, "experiment");
    let study_file = output::Read {
        path: args.study.clone(),
        what: "the study file",
    };
    output::write_all(&outcome.rendered, &[study_file])?;
    print!("{}", outcome_text(&outcome));
    println!(
        "{} samples in {:.1} s",
        table.rows.len(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
