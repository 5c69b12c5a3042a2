//! `mech experiment FILE`: run one experiment file (`experiments/*.toml`) and print its
//! tables; its CSV files and plots go to a subfolder of the output folder.
//!
//! Consumes: the experiment file. Produces: text on stdout, files from the experiment
//! (written all or none).

use super::Error;
use std::path::PathBuf;

use clap::Args;

use crate::output;
use crate::render::report::outcome_text;

#[derive(Args, Clone, Debug)]
pub struct ExperimentArgs {
    /// The experiment file (TOML), e.g. `experiments/hamr_vi_trajectory.toml`.
    pub file: PathBuf,
    /// Folder for the CSV files and plots (a subfolder named after the file is used).
    #[arg(long, default_value = "out/experiments")]
    pub out_dir: PathBuf,
}

pub fn run(args: &ExperimentArgs) -> Result<(), Error> {
    // Drawn once an experiment reports parts (a locomotion grid's walks).
    let bar = std::sync::OnceLock::new();
    let progress = |done: usize, total: usize| {
        let bar = bar.get_or_init(|| {
            super::progress::progress_bar(total as u64, "runs {bar:30} {pos}/{len}")
        });
        bar.set_position(done as u64);
    };
    let outcome =
        crate::render::experiments::run_file_with_progress(&args.file, &args.out_dir, &progress);
    if let Some(bar) = bar.get() {
        bar.finish_and_clear();
    }
    let outcome = outcome?;
    let experiment = output::Read {
        path: args.file.clone(),
        what: "the experiment file",
    };
    output::write_all(&outcome.rendered, &[experiment])?;
    print!("{}", outcome_text(&outcome));
    Ok(())
}
