//! `mech animate`'s page: one self-contained HTML file (no network) that plays an
//! [`Animation`] in 3D, with play/pause, speed, a time slider and a camera turned by dragging.
//!
//! Consumes: an [`Animation`]. Produces: the page's text, `animation.html` with the run as a
//! JSON object in place of `__DATA__`. A canvas and an orthographic projection are all it
//! needs (bodies drawn as points joined to their origin), so the page has no library.
//! Positions are written as integers in ten-thousandths of the view's half-size, from its
//! centre: a page a tenth of the size of one with full floats, at a precision no screen shows.

use serde_json::json;

use crate::animation::Animation;
use crate::render::table::escape_html;

const TEMPLATE: &str = include_str!("animation.html");

/// Most samples a page holds: longer runs are thinned evenly (first and last kept).
pub const MAX_FRAMES: usize = 1000;

/// Integer steps per half-size of the view.
const STEPS: f64 = 10_000.0;

/// The samples a page shows of `samples`: every one up to [`MAX_FRAMES`], else evenly
/// thinned, the first and last kept.
pub fn shown_samples(samples: usize) -> Vec<usize> {
    let stride = samples.div_ceil(MAX_FRAMES).max(1);
    let mut kept: Vec<usize> = (0..samples).step_by(stride).collect();
    if samples > 0 && kept.last() != Some(&(samples - 1)) {
        kept.push(samples - 1);
    }
    kept
}

/// The page for `animation`.
pub fn page(animation: &Animation) -> String {
    let kept = shown_samples(animation.times.len());
    let all = || {
        animation
            .bodies
            .iter()
            .flat_map(|body| body.positions.iter().flatten())
    };
    let (mut low, mut high) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in all() {
        for k in 0..3 {
            low[k] = low[k].min(p[k]);
            high[k] = high[k].max(p[k]);
        }
    }
    let centre: [f64; 3] = std::array::from_fn(|k| 0.5 * (low[k] + high[k]));
    let half = (0..3)
        .map(|k| 0.5 * (high[k] - low[k]))
        .fold(0.0_f64, f64::max)
        .max(1e-9);
    let unit = half / STEPS;
    let step = |value: f64, k: usize| ((value - centre[k]) / unit).round() as i64;
    let bodies: Vec<_> = animation
        .bodies
        .iter()
        .map(|body| {
            let positions: Vec<Vec<i64>> = kept
                .iter()
                .map(|&s| {
                    body.positions[s]
                        .iter()
                        .flat_map(|p| (0..3).map(move |k| step(p[k], k)))
                        .collect()
                })
                .collect();
            json!({ "name": body.name, "labels": body.labels, "positions": positions })
        })
        .collect();
    let times: Vec<f64> = kept.iter().map(|&s| animation.times[s]).collect();
    let duration = times.last().copied().unwrap_or(0.0) - times.first().copied().unwrap_or(0.0);
    let speeds = speeds();
    // Playback of about five seconds, on the 1-2-5 series.
    let wanted = (duration / 5.0).max(1e-9);
    let speed = speeds
        .iter()
        .copied()
        .min_by(|a, b| (a / wanted).ln().abs().total_cmp(&(b / wanted).ln().abs()))
        .unwrap_or(1.0);
    let data = json!({
        "model": animation.model,
        "times": times,
        "half": STEPS,
        "unit": unit,
        "centre": centre,
        "ground": step(low[2], 2),
        "bodies": bodies,
        "speed": speed,
        "speeds": speeds,
    });
    // `</` would end the script element early inside a string.
    let data = data.to_string().replace("</", "<\\/");
    TEMPLATE
        .replace(
            "__TITLE__",
            &escape_html(&format!("{} — mech animate", animation.model)),
        )
        .replace("__DATA__", &data)
}

/// Playback speeds offered: 1-2-5 steps from 1e-4 to 10 times real time.
fn speeds() -> Vec<f64> {
    let mut speeds = Vec::new();
    for decade in -4..=1 {
        for mantissa in [1.0, 2.0, 5.0] {
            let value: f64 = mantissa * 10f64.powi(decade);
            if value <= 10.0 {
                // Printed exactly (`0.0002`, not `0.00020000000000000001`).
                speeds.push(format!("{value:.4e}").parse().unwrap_or(value));
            }
        }
    }
    speeds
}
