//! What a designer reads off the curves, for the data and for each model: the features of a
//! response (seed Table IV, Fig. 8), and the residual RMS per measured series.
//!
//! Consumes: an [`Experiment`], its [`Observations`] and one vector of values in their layout
//! (the measured values themselves, or a model's prediction of them). Produces: [`Feature`]s —
//! per frequency-response channel the low-frequency gain and phase, the largest gain, the
//! resonance frequency and its quality factor (where the sampling resolves it); for
//! force/deflection the blocked force and the free deflection (each from the points nearest
//! its end of the curve: `force_ends`); for a force/deflection table its values; per
//! quasi-static
//! output its peak-to-peak range; for a ring-down its natural frequency and quality factor
//! (`mech flexure fit`'s trace analysis). Also [`series_rms`]: the residual RMS per series.
//!
//! The same estimator reads the data and every prediction at the measured abscissae, so a
//! feature compares like with like: a model's peak between two measured frequencies is seen
//! as the measurement would see it.

use super::experiment::{Experiment, Kind, Observations};

/// One feature of a response: `value` in SI units (`None` where the curve does not show it,
/// e.g. a peak at the edge of the band); `unit` and `scale` for display (`value·scale unit`).
#[derive(Debug, Clone, PartialEq)]
pub struct Feature {
    pub name: String,
    pub value: Option<f64>,
    pub unit: &'static str,
    pub scale: f64,
}

impl Feature {
    fn new(name: impl Into<String>, value: Option<f64>, unit: &'static str, scale: f64) -> Self {
        Feature {
            name: name.into(),
            value: value.filter(|v| v.is_finite()),
            unit,
            scale,
        }
    }

    /// `name [unit]`, for table headers.
    pub fn label(&self) -> String {
        if self.unit.is_empty() {
            self.name.clone()
        } else {
            format!("{} [{}]", self.name, self.unit)
        }
    }

    /// The value in display units, or `-`.
    pub fn display(&self) -> String {
        self.value
            .map_or("-".into(), |v| format!("{:.4}", v * self.scale))
    }
}

/// The features of `values` (laid out as `observations`) for `experiment`'s kind.
pub fn features(
    experiment: &Experiment,
    observations: &Observations,
    values: &[f64],
) -> Vec<Feature> {
    if values.len() != observations.values.len() {
        return Vec::new();
    }
    let curves = Curves {
        observations,
        values,
    };
    match experiment.kind {
        Kind::FrequencyResponse(_) => observations
            .series_names()
            .into_iter()
            .filter_map(|name| name.strip_prefix("ln|H|"))
            .flat_map(|suffix| channel_features(&curves, suffix))
            .collect(),
        Kind::ForceDeflection(_) => force_deflection_features(&curves),
        // The values are the features: one per test and quantity.
        Kind::ForceDeflectionTable(_) => (0..values.len())
            .map(|k| {
                let name = &observations.series[k];
                let (unit, scale) = if name.starts_with("free_deflection") {
                    ("mm", 1e3)
                } else {
                    ("mN", 1e3)
                };
                Feature::new(name.replace('_', " "), Some(values[k]), unit, scale)
            })
            .collect(),
        Kind::QuasiStatic(_) => observations
            .series_names()
            .into_iter()
            .map(|name| peak_to_peak(&curves, name))
            .collect(),
        Kind::Pendulum(_) => ring_down_features(&curves),
    }
}

/// One vector of values laid out as the observations.
struct Curves<'a> {
    observations: &'a Observations,
    values: &'a [f64],
}

impl Curves<'_> {
    /// The abscissae and values of the series `name`.
    fn series(&self, name: &str) -> (Vec<f64>, Vec<f64>) {
        self.observations
            .series
            .iter()
            .zip(&self.observations.abscissa)
            .zip(self.values)
            .filter(|((s, _), _)| s.as_str() == name)
            .map(|((_, &x), &y)| (x, y))
            .unzip()
    }
}

/// One frequency-response channel (the series `ln|H|{suffix}` and `phase{suffix}`): the
/// gain and phase at the lowest frequency, smoothed over the low band, and the resonance.
fn channel_features(curves: &Curves, suffix: &str) -> Vec<Feature> {
    let (frequency, ln_gain) = curves.series(&format!("ln|H|{suffix}"));
    let (_, phase) = curves.series(&format!("phase{suffix}"));
    let channel = suffix.trim_start_matches('.');
    let of = |what: &str| match channel {
        "" => what.to_string(),
        _ => format!("{what} ({channel})"),
    };
    let gain: Vec<f64> = ln_gain.iter().map(|l| l.exp()).collect();
    let peak = resonance(&frequency, &gain);
    let low = low_band(&frequency, peak.map(|p| p.frequency));
    vec![
        Feature::new(
            of("low-frequency gain"),
            low_limit(&low, &ln_gain).map(f64::exp),
            "µm/V",
            1e6,
        ),
        // −η for a hysteretic loss well below resonance.
        Feature::new(
            of("low-frequency phase"),
            low_limit(&low, &phase),
            "deg",
            180.0 / std::f64::consts::PI,
        ),
        Feature::new(
            of("resonance frequency"),
            peak.map(|p| p.frequency),
            "Hz",
            1.0,
        ),
        Feature::new(of("largest gain"), peak.map(|p| p.gain), "µm/V", 1e6),
        Feature::new(of("quality factor"), peak.and_then(|p| p.quality), "", 1.0),
    ]
}

/// The indices and frequencies of the low band: the samples below 0.3 of the resonance
/// frequency (where a second-order response is within 10 % of its static value), all of
/// them when no resonance is seen; the lowest sample alone if none is that low.
fn low_band(frequency: &[f64], resonance: Option<f64>) -> Vec<(usize, f64)> {
    let limit = resonance.map_or(f64::INFINITY, |f| 0.3 * f);
    let band: Vec<(usize, f64)> = frequency
        .iter()
        .enumerate()
        .filter(|(_, &f)| f <= limit)
        .map(|(k, &f)| (k, f))
        .collect();
    if !band.is_empty() {
        return band;
    }
    (0..frequency.len())
        .min_by(|&a, &b| frequency[a].total_cmp(&frequency[b]))
        .map(|k| vec![(k, frequency[k])])
        .unwrap_or_default()
}

/// `values` at the lowest frequency of the low band, read off the least-squares line in
/// `f²` through the band (a second-order response below resonance, `ln|H|` and phase alike,
/// is `a + b f²` to first order), so one noisy sample does not set it; evaluated there, not
/// extrapolated to zero frequency (a band starting at 20 Hz says little about 0 Hz); the
/// sample itself when alone.
fn low_limit(band: &[(usize, f64)], values: &[f64]) -> Option<f64> {
    let points: Vec<(f64, f64)> = band
        .iter()
        .filter_map(|&(k, f)| values.get(k).map(|&v| (f * f, v)))
        .collect();
    let lowest = points.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    match points.as_slice() {
        [] => None,
        [(_, value)] => Some(*value),
        _ => Polynomial::fit(&points, 1).map(|p| p.value(lowest)),
    }
}

/// The blocked force and the free deflection of the force/deflection curve.
fn force_deflection_features(curves: &Curves) -> Vec<Feature> {
    let (distance, force) = curves.series("force");
    let (blocked, free) = force_ends(&distance, &force);
    vec![
        Feature::new("blocked force", blocked, "mN", 1e3),
        Feature::new("free deflection", free, "µm", 1e6),
    ]
}

/// The range of a quasi-static output.
fn peak_to_peak(curves: &Curves, name: &str) -> Feature {
    let (_, y) = curves.series(name);
    let (lo, hi) = y
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    Feature::new(format!("{name} peak-to-peak"), Some(hi - lo), "µm", 1e6)
}

/// The natural frequency and quality factor of the (first) ring-down trace, by `mech flexure
/// fit`'s trace analysis (`Q = 1/2ζ`).
fn ring_down_features(curves: &Curves) -> Vec<Feature> {
    let name = curves
        .observations
        .series_names()
        .first()
        .map(|s| s.to_string());
    let (time, angle) = curves.series(name.as_deref().unwrap_or(""));
    let trace = crate::flexure_fit::trace::analyze_trace(
        &time,
        &angle,
        &crate::flexure_fit::trace::TraceOptions::default(),
    )
    .ok();
    vec![
        Feature::new(
            "natural frequency",
            trace
                .as_ref()
                .map(|t| t.omega_n / (2.0 * std::f64::consts::PI)),
            "Hz",
            1.0,
        ),
        Feature::new(
            "quality factor",
            trace.as_ref().map(|t| 1.0 / (2.0 * t.zeta)),
            "",
            1.0,
        ),
    ]
}

/// The peak of a measured gain curve.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Peak {
    frequency: f64,
    gain: f64,
    quality: Option<f64>,
}

/// The largest gain of the curve, refined with its two neighbours. For a second-order
/// resonance `1/|H|² ∝ (1 − s)² + s/Q²` with `s = f²/f₀²`, a parabola in `f²` — exactly, so
/// the parabola through the three points `(f², 1/g²)` gives `A(f² − v)² + m`: the gain peaks
/// at `f = √v` with `1/√m`, and with `f₀² = √(m/A + v²)` and `β = 2v/f₀² = 2 − 1/Q²`,
/// `Q = 1/√(2 − β)` — from a single sample inside the half-power band, where interpolating
/// its crossings would not do. No Q where the half-power band `f/Q` comes out narrower than
/// the sampling around the peak (not resolved) or the points do not curve upwards; the gain
/// reported is the largest sample (what the measurement saw). `None` at the edge of the band
/// (no resonance seen).
fn resonance(frequency: &[f64], gain: &[f64]) -> Option<Peak> {
    let mut order: Vec<usize> = (0..frequency.len()).collect();
    order.sort_by(|&a, &b| frequency[a].total_cmp(&frequency[b]));
    let f: Vec<f64> = order.iter().map(|&k| frequency[k]).collect();
    let g: Vec<f64> = order.iter().map(|&k| gain[k]).collect();
    let top = (0..g.len()).max_by(|&a, &b| g[a].total_cmp(&g[b]))?;
    if top == 0 || top + 1 == g.len() {
        return None;
    }
    // y = 1/g² against x = f², through three points (Newton's divided differences).
    let x = [f[top - 1], f[top], f[top + 1]].map(|f| f * f);
    let y = [g[top - 1], g[top], g[top + 1]].map(|g| 1.0 / (g * g));
    let (d1, d2) = ((y[1] - y[0]) / (x[1] - x[0]), (y[2] - y[1]) / (x[2] - x[1]));
    let curvature = (d2 - d1) / (x[2] - x[0]);
    let fitted = (curvature > 0.0)
        .then(|| {
            let vertex = (0.5 * (x[0] + x[1]) - d1 / (2.0 * curvature)).clamp(x[0], x[2]);
            let minimum =
                y[0] + d1 * (vertex - x[0]) + curvature * (vertex - x[0]) * (vertex - x[1]);
            (vertex, minimum)
        })
        .filter(|&(_, minimum)| minimum > 0.0);
    // The samples' spacing around the peak: a half-power band narrower than it is an
    // extrapolation of three points (one noisy sample moves it at will), not a measurement.
    let spacing = (f[top] - f[top - 1]).min(f[top + 1] - f[top]);
    let (frequency_peak, quality) = match fitted {
        Some((vertex, minimum)) => {
            let natural_squared = (minimum / curvature + vertex * vertex).sqrt();
            let beta = 2.0 * vertex / natural_squared;
            let quality = (beta < 2.0)
                .then(|| 1.0 / (2.0 - beta).sqrt())
                .filter(|q| vertex.sqrt() / q >= spacing);
            (vertex.sqrt(), quality)
        }
        None => (f[top], None),
    };
    Some(Peak {
        frequency: frequency_peak,
        gain: g[top],
        quality,
    })
}

/// The two ends of a force/deflection curve, each read from the points nearest it (a
/// straight line through the whole curve misses both ends of a curved one: 22.3 against
/// 24.6 mN for a side-loaded leg). The blocked force is the force at zero distance of the
/// least-squares parabola through the five points at the smallest distances (of those above
/// a tenth of the largest force); the free deflection the distance where the least-squares
/// line through the last four points still pressing (above a twentieth of the largest:
/// 2σ of the paper's sensor noise) reaches zero force — a parabola through so few noisy
/// points near zero curves at random. `None` where the curve does not fall to zero.
fn force_ends(distance: &[f64], force: &[f64]) -> (Option<f64>, Option<f64>) {
    let largest = force.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let above = |fraction: f64| {
        let mut points: Vec<(f64, f64)> = distance
            .iter()
            .zip(force)
            .filter(|(_, &f)| f > fraction * largest)
            .map(|(&d, &f)| (d, f))
            .collect();
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        points
    };
    let (pushing, pressing) = (above(0.1), above(0.05));
    if pushing.len() < 2 {
        return (None, None);
    }
    let blocked = Polynomial::fit(&pushing[..pushing.len().min(5)], 2).map(|p| p.value(0.0));
    let tail = &pressing[pressing.len().saturating_sub(4)..];
    let free = Polynomial::fit(tail, 1).and_then(|p| p.line_root_after(tail[0].0));
    (blocked, free)
}

/// A least-squares polynomial of degree `min(degree, points − 1)` in `t = (x − center)/scale`
/// (centred and scaled so the normal equations stay well conditioned for µm abscissae).
struct Polynomial {
    center: f64,
    scale: f64,
    coefficients: Vec<f64>,
}

impl Polynomial {
    fn fit(points: &[(f64, f64)], degree: usize) -> Option<Polynomial> {
        let n = points.len();
        let center = points.iter().map(|p| p.0).sum::<f64>() / n as f64;
        let scale = points
            .iter()
            .map(|p| (p.0 - center).abs())
            .fold(0.0, f64::max);
        if n < 2 || scale <= 0.0 {
            return None;
        }
        let terms = n.min(degree + 1);
        let design = nalgebra::DMatrix::from_fn(n, terms, |row, power| {
            ((points[row].0 - center) / scale).powi(power as i32)
        });
        let values = nalgebra::DVector::from_iterator(n, points.iter().map(|p| p.1));
        let solution = mech_runtime::constraints::svd(design, true, true)?
            .solve(&values, 1e-12)
            .ok()?;
        Some(Polynomial {
            center,
            scale,
            coefficients: solution.iter().copied().collect(),
        })
    }

    fn value(&self, x: f64) -> f64 {
        let t = (x - self.center) / self.scale;
        self.coefficients
            .iter()
            .rev()
            .fold(0.0, |acc, c| acc * t + c)
    }

    /// The root of a line at or beyond `x`; `None` for a flat line or a root before `x`.
    fn line_root_after(&self, x: f64) -> Option<f64> {
        let [c0, c1] = self.coefficients[..] else {
            return None;
        };
        let t = -c0 / c1;
        (t.is_finite() && t >= (x - self.center) / self.scale)
            .then_some(self.center + t * self.scale)
    }
}

/// RMS of the residual of one measured series, before (e.g. the base model) and after (the
/// fitted or best model), over the values `keep` selects (by index), in the series' SI unit
/// (`ln|H|` is relative).
#[derive(Debug, Clone)]
pub struct SeriesResidual {
    pub series: String,
    pub before: f64,
    pub after: f64,
}

/// [`SeriesResidual`] of every series of `observations`.
pub fn series_rms(
    observations: &Observations,
    before: &[f64],
    after: &[f64],
    keep: &dyn Fn(usize) -> bool,
) -> Vec<SeriesResidual> {
    let rms = |predicted: &[f64], series: &str| {
        let (sum, count) = (0..observations.values.len())
            .filter(|&k| keep(k) && observations.series[k] == series)
            .fold((0.0, 0usize), |(sum, n), k| {
                (sum + (predicted[k] - observations.values[k]).powi(2), n + 1)
            });
        (sum / count.max(1) as f64).sqrt()
    };
    observations
        .series_names()
        .into_iter()
        .map(|name| SeriesResidual {
            series: name.to_string(),
            before: rms(before, name),
            after: rms(after, name),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A second-order resonance `1/√((1 − r²)² + (r/Q)²)` sampled at 30 to 120 log-spaced
    /// frequencies from 1 to 150 Hz (steps of 19 % to 4 %, one or two samples in the
    /// half-power band): the estimator, exact for this curve, finds the gain's peak frequency
    /// `f₀√(1 − 1/2Q²)` and Q to 1e-9. Sampled more coarsely than its band (Q = 25 at 9 %
    /// steps), Q is reported unresolved.
    #[test]
    fn resonance_of_a_second_order_peak() {
        for (f0, q, n) in [(80.0, 10.0, 120), (35.0, 8.0, 60), (57.0, 4.0, 30)] {
            let frequency: Vec<f64> = (0..n)
                .map(|k| 150f64.powf(k as f64 / (n - 1) as f64))
                .collect();
            let gain: Vec<f64> = frequency
                .iter()
                .map(|&f| {
                    let r: f64 = f / f0;
                    1.0 / ((1.0 - r * r).powi(2) + (r / q).powi(2)).sqrt()
                })
                .collect();
            let peak = resonance(&frequency, &gain).unwrap();
            // The gain peaks at f₀√(1 − 1/2Q²).
            let expected = f0 * (1.0 - 0.5 / (q * q)).sqrt();
            assert!((peak.frequency / expected - 1.0).abs() < 1e-9, "{peak:?}");
            let quality = peak
                .quality
                .unwrap_or_else(|| panic!("{f0} {q} {n}: {peak:?}"));
            assert!((quality / q - 1.0).abs() < 1e-9, "Q {quality} vs {q}");
        }
        let frequency: Vec<f64> = (0..60).map(|k| 150f64.powf(k as f64 / 59.0)).collect();
        let gain: Vec<f64> = frequency
            .iter()
            .map(|&f| {
                let r: f64 = f / 35.0;
                1.0 / ((1.0 - r * r).powi(2) + (r / 25.0).powi(2)).sqrt()
            })
            .collect();
        assert_eq!(resonance(&frequency, &gain).unwrap().quality, None);
    }

    /// A peak at the edge of the band is no resonance.
    #[test]
    fn no_resonance_at_the_edge_of_the_band() {
        let frequency = [1.0, 2.0, 4.0, 8.0];
        assert!(resonance(&frequency, &[1.0, 2.0, 3.0, 4.0]).is_none());
    }

    /// A straight force/deflection line, with points at zero beyond reach: the blocked force
    /// and the free deflection of the line exactly.
    #[test]
    fn force_ends_of_a_linear_curve() {
        let distance: Vec<f64> = (0..12).map(|k| k as f64 * 100e-6).collect();
        let force: Vec<f64> = distance
            .iter()
            .map(|&d| (20e-3 * (1.0 - d / 800e-6)).max(0.0))
            .collect();
        let (blocked, reach) = force_ends(&distance, &force);
        let (blocked, reach) = (blocked.unwrap(), reach.unwrap());
        assert!((blocked - 20e-3).abs() < 1e-12, "{blocked}");
        assert!((reach - 800e-6).abs() < 1e-12, "{reach}");
    }

    /// A curved one, `F = F_b (1 − d/D)(1 + d/D)` at 127 µm steps: the blocked force exactly
    /// (a parabola), the reach from the local line within its curvature's 1.8 %, where one
    /// line through the points above a tenth of the largest force (the estimator before)
    /// gives the blocked force 10 % high and the reach 30 % long.
    #[test]
    fn force_ends_of_a_curved_curve() {
        let (blocked_force, reach) = (25e-3, 1.2e-3);
        let distance: Vec<f64> = (0..14).map(|k| k as f64 * 127e-6).collect();
        let force: Vec<f64> = distance
            .iter()
            .map(|&d| (blocked_force * (1.0 - d / reach) * (1.0 + d / reach)).max(0.0))
            .collect();
        let (blocked, free) = force_ends(&distance, &force);
        let (blocked, free) = (blocked.unwrap(), free.unwrap());
        assert!((blocked / blocked_force - 1.0).abs() < 1e-9, "{blocked}");
        assert!((free / reach - 1.018).abs() < 1e-3, "{free}");
    }

    /// The low-frequency phase of a hysteretic resonance (η = 0.08, f₀ = 80 Hz) sampled at
    /// 30 log-spaced frequencies from 1 to 150 Hz, each sample off by ±0.01 rad
    /// (alternating): the phase at the lowest frequency, ≈ −atan η, from the low band to
    /// 0.002 rad, where the lowest sample alone is off by the full 0.01.
    #[test]
    fn low_frequency_limit_from_the_low_band() {
        let (eta, f0) = (0.08_f64, 80.0);
        let frequency: Vec<f64> = (0..30).map(|k| 150f64.powf(k as f64 / 29.0)).collect();
        let phase: Vec<f64> = frequency
            .iter()
            .enumerate()
            .map(|(k, &f)| {
                let r2 = (f / f0).powi(2);
                -eta.atan2(1.0 - r2) + if k % 2 == 0 { 0.01 } else { -0.01 }
            })
            .collect();
        let band = low_band(&frequency, Some(f0));
        assert_eq!(band.len(), 19, "the samples below 24 Hz");
        let limit = low_limit(&band, &phase).unwrap();
        assert!(
            (limit + eta.atan()).abs() < 2e-3,
            "{limit} vs {}",
            -eta.atan()
        );
    }
}
