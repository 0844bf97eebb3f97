//! `gvi check SCENE`: symplecticity, energy and momentum-map diagnostics of a run.

use super::run::{SceneArgs, load_scene};
use crate::error::LabError;
use galerkin_vi::geometry::check_report;

pub fn run_check(args: SceneArgs) -> Result<(), LabError> {
    let scene = load_scene(&args)?;
    let system = scene.euclidean()?;
    let gvi = scene.method.integrator()?;
    let report = check_report(
        &gvi,
        system,
        &scene.initial.q,
        &scene.initial.p,
        scene.method.steps,
    )?;
    println!("{report}");
    Ok(())
}
