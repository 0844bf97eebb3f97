//! `gvi work-precision`: max position error against CPU time for the Galerkin method (every
//! basis, several h × n) and the classical peers (Störmer–Verlet, RK4, Gauss collocation,
//! Yoshida-6, Kahan–Li-8, DOP853) on one scene and horizon.
//!
//! Protocol: every method is sampled at t_k = t₀ + kΔ, Δ = the scene's h (the coarsest common
//! grid; fixed-step methods take Δ/m steps, DOP853 stops exactly at every t_k); the error is
//! the max over the samples of the max-norm position error against the exact solution or
//! [`Reference::for_system`]. The time is the median wall-clock time of `repeats` runs in this
//! process (building the method included), run one after another (never in parallel, so that
//! runs do not compete for cores). Timing is measured, never asserted.
//!
//! External peers (e.g. REBOUND's IAS15 and WHFast, `scripts/rebound/work_precision.py`) write
//! rows in the same CSV schema; [`read_external_csv`] reads them (typed errors naming the file
//! and line) and [`WorkPrecisionStudy::merge_external`] merges them into the table, the Pareto
//! front, the fastest table and the chart, marked `external`. [`reference_csv`] writes the
//! reference positions at the sample times for such scripts.
//!
//! A sweep whose predicted cost is absurd is refused up front ([`LabError::CostTooHigh`]):
//! more than [`MAX_SAMPLES`] samples, or more than [`MAX_TOTAL_STEPS`] integration steps in
//! total (samples × steps per sample interval, summed over the configurations, times the
//! repeats, plus the reference run).
//!
//! ```
//! use galerkin_vi_lab::scene::Scene;
//! use galerkin_vi_lab::studies::work_precision::{work_precision, WorkPrecisionConfig};
//! let mut scene = Scene::load("harmonic").unwrap();
//! scene.method.h = 1.0;
//! scene.method.steps = 10;
//! let study = work_precision(&scene.build().unwrap(), &WorkPrecisionConfig::quick()).unwrap();
//! assert!(study.points.iter().any(|p| p.method.starts_with("galerkin")));
//! assert!(!study.pareto_front().is_empty());
//! ```

use super::peers::{KeplerBodies, Peer, QuadPoints, run_peer};
use super::{Reference, max_norm_diff, write_file};
use crate::error::LabError;
use crate::error::Result;
use crate::scene::BuiltScene;
use galerkin_vi::basis::BasisKind;
use galerkin_vi::systems::System;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

mod external;
mod plan;
use plan::sweep_plan;
mod report;

pub use external::{EXTERNAL_COLUMNS, ExternalRows, SkippedRow, read_external, read_external_csv};

/// What to sweep.
#[derive(Debug, Clone, Serialize)]
pub struct WorkPrecisionConfig {
    /// Time span (default: the scene's h · steps).
    pub horizon: Option<f64>,
    /// Timed repetitions per configuration (the median is reported).
    pub repeats: usize,
    /// Galerkin bases to sweep.
    pub bases: Vec<BasisKind>,
    /// Galerkin quadrature point counts to sweep: the paper's 2n Gauss–Legendre points
    /// (families `galerkin-BASIS`), the economical ⌈3n/2⌉ (families `galerkin-BASIS-econ`) and
    /// the compact n (families `galerkin-BASIS-compact`).
    pub quad_points: Vec<QuadPoints>,
    /// Galerkin steps per sample interval (h = Δ/m).
    pub galerkin_divisors: Vec<usize>,
    /// Galerkin numbers of basis functions.
    pub ns: Vec<usize>,
    /// Fixed-step baselines: steps per sample interval, tried in increasing order.
    pub baseline_divisors: Vec<usize>,
    /// Gauss collocation stage counts.
    pub gauss_stages: Vec<usize>,
    /// Stage counts of the Kepler-adapted Galerkin integrator (N-body scenes only; families
    /// `galerkin-kepler-S`).
    pub kepler_stages: Vec<usize>,
    /// Kepler-adapted steps per sample interval (h = Δ/m).
    pub kepler_divisors: Vec<usize>,
    /// Which bodies the Kepler-adapted integrator puts on their Kepler orbits: every planet
    /// (`galerkin-kepler-S`) and/or only the fastest (`galerkin-kepler-S-fast`).
    pub kepler_bodies: Vec<KeplerBodies>,
    /// Numbers of basis functions of the multirate integrator (N-body scenes with a dominant
    /// mass; families `galerkin-multirate-R`).
    pub multirate_ns: Vec<usize>,
    /// Its micro steps per step (R).
    pub multirate_micro_steps: Vec<usize>,
    /// Its steps per sample interval (H = Δ/m).
    pub multirate_divisors: Vec<usize>,
    /// DOP853 tolerances (rtol = atol).
    pub tolerances: Vec<f64>,
    /// Skip fixed-step runs with more steps than this.
    pub max_steps: usize,
}

impl WorkPrecisionConfig {
    /// The full study: h ∈ Δ·{1, ½, ⅓, ¼, ⅕, ⅙, ⅛}, n = 4 … 24 and 26 … 40 in steps of 2, baselines at 1 … 2¹⁴ steps per
    /// interval (at most 2·10⁶ steps), Gauss s = 2, 4, DOP853 at 10⁻⁴ … 10⁻¹⁴, 5 repeats.
    pub fn full() -> Self {
        WorkPrecisionConfig {
            horizon: None,
            repeats: 5,
            bases: BasisKind::ALL.to_vec(),
            quad_points: QuadPoints::ALL.to_vec(),
            galerkin_divisors: vec![1, 2, 3, 4, 5, 6, 8],
            ns: (4..=24).chain((26..=40).step_by(2)).collect(),
            baseline_divisors: (0..=14).map(|k| 1 << k).collect(),
            gauss_stages: vec![2, 4],
            kepler_stages: vec![4, 6, 8],
            kepler_divisors: vec![1, 2, 3, 4, 6, 8],
            kepler_bodies: vec![KeplerBodies::All, KeplerBodies::Fastest],
            multirate_ns: vec![8, 9, 10, 11, 12],
            multirate_micro_steps: vec![2, 3, 4],
            multirate_divisors: vec![1, 2, 3, 4, 5],
            tolerances: half_decades(4, 15),
            max_steps: 2_000_000,
        }
    }

    /// A reduced study (seconds), for tests and smoke runs.
    pub fn quick() -> Self {
        WorkPrecisionConfig {
            horizon: None,
            repeats: 1,
            bases: BasisKind::ALL.to_vec(),
            quad_points: QuadPoints::ALL.to_vec(),
            galerkin_divisors: vec![1, 2],
            ns: vec![4, 8, 12, 16],
            baseline_divisors: vec![1, 4, 16, 64],
            gauss_stages: vec![2],
            kepler_stages: vec![4],
            kepler_divisors: vec![1, 2],
            kepler_bodies: vec![KeplerBodies::All],
            multirate_ns: vec![8],
            multirate_micro_steps: vec![3],
            multirate_divisors: vec![2],
            tolerances: vec![1e-4, 1e-8, 1e-12],
            max_steps: 20_000,
        }
    }

    /// The long-run study (T = 20,000 unless a horizon is given; minutes on Kepler): the
    /// accurate end of every family only — Legendre and Chebyshev–Lagrange at h ∈ Δ·{½, ¼},
    /// n = 16 … 32, baselines at 16 … 128 steps per interval, Gauss s = 4, DOP853 at
    /// 10⁻¹⁰ … 10⁻¹⁵ in half decades — one repeat each.
    pub fn long() -> Self {
        WorkPrecisionConfig {
            horizon: Some(20_000.0),
            repeats: 1,
            bases: vec![BasisKind::Legendre, BasisKind::Chebyshev],
            quad_points: QuadPoints::ALL.to_vec(),
            galerkin_divisors: vec![2, 4],
            ns: vec![16, 20, 24, 28, 32],
            baseline_divisors: vec![16, 32, 64, 128],
            gauss_stages: vec![4],
            kepler_stages: vec![6, 8],
            kepler_divisors: vec![2, 4],
            kepler_bodies: vec![KeplerBodies::All],
            multirate_ns: vec![12, 16],
            multirate_micro_steps: vec![3],
            multirate_divisors: vec![2, 4],
            tolerances: half_decades(10, 15),
            max_steps: 2_000_000,
        }
    }
}

/// 10^(−k/2) for k = 2·`from` … 2·`to`: tolerances from 10^−`from` to 10^−`to` in half
/// decades (DOP853's error is a steep function of its tolerance; a decade grid can miss its
/// cheapest point for an error by up to ~1.5×).
pub fn half_decades(from: u32, to: u32) -> Vec<f64> {
    (2 * from..=2 * to)
        .map(|k| {
            if k % 2 == 0 {
                10f64.powi(-((k / 2) as i32))
            } else {
                10f64.powf(-(k as f64) / 2.0)
            }
        })
        .collect()
}

/// One configuration's cost and error.
#[derive(Debug, Clone, Serialize)]
pub struct WorkPoint {
    /// Method family (`galerkin-chebyshev`, `galerkin-chebyshev-econ` for the economical
    /// quadrature, `stormer-verlet`, `rk4`, `gauss-2`, `yoshida-6`, `kahan-li-8`, `dop853`).
    pub method: String,
    /// Its parameters, e.g. `n = 16, h = 0.5` or `tol = 1e-9`.
    pub parameters: String,
    /// Step size (fixed-step methods).
    pub h: Option<f64>,
    /// Basis functions (Galerkin).
    pub n: Option<usize>,
    /// Quadrature points per step (Galerkin: 2n for the paper's rule, ⌈3n/2⌉ economical, n
    /// compact).
    pub quad_points: Option<usize>,
    /// Tolerance (DOP853).
    pub tolerance: Option<f64>,
    /// Max position error over the samples (∞ on failure).
    pub error: f64,
    /// Median wall-clock seconds.
    pub seconds: f64,
    /// Force evaluations of one run.
    pub force_evaluations: usize,
    /// The failure, if the run did not complete.
    pub failure: Option<String>,
    /// On the Pareto front (no other point is both faster and more accurate).
    pub pareto: bool,
    /// Read from an external file (`--external`), not run by this study.
    pub external: bool,
}

/// The fastest configuration of one method reaching one accuracy.
#[derive(Debug, Clone, Serialize)]
pub struct Fastest {
    /// Method family.
    pub method: String,
    /// Target error.
    pub target: f64,
    /// The fastest point reaching it, if any: (parameters, seconds, error).
    pub best: Option<(String, f64, f64)>,
}

/// The result of a work–precision study.
#[derive(Debug, Clone, Serialize)]
pub struct WorkPrecisionStudy {
    /// Scene name.
    pub scene: String,
    /// Time span.
    pub horizon: f64,
    /// Sample interval Δ.
    pub sample_interval: f64,
    /// What errors are measured against.
    pub reference: String,
    /// Every configuration.
    pub points: Vec<WorkPoint>,
    /// Fastest configuration per method at 10⁻⁶, 10⁻⁹, 10⁻¹².
    pub fastest: Vec<Fastest>,
    /// The external files merged into `points` (see [`WorkPrecisionStudy::merge_external`]).
    pub external_files: Vec<String>,
}

/// The files [`WorkPrecisionStudy::write`] writes into its directory.
pub const FILES: [&str; 4] = [
    "work_precision.csv",
    "work_precision.json",
    "work_precision.md",
    "work_precision.svg",
];

/// The targets of [`WorkPrecisionStudy::fastest`].
pub const TARGETS: [f64; 3] = [1e-6, 1e-9, 1e-12];

/// Run the study on a scene.
pub fn work_precision(
    scene: &BuiltScene,
    config: &WorkPrecisionConfig,
) -> Result<WorkPrecisionStudy> {
    let system = scene.euclidean()?;
    study_system(system, scene, config)
}

/// The study's largest number of samples (the reference positions are held in memory).
pub const MAX_SAMPLES: f64 = 1e8;
/// The study's largest predicted number of integration steps (all configurations, repeats
/// and the reference run together).
pub const MAX_TOTAL_STEPS: f64 = 1e9;

/// Validate the horizon and return (Δ, samples), refusing more than [`MAX_SAMPLES`] samples.
fn sample_grid(scene: &BuiltScene, config: &WorkPrecisionConfig) -> Result<(f64, usize)> {
    let dt = scene.method.h;
    let horizon = config
        .horizon
        .unwrap_or(scene.method.h * scene.method.steps as f64);
    if !(horizon.is_finite() && horizon >= dt) {
        return Err(LabError::InvalidArgument {
            name: "horizon".into(),
            reason: format!("{horizon}: must be finite and at least the scene's h = {dt}"),
        });
    }
    let samples = (horizon / dt).round().max(1.0);
    if samples.is_nan() || samples > MAX_SAMPLES {
        return Err(LabError::CostTooHigh {
            what: format!("the number of samples (T = {horizon:e} every {dt})"),
            estimate: samples,
            limit: MAX_SAMPLES,
        });
    }
    Ok((dt, samples as usize))
}

/// The reference positions at t_k = t₀ + kΔ, k = 0 … samples.
fn reference_positions<S: System>(
    system: &S,
    scene: &BuiltScene,
    dt: f64,
    samples: usize,
) -> Result<(Reference, Vec<Vec<f64>>)> {
    let reference = Reference::for_system(system, &scene.initial, dt, samples as f64 * dt)?;
    let exact: Vec<Vec<f64>> = (0..=samples)
        .map(|k| reference.position(scene.initial.t0 + k as f64 * dt))
        .collect::<Result<_>>()?;
    Ok((reference, exact))
}

/// The reference positions at the study's sample times, as written by
/// `gvi work-precision SCENE --write-reference FILE` for external peers.
#[derive(Debug, Clone, Serialize)]
pub struct ReferenceSamples {
    /// Scene name.
    pub scene: String,
    /// What the positions are (exact solution or a reference run).
    pub reference: String,
    /// Sample times t_k = t₀ + kΔ.
    pub t: Vec<f64>,
    /// Positions at t_k (the system's coordinates; barycentric for N-body scenes).
    pub q: Vec<Vec<f64>>,
}

impl ReferenceSamples {
    /// CSV: a header `k,t,q0,q1,…`, then one line per sample; numbers in Rust's shortest
    /// round-trip form.
    pub fn csv(&self) -> Result<String> {
        let dim = self.q.first().map_or(0, Vec::len);
        let mut head = vec!["k".to_string(), "t".to_string()];
        head.extend((0..dim).map(|i| format!("q{i}")));
        let rows = self.t.iter().zip(&self.q).enumerate().map(|(k, (t, q))| {
            let mut row = vec![k.to_string(), format!("{t:e}")];
            row.extend(q.iter().map(|x| format!("{x:e}")));
            row
        });
        crate::table::csv_records(&head, rows)
    }
}

/// The study's reference positions at its sample times (the same grid, horizon checks and
/// reference as [`work_precision`]), for external peers to measure against.
pub fn reference_csv(scene: &BuiltScene, config: &WorkPrecisionConfig) -> Result<ReferenceSamples> {
    let system = scene.euclidean()?;
    let (dt, samples) = sample_grid(scene, config)?;
    let cost = Reference::estimated_steps(system, &scene.initial, dt, samples as f64 * dt);
    refuse_steps(cost)?;
    let (reference, q) = reference_positions(system, scene, dt, samples)?;
    Ok(ReferenceSamples {
        scene: scene.name.clone(),
        reference: reference.describe().into(),
        t: (0..=samples)
            .map(|k| scene.initial.t0 + k as f64 * dt)
            .collect(),
        q,
    })
}

fn refuse_steps(estimate: f64) -> Result<()> {
    if estimate <= MAX_TOTAL_STEPS {
        Ok(())
    } else {
        Err(LabError::CostTooHigh {
            what: "the total number of integration steps (samples × steps per sample interval \
                   over all configurations, times the repeats, plus the reference run)"
                .into(),
            estimate,
            limit: MAX_TOTAL_STEPS,
        })
    }
}

fn study_system<S: System + 'static>(
    system: &S,
    scene: &BuiltScene,
    config: &WorkPrecisionConfig,
) -> Result<WorkPrecisionStudy> {
    let (dt, samples) = sample_grid(scene, config)?;
    let plan = sweep_plan(system, config, samples);
    // Predicted cost: every run takes samples · m steps (DOP853 at least one per sample).
    let steps: f64 = plan
        .iter()
        .flatten()
        .map(|&(_, m)| samples as f64 * m as f64)
        .sum::<f64>()
        * config.repeats.max(1) as f64
        + Reference::estimated_steps(system, &scene.initial, dt, samples as f64 * dt);
    refuse_steps(steps)?;
    let (reference, exact) = reference_positions(system, scene, dt, samples)?;
    let total: usize = plan.iter().map(Vec::len).sum();
    let pb = crate::progress::bar(total, "work-precision");
    let mut points = Vec::with_capacity(total);
    for family in plan {
        let mut best = f64::INFINITY;
        let mut stalled = 0;
        let len = family.len();
        for (i, (peer, m)) in family.into_iter().enumerate() {
            // A fixed-step family at its round-off floor gains nothing from smaller steps.
            if stalled >= 2 && !matches!(peer, Peer::Galerkin { .. }) {
                pb.inc((len - i) as u64);
                break;
            }
            let p = time_point(system, scene, peer, dt, m, samples, &exact, config.repeats);
            if p.error < 1e-10 && p.error > 0.5 * best {
                stalled += 1;
            }
            best = best.min(p.error);
            points.push(p);
            pb.inc(1);
        }
    }
    pb.finish_and_clear();
    mark_pareto(&mut points);
    let fastest = fastest_table(&points);
    Ok(WorkPrecisionStudy {
        scene: scene.name.clone(),
        horizon: samples as f64 * dt,
        sample_interval: dt,
        reference: reference.describe().into(),
        points,
        fastest,
        external_files: Vec::new(),
    })
}

#[allow(clippy::too_many_arguments)]
fn time_point<S: System + 'static>(
    system: &S,
    scene: &BuiltScene,
    peer: Peer,
    dt: f64,
    m: usize,
    samples: usize,
    exact: &[Vec<f64>],
    repeats: usize,
) -> WorkPoint {
    let h = dt / m as f64;
    let (parameters, hv, n, tolerance) = match peer {
        Peer::Galerkin {
            n,
            points: QuadPoints::Paper,
            ..
        } => (format!("n = {n}, h = {h}"), Some(h), Some(n), None),
        Peer::Galerkin { n, points, .. } => (
            format!("n = {n}, h = {h}, m = {}", points.points(n)),
            Some(h),
            Some(n),
            None,
        ),
        Peer::Multirate { n, micro_steps } => (
            format!("n = {n}, h = {h}, m = {}, R = {micro_steps}", n - 1),
            Some(h),
            Some(n),
            None,
        ),
        Peer::Dop853 { tolerance } => (format!("tol = {tolerance:e}"), None, None, Some(tolerance)),
        _ => (format!("h = {h}"), Some(h), None, None),
    };
    let quad_points = match peer {
        Peer::Galerkin { n, points, .. } => Some(points.points(n)),
        Peer::Multirate { n, .. } => Some(n - 1),
        _ => None,
    };
    let mut point = WorkPoint {
        method: peer.family(),
        parameters,
        h: hv,
        n,
        quad_points,
        tolerance,
        error: f64::INFINITY,
        seconds: f64::NAN,
        force_evaluations: 0,
        failure: None,
        pareto: false,
        external: false,
    };
    let mut times = Vec::with_capacity(repeats.max(1));
    for _ in 0..repeats.max(1) {
        let start = Instant::now();
        let run = run_peer(system, &scene.initial, peer, dt, m, samples);
        times.push(start.elapsed().as_secs_f64());
        match run {
            Err(e) => {
                point.failure = Some(e.to_string());
                return point;
            }
            Ok(run) => {
                point.force_evaluations = run.force_evaluations;
                point.error = run
                    .q
                    .iter()
                    .zip(exact)
                    .map(|(q, e)| max_norm_diff(q, e))
                    .fold(0.0, crate::distance::nan_max);
                if let Some(f) = run.failure {
                    point.failure = Some(f);
                    point.error = f64::INFINITY;
                    break;
                }
            }
        }
    }
    times.sort_by(f64::total_cmp);
    point.seconds = times[times.len() / 2];
    point
}

/// Mark the points no other point beats in both time and error.
pub fn mark_pareto(points: &mut [WorkPoint]) {
    let mut order: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].failure.is_none() && points[i].error.is_finite())
        .collect();
    order.sort_by(|&a, &b| {
        points[a]
            .seconds
            .total_cmp(&points[b].seconds)
            .then(points[a].error.total_cmp(&points[b].error))
    });
    let mut best = f64::INFINITY;
    for p in points.iter_mut() {
        p.pareto = false;
    }
    for i in order {
        if points[i].error < best {
            best = points[i].error;
            points[i].pareto = true;
        }
    }
}

fn fastest_table(points: &[WorkPoint]) -> Vec<Fastest> {
    let mut families: Vec<String> = Vec::new();
    for p in points {
        if !families.contains(&p.method) {
            families.push(p.method.clone());
        }
    }
    let mut out = Vec::new();
    for target in TARGETS {
        for f in &families {
            let best = points
                .iter()
                .filter(|p| &p.method == f && p.failure.is_none() && p.error <= target)
                .min_by(|a, b| a.seconds.total_cmp(&b.seconds))
                .map(|p| (p.parameters.clone(), p.seconds, p.error));
            out.push(Fastest {
                method: f.clone(),
                target,
                best,
            });
        }
    }
    out
}

impl WorkPrecisionStudy {
    /// The Pareto-optimal points, fastest first.
    pub fn pareto_front(&self) -> Vec<&WorkPoint> {
        let mut front: Vec<&WorkPoint> = self.points.iter().filter(|p| p.pareto).collect();
        front.sort_by(|a, b| a.seconds.total_cmp(&b.seconds));
        front
    }

    /// Seconds of the fastest point of `method` (a family name, or a prefix such as
    /// `galerkin`) with error ≤ `target`.
    pub fn fastest_time(&self, method: &str, target: f64) -> Option<f64> {
        self.points
            .iter()
            .filter(|p| p.method.starts_with(method) && p.failure.is_none() && p.error <= target)
            .map(|p| p.seconds)
            .min_by(f64::total_cmp)
    }

    /// Merge external rows (from [`read_external_csv`]) into the study: they are marked
    /// `external`, and the Pareto front and the fastest table are recomputed over all points.
    /// `source` (the file name) is recorded in [`WorkPrecisionStudy::external_files`].
    pub fn merge_external(&mut self, source: &str, points: Vec<WorkPoint>) {
        self.points.extend(points.into_iter().map(|mut p| {
            p.external = true;
            p
        }));
        self.external_files.push(source.to_string());
        mark_pareto(&mut self.points);
        self.fastest = fastest_table(&self.points);
    }

    /// Write `work_precision.{csv,json,svg}` and `work_precision.md` into `dir`.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let [csv, json, md, svg] = FILES.map(|f| dir.join(f));
        write_file(&csv, &self.csv()?)?;
        let text =
            serde_json::to_string_pretty(self).map_err(|e| LabError::Serialize(e.to_string()))?;
        write_file(&json, &text)?;
        write_file(&md, &self.summary())?;
        self.chart()
            .save_svg(&svg)
            .map_err(|e| LabError::Plot(e.to_string()))?;
        Ok(vec![csv, json, md, svg])
    }
}
