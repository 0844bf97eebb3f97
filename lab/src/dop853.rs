//! DOP853 (Hairer's explicit Runge–Kutta 8(5,3) of Dormand & Prince with adaptive steps), from
//! the `differential-equations` crate, as an external peer (cargo feature `dop853`, on by
//! default).
//!
//! Its dense output is only about fourth order between step ends, so states are never
//! interpolated: each call of [`OneStepMethod::step`] integrates the canonical equations from t
//! to t + h (h the *sample interval*) as its own initial-value problem, ending exactly at the
//! sample time, and the next interval starts with the last full accepted step size of this one.
//!
//! It runs the way a careful user of the crate would run it: a fixed-size state `[f64; 2D]` for
//! the dimensions of the built-in scenes (D = 1, 2, 4, 6, 18, 30; a `Vec<f64>` state otherwise),
//! the system's own force (hand-written for the built-in systems), one method object reused for
//! every interval through the crate's low-level `solve_ode`, and an output handler that stores
//! nothing (no per-step history: only the end state is read, from the method itself).

use differential_equations::control::ControlFlag;
use differential_equations::interpolate::Interpolation;
use differential_equations::methods::{DormandPrince, ExplicitRungeKutta, Ordinary};
use differential_equations::ode::{ODE, OrdinaryNumericalMethod, solve_ode};
use differential_equations::solout::Solout;
use differential_equations::solution::Solution;
use differential_equations::traits::State;
use galerkin_vi::baselines::{CanonicalParts, OneStepMethod};
use galerkin_vi::error::{GviError, Result};
use galerkin_vi::lagrangian::Lagrangian;

/// The solver's state (q, p) as a flat buffer: `[f64; N]` (N = 2D) or `Vec<f64>`.
trait Buffer: State<f64> {
    fn zeroed(len: usize) -> Self;
    fn as_slice(&self) -> &[f64];
    fn as_mut_slice(&mut self) -> &mut [f64];
}

impl<const N: usize> Buffer for [f64; N] {
    fn zeroed(_len: usize) -> Self {
        [0.0; N]
    }
    #[inline]
    fn as_slice(&self) -> &[f64] {
        self
    }
    #[inline]
    fn as_mut_slice(&mut self) -> &mut [f64] {
        self
    }
}

impl Buffer for Vec<f64> {
    fn zeroed(len: usize) -> Self {
        vec![0.0; len]
    }
    #[inline]
    fn as_slice(&self) -> &[f64] {
        self
    }
    #[inline]
    fn as_mut_slice(&mut self) -> &mut [f64] {
        self
    }
}

/// The canonical equations y = (q, p), ẏ = (M⁻¹p, f(q)) for the external solver.
struct Canonical<'a, L: Lagrangian> {
    lagrangian: &'a L,
    parts: CanonicalParts,
}

impl<L: Lagrangian, Y: Buffer> ODE<f64, Y> for Canonical<'_, L> {
    #[inline]
    fn diff(&self, _t: f64, y: &Y, dydt: &mut Y) {
        let y = y.as_slice();
        // For `[f64; N]` the split point is a compile-time constant.
        let d = y.len() / 2;
        let (q, p) = y.split_at(d);
        let (dq, dp) = dydt.as_mut_slice().split_at_mut(d);
        self.parts.velocity(p, dq);
        self.lagrangian.force(q, dp);
    }
}

/// An output handler that stores nothing: it only remembers the last two accepted step
/// lengths (the last one may be shortened to hit the sample time).
#[derive(Debug, Default, Clone, Copy)]
struct LastSteps {
    last: f64,
    before_last: f64,
    accepted: usize,
}

impl<Y: State<f64>> Solout<f64, Y> for LastSteps {
    #[inline]
    fn solout<I>(
        &mut self,
        t_curr: f64,
        t_prev: f64,
        _y_curr: &Y,
        _y_prev: &Y,
        _interpolator: &mut I,
        _solution: &mut Solution<f64, Y>,
    ) -> ControlFlag<f64, Y>
    where
        I: Interpolation<f64, Y> + ?Sized,
    {
        // The call after initialisation has t_curr = t_prev.
        if t_curr != t_prev {
            self.before_last = self.last;
            self.last = t_curr - t_prev;
            self.accepted += 1;
        }
        ControlFlag::Continue
    }
}

/// The crate's DOP853 method type for state `Y`.
type Dop853<Y> = ExplicitRungeKutta<Ordinary, DormandPrince, f64, Y, 8, 12, 16>;

/// What one sample interval cost and where the next starts.
struct Interval {
    evaluations: usize,
    steps: usize,
    /// The last full (not shortened) accepted step, when there were at least two.
    next_h0: Option<f64>,
}

/// One sample interval of DOP853, whatever the state type.
trait Engine {
    #[allow(clippy::too_many_arguments)]
    fn advance(
        &mut self,
        t0: f64,
        t1: f64,
        h0: f64,
        max_steps: usize,
        q: &[f64],
        p: &[f64],
        q_next: &mut [f64],
        p_next: &mut [f64],
    ) -> Result<Interval>;
}

/// The method object (reused for every interval), the equations and the start buffer.
struct Solver<'a, L: Lagrangian, Y: Buffer> {
    ode: Canonical<'a, L>,
    method: Dop853<Y>,
    y0: Y,
}

impl<L: Lagrangian, Y: Buffer> Engine for Solver<'_, L, Y> {
    fn advance(
        &mut self,
        t0: f64,
        t1: f64,
        h0: f64,
        max_steps: usize,
        q: &[f64],
        p: &[f64],
        q_next: &mut [f64],
        p_next: &mut [f64],
    ) -> Result<Interval> {
        let d = q.len();
        let y0 = self.y0.as_mut_slice();
        y0[..d].copy_from_slice(q);
        y0[d..].copy_from_slice(p);
        // h0 = 0 asks the method for its initial-step heuristic.
        self.method.h0 = h0;
        self.method.max_steps = max_steps;
        let mut steps = LastSteps::default();
        let solution = solve_ode(&mut self.method, &self.ode, t0, t1, &self.y0, &mut steps)
            .map_err(|e| GviError::Unsupported(format!("DOP853 failed at t = {t0}: {e:?}")))?;
        let t_end = OrdinaryNumericalMethod::<f64, Y>::t(&self.method);
        if (t_end - t1).abs() > 1e-12 * (1.0 + t_end.abs()) {
            return Err(GviError::Unsupported(format!(
                "DOP853 stopped at t = {t_end} instead of {t1}"
            )));
        }
        let y = OrdinaryNumericalMethod::<f64, Y>::y(&self.method).as_slice();
        q_next.copy_from_slice(&y[..d]);
        p_next.copy_from_slice(&y[d..]);
        Ok(Interval {
            evaluations: solution.evals.function,
            steps: solution.steps.accepted + solution.steps.rejected,
            next_h0: (steps.accepted >= 2).then_some(steps.before_last),
        })
    }
}

/// Step attempts allowed per sample interval.
const MAX_STEPS_PER_INTERVAL: usize = 10_000_000;

/// DOP853 with rtol = atol = `tolerance`, stopped exactly at every multiple of the sample
/// interval h.
///
/// ```
/// use galerkin_vi::baselines::OneStepMethod;
/// use galerkin_vi_lab::dop853::Dop853Baseline;
/// use galerkin_vi::systems::HarmonicOscillator;
///
/// let ho = HarmonicOscillator::unit();
/// let mut m = Dop853Baseline::new(&ho, 1.0, 1e-12)?;
/// assert!(m.has_static_state());
/// let (mut q, mut p) = ([0.0], [0.0]);
/// m.step(0.0, &[1.0], &[0.0], &mut q, &mut p)?;
/// assert!((q[0] - 1.0f64.cos()).abs() < 1e-10);
/// assert!(m.force_evaluations() > 0);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
pub struct Dop853Baseline<'a, L: Lagrangian> {
    h: f64,
    tolerance: f64,
    d: usize,
    engine: Box<dyn Engine + 'a>,
    static_state: bool,
    last_step: Option<f64>,
    evaluations: usize,
    steps: usize,
    _lagrangian: std::marker::PhantomData<&'a L>,
}

impl<'a, L: Lagrangian> Dop853Baseline<'a, L> {
    /// DOP853 at tolerance `tolerance` (rtol = atol, in [1e-16, 1)) with output interval h;
    /// a fixed-size state `[f64; 2D]` for D ∈ {1, 2, 4, 6, 18, 30}, a `Vec<f64>` otherwise.
    pub fn new(lagrangian: &'a L, h: f64, tolerance: f64) -> Result<Self> {
        Self::build(lagrangian, h, tolerance, true)
    }

    /// The same method with a `Vec<f64>` state whatever D (the fallback of [`new`](Self::new)
    /// for other dimensions; exposed to check that both give the same states).
    pub fn new_dynamic(lagrangian: &'a L, h: f64, tolerance: f64) -> Result<Self> {
        Self::build(lagrangian, h, tolerance, false)
    }

    fn build(lagrangian: &'a L, h: f64, tolerance: f64, allow_static: bool) -> Result<Self> {
        if !(tolerance.is_finite() && (1e-16..1.0).contains(&tolerance)) {
            return Err(GviError::InvalidParameter {
                name: "DOP853 tolerance".into(),
                value: tolerance,
                reason: "need 1e-16 ≤ tolerance < 1".into(),
            });
        }
        let parts = CanonicalParts::new(lagrangian, h)?;
        let d = parts.d;
        fn solver<'a, L: Lagrangian, Y: Buffer + 'a>(
            lagrangian: &'a L,
            parts: CanonicalParts,
            tolerance: f64,
        ) -> Box<dyn Engine + 'a> {
            let len = 2 * parts.d;
            Box::new(Solver::<L, Y> {
                ode: Canonical { lagrangian, parts },
                method: Dop853::<Y>::dop853().rtol(tolerance).atol(tolerance),
                y0: Y::zeroed(len),
            })
        }
        let (engine, static_state) = match (allow_static, d) {
            (true, 1) => (solver::<L, [f64; 2]>(lagrangian, parts, tolerance), true),
            (true, 2) => (solver::<L, [f64; 4]>(lagrangian, parts, tolerance), true),
            (true, 4) => (solver::<L, [f64; 8]>(lagrangian, parts, tolerance), true),
            (true, 6) => (solver::<L, [f64; 12]>(lagrangian, parts, tolerance), true),
            (true, 18) => (solver::<L, [f64; 36]>(lagrangian, parts, tolerance), true),
            (true, 30) => (solver::<L, [f64; 60]>(lagrangian, parts, tolerance), true),
            _ => (solver::<L, Vec<f64>>(lagrangian, parts, tolerance), false),
        };
        Ok(Dop853Baseline {
            h,
            tolerance,
            d,
            engine,
            static_state,
            last_step: None,
            evaluations: 0,
            steps: 0,
            _lagrangian: std::marker::PhantomData,
        })
    }

    /// Accepted plus rejected adaptive steps so far.
    pub fn adaptive_steps(&self) -> usize {
        self.steps
    }

    /// Whether the state is a fixed-size array (true for the dimensions of the built-in
    /// scenes) rather than a `Vec<f64>`.
    pub fn has_static_state(&self) -> bool {
        self.static_state
    }
}

impl<L: Lagrangian> OneStepMethod for Dop853Baseline<'_, L> {
    fn name(&self) -> String {
        format!(
            "dop853 (tol = {:e}, output every {})",
            self.tolerance, self.h
        )
    }

    fn step_size(&self) -> f64 {
        self.h
    }

    fn force_evaluations(&self) -> usize {
        self.evaluations
    }

    fn step(
        &mut self,
        t: f64,
        q: &[f64],
        p: &[f64],
        q_next: &mut [f64],
        p_next: &mut [f64],
    ) -> Result<()> {
        let d = self.d;
        crate::error::ensure_len("q", d, q.len())?;
        crate::error::ensure_len("p", d, p.len())?;
        crate::error::ensure_len("q_next", d, q_next.len())?;
        crate::error::ensure_len("p_next", d, p_next.len())?;
        let h0 = self.last_step.map_or(0.0, |h0| h0.min(self.h));
        // The method counts step attempts over its whole life: allow as many per interval.
        let max_steps = self.steps.saturating_add(MAX_STEPS_PER_INTERVAL);
        let interval = self
            .engine
            .advance(t, t + self.h, h0, max_steps, q, p, q_next, p_next)?;
        self.evaluations += interval.evaluations;
        self.steps += interval.steps;
        if interval.next_h0.is_some() {
            self.last_step = interval.next_h0;
        }
        Ok(())
    }
}
