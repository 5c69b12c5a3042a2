//! A proptest smoke run of the four cargo-fuzz targets (`fuzz/fuzz_targets/`, issue #18): the
//! same entry points on arbitrary text and bytes and on mutations of the repository's own
//! models, experiment files, data files and signal specs. Each must return `Ok` or `Err` and
//! render its errors; a panic is the failure. An input the fuzzer finds goes in as an explicit
//! regression case at the end (none so far). docs/fuzzing.md says how to run the fuzzer itself.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use mech::signal_spec::{parse_assignment, parse_signal};
use mech_codegen::ir::Dimension;
use proptest::prelude::*;
use proptest::sample::Index;

// The entry points the fuzz targets call (the same file).
#[path = "../../fuzz/entry_points.rs"]
mod entry_points;
use entry_points::{data_csv, experiment_toml, front_end, signal_spec};

// Seeds: the files fuzz/seed.sh copies into the fuzz corpus.

fn files(folders: &[&str], extension: &str) -> Vec<Vec<u8>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut paths: Vec<PathBuf> = folders
        .iter()
        .flat_map(|folder| std::fs::read_dir(root.join(folder)).unwrap())
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == extension))
        .collect();
    paths.sort();
    paths.iter().map(|p| std::fs::read(p).unwrap()).collect()
}

fn models() -> &'static [Vec<u8>] {
    static SEEDS: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    SEEDS.get_or_init(|| files(&["models"], "mech"))
}

fn data_files() -> &'static [Vec<u8>] {
    static SEEDS: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    SEEDS.get_or_init(|| files(&["docs/examples/diagnose", "examples/flexure_data"], "csv"))
}

fn experiment_files() -> &'static [Vec<u8>] {
    static SEEDS: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let folders = [
            "experiments",
            "experiments/studies",
            "docs/examples/diagnose",
        ];
        files(&folders, "toml")
    })
}

/// Signal specs and assignments as the README and docs write them.
const SPECS: &[&str] = &[
    "2.5 mN",
    "constant(2.5 mN)",
    "sine(1 mN, 10 Hz)",
    "sine(amplitude=1 mN, frequency=10 Hz, phase=90 deg, offset=0.5 mN)",
    "sine(amplitude=2 N, frequency=1.5 Hz)",
    "chirp(amplitude=1 mN, f0=1 Hz, f1=100 Hz, duration=2 s, offset=0 mN)",
    "chirp(amp=1 N, f0=0 Hz, f1=1 kHz, duration=500 ms)",
    "drive=sine(amp=2 N, freq=1 kHz)",
    "m=12g",
    "omega_ref=60 Hz",
];

/// One edit of a seed: positions are fractions of the current length, so they stay in range.
#[derive(Clone, Debug)]
enum Edit {
    FlipBit(Index, u8),
    Truncate(Index),
    DeleteLine(Index),
    DuplicateLine(Index),
    Insert(Index, Vec<u8>),
}

fn edit() -> impl Strategy<Value = Edit> {
    let bytes = prop_oneof![
        prop::collection::vec(any::<u8>(), 1..8),
        // Characters the readers split or quote on, and numbers at the edges of f64.
        prop::sample::select(
            &[
                ",",
                "\"",
                "=",
                "\n",
                "\r\n",
                "#",
                "[",
                "]",
                "{",
                "}",
                "(",
                ")",
                ";",
                "'",
                "\\",
                "é",
                "\u{feff}",
                "\0",
                "1e999",
                "-0",
                "NaN",
                "inf",
                "9223372036854775808",
                "1e-400",
            ][..]
        )
        .prop_map(|t| t.as_bytes().to_vec()),
    ];
    prop_oneof![
        (any::<Index>(), 0u8..8).prop_map(|(at, bit)| Edit::FlipBit(at, bit)),
        any::<Index>().prop_map(Edit::Truncate),
        any::<Index>().prop_map(Edit::DeleteLine),
        any::<Index>().prop_map(Edit::DuplicateLine),
        (any::<Index>(), bytes).prop_map(|(at, b)| Edit::Insert(at, b)),
    ]
}

/// Line `i` of `bytes` (modulo the line count) as a byte range, its newline included.
fn line(bytes: &[u8], i: &Index) -> std::ops::Range<usize> {
    let starts: Vec<usize> = std::iter::once(0)
        .chain(
            bytes
                .iter()
                .enumerate()
                .filter(|(_, b)| **b == b'\n')
                .map(|(k, _)| k + 1),
        )
        .filter(|&s| s < bytes.len())
        .collect();
    if starts.is_empty() {
        return 0..0;
    }
    let k = i.index(starts.len());
    starts[k]..starts.get(k + 1).copied().unwrap_or(bytes.len())
}

fn mutate(seed: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut bytes = seed.to_vec();
    for edit in edits {
        let len = bytes.len();
        match edit {
            Edit::FlipBit(at, bit) if len > 0 => bytes[at.index(len)] ^= 1 << bit,
            Edit::Truncate(at) => bytes.truncate(at.index(len + 1)),
            Edit::DeleteLine(i) => {
                bytes.drain(line(&bytes, i));
            }
            Edit::DuplicateLine(i) => {
                let range = line(&bytes, i);
                let copy = bytes[range.clone()].to_vec();
                bytes.splice(range.start..range.start, copy);
            }
            Edit::Insert(at, insert) => {
                let at = at.index(len + 1);
                bytes.splice(at..at, insert.iter().copied());
            }
            Edit::FlipBit(..) => {}
        }
    }
    bytes
}

fn mutated(seeds: fn() -> &'static [Vec<u8>]) -> impl Strategy<Value = Vec<u8>> {
    (any::<Index>(), prop::collection::vec(edit(), 1..6))
        .prop_map(move |(i, edits)| mutate(&seeds()[i.index(seeds().len())], &edits))
}

/// CSV-shaped text: rows of fields that are numbers, edge-case numbers, units or junk.
fn csv_like() -> impl Strategy<Value = String> {
    let field = prop_oneof![
        any::<f64>().prop_map(|x| x.to_string()),
        prop::sample::select(
            &[
                "",
                "time [s]",
                "time [ms]",
                "angle [deg]",
                "force [mN]",
                "t",
                "NaN",
                "inf",
                "-inf",
                "1e308",
                "1e-320",
                "\"1,5\"",
                "#",
                " ",
                "x [",
                "[]",
                "0x10",
            ][..]
        )
        .prop_map(str::to_string),
        "\\PC{0,6}",
    ];
    let row = prop::collection::vec(field, 0..5).prop_map(|fields| fields.join(","));
    prop::collection::vec(row, 0..12).prop_map(|rows| rows.join("\n"))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn front_end_takes_mutated_models(bytes in mutated(models)) {
        front_end(&bytes);
    }

    #[test]
    fn data_readers_take_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..300)) {
        data_csv(&bytes);
    }

    #[test]
    fn data_readers_take_csv_shaped_text(text in csv_like()) {
        data_csv(text.as_bytes());
    }

    #[test]
    fn data_readers_take_mutated_data_files(bytes in mutated(data_files)) {
        data_csv(&bytes);
    }

    #[test]
    fn experiment_readers_take_arbitrary_text(text in "\\PC{0,200}") {
        experiment_toml(text.as_bytes());
    }

    #[test]
    fn experiment_readers_take_mutated_experiment_files(bytes in mutated(experiment_files)) {
        experiment_toml(&bytes);
    }

    #[test]
    fn signal_specs_take_arbitrary_text(text in "\\PC{0,80}") {
        signal_spec(text.as_bytes());
    }

    #[test]
    fn signal_specs_take_mutated_specs(
        i in any::<Index>(),
        edits in prop::collection::vec(edit(), 1..4),
    ) {
        signal_spec(&mutate(SPECS[i.index(SPECS.len())].as_bytes(), &edits));
    }
}

/// The seeds are what the mutations start from: if they stopped parsing, the mutations would
/// only explore the error paths.
#[test]
fn the_seeds_parse() {
    assert!(models().len() >= 10 && data_files().len() >= 5 && experiment_files().len() >= 10);
    for spec in SPECS {
        let value = parse_assignment(spec).map_or(spec.to_string(), |(_, value)| value);
        let parses = [Dimension::FORCE, Dimension::FREQUENCY, Dimension::MASS]
            .into_iter()
            .any(|dimension| parse_signal(&value, dimension).is_ok());
        assert!(parses, "`{spec}`");
    }
    for seed in data_files() {
        mech::output::parse_csv_table(Path::new("seed.csv"), seed).unwrap();
    }
    for seed in experiment_files() {
        let text = std::str::from_utf8(seed).unwrap();
        let paper = mech::experiments::parse(text);
        let diagnosis = mech::diagnose::experiment::parse(Path::new("seed.toml"), text);
        let study = mech::sweep::study::parse(text);
        assert!(
            paper.is_ok() || diagnosis.is_ok() || study.is_ok(),
            "{text}"
        );
    }
}
