//! Fuzz target: `front::load` must not panic on any input (it may return errors, whose
//! rendering must not panic either); a model that loads must also derive and lower to a tape.
//!
//! Consumes: arbitrary bytes from libFuzzer, decoded lossily as UTF-8.
//! Produces: nothing; a panic, overflow, stack overflow or timeout is a finding.
//! The entry point is `entry_points::front_end`, shared with the test suite's smoke run.

#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../entry_points.rs"]
#[allow(dead_code)]
mod entry_points;

fuzz_target!(|data: &[u8]| entry_points::front_end(data));
