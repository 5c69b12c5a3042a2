//! Runs the `mech` binary built for the tests in a scratch folder of its own.

use std::path::{Path, PathBuf};
use std::process::Command;

/// What a run printed and how it ended.
pub struct Run {
    #[allow(dead_code)] // read by the cases that check what was written
    pub stdout: String,
    pub stderr: String,
    /// `None` if killed by a signal; 101 is a Rust panic.
    pub code: Option<i32>,
}

/// A fresh empty folder under the target directory, named after the test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("robustness")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The path of a bundled model.
pub fn model(name: &str) -> String {
    format!("{}/models/{name}.mech", env!("CARGO_MANIFEST_DIR"))
}

/// Runs `mech ARGS` in `dir`; `{model:NAME}` in an argument is replaced by that bundled
/// model's path.
pub fn mech(dir: &Path, args: &[&str]) -> Run {
    let args: Vec<String> = args
        .iter()
        .map(|arg| match arg.strip_prefix("{model:") {
            Some(rest) => model(rest.trim_end_matches('}')),
            None => arg.to_string(),
        })
        .collect();
    let output = Command::new(env!("CARGO_BIN_EXE_mech"))
        .args(&args)
        .current_dir(dir)
        .output()
        .unwrap();
    Run {
        stdout: String::from_utf8_lossy(&output.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
        code: output.status.code(),
    }
}

/// Runs every `(arguments, expected message)` case and asserts that each fails with exit
/// code 1 (an error) or 2 (clap's usage error), not a panic (101) or a signal, and prints
/// the expected text on stderr. All failures are listed together.
pub fn expect_errors(dir: &Path, cases: &[(&[&str], &str)]) {
    let mut failures = Vec::new();
    for (args, expected) in cases {
        let run = mech(dir, args);
        if !matches!(run.code, Some(1 | 2)) || !run.stderr.contains(expected) {
            failures.push(format!(
                "mech {}\n  exit {:?}, expected 1 or 2\n  stderr: {}\n  expected to contain: {expected}",
                args.join(" "),
                run.code,
                run.stderr.trim_end()
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
