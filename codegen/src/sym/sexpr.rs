//! S-expression text form of pool expressions, for one-line tests and debug dumps.
//!
//! Consumes: an id (printing) or text such as `(+ (* 2 x) (sin q0))` (parsing).
//! Produces: text, or an id built through the canonicalizing constructors, so
//! `parse("(+ x x)")` prints as `(* 2 x)`.
//!
//! Grammar: numbers (`2`, `-1/2`, `0.25` — decimals parse exactly), names (`q0`, `u1`, `t`,
//! anything else is a parameter), `(+ a ...)`, `(- a)`, `(- a b)`, `(* a ...)`, `(/ a b)`,
//! `(^ a n)`, `(sin a)` `(cos a)` `(tan a)` `(exp a)` `(ln a)` `(abs a)` `(sqrt a)`,
//! `(atan2 y x)`.

use std::fmt::Write;

use super::expr::{ExprId, ExprPool, Func, Node, Symbol};
use super::Number;

/// Why s-expression text could not be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SexprError {
    UnexpectedEnd,
    UnexpectedClose,
    MissingClose,
    MissingOperator,
    /// A token after the complete expression.
    Trailing(String),
    UnknownOperator(String),
    Arity {
        operator: String,
        expected: &'static str,
    },
    ExponentNotANumber,
}

impl std::fmt::Display for SexprError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SexprError::UnexpectedEnd => f.write_str("unexpected end of input"),
            SexprError::UnexpectedClose => f.write_str("unexpected `)`"),
            SexprError::MissingClose => f.write_str("missing `)`"),
            SexprError::MissingOperator => f.write_str("missing operator after `(`"),
            SexprError::Trailing(token) => write!(f, "unexpected `{token}` after the expression"),
            SexprError::UnknownOperator(name) => write!(f, "unknown operator `{name}`"),
            SexprError::Arity { operator, expected } => {
                write!(f, "`{operator}` takes {expected}")
            }
            SexprError::ExponentNotANumber => f.write_str("the exponent of `^` must be a number"),
        }
    }
}

impl std::error::Error for SexprError {}

impl ExprPool {
    /// The s-expression of `id`.
    pub fn sexpr(&self, id: ExprId) -> String {
        let mut out = String::new();
        self.write_sexpr(id, &mut out);
        out
    }

    fn write_sexpr(&self, id: ExprId, out: &mut String) {
        match self.node(id) {
            Node::Number(n) => {
                let _ = write!(out, "{n}");
            }
            Node::Symbol(s) => out.push_str(&self.symbol_name(*s)),
            Node::Add { constant, terms } => {
                out.push_str("(+");
                if !constant.is_zero() {
                    let _ = write!(out, " {constant}");
                }
                for &(term, c) in terms.iter() {
                    out.push(' ');
                    if c.is_one() {
                        self.write_sexpr(term, out);
                    } else {
                        let _ = write!(out, "(* {c} ");
                        self.write_factors(term, out);
                        out.push(')');
                    }
                }
                out.push(')');
            }
            Node::Mul {
                coefficient,
                factors,
            } if coefficient.is_one() && factors.len() == 1 => {
                self.write_factors(id, out);
            }
            Node::Mul { coefficient, .. } => {
                out.push_str("(*");
                if !coefficient.is_one() {
                    let _ = write!(out, " {coefficient}");
                }
                out.push(' ');
                self.write_factors(id, out);
                out.push(')');
            }
            Node::Call(func, x) => {
                let _ = write!(out, "({} ", func.name());
                self.write_sexpr(*x, out);
                out.push(')');
            }
            Node::Atan2(y, x) => {
                out.push_str("(atan2 ");
                self.write_sexpr(*y, out);
                out.push(' ');
                self.write_sexpr(*x, out);
                out.push(')');
            }
        }
    }

    /// Space-separated factors of a coefficient-1 product (or the expression itself).
    fn write_factors(&self, id: ExprId, out: &mut String) {
        let Node::Mul { factors, .. } = self.node(id) else {
            return self.write_sexpr(id, out);
        };
        for (i, &(base, e)) in factors.iter().enumerate() {
            if i > 0 {
                out.push(' ');
            }
            if e.is_one() {
                self.write_sexpr(base, out);
            } else {
                out.push_str("(^ ");
                self.write_sexpr(base, out);
                let _ = write!(out, " {e})");
            }
        }
    }

    /// Builds an expression from s-expression text.
    pub fn parse_sexpr(&mut self, text: &str) -> Result<ExprId, SexprError> {
        let tokens = tokenize(text);
        let mut position = 0;
        let id = self.parse_tokens(&tokens, &mut position)?;
        if position != tokens.len() {
            return Err(SexprError::Trailing(tokens[position].clone()));
        }
        Ok(id)
    }

    fn parse_tokens(
        &mut self,
        tokens: &[String],
        position: &mut usize,
    ) -> Result<ExprId, SexprError> {
        let token = tokens
            .get(*position)
            .ok_or(SexprError::UnexpectedEnd)?
            .clone();
        *position += 1;
        if token == ")" {
            return Err(SexprError::UnexpectedClose);
        }
        if token != "(" {
            return self.parse_atom(&token);
        }
        let head = tokens
            .get(*position)
            .ok_or(SexprError::MissingOperator)?
            .clone();
        *position += 1;
        let mut args = Vec::new();
        while tokens.get(*position).map(String::as_str) != Some(")") {
            if *position >= tokens.len() {
                return Err(SexprError::MissingClose);
            }
            args.push(self.parse_tokens(tokens, position)?);
        }
        *position += 1;
        self.apply_operator(&head, &args)
    }

    fn parse_atom(&mut self, token: &str) -> Result<ExprId, SexprError> {
        if let Some(number) = parse_number(token) {
            return Ok(self.number(number));
        }
        let symbol = self
            .symbol_by_name(token)
            .unwrap_or_else(|| default_symbol(token, self));
        self.set_name(symbol, token);
        Ok(self.symbol(symbol))
    }

    fn apply_operator(&mut self, head: &str, args: &[ExprId]) -> Result<ExprId, SexprError> {
        let arity = |expected| SexprError::Arity {
            operator: head.to_string(),
            expected,
        };
        Ok(match (head, args) {
            ("+", _) => self.add_all(args),
            ("*", _) => self.mul_all(args),
            ("-", [x]) => self.neg(*x),
            ("-", [a, b]) => self.sub(*a, *b),
            ("-", _) => return Err(arity("one or two arguments")),
            ("/", [a, b]) => self.div(*a, *b),
            ("^", [a, n]) => {
                let e = self.as_number(*n).ok_or(SexprError::ExponentNotANumber)?;
                self.pow(*a, e)
            }
            ("atan2", [y, x]) => self.atan2(*y, *x),
            ("/" | "^" | "atan2", _) => return Err(arity("two arguments")),
            ("sqrt", [x]) => self.sqrt(*x),
            ("sqrt", _) => return Err(arity("one argument")),
            (name, _) => {
                let func = Func::ALL
                    .into_iter()
                    .find(|f| f.name() == name)
                    .ok_or_else(|| SexprError::UnknownOperator(name.to_string()))?;
                let [x] = args else {
                    return Err(arity("one argument"));
                };
                self.call(func, *x)
            }
        })
    }
}

fn tokenize(text: &str) -> Vec<String> {
    text.replace('(', " ( ")
        .replace(')', " ) ")
        .split_whitespace()
        .map(str::to_string)
        .collect()
}

fn parse_number(token: &str) -> Option<Number> {
    let first = token.chars().next()?;
    if !(first.is_ascii_digit() || (first == '-' && token.len() > 1)) {
        return None;
    }
    match token.split_once('/') {
        Some((n, d)) => Some(Number::rational(n.parse().ok()?, d.parse().ok()?)),
        None => Number::parse_decimal(token),
    }
}

/// `q3` → coordinate 3, `u3` → speed 3, `t` → time, anything else a new parameter.
fn default_symbol(name: &str, pool: &ExprPool) -> Symbol {
    let indexed = |prefix: &str| {
        name.strip_prefix(prefix)
            .and_then(|rest| rest.parse::<u32>().ok())
    };
    if let Some(i) = indexed("q") {
        Symbol::Coordinate(i)
    } else if let Some(i) = indexed("u") {
        Symbol::Speed(i)
    } else if name == "t" {
        Symbol::Time
    } else {
        let used = (0..)
            .find(|&i| pool.symbol_name(Symbol::Param(i)) == format!("p{i}"))
            .unwrap_or(0);
        Symbol::Param(used)
    }
}
