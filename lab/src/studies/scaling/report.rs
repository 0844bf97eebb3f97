//! The study's tables, Markdown summary and charts.

use super::{SOLVERS, ScalingStudy, ran};
use crate::error::LabError;
use crate::error::Result;
use crate::plot::{Chart, Series};
use crate::studies::write_file;
use crate::table;
use galerkin_vi::integrator::StageSolver;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// One CSV line of a scaling point.
#[derive(Serialize)]
struct Row<'a> {
    family: &'a str,
    solver: &'a str,
    n: usize,
    bodies: usize,
    dim: usize,
    #[serde(serialize_with = "table::sci")]
    h: f64,
    steps: usize,
    samples: usize,
    batch: usize,
    #[serde(serialize_with = "table::sci")]
    seconds_per_step: f64,
    #[serde(serialize_with = "table::sci")]
    min_seconds_per_step: f64,
    #[serde(serialize_with = "table::plain")]
    iterations: f64,
    #[serde(serialize_with = "table::plain")]
    inner_iterations: f64,
    #[serde(serialize_with = "table::plain")]
    factorizations: f64,
    #[serde(serialize_with = "table::plain")]
    fallbacks: f64,
    #[serde(serialize_with = "table::sci_opt")]
    map_difference: Option<f64>,
    #[serde(serialize_with = "table::quoted")]
    skipped: Option<&'a str>,
    #[serde(serialize_with = "table::quoted")]
    failure: Option<&'a str>,
}

impl ScalingStudy {
    /// Every point as CSV.
    pub fn csv(&self) -> Result<String> {
        table::csv_text(self.points.iter().map(|p| Row {
            family: &p.family,
            solver: &p.solver,
            n: p.n,
            bodies: p.bodies,
            dim: p.dim,
            h: p.h,
            steps: p.steps,
            samples: p.samples,
            batch: p.batch,
            seconds_per_step: p.seconds_per_step,
            min_seconds_per_step: p.min_seconds_per_step,
            iterations: p.iterations,
            inner_iterations: p.inner_iterations,
            factorizations: p.factorizations,
            fallbacks: p.fallbacks,
            map_difference: p.map_difference,
            skipped: p.skipped.as_deref(),
            failure: p.failure.as_deref(),
        }))
    }

    /// Largest relative map difference from exact over all points.
    pub fn max_map_difference(&self) -> f64 {
        self.points
            .iter()
            .filter_map(|p| p.map_difference)
            .fold(0.0, crate::distance::nan_max)
    }

    /// Markdown summary: exponents, auto / best, the point table.
    pub fn summary(&self) -> String {
        let dash = || "—".to_string();
        let mut s = String::from(
            "# Stage-solver scaling\n\n## Fitted exponents (seconds per step ∝ xᵖ)\n\n",
        );
        s.push_str(&table::markdown(
            &[
                "family",
                "x",
                "solver",
                "p",
                "points",
                "rms residual (decades)",
            ],
            self.fits.iter().map(|f| {
                [
                    f.family.clone(),
                    f.variable.clone(),
                    f.solver.clone(),
                    f.exponent.map_or_else(dash, |v| format!("{v:.2}")),
                    f.points.to_string(),
                    f.residual.map_or_else(dash, |v| format!("{v:.3}")),
                ]
            }),
        ));
        let within = self.ratios.iter().filter(|r| r.ratio <= 1.2).count();
        let within_min = self
            .ratios
            .iter()
            .filter(|r| r.ratio_of_minima <= 1.2)
            .count();
        s.push_str(&format!(
            "\n## auto against the fastest explicit solver\n\nWithin 1.2× by the medians: \
             {within} of {} points; by the fastest samples: {within_min}.\n\n",
            self.ratios.len()
        ));
        s.push_str(&table::markdown(
            &[
                "family",
                "n",
                "N",
                "best",
                "best s/step",
                "auto s/step",
                "auto / best",
                "of minima",
            ],
            self.ratios.iter().map(|r| {
                let flag = if r.ratio > 1.2 { " **>1.2**" } else { "" };
                [
                    r.family.clone(),
                    r.n.to_string(),
                    r.bodies.to_string(),
                    r.best.to_string(),
                    format!("{:.3e}", r.best_seconds),
                    format!("{:.3e}", r.auto_seconds),
                    format!("{:.2}{flag}", r.ratio),
                    format!("{:.2}", r.ratio_of_minima),
                ]
            }),
        ));
        s.push_str(&format!(
            "\n## Points\n\nLargest final-state difference from exact (relative): {:.2e}.\n\n",
            self.max_map_difference()
        ));
        s.push_str(&table::markdown(
            &[
                "family",
                "solver",
                "n",
                "N",
                "s/step",
                "Newton it/step",
                "inner it/step",
                "factorisations/step",
                "fallbacks/step",
                "Δ vs exact",
                "note",
            ],
            self.points.iter().map(|p| {
                [
                    p.family.clone(),
                    p.solver.clone(),
                    p.n.to_string(),
                    p.bodies.to_string(),
                    format!("{:.3e}", p.seconds_per_step),
                    format!("{:.2}", p.iterations),
                    format!("{:.1}", p.inner_iterations),
                    format!("{:.2}", p.factorizations),
                    format!("{:.2}", p.fallbacks),
                    p.map_difference.map_or_else(dash, |v| format!("{v:.1e}")),
                    p.skipped
                        .as_deref()
                        .or(p.failure.as_deref())
                        .unwrap_or("")
                        .to_string(),
                ]
            }),
        ));
        s
    }

    /// Time per step against n (Kepler solid, outer solar system dashed) and against N.
    pub fn charts(&self) -> (Chart, Chart) {
        let series = |family: &str, solver: StageSolver, by_n: bool| -> Vec<(f64, f64)> {
            self.points
                .iter()
                .filter(|p| p.family == family && p.solver == solver.as_str() && ran(p))
                .map(|p| {
                    (
                        (if by_n { p.n } else { p.bodies }) as f64,
                        p.seconds_per_step,
                    )
                })
                .collect()
        };
        let mut by_n = Chart::new("Time per step against n", "n", "seconds per step")
            .log_x()
            .log_y();
        let mut by_bodies = Chart::new(
            format!(
                "Time per step against N (planetesimal ring, n = {})",
                self.config.ring_n
            ),
            "bodies N",
            "seconds per step",
        )
        .log_x()
        .log_y();
        for (i, solver) in SOLVERS.into_iter().enumerate() {
            by_n.push(
                Series::line_markers(format!("{solver} (Kepler)"), series("kepler", solver, true))
                    .with_color(i),
            );
            by_n.push(
                Series::dashed(
                    format!("{solver} (outer solar system)"),
                    series("outer-solar-system", solver, true),
                )
                .with_color(i),
            );
            by_bodies.push(
                Series::line_markers(solver.as_str(), series("ring", solver, false)).with_color(i),
            );
        }
        (by_n, by_bodies)
    }

    /// Write `solver_scaling.{csv,json,md}`, `scaling_n.svg` and `scaling_bodies.svg`.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let paths: Vec<PathBuf> = super::FILES.iter().map(|n| dir.join(n)).collect();
        write_file(&paths[0], &self.csv()?)?;
        let json =
            serde_json::to_string_pretty(self).map_err(|e| LabError::Serialize(e.to_string()))?;
        write_file(&paths[1], &json)?;
        write_file(&paths[2], &self.summary())?;
        let (a, b) = self.charts();
        for (chart, path) in [(a, &paths[3]), (b, &paths[4])] {
            chart
                .save_svg(path)
                .map_err(|e| LabError::Plot(e.to_string()))?;
        }
        Ok(paths)
    }
}
