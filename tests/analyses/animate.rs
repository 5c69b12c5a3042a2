//! `mech animate`: the bodies' positions against a closed form, and the page's drawing run
//! in Node.js (on the project's machines) with a canvas that records what is drawn.
//!
//! The pendulum (`models/pendulum.mech`): the bob's origin is at `l (sin θ, −cos θ, 0)`.

use std::process::Command;

use mech::animation::{animate, Animation};
use mech::output::CsvTable;
use mech::render::animation::page;
use mech_runtime::Model;

use crate::common;

const ANGLES: [f64; 3] = [0.0, std::f64::consts::FRAC_PI_2, 2.0];

fn pendulum_run() -> Animation {
    let compiled = common::compile_bundled("pendulum");
    let model = common::tape("pendulum");
    let values: Vec<f64> = (0..model.nparams()).map(|i| model.param(i)).collect();
    let run = CsvTable {
        header: vec!["t".into(), "q_hinge".into()],
        columns: vec![vec![0.0, 0.1, 0.2], ANGLES.to_vec()],
        lines: vec![2, 3, 4],
    };
    animate(&compiled, &values, &run).unwrap()
}

#[test]
fn the_bodies_move_as_the_closed_form_says() {
    let motion = pendulum_run();
    let bob = motion.bodies.iter().find(|b| b.name == "bob").unwrap();
    assert_eq!(bob.labels[0], "bob origin");
    let l = 0.025;
    for (sample, theta) in ANGLES.iter().enumerate() {
        let expected = [l * theta.sin(), -l * theta.cos(), 0.0];
        let at = bob.positions[sample][0];
        for k in 0..3 {
            assert!(
                (at[k] - expected[k]).abs() < 1e-15,
                "sample {sample}: {at:?} vs {expected:?}"
            );
        }
    }
}

#[test]
fn a_run_without_the_coordinates_is_refused_by_name() {
    let compiled = common::compile_bundled("pendulum");
    let run = CsvTable {
        header: vec!["t".into(), "q_elbow".into()],
        columns: vec![vec![0.0], vec![0.0]],
        lines: vec![2],
    };
    let message = animate(&compiled, &[0.01, 0.025, 9.81, 0.0], &run)
        .unwrap_err()
        .to_string();
    assert!(message.contains("no column `q_hinge`"), "{message}");
}

/// The page's own script, run by Node.js: `draw` puts the bob's dot where the orthographic
/// projection of the closed-form position puts it (front view: screen x along world x).
#[test]
fn the_page_draws_the_bob_where_it_is() {
    let html = page(&pendulum_run());
    assert!(
        !html.contains("http://") && !html.contains("https://"),
        "the page must need no network"
    );
    let script = &html[html.find("<script>").unwrap() + 8..html.find("</script>").unwrap()];
    let dir = common::scratch_dir("animate_page");
    let path = dir.join("page.js");
    let harness = r#"
const page = require("./page.js");
const calls = [];
const ctx = new Proxy({}, { get: (_, name) => (...args) => calls.push([name, ...args]), set: () => true });
const camera = { yaw: 0, pitch: 0, zoom: 1 };
page.draw(ctx, camera, 1, 400, 400);
const dots = calls.filter(c => c[0] === "arc").map(c => [c[1], c[2]]);
console.log(JSON.stringify({ dots, centre: page.data.centre, unit: page.data.unit, half: page.data.half }));
"#;
    std::fs::write(&path, script).unwrap();
    std::fs::write(dir.join("harness.js"), harness).unwrap();
    let output = match Command::new("node")
        .arg("harness.js")
        .current_dir(&dir)
        .output()
    {
        Ok(output) => output,
        Err(error) => panic!("node (Node.js, on the project's machines) could not run: {error}"),
    };
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let result: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let number = |v: &serde_json::Value| v.as_f64().unwrap();
    let (unit, half) = (number(&result["unit"]), number(&result["half"]));
    let centre: Vec<f64> = result["centre"]
        .as_array()
        .unwrap()
        .iter()
        .map(number)
        .collect();
    // At θ = π/2 the bob is at (l, 0, 0): screen x = 200 + 200·zoom·(x − cx)/(half·unit).
    let l = 0.025;
    let screen_x = 200.0 + 200.0 * (l - centre[0]) / (half * unit);
    let screen_y = 200.0 - 200.0 * (0.0 - centre[2]) / (half * unit);
    let dots = result["dots"].as_array().unwrap();
    let hit = dots.iter().any(|dot| {
        let (x, y) = (number(&dot[0]), number(&dot[1]));
        (x - screen_x).abs() < 0.05 && (y - screen_y).abs() < 0.05
    });
    assert!(hit, "no dot at ({screen_x}, {screen_y}): {dots:?}");
}
