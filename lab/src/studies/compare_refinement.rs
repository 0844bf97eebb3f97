//! `gvi compare-refinement`: is it cheaper to raise n at fixed h (spectral refinement) or to
//! shrink h at fixed n (classical refinement)? Error against cost — force evaluations (the
//! integrator's `gradient_evaluations`) and CPU seconds — for n-refinement at several fixed h
//! and h-refinement at several fixed n, for every basis in [`BasisKind::ALL`], over the
//! scene's horizon h·steps. Runs are sequential so that the seconds are comparable.
//!
//! ```
//! use galerkin_vi_lab::scene::Scene;
//! use galerkin_vi_lab::studies::compare_refinement::{compare_refinement, CompareConfig};
//! let mut scene = Scene::load("harmonic").unwrap();
//! scene.method.h = 2.0;
//! scene.method.steps = 5;
//! let study = compare_refinement(&scene.build().unwrap(), &CompareConfig::quick()).unwrap();
//! // 2 fixed-h n-paths and 2 fixed-n h-paths for every basis.
//! assert_eq!(study.paths.len(), 4 * galerkin_vi::basis::BasisKind::ALL.len());
//! ```

use super::refine::Vary;
use super::{Measurement, Reference, measure, write_file};
use crate::error::LabError;
use crate::error::Result;
use crate::plot::{Chart, Series};
use crate::scene::BuiltScene;
use crate::table;
use galerkin_vi::basis::BasisKind;
use galerkin_vi::systems::System;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The files [`CompareStudy::write`] writes into its directory.
pub const FILES: [&str; 4] = [
    "compare_refinement.csv",
    "compare_refinement.json",
    "compare_refinement_evaluations.svg",
    "compare_refinement_seconds.svg",
];

/// The paths to compare.
#[derive(Debug, Clone, Serialize)]
pub struct CompareConfig {
    /// Fixed h of the n-refinement paths, as divisors of the scene's h (h = h_scene/m).
    pub fixed_h_divisors: Vec<usize>,
    /// The n values of the n-refinement paths.
    pub ns: Vec<usize>,
    /// Fixed n of the h-refinement paths.
    pub fixed_ns: Vec<usize>,
    /// The h values of the h-refinement paths, as divisors of the scene's h.
    pub h_divisors: Vec<usize>,
}

impl CompareConfig {
    /// n = 4 … 40 at h = h_scene·{1, ½, ¼}; h = h_scene/2^k (k = 0 … 6) at n = 4, 8, 12.
    pub fn full() -> Self {
        CompareConfig {
            fixed_h_divisors: vec![1, 2, 4],
            ns: (4..=40).step_by(2).collect(),
            fixed_ns: vec![4, 8, 12],
            h_divisors: (0..=6).map(|k| 1 << k).collect(),
        }
    }

    /// Two short paths of each kind, for tests.
    pub fn quick() -> Self {
        CompareConfig {
            fixed_h_divisors: vec![1, 2],
            ns: vec![4, 8, 12, 16],
            fixed_ns: vec![4, 8],
            h_divisors: vec![1, 2, 4, 8],
        }
    }
}

/// One refinement path.
#[derive(Debug, Clone, Serialize)]
pub struct RefinementPath {
    /// Basis.
    pub basis: BasisKind,
    /// What varies along the path.
    pub vary: Vary,
    /// The fixed parameter (h for n-refinement, n for h-refinement).
    pub fixed: f64,
    /// The runs along the path.
    pub points: Vec<Measurement>,
}

impl RefinementPath {
    /// Label, e.g. `chebyshev n-refinement at h = 2`.
    pub fn label(&self) -> String {
        match self.vary {
            Vary::N => format!("{} n-refinement at h = {}", self.basis, self.fixed),
            Vary::H => format!("{} h-refinement at n = {}", self.basis, self.fixed),
        }
    }
}

/// The cheapest run reaching a target error.
#[derive(Debug, Clone, Serialize)]
pub struct Cheapest {
    /// Target error.
    pub target: f64,
    /// By force evaluations: (path label, n, h, evaluations).
    pub by_evaluations: Option<(String, usize, f64, usize)>,
    /// By seconds: (path label, n, h, seconds).
    pub by_seconds: Option<(String, usize, f64, f64)>,
}

/// The result of the comparison.
#[derive(Debug, Clone, Serialize)]
pub struct CompareStudy {
    /// Scene name.
    pub scene: String,
    /// Time span of every run.
    pub horizon: f64,
    /// What errors are measured against.
    pub reference: String,
    /// The paths.
    pub paths: Vec<RefinementPath>,
    /// Cheapest path per target (10⁻³, 10⁻⁶, 10⁻⁹, 10⁻¹²).
    pub cheapest: Vec<Cheapest>,
}

/// The memory [`compare_refinement`] needs, estimated before it runs: the reference and the
/// longest run (largest n at the smallest h; the runs are sequential), checked against
/// [`crate::memory::LIMIT_BYTES`].
pub fn ensure_memory(scene: &BuiltScene, config: &CompareConfig) -> Result<()> {
    let system = scene.euclidean()?;
    let base = &scene.method;
    let max_div = config
        .h_divisors
        .iter()
        .chain(&config.fixed_h_divisors)
        .copied()
        .max()
        .unwrap_or(1)
        .max(1) as f64;
    let n = config
        .ns
        .iter()
        .chain(&config.fixed_ns)
        .copied()
        .max()
        .unwrap_or(2);
    let steps = base.steps as f64 * max_div;
    let horizon = base.h * base.steps as f64;
    let reference = Reference::estimated_bytes(system, &scene.initial, base.h / max_div, horizon);
    let run = steps * crate::memory::trajectory_bytes_per_step(n, scene.initial.q.len());
    crate::memory::ensure_fits(
        format!("the comparison (its longest run has {steps:.0} steps)"),
        reference + run,
        "every run keeps its trajectory; fewer --steps",
    )
}

/// Run the comparison on a scene.
pub fn compare_refinement(scene: &BuiltScene, config: &CompareConfig) -> Result<CompareStudy> {
    let system = scene.euclidean()?;
    study_system(system, scene, config)
}

fn study_system<S: System>(
    system: &S,
    scene: &BuiltScene,
    config: &CompareConfig,
) -> Result<CompareStudy> {
    let base = &scene.method;
    let horizon = base.h * base.steps as f64;
    let max_div = config
        .h_divisors
        .iter()
        .chain(&config.fixed_h_divisors)
        .copied()
        .max()
        .unwrap_or(1)
        .max(1);
    if config.h_divisors.contains(&0) || config.fixed_h_divisors.contains(&0) {
        return Err(LabError::InvalidArgument {
            name: "divisors".into(),
            reason: "h divisors must be positive".into(),
        });
    }
    let reference =
        Reference::for_system(system, &scene.initial, base.h / max_div as f64, horizon)?;
    // (basis, vary, fixed, runs as (n, divisor)).
    type Plan = (BasisKind, Vary, f64, Vec<(usize, usize)>);
    let mut plan: Vec<Plan> = Vec::new();
    for basis in BasisKind::ALL {
        for &m in &config.fixed_h_divisors {
            let runs = config.ns.iter().map(|&n| (n, m)).collect();
            plan.push((basis, Vary::N, base.h / m as f64, runs));
        }
        for &n in &config.fixed_ns {
            let runs = config.h_divisors.iter().map(|&m| (n, m)).collect();
            plan.push((basis, Vary::H, n as f64, runs));
        }
    }
    let total: usize = plan.iter().map(|p| p.3.len()).sum();
    let pb = crate::progress::bar(total, "compare-refinement");
    let mut paths = Vec::new();
    for (basis, vary, fixed, runs) in plan {
        let points = runs
            .into_iter()
            .map(|(n, m)| {
                let mut method = base.clone();
                method.basis = basis;
                method.n = n;
                method.quad_points = None;
                method.h = base.h / m as f64;
                method.steps = base.steps * m;
                let r = measure(system, &scene.initial, &method, &reference, 0);
                pb.inc(1);
                r
            })
            .collect();
        paths.push(RefinementPath {
            basis,
            vary,
            fixed,
            points,
        });
    }
    pb.finish_and_clear();
    let cheapest = [1e-3, 1e-6, 1e-9, 1e-12]
        .into_iter()
        .map(|target| cheapest(&paths, target))
        .collect();
    Ok(CompareStudy {
        scene: scene.name.clone(),
        horizon,
        reference: reference.describe().into(),
        paths,
        cheapest,
    })
}

fn ok_points(paths: &[RefinementPath]) -> impl Iterator<Item = (&RefinementPath, &Measurement)> {
    paths.iter().flat_map(|p| {
        p.points
            .iter()
            .filter(|m| m.failure.is_none() && m.map_error.is_finite())
            .map(move |m| (p, m))
    })
}

fn cheapest(paths: &[RefinementPath], target: f64) -> Cheapest {
    let reaching = || ok_points(paths).filter(|(_, m)| m.map_error <= target);
    Cheapest {
        target,
        by_evaluations: reaching()
            .min_by_key(|(_, m)| m.gradient_evaluations)
            .map(|(p, m)| (p.label(), m.n, m.h, m.gradient_evaluations)),
        by_seconds: reaching()
            .min_by(|a, b| a.1.seconds.total_cmp(&b.1.seconds))
            .map(|(p, m)| (p.label(), m.n, m.h, m.seconds)),
    }
}

/// The lower envelope (Pareto front) of (cost, error) points, cheapest first.
pub fn lower_envelope(mut pts: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    pts.retain(|p| p.0.is_finite() && p.1.is_finite());
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut best = f64::INFINITY;
    pts.into_iter()
        .filter(|p| {
            let keep = p.1 < best;
            best = best.min(p.1);
            keep
        })
        .collect()
}

impl CompareStudy {
    /// Log-log chart of the map error against `cost` for every path, with the lower envelope.
    pub fn chart(&self, by_seconds: bool) -> Chart {
        let cost = |m: &Measurement| {
            if by_seconds {
                m.seconds
            } else {
                m.gradient_evaluations as f64
            }
        };
        let xl = if by_seconds {
            "CPU seconds"
        } else {
            "force evaluations"
        };
        let mut chart = Chart::new(
            format!(
                "{}: n- vs h-refinement over T = {}",
                self.scene, self.horizon
            ),
            xl,
            "max position error at step ends",
        )
        .log_x()
        .log_y();
        let mut all = Vec::new();
        for p in &self.paths {
            let pts: Vec<(f64, f64)> = p
                .points
                .iter()
                .filter(|m| m.failure.is_none() && m.map_error > 0.0 && cost(m) > 0.0)
                .map(|m| (cost(m), m.map_error))
                .collect();
            all.extend(pts.iter().copied());
            if !pts.is_empty() {
                chart.push(Series::line_markers(p.label(), pts));
            }
        }
        chart.push(Series::dashed(
            "cheapest (lower envelope)",
            lower_envelope(all),
        ));
        chart
    }

    /// CSV: one row per run with its path.
    pub fn csv(&self) -> Result<String> {
        /// One CSV line: the path, then the run.
        #[derive(Serialize)]
        struct Row<'a> {
            basis: String,
            vary: String,
            #[serde(serialize_with = "table::plain")]
            fixed: f64,
            n: usize,
            #[serde(serialize_with = "table::sci")]
            h: f64,
            steps: usize,
            #[serde(serialize_with = "table::sci")]
            map_error: f64,
            gradient_evaluations: usize,
            newton_iterations: usize,
            #[serde(serialize_with = "table::sci")]
            seconds: f64,
            #[serde(serialize_with = "table::quoted")]
            failure: Option<&'a str>,
        }
        table::csv_text(self.paths.iter().flat_map(|p| {
            p.points.iter().map(move |m| Row {
                basis: p.basis.to_string(),
                vary: format!("{:?}", p.vary),
                fixed: p.fixed,
                n: m.n,
                h: m.h,
                steps: m.steps,
                map_error: m.map_error,
                gradient_evaluations: m.gradient_evaluations,
                newton_iterations: m.newton_iterations,
                seconds: m.seconds,
                failure: m.failure.as_deref(),
            })
        }))
    }

    /// Write `compare_refinement.{csv,json}`, `compare_refinement_evaluations.svg` and
    /// `compare_refinement_seconds.svg` into `dir`.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let [csv, json, evaluations, seconds] = FILES.map(|f| dir.join(f));
        write_file(&csv, &self.csv()?)?;
        let text =
            serde_json::to_string_pretty(self).map_err(|e| LabError::Serialize(e.to_string()))?;
        write_file(&json, &text)?;
        let mut files = vec![csv, json];
        for (by_seconds, svg) in [(false, evaluations), (true, seconds)] {
            self.chart(by_seconds)
                .save_svg(&svg)
                .map_err(|e| LabError::Plot(e.to_string()))?;
            files.push(svg);
        }
        Ok(files)
    }
}
