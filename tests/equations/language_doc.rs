//! The examples of `docs/mech-language.md` beyond loading (codegen's `language_doc.rs`
//! checks that): every example with loop closures assembles from its written `q0`, so a
//! reader's first `mech check` of it succeeds.

use crate::markdown::examples;

use mech::session::Session;
use mech_codegen::diag::SourceFile;
use mech_codegen::Compiled;
use mech_runtime::Model;

/// The examples of `docs/mech-language.md` that load (not the ```` ```mech,fail ```` ones):
/// (`docs/mech-language.md:LINE`, text).
pub(crate) fn language_reference_examples() -> Vec<(String, String)> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/mech-language.md");
    let markdown = std::fs::read_to_string(path).unwrap();
    examples(&markdown)
        .into_iter()
        .filter(|e| !e.must_fail)
        .map(|e| (format!("docs/mech-language.md:{}", e.line), e.text))
        .collect()
}

#[test]
fn language_reference_examples_with_loops_assemble() {
    let mut looped = 0;
    let mut failures = Vec::new();
    for (name, text) in language_reference_examples() {
        let compiled = Compiled::from_source(SourceFile::new(name.clone(), text))
            .unwrap_or_else(|errors| panic!("{name}: {errors}"));
        let session = Session::from_compiled(compiled, &[], &[]).unwrap();
        if session.model.nc() == 0 {
            continue;
        }
        looped += 1;
        if let Err(error) = session.assemble(&[]) {
            failures.push(format!("{name}: {error}"));
        }
    }
    assert!(looped >= 2, "only {looped} examples with loops");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The example as it was: a `distance` loop whose points coincide at `q0` has no gradient
/// there (its row is finite since the residual is `(|d|² − L²)/2L`, but no Newton step moves
/// it); the error says so and points at the loop.
#[test]
fn a_distance_loop_starting_at_zero_length_is_a_clear_error() {
    let text = "
        body crank { mass = 1 mg; com = [0, 0.3 mm, 0]; inertia = [1e-15 kg*m^2, 1e-15 kg*m^2, 1e-15 kg*m^2]; }
        body slider { mass = 0.5 mg; }
        joint crank_angle = pin(newtonian, crank) { axis = z; }
        joint stroke = slider(newtonian, slider) { axis = x; parent_point = [0, 0.5 mm, 0]; }
        loop link = distance(crank, slider) { parent_point = [0, 0.5 mm, 0]; length = 0.1 mm; }
    ";
    let compiled =
        Compiled::from_source(SourceFile::new("coincident".to_string(), text.to_string())).unwrap();
    let session = Session::from_compiled(compiled, &[], &[]).unwrap();
    let error = session.assemble(&[]).unwrap_err().to_string();
    assert!(
        error.contains("row `link.distance` is -5e-5 away")
            && error.contains("coincide")
            && error.contains("coincident:6:9"),
        "{error}"
    );
}

/// `docs/examples/rail.mech` and `docs/examples/contact.mech`, whose `mech derive` and
/// `mech simulate` outputs the page shows (checked by `tests/analyses/docs_commands.rs`), are
/// the examples printed above those outputs.
#[test]
fn the_forces_example_file_is_the_one_on_the_page() {
    let root = env!("CARGO_MANIFEST_DIR");
    let markdown = std::fs::read_to_string(format!("{root}/docs/mech-language.md")).unwrap();
    for example in ["rail", "contact"] {
        let file = std::fs::read_to_string(format!("{root}/docs/examples/{example}.mech")).unwrap();
        assert!(
            examples(&markdown).iter().any(|e| e.text == file),
            "docs/examples/{example}.mech differs from its example in docs/mech-language.md"
        );
    }
}
