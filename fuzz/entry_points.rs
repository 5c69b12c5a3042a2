//! The entry points the fuzz targets exercise, one function each, shared by the cargo-fuzz
//! targets (`fuzz_targets/*.rs`) and the proptest smoke run in the test suite
//! (`tests/robustness/fuzz_smoke.rs`, which includes this file by path), so both run the
//! same code. Each must return on any bytes — `Ok` or an error whose message renders; a
//! panic, overflow or timeout is a finding.

use std::path::Path;
use std::sync::Arc;

use mech::diagnose::data::MeasuredData;
use mech::signal_spec::{file_read, parse_assignment, parse_signal};
use mech_codegen::diag::SourceFile;
use mech_codegen::ir::Dimension;

/// `front::load` (decoded lossily as UTF-8); a model that loads must also derive and lower to
/// a tape.
pub fn front_end(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes).into_owned();
    match mech_codegen::front::load(Arc::new(SourceFile::new("fuzz.mech", text))) {
        Ok(model) => {
            let equations = mech_codegen::kane::derive(&model);
            let _ = mech_codegen::Tape::new(&equations);
        }
        Err(errors) => {
            let _ = errors.to_string();
        }
    }
}

/// The two CSV readers, `MeasuredData::parse` (measured data for `diagnose`) and
/// `output::parse_csv_table` (the table behind `csv(...)` signals), on the bytes of a file.
pub fn data_csv(bytes: &[u8]) {
    let path = Path::new("fuzz.csv");
    if let Err(errors) = MeasuredData::parse(path, bytes) {
        let _ = errors.to_string();
    }
    if let Err(error) = mech::output::parse_csv_table(path, bytes) {
        let _ = error.to_string();
    }
}

/// The experiment files, `experiments::parse` (the paper's experiments),
/// `diagnose::experiment::parse` (diagnosis experiments) and `sweep::study::parse` (`mech
/// sweep`'s studies); none reads the model the file names.
pub fn experiment_toml(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    if let Err(error) = mech::sweep::study::parse(&text) {
        let _ = error.to_string();
    }
    if let Err(error) = mech::experiments::parse(&text) {
        let _ = error.to_string();
    }
    if let Err(error) = mech::diagnose::experiment::parse(Path::new("fuzz.toml"), &text) {
        let _ = error.to_string();
    }
}

/// The input dimensions the front end has, one picked by the first byte.
const DIMENSIONS: [Dimension; 6] = [
    Dimension::NONE,
    Dimension::FORCE,
    Dimension::TORQUE,
    Dimension::VOLTAGE,
    Dimension::LENGTH,
    Dimension::FREQUENCY,
];

/// `signal_spec::parse_assignment`, and `parse_signal` for the dimension the first byte picks.
pub fn signal_spec(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    if let Err(error) = parse_assignment(&text) {
        let _ = error.to_string();
    }
    // `csv(PATH, …)` would read whatever file the input names (`/dev/zero` never ends); the
    // table reader is `data_csv`'s.
    if file_read(&text).is_some() {
        return;
    }
    let dimension = DIMENSIONS[bytes.first().map_or(0, |b| *b as usize) % DIMENSIONS.len()];
    if let Err(error) = parse_signal(&text, dimension) {
        let _ = error.to_string();
    }
}
