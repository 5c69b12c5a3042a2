//! The measured side of a residual, shared by every experiment kind: the observed values
//! with their σ, series and abscissa, and the noise levels experiment files give.
//!
//! Consumes: nothing of the other diagnosis modules but their error type. Produces:
//! [`Observations`], [`noise_value`] and [`key_quantity`].

use mech_codegen::ir::Dimension;

use super::error::KeyError;

/// The measured side of the residual: one flat vector of values, their σ (if known) and a
/// label per value (`foot.x @ line 12`) for reports.
#[derive(Debug, Clone, Default)]
pub struct Observations {
    pub values: Vec<f64>,
    /// One σ per value; `None` when the experiment file gives no noise.
    pub sigma: Option<Vec<f64>>,
    /// The series each value belongs to (an output name, `ln|H|` or `phase`).
    pub series: Vec<String>,
    /// The abscissa of each value (row index for quasi-static data, frequency in Hz).
    pub abscissa: Vec<f64>,
    /// The data row (0-based) each value comes from.
    pub row: Vec<usize>,
}

impl Observations {
    /// Appends one value of `series` at `abscissa`, from data row `row`.
    pub fn push(&mut self, value: f64, series: impl Into<String>, abscissa: f64, row: usize) {
        self.values.push(value);
        self.series.push(series.into());
        self.abscissa.push(abscissa);
        self.row.push(row);
    }

    /// The series in order of first appearance.
    pub fn series_names(&self) -> Vec<&str> {
        let mut names: Vec<&str> = Vec::new();
        for name in &self.series {
            if !names.contains(&name.as_str()) {
                names.push(name);
            }
        }
        names
    }
}

/// A noise level of a quantity of dimension `expected`: a quantity (`5 um`, `3 deg`), or for
/// a dimensionless one a percentage (`5 %`), as an SI number; `key` names the experiment
/// file's key it is read from.
pub fn noise_value(key: &'static str, text: &str, expected: Dimension) -> Result<f64, KeyError> {
    let text = text.trim();
    let value = match text.strip_suffix('%') {
        Some(_) if expected != Dimension::NONE => {
            return Err(KeyError::NoiseUnit {
                key,
                text: text.to_string(),
                found: Dimension::NONE,
                expected,
            })
        }
        Some(percent) => {
            let value: f64 = percent
                .trim()
                .parse()
                .map_err(|_| KeyError::NotPercentage {
                    key,
                    text: text.to_string(),
                })?;
            value / 100.0
        }
        None => {
            let (value, found) =
                mech_codegen::front::units::parse_quantity(text).map_err(|message| {
                    KeyError::Quantity {
                        key,
                        text: text.to_string(),
                        message,
                    }
                })?;
            if found != expected {
                return Err(KeyError::NoiseUnit {
                    key,
                    text: text.to_string(),
                    found,
                    expected,
                });
            }
            value
        }
    };
    if value > 0.0 && value.is_finite() {
        Ok(value)
    } else {
        Err(KeyError::NoiseNotPositive {
            key,
            text: text.to_string(),
        })
    }
}

/// The key `key` of an experiment file as a finite quantity of dimension `expected` (SI);
/// `wrong` makes the error for another dimension or a non-finite value.
pub fn key_quantity(
    key: &'static str,
    text: &str,
    expected: Dimension,
    wrong: fn(&'static str, String) -> KeyError,
) -> Result<f64, KeyError> {
    let (value, dimension) =
        mech_codegen::front::units::parse_quantity(text).map_err(|message| KeyError::Quantity {
            key,
            text: text.to_string(),
            message,
        })?;
    if dimension != expected || !value.is_finite() {
        return Err(wrong(key, text.to_string()));
    }
    Ok(value)
}
