//! What an embedding crate writes: compile the models at build time with mech-codegen.

fn main() -> Result<(), mech_codegen::Errors> {
    // The one-call form, with default options.
    mech_codegen::compile_models(&["models/double_pendulum.mech"])?;

    // The builder form: the same model, split into functions of at most 8 statements (the
    // default is 1000), written under another name so both can be compared in the tests.
    let out_dir =
        std::path::PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let split_dir = out_dir.join("split");
    std::fs::create_dir_all(&split_dir).map_err(|e| mech_codegen::Errors::io("split", &e))?;
    mech_codegen::Builder::new()
        .out_dir(&split_dir)
        .max_statements_per_function(8)
        .compile(&["models/double_pendulum.mech"])
}
