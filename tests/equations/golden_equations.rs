//! Golden equations: what `mech derive MODEL --emit equations` prints for every bundled model
//! stays as it is, so a change in the front end, the symbolic engine or Kane's method that
//! alters any equation shows up as a diff.
//!
//! Consumes: `models/<stem>.mech`. Produces: one test per model, named after it, comparing
//! `describe::equations_text` with `tests/golden/equations/<stem>.txt`, plus one that fails
//! when a model and the list in `tests_per_file!` differ (so a new model cannot go
//! unchecked). `MECH_BLESS=1 cargo test --test equations golden_equations` rewrites the golden files
//! instead.

use crate::support;

use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn golden_dir() -> PathBuf {
    root().join("tests/golden/equations")
}

/// Checks (or, with `MECH_BLESS=1`, rewrites) the golden equations of `models/<stem>.mech`.
fn check(stem: &str) {
    let compiled = mech_codegen::Compiled::from_path(root().join(format!("models/{stem}.mech")))
        .unwrap_or_else(|errors| panic!("models/{stem}.mech does not compile:{errors:?}"));
    let actual = mech::describe::equations_text(&compiled).expect("a bundled model prints");
    let golden = golden_dir().join(format!("{stem}.txt"));
    if support::blessing() {
        std::fs::create_dir_all(golden_dir()).expect("writable tests/golden");
        std::fs::write(&golden, &actual).expect("writable golden file");
        return;
    }
    let expected = std::fs::read_to_string(&golden).unwrap_or_default();
    if actual != expected {
        // The texts run to 130 kB: show the first differing line, not both files.
        let line = actual
            .lines()
            .zip(expected.lines())
            .position(|(a, e)| a != e)
            .unwrap_or_else(|| actual.lines().count().min(expected.lines().count()));
        let show = |text: &str| {
            text.lines()
                .nth(line)
                .unwrap_or("(end of text)")
                .to_string()
        };
        panic!(
            "{} differs from `mech derive models/{stem}.mech --emit equations` at line {} \
             (MECH_BLESS=1 to update):\nexpected: {}\nactual:   {}",
            golden.display(),
            line + 1,
            show(&expected),
            show(&actual)
        );
    }
}

tests_per_file! {
    check:
    andrews,
    ball_double_pendulum,
    cart_pendulum,
    chain1,
    chain2,
    chain4,
    compliant_four_bar,
    contact_ball,
    contact_plate,
    double_pendulum_3d,
    double_pendulum_speeds,
    flexure_rig,
    floating_chain,
    floating_four_bar,
    four_bar,
    gimbal_rig,
    hamr_v2,
    hamr_vi,
    mixed_chain,
    pendulum,
    quadruped,
    rolling_disc,
    slider_crank,
    spherical_five_bar,
    spring_pendulum,
    state_forces,
    triple_pendulum_3d,
    two_mass_chain,
}

#[test]
fn every_bundled_model_has_a_golden_test() {
    let models = root().join("models");
    support::assert_lists_every_file(
        LISTED,
        &models,
        "mech",
        "tests/equations/golden_equations.rs",
    );
}

/// `n` links hanging along -z, pins alternating about x and y (the benchmark's 3D chain with
/// one set of parameters).
fn chain(n: usize) -> String {
    let mut text = String::from(
        "param m = 1 kg; param l = 1 m; param d = 0.5 m; param I = 0.08 kg*m^2;\n\
         gravity = [0, 0, -9.81 m/s^2];\n",
    );
    for k in 1..=n {
        let parent = if k == 1 {
            "newtonian".to_string()
        } else {
            format!("link{}", k - 1)
        };
        let at = if k == 1 {
            ""
        } else {
            "parent_point = [0, 0, -l];"
        };
        let axis = if k % 2 == 1 { "x" } else { "y" };
        text.push_str(&format!(
            "body link{k} {{ mass = m; com = [0, 0, -d]; inertia = [I, I, I / 4]; }}\n\
             joint q{k} = pin({parent}, link{k}) {{ axis = {axis}; {at} q0 = 0.5 rad; }}\n"
        ));
    }
    text
}

#[test]
fn equations_too_large_to_print_are_refused_before_printing() {
    // The estimate is the printout's size: every token of the right-hand sides but brackets.
    let small = crate::common::compile_text("chain6", &chain(6));
    let text = mech::describe::equations_text(&small).expect("6 links print");
    let tokens: u64 = text
        .lines()
        .filter(|line| !line.starts_with("//"))
        .map(|line| {
            let (_, rhs) = line.split_once(" = ").expect("NAME = EXPR");
            rhs.replace(['(', ')'], " ").split_whitespace().count() as u64
        })
        .sum();
    let roots = {
        let eqs = &small.equations;
        let upper = (0..eqs.nu).flat_map(|r| (r..eqs.nu).map(move |s| r + eqs.nu * s));
        let mut roots: Vec<_> = upper.map(|i| eqs.mass_matrix[i]).collect();
        roots.extend(eqs.forcing.iter().chain(&eqs.outputs));
        roots
    };
    assert_eq!(small.equations.pool.printed_size(&roots), tokens);

    // 16 links would print about half a gigabyte: refused, and the message says what to use.
    let large = crate::common::compile_text("chain16", &chain(16));
    let refused = mech::describe::equations_text(&large).expect_err("too large to print");
    assert!(refused.nodes > mech::describe::MAX_PRINTED_NODES);
    let message = refused.to_string();
    assert!(
        message.contains("`--emit tape` or `--emit rust`"),
        "{message}"
    );
}
