//! `gvi work-precision`, `gvi stability` and `gvi compare-refinement`.

use super::run::{SceneArgs, load_scene};
use crate::error::LabError;
use crate::output::Plan;
use crate::studies::compare_refinement::{CompareConfig, compare_refinement};
use crate::studies::peers::{KeplerBodies, QuadPoints};
use crate::studies::stability::{Class, StabilityConfig, stability};
use crate::studies::work_precision::{
    WorkPrecisionConfig, read_external, reference_csv, work_precision,
};
use crate::studies::write_file;
use clap::Args;
use galerkin_vi::basis::BasisKind;
use std::path::PathBuf;

#[derive(Debug, Args)]
// The method flags it sweeps or fixes are refused (run_work_precision): not listed in --help.
#[command(mut_arg("n", |a| a.hide(true)))]
#[command(mut_arg("basis", |a| a.hide(true)))]
#[command(mut_arg("quadrature", |a| a.hide(true)))]
#[command(mut_arg("quad_points", |a| a.hide(true)))]
#[command(mut_arg("economical", |a| a.hide(true)))]
#[command(mut_arg("solver", |a| a.hide(true)))]
pub struct WorkPrecisionArgs {
    /// Time span (default: the scene's h · steps). Samples every scene h.
    #[arg(long)]
    pub horizon: Option<f64>,
    /// Timed repetitions per configuration (the median is reported; default 5, 1 with
    /// --long).
    #[arg(long, value_parser = super::values::count)]
    pub repeats: Option<usize>,
    /// A reduced sweep (seconds), for smoke tests.
    #[arg(long)]
    pub quick: bool,
    /// The long-run sweep: T = 20,000 (unless --horizon is given), only the accurate end of
    /// each family (Legendre and Chebyshev n = 16…32 at h = Δ/2, Δ/4; DOP853 at 1e-10…1e-15
    /// in half decades), one repeat (about a minute on Kepler).
    #[arg(long, conflicts_with = "quick")]
    pub long: bool,
    /// Output directory (default ./out/work-precision).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Merge the rows of an external peer's CSV (the study's schema, e.g. written by
    /// scripts/rebound/work_precision.py) into the table, Pareto front, fastest table and
    /// chart, marked external. Repeatable. Every file is checked before the sweep runs; a bad
    /// file is an error naming the file and line, and nothing is written.
    #[arg(long, value_name = "FILE.csv")]
    pub external: Vec<PathBuf>,
    /// Write the reference positions at the study's sample times (k,t,q0,q1,…; the exact
    /// solution or the study's reference run) to FILE and exit without running the sweep.
    #[arg(long, value_name = "FILE.csv")]
    pub write_reference: Option<PathBuf>,
    /// Galerkin bases to sweep, comma-separated (default: the preset's; e.g.
    /// chebyshev,legendre).
    #[arg(long, value_delimiter = ',', value_parser = super::values::parsed::<BasisKind>)]
    pub bases: Option<Vec<BasisKind>>,
    /// Galerkin numbers of basis functions, comma-separated (default: the preset's).
    #[arg(long, value_delimiter = ',', value_parser = super::values::count)]
    pub ns: Option<Vec<usize>>,
    /// Galerkin steps per sample interval, comma-separated (h = Δ/m; default: the preset's).
    #[arg(long, value_delimiter = ',', value_parser = super::values::count)]
    pub divisors: Option<Vec<usize>>,
    /// Galerkin quadrature point counts, comma-separated: `paper` (2n Gauss–Legendre points,
    /// families galerkin-BASIS), `economical` (⌈3n/2⌉ points, families galerkin-BASIS-econ),
    /// `compact` (n points, families galerkin-BASIS-compact) and `collocation` (n − 1 points:
    /// Gauss collocation, families galerkin-BASIS-colloc). Default: all four.
    #[arg(long, value_delimiter = ',', value_parser = super::values::parsed::<QuadPoints>)]
    pub quadratures: Option<Vec<QuadPoints>>,
    /// Stage counts of the Kepler-adapted Galerkin integrator, comma-separated (N-body scenes;
    /// families galerkin-kepler-S; default: the preset's).
    #[arg(long, value_delimiter = ',', value_parser = super::values::count)]
    pub kepler_stages: Option<Vec<usize>>,
    /// Kepler-adapted steps per sample interval, comma-separated (h = Δ/m; default: the
    /// preset's).
    #[arg(long, value_delimiter = ',', value_parser = super::values::count)]
    pub kepler_divisors: Option<Vec<usize>>,
    /// Which bodies the Kepler-adapted integrator puts on their exact Kepler orbits,
    /// comma-separated: `all` (every planet, families galerkin-kepler-S) and `fastest` (only
    /// the body with the shortest orbit, the others polynomial: galerkin-kepler-S-fast).
    /// Default: the preset's.
    #[arg(long, value_delimiter = ',', value_parser = super::values::parsed::<KeplerBodies>)]
    pub kepler_bodies: Option<Vec<KeplerBodies>>,
    /// Numbers of basis functions of the multirate Galerkin integrator, comma-separated
    /// (N-body scenes with a dominant mass: the shortest orbit on micro steps; families
    /// galerkin-multirate-R; default: the preset's).
    #[arg(long, value_delimiter = ',', value_parser = super::values::count)]
    pub multirate_ns: Option<Vec<usize>>,
    /// Multirate micro steps per step, comma-separated (default: the preset's).
    #[arg(long, value_delimiter = ',', value_parser = super::values::count)]
    pub multirate_micro_steps: Option<Vec<usize>>,
    /// Multirate steps per sample interval, comma-separated (H = Δ/m; default: the preset's).
    #[arg(long, value_delimiter = ',', value_parser = super::values::count)]
    pub multirate_divisors: Option<Vec<usize>>,
    #[command(flatten)]
    pub run: SceneArgs,
}

/// `--write-reference` writes the reference at the study's sample times (set by the scene,
/// `--horizon`, `--quick` and `--long`) and runs no sweep: the sweep's flags would be ignored.
fn refuse_study_flags_with_write_reference(args: &WorkPrecisionArgs) -> Result<(), LabError> {
    for (flag, given) in [
        ("--bases", args.bases.is_some()),
        ("--ns", args.ns.is_some()),
        ("--divisors", args.divisors.is_some()),
        ("--quadratures", args.quadratures.is_some()),
        ("--kepler-stages", args.kepler_stages.is_some()),
        ("--kepler-divisors", args.kepler_divisors.is_some()),
        ("--kepler-bodies", args.kepler_bodies.is_some()),
        ("--multirate-ns", args.multirate_ns.is_some()),
        (
            "--multirate-micro-steps",
            args.multirate_micro_steps.is_some(),
        ),
        ("--multirate-divisors", args.multirate_divisors.is_some()),
        ("--repeats", args.repeats.is_some()),
        ("--external", !args.external.is_empty()),
        ("--out", args.out.is_some()),
    ] {
        if given {
            return Err(LabError::InvalidArgument {
                name: flag.into(),
                reason: "--write-reference writes the reference positions and runs no sweep; \
                         this flag would be ignored"
                    .into(),
            });
        }
    }
    Ok(())
}

pub fn run_work_precision(args: WorkPrecisionArgs) -> Result<(), LabError> {
    let r = &args.run;
    super::refuse_ignored(
        "work-precision",
        r,
        &[
            "--n",
            "--basis",
            "--quadrature",
            "--quad-points",
            "--economical",
            "--solver",
        ],
        "it sweeps the bases, n and the quadrature point counts (--bases, --ns, \
         --quadratures) with the Gauss–Legendre rule and the auto stage solver",
    )?;
    if args.write_reference.is_some() {
        refuse_study_flags_with_write_reference(&args)?;
    }
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out/work-precision"));
    let mut plan = Plan::new();
    match &args.write_reference {
        Some(path) => plan.output("--write-reference", path),
        None => plan.output_dir("--out", &dir, &crate::studies::work_precision::FILES),
    };
    for path in &args.external {
        plan.input("--external file", path);
    }
    plan.scene(&args.run.scene).check()?;
    let scene = load_scene(&args.run)?;
    let mut config = if args.quick {
        WorkPrecisionConfig::quick()
    } else if args.long {
        WorkPrecisionConfig::long()
    } else {
        WorkPrecisionConfig::full()
    };
    if args.horizon.is_some() {
        config.horizon = args.horizon;
    }
    config.repeats = args.repeats.unwrap_or(if args.long { 1 } else { 5 });
    if let Some(b) = &args.bases {
        config.bases = b.clone();
    }
    if let Some(n) = &args.ns {
        config.ns = n.clone();
    }
    if let Some(m) = &args.divisors {
        config.galerkin_divisors = m.clone();
    }
    if let Some(k) = &args.kepler_stages {
        config.kepler_stages = k.clone();
    }
    if let Some(m) = &args.kepler_divisors {
        config.kepler_divisors = m.clone();
    }
    if let Some(k) = &args.kepler_bodies {
        config.kepler_bodies = k.clone();
    }
    if let Some(n) = &args.multirate_ns {
        config.multirate_ns = n.clone();
    }
    if let Some(r) = &args.multirate_micro_steps {
        config.multirate_micro_steps = r.clone();
    }
    if let Some(m) = &args.multirate_divisors {
        config.multirate_divisors = m.clone();
    }
    if let Some(q) = &args.quadratures {
        config.quad_points = QuadPoints::ALL
            .into_iter()
            .filter(|p| q.contains(p))
            .collect();
    }
    if let Some(path) = &args.write_reference {
        let reference = reference_csv(&scene, &config)
            .map_err(|e| super::with_flag(e, "horizon", "--horizon"))?;
        write_file(path, &reference.csv()?)?;
        eprintln!(
            "{}: {} samples of the {} at t = {} … {}\n  wrote {}",
            reference.scene,
            reference.t.len(),
            reference.reference,
            reference.t.first().copied().unwrap_or(f64::NAN),
            reference.t.last().copied().unwrap_or(f64::NAN),
            path.display()
        );
        return Ok(());
    }
    // Check every external file before the sweep: a bad one writes nothing.
    let external = args
        .external
        .iter()
        .map(|path| read_external(path).map(|rows| (path, rows)))
        .collect::<Result<Vec<_>, _>>()?;
    for (path, rows) in &external {
        for skipped in &rows.skipped {
            eprintln!("note: {}: {skipped}", path.display());
        }
    }
    let mut study =
        work_precision(&scene, &config).map_err(|e| super::with_flag(e, "horizon", "--horizon"))?;
    for (path, rows) in external {
        study.merge_external(&path.display().to_string(), rows.points);
    }
    let files = study.write(&dir)?;
    eprint!("{}", study.summary());
    for f in files {
        eprintln!("  wrote {}", f.display());
    }
    Ok(())
}

#[derive(Debug, Args)]
pub struct StabilityArgs {
    /// Steps per Galerkin cell.
    #[arg(long, default_value_t = 100)]
    pub cell_steps: usize,
    /// A reduced grid, for smoke tests.
    #[arg(long)]
    pub quick: bool,
    /// Output directory (default ./out/stability).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub run: SceneArgs,
}

pub fn run_stability(args: StabilityArgs) -> Result<(), LabError> {
    let dir = args.out.unwrap_or_else(|| PathBuf::from("out/stability"));
    Plan::new()
        .output_dir("--out", &dir, &crate::studies::stability::FILES)
        .scene(&args.run.scene)
        .check()?;
    // The map sweeps h and n itself and takes its steps from --cell-steps.
    for (flag, given) in [
        ("--h", args.run.h.is_some()),
        ("--n", args.run.n.is_some()),
        ("--steps", args.run.steps.is_some()),
        ("--quad-points", args.run.quad_points.is_some()),
        ("--economical", args.run.economical),
    ] {
        if given {
            return Err(LabError::InvalidArgument {
                name: flag.into(),
                reason: "stability sweeps h and n over its own grid and takes the steps per \
                         cell from --cell-steps; this flag would be ignored"
                    .into(),
            });
        }
    }
    if args.cell_steps == 0 {
        return Err(LabError::InvalidArgument {
            name: "--cell-steps".into(),
            reason: "need at least one step per cell".into(),
        });
    }
    let scene = load_scene(&args.run)?;
    let mut config = if args.quick {
        StabilityConfig::quick()
    } else {
        StabilityConfig::full()
    };
    config.steps = args.cell_steps;
    let study = stability(&scene, &config)?;
    if study.cells.iter().all(|c| c.class == Class::SolverFailure) {
        return Err(LabError::AllRunsFailed {
            runs: study.cells.len(),
            first: study
                .cells
                .first()
                .and_then(|c| c.message.clone())
                .unwrap_or_default(),
        });
    }
    let files = study.write(&dir)?;
    let counts = study.counts();
    eprintln!(
        "{}: {} cells ({} steps each):",
        study.scene,
        study.cells.len(),
        config.steps
    );
    if let Some((label, scale)) = &study.energy_scale {
        eprintln!("  (classified by the max energy error relative to {label} = {scale:.3e})");
    }
    for (k, c) in Class::ALL.iter().zip(counts) {
        eprintln!("  {:<15} {c}", k.as_str());
    }
    eprintln!(
        "largest stable h (bounded energy over {} steps):",
        config.baseline_steps
    );
    if study.baselines.is_empty() {
        eprintln!("  (no classical baselines: the Lagrangian is not of the form ½vᵀMv − V(q))");
    }
    for b in &study.baselines {
        eprintln!(
            "  {:<15} {:.4} (unstable at {:.4})",
            b.method, b.largest_stable_h, b.smallest_unstable_h
        );
    }
    for f in files {
        eprintln!("  wrote {}", f.display());
    }
    Ok(())
}

#[derive(Debug, Args)]
// The method flags it sweeps are refused (run_compare_refinement): not listed in --help.
#[command(mut_arg("n", |a| a.hide(true)))]
#[command(mut_arg("basis", |a| a.hide(true)))]
#[command(mut_arg("quad_points", |a| a.hide(true)))]
#[command(mut_arg("economical", |a| a.hide(true)))]
pub struct CompareRefinementArgs {
    /// A reduced sweep, for smoke tests.
    #[arg(long)]
    pub quick: bool,
    /// Output directory (default ./out/compare-refinement).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub run: SceneArgs,
}

pub fn run_compare_refinement(args: CompareRefinementArgs) -> Result<(), LabError> {
    let dir = args
        .out
        .unwrap_or_else(|| PathBuf::from("out/compare-refinement"));
    let r = &args.run;
    super::refuse_ignored(
        "compare-refinement",
        r,
        &["--n", "--basis", "--quad-points", "--economical"],
        "it sweeps the bases and n with the quadrature's default number of points",
    )?;
    Plan::new()
        .output_dir("--out", &dir, &crate::studies::compare_refinement::FILES)
        .scene(&args.run.scene)
        .check()?;
    let scene = load_scene(&args.run)?;
    let config = if args.quick {
        CompareConfig::quick()
    } else {
        CompareConfig::full()
    };
    crate::studies::compare_refinement::ensure_memory(&scene, &config)?;
    let study = compare_refinement(&scene, &config)?;
    let files = study.write(&dir)?;
    eprintln!(
        "{}: T = {}, errors against the {}; cheapest path per target:",
        study.scene, study.horizon, study.reference
    );
    for c in &study.cheapest {
        let ev = c
            .by_evaluations
            .as_ref()
            .map(|(l, n, h, e)| format!("{l} (n = {n}, h = {h}): {e} evaluations"))
            .unwrap_or_else(|| "not reached".into());
        let s = c
            .by_seconds
            .as_ref()
            .map(|(l, n, h, s)| format!("{l} (n = {n}, h = {h}): {s:.3e} s"))
            .unwrap_or_else(|| "not reached".into());
        eprintln!("  {:.0e}: {ev}; fastest {s}", c.target);
    }
    for f in files {
        eprintln!("  wrote {}", f.display());
    }
    Ok(())
}
