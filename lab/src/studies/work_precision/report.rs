//! The study's chart, CSV table and Markdown summary.

use super::WorkPrecisionStudy;
use crate::plot::{Chart, Series};

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
        .size(1000, 720);
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
    pub fn csv(&self) -> String {
        let mut out = String::from(
            "method,parameters,h,n,tolerance,error,seconds,force_evaluations,pareto,failure,external\n",
        );
        let opt = |x: Option<f64>| x.map(|v| format!("{v:e}")).unwrap_or_default();
        for p in &self.points {
            out.push_str(&format!(
                "{},\"{}\",{},{},{},{:e},{:e},{},{},{},{}\n",
                p.method,
                p.parameters,
                opt(p.h),
                p.n.map(|n| n.to_string()).unwrap_or_default(),
                opt(p.tolerance),
                p.error,
                p.seconds,
                p.force_evaluations,
                p.pareto,
                p.failure
                    .as_deref()
                    .map(|f| format!("\"{}\"", f.replace('"', "'")))
                    .unwrap_or_default(),
                p.external
            ));
        }
        out
    }

    /// Markdown table of the fastest configurations per method and target.
    pub fn summary(&self) -> String {
        let mut out = format!(
            "{}: T = {}, errors against the {}\n\n| method | target | fastest | seconds | error |\n|---|---|---|---|---|\n",
            self.scene, self.horizon, self.reference
        );
        for f in &self.fastest {
            let method = if self
                .points
                .iter()
                .any(|p| p.method == f.method && p.external)
            {
                format!("{} (external)", f.method)
            } else {
                f.method.clone()
            };
            match &f.best {
                Some((params, s, e)) => out.push_str(&format!(
                    "| {method} | {:.0e} | {params} | {s:.3e} | {e:.2e} |\n",
                    f.target
                )),
                None => out.push_str(&format!(
                    "| {method} | {:.0e} | not reached | | |\n",
                    f.target
                )),
            }
        }
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
