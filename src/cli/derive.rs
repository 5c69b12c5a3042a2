//! `mech derive MODEL --emit equations|rust|tape`: the equations of motion as s-expressions,
//! the generated Rust, or the tape, with operation counts.
//!
//! Consumes: the model path and what to emit. Produces: text on stdout or a file written
//! atomically.

use super::Error;
use std::path::PathBuf;

use clap::{Args, ValueEnum};
use mech_codegen::Compiled;

use crate::{describe, output};

#[derive(Args, Clone, Debug)]
pub struct DeriveArgs {
    pub model: PathBuf,
    /// What to print.
    #[arg(long, value_enum, default_value_t = Emit::Equations)]
    pub emit: Emit,
    /// Write to this file instead of standard output.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Emit {
    /// Equations of motion as s-expressions, with operation counts.
    Equations,
    /// The generated Rust source.
    Rust,
    /// The tape (register instructions), with operation counts.
    Tape,
}

pub fn run(args: &DeriveArgs) -> Result<(), Error> {
    let (path, emit, out) = (args.model.as_path(), args.emit, args.out.as_deref());
    let compiled = Compiled::from_path(path)?;
    let text = match emit {
        Emit::Rust => {
            let options = mech_codegen::RustOptions {
                source_name: path.display().to_string(),
                ..Default::default()
            };
            compiled.rust(&options)
        }
        Emit::Tape => describe::tape_text(&compiled),
        Emit::Equations => describe::equations_text(&compiled)?,
    };
    match out {
        Some(file) => {
            let model = output::Read {
                path: path.to_path_buf(),
                what: "the model",
            };
            Ok(output::write_all(
                &[output::File::new(file, text)],
                &[model],
            )?)
        }
        None => {
            print!("{text}");
            Ok(())
        }
    }
}
