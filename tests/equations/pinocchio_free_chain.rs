//! The floating chain (issue 15: a `free` joint carrying the peers' N-link chain) against
//! Pinocchio's ABA and MuJoCo's `mj_forward`: `u̇` at 3 random states for N = 1, 2, 4 from
//! `tests/peers/free_chain.json`, written by `tests/peers/pinocchio_free_chain.py` (see its
//! docstring and tests/peers/README.md for the conventions converted and how to regenerate).
//! The models are mech-bench's `floating_chain_source(n)` (bench/src/source.rs), the text the
//! benchmark times, compiled here; both back ends of the tape are checked.

#[allow(dead_code)] // only `floating_chain_source` is used here
#[path = "../../bench/src/source.rs"]
mod source;

use crate::common;

use common::{accelerations, assert_close, compile_text, json_numbers};
use mech::tape_model::{Backend, TapeModel};
use mech_runtime::Model;
use serde_json::Value;

const TOLERANCE: f64 = 1e-10;

fn fixture() -> Value {
    let path = format!("{}/tests/peers/free_chain.json", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// mech's names of the coordinates and speeds of the floating chain of `n` links: the pins',
/// then the base's rotation, then its position (velocity, in the base's frame).
fn names(n: usize) -> (Vec<String>, Vec<String>) {
    let pins: Vec<String> = (1..=n).map(|k| format!("q{k}")).collect();
    let base = |parts: &[&str]| {
        parts
            .iter()
            .map(|p| format!("float.{p}"))
            .collect::<Vec<_>>()
    };
    let coordinates = [pins.clone(), base(&["e0", "e1", "e2", "e3", "x", "y", "z"])].concat();
    let speeds = [pins, base(&["wx", "wy", "wz", "vx", "vy", "vz"])].concat();
    (coordinates, speeds)
}

fn check(n: usize) {
    let name = format!("free_chain{n}");
    let fixture = fixture();
    let states = fixture["models"][&name].as_array().unwrap();
    assert_eq!(states.len(), 3, "{name}: states in the fixture");
    let compiled = compile_text(&name, &source::floating_chain_source(n));
    let (coordinates, speeds) = names(n);
    for backend in [Backend::Native, Backend::Interpreter] {
        let model = TapeModel::with_backend(&compiled, backend);
        let ours: Vec<&str> = (0..model.nq()).map(|i| model.coordinate_name(i)).collect();
        assert_eq!(ours, coordinates, "{name}: coordinate order");
        let ours: Vec<&str> = (0..model.nu()).map(|i| model.speed_name(i)).collect();
        assert_eq!(ours, speeds, "{name}: speed order");
        for (k, state) in states.iter().enumerate() {
            let (q, u) = (json_numbers(&state["q"]), json_numbers(&state["u"]));
            let udot = accelerations(&model, &q, &u);
            for peer in ["udot_pinocchio", "udot_mujoco"] {
                let expected = json_numbers(&state[peer]);
                let floor = expected.iter().fold(0.0_f64, |a, b| a.max(b.abs()));
                for (i, e) in expected.iter().enumerate() {
                    assert_close(
                        &format!("{name} ({backend:?}) state {k} u̇[{}] vs {peer}", speeds[i]),
                        udot[i],
                        *e,
                        TOLERANCE,
                        floor,
                    );
                }
            }
        }
    }
}

#[test]
fn free_chain1_matches_pinocchio_and_mujoco() {
    check(1);
}

#[test]
fn free_chain2_matches_pinocchio_and_mujoco() {
    check(2);
}

#[test]
fn free_chain4_matches_pinocchio_and_mujoco() {
    check(4);
}
