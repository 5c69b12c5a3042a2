//! Compiles every bundled model in `models/` through mech-codegen's public build API,
//! exactly as an embedding crate would, with `$OUT_DIR/bundled_models.rs` listing them (a
//! module per model, `NAMES`, `compiled(name)`) for `src/lib.rs`.

use std::path::PathBuf;

fn main() -> Result<(), mech_codegen::Errors> {
    let mut models: Vec<PathBuf> = std::fs::read_dir("models")
        .map_err(|error| mech_codegen::Errors::io("models", &error))?
        .filter_map(|entry| entry.ok().map(|entry| entry.path()))
        .filter(|path| path.extension().is_some_and(|ext| ext == "mech"))
        .collect();
    models.sort(); // the first file with errors is the one reported
    println!("cargo:rerun-if-changed=models");
    mech_codegen::Builder::new()
        .include_file("bundled_models.rs")
        .compile(&models)
}
