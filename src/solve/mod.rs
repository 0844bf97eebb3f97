//! One entry point from a problem and a method to a solution: [`solve`].
//!
//! A problem is a [`System`] with its [`InitialState`]; the method is a [`MethodSpec`]. Whether
//! the method names a fixed n ([`GalerkinIntegrator::integrate`]) or a tolerance that chooses
//! n per step ([`integrate_adaptive`], with [`choose_step`] when `auto_h` asks for h to be
//! chosen too) is the method's business: [`solve`] reads it and returns one [`Solution`]
//! either way, whose [`adaptive`](Solution::adaptive) report and
//! [`step_choice`](Solution::step_choice) say what the tolerance-driven parts did. Callers that
//! tabulate a run key what they print off the solution, never off the method's fields.
//!
//! Two relatives cover what [`solve`] cannot:
//!
//! * [`solve_streaming`] shows each state to a visitor as its step completes and keeps no
//!   history (memory flat in the number of steps). It runs fixed n only: a tolerance-driven
//!   run keeps its whole trajectory, and is refused with [`GviError::Unsupported`].
//! * [`solve_rigid_body`] runs the Lie group integrator on SO(3) ([`crate::lie`]) for a
//!   [`RigidBody`], returning a [`RigidBodySolution`].
//!
//! **Why rigid bodies have their own function** rather than one `solve` generic over a
//! problem trait (or a `Solution` enum): the two kinds share nothing a caller could use
//! without asking which kind it has. A Lie run's states are (R, μ) on T*SO(3), not (q, p)
//! with Galerkin coefficients per step ([`LieTrajectory`] against [`Trajectory`]); it has no
//! tolerance-driven mode, no dense output and keeps no partial run on a Newton failure
//! (so it returns a plain [`Result`]). A trait would give every caller an associated
//! solution type to match on by kind, and an enum the same match at run time; a caller
//! already knows which kind of problem it holds, so two functions with their own types say
//! it in the signature instead.
//!
//! **Method fields a Euclidean solve ignores**: `retraction` (it chooses the chart of the Lie
//! group integrator; one method table can then serve both kinds of scene, as the lab's
//! `--retraction` override does), and with `tol` also `n` and `quad_points` (each rung of the
//! ladder uses its own n at the quadrature's default points).
//!
//! **Failures.** Invalid input is a [`SolveFailure`] without `partial`. A step whose solver
//! fails ends the run with [`SolveFailure::partial`] holding everything computed before it:
//! the trajectory up to the failing step (and, for a tolerance-driven run, its step choice and
//! a report with the force evaluations of the kept steps; the driver returns no per-step
//! indicators or estimates for a failed run).
//!
//! [`GalerkinIntegrator::integrate`]: crate::integrator::GalerkinIntegrator::integrate
//! [`integrate_adaptive`]: crate::adaptive::integrate_adaptive

use crate::adaptive::driver::integrate_adaptive_until;
use crate::adaptive::{ErrorControl, StepChoice, choose_step};
use crate::basis::AnyBasis;
use crate::curve::GalerkinCurveRef;
use crate::error::{GviError, Result};
use crate::integrator::{IntegrationFailure, MAX_STEPS};
use crate::lagrangian::Lagrangian;
use crate::lie::{LieGalerkin, LieTrajectory, Retraction, RigidBody};
use crate::method::{InitialState, MethodSpec};
use crate::stats::StepStats;
use crate::systems::System;
use crate::trajectory::Trajectory;
use serde::Serialize;

/// The result of [`solve`]: the trajectory and, for a tolerance-driven method, what the
/// controller did.
#[derive(Debug, Clone, Serialize)]
pub struct Solution {
    /// The states, Galerkin coefficients and per-step cost (`step_n` holds n per step when
    /// it was chosen per step; `h` is the step actually used, which `auto_h` chooses).
    pub trajectory: Trajectory,
    /// The tolerance-driven run's report; `None` for a fixed-n method.
    pub adaptive: Option<AdaptiveReport>,
    /// The step size chosen from the tolerance (`auto_h`), with its pilot runs; `None`
    /// otherwise.
    pub step_choice: Option<StepChoice>,
}

/// What a tolerance-driven run reports besides its trajectory: the fields of
/// [`AdaptiveRun`](crate::adaptive::AdaptiveRun) other than the trajectory, and the
/// tolerance asked for.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AdaptiveReport {
    /// The requested tolerance on the max position error.
    pub tol: f64,
    /// The error control used.
    pub control: ErrorControl,
    /// The indicator of every accepted step (of the rung whose solution was kept).
    pub indicators: Vec<f64>,
    /// The embedded estimate of every step checked at the next rung (`None`: not checked).
    pub estimates: Vec<Option<f64>>,
    /// Steps solved at two rungs (embedded checks).
    pub checks: usize,
    /// The per-step tolerance used ([`AdaptiveRun::local_tol`]).
    ///
    /// [`AdaptiveRun::local_tol`]: crate::adaptive::AdaptiveRun::local_tol
    pub local_tol: f64,
    /// Steps (and attempts) rejected and redone at a larger n.
    pub rejected: usize,
    /// Total force evaluations, including rejected attempts (excluding the pilots of
    /// [`Solution::step_choice`]).
    pub gradient_evaluations: usize,
    /// Warnings: steps where the tolerance could not be met even at the largest n (kept as
    /// best effort), or a tolerance below the round-off floor.
    pub warnings: Vec<String>,
}

impl AdaptiveReport {
    /// Split a tolerance-driven run into its trajectory and its report.
    fn split(tol: f64, run: crate::adaptive::AdaptiveRun) -> (Trajectory, Self) {
        let report = AdaptiveReport {
            tol,
            control: run.control,
            indicators: run.indicators,
            estimates: run.estimates,
            checks: run.checks,
            local_tol: run.local_tol,
            rejected: run.rejected,
            gradient_evaluations: run.gradient_evaluations,
            warnings: run.warnings,
        };
        (run.trajectory, report)
    }

    /// The report of a failed run, of which only the trajectory of the kept steps survives:
    /// their force evaluations, no indicators, estimates or warnings.
    fn of_partial(tol: f64, control: ErrorControl, local_tol: f64, kept: &Trajectory) -> Self {
        AdaptiveReport {
            tol,
            control,
            indicators: Vec::new(),
            estimates: Vec::new(),
            checks: 0,
            local_tol,
            rejected: 0,
            gradient_evaluations: kept.gradient_evaluations(),
            warnings: Vec::new(),
        }
    }
}

impl Solution {
    /// A fixed-n solution.
    fn fixed(trajectory: Trajectory) -> Self {
        Solution {
            trajectory,
            adaptive: None,
            step_choice: None,
        }
    }

    /// Force (first-derivative) evaluations of the run: for a tolerance-driven run
    /// including rejected attempts and embedded checks (not the pilots of `auto_h`), else
    /// the trajectory's ([`Trajectory::gradient_evaluations`]).
    pub fn gradient_evaluations(&self) -> usize {
        match &self.adaptive {
            Some(a) => a.gradient_evaluations,
            None => self.trajectory.gradient_evaluations(),
        }
    }

    /// The run's warnings (a tolerance not met at the largest n); empty for fixed n.
    pub fn warnings(&self) -> &[String] {
        self.adaptive.as_ref().map_or(&[], |a| &a.warnings)
    }
}

/// A failed [`solve`] (or [`solve_streaming`]): the error and what was computed before it.
#[derive(Debug)]
pub struct SolveFailure<T = Solution> {
    /// What went wrong.
    pub error: GviError,
    /// The run up to the step that failed; `None` when the input was refused before any step.
    pub partial: Option<Box<T>>,
}

impl<T> From<GviError> for SolveFailure<T> {
    fn from(error: GviError) -> Self {
        SolveFailure {
            error,
            partial: None,
        }
    }
}

impl<T> From<SolveFailure<T>> for GviError {
    fn from(f: SolveFailure<T>) -> Self {
        f.error
    }
}

impl std::fmt::Display for SolveFailure<Solution> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.error)?;
        if let Some(s) = &self.partial {
            write!(f, " ({} steps completed before it)", s.trajectory.steps())?;
        }
        Ok(())
    }
}

impl std::error::Error for SolveFailure<Solution> {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.error)
    }
}

/// Integrate `system` from `initial` with `method`: fixed n, or with `tol` n chosen per step
/// (and with `auto_h` also h, for the horizon h · steps). See the [module docs](self).
///
/// The fixed-n solution is [`GalerkinIntegrator::integrate`]'s trajectory of
/// [`MethodSpec::integrator`], the tolerance-driven one [`integrate_adaptive`]'s with
/// [`MethodSpec::adaptive_options`] (after [`choose_step`] for `auto_h`), bit for bit.
///
/// [`GalerkinIntegrator::integrate`]: crate::integrator::GalerkinIntegrator::integrate
/// [`integrate_adaptive`]: crate::adaptive::integrate_adaptive
///
/// Errors: [`MethodSpec::validate`] (`auto_h` without `tol`), the integrator's parameters,
/// the initial state's lengths and finiteness, the step count, [`choose_step`]'s (no time
/// scale, no candidate meets its budget) — all without `partial`; a step's solver failure
/// with `partial` holding the run before it.
///
/// ```
/// use galerkin_vi::method::{InitialState, MethodSpec};
/// use galerkin_vi::solve::solve;
/// use galerkin_vi::systems::Kepler;
///
/// let kepler = Kepler::new(1.0)?;
/// let (q, p) = Kepler::paper_initial_state();
/// let initial = InitialState { t0: 0.0, q: q.to_vec(), p: p.to_vec() };
///
/// // Fixed n = 24, h = 1, 20 steps.
/// let mut method = MethodSpec::spectral(24, 1.0, 20);
/// let fixed = solve(&kepler, &initial, &method)?;
/// assert_eq!(fixed.trajectory.steps(), 20);
/// assert!(fixed.adaptive.is_none());
///
/// // The same horizon with n chosen per step for a tolerance of 1e-8: the same call.
/// method.tol = Some(1e-8);
/// let tolerance_driven = solve(&kepler, &initial, &method)?;
/// let report = tolerance_driven.adaptive.as_ref().expect("n was chosen per step");
/// assert_eq!(report.indicators.len(), 20);
/// assert_eq!(tolerance_driven.trajectory.step_n.len(), 20);
///
/// // Choosing h needs the tolerance: refused, before any step.
/// method.tol = None;
/// method.auto_h = true;
/// let refused = solve(&kepler, &initial, &method).unwrap_err();
/// assert!(refused.partial.is_none());
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
pub fn solve<S: System>(
    system: &S,
    initial: &InitialState,
    method: &MethodSpec,
) -> std::result::Result<Solution, SolveFailure> {
    solve_with(system, initial, method, None)
}

/// [`solve`], asking `stop` before every step whether to stop there (a caller's Ctrl-C, a
/// deadline): a `true` ends the run with [`GviError::Interrupted`] and
/// [`SolveFailure::partial`] holding the steps before it. `stop` is called once per step, so
/// it should be cheap (an atomic load); the pilot runs of `auto_h` are not interrupted. With a
/// `stop` that never says yes the solution is [`solve`]'s bit for bit.
///
/// ```
/// use galerkin_vi::GviError;
/// use galerkin_vi::method::{InitialState, MethodSpec};
/// use galerkin_vi::solve::solve_until;
/// use galerkin_vi::systems::HarmonicOscillator;
/// use std::cell::Cell;
///
/// let oscillator = HarmonicOscillator::new(1.0, 1.0)?;
/// let initial = InitialState { t0: 0.0, q: vec![1.0], p: vec![0.0] };
/// let asked = Cell::new(0);
/// let stop = || { asked.set(asked.get() + 1); asked.get() > 5 };
/// let failure = solve_until(&oscillator, &initial, &MethodSpec::spectral(8, 0.5, 100), &stop)
///     .unwrap_err();
/// assert!(matches!(failure.error, GviError::Interrupted { step: 5, .. }));
/// assert_eq!(failure.partial.map(|s| s.trajectory.steps()), Some(5));
/// # Ok::<(), GviError>(())
/// ```
pub fn solve_until<S: System>(
    system: &S,
    initial: &InitialState,
    method: &MethodSpec,
    stop: &dyn Fn() -> bool,
) -> std::result::Result<Solution, SolveFailure> {
    solve_with(system, initial, method, Some(stop))
}

/// [`solve`] and [`solve_until`]: the fixed-n run is [`GalerkinIntegrator::integrate`]'s step
/// loop (which asks `stop`, or a `stop` that never says yes, before every step).
///
/// [`GalerkinIntegrator::integrate`]: crate::integrator::GalerkinIntegrator::integrate
fn solve_with<S: System>(
    system: &S,
    initial: &InitialState,
    method: &MethodSpec,
    stop: Option<&dyn Fn() -> bool>,
) -> std::result::Result<Solution, SolveFailure> {
    method.validate()?;
    refuse_time_transform(method)?;
    let (t0, q0, p0) = (initial.t0, &initial.q[..], &initial.p[..]);
    let Some(mut opts) = method.adaptive_options() else {
        let gvi = method.integrator()?;
        let never = || false;
        let run = gvi.integrate_until(system, t0, q0, p0, method.steps, stop.unwrap_or(&never));
        return run
            .map(Solution::fixed)
            .map_err(|f: IntegrationFailure| SolveFailure {
                error: f.error,
                partial: f.partial.map(|t| Box::new(Solution::fixed(*t))),
            });
    };
    let mut steps = method.steps;
    let step_choice = if method.auto_h {
        let horizon = method.h * method.steps as f64;
        let choice = choose_step(system, &opts, t0, q0, p0, horizon)?;
        (opts.h, steps) = (choice.h, choice.steps);
        Some(choice)
    } else {
        None
    };
    let never = || false;
    match integrate_adaptive_until(system, &opts, t0, q0, p0, steps, stop.unwrap_or(&never)) {
        Ok(run) => {
            let (trajectory, report) = AdaptiveReport::split(opts.tol, run);
            Ok(Solution {
                trajectory,
                adaptive: Some(report),
                step_choice,
            })
        }
        Err(f) => Err(SolveFailure {
            error: f.error,
            partial: f.partial.map(|t| {
                let report =
                    AdaptiveReport::of_partial(opts.tol, opts.control, opts.step_budget(steps), &t);
                Box::new(Solution {
                    trajectory: *t,
                    adaptive: Some(report),
                    step_choice,
                })
            }),
        }),
    }
}

/// A method with a time transformation runs in fictitious time with physical steps that
/// vary: its states are not a [`Trajectory`] on the grid t₀ + k h.
fn refuse_time_transform(method: &MethodSpec) -> Result<()> {
    if method.time_transform.is_some() {
        return Err(GviError::Unsupported(
            "a time-transformed method runs through \
             galerkin_vi::time_transform::integrate_time_transformed (gvi run), not solve"
                .into(),
        ));
    }
    Ok(())
}

/// One state of a streamed run, shown to the visitor of [`solve_streaming`].
#[derive(Debug, Clone, Copy)]
pub struct StreamStep<'a> {
    /// Step index k of the state (0: the initial state).
    pub step: usize,
    /// Its time t₀ + k h.
    pub t: f64,
    /// Position q_k.
    pub q: &'a [f64],
    /// Momentum p_k.
    pub p: &'a [f64],
    /// The Galerkin curve of the step that led here, from t_{k−1} to t_k (`None` for the
    /// initial state); evaluate it in [`basis`](Self::basis).
    pub curve: Option<GalerkinCurveRef<'a>>,
    /// The cost of that step (`None` for the initial state).
    pub stats: Option<StepStats>,
    /// The basis of the curves.
    pub basis: &'a AnyBasis,
}

/// The end of a [`solve_streaming`] run.
#[derive(Debug)]
pub struct Streamed<B> {
    /// Steps completed (each shown to the visitor).
    pub steps: usize,
    /// What the visitor stopped the run with, if it did.
    pub stopped: Option<B>,
}

impl<B> std::fmt::Display for SolveFailure<Streamed<B>> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.error)?;
        if let Some(s) = &self.partial {
            write!(f, " ({} steps completed before it)", s.steps)?;
        }
        Ok(())
    }
}

impl<B: std::fmt::Debug> std::error::Error for SolveFailure<Streamed<B>> {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.error)
    }
}

/// Integrate like [`solve`] at fixed n, showing `visit` the initial state and then each state
/// as its step completes, with the step's Galerkin curve and cost; nothing is kept, so memory
/// does not grow with the number of steps. The states are those of
/// [`GalerkinIntegrator::integrate`] bit for bit (both are driven by a
/// [`Stepper`](crate::integrator::Stepper)).
///
/// [`GalerkinIntegrator::integrate`]: crate::integrator::GalerkinIntegrator::integrate
///
/// `visit` returning `Err(b)` stops the run: the result is then `Ok` with
/// [`Streamed::stopped`] = `Some(b)` (the state it was shown counts as completed).
///
/// Errors: [`MethodSpec::validate`]; a tolerance-driven method ([`GviError::Unsupported`]:
/// it keeps its whole trajectory, use [`solve`]); the integrator's parameters, the initial
/// state, the step count — all before any visit and without `partial`; a step's solver
/// failure with `partial` counting the steps before it (each was shown to `visit`).
///
/// ```
/// use galerkin_vi::method::{InitialState, MethodSpec};
/// use galerkin_vi::solve::solve_streaming;
/// use galerkin_vi::systems::Kepler;
///
/// let kepler = Kepler::new(1.0)?;
/// let (q, p) = Kepler::paper_initial_state();
/// let initial = InitialState { t0: 0.0, q: q.to_vec(), p: p.to_vec() };
/// let method = MethodSpec::spectral(16, 0.5, 40);
/// let mut evaluations = 0;
/// let end = solve_streaming(&kepler, &initial, &method, |s| {
///     evaluations += s.stats.map_or(0, |st| st.gradient_evaluations);
///     Ok::<(), ()>(())
/// })?;
/// assert_eq!((end.steps, end.stopped), (40, None));
/// assert!(evaluations > 0);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
pub fn solve_streaming<L, B, F>(
    lagrangian: &L,
    initial: &InitialState,
    method: &MethodSpec,
    mut visit: F,
) -> std::result::Result<Streamed<B>, SolveFailure<Streamed<B>>>
where
    L: Lagrangian,
    F: FnMut(StreamStep<'_>) -> std::result::Result<(), B>,
{
    method.validate()?;
    refuse_time_transform(method)?;
    if method.chooses_n() {
        return Err(GviError::Unsupported(
            "a tolerance-driven run is not streamed (it keeps the whole trajectory)".into(),
        )
        .into());
    }
    let steps = method.steps;
    if steps == 0 || steps > MAX_STEPS {
        return Err(GviError::InvalidStepCount {
            steps,
            reason: format!("need 1 ≤ steps ≤ {MAX_STEPS}"),
        }
        .into());
    }
    let gvi = method.integrator()?;
    let mut stepper = gvi.stepper(lagrangian, initial.t0, &initial.q, &initial.p)?;
    let basis = gvi.basis();
    let start = StreamStep {
        step: 0,
        t: stepper.time(),
        q: stepper.position(),
        p: stepper.momentum(),
        curve: None,
        stats: None,
        basis,
    };
    if let Err(b) = visit(start) {
        return Ok(Streamed {
            steps: 0,
            stopped: Some(b),
        });
    }
    for _ in 0..steps {
        let stats = match stepper.step() {
            Ok(stats) => stats,
            Err(error) => {
                return Err(SolveFailure {
                    error,
                    partial: Some(Box::new(Streamed {
                        steps: stepper.steps(),
                        stopped: None,
                    })),
                });
            }
        };
        let state = StreamStep {
            step: stepper.steps(),
            t: stepper.time(),
            q: stepper.position(),
            p: stepper.momentum(),
            curve: Some(stepper.curve()),
            stats: Some(stats),
            basis,
        };
        if let Err(b) = visit(state) {
            return Ok(Streamed {
                steps: stepper.steps(),
                stopped: Some(b),
            });
        }
    }
    Ok(Streamed {
        steps,
        stopped: None,
    })
}

/// The result of [`solve_rigid_body`]: the trajectory on SO(3) and the integrator that made it
/// (for its description and further steps, e.g. a symplecticity defect).
#[derive(Debug, Clone)]
pub struct RigidBodySolution {
    /// Orientations and body momenta at the step ends, Newton iterations per step.
    pub trajectory: LieTrajectory,
    /// The Lie group integrator of the method ([`MethodSpec::lie_integrator`]).
    pub integrator: LieGalerkin,
}

/// The initial state of a rigid body from an [`InitialState`]: `q` is the rotation vector of
/// R₀ = exp(q̂) (always the exponential, whatever the method's retraction) and `p` the body
/// momentum μ₀.
///
/// Errors: `q` or `p` not of length 3.
pub fn rigid_body_initial_state(
    initial: &InitialState,
) -> Result<(crate::lie::so3::Mat3<f64>, [f64; 3])> {
    crate::error::ensure_len("initial q (rotation vector)", 3, initial.q.len())?;
    crate::error::ensure_len("initial p (body momentum)", 3, initial.p.len())?;
    let (q, p) = (&initial.q, &initial.p);
    Ok((Retraction::Exp.map(&[q[0], q[1], q[2]]), [p[0], p[1], p[2]]))
}

/// Integrate a rigid body on SO(3) with the Lie group integrator the method names
/// ([`MethodSpec::lie_integrator`]: basis, n, quadrature, points, h, retraction) from
/// `initial` ([`rigid_body_initial_state`]). Why this is not [`solve`]: see the
/// [module docs](self).
///
/// Errors: [`MethodSpec::validate`]; a tolerance-driven method ([`GviError::Unsupported`]:
/// the Lie group integrator has no tolerance-driven mode); the integrator's parameters; the
/// initial state; a step's Newton failure (no partial run is kept).
///
/// ```
/// use galerkin_vi::lie::FreeRigidBody;
/// use galerkin_vi::method::{InitialState, MethodSpec};
/// use galerkin_vi::solve::solve_rigid_body;
///
/// let body = FreeRigidBody::new([1.0, 2.0, 3.0])?;
/// let initial = InitialState { t0: 0.0, q: vec![0.0; 3], p: vec![0.1, 1.0, 0.2] };
/// let solution = solve_rigid_body(&body, &initial, &MethodSpec::spectral(6, 0.25, 8))?;
/// assert_eq!(solution.trajectory.states.len(), 9);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
pub fn solve_rigid_body<R: RigidBody>(
    body: &R,
    initial: &InitialState,
    method: &MethodSpec,
) -> Result<RigidBodySolution> {
    method.require_fixed_n("the Lie group integrator (rigid bodies)")?;
    let integrator = method.lie_integrator()?;
    let (r0, mu0) = rigid_body_initial_state(initial)?;
    let trajectory = integrator.integrate(body, initial.t0, &r0, &mu0, method.steps)?;
    Ok(RigidBodySolution {
        trajectory,
        integrator,
    })
}

#[cfg(test)]
mod tests;
