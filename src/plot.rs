//! Small charting layer over [`plotters`] producing self-contained SVG.
//!
//! * [`Chart`]: line / marker charts of `(x, y)` series with linear or base-10
//!   logarithmic axes, a legend box and an equal-aspect mode for orbit plots;
//! * [`HeatMap`]: a grid of categorical cells (e.g. stable / unstable) for
//!   stability maps, with a colour legend.
//!
//! Only plotters' `svg_backend` is used, with no font feature: the SVG backend
//! writes text as `<text font-family="sans-serif">` elements (glyphs are
//! rendered by the SVG viewer) and layout uses plotters' built-in approximate
//! font metrics, so neither system libraries nor font files are needed.
//!
//! Rendering never panics on caller data: non-finite coordinates, and
//! non-positive ones on a log axis, are dropped; anything that leaves nothing
//! to draw is reported as a [`PlotError`].

use std::ops::Range;
use std::path::Path;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, ValueFormatter};
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Errors from chart rendering.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Nothing is left to draw (no series, or every point was filtered out).
    #[error("chart `{title}` has no plottable data")]
    NoData {
        /// Title of the offending chart.
        title: String,
    },
    /// The data cannot be drawn: its range overflows `f64`, or a heat-map
    /// coordinate is non-finite (or non-positive on a log axis).
    #[error("chart `{title}`: invalid data: {reason}")]
    InvalidData {
        /// Title of the offending chart.
        title: String,
        /// What is wrong with the data.
        reason: String,
    },
    /// Writing the SVG file (or creating its parent directory) failed.
    #[error("I/O error while saving chart: {0}")]
    Io(#[from] std::io::Error),
    /// The plotters backend reported an error.
    #[error("plotting backend error: {0}")]
    Backend(String),
}

impl PlotError {
    fn no_data(title: &str) -> Self {
        let title = title.to_owned();
        Self::NoData { title }
    }
    fn invalid(title: &str, reason: &str) -> Self {
        let (title, reason) = (title.to_owned(), reason.to_owned());
        Self::InvalidData { title, reason }
    }
}

fn backend_err<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError::Backend(e.to_string())
}

/// Axis scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Linear axis.
    Linear,
    /// Base-10 logarithmic axis; non-positive values are dropped.
    Log10,
}

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
/// (cycling) and, if labelled, an entry in the legend box (upper right).
/// Series left without valid points are skipped, legend entry included.
///
/// # Example
///
/// ```
/// use galerkin_vi::plot::{Chart, Series};
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
/// # Ok::<(), galerkin_vi::plot::PlotError>(())
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
        }
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
    /// Adds a series (builder style).
    pub fn with_series(mut self, s: Series) -> Self {
        self.series.push(s);
        self
    }
    /// Adds a series.
    pub fn push(&mut self, s: Series) {
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
            let (pw, ph) = plot_area_size(size, &self.title);
            let (ux, uy) = ((x.1 - x.0) / f64::from(pw), (y.1 - y.0) / f64::from(ph));
            if ux < uy {
                x = widen(x, uy * f64::from(pw));
            } else {
                y = widen(y, ux * f64::from(ph));
            }
            x = valid_range(x).ok_or_else(|| bad("equal-aspect x range overflows"))?;
            y = valid_range(y).ok_or_else(|| bad("equal-aspect y range overflows"))?;
        }
        Ok((size, Axis::new(x, xlog, 10), Axis::new(y, ylog, 8)))
    }

    /// Draws into `out`; returns the plotting-area size used by plotters.
    fn render(&self, out: &mut String) -> Result<(u32, u32), PlotError> {
        let data = self.prepared();
        let (size, x, y) = self.layout(&data)?;
        let root = SVGBackend::with_string(out, size).into_drawing_area();
        root.fill(&WHITE).map_err(backend_err)?;
        let area = titled(&root, &self.title)?;
        let mut chart = frame(&area, [&self.x_label, &self.y_label], x, y, true)?;
        let mut any_label = false;
        for Prepared(color, s, runs) in &data {
            let (line, dot) = (palette(*color).stroke_width(2), palette(*color).filled());
            let markers = || runs.iter().flatten().map(move |&p| Circle::new(p, 3, dot));
            let anno = match s.style {
                Style::Line | Style::LineMarkers => {
                    chart.draw_series(runs.iter().map(|r| PathElement::new(r.clone(), line)))
                }
                Style::DashedLine => chart.draw_series(
                    runs.iter()
                        .map(|r| DashedPathElement::new(r.clone(), 8, 5, line)),
                ),
                Style::Markers => chart.draw_series(markers()),
            }
            .map_err(backend_err)?;
            if !s.label.is_empty() {
                any_label = true;
                anno.label(s.label.as_str());
                let at = |p: (i32, i32)| EmptyElement::at(p);
                match s.style {
                    Style::Line => {
                        anno.legend(move |p| at(p) + PathElement::new([(0, 0), (20, 0)], line))
                    }
                    Style::DashedLine => anno.legend(move |p| {
                        at(p)
                            + PathElement::new([(0, 0), (7, 0)], line)
                            + PathElement::new([(12, 0), (20, 0)], line)
                    }),
                    Style::Markers => anno.legend(move |p| at(p) + Circle::new((10, 0), 3, dot)),
                    Style::LineMarkers => anno.legend(move |p| {
                        at(p)
                            + PathElement::new([(0, 0), (20, 0)], line)
                            + Circle::new((10, 0), 3, dot)
                    }),
                };
            }
            if s.style == Style::LineMarkers {
                chart.draw_series(markers()).map_err(backend_err)?;
            }
        }
        if any_label {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font((FONT, 16))
                .draw()
                .map_err(backend_err)?;
        }
        let dims = chart.plotting_area().dim_in_pixel();
        root.present().map_err(backend_err)?;
        Ok(dims)
    }
}

/// A categorical heat map (e.g. a stability map over a parameter grid),
/// rendered as a 900×600 SVG with a category legend right of the plot.
///
/// Cell `cells[iy][ix]` is centred at `(x_values[ix], y_values[iy])`; cell
/// edges lie half-way between neighbouring centres (in log space if `x_log`).
/// Unknown category indices are drawn grey; missing cells (short rows, or more
/// cells than coordinates) are left blank.
#[derive(Debug, Clone)]
pub struct HeatMap {
    /// Title drawn above the plot (omitted if empty).
    pub title: String,
    /// x-axis description.
    pub x_label: String,
    /// y-axis description.
    pub y_label: String,
    /// Cell-centre x coordinates (monotonic; positive if `x_log`).
    pub x_values: Vec<f64>,
    /// Cell-centre y coordinates (monotonic).
    pub y_values: Vec<f64>,
    /// Use a base-10 logarithmic x axis (for log-spaced `x_values`).
    pub x_log: bool,
    /// `cells[iy][ix]` is the category index of the cell at `(x_values[ix], y_values[iy])`.
    pub cells: Vec<Vec<usize>>,
    /// Legend label and RGB colour of each category.
    pub categories: Vec<(String, (u8, u8, u8))>,
}

impl HeatMap {
    /// Renders the heat map to an SVG document.
    ///
    /// Fails with [`PlotError::NoData`] if there are no cells or coordinates,
    /// and [`PlotError::InvalidData`] for non-finite coordinates (or
    /// non-positive x with `x_log`).
    pub fn to_svg_string(&self) -> Result<String, PlotError> {
        let mut out = String::new();
        self.render(&mut out)?;
        Ok(out)
    }

    /// Renders the heat map and writes it to `path`, creating parent directories.
    pub fn save_svg(&self, path: impl AsRef<Path>) -> Result<(), PlotError> {
        write_file(path.as_ref(), &self.to_svg_string()?)
    }

    fn render(&self, out: &mut String) -> Result<(), PlotError> {
        let bad = |what| PlotError::invalid(&self.title, what);
        if self.x_values.is_empty()
            || self.y_values.is_empty()
            || self.cells.iter().all(Vec::is_empty)
        {
            return Err(PlotError::no_data(&self.title));
        }
        let x_scale = if self.x_log {
            Scale::Log10
        } else {
            Scale::Linear
        };
        let xs: Option<Vec<f64>> = self.x_values.iter().map(|&v| to_plot(v, x_scale)).collect();
        let ys: Option<Vec<f64>> = self
            .y_values
            .iter()
            .map(|&v| to_plot(v, Scale::Linear))
            .collect();
        let xe = cell_edges(&xs.ok_or_else(|| bad("x not finite (or not positive on log axis)"))?);
        let ye = cell_edges(&ys.ok_or_else(|| bad("y not finite"))?);
        let range =
            |e: &[f64], log| min_max(e.iter().copied()).and_then(|r| padded_range(r, log, 0.0));
        let x = range(&xe, self.x_log).ok_or_else(|| bad("x range overflows"))?;
        let y = range(&ye, false).ok_or_else(|| bad("y range overflows"))?;

        let size = (900, 600);
        let root = SVGBackend::with_string(out, size).into_drawing_area();
        root.fill(&WHITE).map_err(backend_err)?;
        let area = titled(&root, &self.title)?;
        let longest = self
            .categories
            .iter()
            .map(|c| c.0.chars().count() as u32)
            .max();
        let legend_w = (longest.unwrap_or(0) * 9 + 60).clamp(110, size.0 / 3);
        let (main, legend) = area.split_horizontally(size.0 - legend_w);
        let (x, y) = (Axis::new(x, self.x_log, 10), Axis::new(y, false, 8));
        let mut chart = frame(&main, [&self.x_label, &self.y_label], x, y, false)?;
        let cell = |ix: usize, iy: usize, cat: usize| {
            let (r, g, b) = self.categories.get(cat).map_or((160, 160, 160), |c| c.1);
            let (x0, x1) = (*xe.get(ix)?, *xe.get(ix + 1)?);
            let (y0, y1) = (*ye.get(iy)?, *ye.get(iy + 1)?);
            let fill = RGBColor(r, g, b).filled();
            Some(Rectangle::new([(x0, y0), (x1, y1)], fill))
        };
        let mut rects = Vec::new();
        for (iy, row) in self.cells.iter().enumerate() {
            rects.extend(
                row.iter()
                    .enumerate()
                    .filter_map(|(ix, &c)| cell(ix, iy, c)),
            );
        }
        chart.draw_series(rects).map_err(backend_err)?;

        if !self.categories.is_empty() {
            let (top, row_h, n) = (MARGIN as i32, 22, self.categories.len() as i32);
            let frame_box = [
                (4, top),
                (legend_w as i32 - MARGIN as i32, top + 10 + row_h * n),
            ];
            let frame_box = Rectangle::new(frame_box, BLACK);
            legend.draw(&frame_box).map_err(backend_err)?;
            let text =
                TextStyle::from((FONT, 16).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
            for (i, (name, (r, g, b))) in self.categories.iter().enumerate() {
                let yc = top + 5 + row_h * i as i32 + row_h / 2;
                let swatch =
                    Rectangle::new([(12, yc - 7), (26, yc + 7)], RGBColor(*r, *g, *b).filled());
                legend.draw(&swatch).map_err(backend_err)?;
                let label = Text::new(name.as_str(), (34, yc), text.clone());
                legend.draw(&label).map_err(backend_err)?;
            }
        }
        root.present().map_err(backend_err)
    }
}

// --- layout -----------------------------------------------------------------

const FONT: &str = "sans-serif";
const TITLE_SIZE: f64 = 26.0;
const MARGIN: u32 = 15;
const MARGIN_RIGHT: u32 = 30;
const X_AREA: u32 = 55;
const Y_AREA: u32 = 85;

/// Tableau-10 palette (`0xRRGGBB`).
const PALETTE: [u32; 10] = [
    0x1f77b4, 0xff7f0e, 0x2ca02c, 0xd62728, 0x9467bd, 0x8c564b, 0xe377c2, 0x7f7f7f, 0xbcbd22,
    0x17becf,
];

fn palette(i: usize) -> RGBColor {
    let [_, r, g, b] = PALETTE[i % PALETTE.len()].to_be_bytes();
    RGBColor(r, g, b)
}

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
type Plot<'b, 'a> = ChartContext<'b, SVGBackend<'a>, Cartesian2d<Axis, Axis>>;

/// Draws the title (if any) and returns the area below it.
fn titled<'a>(root: &Area<'a>, title: &str) -> Result<Area<'a>, PlotError> {
    if title.is_empty() {
        return Ok(root.clone());
    }
    root.titled(title, (FONT, TITLE_SIZE)).map_err(backend_err)
}

/// Height of the title band cut by `DrawingArea::titled`, using plotters'
/// naive font metrics (`em = size / 1.24²`, text box height `1.24 em`).
fn title_height(title: &str) -> u32 {
    let em = TITLE_SIZE / 1.24 / 1.24;
    let text_h = (em * 0.24).round() as u32 + em.round() as u32;
    u32::from(!title.is_empty()) * (text_h + 2 * (text_h / 2).min(5))
}

/// Plotting-area size of a [`Chart`] image of `size` pixels (see [`frame`]).
fn plot_area_size(size: (u32, u32), title: &str) -> (u32, u32) {
    let w = size.0.saturating_sub(MARGIN + MARGIN_RIGHT + Y_AREA);
    let h = size
        .1
        .saturating_sub(title_height(title) + 2 * MARGIN + X_AREA);
    (w.max(1), h.max(1))
}

/// Builds the Cartesian frame: axes, tick labels, axis descriptions and
/// (if `grid`) grid lines.
fn frame<'b, 'a>(
    area: &'b Area<'a>,
    desc: [&str; 2],
    x: Axis,
    y: Axis,
    grid: bool,
) -> Result<Plot<'b, 'a>, PlotError> {
    let (xf, yf) = (|v: &f64| x.label(*v), |v: &f64| y.label(*v));
    let mut chart = ChartBuilder::on(area)
        .margin(MARGIN)
        .margin_right(MARGIN_RIGHT)
        .x_label_area_size(X_AREA)
        .y_label_area_size(Y_AREA)
        .build_cartesian_2d(x.clone(), y.clone())
        .map_err(backend_err)?;
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(desc[0])
        .y_desc(desc[1])
        .x_label_formatter(&xf)
        .y_label_formatter(&yf);
    mesh.label_style((FONT, 15)).axis_desc_style((FONT, 18));
    mesh.bold_line_style(RGBColor(205, 205, 205))
        .light_line_style(RGBColor(238, 238, 238));
    if !grid {
        mesh.disable_mesh();
    }
    mesh.draw().map_err(backend_err)?;
    Ok(chart)
}

fn write_file(path: &Path, svg: &str) -> Result<(), PlotError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    Ok(std::fs::write(path, svg)?)
}

// --- ranges and ticks -------------------------------------------------------

/// Maps a data value to plot space (`log10` on log axes); `None` if invalid.
fn to_plot(v: f64, scale: Scale) -> Option<f64> {
    match scale {
        Scale::Linear => v.is_finite().then_some(v),
        Scale::Log10 => (v.is_finite() && v > 0.0).then(|| v.log10()),
    }
}

fn min_max(it: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    it.fold(None, |acc, v| {
        Some(acc.map_or((v, v), |(a, b): (f64, f64)| (a.min(v), b.max(v))))
    })
}

/// `(min, max)` widened by `frac` of the span per side, or padded around a
/// degenerate value; `None` unless the result is finite with `lo < hi`.
fn padded_range((min, max): (f64, f64), log: bool, frac: f64) -> Option<(f64, f64)> {
    let (span, mid) = (max - min, min + 0.5 * (max - min));
    let (lo, hi) = if span > 0.0 && span > mid.abs() * 1e-12 {
        (min - frac * span, max + frac * span)
    } else {
        let pad = match (log, mid == 0.0) {
            (true, _) => 0.5,
            (false, true) => 1.0,
            (false, false) => (0.1 * mid.abs()).max(f64::MIN_POSITIVE),
        };
        (mid - pad, mid + pad)
    };
    valid_range((lo.max(f64::MIN), hi.min(f64::MAX))).or_else(|| valid_range((min, max)))
}

/// `Some(range)` if it is finite, with finite positive span.
fn valid_range((lo, hi): (f64, f64)) -> Option<(f64, f64)> {
    ((hi - lo).is_finite() && hi > lo).then_some((lo, hi))
}

/// Widens `(lo, hi)` symmetrically to span `new` (if larger).
fn widen((lo, hi): (f64, f64), new: f64) -> (f64, f64) {
    let extra = 0.5 * (new - (hi - lo)).max(0.0);
    (lo - extra, hi + extra)
}

/// Cell edges (plot space) from cell centres; a lone cell is one unit wide.
fn cell_edges(c: &[f64]) -> Vec<f64> {
    let (Some(&[a, b]), Some(&[y, z])) = (c.first_chunk(), c.last_chunk()) else {
        return c.iter().flat_map(|v| [v - 0.5, v + 0.5]).collect();
    };
    let mids = c.windows(2).map(|w| 0.5 * (w[0] + w[1]));
    std::iter::once(a - 0.5 * (b - a))
        .chain(mids)
        .chain([z + 0.5 * (z - y)])
        .collect()
}

/// One axis in plot space (`log10` values on log axes) with its ticks.
///
/// Implements [`Ranged`] directly because plotters' `WithKeyPoints` over
/// `f64` lacks the `ValueFormatter` that `configure_mesh` requires.
#[derive(Clone)]
struct Axis {
    lo: f64,
    hi: f64,
    log: bool,
    /// Label all ticks `1e-12`-style (log axes reaching outside `[1e-3, 1e5)`).
    sci: bool,
    bold: Vec<f64>,
    light: Vec<f64>,
}

impl Axis {
    fn new((lo, hi): (f64, f64), log: bool, max_ticks: usize) -> Self {
        let (bold, light) = if log {
            log_ticks(lo, hi, max_ticks)
        } else {
            linear_ticks(lo, hi, max_ticks, 5)
        };
        let sci = log && bold.iter().any(|t| !(-3.0..5.0).contains(t));
        Self {
            lo,
            hi,
            log,
            sci,
            bold,
            light,
        }
    }
    fn label(&self, v: f64) -> String {
        fmt_num(if self.log { 10f64.powf(v) } else { v }, self.sci)
    }
}

impl Ranged for Axis {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;
    fn map(&self, v: &f64, (p0, p1): (i32, i32)) -> i32 {
        // Clamped so that pixel coordinates stay small even for stray values.
        let t = ((v - self.lo) / (self.hi - self.lo)).clamp(-1.0, 2.0);
        // (A NaN casts to 0.)
        p0 + (f64::from(p1 - p0) * t).round() as i32
    }
    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.light.clone()
        } else {
            self.bold.clone()
        }
    }
    fn range(&self) -> Range<f64> {
        self.lo..self.hi
    }
}

impl ValueFormatter<f64> for Axis {
    fn format(v: &f64) -> String {
        fmt_num(*v, false)
    }
}

/// Multiples of a "nice" (1-2-5) step in `[lo, hi]` (about `max` of them),
/// plus light ticks at `1/sub` of that step.
fn linear_ticks(lo: f64, hi: f64, max: usize, sub: u32) -> (Vec<f64>, Vec<f64>) {
    let raw = (hi - lo) / max.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let nice = [1.0, 2.0, 5.0].into_iter().find(|&m| raw <= m * mag);
    let step = mag * nice.unwrap_or(10.0);
    let multiples = |step: f64| -> Vec<f64> {
        let (a, b) = ((lo / step).ceil(), (hi / step).floor());
        if !(step > 0.0 && a.is_finite() && b.is_finite() && b >= a && b - a <= 1000.0) {
            return Vec::new();
        }
        let snap = |v: f64| if v.abs() < step * 1e-9 { 0.0 } else { v };
        (0..=(b - a) as i64)
            .map(|k| snap((a + k as f64) * step))
            .collect()
    };
    match multiples(step) {
        bold if bold.is_empty() => (vec![lo, hi], Vec::new()),
        bold if sub > 1 => (bold, multiples(step / f64::from(sub))),
        bold => (bold, Vec::new()),
    }
}

/// Ticks for a log axis in plot space: decades (thinned to about `max`), else
/// 1-2-5 multiples, else nice linear ticks for very narrow ranges.
fn log_ticks(lo: f64, hi: f64, max: usize) -> (Vec<f64>, Vec<f64>) {
    let (first, last) = (lo.ceil() as i64, hi.floor() as i64);
    let in_range = |t: &f64| *t >= lo && *t <= hi;
    let sub = |mults: &[f64]| -> Vec<f64> {
        let decades = lo.floor() as i64..=last;
        decades
            .flat_map(|d| mults.iter().map(move |m| d as f64 + m.log10()))
            .filter(in_range)
            .collect()
    };
    let minor = [2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0];
    if last > first {
        let stride = ((last - first + 1) as usize).div_ceil(max.max(1)) as i64;
        let (bold, light): (Vec<i64>, Vec<i64>) =
            (first..=last).partition(|d| d.rem_euclid(stride) == 0);
        let light = if stride == 1 {
            sub(&minor)
        } else {
            light.into_iter().map(|d| d as f64).collect()
        };
        return (bold.into_iter().map(|d| d as f64).collect(), light);
    }
    match sub(&[1.0, 2.0, 5.0]) {
        bold if bold.len() >= 3 => (bold, sub(&minor)),
        _ => {
            let (lin, _) = linear_ticks(10f64.powf(lo), 10f64.powf(hi), max.min(6), 1);
            let ticks = lin.into_iter().filter(|v| *v > 0.0).map(f64::log10);
            (ticks.filter(in_range).collect(), vec![])
        }
    }
}

/// Compact number: plain for moderate magnitudes (unless `sci`), else
/// `1.5e-12` style; trailing zeros removed.
fn fmt_num(v: f64, sci: bool) -> String {
    let trim = |s: &str| s.trim_end_matches('0').trim_end_matches('.').to_owned();
    if !v.is_finite() {
        String::new()
    } else if v == 0.0 {
        "0".into()
    } else if !sci && (1e-3..1e5).contains(&v.abs()) {
        trim(&format!("{v:.6}"))
    } else {
        let s = format!("{v:.3e}");
        s.split_once('e')
            .map_or_else(|| s.clone(), |(m, e)| format!("{}e{e}", trim(m)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decay(scale: f64) -> Vec<(f64, f64)> {
        let f = |i: i32| (f64::from(i), scale * 10f64.powf(-0.25 * f64::from(i)));
        (0..50).map(f).collect()
    }

    fn ellipse() -> Vec<(f64, f64)> {
        let th = (0..=200).map(|i| f64::from(i) * std::f64::consts::TAU / 200.0);
        th.map(|t| (2.0 * t.cos() - 1.0, t.sin())).collect()
    }

    fn energy_chart() -> Chart {
        let sqrt = decay(1.0)
            .iter()
            .step_by(7)
            .map(|p| (p.0, p.1.sqrt()))
            .collect::<Vec<_>>();
        Chart::new("Energy <error>", "time t", "|H(t) - H(0)|")
            .log_y()
            .with_series(Series::line("cG(2)", decay(1.0)))
            .with_series(Series::dashed("Störmer-Verlet", decay(30.0)))
            .with_series(Series::markers(
                "spectral",
                decay(0.01).into_iter().step_by(5),
            ))
            .with_series(Series::line_markers("order 4", sqrt))
    }

    fn stability_map() -> HeatMap {
        let x_values: Vec<f64> = (0..20)
            .map(|i| 10f64.powf(-3.0 + 0.2 * f64::from(i)))
            .collect();
        let y_values: Vec<f64> = (1..=8).map(f64::from).collect();
        let class = |hq: f64| usize::from(hq > 0.5) + usize::from(hq > 5.0);
        let row = |q: f64| x_values.iter().map(|&h| class(h * q)).collect();
        let cells = y_values.iter().map(|&q| row(q)).collect();
        let cat = |name: &str, rgb| (name.to_owned(), rgb);
        HeatMap {
            title: "Stability map".into(),
            x_label: "step size h".into(),
            y_label: "degree q".into(),
            x_values,
            y_values,
            x_log: true,
            cells,
            categories: vec![
                cat("stable", (44, 160, 44)),
                cat("drift", (255, 127, 14)),
                cat("diverged", (214, 39, 40)),
            ],
        }
    }

    fn assert_contains(svg: &str, texts: &[&str]) {
        for text in texts {
            assert!(svg.contains(text), "missing {text:?}");
        }
    }

    #[test]
    fn svg_contains_title_labels_ticks_and_legend() {
        let svg = energy_chart().to_svg_string().unwrap();
        assert_contains(&svg, &["Energy &lt;error&gt;", "time t", "|H(t) - H(0)|"]);
        assert_contains(&svg, &["cG(2)", "Störmer-Verlet", "spectral", "order 4"]);
        assert_contains(
            &svg,
            &["1e-12", "1e-2", "1e0", ">\n0\n</text>", ">\n40\n</text>"],
        );
        assert!(
            svg.matches("<polyline").count() > 50,
            "dashes are separate polylines"
        );
    }

    #[test]
    fn log_axes_drop_bad_points() {
        let bad = [
            (2.0, -1.0),
            (3.0, 0.0),
            (4.0, f64::NAN),
            (f64::INFINITY, 1.0),
        ];
        let pts = [&[(1.0, 1e-3)], &bad[..], &[(5.0, 0.1)]].concat();
        let chart = Chart::new("t", "x", "y")
            .log_y()
            .with_series(Series::markers("m", pts));
        // Two surviving points plus the legend marker.
        assert_eq!(chart.to_svg_string().unwrap().matches("<circle").count(), 3);
        let chart = chart.log_x();
        let runs = &chart.prepared()[0].2;
        assert_eq!(runs, &[vec![(0.0, -3.0)], vec![(5f64.log10(), -1.0)]]);
    }

    #[test]
    fn no_data_errors() {
        let empty = Chart::new("nothing", "x", "y");
        let err = empty.to_svg_string();
        assert!(matches!(err, Err(PlotError::NoData { title }) if title == "nothing"));
        let bad = Series::line("b", [(1.0, -2.0), (f64::NAN, 1.0)]);
        let chart = empty
            .log_y()
            .with_series(Series::line("a", vec![]))
            .with_series(bad);
        assert!(matches!(
            chart.to_svg_string(),
            Err(PlotError::NoData { .. })
        ));
        // An empty series next to a good one is skipped, legend entry included.
        let mut chart = Chart::new("ok", "x", "y").with_series(Series::line("empty", vec![]));
        chart.push(Series::line("good", decay(1.0)));
        let svg = chart.to_svg_string().unwrap();
        assert!(svg.contains("good") && !svg.contains("empty"));
    }

    #[test]
    fn extreme_inputs_do_not_panic() {
        let huge = Series::dashed("d", [(f64::MAX, 1.0), (-f64::MAX, -1.0)]);
        let huge = Chart::new("big", "x", "y")
            .with_series(huge)
            .to_svg_string();
        assert!(matches!(huge, Err(PlotError::InvalidData { .. })));
        let single = Chart::new("", "", "").with_series(Series::line_markers("", [(1.0, 1.0)]));
        assert!(single.clone().size(0, 0).to_svg_string().is_ok());
        assert!(
            single
                .log_x()
                .log_y()
                .equal_aspect()
                .to_svg_string()
                .is_ok()
        );
        let odd = [
            (5e-324, 1e-320),
            (1.0, 1.0 + 1e-15),
            (f64::MAX, f64::MIN_POSITIVE),
        ];
        let odd = Series::line_markers("p", odd).with_color(99);
        let chart = Chart::new("a", "x", "y").with_series(odd);
        assert!(chart.to_svg_string().is_ok());
        assert!(chart.log_x().log_y().equal_aspect().to_svg_string().is_ok());
        let flat = Series::line("f", [(0.0, 0.0), (0.0, 0.0)]);
        let flat = Chart::new("flat", "x", "y")
            .with_series(flat)
            .size(20_000, 1);
        assert!(flat.equal_aspect().to_svg_string().is_ok());
    }

    #[test]
    fn equal_aspect_orbit() {
        for title in ["Kepler orbit", ""] {
            let chart = Chart::new(title, "q1", "q2").with_series(Series::line("orbit", ellipse()));
            let chart = chart.equal_aspect();
            let (size, x, y) = chart.layout(&chart.prepared()).unwrap();
            let (pw, ph) = plot_area_size(size, title);
            // The layout arithmetic must match plotters' actual plotting area.
            assert_eq!(chart.render(&mut String::new()).unwrap(), (pw, ph));
            let (ux, uy) = ((x.hi - x.lo) / f64::from(pw), (y.hi - y.lo) / f64::from(ph));
            assert!((ux - uy).abs() < 1e-12 * ux, "{ux} vs {uy}");
            assert!(x.lo < -3.0 && x.hi > 1.0 && y.lo < -1.0 && y.hi > 1.0);
        }
    }

    #[test]
    fn heat_map_renders_with_legend() {
        let map = stability_map();
        let svg = map.to_svg_string().unwrap();
        assert_contains(
            &svg,
            &["Stability map", "step size h", "degree q", "0.001", "0.1"],
        );
        assert_contains(&svg, &["stable", "drift", "diverged"]);
        assert!(svg.matches("<rect").count() >= 20 * 8 + 3);
        let cells = vec![vec![7, 1, 2], vec![]];
        let ragged = HeatMap {
            x_values: vec![1.0],
            cells,
            ..map.clone()
        };
        assert!(ragged.to_svg_string().is_ok());
        let bad = HeatMap {
            x_values: vec![1.0, -1.0],
            ..map.clone()
        };
        assert!(matches!(
            bad.to_svg_string(),
            Err(PlotError::InvalidData { .. })
        ));
        let empty = HeatMap {
            cells: vec![],
            categories: vec![],
            ..map
        };
        assert!(matches!(
            empty.to_svg_string(),
            Err(PlotError::NoData { .. })
        ));
    }

    #[test]
    fn ticks_and_number_format() {
        let f = |v| fmt_num(v, false);
        assert_eq!(
            [f(1e-12), f(2.5e7), f(0.1 + 0.2), f(-40.0)],
            ["1e-12", "2.5e7", "0.3", "-40"]
        );
        assert_eq!(fmt_num(100.0, true), "1e2");
        let decades: Vec<f64> = (-12..=-2).map(f64::from).collect();
        assert_eq!(log_ticks(-12.3, -1.7, 12).0, decades);
        assert!((5..=10).contains(&log_ticks(-30.0, 5.0, 10).0.len()));
        assert!(log_ticks(0.01, 0.02, 8).0.len() >= 2);
        let (bold, light) = linear_ticks(-0.1, 1.1, 10, 5);
        assert_eq!((bold.first(), bold.last()), (Some(&0.0), Some(&1.0)));
        assert!(light.len() > bold.len());
        assert_eq!(cell_edges(&[1.0, 2.0, 4.0]), [0.5, 1.5, 3.0, 5.0]);
    }

    #[test]
    fn save_creates_directories() {
        let dir = std::env::temp_dir().join(format!("gvi-plot-test-{}", std::process::id()));
        energy_chart()
            .save_svg(dir.join("nested/chart.svg"))
            .unwrap();
        stability_map().save_svg(dir.join("map.svg")).unwrap();
        let svg = std::fs::read_to_string(dir.join("nested/chart.svg")).unwrap();
        assert!(svg.contains("cG(2)"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
