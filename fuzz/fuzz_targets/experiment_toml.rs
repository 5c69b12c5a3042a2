//! Fuzz target: the experiment files, `experiments::parse` (the paper's experiments) and
//! `diagnose::experiment::parse` (diagnosis experiments), return `Ok` or `Err` on any text and
//! their error messages render. Neither reads the model the file names.
//!
//! Consumes: arbitrary bytes from libFuzzer, decoded lossily as UTF-8.
//! Produces: nothing; a panic, overflow or timeout is a finding.
//! The entry point is `entry_points::experiment_toml`, shared with the test suite's smoke run.

#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../entry_points.rs"]
#[allow(dead_code)]
mod entry_points;

fuzz_target!(|data: &[u8]| entry_points::experiment_toml(data));
