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

mod axis;
mod chart;
mod error;
mod heatmap;
mod layout;
mod legend;

pub use axis::Scale;
pub use chart::{Chart, MAX_POINTS_PER_SERIES, Series, Style, thin};
pub use error::PlotError;
pub use heatmap::HeatMap;

/// Fixtures shared by the tests of the submodules, and tests spanning them.
#[cfg(test)]
mod tests {
    use super::*;

    pub(super) fn decay(scale: f64) -> Vec<(f64, f64)> {
        let f = |i: i32| (f64::from(i), scale * 10f64.powf(-0.25 * f64::from(i)));
        (0..50).map(f).collect()
    }

    pub(super) fn energy_chart() -> Chart {
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

    pub(super) fn stability_map() -> HeatMap {
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

    pub(super) fn assert_contains(svg: &str, texts: &[&str]) {
        for text in texts {
            assert!(svg.contains(text), "missing {text:?}");
        }
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
