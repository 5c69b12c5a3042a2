//! The statistics of a sweep's table: per output its summary (mean, standard deviation,
//! coefficient of variation, percentiles) and the sensitivity ranking of the parameters by
//! Spearman's rank correlation.
//!
//! Consumes: columns of numbers (non-finite values are the failed samples: left out).
//! Produces: [`Summary`] and [`Correlation`] values, plain data.

/// The summary of one column over its finite values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    /// Finite values summarized.
    pub count: usize,
    pub mean: f64,
    /// Sample standard deviation (n − 1); NaN below two values.
    pub sd: f64,
    pub min: f64,
    pub p5: f64,
    pub p50: f64,
    pub p95: f64,
    pub max: f64,
}

impl Summary {
    /// The coefficient of variation, `sd/|mean|`.
    pub fn cv(&self) -> f64 {
        self.sd / self.mean.abs()
    }
}

/// The summary of the finite values of `column` (every field NaN when there are none).
pub fn summary(column: &[f64]) -> Summary {
    let mut values: Vec<f64> = column.iter().copied().filter(|v| v.is_finite()).collect();
    values.sort_by(f64::total_cmp);
    let n = values.len();
    let mean = values.iter().sum::<f64>() / n as f64;
    let sd = if n > 1 {
        (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
    } else {
        f64::NAN
    };
    Summary {
        count: n,
        mean,
        sd,
        min: percentile(&values, 0.0),
        p5: percentile(&values, 5.0),
        p50: percentile(&values, 50.0),
        p95: percentile(&values, 95.0),
        max: percentile(&values, 100.0),
    }
}

/// The `p`-th percentile of `sorted` values, linear between the closest ranks (NaN if empty).
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    match sorted.len() {
        0 => f64::NAN,
        n => {
            let position = p / 100.0 * (n - 1) as f64;
            let (below, fraction) = (position.floor() as usize, position.fract());
            let above = (below + 1).min(n - 1);
            sorted[below] + fraction * (sorted[above] - sorted[below])
        }
    }
}

/// Ranks 1..n of `values`, ties sharing the mean of their ranks.
pub fn ranks(values: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let mut ranks = vec![0.0; values.len()];
    let mut start = 0;
    while start < order.len() {
        let mut end = start + 1;
        while end < order.len() && values[order[end]] == values[order[start]] {
            end += 1;
        }
        // Positions start..end hold ranks start+1..=end: their mean.
        let rank = (start + end + 1) as f64 / 2.0;
        for &i in &order[start..end] {
            ranks[i] = rank;
        }
        start = end;
    }
    ranks
}

/// Spearman's rank correlation of `x` and `y` over the pairs where both are finite: the
/// Pearson correlation of their ranks (ties averaged). NaN with fewer than three pairs or a
/// constant column.
pub fn spearman(x: &[f64], y: &[f64]) -> f64 {
    let (x, y): (Vec<f64>, Vec<f64>) = x
        .iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, b)| (*a, *b))
        .unzip();
    if x.len() < 3 {
        return f64::NAN;
    }
    pearson(&ranks(&x), &ranks(&y))
}

/// Pearson's correlation of two columns of equal length (NaN if one is constant).
fn pearson(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx).powi(2);
        syy += (b - my).powi(2);
    }
    if sxx == 0.0 || syy == 0.0 {
        return f64::NAN;
    }
    sxy / (sxx * syy).sqrt()
}

/// One entry of a sensitivity ranking.
#[derive(Debug, Clone, PartialEq)]
pub struct Correlation {
    /// Column indices into the table's parameters and outputs.
    pub parameter: usize,
    pub output: usize,
    /// Spearman's ρ (NaN: undefined, e.g. the parameter is not varied).
    pub rho: f64,
}

/// Per output (in order), every parameter by `|ρ|`, largest first (undefined ρ last).
pub fn ranking(parameters: &[Vec<f64>], outputs: &[Vec<f64>]) -> Vec<Vec<Correlation>> {
    outputs
        .iter()
        .enumerate()
        .map(|(o, y)| {
            let mut row: Vec<Correlation> = parameters
                .iter()
                .enumerate()
                .map(|(p, x)| Correlation {
                    parameter: p,
                    output: o,
                    rho: spearman(x, y),
                })
                .collect();
            let key = |c: &Correlation| if c.rho.is_nan() { -1.0 } else { c.rho.abs() };
            row.sort_by(|a, b| key(b).total_cmp(&key(a)));
            row
        })
        .collect()
}
