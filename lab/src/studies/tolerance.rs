//! `gvi tolerance-study`: does a tolerance-driven run ([`galerkin_vi::adaptive`]) meet the requested
//! tolerance, and is it cheaper than the cheapest fixed n that meets it?
//!
//! For every requested tolerance and every error control, the scene is run with [`solve`]
//! (the scene's basis, quadrature, h and steps with that `tol`, ladder and control) and its
//! max position error over the step ends (max-norm) is measured against a reference; every
//! fixed n from the smallest to the largest rung of the ladder is run once with the same h and
//! steps, and the cheapest one (force evaluations, [`Trajectory::gradient_evaluations`]) whose error meets
//! the tolerance is the competitor. The reference is the exact solution where one is known,
//! for N-body scenes Gauss collocation with 6 stages at h/K (K as in
//! [`crate::nbody_report`]: the shortest two-body period spans ≥ 256 reference steps, and at
//! least 16 substeps), otherwise the spectral run of [`Reference::for_system`].
//!
//! Each row also carries the oracle bound of [`super::allocation`]: the cheapest choice of n
//! per step with every one-step error known (n from the smallest rung to four above the
//! largest cheapest fixed n, one-step errors against a solve eight above that), within the
//! summed one-step error of the cheapest fixed n — what choosing n alone could save.

use super::allocation::{Allocation, one_step_errors};
use super::{Reference, max_norm_diff, write_file};
use crate::error::Result;
use crate::plot::{Chart, Series};
use crate::scene::BuiltScene;
use crate::table;
use galerkin_vi::adaptive::{DEFAULT_LADDER, ErrorControl};
use galerkin_vi::baselines::GaussCollocationBaseline;
use galerkin_vi::integrator::{GalerkinIntegrator, StageSolver};
use galerkin_vi::method::MethodSpec;
use galerkin_vi::solve::{Solution, solve};
use galerkin_vi::systems::{NBody, System};
use galerkin_vi::trajectory::Trajectory;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// What to measure.
#[derive(Debug, Clone, Serialize)]
pub struct ToleranceConfig {
    /// Requested tolerances (max position error over the run).
    pub tols: Vec<f64>,
    /// Error controls to compare.
    pub controls: Vec<ErrorControl>,
    /// The ladder of n (also the range of the fixed-n scan).
    pub ladder: Vec<usize>,
}

impl Default for ToleranceConfig {
    fn default() -> Self {
        ToleranceConfig {
            tols: vec![1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
            controls: vec![ErrorControl::Calibrated, ErrorControl::Embedded],
            ladder: DEFAULT_LADDER.to_vec(),
        }
    }
}

/// One adaptive run at one tolerance, with the cheapest fixed n meeting the same tolerance.
#[derive(Debug, Clone, Serialize)]
pub struct ToleranceRow {
    /// Requested tolerance.
    pub tol: f64,
    /// Error control.
    pub control: ErrorControl,
    /// Achieved max position error.
    pub error: f64,
    /// error / tol.
    pub factor: f64,
    /// Force evaluations of the adaptive run (including checks and rejected attempts).
    pub cost: usize,
    /// Smallest and largest n used.
    pub n_range: (usize, usize),
    /// Steps solved at two rungs.
    pub checks: usize,
    /// Warnings of the run (tolerance not met at the largest n) or its failure.
    pub warnings: usize,
    /// Cheapest fixed n meeting tol: (n, error, cost).
    pub fixed: Option<(usize, f64, usize)>,
    /// fixed cost / adaptive cost (> 1: the adaptive run is cheaper).
    pub saving: Option<f64>,
    /// Wall time of the adaptive run, seconds (secondary to the deterministic cost).
    pub seconds: f64,
    /// Wall time of the cheapest fixed-n run meeting tol, seconds.
    pub fixed_seconds: Option<f64>,
    /// The oracle bound ([`super::allocation`]): the cheapest per-step allocation of n whose
    /// summed one-step error is at most that of the cheapest fixed n.
    pub oracle: Option<Allocation>,
    /// The oracle's budget: the summed one-step error of the cheapest fixed n.
    pub oracle_budget: Option<f64>,
}

/// One CSV line of the tolerance study (empty cells where a row has no fixed or oracle run).
#[derive(Serialize)]
struct ToleranceCsvRow<'a> {
    scene: &'a str,
    #[serde(serialize_with = "table::sci")]
    tol: f64,
    control: String,
    #[serde(serialize_with = "table::sci")]
    error: f64,
    #[serde(serialize_with = "table::fixed::<3, _>")]
    factor: f64,
    cost: usize,
    n_min: usize,
    n_max: usize,
    checks: usize,
    warnings: usize,
    fixed_n: Option<usize>,
    #[serde(serialize_with = "table::sci_opt")]
    fixed_error: Option<f64>,
    fixed_cost: Option<usize>,
    #[serde(serialize_with = "table::fixed_opt::<3, _>")]
    saving: Option<f64>,
    #[serde(serialize_with = "table::fixed::<4, _>")]
    seconds: f64,
    #[serde(serialize_with = "table::fixed_opt::<4, _>")]
    fixed_seconds: Option<f64>,
    #[serde(serialize_with = "table::fixed_opt::<0, _>")]
    oracle_cost: Option<f64>,
    oracle_n_min: Option<usize>,
    oracle_n_max: Option<usize>,
}

/// The study of one scene.
#[derive(Debug, Clone, Serialize)]
pub struct ToleranceStudy {
    /// Scene name.
    pub scene: String,
    /// Step size and steps.
    pub h: f64,
    /// Number of steps.
    pub steps: usize,
    /// Reference description.
    pub reference: String,
    /// Every fixed n run: (n, error, cost); error NaN for a failed run.
    pub fixed: Vec<(usize, f64, usize)>,
    /// Wall time of every fixed n run, seconds (same order as `fixed`).
    pub fixed_seconds: Vec<f64>,
    /// One row per tolerance and control.
    pub rows: Vec<ToleranceRow>,
}

/// The files [`ToleranceStudy::write_to`] writes for the scene named `scene`:
/// `<scene>-tolerance.csv`, `.md`, `-error.svg` and `-cost.svg`.
pub fn file_names(scene: &str) -> [String; 4] {
    [".csv", ".md", "-error.svg", "-cost.svg"].map(|suffix| format!("{scene}-tolerance{suffix}"))
}

/// The memory [`tolerance_study`] needs, estimated before it runs: the reference positions at
/// the step ends (and the reference run behind them), the largest run (n up to eight above the
/// ladder's top, for the oracle) and the one-step errors of every n, checked against
/// [`crate::memory::LIMIT_BYTES`].
pub fn ensure_memory(scene: &BuiltScene, config: &ToleranceConfig) -> Result<()> {
    let system = scene.euclidean()?;
    let (m, init) = (&scene.method, &scene.initial);
    let d = init.q.len();
    let steps = m.steps as f64;
    let lo = config.ladder.first().copied().unwrap_or(4);
    let hi = config.ladder.last().copied().unwrap_or(64).max(lo);
    let reference = Reference::estimated_bytes(system, init, m.h, m.h * steps)
        + 2.0 * steps * (8 * d + 24) as f64;
    let runs =
        steps * (crate::memory::trajectory_bytes_per_step(hi + 8, d) + 16.0 * (hi - lo + 9) as f64);
    crate::memory::ensure_fits(
        format!("the tolerance study of {} steps", m.steps),
        reference + runs,
        "every run keeps its trajectory; fewer --steps",
    )
}

/// Run the study on a scene (its method's basis, quadrature, h and steps).
pub fn tolerance_study(scene: &BuiltScene, config: &ToleranceConfig) -> Result<ToleranceStudy> {
    let ladder = &config.ladder;
    if ladder.is_empty() || ladder.windows(2).any(|w| w[0] >= w[1]) {
        // Not increasing, the fixed-n scan between its ends would be empty (all-NaN rows).
        return Err(crate::error::LabError::InvalidArgument {
            name: "ladder (--ladder)".into(),
            reason: format!("{ladder:?}: the ladder of n must be non-empty and increasing"),
        });
    }
    let system = scene.euclidean()?;
    let (reference, label) = step_end_reference(system, scene)?;
    study_system(system, scene, config, &reference, label)
}

/// Reference positions at the step ends t0 + k h, k = 0…steps.
fn step_end_reference<S: System>(
    system: &S,
    scene: &BuiltScene,
) -> Result<(Vec<Vec<f64>>, String)> {
    let (m, init) = (&scene.method, &scene.initial);
    if let Some(nbody) = scene.euclidean()?.as_nbody() {
        let k = gauss_substeps(nbody, &init.q, m.h);
        let mut gauss = GaussCollocationBaseline::new(nbody, 6, m.h / k as f64)?;
        let (rq, _) = gauss.integrate_compensated(&init.q, &init.p, m.steps * k, k)?;
        return Ok((rq, format!("Gauss collocation s = 6, h/{k}")));
    }
    let reference = Reference::for_system(system, init, m.h, m.h * m.steps as f64)?;
    let qs = (0..=m.steps)
        .map(|k| reference.position(init.t0 + k as f64 * m.h))
        .collect::<Result<Vec<_>>>()?;
    Ok((qs, reference.describe().to_string()))
}

fn gauss_substeps(system: &NBody, q: &[f64], h: f64) -> usize {
    let (nb, k) = (system.bodies(), system.body_dim());
    let ms = system.masses();
    let mut shortest = f64::INFINITY;
    for i in 0..nb {
        for j in i + 1..nb {
            let r2: f64 = (0..k).map(|c| (q[i * k + c] - q[j * k + c]).powi(2)).sum();
            let period =
                std::f64::consts::TAU * (r2 * r2.sqrt() / (system.g() * (ms[i] + ms[j]))).sqrt();
            shortest = shortest.min(period);
        }
    }
    if shortest.is_finite() && shortest > 0.0 {
        ((h * 256.0 / shortest).ceil() as usize).clamp(16, 100_000)
    } else {
        64
    }
}

/// Index of the cheapest fixed-n run (n, error, cost) whose error meets tol.
fn cheapest_fixed(fixed: &[(usize, f64, usize)], tol: f64) -> Option<usize> {
    fixed
        .iter()
        .enumerate()
        .filter(|(_, f)| f.1 <= tol)
        .min_by_key(|(_, f)| f.2)
        .map(|(i, _)| i)
}

fn max_error(traj: &Trajectory, reference: &[Vec<f64>]) -> f64 {
    if traj.q.len() != reference.len() {
        return f64::NAN;
    }
    traj.q
        .iter()
        .zip(reference)
        .map(|(a, b)| max_norm_diff(a, b))
        .fold(0.0, crate::distance::nan_max)
}

fn study_system<S: System>(
    system: &S,
    scene: &BuiltScene,
    config: &ToleranceConfig,
    reference: &[Vec<f64>],
    label: String,
) -> Result<ToleranceStudy> {
    let (m, init) = (&scene.method, &scene.initial);
    let lo = config.ladder.first().copied().unwrap_or(4);
    let hi = config.ladder.last().copied().unwrap_or(64);
    let mut fixed = Vec::new();
    let mut fixed_seconds = Vec::new();
    for n in lo..=hi {
        let gvi = GalerkinIntegrator::from_kinds(m.basis, n, m.quadrature, None, m.h)?;
        let clock = std::time::Instant::now();
        let result = gvi.integrate(system, init.t0, &init.q, &init.p, m.steps);
        fixed_seconds.push(clock.elapsed().as_secs_f64());
        let (err, cost) = match result {
            Ok(t) => (max_error(&t, reference), t.gradient_evaluations()),
            Err(_) => (f64::NAN, 0),
        };
        fixed.push((n, err, cost));
    }
    // The oracle bound: one-step errors for n from the smallest rung to a few above the
    // largest cheapest fixed n, against a solve eight above that.
    let needed = config
        .tols
        .iter()
        .filter_map(|&tol| cheapest_fixed(&fixed, tol).map(|i| fixed[i].0))
        .max();
    let one_step = match needed {
        Some(nf) => {
            let cap = (nf + 4).min(hi);
            let ns: Vec<usize> = (lo..=cap).collect();
            let cost: Vec<f64> = fixed[..ns.len()]
                .iter()
                .map(|f| {
                    if f.1.is_finite() {
                        f.2 as f64 / m.steps as f64
                    } else {
                        f64::INFINITY
                    }
                })
                .collect();
            one_step_errors(system, scene, &ns, &cost, (cap + 8).min(hi.max(cap + 1))).ok()
        }
        None => None,
    };
    let mut rows = Vec::new();
    for &tol in &config.tols {
        let cheapest_at = cheapest_fixed(&fixed, tol);
        let cheapest = cheapest_at.map(|i| fixed[i]);
        let cheapest_seconds = cheapest_at.map(|i| fixed_seconds[i]);
        let oracle_budget = match (&one_step, cheapest) {
            (Some(e), Some((n, _, _))) => e.fixed_error_sum(n),
            _ => None,
        };
        let oracle = match (&one_step, cheapest, oracle_budget) {
            (Some(e), Some((n, _, cost)), Some(budget)) => e.cheapest_within(budget).map(|a| {
                // The fixed choice itself is feasible: never report more than it.
                if a.cost <= cost as f64 {
                    a
                } else {
                    Allocation {
                        cost: cost as f64,
                        error_sum: budget,
                        n_range: (n, n),
                    }
                }
            }),
            _ => None,
        };
        for &control in &config.controls {
            // The scene's basis, quadrature, h and steps with this tolerance, ladder and
            // control (the controller's own stage solver).
            let method = MethodSpec {
                tol: Some(tol),
                ladder: Some(config.ladder.clone()),
                control: Some(control),
                auto_h: false,
                solver: StageSolver::Auto,
                ..m.clone()
            };
            let clock = std::time::Instant::now();
            let result = solve(system, init, &method);
            let seconds = clock.elapsed().as_secs_f64();
            let row = match result {
                Ok(Solution {
                    trajectory: t,
                    adaptive: Some(run),
                    ..
                }) => {
                    let t = &t;
                    let error = max_error(t, reference);
                    let n_lo = t.step_n.iter().copied().min().unwrap_or(0);
                    let n_hi = t.step_n.iter().copied().max().unwrap_or(0);
                    ToleranceRow {
                        tol,
                        control,
                        error,
                        factor: error / tol,
                        cost: run.gradient_evaluations,
                        n_range: (n_lo, n_hi),
                        checks: run.checks,
                        warnings: run.warnings.len(),
                        fixed: cheapest,
                        saving: cheapest.map(|f| f.2 as f64 / run.gradient_evaluations as f64),
                        seconds,
                        fixed_seconds: cheapest_seconds,
                        oracle,
                        oracle_budget,
                    }
                }
                // A failed run (or, which `solve` never returns for a method with `tol`, one
                // without a tolerance-driven report).
                _ => ToleranceRow {
                    tol,
                    control,
                    error: f64::NAN,
                    factor: f64::NAN,
                    cost: 0,
                    n_range: (0, 0),
                    checks: 0,
                    warnings: 1,
                    fixed: cheapest,
                    saving: None,
                    seconds,
                    fixed_seconds: cheapest_seconds,
                    oracle,
                    oracle_budget,
                },
            };
            rows.push(row);
        }
    }
    Ok(ToleranceStudy {
        scene: scene.name.clone(),
        h: m.h,
        steps: m.steps,
        reference: label,
        fixed,
        fixed_seconds,
        rows,
    })
}

impl ToleranceStudy {
    /// The rows as CSV.
    pub fn to_csv(&self) -> Result<String> {
        table::csv_text(self.rows.iter().map(|r| ToleranceCsvRow {
            scene: &self.scene,
            tol: r.tol,
            control: r.control.to_string(),
            error: r.error,
            factor: r.factor,
            cost: r.cost,
            n_min: r.n_range.0,
            n_max: r.n_range.1,
            checks: r.checks,
            warnings: r.warnings,
            fixed_n: r.fixed.map(|f| f.0),
            fixed_error: r.fixed.map(|f| f.1),
            fixed_cost: r.fixed.map(|f| f.2),
            saving: r.saving,
            seconds: r.seconds,
            fixed_seconds: r.fixed_seconds,
            oracle_cost: r.oracle.map(|a| a.cost),
            oracle_n_min: r.oracle.map(|a| a.n_range.0),
            oracle_n_max: r.oracle.map(|a| a.n_range.1),
        }))
    }

    /// The rows as a Markdown table.
    pub fn to_markdown(&self) -> String {
        let rows = self.rows.iter().map(|r| {
            let (fixed_n, fixed_error, fixed_cost) = match r.fixed {
                Some((n, e, c)) => (n.to_string(), format!("{e:.1e}"), c.to_string()),
                None => ("none ≤ ladder max".into(), "–".into(), "–".into()),
            };
            let (oracle, oracle_saving) = match (r.oracle, r.fixed) {
                (Some(a), Some(f)) => (
                    format!("{:.0} ({}–{})", a.cost, a.n_range.0, a.n_range.1),
                    format!("{:.2}×", f.2 as f64 / a.cost),
                ),
                _ => ("–".into(), "–".into()),
            };
            [
                format!("{:.0e}", r.tol),
                r.control.to_string(),
                format!("{:.1e}", r.error),
                format!("{:.2}", r.factor),
                r.cost.to_string(),
                format!("{}–{}", r.n_range.0, r.n_range.1),
                r.checks.to_string(),
                fixed_n,
                fixed_error,
                fixed_cost,
                r.saving.map_or("–".into(), |s| format!("{s:.2}×")),
                format!("{:.1}", 1e3 * r.seconds),
                r.fixed_seconds
                    .map_or("–".into(), |s| format!("{:.1}", 1e3 * s)),
                oracle,
                oracle_saving,
            ]
        });
        format!(
            "{} (h = {}, {} steps; reference: {})\n\n{}",
            self.scene,
            self.h,
            self.steps,
            self.reference,
            table::markdown(
                &[
                    "tol",
                    "control",
                    "achieved",
                    "×tol",
                    "cost",
                    "n",
                    "checks",
                    "cheapest fixed n",
                    "its error",
                    "its cost",
                    "saving",
                    "time (ms)",
                    "fixed time (ms)",
                    "oracle per-step n: cost (n)",
                    "oracle saving",
                ],
                rows
            )
        )
    }

    /// Achieved error and cost against tol: adaptive (per control) and cheapest fixed n.
    pub fn charts(&self) -> (Chart, Chart) {
        let title = format!("{}: tolerance-driven n against fixed n", self.scene);
        let mut err = Chart::new(&title, "requested tolerance", "achieved max position error")
            .log_x()
            .log_y();
        let mut cost = Chart::new(&title, "requested tolerance", "force evaluations")
            .log_x()
            .log_y();
        let tols: Vec<f64> = self.rows.iter().map(|r| r.tol).collect();
        err.push(Series::dashed("error = tol", tols.iter().map(|&t| (t, t))).with_color(0));
        let mut controls: Vec<ErrorControl> = self.rows.iter().map(|r| r.control).collect();
        controls.dedup();
        controls.sort_by_key(|c| c.to_string());
        controls.dedup();
        for (i, c) in controls.iter().enumerate() {
            let rs = self.rows.iter().filter(|r| r.control == *c);
            err.push(
                Series::line_markers(
                    format!("adaptive ({c})"),
                    rs.clone().map(|r| (r.tol, r.error)),
                )
                .with_color(i + 1),
            );
            cost.push(
                Series::line_markers(
                    format!("adaptive ({c})"),
                    rs.map(|r| (r.tol, r.cost as f64)),
                )
                .with_color(i + 1),
            );
        }
        let fx = self.rows.iter().filter_map(|r| r.fixed.map(|f| (r.tol, f)));
        err.push(
            Series::line_markers("cheapest fixed n", fx.clone().map(|(t, f)| (t, f.1)))
                .with_color(6),
        );
        cost.push(
            Series::line_markers("cheapest fixed n", fx.map(|(t, f)| (t, f.2 as f64)))
                .with_color(6),
        );
        let oracle = self
            .rows
            .iter()
            .filter_map(|r| r.oracle.map(|a| (r.tol, a.cost)));
        cost.push(Series::dashed("oracle per-step n (bound)", oracle).with_color(5));
        (err, cost)
    }

    /// Write `<scene>-tolerance.csv`, `.md`, `-error.svg` and `-cost.svg` to `dir`.
    pub fn write_to(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let [csv, md, es, cs] = file_names(&self.scene).map(|f| dir.join(f));
        write_file(&csv, &self.to_csv()?)?;
        write_file(&md, &self.to_markdown())?;
        let (e, c) = self.charts();
        for (chart, path) in [(e, &es), (c, &cs)] {
            chart
                .save_svg(path)
                .map_err(|e| crate::error::LabError::Plot(e.to_string()))?;
        }
        Ok(vec![csv, md, es, cs])
    }
}
