//! Fuzz target: `front::load` must not panic on any input (it may return errors, whose
//! rendering must not panic either); a model that loads must also derive and lower to a tape.
//!
//! Consumes: arbitrary bytes from libFuzzer, decoded lossily as UTF-8.
//! Produces: nothing; a panic, overflow, stack overflow or timeout is a finding.

#![no_main]

use std::sync::Arc;

use libfuzzer_sys::fuzz_target;
use mech_codegen::diag::SourceFile;
use mech_codegen::front;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data).into_owned();
    match front::load(Arc::new(SourceFile::new("fuzz.mech", text))) {
        Ok(model) => {
            let equations = mech_codegen::kane::derive(&model);
            let _ = mech_codegen::Tape::new(&equations);
        }
        Err(errors) => {
            let _ = errors.to_string();
        }
    }
});
