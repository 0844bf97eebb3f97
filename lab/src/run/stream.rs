//! Streamed `gvi run`: each CSV row is written as its step completes, so memory stays flat in
//! the number of steps and a run stopped early (a failure, a kill) has written every step
//! before it. Used when nothing needs the whole trajectory (no chart, no JSON, no `--tol`).
//!
//! The table and summary are those of [`super::run_scene`]: the same monitor watches the
//! step ends, and the error along the Galerkin curves is sampled from each step's
//! coefficients while they are in the workspace.

use super::{Monitor, RunSummary};
use crate::error::LabError;
use crate::error::Result;
use crate::scene::BuiltScene;
use galerkin_vi::Lagrangian;
use galerkin_vi::basis::Basis;
use galerkin_vi::solve::{SolveFailure, StreamStep, Streamed, solve_streaming};
use galerkin_vi::systems::{AnySystem, System};
use std::io::Write;
use std::time::Instant;

/// Bytes held per step by an in-memory run ([`super::run_scene`]) with `columns` table
/// columns, n basis functions and dimension d: the trajectory (states, coefficients, step
/// statistics, vector headers), the table row, and the output text (about 25 bytes per
/// written number; JSON also writes the coefficients). An estimate for refusing runs up
/// front; measured at 0.46–1.1 KB per step for the shipped scenes. A chart adds no per-step
/// term: it keeps at most [`crate::plot::MAX_POINTS_PER_SERIES`] points per series (a charted
/// Kepler run at n = 8: estimated 716 B per step, measured 576 B per step between 2·10⁴ and
/// 10⁵ steps).
pub fn bytes_per_step(columns: usize, n: usize, d: usize, json: bool) -> f64 {
    let trajectory = crate::memory::trajectory_bytes_per_step(n, d);
    let row = 8 * columns + 24;
    let text = 25 * (columns + if json { n * d + 2 * d } else { 0 });
    trajectory + (row + text) as f64
}

/// What a streamed run reports once its rows are written.
#[derive(Debug)]
pub struct StreamOutcome {
    /// Totals and maxima, as for an in-memory run.
    pub summary: RunSummary,
    /// The failure that stopped the run early (the rows before it are written).
    pub failure: Option<LabError>,
}

/// Integrate a scene (without `tol`: the library refuses to stream a tolerance-driven run)
/// and write its CSV table to `out` step by step.
/// `curve_samples_per_step` as in [`super::RunOptions`].
pub fn stream_scene(
    scene: &BuiltScene,
    curve_samples_per_step: usize,
    out: &mut dyn Write,
) -> Result<StreamOutcome> {
    stream_system(scene.euclidean()?, scene, curve_samples_per_step, out)
}

fn write_row(out: &mut dyn Write, row: &[f64]) -> std::io::Result<()> {
    for (i, x) in row.iter().enumerate() {
        if i > 0 {
            out.write_all(b",")?;
        }
        if i == 0 {
            write!(out, "{}", *x as u64)?;
        } else {
            out.write_all(crate::table::number(*x).as_bytes())?;
        }
    }
    out.write_all(b"\n")
}

fn stream_system(
    system: &AnySystem,
    scene: &BuiltScene,
    samples: usize,
    out: &mut dyn Write,
) -> Result<StreamOutcome> {
    let m = &scene.method;
    let init = &scene.initial;
    // The method's own parameter errors (h) come before the time span's, which depends on h.
    m.validate()?;
    // Lengths, finiteness and steps ≥ 1 were checked when the scene was built.
    let d = system.dim();
    super::monitor::check_time_span(init.t0, m.h, m.steps)?;
    let exact = system.exact_solution(init.t0, &init.q, &init.p)?;
    let mut monitor = Monitor::new(system, &init.q, &init.p, init.t0)?;
    let io = |source| LabError::Io {
        path: "<output>".into(),
        source,
    };

    let names = system.invariant_names();
    let mut header = vec!["step".to_string(), "t".to_string()];
    header.extend(crate::names::state_columns(system));
    header.extend(names.iter().map(|s| s.to_string()));
    if exact.is_some() {
        header.push("position_error".into());
    }

    let start = Instant::now();
    let n = m.n;
    let (mut phi, mut dphi, mut qc) = (vec![0.0; n], vec![0.0; n], vec![0.0; d]);
    let mut row = Vec::with_capacity(header.len());
    let (mut iterations, mut evaluations, mut done) = (0usize, 0usize, 0usize);
    let mut curve_error: Option<f64> = (exact.is_some() && samples > 0).then_some(0.0);
    // The library refuses a tolerance-driven method (it keeps the whole trajectory) before
    // the first visit, so the header is written only for a run that starts.
    // Forced or time-dependent: the energy balance, step by step (the run keeps no curves).
    let mut balance_warning = None;
    let mut meter = if super::has_energy_balance(system) {
        match galerkin_vi::forcing::EnergyMeter::new(
            system,
            n,
            (init.t0, &init.q, &init.p),
            &init.p,
        ) {
            Ok(m) => Some(m),
            Err(e) => {
                balance_warning = Some(format!("no energy balance: {e}"));
                None
            }
        }
    } else {
        None
    };
    let visit = |s: StreamStep<'_>| -> Result<()> {
        if crate::interrupt::requested() {
            // Ctrl-C: stop here; the rows before this step are kept (the caller says where).
            return Err(LabError::Interrupted {
                step: s.step,
                kept: "no row was written".into(),
            });
        }
        if s.step == 0 {
            writeln!(out, "{}", header.join(",")).map_err(io)?;
        }
        row.clear();
        row.push(s.step as f64);
        row.push(s.t);
        row.extend_from_slice(s.q);
        row.extend_from_slice(s.p);
        monitor.observe(system, exact.as_ref(), s.step, s.t, s.q, s.p, &mut row)?;
        write_row(out, &row).map_err(io)?;
        let (Some(curve), Some(stats)) = (s.curve, s.stats) else {
            return Ok(());
        };
        iterations += stats.iterations;
        evaluations += stats.gradient_evaluations;
        done += 1;
        if let Some(m) = meter.as_mut()
            && let Err(e) = m.step(system, curve, s.basis, (s.q, s.p))
        {
            balance_warning = Some(format!("no energy balance: {e}"));
            meter = None;
        }
        if let Some(nbody) = system.as_nbody() {
            let t_a = init.t0 + (s.step - 1) as f64 * curve.h();
            let on_curve = curve.starting_at(t_a);
            let position = |t: f64| on_curve.state_at(s.basis, t).ok().map(|(q, _)| q);
            monitor.closest_on_curve(nbody, t_a, s.t, &position);
        }
        if let (Some(ex), Some(worst)) = (&exact, curve_error.as_mut()) {
            // Sample this step's curve while its coefficients are in the workspace.
            let (c, k, h) = (curve.coefficients(), s.step - 1, curve.h());
            for j in 0..samples {
                let tau = j as f64 / samples as f64;
                s.basis.eval(tau, &mut phi, &mut dphi);
                qc.iter_mut().for_each(|x| *x = 0.0);
                for i in 0..n {
                    for r in 0..d {
                        qc[r] += phi[i] * c[i * d + r];
                    }
                }
                let t = init.t0 + (k as f64 + tau) * h;
                let e = ex
                    .position(t)
                    .iter()
                    .zip(&qc)
                    .map(|(x, y)| (x - y).abs())
                    .fold(0.0, crate::distance::nan_max);
                *worst = crate::distance::nan_max(*worst, e);
            }
        }
        Ok(())
    };
    let failure = match solve_streaming(system, init, m, visit) {
        Ok(Streamed { stopped: None, .. }) => None,
        // An unwritable output, or an initial state the monitor refuses, ends the run as an
        // error; a later non-finite state as a failure with the rows before it written.
        Ok(Streamed {
            stopped: Some(e @ LabError::Io { .. }),
            ..
        })
        | Ok(Streamed {
            steps: 0,
            stopped: Some(e),
        }) => return Err(e),
        Ok(Streamed {
            stopped: Some(e), ..
        }) => Some(e),
        Err(SolveFailure {
            error,
            partial: Some(_),
        }) => Some(error.into()),
        Err(SolveFailure { error, .. }) => return Err(error.into()),
    };
    out.flush().map_err(io)?;
    let seconds = start.elapsed().as_secs_f64();
    let method = format!(
        "{} basis n = {}, {} with {} points, h = {}, {} solver (streamed)",
        m.basis,
        m.n,
        m.quadrature,
        m.quadrature_points(),
        super::fmt_number(m.h),
        m.solver
    );
    let label = |v: Vec<f64>| -> Vec<(String, f64)> {
        names.iter().map(|s| s.to_string()).zip(v).collect()
    };
    let summary = RunSummary {
        system: system.name().to_string(),
        method,
        steps: done,
        max_position_error: monitor.max_pos,
        max_curve_error: curve_error.filter(|_| done > 0).map(|c| {
            // The final time, as in the in-memory run's samples.
            c.max(monitor.max_pos.unwrap_or(0.0))
        }),
        invariant_errors: label(monitor.inv_err.clone()),
        relative_invariant_errors: label(monitor.relative_errors()),
        energy_scale: monitor.energy_scale.map(|(l, s)| (l.to_string(), s)),
        closest_approach: monitor.encounter.clone(),
        energy_balance: meter
            .as_ref()
            .map(|m| super::EnergyBalance::of(m.balance())),
        newton_iterations_per_step: iterations as f64 / done.max(1) as f64,
        seconds,
        command_seconds: None,
        force_evaluations: evaluations,
        warnings: monitor
            .warnings()
            .into_iter()
            .chain(balance_warning)
            .collect(),
        step_choice: None,
    };
    Ok(StreamOutcome { summary, failure })
}
