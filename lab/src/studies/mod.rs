//! Studies: refinement sweeps with fitted rates, the paper's experiments, work–precision
//! against classical peers, stability maps, and n- versus h-refinement cost.
//!
//! Every study measures [`Measurement`]s — one integration of a scene's system with one method
//! — against a [`Reference`] (the exact solution where one is known, otherwise a
//! high-resolution spectral run), writes CSV/JSON tables and SVG charts, and never aborts on a
//! solver failure: the failure is recorded in the measurement and shown.
//!
//! One module per study: [`refine`], [`compare_bases`], [`reproduce`] (the paper's figures),
//! [`work_precision`] (with [`peers`], the classical baselines at their best), [`stability`],
//! [`compare_refinement`], [`tolerance`] (with [`allocation`], the oracle bound) and [`scaling`]
//! (time per step of every stage solver). Sweeps run in parallel (rayon) with a progress bar;
//! each study refuses a sweep whose estimated cost or memory is absurd before doing any work.
//!
//! The guide's studies page (docs/guide/studies.md) lists the command of each study, and
//! docs/studies/ holds the committed outputs.

pub mod allocation;
pub mod compare_bases;
pub mod compare_refinement;
pub mod peers;
pub mod refine;
pub mod reproduce;
pub mod scaling;
pub mod stability;
pub mod tolerance;
pub mod work_precision;

use crate::error::{GviError, LabError, Result};
use crate::scene::{InitialState, MethodSpec};
use crate::table;
use galerkin_vi::baselines::GaussCollocationBaseline;
use galerkin_vi::integrator::GalerkinIntegrator;
use galerkin_vi::systems::{ExactSolution, System};
use galerkin_vi::trajectory::Trajectory;
use serde::Serialize;
use std::time::Instant;

/// What the errors are measured against.
pub enum Reference {
    /// A closed-form solution.
    Exact(ExactSolution),
    /// A high-resolution numerical solution (dense output).
    Numerical(Box<Trajectory>),
    /// Positions sampled every `dt` from `t0` (a Gauss-collocation reference for systems with
    /// many degrees of freedom); only sample times have values.
    Sampled {
        /// First sample time.
        t0: f64,
        /// Sample spacing.
        dt: f64,
        /// Positions at t0 + k dt.
        q: Vec<Vec<f64>>,
    },
}

impl Reference {
    /// The reference position at t.
    pub fn position(&self, t: f64) -> Result<Vec<f64>> {
        match self {
            Reference::Exact(e) => Ok(e.position(t)),
            Reference::Numerical(tr) => Ok(tr.position_at(t)?),
            Reference::Sampled { t0, dt, q } => {
                let x = (t - t0) / dt;
                let k = x.round();
                if (x - k).abs() > 1e-6 || k < 0.0 || k as usize >= q.len() {
                    return Err(GviError::Unsupported(format!(
                        "the reference is sampled every {dt} from {t0}; no value at t = {t}"
                    ))
                    .into());
                }
                Ok(q[k as usize].clone())
            }
        }
    }

    /// The exact solution, or a spectral run at n = 48, h/4 over `horizon` (documented as
    /// the reference for systems without a closed form).
    pub fn for_system<S: System>(
        system: &S,
        initial: &InitialState,
        h: f64,
        horizon: f64,
    ) -> Result<Reference> {
        if let Some(e) = system.exact_solution(initial.t0, &initial.q, &initial.p)? {
            return Ok(Reference::Exact(e));
        }
        if let (Some(tau), true) = (
            system.shortest_time_scale(&initial.q, &initial.p),
            system.dim() > 4,
        ) {
            // Many degrees of freedom: Gauss collocation (s = 6, order 12) with compensated
            // summation, ≥ 256 steps per shortest period, sampled 16 times per step h.
            let per = 16 * ((h * 256.0 / tau / 16.0).ceil() as usize).clamp(1, 10_000);
            let steps = (horizon / h).ceil().max(1.0) as usize;
            let mut gauss = GaussCollocationBaseline::new(system, 6, h / per as f64)?;
            let (q, _) =
                gauss.integrate_compensated(&initial.q, &initial.p, steps * per, per / 16)?;
            return Ok(Reference::Sampled {
                t0: initial.t0,
                dt: h / 16.0,
                q,
            });
        }
        let href = (h / 4.0).min(1.0);
        let steps = (horizon / href).ceil().max(1.0) as usize;
        let gvi = GalerkinIntegrator::spectral(48, href)?;
        let traj = gvi.integrate(system, initial.t0, &initial.q, &initial.p, steps)?;
        Ok(Reference::Numerical(Box::new(traj)))
    }

    /// The integration steps [`Reference::for_system`] would take (0 for an exact solution),
    /// computed without running it, so that absurd horizons can be refused up front.
    pub fn estimated_steps<S: System>(
        system: &S,
        initial: &InitialState,
        h: f64,
        horizon: f64,
    ) -> f64 {
        if matches!(
            system.exact_solution(initial.t0, &initial.q, &initial.p),
            Ok(Some(_))
        ) {
            return 0.0;
        }
        if let (Some(tau), true) = (
            system.shortest_time_scale(&initial.q, &initial.p),
            system.dim() > 4,
        ) {
            let per = 16.0 * (h * 256.0 / tau / 16.0).ceil().clamp(1.0, 10_000.0);
            return (horizon / h).ceil().max(1.0) * per;
        }
        (horizon / (h / 4.0).min(1.0)).ceil().max(1.0)
    }

    /// The bytes [`Reference::for_system`] would hold (0 for an exact solution), estimated
    /// without running it, for [`crate::memory::ensure_fits`].
    pub fn estimated_bytes<S: System>(
        system: &S,
        initial: &InitialState,
        h: f64,
        horizon: f64,
    ) -> f64 {
        let d = system.dim();
        let steps = Self::estimated_steps(system, initial, h, horizon);
        if steps == 0.0 {
            return 0.0;
        }
        if system.shortest_time_scale(&initial.q, &initial.p).is_some() && d > 4 {
            // Sampled 16 times per step h: one position vector per sample.
            let samples = (horizon / h).ceil().max(1.0) * 16.0;
            return samples * (8 * d + 24) as f64;
        }
        steps * crate::memory::trajectory_bytes_per_step(48, d)
    }

    /// Short description for reports.
    pub fn describe(&self) -> &'static str {
        match self {
            Reference::Exact(_) => "exact solution",
            Reference::Numerical(_) => "spectral reference run (n = 48, h/4)",
            Reference::Sampled { .. } => {
                "Gauss collocation reference (s = 6, compensated, ≥ 256 steps per shortest period)"
            }
        }
    }
}

/// One integration and its errors and cost.
#[derive(Debug, Clone, Serialize)]
pub struct Measurement {
    /// Basis.
    pub basis: String,
    /// Quadrature.
    pub quadrature: String,
    /// Number of basis functions.
    pub n: usize,
    /// Step size.
    pub h: f64,
    /// Steps requested.
    pub steps: usize,
    /// Max over step ends of the max-norm position error (the one-step map).
    pub map_error: f64,
    /// Max over sampled t of the Galerkin curves' position error.
    pub curve_error: f64,
    /// Max |I₀(t_k) − I₀(t_0)| of the first invariant (the energy).
    pub energy_error: f64,
    /// Max error of the second invariant (e.g. angular momentum), if the system has one.
    pub momentum_error: Option<f64>,
    /// Total Newton iterations.
    pub newton_iterations: usize,
    /// Force / first-derivative evaluations (per quadrature point).
    pub gradient_evaluations: usize,
    /// Wall-clock seconds of the integration.
    pub seconds: f64,
    /// The solver's error, if the run failed (errors then cover the completed steps only).
    pub failure: Option<String>,
}

/// Integrate `system` from `initial` with `method` and measure everything against
/// `reference`; `curve_samples` points per step for the curve error.
pub fn measure<S: System>(
    system: &S,
    initial: &InitialState,
    method: &MethodSpec,
    reference: &Reference,
    curve_samples: usize,
) -> Measurement {
    let mut m = Measurement {
        basis: method.basis.to_string(),
        quadrature: method.quadrature.to_string(),
        n: method.n,
        h: method.h,
        steps: method.steps,
        map_error: f64::NAN,
        curve_error: f64::NAN,
        energy_error: f64::NAN,
        momentum_error: None,
        newton_iterations: 0,
        gradient_evaluations: 0,
        seconds: 0.0,
        failure: None,
    };
    // The method's own integrator: basis, n, quadrature, points, h and its stage solver.
    let gvi = match method.integrator() {
        Ok(g) => g,
        Err(e) => {
            m.failure = Some(e.to_string());
            return m;
        }
    };
    let start = Instant::now();
    let result = gvi.integrate(system, initial.t0, &initial.q, &initial.p, method.steps);
    m.seconds = start.elapsed().as_secs_f64();
    let traj = match result {
        Ok(t) => t,
        Err(f) => {
            m.failure = Some(f.error.to_string());
            match f.partial {
                Some(p) => *p,
                None => return m,
            }
        }
    };
    if let Err(e) = fill_errors(system, initial, &traj, reference, curve_samples, &mut m) {
        m.failure.get_or_insert(e.to_string());
    }
    if m.failure.is_some() {
        // A failed run has no error figures: the partial run's would look like a success.
        m.map_error = f64::NAN;
        m.curve_error = f64::NAN;
        m.energy_error = f64::NAN;
        m.momentum_error = None;
    }
    m
}

fn fill_errors<S: System>(
    system: &S,
    initial: &InitialState,
    traj: &Trajectory,
    reference: &Reference,
    curve_samples: usize,
    m: &mut Measurement,
) -> Result<()> {
    m.newton_iterations = traj.newton_iterations();
    m.gradient_evaluations = traj.gradient_evaluations();
    let mut map = 0.0f64;
    for k in 0..traj.q.len() {
        map = nan_max(
            map,
            max_norm_diff(&traj.q[k], &reference.position(traj.time(k))?),
        );
    }
    m.map_error = map;
    if !map.is_finite() {
        return Err(GviError::NonFinite {
            what: "position error at a step end".into(),
            value: map,
        }
        .into());
    }
    let mut curve = map;
    if traj.steps() > 0 && curve_samples > 0 {
        for t in traj.sample_times(curve_samples) {
            curve = nan_max(
                curve,
                max_norm_diff(&traj.position_at(t)?, &reference.position(t)?),
            );
        }
    }
    m.curve_error = curve;
    if !curve.is_finite() {
        return Err(GviError::NonFinite {
            what: "position error along the Galerkin curves".into(),
            value: curve,
        }
        .into());
    }
    let k = system.invariant_names().len();
    if k > 0 {
        let (mut i0, mut i) = (vec![0.0; k], vec![0.0; k]);
        system.invariants(&initial.q, &initial.p, &mut i0);
        let mut worst = vec![0.0f64; k];
        for s in 0..traj.q.len() {
            system.invariants(&traj.q[s], &traj.p[s], &mut i);
            for c in 0..k {
                worst[c] = nan_max(worst[c], (i[c] - i0[c]).abs());
            }
        }
        if let Some(&w) = worst.iter().find(|w| !w.is_finite()) {
            return Err(GviError::NonFinite {
                what: "invariant error".into(),
                value: w,
            }
            .into());
        }
        m.energy_error = worst[0];
        m.momentum_error = worst.get(1).copied();
    }
    Ok(())
}

pub(crate) use crate::distance::{max_norm_diff, nan_max};

/// Memory above which a study is refused before it starts (the one limit,
/// [`crate::memory::LIMIT_BYTES`]).
pub const MAX_STUDY_BYTES: f64 = crate::memory::LIMIT_BYTES;

/// Refuse a study whose runs would hold an absurd amount of memory: each run keeps its
/// trajectory ([`crate::memory::trajectory_bytes_per_step`]), and rayon runs as many at once
/// as it has threads ([`crate::memory::ensure_fits`]).
pub fn refuse_memory(steps_per_run: f64, n: usize, d: usize) -> Result<()> {
    let per_step = crate::memory::trajectory_bytes_per_step(n, d);
    let parallel = rayon::current_num_threads().max(1) as f64;
    crate::memory::ensure_fits(
        format!(
            "the sweep ({steps_per_run:.3e} steps per run at about {per_step:.0} bytes each, \
             {parallel} runs at once)"
        ),
        steps_per_run * per_step * parallel,
        "lower --steps or the range",
    )
}

/// Refuse a study whose every run failed: there is nothing to report.
pub fn ensure_some_succeeded(ms: &[Measurement]) -> Result<()> {
    if !ms.is_empty() && ms.iter().all(|m| m.failure.is_some()) {
        return Err(LabError::AllRunsFailed {
            runs: ms.len(),
            first: ms[0].failure.clone().unwrap_or_default(),
        });
    }
    Ok(())
}

/// One CSV line of a [`Measurement`] (the formats of `docs/studies/`, see [`crate::table`]);
/// `kinetic_condition` is a column only when given (`compare-bases`).
#[derive(Serialize)]
pub(crate) struct MeasurementRow<'a> {
    basis: &'a str,
    quadrature: &'a str,
    n: usize,
    #[serde(serialize_with = "table::sci")]
    h: f64,
    steps: usize,
    #[serde(serialize_with = "table::sci")]
    map_error: f64,
    #[serde(serialize_with = "table::sci")]
    curve_error: f64,
    #[serde(serialize_with = "table::sci")]
    energy_error: f64,
    #[serde(serialize_with = "table::sci_opt")]
    momentum_error: Option<f64>,
    newton_iterations: usize,
    gradient_evaluations: usize,
    #[serde(serialize_with = "table::sci")]
    seconds: f64,
    #[serde(serialize_with = "table::quoted")]
    failure: Option<&'a str>,
    #[serde(
        serialize_with = "table::sci_opt",
        skip_serializing_if = "Option::is_none"
    )]
    kinetic_condition: Option<f64>,
}

impl<'a> MeasurementRow<'a> {
    /// The row of `m`, with an optional kinetic-matrix condition number column.
    pub(crate) fn new(m: &'a Measurement, kinetic_condition: Option<f64>) -> Self {
        Self {
            basis: &m.basis,
            quadrature: &m.quadrature,
            n: m.n,
            h: m.h,
            steps: m.steps,
            map_error: m.map_error,
            curve_error: m.curve_error,
            energy_error: m.energy_error,
            momentum_error: m.momentum_error,
            newton_iterations: m.newton_iterations,
            gradient_evaluations: m.gradient_evaluations,
            seconds: m.seconds,
            failure: m.failure.as_deref(),
            kinetic_condition,
        }
    }
}

/// Measurements as CSV.
pub fn measurements_csv(ms: &[Measurement]) -> Result<String> {
    table::csv_text(ms.iter().map(|m| MeasurementRow::new(m, None)))
}

pub use crate::output::write_file;
