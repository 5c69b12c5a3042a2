//! `mech assemble MODEL`: close the loops of a model — mobility, the singular values that
//! decide it, and a consistent state.
//!
//! Consumes: the model path, `--set` values and the coordinates held independent. Produces:
//! the assembly report on stdout and, with `--out`, the state as CSV.

use super::Error;
use std::path::PathBuf;

use clap::Args;
use mech_runtime::Model;

use super::args::ModelArgs;
use crate::output;
use crate::session;

#[derive(Args, Clone, Debug)]
pub struct AssembleArgs {
    #[command(flatten)]
    pub common: ModelArgs,
    /// CSV file for the assembled coordinates and speeds.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn run(args: &AssembleArgs) -> Result<(), Error> {
    let reads = args.common.check_outputs(&[args.out.as_deref()], None)?;
    let (session, _) = args.common.open("assemble")?;
    let state = session.assemble(&args.common.independent)?;
    print!("{}", session::assembly_report(&session.model, &state));
    if let Some(out) = &args.out {
        let model = &session.model;
        let mut header: Vec<String> = (0..model.nq())
            .map(|i| format!("q_{}", model.coordinate_name(i)))
            .collect();
        header.extend((0..model.nu()).map(|i| format!("u_{}", model.speed_name(i))));
        let row: Vec<f64> = state.q.iter().chain(&state.u).copied().collect();
        output::write_all(&[output::File::csv(out, &header, &[row])?], &reads)?;
        println!("\nwritten to {}", out.display());
    }
    Ok(())
}
