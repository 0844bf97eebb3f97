//! `gvi refine` and `gvi reproduce`.

use super::run::{SceneArgs, load_scene};
use crate::error::LabError;
use crate::studies::refine::{Vary, parse_range, refine};
use crate::studies::reproduce::{Size, reproduce};
use clap::{Args, ValueEnum};
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
    pub range: String,
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
        VaryArg::N => super::refuse_ignored(
            "refine --vary n",
            &[("--n", r.n.is_some())],
            "n is swept (--range)",
        )?,
        VaryArg::H => super::refuse_ignored(
            "refine --vary h",
            &[("--h", r.h.is_some())],
            "h is swept (--range)",
        )?,
    }
    crate::output::check_output_dir(&dir)?;
    let scene = load_scene(&args.run)?;
    let values = parse_range(&args.range)?;
    let vary = match args.vary {
        VaryArg::N => Vary::N,
        VaryArg::H => Vary::H,
    };
    let study = refine(&scene, vary, &values, args.fixed_steps)?;
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
    /// A reduced version (seconds instead of minutes), for smoke tests.
    #[arg(long)]
    pub quick: bool,
}

pub fn run_reproduce(args: ReproduceArgs) -> Result<(), LabError> {
    let dir = args.out.unwrap_or_else(|| PathBuf::from("out/reproduce"));
    crate::output::check_output_dir(&dir)?;
    let size = if args.quick { Size::Quick } else { Size::Full };
    let rep = reproduce(&dir, size)?;
    eprint!("{}", rep.markdown());
    eprintln!("wrote {}", dir.join("summary.md").display());
    Ok(())
}

#[derive(Debug, Args)]
pub struct CompareBasesArgs {
    /// Values of n: A:B:STEP (default 4:48:4).
    #[arg(long, default_value = "4:48:4")]
    pub range: String,
    /// Quadratures to pair with every basis, comma-separated (default: all).
    #[arg(long)]
    pub quadratures: Option<String>,
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
        &[
            ("--n", r.n.is_some()),
            ("--basis", r.basis.is_some()),
            ("--quadrature", r.quadrature.is_some()),
            ("--quad-points", r.quad_points.is_some()),
            ("--economical", r.economical),
        ],
        "it sweeps every basis and quadrature over n (set n with --range and the quadratures \
         with --quadratures)",
    )?;
    crate::output::check_output_dir(&dir)?;
    use galerkin_vi::quadrature::QuadratureKind;
    let scene = load_scene(&args.run)?;
    let ns: Vec<usize> = parse_range(&args.range)?
        .into_iter()
        .map(|x| x.round() as usize)
        .collect();
    let quads: Vec<QuadratureKind> = match &args.quadratures {
        None => QuadratureKind::ALL.to_vec(),
        Some(list) => list.split(',').map(str::parse).collect::<Result<_, _>>()?,
    };
    let cmp = crate::studies::compare_bases::compare_bases(&scene, &ns, &quads)?;
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
