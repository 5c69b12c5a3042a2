//! Golden diagnostics: every `tests/ui/<error_kind>.mech` must fail to load, and its rendered
//! errors must equal `tests/ui/<error_kind>.stderr`.
//!
//! Consumes: the `.mech` files in `codegen/tests/ui/` (paths shown relative to the crate root,
//! so the goldens do not depend on the machine).
//! Produces: one test per file, named after it, plus one that fails when a file and the
//! list in `ui_tests!` differ (so a new file cannot go unchecked).
//! `MECH_BLESS=1 cargo test -p mech-codegen --test ui` rewrites the `.stderr` files instead.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use mech_codegen::diag::SourceFile;
use mech_codegen::front;

fn ui_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ui")
}

/// `MECH_BLESS=1`: rewrite the golden files instead of comparing.
fn blessing() -> bool {
    std::env::var_os("MECH_BLESS").is_some_and(|v| v == "1")
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

/// Checks (or, with `MECH_BLESS=1`, rewrites) the golden file of `tests/ui/<stem>.mech`.
fn check(stem: &str) {
    let path = ui_dir().join(format!("{stem}.mech"));
    let actual = render(&path);
    let golden = path.with_extension("stderr");
    if blessing() {
        std::fs::write(&golden, &actual).expect("writable .stderr file");
        return;
    }
    let expected = std::fs::read_to_string(&golden).unwrap_or_default();
    assert!(
        actual != "(loaded without errors)\n",
        "tests/ui/{stem}.mech loaded without errors; a ui file must fail"
    );
    assert!(
        actual == expected,
        "{} differs (MECH_BLESS=1 to update):\nexpected:\n{expected}\nactual:\n{actual}",
        golden.display()
    );
}

/// One `#[test]` per file stem, and `UI_FILES`, the stems listed.
macro_rules! ui_tests {
    ($($stem:ident,)*) => {
        const UI_FILES: &[&str] = &[$(stringify!($stem)),*];
        $(
            #[test]
            fn $stem() {
                check(stringify!($stem));
            }
        )*
    };
}

ui_tests! {
    actuator_missing_voltage,
    add_mass_and_length,
    axis_on_weld,
    detached_cycle,
    disconnected_body,
    division_by_zero,
    duplicate_field,
    expected_rotation,
    expected_vector,
    exponent_not_constant,
    flexure_missing_frequency,
    flexure_on_slider,
    function_argument_dimension,
    inertia_four_entries,
    input_in_body_property,
    joint_to_itself,
    let_before_definition,
    loop_bad_component,
    loop_field_of_other_kind,
    loop_missing_axis,
    many_errors,
    missing_axis,
    missing_mass,
    nested_too_deeply,
    newtonian_child,
    non_constant_axis,
    non_integer_dimension,
    not_a_number,
    number_out_of_range,
    param_not_constant,
    point_on_wrong_body,
    redefinition,
    reserved_name,
    scalar_output_in_frame,
    syntax_expected_expression,
    syntax_missing_semicolon,
    syntax_unclosed_block,
    twist_along_loop_axis,
    two_parent_joints,
    unknown_body,
    unknown_field,
    unknown_frame,
    unknown_function,
    unknown_joint_kind,
    unknown_loop_kind,
    unknown_material,
    unknown_name,
    unknown_point,
    unknown_unit,
    unterminated_comment,
    wrong_component_count,
    wrong_dimension,
    zero_axis,
}

/// The sorted stems of `tests/ui/*.<extension>`.
fn stems(extension: &str) -> Vec<String> {
    let mut stems: Vec<String> = std::fs::read_dir(ui_dir())
        .expect("tests/ui exists")
        .map(|entry| entry.expect("readable directory entry").path())
        .filter(|path| path.extension().is_some_and(|e| e == extension))
        .map(|path| {
            path.file_stem()
                .expect("a file stem")
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    stems.sort();
    stems
}

#[test]
fn every_ui_file_has_a_test_and_a_golden_file() {
    let mut listed: Vec<String> = UI_FILES.iter().map(|s| s.to_string()).collect();
    listed.sort();
    assert_eq!(
        stems("mech"),
        listed,
        "tests/ui/*.mech and the list in `ui_tests!` (codegen/tests/ui.rs) differ: add the new file's stem there"
    );
    // Blessing writes the missing .stderr files, possibly after this test has listed them.
    if !blessing() {
        assert_eq!(
            stems("stderr"),
            listed,
            "a .stderr without its .mech, or the reverse"
        );
    }
}
