//! The `gvi` command-line tool: clap definitions and the glue from flags to the lab.
//!
//! One module per group of subcommands: `run` (`gvi run`, the scene and method flags every
//! command shares as `SceneArgs`), `check`, `study`/`study2` (refine, compare-bases, reproduce,
//! work-precision, stability, compare-refinement), `tolerance`, `scaling`, `nbody`, `periodic`
//! and `ensemble`. [`values`] holds the typed value parsers clap uses (comma lists, ranges,
//! tolerances), so that the library and the studies receive typed values, never strings.
//!
//! The flow of every command: parse the flags, load the scene and apply the flag overrides
//! (`Scene::with_overrides`), build it once (`Scene::build`: the system, the validated initial
//! state, the method), run, write through the atomic writer. Errors are [`LabError`]s printed by
//! `main` with exit status 1 (clap's own usage errors exit with 2).
//!
//! Every subcommand and flag is documented in the guide's command-line page
//! (docs/guide/command-line.md in the repository).

mod check;
mod ensemble;
mod nbody;
mod periodic;
mod run;
mod scaling;
mod section;
mod study;
mod study2;
mod tolerance;
pub mod values;

use crate::error::LabError;
use clap::{Parser, Subcommand};

/// Galerkin and spectral variational integrators (Hall & Leok).
#[derive(Debug, Parser)]
#[command(name = "gvi", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Integrate a scene (built-in name or TOML path) and write its table (CSV or JSON).
    Run(Box<run::RunArgs>),
    /// Geometric diagnostics: symplecticity defect of every step's exact Jacobian, energy and
    /// momentum-map errors at step ends and along the Galerkin curves.
    Check(Box<run::SceneArgs>),
    /// n- or h-refinement sweep with the fitted rate (CSV, JSON, SVG in --out).
    Refine(Box<study::RefineArgs>),
    /// Every basis × quadrature over a range of n at fixed h: error and kinetic condition
    /// number against n (CSV, JSON, SVG in --out).
    CompareBases(Box<study::CompareBasesArgs>),
    /// Regenerate the paper's experiments (charts and summary.md in --out; about 2 s on 2
    /// cores).
    Reproduce(study::ReproduceArgs),
    /// Max position error against CPU time for the Galerkin method and classical peers
    /// (Verlet, RK4, Gauss, compositions, DOP853), with the Pareto front (CSV, JSON, SVG).
    WorkPrecision(Box<study2::WorkPrecisionArgs>),
    /// Stability map over (h, n) of the Galerkin method and the largest stable h of each
    /// baseline (CSV, JSON, SVG heat map).
    Stability(Box<study2::StabilityArgs>),
    /// n-refinement at fixed h against h-refinement at fixed n: error against force
    /// evaluations and seconds (CSV, JSON, SVG).
    CompareRefinement(Box<study2::CompareRefinementArgs>),
    /// N-body accuracy report: per-body position errors, energy and momentum errors and
    /// Mercury's perihelion drift against a Gauss-collocation reference (CSV, SVG, summary).
    NbodyReport(Box<nbody::NBodyReportArgs>),
    /// Tolerance-driven n against the cheapest fixed n meeting each tolerance and against
    /// the oracle bound (best per-step n with every one-step error known): achieved error
    /// and force evaluations against tol (CSV, Markdown, SVG in --out).
    ToleranceStudy(Box<tolerance::ToleranceArgs>),
    /// Time per step of every stage solver against n (Kepler, outer solar system) and the
    /// number of bodies (planetesimal ring), with fitted exponents and auto / best ratios
    /// (CSV, JSON, Markdown, SVG in --out).
    SolverScaling(Box<scaling::ScalingArgs>),
    /// Find a periodic orbit (choreography) of a scene's `[periodic]` table by periodic Galerkin
    /// (Fourier basis, Newton on the action), with its Floquet multipliers and a closing run.
    Periodic(Box<periodic::PeriodicArgs>),
    /// Many runs from Gaussian perturbations of a scene's initial state, in parallel: one CSV
    /// row per member (final state, invariant errors, Lyapunov estimate), summary statistics
    /// and the throughput on all threads against one.
    Ensemble(Box<ensemble::EnsembleArgs>),
    /// Poincaré section g(t, q, p) = 0 or stroboscopic map, located on the Galerkin curves,
    /// for one orbit or a fan of orbits on one energy surface (CSV, SVG).
    Section(Box<section::SectionArgs>),
    /// List the built-in scenes.
    Scenes,
}

/// Parse and run; errors are reported by the caller.
pub fn main_with(cli: Cli) -> Result<(), LabError> {
    match cli.command {
        Command::Run(args) => run::run(*args),
        Command::Check(args) => check::run_check(*args),
        Command::Refine(args) => study::run_refine(*args),
        Command::CompareBases(args) => study::run_compare_bases(*args),
        Command::Reproduce(args) => study::run_reproduce(args),
        Command::WorkPrecision(args) => study2::run_work_precision(*args),
        Command::Stability(args) => study2::run_stability(*args),
        Command::CompareRefinement(args) => study2::run_compare_refinement(*args),
        Command::NbodyReport(args) => nbody::run_nbody_report(*args),
        Command::ToleranceStudy(args) => tolerance::run_tolerance_study(*args),
        Command::SolverScaling(args) => scaling::run_solver_scaling(*args),
        Command::Periodic(args) => periodic::run_periodic(*args),
        Command::Ensemble(args) => ensemble::run_ensemble_command(*args),
        Command::Section(args) => section::run_section_command(*args),
        Command::Scenes => crate::output::print(&scenes_listing()?),
    }
}

/// What `gvi scenes` prints: one line per built-in scene, its name, its system type and its
/// description.
pub fn scenes_listing() -> Result<String, LabError> {
    let mut text = String::new();
    for name in crate::scene::Scene::builtin_names() {
        let scene = crate::scene::Scene::load(name)?;
        let kind = crate::scene::system_type(&scene.system);
        text.push_str(&format!("{name:<20} {kind:<12} {}\n", scene.description));
    }
    Ok(text)
}

/// Refuse the method flags (`--n`, `--h`, `--basis`, `--quadrature`, `--quad-points`,
/// `--economical`, `--solver`) among `flags` that a command would ignore because it sweeps or
/// sets those values itself.
pub fn refuse_ignored(
    command: &str,
    run: &run::SceneArgs,
    flags: &[&str],
    why: &str,
) -> Result<(), LabError> {
    let given = |flag: &str| match flag {
        "--n" => run.n.is_some(),
        "--h" => run.h.is_some(),
        "--basis" => run.basis.is_some(),
        "--quadrature" => run.quadrature.is_some(),
        "--quad-points" => run.quad_points.is_some(),
        "--economical" => run.economical,
        "--solver" => run.solver.is_some(),
        "--omega" => run.omega.is_some(),
        "--harmonics" => run.harmonics.is_some(),
        _ => false,
    };
    match flags.iter().find(|f| given(f)) {
        Some(name) => Err(LabError::InvalidArgument {
            name: (*name).to_string(),
            reason: format!("`gvi {command}` does not use {name}: {why}"),
        }),
        None => Ok(()),
    }
}

/// Name the flag behind a study setting in the study's error: the studies name their
/// settings (`sweep values`, `horizon`), the command line adds the flag (`--range`).
pub fn with_flag(e: LabError, setting: &str, flag: &str) -> LabError {
    match e {
        LabError::InvalidArgument { name, reason } if name == setting => {
            LabError::InvalidArgument {
                name: format!("{setting} ({flag})"),
                reason,
            }
        }
        other => other,
    }
}

pub use crate::output::write_output;

#[cfg(test)]
mod tests {
    /// Every built-in scene has its line in `gvi scenes`, `planetesimal-ring` included.
    #[test]
    fn gvi_scenes_lists_every_builtin_scene() {
        let listing = super::scenes_listing().unwrap();
        let names: Vec<&str> = listing
            .lines()
            .filter_map(|l| l.split_whitespace().next())
            .collect();
        assert_eq!(names, crate::scene::Scene::builtin_names());
        assert!(listing.contains("planetesimal-ring    nbody"), "{listing}");
        assert!(
            listing.contains("henon-heiles         lagrangian"),
            "{listing}"
        );
    }
}
