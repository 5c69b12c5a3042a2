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

use std::sync::Arc;

use mech_codegen::diag::SourceFile;
use mech_codegen::urdf;

/// Checks (or, with `MECH_BLESS=1`, rewrites) the golden file of `tests/urdf_ui/<stem>.urdf`:
/// what the import reports for it.
fn check(stem: &str) {
    support::check_failing_input(
        "tests/urdf_ui",
        stem,
        "urdf",
        "(imported without errors)\n",
        |shown, text| {
            urdf::import(
                Arc::new(SourceFile::new(shown, text)),
                &urdf::Options::default(),
            )
            .map(drop)
            .map_err(|errors| errors.to_string())
        },
    );
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
    support::assert_lists_every_input_and_golden(
        LISTED,
        "tests/urdf_ui",
        "urdf",
        "codegen/tests/urdf_ui.rs",
    );
}
