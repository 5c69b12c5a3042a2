//! Numbers of the symbolic engine: exact rationals where the source is exact, floats otherwise.
//!
//! Consumes: decimal literals (`0.5`, `1e-3`) and unit scale factors (`mm` = 1/1000).
//! Produces: [`Number`], which hashes and compares by value (floats by bit pattern), so the
//! expression pool can hash-cons constants.

use std::fmt;

/// A constant: an exact rational `num/den` (den > 0, lowest terms) or a binary float.
///
/// Arithmetic stays exact while both operands are rational and nothing overflows `i64`;
/// otherwise it falls back to `f64`. A float whose value is an integer of small magnitude is
/// *not* turned back into a rational: exactness is a property of the source, not the value.
#[derive(Clone, Copy, Debug)]
pub enum Number {
    Rational(i64, i64),
    Float(f64),
}

impl PartialEq for Number {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (Number::Rational(a, b), Number::Rational(c, d)) => a == c && b == d,
            (Number::Float(x), Number::Float(y)) => x.to_bits() == y.to_bits(),
            _ => false,
        }
    }
}
impl Eq for Number {}

impl std::hash::Hash for Number {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        match *self {
            Number::Rational(a, b) => (0u8, a, b).hash(state),
            Number::Float(x) => (1u8, x.to_bits()).hash(state),
        }
    }
}

fn gcd(mut a: i128, mut b: i128) -> i128 {
    a = a.abs();
    b = b.abs();
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

// Named methods rather than only operator traits: they read like the arithmetic they do and
// serve as function pointers (`combine_like(items, Number::add)`); the traits below delegate.
#[allow(clippy::should_implement_trait)]
impl Number {
    pub const ZERO: Number = Number::Rational(0, 1);
    pub const ONE: Number = Number::Rational(1, 1);
    pub const MINUS_ONE: Number = Number::Rational(-1, 1);

    pub fn int(n: i64) -> Number {
        Number::Rational(n, 1)
    }

    /// `num/den` reduced to lowest terms; a float if it does not fit `i64` or `den == 0`.
    pub fn rational(num: i128, den: i128) -> Number {
        if den == 0 {
            return Number::Float(num as f64 / den as f64);
        }
        let g = gcd(num, den).max(1);
        let (mut n, mut d) = (num / g, den / g);
        if d < 0 {
            n = -n;
            d = -d;
        }
        match (i64::try_from(n), i64::try_from(d)) {
            (Ok(n), Ok(d)) => Number::Rational(n, d),
            _ => Number::Float(n as f64 / d as f64),
        }
    }

    /// Parses a decimal literal (`12`, `0.5`, `2.5e-3`) exactly when it fits.
    pub fn parse_decimal(text: &str) -> Option<Number> {
        let value: f64 = text.parse().ok()?;
        let (mantissa, exponent) = match text.find(['e', 'E']) {
            Some(i) => (&text[..i], text[i + 1..].parse::<i32>().ok()?),
            None => (text, 0),
        };
        let (int_part, frac_part) = mantissa.split_once('.').unwrap_or((mantissa, ""));
        let digits = format!("{int_part}{frac_part}");
        let scale = exponent - frac_part.len() as i32;
        let exact = (|| {
            let n: i128 = digits.parse().ok()?;
            let pow = 10i128.checked_pow(scale.unsigned_abs())?;
            Some(if scale >= 0 {
                Number::rational(n.checked_mul(pow)?, 1)
            } else {
                Number::rational(n, pow)
            })
        })();
        match exact {
            Some(n @ Number::Rational(..)) => Some(n),
            _ => Some(Number::Float(value)),
        }
    }

    pub fn to_f64(self) -> f64 {
        match self {
            Number::Rational(n, d) => n as f64 / d as f64,
            Number::Float(x) => x,
        }
    }

    pub fn is_zero(self) -> bool {
        self.to_f64() == 0.0
    }
    pub fn is_one(self) -> bool {
        self.to_f64() == 1.0
    }
    pub fn is_negative(self) -> bool {
        self.to_f64() < 0.0
    }
    pub fn is_exact(self) -> bool {
        matches!(self, Number::Rational(..))
    }

    /// The integer value, if this is an exact integer.
    pub fn as_integer(self) -> Option<i64> {
        match self {
            Number::Rational(n, 1) => Some(n),
            _ => None,
        }
    }

    pub fn add(self, other: Number) -> Number {
        match (self, other) {
            (Number::Rational(a, b), Number::Rational(c, d)) => Number::rational(
                a as i128 * d as i128 + c as i128 * b as i128,
                b as i128 * d as i128,
            ),
            _ => Number::Float(self.to_f64() + other.to_f64()),
        }
    }
    pub fn mul(self, other: Number) -> Number {
        match (self, other) {
            (Number::Rational(a, b), Number::Rational(c, d)) => {
                Number::rational(a as i128 * c as i128, b as i128 * d as i128)
            }
            _ => Number::Float(self.to_f64() * other.to_f64()),
        }
    }
    pub fn neg(self) -> Number {
        self.mul(Number::MINUS_ONE)
    }
    pub fn sub(self, other: Number) -> Number {
        self.add(other.neg())
    }
    /// `1/self`; a float infinity for zero (callers check before dividing by a constant zero).
    pub fn recip(self) -> Number {
        match self {
            Number::Rational(n, d) if n != 0 => Number::rational(d as i128, n as i128),
            _ => Number::Float(1.0 / self.to_f64()),
        }
    }
    pub fn div(self, other: Number) -> Number {
        self.mul(other.recip())
    }
    /// `self^exponent` for an integer exponent, exact for rationals while it fits.
    pub fn powi(self, exponent: i64) -> Number {
        match self {
            Number::Rational(n, d) if exponent.unsigned_abs() <= 64 => {
                let e = exponent.unsigned_abs() as u32;
                let value = (|| {
                    Some(Number::rational(
                        (n as i128).checked_pow(e)?,
                        (d as i128).checked_pow(e)?,
                    ))
                })();
                let value = value.unwrap_or(Number::Float(self.to_f64().powi(e as i32)));
                if exponent < 0 {
                    value.recip()
                } else {
                    value
                }
            }
            _ => Number::Float(self.to_f64().powf(exponent as f64)),
        }
    }
}

// The operators are the exact arithmetic of the methods of the same name.
macro_rules! number_operator {
    ($($trait:ident $method:ident),*) => {$(
        impl std::ops::$trait for Number {
            type Output = Number;
            fn $method(self, other: Number) -> Number {
                Number::$method(self, other)
            }
        }
    )*};
}
number_operator!(Add add, Sub sub, Mul mul, Div div);

impl std::ops::Neg for Number {
    type Output = Number;
    fn neg(self) -> Number {
        Number::neg(self)
    }
}

impl fmt::Display for Number {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Number::Rational(n, 1) => write!(f, "{n}"),
            Number::Rational(n, d) => write!(f, "{n}/{d}"),
            // `{:?}` prints the shortest round-trip form and always keeps a `.` or exponent.
            Number::Float(x) => write!(f, "{x:?}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Number;

    #[test]
    fn decimals_are_exact() {
        assert_eq!(Number::parse_decimal("0.5"), Some(Number::Rational(1, 2)));
        assert_eq!(
            Number::parse_decimal("9.81"),
            Some(Number::Rational(981, 100))
        );
        assert_eq!(
            Number::parse_decimal("2.5e-3"),
            Some(Number::Rational(1, 400))
        );
        assert_eq!(
            Number::parse_decimal("12e2"),
            Some(Number::Rational(1200, 1))
        );
        assert_eq!(Number::parse_decimal("1e300"), Some(Number::Float(1e300)));
    }

    #[test]
    fn arithmetic_stays_exact() {
        let third = Number::rational(1, 3);
        assert_eq!(third.add(third).add(third), Number::ONE);
        assert_eq!(Number::rational(2, 3).powi(-2), Number::rational(9, 4));
        assert_eq!(
            Number::Float(0.5).add(Number::rational(1, 2)),
            Number::Float(1.0)
        );
        assert_eq!(Number::rational(-4, -6), Number::Rational(2, 3));
    }
}
