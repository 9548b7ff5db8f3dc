//! Verification harness: convergence-study results, their files and plots,
//! and the Markdown summary of the latest runs.
//!
//! A study (e.g. a manufactured-solution convergence test) produces a
//! [`StudyResult`]: one [`Series`] per method/quantity, each a list of
//! [`Point`]s `(h, error, wall_s, updates_per_s)` and the observed order of
//! convergence from [`fit_order`]. [`write_study`] stores it as JSON, CSV
//! and a log-log PNG; [`write_results_md`] collects every stored study into
//! the Markdown table committed as `RESULTS.md`. [`plot_xy`] is the generic
//! plotting helper that work-precision and paper figures reuse.
//!
//! # Non-finite numbers
//! JSON has no NaN or infinity. Every `f64` field of the result types is
//! written as `null` when it is not finite, and `null` reads back as NaN.
//! The JSON is therefore also readable by consumers that model these fields
//! as `Option<f64>` (`null` ↔ `None`), and by Python's `json` (`None`).
//!
//! Floats are written in shortest round-trip form, but serde_json parses
//! them exactly only with its `float_roundtrip` feature; without it a value
//! read back from the JSON may differ from the written one by 1 ulp. The
//! CSV written by [`write_study`] is always bit-exact.
//!
//! This module depends on nothing else in `mpmice`; all file writes are atomic
//! (temporary sibling + rename).

use std::fmt::Write as _;
use std::fs::{self, File};
use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use crate::output::fmt_f64;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use serde::{Deserialize, Serialize};

/// The result of one verification study, stored as `STUDY.json`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StudyResult {
    /// Study name; also the stem of its output files and the plot title.
    pub study: String,
    /// One series per method, quantity or norm.
    pub series: Vec<Series>,
    /// Free-form remarks (parameters, caveats); omitted from the JSON when
    /// empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    /// What `h` is, with its unit, e.g. `"cell size Δx [m]"` or
    /// `"particle spacing h [cells]"`; the x-axis label of the study's plot. Empty (and
    /// omitted from the JSON) when unknown: the plot then falls back to a
    /// generic label.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub h_axis: String,
    /// What `error` is, with its unit, e.g. `"L1 density error [kg/m³]"`
    /// or `"relative error [-]"`; the y-axis label of the study's plot. Empty
    /// (and omitted from the JSON) when unknown: the plot then falls back to
    /// a generic label.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub error_axis: String,
}

/// One convergence series: errors of one quantity in one norm against `h`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Series {
    /// Legend label, e.g. `"MPM velocity"`.
    pub label: String,
    /// Norm of the error, e.g. `"L2"` or `"Linf"`.
    pub norm: String,
    /// The measurements, in any order.
    pub points: Vec<Point>,
    /// Least-squares order from [`fit_order`]; NaN (JSON `null`) when it
    /// cannot be fitted.
    #[serde(with = "finite_or_null")]
    pub observed_order: f64,
}

impl Series {
    /// A series whose `observed_order` is fitted from `points`.
    pub fn new(label: impl Into<String>, norm: impl Into<String>, points: Vec<Point>) -> Self {
        let observed_order = fit_order(&points);
        Series {
            label: label.into(),
            norm: norm.into(),
            points,
            observed_order,
        }
    }
}

/// One measurement of a convergence series.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Point {
    /// Resolution (cell size, time step, ...).
    #[serde(with = "finite_or_null")]
    pub h: f64,
    /// Error in the series' norm.
    #[serde(with = "finite_or_null")]
    pub error: f64,
    /// Wall-clock time of the run in seconds.
    #[serde(with = "finite_or_null")]
    pub wall_s: f64,
    /// Throughput of the run (e.g. particle or cell updates per second).
    #[serde(with = "finite_or_null")]
    pub updates_per_s: f64,
    /// Study-specific numbers (e.g. energy drift); omitted when empty.
    #[serde(default, skip_serializing_if = "serde_json::Map::is_empty")]
    pub extra: serde_json::Map<String, serde_json::Value>,
}

impl Point {
    /// A point without extra numbers.
    pub fn new(h: f64, error: f64, wall_s: f64, updates_per_s: f64) -> Self {
        Point {
            h,
            error,
            wall_s,
            updates_per_s,
            extra: serde_json::Map::new(),
        }
    }

    /// Adds a study-specific number (non-finite values are stored as
    /// `null`).
    pub fn with_extra(mut self, key: impl Into<String>, value: f64) -> Self {
        let v = serde_json::Number::from_f64(value)
            .map_or(serde_json::Value::Null, serde_json::Value::Number);
        self.extra.insert(key.into(), v);
        self
    }
}

/// Serde adapter for an `f64` field: non-finite values are written as
/// `null`, and `null` reads back as NaN. Use with
/// `#[serde(with = "finite_or_null")]`.
pub mod finite_or_null {
    use serde::{Deserialize, Deserializer, Serializer};

    /// Writes `value`, or `null` when it is NaN or infinite.
    pub fn serialize<S: Serializer>(value: &f64, s: S) -> Result<S::Ok, S::Error> {
        if value.is_finite() {
            s.serialize_f64(*value)
        } else {
            s.serialize_none()
        }
    }

    /// Reads a number, or `null` as NaN.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}

/// Observed order of convergence: the least-squares slope of `ln(error)`
/// against `ln(h)`.
///
/// Points whose `h` or `error` is not finite and positive are skipped.
/// Returns NaN when fewer than two valid points remain or all valid points
/// share one `h`.
pub fn fit_order(points: &[Point]) -> f64 {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.h.is_finite() && p.h > 0.0 && p.error.is_finite() && p.error > 0.0)
        .map(|p| (p.h.ln(), p.error.ln()))
        .collect();
    fit_line(&logs).map_or(f64::NAN, |(slope, _)| slope)
}

/// Least-squares line `y = a + b x` through `points`: `Some((b, a))`, or
/// `None` when there are fewer than two points or all share one `x`.
/// [`fit_order`] is this on `(ln h, ln error)`.
pub fn fit_line(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    if points.len() < 2 {
        return None;
    }
    let n = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = points.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    (sxx > 0.0).then(|| {
        let slope = sxy / sxx;
        (slope, my - slope * mx)
    })
}

/// File stem for a study name: characters other than ASCII letters,
/// digits, `-`, `_` and `.` become `_`.
fn study_stem(study: &str) -> Result<String> {
    let stem: String = study
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    if stem.is_empty() || stem.chars().all(|c| c == '.') {
        bail!("study name {study:?} cannot be used as a file name");
    }
    Ok(stem)
}

/// Quotes a CSV cell if needed (RFC 4180).
fn csv_cell(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Writes `dir/STUDY.json` (pretty), `dir/STUDY.csv` and `dir/STUDY.png`,
/// where `STUDY` is `result.study` with characters other than ASCII
/// letters, digits, `-`, `_`, `.` replaced by `_`. Creates `dir` if needed.
///
/// The CSV has the columns `series,norm,h,error,wall_s,updates_per_s`, one
/// row per point. The PNG is a log-log plot of error against `h` with one
/// line-and-markers series per [`Series`] (points sorted by `h`), labelled
/// with the series label, norm and observed order, and [`plot_xy`]'s
/// reference slope triangle; its axes are labelled with
/// [`StudyResult::h_axis`] and [`StudyResult::error_axis`] (generic labels
/// where these are empty). Every file is written atomically.
///
/// # Errors
/// An unusable study name, or any I/O, serialisation or plotting error.
pub fn write_study(dir: &Path, result: &StudyResult) -> Result<()> {
    let stem = study_stem(&result.study)?;
    fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;

    let mut json = serde_json::to_vec_pretty(result).context("serialising study")?;
    json.push(b'\n');
    atomic_write_bytes(&dir.join(format!("{stem}.json")), &json)?;

    let mut csv = String::from("series,norm,h,error,wall_s,updates_per_s\n");
    for s in &result.series {
        for p in &s.points {
            let _ = writeln!(
                csv,
                "{},{},{},{},{},{}",
                csv_cell(&s.label),
                csv_cell(&s.norm),
                fmt_f64(p.h),
                fmt_f64(p.error),
                fmt_f64(p.wall_s),
                fmt_f64(p.updates_per_s)
            );
        }
    }
    atomic_write_bytes(&dir.join(format!("{stem}.csv")), csv.as_bytes())?;

    let plot_series: Vec<PlotSeries> = result
        .series
        .iter()
        .map(|s| {
            let mut points: Vec<(f64, f64)> = s.points.iter().map(|p| (p.h, p.error)).collect();
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            let order = if s.observed_order.is_finite() {
                format!("{:.2}", s.observed_order)
            } else {
                "n/a".to_string()
            };
            PlotSeries {
                label: format!("{} ({}), order {order}", s.label, s.norm),
                points,
                style: Style::LineMarkers,
            }
        })
        .collect();
    let x_label = if result.h_axis.is_empty() {
        "h (resolution, in the study's units)"
    } else {
        result.h_axis.as_str()
    };
    let y_label = if result.error_axis.is_empty() {
        "error (norm in the legend)"
    } else {
        result.error_axis.as_str()
    };
    plot_xy(
        &dir.join(format!("{stem}.png")),
        &result.study,
        x_label,
        y_label,
        true,
        true,
        &plot_series,
    )
}

/// The reference slope triangle that [`plot_xy`] adds to a log-log plot:
/// slope the median of the least-squares slopes of `ln y` on `ln x`
/// ([`fit_line`]) of the labelled series with two distinct positive `x`
/// (the upper one of an even count), rounded to the nearest half (at least
/// ½ in size, sign kept), spanning a factor 2 in `x` from those series'
/// smallest `x`, starting below the smallest `y` of all series (so it
/// covers no data). Points that are not finite and positive are ignored.
/// `None` without such a series.
pub fn slope_triangle(series: &[PlotSeries]) -> Option<PlotSeries> {
    let positive = |p: &&(f64, f64)| p.0.is_finite() && p.0 > 0.0 && p.1.is_finite() && p.1 > 0.0;
    let fits: Vec<(f64, f64)> = series
        .iter()
        .filter(|s| !s.label.is_empty())
        .filter_map(|s| {
            let logs: Vec<(f64, f64)> = s
                .points
                .iter()
                .filter(positive)
                .map(|p| (p.0.ln(), p.1.ln()))
                .collect();
            let (slope, _) = fit_line(&logs)?;
            let x0 = logs.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
            Some((slope, x0.exp()))
        })
        .collect();
    let mut slopes: Vec<f64> = fits.iter().map(|f| f.0).collect();
    slopes.sort_by(f64::total_cmp);
    let slope = *slopes.get(slopes.len() / 2)?;
    let x0 = fits.iter().map(|f| f.1).fold(f64::INFINITY, f64::min);
    let y_min = series
        .iter()
        .flat_map(|s| s.points.iter().filter(positive))
        .map(|p| p.1)
        .fold(f64::INFINITY, f64::min);
    let rounded = (slope * 2.0).round() / 2.0;
    let order = if rounded.abs() < 0.5 {
        0.5f64.copysign(slope)
    } else {
        rounded
    };
    let (x1, y0) = (2.0 * x0, 0.4 * y_min);
    let y1 = y0 * 2f64.powf(order);
    Some(PlotSeries {
        label: format!("slope {order}"),
        points: vec![(x0, y0), (x1, y0), (x1, y1), (x0, y0)],
        style: Style::Line,
    })
}

/// How a [`PlotSeries`] is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// A polyline through the points, in the given order.
    Line,
    /// A marker at each point.
    Markers,
    /// Both.
    LineMarkers,
}

/// One data series of [`plot_xy`].
#[derive(Clone, Debug, PartialEq)]
pub struct PlotSeries {
    /// Legend entry (no legend entry when empty).
    pub label: String,
    /// `(x, y)` points, drawn in this order.
    pub points: Vec<(f64, f64)>,
    /// Line, markers or both.
    pub style: Style,
}

/// Plot width and height in pixels.
const PLOT_SIZE: (u32, u32) = (1000, 750);
/// Margin around a chart, pixels.
const MARGIN: u32 = 25;
/// Height of the x-axis label area and width of the y-axis one, pixels.
const LABEL_AREA: (u32, u32) = (60, 95);
/// Title font size, pixels (the title takes 10 px more height).
const TITLE_FONT: u32 = 30;
/// Legend font size, pixels.
const LEGEND_FONT: u32 = 18;
/// Width of the colour bar beside a field plot, pixels.
const COLOR_BAR_WIDTH: u32 = 170;
/// Where a legend may go, in order of preference (corners first).
const LEGEND_POSITIONS: [SeriesLabelPosition; 8] = [
    SeriesLabelPosition::UpperLeft,
    SeriesLabelPosition::UpperRight,
    SeriesLabelPosition::LowerLeft,
    SeriesLabelPosition::LowerRight,
    SeriesLabelPosition::UpperMiddle,
    SeriesLabelPosition::LowerMiddle,
    SeriesLabelPosition::MiddleLeft,
    SeriesLabelPosition::MiddleRight,
];

/// Series colours (the "tab10" palette).
const COLORS: [RGBColor; 10] = [
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

/// Draws a 1000×750 PNG line/marker plot at `path` (written atomically;
/// taller when the legend goes below the chart, see below).
///
/// Points that are not finite, or not positive on a logarithmic axis, are
/// skipped. Axis ranges cover the remaining points with padding (5% of the
/// span, or of the decades on a log axis; a single value gets a default
/// width). Empty input still gives a valid (empty) plot. If text cannot be
/// rendered (no usable system font), the plot is drawn without title, axis
/// labels and legend instead of failing, and a warning goes to stderr.
///
/// A log-log plot gets a reference [`slope_triangle`] (a legend entry
/// `slope p`). The legend goes to the corner (or, failing that, the edge
/// middle) whose box covers the fewest data points and line samples; when
/// every place would cover some, the top of the y range is raised until
/// the legend fits above the data, or, for a legend taller than 70 % of
/// the chart, the legend goes in a panel below the chart.
///
/// # Errors
/// Any I/O or drawing error other than a text-rendering failure.
pub fn plot_xy(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    log_x: bool,
    log_y: bool,
    series: &[PlotSeries],
) -> Result<()> {
    let keep = |&(x, y): &(f64, f64)| {
        x.is_finite() && y.is_finite() && (!log_x || x > 0.0) && (!log_y || y > 0.0)
    };
    let mut cleaned: Vec<PlotSeries> = series
        .iter()
        .map(|s| PlotSeries {
            label: s.label.clone(),
            points: s.points.iter().copied().filter(keep).collect(),
            style: s.style,
        })
        .collect();
    if log_x && log_y {
        cleaned.extend(slope_triangle(&cleaned));
    }
    let x_range = axis_range(
        cleaned.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
        log_x,
    );
    let y_range = axis_range(
        cleaned.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
        log_y,
    );
    let mut plot = Plot {
        title,
        x_label,
        y_label,
        log_x,
        log_y,
        x_range,
        y_range,
        series: &cleaned,
        field: None,
    };
    plot.make_room_for_legend();
    plot.write_atomically(path)
}

/// Padded `(min, max)` of the values (already filtered for the axis type).
fn axis_range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    let range = if lo > hi {
        // No data.
        if log {
            (1.0, 10.0)
        } else {
            (0.0, 1.0)
        }
    } else if log {
        let decades = (hi / lo).log10();
        let pad = if decades > 0.0 { 0.05 * decades } else { 0.5 };
        let f = 10f64.powf(pad);
        (lo / f, hi * f)
    } else {
        let span = hi - lo;
        let pad = if span > 0.0 {
            0.05 * span
        } else if lo != 0.0 {
            0.1 * lo.abs()
        } else {
            1.0
        };
        (lo - pad, hi + pad)
    };
    let ok = range.0.is_finite() && range.1.is_finite() && range.0 < range.1;
    match (ok, log) {
        (true, _) => range,
        // Degenerate (overflowing or subnormal) data: fall back to the raw
        // bounds when usable, else a default.
        (false, _) if lo.is_finite() && hi.is_finite() && lo < hi => (lo, hi),
        (false, true) => (1.0, 10.0),
        (false, false) => (-1.0, 1.0),
    }
}

/// Tick label for a linear axis spanning `span` (pass 0 for a log axis):
/// values below `1e-9 · span` are shown as 0 (round-off of tick
/// generation), otherwise a few significant digits (enough to resolve a
/// tenth of the span), trailing zeros removed.
fn tick_label(v: f64, span: f64) -> String {
    fn trim(s: &str) -> &str {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.')
        } else {
            s
        }
    }
    let a = v.abs();
    if v == 0.0 || a < 1e-9 * span {
        "0".to_string()
    } else if (1e-2..1e4).contains(&a) {
        let by_value = 3 - a.log10().floor() as i32;
        let by_span = if span > 0.0 && span.is_finite() {
            (-(span / 10.0).log10()).ceil() as i32
        } else {
            0
        };
        let decimals = by_value.max(by_span).clamp(0, 12) as usize;
        trim(&format!("{v:.decimals$}")).to_string()
    } else {
        let s = format!("{v:.2e}");
        match s.split_once('e') {
            Some((m, e)) => format!("{}e{e}", trim(m)),
            None => s,
        }
    }
}

/// Labelled ("bold") and grid-only ("light") ticks of a log axis over
/// `[lo, hi]`: powers of ten (every few when there are many decades), plus
/// 2 and 5 times them over one to a few decades, or every integer mantissa
/// within less than a decade; linear ticks when that leaves fewer than two.
fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    let decades = (hi / lo).log10();
    let k0 = lo.log10().floor() as i32;
    let k1 = hi.log10().ceil() as i32;
    let step = if decades > 8.0 {
        (decades / 8.0).ceil() as i32
    } else {
        1
    };
    let bold_m: &[u32] = if decades > 2.5 {
        &[1]
    } else if decades >= 0.9 {
        &[1, 2, 5]
    } else {
        &[1, 2, 3, 4, 5, 6, 7, 8, 9]
    };
    let (mut bold, mut light) = (Vec::new(), Vec::new());
    for k in k0..=k1 {
        let labelled = k.rem_euclid(step) == 0;
        for m in 1..=9u32 {
            // Parsing "me k" gives the exact decimal value (no 0.30000000000000004).
            let Ok(v) = format!("{m}e{k}").parse::<f64>() else {
                continue;
            };
            if v < lo || v > hi {
                continue;
            }
            if labelled && bold_m.contains(&m) {
                bold.push(v);
            } else if m == 1 || decades <= 5.0 {
                light.push(v);
            }
        }
    }
    if bold.len() < 2 {
        bold = linear_ticks(lo, hi);
        light.clear();
    }
    (bold, light)
}

/// About five "nice" (1, 2, 5 × 10^k spaced) ticks within `[lo, hi]`.
fn linear_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let raw = (hi - lo) / 5.0;
    if !(raw > 0.0 && raw.is_finite()) {
        return vec![lo, hi];
    }
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|i| i as f64 * step).collect()
}

/// Everything needed to draw one plot.
struct Plot<'a> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    log_x: bool,
    log_y: bool,
    x_range: (f64, f64),
    y_range: (f64, f64),
    series: &'a [PlotSeries],
    /// A cell field drawn under the series (linear axes only).
    field: Option<FieldLayer<'a>>,
}

/// The cell field of a [`plot_field`] plot.
#[derive(Clone, Copy)]
struct FieldLayer<'a> {
    field: &'a CellField,
    /// Range of its finite values (the colour scale).
    range: (f64, f64),
    /// Name and unit of the values (the colour bar's label).
    label: &'a str,
}

/// A scalar field on a uniform grid of cells for [`plot_field`]: cell
/// `(i, j)` spans `[x0 + i dx, x0 + (i + 1) dx] × [y0 + j dy, …]` and holds
/// `values[i + nx j]`.
#[derive(Debug, Clone)]
pub struct CellField {
    /// Lower corner of the grid.
    pub lower: (f64, f64),
    /// Cell size.
    pub h: (f64, f64),
    /// Cells per direction.
    pub cells: (usize, usize),
    /// Values, x fastest.
    pub values: Vec<f64>,
}

impl CellField {
    /// Blue (min) → white → red (max) for `v` on `[lo, hi]`.
    fn color(v: f64, lo: f64, hi: f64) -> RGBColor {
        let t = if hi > lo {
            ((v - lo) / (hi - lo)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let mix = |a: f64, b: f64, t: f64| (a + (b - a) * t).round() as u8;
        if t < 0.5 {
            let u = 2.0 * t;
            RGBColor(
                mix(40.0, 255.0, u),
                mix(70.0, 255.0, u),
                mix(200.0, 255.0, u),
            )
        } else {
            let u = 2.0 * t - 1.0;
            RGBColor(
                mix(255.0, 200.0, u),
                mix(255.0, 30.0, u),
                mix(255.0, 30.0, u),
            )
        }
    }
}

/// Draws a 1000×750 PNG of a cell field (colour scale blue → white → red
/// from its smallest to its largest finite value, shown by a colour bar on
/// the right with ticks, labelled `value_label` (name and unit, e.g.
/// `"p [Pa]"`), the exact minimum written below it and the maximum above)
/// with line/marker series on top, at `path` (written atomically, as
/// [`plot_xy`]; the legend avoids the series).
///
/// # Errors
/// Any I/O or drawing error other than a text-rendering failure.
pub fn plot_field(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    value_label: &str,
    field: &CellField,
    series: &[PlotSeries],
) -> Result<()> {
    let (nx, ny) = field.cells;
    let x_range = (field.lower.0, field.lower.0 + nx as f64 * field.h.0);
    let y_range = (field.lower.1, field.lower.1 + ny as f64 * field.h.1);
    let range = field
        .values
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let plot = Plot {
        title,
        x_label,
        y_label,
        log_x: false,
        log_y: false,
        x_range,
        y_range,
        series,
        field: Some(FieldLayer {
            field,
            range,
            label: value_label,
        }),
    };
    plot.write_atomically(path)
}

/// Estimated size `(width, height)` in pixels of the legend of `series`
/// (a generous 0.62 em per character of the longest label); `None` when no
/// series has a label.
fn legend_size(series: &[PlotSeries]) -> Option<(f64, f64)> {
    let labels = series.iter().filter(|s| !s.label.is_empty());
    let entries = labels.clone().count();
    let chars = labels.map(|s| s.label.chars().count()).max()?;
    let font = f64::from(LEGEND_FONT);
    // plotters: 30 px for the glyph, a 10 px margin all round, 1.25 em lines.
    Some((
        0.62 * font * chars as f64 + 50.0,
        1.25 * font * entries as f64 + 20.0,
    ))
}

/// Top-left corner of a legend box of `size` at `pos` in a plotting area
/// of `area` pixels (as plotters lays it out: 5 px from the edges).
fn legend_corner(pos: &SeriesLabelPosition, size: (f64, f64), area: (u32, u32)) -> (f64, f64) {
    use SeriesLabelPosition::*;
    let (w, h) = (f64::from(area.0), f64::from(area.1));
    let x = match pos {
        UpperLeft | MiddleLeft | LowerLeft => 5.0,
        UpperRight | MiddleRight | LowerRight => w - size.0 - 5.0,
        _ => (w - size.0) / 2.0,
    };
    let y = match pos {
        UpperLeft | UpperMiddle | UpperRight => 5.0,
        LowerLeft | LowerMiddle | LowerRight => h - size.1 - 5.0,
        _ => (h - size.1) / 2.0,
    };
    (x, y)
}

/// Raises `range`'s top so that its old extent fills the lower `1 − free`
/// of the axis (in log space on a log axis).
fn raise_top((lo, hi): (f64, f64), log: bool, free: f64) -> (f64, f64) {
    if log {
        (lo, lo * (hi / lo).powf(1.0 / (1.0 - free)))
    } else {
        (lo, lo + (hi - lo) / (1.0 - free))
    }
}

impl Plot<'_> {
    /// Size in pixels of the plotting area (inside the axes) of a plot
    /// without a field, as `render_in` lays it out with text.
    const AREA: (u32, u32) = (
        PLOT_SIZE.0 - 2 * MARGIN - LABEL_AREA.1,
        PLOT_SIZE.1 - (TITLE_FONT + 10) - 2 * MARGIN - LABEL_AREA.0,
    );

    /// [`Plot::AREA`], less the colour bar of a field plot.
    fn area_estimate(&self) -> (u32, u32) {
        let bar = if self.field.is_some() {
            COLOR_BAR_WIDTH
        } else {
            0
        };
        (Self::AREA.0 - bar, Self::AREA.1)
    }

    /// Height of the panel below the chart that holds the legend when it
    /// would cover data anywhere inside (0 when it fits inside, or with
    /// no `text`).
    fn legend_panel(&self, text: bool) -> u32 {
        match legend_size(self.series) {
            Some((_, h)) if text && self.legend_position(self.area_estimate()).1 > 0 => {
                h.ceil() as u32 + 10
            }
            _ => 0,
        }
    }

    /// Pixel position of a data point in a plotting area of `area` pixels
    /// (origin top left).
    fn to_pixel(&self, (x, y): (f64, f64), area: (u32, u32)) -> (f64, f64) {
        let frac = |v: f64, (lo, hi): (f64, f64), log: bool| {
            if log {
                (v / lo).ln() / (hi / lo).ln()
            } else {
                (v - lo) / (hi - lo)
            }
        };
        (
            frac(x, self.x_range, self.log_x) * f64::from(area.0),
            (1.0 - frac(y, self.y_range, self.log_y)) * f64::from(area.1),
        )
    }

    /// Pixel positions of every data point, and of samples every 4 px
    /// along the lines of line series.
    fn data_pixels(&self, area: (u32, u32)) -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        for s in self.series {
            let px: Vec<(f64, f64)> = s.points.iter().map(|&p| self.to_pixel(p, area)).collect();
            out.extend(&px);
            if s.style == Style::Markers {
                continue;
            }
            for w in px.windows(2) {
                let (dx, dy) = (w[1].0 - w[0].0, w[1].1 - w[0].1);
                // NaN (a non-finite point) casts to 0 steps.
                let steps = (dx.hypot(dy) / 4.0).ceil().min(1e4) as usize;
                out.extend((1..steps).map(|k| {
                    let t = k as f64 / steps as f64;
                    (w[0].0 + t * dx, w[0].1 + t * dy)
                }));
            }
        }
        out
    }

    /// The legend position (of [`LEGEND_POSITIONS`], the first on a tie)
    /// whose box covers the fewest data pixels, with that number, in a
    /// plotting area of `area` pixels. A point within 6 px of the box (a
    /// marker's radius, a line's width) counts as covered.
    fn legend_position(&self, area: (u32, u32)) -> (SeriesLabelPosition, usize) {
        let Some(size) = legend_size(self.series) else {
            return (SeriesLabelPosition::UpperLeft, 0);
        };
        let pixels = self.data_pixels(area);
        let covered = |pos: &SeriesLabelPosition| {
            let (x0, y0) = legend_corner(pos, size, area);
            let (x1, y1) = (x0 + size.0, y0 + size.1);
            pixels
                .iter()
                .filter(|p| p.0 > x0 - 6.0 && p.0 < x1 + 6.0 && p.1 > y0 - 6.0 && p.1 < y1 + 6.0)
                .count()
        };
        LEGEND_POSITIONS
            .iter()
            .map(|pos| (pos.clone(), covered(pos)))
            .min_by_key(|c| c.1)
            .unwrap_or((SeriesLabelPosition::UpperLeft, 0))
    }

    /// When the legend would cover data wherever it goes, raises the top of
    /// the y range so that it fits above the data (unless that would take
    /// more than 70 % of the height: then it goes below the chart).
    fn make_room_for_legend(&mut self) {
        let Some((_, height)) = legend_size(self.series) else {
            return;
        };
        let area = self.area_estimate();
        if self.legend_position(area).1 == 0 {
            return;
        }
        let free = (height + 15.0) / f64::from(area.1);
        if free < 0.7 {
            self.y_range = raise_top(self.y_range, self.log_y, free);
        }
    }

    /// Renders to a temporary sibling of `path` and renames it into place.
    fn write_atomically(&self, path: &Path) -> Result<()> {
        let tmp = tmp_sibling(path, ".png")?;
        let result = self.render_with_fallback(&tmp).and_then(|()| {
            File::open(&tmp)
                .and_then(|f| f.sync_all())
                .with_context(|| format!("syncing {}", tmp.display()))?;
            fs::rename(&tmp, path).with_context(|| format!("renaming to {}", path.display()))
        });
        if result.is_err() {
            let _ = fs::remove_file(&tmp);
        }
        result
    }

    /// Renders with text; on failure (error or panic inside the font
    /// machinery) renders again without any text.
    fn render_with_fallback(&self, path: &Path) -> Result<()> {
        let with_text =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| self.render(path, true)));
        let err = match with_text {
            Ok(Ok(())) => return Ok(()),
            Ok(Err(e)) => e.to_string(),
            Err(_) => "panic while drawing text".to_string(),
        };
        eprintln!(
            "warning: plot {} drawn without text ({err})",
            path.display()
        );
        self.render(path, false)
    }

    /// Renders to `path` (PNG, chosen by the `.png` extension).
    fn render(&self, path: &Path, text: bool) -> Result<()> {
        let (x0, x1) = self.x_range;
        let (y0, y1) = self.y_range;
        let log_axis = |lo: f64, hi: f64| {
            let (bold, light) = log_ticks(lo, hi);
            (lo..hi)
                .log_scale()
                .with_key_points(bold)
                .with_light_points(light)
        };
        match (self.log_x, self.log_y) {
            (false, false) => self.render_in(path, text, x0..x1, y0..y1),
            (true, false) => self.render_in(path, text, log_axis(x0, x1), y0..y1),
            (false, true) => self.render_in(path, text, x0..x1, log_axis(y0, y1)),
            (true, true) => self.render_in(path, text, log_axis(x0, x1), log_axis(y0, y1)),
        }
    }

    /// Renders into `path` with axes `x` and `y`: the title, a colour bar
    /// on the right for a field, then the chart, with the legend in a panel
    /// below (the image taller) when it would cover data inside.
    fn render_in<X, Y>(&self, path: &Path, text: bool, x: X, y: Y) -> Result<()>
    where
        X: AsRangedCoord<Value = f64>,
        Y: AsRangedCoord<Value = f64>,
        X::CoordDescType: ValueFormatter<f64>,
        Y::CoordDescType: ValueFormatter<f64>,
    {
        let panel = self.legend_panel(text);
        let size = (PLOT_SIZE.0, PLOT_SIZE.1 + panel);
        let root = BitMapBackend::new(path, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw_err(&e))?;
        let (top, bottom) = root.split_vertically(PLOT_SIZE.1);
        if panel > 0 {
            draw_legend_panel(&bottom, self.series)?;
        }
        let body = if text {
            top.titled(self.title, ("sans-serif", TITLE_FONT))
                .map_err(|e| draw_err(&e))?
        } else {
            top
        };
        let main = match self.field {
            Some(layer) => {
                let (main, bar) = body.split_horizontally(PLOT_SIZE.0 - COLOR_BAR_WIDTH);
                draw_color_bar(&bar, layer, text)?;
                main
            }
            None => body,
        };
        self.draw_chart(&main, text, panel > 0, x, y)?;
        root.present().map_err(|e| draw_err(&e))?;
        Ok(())
    }

    /// Draws the axes, the field's cells, the series and, unless `below`
    /// (then the legend has a panel of its own), the legend.
    fn draw_chart<X, Y>(
        &self,
        area: &BitMapArea<'_>,
        text: bool,
        below: bool,
        x: X,
        y: Y,
    ) -> Result<()>
    where
        X: AsRangedCoord<Value = f64>,
        Y: AsRangedCoord<Value = f64>,
        X::CoordDescType: ValueFormatter<f64>,
        Y::CoordDescType: ValueFormatter<f64>,
    {
        let mut chart = chart_builder(area, text)
            .build_cartesian_2d(x, y)
            .map_err(|e| draw_err(&e))?;
        if text {
            // Log axes: no round-off snapping (span 0 disables it).
            let span = |(lo, hi): (f64, f64), log: bool| if log { 0.0 } else { hi - lo };
            let x_span = span(self.x_range, self.log_x);
            let y_span = span(self.y_range, self.log_y);
            chart
                .configure_mesh()
                .x_desc(self.x_label)
                .y_desc(self.y_label)
                .x_label_formatter(&|v| tick_label(*v, x_span))
                .y_label_formatter(&|v| tick_label(*v, y_span))
                .light_line_style(BLACK.mix(0.06))
                .label_style(("sans-serif", 18))
                .axis_desc_style(("sans-serif", 22))
                .draw()
                .map_err(|e| draw_err(&e))?;
        }
        if let (Some(layer), false, false) = (self.field, self.log_x, self.log_y) {
            let (f, (lo, hi)) = (layer.field, layer.range);
            let (nx, ny) = f.cells;
            let cells = (0..nx * ny).map(|k| {
                let (i, j) = ((k % nx) as f64, (k / nx) as f64);
                let x = f.lower.0 + i * f.h.0;
                let y = f.lower.1 + j * f.h.1;
                Rectangle::new(
                    [(x, y), (x + f.h.0, y + f.h.1)],
                    CellField::color(f.values[k], lo, hi).filled(),
                )
            });
            chart.draw_series(cells).map_err(|e| draw_err(&e))?;
        }
        for (i, s) in self.series.iter().enumerate() {
            draw_one_series(&mut chart, s, COLORS[i % COLORS.len()], text)?;
        }
        if text && !below && self.series.iter().any(|s| !s.label.is_empty()) {
            let position = self.legend_position(chart.plotting_area().dim_in_pixel()).0;
            chart
                .configure_series_labels()
                .position(position)
                .label_font(("sans-serif", LEGEND_FONT))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(|e| draw_err(&e))?;
        }
        Ok(())
    }
}

/// The chart layout of [`plot_xy`] and [`plot_field`] in `area`: margins
/// and, with `text`, the axis label areas ([`Plot::AREA`] assumes these).
fn chart_builder<'a, 'b, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, plotters::coord::Shift>,
    text: bool,
) -> ChartBuilder<'a, 'b, DB> {
    let mut builder = ChartBuilder::on(area);
    builder.margin(MARGIN);
    if text {
        builder
            .x_label_area_size(LABEL_AREA.0)
            .y_label_area_size(LABEL_AREA.1);
    }
    builder
}

/// The drawing area of a PNG plot.
type BitMapArea<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

/// A drawing error as an [`anyhow::Error`].
fn draw_err(e: &dyn std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!("drawing plot: {e}")
}

/// Draws one series (line, markers or both) and, with `text`, its legend
/// entry.
fn draw_one_series<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    s: &PlotSeries,
    color: RGBColor,
    text: bool,
) -> Result<()>
where
    DB: DrawingBackend + 'a,
    CT: CoordTranslate<From = (f64, f64)>,
{
    let line = color.stroke_width(2);
    let marker = color.filled();
    let markers = || s.points.iter().map(move |&p| Circle::new(p, 5, marker));
    let anno = match s.style {
        Style::Line | Style::LineMarkers => chart
            .draw_series(LineSeries::new(s.points.iter().copied(), line))
            .map_err(|e| draw_err(&e))?,
        Style::Markers => chart.draw_series(markers()).map_err(|e| draw_err(&e))?,
    };
    if text && !s.label.is_empty() {
        let style = s.style;
        anno.label(s.label.as_str())
            .legend(move |at| legend_glyph(style, color, at));
    }
    if s.style == Style::LineMarkers {
        chart.draw_series(markers()).map_err(|e| draw_err(&e))?;
    }
    Ok(())
}

/// A legend glyph: a line and a marker, either possibly invisible.
type Glyph<DB> = plotters::element::ComposedElement<
    (i32, i32),
    DB,
    PathElement<(i32, i32)>,
    Circle<(i32, i32), i32>,
>;

/// The legend glyph of a series drawn in `style` and `color`, 24 px wide,
/// its left end at `at`.
fn legend_glyph<DB: DrawingBackend>(style: Style, color: RGBColor, at: (i32, i32)) -> Glyph<DB> {
    let shown = |on: bool, s: ShapeStyle| if on { s } else { TRANSPARENT.filled() };
    let line = shown(style != Style::Markers, color.stroke_width(2));
    let marker = shown(style != Style::Line, color.filled());
    EmptyElement::at(at)
        + PathElement::new(vec![(0, 0), (24, 0)], line)
        + Circle::new((12, 0), 5, marker)
}

/// The legend of `series` in a panel of its own (below a chart whose
/// legend would cover data): one line per labelled series, in the
/// chart's colours, framed.
fn draw_legend_panel(area: &BitMapArea<'_>, series: &[PlotSeries]) -> Result<()> {
    let Some((w, h)) = legend_size(series) else {
        return Ok(());
    };
    let x0 = MARGIN as i32;
    let frame = Rectangle::new([(x0, 0), (x0 + w as i32, h as i32)], BLACK);
    area.draw(&frame).map_err(|e| draw_err(&e))?;
    let font = ("sans-serif", LEGEND_FONT).into_font();
    let style = font
        .into_text_style(area)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let line = 1.25 * f64::from(LEGEND_FONT);
    let labelled = series
        .iter()
        .enumerate()
        .filter(|(_, s)| !s.label.is_empty());
    for (row, (i, s)) in labelled.enumerate() {
        let y = (10.0 + line * (row as f64 + 0.5)) as i32;
        let glyph = legend_glyph(s.style, COLORS[i % COLORS.len()], (x0 + 10, y));
        area.draw(&glyph).map_err(|e| draw_err(&e))?;
        area.draw_text(&s.label, &style, (x0 + 40, y))
            .map_err(|e| draw_err(&e))?;
    }
    Ok(())
}

/// The colour bar of a field plot in `area`: a vertical strip of the
/// field's colour scale with ticks and, with `text`, the field's label and
/// its exact minimum and maximum below and above the strip. Its margins
/// match the chart's, so the strip spans the chart's height.
fn draw_color_bar(area: &BitMapArea<'_>, layer: FieldLayer<'_>, text: bool) -> Result<()> {
    let (lo, hi) = layer.range;
    let (b0, b1) = if lo < hi {
        (lo, hi)
    } else {
        axis_range([lo, hi].into_iter().filter(|v| v.is_finite()), false)
    };
    let mut builder = ChartBuilder::on(area);
    builder
        .margin_top(MARGIN)
        .margin_bottom(MARGIN)
        .margin_left(5)
        .margin_right(10);
    if text {
        builder
            .x_label_area_size(LABEL_AREA.0)
            .right_y_label_area_size(COLOR_BAR_WIDTH - 65);
    }
    let mut chart = builder
        .build_cartesian_2d(0.0..1.0, b0..b1)
        .map_err(|e| draw_err(&e))?;
    if text {
        chart
            .configure_mesh()
            .disable_mesh()
            .x_labels(0)
            .y_labels(6)
            .y_desc(layer.label)
            .y_label_formatter(&|v| tick_label(*v, b1 - b0))
            .label_style(("sans-serif", 18))
            .axis_desc_style(("sans-serif", 22))
            .draw()
            .map_err(|e| draw_err(&e))?;
    }
    let n = 200;
    let strip = (0..n).map(|k| {
        let v0 = b0 + (b1 - b0) * k as f64 / n as f64;
        let v1 = b0 + (b1 - b0) * (k + 1) as f64 / n as f64;
        Rectangle::new(
            [(0.0, v0), (1.0, v1)],
            CellField::color(0.5 * (v0 + v1), lo, hi).filled(),
        )
    });
    chart.draw_series(strip).map_err(|e| draw_err(&e))?;
    let frame = Rectangle::new([(0.0, b0), (1.0, b1)], BLACK.stroke_width(1));
    chart
        .draw_series(std::iter::once(frame))
        .map_err(|e| draw_err(&e))?;
    if text {
        // The strip's corners in the area's own pixels.
        let base = area.get_base_pixel();
        let (x, top) = chart.backend_coord(&(0.0, b1));
        let (_, bottom) = chart.backend_coord(&(0.0, b0));
        let font = ("sans-serif", 16).into_font();
        for (name, v, y, v_pos) in [
            ("max", hi, top - 4, VPos::Bottom),
            ("min", lo, bottom + 4, VPos::Top),
        ] {
            let style = font
                .clone()
                .into_text_style(area)
                .pos(Pos::new(HPos::Left, v_pos));
            area.draw_text(
                &format!("{name} {}", tick_label(v, 0.0)),
                &style,
                (x - base.0, y - base.1),
            )
            .map_err(|e| draw_err(&e))?;
        }
    }
    Ok(())
}

/// Start and end of the generated block in `RESULTS.md`.
const MD_BEGIN: &str = "<!-- verification-results:begin -->";
const MD_END: &str = "<!-- verification-results:end -->";

/// Escapes text for a Markdown table cell.
fn md_cell(s: &str) -> String {
    s.replace('|', "\\|").replace(['\n', '\r'], " ")
}

/// Reads every `*.json` study in `results_dir` (sorted by file name) and
/// writes a Markdown table with one row per series: study, series label,
/// norm, finest `h`, error at the finest `h`, observed order and the total
/// wall time of the series, followed by the studies' notes.
///
/// `*.json` files that do not parse as a [`StudyResult`] are listed as
/// skipped below the table. If `md_path` already exists and contains the
/// markers `<!-- verification-results:begin -->` and
/// `<!-- verification-results:end -->`, only the text between them is
/// replaced (hand-written text around them is kept); otherwise the whole
/// file is written, with the markers. The write is atomic.
///
/// # Errors
/// An unreadable directory, file or existing `md_path`, or a failed write.
pub fn write_results_md(results_dir: &Path, md_path: &Path) -> Result<()> {
    let mut files: Vec<PathBuf> = fs::read_dir(results_dir)
        .with_context(|| format!("reading {}", results_dir.display()))?
        .map(|e| e.map(|e| e.path()))
        .collect::<std::io::Result<_>>()
        .with_context(|| format!("listing {}", results_dir.display()))?;
    files.retain(|p| p.is_file() && p.extension().is_some_and(|e| e == "json"));
    files.sort();

    let mut table = String::new();
    table.push_str(
        "| study | series | norm | finest h | finest error | observed order | total wall [s] |\n",
    );
    table.push_str("|---|---|---|---:|---:|---:|---:|\n");
    let mut notes = String::new();
    let mut skipped = Vec::new();
    for file in &files {
        let name = file
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let text =
            fs::read_to_string(file).with_context(|| format!("reading {}", file.display()))?;
        let study: StudyResult = match serde_json::from_str(&text) {
            Ok(s) => s,
            Err(e) => {
                skipped.push(format!("`{}` ({e})", md_cell(&name)));
                continue;
            }
        };
        for s in &study.series {
            let finest = s
                .points
                .iter()
                .filter(|p| p.h.is_finite() && p.h > 0.0)
                .min_by(|a, b| a.h.total_cmp(&b.h));
            let (h, err) = finest.map_or(("—".to_string(), "—".to_string()), |p| {
                (format!("{:.3e}", p.h), format!("{:.3e}", p.error))
            });
            let order = if s.observed_order.is_finite() {
                format!("{:.2}", s.observed_order)
            } else {
                "—".to_string()
            };
            let wall: f64 = s
                .points
                .iter()
                .map(|p| p.wall_s)
                .filter(|w| w.is_finite())
                .sum();
            let _ = writeln!(
                table,
                "| {} | {} | {} | {h} | {err} | {order} | {wall:.2} |",
                md_cell(&study.study),
                md_cell(&s.label),
                md_cell(&s.norm)
            );
        }
        for n in &study.notes {
            let _ = writeln!(notes, "- **{}**: {}", md_cell(&study.study), md_cell(n));
        }
    }

    let mut block = String::new();
    block.push_str(MD_BEGIN);
    block.push_str("\n\n");
    block.push_str(&table);
    if !notes.is_empty() {
        block.push_str("\nNotes:\n\n");
        block.push_str(&notes);
    }
    if !skipped.is_empty() {
        let _ = writeln!(
            block,
            "\nSkipped (not a study result): {}",
            skipped.join(", ")
        );
    }
    block.push('\n');
    block.push_str(MD_END);

    let existing = match fs::read_to_string(md_path) {
        Ok(s) => Some(s),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
        Err(e) => return Err(e).with_context(|| format!("reading {}", md_path.display())),
    };
    let spliced = existing.as_deref().and_then(|old| {
        let b = old.find(MD_BEGIN)?;
        let e = old[b..].find(MD_END)? + b + MD_END.len();
        Some(format!("{}{block}{}", &old[..b], &old[e..]))
    });
    // Name the results folder relative to the Markdown file, so the
    // committed text does not depend on the machine it was made on.
    let shown = md_path
        .parent()
        .and_then(|base| results_dir.strip_prefix(base).ok())
        .unwrap_or(results_dir);
    let out = spliced.unwrap_or_else(|| {
        format!(
            "# Verification results\n\nGenerated from `{}` by the verification harness \
             (`cargo run --release -p verification -- report` rebuilds this table from the \
             stored results; a full study run refreshes them).\n\n{block}\n",
            shown.display()
        )
    });
    atomic_write_bytes(md_path, out.as_bytes())
}

/// Writes `bytes` to `path` atomically ([`crate::output::atomic_write`]).
fn atomic_write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    crate::output::atomic_write(path, |w| w.write_all(bytes))
        .with_context(|| format!("writing {}", path.display()))
}

fn tmp_sibling(path: &Path, suffix: &str) -> Result<PathBuf> {
    crate::output::tmp_sibling(path, suffix)
        .with_context(|| format!("output path `{}`", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_triangle_has_the_rounded_order_below_the_data() {
        let s = |label: &str, e: [f64; 3]| PlotSeries {
            label: label.into(),
            points: [0.1, 0.05, 0.025].into_iter().zip(e).collect(),
            style: Style::LineMarkers,
        };
        // The median slope (2 of 0, 1, 2, 2.1) names the triangle.
        let series = [
            s("", [1.0, 1.0, 1.0]),
            s("flat", [3e-3, 3e-3, 3e-3]),
            s("a", [4e-2, 1.1e-2, 2.6e-3]),
            s("b", [1e-3, 5e-4, 2.5e-4]),
            s("c", [4e-2, 1e-2, 2.3e-3]),
        ];
        let t = slope_triangle(&series).expect("triangle");
        assert_eq!(t.label, "slope 2");
        let (h0, y0) = t.points[0];
        assert_eq!(h0, 0.025);
        assert!(y0 < 2.5e-4);
        let (h1, y1) = t.points[2];
        assert!(((y1 / y0).ln() / (h1 / h0).ln() - 2.0).abs() < 1e-12);
        // Work-precision (error falling with cost): a negative slope.
        let t = slope_triangle(&[s("w", [1e-4, 4e-4, 1.6e-3])]).expect("triangle");
        assert_eq!(t.label, "slope -2");
        assert!(slope_triangle(&[s("c", [f64::NAN, -1.0, 1.0])]).is_none());
        assert!(slope_triangle(&[]).is_none());
    }

    #[test]
    fn fit_line_is_fit_order_in_logs() {
        assert_eq!(
            fit_line(&[(0.0, 1.0), (1.0, 3.0), (2.0, 5.0)]),
            Some((2.0, 1.0))
        );
        assert_eq!(fit_line(&[(1.0, 1.0), (1.0, 3.0)]), None);
        assert_eq!(fit_line(&[(1.0, 1.0)]), None);
        let pts = power_law(3.0, 1.5, &[0.1, 0.05, 0.025]);
        let logs: Vec<(f64, f64)> = pts.iter().map(|p| (p.h.ln(), p.error.ln())).collect();
        assert_eq!(fit_line(&logs).map(|f| f.0), Some(fit_order(&pts)));
    }

    /// A scatter plot of `points` on the unit square (or on `[1e-3, 1]²`
    /// with log axes), with a legend entry.
    fn scatter(points: Vec<(f64, f64)>, log: bool) -> (Vec<PlotSeries>, (f64, f64)) {
        let series = vec![PlotSeries {
            label: "data".into(),
            points,
            style: Style::Markers,
        }];
        (series, if log { (1e-3, 1.0) } else { (0.0, 1.0) })
    }

    fn plot_of<'a>(series: &'a [PlotSeries], range: (f64, f64), log: bool) -> Plot<'a> {
        Plot {
            title: "legend",
            x_label: "x [m]",
            y_label: "y [m]",
            log_x: log,
            log_y: log,
            x_range: range,
            y_range: range,
            series,
            field: None,
        }
    }

    #[test]
    fn legend_goes_to_the_empty_corner() {
        // A 6 x 6 block of points in each corner but the lower right.
        let block = |x0: f64, y0: f64| {
            (0..36).map(move |k| (x0 + 0.05 * (k % 6) as f64, y0 + 0.05 * (k / 6) as f64))
        };
        let lin: Vec<(f64, f64)> = block(0.0, 0.72)
            .chain(block(0.72, 0.72))
            .chain(block(0.0, 0.0))
            .collect();
        let (series, range) = scatter(lin.clone(), false);
        let (pos, covered) = plot_of(&series, range, false).legend_position(Plot::AREA);
        assert_eq!((pos, covered), (SeriesLabelPosition::LowerRight, 0));
        // The same layout on log axes: x -> 1e-3^(1 - x).
        let to_log = |(x, y): (f64, f64)| (1e-3f64.powf(1.0 - x), 1e-3f64.powf(1.0 - y));
        let (series, range) = scatter(lin.into_iter().map(to_log).collect(), true);
        let (pos, covered) = plot_of(&series, range, true).legend_position(Plot::AREA);
        assert_eq!((pos, covered), (SeriesLabelPosition::LowerRight, 0));
    }

    #[test]
    fn estimated_plot_area_is_the_charts() {
        let mut buf = vec![0u8; (PLOT_SIZE.0 * PLOT_SIZE.1 * 3) as usize];
        let root = BitMapBackend::with_buffer(&mut buf, PLOT_SIZE).into_drawing_area();
        let body = root
            .titled("a title", ("sans-serif", TITLE_FONT))
            .expect("fonts");
        let chart = chart_builder(&body, true)
            .build_cartesian_2d(0.0..1.0, 0.0..1.0)
            .unwrap();
        let (w, h) = chart.plotting_area().dim_in_pixel();
        assert_eq!(w, Plot::AREA.0);
        assert!(h.abs_diff(Plot::AREA.1) <= 6, "{h} vs {}", Plot::AREA.1);
    }

    #[test]
    fn legend_gets_room_above_data_that_fills_the_plot() {
        let wave: Vec<(f64, f64)> = (0..=400)
            .map(|k| {
                (
                    k as f64 / 400.0,
                    0.5 + 0.45 * (40.0 * k as f64 / 400.0).sin(),
                )
            })
            .collect();
        let series = vec![PlotSeries {
            label: "a line that crosses every corner".into(),
            points: wave,
            style: Style::Line,
        }];
        let mut plot = plot_of(&series, (0.0, 1.0), false);
        assert!(plot.legend_position(Plot::AREA).1 > 0);
        plot.make_room_for_legend();
        assert!(plot.y_range.1 > 1.0);
        assert_eq!(
            plot.legend_position(Plot::AREA),
            (SeriesLabelPosition::UpperLeft, 0)
        );
    }

    const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0D, 0x0A, 0x1A, 0x0A];

    fn test_dir(tag: &str) -> PathBuf {
        use std::sync::atomic::{AtomicU64, Ordering};
        static N: AtomicU64 = AtomicU64::new(0);
        let n = N.fetch_add(1, Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("harness-test-{tag}-{}-{n}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).expect("create test dir");
        dir
    }

    fn assert_png(path: &Path) {
        let bytes = fs::read(path).expect("read png");
        assert!(bytes.len() > 1000, "png too small: {}", bytes.len());
        assert_eq!(bytes[..8], PNG_SIGNATURE, "{}", path.display());
        // IHDR: width and height.
        assert_eq!(&bytes[12..16], b"IHDR");
        let w = u32::from_be_bytes(bytes[16..20].try_into().expect("4"));
        let h = u32::from_be_bytes(bytes[20..24].try_into().expect("4"));
        assert_eq!((w, h), PLOT_SIZE);
    }

    fn no_tmp_files(dir: &Path) {
        for e in fs::read_dir(dir).expect("dir") {
            let name = e.expect("entry").file_name().to_string_lossy().into_owned();
            assert!(!name.contains(".tmp"), "temporary file left: {name}");
        }
    }

    /// `a` and `b` are equal or adjacent doubles (serde_json without its
    /// `float_roundtrip` feature may parse a value 1 ulp off).
    fn within_one_ulp(a: f64, b: f64) -> bool {
        a == b || (a.signum() == b.signum() && a.to_bits().abs_diff(b.to_bits()) <= 1)
    }

    fn assert_series_close(a: &Series, b: &Series) {
        assert_eq!((&a.label, &a.norm), (&b.label, &b.norm));
        assert!(within_one_ulp(a.observed_order, b.observed_order));
        assert_eq!(a.points.len(), b.points.len());
        for (p, q) in a.points.iter().zip(&b.points) {
            for (x, y) in [
                (p.h, q.h),
                (p.error, q.error),
                (p.wall_s, q.wall_s),
                (p.updates_per_s, q.updates_per_s),
            ] {
                assert!(within_one_ulp(x, y), "{x:e} vs {y:e}");
            }
            assert_eq!(p.extra, q.extra);
        }
    }

    fn power_law(c: f64, p: f64, hs: &[f64]) -> Vec<Point> {
        hs.iter()
            .map(|&h| Point::new(h, c * h.powf(p), 0.1, 1e6))
            .collect()
    }

    #[test]
    fn fit_order_recovers_exact_power_laws() {
        let hs = [0.1, 0.05, 0.025, 0.0125, 0.00625];
        for (c, p) in [(3.0, 2.0), (0.5, 1.0), (7.0, 0.5), (1e-3, 4.0)] {
            let o = fit_order(&power_law(c, p, &hs));
            assert!((o - p).abs() < 1e-12, "c={c} p={p}: got {o}");
        }
        // Order of points does not matter.
        let mut pts = power_law(3.0, 2.0, &hs);
        pts.reverse();
        pts.swap(0, 3);
        assert!((fit_order(&pts) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn fit_order_skips_bad_points() {
        let mut pts = power_law(3.0, 2.0, &[0.1, 0.05, 0.025]);
        pts.push(Point::new(0.2, 0.0, 1.0, 1.0));
        pts.push(Point::new(0.4, -1.0, 1.0, 1.0));
        pts.push(Point::new(0.3, f64::NAN, 1.0, 1.0));
        pts.push(Point::new(0.6, f64::INFINITY, 1.0, 1.0));
        pts.push(Point::new(0.0, 1.0, 1.0, 1.0));
        pts.push(Point::new(f64::NAN, 1.0, 1.0, 1.0));
        assert!((fit_order(&pts) - 2.0).abs() < 1e-12);

        assert!(fit_order(&[]).is_nan());
        assert!(fit_order(&power_law(3.0, 2.0, &[0.1])).is_nan());
        let one_valid = vec![
            Point::new(0.1, 1.0, 0.0, 0.0),
            Point::new(0.05, 0.0, 0.0, 0.0),
        ];
        assert!(fit_order(&one_valid).is_nan());
        // Same h twice: no slope.
        assert!(fit_order(&power_law(3.0, 2.0, &[0.1, 0.1])).is_nan());
    }

    fn sample_study() -> StudyResult {
        let hs = [0.1, 0.05, 0.025, 0.0125];
        let mut pts = power_law(3.0, 2.0, &hs);
        pts[0] = pts[0].clone().with_extra("energy_drift", 1.5e-9);
        pts[1] = pts[1].clone().with_extra("bad", f64::NAN);
        StudyResult {
            study: "manufactured_1d".to_string(),
            series: vec![
                Series::new("MPM, velocity", "L2", pts),
                Series::new("ICE | pressure", "Linf", power_law(0.7, 1.0, &hs)),
                // One point only: order NaN.
                Series::new("single", "L2", power_law(1.0, 1.0, &[0.1])),
            ],
            notes: vec!["CFL 0.4".to_string()],
            ..Default::default()
        }
    }

    #[test]
    fn json_round_trip_with_nan_order() {
        let mut study = sample_study();
        study.series[2].points[0].updates_per_s = f64::INFINITY;
        let json = serde_json::to_string_pretty(&study).expect("to json");
        assert!(json.contains("\"observed_order\": null"), "{json}");
        assert!(json.contains("\"updates_per_s\": null"));
        assert!(json.contains("\"energy_drift\": 1.5e-9"));
        assert!(json.contains("\"bad\": null"));
        assert!(json.contains("\"notes\""));

        let back: StudyResult = serde_json::from_str(&json).expect("from json");
        assert!(back.series[2].observed_order.is_nan());
        assert!(back.series[2].points[0].updates_per_s.is_nan());
        assert_eq!(back.study, study.study);
        assert_eq!(back.notes, study.notes);
        for (a, b) in back.series.iter().zip(&study.series).take(2) {
            assert_series_close(a, b);
        }

        // Consumers modelling the field as Option<f64> read null as None.
        #[derive(Deserialize)]
        struct OptSeries {
            observed_order: Option<f64>,
        }
        #[derive(Deserialize)]
        struct OptStudy {
            series: Vec<OptSeries>,
        }
        let opt: OptStudy = serde_json::from_str(&json).expect("option view");
        assert_eq!(opt.series[2].observed_order, None);
        assert!((opt.series[0].observed_order.expect("order") - 2.0).abs() < 1e-12);

        // Empty notes / extra are omitted.
        let plain = StudyResult {
            study: "s".into(),
            series: vec![Series::new("a", "L2", power_law(1.0, 1.0, &[0.1, 0.05]))],
            notes: vec![],
            ..Default::default()
        };
        let json = serde_json::to_string(&plain).expect("json");
        assert!(!json.contains("notes") && !json.contains("extra"), "{json}");
        let back: StudyResult = serde_json::from_str(&json).expect("back");
        assert_eq!(back.study, plain.study);
        assert_series_close(&back.series[0], &plain.series[0]);
    }

    #[test]
    fn write_study_produces_three_files() {
        let dir = test_dir("study").join("nested");
        let study = sample_study();
        write_study(&dir, &study).expect("write study");

        let json = fs::read_to_string(dir.join("manufactured_1d.json")).expect("json");
        let back: StudyResult = serde_json::from_str(&json).expect("parse");
        assert_eq!(back.series.len(), 3);
        assert_series_close(&back.series[0], &study.series[0]);

        let csv = fs::read_to_string(dir.join("manufactured_1d.csv")).expect("csv");
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[0], "series,norm,h,error,wall_s,updates_per_s");
        assert_eq!(lines.len(), 1 + 4 + 4 + 1);
        assert!(
            lines[1].starts_with("\"MPM, velocity\",L2,0.1,"),
            "{}",
            lines[1]
        );
        let last: Vec<&str> = lines[4].rsplitn(4, ',').collect();
        let e: f64 = last[2].parse().expect("error value");
        assert_eq!(e.to_bits(), study.series[0].points[3].error.to_bits());

        assert_png(&dir.join("manufactured_1d.png"));
        no_tmp_files(&dir);
        let _ = fs::remove_dir_all(dir.parent().expect("parent"));
    }

    #[test]
    fn study_axes_are_written_and_optional() {
        let dir = test_dir("axes");
        let study = StudyResult {
            h_axis: "cell size Δx [m]".to_string(),
            error_axis: "L1 density error [kg/m³]".to_string(),
            ..sample_study()
        };
        write_study(&dir, &study).expect("write study");
        let json = fs::read_to_string(dir.join("manufactured_1d.json")).expect("json");
        assert!(json.contains("\"h_axis\": \"cell size Δx [m]\""), "{json}");
        assert!(
            json.contains("\"error_axis\": \"L1 density error [kg/m³]\""),
            "{json}"
        );
        let back: StudyResult = serde_json::from_str(&json).expect("parse");
        assert_eq!(back.h_axis, study.h_axis);
        assert_eq!(back.error_axis, study.error_axis);
        assert_png(&dir.join("manufactured_1d.png"));

        // Empty axes are omitted, and JSON written before the axes existed
        // still loads (with empty axes).
        let plain = sample_study();
        let json = serde_json::to_string(&plain).expect("json");
        assert!(
            !json.contains("h_axis") && !json.contains("error_axis"),
            "{json}"
        );
        let old = r#"{"study": "old", "series": [{"label": "a", "norm": "L2",
            "points": [{"h": 0.1, "error": 0.01, "wall_s": 1.0, "updates_per_s": null}],
            "observed_order": null}]}"#;
        let back: StudyResult = serde_json::from_str(old).expect("old json");
        assert_eq!(back.study, "old");
        assert!(back.h_axis.is_empty() && back.error_axis.is_empty());
        assert!(back.series[0].points[0].updates_per_s.is_nan());
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn plot_xy_is_robust() {
        let dir = test_dir("plot");
        let s = |label: &str, points: Vec<(f64, f64)>, style| PlotSeries {
            label: label.to_string(),
            points,
            style,
        };
        let cases: Vec<(bool, bool, Vec<PlotSeries>)> = vec![
            (true, true, vec![]),
            (false, false, vec![s("empty", vec![], Style::Line)]),
            (
                true,
                true,
                vec![s("one", vec![(0.1, 0.01)], Style::LineMarkers)],
            ),
            (
                false,
                false,
                vec![s("one", vec![(0.0, 0.0)], Style::Markers)],
            ),
            (
                true,
                true,
                vec![
                    s(
                        "mixed",
                        vec![
                            (0.0, 1.0),
                            (-1.0, 2.0),
                            (0.1, -3.0),
                            (0.2, 0.04),
                            (0.4, 0.16),
                        ],
                        Style::LineMarkers,
                    ),
                    s(
                        "nonfinite",
                        vec![(f64::NAN, 1.0), (1.0, f64::INFINITY)],
                        Style::Line,
                    ),
                ],
            ),
            (
                false,
                true,
                vec![
                    s(
                        "a",
                        (1..20).map(|i| (i as f64, (i as f64).exp())).collect(),
                        Style::Line,
                    ),
                    s("", vec![(5.0, 1e3)], Style::Markers),
                ],
            ),
            (
                true,
                false,
                vec![s("b", vec![(1e-6, -5.0), (1e3, 5.0)], Style::LineMarkers)],
            ),
        ];
        for (i, (lx, ly, series)) in cases.iter().enumerate() {
            let path = dir.join(format!("case{i}.png"));
            plot_xy(&path, "robustness", "x [m]", "y [-]", *lx, *ly, series)
                .unwrap_or_else(|e| panic!("case {i}: {e:#}"));
            assert_png(&path);
        }
        no_tmp_files(&dir);
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn field_plot_is_a_png_with_a_diverging_scale() {
        let dir = test_dir("field");
        let field = CellField {
            lower: (0.0, 0.0),
            h: (0.5, 0.25),
            cells: (2, 4),
            values: (0..8).map(f64::from).collect(),
        };
        let path = dir.join("field.png");
        plot_field(&path, "field", "x [m]", "y [m]", "v [-]", &field, &[]).unwrap();
        assert_png(&path);
        assert_eq!(CellField::color(0.0, 0.0, 7.0), RGBColor(40, 70, 200));
        assert_eq!(CellField::color(3.5, 0.0, 7.0), RGBColor(255, 255, 255));
        assert_eq!(CellField::color(7.0, 0.0, 7.0), RGBColor(200, 30, 30));
    }

    #[test]
    fn color_bar_runs_from_blue_at_the_minimum_to_red_at_the_maximum() {
        let (w, h) = (COLOR_BAR_WIDTH, PLOT_SIZE.1);
        let mut buf = vec![0u8; (w * h * 3) as usize];
        let field = CellField {
            lower: (0.0, 0.0),
            h: (1.0, 1.0),
            cells: (1, 1),
            values: vec![0.0],
        };
        let layer = FieldLayer {
            field: &field,
            range: (-1.0, 3.0),
            label: "v [-]",
        };
        {
            let area = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            area.fill(&WHITE).unwrap();
            draw_color_bar(&area, layer, true).expect("colour bar");
            area.present().unwrap();
        }
        let rgb = |x: u32, y: u32| {
            let i = 3 * (y * w + x) as usize;
            (buf[i], buf[i + 1], buf[i + 2])
        };
        // The strip: 5 px in from the left, MARGIN below the top, above the
        // x label area.
        let (top, bottom) = (rgb(20, MARGIN + 4), rgb(20, h - MARGIN - LABEL_AREA.0 - 4));
        assert!(top.0 > 190 && top.2 < 60, "top {top:?}");
        assert!(bottom.2 > 190 && bottom.0 < 60, "bottom {bottom:?}");
    }

    #[test]
    fn text_rendering_and_textless_fallback() {
        let dir = test_dir("text");
        let series = [PlotSeries {
            label: "e = 3 h^2".to_string(),
            points: vec![(0.1, 0.03), (0.05, 0.0075)],
            style: Style::LineMarkers,
        }];
        let plot = Plot {
            title: "text",
            x_label: "h",
            y_label: "error",
            log_x: true,
            log_y: true,
            x_range: (0.04, 0.2),
            y_range: (0.005, 0.05),
            series: &series,
            field: None,
        };
        let with_text = dir.join("with_text.png");
        let text_ok = plot.render(&with_text, true);
        assert!(
            text_ok.is_ok(),
            "text rendering failed here (fonts?): {:?}",
            text_ok.err()
        );
        assert_png(&with_text);
        let without = dir.join("without_text.png");
        plot.render(&without, false).expect("textless render");
        assert_png(&without);
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn axis_ranges_are_padded() {
        let (lo, hi) = axis_range([0.1, 0.001].into_iter(), true);
        assert!(lo < 0.001 && hi > 0.1);
        let (lo, hi) = axis_range([2.0].into_iter(), true);
        assert!(lo < 2.0 && hi > 2.0 && lo > 0.0);
        let (lo, hi) = axis_range([0.0].into_iter(), false);
        assert!(lo < 0.0 && hi > 0.0);
        let (lo, hi) = axis_range(std::iter::empty(), false);
        assert!(lo < hi);
        let (lo, hi) = axis_range([-f64::MAX, f64::MAX].into_iter(), false);
        assert!(lo < hi && lo.is_finite() && hi.is_finite());
        assert_eq!(tick_label(0.001, 0.1), "1e-3");
        assert_eq!(tick_label(0.25, 1.0), "0.25");
        assert_eq!(tick_label(100.0, 1e3), "100");
        assert_eq!(tick_label(2.5e-7, 1e-6), "2.5e-7");
        assert_eq!(tick_label(2.220446049250313e-16, 2.0), "0");
        assert_eq!(tick_label(1.0001, 0.0005), "1.0001");
        // Log axes pass span 0: small values are not snapped to zero.
        assert_eq!(tick_label(1e3, 0.0), "1000");
        assert_eq!(tick_label(1e-20, 0.0), "1e-20");
    }

    #[test]
    fn log_ticks_are_nice_and_unique() {
        let (bold, light) = log_ticks(0.004, 0.14);
        assert_eq!(bold, vec![0.005, 0.01, 0.02, 0.05, 0.1]);
        assert!(light.contains(&0.004) && light.contains(&0.09));
        let (bold, _) = log_ticks(1e-12, 1.0);
        assert!(bold.len() <= 9 && bold.contains(&1e-12) && bold.contains(&1.0));
        let (bold, light) = log_ticks(1.0, 1.05);
        assert!(bold.len() >= 2 && light.is_empty(), "{bold:?}");
        for (lo, hi) in [(0.004, 0.14), (3e-7, 2e4), (0.04, 0.2), (1.0, 1.05)] {
            let (bold, light) = log_ticks(lo, hi);
            let mut all: Vec<f64> = bold.iter().chain(&light).copied().collect();
            assert!(all.iter().all(|v| *v >= lo && *v <= hi));
            all.sort_by(f64::total_cmp);
            all.dedup();
            assert_eq!(all.len(), bold.len() + light.len(), "duplicate ticks");
        }
    }

    #[test]
    fn results_md_lists_series_and_keeps_surrounding_text() {
        let dir = test_dir("md");
        let results = dir.join("results");
        write_study(&results, &sample_study()).expect("study 1");
        let other = StudyResult {
            study: "taylor_green".to_string(),
            series: vec![Series::new(
                "grid velocity",
                "L2",
                power_law(2.0, 2.0, &[0.1, 0.05]),
            )],
            notes: vec![],
            ..Default::default()
        };
        write_study(&results, &other).expect("study 2");
        fs::write(results.join("work_precision.json"), "{\"runs\": []}").expect("other json");

        let md = dir.join("RESULTS.md");
        write_results_md(&results, &md).expect("md");
        let text = fs::read_to_string(&md).expect("read md");
        assert!(text.contains("| study | series | norm | finest h |"));
        assert!(
            text.contains("| manufactured_1d | MPM, velocity | L2 | 1.250e-2 |"),
            "{text}"
        );
        assert!(text.contains("| manufactured_1d | ICE \\| pressure | Linf |"));
        assert!(text.contains("| manufactured_1d | single | L2 | 1.000e-1 | 1.000e-1 | — |"));
        assert!(text.contains("| taylor_green | grid velocity | L2 | 5.000e-2 | 5.000e-3 | 2.00 |"));
        assert!(
            text.contains("| 2.00 | 0.40 |"),
            "total wall of 4 points: {text}"
        );
        assert!(text.contains("- **manufactured_1d**: CFL 0.4"));
        assert!(text.contains("Skipped (not a study result): `work_precision.json`"));
        let rows = text.lines().filter(|l| l.starts_with("| ")).count();
        assert_eq!(rows, 1 + 4, "header + 4 series rows");

        // Hand-written text around the markers survives a regeneration.
        let edited = format!("# My results\n\nIntro.\n\n{}\n\nOutro.\n", {
            let b = text.find(MD_BEGIN).expect("begin");
            let e = text.find(MD_END).expect("end") + MD_END.len();
            &text[b..e]
        });
        fs::write(&md, edited).expect("edit");
        fs::remove_file(results.join("taylor_green.json")).expect("rm");
        write_results_md(&results, &md).expect("md again");
        let text = fs::read_to_string(&md).expect("read md");
        assert!(text.starts_with("# My results\n\nIntro.\n\n"));
        assert!(text.ends_with("\n\nOutro.\n"));
        assert!(!text.contains("taylor_green"));
        no_tmp_files(&dir);
        let _ = fs::remove_dir_all(&dir);
    }
}
