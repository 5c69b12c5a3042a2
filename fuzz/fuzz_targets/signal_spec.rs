//! Fuzz target: `signal_spec::parse_signal` (for each input dimension the front end has) and
//! `parse_assignment` return `Ok` or `Err` on any text and their error messages render.
//!
//! Consumes: arbitrary bytes from libFuzzer, decoded lossily as UTF-8.
//! Produces: nothing; a panic, overflow or timeout is a finding.
//! The entry point is `entry_points::signal_spec`, shared with the test suite's smoke run.

#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../entry_points.rs"]
#[allow(dead_code)]
mod entry_points;

fuzz_target!(|data: &[u8]| entry_points::signal_spec(data));
