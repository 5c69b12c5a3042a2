//! The README's example is real: its model is `models/pendulum.mech` and the `derive`
//! output it shows is what the code prints.

fn fenced_block_after(text: &str, marker: &str, language: &str) -> String {
    let start = text
        .find(marker)
        .unwrap_or_else(|| panic!("README lost the marker {marker:?}"));
    let rest = &text[start..];
    let open = format!("```{language}\n");
    let body = &rest[rest.find(&open).unwrap() + open.len()..];
    body[..body.find("```").unwrap()].to_string()
}

#[test]
fn readme_example_is_the_bundled_pendulum_and_its_output() {
    let root = env!("CARGO_MANIFEST_DIR");
    let readme = std::fs::read_to_string(format!("{root}/README.md")).unwrap();
    let model = std::fs::read_to_string(format!("{root}/models/pendulum.mech")).unwrap();
    assert_eq!(
        fenced_block_after(&readme, "## A minimal model", "mech"),
        model
    );

    let compiled =
        mech_codegen::Compiled::from_path(format!("{root}/models/pendulum.mech")).unwrap();
    let shown = fenced_block_after(&readme, "prints the equations", "text");
    assert_eq!(
        shown,
        mech::describe::equations_text(&compiled).expect("small")
    );
}
