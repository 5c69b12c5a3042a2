//! Fuzz target: the two CSV readers, `MeasuredData::parse` (measured data for `diagnose`) and
//! `output::parse_csv_table` (the table behind `csv(...)` signals), return `Ok` or `Err` on any
//! bytes and their error messages render.
//!
//! Consumes: arbitrary bytes from libFuzzer, as the contents of a file.
//! Produces: nothing; a panic, overflow or timeout is a finding.

#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use mech::diagnose::data::MeasuredData;
use mech::output::parse_csv_table;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.csv");
    if let Err(errors) = MeasuredData::parse(path, data) {
        let _ = errors.to_string();
    }
    if let Err(error) = parse_csv_table(path, data) {
        let _ = error.to_string();
    }
});
