//! Byte-level mutations and splices of a valid input, shared by the fuzz-style proptests
//! (`fuzz_front.rs`, `fuzz_urdf.rs`).

use proptest::prelude::*;

/// One mutation for [`mutated`] of a seed of `seed_len` bytes: at a position in it, remove
/// fewer than `max_remove` bytes and insert either a few arbitrary bytes or one of `tokens` (the
/// pieces that make mutations reach past the first parser).
pub fn mutation(
    seed_len: usize,
    max_remove: usize,
    tokens: &'static [&'static str],
) -> impl Strategy<Value = (usize, usize, Vec<u8>)> {
    let insert = prop_oneof![
        prop::collection::vec(any::<u8>(), 0..8),
        prop::sample::select(tokens).prop_map(|t| t.as_bytes().to_vec()),
    ];
    (0..seed_len, 0..max_remove, insert)
}

/// `seed` with each `(at, remove, insert)` applied in turn: `remove` bytes from `at`
/// replaced by `insert` (positions clamped to the text).
pub fn mutated(seed: &str, mutations: Vec<(usize, usize, Vec<u8>)>) -> Vec<u8> {
    let mut bytes = seed.as_bytes().to_vec();
    for (at, remove, insert) in mutations {
        let at = at.min(bytes.len());
        let end = (at + remove).min(bytes.len());
        bytes.splice(at..end, insert);
    }
    bytes
}

/// `seed` with its bytes between `a` and `b` copied in at `c`.
pub fn spliced(seed: &str, a: usize, b: usize, c: usize) -> Vec<u8> {
    let bytes = seed.as_bytes();
    let (from, to) = (a.min(b), a.max(b));
    let mut spliced = bytes[..c].to_vec();
    spliced.extend_from_slice(&bytes[from..to]);
    spliced.extend_from_slice(&bytes[c..]);
    spliced
}
