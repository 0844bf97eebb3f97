//! Shared SVG page layout over plotters: fonts, margins, palette, title band,
//! the Cartesian frame, and writing the file.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::axis::Axis;
use super::error::{PlotError, backend_err};

pub(super) const FONT: &str = "sans-serif";
const TITLE_SIZE: f64 = 26.0;
pub(super) const MARGIN: u32 = 15;
const MARGIN_RIGHT: u32 = 30;
const X_AREA: u32 = 55;
const Y_AREA: u32 = 85;

/// Tableau-10 palette (`0xRRGGBB`).
const PALETTE: [u32; 10] = [
    0x1f77b4, 0xff7f0e, 0x2ca02c, 0xd62728, 0x9467bd, 0x8c564b, 0xe377c2, 0x7f7f7f, 0xbcbd22,
    0x17becf,
];

pub(super) fn palette(i: usize) -> RGBColor {
    let [_, r, g, b] = PALETTE[i % PALETTE.len()].to_be_bytes();
    RGBColor(r, g, b)
}

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
type Plot<'b, 'a> = ChartContext<'b, SVGBackend<'a>, Cartesian2d<Axis, Axis>>;

/// Draws the title (if any) and returns the area below it.
pub(super) fn titled<'a>(root: &Area<'a>, title: &str) -> Result<Area<'a>, PlotError> {
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

/// Plotting-area size of a [`Chart`](super::Chart) image of `size` pixels (see [`frame`]).
pub(super) fn plot_area_size(size: (u32, u32), title: &str) -> (u32, u32) {
    let w = size.0.saturating_sub(MARGIN + MARGIN_RIGHT + Y_AREA);
    let h = size
        .1
        .saturating_sub(title_height(title) + 2 * MARGIN + X_AREA);
    (w.max(1), h.max(1))
}

/// Builds the Cartesian frame: axes, tick labels, axis descriptions and
/// (if `grid`) grid lines.
pub(super) fn frame<'b, 'a>(
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

/// Write the SVG through the crate's one atomic writer ([`crate::output::write_atomic`]).
pub(super) fn write_file(path: &Path, svg: &str) -> Result<(), PlotError> {
    crate::output::write_atomic(path, svg.as_bytes()).map_err(|e| match e {
        crate::error::LabError::Io { source, .. } => PlotError::Io(source),
        other => PlotError::Io(std::io::Error::other(other.to_string())),
    })
}
