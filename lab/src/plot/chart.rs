//! The line / marker [`Chart`] model ([`Series`], [`Style`]) and its SVG
//! rendering.

use std::path::Path;

use plotters::element::DashedPathElement;
use plotters::prelude::*;

use super::axis::{Axis, Scale, min_max, padded_range, to_plot, valid_range, widen};
use super::error::{PlotError, backend_err};
use super::layout::{FONT, frame, palette, plot_area_size, titled, write_file};
use super::legend;

/// An axis range (lo, hi) in plot space.
type Range = (f64, f64);

/// How a [`Series`] is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// Solid polyline.
    Line,
    /// Filled circular markers only.
    Markers,
    /// Solid polyline with a marker at every point.
    LineMarkers,
    /// Dashed polyline.
    DashedLine,
}

/// The most points a series keeps: a chart of a long run shows what a chart can show (a few
/// thousand points per series, an SVG of at most a few MB), not every step. Longer series are
/// thinned on [`Chart::push`] by [`thin`].
pub const MAX_POINTS_PER_SERIES: usize = 4000;

/// The most dashes a dashed series is drawn with (each is an SVG element); a longer dashed
/// series is drawn solid.
const MAX_DASHES: f64 = 20_000.0;

/// Every k-th point of `points` (k the smallest stride leaving at most `max`), the last point
/// kept, so that a line still ends where the data end.
pub fn thin<T: Copy>(points: &[T], max: usize) -> Vec<T> {
    let max = max.max(2);
    if points.len() <= max {
        return points.to_vec();
    }
    let stride = (points.len() - 1).div_ceil(max - 1);
    let mut out: Vec<T> = points.iter().step_by(stride).copied().collect();
    if !(points.len() - 1).is_multiple_of(stride)
        && let Some(&last) = points.last()
    {
        out.push(last);
    }
    out
}

/// One data series of a [`Chart`].
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend label; an empty label gives no legend entry.
    pub label: String,
    /// Data points `(x, y)`, drawn in order; dropped (invalid) points break the line.
    pub points: Vec<(f64, f64)>,
    /// Drawing style.
    pub style: Style,
    /// Explicit palette index (modulo the palette size); `None` uses the
    /// series' position in [`Chart::series`].
    pub color: Option<usize>,
}

impl Series {
    /// Creates a series with the given style and automatic colour.
    pub fn new(
        label: impl Into<String>,
        points: impl IntoIterator<Item = (f64, f64)>,
        style: Style,
    ) -> Self {
        let (label, points) = (label.into(), points.into_iter().collect());
        Self {
            label,
            points,
            style,
            color: None,
        }
    }
    /// A solid line series.
    pub fn line(label: impl Into<String>, points: impl IntoIterator<Item = (f64, f64)>) -> Self {
        Self::new(label, points, Style::Line)
    }
    /// A markers-only series.
    pub fn markers(label: impl Into<String>, points: impl IntoIterator<Item = (f64, f64)>) -> Self {
        Self::new(label, points, Style::Markers)
    }
    /// A line series with a marker at every point.
    pub fn line_markers(
        label: impl Into<String>,
        points: impl IntoIterator<Item = (f64, f64)>,
    ) -> Self {
        Self::new(label, points, Style::LineMarkers)
    }
    /// A dashed line series.
    pub fn dashed(label: impl Into<String>, points: impl IntoIterator<Item = (f64, f64)>) -> Self {
        Self::new(label, points, Style::DashedLine)
    }
    /// Uses palette colour `index` (modulo the palette size) for this series.
    pub fn with_color(mut self, index: usize) -> Self {
        self.color = Some(index);
        self
    }
}

/// A 2-D line/marker chart rendered to SVG.
///
/// Axis ranges are chosen from the data with a 5 % margin (in log space for
/// log axes). Each series gets a colour from a fixed 10-colour palette
/// (cycling) and, if labelled, an entry in the legend box: in the corner of the plot
/// that covers no data (upper right if free), or, when every corner holds data, in a
/// panel right of the plot (the image widens by the panel, the plot keeps its size).
/// Series left without valid points are skipped, legend entry included.
///
/// # Example
///
/// ```
/// use galerkin_vi_lab::plot::{Chart, Series};
///
/// // Error of a 4th-order method against the step size.
/// let steps = (1..=6).map(|k| 0.5f64.powi(k));
/// let errors: Vec<(f64, f64)> = steps.map(|h| (h, 3.0 * h.powi(4))).collect();
/// let chart = Chart::new("Convergence", "step size h", "max energy error")
///     .log_x()
///     .log_y()
///     .with_series(Series::line_markers("order 4", errors));
/// let svg = chart.to_svg_string()?;
/// assert!(svg.contains("Convergence") && svg.contains("order 4"));
/// assert!(svg.contains("1e-4")); // log-axis tick label
/// // chart.save_svg("target/plots/convergence.svg")?;
/// # Ok::<(), galerkin_vi_lab::plot::PlotError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Chart {
    /// Title drawn above the plot (omitted if empty).
    pub title: String,
    /// x-axis description.
    pub x_label: String,
    /// y-axis description.
    pub y_label: String,
    /// x-axis scale.
    pub x_scale: Scale,
    /// y-axis scale.
    pub y_scale: Scale,
    /// Series, drawn in order (later series on top).
    pub series: Vec<Series>,
    /// Give both axes the same data units per pixel (orbit plots) by widening
    /// the shorter range; applied in log space on log axes.
    pub equal_aspect: bool,
    /// Image width in pixels (clamped to `320..=16384`).
    pub width: u32,
    /// Image height in pixels (clamped to `240..=16384`).
    pub height: u32,
    /// Keep the legend off the data: when every corner of the plot holds data, raise the
    /// top of the y range until the legend fits above the data (orbit charts, whose curves
    /// reach every corner). Off by default: the legend then goes to a corner free of data,
    /// or right of the plot if there is none.
    pub keep_legend_clear: bool,
}

/// Palette index, series, and its valid points in plot space split into
/// unbroken runs.
struct Prepared<'a>(usize, &'a Series, Vec<Vec<(f64, f64)>>);

impl Chart {
    /// Creates an empty 800×600 chart with linear axes.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            series: Vec::new(),
            equal_aspect: false,
            width: 800,
            height: 600,
            keep_legend_clear: false,
        }
    }
    /// Keeps the legend off the data ([`Chart::keep_legend_clear`]).
    pub fn legend_clear_of_data(mut self) -> Self {
        self.keep_legend_clear = true;
        self
    }
    /// Uses a base-10 logarithmic y axis.
    pub fn log_y(mut self) -> Self {
        self.y_scale = Scale::Log10;
        self
    }
    /// Uses a base-10 logarithmic x axis.
    pub fn log_x(mut self) -> Self {
        self.x_scale = Scale::Log10;
        self
    }
    /// Enables equal aspect ratio (same data units per pixel on both axes).
    pub fn equal_aspect(mut self) -> Self {
        self.equal_aspect = true;
        self
    }
    /// Sets the image size in pixels.
    pub fn size(mut self, width: u32, height: u32) -> Self {
        (self.width, self.height) = (width, height);
        self
    }
    /// Adds a series (builder style; thinned as by [`Chart::push`]).
    pub fn with_series(mut self, s: Series) -> Self {
        self.push(s);
        self
    }
    /// Adds a series, thinned to at most [`MAX_POINTS_PER_SERIES`] points ([`thin`]).
    pub fn push(&mut self, mut s: Series) {
        if s.points.len() > MAX_POINTS_PER_SERIES {
            s.points = thin(&s.points, MAX_POINTS_PER_SERIES);
        }
        self.series.push(s);
    }

    /// Renders the chart to an SVG document.
    ///
    /// Fails with [`PlotError::NoData`] if no series has a drawable point.
    pub fn to_svg_string(&self) -> Result<String, PlotError> {
        let mut out = String::new();
        self.render(&mut out)?;
        Ok(out)
    }

    /// Renders the chart and writes it to `path`, creating parent directories.
    pub fn save_svg(&self, path: impl AsRef<Path>) -> Result<(), PlotError> {
        write_file(path.as_ref(), &self.to_svg_string()?)
    }

    /// Maps a data point to plot space; `None` if it cannot be drawn.
    fn to_plot(&self, (x, y): (f64, f64)) -> Option<(f64, f64)> {
        Some((to_plot(x, self.x_scale)?, to_plot(y, self.y_scale)?))
    }

    fn prepared(&self) -> Vec<Prepared<'_>> {
        let runs = |s: &Series| -> Vec<Vec<(f64, f64)>> {
            let runs = s.points.split(|&p| self.to_plot(p).is_none());
            let runs = runs.map(|r| {
                r.iter()
                    .filter_map(|&p| self.to_plot(p))
                    .collect::<Vec<_>>()
            });
            runs.filter(|r| !r.is_empty()).collect()
        };
        let all = self.series.iter().enumerate();
        let all = all.map(|(i, s)| Prepared(s.color.unwrap_or(i), s, runs(s)));
        all.filter(|p| !p.2.is_empty()).collect()
    }

    /// Widen the axis with the smaller units per pixel so that both have the same: a circle
    /// draws as a circle.
    fn equal_aspect_axes(
        &self,
        size: (u32, u32),
        mut x: Range,
        mut y: Range,
    ) -> Result<(Range, Range), PlotError> {
        let bad = |what| PlotError::invalid(&self.title, what);
        let (pw, ph) = plot_area_size(size, &self.title);
        let (ux, uy) = ((x.1 - x.0) / f64::from(pw), (y.1 - y.0) / f64::from(ph));
        if ux < uy {
            x = widen(x, uy * f64::from(pw));
        } else {
            y = widen(y, ux * f64::from(ph));
        }
        x = valid_range(x).ok_or_else(|| bad("equal-aspect x range overflows"))?;
        y = valid_range(y).ok_or_else(|| bad("equal-aspect y range overflows"))?;
        Ok((x, y))
    }

    /// Image size and axes (in plot space) for the prepared data.
    fn layout(&self, data: &[Prepared]) -> Result<((u32, u32), Axis, Axis), PlotError> {
        let pts = || data.iter().flat_map(|d| d.2.iter().flatten());
        let bad = |what| PlotError::invalid(&self.title, what);
        let (xlog, ylog) = (self.x_scale == Scale::Log10, self.y_scale == Scale::Log10);
        let xr = min_max(pts().map(|p| p.0)).ok_or_else(|| PlotError::no_data(&self.title))?;
        let yr = min_max(pts().map(|p| p.1)).ok_or_else(|| PlotError::no_data(&self.title))?;
        let mut x = padded_range(xr, xlog, 0.05).ok_or_else(|| bad("x range overflows"))?;
        let mut y = padded_range(yr, ylog, 0.05).ok_or_else(|| bad("y range overflows"))?;
        let size = (self.width, self.height);
        let size = (size.0.clamp(320, 16_384), size.1.clamp(240, 16_384));
        if self.equal_aspect {
            (x, y) = self.equal_aspect_axes(size, x, y)?;
        }
        if self.keep_legend_clear {
            let (_, box_h) = self.legend_box(data, size);
            let covered = self.corner_coverage(data, size, x, y);
            if box_h < 0.5 && covered.iter().all(|c| c.1 > 0) {
                // The data's top at 1 − box_h − 3 % of the plot height: the band above is free.
                let top = (yr.1 - y.0) / (1.0 - box_h - 0.03);
                y = valid_range((y.0, y.0 + top)).ok_or_else(|| bad("y range overflows"))?;
                if self.equal_aspect {
                    (x, y) = self.equal_aspect_axes(size, x, y)?;
                }
            }
        }
        Ok((size, Axis::new(x, xlog, 10), Axis::new(y, ylog, 8)))
    }

    /// The legend box's width and height as fractions of the plot area, estimated from the
    /// labels ([`legend::box_pixels`]).
    fn legend_box(&self, data: &[Prepared], size: (u32, u32)) -> (f64, f64) {
        let (w, h) = legend::box_pixels(data.iter().map(|d| d.1.label.as_str()));
        let (pw, ph) = plot_area_size(size, &self.title);
        ((w / f64::from(pw)).min(1.0), (h / f64::from(ph)).min(1.0))
    }

    /// Where the legend goes: the least covered corner ([`Chart::corner_coverage`]; upper
    /// right on a tie, so charts whose upper right is free keep their legend there), or
    /// `None`, a panel right of the plot, when every corner would cover data.
    fn legend_place(
        &self,
        data: &[Prepared],
        size: (u32, u32),
        x: (f64, f64),
        y: (f64, f64),
    ) -> Option<SeriesLabelPosition> {
        // The first of the least covered (min_by_key keeps the first of equal keys).
        let least = self
            .corner_coverage(data, size, x, y)
            .into_iter()
            .min_by_key(|c| c.1);
        least.filter(|c| c.1 == 0).map(|c| c.0)
    }

    /// How many data samples the legend box would cover in each corner (upper right, upper
    /// left, lower right, lower left), for plot ranges `x` and `y`.
    fn corner_coverage(
        &self,
        data: &[Prepared],
        size: (u32, u32),
        x: (f64, f64),
        y: (f64, f64),
    ) -> [(SeriesLabelPosition, usize); 4] {
        let (box_w, box_h) = self.legend_box(data, size);
        // Data in fractions of the plot area, (0, 0) at the lower left.
        let frac = |(px, py): (f64, f64)| ((px - x.0) / (x.1 - x.0), (py - y.0) / (y.1 - y.0));
        let mut samples = Vec::new();
        for d in data {
            for run in &d.2 {
                samples.extend(run.iter().map(|&p| frac(p)));
                if d.1.style != Style::Markers {
                    for w in run.windows(2) {
                        let (a, b) = (frac(w[0]), frac(w[1]));
                        samples.extend((1..8).map(|i| {
                            let t = f64::from(i) / 8.0;
                            (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1))
                        }));
                    }
                }
            }
        }
        let covered = |left: bool, top: bool| {
            let inside = |&(u, v): &(f64, f64)| {
                let in_x = if left { u <= box_w } else { u >= 1.0 - box_w };
                let in_y = if top { v >= 1.0 - box_h } else { v <= box_h };
                in_x && in_y
            };
            samples.iter().filter(|p| inside(p)).count()
        };
        [
            (SeriesLabelPosition::UpperRight, covered(false, true)),
            (SeriesLabelPosition::UpperLeft, covered(true, true)),
            (SeriesLabelPosition::LowerRight, covered(false, false)),
            (SeriesLabelPosition::LowerLeft, covered(true, false)),
        ]
    }

    /// Draws into `out`; returns the plotting-area size used by plotters.
    fn render(&self, out: &mut String) -> Result<(u32, u32), PlotError> {
        let data = self.prepared();
        let (size, x, y) = self.layout(&data)?;
        let entries: Vec<legend::Entry> = data
            .iter()
            .filter(|d| !d.1.label.is_empty())
            .map(|d| legend::Entry {
                label: &d.1.label,
                style: d.1.style,
                color: d.0,
            })
            .collect();
        // A legend that would cover data in every corner goes into a panel right of the
        // plot: the image widens, the plot keeps its size.
        let corner = self.legend_place(&data, size, (x.lo, x.hi), (y.lo, y.hi));
        let panel = match corner {
            None if !entries.is_empty() => legend::panel_width(&entries),
            _ => 0,
        };
        let (pw, ph) = plot_area_size(size, &self.title);
        let (sx, sy) = (f64::from(pw) / (x.hi - x.lo), f64::from(ph) / (y.hi - y.lo));
        let root = SVGBackend::with_string(out, (size.0 + panel, size.1)).into_drawing_area();
        root.fill(&WHITE).map_err(backend_err)?;
        let (area, side) = titled(&root, &self.title)?.split_horizontally(size.0);
        let mut chart = frame(&area, [&self.x_label, &self.y_label], x, y, true)?;
        // Pixels along a series: a dashed line longer than MAX_DASHES dashes (a long run
        // retracing its orbit) is drawn solid, since every dash is an SVG element.
        let pixels = |runs: &[Vec<(f64, f64)>]| -> f64 {
            let seg = |w: &[(f64, f64)]| ((w[1].0 - w[0].0) * sx).hypot((w[1].1 - w[0].1) * sy);
            runs.iter().flat_map(|r| r.windows(2).map(seg)).sum()
        };
        for Prepared(color, s, runs) in &data {
            let (line, dot) = (palette(*color).stroke_width(2), palette(*color).filled());
            let markers = || runs.iter().flatten().map(move |&p| Circle::new(p, 3, dot));
            let anno = match s.style {
                Style::Line | Style::LineMarkers => {
                    chart.draw_series(runs.iter().map(|r| PathElement::new(r.clone(), line)))
                }
                Style::DashedLine if pixels(runs) > 13.0 * MAX_DASHES => {
                    chart.draw_series(runs.iter().map(|r| PathElement::new(r.clone(), line)))
                }
                Style::DashedLine => chart.draw_series(
                    runs.iter()
                        .map(|r| DashedPathElement::new(r.clone(), 8, 5, line)),
                ),
                Style::Markers => chart.draw_series(markers()),
            }
            .map_err(backend_err)?;
            if corner.is_some() && !s.label.is_empty() {
                let (style, color) = (s.style, *color);
                anno.label(s.label.as_str())
                    .legend(move |at| legend::Swatch { at, style, color });
            }
            if s.style == Style::LineMarkers {
                chart.draw_series(markers()).map_err(backend_err)?;
            }
        }
        match corner {
            _ if entries.is_empty() => {}
            Some(corner) => chart
                .configure_series_labels()
                .position(corner)
                .background_style(legend::background())
                .border_style(BLACK)
                .label_font((FONT, legend::LEGEND_FONT))
                .draw()
                .map_err(backend_err)?,
            None => legend::draw_outside(&side, &entries)?,
        }
        let dims = chart.plotting_area().dim_in_pixel();
        root.present().map_err(backend_err)?;
        Ok(dims)
    }
}

#[cfg(test)]
#[path = "chart_tests.rs"]
mod tests;
