//! `gvi nbody-report SCENE`: accuracy of an N-body run against a Gauss-collocation reference.

use crate::error::LabError;
use crate::nbody_report::{ReportOptions, file_names, nbody_report};
use crate::output::Plan;
use crate::scene::{Overrides, Scene};
use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct NBodyReportArgs {
    /// N-body scene: solar-system, outer-solar-system, two-body, figure-eight,
    /// lagrange-triangle, planetesimal-ring, or a TOML path.
    pub scene: String,
    /// Output directory for SCENE-errors.csv/.svg, SCENE-orbits.svg and SCENE-summary.txt.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Number of basis functions n (default: the scene's).
    #[arg(long)]
    pub n: Option<usize>,
    /// Step size h (default: the scene's).
    #[arg(long)]
    pub h: Option<f64>,
    /// Number of steps (default: the scene's).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Stages of the Gauss-collocation reference (order 2s).
    #[arg(long, default_value_t = 6)]
    pub stages: usize,
    /// Reference steps per Galerkin step (default: automatic).
    #[arg(long)]
    pub substeps: Option<usize>,
    /// Skip the half-step cross-check of the reference.
    #[arg(long)]
    pub no_cross_check: bool,
}

pub fn run_nbody_report(args: NBodyReportArgs) -> Result<(), LabError> {
    if args.substeps == Some(0) {
        return Err(LabError::InvalidArgument {
            name: "--substeps".into(),
            reason: "the reference needs at least 1 step per Galerkin step".into(),
        });
    }
    if args.stages == 0 {
        return Err(LabError::InvalidArgument {
            name: "--stages".into(),
            reason: "Gauss collocation needs at least 1 stage".into(),
        });
    }
    crate::output::check_output_dir(&args.out)?;
    let scene = Scene::load(&args.scene)?
        .with_overrides(&Overrides {
            n: args.n,
            h: args.h,
            steps: args.steps,
            ..Overrides::default()
        })
        .build()?;
    super::run::refuse_time_transform(&scene.method)?;
    Plan::new()
        .output_dir("--out", &args.out, &file_names(&scene.name))
        .scene(&args.scene)
        .check()?;
    let options = ReportOptions {
        stages: args.stages,
        substeps: args.substeps,
        cross_check: !args.no_cross_check,
    };
    crate::nbody_report::ensure_memory(&scene, &options)?;
    let report = nbody_report(&scene, options)?;
    let files = report.write_to(&args.out)?;
    crate::output::print(&report.to_string())?;
    eprintln!("wrote {} in {}", files.join(", "), args.out.display());
    Ok(())
}
