//! The model's physical rules at run time: a `--set` value that breaks one (a negative mass,
//! an impossible inertia, a flexure thickness that is not positive) is refused with the rule,
//! as the same value written in the model is refused when it is read (E05xx, ui tests).

use std::path::Path;

use crate::common::bundled_path;

use mech::session::{Error, Session};
use mech_codegen::ir::plausible::Violation;
use mech_runtime::Model;

fn open(model: &str, sets: &[&str]) -> Result<Session, Error> {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Session::open(Path::new(&bundled_path(model)), &sets, &[])
}

/// The rule broken, or a panic naming what happened instead.
fn broken(result: Result<Session, Error>) -> Violation {
    match result {
        Err(Error::Implausible { broken, .. }) => broken.violation,
        Err(other) => panic!("expected an implausible value, got: {other}"),
        Ok(_) => panic!("expected an implausible value, the session opened"),
    }
}

#[test]
fn a_negative_mass_is_refused_and_zero_is_kept() {
    let violation = broken(open("pendulum", &["m=-3 g"]));
    assert_eq!(violation, Violation::NegativeMass(-0.003));
    let massless = open("pendulum", &["m=0 g"]).expect("a massless bob is legal");
    let m = massless.model.param_index("m").expect("pendulum has m");
    assert_eq!(massless.model.param(m), 0.0);
}

#[test]
fn settings_are_checked_together_and_a_refused_one_is_not_kept() {
    // The rig's pendulum has I = I_p − m L_cm² about its centre of mass: L_cm = 3 mm → 30 mm
    // alone makes it negative, with I_p raised as well it is a plausible pendulum.
    assert!(matches!(
        broken(open("flexure_rig", &["L_cm=30 mm"])),
        Violation::NegativeMoment(_)
    ));
    for sets in [
        ["L_cm=30 mm", "I_p=1e-6 kg*m^2"],
        ["I_p=1e-6 kg*m^2", "L_cm=30 mm"],
    ] {
        open("flexure_rig", &sets).expect("plausible together, in either order");
    }

    let mut session = open("flexure_rig", &[]).expect("the bundled rig");
    let h = session.model.param_index("h").expect("the rig has h");
    let before = session.model.param(h);
    let error = session.set("h=-1 um").expect_err("a negative thickness");
    assert!(
        error.to_string().starts_with(
            "--set h=-1 um: flexure `specimen_hinge` has a `thickness` that is not positive"
        ),
        "{error}"
    );
    assert_eq!(session.model.param(h), before, "the refused value was kept");
    session.set("h=30 um").expect("a positive thickness");
    assert_eq!(session.model.param(h), 30e-6);
    // In SI without a unit (Python's `set_si`): the same rule.
    let error = session.set_si(h, 0.0).expect_err("a zero thickness");
    assert!(
        error.to_string().starts_with("--set h=0: flexure"),
        "{error}"
    );
    assert_eq!(session.model.param(h), 30e-6);
}

/// A contact's ranges (E0506) at run time: a negative friction coefficient or a zero
/// stiffness set on the bundled ball is refused; zero damping and friction are kept.
#[test]
fn a_contact_property_out_of_range_is_refused() {
    let violation = broken(open("contact_ball", &["mu=-0.1"]));
    assert!(
        matches!(violation, Violation::ContactOutOfRange { field: "friction", positive: false, value, .. } if value == -0.1),
        "{violation:?}"
    );
    let violation = broken(open("contact_ball", &["k=0 N/m"]));
    assert!(
        matches!(
            violation,
            Violation::ContactOutOfRange {
                field: "stiffness",
                positive: true,
                ..
            }
        ),
        "{violation:?}"
    );
    open("contact_ball", &["mu=0", "alpha=0 s/m"]).expect("an elastic frictionless contact");
}
