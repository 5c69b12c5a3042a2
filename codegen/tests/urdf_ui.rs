//! Golden diagnostics of `mech import urdf`: every `tests/urdf_ui/<error_kind>.urdf` must fail
//! to import, and its rendered errors (file, line, column, label, help) must equal
//! `tests/urdf_ui/<error_kind>.stderr`.
//!
//! Consumes: the URDF files in `codegen/tests/urdf_ui/` (shown relative to the crate root).
//! Produces: one test per file, plus one that fails when a file and the list differ.
//! `MECH_BLESS=1 cargo test -p mech-codegen --test urdf_ui` rewrites the `.stderr` files.

#[macro_use]
#[path = "support/golden.rs"]
mod support;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use mech_codegen::diag::SourceFile;
use mech_codegen::urdf;

fn ui_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/urdf_ui")
}

/// What the import reports for a file, or a note that it unexpectedly imported.
fn render(path: &Path) -> String {
    let name = path.file_name().expect("a file name").to_string_lossy();
    let text = std::fs::read_to_string(path).expect("readable URDF file");
    let file = Arc::new(SourceFile::new(format!("tests/urdf_ui/{name}"), text));
    match urdf::import(file, &urdf::Options::default()) {
        Ok(_) => "(imported without errors)\n".to_string(),
        Err(errors) => errors.to_string(),
    }
}

fn check(stem: &str) {
    let path = ui_dir().join(format!("{stem}.urdf"));
    support::check_failure(&path, &render(&path), "(imported without errors)\n");
}

tests_per_file! {
    check:
    bad_number,
    cycle_without_loop_joint,
    detached_cycle,
    expression_as_number,
    malformed_xml,
    missing_child,
    missing_link,
    misspelled_link,
    not_a_robot,
    spring_on_unknown_joint,
    two_roots,
    undeclared_drake_prefix,
    unknown_joint_type,
    wrong_vector_length,
}

#[test]
fn every_ui_file_has_a_test_and_a_golden_file() {
    support::assert_lists_every_file(LISTED, &ui_dir(), "urdf", "codegen/tests/urdf_ui.rs");
    if !support::blessing() {
        support::assert_lists_every_file(LISTED, &ui_dir(), "stderr", "codegen/tests/urdf_ui.rs");
    }
}
