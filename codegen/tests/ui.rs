//! Golden diagnostics: every `tests/ui/<error_kind>.mech` must fail to load, and its rendered
//! errors must equal `tests/ui/<error_kind>.stderr`.
//!
//! Consumes: the `.mech` files in `codegen/tests/ui/` (paths shown relative to the crate root,
//! so the goldens do not depend on the machine).
//! Produces: one test that reports every mismatching file. `MECH_BLESS=1 cargo test -p
//! mech-codegen --test ui` rewrites the `.stderr` files instead.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use mech_codegen::diag::SourceFile;
use mech_codegen::front;

fn ui_files() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ui");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/ui exists")
        .map(|entry| entry.expect("readable directory entry").path())
        .filter(|path| path.extension().is_some_and(|e| e == "mech"))
        .collect();
    files.sort();
    files
}

/// What `front::load` prints for a file, or a note that it unexpectedly loaded.
fn render(path: &Path) -> String {
    let name = path.file_name().expect("a file name").to_string_lossy();
    let shown = format!("tests/ui/{name}");
    let text = std::fs::read_to_string(path).expect("readable .mech file");
    match front::load(Arc::new(SourceFile::new(shown, text))) {
        Ok(_) => "(loaded without errors)\n".to_string(),
        Err(errors) => errors.to_string(),
    }
}

#[test]
fn diagnostics_match_the_golden_files() {
    let bless = std::env::var_os("MECH_BLESS").is_some_and(|v| v == "1");
    let files = ui_files();
    assert!(
        files.len() >= 20,
        "expected the ui corpus, found {} files",
        files.len()
    );
    let mut failures = Vec::new();
    for path in &files {
        let actual = render(path);
        let golden = path.with_extension("stderr");
        if bless {
            std::fs::write(&golden, &actual).expect("writable .stderr file");
            continue;
        }
        let expected = std::fs::read_to_string(&golden).unwrap_or_default();
        if actual == "(loaded without errors)\n" || actual != expected {
            failures.push(format!(
                "── {} ──\nexpected:\n{expected}\nactual:\n{actual}",
                golden.display()
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} ui test(s) failed (MECH_BLESS=1 to update):\n{}",
        failures.len(),
        failures.join("\n")
    );
}
