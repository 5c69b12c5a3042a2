//! Golden equations: what `mech derive MODEL --emit equations` prints for every bundled model
//! stays as it is, so a change in the front end, the symbolic engine or Kane's method that
//! alters any equation shows up as a diff.
//!
//! Consumes: `models/<stem>.mech`. Produces: one test per model, named after it, comparing
//! `describe::equations_text` with `tests/golden/equations/<stem>.txt`, plus one that fails
//! when a model and the list in `golden_tests!` differ (so a new model cannot go unchecked).
//! `MECH_BLESS=1 cargo test --test golden_equations` rewrites the golden files instead.

use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn golden_dir() -> PathBuf {
    root().join("tests/golden/equations")
}

/// Checks (or, with `MECH_BLESS=1`, rewrites) the golden equations of `models/<stem>.mech`.
fn check(stem: &str) {
    let compiled = mech_codegen::Compiled::from_path(root().join(format!("models/{stem}.mech")))
        .unwrap_or_else(|errors| panic!("models/{stem}.mech does not compile:{errors:?}"));
    let actual = mech::describe::equations_text(&compiled);
    let golden = golden_dir().join(format!("{stem}.txt"));
    if std::env::var_os("MECH_BLESS").is_some_and(|v| v == "1") {
        std::fs::create_dir_all(golden_dir()).expect("writable tests/golden");
        std::fs::write(&golden, &actual).expect("writable golden file");
        return;
    }
    let expected = std::fs::read_to_string(&golden).unwrap_or_default();
    if actual != expected {
        // The texts run to 130 kB: show the first differing line, not both files.
        let line = actual
            .lines()
            .zip(expected.lines())
            .position(|(a, e)| a != e)
            .unwrap_or_else(|| actual.lines().count().min(expected.lines().count()));
        let show = |text: &str| {
            text.lines()
                .nth(line)
                .unwrap_or("(end of text)")
                .to_string()
        };
        panic!(
            "{} differs from `mech derive models/{stem}.mech --emit equations` at line {} \
             (MECH_BLESS=1 to update):\nexpected: {}\nactual:   {}",
            golden.display(),
            line + 1,
            show(&expected),
            show(&actual)
        );
    }
}

/// One `#[test]` per model stem, and `MODELS`, the stems listed.
macro_rules! golden_tests {
    ($($stem:ident,)*) => {
        const MODELS: &[&str] = &[$(stringify!($stem)),*];
        $(
            #[test]
            fn $stem() {
                check(stringify!($stem));
            }
        )*
    };
}

golden_tests! {
    cart_pendulum,
    chain1,
    chain2,
    chain4,
    double_pendulum_3d,
    flexure_rig,
    four_bar,
    hamr_v2,
    hamr_vi,
    mixed_chain,
    pendulum,
    slider_crank,
    spherical_five_bar,
    triple_pendulum_3d,
    two_mass_chain,
}

#[test]
fn every_bundled_model_has_a_golden_test() {
    let mut on_disk: Vec<String> = std::fs::read_dir(root().join("models"))
        .expect("models/ exists")
        .map(|entry| entry.expect("readable directory entry").path())
        .filter(|path| path.extension().is_some_and(|e| e == "mech"))
        .map(|path| {
            path.file_stem()
                .expect("a file stem")
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    on_disk.sort();
    let mut listed: Vec<String> = MODELS.iter().map(|s| s.to_string()).collect();
    listed.sort();
    assert_eq!(
        on_disk, listed,
        "models/*.mech and the list in `golden_tests!` (tests/golden_equations.rs) differ: add the new model's stem there"
    );
}
