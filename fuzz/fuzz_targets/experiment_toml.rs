//! Fuzz target: the experiment files, `experiments::parse` (the paper's experiments) and
//! `diagnose::experiment::parse` (diagnosis experiments), return `Ok` or `Err` on any text and
//! their error messages render. Neither reads the model the file names.
//!
//! Consumes: arbitrary bytes from libFuzzer, decoded lossily as UTF-8.
//! Produces: nothing; a panic, overflow or timeout is a finding.

#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Err(error) = mech::experiments::parse(&text) {
        let _ = error.to_string();
    }
    if let Err(error) = mech::diagnose::experiment::parse(Path::new("fuzz.toml"), &text) {
        let _ = error.to_string();
    }
});
