//! The README's section "Embedding the generated Rust" shows this crate's `Cargo.toml`,
//! `build.rs` and `src/main.rs` in full: each block after a `<!-- embed: FILE -->` marker
//! must be that file, byte for byte, except that the README's dependency paths are written
//! from a crate next to a checkout (`path = "../mech/…"`) and this crate's from inside it
//! (`path = "../../…"`).

use std::path::Path;

/// `(file, block)` for every marked block of `readme`.
fn marked_blocks(readme: &str) -> Vec<(String, String)> {
    let mut blocks = Vec::new();
    let mut lines = readme.lines();
    while let Some(line) = lines.next() {
        let Some(file) = line
            .trim()
            .strip_prefix("<!-- embed: ")
            .and_then(|rest| rest.strip_suffix(" -->"))
        else {
            continue;
        };
        let fence = lines.next().unwrap_or_default();
        assert!(
            fence.starts_with("```"),
            "no code block after the marker of {file}"
        );
        let mut block = String::new();
        for line in lines.by_ref().take_while(|line| *line != "```") {
            block.push_str(line);
            block.push('\n');
        }
        blocks.push((file.to_string(), block));
    }
    blocks
}

#[test]
fn readme_shows_this_crate_as_it_is() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(crate_dir.join("../../README.md")).unwrap();
    let blocks = marked_blocks(&readme);
    let shown: Vec<&str> = blocks.iter().map(|(file, _)| file.as_str()).collect();
    assert_eq!(shown, ["Cargo.toml", "build.rs", "src/main.rs"]);
    for (file, block) in blocks {
        let actual = std::fs::read_to_string(crate_dir.join(&file)).unwrap();
        let expected = block.replace("path = \"../mech/", "path = \"../../");
        assert!(
            actual == expected,
            "README.md's {file} differs from examples/embed/{file}; copy the file into the \
             README (with paths `../mech/…`)"
        );
    }
}

/// The example's four-bar is the bundled one (a copy, so the crate builds on its own).
#[test]
fn the_four_bar_is_the_bundled_one() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let copy = std::fs::read_to_string(root.join("models/four_bar.mech")).unwrap();
    let bundled = std::fs::read_to_string(root.join("../../models/four_bar.mech")).unwrap();
    assert_eq!(
        copy, bundled,
        "examples/embed/models/four_bar.mech drifted from models/"
    );
}
