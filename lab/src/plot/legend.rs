//! The legend of a [`Chart`](super::Chart): one swatch per labelled series, drawn either in
//! a corner of the plot (plotters' series labels) or, when every corner holds data, in a
//! panel to the right of the plot, where it hides nothing.

use plotters::coord::Shift;
use plotters::element::MultiLineText;
use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;
use plotters_backend::DrawingErrorKind;

use super::chart::Style;
use super::error::{PlotError, backend_err};
use super::layout::{FONT, MARGIN, palette};

/// A pixel position, as plotters' backends take it.
type BackendCoord = (i32, i32);

/// Legend text size in pixels.
pub(super) const LEGEND_FONT: u32 = 16;
/// Plotters' series-label layout: the swatch column's width, the margin inside the box, and
/// the box's offset from the plot's edges (`SeriesLabelStyle::draw`, `layout_label_area`).
const SWATCH_AREA: i32 = 30;
const BOX_MARGIN: i32 = 10;
const EDGE_OFFSET: f64 = 5.0;

/// One legend entry: the series' label, style and palette index.
pub(super) struct Entry<'a> {
    pub label: &'a str,
    pub style: Style,
    pub color: usize,
}

/// The labels laid out as plotters lays out its corner legend (its naive font metrics), at
/// `at` (the text's top left).
fn text<'a>(
    labels: impl Iterator<Item = &'a str>,
    at: BackendCoord,
) -> MultiLineText<'a, BackendCoord, &'a str> {
    let mut text = MultiLineText::new(at, (FONT, LEGEND_FONT));
    for l in labels.filter(|l| !l.is_empty()) {
        text.push_line(l);
    }
    text
}

/// The legend box's width and height in pixels, as plotters draws it in a corner (text,
/// swatch column and margins), plus its offset from the plot's edges: what the box covers.
pub(super) fn box_pixels<'a>(labels: impl Iterator<Item = &'a str>) -> (f64, f64) {
    // The naive metrics cannot fail; an empty box if they ever did.
    let (w, h) = text(labels, (0, 0)).estimate_dimension().unwrap_or((0, 0));
    let w = f64::from(w + SWATCH_AREA + 2 * BOX_MARGIN) + EDGE_OFFSET;
    (w, f64::from(h + 2 * BOX_MARGIN) + EDGE_OFFSET)
}

/// Width of the panel to the right of the plot that holds an outside legend.
pub(super) fn panel_width(entries: &[Entry]) -> u32 {
    let (w, _) = box_pixels(entries.iter().map(|e| e.label));
    w.ceil() as u32 + MARGIN
}

/// The swatch of a series in its legend row: a line, a dashed line, a marker or a line
/// through a marker, as the series is drawn, in the series' palette colour. Its one point
/// is the row's left end; 20 px wide.
pub(super) struct Swatch {
    /// Left end of the swatch.
    pub at: BackendCoord,
    /// How the series is drawn.
    pub style: Style,
    /// Palette index of the series.
    pub color: usize,
}

impl<'a> PointCollection<'a, BackendCoord> for &'a Swatch {
    type Point = &'a BackendCoord;
    type IntoIter = std::iter::Once<&'a BackendCoord>;
    fn point_iter(self) -> Self::IntoIter {
        std::iter::once(&self.at)
    }
}

impl<DB: DrawingBackend> Drawable<DB> for Swatch {
    fn draw<I: Iterator<Item = BackendCoord>>(
        &self,
        mut pos: I,
        backend: &mut DB,
        _: (u32, u32),
    ) -> Result<(), DrawingErrorKind<DB::ErrorType>> {
        let Some((x, y)) = pos.next() else {
            return Ok(());
        };
        let (line, dot) = (
            palette(self.color).stroke_width(2),
            palette(self.color).filled(),
        );
        let mut segment = |a: i32, b: i32| backend.draw_line((x + a, y), (x + b, y), &line);
        match self.style {
            Style::Line | Style::LineMarkers => segment(0, 20)?,
            Style::DashedLine => {
                segment(0, 7)?;
                segment(12, 20)?;
            }
            Style::Markers => {}
        }
        if matches!(self.style, Style::Markers | Style::LineMarkers) {
            backend.draw_circle((x + 10, y), 3, &dot, true)?;
        }
        Ok(())
    }
}

/// The box background: white at 85 % opacity, as plotters' corner legend.
pub(super) fn background() -> RGBAColor {
    WHITE.mix(0.85)
}

/// Draws the legend in `panel`, the strip right of the plot, its top level with the plot's:
/// the same box, text and swatches as plotters' corner legend.
pub(super) fn draw_outside<DB: DrawingBackend>(
    panel: &DrawingArea<DB, Shift>,
    entries: &[Entry],
) -> Result<(), PlotError> {
    let (x0, y0) = (0, MARGIN as i32);
    let labels = text(
        entries.iter().map(|e| e.label),
        (x0 + SWATCH_AREA + BOX_MARGIN, y0 + BOX_MARGIN),
    );
    let font_err = |e| PlotError::invalid("legend", &format!("font layout: {e:?}"));
    let (w, h) = labels.estimate_dimension().map_err(font_err)?;
    let frame = [
        (x0, y0),
        (
            x0 + w + SWATCH_AREA + 2 * BOX_MARGIN,
            y0 + h + 2 * BOX_MARGIN,
        ),
    ];
    panel
        .draw(&Rectangle::new(frame, background().filled()))
        .map_err(backend_err)?;
    panel
        .draw(&Rectangle::new(frame, BLACK))
        .map_err(backend_err)?;
    panel.draw(&labels).map_err(backend_err)?;
    let rows = labels.compute_line_layout().map_err(font_err)?;
    for (((_, top), (_, bottom)), e) in rows.into_iter().zip(entries) {
        let swatch = Swatch {
            at: (x0 + BOX_MARGIN, (top + bottom) / 2),
            style: e.style,
            color: e.color,
        };
        panel.draw(&swatch).map_err(backend_err)?;
    }
    Ok(())
}
