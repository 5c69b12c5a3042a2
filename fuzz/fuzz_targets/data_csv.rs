//! Fuzz target: the two CSV readers, `MeasuredData::parse` (measured data for `diagnose`) and
//! `output::parse_csv_table` (the table behind `csv(...)` signals), return `Ok` or `Err` on any
//! bytes and their error messages render.
//!
//! Consumes: arbitrary bytes from libFuzzer, as the contents of a file.
//! Produces: nothing; a panic, overflow or timeout is a finding.
//! The entry point is `entry_points::data_csv`, shared with the test suite's smoke run.

#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../entry_points.rs"]
#[allow(dead_code)]
mod entry_points;

fuzz_target!(|data: &[u8]| entry_points::data_csv(data));
