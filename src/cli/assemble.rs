//! `mech assemble MODEL`: close the loops of a model — mobility, the singular values that
//! decide it, and a consistent state.
//!
//! Consumes: the model path, `--set` values and the coordinates held independent. Produces:
//! the assembly report on stdout and, with `--out`, the state as CSV.

use std::path::PathBuf;

use clap::Args;
use mech_runtime::Model;

use crate::output;
use crate::session::{self, Session};

#[derive(Args, Clone, Debug)]
pub struct AssembleArgs {
    pub model: PathBuf,
    /// Set a parameter: `--set 'm=12 g'` (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub sets: Vec<String>,
    /// Hold this coordinate (at VALUE, or its q0): `--independent crank_angle=1rad`.
    #[arg(long = "independent", value_name = "NAME[=VALUE]")]
    pub independent: Vec<String>,
    /// CSV file for the assembled coordinates and speeds.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn run(args: &AssembleArgs) -> Result<(), String> {
    let (path, sets, independent, out) = (
        args.model.as_path(),
        &args.sets,
        &args.independent,
        args.out.as_deref(),
    );
    let session = Session::open(path, sets, &[])?;
    let state = session.assemble(independent)?;
    print!("{}", session::assembly_report(&session.model, &state));
    if let Some(out) = out {
        let model = &session.model;
        let names: Vec<&str> = (0..model.nq()).map(|i| model.coordinate_name(i)).collect();
        let mut header: Vec<String> = names.iter().map(|n| format!("q_{n}")).collect();
        header.extend(names.iter().map(|n| format!("u_{n}")));
        let row: Vec<f64> = state.q.iter().chain(&state.u).copied().collect();
        output::write_csv(out, &header, &[row])
            .map_err(|e| format!("cannot write {}: {e}", out.display()))?;
        println!("\nwritten to {}", out.display());
    }
    Ok(())
}
