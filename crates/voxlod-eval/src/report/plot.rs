//! SVG plots of error against cost (plotters' SVG backend): one series per method, drawn as
//! lines, points or both, with optional log-scale axes, axis labels and a legend.
//!
//! Points that cannot be drawn — NaN or infinite coordinates, values ≤ 0 on a log axis, or
//! magnitudes beyond [`PLOTTABLE_LIMIT`] — are skipped, never a panic, and listed in
//! [`RenderedPlot::skipped`] so that a report can say so.

use std::ops::Range;
use std::path::Path;

use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::prelude::*;
use serde::Serialize;

use crate::{Error, Result};

/// How a series is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SeriesStyle {
    /// A polyline through the points in the order given.
    Line,
    /// A marker at every point.
    Points,
    /// Both: a polyline with a marker at every point.
    #[default]
    LineAndPoints,
}

/// One named series of `(x, y)` points, e.g. one method's (cost, error) at several settings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Series {
    /// Name shown in the legend.
    pub name: String,
    /// The points, in drawing order for lines.
    pub points: Vec<(f64, f64)>,
    /// How the series is drawn.
    pub style: SeriesStyle,
}

impl Series {
    /// A series drawn as a line with markers.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self { name: name.into(), points, style: SeriesStyle::default() }
    }

    /// The same series drawn with `style`.
    pub fn with_style(mut self, style: SeriesStyle) -> Self {
        self.style = style;
        self
    }
}

/// A 2D plot. Public fields; [`Default`] gives an empty 800×500 plot with linear axes.
#[derive(Clone, Debug, PartialEq)]
pub struct Plot {
    /// Title above the plot.
    pub title: String,
    /// Label of the x axis (e.g. "render time (ms)").
    pub x_label: String,
    /// Label of the y axis (e.g. "MSE").
    pub y_label: String,
    /// Logarithmic x axis (points with x ≤ 0 are skipped).
    pub log_x: bool,
    /// Logarithmic y axis (points with y ≤ 0 are skipped).
    pub log_y: bool,
    /// The series, drawn in order with a colour each.
    pub series: Vec<Series>,
    /// Width and height of the SVG in pixels.
    pub size: (u32, u32),
}

impl Default for Plot {
    fn default() -> Self {
        Self {
            title: String::new(),
            x_label: String::new(),
            y_label: String::new(),
            log_x: false,
            log_y: false,
            series: Vec::new(),
            size: (800, 500),
        }
    }
}

/// A point left out of a plot, and why.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SkippedPoint {
    /// The series' name.
    pub series: String,
    /// Index of the point in the series.
    pub index: usize,
    /// The point (serialized with non-finite values as strings).
    #[serde(serialize_with = "point_json")]
    pub point: (f64, f64),
    /// Why it was skipped.
    pub reason: &'static str,
}

fn point_json<S: serde::Serializer>(p: &(f64, f64), s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeTuple;
    let mut t = s.serialize_tuple(2)?;
    t.serialize_element(&crate::json::number(p.0))?;
    t.serialize_element(&crate::json::number(p.1))?;
    t.end()
}

/// A rendered plot: the SVG document and the points that were left out.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderedPlot {
    /// The SVG document.
    pub svg: String,
    /// Points that could not be drawn.
    pub skipped: Vec<SkippedPoint>,
}

/// Okabe–Ito colours: distinguishable with the common colour-vision deficiencies.
const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
    RGBColor(240, 228, 66),
];

impl Plot {
    /// Renders the plot as an SVG document.
    pub fn render_svg(&self) -> Result<RenderedPlot> {
        let mut skipped = Vec::new();
        let mut drawable = Vec::with_capacity(self.series.len());
        for s in &self.series {
            let mut kept = Vec::with_capacity(s.points.len());
            for (index, &(x, y)) in s.points.iter().enumerate() {
                let reason = if !x.is_finite() || !y.is_finite() {
                    Some("not finite")
                } else if (self.log_x && x <= 0.0) || (self.log_y && y <= 0.0) {
                    Some("not positive on a log axis")
                } else if !plottable(x, self.log_x) || !plottable(y, self.log_y) {
                    Some("beyond the plottable range")
                } else {
                    None
                };
                match reason {
                    Some(reason) => skipped.push(SkippedPoint {
                        series: s.name.clone(),
                        index,
                        point: (x, y),
                        reason,
                    }),
                    None => kept.push((x, y)),
                }
            }
            drawable.push(kept);
        }
        let xr = axis_range(drawable.iter().flatten().map(|p| p.0), self.log_x);
        let yr = axis_range(drawable.iter().flatten().map(|p| p.1), self.log_y);

        let mut svg = String::new();
        let result = {
            let root = SVGBackend::with_string(&mut svg, self.size).into_drawing_area();
            match (self.log_x, self.log_y) {
                (false, false) => self.draw(&root, &drawable, xr, yr),
                (true, false) => self.draw(&root, &drawable, xr.log_scale(), yr),
                (false, true) => self.draw(&root, &drawable, xr, yr.log_scale()),
                (true, true) => self.draw(&root, &drawable, xr.log_scale(), yr.log_scale()),
            }
        };
        result.map_err(|reason| Error::Plot { title: self.title.clone(), reason })?;
        Ok(RenderedPlot { svg, skipped })
    }

    /// Renders the plot and writes the SVG atomically; returns the skipped points.
    pub fn write_svg(&self, path: &Path) -> Result<Vec<SkippedPoint>> {
        let rendered = self.render_svg()?;
        voxlod_format::io::write_bytes_atomic(path, rendered.svg.as_bytes())
            .map_err(|source| Error::Write { path: path.to_owned(), source })?;
        Ok(rendered.skipped)
    }

    fn draw<X, Y>(
        &self,
        root: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
        drawable: &[Vec<(f64, f64)>],
        x: X,
        y: Y,
    ) -> std::result::Result<(), String>
    where
        X: AsRangedCoord<Value = f64>,
        Y: AsRangedCoord<Value = f64>,
        X::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
        Y::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        root.fill(&WHITE).map_err(e)?;
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d(x, y)
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .max_light_lines(4)
            .light_line_style(RGBColor(240, 240, 240))
            .bold_line_style(RGBColor(210, 210, 210))
            .x_label_formatter(&|v| tick_label(*v))
            .y_label_formatter(&|v| tick_label(*v))
            .draw()
            .map_err(e)?;
        for (i, (series, points)) in self.series.iter().zip(drawable).enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            let line = colour.stroke_width(2);
            let style = series.style;
            let markers = || points.iter().map(|&p| Circle::new(p, 4, colour.filled()));
            let anno = match style {
                SeriesStyle::Points => chart.draw_series(markers()).map_err(e)?,
                SeriesStyle::Line | SeriesStyle::LineAndPoints => {
                    if style == SeriesStyle::LineAndPoints {
                        chart.draw_series(markers()).map_err(e)?;
                    }
                    chart.draw_series(LineSeries::new(points.iter().copied(), line)).map_err(e)?
                }
            };
            anno.label(series.name.as_str()).legend(move |(x, y)| {
                if style == SeriesStyle::Points {
                    Circle::new((x + 10, y), 4, colour.filled()).into_dyn()
                } else {
                    PathElement::new([(x, y), (x + 20, y)], line).into_dyn()
                }
            });
        }
        if !self.series.is_empty() {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(e)?;
        }
        root.present().map_err(e)
    }
}

/// A tick label: 4 significant digits without trailing zeros (`0.3`, not
/// `0.30000000000000004`; `1.5e-7`, not `1.500e-7`).
fn tick_label(v: f64) -> String {
    let s = super::format_number(v, super::NumberFormat::Significant(4));
    let (mantissa, exponent) = match s.split_once('e') {
        Some((m, e)) => (m, format!("e{e}")),
        None => (s.as_str(), String::new()),
    };
    let mantissa = if mantissa.contains('.') {
        mantissa.trim_end_matches('0').trim_end_matches('.')
    } else {
        mantissa
    };
    format!("{mantissa}{exponent}")
}

fn plottable(v: f64, log: bool) -> bool {
    v.abs() <= PLOTTABLE_LIMIT && (!log || v >= 1.0 / PLOTTABLE_LIMIT)
}

/// Coordinates beyond this magnitude (and, on a log axis, below its inverse) are skipped: no
/// measured error or cost gets there, and plotters' log-axis ticks loop (practically) forever
/// when the ratio of the axis ends overflows to infinity (1e-300 to 1e300 did).
pub const PLOTTABLE_LIMIT: f64 = 1e100;

/// The axis range covering `values` with a 5% margin; a sensible default when there are none or
/// when they (nearly) coincide. On a log axis the margin is multiplicative and the range is
/// rounded out to whole decades. The result is always finite, non-empty and, for log axes,
/// positive.
fn axis_range(values: impl Iterator<Item = f64>, log: bool) -> Range<f64> {
    let (lo, hi) =
        values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo > hi {
        return if log { 1.0..10.0 } else { 0.0..1.0 };
    }
    if log {
        let (ln_lo, ln_hi) = (lo.ln(), hi.ln());
        let (ln_lo, ln_hi) = if ln_hi - ln_lo < 1e-9 {
            (ln_lo - 2f64.ln(), ln_hi + 2f64.ln())
        } else {
            let pad = 0.05 * (ln_hi - ln_lo);
            (ln_lo - pad, ln_hi + pad)
        };
        // Out to whole decades, so that every log axis has labelled ticks at both ends.
        let limit = PLOTTABLE_LIMIT.log10() + 5.0;
        let lo = (ln_lo / 10f64.ln()).floor().max(-limit);
        let hi = (ln_hi / 10f64.ln()).ceil().min(limit);
        // Nudged outwards: plotters finds the first tick as 10^ceil(log10(start)), and
        // log10(0.001) rounds to −2.9999999999999996, which would drop the lowest label.
        10f64.powf(lo) * (1.0 - 1e-9)..10f64.powf(hi) * (1.0 + 1e-9)
    } else {
        let scale = lo.abs().max(hi.abs());
        if hi - lo <= scale * 1e-9 {
            let d = if scale == 0.0 { 1.0 } else { scale * 0.1 };
            lo - d..hi + d
        } else {
            let pad = (hi - lo) * 0.05;
            lo - pad..hi + pad
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick_label(0.30000000000000004), "0.3");
        assert_eq!(tick_label(100.0), "100");
        assert_eq!(tick_label(0.0), "0");
        assert_eq!(tick_label(1.5e-7), "1.5e-7");
        assert_eq!(tick_label(-2.25), "-2.25");
        assert_eq!(tick_label(1234567.0), "1.235e6");
    }

    #[test]
    fn axis_ranges_cover_the_data_and_log_ranges_are_whole_decades() {
        let near = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-8;
        let r = axis_range([0.0012, 0.02].into_iter(), true);
        assert!(near(r.start, 1e-3) && r.start < 1e-3 && near(r.end, 1e-1) && r.end > 1e-1);
        let r = axis_range([5.0, 120.0].into_iter(), true);
        assert!(near(r.start, 1.0) && near(r.end, 1000.0), "{r:?}");
        let r = axis_range([2.0, 4.0].into_iter(), false);
        assert!(r.start < 2.0 && r.end > 4.0 && r.start > 1.8 && r.end < 4.2, "{r:?}");
        assert_eq!(axis_range(std::iter::empty(), false), 0.0..1.0);
        let r = axis_range([7.0].into_iter(), false);
        assert!(r.start < 7.0 && r.end > 7.0);
    }
}
