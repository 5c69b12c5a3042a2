//! Timing of the force/deflection experiment's sensor sweep (docs/benchmarks.md §10) on
//! HAMR-VI and on the model-form extension `mech diagnose` fits (`src/diagnose/extend.rs`:
//! fb3 twisting about y, every other hinge and loop closure compliant off its axis; 20
//! coordinates and 11 degrees of freedom against 8 and 2). Each sensor position is one static
//! equilibrium with the foot held (`solve_statics_with_loads`); the sweep starts each from
//! the last. Swing and lift at 225 V, 127 µm steps, with and without the 30 % off-axis load.
//! Times are the fastest of 5 sweeps, per sensor point.
//!
//! ```text
//! cargo run --release --example extended_statics_timing
//! ```

use mech::diagnose::extend::{open_leg, Extension};
use mech::experiments::leg::{Dof, ForceTest, Leg, Sensor};

mod common;
use common::{fastest, leg_spec};

fn main() {
    let spec = leg_spec("hamr_vi");
    let legs: [(&str, Leg); 2] = [
        ("HAMR-VI", Leg::open(&spec).expect("the leg opens")),
        (
            "extended (fb3 twist)",
            open_leg(&spec, &Extension::Twist(vec![("fb3".into(), 1)]))
                .expect("the extension opens"),
        ),
    ];
    println!(
        "| model | sweep, 225 V, 127 µm steps | sensor points | ms per point | ms per sweep |"
    );
    println!("|---|---|---|---|---|");
    for (name, leg) in &legs {
        for dof in [Dof::Swing, Dof::Lift] {
            for fraction in [0.0, 0.3] {
                let (best, test) = fastest(5, || {
                    ForceTest::new(dof, 225.0, Sensor::Steps(127e-6))
                        .off_axis(fraction)
                        .run(leg)
                        .expect("the sweep runs")
                });
                let points = test.points.len();
                println!(
                    "| {name} | {}, off-axis load {:.0} % | {points} | {:.2} | {:.1} |",
                    dof.name(),
                    fraction * 100.0,
                    best * 1e3 / points as f64,
                    best * 1e3
                );
            }
        }
    }
}
