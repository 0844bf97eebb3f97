//! Running a scene: build the system and the integrator, integrate, and tabulate the states,
//! invariants and (where an exact solution exists) errors. This is what `gvi run` does.
//!
//! A run keeps the whole trajectory (for charts, JSON and `--tol`); the streamed form in
//! [`stream`] writes CSV rows as the steps complete and holds no history. Both go through the
//! monitors of `monitor` (non-finite states, collisions, sanity warnings) and give the same rows
//! byte for byte. A step whose solver fails ends the run with the failure recorded and the rows
//! before it kept. Rigid bodies on SO(3) run in [`rigid_body`].
//!
//! The CSV columns and the summary printed on stderr are described in the guide's command-line
//! page (docs/guide/command-line.md).

use crate::distance::max_norm_diff;
use crate::error::LabError;
use crate::error::Result;
use crate::plot::{Chart, Series};
use crate::scene::{BuiltScene, BuiltSystem, Scene};
use galerkin_vi::GviError;
use galerkin_vi::solve::{AdaptiveReport, Solution, solve_until};
use galerkin_vi::systems::{AnySystem, System};
use galerkin_vi::trajectory::Trajectory;
use serde::Serialize;
use std::time::Instant;

mod chart;
mod monitor;
use chart::run_chart;
pub use chart::{chart_indices, chart_times};
pub mod rigid_body;
pub mod stream;
pub mod time_transform;
use monitor::Monitor;
pub use monitor::{Encounter, SANITY_THRESHOLD};

/// What a run produced. On a Newton failure `failure` is set and the table holds the steps
/// completed before it.
#[derive(Debug, Serialize)]
pub struct RunResult {
    /// The scene, with command-line overrides applied.
    pub scene: Scene,
    /// Column names: `step,t`, the coordinates and momenta ([`crate::names::state_columns`]:
    /// `q0,…,p0,…`, or an expression Lagrangian's own `theta,…,p_theta,…`), then invariants,
    /// then `position_error` if known.
    pub columns: Vec<String>,
    /// One row per step end.
    pub rows: Vec<Vec<f64>>,
    /// Totals and maxima.
    pub summary: RunSummary,
    /// The trajectory (states, Galerkin coefficients, per-step cost).
    pub trajectory: Option<Trajectory>,
    /// The solver error, if the run stopped early.
    #[serde(serialize_with = "serialize_error")]
    pub failure: Option<LabError>,
    /// Chart of the run (orbit for 2-D systems, q(t) otherwise; for N-body systems one orbit
    /// per body, xy projection), when requested.
    #[serde(skip)]
    pub chart: Option<Chart>,
    /// For N-body runs whose orbits span more than a factor 10 in size (the solar system):
    /// a zoomed chart of the inner bodies (those whose orbit stays within a tenth of the
    /// largest), when a chart was requested and at least three bodies qualify.
    #[serde(skip)]
    pub inner_chart: Option<Chart>,
    /// n against time, for tolerance-driven runs with a chart.
    #[serde(skip)]
    pub n_chart: Option<Chart>,
}

fn serialize_error<S: serde::Serializer>(e: &Option<LabError>, s: S) -> Result<S::Ok, S::Error> {
    match e {
        Some(e) => s.serialize_some(&e.to_string()),
        None => s.serialize_none(),
    }
}

/// Summary numbers of a run.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// System name.
    pub system: String,
    /// Method description.
    pub method: String,
    /// Steps completed.
    pub steps: usize,
    /// Max over step ends of the max-norm position error (one-step map), if exact known.
    pub max_position_error: Option<f64>,
    /// Max over t of the Galerkin curves' position error (sampled), if exact known.
    pub max_curve_error: Option<f64>,
    /// Max |I(t_k) − I(t_0)| for each invariant.
    pub invariant_errors: Vec<(String, f64)>,
    /// Max |E(t_k) − E(t_0)| over the energy scale ([`RunSummary::energy_scale`]) for the
    /// energy (NaN for the other invariants, which are often zero up to round-off, and where
    /// the scale is 0).
    pub relative_invariant_errors: Vec<(String, f64)>,
    /// The scale of the relative energy error: how it was taken (`T₀ + |V₀|`, the kinetic
    /// energy plus the magnitude of the potential at the start, for systems with a mass
    /// matrix; `|E₀|` otherwise) and its value.
    pub energy_scale: Option<(String, f64)>,
    /// For point masses: the closest approach of two bodies on the Galerkin curves.
    pub closest_approach: Option<Encounter>,
    /// Forced or time-dependent systems (no conserved energy): the energy balance
    /// E_k − E_0 = ∫(f·q̇ − ∂L/∂t) dt along the Galerkin curves (galerkin_vi::forcing).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub energy_balance: Option<EnergyBalance>,
    /// Newton iterations per step (mean).
    pub newton_iterations_per_step: f64,
    /// Wall-clock seconds of the integration (of a streamed run: with its rows written).
    pub seconds: f64,
    /// Wall-clock seconds of the whole command, from its start to the last file written (set
    /// by `gvi run` just before the summary is printed; the integration is often a small
    /// part of it: tabulating, the errors along the curves, charts, writing).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub command_seconds: Option<f64>,
    /// Force (first-derivative) evaluations, including rejected attempts of `--tol` runs.
    pub force_evaluations: usize,
    /// Warnings (e.g. a tolerance not met at the largest n: best effort kept).
    pub warnings: Vec<String>,
    /// The step size chosen from the tolerance (`auto_h`), with its pilot runs (their force
    /// evaluations are not included in `force_evaluations`).
    pub step_choice: Option<galerkin_vi::adaptive::StepChoice>,
}

/// The energy balance of a forced or time-dependent run, summarised.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct EnergyBalance {
    /// Largest |E_k − E_0|: how far the energy moved.
    pub max_change: f64,
    /// Largest |E_k − E_0 − source_k|: zero for the exact motion.
    pub max_defect: f64,
}

impl EnergyBalance {
    /// From the library's balance.
    pub fn of(b: &galerkin_vi::forcing::Balance) -> Self {
        EnergyBalance {
            max_change: b.max_change(),
            max_defect: b.max_defect(),
        }
    }
}

/// Whether a system has an energy balance instead of a conserved energy.
pub(crate) fn has_energy_balance(system: &AnySystem) -> bool {
    use galerkin_vi::Lagrangian;
    !system.is_autonomous() || system.is_forced()
}

impl std::fmt::Display for RunSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "{}: {}, {} steps", self.system, self.method, self.steps)?;
        if let Some(e) = self.max_position_error {
            writeln!(f, "  max position error at step ends: {e:.3e}")?;
        }
        if let Some(e) = self.max_curve_error {
            writeln!(f, "  max position error along the Galerkin curves: {e:.3e}")?;
        }
        for ((name, e), (_, rel)) in self
            .invariant_errors
            .iter()
            .zip(&self.relative_invariant_errors)
        {
            match (&self.energy_scale, name == "energy") {
                _ if rel.is_nan() => writeln!(f, "  max {name} error: {e:.3e}")?,
                (Some((label, scale)), true) => writeln!(
                    f,
                    "  max {name} error: {e:.3e} (relative {rel:.3e}, to {label} = {scale:.3e})"
                )?,
                _ => writeln!(f, "  max {name} error: {e:.3e} (relative {rel:.3e})")?,
            }
        }
        if let Some(b) = &self.energy_balance {
            writeln!(
                f,
                "  energy balance (E − E₀ − work of the force + ∫∂L/∂t): max {:.3e}, with E \
                 changing by up to {:.3e}",
                b.max_defect, b.max_change
            )?;
        }
        if let Some(c) = &self.closest_approach {
            writeln!(
                f,
                "  closest approach on the Galerkin curves: {} and {} at {:.3e} (t = {:.6e})",
                c.a, c.b, c.separation, c.t
            )?;
        }
        write!(
            f,
            "  Newton iterations per step: {:.2}; force evaluations: {}; integration time: {:.3} s",
            self.newton_iterations_per_step, self.force_evaluations, self.seconds
        )?;
        if let Some(total) = self.command_seconds {
            write!(f, "; whole command: {total:.3} s (wall clock)")?;
        }
        if let Some(c) = &self.step_choice {
            write!(
                f,
                "\n  h chosen from tol: {:.6e} ({} steps; time scale {:.4e}; pilot force \
                 evaluations per unit time: {}; pilots cost {} evaluations)",
                c.h,
                c.steps,
                c.time_scale,
                c.pilots
                    .iter()
                    .map(|p| format!("h = {:.3e}: {:.4e}", p.h, p.cost_per_time))
                    .collect::<Vec<_>>()
                    .join(", "),
                c.pilot_evaluations
            )?;
        }
        for w in &self.warnings {
            write!(f, "\n  warning: {w}")?;
        }
        Ok(())
    }
}

/// Options for [`run_scene`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunOptions {
    /// Samples per step for the error along the Galerkin curves (0: skip).
    pub curve_samples_per_step: usize,
    /// Build a chart.
    pub chart: bool,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            curve_samples_per_step: 16,
            chart: false,
        }
    }
}

/// Run a built scene. Invalid input is an `Err`; a Newton failure is `Ok` with
/// [`RunResult::failure`] set and the partial trajectory kept.
pub fn run_scene(scene: &BuiltScene, options: RunOptions) -> Result<RunResult> {
    run_scene_until(scene, options, &|| false)
}

/// [`run_scene`], asking `stop` before every step (and every few thousand table rows) whether
/// to stop (the Python layer's Ctrl-C): a `true` is an `Err` with
/// [`GviError::Interrupted`] and nothing of the run is
/// kept. Rigid bodies (Lie group runs) are not interrupted.
pub fn run_scene_until(
    scene: &BuiltScene,
    options: RunOptions,
    stop: &dyn Fn() -> bool,
) -> Result<RunResult> {
    match &scene.system {
        BuiltSystem::RigidBody(body) => rigid_body::run_rigid_body(body, scene),
        BuiltSystem::Euclidean(system) => run_system(system, scene, options, stop),
    }
}

/// The memory an in-memory run of `scene` ([`run_scene`]) holds per step and in all: the
/// trajectory at the largest n the method may use, the table row and, with `text`, the
/// output text (JSON when `json`) ([`stream::bytes_per_step`]). `gvi run` refuses a chart,
/// JSON or `--tol` run above [`crate::memory::LIMIT_BYTES`] with it; the Python layer holds
/// its `run_scene` to the same estimate and limit.
pub fn in_memory_bytes(scene: &BuiltScene, json: bool) -> (f64, f64) {
    let d = scene.initial.q.len();
    let columns = 2 + 2 * d + 6;
    let per_step = stream::bytes_per_step(columns, scene.method.largest_n(), d, json);
    (per_step, per_step * scene.method.steps as f64)
}

/// Run a built scene's initial state and method on its (Euclidean) system; the state was
/// checked against it by [`crate::scene::Scene::build`]. The library's
/// [`galerkin_vi::solve::solve`] decides how (fixed n, or n chosen per step with `tol`, h
/// chosen with `auto_h`); the table adds the n, indicator and estimate columns when the
/// solution has a tolerance-driven report.
fn run_system(
    system: &AnySystem,
    scene: &BuiltScene,
    options: RunOptions,
    stop: &dyn Fn() -> bool,
) -> Result<RunResult> {
    let m = &scene.method;
    let init = &scene.initial;
    // The method's own parameter errors (h) come before the time span's, which depends on h.
    m.validate()?;
    let exact = system.exact_solution(init.t0, &init.q, &init.p)?;
    let start = Instant::now();
    monitor::check_time_span(init.t0, m.h, m.steps)?;
    let (solution, failure) = match solve_until(system, init, m, stop) {
        Ok(s) => (s, None),
        // Stopped on request: nothing of the run is kept.
        Err(f) if matches!(f.error, GviError::Interrupted { .. }) => return Err(f.error.into()),
        Err(f) => match f.partial {
            Some(partial) => (*partial, Some(f.error.into())),
            None => return Err(f.error.into()),
        },
    };
    let seconds = start.elapsed().as_secs_f64();

    let names = system.invariant_names();
    let mut columns = vec!["step".to_string(), "t".to_string()];
    columns.extend(crate::names::state_columns(system));
    columns.extend(names.iter().map(|s| s.to_string()));
    if exact.is_some() {
        columns.push("position_error".into());
    }
    if solution.adaptive.is_some() {
        columns.push("n".into());
        columns.push("indicator".into());
        columns.push("estimate".into());
    }
    let Solution {
        mut trajectory,
        adaptive,
        step_choice,
    } = solution;
    let mut monitor = Monitor::new(system, &init.q, &init.p, init.t0)?;
    let mut rows = Vec::with_capacity(trajectory.q.len());
    let mut failure = failure;
    for k in 0..trajectory.q.len() {
        let t = trajectory.time(k);
        if k % 4096 == 4095 && stop() {
            return Err(GviError::Interrupted { step: k, t }.into());
        }
        let (q, p) = (&trajectory.q[k], &trajectory.p[k]);
        let mut row = vec![k as f64, t];
        row.extend_from_slice(q);
        row.extend_from_slice(p);
        if let Err(e) = monitor.observe(system, exact.as_ref(), k, t, q, p, &mut row) {
            // The first non-finite step end: keep the steps before it.
            failure = Some(e);
            truncate(&mut trajectory, k);
            break;
        }
        if let (Some(nbody), true) = (system.as_nbody(), k > 0) {
            let curves = &trajectory;
            let position = |s: f64| curves.position_at(s).ok();
            monitor.closest_on_curve(nbody, curves.time(k - 1), t, &position);
        }
        if let Some(a) = &adaptive {
            // Row k is the state at t_k: report the n, indicator and embedded estimate (NaN:
            // not checked) of the step that led there.
            let (n, i, e) = match k {
                0 => (f64::NAN, f64::NAN, f64::NAN),
                _ => (
                    trajectory.n_of_step(k - 1) as f64,
                    a.indicators.get(k - 1).copied().unwrap_or(f64::NAN),
                    a.estimates
                        .get(k - 1)
                        .copied()
                        .flatten()
                        .unwrap_or(f64::NAN),
                ),
            };
            row.push(n);
            row.push(i);
            row.push(e);
        }
        rows.push(row);
    }
    let max_pos = monitor.max_pos;
    let max_curve_error = match (&exact, options.curve_samples_per_step) {
        (Some(ex), s) if s > 0 && trajectory.steps() > 0 => {
            let mut worst = 0.0f64;
            for t in trajectory.sample_times(s) {
                worst = worst.max(max_norm_diff(&trajectory.position_at(t)?, &ex.position(t)));
            }
            Some(worst)
        }
        _ => None,
    };
    let steps = trajectory.steps();
    let n_range = (!trajectory.step_n.is_empty()).then(|| {
        let lo = trajectory.step_n.iter().copied().min().unwrap_or(0);
        let hi = trajectory.step_n.iter().copied().max().unwrap_or(0);
        (lo, hi)
    });
    let method = match (&adaptive, n_range) {
        (Some(AdaptiveReport { tol, .. }), Some((lo, hi))) => format!(
            "{} basis, n chosen per step in {lo}…{hi} for tol = {tol:e}, {} (default points), h = {}, {} solver",
            m.basis,
            m.quadrature,
            fmt_number(trajectory.h),
            m.solver
        ),
        // A tolerance-driven run that failed at its first step.
        (Some(AdaptiveReport { tol, .. }), None) => format!(
            "{} basis, n chosen per step for tol = {tol:e}, {} (default points), h = {}, {} solver",
            m.basis,
            m.quadrature,
            fmt_number(trajectory.h),
            m.solver
        ),
        (None, _) => format!(
            "{} basis n = {}, {} with {} points, h = {}, {} solver",
            m.basis,
            m.n,
            m.quadrature,
            m.quadrature_points(),
            fmt_number(m.h),
            m.solver
        ),
    };
    let (mut warnings, force_evaluations) = match &adaptive {
        Some(a) => (a.warnings.clone(), a.gradient_evaluations),
        None => (Vec::new(), trajectory.gradient_evaluations()),
    };
    warnings.extend(monitor.warnings());
    let energy_balance = if has_energy_balance(system) && steps > 0 {
        match galerkin_vi::forcing::energy_balance(system, &trajectory) {
            Ok(b) => Some(EnergyBalance::of(&b)),
            Err(e) => {
                warnings.push(format!("no energy balance: {e}"));
                None
            }
        }
    } else {
        None
    };
    let summary = RunSummary {
        system: system.name().to_string(),
        method,
        warnings,
        force_evaluations,
        step_choice,
        steps,
        max_position_error: max_pos,
        max_curve_error,
        invariant_errors: names
            .iter()
            .map(|s| s.to_string())
            .zip(monitor.inv_err.iter().copied())
            .collect(),
        relative_invariant_errors: names
            .iter()
            .map(|s| s.to_string())
            .zip(monitor.relative_errors())
            .collect(),
        energy_scale: monitor.energy_scale.map(|(l, s)| (l.to_string(), s)),
        closest_approach: monitor.encounter.clone(),
        energy_balance,
        newton_iterations_per_step: trajectory.newton_iterations() as f64 / steps.max(1) as f64,
        seconds,
        command_seconds: None,
    };
    let (chart, inner_chart) = if options.chart && steps > 0 {
        match system.body_names() {
            Some(names) => {
                let (all, inner) = crate::nbody_report::orbit_charts(
                    &names,
                    &scene.name,
                    scene.units(),
                    &trajectory,
                )?;
                (Some(all), inner)
            }
            None => (
                Some(run_chart(system, scene, &trajectory, exact.as_ref())?),
                None,
            ),
        }
    } else {
        (None, None)
    };
    let n_chart = (options.chart && !trajectory.step_n.is_empty()).then(|| {
        let pts: Vec<(f64, f64)> = chart_indices(trajectory.steps())
            .into_iter()
            .map(|k| {
                (
                    trajectory.time(k) + 0.5 * trajectory.h,
                    trajectory.n_of_step(k) as f64,
                )
            })
            .collect();
        Chart::new(
            format!(
                "{}: n chosen per step (tol = {:e})",
                scene.name,
                adaptive.as_ref().map_or(f64::NAN, |a| a.tol)
            ),
            "t (step midpoint)",
            "n",
        )
        .with_series(Series::line_markers("n", pts))
    });
    Ok(RunResult {
        n_chart,
        scene: scene.scene(),
        columns,
        rows,
        summary,
        trajectory: Some(trajectory),
        failure,
        chart,
        inner_chart,
    })
}

pub use crate::error::fmt_number;

/// The start checks of a run, for every command built from a scene: coincident bodies (a
/// collision) and non-finite initial invariants (a singular start such as Kepler at the
/// origin), with the messages `gvi run` gives.
pub fn check_start<S: System>(system: &S, q0: &[f64], p0: &[f64], t0: f64) -> Result<()> {
    // In the run's order: the exact solution's own errors (Kepler elements that overflow
    // name `mu`) come before the monitor's.
    system.exact_solution(t0, q0, p0)?;
    Monitor::new(system, q0, p0, t0).map(|_| ())
}

/// Keep the first `states` step ends (and the `states − 1` steps between them).
fn truncate(traj: &mut Trajectory, states: usize) {
    let steps = states.saturating_sub(1);
    traj.q.truncate(states);
    traj.p.truncate(states);
    traj.coefficients.truncate(steps);
    traj.stats.truncate(steps);
    traj.step_n.truncate(steps);
}

impl RunResult {
    /// The table as CSV text (header line, then one row per step end): `step` and `n` as
    /// integers, the other columns as [`crate::table::number`] writes them (shortest
    /// round-trip digits: `0.4`, `200`, `1e-300`; read back bit for bit), NaN as an empty cell.
    pub fn to_csv(&self) -> Result<String> {
        let integer: Vec<bool> = self
            .columns
            .iter()
            .map(|c| matches!(c.as_str(), "step" | "n"))
            .collect();
        let cell = |(x, &integer): (&f64, &bool)| {
            if integer && !x.is_nan() {
                format!("{}", *x as u64)
            } else {
                crate::table::number(*x)
            }
        };
        crate::table::csv_records(
            &self.columns,
            self.rows
                .iter()
                .map(|row| row.iter().zip(&integer).map(cell)),
        )
    }

    /// The whole result as JSON (scene, columns, rows, summary, trajectory with coefficients).
    pub fn to_json(&self) -> Result<String> {
        serde_json::to_string_pretty(self).map_err(|e| LabError::Serialize(e.to_string()))
    }
}
