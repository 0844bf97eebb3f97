//! `gvi refine`: n- or h-refinement sweeps in parallel, with the fitted rate.
//!
//! ```
//! use galerkin_vi_lab::scene::Scene;
//! use galerkin_vi_lab::studies::refine::{refine, Vary, RateFit};
//! let scene = Scene::load("kepler").unwrap().build().unwrap();
//! let ns: Vec<f64> = (10..=30).step_by(4).map(|n| n as f64).collect();
//! let study = refine(&scene, Vary::N, &ns, false).unwrap();
//! match study.fit {
//!     RateFit::Geometric(f) => assert!((f.rate - 0.56).abs() < 0.08),
//!     other => panic!("{other:?}"),
//! }
//! ```

use super::{Measurement, Reference, measure, measurements_csv, write_file};
use crate::error::LabError;
use crate::error::Result;
use crate::fit::{AlgebraicFit, GeometricFit, fit_algebraic, fit_geometric};
use crate::plot::{Chart, Series};
use crate::scene::BuiltScene;
use galerkin_vi::basis::BasisKind;
use galerkin_vi::systems::System;
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The files [`RefineStudy::write`] writes into its directory.
pub const FILES: [&str; 3] = ["refine.csv", "refine.json", "refine.svg"];

/// Which parameter a sweep varies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Vary {
    /// The number of basis functions (error ≈ C·Kⁿ expected).
    N,
    /// The step size (error ≈ C·h^p expected).
    H,
}

/// A fitted convergence rate.
#[derive(Debug, Clone, Serialize)]
pub enum RateFit {
    /// error ≈ C·Kⁿ.
    Geometric(GeometricFit),
    /// error ≈ C·h^p.
    Algebraic(AlgebraicFit),
    /// Why no rate could be fitted.
    Unavailable(String),
}

impl std::fmt::Display for RateFit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RateFit::Geometric(g) => write!(
                f,
                "error ≈ {:.3e}·{:.4}ⁿ over n ∈ [{}, {}] ({} points, residual {:.3} decades{})",
                g.constant,
                g.rate,
                g.window.0,
                g.window.1,
                g.points_used,
                g.residual,
                g.floor
                    .map(|x| format!(", round-off floor ≈ {x:.1e}"))
                    .unwrap_or_default()
            ),
            RateFit::Algebraic(a) => write!(
                f,
                "error ≈ {:.3e}·h^{:.3} over h ∈ [{:.4e}, {:.4e}] ({} points, residual {:.3} decades{})",
                a.constant,
                a.order,
                a.window.0,
                a.window.1,
                a.points_used,
                a.residual,
                a.floor
                    .map(|x| format!(", round-off floor ≈ {x:.1e}"))
                    .unwrap_or_default()
            ),
            RateFit::Unavailable(why) => write!(f, "no fit: {why}"),
        }
    }
}

/// The result of a refinement sweep.
#[derive(Debug, Clone, Serialize)]
pub struct RefineStudy {
    /// Scene name.
    pub scene: String,
    /// What was varied.
    pub vary: Vary,
    /// Integration horizon (time span) of each run; for h-sweeps with `fixed_steps` it varies.
    pub horizon: f64,
    /// Whether h-sweeps keep the number of steps (the paper's protocol) instead of the horizon.
    pub fixed_steps: bool,
    /// What errors are measured against.
    pub reference: String,
    /// One measurement per value.
    pub points: Vec<Measurement>,
    /// Fit of the one-step-map error.
    pub fit: RateFit,
    /// Fit of the Galerkin-curve error.
    pub curve_fit: RateFit,
}

/// Run the sweep: every value of `values` (n or h) with the scene's other settings, in
/// parallel. For h-sweeps the horizon h·steps of the scene is kept (steps = round(T/h))
/// unless `fixed_steps`.
pub fn refine(
    scene: &BuiltScene,
    vary: Vary,
    values: &[f64],
    fixed_steps: bool,
) -> Result<RefineStudy> {
    if values.is_empty() {
        return Err(LabError::InvalidArgument {
            name: "sweep values".into(),
            reason: "no values to sweep".into(),
        });
    }
    let system = scene.euclidean()?;
    refine_system(system, scene, vary, values, fixed_steps)
}

fn refine_system<S: System + Sync>(
    system: &S,
    scene: &BuiltScene,
    vary: Vary,
    values: &[f64],
    fixed_steps: bool,
) -> Result<RefineStudy> {
    let base = &scene.method;
    let horizon = base.h * base.steps as f64;
    let hmin = match vary {
        Vary::N => base.h,
        Vary::H => values.iter().cloned().fold(f64::INFINITY, f64::min),
    };
    let ref_horizon = match (vary, fixed_steps) {
        (Vary::H, true) => values.iter().cloned().fold(0.0, f64::max) * base.steps as f64,
        _ => horizon,
    };
    check_values(vary, values, base, fixed_steps)?;
    let total: f64 = values
        .iter()
        .map(|&x| match (vary, fixed_steps) {
            (Vary::H, false) => (horizon / x).round().max(1.0),
            _ => base.steps as f64,
        })
        .sum::<f64>()
        + Reference::estimated_steps(system, &scene.initial, hmin, ref_horizon);
    let limit = crate::studies::work_precision::MAX_TOTAL_STEPS;
    if total.is_nan() || total > limit {
        return Err(LabError::CostTooHigh {
            what: "the total number of integration steps (every run plus the reference)".into(),
            estimate: total,
            limit,
        });
    }
    let max_steps = values
        .iter()
        .map(|&x| match (vary, fixed_steps) {
            (Vary::H, false) => (horizon / x).round().max(1.0),
            _ => base.steps as f64,
        })
        .fold(0.0, f64::max);
    let max_n = match vary {
        Vary::N => values.iter().fold(0.0f64, |a, &b| a.max(b)) as usize,
        Vary::H => base.n,
    };
    super::refuse_memory(max_steps, max_n, system.dim())?;
    let reference = Reference::for_system(system, &scene.initial, hmin, ref_horizon)?;
    let methods: Vec<_> = values
        .iter()
        .map(|&x| {
            let mut m = base.clone();
            match vary {
                Vary::N => m.n = x.round().max(0.0) as usize,
                Vary::H => {
                    m.h = x;
                    if !fixed_steps {
                        m.steps = (horizon / x).round().max(1.0) as usize;
                    }
                }
            }
            m
        })
        .collect();
    let pb = crate::progress::bar(methods.len(), "refine");
    let points: Vec<Measurement> = methods
        .par_iter()
        .map(|m| {
            let r = measure(system, &scene.initial, m, &reference, 16);
            pb.inc(1);
            r
        })
        .collect();
    pb.finish_and_clear();
    let fit = fit_points(vary, &points, |m| m.map_error);
    let curve_fit = fit_points(vary, &points, |m| m.curve_error);
    Ok(RefineStudy {
        scene: scene.name.clone(),
        vary,
        horizon,
        fixed_steps,
        reference: reference.describe().into(),
        points,
        fit,
        curve_fit,
    })
}

/// The largest n a basis accepts (its `MAX_N`).
fn max_n(kind: BasisKind) -> usize {
    use galerkin_vi::basis::{ChebyshevLagrange, Enriched, Fourier, Hermite, Legendre};
    match kind {
        BasisKind::Chebyshev => ChebyshevLagrange::MAX_N,
        BasisKind::Legendre => Legendre::MAX_N,
        BasisKind::Hermite => Hermite::MAX_N,
        BasisKind::Fourier => Fourier::MAX_N,
        // Degree p plus one harmonic (the study's n is the number of functions).
        BasisKind::Enriched => Enriched::MAX_DEGREE + 3,
    }
}

/// Reject sweep values no run could use: n not a whole number ≥ 2; h longer than the
/// horizon (a sweep over one truncated step fits a meaningless rate) or so short that the
/// horizon needs more than [`galerkin_vi::integrator::MAX_STEPS`] steps.
fn check_values(
    vary: Vary,
    values: &[f64],
    base: &crate::scene::MethodSpec,
    fixed_steps: bool,
) -> Result<()> {
    let bad = |reason: String| LabError::InvalidArgument {
        name: "sweep values".into(),
        reason,
    };
    let horizon = base.h * base.steps as f64;
    for &x in values {
        match vary {
            Vary::N => {
                // The basis's own limit (1024 for the polynomial bases, 4096 for Fourier),
                // so that the message names the limit that is enforced.
                let max = max_n(base.basis);
                if !(x >= 2.0 && x.fract() == 0.0 && x <= max as f64) {
                    return Err(bad(format!(
                        "n = {x:e} is not a whole number of basis functions in 2…{max} (the \
                         {} basis's limit)",
                        base.basis
                    )));
                }
            }
            Vary::H if fixed_steps => {
                if !(x * base.steps as f64).is_finite() {
                    return Err(bad(format!(
                        "h = {x:e} times {} steps is not a finite time span",
                        base.steps
                    )));
                }
            }
            Vary::H => {
                if x > horizon {
                    return Err(bad(format!(
                        "h = {x:e} is longer than the horizon T = h·steps = {horizon:e} of the \
                         scene (use --fixed-steps, or a longer scene)"
                    )));
                }
                let steps = horizon / x;
                if steps > galerkin_vi::integrator::MAX_STEPS as f64 {
                    return Err(bad(format!(
                        "h = {x:e} needs {steps:.3e} steps to cover T = {horizon:e}, more than \
                         {:e}",
                        galerkin_vi::integrator::MAX_STEPS as f64
                    )));
                }
            }
        }
    }
    Ok(())
}

fn fit_points(vary: Vary, points: &[Measurement], err: impl Fn(&Measurement) -> f64) -> RateFit {
    let ok: Vec<&Measurement> = points.iter().filter(|m| m.failure.is_none()).collect();
    let x: Vec<f64> = ok
        .iter()
        .map(|m| match vary {
            Vary::N => m.n as f64,
            Vary::H => m.h,
        })
        .collect();
    let y: Vec<f64> = ok.iter().map(|m| err(m)).collect();
    let r = match vary {
        Vary::N => fit_geometric(&x, &y).map(RateFit::Geometric),
        Vary::H => fit_algebraic(&x, &y).map(RateFit::Algebraic),
    };
    r.unwrap_or_else(|e| RateFit::Unavailable(e.to_string()))
}

impl RefineStudy {
    /// Error against n (log y) or h (log-log): one-step map, curves, energy.
    pub fn chart(&self) -> Chart {
        let x = |m: &Measurement| match self.vary {
            Vary::N => m.n as f64,
            Vary::H => m.h,
        };
        let ok = || self.points.iter().filter(|m| m.failure.is_none());
        let series = |f: fn(&Measurement) -> f64| ok().map(|m| (x(m), f(m))).collect::<Vec<_>>();
        let (xl, title) = match self.vary {
            Vary::N => ("n (basis functions)", "n-refinement"),
            Vary::H => ("h (step size)", "h-refinement"),
        };
        let mut chart = Chart::new(
            format!("{}: {title} ({})", self.scene, self.fit),
            xl,
            "max error",
        )
        .log_y();
        if self.vary == Vary::H {
            chart = chart.log_x();
        }
        chart.push(Series::line_markers(
            "one-step map",
            series(|m| m.map_error),
        ));
        chart.push(Series::line_markers(
            "Galerkin curves",
            series(|m| m.curve_error),
        ));
        chart.push(Series::line_markers("energy", series(|m| m.energy_error)));
        let mom: Vec<(f64, f64)> = ok()
            .filter_map(|m| m.momentum_error.map(|e| (x(m), e)))
            .collect();
        if !mom.is_empty() {
            chart.push(Series::line_markers("second invariant", mom));
        }
        let failed: Vec<(f64, f64)> = self
            .points
            .iter()
            .filter(|m| m.failure.is_some())
            .map(|m| (x(m), 1.0))
            .collect();
        if !failed.is_empty() {
            chart.push(Series::markers("solver failure (plotted at 1)", failed));
        }
        chart
    }

    /// Write `refine.csv`, `refine.json` and `refine.svg` ([`FILES`]) into `dir`; returns
    /// the paths.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let [csv, json, svg] = FILES.map(|f| dir.join(f));
        write_file(&csv, &measurements_csv(&self.points)?)?;
        let text =
            serde_json::to_string_pretty(self).map_err(|e| LabError::Serialize(e.to_string()))?;
        write_file(&json, &text)?;
        self.chart()
            .save_svg(&svg)
            .map_err(|e| LabError::Plot(e.to_string()))?;
        Ok(vec![csv, json, svg])
    }
}
