//! Units of measure: the unit table, SI prefixes, and checked dimension arithmetic.
//!
//! Consumes: unit names (`mN`, `kg`, `deg`) and unit expressions from the AST.
//! Produces: a scale to SI (an exact [`Number`] where possible) and an [`crate::ir::Dimension`].
//! The internal unit system is SI: kg, m, s, A, and rad (dimensionless).

use crate::ir::Dimension;
use crate::sym::Number;

use super::ast;

/// A unit: multiply a value in this unit by `scale` to get SI.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unit {
    pub scale: Number,
    pub dimension: Dimension,
}

const fn dim(mass: i8, length: i8, time: i8, current: i8) -> Dimension {
    Dimension {
        mass,
        length,
        time,
        current,
    }
}

/// Base units (before prefixes): name, scale numerator/denominator, dimension.
const BASE_UNITS: &[(&str, i64, i64, Dimension)] = &[
    ("m", 1, 1, dim(0, 1, 0, 0)),
    ("g", 1, 1000, dim(1, 0, 0, 0)),
    ("s", 1, 1, dim(0, 0, 1, 0)),
    ("Hz", 1, 1, dim(0, 0, -1, 0)),
    ("N", 1, 1, dim(1, 1, -2, 0)),
    ("J", 1, 1, dim(1, 2, -2, 0)),
    ("W", 1, 1, dim(1, 2, -3, 0)),
    ("Pa", 1, 1, dim(1, -1, -2, 0)),
    ("V", 1, 1, dim(1, 2, -3, -1)),
    ("A", 1, 1, dim(0, 0, 0, 1)),
    ("C", 1, 1, dim(0, 0, 1, 1)),
    ("F", 1, 1, dim(-1, -2, 4, 2)),
    ("rad", 1, 1, dim(0, 0, 0, 0)),
];

/// SI prefixes: symbol, power of ten.
const PREFIXES: &[(&str, i32)] = &[
    ("G", 9),
    ("M", 6),
    ("k", 3),
    ("c", -2),
    ("m", -3),
    ("u", -6),
    ("µ", -6),
    ("μ", -6),
    ("n", -9),
    ("p", -12),
];

/// Degrees: π/180 rad (a float; every other scale is exact).
const DEGREE: &str = "deg";

/// Looks up a unit name such as `mm`, `kN`, `deg`, `µm`.
pub fn lookup(name: &str) -> Option<Unit> {
    if name == DEGREE {
        return Some(Unit {
            scale: Number::Float(std::f64::consts::PI / 180.0),
            dimension: Dimension::NONE,
        });
    }
    if let Some(unit) = base_unit(name) {
        return Some(unit);
    }
    PREFIXES.iter().find_map(|&(prefix, power)| {
        let base = base_unit(name.strip_prefix(prefix)?)?;
        Some(Unit {
            scale: base.scale.mul(power_of_ten(power)),
            dimension: base.dimension,
        })
    })
}

fn base_unit(name: &str) -> Option<Unit> {
    BASE_UNITS
        .iter()
        .find(|(base, ..)| *base == name)
        .map(|&(_, num, den, dimension)| Unit {
            scale: Number::rational(num as i128, den as i128),
            dimension,
        })
}

fn power_of_ten(power: i32) -> Number {
    let magnitude = 10i128.pow(power.unsigned_abs());
    if power >= 0 {
        Number::rational(magnitude, 1)
    } else {
        Number::rational(1, magnitude)
    }
}

/// Every unit name the table accepts (for "did you mean" suggestions), in a fixed order.
pub fn all_unit_names() -> Vec<String> {
    let mut names = vec![DEGREE.to_string()];
    for (base, ..) in BASE_UNITS {
        names.push(base.to_string());
        for (prefix, _) in PREFIXES {
            names.push(format!("{prefix}{base}"));
        }
    }
    names
}

/// Largest magnitude of a dimension exponent (keeps `i8` arithmetic far from overflow).
pub const MAX_EXPONENT: i32 = 60;

/// `a * b` for dimensions, or `None` if an exponent would leave ±[`MAX_EXPONENT`].
pub fn dim_mul(a: Dimension, b: Dimension) -> Option<Dimension> {
    dim_map2(a, b, |x, y| x + y)
}

/// `a / b` for dimensions, checked like [`dim_mul`].
pub fn dim_div(a: Dimension, b: Dimension) -> Option<Dimension> {
    dim_map2(a, b, |x, y| x - y)
}

/// `a^(num/den)`: `None` if an exponent is not an integer or is out of range.
pub fn dim_pow(a: Dimension, num: i64, den: i64) -> Option<Dimension> {
    let scale = |x: i8| -> Option<i8> {
        let scaled = (x as i128).checked_mul(num as i128)?;
        if den == 0 || scaled % den as i128 != 0 {
            return None;
        }
        in_range(scaled / den as i128)
    };
    Some(Dimension {
        mass: scale(a.mass)?,
        length: scale(a.length)?,
        time: scale(a.time)?,
        current: scale(a.current)?,
    })
}

fn dim_map2(a: Dimension, b: Dimension, f: impl Fn(i128, i128) -> i128) -> Option<Dimension> {
    let op = |x: i8, y: i8| in_range(f(x as i128, y as i128));
    Some(Dimension {
        mass: op(a.mass, b.mass)?,
        length: op(a.length, b.length)?,
        time: op(a.time, b.time)?,
        current: op(a.current, b.current)?,
    })
}

fn in_range(x: i128) -> Option<i8> {
    if x.abs() <= MAX_EXPONENT as i128 {
        i8::try_from(x).ok()
    } else {
        None
    }
}

/// How a dimension is named in messages: its SI form, or "dimensionless".
pub fn describe(dimension: Dimension) -> String {
    if dimension == Dimension::NONE {
        "dimensionless".to_string()
    } else {
        dimension.to_string()
    }
}

/// Why a unit expression could not be evaluated.
#[derive(Clone, Debug, PartialEq)]
pub enum UnitError {
    /// The factor at this index names no unit.
    Unknown(usize),
    /// The exponent of the factor at this index is not a small integer.
    BadExponent(usize),
    /// The combined dimension is out of range.
    Overflow,
}

/// Evaluates a unit expression such as `N*m/rad` to its SI scale and dimension.
pub fn evaluate(unit: &ast::Unit) -> Result<Unit, UnitError> {
    let mut total = Unit {
        scale: Number::ONE,
        dimension: Dimension::NONE,
    };
    for (index, factor) in unit.factors.iter().enumerate() {
        let base = lookup(&factor.name.name).ok_or(UnitError::Unknown(index))?;
        let exponent = match &factor.exponent {
            None => 1,
            Some(text) => text
                .parse::<i64>()
                .ok()
                .filter(|e| e.abs() <= MAX_EXPONENT as i64)
                .ok_or(UnitError::BadExponent(index))?,
        };
        let exponent = if factor.divide { -exponent } else { exponent };
        let dimension = dim_pow(base.dimension, exponent, 1).ok_or(UnitError::Overflow)?;
        total.scale = total.scale.mul(base.scale.powi(exponent));
        total.dimension = dim_mul(total.dimension, dimension).ok_or(UnitError::Overflow)?;
    }
    Ok(total)
}

/// Parses a decimal literal, exactly where possible; `None` if it is out of range.
pub fn parse_literal(text: &str) -> Option<Number> {
    let value: f64 = text.parse().ok()?;
    if !value.is_finite() {
        return None;
    }
    let exponent_digits = text
        .find(['e', 'E'])
        .map_or("", |i| text.get(i + 1..).unwrap_or(""));
    let exponent_digits = exponent_digits
        .trim_start_matches(['+', '-'])
        .trim_start_matches('0');
    // Exponents beyond a few hundred overflow `Number::parse_decimal`'s arithmetic; such a
    // literal is a float (0 or out of range) anyway.
    if exponent_digits.len() > 3 || text.len() > 400 {
        return Some(Number::Float(value));
    }
    Number::parse_decimal(text)
}

/// Why a quantity such as `10 mN` could not be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum QuantityError {
    /// Not a number with an optional unit (the grammar's message).
    Syntax(String),
    NumberOutOfRange {
        literal: String,
    },
    UnknownUnit {
        name: String,
    },
    /// A unit's exponent that is not an integer in range.
    BadExponent {
        name: String,
    },
    DimensionOverflow,
    /// The value in SI is not finite.
    ValueOutOfRange {
        text: String,
    },
}

impl std::fmt::Display for QuantityError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            QuantityError::Syntax(message) => f.write_str(message),
            QuantityError::NumberOutOfRange { literal } => {
                write!(f, "number `{literal}` is out of range")
            }
            QuantityError::UnknownUnit { name } => write!(f, "unknown unit `{name}`"),
            QuantityError::BadExponent { name } => write!(
                f,
                "the exponent of `{name}` must be an integer between -{MAX_EXPONENT} and {MAX_EXPONENT}"
            ),
            QuantityError::DimensionOverflow => f.write_str("the unit's dimension is out of range"),
            QuantityError::ValueOutOfRange { text } => write!(f, "`{text}` is out of range"),
        }
    }
}

impl std::error::Error for QuantityError {}

/// Parses a quantity such as `10 mN`, `30 deg`, `2.5`, `-1e-3 kg*m^2` into its SI value and
/// dimension (used by the command line for `--set name=value`).
pub fn parse_quantity(text: &str) -> Result<(f64, Dimension), QuantityError> {
    let (negative, literal, unit) =
        super::parse::parse_quantity_text(text.trim()).map_err(QuantityError::Syntax)?;
    let number = parse_literal(&literal).ok_or_else(|| QuantityError::NumberOutOfRange {
        literal: literal.clone(),
    })?;
    let unit = match &unit {
        None => Unit {
            scale: Number::ONE,
            dimension: Dimension::NONE,
        },
        Some(unit) => evaluate(unit).map_err(|error| quantity_unit_error(unit, &error))?,
    };
    let value = number.mul(unit.scale).to_f64();
    if !value.is_finite() {
        return Err(QuantityError::ValueOutOfRange {
            text: text.trim().to_string(),
        });
    }
    Ok((if negative { -value } else { value }, unit.dimension))
}

fn quantity_unit_error(unit: &ast::Unit, error: &UnitError) -> QuantityError {
    let factor_name = |i: usize| {
        unit.factors
            .get(i)
            .map_or("", |f| f.name.name.as_str())
            .to_string()
    };
    match error {
        UnitError::Unknown(i) => QuantityError::UnknownUnit {
            name: factor_name(*i),
        },
        UnitError::BadExponent(i) => QuantityError::BadExponent {
            name: factor_name(*i),
        },
        UnitError::Overflow => QuantityError::DimensionOverflow,
    }
}
