//! `gvi tolerance-study SCENE`.

use super::values::{self, Tolerances};
use crate::error::LabError;
use crate::output::Plan;
use crate::scene::{Overrides, Scene};
use crate::studies::tolerance::{ToleranceConfig, file_names, tolerance_study};
use clap::Args;
use galerkin_vi::adaptive::ErrorControl;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct ToleranceArgs {
    /// Built-in scene name (see `gvi scenes`) or path to a TOML scene file.
    pub scene: String,
    /// Tolerances: `A:B` for every decade from A to B (e.g. 1e-6:1e-12), or a comma list.
    #[arg(long, default_value = "1e-6:1e-12")]
    pub tols: Tolerances,
    /// Error controls to compare, comma-separated (indicator, embedded, calibrated).
    #[arg(
        long,
        default_value = "calibrated,embedded",
        value_delimiter = ',',
        value_parser = values::parsed::<ErrorControl>
    )]
    pub controls: Vec<ErrorControl>,
    /// Ladder of n, comma-separated (default 4,6,…,64); fixed n runs scan its range.
    #[arg(long, value_delimiter = ',', value_parser = values::basis_count)]
    pub ladder: Option<Vec<usize>>,
    /// Basis (default: the scene's).
    #[arg(long)]
    pub basis: Option<String>,
    /// Step size (default: the scene's).
    #[arg(long)]
    pub h: Option<f64>,
    /// Number of steps (default: the scene's).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Kepler scenes only: start at periapsis of the orbit with semi-major axis 1 and this
    /// eccentricity.
    #[arg(long)]
    pub eccentricity: Option<f64>,
    /// Output directory for CSV, Markdown and SVG (default: print the table only).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn run_tolerance_study(args: ToleranceArgs) -> Result<(), LabError> {
    if let Some(dir) = &args.out {
        crate::output::check_output_dir(dir)?;
    }
    let scene_arg = args.scene.as_str();
    let mut scene = Scene::load(&args.scene)?;
    super::run::refuse_time_transform(&scene.method)?;
    let mut overrides = Overrides {
        basis: args.basis.as_deref().map(str::parse).transpose()?,
        h: args.h,
        steps: args.steps,
        ..Overrides::default()
    };
    if let Some(e) = args.eccentricity {
        if !(0.0..1.0).contains(&e) || scene.initial.q.len() != 2 {
            return Err(LabError::InvalidArgument {
                name: "--eccentricity".into(),
                reason: "needs 0 ≤ e < 1 and a planar two-dimensional (Kepler) scene".into(),
            });
        }
        overrides.q0 = Some(vec![1.0 - e, 0.0]);
        overrides.p0 = Some(vec![0.0, ((1.0 + e) / (1.0 - e)).sqrt()]);
        scene.name = format!("{}-e{e}", scene.name);
    }
    let scene = scene.with_overrides(&overrides).build()?;
    if let Some(dir) = &args.out {
        Plan::new()
            .output_dir("--out", dir, &file_names(&scene.name))
            .scene(scene_arg)
            .check()?;
    }
    let mut config = ToleranceConfig {
        tols: args.tols.values().to_vec(),
        ..ToleranceConfig::default()
    };
    config.controls = args.controls.clone();
    if let Some(l) = &args.ladder {
        config.ladder = l.clone();
    }
    crate::studies::tolerance::ensure_memory(&scene, &config)?;
    let study = tolerance_study(&scene, &config)?;
    crate::output::print(&format!("{}\n", study.to_markdown()))?;
    if let Some(dir) = &args.out {
        for p in study.write_to(dir)? {
            eprintln!("written {}", p.display());
        }
    }
    Ok(())
}
