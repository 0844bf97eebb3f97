//! The categorical [`HeatMap`] chart (e.g. stability maps).

use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::axis::{Axis, Scale, cell_edges, min_max, padded_range, to_plot};
use super::error::{PlotError, backend_err};
use super::layout::{FONT, MARGIN, frame, titled, write_file};

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::tests::{assert_contains, stability_map};

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
}
