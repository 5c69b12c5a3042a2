//! Robustness: `urdf::import` never panics, whatever the file, and what it writes goes
//! through the front end without a panic either (it may be rejected).
//!
//! Consumes: arbitrary strings, and byte-level mutations and splices of a valid URDF that
//! uses every element the importer translates. Produces: proptest cases (a few hundred).

use std::sync::Arc;

use mech_codegen::diag::SourceFile;
use mech_codegen::{front, urdf};
use proptest::prelude::*;

#[path = "support/mutate.rs"]
mod mutate;

const VALID: &str = r#"<?xml version="1.0"?>
<robot name="seed" xmlns:drake="http://drake.mit.edu">
  <link name="base"><inertial><origin xyz="0 0 -0.1"/><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" iyz="0" ixz="0"/></inertial></link>
  <link name="crank"><inertial><origin xyz="0.01 0 0" rpy="0 0.3 0"/><mass value="0.01"/><inertia ixx="1e-6" iyy="2e-6" izz="2e-6" ixy="0" iyz="0" ixz="0"/></inertial></link>
  <link name="rocker"><inertial><mass value="0.01"/><inertia ixx="1e-6" iyy="1e-6" izz="1e-6" ixy="0" iyz="0" ixz="0"/></inertial>
    <collision name="foot"><origin xyz="0 -0.02 0"/><geometry><sphere radius="0"/></geometry></collision></link>
  <link name="cart"/>
  <joint name="a" type="revolute"><origin xyz="0 0 0" rpy="0 0 0.1"/><parent link="base"/><child link="crank"/><axis xyz="0 0 1"/><limit lower="-1" upper="1"/><dynamics damping="0.01"/></joint>
  <joint name="b" type="continuous"><origin xyz="0.03 0 0"/><parent link="base"/><child link="rocker"/><axis xyz="0 0 1"/></joint>
  <joint name="c" type="prismatic"><origin xyz="0 0.05 0"/><parent link="base"/><child link="cart"/><axis xyz="1 0 0"/></joint>
  <loop_joint name="l" type="continuous"><axis xyz="0 0 1"/><link1 link="crank" xyz="0.02 0 0" rpy="0 0 0"/><link2 link="rocker" xyz="0 0.02 0" rpy="0 0 0"/></loop_joint>
  <force_element name="k"><torsional_spring stiffness="0.1" rest_angle="0"><joint name="l"/></torsional_spring></force_element>
  <force_element name="s"><prismatic_spring stiffness="10" rest_length="0"><joint name="c"/></prismatic_spring></force_element>
  <force_element name="band"><linear_spring_damper stiffness="5" damping="0.1"><link1 link="base" xyz="0 0.1 0"/><link2 link="cart" xyz="0 0 0"/></linear_spring_damper></force_element>
  <transmission type="SimpleTransmission" name="t"><actuator name="m"/><joint name="a"/><mechanicalReduction>1</mechanicalReduction></transmission>
</robot>
"#;

/// Imports `bytes` (lossily decoded) and, if that succeeds, loads the model it writes;
/// panics are the failures.
fn import_bytes(bytes: &[u8], snap: bool) {
    let text = String::from_utf8_lossy(bytes).into_owned();
    let options = urdf::Options {
        snap,
        ..urdf::Options::default()
    };
    match urdf::import(Arc::new(SourceFile::new("fuzz.urdf", text)), &options) {
        Ok(imported) => {
            let _ = imported.render_warnings();
            let _ = front::load(Arc::new(SourceFile::new("fuzz.mech", imported.text)));
        }
        Err(errors) => {
            let _ = errors.to_string();
        }
    }
}

/// Pieces that make mutations reach past the XML parser.
const TOKENS: &[&str] = &[
    "<",
    ">",
    "/>",
    "\"",
    "=",
    " ",
    "\n",
    ",",
    "-",
    ".",
    "e",
    "E-4",
    "0",
    "1e999",
    "nan",
    "pi/9",
    "µ",
    "&amp;",
    "&#45;",
    "<!-- -->",
    "link",
    "joint",
    "loop_joint",
    "link1",
    "link2",
    "base",
    "crank",
    "rocker",
    "cart",
    "fixed",
    "floating",
    "planar",
    "ball",
    "revolute",
    "prismatic",
    "xyz=\"1 2 3\"",
    "rpy=\"1 2 3\"",
    "axis",
    "origin",
    "inertial",
    "mass",
    "inertia",
];

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_strings_do_not_panic(text in "\\PC{0,200}") {
        import_bytes(text.as_bytes(), true);
    }

    #[test]
    fn mutated_urdf_does_not_panic(mutations in prop::collection::vec(mutate::mutation(VALID.len(), 16, TOKENS), 1..6), snap in any::<bool>()) {
        import_bytes(&mutate::mutated(VALID, mutations), snap);
    }

    #[test]
    fn spliced_urdf_does_not_panic(a in 0..VALID.len(), b in 0..VALID.len(), c in 0..VALID.len()) {
        import_bytes(&mutate::spliced(VALID, a, b, c), true);
    }
}

/// The seed imports, and its model loads: the mutations start from a file that works.
#[test]
fn the_seed_urdf_imports_into_a_model_that_loads() {
    let imported = urdf::import(
        Arc::new(SourceFile::new("seed.urdf", VALID)),
        &urdf::Options::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    front::load(Arc::new(SourceFile::new(
        "seed.mech",
        imported.text.clone(),
    )))
    .unwrap_or_else(|e| panic!("{e}\n{}", imported.text));
}
