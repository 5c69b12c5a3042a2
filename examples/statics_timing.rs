//! Timing of the runtime statics on the HAMR-VI leg (docs/benchmarks.md §10): one static
//! equilibrium from the rest position with one or both actuators driven at ±112.5 V, free,
//! with the foot held along z or x, and held along z with a 30 % side load along y; then the
//! force/deflection experiment's sensor sweep. Tape model, as `mech diagnose` and the
//! experiments use it. Times are the fastest of 5 runs per case; the residuals are
//! `max |F + Jᵀλ|` (model units) and `max |φ|` at the solution.
//!
//! ```text
//! cargo run --release --example statics_timing
//! ```

use mech::experiments::leg::{Dof, ForceTest, Leg, Sensor};
use mech_runtime::{solve_statics_with_loads, Fixture, SideLoad, StaticsOptions};

mod common;
use common::{fastest, leg_spec};

fn main() {
    let leg = Leg::open(&leg_spec("hamr_vi")).expect("the leg opens");
    let rest_inputs = leg.inputs(0.0, 0.0);
    let rest = leg
        .equilibrium(&leg.q0, &rest_inputs, &[])
        .expect("rest equilibrium")
        .q;
    let foot = leg.foot_at(&rest, &rest_inputs);
    let v = 112.5;
    let drives = [(v, 0.0), (0.0, v), (v, v), (-v, v), (v, -v), (-v, -v)];
    let side = |held| SideLoad {
        fixture: 0,
        held,
        along: 1,
        ratio: 0.3,
    };
    let cases: [(&str, Vec<Fixture>, Vec<SideLoad>); 4] = [
        ("free", Vec::new(), Vec::new()),
        ("foot z held", vec![leg.fixture(foot, vec![2])], Vec::new()),
        ("foot x held", vec![leg.fixture(foot, vec![0])], Vec::new()),
        (
            "foot z held, 30 % side load",
            vec![leg.fixture(foot, vec![2])],
            vec![side(2)],
        ),
    ];
    println!("| case | v_lift, v_swing (V) | Newton iterations | ms per equilibrium | force residual | constraint residual |");
    println!("|---|---|---|---|---|---|");
    for (name, fixtures, loads) in &cases {
        let mut both = Vec::new();
        for &(lift, swing) in &drives {
            let inputs = leg.inputs(lift, swing);
            let (time, result) = fastest(5, || {
                let mut q = rest.clone();
                let options = StaticsOptions::default();
                solve_statics_with_loads(
                    leg.model(),
                    0.0,
                    &mut q,
                    &inputs,
                    fixtures,
                    loads,
                    &options,
                )
            });
            if lift != 0.0 && swing != 0.0 {
                both.push(time);
            }
            match result {
                Ok(eq) => println!(
                    "| {name} | {lift}, {swing} | {} | {:.3} | {:.1e} | {:.1e} |",
                    eq.iterations,
                    time * 1e3,
                    eq.force_residual,
                    eq.constraint_residual
                ),
                Err(e) => println!(
                    "| {name} | {lift}, {swing} | failed: {e} | {:.3} | | |",
                    time * 1e3
                ),
            }
        }
        let mean = both.iter().sum::<f64>() / both.len() as f64;
        println!(
            "| {name}: mean, both driven | | | **{:.3}** | | |",
            mean * 1e3
        );
    }
    println!();
    println!("| force/deflection sweep, 225 V, 127 µm steps | sensor points | ms per point |");
    println!("|---|---|---|");
    for dof in [Dof::Lift, Dof::Swing] {
        for fraction in [0.0, 0.3] {
            let (time, test) = fastest(5, || {
                ForceTest::new(dof, 225.0, Sensor::Steps(127e-6))
                    .off_axis(fraction)
                    .run(&leg)
                    .expect("the sweep runs")
            });
            println!(
                "| {}, off-axis load {:.0} % | {} | {:.3} |",
                dof.name(),
                fraction * 100.0,
                test.points.len(),
                time * 1e3 / test.points.len() as f64
            );
        }
    }
}
