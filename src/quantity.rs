//! Quantities with units as users write them (`225 V`, `2.2 +- 0.1 mm`), checked against the
//! dimension expected and converted to SI: the one parser of the analyses' files and
//! options. The units and dimensions themselves are the language's
//! ([`mech_codegen::front::units`], [`Dimension`]).
//!
//! Consumes: text and the expected [`Dimension`]. Produces: SI values, or errors that name
//! the option or key and show the expected form.

use mech_codegen::ir::Dimension;

/// Parses `text` (`2 mm`, `25 um`, `0.2 g`) as a quantity of dimension `expected` and returns
/// its SI value. A bare number is accepted only for dimensionless quantities unless
/// `bare_is_si`.
pub fn parse_si(
    what: &str,
    text: &str,
    expected: Dimension,
    bare_is_si: bool,
) -> Result<f64, String> {
    let (value, dimension) =
        mech_codegen::front::units::parse_quantity(text).map_err(|e| format!("{what}: {e}"))?;
    if dimension == expected || (bare_is_si && dimension == Dimension::NONE) {
        if !value.is_finite() {
            return Err(format!("{what}: `{text}` is not finite"));
        }
        return Ok(value);
    }
    if dimension == Dimension::NONE {
        return Err(format!(
            "{what}: `{text}` has no unit; write it with a unit of {expected} (e.g. `2 mm`, `25 um`)"
        ));
    }
    Err(format!(
        "{what}: `{text}` has unit {dimension}, but {what} needs {expected}"
    ))
}

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

/// Parses `text` (e.g. `"225 V"`) as a quantity of dimension `expected`, in SI. `key` names
/// the TOML key in errors.
pub fn quantity(key: &str, text: &str, expected: Dimension) -> Result<f64, String> {
    let (value, dimension) = mech_codegen::front::units::parse_quantity(text)
        .map_err(|e| format!("key `{key}`: `{text}`: {e}"))?;
    if dimension != expected || !value.is_finite() {
        return Err(format!(
            "key `{key}`: expected {}, got `{text}`",
            dimension_name(expected)
        ));
    }
    Ok(value)
}

/// As [`quantity`], and positive.
pub fn positive(key: &str, text: &str, expected: Dimension) -> Result<f64, String> {
    let value = quantity(key, text, expected)?;
    if value <= 0.0 {
        return Err(format!(
            "key `{key}`: expected a positive value, got `{text}`"
        ));
    }
    Ok(value)
}

/// A paper value with its uncertainty: `"2.2 mm"` or `"2.2 +- 0.1 mm"`.
pub fn paper_value(key: &str, text: &str, expected: Dimension) -> Result<(f64, f64), String> {
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
                spread
                    .trim()
                    .parse::<f64>()
                    .map_err(|e| format!("key `{key}`: {e}"))?
            } else {
                quantity(key, &format!("{spread} {unit}"), expected)?
            };
            Ok((mean, spread))
        }
        None => Ok((quantity(key, text, expected)?, 0.0)),
    }
}
