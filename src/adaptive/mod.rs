//! Model no more than a scene needs: tolerance-driven choice of n per step.
//!
//!
//! Each step's Galerkin curve carries its own error indicator: the size of its last two
//! Chebyshev coefficients (the decay test of chebfun's "happiness" check;
//! [`GalerkinIntegrator::modal_indicator`](crate::integrator::GalerkinIntegrator::modal_indicator)).
//! [`integrate_adaptive`] chooses n per step from a ladder under one of three
//! [`ErrorControl`]s:
//!
//! * **Embedded** (default): a step is solved at its rung n_i and at the next rung n_{i+1};
//!   e = |q_i − q_{i+1}|∞ estimates rung i's one-step position error (measured against the
//!   exact one-step error on Kepler and the oscillator: 0.96–1.00 of it, test
//!   `embedded_estimate_tracks_the_one_step_error_across_n`). The lowest rung with
//!   e ≤ [`ESTIMATE_SAFETY`]·tol/steps is taken, and with [`AdaptiveOptions::extrapolate`] the
//!   rung-(i+1) solution is kept (local extrapolation). What makes it cheap (cost = force
//!   evaluations, [`AdaptiveRun::gradient_evaluations`]):
//!   - *Warm starts* ([`AdaptiveOptions::warm_start`], via
//!     [`Workspace::warm_start`](crate::integrator::Workspace::warm_start)): the solve at
//!     n_{i+1} starts from rung i's curve of the same step, refitted at rung (i+1)'s nodes
//!     (2 Newton iterations, 3 force evaluations per quadrature node, against ≈ 7 for a solve
//!     from the integrator's guess competition); a step's first solve starts from the last
//!     accepted curve continued over the step (its Chebyshev series truncated where
//!     |a_j|·T_j(3) outgrows the curve: continuing round-off modes gave starts from which
//!     Newton stopped at residuals of 1e-4) or cold, whichever has recently cost less per
//!     node (on the outer solar system, h = 5 years, continuation is the worse start).
//!   - *Loose lower member*: the never-kept rung-i solve of a pair stops Newton at 0.1 of the
//!     budget (kept steps are always solved to round-off; test `kept_steps_are_solved_to_round_off`).
//!   - *Jumps*: a rung that misses the budget is followed by the smallest rung predicted to
//!     meet it from e·exp(−1.5σΔn), σ the geometric decay rate of the Chebyshev coefficients
//!     (the estimate was measured to decay 1.5–1.7× as fast as the coefficients); after a
//!     step the next starts up to 5 rungs lower (one per factor 20 below the budget).
//!   - *Unchecked steps*: within [`AdaptiveOptions::check_every`] steps of a check at the same
//!     rung, a step whose modal indicator has not grown since that check is solved at that rung
//!     alone (error predicted as e·ind/ind_check, kept without extrapolation); a step that may
//!     go down stays at its rung unchecked when that is predicted cheaper than a checked step
//!     lower down followed by unchecked steps there, amortised over the measured number of
//!     steps a rung stays right (moving average of the runs at one rung, at most
//!     `check_every`; comparing single steps kept the oscillator at h = 20 on n = 40 for a
//!     whole run where n = 21 meets tol).
//!   - *Memory*: a step down whose first estimate misses the budget keeps later steps down
//!     (for `check_every` steps) no lower than the middle between it and the current rung
//!     (bisection), and a climb does not jump past a rung that met the budget within
//!     `check_every` steps (the decay model fitted on an unresolved curve overshoots: the
//!     oscillator at h = 20 jumped from n = 20 to 40 where 24 had just passed).
//!   - *Swings*: when the lower rungs of the last three steps differ in n by a factor of 1.5
//!     or more, the next step starts no higher than the lowest of them
//!     ([`AdaptiveOptions::follow_swings`]): at large h the need swings from step to step
//!     (Kepler e = 0.6 at h = 2, three steps per orbit: n ≈ 45, 10 and 13 in turn at
//!     tol = 1e-8), and a step after a hard one had started at the hard one's rung. Without
//!     the spread condition the outer solar system at tol = 1e-6 cost 1.62× the fixed n
//!     instead of 1.37× (its rare easy steps led the next ones into failed steps down).
//!   - *Starts*: continued or cold is chosen by the cost of solves to round-off only (loose
//!     solves stop early whatever their start); the start that loses is retried at doubling
//!     intervals, 8 to 64 steps (on the outer solar system the continued start costs 8–13
//!     Newton iterations against 3 from the predictor).
//!   - *Round-off floor*: a climb whose estimates stall at the round-off level, or the top
//!     pair of the ladder missing a budget there, measures the floor of the estimates; later
//!     steps use twice that floor as their budget (one warning per run), and a check at the
//!     floor lets the next one probe a rung lower (outer solar system, tol = 1e-10: one-step
//!     differences between solves at n ≥ 14 are 3e-13…1e-12 AU whatever n; without this the
//!     run climbed to n = 24–28 and stayed there, 3.7× the cost of the fixed n).
//!
//!   Measured (`gvi tolerance-study`, 100 steps, tol = 1e-6…1e-12, see
//!   docs/guide/tolerance-driven-n.md; "saving" = cost of the cheapest fixed n meeting tol /
//!   adaptive cost): Kepler e = 0.6 at h = 0.25
//!   (Legendre): achieved/tol ≤ 0.05, saving 1.27–1.48×; at h = 1 (≈ 6 steps per orbit, the
//!   needed n changes 4× from step to step, so most steps are a fresh search): achieved/tol
//!   ≤ 0.16, saving 0.97–1.07×; at the scene's h = 2 (Chebyshev): 0.75–0.92× (oracle
//!   1.87–2.31×), and at 1e-10…1e-12 the run stops at 4.7e-10…6.0e-10 (warned) because the
//!   Chebyshev–Lagrange solves at n ≥ 56 are round-off limited there (fixed n = 64 reaches
//!   only 6.2e-10, n = 58 8.6e-12); Kepler e = 0.9 (h = 0.25): achieved/tol ≤ 1.8, saving
//!   3.68–4.61× (at 1e-12 no fixed n ≤ 64 meets tol); the oscillator at h = 20 (Chebyshev):
//!   0.85–1.08×; the outer solar system: 0.68–0.76× at 1e-6…1e-10. The oracle bound of
//!   the lab's allocation study (`gvi tolerance-study`, docs/guide/tolerance-driven-n.md)
//!   shows why the last two cannot be won by choosing n: an exact per-step choice, knowing every one-step error and paying nothing to learn it,
//!   saves 1.00–1.03× on the oscillator and 1.01–1.06× on the outer solar system (their need
//!   hardly varies), against 1.2–1.6× on e = 0.6 and 5.5–6.4× on e = 0.9.
//!   Switches (Kepler e = 0.6, h = 0.25, tol = 1e-8): without warm starts the run costs
//!   1.86× the defaults, checking every step 1.32× (test
//!   `warm_starts_and_unchecked_steps_each_cut_the_cost`); at h = 2 not following the swings
//!   costs 1.21–1.33× (test `following_swings_cuts_the_cost_only_where_the_need_swings`).
//!
//!   **Long runs.** The budget per step is tol/steps, which bounds the sum of the local
//!   errors, not their propagation: on an eccentric orbit a local error becomes an energy
//!   error, the energy error a period error, and the period error a phase error that grows
//!   with every orbit. Kepler e = 0.9, tol = 1e-8, T = 100 (16 orbits) with 1 019 steps: every
//!   step's true one-step error is within 0.6 of its budget and their sum is 0.01 tol, but the
//!   global error is 3.2 tol (near periapsis, r = 0.1, a position error δ moves the energy by
//!   ≈ δ·μ/r² = 100 δ). With 509 steps 0.69 tol, with 2 037 steps 1.8 tol (13 tol without
//!   following swings). The per-step budget does not model this propagation; the tolerance is
//!   met within the stated 2.2× at the 100–500 steps of the studies and tests.
//! * **Indicator**: the indicator alone, with a fixed relation error ≈ indicator^α
//!   ([`INDICATOR_EXPONENT`], calibrated on Kepler e = 0.6). One solve per step; on e = 0.6
//!   achieved/tol 0.7–4.4 at 0.77–0.86× the cost of the cheapest fixed n, but on e = 0.9
//!   achieved/tol 55–1115: the calibration does not transfer (near periapsis the step is
//!   under-resolved and the error is of the size of the indicator, not its 1.7th power).
//! * **Calibrated** (experimental): the indicator scaled by ratios error/indicator measured
//!   online per rung by embedded checks (first use of a rung, every
//!   [`AdaptiveOptions::check_every`] steps, when the indicator jumps 10×), with the next
//!   rung predicted from the geometric decay rate of the Chebyshev coefficients. Measured not
//!   robust: the ratio at a given n depends on where on the orbit it was measured (tiny
//!   where the orbit is slow), and on e = 0.9 achieved/tol reached up to 7.7e5; on e = 0.6 it
//!   cost 1.2–2.2× the fixed n. Also measured and rejected: predicting the kept rung's
//!   error as e·ind_{i+1}/ind_i (10–15 % cheaper, but achieved/tol up to 18 on e = 0.9), and
//!   predicting the next step's rung from the trend of the estimates (costlier on e = 0.6).
//!
//! The per-step budget tol/steps (times a safety factor) bounds the sum of the local errors,
//! which bounds the phase error that dominates long runs. A budget that the largest rung
//! cannot meet is kept as best effort with a warning per step (never a silent miss).
//!
//! **What is preserved.** Every step is the exact discrete flow of its own discrete Lagrangian
//! L_d^{(n_k)}, a symplectic and momentum-preserving map; a composition of symplectic maps is
//! symplectic, and each step conserves the Noether momenta of a symmetric Lagrangian, so a run
//! with varying n is symplectic and conserves momentum maps exactly as a fixed-n run (tested).
//! **What is not:** the run is no longer the flow of a single discrete Lagrangian, so the
//! backward-error argument for near-conservation of energy over exponentially long times does
//! not apply to it as a whole; energy errors are bounded by the largest per-step error
//! instead (measured in the tests).
//!
//! **Step size.** The run keeps one h throughout; [`choose_step`] (CLI `--auto-h`, scene
//! `auto_h = true`) picks it from the tolerance and the system's time scale τ by pilot runs
//! over one τ at h = τ/2, τ/4, … with the full run's per-step budget (see its module docs;
//! measured on Kepler e = 0.6 and 0.9: the chosen h's run is the cheapest of the candidates
//! that meet tol, the pilots cost 0.4–0.5 of a 16-period run).
//!
//! **Indicator against the true error.** Measured on Kepler (e = 0.6, h = 2 and 0.5,
//! n = 6…40, from periapsis and apoapsis) and the oscillator: the one-step position error is
//! at most 3.6× the indicator above the round-off floor (≤ 1× for n ≥ 12), and can be far
//! below it where the orbit is slow — the one-step map is superconvergent while the indicator
//! measures the curve (test `indicator_bounds_the_one_step_error`).
//!
//! **Local extrapolation and structure.** Keeping the higher rung's solution does not mix the
//! two: the accepted step is the exact discrete flow of L_d^{(n_{i+1})} alone, so everything
//! said above holds for it; the lower rung serves only as the error estimate. Warm starts
//! change only where Newton starts, not the equations it solves; a warm-started solve to be
//! kept whose stage residual is not at round-off (above 1e-8·max|p|) is redone cold.

mod descent;
pub(crate) mod driver;
mod embedded;
mod indicator;
mod ladder;
mod step_size;

pub use driver::integrate_adaptive;
pub use step_size::{Pilot, StepChoice, choose_step};

use crate::basis::BasisKind;
use crate::error::{GviError, Result};
use crate::quadrature::QuadratureKind;
use crate::trajectory::Trajectory;
use serde::{Deserialize, Serialize};

/// Measured exponent α in (one-step error) ≈ (indicator)^α above the round-off floor (see
/// the module docs): the per-step indicator tolerance is (tol / steps)^(1/α).
pub const INDICATOR_EXPONENT: f64 = 1.7;

/// Safety factor on the tolerance: the per-step indicator tolerance is
/// (SAFETY · tol / steps)^(1/α).
pub const SAFETY: f64 = 0.1;

/// Safety factor of the estimate-based controls: the per-step budget is
/// ESTIMATE_SAFETY · tol / steps.
pub const ESTIMATE_SAFETY: f64 = 0.5;

/// Default spacing of the embedded checks: at least every this many steps
/// ([`ErrorControl::Embedded`] and [`ErrorControl::Calibrated`]).
pub const CHECK_EVERY: usize = 8;

/// The default ladder of n.
pub const DEFAULT_LADDER: [usize; 14] = [4, 6, 8, 10, 12, 14, 16, 20, 24, 28, 32, 40, 48, 64];

/// Settings of a tolerance-driven run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveOptions {
    /// Requested tolerance on the max position error over the run.
    pub tol: f64,
    /// The values of n to choose from, increasing.
    pub ladder: Vec<usize>,
    /// Basis.
    pub basis: BasisKind,
    /// Quadrature (default points for each n).
    pub quadrature: QuadratureKind,
    /// Step size.
    pub h: f64,
    /// How the local error is estimated (default [`ErrorControl::Embedded`]).
    #[serde(default)]
    pub control: ErrorControl,
    /// When a step is solved at two rungs, keep the higher rung's solution (local
    /// extrapolation; default true). Either way the accepted step is the exact discrete flow
    /// of the discrete Lagrangian of its own n.
    #[serde(default = "default_true")]
    pub extrapolate: bool,
    /// Solve at the next rung as a check at least every this many steps (default
    /// [`CHECK_EVERY`]; 1: check every step).
    #[serde(default = "default_check_every")]
    pub check_every: usize,
    /// Start each solve's Newton iteration from a curve already at hand instead of the
    /// integrator's guess competition (default true): the first solve of a step from the last
    /// accepted curve continued over the step, a solve at a higher rung from the lower rung's
    /// curve of the same step. Changes only where Newton starts, not the map it solves.
    #[serde(default = "default_true")]
    pub warm_start: bool,
    /// Follow swings of the need ([`ErrorControl::Embedded`]; default true): when the n of the
    /// last three steps' lower rungs differ by a factor of 1.5 or more, a step starts no higher
    /// than the lowest of them, since the step after a hard one is usually easy (Kepler at
    /// h = 2: three steps per orbit needing n ≈ 45, 10 and 13 in turn). Changes only where the
    /// search for a step's n starts.
    #[serde(default = "default_true")]
    pub follow_swings: bool,
    /// The stage solver of every rung's integrator (default `Exact`: the controller's costs,
    /// force evaluations per solve, were measured and its thresholds tuned with exact Newton,
    /// which needs the fewest iterations; a structured solver gives the same map at more
    /// evaluations and less linear algebra per step).
    pub solver: crate::integrator::StageSolver,
}

fn default_true() -> bool {
    true
}

fn default_check_every() -> usize {
    CHECK_EVERY
}

/// How [`integrate_adaptive`] estimates each step's local position error.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ErrorControl {
    /// The modal indicator alone, with the fixed relation error ≈ indicator^α
    /// ([`INDICATOR_EXPONENT`], calibrated on Kepler e = 0.6; does not transfer, see the
    /// module docs). One solve per step.
    Indicator,
    /// A step is solved at its rung and at the next one; the difference of the step-end
    /// positions is the error estimate of the lower rung. Two solves per checked step (the
    /// second warm-started); between checks, steps whose indicator does not grow are solved
    /// once (see the module docs).
    #[default]
    Embedded,
    /// The indicator, scaled by a ratio (error / indicator) measured online by embedded checks:
    /// at the first steps, every [`AdaptiveOptions::check_every`] steps, after every change of
    /// rung and whenever the indicator jumps. One solve per step between checks.
    /// Experimental: measured not robust (see the module docs).
    Calibrated,
}

impl std::fmt::Display for ErrorControl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ErrorControl::Indicator => "indicator",
            ErrorControl::Embedded => "embedded",
            ErrorControl::Calibrated => "calibrated",
        })
    }
}

impl std::str::FromStr for ErrorControl {
    type Err = GviError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "indicator" => Ok(ErrorControl::Indicator),
            "embedded" => Ok(ErrorControl::Embedded),
            "calibrated" => Ok(ErrorControl::Calibrated),
            _ => Err(GviError::InvalidInput {
                name: "control".into(),
                reason: format!("'{s}' is not one of indicator, embedded, calibrated"),
            }),
        }
    }
}

impl AdaptiveOptions {
    /// Options with the default ladder.
    pub fn new(tol: f64, basis: BasisKind, quadrature: QuadratureKind, h: f64) -> Self {
        AdaptiveOptions {
            tol,
            ladder: DEFAULT_LADDER.to_vec(),
            basis,
            quadrature,
            h,
            control: ErrorControl::default(),
            extrapolate: true,
            check_every: CHECK_EVERY,
            warm_start: true,
            follow_swings: true,
            solver: crate::integrator::StageSolver::Exact,
        }
    }

    /// The same options with another error control.
    pub fn with_control(mut self, control: ErrorControl) -> Self {
        self.control = control;
        self
    }

    fn validate(&self) -> Result<()> {
        if !(self.tol.is_finite() && self.tol > 0.0) {
            return Err(GviError::InvalidInput {
                name: "tol".into(),
                reason: format!("{} must be finite and positive", self.tol),
            });
        }
        if self.ladder.is_empty() || self.ladder.windows(2).any(|w| w[0] >= w[1]) {
            return Err(GviError::InvalidInput {
                name: "ladder".into(),
                reason: "the ladder of n must be non-empty and increasing".into(),
            });
        }
        if self.check_every == 0 {
            return Err(GviError::InvalidInput {
                name: "check_every".into(),
                reason: "must be at least 1".into(),
            });
        }
        Ok(())
    }

    /// The per-step budget of the position error: SAFETY · tol / steps for the estimate-based
    /// controls (the indicator control raises it to the power 1/α, see [`INDICATOR_EXPONENT`]).
    pub fn step_budget(&self, steps: usize) -> f64 {
        let safety = match self.control {
            ErrorControl::Indicator => SAFETY,
            _ => ESTIMATE_SAFETY,
        };
        safety * self.tol / steps.max(1) as f64
    }
}

/// A tolerance-driven run.
#[derive(Debug, Clone, Serialize)]
pub struct AdaptiveRun {
    /// The trajectory (`step_n` holds n per step).
    pub trajectory: Trajectory,
    /// The indicator of every accepted step (of the rung whose solution was kept).
    pub indicators: Vec<f64>,
    /// The embedded estimate of every step that was checked at the next rung: the max-norm
    /// difference of the step-end positions of rungs i and i + 1 (`None`: not checked).
    pub estimates: Vec<Option<f64>>,
    /// The error control used.
    pub control: ErrorControl,
    /// Steps solved at two rungs (embedded checks).
    pub checks: usize,
    /// The per-step tolerance used: on the indicator for [`ErrorControl::Indicator`], on the
    /// estimated one-step position error otherwise ([`AdaptiveOptions::step_budget`]).
    pub local_tol: f64,
    /// Steps (and attempts) rejected and redone at a larger n.
    pub rejected: usize,
    /// Total force evaluations, including rejected attempts.
    pub gradient_evaluations: usize,
    /// Warnings: steps where the tolerance could not be met even at the largest n (the best
    /// effort was kept), or where it lies below the round-off floor.
    pub warnings: Vec<String>,
}
