//! The values a study gives its parameters: Monte-Carlo draws from a distribution, or the
//! points of a grid (the cartesian product of each parameter's values).
//!
//! Consumes: a [`Source`] per parameter (SI values or factors, already checked) and a sample
//! index. Produces: that sample's value of every parameter. A Monte-Carlo sample `i` draws
//! from its own ChaCha8 stream (`seed`, stream `i`), so its values depend only on the seed
//! and its index: the same on one thread or many, locally or on a cluster's workers.

use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal, Uniform};

/// Draws of a truncated normal rejected in a row before the sample is given up: bounds that
/// keep so little of the normal (under about 0.01 %) make a study of their own.
pub const TRUNCATED_TRIES: usize = 100_000;

/// A distribution of one parameter's values (SI, or factors of the nominal value).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Dist {
    Normal {
        mean: f64,
        sd: f64,
    },
    Uniform {
        low: f64,
        high: f64,
    },
    /// The normal, redrawn until inside `[low, high]`.
    TruncatedNormal {
        mean: f64,
        sd: f64,
        low: f64,
        high: f64,
    },
}

/// Where one parameter's values come from.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    Draw(Dist),
    Grid(Vec<f64>),
}

/// Why a sample's values could not be drawn.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DrawError {
    #[error(
        "parameter `{parameter}`: {TRUNCATED_TRIES} draws of the normal in a row fell outside \
         [{low}, {high}]; the bounds keep too little of the distribution"
    )]
    Truncation {
        parameter: String,
        low: f64,
        high: f64,
    },
}

impl Dist {
    /// One value from `rng`; `None` if a truncated normal rejected [`TRUNCATED_TRIES`] draws.
    fn draw(&self, rng: &mut ChaCha8Rng) -> Option<f64> {
        match *self {
            Dist::Normal { mean, sd } => Some(normal(mean, sd).sample(rng)),
            Dist::Uniform { low, high } => {
                // Checked low < high, both finite, when the study was read.
                let uniform = Uniform::new(low, high).ok()?;
                Some(uniform.sample(rng))
            }
            Dist::TruncatedNormal {
                mean,
                sd,
                low,
                high,
            } => {
                let normal = normal(mean, sd);
                (0..TRUNCATED_TRIES)
                    .map(|_| normal.sample(rng))
                    .find(|x| (low..=high).contains(x))
            }
        }
    }
}

/// The normal of `mean` and `sd` (checked finite, `sd ≥ 0`, when the study was read).
fn normal(mean: f64, sd: f64) -> Normal<f64> {
    Normal::new(mean, sd).unwrap_or_else(|_| Normal::new(mean, 0.0).expect("sd 0 is valid"))
}

/// The number of samples of a grid: the product of its parameters' value counts (`None`
/// on overflow).
pub fn grid_size(sources: &[Source]) -> Option<usize> {
    sources.iter().try_fold(1usize, |n, source| match source {
        Source::Grid(values) => n.checked_mul(values.len()),
        Source::Draw(_) => Some(n),
    })
}

/// The values of sample `index` for parameters `names` with their `sources`: each drawn
/// in order from the sample's stream of `seed`, or the grid point `index` (the last
/// parameter varying fastest).
pub fn values(
    names: &[String],
    sources: &[Source],
    seed: u64,
    index: usize,
) -> Result<Vec<f64>, DrawError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(index as u64);
    let mut rest = index;
    let mut values = vec![0.0; sources.len()];
    for (k, source) in sources.iter().enumerate().rev() {
        if let Source::Grid(points) = source {
            values[k] = points[rest % points.len()];
            rest /= points.len();
        }
    }
    for (k, source) in sources.iter().enumerate() {
        if let Source::Draw(dist) = source {
            values[k] = dist.draw(&mut rng).ok_or_else(|| {
                let (low, high) = match *dist {
                    Dist::TruncatedNormal { low, high, .. } => (low, high),
                    _ => (f64::NAN, f64::NAN),
                };
                DrawError::Truncation {
                    parameter: names[k].clone(),
                    low,
                    high,
                }
            })?;
        }
    }
    Ok(values)
}
