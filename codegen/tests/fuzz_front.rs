//! Robustness: `front::load` (and, for models that load, derivation and the tape) never
//! panics, whatever the input.
//!
//! Consumes: arbitrary strings, and byte-level mutations and splices of a valid model.
//! Produces: proptest cases (a few hundred, so the test runs in seconds in debug builds).
//! The same property runs unbounded under cargo-fuzz in `fuzz/fuzz_targets/front_end.rs`.

use std::sync::Arc;

use mech_codegen::diag::SourceFile;
use mech_codegen::front;
use proptest::prelude::*;

#[path = "support/mutate.rs"]
mod mutate;

const VALID: &str = "/// A pendulum.
model pendulum;
param m = 10 g;
param l = 25 mm;
param g = 9.81 m/s^2;
param k = 0 uN*m/rad;
let I_c = m * l^2 / 12;
input drive = 0 mN;
gravity = [0, -g, 0];
newtonian { point anchor = [0, 0, 0]; frame tilted = rotate(z, 30 deg); }
body arm {
    mass = m;
    com = [0, -l/2, 0];
    inertia = [I_c, 0, I_c];
    point tip = [0, -l, 0];
    frame f = rotate(x, 10 deg) * rotate(z, 5 deg) at [0, -l, 0];
}
joint hinge = pin(newtonian, arm) {
    axis = z; parent_point = newtonian.anchor; child_point = [0, l, 0];
    parent_frame = newtonian.tilted; child_frame = arm.f;
    q0 = 30 deg; u0 = 0 rad/s; stiffness = k; rest = 0 deg; damping = 0 N*m*s/rad;
}
force push at arm.tip = [drive * sin(2 * pi * t / 1 s), 0, 0] in newtonian;
torque twist on arm = [0, 0, 1 uN*m] in arm;
input drive_v = 0 V;
body arm2 { mass = m; com = [0, -l/2, 0]; inertia = [I_c, 0, I_c]; }
joint elbow = pin(arm, arm2) { axis = z; parent_point = arm.tip; }
body cart { mass = m; }
joint rail = slider(newtonian, cart) { axis = x; }
loop close = revolute(arm2, cart) { axis = z; parent_point = [0, -l, 0]; stiffness = k; }
loop reach = distance(arm, cart) { length = 2 * l; }
loop touch = coincident(arm2, newtonian) { components = [x, y]; }
material kapton { loss_factor = 0.08; }
flexure fl on elbow { width = 1 mm; thickness = 25 um; length = 100 um; reference_frequency = 40 Hz; twist_axis = y; }
flexure fc on close { stiffness = 1 uN*m/rad; reference_frequency = 40 Hz; }
actuator act on rail { blocked_force = 320 mN; free_deflection = 300 um; rated_voltage = 225 V; voltage = drive_v; }
spring tie between arm.tip and cart { stiffness = 10 N/m; rest_length = l; damping = 0.01 N*s/m; }
output tip = position(arm.tip) in newtonian;
output angle = hinge.q;
output ke = kinetic_energy;
";

/// Loads `bytes` (lossily decoded) and renders any errors; panics are the failures.
fn load_bytes(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes).into_owned();
    match front::load(Arc::new(SourceFile::new("fuzz.mech", text))) {
        // A model that loads must also derive and lower to a tape without panicking.
        Ok(model) => {
            let equations = mech_codegen::kane::derive(&model);
            let _ = mech_codegen::Tape::new(&equations);
        }
        Err(errors) => {
            let _ = errors.to_string();
        }
    }
}

/// Tokens that make mutations reach deeper into the grammar than random bytes do.
const TOKENS: &[&str] = &[
    "loop",
    "coincident",
    "revolute",
    "distance",
    "material",
    "flexure",
    "actuator",
    "on",
    "spring",
    "between",
    "and",
    "rest_length",
    "twist_axis",
    "(",
    ")",
    "[",
    "]",
    "{",
    "}",
    ";",
    ",",
    ".",
    "=",
    "^",
    "-",
    "*",
    "/",
    "+",
    "^-",
    " ",
    "\n",
    "µ",
    "θ",
    "0",
    "1e999",
    "1e-99999",
    "99999999999999999999999",
    "0.5",
    "mm",
    "deg",
    "kg*m^2",
    "m^-100",
    "newtonian",
    "arm",
    "hinge",
    "tip",
    "com",
    "q",
    "u",
    "t",
    "pi",
    "let",
    "param",
    "body",
    "joint",
    "pin",
    "weld",
    "slider",
    "rotate(z, 1)",
    "position(arm)",
    "at",
    "in",
    "on",
    "///",
    "//",
    "/*",
    "*/",
];

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_strings_do_not_panic(text in "\\PC{0,200}") {
        load_bytes(text.as_bytes());
    }

    #[test]
    fn token_soup_does_not_panic(tokens in prop::collection::vec(prop::sample::select(TOKENS), 0..60)) {
        load_bytes(tokens.join(" ").as_bytes());
    }

    #[test]
    fn mutated_models_do_not_panic(mutations in prop::collection::vec(mutate::mutation(VALID.len(), 12, TOKENS), 1..6)) {
        load_bytes(&mutate::mutated(VALID, mutations));
    }

    #[test]
    fn spliced_models_do_not_panic(a in 0..VALID.len(), b in 0..VALID.len(), c in 0..VALID.len()) {
        load_bytes(&mutate::spliced(VALID, a, b, c));
    }
}

#[test]
fn the_seed_model_is_valid() {
    front::load(Arc::new(SourceFile::new("seed.mech", VALID))).unwrap();
}
