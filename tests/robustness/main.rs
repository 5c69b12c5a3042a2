//! Hostile input to the `mech` binary (issue #18): bad command-line values, bad data and
//! experiment files, outputs that would overwrite inputs. Each case found by the black-box
//! run of the issue is kept here, with the message it must get. And the code's own shape
//! (#14): no circle among the files of a crate (`file_circles.rs`).
//!
//! One test binary per group, so the suite links a few binaries instead of one per file.

mod command_line;
mod data_files;
mod file_circles;
mod fuzz_smoke;
mod outputs;
mod support;
