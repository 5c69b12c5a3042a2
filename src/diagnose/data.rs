//! Measured data: a CSV file whose column headers carry units.
//!
//! Consumes: the path of a CSV file (or its bytes, with the path to name in messages).
//! Produces: a [`MeasuredData`] with every column converted to SI and its physical
//! [`Dimension`], or [`DataErrors`]: every problem of the file (up to [`MAX_ERRORS`]), each
//! naming the file, the line (1-based, as an editor shows it) and the column (name and
//! 1-based index).
//!
//! The format (documented in `docs/diagnose.md`, "Measured data"):
//!
//! ```text
//! # HAMR-VI lift sweep, 2024-03-02     <- `#` lines are comments (anywhere)
//! t [s], v_lift [V], foot.z [mm], phase [deg], ratio
//! 0.000, 0, 0.000, 0, 1
//! 0.001, 1.5, 0.012, 0.3, 1
//! ```
//!
//! - the first line that is not a comment or blank is the header;
//! - each header is `name [unit]`; the unit is anything the `.mech` language accepts
//!   (`mm`, `mN`, `uN*m/rad`, `mm/V`, `deg`, `Hz`, ...), plus `%`; a dimensionless column may
//!   omit the unit (or write `[]`, `[1]` or `[-]`);
//! - values are converted to SI: `mm` → m, `mN` → N, `deg` → rad (angles are dimensionless
//!   in SI, so `phase [deg]` and `phase [rad]` are both dimensionless and both stored in
//!   radians), `Hz` → 1/s, `%` → fraction;
//! - every value must be a finite number; every row must have as many fields as the header;
//! - fields are separated by commas and trimmed; a field may be quoted (`"a, b"`, `""` for
//!   a quote) but may not span lines.

use std::fmt;
use std::path::{Path, PathBuf};

use mech_codegen::diag::closest;
use mech_codegen::front::units;
use mech_codegen::ir::Dimension;

/// At most this many errors are reported for one file; the rest are counted.
pub const MAX_ERRORS: usize = 20;

/// One column of measured data.
#[derive(Clone, Debug, PartialEq)]
pub struct Column {
    /// The name, without the unit: `foot.x` for the header `foot.x [mm]`.
    pub name: String,
    /// The unit as written between the brackets (`mm`); empty if none was given.
    pub unit_text: String,
    /// The physical dimension of the unit ([`Dimension::NONE`] for angles and ratios).
    pub dimension: Dimension,
    /// The factor that converted the file's numbers to SI (`1e-3` for `mm`).
    pub scale: f64,
    /// The values in SI units, one per data row.
    pub values: Vec<f64>,
}

/// A measured-data file, loaded and checked: every column has the same number of finite
/// values, in SI units.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasuredData {
    /// The file, as named in messages.
    pub path: PathBuf,
    /// The columns, in file order.
    pub columns: Vec<Column>,
    /// Number of data rows.
    pub rows: usize,
    /// The 1-based line number in the file of each data row (for messages).
    pub lines: Vec<usize>,
}

/// One problem with a measured-data file. Every variant names the file; those about a
/// place in the file name the line (1-based) and, where it applies, the column (its name and
/// 1-based index).
#[derive(Clone, Debug, PartialEq)]
pub enum DataError {
    /// The file cannot be read.
    Io { path: PathBuf, message: String },
    /// The file is not UTF-8 text ([`crate::output::encoding_problem`]'s words).
    NotText { path: PathBuf, problem: String },
    /// The file has no header line (it is empty, or holds only comments and blank lines).
    Empty { path: PathBuf },
    /// The file has a header but no data rows.
    NoRows { path: PathBuf, header_line: usize },
    /// A column header is malformed or its unit is unknown.
    BadHeader {
        path: PathBuf,
        line: usize,
        index: usize,
        text: String,
        message: String,
    },
    /// Two columns have the same name.
    DuplicateColumn {
        path: PathBuf,
        line: usize,
        name: String,
        first: usize,
        second: usize,
    },
    /// A row has the wrong number of fields.
    FieldCount {
        path: PathBuf,
        line: usize,
        found: usize,
        expected: usize,
    },
    /// A field is not a number.
    BadNumber {
        path: PathBuf,
        line: usize,
        index: usize,
        column: String,
        text: String,
    },
    /// A field is NaN or infinite (as written, or after conversion to SI).
    NonFinite {
        path: PathBuf,
        line: usize,
        index: usize,
        column: String,
        text: String,
    },
    /// A value beyond [`OUTLIER_FACTOR`] times the median magnitude of its column: a typo
    /// or a logger's overflow, which a fit would chase as if the model were wrong.
    Outlier {
        path: PathBuf,
        line: usize,
        index: usize,
        column: String,
        text: String,
        /// The column's median magnitude, in the file's unit.
        median: f64,
    },
    /// A column does not increase strictly (see [`MeasuredData::check_time_monotonic`]).
    NotIncreasing {
        path: PathBuf,
        line: usize,
        previous_line: usize,
        index: usize,
        column: String,
        previous: f64,
        value: f64,
    },
    /// A required column is missing.
    MissingColumn {
        path: PathBuf,
        name: String,
        available: Vec<String>,
        suggestion: Option<String>,
    },
    /// A required column has the wrong dimension.
    DimensionMismatch {
        path: PathBuf,
        index: usize,
        column: String,
        unit_text: String,
        expected: Dimension,
        found: Dimension,
    },
}

/// Every error found in one file (at most [`MAX_ERRORS`]; `omitted` counts the rest).
#[derive(Clone, Debug, PartialEq)]
pub struct DataErrors {
    pub path: PathBuf,
    pub errors: Vec<DataError>,
    pub omitted: usize,
}

impl MeasuredData {
    /// The 1-based file line of data row `row` (0 if there is no such row).
    pub fn line(&self, row: usize) -> usize {
        self.lines.get(row).copied().unwrap_or(0)
    }

    /// Reads and checks the CSV file at `path`.
    pub fn load(path: &Path) -> Result<MeasuredData, DataErrors> {
        match std::fs::read(path) {
            Ok(bytes) => MeasuredData::parse(path, &bytes),
            Err(e) => Err(DataErrors {
                path: path.to_path_buf(),
                errors: vec![DataError::Io {
                    path: path.to_path_buf(),
                    message: e.to_string(),
                }],
                omitted: 0,
            }),
        }
    }

    /// Parses and checks CSV `bytes`; `path` only names the file in messages.
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<MeasuredData, DataErrors> {
        let mut errors = Collector::new(path);
        if let Some(problem) = crate::output::encoding_problem(bytes) {
            let path = path.to_path_buf();
            errors.push(DataError::NotText { path, problem });
            return Err(errors.finish());
        }
        let data = parse_bytes(path, bytes, &mut errors);
        match data {
            Some(data) if errors.errors.is_empty() => Ok(data),
            _ => Err(errors.finish()),
        }
    }

    /// The column called `name`, if any.
    pub fn find(&self, name: &str) -> Option<&Column> {
        self.columns.iter().find(|c| c.name == name)
    }

    /// The SI values of the column called `name`, if any.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.find(name).map(|c| c.values.as_slice())
    }

    /// The column names, in file order.
    pub fn names(&self) -> Vec<&str> {
        self.columns.iter().map(|c| c.name.as_str()).collect()
    }

    /// The SI values of the column `name`, which must exist and have dimension `expected`.
    pub fn require(&self, name: &str, expected: Dimension) -> Result<&[f64], DataError> {
        let (index, column) = self.find_indexed(name)?;
        if column.dimension != expected {
            return Err(DataError::DimensionMismatch {
                path: self.path.clone(),
                index: index + 1,
                column: column.name.clone(),
                unit_text: column.unit_text.clone(),
                expected,
                found: column.dimension,
            });
        }
        Ok(&column.values)
    }

    /// Checks that the column `name` (usually time) increases strictly; the error names the
    /// first row where it does not.
    pub fn check_time_monotonic(&self, name: &str) -> Result<(), DataError> {
        let (index, column) = self.find_indexed(name)?;
        for (k, pair) in column.values.windows(2).enumerate() {
            // Not `a >= b`: this also rejects NaN (which `parse` never lets in, but a
            // hand-built `MeasuredData` might hold).
            let increasing = pair[0] < pair[1];
            if !increasing {
                return Err(DataError::NotIncreasing {
                    path: self.path.clone(),
                    line: self.line(k + 1),
                    previous_line: self.line(k),
                    index: index + 1,
                    column: column.name.clone(),
                    previous: pair[0],
                    value: pair[1],
                });
            }
        }
        Ok(())
    }

    fn find_indexed(&self, name: &str) -> Result<(usize, &Column), DataError> {
        self.columns
            .iter()
            .enumerate()
            .find(|(_, c)| c.name == name)
            .ok_or_else(|| {
                let names = self.names();
                DataError::MissingColumn {
                    path: self.path.clone(),
                    name: name.to_string(),
                    available: names.iter().map(|s| s.to_string()).collect(),
                    suggestion: closest(name, &names).map(str::to_string),
                }
            })
    }
}

/// Collects errors up to [`MAX_ERRORS`].
struct Collector {
    path: PathBuf,
    errors: Vec<DataError>,
    omitted: usize,
}

impl Collector {
    fn new(path: &Path) -> Collector {
        Collector {
            path: path.to_path_buf(),
            errors: Vec::new(),
            omitted: 0,
        }
    }
    fn push(&mut self, error: DataError) {
        if self.errors.len() < MAX_ERRORS {
            self.errors.push(error);
        } else {
            self.omitted += 1;
        }
    }
    fn finish(self) -> DataErrors {
        DataErrors {
            path: self.path,
            errors: self.errors,
            omitted: self.omitted,
        }
    }
}

/// A parsed header field.
struct Header {
    name: String,
    unit_text: String,
    conversion: Conversion,
    dimension: Dimension,
}

/// The parser proper: `None` when nothing usable came out (errors are in `errors`).
fn parse_bytes(path: &Path, bytes: &[u8], errors: &mut Collector) -> Option<MeasuredData> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let mut header: Option<(usize, Vec<Header>)> = None;
    let mut columns: Vec<Vec<f64>> = Vec::new();
    let mut lines = Vec::new();
    for (number, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = number + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let text = String::from_utf8_lossy(raw);
        let trimmed = text.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        let record = split_fields(trimmed);
        let Some((_, fields)) = &header else {
            header = Some((line, parse_header_line(path, line, &record, errors)));
            continue;
        };
        if columns.len() != fields.len() {
            columns = vec![Vec::new(); fields.len()];
        }
        if record.len() != fields.len() {
            errors.push(DataError::FieldCount {
                path: path.to_path_buf(),
                line,
                found: record.len(),
                expected: fields.len(),
            });
            continue;
        }
        for (j, (text, column)) in record.iter().zip(fields).enumerate() {
            match parse_value(text, column.conversion) {
                Ok(value) => columns[j].push(value),
                Err(non_finite) => {
                    let (path, index, column, text) =
                        (path.to_path_buf(), j + 1, column.name.clone(), text.clone());
                    errors.push(if non_finite {
                        DataError::NonFinite {
                            path,
                            line,
                            index,
                            column,
                            text,
                        }
                    } else {
                        DataError::BadNumber {
                            path,
                            line,
                            index,
                            column,
                            text,
                        }
                    });
                    columns[j].push(f64::NAN);
                }
            }
        }
        lines.push(line);
    }
    let Some((header_line, fields)) = header else {
        errors.push(DataError::Empty {
            path: path.to_path_buf(),
        });
        return None;
    };
    if lines.is_empty() && errors.errors.is_empty() {
        errors.push(DataError::NoRows {
            path: path.to_path_buf(),
            header_line,
        });
        return None;
    }
    check_outliers(path, &fields, &columns, &lines, errors);
    let rows = lines.len();
    let columns = fields
        .into_iter()
        .zip(columns.into_iter().chain(std::iter::repeat(Vec::new())))
        .map(|(h, values)| Column {
            name: h.name,
            unit_text: h.unit_text,
            dimension: h.dimension,
            scale: h.conversion.scale(),
            values,
        })
        .collect();
    Some(MeasuredData {
        path: path.to_path_buf(),
        columns,
        rows,
        lines,
    })
}

/// An error for each value far beyond its column's median magnitude ([`outliers`]), at its
/// file `lines` (one per row).
fn check_outliers(
    path: &Path,
    fields: &[Header],
    columns: &[Vec<f64>],
    lines: &[usize],
    errors: &mut Collector,
) {
    for (index, (column, values)) in fields.iter().zip(columns).enumerate() {
        for (row, median) in outliers(values) {
            let scale = column.conversion.scale();
            errors.push(DataError::Outlier {
                path: path.to_path_buf(),
                line: lines[row],
                index: index + 1,
                column: column.name.clone(),
                text: format!("{:e}", values[row] / scale),
                median: median / scale,
            });
        }
    }
}

/// How far beyond its column's median magnitude a value may lie. Measured series span a
/// few decades at most (a ring-down from 10° to 0.01°, a force from µN to mN); 10⁶ leaves
/// room for any of them and catches a stray exponent.
pub const OUTLIER_FACTOR: f64 = 1e6;

/// The rows of `values` beyond [`OUTLIER_FACTOR`] times the median of the nonzero
/// magnitudes, each with that median.
fn outliers(values: &[f64]) -> Vec<(usize, f64)> {
    let mut magnitudes: Vec<f64> = values
        .iter()
        .map(|v| v.abs())
        .filter(|m| *m > 0.0 && m.is_finite())
        .collect();
    if magnitudes.is_empty() {
        return Vec::new();
    }
    let middle = magnitudes.len() / 2;
    let median = *magnitudes.select_nth_unstable_by(middle, f64::total_cmp).1;
    values
        .iter()
        .enumerate()
        .filter(|(_, v)| v.abs() > OUTLIER_FACTOR * median)
        .map(|(row, _)| (row, median))
        .collect()
}

/// Splits one line at commas into trimmed fields. A field may be quoted (`"a, b"`, with
/// `""` for a quote inside); an unterminated quote runs to the end of the line. Fields do
/// not span lines.
fn split_fields(line: &str) -> Vec<String> {
    let mut fields = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            '"' if quoted => quoted = false,
            '"' if field.trim().is_empty() => {
                field.clear();
                quoted = true;
            }
            ',' if !quoted => fields.push(std::mem::take(&mut field).trim().to_string()),
            c => field.push(c),
        }
    }
    fields.push(field.trim().to_string());
    fields
}

/// How a column's numbers become SI values.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Conversion {
    /// Multiply by the scale (`deg`: π/180).
    Multiply(f64),
    /// Divide by an integer (`mm`: 1000), so that `5 um` is exactly the double nearest to
    /// 5e-6 rather than `5 × 1e-6`, which is off by an ulp.
    Divide(f64),
}

impl Conversion {
    fn from_scale(scale: f64) -> Conversion {
        let inverse = 1.0 / scale;
        let whole = inverse.round();
        if scale < 1.0 && whole.is_finite() && (inverse - whole).abs() <= 1e-9 * whole {
            Conversion::Divide(whole)
        } else {
            Conversion::Multiply(scale)
        }
    }
    fn scale(self) -> f64 {
        match self {
            Conversion::Multiply(scale) => scale,
            Conversion::Divide(divisor) => 1.0 / divisor,
        }
    }
    fn apply(self, value: f64) -> f64 {
        match self {
            Conversion::Multiply(scale) => value * scale,
            Conversion::Divide(divisor) => value / divisor,
        }
    }
}

/// Parses a field: `Ok(SI value)`, or `Err(true)` for NaN/infinite (as written or after
/// conversion), `Err(false)` for text that is not a number.
fn parse_value(text: &str, conversion: Conversion) -> Result<f64, bool> {
    let value: f64 = text.parse().map_err(|_| false)?;
    let si = conversion.apply(value);
    if si.is_finite() {
        Ok(si)
    } else {
        Err(true)
    }
}

/// Parses the header line; a bad field is reported and kept as a dimensionless column (so
/// the rows can still be checked).
fn parse_header_line(
    path: &Path,
    line: usize,
    record: &[String],
    errors: &mut Collector,
) -> Vec<Header> {
    let mut headers: Vec<Header> = Vec::with_capacity(record.len());
    for (j, text) in record.iter().enumerate() {
        let text = text.clone();
        let header = match parse_header(&text) {
            Ok(header) => header,
            Err(message) => {
                errors.push(DataError::BadHeader {
                    path: path.to_path_buf(),
                    line,
                    index: j + 1,
                    text: text.clone(),
                    message,
                });
                Header {
                    name: text,
                    unit_text: String::new(),
                    conversion: Conversion::Multiply(1.0),
                    dimension: Dimension::NONE,
                }
            }
        };
        if let Some(first) = headers.iter().position(|h| h.name == header.name) {
            errors.push(DataError::DuplicateColumn {
                path: path.to_path_buf(),
                line,
                name: header.name.clone(),
                first: first + 1,
                second: j + 1,
            });
        }
        headers.push(header);
    }
    headers
}

/// Parses one header field, `name [unit]` or `name`.
fn parse_header(text: &str) -> Result<Header, String> {
    let text = text.trim();
    let (name, unit_text) = match text.find('[') {
        None => {
            if text.contains(']') {
                return Err("a `]` without `[`: write the unit as `name [unit]`".to_string());
            }
            (text, "")
        }
        Some(open) => {
            let rest = &text[open + 1..];
            let Some(close) = rest.find(']') else {
                return Err("the unit is not closed: write `name [unit]`".to_string());
            };
            if !rest[close + 1..].trim().is_empty() {
                return Err(format!(
                    "text after the unit (`{}`): write `name [unit]`",
                    rest[close + 1..].trim()
                ));
            }
            (text[..open].trim(), rest[..close].trim())
        }
    };
    if name.is_empty() {
        return Err("the column has no name: write `name [unit]`, e.g. `t [s]`".to_string());
    }
    if name.contains(['[', ']']) {
        return Err("a name may not contain brackets".to_string());
    }
    let (scale, dimension) = parse_unit(unit_text)?;
    Ok(Header {
        name: name.to_string(),
        unit_text: unit_text.to_string(),
        conversion: Conversion::from_scale(scale),
        dimension,
    })
}

/// The SI scale and dimension of a unit written in a header.
fn parse_unit(unit: &str) -> Result<(f64, Dimension), String> {
    match unit {
        "" | "1" | "-" => return Ok((1.0, Dimension::NONE)),
        "%" => return Ok((0.01, Dimension::NONE)),
        "dB" | "db" => {
            return Err(
                "`dB` is logarithmic and cannot be converted by a factor: give the gain as a \
                 ratio (e.g. `gain [mm/V]`, value 10^(dB/20) in those units)"
                    .to_string(),
            )
        }
        _ => {}
    }
    if unit.starts_with(|c: char| c.is_ascii_digit() || c == '.' || c == '-' || c == '+') {
        return Err(format!(
            "unit `{unit}` starts with a number: write units only (`mm`, `1/s` as `Hz`)"
        ));
    }
    let (scale, dimension) = units::parse_quantity(&format!("1 {unit}")).map_err(|e| {
        let e = e.to_string();
        let mut message = if e.contains(unit) {
            e
        } else {
            format!("unit `{unit}`: {e}")
        };
        let names = units::all_unit_names();
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        if let Some(close) = closest(unit, &names) {
            message.push_str(&format!("; did you mean `{close}`?"));
        }
        message
    })?;
    if !(scale.is_finite() && scale > 0.0) {
        return Err(format!("unit `{unit}` is out of range"));
    }
    Ok((scale, dimension))
}

/// A unit to suggest for a dimension in messages.
fn example_unit(dimension: Dimension) -> Option<&'static str> {
    let per_second = Dimension::TIME.powi(-1);
    Some(match dimension {
        d if d == Dimension::NONE => "deg`, `rad` or no unit",
        d if d == Dimension::LENGTH => "mm",
        d if d == Dimension::FORCE => "mN",
        d if d == Dimension::TORQUE => "uN*m",
        d if d == Dimension::TIME => "s",
        d if d == Dimension::MASS => "mg",
        d if d == per_second => "Hz",
        _ => return None,
    })
}

impl fmt::Display for DataError {
    /// `` `path`, line L, column I (`name`): problem ``, as much of the place as applies.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let separator = match self {
            DataError::MissingColumn { .. } => " ",
            _ => ": ",
        };
        write!(f, "{}{separator}{}", self.place(), self.problem())
    }
}

impl DataError {
    /// Where the problem is: the file, then the line and the column where they apply.
    fn place(&self) -> String {
        let (path, line, column) = match self {
            DataError::Io { path, .. }
            | DataError::NotText { path, .. }
            | DataError::Empty { path }
            | DataError::MissingColumn { path, .. } => (path, None, None),
            DataError::NoRows { path, header_line } => (path, Some(*header_line), None),
            DataError::FieldCount { path, line, .. } => (path, Some(*line), None),
            DataError::BadHeader {
                path,
                line,
                index,
                text: name,
                ..
            }
            | DataError::DuplicateColumn {
                path,
                line,
                second: index,
                name,
                ..
            }
            | DataError::BadNumber {
                path,
                line,
                index,
                column: name,
                ..
            }
            | DataError::NonFinite {
                path,
                line,
                index,
                column: name,
                ..
            }
            | DataError::Outlier {
                path,
                line,
                index,
                column: name,
                ..
            }
            | DataError::NotIncreasing {
                path,
                line,
                index,
                column: name,
                ..
            } => (path, Some(*line), Some((*index, name))),
            DataError::DimensionMismatch {
                path,
                index,
                column,
                ..
            } => (path, None, Some((*index, column))),
        };
        let mut place = format!("`{}`", path.display());
        if let Some(line) = line {
            place.push_str(&format!(", line {line}"));
        }
        if let Some((index, name)) = column {
            place.push_str(&format!(", column {index} (`{name}`)"));
        }
        place
    }

    /// What is wrong there, and how to mend it where that is not obvious.
    fn problem(&self) -> String {
        match self {
            DataError::Io { message, .. } => format!("cannot read the file: {message}"),
            DataError::NotText { problem, .. } => problem.clone(),
            DataError::Empty { .. } => "the file is empty: the first line that is not a `#` \
                                        comment must be the header, e.g. `t [s], foot.x [mm]`"
                .to_string(),
            DataError::NoRows { .. } => "a header but no data rows".to_string(),
            DataError::BadHeader { message, .. } => message.clone(),
            DataError::DuplicateColumn { first, .. } => {
                format!("the name of column {first} again; column names must be unique")
            }
            DataError::FieldCount {
                found, expected, ..
            } => format!(
                "{found} field{}, but the header has {expected} column{}",
                plural(*found),
                plural(*expected)
            ),
            DataError::BadNumber { text, .. } if text.is_empty() => {
                "the field is empty".to_string()
            }
            DataError::BadNumber { text, .. } => format!("`{text}` is not a number"),
            DataError::Outlier { text, median, .. } => format!(
                "`{text}` is more than {OUTLIER_FACTOR:e} times the column's median magnitude \
                 ({median:e}): a typo or an overflow of the logger? Correct or remove the row"
            ),
            DataError::NonFinite { text, .. } => format!(
                "`{text}` is not finite (NaN, infinite or out of range in SI units); remove \
                 the row or fill the gap"
            ),
            DataError::NotIncreasing {
                previous_line,
                column,
                previous,
                value,
                ..
            } => format!(
                "{value} (SI) does not increase from {previous} on line {previous_line}; \
                 `{column}` must increase strictly (sort the rows, remove repeated samples)"
            ),
            DataError::MissingColumn {
                name,
                available,
                suggestion,
                ..
            } => missing_column(name, available, suggestion.as_deref()),
            DataError::DimensionMismatch {
                column,
                unit_text,
                expected,
                found,
                ..
            } => dimension_mismatch(column, unit_text, *expected, *found),
        }
    }
}

/// `has no column …; its columns are …`, with a suggestion or how to add the column.
fn missing_column(name: &str, available: &[String], suggestion: Option<&str>) -> String {
    let list = available
        .iter()
        .map(|a| format!("`{a}`"))
        .collect::<Vec<_>>()
        .join(", ");
    let mend = match suggestion {
        Some(s) => format!("did you mean `{s}`?"),
        None => format!("add a column with the header `{name} [unit]` or rename one"),
    };
    format!("has no column `{name}`; its columns are {list}; {mend}")
}

/// `expected D, found D (unit)`, and a unit of the expected dimension to write.
fn dimension_mismatch(
    column: &str,
    unit_text: &str,
    expected: Dimension,
    found: Dimension,
) -> String {
    let unit = if unit_text.is_empty() {
        "no unit".to_string()
    } else {
        format!("`[{unit_text}]`")
    };
    let mut problem = format!(
        "expected {}, found {} ({unit})",
        units::describe(expected),
        units::describe(found)
    );
    if let Some(example) = example_unit(expected) {
        problem.push_str(&format!(
            "; give the unit in the header, e.g. `{column} [{example}]`"
        ));
    }
    problem
}

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

impl std::error::Error for DataError {}

impl fmt::Display for DataErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, error) in self.errors.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "error: {error}")?;
        }
        if self.omitted > 0 {
            write!(
                f,
                "\n... and {} more error{} in `{}`",
                self.omitted,
                plural(self.omitted),
                self.path.display()
            )?;
        }
        Ok(())
    }
}

impl std::error::Error for DataErrors {}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<MeasuredData, DataErrors> {
        MeasuredData::parse(Path::new("run/measured.csv"), text.as_bytes())
    }

    fn errors(text: &str) -> Vec<String> {
        match parse(text) {
            Ok(data) => panic!("expected errors, parsed {data:?}"),
            Err(e) => e.errors.iter().map(ToString::to_string).collect(),
        }
    }

    fn single_error(text: &str) -> String {
        let all = errors(text);
        assert_eq!(all.len(), 1, "{all:#?}");
        all.into_iter().next().unwrap_or_default()
    }

    fn assert_contains(message: &str, parts: &[&str]) {
        for part in parts {
            assert!(message.contains(part), "`{part}` not in: {message}");
        }
    }

    #[test]
    fn converts_units_to_si() {
        let data = parse(
            "# a comment before the header\n\
             t [s], foot.x [mm], force.x [mN], v_lift [V], frequency [Hz], gain [mm/V], \
             phase [deg], ratio, share [%], torque [uN*m]\n\
             # a comment between rows\n\
             0.5, 2, 3, 100, 40, 0.25, 90, 7, 50, 2\n\
             \n   # an indented comment\n\
             1.5, -4e1, 0, 0, 1e3, 1, -180, 0, 100, 0\n",
        )
        .expect("valid file");
        assert_eq!(data.rows, 2);
        assert_eq!(data.lines, vec![4, 7]);
        let close = |a: &[f64], b: &[f64]| {
            assert_eq!(a.len(), b.len());
            for (x, y) in a.iter().zip(b) {
                assert!((x - y).abs() <= 1e-15 * y.abs().max(1.0), "{a:?} vs {b:?}");
            }
        };
        close(data.require("t", Dimension::TIME).unwrap(), &[0.5, 1.5]);
        close(
            data.require("foot.x", Dimension::LENGTH).unwrap(),
            &[2e-3, -4e-2],
        );
        close(
            data.require("force.x", Dimension::FORCE).unwrap(),
            &[3e-3, 0.0],
        );
        let volt = Dimension::TORQUE.div(Dimension::TIME.mul(Dimension::CURRENT));
        close(data.require("v_lift", volt).unwrap(), &[100.0, 0.0]);
        close(
            data.require("frequency", Dimension::TIME.powi(-1)).unwrap(),
            &[40.0, 1000.0],
        );
        close(
            data.require("gain", Dimension::LENGTH.div(volt)).unwrap(),
            &[0.25e-3, 1e-3],
        );
        // Angles are dimensionless and stored in radians.
        close(
            data.require("phase", Dimension::NONE).unwrap(),
            &[std::f64::consts::FRAC_PI_2, -std::f64::consts::PI],
        );
        close(data.require("ratio", Dimension::NONE).unwrap(), &[7.0, 0.0]);
        close(data.require("share", Dimension::NONE).unwrap(), &[0.5, 1.0]);
        close(
            data.require("torque", Dimension::TORQUE).unwrap(),
            &[2e-6, 0.0],
        );
        let phase = data.find("phase").unwrap();
        assert_eq!(phase.unit_text, "deg");
        assert_eq!(data.columns[7].unit_text, "");
        assert_eq!(data.column("nope"), None);
        assert!(data.check_time_monotonic("t").is_ok());
    }

    #[test]
    fn byte_order_mark_and_crlf_are_accepted() {
        let data = MeasuredData::parse(
            Path::new("x.csv"),
            b"\xEF\xBB\xBFt [s],y [mm]\r\n0,1\r\n1,2\r\n",
        )
        .expect("valid");
        assert_eq!(data.names(), vec!["t", "y"]);
        assert_eq!(data.column("y"), Some(&[1e-3, 2e-3][..]));
    }

    #[test]
    fn quoted_fields_may_hold_commas() {
        let data = parse("\"t [s]\", \"a, \"\"b\"\" [mm]\"\n\"0\", 1\n").expect("valid");
        assert_eq!(data.names(), vec!["t", "a, \"b\""]);
        assert_eq!(data.column("a, \"b\""), Some(&[1e-3][..]));
    }

    #[test]
    fn wrong_field_count_names_file_and_line() {
        let message = single_error("t [s], y [mm]\n0, 1\n1, 2, 3\n");
        assert_contains(
            &message,
            &["run/measured.csv", "line 3", "3 fields", "2 columns"],
        );
    }

    #[test]
    fn unparsable_number_names_file_line_and_column() {
        let message = single_error("t [s], y [mm]\n0, 1\n# c\n1, 2x\n");
        assert_contains(
            &message,
            &["run/measured.csv", "line 4", "column 2", "`y`", "`2x`"],
        );
        let message = single_error("t [s], y [mm]\n0, \n");
        assert_contains(&message, &["line 2", "column 2", "empty"]);
    }

    #[test]
    fn non_finite_values_are_rejected() {
        let all = errors("t [s], y [mm]\nNaN, 1\n1, inf\n2, 1e309\n");
        assert_eq!(all.len(), 3, "{all:#?}");
        assert_contains(&all[0], &["run/measured.csv", "line 2", "column 1", "`t`"]);
        assert_contains(&all[1], &["line 3", "column 2", "`y`", "not finite"]);
        assert_contains(&all[2], &["line 4", "column 2", "`1e309`"]);
        // Finite as written, infinite in SI.
        let message = single_error("p [GPa]\n1e300\n");
        assert_contains(&message, &["line 2", "column 1", "`p`", "not finite"]);
    }

    #[test]
    fn empty_files_are_rejected() {
        for text in ["", "\n\n", "# only a comment\n  \n"] {
            let message = single_error(text);
            assert_contains(&message, &["run/measured.csv", "empty", "header"]);
        }
        let message = single_error("# c\nt [s], y [mm]\n");
        assert_contains(&message, &["run/measured.csv", "line 2", "no data rows"]);
    }

    #[test]
    fn duplicate_columns_are_rejected() {
        let message = single_error("t [s], y [mm], y [m]\n0, 1, 2\n");
        assert_contains(
            &message,
            &[
                "run/measured.csv",
                "line 1",
                "column 3",
                "`y`",
                "column 2",
                "unique",
            ],
        );
    }

    #[test]
    fn bad_headers_are_rejected() {
        let all = errors("t [s], y [furlong], z [mm, [mm], w [mm] x, q [dB]\n0,1,2,3,4,5\n");
        assert_eq!(all.len(), 5, "{all:#?}");
        assert_contains(&all[0], &["line 1", "column 2", "unknown unit `furlong`"]);
        let message = single_error("t [s], f [mNN]\n0, 1\n");
        assert_contains(
            &message,
            &[
                "column 2 (`f [mNN]`)",
                "unknown unit `mNN`",
                "did you mean `mN`?",
            ],
        );
        assert_contains(&all[1], &["column 3", "not closed"]);
        assert_contains(&all[2], &["column 4", "no name"]);
        assert_contains(&all[3], &["column 5", "after the unit"]);
        assert_contains(&all[4], &["column 6", "dB"]);
    }

    #[test]
    fn collects_every_error_up_to_the_cap() {
        let mut text = String::from("t [s], y [mm]\n");
        for i in 0..30 {
            text.push_str(&format!("{i}, oops\n"));
        }
        text.push_str("1, 2, 3\n");
        let e = parse(&text).unwrap_err();
        assert_eq!(e.errors.len(), MAX_ERRORS);
        assert_eq!(e.omitted, 11);
        let shown = e.to_string();
        assert_contains(&shown, &["line 2", "line 21", "11 more errors"]);
        assert!(!shown.contains("line 22,"), "{shown}");
    }

    #[test]
    fn time_must_increase_strictly() {
        let data = parse("# rig 2\nt [ms], y\n0, 1\n1, 1\n# gap\n1, 2\n3, 4\n2, 5\n").unwrap();
        let message = data.check_time_monotonic("t").unwrap_err().to_string();
        assert_contains(
            &message,
            &[
                "run/measured.csv",
                "line 6",
                "line 4",
                "column 1",
                "`t`",
                "increase",
            ],
        );
        let message = data.check_time_monotonic("time").unwrap_err().to_string();
        assert_contains(&message, &["no column `time`", "`t`, `y`"]);
    }

    #[test]
    fn require_reports_missing_columns_and_wrong_dimensions() {
        let data = parse("t [s], foot.x [mm], force.x [mN]\n0, 1, 2\n").unwrap();
        let message = data.require("foot.y", Dimension::LENGTH).unwrap_err();
        assert!(matches!(message, DataError::MissingColumn { .. }));
        assert_contains(
            &message.to_string(),
            &[
                "run/measured.csv",
                "no column `foot.y`",
                "`t`, `foot.x`, `force.x`",
                "did you mean `foot.x`",
            ],
        );
        let message = data.require("velocity", Dimension::LENGTH).unwrap_err();
        assert_contains(&message.to_string(), &["`velocity [unit]`"]);
        let message = data.require("force.x", Dimension::LENGTH).unwrap_err();
        assert_contains(
            &message.to_string(),
            &[
                "run/measured.csv",
                "column 3",
                "`force.x`",
                "expected m",
                "found N",
                "`[mN]`",
                "`force.x [mm]`",
            ],
        );
    }

    #[test]
    fn load_reports_unreadable_files() {
        let e = MeasuredData::load(Path::new("/nonexistent/mech/measured.csv")).unwrap_err();
        assert_contains(
            &e.to_string(),
            &["/nonexistent/mech/measured.csv", "cannot read"],
        );
    }

    #[test]
    fn load_reads_a_file() {
        let dir = std::env::temp_dir().join(format!("mech-diagnose-data-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("m.csv");
        std::fs::write(&path, "t [s], y [um]\n0, 5\n").unwrap();
        let data = MeasuredData::load(&path).unwrap();
        assert_eq!(data.column("y"), Some(&[5e-6][..]));
        assert_eq!(data.path, path);
        std::fs::remove_dir_all(&dir).ok();
    }

    proptest::proptest! {
        #[test]
        fn never_panics_on_arbitrary_bytes(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..200)) {
            let _ = MeasuredData::parse(Path::new("fuzz.csv"), &bytes);
        }

        #[test]
        fn never_panics_on_csv_like_text(text in "[ta-c#\\[\\]%.,\n\r\"0-9eE+ -]{0,120}( \\[(mm|deg|dB|1/s|N\\*m)\\])?[,\n0-9.]{0,40}") {
            if let Ok(data) = MeasuredData::parse(Path::new("fuzz.csv"), text.as_bytes()) {
                for column in &data.columns {
                    proptest::prop_assert_eq!(column.values.len(), data.rows);
                    proptest::prop_assert!(column.values.iter().all(|v| v.is_finite()));
                }
                let _ = data.check_time_monotonic("t");
                let _ = data.require("a", Dimension::NONE).map_err(|e| e.to_string());
            } else if let Err(e) = MeasuredData::parse(Path::new("fuzz.csv"), text.as_bytes()) {
                proptest::prop_assert!(!e.errors.is_empty());
                let _ = e.to_string();
            }
        }
    }
}
