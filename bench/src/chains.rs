//! The chains of [`SIZES`](crate::SIZES) compiled to Rust by `build.rs`: one module
//! `chain{N}` per size, holding the generated struct `Chain{N}`, and the macro
//! `for_each_generated_chain!` that visits them.

include!(concat!(env!("OUT_DIR"), "/chains.rs"));
