//! The build API ([`mech_codegen::Builder`], what `build.rs` calls) on a model with an error:
//! the error comes back once, as the spanned diagnostic, and nothing is written, so the
//! build fails on the `.mech` error alone and not on Rust errors in the crate.
//!
//! Consumes: two models written into a fresh directory under the system's temporary one.
//! Produces: nothing outside that directory (removed at the end).

use std::path::{Path, PathBuf};

const GOOD: &str = "
model good;
param m = 10 g;
body b { mass = m; com = [0, -10 mm, 0]; inertia = [1, 1, 1] * 1e-9 kg*m^2; }
joint j = pin(newtonian, b) { axis = z; }
";

/// A unit typo (`mn` for `mm`) in a param used three times.
const TYPO: &str = "
model typo;
param l = 40 mn;
body b { mass = 10 g; com = [0, -l/2, 0]; inertia = [1, 1, 1] * 1e-9 kg*m^2; }
joint j = pin(newtonian, b) { axis = z; parent_point = [0, -l, 0]; q0 = 0.1 rad; }
output half = l / 2;
";

/// A directory of its own for one test, holding `files`, with an empty `out/`.
fn scratch(test: &str, files: &[(&str, &str)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mech-build-api-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("out")).unwrap();
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    dir
}

fn written(out: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(out)
        .unwrap()
        .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn a_model_with_an_error_fails_with_its_diagnostic_and_writes_nothing() {
    let dir = scratch("typo", &[("good.mech", GOOD), ("typo.mech", TYPO)]);
    let result = mech_codegen::Builder::new()
        .out_dir(dir.join("out"))
        .emit_rerun_if_changed(false)
        .include_file("models.rs")
        .compile(&[dir.join("good.mech"), dir.join("typo.mech")]);
    let message = result.expect_err("a unit typo is an error").to_string();
    // The one diagnostic, with its place and the suggestion, and nothing else.
    assert!(
        message.contains("error[E0206]: unknown unit `mn`"),
        "{message}"
    );
    assert!(message.contains("typo.mech:3:14"), "{message}");
    assert!(message.contains("did you mean `mN`?"), "{message}");
    assert_eq!(message.matches("error[").count(), 1, "{message}");
    // Not even the good model before it: no half-written set of modules.
    assert_eq!(written(&dir.join("out")), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn good_models_are_written_into_an_output_directory_created_if_needed() {
    let dir = scratch("good", &[("good.mech", GOOD)]);
    mech_codegen::Builder::new()
        .out_dir(dir.join("out/nested"))
        .emit_rerun_if_changed(false)
        .include_file("models.rs")
        .compile(&[dir.join("good.mech")])
        .unwrap();
    assert_eq!(written(&dir.join("out/nested")), ["good.rs", "models.rs"]);
    std::fs::remove_dir_all(&dir).unwrap();
}
