//! `gvi periodic SCENE`: find a periodic orbit by periodic Galerkin and analyse it.

use super::run::Format;
use super::values;
use super::write_output;
use crate::error::LabError;
use crate::output::Plan;
use crate::periodic::{PeriodicRequest, analyse_scene};
use crate::scene::Scene;
use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct PeriodicArgs {
    /// Built-in scene name or TOML path; the scene needs a `[periodic]` table.
    pub scene: String,
    /// Fourier modes K (default: the scene's). A comma-separated list refines in K: the
    /// largest is the main solve, and the Euler–Lagrange residual against K is fitted.
    #[arg(long, value_delimiter = ',', value_parser = values::modes)]
    pub modes: Option<Vec<usize>>,
    /// Output format of --output (or stdout).
    #[arg(long, value_enum, default_value = "json")]
    pub format: Format,
    /// Write the report (JSON) or the orbit table (CSV) here instead of stdout.
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// Write an SVG of the orbit (the choreography) here.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Write an SVG of the refinement in K here (with a --modes list).
    #[arg(long)]
    pub refine_plot: Option<PathBuf>,
    /// Periods of the closing run with the time-stepping integrator (0: skip).
    #[arg(long, default_value_t = 100)]
    pub periods: usize,
}

pub fn run_periodic(args: PeriodicArgs) -> Result<(), LabError> {
    let scene = Scene::load(&args.scene)?.build()?;
    Plan::new()
        .output_opt("--output", args.output.as_deref())
        .chart_opt("--plot", args.plot.as_deref())
        .chart_opt("--refine-plot", args.refine_plot.as_deref())
        .scene(&args.scene)
        .check()?;
    let mut request = PeriodicRequest {
        periods: args.periods,
        ..PeriodicRequest::default()
    };
    if let Some(modes) = &args.modes {
        request.modes.extend(modes);
    }
    let report = analyse_scene(&scene, &request)?;
    let text = match args.format {
        Format::Json => report.to_json()?,
        Format::Csv => report.to_csv()?,
    };
    write_output(args.output.as_deref(), &text)?;
    let summary = report.summary();
    if args.output.is_some() {
        crate::output::print(&summary)?;
    } else {
        eprint!("{summary}");
    }
    if let Some(path) = &args.plot {
        report
            .orbit_chart()
            .save_svg(path)
            .map_err(|e| LabError::Plot(e.to_string()))?;
    }
    if let Some(path) = &args.refine_plot {
        if report.refinement.len() < 2 {
            return Err(LabError::InvalidArgument {
                name: "--refine-plot".into(),
                reason: "needs a list of modes, e.g. --modes 10,20,30,40".into(),
            });
        }
        report
            .refinement_chart()
            .save_svg(path)
            .map_err(|e| LabError::Plot(e.to_string()))?;
    }
    Ok(())
}
