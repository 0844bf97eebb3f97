//! Stage-solver scaling: wall-clock time per step of every [`StageSolver`] against the number
//! n of basis functions (Kepler e = 0.6 and the outer solar system) and against the number N
//! of bodies (a synthetic planetesimal ring, [`RingConfig`], at fixed n), with fitted log-log
//! exponents and the ratio of `auto` to the fastest explicit solver at every point.
//!
//! Each point integrates a fixed number of steps with an integrator built once: one untimed
//! 1-step warm-up, then the median of `repeats` timed [`GalerkinIntegrator::integrate`] calls.
//! A point predicted to exceed `budget_seconds` (a dense LU of size s = (n − 1)·D costs ~⅔s³
//! flops; the prediction extrapolates the same solver's previous point as s³ for `exact` and s²
//! otherwise, or assumes 1 GFlop/s and two factorisations per step for a first `exact` point) is
//! recorded as skipped with the reason. Every solver must give the same one-step map: the max
//! position difference of the final state from the `exact` solver's is recorded, relative to
//! the largest |q| of that state.

use crate::error::LabError;
use crate::error::{GviError, Result};
use crate::fit::log_linear_fit;
use galerkin_vi::integrator::{GalerkinIntegrator, NewtonOptions, StageSolver};
use galerkin_vi::lagrangian::Lagrangian;

use crate::ring::{RingConfig, planetesimal_ring};
use crate::scene::{InitialState, Scene};
use galerkin_vi::systems::Kepler;
use serde::Serialize;

use std::time::Instant;

/// The files [`ScalingStudy::write`] writes into its directory.
pub const FILES: [&str; 5] = [
    "solver_scaling.csv",
    "solver_scaling.json",
    "solver_scaling.md",
    "scaling_n.svg",
    "scaling_bodies.svg",
];

/// Solvers in the order they run (`exact` first: it is the reference of the others).
pub const SOLVERS: [StageSolver; 5] = [
    StageSolver::Exact,
    StageSolver::Kronecker,
    StageSolver::NewtonKrylov,
    StageSolver::Modal,
    StageSolver::Auto,
];

/// Settings of [`solver_scaling`].
#[derive(Debug, Clone, Serialize)]
pub struct ScalingConfig {
    /// Values of n for the n sweeps.
    pub ns: Vec<usize>,
    /// Values of N (bodies) for the ring sweep.
    pub bodies: Vec<usize>,
    /// n of the ring sweep.
    pub ring_n: usize,
    /// Step of the Kepler sweep.
    pub kepler_h: f64,
    /// Steps per run: Kepler, outer solar system, ring.
    pub steps: [usize; 3],
    /// Timed samples per point (the median is reported).
    pub repeats: usize,
    /// Shortest timed sample: a sample repeats the run until it lasts this long (short runs
    /// are dominated by scheduler noise on a shared machine).
    pub min_sample_seconds: f64,
    /// Points predicted to take longer (all runs) are skipped.
    pub budget_seconds: f64,
}

impl ScalingConfig {
    /// The full study: n ∈ {8, 12, 16, 24, 32, 48, 64}, N ∈ {2, 4, …, 64}, median of 3.
    pub fn full() -> Self {
        ScalingConfig {
            ns: vec![8, 12, 16, 24, 32, 48, 64],
            bodies: vec![2, 4, 8, 16, 32, 64],
            ring_n: 16,
            kepler_h: 1.0,
            steps: [32, 8, 8],
            repeats: 5,
            min_sample_seconds: 0.1,
            budget_seconds: 8.0,
        }
    }

    /// A seconds-long version for tests and `--quick`.
    pub fn quick() -> Self {
        ScalingConfig {
            ns: vec![8, 16, 32],
            bodies: vec![2, 4, 8],
            ring_n: 16,
            kepler_h: 1.0,
            steps: [8, 2, 2],
            repeats: 1,
            min_sample_seconds: 0.0,
            budget_seconds: 2.0,
        }
    }

    fn validate(&self) -> Result<()> {
        let bad = |name: &str, reason: String| LabError::InvalidArgument {
            name: name.into(),
            reason,
        };
        if self.ns.is_empty() || self.ns.iter().any(|&n| n < 2) || self.ring_n < 2 {
            return Err(bad("n", "every n must be at least 2".into()));
        }
        if self.bodies.is_empty() || self.bodies.iter().any(|&b| b < 2) {
            return Err(bad("bodies", "every N must be at least 2".into()));
        }
        if !(self.kepler_h.is_finite() && self.kepler_h > 0.0) {
            return Err(GviError::InvalidStepSize { h: self.kepler_h }.into());
        }
        if self.steps.contains(&0) || self.repeats == 0 {
            return Err(bad("steps", "steps and repeats must be positive".into()));
        }
        if !(self.min_sample_seconds.is_finite() && self.min_sample_seconds >= 0.0) {
            return Err(bad(
                "min_sample_seconds",
                "must be finite and non-negative".into(),
            ));
        }
        if !(self.budget_seconds.is_finite() && self.budget_seconds > 0.0) {
            return Err(bad("budget", "must be finite and positive".into()));
        }
        Ok(())
    }
}

/// One (family, size, solver) point.
#[derive(Debug, Clone, Serialize)]
pub struct ScalingPoint {
    /// `kepler`, `outer-solar-system` or `ring`.
    pub family: String,
    /// Solver.
    pub solver: String,
    /// Basis functions.
    pub n: usize,
    /// Bodies (1 for Kepler's relative coordinate).
    pub bodies: usize,
    /// Configuration dimension D.
    pub dim: usize,
    /// Step size.
    pub h: f64,
    /// Steps per run.
    pub steps: usize,
    /// Timed samples.
    pub samples: usize,
    /// Runs per sample.
    pub batch: usize,
    /// Median over the samples of seconds per step (NaN if skipped or failed).
    pub seconds_per_step: f64,
    /// Fastest sample's seconds per step.
    pub min_seconds_per_step: f64,
    /// Newton iterations per step.
    pub iterations: f64,
    /// Inner (GMRES) iterations per step.
    pub inner_iterations: f64,
    /// Factorisations (dense LU or Kronecker freezes) per step.
    pub factorizations: f64,
    /// Fallbacks per step.
    pub fallbacks: f64,
    /// Max |q − q_exact| of the final state over max |q_exact| (None where exact did not run).
    pub map_difference: Option<f64>,
    /// Why the point was skipped.
    pub skipped: Option<String>,
    /// The integration error, if a run failed.
    pub failure: Option<String>,
}

/// A fitted exponent: seconds per step ≈ C·xᵖ.
#[derive(Debug, Clone, Serialize)]
pub struct ExponentFit {
    /// Family.
    pub family: String,
    /// `n` or `N`.
    pub variable: String,
    /// Solver.
    pub solver: String,
    /// The exponent p (None with fewer than 2 points).
    pub exponent: Option<f64>,
    /// Points used.
    pub points: usize,
    /// RMS residual in decades.
    pub residual: Option<f64>,
}

/// `auto` against the fastest explicit solver at one point.
#[derive(Debug, Clone, Serialize)]
pub struct AutoRatio {
    /// Family.
    pub family: String,
    /// n.
    pub n: usize,
    /// N.
    pub bodies: usize,
    /// The fastest of exact, kronecker, newton-krylov.
    pub best: String,
    /// Its seconds per step.
    pub best_seconds: f64,
    /// auto's seconds per step.
    pub auto_seconds: f64,
    /// auto / best (medians).
    pub ratio: f64,
    /// auto / best of the fastest samples (less sensitive to other load on the machine).
    pub ratio_of_minima: f64,
}

/// The study's results.
#[derive(Debug, Clone, Serialize)]
pub struct ScalingStudy {
    /// Settings.
    pub config: ScalingConfig,
    /// Every point, in run order.
    pub points: Vec<ScalingPoint>,
    /// Fitted exponents.
    pub fits: Vec<ExponentFit>,
    /// auto / best at every point where auto and another solver ran.
    pub ratios: Vec<AutoRatio>,
}

struct Case {
    family: &'static str,
    n: usize,
    bodies: usize,
    h: f64,
    steps: usize,
}

/// Run the study (`progress`: show a bar on a terminal).
pub fn solver_scaling(config: &ScalingConfig, progress: bool) -> Result<ScalingStudy> {
    config.validate()?;
    let kepler_scene = Scene::load("kepler")?;
    let kepler = Kepler::new(1.0)?;
    let outer_scene = Scene::load("outer-solar-system")?.build()?;
    let outer = outer_scene
        .euclidean()?
        .as_nbody()
        .cloned()
        .ok_or_else(|| GviError::Unsupported("outer-solar-system is not an N-body scene".into()))?;
    let outer_init = outer_scene.initial.clone();
    let mut cases = Vec::new();
    for &n in &config.ns {
        cases.push(Case {
            family: "kepler",
            n,
            bodies: 1,
            h: config.kepler_h,
            steps: config.steps[0],
        });
    }
    for &n in &config.ns {
        let (h, steps) = (outer_scene.method.h, config.steps[1]);
        cases.push(Case {
            family: "outer-solar-system",
            n,
            bodies: outer.bodies(),
            h,
            steps,
        });
    }
    for &b in &config.bodies {
        let h = RingConfig::with_bodies(b).step();
        cases.push(Case {
            family: "ring",
            n: config.ring_n,
            bodies: b,
            h,
            steps: config.steps[2],
        });
    }
    let pb = progress.then(|| crate::progress::bar(cases.len() * SOLVERS.len(), "solver-scaling"));
    let mut points = Vec::new();
    // Previous measured (size, seconds per step) per (family, solver), for the skip prediction.
    let mut last: std::collections::HashMap<(&str, StageSolver), (f64, f64)> = Default::default();
    for case in &cases {
        let ring;
        let (init, run): (&InitialState, &dyn Fn(&Runner) -> Outcome) = match case.family {
            "kepler" => (&kepler_scene.initial, &|r: &Runner| r.run(&kepler)),
            "outer-solar-system" => (&outer_init, &|r: &Runner| r.run(&outer)),
            _ => {
                ring = planetesimal_ring(&RingConfig::with_bodies(case.bodies))?;
                (&ring.1, &|r: &Runner| r.run(&ring.0))
            }
        };
        let dim = init.q.len();
        let size = ((case.n - 1) * dim) as f64;
        let mut reference: Option<Vec<f64>> = None;
        for solver in SOLVERS {
            if let Some(pb) = &pb {
                pb.set_message(format!("{} n={} N={}", case.family, case.n, case.bodies));
            }
            let mut point = ScalingPoint {
                family: case.family.into(),
                solver: solver.to_string(),
                n: case.n,
                bodies: case.bodies,
                dim,
                h: case.h,
                steps: case.steps,
                samples: 0,
                batch: 0,
                seconds_per_step: f64::NAN,
                min_seconds_per_step: f64::NAN,
                iterations: f64::NAN,
                inner_iterations: f64::NAN,
                factorizations: f64::NAN,
                fallbacks: f64::NAN,
                map_difference: None,
                skipped: None,
                failure: None,
            };
            let predicted = predict(last.get(&(case.family, solver)).copied(), solver, size);
            let per_run = predicted * case.steps as f64;
            if per_run > config.budget_seconds {
                point.skipped = Some(format!(
                    "predicted {per_run:.1} s per {}-step run (Newton size {size}) exceeds the \
                     {} s budget",
                    case.steps, config.budget_seconds
                ));
            } else {
                let options = NewtonOptions {
                    solver,
                    ..NewtonOptions::default()
                };
                let runner = Runner {
                    n: case.n,
                    h: case.h,
                    steps: case.steps,
                    config,
                    init,
                    options,
                };
                match run(&runner) {
                    Outcome::Done {
                        median,
                        min,
                        samples,
                        batch,
                        stats,
                        q,
                    } => {
                        let per = |x: usize| x as f64 / case.steps as f64;
                        (point.samples, point.batch) = (samples, batch);
                        point.seconds_per_step = median / case.steps as f64;
                        point.min_seconds_per_step = min / case.steps as f64;
                        (point.iterations, point.inner_iterations) = (per(stats[0]), per(stats[1]));
                        (point.factorizations, point.fallbacks) = (per(stats[2]), per(stats[3]));
                        last.insert((case.family, solver), (size, point.seconds_per_step));
                        match &reference {
                            Some(r) => point.map_difference = Some(relative_difference(&q, r)),
                            None if solver == StageSolver::Exact => {
                                point.map_difference = Some(0.0);
                                reference = Some(q);
                            }
                            None => {}
                        }
                    }
                    Outcome::Failed(e) => point.failure = Some(e),
                }
            }
            points.push(point);
            if let Some(pb) = &pb {
                pb.inc(1);
            }
        }
    }
    if let Some(pb) = pb {
        pb.finish_and_clear();
    }
    let fits = fit_exponents(&points);
    let ratios = auto_ratios(&points);
    Ok(ScalingStudy {
        config: config.clone(),
        points,
        fits,
        ratios,
    })
}

/// Predicted seconds per step.
fn predict(previous: Option<(f64, f64)>, solver: StageSolver, size: f64) -> f64 {
    let power = if solver == StageSolver::Exact {
        3.0
    } else {
        2.0
    };
    match previous {
        Some((s0, t0)) if s0 > 0.0 && t0.is_finite() => t0 * (size / s0).max(1.0).powf(power),
        _ if solver == StageSolver::Exact => 2.0 * (2.0 / 3.0) * size.powi(3) / 1e9,
        _ => 0.0,
    }
}

fn relative_difference(q: &[f64], reference: &[f64]) -> f64 {
    let scale = reference
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()))
        .max(f64::MIN_POSITIVE);
    super::max_norm_diff(q, reference) / scale
}

struct Runner<'a> {
    n: usize,
    h: f64,
    steps: usize,
    config: &'a ScalingConfig,
    init: &'a InitialState,
    options: NewtonOptions,
}

enum Outcome {
    /// Median seconds of a run, summed [iterations, inner, factorizations, fallbacks] of the
    /// last run and its final position.
    Done {
        median: f64,
        min: f64,
        samples: usize,
        batch: usize,
        stats: [usize; 4],
        q: Vec<f64>,
    },
    Failed(String),
}

impl Runner<'_> {
    fn run<L: Lagrangian>(&self, lag: &L) -> Outcome {
        let gvi = match GalerkinIntegrator::spectral(self.n, self.h) {
            Ok(g) => g.with_options(self.options),
            Err(e) => return Outcome::Failed(e.to_string()),
        };
        let (t0, q0, p0) = (self.init.t0, &self.init.q, &self.init.p);
        if let Err(f) = gvi.integrate(lag, t0, q0, p0, 1) {
            return Outcome::Failed(f.error.to_string());
        }
        let timed = |batch: usize| {
            let start = Instant::now();
            let mut last = None;
            for _ in 0..batch {
                match gvi.integrate(lag, t0, q0, p0, self.steps) {
                    Ok(t) => last = Some(t),
                    Err(f) => return Err(f.error.to_string()),
                }
            }
            let seconds = start.elapsed().as_secs_f64() / batch as f64;
            last.map(|t| (seconds, t))
                .ok_or_else(|| "no run".to_string())
        };
        // The first run sets the batch (runs per sample) and how many samples fit the budget.
        let (first, mut traj) = match timed(1) {
            Ok(x) => x,
            Err(e) => return Outcome::Failed(e),
        };
        let c = self.config;
        let batch = ((c.min_sample_seconds / first.max(1e-9)).ceil() as usize).clamp(1, 100_000);
        let affordable = (c.budget_seconds / (first * batch as f64)).floor() as usize;
        let samples = c.repeats.min(affordable).max(1);
        let mut times = Vec::with_capacity(samples);
        if batch == 1 {
            times.push(first);
        }
        while times.len() < samples {
            match timed(batch) {
                Ok((seconds, t)) => {
                    times.push(seconds);
                    traj = t;
                }
                Err(e) => return Outcome::Failed(e),
            }
        }
        times.sort_by(f64::total_cmp);
        let mut stats = [0usize; 4];
        for s in &traj.stats {
            stats[0] += s.iterations;
            stats[1] += s.inner_iterations;
            stats[2] += s.factorizations;
            stats[3] += s.fallbacks;
        }
        let q = traj.q.last().cloned().unwrap_or_default();
        Outcome::Done {
            median: if times.len() % 2 == 1 {
                times[times.len() / 2]
            } else {
                0.5 * (times[times.len() / 2 - 1] + times[times.len() / 2])
            },
            min: times[0],
            samples,
            batch,
            stats,
            q,
        }
    }
}

fn ran(p: &ScalingPoint) -> bool {
    p.seconds_per_step.is_finite() && p.seconds_per_step > 0.0
}

fn fit_exponents(points: &[ScalingPoint]) -> Vec<ExponentFit> {
    let mut fits = Vec::new();
    for (family, variable) in [("kepler", "n"), ("outer-solar-system", "n"), ("ring", "N")] {
        for solver in SOLVERS {
            let pts: Vec<&ScalingPoint> = points
                .iter()
                .filter(|p| p.family == family && p.solver == solver.as_str() && ran(p))
                .collect();
            let x: Vec<f64> = pts
                .iter()
                .map(|p| (if variable == "n" { p.n } else { p.bodies } as f64).log10())
                .collect();
            let y: Vec<f64> = pts.iter().map(|p| p.seconds_per_step).collect();
            let fit = log_linear_fit(&x, &y).ok();
            fits.push(ExponentFit {
                family: family.into(),
                variable: variable.into(),
                solver: solver.to_string(),
                exponent: fit.map(|f| f.0),
                points: pts.len(),
                residual: fit.map(|f| f.2),
            });
        }
    }
    fits
}

fn auto_ratios(points: &[ScalingPoint]) -> Vec<AutoRatio> {
    let mut out = Vec::new();
    for auto in points.iter().filter(|p| p.solver == "auto" && ran(p)) {
        let best = explicit_at(points, auto)
            .min_by(|a, b| a.seconds_per_step.total_cmp(&b.seconds_per_step));
        if let Some(best) = best {
            out.push(AutoRatio {
                family: auto.family.clone(),
                n: auto.n,
                bodies: auto.bodies,
                best: best.solver.clone(),
                best_seconds: best.seconds_per_step,
                auto_seconds: auto.seconds_per_step,
                ratio: auto.seconds_per_step / best.seconds_per_step,
                ratio_of_minima: auto.min_seconds_per_step
                    / best_min(points, auto).unwrap_or(f64::NAN),
            });
        }
    }
    out
}

/// The points of the explicit solvers (not `auto`) that ran at `auto`'s point.
fn explicit_at<'a>(
    points: &'a [ScalingPoint],
    auto: &'a ScalingPoint,
) -> impl Iterator<Item = &'a ScalingPoint> {
    points.iter().filter(move |p| {
        p.family == auto.family
            && p.n == auto.n
            && p.bodies == auto.bodies
            && p.solver != "auto"
            && ran(p)
    })
}

/// The fastest sample of any explicit solver at `auto`'s point.
fn best_min(points: &[ScalingPoint], auto: &ScalingPoint) -> Option<f64> {
    explicit_at(points, auto)
        .map(|p| p.min_seconds_per_step)
        .min_by(f64::total_cmp)
}

mod report;
