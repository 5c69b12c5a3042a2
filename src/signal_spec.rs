//! Input signals written on the command line: `--input NAME=SPEC`.
//!
//! Consumes: the text of a signal specification and the dimension of the input it drives.
//! Produces: a [`Signal`] with every value in SI units, or an [`Error`] whose message is one
//! line saying what is wrong and what to write instead. Callers prefix errors with the input,
//! e.g. ``input `drive`: sine() is missing `frequency` ``. `NAME=VALUE` settings are split by
//! [`parse_assignment`] (errors: [`AssignmentError`]).
//!
//! # Grammar
//!
//! | spec | signal |
//! |---|---|
//! | `2.5 mN`, `constant(2.5 mN)` | [`Signal::Constant`] |
//! | `sine(amplitude=1 mN, frequency=10 Hz, phase=90 deg, offset=0 mN)` | [`Signal::Sine`] |
//! | `chirp(amplitude=1 mN, f0=1 Hz, f1=100 Hz, duration=2 s, offset=0 mN)` | [`Signal::Chirp`] |
//! | `csv(path/to/file.csv, column=voltage, unit=mV)` | [`Signal::Table`] |
//!
//! - Quantities are parsed by [`units::parse_quantity`] and must have the right dimension:
//!   amplitudes, offsets and constants that of the input; frequencies 1/s; phases none (a
//!   bare number is radians, or write `deg`); durations s. A bare number for a dimensioned
//!   input is rejected with a hint showing the unit to use.
//! - A frequency written with an angle unit (`rad/s`, `deg/s`) is an angular frequency and
//!   is converted to Hz (divided by 2π); `Hz`, `kHz` and `s^-1` are taken as cycles per second.
//! - Arguments may also be given by position, in the order of the table (`sine(1 mN, 10 Hz)`),
//!   but not after a keyword argument. `phase` and `offset` default to 0. Keys may be
//!   abbreviated: `amp`, `freq`.
//! - `csv(...)`: the path comes first (quote it if it contains a comma); the first column of
//!   the file is time in seconds; `column` may be left out if the file has exactly one other
//!   column; `unit` gives the unit of the values and is required unless the input is
//!   dimensionless. See [`crate::output::read_csv_table`] for the file format.

use std::f64::consts::TAU;
use std::fmt;
use std::path::Path;

use mech_codegen::diag::edit_distance;
use mech_codegen::front::units;
use mech_codegen::ir::Dimension;
use mech_runtime::signal::{Signal, Table};
use mech_runtime::RuntimeError;

use crate::output::{self, quoted_list, CsvError};
use crate::quantity::{example_quantity, leading_number, unit_hint};

/// Why a `NAME=VALUE` setting cannot be split.
#[derive(Debug, Clone, PartialEq)]
pub enum AssignmentError {
    /// There is no `=`.
    NoEquals { text: String },
    /// Nothing precedes the `=`.
    NoName { text: String },
    /// What precedes the `=` is not a name.
    NotAName { text: String, name: String },
    /// Nothing follows the `=`.
    NoValue { name: String },
}

impl fmt::Display for AssignmentError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AssignmentError::NoEquals { text } => {
                write!(f, "expected NAME=VALUE, found `{text}` (no `=`)")
            }
            AssignmentError::NoName { text } => {
                write!(
                    f,
                    "expected NAME=VALUE, found `{text}` (no name before `=`)"
                )
            }
            AssignmentError::NotAName { text, name } => {
                write!(
                    f,
                    "expected NAME=VALUE, found `{text}`: `{name}` is not a name"
                )
            }
            AssignmentError::NoValue { name } => write!(f, "`{name}=` has no value after `=`"),
        }
    }
}

impl std::error::Error for AssignmentError {}

/// Why a signal specification cannot be read (see the module documentation for what can).
/// Functions are named as written by the user where the error comes before the function is
/// known, and by their canonical name after.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// Only white space.
    Empty,
    /// Starts with a letter but is no `name(...)` call.
    NotASignal { spec: String },
    /// A signal function written without its arguments: `sine`.
    MissingParentheses {
        name: String,
        /// The function `name` is (or is close to), for the example.
        function: &'static str,
    },
    /// `name(...` without the closing `)`.
    MissingClosingParenthesis { spec: String },
    /// `name(...)` where `name` is no signal function.
    UnknownFunction {
        function: String,
        /// The function meant, if `function` looks like a typo of one.
        suggestion: Option<&'static str>,
    },
    /// A `(` or `)` without its partner among the arguments.
    UnmatchedParenthesis { function: String, parenthesis: char },
    /// A quote opened among the arguments and never closed.
    UnterminatedQuote { function: String, quote: char },
    /// `f(a,, b)`.
    EmptyArgument {
        function: String,
        /// 1-based.
        position: usize,
    },
    /// `key=` with nothing after it.
    KeyWithoutValue { function: String, key: String },
    /// A positional argument after a `key=value` one.
    PositionalAfterKeyword {
        function: &'static str,
        value: String,
    },
    /// More positional arguments than the function has parameters.
    TooManyArguments {
        function: &'static str,
        parameters: Vec<&'static str>,
        given: usize,
    },
    /// A key the function does not have.
    UnknownKey {
        function: &'static str,
        key: String,
        /// The parameter meant, if `key` looks like a typo of one of its names.
        suggestion: Option<&'static str>,
        parameters: Vec<&'static str>,
    },
    /// A parameter given twice (by position and key, or under two of its names).
    GivenTwice {
        function: &'static str,
        parameter: &'static str,
    },
    /// A required parameter that is not given.
    MissingArgument {
        function: &'static str,
        parameter: &'static str,
    },
    /// A quantity argument that cannot be used.
    Argument {
        /// The parameter, e.g. `amplitude`.
        name: &'static str,
        /// The argument as written.
        text: String,
        problem: ArgumentProblem,
    },
    /// The file of `csv(...)` cannot be read as a numeric table.
    Csv(CsvError),
    /// `csv(...)` without `column=` on a file with more than one column besides time.
    AmbiguousColumn { path: String, columns: Vec<String> },
    /// `unit=` that is not a unit; the unit parser's reason.
    BadUnit { unit: String, reason: String },
    /// `unit=` of another dimension than the input's.
    WrongUnit {
        unit: String,
        found: Dimension,
        expected: Dimension,
    },
    /// No `unit=` for an input that has a dimension.
    MissingUnit { expected: Dimension },
    /// The table of `csv(...)` is not a signal (e.g. times not increasing).
    Table { path: String, error: RuntimeError },
    /// The signal's values are out of range.
    Invalid(RuntimeError),
}

/// What is wrong with a quantity argument, for [`Error::Argument`].
#[derive(Debug, Clone, PartialEq)]
pub enum ArgumentProblem {
    /// It does not start like a number.
    NotAQuantity {
        expected: Dimension,
    },
    /// It starts like a number but is not a quantity; the unit parser's reason.
    BadSyntax(String),
    /// A unit of another dimension (`found` is dimensionless for a bare number).
    WrongDimension {
        kind: QuantityKind,
        found: Dimension,
        expected: Dimension,
    },
    NegativeFrequency,
    NotPositiveDuration,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Empty => write!(f, "the signal is empty; {FORMS}"),
            Error::NotASignal { spec } => write!(f, "`{spec}` is not a signal; {FORMS}"),
            Error::MissingParentheses { name, function } => write!(
                f,
                "`{name}` needs arguments in parentheses, e.g. `{}`",
                example_call(function)
            ),
            Error::MissingClosingParenthesis { spec } => {
                write!(f, "`{spec}` is missing the closing `)`")
            }
            Error::UnknownFunction {
                function,
                suggestion: Some(near),
            } => write!(
                f,
                "unknown signal `{function}(...)`, did you mean `{near}(...)`?"
            ),
            Error::UnknownFunction {
                function,
                suggestion: None,
            } => write!(f, "unknown signal `{function}(...)`; {FORMS}"),
            Error::UnmatchedParenthesis {
                function,
                parenthesis,
            } => write!(f, "{function}(...) has an unmatched `{parenthesis}`"),
            Error::UnterminatedQuote { function, quote: q } => {
                write!(f, "{function}(...) has an unterminated {q}quote{q}")
            }
            Error::EmptyArgument { function, position } => {
                write!(f, "{function}(...): argument {position} is empty")
            }
            Error::KeyWithoutValue { function, key } => {
                write!(f, "{function}(...): `{key}=` has no value")
            }
            Error::PositionalAfterKeyword { function, value } => write!(
                f,
                "{function}(...): `{value}` needs a key (positional arguments must come before \
                 `key=value` ones)"
            ),
            Error::TooManyArguments {
                function,
                parameters,
                given,
            } => write!(
                f,
                "{function}(...) takes at most {} argument{} ({}), but got {given}",
                parameters.len(),
                if parameters.len() == 1 { "" } else { "s" },
                quoted_list(parameters)
            ),
            Error::UnknownKey {
                function,
                key,
                suggestion: Some(near),
                ..
            } => write!(
                f,
                "unknown key `{key}` in {function}(...), did you mean `{near}`?"
            ),
            Error::UnknownKey {
                function,
                key,
                suggestion: None,
                parameters,
            } => write!(
                f,
                "unknown key `{key}` in {function}(...); its keys are {}",
                quoted_list(parameters)
            ),
            Error::GivenTwice {
                function,
                parameter,
            } => write!(f, "{function}(...): `{parameter}` is given twice"),
            Error::MissingArgument {
                function,
                parameter,
            } => write!(
                f,
                "{function}() is missing `{parameter}`, e.g. `{}`",
                example_call(function)
            ),
            Error::Argument {
                name,
                text,
                problem,
            } => {
                write!(f, "{name} `{text}`")?;
                write_argument_problem(f, text, problem)
            }
            Error::Csv(error) => write!(f, "{error}"),
            Error::AmbiguousColumn { path, columns } => write!(
                f,
                "csv(...): `{path}` has the columns {}; choose one with `column=NAME`",
                quoted_list(columns)
            ),
            Error::BadUnit { unit, reason } => write!(f, "csv(...): `unit={unit}`: {reason}"),
            Error::WrongUnit {
                unit,
                found,
                expected,
            } => write!(
                f,
                "csv(...): `unit={unit}` is {}, but the input needs {}{}",
                units::describe(*found),
                units::describe(*expected),
                unit_hint(*expected).map_or(String::new(), |u| format!(" (e.g. `unit={u}`)"))
            ),
            Error::MissingUnit { expected } => write!(
                f,
                "csv(...): give the unit of the values, e.g. `unit={}`: the input needs {expected}",
                unit_hint(*expected).unwrap_or_else(|| expected.to_string()),
            ),
            Error::Table { path, error } => write!(f, "`{path}`: {error}"),
            Error::Invalid(error) => write!(f, "{error}"),
        }
    }
}

/// What follows ``amplitude `1 mm` `` in a message about a quantity argument.
fn write_argument_problem(
    f: &mut fmt::Formatter<'_>,
    text: &str,
    problem: &ArgumentProblem,
) -> fmt::Result {
    match problem {
        ArgumentProblem::NotAQuantity { expected } => write!(
            f,
            " is not a quantity: expected a number with an optional unit, such as `{}`",
            example_quantity("1", *expected)
        ),
        ArgumentProblem::BadSyntax(reason) => write!(f, ": {reason}"),
        ArgumentProblem::WrongDimension {
            kind,
            found,
            expected,
        } => {
            let needed = match kind {
                QuantityKind::Value if *expected == Dimension::NONE => {
                    "the input is dimensionless".to_string()
                }
                QuantityKind::Value => format!("the input needs {expected}"),
                QuantityKind::Frequency => "a frequency needs 1/s".to_string(),
                QuantityKind::Phase => "a phase is an angle (dimensionless)".to_string(),
                QuantityKind::Duration => "a duration needs s".to_string(),
            };
            let given = if *found == Dimension::NONE {
                "has no unit".to_string()
            } else {
                format!("is in {found}")
            };
            let number = leading_number(text).unwrap_or("1");
            let example = match kind {
                QuantityKind::Phase => format!("{number} deg"),
                _ => example_quantity(number, *expected),
            };
            write!(f, " {given}, but {needed}: write e.g. `{example}`")
        }
        ArgumentProblem::NegativeFrequency => f.write_str(
            " is negative; frequencies must be >= 0 (use a negative amplitude or a phase to \
             invert the signal)",
        ),
        ArgumentProblem::NotPositiveDuration => f.write_str(" must be > 0"),
    }
}

impl std::error::Error for Error {}

impl From<CsvError> for Error {
    fn from(error: CsvError) -> Error {
        Error::Csv(error)
    }
}

/// Splits `name=value` at the first `=` into trimmed `(name, value)`, as used by `--set` and
/// `--input`. The name must be non-empty and made of letters, digits, `_` and `.`; the value
/// must be non-empty.
pub fn parse_assignment(text: &str) -> Result<(String, String), AssignmentError> {
    let whole = || text.trim().to_string();
    let Some((name, value)) = text.split_once('=') else {
        return Err(AssignmentError::NoEquals { text: whole() });
    };
    let (name, value) = (name.trim(), value.trim());
    if name.is_empty() {
        return Err(AssignmentError::NoName { text: whole() });
    }
    if !name
        .chars()
        .all(|c| c.is_alphanumeric() || c == '_' || c == '.')
    {
        return Err(AssignmentError::NotAName {
            text: whole(),
            name: name.to_string(),
        });
    }
    if value.is_empty() {
        return Err(AssignmentError::NoValue {
            name: name.to_string(),
        });
    }
    Ok((name.to_string(), value.to_string()))
}

/// Parses a signal specification (see the module documentation) for an input of dimension
/// `expected`.
pub fn parse_signal(spec: &str, expected: Dimension) -> Result<Signal, Error> {
    let spec = spec.trim();
    if spec.is_empty() {
        return Err(Error::Empty);
    }
    let signal = match split_call(spec)? {
        None => Signal::Constant(quantity(spec, "value", expected, QuantityKind::Value)?),
        Some((function, args)) => {
            let args = split_arguments(function, args)?;
            match function {
                "constant" | "const" => constant(&args, expected)?,
                "sine" | "sin" => sine(&args, expected)?,
                "chirp" => chirp(&args, expected)?,
                "csv" => csv(&args, expected)?,
                _ => {
                    return Err(Error::UnknownFunction {
                        function: function.to_string(),
                        suggestion: suggest(function, FUNCTIONS),
                    })
                }
            }
        }
    };
    signal.validate().map_err(Error::Invalid)?;
    Ok(signal)
}

/// What every error about an unrecognised signal suggests.
const FORMS: &str =
    "expected a quantity such as `2.5 mN`, `sine(amplitude=1 mN, frequency=10 Hz)`, \
     `chirp(amplitude=1 mN, f0=1 Hz, f1=100 Hz, duration=2 s)` or `csv(file.csv, column=NAME)`";

/// The signal functions, for suggestions.
const FUNCTIONS: &[&str] = &["constant", "sine", "chirp", "csv"];

/// `name(args)` → `Some((name, args))`; a spec not starting with a letter → `None` (a
/// quantity). Anything else that starts with a letter is an error.
fn split_call(spec: &str) -> Result<Option<(&str, &str)>, Error> {
    if !spec.starts_with(|c: char| c.is_ascii_alphabetic()) {
        return Ok(None);
    }
    let name_end = spec
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(spec.len());
    let name = &spec[..name_end];
    let rest = spec[name_end..].trim_start();
    let Some(inner) = rest.strip_prefix('(') else {
        return Err(match suggest(name, FUNCTIONS) {
            Some(function) if rest.is_empty() => Error::MissingParentheses {
                name: name.to_string(),
                function,
            },
            _ => Error::NotASignal {
                spec: spec.to_string(),
            },
        });
    };
    let Some(args) = inner.trim_end().strip_suffix(')') else {
        return Err(Error::MissingClosingParenthesis {
            spec: spec.to_string(),
        });
    };
    Ok(Some((name, args)))
}

fn example_call(function: &str) -> &'static str {
    match function {
        "sine" => "sine(amplitude=1 mN, frequency=10 Hz)",
        "chirp" => "chirp(amplitude=1 mN, f0=1 Hz, f1=100 Hz, duration=2 s)",
        "csv" => "csv(file.csv, column=NAME)",
        _ => "constant(2.5 mN)",
    }
}

/// One argument of a call: `key=value` or a positional `value` (both trimmed).
#[derive(Debug)]
struct Argument<'a> {
    key: Option<&'a str>,
    value: &'a str,
}

/// Splits `a, key=b, ...` at top-level commas (outside parentheses and quotes). A trailing
/// comma is allowed; an empty argument elsewhere is an error.
fn split_arguments<'a>(function: &str, text: &'a str) -> Result<Vec<Argument<'a>>, Error> {
    let unmatched = |parenthesis| Error::UnmatchedParenthesis {
        function: function.to_string(),
        parenthesis,
    };
    let mut pieces = Vec::new();
    let (mut depth, mut quote, mut start) = (0i32, None, 0);
    for (i, c) in text.char_indices() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '(') => depth += 1,
            (None, ')') => depth -= 1,
            (None, ',') if depth == 0 => {
                pieces.push(&text[start..i]);
                start = i + 1;
            }
            _ => {}
        }
        if depth < 0 {
            return Err(unmatched(')'));
        }
    }
    if let Some(quote) = quote {
        return Err(Error::UnterminatedQuote {
            function: function.to_string(),
            quote,
        });
    }
    if depth != 0 {
        return Err(unmatched('('));
    }
    pieces.push(&text[start..]);
    if pieces.len() > 1 && pieces.last().is_some_and(|p| p.trim().is_empty()) {
        pieces.pop();
    }
    if pieces.len() == 1 && pieces[0].trim().is_empty() {
        return Ok(Vec::new());
    }
    pieces
        .into_iter()
        .enumerate()
        .map(|(i, piece)| {
            let piece = piece.trim();
            if piece.is_empty() {
                return Err(Error::EmptyArgument {
                    function: function.to_string(),
                    position: i + 1,
                });
            }
            // `key=value` only if what precedes the first `=` is a plain key (so a quoted
            // path containing `=` stays positional).
            if let Some((key, value)) = piece.split_once('=') {
                let key = key.trim();
                if !key.is_empty() && key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                    let value = value.trim();
                    if value.is_empty() {
                        return Err(Error::KeyWithoutValue {
                            function: function.to_string(),
                            key: key.to_string(),
                        });
                    }
                    return Ok(Argument {
                        key: Some(key),
                        value,
                    });
                }
            }
            Ok(Argument {
                key: None,
                value: piece,
            })
        })
        .collect()
}

/// A parameter of a signal function: canonical name, accepted abbreviations, and whether it
/// must be given.
struct Param {
    name: &'static str,
    aliases: &'static [&'static str],
    required: bool,
}

const fn param(name: &'static str, aliases: &'static [&'static str], required: bool) -> Param {
    Param {
        name,
        aliases,
        required,
    }
}

/// Matches `args` to `params` (positional ones in order, then by key) and returns one value
/// text per parameter, `None` for optional ones not given.
fn bind<'a>(
    function: &'static str,
    params: &[Param],
    args: &[Argument<'a>],
) -> Result<Vec<Option<&'a str>>, Error> {
    let mut values: Vec<Option<&'a str>> = vec![None; params.len()];
    let mut seen_keyword = false;
    for (position, arg) in args.iter().enumerate() {
        let index = match arg.key {
            None => {
                if seen_keyword {
                    return Err(Error::PositionalAfterKeyword {
                        function,
                        value: arg.value.to_string(),
                    });
                }
                if position >= params.len() {
                    return Err(Error::TooManyArguments {
                        function,
                        parameters: params.iter().map(|p| p.name).collect(),
                        given: args.len(),
                    });
                }
                position
            }
            Some(key) => {
                seen_keyword = true;
                params
                    .iter()
                    .position(|p| p.name == key || p.aliases.contains(&key))
                    .ok_or_else(|| unknown_key(function, key, params))?
            }
        };
        if values[index].is_some() {
            return Err(Error::GivenTwice {
                function,
                parameter: params[index].name,
            });
        }
        values[index] = Some(arg.value);
    }
    if let Some((missing, _)) = params
        .iter()
        .zip(&values)
        .find(|(p, v)| p.required && v.is_none())
    {
        return Err(Error::MissingArgument {
            function,
            parameter: missing.name,
        });
    }
    Ok(values)
}

fn unknown_key(function: &'static str, key: &str, params: &[Param]) -> Error {
    let candidates: Vec<&'static str> = params
        .iter()
        .flat_map(|p| std::iter::once(p.name).chain(p.aliases.iter().copied()))
        .collect();
    // Suggest the canonical name even when the near match is an alias.
    let suggestion = suggest(key, &candidates).map(|near| {
        params
            .iter()
            .find(|p| p.name == near || p.aliases.contains(&near))
            .map_or(near, |p| p.name)
    });
    Error::UnknownKey {
        function,
        key: key.to_string(),
        suggestion,
        parameters: params.iter().map(|p| p.name).collect(),
    }
}

fn constant(args: &[Argument], expected: Dimension) -> Result<Signal, Error> {
    const PARAMS: &[Param] = &[param("value", &[], true)];
    let values = bind("constant", PARAMS, args)?;
    let value = quantity(
        values[0].unwrap_or_default(),
        "value",
        expected,
        QuantityKind::Value,
    )?;
    Ok(Signal::Constant(value))
}

fn sine(args: &[Argument], expected: Dimension) -> Result<Signal, Error> {
    const PARAMS: &[Param] = &[
        param("amplitude", &["amp"], true),
        param("frequency", &["freq"], true),
        param("phase", &[], false),
        param("offset", &[], false),
    ];
    let v = bind("sine", PARAMS, args)?;
    let optional = |text: Option<&str>, name, kind| {
        text.map_or(Ok(0.0), |text| quantity(text, name, expected, kind))
    };
    Ok(Signal::Sine {
        amplitude: quantity(
            v[0].unwrap_or_default(),
            "amplitude",
            expected,
            QuantityKind::Value,
        )?,
        frequency_hz: quantity(
            v[1].unwrap_or_default(),
            "frequency",
            expected,
            QuantityKind::Frequency,
        )?,
        phase_rad: optional(v[2], "phase", QuantityKind::Phase)?,
        offset: optional(v[3], "offset", QuantityKind::Value)?,
    })
}

fn chirp(args: &[Argument], expected: Dimension) -> Result<Signal, Error> {
    const PARAMS: &[Param] = &[
        param("amplitude", &["amp"], true),
        param("f0", &[], true),
        param("f1", &[], true),
        param("duration", &[], true),
        param("offset", &[], false),
    ];
    let v = bind("chirp", PARAMS, args)?;
    let required =
        |i: usize, kind| quantity(v[i].unwrap_or_default(), PARAMS[i].name, expected, kind);
    Ok(Signal::Chirp {
        amplitude: required(0, QuantityKind::Value)?,
        f0_hz: required(1, QuantityKind::Frequency)?,
        f1_hz: required(2, QuantityKind::Frequency)?,
        duration: required(3, QuantityKind::Duration)?,
        offset: match v[4] {
            Some(text) => quantity(text, "offset", expected, QuantityKind::Value)?,
            None => 0.0,
        },
    })
}

/// The parameters of `csv(...)`.
const CSV_PARAMS: &[Param] = &[
    param("path", &["file"], true),
    param("column", &["col"], false),
    param("unit", &[], false),
];

/// The file a signal specification reads (`csv(path, ...)`), if any: an output of the same
/// run must not replace it.
pub fn file_read(spec: &str) -> Option<std::path::PathBuf> {
    let (function, args) = split_call(spec.trim()).ok()??;
    if function != "csv" {
        return None;
    }
    let args = split_arguments(function, args).ok()?;
    let v = bind("csv", CSV_PARAMS, &args).ok()?;
    Some(Path::new(unquote(v[0]?)).to_path_buf())
}

fn csv(args: &[Argument], expected: Dimension) -> Result<Signal, Error> {
    let v = bind("csv", CSV_PARAMS, args)?;
    let path_text = unquote(v[0].unwrap_or_default());
    let path = Path::new(path_text);
    let (times, mut values) = match v[1].map(unquote) {
        Some(column) => output::read_csv_column(path, column)?,
        None => {
            let mut table = output::read_csv_table(path)?;
            if table.columns.len() != 2 {
                return Err(Error::AmbiguousColumn {
                    path: path_text.to_string(),
                    columns: table.header,
                });
            }
            let values = table.columns.pop().unwrap_or_default();
            (table.columns.pop().unwrap_or_default(), values)
        }
    };
    let scale = match v[2] {
        Some(unit) => {
            let unit = unquote(unit);
            let (scale, found) =
                units::parse_quantity(&format!("1 {unit}")).map_err(|reason| Error::BadUnit {
                    unit: unit.to_string(),
                    reason: reason.to_string(),
                })?;
            if found != expected {
                return Err(Error::WrongUnit {
                    unit: unit.to_string(),
                    found,
                    expected,
                });
            }
            scale
        }
        None if expected == Dimension::NONE => 1.0,
        None => return Err(Error::MissingUnit { expected }),
    };
    values.iter_mut().for_each(|v| *v *= scale);
    let table = Table::new(times, values).map_err(|error| Error::Table {
        path: path_text.to_string(),
        error,
    })?;
    Ok(Signal::Table(table))
}

/// Removes one pair of matching surrounding quotes.
fn unquote(text: &str) -> &str {
    for q in ['"', '\''] {
        if let Some(inner) = text.strip_prefix(q).and_then(|t| t.strip_suffix(q)) {
            return inner;
        }
    }
    text
}

/// What a quantity argument is, which fixes its dimension and conversion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum QuantityKind {
    /// A value of the input: amplitude, offset, constant.
    Value,
    /// A frequency, converted to Hz.
    Frequency,
    /// A phase, converted to radians.
    Phase,
    /// A duration in seconds.
    Duration,
}

/// Parses the quantity `text` given for argument `name` and checks its dimension; returns
/// the SI value (frequencies in Hz).
fn quantity(
    text: &str,
    name: &'static str,
    input: Dimension,
    kind: QuantityKind,
) -> Result<f64, Error> {
    let expected = match kind {
        QuantityKind::Value => input,
        QuantityKind::Frequency => Dimension::FREQUENCY,
        QuantityKind::Phase => Dimension::NONE,
        QuantityKind::Duration => Dimension::TIME,
    };
    let text = text.trim();
    let error = |problem| Error::Argument {
        name,
        text: text.to_string(),
        problem,
    };
    if !text.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '.') {
        return Err(error(ArgumentProblem::NotAQuantity { expected }));
    }
    let (value, found) = units::parse_quantity(text)
        .map_err(|reason| error(ArgumentProblem::BadSyntax(reason.to_string())))?;
    if found != expected {
        return Err(error(ArgumentProblem::WrongDimension {
            kind,
            found,
            expected,
        }));
    }
    // A frequency in rad/s or deg/s is angular: convert to cycles per second.
    let value = if kind == QuantityKind::Frequency && mentions_angle_unit(text) {
        value / TAU
    } else {
        value
    };
    if kind == QuantityKind::Frequency && value < 0.0 {
        return Err(error(ArgumentProblem::NegativeFrequency));
    }
    if kind == QuantityKind::Duration && value <= 0.0 {
        return Err(error(ArgumentProblem::NotPositiveDuration));
    }
    Ok(value)
}

/// Whether the unit part of a quantity contains an angle unit (`rad`, `mrad`, `deg`, ...):
/// any unit name that is dimensionless.
fn mentions_angle_unit(text: &str) -> bool {
    text.split(|c: char| !c.is_alphabetic())
        .filter(|word| !word.is_empty())
        .any(|word| units::lookup(word).is_some_and(|u| u.dimension == Dimension::NONE))
}

/// The candidate closest to `word` by edit distance, if it is close enough to be a typo
/// (more lenient than the language's `closest`: signal names are few and long).
fn suggest<'a>(word: &str, candidates: &[&'a str]) -> Option<&'a str> {
    let limit = word.chars().count().div_ceil(3).clamp(1, 3);
    candidates
        .iter()
        .map(|&c| (edit_distance(word, c), c))
        .filter(|&(d, _)| d <= limit)
        .min_by_key(|&(d, _)| d)
        .map(|(_, c)| c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const FORCE: Dimension = Dimension::FORCE;

    fn ok(spec: &str) -> Signal {
        parse_signal(spec, FORCE).unwrap_or_else(|e| panic!("`{spec}`: {e}"))
    }

    fn err(spec: &str) -> String {
        match parse_signal(spec, FORCE) {
            Ok(signal) => panic!("`{spec}` parsed as {signal:?}"),
            Err(e) => e.to_string(),
        }
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0)
    }

    #[test]
    fn assignments() {
        assert_eq!(
            parse_assignment("drive = sine(amp=1 mN, freq=10 Hz)").unwrap(),
            (
                "drive".to_string(),
                "sine(amp=1 mN, freq=10 Hz)".to_string()
            )
        );
        assert_eq!(
            parse_assignment("arm.length=2 mm").unwrap(),
            ("arm.length".to_string(), "2 mm".to_string())
        );
        for (text, message) in [
            ("drive", "expected NAME=VALUE, found `drive` (no `=`)"),
            (
                "=1 mN",
                "expected NAME=VALUE, found `=1 mN` (no name before `=`)",
            ),
            ("drive= ", "`drive=` has no value after `=`"),
            (
                "sine(amp=1 mN)",
                "expected NAME=VALUE, found `sine(amp=1 mN)`: `sine(amp` is not a name",
            ),
        ] {
            assert_eq!(parse_assignment(text).unwrap_err().to_string(), message);
        }
    }

    #[test]
    fn constants() {
        assert_eq!(ok("2.5 mN"), Signal::Constant(2.5e-3));
        assert_eq!(ok("  -3 N "), Signal::Constant(-3.0));
        assert_eq!(ok("constant(2.5 mN)"), Signal::Constant(2.5e-3));
        assert_eq!(ok("constant(value=1 kN)"), Signal::Constant(1e3));
        assert_eq!(
            parse_signal("0.5", Dimension::NONE).unwrap(),
            Signal::Constant(0.5)
        );
        let Signal::Constant(angle) = parse_signal("30 deg", Dimension::NONE).unwrap() else {
            panic!()
        };
        assert!(close(angle, PI / 6.0));
    }

    #[test]
    fn sines() {
        let Signal::Sine {
            amplitude,
            frequency_hz,
            phase_rad,
            offset,
        } = ok("sine(amplitude=1 mN, frequency=10 Hz, phase=90 deg, offset=0.5 mN)")
        else {
            panic!()
        };
        assert!(close(amplitude, 1e-3) && close(frequency_hz, 10.0));
        assert!(close(phase_rad, PI / 2.0) && close(offset, 5e-4));

        assert_eq!(
            ok("sine(amp=2 N, freq=1 kHz)"),
            Signal::Sine {
                amplitude: 2.0,
                frequency_hz: 1000.0,
                phase_rad: 0.0,
                offset: 0.0
            }
        );
        // Positional, then keyword; angular frequencies are converted to Hz.
        let Signal::Sine {
            frequency_hz,
            phase_rad,
            ..
        } = ok("sine(1 N, 360 deg/s, phase=0.5,)")
        else {
            panic!()
        };
        assert!(close(frequency_hz, 1.0) && close(phase_rad, 0.5));
        let Signal::Sine { frequency_hz, .. } = ok("sin(1 N, frequency = 10 rad/s)") else {
            panic!()
        };
        assert!(close(frequency_hz, 10.0 / TAU));
    }

    #[test]
    fn chirps() {
        assert_eq!(
            ok("chirp(amplitude=1 mN, f0=1 Hz, f1=100 Hz, duration=2 s, offset=-1 mN)"),
            Signal::Chirp {
                amplitude: 1e-3,
                f0_hz: 1.0,
                f1_hz: 100.0,
                duration: 2.0,
                offset: -1e-3
            }
        );
        let Signal::Chirp { duration, .. } =
            ok("chirp(amp=1 N, f0=0 Hz, f1=1 kHz, duration=500 ms)")
        else {
            panic!()
        };
        assert!(close(duration, 0.5));
    }

    fn temp_csv(name: &str, contents: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("mech-signal-spec-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, contents).unwrap();
        path
    }

    #[test]
    fn csv_tables() {
        let path = temp_csv("drive.csv", "t,force,other\n0,1,5\n0.5,2,6\n1,4,7\n");
        let spec = format!("csv({}, column=force, unit=mN)", path.display());
        let Signal::Table(table) = ok(&spec) else {
            panic!()
        };
        assert_eq!(table.times(), &[0.0, 0.5, 1.0]);
        assert_eq!(table.values(), &[1e-3, 2e-3, 4e-3]);

        // Quoted path, `file=` key, single data column, dimensionless input needs no unit.
        let two = temp_csv("two.csv", "time,angle\n0,0.1\n1,0.2\n");
        let spec = format!("csv(file=\"{}\")", two.display());
        let Signal::Table(table) = parse_signal(&spec, Dimension::NONE).unwrap() else {
            panic!()
        };
        assert_eq!(table.values(), &[0.1, 0.2]);

        let e = err(&format!("csv({})", path.display()));
        assert!(
            e.ends_with("has the columns `t`, `force`, `other`; choose one with `column=NAME`"),
            "{e}"
        );
        let e = err(&format!("csv({}, column=force)", path.display()));
        assert_eq!(
            e,
            "csv(...): give the unit of the values, e.g. `unit=N`: the input needs N"
        );
        let e = err(&format!("csv({}, column=force, unit=mm)", path.display()));
        assert_eq!(
            e,
            "csv(...): `unit=mm` is m, but the input needs N (e.g. `unit=N`)"
        );
        let e = err(&format!("csv({}, column=forse, unit=N)", path.display()));
        assert!(e.contains("has no column `forse`"), "{e}");
        let unsorted = temp_csv("unsorted.csv", "t,f\n1,1\n0,2\n");
        let e = err(&format!("csv({}, unit=N)", unsorted.display()));
        assert!(e.contains("must increase strictly"), "{e}");
        let e = err("csv(column=force)");
        assert!(e.starts_with("csv() is missing `path`"), "{e}");
    }

    #[test]
    fn dimension_errors() {
        assert_eq!(
            err("2.5"),
            "value `2.5` has no unit, but the input needs N: write e.g. `2.5 N`"
        );
        assert_eq!(
            err("sine(amplitude=1 mm, frequency=10 Hz)"),
            "amplitude `1 mm` is in m, but the input needs N: write e.g. `1 N`"
        );
        assert_eq!(
            err("sine(amplitude=1 N, frequency=10)"),
            "frequency `10` has no unit, but a frequency needs 1/s: write e.g. `10 Hz`"
        );
        assert_eq!(
            err("sine(amplitude=1 N, frequency=10 Hz, phase=1 s)"),
            "phase `1 s` is in s, but a phase is an angle (dimensionless): write e.g. `1 deg`"
        );
        assert_eq!(
            err("chirp(amplitude=1 N, f0=1 Hz, f1=2 Hz, duration=2)"),
            "duration `2` has no unit, but a duration needs s: write e.g. `2 s`"
        );
        assert_eq!(
            parse_signal("1 N", Dimension::NONE)
                .unwrap_err()
                .to_string(),
            "value `1 N` is in N, but the input is dimensionless: write e.g. `1`"
        );
        let voltage = Dimension {
            mass: 1,
            length: 2,
            time: -3,
            current: -1,
        };
        assert_eq!(
            parse_signal("3", voltage).unwrap_err().to_string(),
            "value `3` has no unit, but the input needs V: write e.g. `3 V`"
        );
    }

    #[test]
    fn structural_errors() {
        assert_eq!(
            err("sine(amplitude=1 mN)"),
            "sine() is missing `frequency`, e.g. `sine(amplitude=1 mN, frequency=10 Hz)`"
        );
        assert_eq!(
            err("sine(amplitude=1 mN, freqency=10 Hz)"),
            "unknown key `freqency` in sine(...), did you mean `frequency`?"
        );
        assert_eq!(
            err("sine(amplitude=1 mN, frq=10 Hz)"),
            "unknown key `frq` in sine(...), did you mean `frequency`?"
        );
        assert_eq!(
            err("sine(amplitude=1 mN, colour=red)"),
            "unknown key `colour` in sine(...); its keys are `amplitude`, `frequency`, `phase`, `offset`"
        );
        assert_eq!(
            err("sine(amp=1 mN, amplitude=2 mN, freq=1 Hz)"),
            "sine(...): `amplitude` is given twice"
        );
        assert_eq!(
            err("sine(amp=1 mN, 10 Hz)"),
            "sine(...): `10 Hz` needs a key (positional arguments must come before `key=value` ones)"
        );
        assert_eq!(
            err("sine(1 N, 1 Hz, 0, 0 N, 5)"),
            "sine(...) takes at most 4 arguments (`amplitude`, `frequency`, `phase`, `offset`), but got 5"
        );
        assert_eq!(
            err("sine(amp=1 mN,, freq=1 Hz)"),
            "sine(...): argument 2 is empty"
        );
        assert_eq!(
            err("sine(amp=, freq=1 Hz)"),
            "sine(...): `amp=` has no value"
        );
        assert_eq!(
            err("sine(amp=1 mN, freq=1 Hz"),
            "`sine(amp=1 mN, freq=1 Hz` is missing the closing `)`"
        );
        assert_eq!(
            err("sine"),
            "`sine` needs arguments in parentheses, e.g. `sine(amplitude=1 mN, frequency=10 Hz)`"
        );
        assert_eq!(
            err("sinus(amp=1 mN)"),
            "unknown signal `sinus(...)`, did you mean `sine(...)`?"
        );
        assert!(err("square(1 N)").starts_with("unknown signal `square(...)`; expected a quantity"));
        assert!(err("").starts_with("the signal is empty; expected a quantity such as `2.5 mN`"));
        assert!(err("hello world").starts_with("`hello world` is not a signal; expected"));
        assert_eq!(
            err("sine(amplitude=abc, frequency=1 Hz)"),
            "amplitude `abc` is not a quantity: expected a number with an optional unit, such as `1 N`"
        );
        assert_eq!(err("1 foo"), "value `1 foo`: unknown unit `foo`");
        assert_eq!(
            err("sine(amplitude=1 N, frequency=-1 Hz)"),
            "frequency `-1 Hz` is negative; frequencies must be >= 0 (use a negative amplitude or a phase to invert the signal)"
        );
        assert_eq!(
            err("chirp(amp=1 N, f0=1 Hz, f1=2 Hz, duration=0 s)"),
            "duration `0 s` must be > 0"
        );
        assert_eq!(
            err("constant(1 N, 2 N)"),
            "constant(...) takes at most 1 argument (`value`), but got 2"
        );
    }

    #[test]
    fn errors_carry_the_facts() {
        assert_eq!(
            parse_assignment("drive").unwrap_err(),
            AssignmentError::NoEquals {
                text: "drive".to_string()
            }
        );
        assert_eq!(
            parse_signal("sine(amplitude=1 mN)", FORCE).unwrap_err(),
            Error::MissingArgument {
                function: "sine",
                parameter: "frequency"
            }
        );
        assert_eq!(
            parse_signal("sine(amplitude=1 mm, frequency=10 Hz)", FORCE).unwrap_err(),
            Error::Argument {
                name: "amplitude",
                text: "1 mm".to_string(),
                problem: ArgumentProblem::WrongDimension {
                    kind: QuantityKind::Value,
                    found: Dimension::LENGTH,
                    expected: FORCE
                }
            }
        );
        let missing = std::env::temp_dir().join("mech-signal-spec-no-such-file.csv");
        let error = parse_signal(&format!("csv({}, unit=N)", missing.display()), FORCE);
        assert!(
            matches!(&error, Err(Error::Csv(csv)) if csv.path == missing),
            "{error:?}"
        );
    }

    #[test]
    fn helpers() {
        assert_eq!(leading_number("2.5mN"), Some("2.5"));
        assert_eq!(leading_number("-1e-3 N"), Some("-1e-3"));
        assert_eq!(leading_number("abc"), None);
        assert!(mentions_angle_unit("10 rad/s") && mentions_angle_unit("5 deg/s"));
        assert!(!mentions_angle_unit("10 Hz") && !mentions_angle_unit("1e3 s^-1"));
    }
}
