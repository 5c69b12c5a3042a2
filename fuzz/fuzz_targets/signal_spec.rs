//! Fuzz target: `signal_spec::parse_signal` (for each input dimension the front end has) and
//! `parse_assignment` return `Ok` or `Err` on any text and their error messages render.
//!
//! Consumes: arbitrary bytes from libFuzzer, decoded lossily as UTF-8.
//! Produces: nothing; a panic, overflow or timeout is a finding.

#![no_main]

use libfuzzer_sys::fuzz_target;
use mech::signal_spec::{file_read, parse_assignment, parse_signal};
use mech_codegen::ir::Dimension;

const DIMENSIONS: [Dimension; 6] = [
    Dimension::NONE,
    Dimension::FORCE,
    Dimension::TORQUE,
    Dimension::VOLTAGE,
    Dimension::LENGTH,
    Dimension::FREQUENCY,
];

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Err(error) = parse_assignment(&text) {
        let _ = error.to_string();
    }
    // `csv(PATH, …)` would read whatever file the fuzzer names (`/dev/zero` never ends); the
    // table reader is the `data_csv` target's.
    if file_read(&text).is_some() {
        return;
    }
    let dimension = DIMENSIONS[data.first().map_or(0, |b| *b as usize) % DIMENSIONS.len()];
    if let Err(error) = parse_signal(&text, dimension) {
        let _ = error.to_string();
    }
});
