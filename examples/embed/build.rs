//! Compiles the `.mech` models into `$OUT_DIR/<model>.rs` at build time, for
//! `mech_runtime::include_model!`. A model with errors fails the build with its diagnostics.

fn main() -> Result<(), mech_codegen::Errors> {
    mech_codegen::compile_models(&["models/double_pendulum.mech", "models/four_bar.mech"])?;

    // The builder form, for other settings: the double pendulum again, into another
    // directory, split into functions of at most 8 statements (default 1000). Only the
    // tests use it (tests/generated_code.rs).
    let out_dir = std::path::PathBuf::from(std::env::var_os("OUT_DIR").expect("set by cargo"));
    mech_codegen::Builder::new()
        .out_dir(out_dir.join("split"))
        .max_statements_per_function(8)
        .compile(&["models/double_pendulum.mech"])
}
