//! The study's tables, Markdown summary and charts.

use super::{SOLVERS, ScalingStudy, ran};
use crate::error::LabError;
use crate::error::Result;
use crate::plot::{Chart, Series};
use crate::studies::write_file;
use galerkin_vi::integrator::StageSolver;
use std::path::{Path, PathBuf};

fn opt(x: Option<f64>) -> String {
    x.map(|v| format!("{v:e}")).unwrap_or_default()
}

impl ScalingStudy {
    /// Every point as CSV.
    pub fn csv(&self) -> String {
        let mut s = String::from(
            "family,solver,n,bodies,dim,h,steps,samples,batch,seconds_per_step,\
             min_seconds_per_step,\
             iterations,\
             inner_iterations,factorizations,fallbacks,map_difference,skipped,failure\n",
        );
        let quote = |x: &Option<String>| {
            x.as_deref()
                .map(|f| format!("\"{}\"", f.replace('"', "'")))
                .unwrap_or_default()
        };
        for p in &self.points {
            s.push_str(&format!(
                "{},{},{},{},{},{:e},{},{},{},{:e},{:e},{},{},{},{},{},{},{}\n",
                p.family,
                p.solver,
                p.n,
                p.bodies,
                p.dim,
                p.h,
                p.steps,
                p.samples,
                p.batch,
                p.seconds_per_step,
                p.min_seconds_per_step,
                p.iterations,
                p.inner_iterations,
                p.factorizations,
                p.fallbacks,
                opt(p.map_difference),
                quote(&p.skipped),
                quote(&p.failure)
            ));
        }
        s
    }

    /// Largest relative map difference from exact over all points.
    pub fn max_map_difference(&self) -> f64 {
        self.points
            .iter()
            .filter_map(|p| p.map_difference)
            .fold(0.0, f64::max)
    }

    /// Markdown summary: exponents, auto / best, the point table.
    pub fn summary(&self) -> String {
        let mut s = String::from(
            "# Stage-solver scaling\n\n## Fitted exponents (seconds per step ∝ xᵖ)\n\n",
        );
        s.push_str(
            "| family | x | solver | p | points | rms residual (decades) |\n\
             |---|---|---|---|---|---|\n",
        );
        for f in &self.fits {
            let p = f
                .exponent
                .map(|v| format!("{v:.2}"))
                .unwrap_or_else(|| "—".into());
            let r = f
                .residual
                .map(|v| format!("{v:.3}"))
                .unwrap_or_else(|| "—".into());
            s.push_str(&format!(
                "| {} | {} | {} | {p} | {} | {r} |\n",
                f.family, f.variable, f.solver, f.points
            ));
        }
        let within = self.ratios.iter().filter(|r| r.ratio <= 1.2).count();
        let within_min = self
            .ratios
            .iter()
            .filter(|r| r.ratio_of_minima <= 1.2)
            .count();
        s.push_str(&format!(
            "\n## auto against the fastest explicit solver\n\nWithin 1.2× by the medians: \
             {within} of {} points; by the fastest samples: {within_min}.\n\n\
             | family | n | N | best | best s/step | auto s/step | auto / best | of minima |\n\
             |---|---|---|---|---|---|---|---|\n",
            self.ratios.len()
        ));
        for r in &self.ratios {
            let flag = if r.ratio > 1.2 { " **>1.2**" } else { "" };
            s.push_str(&format!(
                "| {} | {} | {} | {} | {:.3e} | {:.3e} | {:.2}{flag} | {:.2} |\n",
                r.family,
                r.n,
                r.bodies,
                r.best,
                r.best_seconds,
                r.auto_seconds,
                r.ratio,
                r.ratio_of_minima
            ));
        }
        s.push_str(&format!(
            "\n## Points\n\nLargest final-state difference from exact (relative): {:.2e}.\n\n\
             | family | solver | n | N | s/step | Newton it/step | inner it/step | \
             factorisations/step | fallbacks/step | Δ vs exact | note |\n\
             |---|---|---|---|---|---|---|---|---|---|---|\n",
            self.max_map_difference()
        ));
        for p in &self.points {
            let note = p.skipped.as_deref().or(p.failure.as_deref()).unwrap_or("");
            s.push_str(&format!(
                "| {} | {} | {} | {} | {:.3e} | {:.2} | {:.1} | {:.2} | {:.2} | {} | {note} |\n",
                p.family,
                p.solver,
                p.n,
                p.bodies,
                p.seconds_per_step,
                p.iterations,
                p.inner_iterations,
                p.factorizations,
                p.fallbacks,
                p.map_difference
                    .map(|v| format!("{v:.1e}"))
                    .unwrap_or_else(|| "—".into())
            ));
        }
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
        let names = [
            "solver_scaling.csv",
            "solver_scaling.json",
            "solver_scaling.md",
            "scaling_n.svg",
            "scaling_bodies.svg",
        ];
        let paths: Vec<PathBuf> = names.iter().map(|n| dir.join(n)).collect();
        write_file(&paths[0], &self.csv())?;
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
