//! mech-codegen: the build-time compiler for `.mech` models.
//!
//! # Pipeline
//! ```text
//! .mech text ─front::parse─▶ AST ─front::lower─▶ ir::Model ─kane::derive─▶ Equations
//!                                                               ├─back::rust::emit─▶ Rust source
//!                                                               └─back::tape::Tape::new─▶ tape
//! ```
//! Each phase is a function from plain data to plain data; the front end collects every
//! error of a phase into [`Errors`] (file, line, column, label, help).
//!
//! # Symbols
//! `q` generalized coordinates, `u` generalized speeds (`u = q̇`, except for the unit
//! quaternions of `ball` and `free` joints: `q̇ = W(q) u`), `M(q)` the mass matrix,
//! `F(t, q, u, inputs)` the forcing, so that `M u̇ = F`. Kane's method gives
//! `F_r + F_r* = 0` for each speed r (see [`kane`]). Internally every quantity is in SI units
//! (kg, m, s, rad, A).
//!
//! # Embedding (build.rs)
//! ```no_run
//! // build.rs
//! fn main() -> Result<(), mech_codegen::Errors> {
//!     mech_codegen::compile_models(&["models/pendulum.mech"])
//! }
//! ```
//! ```ignore
//! // src/lib.rs
//! pub mod pendulum { mech_runtime::include_model!("pendulum"); }
//! ```
//! [`compile_models`] writes `$OUT_DIR/<model>.rs` (only when its bytes change) and prints
//! `cargo:rerun-if-changed` for every `.mech` file it reads. A model with errors writes
//! nothing and returns the diagnostics, which `main` returning `Err` prints as they are:
//! the build fails on them alone. Note that any
//! `rerun-if-changed` line replaces cargo's default of re-running when any package file
//! changes; a build script that also depends on other files must list them too.
//!
//! For many models, [`Builder::include_file`] also writes one file listing them all (like
//! prost-build's `include_file`): a module per model, `NAMES`, and `compiled(name)`.
//! ```no_run
//! // build.rs
//! fn main() -> Result<(), mech_codegen::Errors> {
//!     mech_codegen::Builder::new()
//!         .include_file("models.rs")
//!         .compile(&["models/pendulum.mech", "models/cart_pendulum.mech"])
//! }
//! ```
//! ```ignore
//! // src/lib.rs
//! pub mod models { include!(concat!(env!("OUT_DIR"), "/models.rs")); }
//! // models::pendulum::Pendulum, models::NAMES, models::compiled("pendulum")
//! ```

pub mod back;
pub mod diag;
pub mod front;
pub mod ir;
pub mod kane;
pub mod physics;
pub mod sym;
pub mod urdf;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub use back::rust::RustOptions;
pub use back::tape::Tape;
pub use diag::{Diagnostic, Errors, SourceFile};
pub use kane::Equations;

/// A model through the whole pipeline: its IR and its equations of motion.
#[derive(Clone, Debug)]
pub struct Compiled {
    pub model: ir::Model,
    pub equations: Equations,
    /// The text the model was compiled from (`None` for a model built in memory): for
    /// run-time errors that point at a declaration, such as a loop that does not close.
    pub source: Option<Arc<SourceFile>>,
}

impl Compiled {
    /// Parses, lowers and derives a model from source text.
    pub fn from_source(file: SourceFile) -> Result<Compiled, Errors> {
        let file = Arc::new(file);
        let model = front::load(file.clone())?;
        let equations = kane::derive(&model);
        Ok(Compiled {
            model,
            equations,
            source: Some(file),
        })
    }

    /// Derives a model built or transformed in memory (e.g. by `ir::transform`).
    pub fn from_model(model: ir::Model) -> Compiled {
        let equations = kane::derive(&model);
        Compiled {
            model,
            equations,
            source: None,
        }
    }

    /// Reads and compiles a `.mech` file; diagnostics show `path` as given.
    pub fn from_path(path: impl AsRef<Path>) -> Result<Compiled, Errors> {
        let path = path.as_ref();
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|error| Errors::io(&shown, &error))?;
        Compiled::from_source(SourceFile::new(shown, text))
    }

    pub fn rust(&self, options: &RustOptions) -> String {
        back::rust::emit(&self.model, &self.equations, options)
    }

    pub fn tape(&self) -> Tape {
        Tape::new(&self.equations)
    }
}

/// Compiles `.mech` files into `$OUT_DIR/<model>.rs` with default options.
pub fn compile_models(paths: &[impl AsRef<Path>]) -> Result<(), Errors> {
    Builder::new().compile(paths)
}

/// Options of [`compile_models`], prost-build style (`&mut self` setters).
#[derive(Clone, Debug)]
pub struct Builder {
    out_dir: Option<PathBuf>,
    rust: RustOptions,
    emit_rerun_if_changed: bool,
    include_file: Option<PathBuf>,
}

impl Default for Builder {
    fn default() -> Self {
        Builder {
            out_dir: None,
            rust: RustOptions::default(),
            emit_rerun_if_changed: true,
            include_file: None,
        }
    }
}

impl Builder {
    pub fn new() -> Builder {
        Builder::default()
    }

    /// Where to write generated files (default: `$OUT_DIR`).
    pub fn out_dir(&mut self, dir: impl Into<PathBuf>) -> &mut Self {
        self.out_dir = Some(dir.into());
        self
    }

    /// Path of the runtime crate in generated code (default `::mech_runtime`), for crates
    /// that re-export it.
    pub fn runtime_path(&mut self, path: impl Into<String>) -> &mut Self {
        self.rust.runtime_path = path.into();
        self
    }

    /// Longest generated function before it is split into parts (default 1000 statements).
    pub fn max_statements_per_function(&mut self, statements: usize) -> &mut Self {
        self.rust.max_statements = statements;
        self
    }

    /// Print `cargo:rerun-if-changed=<file>` for each model (default true).
    pub fn emit_rerun_if_changed(&mut self, emit: bool) -> &mut Self {
        self.emit_rerun_if_changed = emit;
        self
    }

    /// Also write `name` (relative to the output directory) listing every model of the
    /// [`compile`](Builder::compile) call: `pub mod <model>` including `<model>.rs`,
    /// `NAMES: &[&str]` (sorted) and `compiled(name) -> Option<Box<dyn Model>>` (see
    /// [`back::include`]). Include it with
    /// `include!(concat!(env!("OUT_DIR"), "/<name>"))`.
    pub fn include_file(&mut self, name: impl Into<PathBuf>) -> &mut Self {
        self.include_file = Some(name.into());
        self
    }

    /// Compiles every file, then writes `<model>.rs` for each (and the include file) into
    /// the output directory, creating it if needed. Stops at the first file with errors and
    /// returns all of its diagnostics, having written nothing: the build script fails on the
    /// `.mech` error alone, not on Rust errors in a half-written set of modules. Two files
    /// declaring the same model name are an error (`E0002`): the second would overwrite the
    /// first's `<model>.rs`.
    pub fn compile(&self, paths: &[impl AsRef<Path>]) -> Result<(), Errors> {
        let out_dir = match &self.out_dir {
            Some(dir) => dir.clone(),
            None => std::env::var_os("OUT_DIR")
                .map(PathBuf::from)
                .ok_or_else(|| {
                    let error = std::io::Error::other(
                        "OUT_DIR is not set: call from build.rs or set Builder::out_dir",
                    );
                    Errors::io("OUT_DIR", &error)
                })?,
        };
        // Model name → (the file declaring it, the generated source).
        let mut sources: BTreeMap<String, (String, String)> = BTreeMap::new();
        for path in paths {
            let path = path.as_ref();
            if self.emit_rerun_if_changed {
                println!("cargo:rerun-if-changed={}", path.display());
            }
            let compiled = Compiled::from_path(path)?;
            let shown = path.display().to_string();
            if let Some((first, _)) = sources.get(&compiled.model.name) {
                let diagnostic = Diagnostic::error(
                    "E0002",
                    format!(
                        "model `{}` is also declared by `{first}`",
                        compiled.model.name
                    ),
                )
                .with_help("give one of them another name: `model NAME;`");
                return Err(Errors::new(
                    Arc::new(SourceFile::new(shown, "")),
                    vec![diagnostic],
                ));
            }
            let options = RustOptions {
                source_name: shown.clone(),
                ..self.rust.clone()
            };
            let source = compiled.rust(&options);
            sources.insert(compiled.model.name.clone(), (shown, source));
        }
        let write = |name: &Path, bytes: &[u8]| {
            let target = out_dir.join(name);
            std::fs::create_dir_all(&out_dir)
                .and_then(|()| write_if_changed(&target, bytes))
                .map_err(|error| Errors::io(&target.display().to_string(), &error))
        };
        for (name, (_, source)) in &sources {
            write(Path::new(&format!("{name}.rs")), source.as_bytes())?;
        }
        if let Some(name) = &self.include_file {
            let names: Vec<String> = sources.into_keys().collect();
            let source = back::include::emit(&names, &self.rust.runtime_path);
            write(name, source.as_bytes())?;
        }
        Ok(())
    }
}

/// Writes `bytes` unless the file already holds them (so dependents are not rebuilt), via a
/// temporary file and a rename so a reader never sees a half-written file.
pub fn write_if_changed(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    if std::fs::read(path).is_ok_and(|existing| existing == bytes) {
        return Ok(());
    }
    let temporary = path.with_extension("rs.tmp");
    std::fs::write(&temporary, bytes)?;
    std::fs::rename(&temporary, path)
}
