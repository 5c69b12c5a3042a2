//! `mech animate MODEL RUN.csv --out view.html`: a simulated run played in 3D, as one
//! self-contained HTML page.
//!
//! Consumes: the model path, `--set` values as for the run, the run's CSV (`mech simulate`'s
//! columns `t` and `q_*`). Produces: the page (written atomically), and a line saying what
//! it holds.

use std::path::PathBuf;

use clap::Args;
use mech_runtime::Model;

use super::args::ModelArgs;
use super::Error;
use crate::output;
use crate::render::animation;

#[derive(Args, Clone, Debug)]
pub struct AnimateArgs {
    #[command(flatten)]
    pub common: ModelArgs,
    /// The run: the CSV `mech simulate --out` wrote for this model (and these `--set`s).
    pub run: PathBuf,
    /// The HTML page to write.
    #[arg(long)]
    pub out: PathBuf,
}

pub fn run(args: &AnimateArgs) -> Result<(), Error> {
    let mut reads = args.common.check_outputs(&[Some(&args.out)], None)?;
    reads.push(output::Read {
        path: args.run.clone(),
        what: "the run",
    });
    output::check_outputs([args.out.as_path()], &reads)?;
    let (session, _) = args.common.open("animate")?;
    let table = output::read_csv_table(&args.run)?;
    let values: Vec<f64> = (0..session.model.nparams())
        .map(|i| session.model.param(i))
        .collect();
    let motion = crate::animation::animate(&session.compiled, &values, &table)?;
    let page = animation::page(&motion);
    output::write_all(&[output::File::new(&args.out, page)], &reads)?;
    let frames = animation::shown_samples(motion.times.len()).len();
    println!(
        "wrote {}: {} bodies over {:.4} s ({} of {} samples shown)",
        args.out.display(),
        motion.bodies.len(),
        motion.times.last().copied().unwrap_or(0.0) - motion.times[0],
        frames,
        motion.times.len()
    );
    Ok(())
}
