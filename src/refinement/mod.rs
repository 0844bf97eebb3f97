//! Refinement studies and basis comparisons for any basis and quadrature, including a user's.
//!
//! Everything here is generic over [`Basis`] and [`Quadrature`] (no closed list of kinds):
//! a study takes a *family* of integrators — a closure n ↦ integrator for n-refinement at a
//! fixed step, h ↦ integrator for h-refinement at a fixed n — so a basis or a rule written
//! outside the crate is studied exactly as the built-in ones are.
//!
//! - [`Problem`]: the Lagrangian, the initial state and the time horizon of a study,
//!   validated once.
//! - [`n_refinement`] and [`h_refinement`]: one [`RefinementPoint`] per member of the
//!   family, with the error of the one-step map (step ends) and of the Galerkin curves
//!   (dense output at [`Trajectory::sample_times`]) against a reference solution, and the
//!   cost (gradient evaluations, Newton iterations).
//! - [`measure`]: the same errors for any one trajectory.
//! - [`fitted_rate`]: the least-squares rate of a study — the algebraic order p of
//!   error ≈ C hᵖ, or the geometric factor r of error ≈ C rⁿ (the paper's O(0.56ⁿ);
//!   ρ = 1/r in the notation error ≈ C ρ⁻ⁿ) — ignoring points at the round-off floor.
//! - [`compare_bases`] and [`compare_trajectories`]: the largest pairwise difference of the
//!   dense output (positions and velocities) of several integrators on one problem, through
//!   the small trait object [`DynIntegrator`] that every [`GalerkinIntegrator`] implements.
//!
//! Errors are measured in the max-norm over components (ℓ∞), and maximised over the step
//! ends (map error) or over the sample times (curve error), the conventions of
//! docs/DESIGN.md §2. A run whose positions become non-finite gets an infinite error, which
//! [`fitted_rate`] ignores; an integration that fails (a Newton failure) ends the study with
//! its typed error.
//!
//! ```
//! use galerkin_vi::prelude::*;
//! use galerkin_vi::refinement::{ErrorMeasure, Problem, RefineBy, fitted_rate, n_refinement};
//!
//! let osc = HarmonicOscillator::unit();
//! let exact = osc.exact_solution(0.0, &[1.0], &[0.0])?.ok_or(GviError::Unsupported("exact".into()))?;
//! let problem = Problem::new(&osc, 0.0, &[1.0], &[0.0], 10.0)?;
//! let points = n_refinement(
//!     |n| GalerkinIntegrator::spectral(n, 1.0), // any basis and quadrature family
//!     &[3, 4, 5, 6, 7],
//!     &problem,
//!     |t| exact.position(t),
//!     8,
//! )?;
//! let fit = fitted_rate(&points, RefineBy::N, ErrorMeasure::Map)?;
//! assert!(fit.rate < 0.05); // measured 0.0033: each added function gains 300×
//! # Ok::<(), galerkin_vi::GviError>(())
//! ```

use crate::basis::Basis;
use crate::error::{GviError, Result, ensure_finite, ensure_len};
use crate::integrator::{GalerkinIntegrator, MAX_STEPS};
use crate::lagrangian::Lagrangian;
use crate::quadrature::Quadrature;
use crate::trajectory::Trajectory;
use serde::{Deserialize, Serialize};

mod compare;
mod fit;

pub use compare::{Comparison, DynIntegrator, compare_bases, compare_trajectories};
pub use fit::{FittedRate, RefineBy, fitted_rate, fitted_rate_above};

/// Errors below this are at the round-off floor of a double-precision run and carry no
/// information about the rate: [`fitted_rate`] ignores them. 1e-13 ≈ 450 ε. Measured on
/// Kepler e = 0.6, h = 0.5, T = 20 (spectral method): the map error stops falling at
/// n ≈ 20 and then wanders between 6e-15 and 3.6e-14 (n = 20 … 40), the curve error between
/// 9e-15 and 4.3e-14 (n = 28 … 40); the floor sits above both. Longer runs accumulate more
/// round-off: raise it with [`fitted_rate_above`].
pub const ROUND_OFF_FLOOR: f64 = 1e-13;

/// The relative tolerance within which a horizon must be a whole number of steps
/// ([`steps_for_horizon`]).
pub const HORIZON_TOLERANCE: f64 = 1e-9;

/// The Lagrangian, the initial state (t0, q0, p0) and the time horizon of a study, validated
/// once: matching dimensions, finite values, a finite positive horizon.
#[derive(Debug, Clone, Copy)]
pub struct Problem<'a, L: Lagrangian> {
    lagrangian: &'a L,
    t0: f64,
    q0: &'a [f64],
    p0: &'a [f64],
    horizon: f64,
}

impl<'a, L: Lagrangian> Problem<'a, L> {
    /// A study problem: integrate `lagrangian` from (q0, p0) at t0 over [t0, t0 + horizon].
    ///
    /// Errors: q0 or p0 of a length other than the Lagrangian's dimension
    /// ([`GviError::DimensionMismatch`]); non-finite t0, q0 or p0 ([`GviError::NonFinite`]); a
    /// horizon that is not finite and positive ([`GviError::InvalidInput`]).
    pub fn new(
        lagrangian: &'a L,
        t0: f64,
        q0: &'a [f64],
        p0: &'a [f64],
        horizon: f64,
    ) -> Result<Self> {
        let d = lagrangian.dim();
        ensure_len("initial position q0", d, q0.len())?;
        ensure_len("initial momentum p0", d, p0.len())?;
        ensure_finite("initial time t0", &[t0])?;
        ensure_finite("initial position q0", q0)?;
        ensure_finite("initial momentum p0", p0)?;
        if !(horizon.is_finite() && horizon > 0.0) {
            return Err(GviError::InvalidInput {
                name: "horizon".into(),
                reason: format!("{horizon} is not a finite positive time span"),
            });
        }
        Ok(Problem {
            lagrangian,
            t0,
            q0,
            p0,
            horizon,
        })
    }

    /// The Lagrangian.
    pub fn lagrangian(&self) -> &'a L {
        self.lagrangian
    }

    /// The initial time t0.
    pub fn t0(&self) -> f64 {
        self.t0
    }

    /// The initial position q0.
    pub fn q0(&self) -> &'a [f64] {
        self.q0
    }

    /// The initial momentum p0.
    pub fn p0(&self) -> &'a [f64] {
        self.p0
    }

    /// The time span T of the study (the runs cover [t0, t0 + T]).
    pub fn horizon(&self) -> f64 {
        self.horizon
    }

    /// Run one integrator over the horizon (steps = T/h, see [`steps_for_horizon`]).
    ///
    /// Errors: as [`steps_for_horizon`]; the integration's error (a Newton failure).
    pub fn run<I: DynIntegrator<L> + ?Sized>(&self, integrator: &I) -> Result<Trajectory> {
        let steps = steps_for_horizon(self.horizon, integrator.step_size())?;
        integrator.integrate_dyn(self.lagrangian, self.t0, self.q0, self.p0, steps)
    }
}

/// The number of steps of size h in a horizon T: round(T/h), checked.
///
/// Errors ([`GviError::InvalidInput`]): T or h not finite and positive; T/h not within a
/// relative [`HORIZON_TOLERANCE`] of a whole number (the study would otherwise end at another
/// time than the reference is compared at); fewer than 1 or more than
/// [`MAX_STEPS`] steps.
///
/// ```
/// use galerkin_vi::refinement::steps_for_horizon;
/// assert_eq!(steps_for_horizon(2.0 * std::f64::consts::PI, std::f64::consts::PI / 32.0)?, 64);
/// assert!(steps_for_horizon(1.0, 0.3).is_err());
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
pub fn steps_for_horizon(horizon: f64, h: f64) -> Result<usize> {
    let invalid = |reason: String| GviError::InvalidInput {
        name: "horizon".into(),
        reason,
    };
    if !(horizon.is_finite() && horizon > 0.0) {
        return Err(invalid(format!(
            "{horizon} is not a finite positive time span"
        )));
    }
    if !(h.is_finite() && h > 0.0) {
        return Err(GviError::InvalidStepSize { h });
    }
    let ratio = horizon / h;
    let steps = ratio.round();
    if !(1.0..=MAX_STEPS as f64).contains(&steps) {
        return Err(invalid(format!(
            "{horizon} is {ratio} steps of h = {h}: need 1 ≤ steps ≤ {MAX_STEPS}"
        )));
    }
    if (ratio - steps).abs() > HORIZON_TOLERANCE * steps {
        return Err(invalid(format!(
            "{horizon} is not a whole number of steps of h = {h} ({ratio} steps)"
        )));
    }
    Ok(steps as usize)
}

/// One run of a refinement study: the method's size, its errors against the reference and
/// its cost.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RefinementPoint {
    /// Number of basis functions n.
    pub n: usize,
    /// Step size h.
    pub h: f64,
    /// Number of steps (T/h).
    pub steps: usize,
    /// Error of the Galerkin curves: max over the sample times t of ‖q(t) − q_ref(t)‖_∞,
    /// with q(t) the dense output ([`Trajectory::position_at`]). The sample times include
    /// every step end, so `error ≥ map_error`. Infinite when the run became non-finite.
    pub error: f64,
    /// Error of the one-step map: max over the step ends t_k of ‖q_k − q_ref(t_k)‖_∞.
    /// Infinite when the run became non-finite.
    pub map_error: f64,
    /// Force (first-derivative) evaluations of the whole run.
    pub gradient_evaluations: usize,
    /// Newton iterations of the whole run.
    pub newton_iterations: usize,
}

/// Which error of a [`RefinementPoint`] a fit uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ErrorMeasure {
    /// The one-step map at the step ends ([`RefinementPoint::map_error`]).
    Map,
    /// The Galerkin curves at the sample times ([`RefinementPoint::error`]).
    Curve,
}

impl ErrorMeasure {
    /// The error of `point` this measure names.
    pub fn of(self, point: &RefinementPoint) -> f64 {
        match self {
            ErrorMeasure::Map => point.map_error,
            ErrorMeasure::Curve => point.error,
        }
    }
}

/// ‖a − b‖_∞, or ∞ when any entry is not finite (so that a diverged run never looks
/// accurate: `f64::max` would drop a NaN).
fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    let mut worst = 0.0f64;
    for (x, y) in a.iter().zip(b) {
        let d = (x - y).abs();
        if !d.is_finite() {
            return f64::INFINITY;
        }
        worst = worst.max(d);
    }
    worst
}

/// The reference position at t, checked for length and finiteness.
fn reference_at(reference: &impl Fn(f64) -> Vec<f64>, t: f64, dim: usize) -> Result<Vec<f64>> {
    let r = reference(t);
    ensure_len("reference position", dim, r.len())?;
    ensure_finite("reference position", &r)?;
    Ok(r)
}

/// The errors and cost of one trajectory against a reference position q_ref(t): the map
/// error at the step ends and the curve error at [`Trajectory::sample_times`]
/// (`samples_per_step` points per step plus the end time), as a [`RefinementPoint`].
///
/// Errors: `samples_per_step` = 0 or a trajectory with no steps ([`GviError::InvalidInput`]);
/// a reference of the wrong length ([`GviError::DimensionMismatch`]) or non-finite
/// ([`GviError::NonFinite`]); dense output unavailable (a deserialised trajectory of a
/// user's basis not attached again: [`GviError::BasisNotAttached`]).
pub fn measure(
    trajectory: &Trajectory,
    reference: impl Fn(f64) -> Vec<f64>,
    samples_per_step: usize,
) -> Result<RefinementPoint> {
    if samples_per_step == 0 {
        return Err(GviError::InvalidInput {
            name: "samples per step".into(),
            reason: "need at least 1 sample per step".into(),
        });
    }
    if trajectory.steps() == 0 {
        return Err(GviError::InvalidInput {
            name: "trajectory".into(),
            reason: "it has no steps to measure".into(),
        });
    }
    let dim = trajectory.dim;
    let mut map_error = 0.0f64;
    for (k, q) in trajectory.q.iter().enumerate() {
        let r = reference_at(&reference, trajectory.time(k), dim)?;
        map_error = map_error.max(max_abs_diff(q, &r));
    }
    let mut error = map_error;
    for t in trajectory.sample_times(samples_per_step) {
        let r = reference_at(&reference, t, dim)?;
        let q = trajectory.position_at(t)?;
        error = error.max(max_abs_diff(&q, &r));
    }
    Ok(RefinementPoint {
        n: trajectory.n,
        h: trajectory.h,
        steps: trajectory.steps(),
        error,
        map_error,
        gradient_evaluations: trajectory.gradient_evaluations(),
        newton_iterations: trajectory.newton_iterations(),
    })
}

/// n-refinement at a fixed step: for every n in `ns`, build `family(n)`, integrate the
/// problem over its horizon (T/h steps) and [`measure`] the errors against `reference`
/// (the exact or a reference position at time t) with `samples_per_step` curve samples per
/// step.
///
/// The family may be any basis and quadrature, e.g. `|n| GalerkinIntegrator::new(MyBasis::new(n)?,
/// MyRule::new(n + 1)?, 0.5)`. Its h need not be the same for every n (each run uses its own
/// integrator's h).
///
/// Errors: an empty `ns` ([`GviError::InvalidInput`]); the family's error for an n; a horizon
/// that is not a whole number of the integrator's steps ([`steps_for_horizon`]); an
/// integration failure (its typed error, e.g. [`GviError::NewtonFailure`]); the errors of
/// [`measure`].
pub fn n_refinement<B: Basis, Q: Quadrature, L: Lagrangian>(
    mut family: impl FnMut(usize) -> Result<GalerkinIntegrator<B, Q>>,
    ns: &[usize],
    problem: &Problem<'_, L>,
    reference: impl Fn(f64) -> Vec<f64>,
    samples_per_step: usize,
) -> Result<Vec<RefinementPoint>> {
    if ns.is_empty() {
        return Err(GviError::InvalidInput {
            name: "ns".into(),
            reason: "an n-refinement study needs at least one n".into(),
        });
    }
    let mut points = Vec::with_capacity(ns.len());
    for &n in ns {
        let gvi = family(n)?;
        let traj = problem.run(&gvi)?;
        points.push(measure(&traj, &reference, samples_per_step)?);
    }
    Ok(points)
}

/// h-refinement at a fixed n: for every h in `hs`, build `family(h)`, integrate the problem
/// over its horizon (which must be a whole number of steps of every h) and [`measure`] the
/// errors as [`n_refinement`] does.
///
/// Errors: an empty `hs` ([`GviError::InvalidInput`]); as [`n_refinement`].
pub fn h_refinement<B: Basis, Q: Quadrature, L: Lagrangian>(
    mut family: impl FnMut(f64) -> Result<GalerkinIntegrator<B, Q>>,
    hs: &[f64],
    problem: &Problem<'_, L>,
    reference: impl Fn(f64) -> Vec<f64>,
    samples_per_step: usize,
) -> Result<Vec<RefinementPoint>> {
    if hs.is_empty() {
        return Err(GviError::InvalidInput {
            name: "hs".into(),
            reason: "an h-refinement study needs at least one h".into(),
        });
    }
    let mut points = Vec::with_capacity(hs.len());
    for &h in hs {
        // Check before building: the family may be expensive, and the error names the horizon.
        steps_for_horizon(problem.horizon(), h)?;
        let gvi = family(h)?;
        let traj = problem.run(&gvi)?;
        points.push(measure(&traj, &reference, samples_per_step)?);
    }
    Ok(points)
}

#[cfg(test)]
mod tests;
