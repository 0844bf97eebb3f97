//! `gvi solver-scaling`.

use crate::error::LabError;
use crate::studies::scaling::{ScalingConfig, solver_scaling};
use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct ScalingArgs {
    /// A seconds-long version (n ∈ {8, 16, 32}, N ∈ {2, 4, 8}, one run per point).
    #[arg(long)]
    pub quick: bool,
    /// Skip points predicted to take longer than this many seconds (all timed runs).
    #[arg(long)]
    pub budget: Option<f64>,
    /// Output directory for CSV, JSON, Markdown and SVG (default: print the summary only).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn run_solver_scaling(args: ScalingArgs) -> Result<(), LabError> {
    if let Some(dir) = &args.out {
        crate::output::Plan::new()
            .output_dir("--out", dir, &crate::studies::scaling::FILES)
            .check()?;
    }
    let mut config = if args.quick {
        ScalingConfig::quick()
    } else {
        ScalingConfig::full()
    };
    if let Some(b) = args.budget {
        config.budget_seconds = b;
    }
    let study = solver_scaling(&config, true)?;
    match &args.out {
        Some(dir) => {
            for path in study.write(dir)? {
                eprintln!("wrote {}", path.display());
            }
            crate::output::print(&study.summary())?;
        }
        None => crate::output::print(&study.summary())?,
    }
    Ok(())
}
