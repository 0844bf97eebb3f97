//! `gvi run` with a Poincaré time transformation (`[method.time_transform]` or
//! `--time-transform`): fixed fictitious steps of the scene's h, physical steps that follow
//! the monitor, rows in physical time (at the step ends, or at t₀ + k·every located on t(s)),
//! and a chart of the physical step size against time (galerkin_vi::time_transform).

use crate::error::{LabError, Result};
use crate::plot::{Chart, Series};
use crate::scene::{BuiltScene, BuiltSystem};
use galerkin_vi::GviError;
use galerkin_vi::events::EventOptions;
use galerkin_vi::method::{InitialState, MethodSpec};
use galerkin_vi::systems::{AnySystem, System};
use galerkin_vi::time_transform::{
    Monitor, TimeTransformOptions, TimeTransformSpec, TimeTransformed, TimeTransformedRun,
    integrate_time_transformed_until,
};
use serde::Serialize;
use std::time::Instant;

/// What a time-transformed run produced; on a solver failure `failure` is set and the rows
/// before it are kept.
#[derive(Debug, Serialize)]
pub struct TimeTransformResult {
    /// `step,s,t,dt`, the coordinates and momenta, the invariants, `position_error` if the
    /// exact solution is known.
    pub columns: Vec<String>,
    /// One row per step end (or per output time with `every`).
    pub rows: Vec<Vec<f64>>,
    /// Totals and extremes.
    pub summary: TimeTransformSummary,
    /// The error that ended the run early, if any.
    #[serde(serialize_with = "serialize_error")]
    pub failure: Option<LabError>,
    /// Physical step size against physical time, when asked for.
    #[serde(skip)]
    pub chart: Option<Chart>,
}

fn serialize_error<S: serde::Serializer>(
    e: &Option<LabError>,
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    match e {
        Some(e) => s.serialize_some(&e.to_string()),
        None => s.serialize_none(),
    }
}

/// Summary numbers of a time-transformed run.
#[derive(Debug, Clone, Serialize)]
pub struct TimeTransformSummary {
    /// System name.
    pub system: String,
    /// Method description (basis, n, Δs, monitor).
    pub method: String,
    /// Fictitious steps taken.
    pub steps: usize,
    /// The physical time reached.
    pub t: f64,
    /// The energy level E₀.
    pub energy_level: f64,
    /// Max |H − H₀| over the rows, and relative to T₀ + |V₀|.
    pub max_energy_error: f64,
    /// Max relative energy error.
    pub max_relative_energy_error: f64,
    /// Max position error against the exact solution, if known.
    pub max_position_error: Option<f64>,
    /// Smallest and largest physical step.
    pub min_step: f64,
    /// Largest physical step.
    pub max_step: f64,
    /// Newton iterations per step (mean).
    pub newton_iterations_per_step: f64,
    /// Force (first-derivative) evaluations.
    pub force_evaluations: usize,
    /// Wall-clock seconds of the integration.
    pub seconds: f64,
}

impl std::fmt::Display for TimeTransformSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{}: {}, {} fictitious steps to t = {}",
            self.system, self.method, self.steps, self.t
        )?;
        if let Some(e) = self.max_position_error {
            writeln!(f, "  max position error: {e:.3e}")?;
        }
        writeln!(
            f,
            "  max energy error: {:.3e} (relative {:.3e}); E0 = {}",
            self.max_energy_error, self.max_relative_energy_error, self.energy_level
        )?;
        writeln!(
            f,
            "  physical steps from {:.3e} to {:.3e}",
            self.min_step, self.max_step
        )?;
        write!(
            f,
            "  Newton iterations per step: {:.2}; force evaluations: {}; integration time: {:.3} s",
            self.newton_iterations_per_step, self.force_evaluations, self.seconds
        )
    }
}

impl TimeTransformResult {
    /// The table as CSV.
    pub fn to_csv(&self) -> Result<String> {
        let cell = |(c, x): (&String, &f64)| {
            if c == "step" {
                format!("{}", *x as u64)
            } else {
                crate::table::number(*x)
            }
        };
        crate::table::csv_records(
            &self.columns,
            self.rows
                .iter()
                .map(|r| self.columns.iter().zip(r).map(cell)),
        )
    }

    /// The result as JSON (columns, rows, summary, failure).
    pub fn to_json(&self) -> Result<String> {
        serde_json::to_string_pretty(self).map_err(|e| LabError::Serialize(e.to_string()))
    }
}

/// Run a built scene whose method has a time transformation.
///
/// Errors: a scene without one, a rigid body, a monitor that does not fit the system or is
/// not positive at the initial state, E₀ or the times not finite — before any step. A
/// solver failure after the first step is `Ok` with [`TimeTransformResult::failure`] set.
pub fn run_time_transformed(scene: &BuiltScene, chart: bool) -> Result<TimeTransformResult> {
    run_time_transformed_until(scene, chart, &|| false)
}

/// [`run_time_transformed`] that asks `stop` before every fictitious step (Ctrl-C in the
/// Python bindings): a `true` ends the run with [`TimeTransformResult::failure`] set to
/// [`GviError::Interrupted`] and the rows before it kept.
pub fn run_time_transformed_until(
    scene: &BuiltScene,
    chart: bool,
    stop: &dyn Fn() -> bool,
) -> Result<TimeTransformResult> {
    let BuiltSystem::Euclidean(system) = &scene.system else {
        return Err(GviError::Unsupported(
            "a time transformation needs a system on R^D, not a rigid body on SO(3)".into(),
        )
        .into());
    };
    let (mut result, run) = run_system(system, &scene.method, &scene.initial, stop)?;
    if chart {
        result.chart = Some(step_chart(scene, &run));
    }
    Ok(result)
}

/// Run `system` from `initial` with `method`, which has a time transformation (the Python
/// bindings' `Integrator(time_transform=...)`); `stop` as in [`run_time_transformed_until`].
/// No chart.
///
/// Errors: those of [`run_time_transformed`].
pub fn run_time_transformed_system(
    system: &AnySystem,
    method: &MethodSpec,
    initial: &InitialState,
    stop: &dyn Fn() -> bool,
) -> Result<TimeTransformResult> {
    run_system(system, method, initial, stop).map(|(result, _)| result)
}

/// The run and, for the chart, its step ends.
fn run_system(
    system: &AnySystem,
    method: &MethodSpec,
    init: &InitialState,
    stop: &dyn Fn() -> bool,
) -> Result<(TimeTransformResult, TimeTransformedRun)> {
    let Some(spec) = &method.time_transform else {
        return Err(GviError::Unsupported("the method has no time transformation".into()).into());
    };
    if method.chooses_n() {
        return Err(GviError::Unsupported(
            "a time-transformed run takes a fixed n (tol chooses n per step)".into(),
        )
        .into());
    }
    let monitor = spec.monitor_for(system)?;
    let tt = TimeTransformed::new(system.clone(), monitor, &init.q, &init.p, spec.energy)?;
    let gvi = method.integrator()?;
    let options = TimeTransformOptions {
        t_end: spec.t_end,
        max_steps: method.steps,
        every: spec.every,
        // The step ends are kept for the summary (energy, step range) and the chart even
        // when the rows are at output times.
        keep_steps: true,
        keep_curves: false,
        events: EventOptions::default(),
    };
    let exact = system.exact_solution(init.t0, &init.q, &init.p)?;
    let start = Instant::now();
    let integrated = integrate_time_transformed_until(
        &gvi,
        &tt,
        init.t0,
        &init.q,
        &init.p,
        &mut [],
        &options,
        stop,
    );
    let (run, failure) = match integrated {
        Ok(run) => (run, None),
        Err(f) => match f.partial {
            Some(p) => (*p, Some(LabError::from(f.error))),
            None => return Err(f.error.into()),
        },
    };
    let seconds = start.elapsed().as_secs_f64();

    let names = system.invariant_names();
    let mut columns: Vec<String> = ["step", "s", "t", "dt"].map(String::from).to_vec();
    columns.extend(crate::names::state_columns(system));
    columns.extend(names.iter().map(|s| s.to_string()));
    if exact.is_some() {
        columns.push("position_error".into());
    }
    let states = if spec.every.is_some() {
        &run.outputs
    } else {
        &run.step_ends
    };
    let h0 = tt.hamiltonian(&init.q, &init.p);
    let v0 = tt.potential(&init.q);
    let scale = (h0 - v0).abs() + v0.abs();
    let mut inv = vec![0.0; names.len()];
    let (mut max_e, mut max_pos) = (0.0f64, None::<f64>);
    let mut rows = Vec::with_capacity(states.len());
    for o in states {
        let mut row = vec![o.step as f64, o.s, o.t, o.dt];
        row.extend_from_slice(&o.q);
        row.extend_from_slice(&o.p);
        system.invariants(&o.q, &o.p, &mut inv);
        row.extend_from_slice(&inv);
        max_e = galerkin_vi::reduce::nan_max(max_e, (tt.hamiltonian(&o.q, &o.p) - h0).abs());
        if let Some(ex) = &exact {
            let qe = ex.position(o.t);
            let err =
                o.q.iter()
                    .zip(&qe)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, galerkin_vi::reduce::nan_max);
            max_pos = Some(galerkin_vi::reduce::nan_max(max_pos.unwrap_or(0.0), err));
            row.push(err);
        }
        rows.push(row);
    }
    // The energy error over every step end as well as the rows.
    for o in &run.step_ends {
        max_e = galerkin_vi::reduce::nan_max(max_e, (tt.hamiltonian(&o.q, &o.p) - h0).abs());
    }
    let (min_step, max_step) = step_range(&run);
    let steps = run.steps();
    let summary = TimeTransformSummary {
        system: system.name().to_string(),
        method: format!(
            "{} n = {}, Δs = {}, monitor {} (normalised to 1 at the start)",
            method.basis.as_str(),
            gvi.n(),
            gvi.step_size(),
            tt.monitor().name()
        ),
        steps,
        t: run.end.t,
        energy_level: tt.energy_level(),
        max_energy_error: max_e,
        max_relative_energy_error: if scale > 0.0 { max_e / scale } else { f64::NAN },
        max_position_error: max_pos,
        min_step,
        max_step,
        newton_iterations_per_step: run.newton_iterations as f64 / steps.max(1) as f64,
        force_evaluations: run.gradient_evaluations,
        seconds,
    };
    let result = TimeTransformResult {
        columns,
        rows,
        summary,
        failure,
        chart: None,
    };
    Ok((result, run))
}

/// The smallest and largest physical step of the run (from the step ends).
fn step_range(run: &TimeTransformedRun) -> (f64, f64) {
    let states = if run.step_ends.len() > 1 {
        &run.step_ends[1..]
    } else {
        &run.outputs[..]
    };
    states
        .iter()
        .map(|o| o.dt)
        .filter(|dt| *dt > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), dt| {
            (lo.min(dt), hi.max(dt))
        })
}

/// The physical step Δt_k against t_k (log scale), from the step ends. A long run keeps the
/// smallest and the largest step of each of [`crate::plot::MAX_POINTS_PER_SERIES`]/2 runs of
/// consecutive steps: striding would skip the short steps of an encounter, which are the
/// point of the chart.
fn step_chart(scene: &BuiltScene, run: &TimeTransformedRun) -> Chart {
    let all: Vec<(f64, f64)> = run.step_ends.iter().skip(1).map(|o| (o.t, o.dt)).collect();
    let max = crate::plot::MAX_POINTS_PER_SERIES;
    let points = if all.len() <= max {
        all
    } else {
        let chunk = all.len().div_ceil(max / 2);
        let mut kept = Vec::with_capacity(max);
        for c in all.chunks(chunk) {
            let lo = c.iter().min_by(|a, b| a.1.total_cmp(&b.1));
            let hi = c.iter().max_by(|a, b| a.1.total_cmp(&b.1));
            if let (Some(&lo), Some(&hi)) = (lo, hi) {
                let (a, b) = if lo.0 <= hi.0 { (lo, hi) } else { (hi, lo) };
                kept.push(a);
                kept.push(b);
            }
        }
        kept
    };
    let mut chart = Chart::new(
        format!("{} — physical step size", scene.title()),
        "t",
        "physical step Δt",
    )
    .log_y()
    .legend_clear_of_data();
    chart.push(Series::line("Δt = ∫ g ds per fictitious step", points));
    chart
}

/// Whether the lab can run `system` time-transformed with `spec` from (q, p): the check
/// [`crate::scene::Scene::build`] makes, so bad input fails before any run (a monitor that
/// does not fit the system or is not finite and positive at q, E₀ not finite, a system
/// that is not separable).
pub fn check(system: &AnySystem, spec: &TimeTransformSpec, q: &[f64], p: &[f64]) -> Result<()> {
    let monitor = spec.monitor_for(system)?;
    TimeTransformed::new(system.clone(), monitor, q, p, spec.energy)?;
    Ok(())
}
