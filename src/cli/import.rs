//! `mech import urdf FILE --out MODEL.mech`: a URDF robot (with Drake's `loop_joint` and
//! force elements) translated into a `.mech` model; what is not translated is listed as
//! comments in the model and as warnings on stderr.
//!
//! Consumes: the URDF path, the units of its numbers, the base and `--snap`. Produces: the
//! model file (written all or none, never over the URDF), warnings on stderr, a summary on
//! stdout.

use super::Error;
use std::path::PathBuf;
use std::sync::Arc;

use clap::{Args, Subcommand, ValueEnum};
use mech_codegen::urdf::{self, Base, Options, Units};
use mech_codegen::{Errors, SourceFile};

use crate::output;
use crate::render::terminal::terminal_safe;

#[derive(Subcommand, Clone, Debug)]
pub enum ImportCommand {
    /// A URDF file (Drake's `loop_joint` and `force_element` extensions included).
    Urdf(UrdfArgs),
}

#[derive(Args, Clone, Debug)]
pub struct UrdfArgs {
    /// The URDF file.
    pub file: PathBuf,
    /// The `.mech` file to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Unit of the file's lengths (URDF's own is m; the HAMR files use mm).
    #[arg(long, default_value = "m")]
    pub length: String,
    /// Unit of the file's masses (URDF's own is kg; the HAMR files use g).
    #[arg(long, default_value = "kg")]
    pub mass: String,
    /// Unit of the file's times (URDF's own is s; the HAMR files use ms).
    #[arg(long, default_value = "s")]
    pub time: String,
    /// What the root link becomes: the fixed Newtonian frame, or a body on a free joint.
    #[arg(long, value_enum, default_value_t = BaseArg::Fixed)]
    pub base: BaseArg,
    /// Move loop-joint points that miss each other at the zero pose by round-off onto the
    /// closure's axis where the other hinge axes meet it (documented in the model's header).
    #[arg(long)]
    pub snap: bool,
    /// Another URDF of the same robot: the inertial data of the links both files name are
    /// compared, each disagreement a warning with both files' numbers.
    #[arg(long, value_name = "OTHER.urdf")]
    pub compare: Option<PathBuf>,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum BaseArg {
    Fixed,
    Floating,
}

pub fn run(command: &ImportCommand) -> Result<(), Error> {
    match command {
        ImportCommand::Urdf(args) => urdf(args),
    }
}

fn urdf(args: &UrdfArgs) -> Result<(), Error> {
    let mut options = Options {
        units: Units::new(&args.length, &args.mass, &args.time)?,
        base: match args.base {
            BaseArg::Fixed => Base::Fixed,
            BaseArg::Floating => Base::Floating,
        },
        snap: args.snap,
        compare: None,
    };
    let source = args.file.as_path();
    let read = output::Read {
        path: source.to_path_buf(),
        what: "the URDF file",
    };
    let mut reads = vec![read];
    if let Some(other) = &args.compare {
        reads.push(output::Read {
            path: other.clone(),
            what: "the URDF file compared",
        });
        options.compare = Some(Arc::new(source_file(other)?));
    }
    output::check_outputs([args.out.as_path()], &reads)?;
    let imported = urdf::import(Arc::new(source_file(source)?), &options)?;
    output::write_all(
        &[output::File::new(&args.out, imported.text.as_bytes())],
        &reads,
    )?;
    if !imported.warnings.is_empty() {
        eprintln!("{}", terminal_safe(imported.render_warnings().trim_end()));
    }
    println!(
        "wrote {}: {} bodies, {} joints, {} loop closures; {} warnings",
        args.out.display(),
        imported.bodies,
        imported.joints,
        imported.loops,
        imported.warnings.len()
    );
    Ok(())
}

/// A file's text, shown in messages by its path as given.
fn source_file(path: &std::path::Path) -> Result<SourceFile, Errors> {
    let shown = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|error| Errors::io(&shown, &error))?;
    Ok(SourceFile::new(shown, text))
}
