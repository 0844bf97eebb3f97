//! The chart of a run (orbit for 2-D systems, q(t) otherwise) and the sampling that keeps
//! every chart of a long run small.

use crate::error::Result;
use crate::plot::{Chart, Series};
use crate::scene::BuiltScene;
use galerkin_vi::Lagrangian;
use galerkin_vi::systems::AnySystem;
use galerkin_vi::trajectory::Trajectory;

/// Times at which a chart samples a trajectory's Galerkin curves: `per_step` per step while
/// that gives at most [`crate::plot::MAX_POINTS_PER_SERIES`] points, otherwise that many
/// evenly spaced over the run (a chart cannot show more; the run's table has every step).
pub fn chart_times(traj: &Trajectory, per_step: usize) -> Vec<f64> {
    let max = crate::plot::MAX_POINTS_PER_SERIES;
    if traj.steps().saturating_mul(per_step.max(1)) < max {
        return traj.sample_times(per_step);
    }
    let (t0, t1) = (traj.time(0), traj.end_time());
    let m = (max - 1) as f64;
    (0..max).map(|i| t0 + (t1 - t0) * i as f64 / m).collect()
}

/// Indices of the step ends a chart marks: all of them, or evenly strided to at most
/// [`crate::plot::MAX_POINTS_PER_SERIES`] (the last kept).
pub fn chart_indices(states: usize) -> Vec<usize> {
    crate::plot::thin(
        &(0..states).collect::<Vec<_>>(),
        crate::plot::MAX_POINTS_PER_SERIES,
    )
}

/// Orbit (2-D) or q(t) (1-D) chart: Galerkin curves, step ends and, if known, the exact
/// solution.
pub(super) fn run_chart(
    system: &AnySystem,
    scene: &BuiltScene,
    traj: &Trajectory,
    exact: Option<&galerkin_vi::systems::ExactSolution>,
) -> Result<Chart> {
    let samples = chart_times(traj, 32);
    let title = scene.title();
    let two_d = system.dim() >= 2;
    let point = |q: &[f64], t: f64| if two_d { (q[0], q[1]) } else { (t, q[0]) };
    let mut curve = Vec::with_capacity(samples.len());
    for &t in &samples {
        curve.push(point(&traj.position_at(t)?, t));
    }
    let ends: Vec<(f64, f64)> = chart_indices(traj.q.len())
        .into_iter()
        .map(|k| point(&traj.q[k], traj.time(k)))
        .collect();
    let axes = crate::names::axis_names(system);
    let axis = |i: usize| axes.get(i).cloned().unwrap_or_default();
    let mut chart = if two_d {
        Chart::new(title, axis(0), axis(1))
            .equal_aspect()
            .legend_clear_of_data()
    } else {
        Chart::new(title, "t", axis(0)).legend_clear_of_data()
    };
    if let Some(ex) = exact {
        let pts: Vec<(f64, f64)> = samples.iter().map(|&t| point(&ex.position(t), t)).collect();
        chart.push(Series::dashed("exact solution", pts));
    }
    chart.push(Series::line("Galerkin curves", curve));
    chart.push(Series::markers("step ends (q_k)", ends));
    Ok(chart)
}
