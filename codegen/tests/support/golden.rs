//! Golden-file tests with one `#[test]` per input file, shared by `codegen/tests/ui.rs`,
//! `codegen/tests/urdf_ui.rs` and the `mech` crate's `tests/equations/` (included there by
//! `#[path]`).
//!
//! Consumes: a directory of inputs and the list of their stems written in the test file.
//! Produces: the tests (`tests_per_file!`) and the check that the list and the directory
//! agree, so an input added without its test fails; `MECH_BLESS=1` selects bless mode.

use std::path::Path;

/// `MECH_BLESS=1`: rewrite the golden files instead of comparing.
pub fn blessing() -> bool {
    std::env::var_os("MECH_BLESS").is_some_and(|v| v == "1")
}

/// The sorted stems of `dir/*.<extension>`.
pub fn stems(dir: &Path, extension: &str) -> Vec<String> {
    let mut stems: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|error| panic!("cannot list {}: {error}", dir.display()))
        .map(|entry| entry.expect("readable directory entry").path())
        .filter(|path| path.extension().is_some_and(|e| e == extension))
        .map(|path| {
            let stem = path.file_stem().expect("a file stem");
            stem.to_string_lossy().into_owned()
        })
        .collect();
    stems.sort();
    stems
}

/// Fails unless `listed` names exactly the files `dir/*.<extension>`.
pub fn assert_lists_every_file(listed: &[&str], dir: &Path, extension: &str, list_in: &str) {
    let mut listed: Vec<String> = listed.iter().map(|s| s.to_string()).collect();
    listed.sort();
    assert_eq!(
        stems(dir, extension),
        listed,
        "{}/*.{extension} and the list in `tests_per_file!` ({list_in}) differ: add the new file's stem there",
        dir.display()
    );
}

/// `tests_per_file!(check: a, b,)`: `#[test] fn a() { check("a") }`, ..., and `LISTED`, the
/// stems, for [`assert_lists_every_file`].
macro_rules! tests_per_file {
    ($check:ident: $($stem:ident,)*) => {
        const LISTED: &[&str] = &[$(stringify!($stem)),*];
        $(
            #[test]
            fn $stem() {
                $check(stringify!($stem));
            }
        )*
    };
}

/// Checks the diagnostics `actual` of `input`, a file that must fail, against its golden
/// `.stderr` file beside it, or rewrites that with `MECH_BLESS=1`. `succeeded` is what
/// `actual` reads when the input did not fail.
#[allow(dead_code)] // used by the ui tests, not by every file that includes this one
fn check_failure(input: &Path, actual: &str, succeeded: &str) {
    let golden = input.with_extension("stderr");
    if blessing() {
        std::fs::write(&golden, actual).expect("writable .stderr file");
        return;
    }
    let expected = std::fs::read_to_string(&golden).unwrap_or_default();
    assert!(
        actual != succeeded,
        "{}: {}; a ui file must fail",
        input.display(),
        succeeded.trim_end()
    );
    assert!(
        actual == expected,
        "{} differs (MECH_BLESS=1 to update):\nexpected:\n{expected}\nactual:\n{actual}",
        golden.display()
    );
}

/// The golden test of `<crate root>/<dir>/<stem>.<extension>`, an input that must fail:
/// `render` takes the file's path as shown (`<dir>/<file name>`, relative to the crate root so
/// the goldens do not depend on the machine) and its text, and returns `Ok(())` if it loaded,
/// else its rendered errors; these (or `succeeded`) are checked by [`check_failure`].
#[allow(dead_code)] // used by the ui tests, not by every file that includes this one
pub fn check_failing_input(
    dir: &str,
    stem: &str,
    extension: &str,
    succeeded: &str,
    render: impl FnOnce(String, String) -> Result<(), String>,
) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(dir)
        .join(format!("{stem}.{extension}"));
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|error| panic!("cannot read {}: {error}", path.display()));
    let actual = match render(format!("{dir}/{stem}.{extension}"), text) {
        Ok(()) => succeeded.to_string(),
        Err(errors) => errors,
    };
    check_failure(&path, &actual, succeeded);
}

/// Fails unless `listed` names exactly the inputs `<crate root>/<dir>/*.<extension>` and,
/// unless blessing (which writes the missing ones, possibly after this has listed them),
/// their golden `.stderr` files.
#[allow(dead_code)] // used by the ui tests, not by every file that includes this one
pub fn assert_lists_every_input_and_golden(
    listed: &[&str],
    dir: &str,
    extension: &str,
    list_in: &str,
) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    assert_lists_every_file(listed, &dir, extension, list_in);
    if !blessing() {
        assert_lists_every_file(listed, &dir, "stderr", list_in);
    }
}
