//! Bad command-line values: each gets an error that names the option and the expected form.

use crate::support::{expect_errors, mech, model, scratch};

#[test]
fn a_value_that_is_not_a_quantity_names_the_option_and_the_form() {
    let dir = scratch("not_a_quantity");
    let form = "expected a number with an optional unit, such as `10 mN`";
    expect_errors(
        &dir,
        &[
            (&["statics", "{model:pendulum}", "--set", "m=NaN"], "--set m: expected a number with an optional unit, such as `10 mN` or `-2.5e-3` (only finite numbers); got `NaN`"),
            (&["statics", "{model:pendulum}", "--set", "m=inf"], "(only finite numbers); got `inf`"),
            (&["statics", "{model:pendulum}", "--set", "m=abc"], form),
            (&["statics", "{model:pendulum}", "--set", "m="], "--set: `m=` has no value after `=`"),
            (&["assemble", "{model:four_bar}", "--independent", "crank_angle=fast"], form),
        ],
    );
}

#[test]
fn a_unit_of_the_wrong_dimension_is_refused() {
    let dir = scratch("wrong_dimension");
    expect_errors(
        &dir,
        &[
            (
                &["statics", "{model:pendulum}", "--set", "m=1 m"],
                "--set m: `1 m` has unit m, but `m` needs kg (e.g. `m=2 kg`)",
            ),
            (
                &["statics", "{model:pendulum}", "--set", "l=0.1"],
                "--set l: `0.1` has no unit, but `l` needs m",
            ),
            // Units were ignored here: 1 m was read as 1 rad.
            (
                &[
                    "assemble",
                    "{model:four_bar}",
                    "--independent",
                    "crank_angle=1 m",
                ],
                "--independent crank_angle: `1 m` has unit m, but `crank_angle` needs no unit",
            ),
            (
                &[
                    "bode",
                    "{model:hamr_vi}",
                    "--drive",
                    "v_lift",
                    "--output",
                    "foot.z",
                    "--from",
                    "1 Hz",
                    "--to",
                    "1 kHz",
                    "--chirp",
                    "--chirp-amplitude",
                    "1 mm",
                ],
                "--chirp-amplitude v_lift: `1 mm` has unit m, but `v_lift` needs V",
            ),
        ],
    );
}

#[test]
fn negative_and_non_finite_numbers_get_the_options_own_check() {
    let dir = scratch("negative_numbers");
    let stiffness = |option: &'static str, value: &'static str| {
        vec![
            "flexure",
            "stiffness",
            "--width",
            "1 mm",
            "--thickness",
            "25 um",
            "--length",
            "100 um",
            option,
            value,
        ]
    };
    // clap's tip ("to pass '-1' as a value, use '-- -1'") was printed for these.
    expect_errors(
        &dir,
        &[
            (
                &[
                    "simulate",
                    "{model:pendulum}",
                    "--t-end",
                    "-1",
                    "--out",
                    "run.csv",
                ],
                "--t-end: expected a positive time such as `2 s` or `500 ms`, got `-1`",
            ),
            (
                &[
                    "simulate",
                    "{model:pendulum}",
                    "--t-end",
                    "1",
                    "--rtol",
                    "-1e-6",
                    "--out",
                    "run.csv",
                ],
                "--rtol",
            ),
            (
                &[
                    "simulate",
                    "{model:pendulum}",
                    "--t-end",
                    "1",
                    "--atol",
                    "NaN",
                    "--out",
                    "run.csv",
                ],
                "expected a number above zero",
            ),
            (
                &stiffness("--poisson", "0.7"),
                "Poisson's ratio between -1 and 0.5",
            ),
            (
                &stiffness("--loss-factor", "inf"),
                "expected a number at or above zero",
            ),
        ],
    );
}

#[test]
fn counts_are_bounded_before_anything_is_allocated() {
    let dir = scratch("counts");
    expect_errors(
        &dir,
        &[
            // Aborted allocating 800 GB.
            (&["simulate", "{model:pendulum}", "--t-end", "1 s", "--dt-out", "1e-12 s", "--out", "run.csv"], "gives 1.000e12 samples, more than the 1000000 a run stores; choose an interval of at least 1.000e-6 s"),
            // Ran without bound.
            (&["bode", "{model:hamr_vi}", "--drive", "v_lift", "--output", "foot.z", "--from", "1 Hz", "--to", "1 kHz", "--points", "100000000"], "'--points <POINTS>': expected a whole number from 2 to 1000000"),
            (&["bode", "{model:hamr_vi}", "--drive", "v_lift", "--output", "foot.z", "--from", "1 Hz", "--to", "1 kHz", "--points", "1"], "expected a whole number from 2"),
            (&["bode", "{model:hamr_vi}", "--drive", "v_lift", "--output", "foot.z", "--from", "1 Hz", "--to", "1 kHz", "--points", "0"], "expected a whole number from 2"),
        ],
    );
}

#[test]
fn settings_given_twice_or_signals_where_a_constant_is_held_are_refused() {
    let dir = scratch("repeated");
    expect_errors(
        &dir,
        &[
            (&["statics", "{model:pendulum}", "--set", "m=1 g", "--set", "m=2 g"], "--set m: given twice (`m=1 g` and `m=2 g`); give it once"),
            (&["statics", "{model:hamr_vi}", "--input", "v_lift=10 V", "--input", "v_lift=20 V"], "--input v_lift: given twice"),
            // Was accepted: the statics found an "equilibrium" of a negative mass.
            (&["statics", "{model:pendulum}", "--set", "m=-1 kg"], "--set m=-1 kg: body `bob` has a negative mass"),
            // Read at t = 0 without a word before.
            (&["statics", "{model:hamr_vi}", "--input", "v_lift=sine(amplitude=100 V, frequency=1 Hz)"], "--input v_lift: `mech statics` holds inputs constant; give a value such as `v_lift=2 V`"),
            (&["linearize", "{model:hamr_vi}", "--input", "v_lift=sine(amplitude=100 V, frequency=1 Hz)"], "`mech linearize` holds inputs constant"),
        ],
    );
}

/// `mech linearize --steady --sweep`: the form, the name, the unit and the count are checked
/// before any work, and the options that need `--steady` or `--sweep` say so.
#[test]
fn steady_sweeps_are_checked() {
    let dir = scratch("steady_sweeps");
    let bicycle = "{model:benchmarks/whipple_bicycle}";
    let steady = |sweep: &'static str| -> Vec<&'static str> {
        vec!["linearize", bicycle, "--steady", "--sweep", sweep]
    };
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (steady("rear=0..3 rad/s"), "--sweep `rear=0..3 rad/s`: expected `NAME=FROM..TO:N`, e.g. `v=0..10 m/s:41`; no `:N`"),
        (steady("rear 0..3:4"), "no `=`"),
        (steady("rear=0..3 rad/s:1"), "N is a whole number from 2 to 10000"),
        (steady("rear=0..3 rad/s:100000"), "N is a whole number from 2 to 10000"),
        (steady("speed=0..3 m/s:4"), "`speed` is neither a parameter nor a speed of `whipple_bicycle` (w, c, lambda, rR, rF, v, x, y, yaw, roll, pitch, rear, steer, front)"),
        (steady("rear=0..3 m/s:4"), "--sweep rear: `0 m/s` has unit m/s, but `rear` needs an angular speed (e.g. `rear=2 rad/s`)"),
        (vec!["linearize", bicycle, "--sweep", "rear=0..3 rad/s:4"], "--steady"),
        (vec!["linearize", bicycle, "--steady", "--plot", "e.svg"], "--sweep"),
        (vec!["linearize", "{model:ball_double_pendulum}", "--steady"], "steady-motion linearization of model `ball_double_pendulum` is not supported yet"),
        // Velocity constraints: the analyses on the coordinates point at the constraint.
        (vec!["statics", "{model:rolling_disc}"], "error[E0602]: statics of model `rolling_disc` is not possible: it has velocity constraints"),
        (vec!["linearize", "{model:rolling_disc}"], "rolling_disc.mech:25:1"),
        (vec!["simulate", "{model:rolling_disc}", "--t-end", "0.1", "--out", "run.csv", "--method", "rosenbrock"], "`roll` is a condition on the speeds, with no form in the coordinates"),
    ];
    let cases: Vec<(&[&str], &str)> = cases.iter().map(|(a, e)| (&a[..], *e)).collect();
    expect_errors(&dir, &cases);
}

/// Options on a model with `speed` declarations: `--independent` on a loop model says why a
/// coordinate cannot be held (not that it is a quaternion's part), and `--u0` takes each
/// chosen speed in its own unit.
#[test]
fn options_on_a_model_with_chosen_speeds() {
    let dir = scratch("chosen_speeds_independent");
    let text = std::fs::read_to_string(model("four_bar")).unwrap();
    let chosen = format!(
        "{text}\nspeed crank_rate = crank_angle.u;\nspeed coupler_rate = coupler_angle.u;\n\
         speed rocker_rate = rocker_angle.u;\n"
    );
    std::fs::write(dir.join("four_bar_speeds.mech"), chosen).unwrap();
    expect_errors(
        &dir,
        &[(
            &[
                "assemble",
                "four_bar_speeds.mech",
                "--independent",
                "crank_angle",
            ],
            "--independent crank_angle: the model's speeds are chosen by `speed` declarations, \
             so no coordinate's rate is a speed, and the loop closure holds coordinates whose \
             rate is a speed",
        )],
    );
    // A chosen speed's unit is its own (the tip's velocity, m/s), not that of the coordinate
    // with its index (the elbow's angle).
    let pendulum = "{model:double_pendulum_speeds}";
    expect_errors(
        &dir,
        &[(
            &[
                "simulate",
                pendulum,
                "--t-end",
                "0.01",
                "--out",
                "a.csv",
                "--u0",
                "tip_speed=1 rad/s",
            ],
            "--u0 tip_speed: `1 rad/s` is an angular speed, but `tip_speed` needs m/s",
        )],
    );
    let run = mech(
        &dir,
        &[
            "simulate",
            pendulum,
            "--t-end",
            "0.01",
            "--out",
            "b.csv",
            "--u0",
            "tip_speed=1 m/s",
        ],
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
}

#[test]
fn escape_sequences_in_an_input_file_are_shown_not_sent_to_the_terminal() {
    let dir = scratch("escapes");
    let model = "model x;\nbody b { mass = 1 g; }\nparam \u{1b}[2Jq = 3;\n";
    std::fs::write(dir.join("escape.mech"), model).unwrap();
    let run = crate::support::mech(&dir, &["check", "escape.mech"]);
    assert_eq!(run.code, Some(1), "{}", run.stderr);
    assert!(!run.stderr.contains('\u{1b}'), "{:?}", run.stderr);
    assert!(run.stderr.contains("param ␛[2Jq = 3;"), "{}", run.stderr);
    assert!(run.stderr.contains("escape.mech:3:7"), "{}", run.stderr);
}

/// A model with ball joints (unit quaternions, `q̇ = W(q) u`): the analyses written for
/// `q̇ = u` refuse it with one message naming what is not supported and what works, and
/// nothing indexes `u` by a coordinate's index past its end.
#[test]
fn analyses_not_written_for_quaternions_refuse_a_ball_joint_model() {
    let dir = scratch("quaternion_analyses");
    let refused = "is not supported yet: its coordinates' rates are not its speeds (q̇ = \
                   W(q) u: a ball or free joint's unit quaternion or Euler angles, or `speed` \
                   declarations)";
    let model = "{model:ball_double_pendulum}";
    expect_errors(
        &dir,
        &[
            (&["statics", model], refused),
            (&["linearize", model], refused),
            (
                &["simulate", model, "--t-end", "0.1", "--out", "run.csv", "--method", "rosenbrock"],
                "simulation in reduced coordinates of model `ball_double_pendulum` is not supported yet",
            ),
        ],
    );
    for args in [
        &["check", model][..],
        &["assemble", model, "--out", "state.csv"],
        &[
            "simulate", model, "--t-end", "0.1", "--out", "run.csv", "--plot", "run.svg",
        ],
    ] {
        let run = crate::support::mech(&dir, args);
        assert_eq!(run.code, Some(0), "mech {}: {}", args.join(" "), run.stderr);
    }
    let header = std::fs::read_to_string(dir.join("run.csv")).unwrap();
    let header = header.lines().next().unwrap();
    assert!(
        header.starts_with("t,q_shoulder.e0,") && header.contains(",u_elbow.wz,ke,pe,"),
        "{header}"
    );
}

/// `simulate --q0`, `--u0` (each value in its coordinate's or speed's unit),
/// `--max-steps` (a budget the run stops at, with the time it reached; `bode --chirp` too)
/// and `--threads` (1 or 2).
#[test]
fn initial_states_and_the_step_budget_are_checked() {
    let dir = scratch("initial_state");
    let simulate = |model: &'static str, option: &'static str, value: &'static str| {
        vec![
            "simulate", model, "--t-end", "1 s", "--out", "run.csv", option, value,
        ]
    };
    expect_errors(
        &dir,
        &[
            (
                &simulate("{model:pendulum}", "--q0", "hinge=10 mm"),
                "--q0 hinge: `10 mm` has unit m, but `hinge` needs no unit",
            ),
            (
                &simulate("{model:pendulum}", "--u0", "hinge=2"),
                "--u0 hinge: `2` has no unit, but `hinge` needs an angular speed (e.g. `hinge=2 rad/s`)",
            ),
            (
                &simulate("{model:cart_pendulum}", "--u0", "x=2 rad/s"),
                "--u0 x: `2 rad/s` is an angular speed, but `x` needs m/s (e.g. `x=2 m/s`)",
            ),
            (
                &simulate("{model:pendulum}", "--q0", "hing=2 deg"),
                "--q0: unknown coordinate `hing`; coordinates of `pendulum`: hinge",
            ),
            (
                &simulate("{model:pendulum}", "--u0", "hing=2 rad/s"),
                "--u0: unknown speed `hing`; speeds of `pendulum`: hinge",
            ),
            (
                &simulate("{model:ball_double_pendulum}", "--q0", "shoulder.e0=1"),
                "--q0 shoulder.e0: a quaternion's parts cannot be set one by one",
            ),
            (
                &simulate("{model:pendulum}", "--max-steps", "0"),
                "expected a whole number of at least 1",
            ),
            (
                &simulate("{model:pendulum}", "--max-steps", "20"),
                "simulation of `pendulum` failed: gave up at t = ",
            ),
            (
                &simulate("{model:floating_four_bar}", "--independent", "base.e1"),
                "--independent base.e1: a quaternion's parts cannot be held one by one",
            ),
            (
                &simulate("{model:pendulum}", "--threads", "3"),
                "invalid value '3' for '--threads <THREADS>': 3 is not in 1..=2",
            ),
            (
                &[
                    "bode",
                    "{model:two_mass_chain}",
                    "--drive",
                    "push",
                    "--output",
                    "x2.x",
                    "--from",
                    "1 Hz",
                    "--to",
                    "10 Hz",
                    "--chirp",
                    "--max-steps",
                    "50",
                ],
                "gave up at t = ",
            ),
        ],
    );
}

/// `--q0` and `--u0` are where the run starts: the CSV's first row holds them, in SI.
#[test]
fn the_run_starts_where_q0_and_u0_say() {
    let dir = scratch("initial_state_used");
    let pendulum = model("pendulum");
    let args = [
        "simulate",
        &pendulum,
        "--t-end",
        "10 ms",
        "--dt-out",
        "5 ms",
        "--out",
        "run.csv",
        "--q0",
        "hinge=10 deg",
        "--u0",
        "hinge=2 rad/s",
    ];
    let run = mech(&dir, &args);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let csv = std::fs::read_to_string(dir.join("run.csv")).unwrap();
    let first: Vec<f64> = csv
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    // t, q_hinge, u_hinge, …
    assert_eq!(first[0], 0.0);
    assert!(
        (first[1] - 10f64.to_radians()).abs() < 1e-15,
        "{}",
        first[1]
    );
    assert_eq!(first[2], 2.0);
}
