//! `gvi check SCENE`: symplecticity, energy and momentum-map diagnostics of a run.

use super::run::{SceneArgs, load_scene};
use crate::error::LabError;
use crate::memory::{ensure_fits, trajectory_bytes_per_step};
use galerkin_vi::geometry::{CURVE_SAMPLES_PER_STEP, check_report};

/// Bytes per step `gvi check` holds besides the trajectory: the energy at the step ends and
/// along the curves (time and value per sample), its deviations, the momentum maps at the
/// step ends (at most 4 with their times).
fn diagnostics_bytes_per_step() -> f64 {
    (16 * (1 + CURVE_SAMPLES_PER_STEP) + 8 * CURVE_SAMPLES_PER_STEP + 4 * 16) as f64
}

pub fn run_check(args: SceneArgs) -> Result<(), LabError> {
    let scene = load_scene(&args)?;
    let system = scene.euclidean()?;
    let gvi = scene.method.integrator()?;
    let steps = scene.method.steps;
    let per_step = trajectory_bytes_per_step(scene.method.n, scene.initial.q.len())
        + diagnostics_bytes_per_step();
    ensure_fits(
        format!("the check of {steps} steps"),
        per_step * steps as f64,
        "the check keeps the whole run; fewer --steps",
    )?;
    let report = check_report(&gvi, system, &scene.initial.q, &scene.initial.p, steps)?;
    crate::output::print(&format!("{report}\n"))?;
    Ok(())
}
