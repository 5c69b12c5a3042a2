//! Runs the example binary: it asserts its own checks (the four-bar's loop stays closed,
//! its energy is conserved) and fails with a non-zero status when one does not hold.

#[test]
fn the_example_runs_and_its_checks_hold() {
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_mech-embed-example"))
        .output()
        .expect("the example binary runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(stdout.contains("kinetic energy"), "{stdout}");
    assert!(stdout.contains("max |φ|"), "{stdout}");
}
