//! Text, CSV and chart output of a [`PeriodicReport`].

use super::PeriodicReport;
use crate::error::LabError;
use crate::error::Result;
use crate::plot::{Chart, Series};
use std::fmt::Write;

impl PeriodicReport {
    /// A human-readable summary (period, energy, action, residual, invariants, multipliers,
    /// closing, refinement).
    pub fn summary(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "periodic {} ({}), K = {} modes, M = {} trapezoid nodes",
            self.scene, self.kind, self.modes, self.nodes
        );
        let _ = writeln!(
            s,
            "  Newton iterations    {} (residuals {})",
            self.iterations,
            self.residual_history
                .iter()
                .map(|r| format!("{r:.1e}"))
                .collect::<Vec<_>>()
                .join(" → ")
        );
        let _ = writeln!(s, "  residual             {:.3e}", self.residual);
        let _ = write!(s, "  period               {:.12}", self.period);
        if let Some(r) = self.reference_period {
            let _ = write!(s, "   (reference {r}, difference {:.2e})", self.period - r);
        }
        let _ = writeln!(s);
        let _ = writeln!(
            s,
            "  energy               {:.15} (spread over the nodes {:.1e})",
            self.energy, self.energy_spread
        );
        if let Some(e) = self.target_energy {
            let _ = writeln!(s, "  prescribed energy    {e:.15}");
        }
        let _ = writeln!(s, "  action               {:.15}", self.action);
        let _ = writeln!(
            s,
            "  Euler–Lagrange resid {:.3e} (max along the series); last modes {:.1e} of the largest",
            self.equation_residual, self.tail
        );
        for (name, value) in &self.invariants {
            let _ = writeln!(s, "  {name:<20} {value:.15e}");
        }
        if !self.multipliers.is_empty() {
            let _ = writeln!(
                s,
                "  Floquet multipliers  ({} within 1e-4 of 1, {} expected from the symmetries; max ||λ|−1| = {:.2e}; monodromy symplecticity defect {:.1e})",
                self.trivial_multipliers,
                self.expected_trivial_multipliers,
                self.max_modulus_defect.unwrap_or(f64::NAN),
                self.monodromy_symplecticity_defect.unwrap_or(f64::NAN)
            );
            for (i, z) in self.multipliers.iter().enumerate() {
                let tag = if i < self.trivial_multipliers {
                    "trivial"
                } else {
                    ""
                };
                let _ = writeln!(
                    s,
                    "    {:+.12} {:+.12}i   |λ| = {:.12}  {tag}",
                    z[0],
                    z[1],
                    z[0].hypot(z[1])
                );
            }
        }
        if let Some(c) = &self.closing {
            let _ = writeln!(
                s,
                "  closing              after 1 period {:.2e}, after {} periods |Δq| = {:.2e}, |Δp| = {:.2e} ({} steps/period, n = {})",
                c.position_distance_one_period,
                c.periods,
                c.position_distance,
                c.momentum_distance,
                c.steps_per_period,
                c.n
            );
        }
        if self.refinement.len() > 1 {
            let _ = writeln!(
                s,
                "  refinement in K:   K   period              action              E–L residual  difference"
            );
            for r in &self.refinement {
                let _ = writeln!(
                    s,
                    "                    {:>3}   {:.15}   {:.15}   {:.2e}      {:.2e}",
                    r.modes, r.period, r.action, r.equation_residual, r.difference
                );
            }
            if let Some(f) = &self.refinement_fit {
                let _ = writeln!(
                    s,
                    "  fitted: E–L residual ≈ {:.2e} · {:.4}^K (K in {:.0}…{:.0}, {} points, rms {:.2} decades)",
                    f.constant, f.rate, f.window.0, f.window.1, f.points_used, f.residual
                );
            }
        }
        s
    }

    /// The orbit table as CSV (`t, q…, p…`), preceded by `# name = value` summary lines.
    pub fn to_csv(&self) -> Result<String> {
        let mut s = String::new();
        let _ = writeln!(s, "# scene = {}", self.scene);
        let _ = writeln!(s, "# modes = {}", self.modes);
        let _ = writeln!(s, "# period = {:.17e}", self.period);
        let _ = writeln!(s, "# energy = {:.17e}", self.energy);
        let _ = writeln!(s, "# action = {:.17e}", self.action);
        let _ = writeln!(s, "# residual = {:.3e}", self.residual);
        if let Some(l) = self.angular_momentum {
            let _ = writeln!(s, "# angular_momentum = {l:.17e}");
        }
        let mults: Vec<String> = self
            .multipliers
            .iter()
            .map(|z| format!("{:.12e}{:+.12e}i", z[0], z[1]))
            .collect();
        let _ = writeln!(s, "# multipliers = {}", mults.join(" "));
        let d = self.q0.len();
        let mut head = vec!["t".to_string()];
        if self.state_names.len() == 2 * d {
            head.extend(self.state_names.iter().cloned());
        } else {
            head.extend((0..d).map(|i| format!("q{i}")));
            head.extend((0..d).map(|i| format!("p{i}")));
        }
        let rows = self.t.iter().enumerate().map(|(k, t)| {
            std::iter::once(t)
                .chain(&self.q[k])
                .chain(&self.p[k])
                .map(|x| format!("{x:.17e}"))
        });
        s.push_str(&crate::table::csv_records(&head, rows)?);
        Ok(s)
    }

    /// The report as pretty JSON.
    pub fn to_json(&self) -> Result<String> {
        serde_json::to_string_pretty(self).map_err(|e| LabError::Serialize(e.to_string()))
    }

    /// The orbit: one curve per body in the plane of the first two axes (N bodies), or the
    /// phase portrait (q₀, p₀) otherwise.
    pub fn orbit_chart(&self) -> Chart {
        let title = format!(
            "{}: periodic orbit, T = {:.10}, K = {}",
            self.scene, self.period, self.modes
        );
        match self.body_dim {
            Some(k) => {
                let bodies = self.q0.len() / k;
                let mut chart = Chart::new(title, "x", "y").equal_aspect();
                for b in 0..bodies {
                    let pts = self.q.iter().map(|q| (q[b * k], q[b * k + 1]));
                    chart.push(Series::line(format!("body {}", b + 1), pts).with_color(b));
                    chart.push(
                        Series::markers(
                            format!("body {} at t = 0", b + 1),
                            [(self.q0[b * k], self.q0[b * k + 1])],
                        )
                        .with_color(b),
                    );
                }
                chart
            }
            None => {
                let d = self.q0.len();
                let (q, p) = match (self.state_names.first(), self.state_names.get(d)) {
                    // An expression Lagrangian's names (the first coordinate's phase plane).
                    (Some(q), Some(p)) if q != "q0" => (q.clone(), p.clone()),
                    _ => ("q".to_string(), "p".to_string()),
                };
                Chart::new(title, q, p)
            }
            .with_series(Series::line(
                "orbit",
                self.q.iter().zip(&self.p).map(|(q, p)| (q[0], p[0])),
            )),
        }
    }

    /// The refinement in K: Euler–Lagrange residual and period (or action) difference against
    /// K on a log scale, with the fitted geometric rate.
    pub fn refinement_chart(&self) -> Chart {
        let mut chart = Chart::new(
            format!(
                "{}: exponential convergence in the number of modes K",
                self.scene
            ),
            "modes K",
            "error",
        )
        .log_y();
        chart.push(Series::line_markers(
            "max Euler–Lagrange residual along the series",
            self.refinement
                .iter()
                .map(|r| (r.modes as f64, r.equation_residual)),
        ));
        let label = if self.target_energy.is_some() {
            "|T_K − T_Kmax|"
        } else {
            "|S_K − S_Kmax|"
        };
        chart.push(Series::line_markers(
            label,
            self.refinement
                .iter()
                .filter(|r| r.difference > 0.0)
                .map(|r| (r.modes as f64, r.difference)),
        ));
        if let Some(f) = &self.refinement_fit {
            let (a, b) = f.window;
            let pts = [a, b].map(|k| (k, f.constant * f.rate.powf(k)));
            chart.push(Series::dashed(
                format!("fit {:.2e} · {:.3}^K", f.constant, f.rate),
                pts,
            ));
        }
        chart
    }
}
