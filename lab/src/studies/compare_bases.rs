//! `gvi compare-bases`: every basis × quadrature over a range of n at the scene's fixed h —
//! error against n and kinetic-matrix condition number against n.
//!
//! The polynomial bases (Chebyshev–Lagrange, Legendre, Hermite) span the same space, so with
//! the same quadrature they define the same discrete map; what differs is conditioning. The
//! Fourier basis spans another space and converges algebraically on non-periodic motion.
//! Pairings whose quadrature is too weak for the basis are recorded as failures (the typed
//! `QuadratureTooWeak` error), not silently skipped.

use super::{Measurement, MeasurementRow, Reference, measure, write_file};
use crate::error::LabError;
use crate::error::Result;
use crate::plot::{Chart, Series};
use crate::scene::BuiltScene;
use galerkin_vi::Lagrangian;
use galerkin_vi::basis::BasisKind;
use galerkin_vi::integrator::GalerkinIntegrator;
use galerkin_vi::quadrature::QuadratureKind;
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The files [`BasisComparison::write`] writes into its directory.
pub const FILES: [&str; 4] = [
    "compare-bases.csv",
    "compare-bases.json",
    "compare-bases-error.svg",
    "compare-bases-condition.svg",
];

/// One row: a pairing at one n.
#[derive(Debug, Clone, Serialize)]
pub struct BasisPoint {
    /// The run's errors and cost.
    pub measurement: Measurement,
    /// Condition number of the stage block of the kinetic matrix (∞ if singular).
    pub kinetic_condition: f64,
}

/// The comparison.
#[derive(Debug, Clone, Serialize)]
pub struct BasisComparison {
    /// Scene name.
    pub scene: String,
    /// Step size used throughout.
    pub h: f64,
    /// Errors are measured against this.
    pub reference: String,
    /// Every pairing at every n.
    pub points: Vec<BasisPoint>,
}

/// Run every basis × quadrature for every n in `ns` at the scene's h, in parallel.
pub fn compare_bases(
    scene: &BuiltScene,
    ns: &[usize],
    quadratures: &[QuadratureKind],
) -> Result<BasisComparison> {
    if ns.is_empty() {
        return Err(LabError::InvalidArgument {
            name: "values of n".into(),
            reason: "no values of n".into(),
        });
    }
    let system = scene.euclidean()?;
    let (scene, ns, quads) = (scene, ns, quadratures);
    let m = &scene.method;
    let horizon = m.h * m.steps as f64;
    let total = (BasisKind::ALL.len() * quads.len() * ns.len()) as f64 * m.steps as f64
        + Reference::estimated_steps(system, &scene.initial, m.h, horizon);
    let limit = super::work_precision::MAX_TOTAL_STEPS;
    if total > limit {
        return Err(LabError::CostTooHigh {
            what: "the total number of integration steps (bases × quadratures × values \
                   of n × steps, plus the reference; lower --steps or the range)"
                .into(),
            estimate: total,
            limit,
        });
    }
    let max_n = ns.iter().copied().max().unwrap_or(0);
    super::refuse_memory(m.steps as f64, max_n, system.dim())?;
    let reference = Reference::for_system(system, &scene.initial, m.h, horizon)?;
    let mut jobs = Vec::new();
    for &b in &BasisKind::ALL {
        for &q in quads {
            for &n in ns {
                let mut method = m.clone();
                method.basis = b;
                method.quadrature = q;
                method.n = n;
                method.quad_points = None;
                jobs.push(method);
            }
        }
    }
    let pb = crate::progress::bar(jobs.len(), "compare-bases");
    let points = jobs
        .par_iter()
        .map(|method| {
            let kinetic_condition = GalerkinIntegrator::from_kinds(
                method.basis,
                method.n,
                method.quadrature,
                None,
                method.h,
            )
            .map(|g| g.kinetic_condition_number())
            .unwrap_or(f64::INFINITY);
            let measurement = measure(system, &scene.initial, method, &reference, 8);
            pb.inc(1);
            BasisPoint {
                measurement,
                kinetic_condition,
            }
        })
        .collect();
    pb.finish_and_clear();
    Ok(BasisComparison {
        scene: scene.name.clone(),
        h: m.h,
        reference: reference.describe().into(),
        points,
    })
}

impl BasisComparison {
    fn series(&self, f: impl Fn(&BasisPoint) -> Option<f64>) -> Vec<Series> {
        let mut out = Vec::new();
        for b in BasisKind::ALL {
            for q in QuadratureKind::ALL {
                let pts: Vec<(f64, f64)> = self
                    .points
                    .iter()
                    .filter(|p| {
                        p.measurement.basis == b.as_str() && p.measurement.quadrature == q.as_str()
                    })
                    .filter_map(|p| f(p).map(|y| (p.measurement.n as f64, y)))
                    .collect();
                if !pts.is_empty() {
                    let label = format!("{b} + {q}");
                    // Fourier spans another space: dashed, so it reads apart from the rest.
                    out.push(if b == BasisKind::Fourier {
                        Series::dashed(label, pts)
                    } else {
                        Series::line_markers(label, pts)
                    });
                }
            }
        }
        out
    }

    /// Error of the one-step map against n, one series per pairing (failures omitted).
    pub fn error_chart(&self) -> Chart {
        let mut c = Chart::new(
            format!("{}: one-step map error, h = {}", self.scene, self.h),
            "n (basis functions)",
            "max position error",
        )
        .log_y();
        for s in self.series(|p| {
            p.measurement
                .failure
                .is_none()
                .then_some(p.measurement.map_error)
        }) {
            c.push(s);
        }
        c
    }

    /// Kinetic-matrix condition number against n (per basis; the quadrature only matters
    /// when it is too weak).
    pub fn condition_chart(&self) -> Chart {
        let mut c = Chart::new(
            format!("{}: kinetic stage-matrix condition number", self.scene),
            "n (basis functions)",
            "condition number",
        )
        .log_y();
        for s in self.series(|p| {
            (p.measurement.quadrature == "gauss-legendre" && p.kinetic_condition.is_finite())
                .then_some(p.kinetic_condition)
        }) {
            c.push(s);
        }
        c
    }

    /// Write `compare-bases.csv`, `.json`, `-error.svg`, `-condition.svg` into `dir`.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let csv = crate::table::csv_text(
            self.points
                .iter()
                .map(|p| MeasurementRow::new(&p.measurement, Some(p.kinetic_condition))),
        )?;
        let files = FILES.map(|f| dir.join(f));
        write_file(&files[0], &csv)?;
        let json =
            serde_json::to_string_pretty(self).map_err(|e| LabError::Serialize(e.to_string()))?;
        write_file(&files[1], &json)?;
        self.error_chart()
            .save_svg(&files[2])
            .map_err(|e| LabError::Plot(e.to_string()))?;
        self.condition_chart()
            .save_svg(&files[3])
            .map_err(|e| LabError::Plot(e.to_string()))?;
        Ok(files.to_vec())
    }
}
