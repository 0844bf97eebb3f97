//! The one Newton driver of the crate: every nonlinear solve — the Galerkin step's stage
//! equations (nodal and velocity form), periodic orbits, Lie group steps and the Gauss
//! collocation baseline — is a [`NewtonIteration`] run by [`drive`].
//!
//! As in argmin and OrdinaryDiffEq.jl's nonlinear solvers, the problem supplies one
//! iteration (its residual, its linear solve and update, and how it adapts its linear solve),
//! and the driver owns the loop and decides termination, once, by one policy
//! ([`Termination`]) whose values each solver chooses:
//!
//! - **converged** when the correction is below `tolerance` relative to the unknowns' scale;
//!   or, for quadratically converging solves, when the contraction estimate θ = |δ_k|/|δ_{k−1}|
//!   bounds the remaining error, θ/(1 − θ)|δ| ≤ tolerance (θ below `estimate_below`); or at
//!   the round-off floor, when the correction no longer shrinks (θ above `floor_theta`, or it
//!   grew) but is below `floor` relative to the scale; or when the residual itself is below
//!   `residual_tolerance`;
//! - **failed** on a non-finite residual or correction, at the iteration limit, or when the
//!   problem's own divergence test ([`Divergence`]) fires;
//! - otherwise the problem is told the [`Progress`] and may change its linear solve
//!   ([`Adapt`]): refactor, refreeze, escalate.
//!
//! A problem's linear solve may change within one solve (the frozen Hessian of the Kronecker
//! solver converges linearly, the dense exact matrix quadratically), so each correction names
//! the [`Termination`] that applies to it.

pub use crate::stats::StepFailure as NewtonFailure;

/// The size of a correction just applied and of the unknowns it was applied to (max-norms),
/// for convergence tests relative to the scale of the unknowns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Correction {
    /// max |δ|.
    pub size: f64,
    /// The scale of the unknowns after the update (never 0: at least the smallest positive
    /// normal).
    pub scale: f64,
}

/// When a Newton iteration stops: the one termination policy, with the values a solver
/// chooses for its linear solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Termination {
    /// Iteration limit.
    pub max_iterations: usize,
    /// Converged when |δ| ≤ `tolerance` · scale.
    pub tolerance: f64,
    /// Converged when θ < `estimate_below` and θ/(1 − θ)·|δ| ≤ `tolerance` · scale (the
    /// contraction estimate of the remaining error); `None` for iterations whose estimate is
    /// unreliable near round-off (the linearly converging frozen-Hessian iterations, whose
    /// early stop leaves a one-signed remainder that drifts over long runs).
    pub estimate_below: Option<f64>,
    /// Converged at the round-off floor when the correction stopped shrinking (θ >
    /// `floor_theta`, or it grew) while |δ| ≤ `floor` · scale.
    pub floor: f64,
    /// See [`floor`](Self::floor).
    pub floor_theta: f64,
    /// Converged as soon as the residual is at most this (before any correction).
    pub residual_tolerance: Option<f64>,
    /// Fail when the iteration diverges.
    pub divergence: Option<Divergence>,
}

impl Termination {
    /// Corrections-only tests: |δ| ≤ `tolerance` · scale, the estimate below
    /// `estimate_below`, the floor at `floor` for θ > `floor_theta`; no residual test, no
    /// divergence test.
    pub fn new(
        max_iterations: usize,
        tolerance: f64,
        estimate_below: Option<f64>,
        floor: f64,
        floor_theta: f64,
    ) -> Self {
        Termination {
            max_iterations,
            tolerance,
            estimate_below,
            floor,
            floor_theta,
            residual_tolerance: None,
            divergence: None,
        }
    }

    /// Whether a correction of `progress` ends the iteration, and by which test.
    pub fn converged(&self, progress: &Progress) -> Option<ConvergedBy> {
        let (delta, scale, theta) = (progress.delta, progress.scale, progress.theta);
        let tol = self.tolerance * scale;
        if delta == 0.0 || delta <= tol {
            return Some(ConvergedBy::Tolerance);
        }
        if let Some(below) = self.estimate_below
            && theta < below
            && theta / (1.0 - theta) * delta <= tol
        {
            return Some(ConvergedBy::Estimate);
        }
        let stopped = progress.growing || (theta.is_finite() && theta > self.floor_theta);
        if stopped && delta <= self.floor * scale {
            return Some(ConvergedBy::Floor);
        }
        None
    }
}

/// A divergence test on the corrections: fail once, after `after` iterations, a correction
/// exceeds `growth` times the previous one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Divergence {
    /// Iterations before the test applies.
    pub after: usize,
    /// Growth factor of the correction that counts as divergence.
    pub growth: f64,
}

/// Which test ended a converged iteration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConvergedBy {
    /// The residual was below `residual_tolerance` (no correction taken).
    Residual,
    /// The correction was below the tolerance.
    Tolerance,
    /// The contraction estimate bounded the remaining error.
    Estimate,
    /// The correction stopped shrinking at the round-off floor.
    Floor,
}

/// The outcome of a Newton solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NewtonStatus {
    /// Converged, by the test named.
    Converged(ConvergedBy),
    /// Stopped without converging; the [`NewtonFailure`] says why.
    Failed,
}

/// One correction's progress, as the driver measured it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Corrections taken so far (this one included).
    pub iteration: usize,
    /// max |δ| of this correction.
    pub delta: f64,
    /// The unknowns' scale after it.
    pub scale: f64,
    /// The contraction estimate |δ_k| / |δ_{k−1}| (∞ on a new linear solve's first one).
    pub theta: f64,
    /// The correction is larger than the previous one.
    pub growing: bool,
}

/// What a problem does after a correction that did not converge.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Adapt {
    /// Keep iterating; θ continues from this correction.
    Continue,
    /// Keep iterating with a new linear solve; θ starts afresh.
    Restart,
    /// Stop: the iteration stalls and the problem has no better linear solve (its caller may
    /// hand the problem to another solver).
    GiveUp,
}

/// One Newton iteration of a problem: the pieces [`drive`] runs.
pub trait NewtonIteration {
    /// Evaluate the residual F at the current iterate (the first call, `iteration` = 0, may
    /// reuse one already known) and return max |F| (∞ or NaN if not finite).
    fn residual(&mut self, iteration: usize) -> f64;

    /// Solve for the correction δ (−F in the problem's linear solve), apply it to the
    /// unknowns, and return its size with the [`Termination`] that applies to this linear
    /// solve.
    ///
    /// Errors: the linear solve failed (a singular matrix).
    fn correct(&mut self, iteration: usize) -> Result<(Correction, Termination), NewtonFailure>;

    /// After a correction that did not converge: how to go on.
    fn adapt(&mut self, progress: &Progress) -> Adapt {
        let _ = progress;
        Adapt::Continue
    }

    /// After convergence: final evaluations at the solution (the residual and what depends on
    /// it).
    ///
    /// Errors: the problem's own checks of the solution.
    fn finish(&mut self, by: ConvergedBy) -> Result<(), NewtonFailure> {
        let _ = by;
        Ok(())
    }
}

/// Run Newton's iteration on `problem` until its [`Termination`] says it converged or failed.
/// Returns the test that ended it and the number of corrections taken.
///
/// `first` is the termination that applies before any correction (its iteration limit and
/// residual tolerance); each correction brings its own.
///
/// Errors: [`NewtonFailure`] with the last residual, the iterations and the reason
/// (non-finite residual or update, iteration limit, divergence, a failed linear solve, or the
/// problem's [`finish`](NewtonIteration::finish)).
pub fn drive<P: NewtonIteration + ?Sized>(
    problem: &mut P,
    first: &Termination,
) -> Result<(ConvergedBy, usize), NewtonFailure> {
    run(problem, first).map_err(|stop| match stop {
        Stop::Driver {
            residual,
            iterations,
            reason,
        } => NewtonFailure {
            residual,
            iterations,
            reason: reason.to_string(),
        },
        Stop::Problem(failure) => failure,
    })
}

/// Whether `problem` converges: [`drive`] for a caller to whom a failure is an outcome, not an
/// error — a fixed-point iteration that hands over to Newton when it stops contracting (the
/// Gauss collocation baseline). The same iteration and termination; only the driver's own
/// failures build no [`NewtonFailure`], so that the hand-over allocates nothing (the
/// baselines' steps are allocation-free: lab/tests/allocation.rs).
pub fn converges<P: NewtonIteration + ?Sized>(problem: &mut P, first: &Termination) -> bool {
    run(problem, first).is_ok()
}

/// Why [`run`] stopped without converging: a test of the driver (its reason static), or the
/// problem's own failure.
enum Stop {
    Driver {
        residual: f64,
        iterations: usize,
        reason: &'static str,
    },
    Problem(NewtonFailure),
}

/// The loop of [`drive`] and [`converges`].
fn run<P: NewtonIteration + ?Sized>(
    problem: &mut P,
    first: &Termination,
) -> Result<(ConvergedBy, usize), Stop> {
    let fail = |residual: f64, iterations: usize, reason: &'static str| Stop::Driver {
        residual,
        iterations,
        reason,
    };
    let mut termination = *first;
    let mut previous = f64::INFINITY;
    let mut it = 0;
    loop {
        let residual = problem.residual(it);
        if !residual.is_finite() {
            return Err(fail(
                residual,
                it,
                "non-finite residual (the iteration diverged)",
            ));
        }
        if termination
            .residual_tolerance
            .is_some_and(|tol| residual <= tol)
        {
            problem
                .finish(ConvergedBy::Residual)
                .map_err(Stop::Problem)?;
            return Ok((ConvergedBy::Residual, it));
        }
        if it >= termination.max_iterations {
            return Err(fail(residual, it, "iteration limit reached"));
        }
        let (correction, applies) = problem.correct(it).map_err(Stop::Problem)?;
        termination = applies;
        it += 1;
        let (delta, scale) = (correction.size, correction.scale);
        if !delta.is_finite() || !scale.is_finite() {
            return Err(fail(f64::INFINITY, it, "non-finite Newton update"));
        }
        let theta = if previous.is_finite() {
            delta / previous
        } else {
            f64::INFINITY
        };
        let progress = Progress {
            iteration: it,
            delta,
            scale,
            theta,
            growing: delta > previous,
        };
        if let Some(by) = termination.converged(&progress) {
            problem.finish(by).map_err(Stop::Problem)?;
            return Ok((by, it));
        }
        if let Some(d) = termination.divergence
            && it > d.after
            && delta > d.growth * previous
        {
            return Err(fail(residual, it, "the iteration diverges"));
        }
        previous = match problem.adapt(&progress) {
            Adapt::Continue => delta,
            Adapt::Restart => f64::INFINITY,
            Adapt::GiveUp => return Err(fail(residual, it, "the iteration stalls")),
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Newton on x² = 2 (scalar): quadratic convergence ends by the tolerance or the estimate
    /// within 6 corrections; the same iteration with a frozen derivative (linear convergence)
    /// needs more and, without the estimate, stops by the tolerance or the floor.
    struct Sqrt2 {
        x: f64,
        f: f64,
        frozen: Option<f64>,
        termination: Termination,
    }

    impl NewtonIteration for Sqrt2 {
        fn residual(&mut self, _: usize) -> f64 {
            self.f = self.x * self.x - 2.0;
            self.f.abs()
        }
        fn correct(&mut self, _: usize) -> Result<(Correction, Termination), NewtonFailure> {
            let slope = self.frozen.unwrap_or(2.0 * self.x);
            let delta = -self.f / slope;
            self.x += delta;
            let c = Correction {
                size: delta.abs(),
                scale: self.x.abs(),
            };
            Ok((c, self.termination))
        }
    }

    #[test]
    fn quadratic_and_linear_iterations_terminate() {
        let quadratic = Termination::new(40, 1e-16, Some(1.0), 1e-10, 0.5);
        let mut p = Sqrt2 {
            x: 1.0,
            f: 0.0,
            frozen: None,
            termination: quadratic,
        };
        let (by, it) = drive(&mut p, &quadratic).unwrap();
        assert!(it <= 6, "{by:?} after {it}");
        assert!((p.x - std::f64::consts::SQRT_2).abs() <= 4e-16);
        let linear = Termination::new(100, 1e-16, None, 1e-13, 0.5);
        let mut p = Sqrt2 {
            x: 1.0,
            f: 0.0,
            frozen: Some(2.6),
            termination: linear,
        };
        let (by, it) = drive(&mut p, &linear).unwrap();
        assert!(it > 6 && by != ConvergedBy::Estimate, "{by:?} after {it}");
        assert!((p.x - std::f64::consts::SQRT_2).abs() <= 1e-15);
    }

    /// Negative control: a slope of the wrong sign diverges; the iteration limit or the
    /// divergence test ends it with a failure, never a silent "converged".
    #[test]
    fn a_diverging_iteration_fails() {
        let mut t = Termination::new(50, 1e-16, Some(1.0), 1e-10, 0.5);
        t.divergence = Some(Divergence {
            after: 3,
            growth: 2.0,
        });
        let mut p = Sqrt2 {
            x: 1.0,
            f: 0.0,
            frozen: Some(-0.5),
            termination: t,
        };
        let err = drive(&mut p, &t).unwrap_err();
        assert!(
            err.reason.contains("diverge") || err.reason.contains("non-finite"),
            "{err:?}"
        );
        // `converges` runs the same iteration without building the failure.
        p.x = 1.0;
        assert!(!converges(&mut p, &t));
    }
}
