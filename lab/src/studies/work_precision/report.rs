//! The study's chart, CSV table and Markdown summary.

use super::WorkPrecisionStudy;
use crate::error::Result;
use crate::plot::{Chart, Series};
use crate::table;
use serde::Serialize;

/// One CSV line of a work–precision point.
#[derive(Serialize)]
struct WorkRow<'a> {
    method: &'a str,
    #[serde(serialize_with = "table::quoted")]
    parameters: Option<&'a str>,
    #[serde(serialize_with = "table::sci_opt")]
    h: Option<f64>,
    n: Option<usize>,
    quad_points: Option<usize>,
    #[serde(serialize_with = "table::sci_opt")]
    tolerance: Option<f64>,
    #[serde(serialize_with = "table::sci")]
    error: f64,
    #[serde(serialize_with = "table::sci")]
    seconds: f64,
    force_evaluations: usize,
    pareto: bool,
    #[serde(serialize_with = "table::quoted")]
    failure: Option<&'a str>,
    external: bool,
}

impl WorkPrecisionStudy {
    /// Log-log chart of error against seconds: one series per method (Galerkin per h), and
    /// the Pareto front.
    pub fn chart(&self) -> Chart {
        let mut chart = Chart::new(
            format!(
                "{}: work–precision over T = {} (samples every {})",
                self.scene, self.horizon, self.sample_interval
            ),
            "CPU seconds (median)",
            "max position error",
        )
        .log_x()
        .log_y()
        .size(1100, 900);
        // One series per method: the Galerkin bases as markers over all (n, h) — their
        // envelope is the point — and the baselines as lines over their step or tolerance.
        let mut keys: Vec<String> = Vec::new();
        for p in &self.points {
            if !keys.contains(&p.method) {
                keys.push(p.method.clone());
            }
        }
        for k in keys {
            let pts: Vec<(f64, f64)> = self
                .points
                .iter()
                .filter(|p| p.method == k && p.failure.is_none() && p.error > 0.0)
                .map(|p| (p.seconds, p.error))
                .collect();
            if pts.is_empty() {
                continue;
            }
            let external = self.points.iter().any(|p| p.method == k && p.external);
            chart.push(if external {
                Series::line_markers(format!("{k} (external)"), pts)
            } else if k.starts_with("galerkin-kepler") {
                Series::markers(format!("{k} (all h)"), pts)
            } else if k.starts_with("galerkin") && k.ends_with("-econ") {
                Series::markers(format!("{k} (all n, h; ⌈3n/2⌉ Gauss points)"), pts)
            } else if k.starts_with("galerkin") && k.ends_with("-compact") {
                Series::markers(format!("{k} (all n, h; n Gauss points)"), pts)
            } else if k.starts_with("galerkin") && k.ends_with("-colloc") {
                Series::markers(format!("{k} (all n, h; n − 1 Gauss points)"), pts)
            } else if k.starts_with("galerkin") {
                Series::markers(format!("{k} (all n, h)"), pts)
            } else {
                Series::line_markers(k, pts)
            });
        }
        let front: Vec<(f64, f64)> = self
            .pareto_front()
            .iter()
            .filter(|p| p.error > 0.0)
            .map(|p| (p.seconds, p.error))
            .collect();
        chart.push(Series::dashed("Pareto front", front));
        chart
    }

    /// CSV of every point.
    pub fn csv(&self) -> Result<String> {
        table::csv_text(self.points.iter().map(|p| WorkRow {
            method: &p.method,
            parameters: Some(&p.parameters),
            h: p.h,
            n: p.n,
            quad_points: p.quad_points,
            tolerance: p.tolerance,
            error: p.error,
            seconds: p.seconds,
            force_evaluations: p.force_evaluations,
            pareto: p.pareto,
            failure: p.failure.as_deref(),
            external: p.external,
        }))
    }

    /// Markdown table of the fastest configurations per method and target.
    pub fn summary(&self) -> String {
        let rows = self.fastest.iter().map(|f| {
            let method = if self
                .points
                .iter()
                .any(|p| p.method == f.method && p.external)
            {
                format!("{} (external)", f.method)
            } else {
                f.method.clone()
            };
            let target = format!("{:.0e}", f.target);
            match &f.best {
                Some((params, s, e)) => [
                    method,
                    target,
                    params.clone(),
                    format!("{s:.3e}"),
                    format!("{e:.2e}"),
                ],
                None => [
                    method,
                    target,
                    "not reached".into(),
                    String::new(),
                    String::new(),
                ],
            }
        });
        let mut out = format!(
            "{}: T = {}, errors against the {}\n\n{}",
            self.scene,
            self.horizon,
            self.reference,
            table::markdown(&["method", "target", "fastest", "seconds", "error"], rows)
        );
        if let (Some(g), Some(d)) = (
            self.fastest_time("galerkin", 1e-9),
            self.fastest_time("dop853", 1e-9),
        ) {
            out.push_str(&format!(
                "\nAt 1e-9: best Galerkin {g:.3e} s, DOP853 {d:.3e} s (DOP853 / Galerkin = {:.2})\n",
                d / g
            ));
        }
        if !self.external_files.is_empty() {
            out.push_str(&format!(
                "\nExternal rows (timed by their own tools, marked \"(external)\"): {}\n",
                self.external_files.join(", ")
            ));
        }
        out
    }
}
