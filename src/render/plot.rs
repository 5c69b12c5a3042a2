//! Plots of simulation results and analyses, rendered headless (no system fonts needed).
//!
//! Consumes: sampled time series grouped into panels ([`plot_time_series`]), `(x, y)` curves
//! ([`plot_xy`], [`XyPlot`]: fits, paths in a plane drawn to equal scale) or a frequency
//! response ([`plot_bode`]), and an output path whose extension picks the format (`.svg` or
//! `.png`).
//! Produces: the image as a [`File`] in memory, for the run to write with its other files
//! ([`crate::output::write_all`]).
//!
//! Text is drawn with DejaVu Sans, bundled from `assets/` and registered with plotters as
//! `sans-serif` on first use. Non-finite samples (NaN, ±inf) are skipped: the line is broken
//! there rather than drawn through them. Constant data gets a padded axis range. Legends
//! stand in a column right of the data, never over it.

use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use crate::output::File;

use plotters::coord::ranged1d::{Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// DejaVu Sans 2.37 (Bitstream Vera licence, see `assets/DejaVuSans-LICENSE.txt`).
static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// Image width in pixels.
const WIDTH: u32 = 1000;
/// Height of one panel of [`plot_time_series`] in pixels.
const PANEL_HEIGHT: u32 = 260;
/// Height reserved for the figure title in pixels.
const TITLE_HEIGHT: u32 = 50;
/// Height of a [`plot_xy`] figure in pixels.
const XY_HEIGHT: u32 = 600;

/// Line colours (Tableau 10), used in order and then repeated.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// One named sequence of samples, one value per time of the figure.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend entry (no entry if empty).
    pub name: String,
    /// Samples; NaN and ±inf are skipped.
    pub values: Vec<f64>,
}

/// One panel of a [`plot_time_series`] figure: its own title, y axis and legend.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Caption above the panel.
    pub title: String,
    /// Label of the y axis, with its unit, e.g. `"q [rad]"`.
    pub y_label: String,
    /// The lines in this panel.
    pub series: Vec<Series>,
}

/// How an [`XyPlot`] draws one curve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CurveStyle {
    /// Palette index (wraps), so that curves that belong together can share a colour.
    pub color: usize,
    /// Dashed instead of solid.
    pub dashed: bool,
}

/// A point of an [`XyPlot`] figure marked with a star, in the colour of curve `curve`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Star {
    pub curve: usize,
    pub x: f64,
    pub y: f64,
}

/// Measured values drawn as markers with error bars, not joined by lines (the paper's
/// measurements, data a model is fitted to).
#[derive(Debug, Clone, PartialEq)]
pub struct Measured {
    /// Legend entry (no entry if empty); where no uncertainty is given it should say so.
    pub name: String,
    /// Palette index (wraps), e.g. the colour of the model curve it is compared with.
    pub color: usize,
    pub points: Vec<ErrorPoint>,
}

/// A measured point and the half-lengths of its error bars (±1 s.d., ±σ), in the plot's
/// units; 0 or NaN: no bar.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ErrorPoint {
    pub x: f64,
    pub y: f64,
    pub x_error: f64,
    pub y_error: f64,
}

impl ErrorPoint {
    /// Where the point and its bars reach: `(x_lo, x_hi, y_lo, y_hi)`.
    fn extent(&self) -> [(f64, f64); 2] {
        let bar = |e: f64| if e.is_finite() { e.abs() } else { 0.0 };
        let (dx, dy) = (bar(self.x_error), bar(self.y_error));
        [(self.x - dx, self.x + dx), (self.y - dy, self.y + dy)]
    }
}

/// Why a plot could not be made. Displays as one line naming the output file.
#[derive(Debug)]
pub struct PlotError {
    /// The output file asked for.
    pub path: PathBuf,
    /// What went wrong.
    pub kind: PlotErrorKind,
}

impl PlotError {
    fn invalid(path: &Path, message: String) -> PlotError {
        PlotError {
            path: path.to_path_buf(),
            kind: PlotErrorKind::InvalidData(message),
        }
    }
}

/// The kinds of [`PlotError`].
#[derive(Debug)]
pub enum PlotErrorKind {
    /// The extension is not `.svg` or `.png`.
    UnsupportedFormat,
    /// The data cannot be plotted (mismatched lengths, nothing to plot, ...).
    InvalidData(String),
    /// Plotters or the PNG encoder failed.
    Render(String),
}

impl fmt::Display for PlotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let path = self.path.display();
        match &self.kind {
            PlotErrorKind::UnsupportedFormat => write!(
                f,
                "cannot plot to `{path}`: unsupported file type; use a `.svg` or `.png` extension"
            ),
            PlotErrorKind::InvalidData(msg) => write!(f, "cannot plot to `{path}`: {msg}"),
            PlotErrorKind::Render(msg) => {
                write!(f, "cannot plot to `{path}`: rendering failed: {msg}")
            }
        }
    }
}

impl std::error::Error for PlotError {}

/// Plots `panels` stacked vertically over a shared time axis `times` (seconds), each with its
/// own y axis and legend, under the figure `title`. Every series must have one value per time.
/// The format follows the extension of `path`: `.svg` or `.png` (case-insensitive).
pub fn plot_time_series(
    path: &Path,
    title: &str,
    times: &[f64],
    panels: &[Panel],
) -> Result<File, PlotError> {
    let fail = |msg: String| PlotError::invalid(path, msg);
    let format = Format::of(path)?;
    if panels.is_empty() {
        return Err(fail("nothing to plot (no panels)".into()));
    }
    for panel in panels {
        for series in &panel.series {
            if series.values.len() != times.len() {
                return Err(fail(format!(
                    "series `{}` of panel `{}` has {} values but there are {} times",
                    series.name,
                    panel.title,
                    series.values.len(),
                    times.len()
                )));
            }
        }
    }
    let height = TITLE_HEIGHT + PANEL_HEIGHT * panels.len() as u32;
    let figure = TimeSeriesFigure {
        title,
        times,
        panels,
    };
    render(path, format, (WIDTH, height), &figure)
}

/// Plots `curves` given as `(name, xs, ys)` on one pair of axes, optionally with a logarithmic
/// x axis (then only points with `x > 0` are drawn). Same formats and conventions as
/// [`plot_time_series`]; [`XyPlot`] draws more (styles, stars, equal scale).
pub fn plot_xy(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    curves: &[(String, Vec<f64>, Vec<f64>)],
    log_x: bool,
) -> Result<File, PlotError> {
    XyPlot {
        log_x,
        ..XyPlot::new(title, x_label, y_label, curves)
    }
    .render(path)
}

/// An x–y figure: named curves `(name, xs, ys)` on one pair of axes, the legend to the right
/// of the data, and what else is drawn on them.
#[derive(Debug, Clone, Copy)]
pub struct XyPlot<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub curves: &'a [(String, Vec<f64>, Vec<f64>)],
    /// A logarithmic x axis: only points with `x > 0` are drawn.
    pub log_x: bool,
    /// One per curve (colour, dashes); `None`: palette colours in order, solid.
    pub styles: Option<&'a [CurveStyle]>,
    /// Points marked with a star, e.g. the chosen designs on design curves.
    pub stars: &'a [Star],
    /// Measured values, markers with error bars, drawn over the curves.
    pub measured: &'a [Measured],
    /// x and y drawn to the same scale (the same length per pixel), the data centred: a
    /// path in a plane keeps its shape. Linear axes only.
    pub equal_scale: bool,
}

impl<'a> XyPlot<'a> {
    /// Plain curves on linear axes.
    pub fn new(
        title: &'a str,
        x_label: &'a str,
        y_label: &'a str,
        curves: &'a [(String, Vec<f64>, Vec<f64>)],
    ) -> XyPlot<'a> {
        XyPlot {
            title,
            x_label,
            y_label,
            curves,
            log_x: false,
            styles: None,
            stars: &[],
            measured: &[],
            equal_scale: false,
        }
    }

    /// Renders the figure to a file whose extension picks the format (`.svg` or `.png`),
    /// after checking its data: something to draw, as many x as y values, one style per
    /// curve, stars on existing curves, positive x on a log axis.
    pub fn render(&self, path: &Path) -> Result<File, PlotError> {
        let fail = |msg: String| PlotError::invalid(path, msg);
        let format = Format::of(path)?;
        if self.curves.is_empty() && self.measured.is_empty() {
            return Err(fail("nothing to plot (no curves)".into()));
        }
        for (name, xs, ys) in self.curves {
            if xs.len() != ys.len() {
                return Err(fail(format!(
                    "curve `{name}` has {} x values but {} y values",
                    xs.len(),
                    ys.len()
                )));
            }
        }
        if let Some(styles) = self.styles.filter(|s| s.len() != self.curves.len()) {
            return Err(fail(format!(
                "{} curves but {} styles",
                self.curves.len(),
                styles.len()
            )));
        }
        if let Some(star) = self.stars.iter().find(|s| s.curve >= self.curves.len()) {
            return Err(fail(format!(
                "a star refers to curve {} of {}",
                star.curve,
                self.curves.len()
            )));
        }
        let positive = self.xs().any(|x| x > 0.0 && x.is_finite());
        if self.log_x && !positive {
            return Err(fail(
                "a logarithmic x axis needs some positive x values, but there are none".into(),
            ));
        }
        render(path, format, (WIDTH, XY_HEIGHT), self)
    }

    /// Every x value drawn or marked, error bars' ends included.
    fn xs(&self) -> impl Iterator<Item = f64> + '_ {
        let curves = self.curves.iter().flat_map(|(_, xs, _)| xs.iter().copied());
        let bars = self.measured_points().flat_map(|p| {
            let [(lo, hi), _] = p.extent();
            [lo, hi]
        });
        curves.chain(self.stars.iter().map(|s| s.x)).chain(bars)
    }

    fn measured_points(&self) -> impl Iterator<Item = &ErrorPoint> + '_ {
        self.measured.iter().flat_map(|m| &m.points)
    }

    /// Curve `index`'s style: its `styles` entry, else its palette colour in order, solid.
    fn style(&self, index: usize) -> CurveStyle {
        self.styles
            .and_then(|s| s.get(index))
            .copied()
            .unwrap_or(CurveStyle {
                color: index,
                dashed: false,
            })
    }

    /// The legend: the named curves, then the named measurements.
    fn legend(&self) -> Vec<LegendEntry<'a>> {
        let curves = self.curves.iter().enumerate();
        let lines =
            curves
                .filter(|(_, (name, _, _))| !name.is_empty())
                .map(|(index, (name, _, _))| {
                    let CurveStyle { color, dashed } = self.style(index);
                    LegendEntry {
                        name,
                        color,
                        sample: Sample::Line { dashed },
                    }
                });
        let markers = self.measured.iter().filter(|m| !m.name.is_empty());
        let markers = markers.map(|m| LegendEntry {
            name: &m.name,
            color: m.color,
            sample: Sample::Marker {
                bars: m.points.iter().any(|p| p.x_error > 0.0 || p.y_error > 0.0),
            },
        });
        lines.chain(markers).collect()
    }
}

// ---------------------------------------------------------------------------------------------
// Rendering
// ---------------------------------------------------------------------------------------------

/// Output image formats.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Format {
    Svg,
    Png,
}

/// An error now if `path` names no format a plot can have (`.svg` or `.png`): a command
/// checks its plot path before its work, not after.
pub fn check_path(path: &Path) -> Result<(), PlotError> {
    Format::of(path).map(|_| ())
}

impl Format {
    fn of(path: &Path) -> Result<Format, PlotError> {
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("svg") => Ok(Format::Svg),
            Some("png") => Ok(Format::Png),
            _ => Err(PlotError {
                path: path.to_path_buf(),
                kind: PlotErrorKind::UnsupportedFormat,
            }),
        }
    }
}

/// Something that draws itself onto any plotters backend.
trait Figure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>;
}

/// Renders `figure` in memory in `format`, then writes it atomically to `path`.
fn render(
    path: &Path,
    format: Format,
    size: (u32, u32),
    figure: &impl Figure,
) -> Result<File, PlotError> {
    let error = |kind| PlotError {
        path: path.to_path_buf(),
        kind,
    };
    register_fonts().map_err(|msg| error(PlotErrorKind::Render(msg)))?;
    let bytes = match format {
        Format::Svg => {
            let mut svg = String::new();
            draw_and_present(figure, SVGBackend::with_string(&mut svg, size))
                .map_err(|m| error(PlotErrorKind::Render(m)))?;
            svg.into_bytes()
        }
        Format::Png => {
            let mut pixels = vec![0u8; size.0 as usize * size.1 as usize * 3];
            draw_and_present(figure, BitMapBackend::with_buffer(&mut pixels, size))
                .map_err(|m| error(PlotErrorKind::Render(m)))?;
            encode_png(&pixels, size).map_err(|m| error(PlotErrorKind::Render(m)))?
        }
    };
    Ok(File::new(path, bytes))
}

/// Draws `figure` on `backend` and flushes it into the backend's buffer.
fn draw_and_present<DB: DrawingBackend>(figure: &impl Figure, backend: DB) -> Result<(), String> {
    let root = backend.into_drawing_area();
    figure.draw(&root)?;
    root.present().map_err(|e| e.to_string())
}

/// Encodes 8-bit RGB pixels as a PNG file in memory.
fn encode_png(pixels: &[u8], (width, height): (u32, u32)) -> Result<Vec<u8>, String> {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(pixels).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())?;
    Ok(bytes)
}

/// Registers the bundled font as `sans-serif` (all styles), once per process.
fn register_fonts() -> Result<(), String> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        [
            FontStyle::Normal,
            FontStyle::Bold,
            FontStyle::Italic,
            FontStyle::Oblique,
        ]
        .into_iter()
        .all(|style| plotters::style::register_font("sans-serif", style, FONT).is_ok())
    });
    if ok {
        Ok(())
    } else {
        Err("the bundled font could not be loaded".into())
    }
}

struct TimeSeriesFigure<'a> {
    title: &'a str,
    times: &'a [f64],
    panels: &'a [Panel],
}

impl Figure for TimeSeriesFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        root.fill(&WHITE).map_err(e)?;
        let (title_area, body) = root.split_vertically(TITLE_HEIGHT);
        draw_title(&title_area, self.title)?;
        let t_range = axis_range(self.times.iter().copied());
        let legends: Vec<Vec<LegendEntry>> = self
            .panels
            .iter()
            .map(|panel| {
                let series = panel.series.iter().enumerate();
                series
                    .filter(|(_, s)| !s.name.is_empty())
                    .map(|(index, s)| LegendEntry {
                        name: &s.name,
                        color: index,
                        sample: Sample::Line { dashed: false },
                    })
                    .collect()
            })
            .collect();
        // One legend width for all panels, so that their time axes line up.
        let all: Vec<LegendEntry> = legends.iter().flatten().copied().collect();
        let legend_width = legend_width(&body, &all)?;
        let areas = body.split_evenly((self.panels.len(), 1));
        for (index, ((area, panel), legend)) in
            areas.iter().zip(self.panels).zip(&legends).enumerate()
        {
            let last = index + 1 == self.panels.len();
            let (width, _) = area.dim_in_pixel();
            let (area, legend_area) = area.split_horizontally(width - legend_width);
            let values = panel.series.iter().flat_map(|s| s.values.iter().copied());
            let y_range = axis_range(values);
            let mut chart = ChartBuilder::on(&area)
                .caption(&panel.title, ("sans-serif", 17))
                .margin(8)
                .margin_right(25)
                .x_label_area_size(if last { 50 } else { 30 })
                .y_label_area_size(90)
                .build_cartesian_2d(t_range.clone(), y_range.clone())
                .map_err(e)?;
            let x_format = |v: &f64| linear_tick(*v, &t_range);
            let y_format = |v: &f64| linear_tick(*v, &y_range);
            let mut mesh = chart.configure_mesh();
            mesh.x_label_formatter(&x_format)
                .y_label_formatter(&y_format)
                .y_desc(panel.y_label.as_str())
                .x_labels(10)
                .y_labels(6)
                .label_style(("sans-serif", 13))
                .axis_desc_style(("sans-serif", 14));
            if last {
                mesh.x_desc("t [s]");
            }
            mesh.draw().map_err(e)?;
            let curves = panel.series.iter().enumerate().map(|(index, s)| {
                let style = CurveStyle {
                    color: index,
                    dashed: false,
                };
                (self.times, s.values.as_slice(), style)
            });
            draw_curves(&mut chart, curves, &[], &|_| 0, &[])?;
            draw_legend(&legend_area, chart.plotting_area(), legend)?;
        }
        Ok(())
    }
}

impl Figure for XyPlot<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (title_area, body) = root.split_vertically(TITLE_HEIGHT);
        draw_title(&title_area, self.title)?;
        draw_xy_panel(&body, self)
    }
}

/// A Bode plot: magnitude over phase, sharing a logarithmic frequency axis.
struct BodeFigure<'a> {
    title: &'a str,
    magnitude_label: &'a str,
    magnitude: &'a [(String, Vec<f64>, Vec<f64>)],
    phase: &'a [(String, Vec<f64>, Vec<f64>)],
}

impl Figure for BodeFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (title_area, body) = root.split_vertically(TITLE_HEIGHT);
        draw_title(&title_area, self.title)?;
        let (_, height) = body.dim_in_pixel();
        let (top, bottom) = body.split_vertically(height / 2);
        let panel = |y_label, curves| XyPlot {
            log_x: true,
            ..XyPlot::new("", "f [Hz]", y_label, curves)
        };
        draw_xy_panel(&top, &panel(self.magnitude_label, self.magnitude))?;
        draw_xy_panel(&bottom, &panel("phase [deg]", self.phase))
    }
}

/// Plots a frequency response: `magnitude` (dB, the axis labelled `magnitude_label`, which
/// names the reference: `magnitude [dB re 1 m/V]`) and `phase` (degrees) curves
/// `(name, f, value)` in two panels over a logarithmic frequency axis. Same formats as
/// [`plot_time_series`].
pub fn plot_bode(
    path: &Path,
    title: &str,
    magnitude_label: &str,
    magnitude: &[(String, Vec<f64>, Vec<f64>)],
    phase: &[(String, Vec<f64>, Vec<f64>)],
) -> Result<File, PlotError> {
    let format = Format::of(path)?;
    let positive = |curves: &[(String, Vec<f64>, Vec<f64>)]| {
        curves
            .iter()
            .any(|(_, f, _)| f.iter().any(|&x| x > 0.0 && x.is_finite()))
    };
    if !positive(magnitude) || !positive(phase) {
        return Err(PlotError {
            path: path.to_path_buf(),
            kind: PlotErrorKind::InvalidData("a Bode plot needs positive frequencies".into()),
        });
    }
    let figure = BodeFigure {
        title,
        magnitude_label,
        magnitude,
        phase,
    };
    render(path, format, (WIDTH, 2 * XY_HEIGHT - TITLE_HEIGHT), &figure)
}

/// `plot`'s axes, curves and marks in `area` (its title is the caller's), its legend to the
/// right of the data.
fn draw_xy_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    plot: &XyPlot,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let legend = plot.legend();
    let (width, _) = area.dim_in_pixel();
    let (area, legend_area) = area.split_horizontally(width - legend_width(area, &legend)?);
    let visible = |x: f64| !plot.log_x || x > 0.0;
    let xs = plot.xs().filter(|&x| visible(x));
    let curve_ys = plot.curves.iter().flat_map(|(_, xs, ys)| {
        xs.iter()
            .zip(ys)
            .filter(|(&x, _)| visible(x))
            .map(|(_, &y)| y)
    });
    let star_ys = plot.stars.iter().filter(|s| visible(s.x)).map(|s| s.y);
    let bar_ys = plot
        .measured_points()
        .filter(|p| visible(p.x))
        .flat_map(|p| {
            let [_, (lo, hi)] = p.extent();
            [lo, hi]
        });
    let y_range = axis_range(curve_ys.chain(star_ys).chain(bar_ys));
    let mut builder = ChartBuilder::on(&area);
    builder
        .margin(10)
        .margin_right(30)
        .x_label_area_size(50)
        .y_label_area_size(90);
    let curves = plot
        .curves
        .iter()
        .enumerate()
        .map(|(index, (_, xs, ys))| (xs.as_slice(), ys.as_slice(), plot.style(index)));
    let star_color = |curve: usize| plot.style(curve).color;
    if plot.log_x {
        let x_range = log_axis_range(xs);
        let y_format = |v: &f64| linear_tick(*v, &y_range);
        let mut chart = builder
            .build_cartesian_2d(x_range.log_scale(), y_range.clone())
            .map_err(e)?;
        let x_format = |v: &f64| significant(*v, 3);
        configure_xy_mesh(&mut chart, plot.x_label, plot.y_label, &x_format, &y_format)?;
        draw_curves(&mut chart, curves, plot.stars, &star_color, plot.measured)?;
        draw_legend(&legend_area, chart.plotting_area(), &legend)
    } else {
        let mut x_range = axis_range(xs);
        let mut y_range = y_range;
        if plot.equal_scale {
            // The plotting area's size in pixels (building the chart draws nothing).
            let probe = builder
                .build_cartesian_2d(x_range.clone(), y_range.clone())
                .map_err(e)?;
            let pixels = probe.plotting_area().dim_in_pixel();
            (x_range, y_range) = equal_scale(x_range, y_range, pixels);
        }
        let mut chart = builder
            .build_cartesian_2d(x_range.clone(), y_range.clone())
            .map_err(e)?;
        let x_format = |v: &f64| linear_tick(*v, &x_range);
        let y_format = |v: &f64| linear_tick(*v, &y_range);
        configure_xy_mesh(&mut chart, plot.x_label, plot.y_label, &x_format, &y_format)?;
        draw_curves(&mut chart, curves, plot.stars, &star_color, plot.measured)?;
        draw_legend(&legend_area, chart.plotting_area(), &legend)
    }
}

/// The ranges `x` and `y` widened about their centres so that one unit takes as many pixels
/// along x as along y in a plotting area of `(width, height)` pixels.
fn equal_scale(
    x: Range<f64>,
    y: Range<f64>,
    (width, height): (u32, u32),
) -> (Range<f64>, Range<f64>) {
    let (width, height) = (f64::from(width.max(1)), f64::from(height.max(1)));
    let per_pixel = ((x.end - x.start) / width).max((y.end - y.start) / height);
    let widen = |range: Range<f64>, pixels: f64| {
        let (centre, half) = (0.5 * (range.start + range.end), 0.5 * per_pixel * pixels);
        centre - half..centre + half
    };
    (widen(x, width), widen(y, height))
}

/// How a legend entry is drawn: its name beside a sample of its line or marker.
#[derive(Debug, Clone, Copy)]
struct LegendEntry<'a> {
    name: &'a str,
    /// Palette index (wraps).
    color: usize,
    sample: Sample,
}

#[derive(Debug, Clone, Copy)]
enum Sample {
    Line {
        dashed: bool,
    },
    /// A measured point, with a vertical error bar if the measurement has bars.
    Marker {
        bars: bool,
    },
}

/// Radius of a measured point's marker, and half the width of an error bar's caps, in pixels.
const MARKER_RADIUS: i32 = 5;
const CAP: i32 = 5;

/// The marker of a measured point, a circle of [`MARKER_RADIUS`] drawn in these styles in
/// turn: filled in `color`, then outlined in black.
fn marker_styles(color: RGBColor) -> [ShapeStyle; 2] {
    [color.filled(), BLACK.stroke_width(1)]
}

/// Legend text size in pixels.
const LEGEND_FONT: u32 = 13;
/// Height of one legend line, and the length of a line sample, in pixels.
const LEGEND_LINE: i32 = 20;
const LEGEND_SAMPLE: i32 = 26;

/// The width of the column right of the data that holds `entries`: their longest name, the
/// sample and padding; 0 without entries, at most a third of `area`.
fn legend_width<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
) -> Result<u32, String> {
    let font = TextStyle::from(("sans-serif", LEGEND_FONT).into_font());
    let mut widest = 0;
    for entry in entries {
        let (width, _) = area
            .estimate_text_size(entry.name, &font)
            .map_err(|e| e.to_string())?;
        widest = widest.max(width);
    }
    let (area_width, _) = area.dim_in_pixel();
    Ok(if entries.is_empty() {
        0
    } else {
        (widest + LEGEND_SAMPLE as u32 + 30).min(area_width / 3)
    })
}

/// Draws `entries` in `column` (right of the data), from the top of the `plotting` area down,
/// in a light box.
fn draw_legend<DB: DrawingBackend, X: Ranged, Y: Ranged>(
    column: &DrawingArea<DB, Shift>,
    plotting: &DrawingArea<DB, Cartesian2d<X, Y>>,
    entries: &[LegendEntry],
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    if entries.is_empty() {
        return Ok(());
    }
    let top = plotting.get_base_pixel().1 - column.get_base_pixel().1;
    let (width, _) = column.dim_in_pixel();
    let bottom = top + LEGEND_LINE * entries.len() as i32 + 8;
    column
        .draw(&Rectangle::new(
            [(0, top), (width as i32 - 4, bottom)],
            BLACK.mix(0.4),
        ))
        .map_err(e)?;
    let text = TextStyle::from(("sans-serif", LEGEND_FONT).into_font())
        .pos(Pos::new(HPos::Left, VPos::Center))
        .color(&BLACK);
    for (index, entry) in entries.iter().enumerate() {
        let y = top + 4 + LEGEND_LINE / 2 + LEGEND_LINE * index as i32;
        let color = PALETTE[entry.color % PALETTE.len()];
        let (start, end) = ((8, y), (8 + LEGEND_SAMPLE, y));
        match entry.sample {
            Sample::Line { dashed: false } => column
                .draw(&PathElement::new(vec![start, end], color.stroke_width(2)))
                .map_err(e)?,
            Sample::Line { dashed: true } => column
                .draw(&DashedPathElement::new(
                    vec![start, end],
                    8,
                    5,
                    color.stroke_width(2),
                ))
                .map_err(e)?,
            Sample::Marker { bars } => {
                let middle = 8 + LEGEND_SAMPLE / 2;
                if bars {
                    let half = LEGEND_LINE / 2 - 2;
                    for path in [
                        vec![(middle, y - half), (middle, y + half)],
                        vec![(middle - CAP, y - half), (middle + CAP, y - half)],
                        vec![(middle - CAP, y + half), (middle + CAP, y + half)],
                    ] {
                        column
                            .draw(&PathElement::new(path, color.stroke_width(1)))
                            .map_err(e)?;
                    }
                }
                for style in marker_styles(color) {
                    column
                        .draw(&Circle::new((middle, y), MARKER_RADIUS, style))
                        .map_err(e)?;
                }
            }
        }
        column
            .draw(&Text::new(
                entry.name.to_string(),
                (16 + LEGEND_SAMPLE, y),
                text.clone(),
            ))
            .map_err(e)?;
    }
    Ok(())
}

/// Draws the figure title centred in `area`.
fn draw_title<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
) -> Result<(), String> {
    let (width, height) = area.dim_in_pixel();
    let style = TextStyle::from(("sans-serif", 22).into_font())
        .pos(Pos::new(HPos::Center, VPos::Center))
        .color(&BLACK);
    area.draw(&Text::new(
        title.to_string(),
        (width as i32 / 2, height as i32 / 2),
        style,
    ))
    .map_err(|e| e.to_string())
}

fn configure_xy_mesh<'a, DB, X>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, RangedCoordf64>>,
    x_label: &str,
    y_label: &str,
    x_format: &dyn Fn(&f64) -> String,
    y_format: &dyn Fn(&f64) -> String,
) -> Result<(), String>
where
    DB: DrawingBackend + 'a,
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .x_label_formatter(x_format)
        .y_label_formatter(y_format)
        .x_labels(12)
        .y_labels(10)
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 15))
        .draw()
        .map_err(|e| e.to_string())
}

/// Draws each `(xs, ys, style)` curve, broken at non-finite points, then the `stars`, each in
/// the palette colour `star_color` gives for its curve, then the `measured` points.
fn draw_curves<'a, 'c, DB, X>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, RangedCoordf64>>,
    curves: impl Iterator<Item = (&'c [f64], &'c [f64], CurveStyle)>,
    stars: &[Star],
    star_color: &dyn Fn(usize) -> usize,
    measured: &[Measured],
) -> Result<(), String>
where
    DB: DrawingBackend + 'a,
    X: Ranged<ValueType = f64>,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let x_range = chart.x_range();
    // Points outside the x range (x <= 0 on a log axis) are dropped like non-finite ones.
    let in_range = |x: f64| x >= x_range.start.min(x_range.end);
    for (xs, ys, CurveStyle { color, dashed }) in curves {
        let style = PALETTE[color % PALETTE.len()].stroke_width(2);
        let segments = finite_segments(xs, ys, in_range);
        if dashed {
            chart.draw_series(
                segments
                    .into_iter()
                    .map(move |segment| DashedPathElement::new(segment, 8, 5, style)),
            )
        } else {
            chart.draw_series(
                segments
                    .into_iter()
                    .map(move |segment| PathElement::new(segment, style)),
            )
        }
        .map_err(e)?;
    }
    // A five-pointed star around each marked point, outlined in black.
    let star_shape = star_shape();
    let outline: Vec<(i32, i32)> = star_shape.iter().chain(&star_shape[..1]).copied().collect();
    chart
        .draw_series(
            stars
                .iter()
                .filter(|s| s.x.is_finite() && s.y.is_finite() && in_range(s.x))
                .map(|s| {
                    let color = PALETTE[star_color(s.curve) % PALETTE.len()];
                    EmptyElement::at((s.x, s.y))
                        + Polygon::new(star_shape.clone(), color.filled())
                        + PathElement::new(outline.clone(), BLACK.stroke_width(1))
                }),
        )
        .map_err(e)?;
    // The measurements: markers with their error bars (a line with caps each way that has
    // a bar); points or bar ends off the axes (x <= 0 on a log axis) left out.
    for measurement in measured {
        let color = PALETTE[measurement.color % PALETTE.len()];
        let points = measurement
            .points
            .iter()
            .filter(|p| p.x.is_finite() && in_range(p.x) && p.y.is_finite());
        let style = color.stroke_width(1);
        for point in points.clone() {
            let [(x_lo, x_hi), (y_lo, y_hi)] = point.extent();
            // A bar in data units, and a cap in pixels at each end.
            let cap = |at: (f64, f64), vertical: bool| {
                let tick = if vertical {
                    vec![(-CAP, 0), (CAP, 0)]
                } else {
                    vec![(0, -CAP), (0, CAP)]
                };
                EmptyElement::at(at) + PathElement::new(tick, style)
            };
            let vertical = (y_hi > y_lo).then_some(((point.x, y_lo), (point.x, y_hi), true));
            let horizontal = (x_hi > x_lo && in_range(x_lo)).then_some((
                (x_lo, point.y),
                (x_hi, point.y),
                false,
            ));
            for (low, high, vertical) in vertical.into_iter().chain(horizontal) {
                chart
                    .draw_series([PathElement::new(vec![low, high], style)])
                    .map_err(e)?;
                chart
                    .draw_series([cap(low, vertical), cap(high, vertical)])
                    .map_err(e)?;
            }
        }
        for style in marker_styles(color) {
            let circles = points
                .clone()
                .map(|p| Circle::new((p.x, p.y), MARKER_RADIUS, style));
            chart.draw_series(circles).map_err(e)?;
        }
    }
    Ok(())
}

/// The corners of a five-pointed star in pixels around its centre, the top point first.
fn star_shape() -> Vec<(i32, i32)> {
    (0..10)
        .map(|k| {
            let radius = if k % 2 == 0 { 9.0 } else { 4.0 };
            let angle = std::f64::consts::PI * (k as f64 / 5.0 - 0.5);
            (
                (radius * angle.cos()).round() as i32,
                (radius * angle.sin()).round() as i32,
            )
        })
        .collect()
}

/// Splits the points `(xs[i], ys[i])` into runs of consecutive finite points accepted by `keep`.
/// A single isolated point becomes a tiny horizontal dash so it stays visible.
fn finite_segments(xs: &[f64], ys: &[f64], keep: impl Fn(f64) -> bool) -> Vec<Vec<(f64, f64)>> {
    let mut segments = Vec::new();
    let mut current: Vec<(f64, f64)> = Vec::new();
    for (&x, &y) in xs.iter().zip(ys) {
        if x.is_finite() && y.is_finite() && keep(x) {
            current.push((x, y));
        } else if !current.is_empty() {
            segments.push(std::mem::take(&mut current));
        }
    }
    if !current.is_empty() {
        segments.push(current);
    }
    for segment in &mut segments {
        if segment.len() == 1 {
            let point = segment[0];
            segment.push(point);
        }
    }
    segments
}

/// The axis range for `values`: their finite extent padded by 5 % on each side; a constant
/// gets ±10 % of its magnitude (±1 around zero); no finite values gives `-1..1`.
fn axis_range(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if lo > hi {
        return -1.0..1.0;
    }
    let span = hi - lo;
    let pad = if span > 0.0 && span.is_finite() && span > 1e-12 * lo.abs().max(hi.abs()) {
        0.05 * span
    } else if lo == 0.0 && hi == 0.0 {
        1.0
    } else {
        0.1 * lo.abs().max(hi.abs())
    };
    let (lo, hi) = (lo - pad, hi + pad);
    if lo.is_finite() && hi.is_finite() {
        lo..hi
    } else {
        f64::MIN / 2.0..f64::MAX / 2.0
    }
}

/// The range of the positive finite `values` for a log axis, padded by a factor 1.1 at both
/// ends (a factor 2 for a single value); `1..10` if there are none.
fn log_axis_range(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if lo > hi {
        1.0..10.0
    } else if lo == hi {
        lo / 2.0..hi * 2.0
    } else {
        lo / 1.1..hi * 1.1
    }
}

/// A tick label on a linear axis spanning `range`: as many decimals as the tick spacing
/// needs, in scientific notation for very small or large magnitudes.
fn linear_tick(value: f64, range: &Range<f64>) -> String {
    let span = (range.end - range.start).abs();
    let magnitude = range.start.abs().max(range.end.abs());
    if !(span > 0.0 && span.is_finite()) {
        return significant(value, 4);
    }
    // Ticks are about a tenth of the span apart; one more digit than that resolves them.
    let step_exponent = (span / 10.0).log10().floor() as i32;
    let value = if value.abs() < span * 1e-9 {
        0.0
    } else {
        value
    };
    if (1e-3..1e5).contains(&magnitude) {
        let decimals = (-step_exponent).clamp(0, 12) as usize;
        format!("{value:.decimals$}")
    } else {
        if value == 0.0 {
            return "0".into();
        }
        let digits = (value.abs().log10().floor() as i32 - step_exponent).clamp(0, 8) as usize;
        format!("{value:.digits$e}")
    }
}

/// `value` with at most `digits` significant digits, trailing zeros removed; scientific
/// notation outside `1e-3 ≤ |value| < 1e5`.
pub(crate) fn significant(value: f64, digits: usize) -> String {
    if value == 0.0 || !value.is_finite() {
        return format!("{value}");
    }
    let exponent = value.abs().log10().floor() as i32;
    let trim = |s: String| {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    };
    if (-3..5).contains(&exponent) {
        let decimals = (digits as i32 - 1 - exponent).max(0) as usize;
        trim(format!("{value:.decimals$}"))
    } else {
        let formatted = format!("{value:.*e}", digits.saturating_sub(1));
        let (mantissa, exp) = formatted.split_once('e').unwrap_or((&formatted, "0"));
        format!("{}e{exp}", trim(mantissa.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    fn temp_dir(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("mech-plot-test-{tag}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn demo_panels(times: &[f64]) -> Vec<Panel> {
        let sine: Vec<f64> = times.iter().map(|t| (6.0 * t).sin() * 1e-3).collect();
        let cosine: Vec<f64> = times.iter().map(|t| (6.0 * t).cos() * 1e-3).collect();
        let mut gappy: Vec<f64> = times.iter().map(|t| 2.0 * t - 1.0).collect();
        gappy[10] = f64::NAN;
        gappy[20] = f64::INFINITY;
        vec![
            Panel {
                title: "Coordinates".into(),
                y_label: "q [m]".into(),
                series: vec![
                    Series {
                        name: "q1".into(),
                        values: sine,
                    },
                    Series {
                        name: "q2".into(),
                        values: cosine,
                    },
                ],
            },
            Panel {
                title: "Speeds".into(),
                y_label: "u [m/s]".into(),
                series: vec![
                    Series {
                        name: "u1 (gaps)".into(),
                        values: gappy,
                    },
                    Series {
                        name: "constant".into(),
                        values: vec![0.25; times.len()],
                    },
                ],
            },
        ]
    }

    #[test]
    fn renders_svg_and_png() {
        let dir = temp_dir("render");
        let times: Vec<f64> = (0..200).map(|i| i as f64 * 0.01).collect();
        let panels = demo_panels(&times);

        let svg = dir.join("out.svg");
        let file = plot_time_series(&svg, "Pendulum response", &times, &panels).unwrap();
        assert_eq!(file.path, svg);
        let text = String::from_utf8(file.bytes).unwrap();
        assert!(text.starts_with("<svg"), "{}", &text[..40]);
        for needle in [
            "Pendulum response",
            "Coordinates",
            "u1 (gaps)",
            "t [s]",
            "q [m]",
        ] {
            assert!(text.contains(needle), "SVG lacks `{needle}`");
        }

        let png_path = dir.join("out.PNG");
        let bytes = plot_time_series(&png_path, "Pendulum response", &times, &panels)
            .unwrap()
            .bytes;
        assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"));
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn renders_xy_with_log_axis() {
        let dir = temp_dir("xy");
        let f: Vec<f64> = (0..100).map(|i| 10f64.powf(i as f64 / 33.0)).collect();
        let gain: Vec<f64> = f
            .iter()
            .map(|&f| {
                -10.0 * ((1.0 - (f / 10.0).powi(2)).powi(2) + (0.2 * f / 10.0).powi(2)).log10()
            })
            .collect();
        let mut with_zero = f.clone();
        with_zero[0] = 0.0; // not drawable on a log axis: skipped
        let curves = vec![
            ("ζ = 0.1".to_string(), f.clone(), gain.clone()),
            (
                "shifted".to_string(),
                with_zero,
                gain.iter().map(|g| g - 3.0).collect(),
            ),
        ];
        let mut bode_svg = String::new();
        for name in ["bode.svg", "bode.png"] {
            let path = dir.join(name);
            let file = plot_xy(
                &path,
                "Frequency response",
                "f [Hz]",
                "|G| [dB]",
                &curves,
                true,
            )
            .unwrap();
            assert!(file.bytes.len() > 1000);
            if name.ends_with("svg") {
                bode_svg = String::from_utf8(file.bytes).unwrap();
            }
        }
        plot_xy(&dir.join("lin.svg"), "Linear", "x", "y", &curves, false).unwrap();
        let text = bode_svg;
        assert!(text.contains("Frequency response") && text.contains("f [Hz]"));
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn degenerate_data_does_not_panic() {
        let dir = temp_dir("degenerate");
        let panels = |values: Vec<f64>| {
            vec![Panel {
                title: "p".into(),
                y_label: "y".into(),
                series: vec![Series {
                    name: String::new(),
                    values,
                }],
            }]
        };
        let path = dir.join("d.png");
        plot_time_series(&path, "one", &[0.0], &panels(vec![1.0])).unwrap();
        plot_time_series(&path, "nan", &[0.0, 1.0], &panels(vec![f64::NAN; 2])).unwrap();
        plot_time_series(&path, "zero", &[0.0, 1.0], &panels(vec![0.0; 2])).unwrap();
        plot_time_series(&path, "tiny", &[0.0, 1.0], &panels(vec![1e-9, 1e-9])).unwrap();
        plot_time_series(&path, "huge", &[0.0, 1.0], &panels(vec![-1e300, 1e300])).unwrap();
        plot_time_series(&path, "empty", &[], &panels(vec![])).unwrap();
        let no_series = [Panel {
            title: "none".into(),
            y_label: "y".into(),
            series: vec![],
        }];
        plot_time_series(&dir.join("n.svg"), "none", &[0.0, 1.0], &no_series).unwrap();
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn errors() {
        let dir = temp_dir("errors");
        let times = [0.0, 1.0];
        let panels = demo_panels(&(0..30).map(f64::from).collect::<Vec<_>>());

        let bad = dir.join("out.jpg");
        let error = plot_time_series(&bad, "t", &times, &[]).unwrap_err();
        assert!(matches!(error.kind, PlotErrorKind::UnsupportedFormat));
        let message = error.to_string();
        assert!(
            message.contains("out.jpg") && message.contains("`.svg` or `.png`"),
            "{message}"
        );
        assert!(plot_xy(&dir.join("noext"), "t", "x", "y", &[], false).is_err());

        let error = plot_time_series(&dir.join("a.svg"), "t", &times, &panels).unwrap_err();
        assert_eq!(
            error.to_string(),
            format!(
                "cannot plot to `{}`: series `q1` of panel `Coordinates` has 30 values but there are 2 times",
                dir.join("a.svg").display()
            )
        );
        let error = plot_time_series(&dir.join("a.svg"), "t", &times, &[]).unwrap_err();
        assert!(error.to_string().contains("no panels"));

        let curves = [("c".to_string(), vec![-1.0, 0.0], vec![1.0, 2.0])];
        let error = plot_xy(&dir.join("b.png"), "t", "x", "y", &curves, true).unwrap_err();
        assert!(error.to_string().contains("positive x"), "{error}");
        let ragged = [("c".to_string(), vec![1.0], vec![1.0, 2.0])];
        let error = plot_xy(&dir.join("b.png"), "t", "x", "y", &ragged, false).unwrap_err();
        assert!(error.to_string().contains("1 x values but 2 y values"));
        assert!(
            fs::read_dir(&dir).unwrap().next().is_none(),
            "no files written"
        );
        let _ = fs::remove_dir_all(&dir);
    }

    /// The pixel points of the SVG polylines with more than two points (curves, not legend
    /// samples or ticks).
    fn svg_curves(svg: &str) -> Vec<Vec<(f64, f64)>> {
        svg.split("points=\"")
            .skip(1)
            .map(|rest| {
                let points = &rest[..rest.find('"').unwrap()];
                points
                    .split_whitespace()
                    .map(|pair| {
                        let (x, y) = pair.split_once(',').unwrap();
                        (x.parse().unwrap(), y.parse().unwrap())
                    })
                    .collect::<Vec<(f64, f64)>>()
            })
            .filter(|points| points.len() > 2)
            .collect()
    }

    /// The x pixel of the SVG text element that holds `text`.
    fn svg_text_x(svg: &str, text: &str) -> f64 {
        let at = svg.find(text).unwrap_or_else(|| panic!("no `{text}`"));
        let start = svg[..at].rfind("<text x=\"").unwrap() + "<text x=\"".len();
        let end = start + svg[start..].find('"').unwrap();
        svg[start..end].parse().unwrap()
    }

    /// A circle keeps its shape with `equal_scale` (as many pixels across as up) and not
    /// without it, on a wide figure; its legend is right of every point of the data.
    #[test]
    fn equal_scale_and_legend_outside_the_data() {
        let dir = temp_dir("equal");
        let angles = (0..=72).map(|k| std::f64::consts::TAU * k as f64 / 72.0);
        let (xs, ys): (Vec<f64>, Vec<f64>) = angles.map(|a| (a.cos(), a.sin())).unzip();
        let curves = [("unit circle".to_string(), xs, ys)];
        let extent = |equal_scale: bool| {
            let plot = XyPlot {
                equal_scale,
                ..XyPlot::new("circle", "x [m]", "y [m]", &curves)
            };
            let svg = String::from_utf8(plot.render(&dir.join("c.svg")).unwrap().bytes).unwrap();
            let points = svg_curves(&svg).concat();
            let span = |pick: fn(&(f64, f64)) -> f64| {
                let values = points.iter().map(pick);
                values.clone().fold(f64::MIN, f64::max) - values.fold(f64::MAX, f64::min)
            };
            let right = points.iter().map(|p| p.0).fold(f64::MIN, f64::max);
            assert!(
                svg_text_x(&svg, "unit circle") > right + 20.0,
                "legend over the data"
            );
            (span(|p| p.0), span(|p| p.1))
        };
        let (width, height) = extent(true);
        assert!((width - height).abs() <= 2.0, "{width} × {height} px");
        let (width, height) = extent(false);
        assert!(width > 1.3 * height, "{width} × {height} px");
        let _ = fs::remove_dir_all(&dir);
    }

    /// Measured points are markers (filled, then outlined) with their error bars, and the
    /// axes reach the bars' ends: a bar of ±5 around 10 over a curve below 1 takes the axis
    /// to 15 (ticks to 14; to 10 without the bar).
    #[test]
    fn measured_points_with_error_bars() {
        let dir = temp_dir("measured");
        let curves = [("model".to_string(), vec![0.0, 2.0], vec![0.0, 1.0])];
        let measured = [Measured {
            name: "paper (± s.d.)".into(),
            color: 0,
            points: vec![
                ErrorPoint {
                    x: 1.0,
                    y: 10.0,
                    x_error: 0.0,
                    y_error: 5.0,
                },
                ErrorPoint {
                    x: 1.5,
                    y: 0.5,
                    ..ErrorPoint::default()
                },
            ],
        }];
        let plot = XyPlot {
            measured: &measured,
            ..XyPlot::new("measured", "x", "y", &curves)
        };
        let svg = String::from_utf8(plot.render(&dir.join("m.svg")).unwrap().bytes).unwrap();
        assert_eq!(svg.matches("<circle").count(), 2 * (2 + 1), "{svg}");
        assert!(svg.contains("paper (± s.d.)"));
        assert!(svg.contains(">\n14\n<"), "no tick at 14: the bar is cut");
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn tick_labels() {
        assert_eq!(linear_tick(0.5, &(0.0..1.0)), "0.5");
        assert_eq!(linear_tick(0.0, &(-1.0..1.0)), "0.0");
        assert_eq!(linear_tick(200.0, &(0.0..1000.0)), "200");
        assert_eq!(linear_tick(2e-6, &(0.0..1e-5)), "2e-6");
        assert_eq!(linear_tick(-4e7, &(-5e7..5e7)), "-4e7");
        assert_eq!(significant(1000.0, 3), "1000");
        assert_eq!(significant(0.2, 3), "0.2");
        assert_eq!(significant(1e6, 3), "1e6");
        assert_eq!(significant(123456.0, 3), "1.23e5");
    }

    #[test]
    fn segments_break_at_non_finite_points() {
        let xs = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
        let ys = [0.0, f64::NAN, 2.0, 3.0, f64::INFINITY, 5.0];
        let segments = finite_segments(&xs, &ys, |_| true);
        assert_eq!(
            segments,
            vec![
                vec![(0.0, 0.0), (0.0, 0.0)],
                vec![(2.0, 2.0), (3.0, 3.0)],
                vec![(5.0, 5.0), (5.0, 5.0)],
            ]
        );
    }
}
