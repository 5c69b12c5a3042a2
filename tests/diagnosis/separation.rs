//! Which standard test tells tied causes apart (`mech::diagnose::separate`).

use crate::common;

use mech::diagnose::experiment::Extensions;
use mech::diagnose::separate::{separations, SEPARATES};
use mech::experiments::leg::{Dof, ForceTest, Leg, Sensor};

/// HAMR-VI with the lift crank-slider's flexure `name` twice as stiff.
fn stiffer(name: &str) -> Leg {
    let mut leg = Leg::open(&common::hamr_vi_spec()).unwrap();
    let k = leg.param(name).unwrap();
    common::set_leg_param(&mut leg, name, 2.0 * k);
    leg
}

/// Two causes in series on the lift side (l1 or l3 twice as stiff): every probe is scored,
/// best first; the lift force/deflection probe's χ² equals one computed here from the force
/// tests themselves (0.3 mN noise, the sensor every 127 µm out to 4 mm); the same model
/// twice separates by nothing.
#[test]
fn the_probes_score_how_far_apart_two_causes_predict() {
    let legs = || {
        vec![
            (stiffer("k_l1"), Extensions::default()),
            (stiffer("k_l3"), Extensions::default()),
        ]
    };
    let spec = common::hamr_vi_spec();
    let scored = separations(&spec, &legs());
    assert_eq!(scored.len(), 4, "{scored:?}");
    assert!(
        scored.windows(2).all(|w| w[0].chi2 >= w[1].chi2),
        "{scored:?}"
    );
    let lift = scored
        .iter()
        .find(|s| s.probe.starts_with("lift force/deflection"))
        .unwrap();
    let distances: Vec<f64> = (0..32).map(|k| 127e-6 * k as f64).collect();
    let forces = |leg: &Leg| -> Vec<f64> {
        ForceTest::new(Dof::Lift, 225.0, Sensor::At(distances.clone()))
            .run(leg)
            .unwrap()
            .points
            .iter()
            .map(|p| p.force.max(0.0))
            .collect()
    };
    let by_hand: f64 = forces(&stiffer("k_l1"))
        .iter()
        .zip(forces(&stiffer("k_l3")))
        .map(|(a, b)| ((a - b) / 0.3e-3).powi(2))
        .sum();
    assert!(
        (lift.chi2 / by_hand - 1.0).abs() < 1e-6 && by_hand > 0.0,
        "probe χ² {} against {by_hand}",
        lift.chi2
    );
    let same = separations(
        &spec,
        &[
            (stiffer("k_l1"), Extensions::default()),
            (stiffer("k_l1"), Extensions::default()),
        ],
    );
    assert!(same.iter().all(|s| s.chi2 < 1e-12), "{same:?}");
    assert!(scored[0].chi2 > SEPARATES, "{scored:?}");
}
