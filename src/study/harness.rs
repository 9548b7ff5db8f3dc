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
    if logs.len() < 2 {
        return f64::NAN;
    }
    let n = logs.len() as f64;
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    if sxx > 0.0 {
        sxy / sxx
    } else {
        f64::NAN
    }
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
/// with the series label, norm and observed order. Every file is written
/// atomically.
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

    let mut plot_series: Vec<PlotSeries> = result
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
    if let Some(t) = slope_triangle(&result.series) {
        plot_series.push(t);
    }
    plot_xy(
        &dir.join(format!("{stem}.png")),
        &result.study,
        "h",
        "error",
        true,
        true,
        &plot_series,
    )
}

/// A reference slope triangle for a log-log plot of error against `h`:
/// slope the observed order of the first series that has one, rounded to
/// the nearest half (at least ½), spanning a factor 2 in `h` from the
/// smallest `h`, below the smallest error there (so it covers no data).
/// `None` without a series with a finite order and positive points.
pub fn slope_triangle(series: &[Series]) -> Option<PlotSeries> {
    let s = series.iter().find(|s| s.observed_order.is_finite())?;
    let order = ((s.observed_order * 2.0).round() / 2.0).max(0.5);
    let valid = |p: &&Point| p.h.is_finite() && p.h > 0.0 && p.error.is_finite() && p.error > 0.0;
    let h0 = s
        .points
        .iter()
        .filter(valid)
        .map(|p| p.h)
        .fold(f64::INFINITY, f64::min);
    let e_min = series
        .iter()
        .flat_map(|s| s.points.iter().filter(valid))
        .map(|p| p.error)
        .fold(f64::INFINITY, f64::min);
    if !(h0.is_finite() && e_min.is_finite()) {
        return None;
    }
    let (h1, y0) = (2.0 * h0, 0.4 * e_min);
    let y1 = y0 * 2f64.powf(order);
    Some(PlotSeries {
        label: format!("slope {order}"),
        points: vec![(h0, y0), (h1, y0), (h1, y1), (h0, y0)],
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

/// Draws a 1000×750 PNG line/marker plot at `path` (written atomically).
///
/// Points that are not finite, or not positive on a logarithmic axis, are
/// skipped. Axis ranges cover the remaining points with padding (5% of the
/// span, or of the decades on a log axis; a single value gets a default
/// width). Empty input still gives a valid (empty) plot. If text cannot be
/// rendered (no usable system font), the plot is drawn without title, axis
/// labels and legend instead of failing, and a warning goes to stderr.
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
    let cleaned: Vec<PlotSeries> = series
        .iter()
        .map(|s| PlotSeries {
            label: s.label.clone(),
            points: s.points.iter().copied().filter(keep).collect(),
            style: s.style,
        })
        .collect();
    let x_range = axis_range(
        cleaned.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
        log_x,
    );
    let y_range = axis_range(
        cleaned.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
        log_y,
    );
    let plot = Plot {
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
    /// A cell field drawn under the series (linear axes only), with the
    /// range of its finite values (the colour scale).
    field: Option<(&'a CellField, (f64, f64))>,
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
/// from its smallest to its largest finite value, appended to the title as
/// `[min, max]`) with
/// line/marker series on top, at `path` (written atomically, as
/// [`plot_xy`]).
///
/// # Errors
/// Any I/O or drawing error other than a text-rendering failure.
pub fn plot_field(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    field: &CellField,
    series: &[PlotSeries],
) -> Result<()> {
    let (nx, ny) = field.cells;
    let x_range = (field.lower.0, field.lower.0 + nx as f64 * field.h.0);
    let y_range = (field.lower.1, field.lower.1 + ny as f64 * field.h.1);
    let (lo, hi) = field
        .values
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let title = format!("{title} [{lo:.2e}, {hi:.2e}]");
    let plot = Plot {
        title: &title,
        x_label,
        y_label,
        log_x: false,
        log_y: false,
        x_range,
        y_range,
        series,
        field: Some((field, (lo, hi))),
    };
    plot.write_atomically(path)
}

impl Plot<'_> {
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

    fn render_in<X, Y>(&self, path: &Path, text: bool, x: X, y: Y) -> Result<()>
    where
        X: AsRangedCoord<Value = f64>,
        Y: AsRangedCoord<Value = f64>,
        X::CoordDescType: ValueFormatter<f64>,
        Y::CoordDescType: ValueFormatter<f64>,
    {
        let draw_err = |e: &dyn std::fmt::Display| anyhow::anyhow!("drawing plot: {e}");
        let root = BitMapBackend::new(path, PLOT_SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw_err(&e))?;
        let mut builder = ChartBuilder::on(&root);
        builder.margin(25);
        if text {
            builder
                .caption(self.title, ("sans-serif", 30))
                .x_label_area_size(60)
                .y_label_area_size(95);
        }
        let mut chart = builder.build_cartesian_2d(x, y).map_err(|e| draw_err(&e))?;
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
        if let (Some((f, (lo, hi))), false, false) = (self.field, self.log_x, self.log_y) {
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
            let color = COLORS[i % COLORS.len()];
            let line = color.stroke_width(2);
            let marker = color.filled();
            let anno = match s.style {
                Style::Line | Style::LineMarkers => chart
                    .draw_series(LineSeries::new(s.points.iter().copied(), line))
                    .map_err(|e| draw_err(&e))?,
                Style::Markers => chart
                    .draw_series(s.points.iter().map(|&p| Circle::new(p, 5, marker)))
                    .map_err(|e| draw_err(&e))?,
            };
            if text && !s.label.is_empty() {
                anno.label(s.label.as_str());
                match s.style {
                    Style::Line => {
                        anno.legend(move |(lx, ly)| {
                            PathElement::new(vec![(lx, ly), (lx + 24, ly)], line)
                        });
                    }
                    Style::Markers => {
                        anno.legend(move |(lx, ly)| Circle::new((lx + 12, ly), 5, marker));
                    }
                    Style::LineMarkers => {
                        anno.legend(move |(lx, ly)| {
                            EmptyElement::at((lx, ly))
                                + PathElement::new(vec![(0, 0), (24, 0)], line)
                                + Circle::new((12, 0), 5, marker)
                        });
                    }
                }
            }
            if s.style == Style::LineMarkers {
                chart
                    .draw_series(s.points.iter().map(|&p| Circle::new(p, 5, marker)))
                    .map_err(|e| draw_err(&e))?;
            }
        }
        if text && self.series.iter().any(|s| !s.label.is_empty()) {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .label_font(("sans-serif", 18))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(|e| draw_err(&e))?;
        }
        root.present().map_err(|e| draw_err(&e))?;
        Ok(())
    }
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
        let pts = |e: [f64; 3]| -> Vec<Point> {
            [0.1, 0.05, 0.025]
                .iter()
                .zip(e)
                .map(|(&h, e)| Point::new(h, e, 0.0, 0.0))
                .collect()
        };
        let s = vec![
            Series::new("a", "L1", pts([4e-2, 1.1e-2, 2.6e-3])),
            Series::new("b", "L1", pts([1e-3, 5e-4, 2.5e-4])),
        ];
        let t = slope_triangle(&s).expect("triangle");
        assert_eq!(t.label, "slope 2");
        let (h0, y0) = t.points[0];
        assert_eq!(h0, 0.025);
        assert!(y0 < 2.5e-4);
        let (h1, y1) = t.points[2];
        assert!(((y1 / y0).ln() / (h1 / h0).ln() - 2.0).abs() < 1e-12);
        assert!(slope_triangle(&[Series::new("c", "L1", vec![])]).is_none());
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
        plot_field(&path, "field", "x", "y", &field, &[]).unwrap();
        assert_png(&path);
        assert_eq!(CellField::color(0.0, 0.0, 7.0), RGBColor(40, 70, 200));
        assert_eq!(CellField::color(3.5, 0.0, 7.0), RGBColor(255, 255, 255));
        assert_eq!(CellField::color(7.0, 0.0, 7.0), RGBColor(200, 30, 30));
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
