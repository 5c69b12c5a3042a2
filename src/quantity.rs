//! Quantities with units as users write them (`225 V`, `2.2 +- 0.1 mm`), checked against the
//! dimension expected and converted to SI: the one parser of the analyses' files and
//! options. The units and dimensions themselves are the language's
//! ([`mech_codegen::front::units`], [`Dimension`]).
//!
//! Consumes: text and the expected [`Dimension`]. Produces: SI values, or an [`Error`] that
//! names the option or key, the text, and what was expected.

use std::fmt;

use mech_codegen::ir::Dimension;

/// Why a quantity cannot be used: what it sets, the text as written, and what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct Error {
    pub subject: Subject,
    /// The quantity as written (for a paper value, the part that failed).
    pub text: String,
    pub kind: ErrorKind,
}

/// What a quantity sets, which decides how messages name it.
#[derive(Debug, Clone, PartialEq)]
pub enum Subject {
    /// An option or key named as it is (`--mass`, `pendulum.mass`): [`parse_si`].
    Plain(String),
    /// A key of an experiment file, named ``key `voltage` ``: [`quantity`], [`positive`],
    /// [`paper_value`].
    Key(String),
}

/// What is wrong with a quantity, for [`Error`].
#[derive(Debug, Clone, PartialEq)]
pub enum ErrorKind {
    /// Not a number with a known unit; the unit parser's (or number parser's) reason.
    BadSyntax(String),
    /// A unit of another dimension (`found` is dimensionless for a bare number).
    WrongDimension {
        found: Dimension,
        expected: Dimension,
    },
    /// Infinite or NaN in SI.
    NotFinite,
    /// Zero or negative where a positive value is needed.
    NotPositive,
}

impl fmt::Display for Subject {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Subject::Plain(name) => f.write_str(name),
            Subject::Key(key) => write!(f, "key `{key}`"),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Error {
            subject,
            text,
            kind,
        } = self;
        write!(f, "{subject}: ")?;
        match (subject, kind) {
            (Subject::Plain(_), ErrorKind::BadSyntax(reason)) => f.write_str(reason),
            (Subject::Key(_), ErrorKind::BadSyntax(reason)) => write!(f, "`{text}`: {reason}"),
            (Subject::Plain(_), ErrorKind::WrongDimension { found, expected })
                if *found == Dimension::NONE =>
            {
                let number = leading_number(text).unwrap_or("1");
                write!(
                    f,
                    "`{text}` has no unit; write it with a unit of {expected}, e.g. `{}`",
                    example_quantity(number, *expected)
                )
            }
            (Subject::Plain(name), ErrorKind::WrongDimension { found, expected }) => {
                write!(f, "`{text}` has unit {found}, but {name} needs {expected}")
            }
            (Subject::Key(_), ErrorKind::WrongDimension { expected, .. }) => {
                write!(f, "expected {}, got `{text}`", dimension_name(*expected))
            }
            (_, ErrorKind::NotFinite) => write!(f, "`{text}` is not finite"),
            (_, ErrorKind::NotPositive) => write!(f, "expected a positive value, got `{text}`"),
        }
    }
}

impl std::error::Error for Error {}

/// Parses `text` (`2 mm`, `25 um`, `0.2 g`) as a quantity of dimension `expected` and returns
/// its SI value. A bare number is accepted only for dimensionless quantities unless
/// `bare_is_si`. `what` names the option or key in errors.
pub fn parse_si(
    what: &str,
    text: &str,
    expected: Dimension,
    bare_is_si: bool,
) -> Result<f64, Error> {
    let error = |kind| Error {
        subject: Subject::Plain(what.to_string()),
        text: text.to_string(),
        kind,
    };
    let (value, found) = mech_codegen::front::units::parse_quantity(text)
        .map_err(|e| error(ErrorKind::BadSyntax(e.to_string())))?;
    if found != expected && !(bare_is_si && found == Dimension::NONE) {
        return Err(error(ErrorKind::WrongDimension { found, expected }));
    }
    if !value.is_finite() {
        return Err(error(ErrorKind::NotFinite));
    }
    Ok(value)
}

/// Parses `text` (e.g. `"225 V"`) as a quantity of dimension `expected`, in SI. `key` names
/// the TOML key in errors.
pub fn quantity(key: &str, text: &str, expected: Dimension) -> Result<f64, Error> {
    let error = |kind| key_error(key, text, kind);
    let (value, found) = mech_codegen::front::units::parse_quantity(text)
        .map_err(|e| error(ErrorKind::BadSyntax(e.to_string())))?;
    if found != expected {
        return Err(error(ErrorKind::WrongDimension { found, expected }));
    }
    if !value.is_finite() {
        return Err(error(ErrorKind::NotFinite));
    }
    Ok(value)
}

/// As [`quantity`], and positive.
pub fn positive(key: &str, text: &str, expected: Dimension) -> Result<f64, Error> {
    let value = quantity(key, text, expected)?;
    if value <= 0.0 {
        return Err(key_error(key, text, ErrorKind::NotPositive));
    }
    Ok(value)
}

/// A paper value with its uncertainty: `"2.2 mm"` or `"2.2 +- 0.1 mm"`.
pub fn paper_value(key: &str, text: &str, expected: Dimension) -> Result<(f64, f64), Error> {
    match text.split_once("+-") {
        Some((mean, rest)) => {
            // `2.2 +- 0.1 mm`: the unit follows the spread.
            let rest = rest.trim();
            let split = rest
                .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == '-'))
                .unwrap_or(rest.len());
            let (spread, unit) = rest.split_at(split);
            let mean = quantity(key, &format!("{} {unit}", mean.trim()), expected)?;
            let spread = if unit.trim().is_empty() && expected == Dimension::NONE {
                let spread = spread.trim();
                spread.parse::<f64>().map_err(|_| {
                    key_error(
                        key,
                        text,
                        ErrorKind::BadSyntax(format!("the spread `{spread}` is not a number")),
                    )
                })?
            } else {
                quantity(key, &format!("{spread} {unit}"), expected)?
            };
            Ok((mean, spread))
        }
        None => Ok((quantity(key, text, expected)?, 0.0)),
    }
}

fn key_error(key: &str, text: &str, kind: ErrorKind) -> Error {
    Error {
        subject: Subject::Key(key.to_string()),
        text: text.to_string(),
        kind,
    }
}

/// What a key of dimension `d` expects, with an example, for messages about experiment files.
fn dimension_name(d: Dimension) -> &'static str {
    match d {
        Dimension::VOLTAGE => "a voltage (e.g. `225 V`)",
        Dimension::FREQUENCY => "a frequency (e.g. `1 Hz`)",
        Dimension::LENGTH => "a length (e.g. `127 um`)",
        Dimension::FORCE => "a force (e.g. `17.7 mN`)",
        Dimension::TORQUE => "an energy (e.g. `38.9 uJ`)",
        Dimension::TIME => "a time (e.g. `2 s`)",
        _ => "a quantity with a unit",
    }
}

/// The longest prefix of `text` that is a plain number (`2.5` of `2.5mN`).
pub(crate) fn leading_number(text: &str) -> Option<&str> {
    text.char_indices()
        .map(|(i, c)| i + c.len_utf8())
        .rfind(|&end| text[..end].parse::<f64>().is_ok())
        .map(|end| &text[..end])
}

/// `number` with a unit of `dimension`: `1 N`, `10 Hz`, `0.5` (dimensionless).
pub(crate) fn example_quantity(number: &str, dimension: Dimension) -> String {
    match unit_hint(dimension) {
        Some(unit) => format!("{number} {unit}"),
        None => number.to_string(),
    }
}

/// A familiar unit for `dimension` (`N` rather than `kg*m/s^2`: its `Display`), or its SI
/// form; `None` if dimensionless.
pub(crate) fn unit_hint(dimension: Dimension) -> Option<String> {
    (dimension != Dimension::NONE).then(|| dimension.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_name_the_option_and_the_unit_expected() {
        assert_eq!(
            parse_si("--mass", "12 g", Dimension::MASS, false),
            Ok(0.012)
        );
        assert_eq!(parse_si("mass", "0.5", Dimension::MASS, true), Ok(0.5));
        let error = parse_si("--mass", "12", Dimension::MASS, false).unwrap_err();
        assert_eq!(
            error.kind,
            ErrorKind::WrongDimension {
                found: Dimension::NONE,
                expected: Dimension::MASS
            }
        );
        assert_eq!(
            error.to_string(),
            "--mass: `12` has no unit; write it with a unit of kg, e.g. `12 kg`"
        );
        assert_eq!(
            parse_si("--mass", "12 mm", Dimension::MASS, false)
                .unwrap_err()
                .to_string(),
            "--mass: `12 mm` has unit m, but --mass needs kg"
        );
        assert_eq!(
            parse_si("--mass", "1 foo", Dimension::MASS, false)
                .unwrap_err()
                .to_string(),
            "--mass: unknown unit `foo`"
        );
    }

    #[test]
    fn keys_name_the_key_and_show_an_example() {
        assert_eq!(positive("voltage", "225 V", Dimension::VOLTAGE), Ok(225.0));
        assert_eq!(
            quantity("voltage", "225 mm", Dimension::VOLTAGE)
                .unwrap_err()
                .to_string(),
            "key `voltage`: expected a voltage (e.g. `225 V`), got `225 mm`"
        );
        let error = positive("voltage", "-1 V", Dimension::VOLTAGE).unwrap_err();
        assert_eq!(error.kind, ErrorKind::NotPositive);
        assert_eq!(
            error.to_string(),
            "key `voltage`: expected a positive value, got `-1 V`"
        );
        assert_eq!(
            quantity("voltage", "1 foo", Dimension::VOLTAGE)
                .unwrap_err()
                .to_string(),
            "key `voltage`: `1 foo`: unknown unit `foo`"
        );
    }

    #[test]
    fn paper_values_with_and_without_spread() {
        assert_eq!(
            paper_value("d", "2.2 mm", Dimension::LENGTH),
            Ok((2.2e-3, 0.0))
        );
        let (mean, spread) = paper_value("d", "2.2 +- 0.1 mm", Dimension::LENGTH).unwrap();
        assert!((mean - 2.2e-3).abs() < 1e-15 && (spread - 1e-4).abs() < 1e-15);
        assert_eq!(
            paper_value("ratio", "0.5 +- 0.1", Dimension::NONE),
            Ok((0.5, 0.1))
        );
        assert_eq!(
            paper_value("ratio", "0.5 +- 0.1.2", Dimension::NONE)
                .unwrap_err()
                .to_string(),
            "key `ratio`: `0.5 +- 0.1.2`: the spread `0.1.2` is not a number"
        );
    }
}
