//! `gvi refine` and `gvi reproduce`.

use super::run::{SceneArgs, load_scene};
use super::values::Range;
use crate::error::LabError;
use crate::output::Plan;
use crate::studies::refine::{Vary, refine};
use crate::studies::reproduce::{Size, reproduce};
use clap::{Args, ValueEnum};
use galerkin_vi::quadrature::QuadratureKind;
use std::path::PathBuf;

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum VaryArg {
    N,
    H,
}

#[derive(Debug, Args)]
pub struct RefineArgs {
    /// Vary n (geometric rate fitted) or h (algebraic order fitted).
    #[arg(long, value_enum)]
    pub vary: VaryArg,
    /// Values: A:B:STEP (arithmetic) or A:B:xFACTOR (geometric), e.g. 4:44:2 or 0.01:0.5:x1.5.
    #[arg(long)]
    pub range: Range,
    /// For h-sweeps, keep the scene's number of steps (the paper's protocol) instead of its
    /// time horizon.
    #[arg(long)]
    pub fixed_steps: bool,
    /// Output directory (default ./out/refine).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub run: SceneArgs,
}

pub fn run_refine(args: RefineArgs) -> Result<(), LabError> {
    let dir = args.out.unwrap_or_else(|| PathBuf::from("out/refine"));
    let r = &args.run;
    match args.vary {
        VaryArg::N => {
            super::refuse_ignored("refine --vary n", r, &["--n"], "n is swept (--range)")?
        }
        VaryArg::H => {
            super::refuse_ignored("refine --vary h", r, &["--h"], "h is swept (--range)")?
        }
    }
    Plan::new()
        .output_dir("--out", &dir, &crate::studies::refine::FILES)
        .scene(&args.run.scene)
        .check()?;
    let scene = load_scene(&args.run)?;
    let vary = match args.vary {
        VaryArg::N => Vary::N,
        VaryArg::H => Vary::H,
    };
    let study = refine(&scene, vary, args.range.values(), args.fixed_steps)
        .map_err(|e| super::with_flag(e, "sweep values", "--range"))?;
    crate::studies::ensure_some_succeeded(&study.points)?;
    let files = study.write(&dir)?;
    eprintln!(
        "{}: {:?}-refinement, {} runs ({} failed), errors against the {}",
        study.scene,
        study.vary,
        study.points.len(),
        study.points.iter().filter(|m| m.failure.is_some()).count(),
        study.reference
    );
    eprintln!("  one-step map: {}", study.fit);
    eprintln!("  Galerkin curves: {}", study.curve_fit);
    for f in files {
        eprintln!("  wrote {}", f.display());
    }
    Ok(())
}

#[derive(Debug, Args)]
pub struct ReproduceArgs {
    /// Output directory (default ./out/reproduce).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// A reduced version (fewer values of n and h, about a quarter of the time), for smoke
    /// tests.
    #[arg(long)]
    pub quick: bool,
}

pub fn run_reproduce(args: ReproduceArgs) -> Result<(), LabError> {
    let dir = args.out.unwrap_or_else(|| PathBuf::from("out/reproduce"));
    Plan::new()
        .output_dir("--out", &dir, &["summary.md", "summary.json"])
        .check()?;
    let size = if args.quick { Size::Quick } else { Size::Full };
    let rep = reproduce(&dir, size)?;
    eprint!("{}", rep.markdown());
    eprintln!("wrote {}", dir.join("summary.md").display());
    Ok(())
}

#[derive(Debug, Args)]
// The method flags it sweeps are refused (run_compare_bases): not listed in --help.
#[command(mut_arg("n", |a| a.hide(true)))]
#[command(mut_arg("basis", |a| a.hide(true)))]
#[command(mut_arg("quadrature", |a| a.hide(true)))]
#[command(mut_arg("quad_points", |a| a.hide(true)))]
#[command(mut_arg("economical", |a| a.hide(true)))]
pub struct CompareBasesArgs {
    /// Values of n: A:B:STEP (arithmetic) or A:B:xFACTOR (geometric), rounded to whole n.
    #[arg(long, default_value = "4:48:4")]
    pub range: Range,
    /// Quadratures to pair with every basis, comma-separated (default: all).
    #[arg(long, value_delimiter = ',', value_parser = super::values::parsed::<QuadratureKind>)]
    pub quadratures: Option<Vec<QuadratureKind>>,
    /// Output directory (default ./out/compare-bases).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub run: SceneArgs,
}

pub fn run_compare_bases(args: CompareBasesArgs) -> Result<(), LabError> {
    let dir = args
        .out
        .unwrap_or_else(|| PathBuf::from("out/compare-bases"));
    let r = &args.run;
    super::refuse_ignored(
        "compare-bases",
        r,
        &[
            "--n",
            "--basis",
            "--quadrature",
            "--quad-points",
            "--economical",
        ],
        "it sweeps every basis and quadrature over n (set n with --range and the quadratures \
         with --quadratures)",
    )?;
    Plan::new()
        .output_dir("--out", &dir, &crate::studies::compare_bases::FILES)
        .scene(&args.run.scene)
        .check()?;
    let scene = load_scene(&args.run)?;
    let ns: Vec<usize> = args
        .range
        .values()
        .iter()
        .map(|x| x.round() as usize)
        .collect();
    let quads: Vec<QuadratureKind> = match &args.quadratures {
        None => QuadratureKind::ALL.to_vec(),
        Some(list) => list.clone(),
    };
    let cmp = crate::studies::compare_bases::compare_bases(&scene, &ns, &quads)
        .map_err(|e| super::with_flag(e, "values of n", "--range"))?;
    let measurements: Vec<_> = cmp.points.iter().map(|p| p.measurement.clone()).collect();
    crate::studies::ensure_some_succeeded(&measurements)?;
    let files = cmp.write(&dir)?;
    eprintln!(
        "{}: {} runs at h = {} ({} failed or rejected), errors against the {}",
        cmp.scene,
        cmp.points.len(),
        cmp.h,
        cmp.points
            .iter()
            .filter(|p| p.measurement.failure.is_some())
            .count(),
        cmp.reference
    );
    for f in files {
        eprintln!("  wrote {}", f.display());
    }
    Ok(())
}
