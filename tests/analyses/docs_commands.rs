//! The commands the README and `docs/` show are real: every fenced block line `$ mech …` is
//! run (by `sh`, from a scratch folder that links the repository's `models/`, `docs/`,
//! `examples/` and `experiments/`, and `reference/`, the shared reference folder beside the
//! repository), and what it prints, stdout then stderr, must be the lines
//! the page shows under it. A line `...` or `[...]` on the page stands for any number of
//! printed lines; `$ echo $?` shows the exit code of the command before it; timings
//! (`in 1.2 s`) are masked. A page marks a block before its fence with
//! `<!-- docs-test: slow -->` (run by `cargo test --test analyses -- --ignored`, as CI does)
//! or `<!-- docs-test: skip (why) -->`.
//!
//! Every mismatch of a run is reported together, each with its page, line and a diff, so
//! a changed output is fixed by rerunning the command shown.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::markdown;

/// One documented command and the output the page shows for it.
struct Documented {
    page: String,
    line: usize,
    command: String,
    expected: Vec<String>,
    slow: bool,
}

const PAGES: [&str; 9] = [
    "README.md",
    "docs/analysis.md",
    "docs/benchmarks.md",
    "docs/diagnose.md",
    "docs/experiments.md",
    "docs/flexure-and-actuator.md",
    "docs/import.md",
    "docs/mech-language.md",
    "docs/sweep.md",
];

fn documented_commands() -> Vec<Documented> {
    let root = env!("CARGO_MANIFEST_DIR");
    let mut commands = Vec::new();
    for page in PAGES {
        let text = std::fs::read_to_string(format!("{root}/{page}")).unwrap();
        for block in markdown::blocks(&text) {
            let marker = block.preceding.strip_prefix("<!-- docs-test:");
            if marker.is_some_and(|m| m.trim_start().starts_with("skip"))
                || !block.text.starts_with("$ ")
            {
                continue;
            }
            let slow = marker.is_some_and(|m| m.trim_start().starts_with("slow"));
            let mut lines = block.text.lines().enumerate().peekable();
            while let Some((offset, first)) = lines.next() {
                let mut command = first.strip_prefix("$ ").unwrap_or(first).to_string();
                while command.ends_with('\\') {
                    let Some((_, next)) = lines.next() else { break };
                    command.push('\n');
                    command.push_str(next);
                }
                let mut expected = Vec::new();
                while let Some((_, line)) = lines.next_if(|(_, l)| !l.starts_with("$ ")) {
                    expected.push(line.to_string());
                }
                while expected.last().is_some_and(|l| l.trim().is_empty()) {
                    expected.pop();
                }
                commands.push(Documented {
                    page: page.to_string(),
                    line: block.line + offset,
                    command,
                    expected,
                    slow,
                });
            }
        }
    }
    commands
}

/// A scratch folder that sees the repository's inputs under their documented paths, with
/// `mech` on the PATH.
fn workspace() -> PathBuf {
    let dir = crate::common::scratch_dir("docs_commands");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::create_dir_all(dir.join("bin")).unwrap();
    for (link, target) in [
        ("models", root.join("models")),
        ("docs", root.join("docs")),
        ("examples", root.join("examples")),
        ("experiments", root.join("experiments")),
        // The URDF files of docs/import.md: the shared reference folder beside the
        // repository (read in place, never copied into it).
        ("reference", root.join("../shared/reference")),
        ("bin/mech", PathBuf::from(env!("CARGO_BIN_EXE_mech"))),
    ] {
        let link = dir.join(link);
        if std::fs::symlink_metadata(&link).is_err() {
            std::os::unix::fs::symlink(target, link).unwrap();
        }
    }
    bad_flexure_data(
        &root.join("examples/flexure_data"),
        &dir.join("bad_flexure_data"),
    );
    dir
}

/// `bad_flexure_data/` as docs/flexure-and-actuator.md describes it: the specimens of
/// `examples/flexure_data/` with `u02.csv` rewritten in degrees (its `.toml` still declaring
/// radians), `NaN` as the angle on line 102 of `u03.csv`, and `c03.csv` cut after 59 rows.
fn bad_flexure_data(good: &Path, bad: &Path) {
    std::fs::create_dir_all(bad).unwrap();
    for entry in std::fs::read_dir(good).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        if !(name.ends_with(".csv") || name.ends_with(".toml")) {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let lines = text.lines().enumerate().filter_map(|(index, line)| {
            let (time, angle) = line.split_once(',').unwrap_or((line, ""));
            match name.as_str() {
                "u02.csv" if index > 0 => {
                    let degrees = angle.parse::<f64>().unwrap().to_degrees();
                    Some(format!("{time},{degrees}"))
                }
                "u03.csv" if index + 1 == 102 => Some(format!("{time},NaN")),
                "c03.csv" if index > 59 => None,
                _ => Some(line.to_string()),
            }
        });
        let changed: String = lines.map(|line| line + "\n").collect();
        std::fs::write(bad.join(&name), changed).unwrap();
    }
}

/// Timings vary from run to run: `in 1.2 s` → `in … s`.
fn masked(line: &str) -> String {
    let mut out = String::new();
    let mut rest = line.trim_end();
    while let Some(at) = rest.find("in ") {
        out.push_str(&rest[..at + 3]);
        rest = &rest[at + 3..];
        let number = rest
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(rest.len());
        let unit = rest[number..].strip_prefix(" s");
        if number > 0 && unit.is_some_and(|u| !u.starts_with(char::is_alphabetic)) {
            out.push('…');
            rest = &rest[number..];
        }
    }
    out.push_str(rest);
    out
}

/// Whether `printed` is `shown`, a line `...`/`[...]` of `shown` standing for any lines.
fn matches(shown: &[String], printed: &[String]) -> bool {
    match shown.split_first() {
        None => printed.is_empty(),
        Some((first, rest)) if first == "..." || first == "[...]" => {
            (0..=printed.len()).any(|skip| matches(rest, &printed[skip..]))
        }
        Some((first, rest)) => printed
            .split_first()
            .is_some_and(|(line, more)| masked(line) == masked(first) && matches(rest, more)),
    }
}

/// Runs the documented commands (slow ones or the others) in order and returns a report of
/// every mismatch.
fn mismatches(slow: bool) -> Vec<String> {
    let dir = workspace();
    let path = format!(
        "{}:{}",
        dir.join("bin").display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut last_status = 0;
    let mut failures = Vec::new();
    for documented in documented_commands().into_iter().filter(|c| c.slow == slow) {
        let printed: Vec<String> = if documented.command == "echo $?" {
            vec![last_status.to_string()]
        } else {
            let output = Command::new("sh")
                .arg("-c")
                .arg(&documented.command)
                .current_dir(&dir)
                .env("PATH", &path)
                .output()
                .unwrap();
            last_status = output.status.code().unwrap_or(-1);
            let text = String::from_utf8_lossy(&output.stdout).to_string()
                + &String::from_utf8_lossy(&output.stderr);
            let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
            while lines.last().is_some_and(|l| l.trim().is_empty()) {
                lines.pop();
            }
            lines
        };
        if !matches(&documented.expected, &printed) {
            failures.push(format!(
                "{}:{}: `{}` printed\n{}\n  but the page shows\n{}",
                documented.page,
                documented.line,
                documented.command,
                indent(&printed),
                indent(&documented.expected),
            ));
        }
    }
    failures
}

fn indent(lines: &[String]) -> String {
    lines
        .iter()
        .map(|l| format!("    | {l}"))
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn the_documented_commands_print_what_the_pages_show() {
    let failures = mismatches(false);
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
#[ignore = "slow: run by CI (`cargo test --test analyses -- --ignored`)"]
fn the_slow_documented_commands_print_what_the_pages_show() {
    let failures = mismatches(true);
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn elided_lines_and_timings() {
    let lines = |text: &str| text.lines().map(str::to_string).collect::<Vec<_>>();
    assert!(matches(&lines("a\n...\nd"), &lines("a\nb\nc\nd")));
    assert!(matches(&lines("a\n[...]\nb"), &lines("a\nb")));
    assert!(!matches(&lines("a\n...\nd"), &lines("a\nb\nc")));
    assert!(!matches(&lines("a\nb"), &lines("a\nb\nc")));
    assert!(matches(
        &lines("done in 1.5 s."),
        &lines("done in 12.25 s.")
    ));
    assert!(!matches(&lines("x = 1.5"), &lines("x = 1.6")));
    assert_eq!(masked("in 3 steps in 2.0 s"), "in 3 steps in … s");
}

/// The parser sees every documented command, and a slow one only where the page marks it.
#[test]
fn every_page_with_commands_is_read() {
    let commands = documented_commands();
    for page in [
        "docs/analysis.md",
        "docs/diagnose.md",
        "docs/flexure-and-actuator.md",
        "docs/import.md",
        "docs/sweep.md",
    ] {
        assert!(commands.iter().any(|c| c.page == page), "{page}");
    }
    let continued = commands
        .iter()
        .find(|c| c.command.starts_with("mech fit --experiment"))
        .unwrap();
    assert!(
        continued.command.contains("--data"),
        "{}",
        continued.command
    );
}
