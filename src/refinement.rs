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

/// An integrator as a trait object, for comparing integrators of different basis and
/// quadrature types on one problem ([`compare_bases`]). Every [`GalerkinIntegrator`]
/// implements it; a wrapper around another one-step method that produces a [`Trajectory`]
/// can too.
pub trait DynIntegrator<L: Lagrangian> {
    /// A label for reports, e.g. `bernstein n=12 gauss-radau(12) h=0.5`.
    fn label(&self) -> String;
    /// The step size h.
    fn step_size(&self) -> f64;
    /// Integrate `steps` steps from (q0, p0) at t0, keeping the Galerkin curves.
    fn integrate_dyn(
        &self,
        lagrangian: &L,
        t0: f64,
        q0: &[f64],
        p0: &[f64],
        steps: usize,
    ) -> Result<Trajectory>;
}

impl<B: Basis, Q: Quadrature, L: Lagrangian> DynIntegrator<L> for GalerkinIntegrator<B, Q> {
    fn label(&self) -> String {
        format!(
            "{} n={} {}({}) h={}",
            self.basis().name(),
            self.n(),
            self.rule().family,
            self.rule().len(),
            self.step_size()
        )
    }
    fn step_size(&self) -> f64 {
        GalerkinIntegrator::step_size(self)
    }
    fn integrate_dyn(
        &self,
        lagrangian: &L,
        t0: f64,
        q0: &[f64],
        p0: &[f64],
        steps: usize,
    ) -> Result<Trajectory> {
        Ok(self.integrate(lagrangian, t0, q0, p0, steps)?)
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
        .fold(0.0, f64::max);
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

/// The pairwise differences of several runs' dense output (see [`compare_trajectories`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// A label per run, in input order.
    pub labels: Vec<String>,
    /// Number of sample times compared.
    pub samples: usize,
    /// `position[a][b]`: max over the sample times of ‖q_a(t) − q_b(t)‖_∞ (symmetric, zero
    /// diagonal).
    pub position: Vec<Vec<f64>>,
    /// `velocity[a][b]`: the same for q̇(t).
    pub velocity: Vec<Vec<f64>>,
    /// The largest entry of `position`.
    pub max_position: f64,
    /// The largest entry of `velocity`.
    pub max_velocity: f64,
}

/// The largest pairwise difference of the dense output q(t), q̇(t) of several trajectories at
/// the given times (any bases, step sizes and quadratures; each trajectory evaluates its own
/// curves). Labels are "basis n=… quadrature(points) h=…" from each trajectory's record.
///
/// Errors: no trajectories or no times ([`GviError::InvalidInput`]); trajectories of different
/// dimensions ([`GviError::DimensionMismatch`]); a time outside a trajectory's span or dense
/// output unavailable (the error of [`Trajectory::state_on_curve`]).
pub fn compare_trajectories(trajectories: &[&Trajectory], times: &[f64]) -> Result<Comparison> {
    let Some(first) = trajectories.first() else {
        return Err(GviError::InvalidInput {
            name: "trajectories".into(),
            reason: "nothing to compare".into(),
        });
    };
    if times.is_empty() {
        return Err(GviError::InvalidInput {
            name: "times".into(),
            reason: "no sample times".into(),
        });
    }
    for t in trajectories {
        ensure_len("trajectory dimension", first.dim, t.dim)?;
    }
    let m = trajectories.len();
    let mut position = vec![vec![0.0f64; m]; m];
    let mut velocity = vec![vec![0.0f64; m]; m];
    let mut states = Vec::with_capacity(m);
    for &t in times {
        states.clear();
        for traj in trajectories {
            states.push(traj.state_on_curve(t)?);
        }
        for a in 0..m {
            for b in a + 1..m {
                let dq = max_abs_diff(&states[a].0, &states[b].0);
                let dv = max_abs_diff(&states[a].1, &states[b].1);
                position[a][b] = position[a][b].max(dq);
                velocity[a][b] = velocity[a][b].max(dv);
            }
        }
    }
    for a in 0..m {
        for b in 0..a {
            position[a][b] = position[b][a];
            velocity[a][b] = velocity[b][a];
        }
    }
    let largest = |x: &Vec<Vec<f64>>| x.iter().flatten().copied().fold(0.0, f64::max);
    Ok(Comparison {
        labels: trajectories
            .iter()
            .map(|t| {
                format!(
                    "{} n={} {}({}) h={}",
                    t.basis, t.n, t.quadrature, t.quad_points, t.h
                )
            })
            .collect(),
        samples: times.len(),
        max_position: largest(&position),
        max_velocity: largest(&velocity),
        position,
        velocity,
    })
}

/// Run several integrators — any bases, quadratures and step sizes — on one problem and
/// compare their dense output: the max pairwise difference of q(t) and q̇(t) at the times
/// t0 + T i/N, i = 0 … N, with N = `samples_per_step` × the largest number of steps of
/// any run.
///
/// Polynomial bases of the same n under the same quadrature define the same discrete
/// Lagrangian (docs/DESIGN.md §2), so their differences are round-off; a basis of another
/// space (Fourier) or another quadrature differs by the methods' errors.
///
/// Errors: no integrators or `samples_per_step` = 0 ([`GviError::InvalidInput`]); as
/// [`Problem::run`] and [`compare_trajectories`].
pub fn compare_bases<L: Lagrangian>(
    integrators: &[&dyn DynIntegrator<L>],
    problem: &Problem<'_, L>,
    samples_per_step: usize,
) -> Result<Comparison> {
    if integrators.is_empty() {
        return Err(GviError::InvalidInput {
            name: "integrators".into(),
            reason: "nothing to compare".into(),
        });
    }
    if samples_per_step == 0 {
        return Err(GviError::InvalidInput {
            name: "samples per step".into(),
            reason: "need at least 1 sample per step".into(),
        });
    }
    let trajectories = integrators
        .iter()
        .map(|gvi| problem.run(*gvi))
        .collect::<Result<Vec<_>>>()?;
    let steps = trajectories.iter().map(|t| t.steps()).max().unwrap_or(1);
    let samples = steps.saturating_mul(samples_per_step);
    let (t0, span) = (problem.t0(), problem.horizon());
    let mut times: Vec<f64> = (0..samples)
        .map(|i| t0 + span * i as f64 / samples as f64)
        .collect();
    // The last time is each run's own end time (they agree to HORIZON_TOLERANCE).
    times.push(
        trajectories
            .iter()
            .map(|t| t.end_time())
            .fold(f64::INFINITY, f64::min),
    );
    let refs: Vec<&Trajectory> = trajectories.iter().collect();
    let mut comparison = compare_trajectories(&refs, &times)?;
    comparison.labels = integrators.iter().map(|g| g.label()).collect();
    Ok(comparison)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::basis::{ChebyshevLagrange, Fourier, Hermite, Legendre};
    use crate::quadrature::GaussLegendre;
    use crate::systems::{Kepler, System};

    fn kepler_reference() -> (Kepler, [f64; 2], [f64; 2], crate::systems::ExactSolution) {
        let kepler = Kepler::new(1.0).unwrap();
        let (q0, p0) = Kepler::paper_initial_state();
        let exact = kepler.exact_solution(0.0, &q0, &p0).unwrap().unwrap();
        (kepler, q0, p0, exact)
    }

    /// Chebyshev n = 4 (degree s = 3) with 8-point Gauss–Legendre on Kepler e = 0.6 over one
    /// period, h = 2π/64 … 2π/256: the one-step map has order 2s = 2(n − 1) = 6 (the
    /// superconvergence of Galerkin methods with exact-enough quadrature; the guide's
    /// "order 2(n − 1)"), the Galerkin curves only about s + 1 = 4 (the local error of the
    /// interior of the curve). Measured: map order 6.0014 with a max log-residual 8.6e-4
    /// (errors 1.2e-5 … 3.0e-9, all above the floor); curve order 4.27, residual 0.14 (its
    /// local slopes fall from 4.6 to 3.9: pre-asymptotic). Tolerances: 0.1 on the map order
    /// (70× the measured deviation; a wrong order is off by ≥ 1) and [3.5, 5] on the curve order.
    /// Negative control: the curve error, fitted as if it were the map's, misses 6.
    #[test]
    fn h_refinement_of_chebyshev_n4_has_order_six() {
        let (kepler, q0, p0, exact) = kepler_reference();
        let period = std::f64::consts::TAU;
        let problem = Problem::new(&kepler, 0.0, &q0, &p0, period).unwrap();
        let hs: Vec<f64> = [64.0, 96.0, 128.0, 192.0, 256.0]
            .iter()
            .map(|s| period / s)
            .collect();
        let points = h_refinement(
            |h| GalerkinIntegrator::new(ChebyshevLagrange::new(4)?, GaussLegendre::new(8)?, h),
            &hs,
            &problem,
            |t| exact.position(t),
            8,
        )
        .unwrap();
        for p in &points {
            println!(
                "h = {:.4e}: map {:.3e}, curve {:.3e}",
                p.h, p.map_error, p.error
            );
            assert!(p.error >= p.map_error && p.n == 4);
            assert_eq!(p.steps, steps_for_horizon(period, p.h).unwrap());
        }
        let map = fitted_rate(&points, RefineBy::H, ErrorMeasure::Map).unwrap();
        let curve = fitted_rate(&points, RefineBy::H, ErrorMeasure::Curve).unwrap();
        println!("map {map:?}\ncurve {curve:?}");
        assert_eq!((map.used, map.ignored), (points.len(), 0));
        assert!((map.rate - 6.0).abs() < 0.1, "order {}", map.rate);
        assert!(map.max_residual < 0.05, "{map:?}");
        assert!(map.rho().is_none());
        assert!(
            (3.5..5.0).contains(&curve.rate),
            "curve order {}",
            curve.rate
        );
        assert!((curve.rate - 6.0).abs() > 0.5);
    }

    /// n-refinement of the spectral method at a large fixed step (Kepler e = 0.6, h = 1,
    /// T = 20, n = 6 … 20): every added pair of basis functions lowers both errors, and the
    /// fitted factor per basis function r is well below 1 (geometric convergence). Measured:
    /// map errors 4.7e-1 … 1.8e-8, r = 0.30 (ρ = 3.3), max log-residual 0.36; curve errors
    /// 6.5e-1 … 3.1e-7, r = 0.36, residual 1.0 (the curve error falls more slowly at large
    /// n, as the paper's square-root rate for the curves says). Bounds: r < 0.6 (an algebraic
    /// rate n⁻ᵖ would show a factor creeping towards 1) and a straight law (max log-residual
    /// < 2, i.e. within e² of C rⁿ).
    #[test]
    fn n_refinement_decreases_geometrically() {
        let (kepler, q0, p0, exact) = kepler_reference();
        let problem = Problem::new(&kepler, 0.0, &q0, &p0, 20.0).unwrap();
        let ns: Vec<usize> = (6..=20).step_by(2).collect();
        let points = n_refinement(
            |n| GalerkinIntegrator::spectral(n, 1.0),
            &ns,
            &problem,
            |t| exact.position(t),
            8,
        )
        .unwrap();
        for p in &points {
            println!(
                "n = {:2}: map {:.3e}, curve {:.3e}, {} evaluations",
                p.n, p.map_error, p.error, p.gradient_evaluations
            );
            assert!(p.gradient_evaluations > 0 && p.steps == 20);
        }
        for w in points.windows(2) {
            if w[1].map_error > ROUND_OFF_FLOOR {
                assert!(w[1].map_error < w[0].map_error, "{w:?}");
                assert!(w[1].error < w[0].error, "{w:?}");
            }
        }
        let map = fitted_rate(&points, RefineBy::N, ErrorMeasure::Map).unwrap();
        let curve = fitted_rate(&points, RefineBy::N, ErrorMeasure::Curve).unwrap();
        println!("map {map:?}\ncurve {curve:?}");
        assert!(map.rate < 0.6 && curve.rate < 0.6, "{map:?} {curve:?}");
        assert!(map.rho().is_some_and(|rho| rho > 1.0 / 0.6));
        assert!(map.max_residual < 2.0 && curve.max_residual < 2.0);
    }

    /// Points at the round-off floor or non-finite are ignored by the fit, and reported.
    #[test]
    fn the_fit_ignores_the_floor_and_diverged_runs() {
        let point = |n: usize, error: f64| RefinementPoint {
            n,
            h: 1.0,
            steps: 1,
            error,
            map_error: error,
            gradient_evaluations: 0,
            newton_iterations: 0,
        };
        // error = 10 · 0.5ⁿ exactly, then the floor, then a diverged run.
        let mut points: Vec<RefinementPoint> = (2..8)
            .map(|n| point(n, 10.0 * 0.5f64.powi(n as i32)))
            .collect();
        points.push(point(40, 3e-15));
        points.push(point(42, f64::NAN));
        points.push(point(44, f64::INFINITY));
        let fit = fitted_rate(&points, RefineBy::N, ErrorMeasure::Curve).unwrap();
        assert_eq!((fit.used, fit.ignored), (6, 3));
        assert!((fit.rate - 0.5).abs() < 1e-14 && (fit.intercept - 10f64.ln()).abs() < 1e-13);
        assert!((fit.rho().unwrap() - 2.0).abs() < 1e-13 && fit.max_residual < 1e-13);
        // Algebraic: error = 3 h⁴.
        let hs = [0.1, 0.05, 0.025];
        let pts: Vec<RefinementPoint> = hs
            .iter()
            .map(|&h| RefinementPoint {
                h,
                ..point(4, 3.0 * h.powi(4))
            })
            .collect();
        let fit = fitted_rate(&pts, RefineBy::H, ErrorMeasure::Map).unwrap();
        assert!((fit.rate - 4.0).abs() < 1e-12 && (fit.intercept - 3f64.ln()).abs() < 1e-11);
        // Too few usable points, or no spread in x: typed errors, no panic.
        assert!(matches!(
            fitted_rate(&points[6..], RefineBy::N, ErrorMeasure::Map),
            Err(GviError::InvalidInput { .. })
        ));
        assert!(matches!(
            fitted_rate(
                &[point(3, 1e-3), point(3, 1e-4)],
                RefineBy::N,
                ErrorMeasure::Map
            ),
            Err(GviError::InvalidInput { .. })
        ));
        assert!(fitted_rate(&[], RefineBy::H, ErrorMeasure::Map).is_err());
        assert!(fitted_rate_above(&pts, RefineBy::H, ErrorMeasure::Map, f64::NAN).is_err());
        let bad_h = [RefinementPoint { h: 0.0, ..pts[0] }, pts[1]];
        assert!(fitted_rate(&bad_h, RefineBy::H, ErrorMeasure::Map).is_err());
    }

    /// User input that cannot make a study is refused with a typed error, never a panic.
    #[test]
    fn invalid_studies_are_typed_errors() {
        let (kepler, q0, p0, exact) = kepler_reference();
        let reference = |t: f64| exact.position(t);
        let family = |n: usize| GalerkinIntegrator::spectral(n, 0.5);
        let input =
            |r: Result<Vec<RefinementPoint>>| matches!(r, Err(GviError::InvalidInput { .. }));
        for horizon in [f64::NAN, f64::INFINITY, 0.0, -1.0] {
            assert!(matches!(
                Problem::new(&kepler, 0.0, &q0, &p0, horizon),
                Err(GviError::InvalidInput { .. })
            ));
        }
        assert!(matches!(
            Problem::new(&kepler, 0.0, &q0[..1], &p0, 1.0),
            Err(GviError::DimensionMismatch { .. })
        ));
        assert!(matches!(
            Problem::new(&kepler, f64::NAN, &q0, &p0, 1.0),
            Err(GviError::NonFinite { .. })
        ));
        assert!(matches!(
            Problem::new(&kepler, 0.0, &q0, &[0.0, f64::INFINITY], 1.0),
            Err(GviError::NonFinite { .. })
        ));
        let problem = Problem::new(&kepler, 0.0, &q0, &p0, 2.0).unwrap();
        assert!(input(n_refinement(family, &[], &problem, reference, 4)));
        assert!(input(h_refinement(
            |h| GalerkinIntegrator::spectral(6, h),
            &[],
            &problem,
            reference,
            4
        )));
        // 2.0 is not a whole number of steps of 0.3 …
        assert!(input(h_refinement(
            |h| GalerkinIntegrator::spectral(6, h),
            &[0.5, 0.3],
            &problem,
            reference,
            4
        )));
        // … nor of an integrator's own h = 0.75 …
        assert!(input(n_refinement(
            |n| GalerkinIntegrator::spectral(n, 0.75),
            &[6],
            &problem,
            reference,
            4
        )));
        // … and 2 = 4 × 0.5 is.
        assert_eq!(steps_for_horizon(2.0, 0.5).unwrap(), 4);
        assert!(steps_for_horizon(1e300, 1e-300).is_err());
        assert!(matches!(
            steps_for_horizon(1.0, -0.5),
            Err(GviError::InvalidStepSize { .. })
        ));
        // Zero samples per step; a reference of the wrong length or non-finite.
        assert!(input(n_refinement(family, &[6], &problem, reference, 0)));
        assert!(matches!(
            n_refinement(family, &[6], &problem, |_| vec![0.0; 3], 4),
            Err(GviError::DimensionMismatch { .. })
        ));
        assert!(matches!(
            n_refinement(family, &[6], &problem, |_| vec![0.0, f64::NAN], 4),
            Err(GviError::NonFinite { .. })
        ));
        // The family's own error is passed through (n = 1 is not a basis).
        assert!(matches!(
            n_refinement(family, &[1], &problem, reference, 4),
            Err(GviError::InvalidBasisSize { .. })
        ));
        let empty: [&dyn DynIntegrator<Kepler>; 0] = [];
        assert!(matches!(
            compare_bases(&empty, &problem, 4),
            Err(GviError::InvalidInput { .. })
        ));
        assert!(compare_trajectories(&[], &[0.0]).is_err());
    }

    /// Chebyshev, Legendre and Hermite with the same n and quadrature are the same method
    /// (docs/DESIGN.md §2): their dense output agrees to round-off even at different types,
    /// compared through `DynIntegrator`. Fourier spans another space: its difference is the
    /// methods' error (negative control). Measured (Kepler, n = 12, 24 Gauss points, h = 0.5,
    /// T = 10, 161 sample times): polynomial bases within 3.3e-15 in position and 1.3e-13 in
    /// velocity (bounds 1e-13 and 1e-11); Fourier differs by 7.5e-4 in position.
    #[test]
    fn polynomial_bases_agree_and_fourier_differs() {
        let (kepler, q0, p0, _) = kepler_reference();
        let problem = Problem::new(&kepler, 0.0, &q0, &p0, 10.0).unwrap();
        let quad = || GaussLegendre::new(24).unwrap();
        let cheb =
            GalerkinIntegrator::new(ChebyshevLagrange::new(12).unwrap(), quad(), 0.5).unwrap();
        let leg = GalerkinIntegrator::new(Legendre::new(12).unwrap(), quad(), 0.5).unwrap();
        let her = GalerkinIntegrator::new(Hermite::new(12).unwrap(), quad(), 0.5).unwrap();
        let same = compare_bases(&[&cheb, &leg, &her], &problem, 8).unwrap();
        println!("{same:?}");
        assert_eq!(same.labels[1], "legendre n=12 gauss-legendre(24) h=0.5");
        assert_eq!(same.samples, 20 * 8 + 1);
        assert!(
            same.max_position < 1e-13 && same.max_velocity < 1e-11,
            "{same:?}"
        );
        assert_eq!(same.position[0][0], 0.0);
        assert_eq!(same.position[1][2], same.position[2][1]);
        let fourier = GalerkinIntegrator::new(Fourier::new(12).unwrap(), quad(), 0.5).unwrap();
        let other = compare_bases(&[&cheb, &fourier], &problem, 8).unwrap();
        println!("{other:?}");
        assert!(other.max_position > 1e-5, "{other:?}");
    }
}
