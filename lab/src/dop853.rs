//! DOP853 (Hairer's explicit Runge–Kutta 8(5,3) of Dormand & Prince with adaptive steps), from
//! the `differential-equations` crate, as an external peer (cargo feature `dop853`, on by
//! default).
//!
//! States are never interpolated: the samples are step ends. One run integrates the whole span
//! with one method object, initialised once: consecutive calls of [`OneStepMethod::step`] that
//! continue from the state the previous call returned (the study's sampling loop) keep
//! stepping the same solution, and a step that would pass the next sample time is shortened to
//! end exactly on it — the loop of the crate's own `solve_ode`, with output points. After such a
//! shortened step the next step starts from the controller's proposal before shortening
//! (the usual treatment of output points in step-size control, e.g. `tstops` in
//! OrdinaryDiffEq.jl), so that sampling costs about one extra step per sample and nothing
//! else. A call that does not continue the previous one (another state or time) starts a new
//! solution, with the last full step as its first.
//!
//! It runs the way a careful user of the crate would run it: a fixed-size state `[f64; 2D]` for
//! the dimensions of the built-in scenes (D = 1, 2, 4, 6, 18, 30; a `Vec<f64>` state otherwise),
//! the system's own force (hand-written for the built-in systems), one method object for the
//! whole span and no stored history (`benches/peers.rs` times it against the crate's
//! `solve_ode` over the whole span with an output handler that stores nothing).

use differential_equations::methods::{DormandPrince, ExplicitRungeKutta, Ordinary};
use differential_equations::ode::{ODE, OrdinaryNumericalMethod};
use differential_equations::status::Status;
use differential_equations::traits::State;
use galerkin_vi::baselines::{CanonicalParts, OneStepMethod, force_static};
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

/// The canonical equations y = (q, p), ẏ = (M⁻¹p, f(q)) for the external solver, on a
/// `Vec<f64>` state of any length.
struct Canonical<'a, L: Lagrangian> {
    lagrangian: &'a L,
    parts: CanonicalParts,
}

impl<L: Lagrangian> ODE<f64, Vec<f64>> for Canonical<'_, L> {
    #[inline]
    fn diff(&self, _t: f64, y: &Vec<f64>, dydt: &mut Vec<f64>) {
        let d = y.len() / 2;
        let (q, p) = y.split_at(d);
        let (dq, dp) = dydt.split_at_mut(d);
        self.parts.velocity(p, dq);
        self.lagrangian.force(q, dp);
    }
}

/// The same equations on a fixed-size state `[f64; N]`, N = 2D, through the fixed-size kernels
/// the fixed-step baselines use (`velocity_static`, `force_static`): every length is a
/// compile-time constant, as in a hand-written right-hand side.
struct FixedCanonical<'a, L: Lagrangian, const D: usize> {
    lagrangian: &'a L,
    parts: CanonicalParts,
}

impl<L: Lagrangian, const D: usize, const N: usize> ODE<f64, [f64; N]>
    for FixedCanonical<'_, L, D>
{
    #[inline(always)]
    fn diff(&self, _t: f64, y: &[f64; N], dydt: &mut [f64; N]) {
        // N = 2D (checked where it is built), so every index below is in range and known.
        let q: [f64; D] = std::array::from_fn(|i| y[i]);
        let p: [f64; D] = std::array::from_fn(|i| y[D + i]);
        let v = self.parts.velocity_static(&p);
        let f = force_static(self.lagrangian, &q);
        dydt[..D].copy_from_slice(&v);
        dydt[D..].copy_from_slice(&f);
    }
}

/// The crate's DOP853 method type for state `Y`.
type Dop853<Y> = ExplicitRungeKutta<Ordinary, DormandPrince, f64, Y, 8, 12, 16>;

/// What one sample interval cost and where the next starts.
struct Interval {
    evaluations: usize,
    steps: usize,
    /// The last full (not shortened) accepted step, if there was one.
    full_step: Option<f64>,
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

/// The method object (one for the whole run), the equations and the start buffer.
struct Solver<F, Y: Buffer> {
    ode: F,
    method: Dop853<Y>,
    y0: Y,
    /// Whether `method` holds a solution that a call may continue.
    running: bool,
}

/// Whether two times agree to a few rounding errors (a sample time computed as t₀ + kΔ
/// against the same time reached as a sum of steps).
#[inline]
fn same_time(a: f64, b: f64) -> bool {
    (a - b).abs() <= 16.0 * f64::EPSILON * a.abs().max(b.abs()).max(1.0)
}

impl<F: ODE<f64, Y>, Y: Buffer> Solver<F, Y> {
    /// Whether the method's current solution is at (t0, q, p), bit for bit in the state.
    fn continues(&self, t0: f64, q: &[f64], p: &[f64]) -> bool {
        if !self.running {
            return false;
        }
        let t = OrdinaryNumericalMethod::<f64, Y>::t(&self.method);
        let y = OrdinaryNumericalMethod::<f64, Y>::y(&self.method).as_slice();
        let d = q.len();
        same_time(t, t0) && y[..d] == *q && y[d..] == *p
    }
}

impl<F: ODE<f64, Y>, Y: Buffer> Engine for Solver<F, Y> {
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
        let fail = |t: f64, e: &dyn std::fmt::Debug| {
            GviError::Unsupported(format!("DOP853 failed at t = {t}: {e:?}"))
        };
        let d = q.len();
        let mut evaluations = 0;
        let mut steps = 0;
        let mut full_step = None;
        self.method.max_steps = max_steps;
        if !self.continues(t0, q, p) {
            self.running = false;
            let y0 = self.y0.as_mut_slice();
            y0[..d].copy_from_slice(q);
            y0[d..].copy_from_slice(p);
            // h0 = 0 asks the method for its initial-step heuristic.
            self.method.h0 = h0;
            let evals = self
                .method
                .init(&self.ode, t0, t1, &self.y0)
                .map_err(|e| fail(t0, &e))?;
            evaluations += evals.function;
            self.running = true;
        }
        // The loop of `solve_ode`, ending exactly at t1.
        loop {
            let t = OrdinaryNumericalMethod::<f64, Y>::t(&self.method);
            if same_time(t, t1) {
                break;
            }
            let h = OrdinaryNumericalMethod::<f64, Y>::h(&self.method);
            let shortened = t + h > t1;
            if shortened {
                self.method.set_h(t1 - t);
            }
            match self.method.step(&self.ode) {
                Ok(evals) => evaluations += evals.function,
                Err(e) => {
                    self.running = false;
                    return Err(fail(t, &e));
                }
            }
            steps += 1;
            if matches!(
                OrdinaryNumericalMethod::<f64, Y>::status(&self.method),
                Status::RejectedStep
            ) {
                continue;
            }
            if shortened {
                // Accepted as shortened: go on from the proposal before shortening, unless
                // the controller now proposes more.
                let proposed = OrdinaryNumericalMethod::<f64, Y>::h(&self.method);
                self.method.set_h(proposed.max(h));
            } else {
                full_step = Some(h);
            }
        }
        let t_end = OrdinaryNumericalMethod::<f64, Y>::t(&self.method);
        if !same_time(t_end, t1) {
            self.running = false;
            return Err(GviError::Unsupported(format!(
                "DOP853 stopped at t = {t_end} instead of {t1}"
            )));
        }
        let y = OrdinaryNumericalMethod::<f64, Y>::y(&self.method).as_slice();
        q_next.copy_from_slice(&y[..d]);
        p_next.copy_from_slice(&y[d..]);
        Ok(Interval {
            evaluations,
            steps,
            full_step,
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
/// # Ok::<(), galerkin_vi_lab::error::LabError>(())
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
        fn solver<'a, F: ODE<f64, Y> + 'a, Y: Buffer + 'a>(
            ode: F,
            len: usize,
            tolerance: f64,
        ) -> Box<dyn Engine + 'a> {
            Box::new(Solver::<F, Y> {
                ode,
                method: Dop853::<Y>::dop853().rtol(tolerance).atol(tolerance),
                y0: Y::zeroed(len),
                running: false,
            })
        }
        fn fixed<'a, L: Lagrangian, const D: usize, const N: usize>(
            lagrangian: &'a L,
            parts: CanonicalParts,
            tolerance: f64,
        ) -> Box<dyn Engine + 'a> {
            const { assert!(N == 2 * D) };
            solver::<_, [f64; N]>(FixedCanonical::<L, D> { lagrangian, parts }, N, tolerance)
        }
        let (engine, static_state) = match (allow_static, d) {
            (true, 1) => (fixed::<L, 1, 2>(lagrangian, parts, tolerance), true),
            (true, 2) => (fixed::<L, 2, 4>(lagrangian, parts, tolerance), true),
            (true, 4) => (fixed::<L, 4, 8>(lagrangian, parts, tolerance), true),
            (true, 6) => (fixed::<L, 6, 12>(lagrangian, parts, tolerance), true),
            (true, 18) => (fixed::<L, 18, 36>(lagrangian, parts, tolerance), true),
            (true, 30) => (fixed::<L, 30, 60>(lagrangian, parts, tolerance), true),
            _ => (
                solver::<_, Vec<f64>>(Canonical { lagrangian, parts }, 2 * d, tolerance),
                false,
            ),
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
        if interval.full_step.is_some() {
            self.last_step = interval.full_step;
        }
        Ok(())
    }
}
