//! Fitted convergence rates of a refinement study: the algebraic order in h and the
//! geometric factor in n.

use super::*;

/// The independent variable of a fitted rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RefineBy {
    /// Algebraic convergence in the step: ln error against ln h, error ≈ C hᵖ.
    H,
    /// Geometric (spectral) convergence in the number of basis functions: ln error against
    /// n, error ≈ C rⁿ.
    N,
}

/// The least-squares rate of a refinement study (see [`fitted_rate`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FittedRate {
    /// The independent variable.
    pub by: RefineBy,
    /// The error fitted.
    pub measure: ErrorMeasure,
    /// Slope of the least-squares line: d ln(error)/d ln(h) for [`RefineBy::H`],
    /// d ln(error)/dn for [`RefineBy::N`].
    pub slope: f64,
    /// Intercept of the line (ln C).
    pub intercept: f64,
    /// The rate in its usual form: for [`RefineBy::H`] the order p = slope (error ≈ C hᵖ);
    /// for [`RefineBy::N`] the factor per added basis function r = e^slope (error ≈ C rⁿ,
    /// the paper's O(0.56ⁿ); below 1 when the error falls).
    pub rate: f64,
    /// Points the fit used.
    pub used: usize,
    /// Points ignored: at or below the floor, or not finite.
    pub ignored: usize,
    /// Largest |ln error − fitted line| over the points used: how straight the data are (0.1
    /// is a 10 % scatter about the fitted law).
    pub max_residual: f64,
}

impl FittedRate {
    /// For [`RefineBy::N`], ρ = 1/r in the notation error ≈ C ρ⁻ⁿ (above 1 when the error
    /// falls); for [`RefineBy::H`], `None`.
    pub fn rho(&self) -> Option<f64> {
        match self.by {
            RefineBy::N => Some(1.0 / self.rate),
            RefineBy::H => None,
        }
    }
}

/// The least-squares rate of a refinement study, with the round-off floor
/// [`ROUND_OFF_FLOOR`] (see [`fitted_rate_above`]).
pub fn fitted_rate(
    points: &[RefinementPoint],
    by: RefineBy,
    measure: ErrorMeasure,
) -> Result<FittedRate> {
    fitted_rate_above(points, by, measure, ROUND_OFF_FLOOR)
}

/// The least-squares line through (x, ln error) with x = ln h ([`RefineBy::H`], slope = the
/// algebraic order p of error ≈ C hᵖ) or x = n ([`RefineBy::N`], slope = ln r of the
/// geometric law error ≈ C rⁿ).
///
/// Points whose error is at or below `floor` (round-off: the error no longer follows the
/// law, and would flatten the slope) or not finite (a diverged run) are ignored and
/// counted in [`FittedRate::ignored`]. The fit does not detect a pre-asymptotic regime:
/// choose the points so that they are in the asymptotic one, and read
/// [`FittedRate::max_residual`] for how straight they are.
///
/// Errors ([`GviError::InvalidInput`]): fewer than two usable points, or all of them at the
/// same x; a negative or non-finite floor; a non-finite or non-positive h.
pub fn fitted_rate_above(
    points: &[RefinementPoint],
    by: RefineBy,
    measure: ErrorMeasure,
    floor: f64,
) -> Result<FittedRate> {
    if !(floor.is_finite() && floor >= 0.0) {
        return Err(GviError::InvalidInput {
            name: "floor".into(),
            reason: format!("{floor} is not a finite non-negative error"),
        });
    }
    let mut xy = Vec::with_capacity(points.len());
    for p in points {
        let e = measure.of(p);
        if !(e.is_finite() && e > floor) {
            continue;
        }
        let x = match by {
            RefineBy::H => {
                if !(p.h.is_finite() && p.h > 0.0) {
                    return Err(GviError::InvalidInput {
                        name: "refinement point".into(),
                        reason: format!("step size h = {} is not finite and positive", p.h),
                    });
                }
                p.h.ln()
            }
            RefineBy::N => p.n as f64,
        };
        xy.push((x, e.ln()));
    }
    let used = xy.len();
    let ignored = points.len() - used;
    if used < 2 {
        return Err(GviError::InvalidInput {
            name: "refinement points".into(),
            reason: format!(
                "a rate needs at least two finite errors above the floor {floor:e}; {used} of {} are",
                points.len()
            ),
        });
    }
    let k = used as f64;
    let mx = xy.iter().map(|p| p.0).sum::<f64>() / k;
    let my = xy.iter().map(|p| p.1).sum::<f64>() / k;
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    if sxx <= 0.0 || !sxx.is_finite() {
        return Err(GviError::InvalidInput {
            name: "refinement points".into(),
            reason: "all usable points have the same n or h: no slope to fit".into(),
        });
    }
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let max_residual = xy
        .iter()
        .map(|p| (p.1 - (intercept + slope * p.0)).abs())
        .fold(0.0, crate::reduce::nan_max);
    let rate = match by {
        RefineBy::H => slope,
        RefineBy::N => slope.exp(),
    };
    Ok(FittedRate {
        by,
        measure,
        slope,
        intercept,
        rate,
        used,
        ignored,
        max_residual,
    })
}
