//! [`integrate_time_transformed`]: a time-transformed run to a physical end time, with output
//! at requested physical times and events in physical time, all located on the steps'
//! Galerkin curves through t(τ) (see `clock`).

use super::clock::CurveClock;
use super::{Monitor, TimeTransformed};
use crate::basis::Basis;
use crate::curve::GalerkinCurveRef;
use crate::error::{GviError, Result};
use crate::events::{Crossing, CurveProbe, Event, EventOptions, illinois};
use crate::integrator::{GalerkinIntegrator, MAX_STEPS};
use crate::lagrangian::Lagrangian;
use crate::quadrature::Quadrature;

/// How a time-transformed run ends and what it records.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeTransformOptions {
    /// The physical end time: the run stops on the curve where t(s) = t_end. `None`: after
    /// `max_steps` fictitious steps.
    pub t_end: Option<f64>,
    /// The most fictitious steps to take (reaching it before `t_end` is an error).
    pub max_steps: usize,
    /// States at t₀ + k·every (k ≥ 0, up to t_end) in physical time, each located on the
    /// curve as the zero of t(s) − t₀ − k·every. `None`: none.
    pub every: Option<f64>,
    /// Record every step end (physical time, fictitious time, state, physical step).
    pub keep_steps: bool,
    /// Keep every step's Galerkin coefficients for dense output
    /// ([`TimeTransformedRun::state_at`]).
    pub keep_curves: bool,
    /// Samples per step and tolerance for events and output times.
    pub events: EventOptions,
}

impl Default for TimeTransformOptions {
    fn default() -> Self {
        TimeTransformOptions {
            t_end: None,
            max_steps: 1000,
            every: None,
            keep_steps: true,
            keep_curves: false,
            events: EventOptions::default(),
        }
    }
}

/// A state of a time-transformed run at a physical time.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputState {
    /// Physical time t.
    pub t: f64,
    /// Fictitious time s.
    pub s: f64,
    /// Position.
    pub q: Vec<f64>,
    /// Physical momentum.
    pub p: Vec<f64>,
    /// The fictitious step (0-based) whose curve holds it; for a step end, the steps
    /// completed.
    pub step: usize,
    /// For a step end: the physical length of the step that led here (0 at the start); for
    /// a located state: the physical length of the step holding it.
    pub dt: f64,
}

/// The result of [`integrate_time_transformed`].
#[derive(Debug, Clone, PartialEq)]
pub struct TimeTransformedRun {
    /// The states at t₀ + k·every, in time order.
    pub outputs: Vec<OutputState>,
    /// Every step end, starting with the initial state (with `keep_steps`).
    pub step_ends: Vec<OutputState>,
    /// Every crossing of an event (its `t` physical), in time order.
    pub crossings: Vec<Crossing>,
    /// The final state: at t_end, at the stopping event, or at the last step end.
    pub end: OutputState,
    /// Whether an event with a stop action ended the run.
    pub stopped: bool,
    /// Newton iterations of all steps.
    pub newton_iterations: usize,
    /// Evaluations of the Lagrangian's first derivatives (per quadrature node and
    /// iteration), the cost measure of [`crate::Trajectory::gradient_evaluations`].
    pub gradient_evaluations: usize,
    /// The Galerkin coefficients of every step, n×D each, with `keep_curves`.
    pub curves: Vec<f64>,
    n: usize,
    d: usize,
    ds: f64,
}

impl TimeTransformedRun {
    /// Steps completed.
    pub fn steps(&self) -> usize {
        self.end.step
    }

    /// Dense output: (q, p) at physical time t, from the stored curves (`keep_curves` and
    /// `keep_steps`), located on the curve of the step holding t as the zero of t(τ) − t.
    /// `gvi` and `tt` must be the run's.
    ///
    /// Errors: no curves kept, t outside the run, an integrator or Lagrangian of another n
    /// or dimension.
    pub fn state_at<B: Basis, Q: Quadrature, S: Lagrangian, M: Monitor>(
        &self,
        gvi: &GalerkinIntegrator<B, Q>,
        tt: &TimeTransformed<S, M>,
        t: f64,
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        let (n, d) = (self.n, self.d);
        let steps = self.step_ends.len().saturating_sub(1);
        if self.curves.len() != steps * n * d || steps == 0 {
            return Err(GviError::Unsupported(
                "dense output needs a run with keep_curves and keep_steps".into(),
            ));
        }
        crate::error::ensure_len("integrator n", n, gvi.n())?;
        crate::error::ensure_len("Lagrangian dimension", d, tt.dim())?;
        let (first, last) = (self.step_ends[0].t, self.step_ends[steps].t);
        if !(t.is_finite() && t >= first && t <= last) {
            return Err(GviError::InvalidInput {
                name: "t".into(),
                reason: format!("{t} is outside the run [{first}, {last}]"),
            });
        }
        let k = self.step_ends[1..]
            .partition_point(|e| e.t < t)
            .min(steps - 1);
        let curve = GalerkinCurveRef::new(
            &self.curves[k * n * d..(k + 1) * n * d],
            n,
            d,
            self.ds,
            self.step_ends[k].s,
        )?;
        let mut probe = Probe::new(gvi, d);
        let t_k = self.step_ends[k].t;
        let target = t;
        let mut f = |tau: f64| t_k + probe.clock.partial(&curve, gvi.basis(), tt, tau) - target;
        let (fa, fb) = (f(0.0), f(1.0));
        let tau = illinois(&mut f, (0.0, fa), (1.0, fb), 4.0 * f64::EPSILON);
        probe.state(&curve, gvi.basis(), tt, tau);
        Ok((probe.at.q, probe.at.p))
    }
}

/// A failed [`integrate_time_transformed`]: the error and the run up to the last completed
/// step.
#[derive(Debug)]
pub struct TimeTransformFailure {
    /// What went wrong.
    pub error: GviError,
    /// The run before it (`None` when the input was refused before any step).
    pub partial: Option<Box<TimeTransformedRun>>,
}

impl std::fmt::Display for TimeTransformFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.error)?;
        if let Some(p) = &self.partial {
            write!(f, " ({} steps to t = {} kept)", p.steps(), p.end.t)?;
        }
        Ok(())
    }
}

impl std::error::Error for TimeTransformFailure {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.error)
    }
}

impl From<GviError> for TimeTransformFailure {
    fn from(error: GviError) -> Self {
        TimeTransformFailure {
            error,
            partial: None,
        }
    }
}

/// Buffers for the physical time on a curve (`clock`) and the state there (`at`: the event
/// locator's probe, whose Legendre transform is then the time-transformed Lagrangian's,
/// p = ∂L̃/∂q', the physical momentum; the time it passes is the fictitious s, which the
/// autonomous L̃ does not read, so the state is the one the run's own buffers gave).
struct Probe {
    clock: CurveClock,
    at: CurveProbe,
}

impl Probe {
    fn new<B: Basis, Q: Quadrature>(gvi: &GalerkinIntegrator<B, Q>, d: usize) -> Self {
        Probe {
            clock: CurveClock::new(gvi, d),
            at: CurveProbe::new(gvi.n(), d),
        }
    }

    /// (q, p) at local time τ into `self.at.q`, `self.at.p`.
    fn state<B: Basis + ?Sized, S: Lagrangian, M: Monitor>(
        &mut self,
        curve: &GalerkinCurveRef<'_>,
        basis: &B,
        tt: &TimeTransformed<S, M>,
        tau: f64,
    ) {
        self.at.state(curve, basis, tt, tau);
    }
}

/// Integrate the time-transformed Lagrangian `tt` with `gvi` (step size = the fictitious
/// step Δs) from (q₀, p₀) at physical time t₀, to `options.t_end` in physical time or for
/// `options.max_steps` fictitious steps, locating the output times t₀ + k·every, t_end and the
/// zeros of each event's g(t, q, p) (t physical) on every step's Galerkin curve.
///
/// Events may record or stop; an event with a map is refused ([`GviError::Unsupported`]): a
/// map that changes the energy moves the state off H̃ = 0, and the run would have to restart
/// with a new E₀ (stop at the event and start a new run from the mapped state instead).
///
/// Errors (with the run so far in `partial` once a step was taken): invalid options, t_end
/// before t₀, an event with a map; the monitor not finite and positive at q₀; a step's solver
/// failure; a physical step not finite and positive; `max_steps` reached before t_end
/// ([`GviError::InvalidStepCount`]); an event's g not finite.
pub fn integrate_time_transformed<B: Basis, Q: Quadrature, S: Lagrangian, M: Monitor>(
    gvi: &GalerkinIntegrator<B, Q>,
    tt: &TimeTransformed<S, M>,
    t0: f64,
    q0: &[f64],
    p0: &[f64],
    events: &mut [Event<'_>],
    options: &TimeTransformOptions,
) -> std::result::Result<TimeTransformedRun, TimeTransformFailure> {
    integrate_time_transformed_until(gvi, tt, t0, q0, p0, events, options, &|| false)
}

/// [`integrate_time_transformed`] that asks `stop` before every fictitious step (Ctrl-C in
/// the Python bindings, a deadline): a `true` ends the run with [`GviError::Interrupted`] and
/// the run so far in `partial`. With a `stop` that never says yes the run is
/// [`integrate_time_transformed`]'s bit for bit.
#[allow(clippy::too_many_arguments)]
pub fn integrate_time_transformed_until<B: Basis, Q: Quadrature, S: Lagrangian, M: Monitor>(
    gvi: &GalerkinIntegrator<B, Q>,
    tt: &TimeTransformed<S, M>,
    t0: f64,
    q0: &[f64],
    p0: &[f64],
    events: &mut [Event<'_>],
    options: &TimeTransformOptions,
    stop: &dyn Fn() -> bool,
) -> std::result::Result<TimeTransformedRun, TimeTransformFailure> {
    options.events.validate()?;
    if options.max_steps == 0 || options.max_steps > MAX_STEPS {
        return Err(GviError::InvalidStepCount {
            steps: options.max_steps,
            reason: format!("need 1 ≤ max_steps ≤ {MAX_STEPS}"),
        }
        .into());
    }
    if let Some(t_end) = options.t_end
        && !(t_end.is_finite() && t_end >= t0)
    {
        return Err(GviError::InvalidParameter {
            name: "t_end".into(),
            value: t_end,
            reason: format!("must be finite and at least t0 = {t0}"),
        }
        .into());
    }
    if let Some(every) = options.every.filter(|e| !(e.is_finite() && *e > 0.0)) {
        return Err(GviError::InvalidParameter {
            name: "every".into(),
            value: every,
            reason: "must be finite and positive".into(),
        }
        .into());
    }
    if let Some(e) = events.iter().find(|e| e.maps()) {
        return Err(GviError::Unsupported(format!(
            "event '{}' maps the state; a time-transformed run cannot restart at a new energy \
             level (stop at the event and start a new run from the mapped state)",
            e.name()
        ))
        .into());
    }
    let mut stepper = tt.stepper(gvi, t0, q0, p0)?;
    let d = tt.dim();
    let mut probe = Probe::new(gvi, d);
    let samples = options.events.samples_per_step;
    let tau_tol = options.events.local_time_tolerance;
    // g of each event at the previous sample.
    let mut previous: Vec<f64> = Vec::with_capacity(events.len());
    for e in events.iter() {
        let g = e.evaluate(t0, q0, p0);
        if !g.is_finite() {
            return Err(GviError::NonFinite {
                what: format!("event '{}' at t = {t0}", e.name()),
                value: g,
            }
            .into());
        }
        previous.push(g);
    }
    let mut current = previous.clone();
    let mut found: Vec<(Crossing, f64)> = Vec::new();
    let start = OutputState {
        t: t0,
        s: 0.0,
        q: q0.to_vec(),
        p: p0.to_vec(),
        step: 0,
        dt: 0.0,
    };
    let mut run = TimeTransformedRun {
        outputs: Vec::new(),
        step_ends: if options.keep_steps {
            vec![start.clone()]
        } else {
            Vec::new()
        },
        crossings: Vec::new(),
        end: start,
        stopped: false,
        newton_iterations: 0,
        gradient_evaluations: 0,
        curves: Vec::new(),
        n: gvi.n(),
        d,
        ds: gvi.step_size(),
    };
    let t_end = options.t_end.unwrap_or(f64::INFINITY);
    // The next output time t₀ + k·every (k counted, not accumulated).
    let mut k_out = 0usize;
    let next_output = |k: usize| options.every.map_or(f64::INFINITY, |e| t0 + k as f64 * e);
    // An output exactly at t0 is the initial state.
    if options.every.is_some() {
        run.outputs.push(run.end.clone());
        k_out = 1;
    }
    let fail = |error: GviError, run: TimeTransformedRun| TimeTransformFailure {
        error,
        partial: Some(Box::new(run)),
    };
    if t_end == t0 {
        return Ok(run);
    }
    loop {
        if stepper.steps() >= options.max_steps {
            if options.t_end.is_some() {
                let error = GviError::InvalidStepCount {
                    steps: options.max_steps,
                    reason: format!(
                        "max_steps fictitious steps reached t = {} before t_end = {t_end}; \
                         raise the step count or Δs",
                        stepper.time()
                    ),
                };
                return Err(fail(error, run));
            }
            return Ok(run);
        }
        if stop() {
            let error = GviError::Interrupted {
                step: stepper.steps(),
                t: stepper.time(),
            };
            return Err(fail(error, run));
        }
        let stats = match stepper.step() {
            Ok(s) => s,
            Err(e) => return Err(fail(e, run)),
        };
        run.newton_iterations += stats.iterations;
        run.gradient_evaluations += stats.gradient_evaluations;
        let step = stepper.steps() - 1;
        let (t_a, t_b, dt) = (stepper.previous_time(), stepper.time(), stepper.last_step());
        let (inner, clock, _) = stepper.parts();
        let curve = inner.curve();
        let basis = gvi.basis();
        let mut stop_at: Option<f64> = None;
        if options.keep_curves {
            run.curves.extend_from_slice(curve.coefficients());
        }
        // Events: sign changes of g between samples of the curve, located in τ; this step's
        // crossings in `found` with their local times, then in time order up to the first
        // that stops the run.
        found.clear();
        if !events.is_empty() {
            let mut tau_prev = 0.0;
            for j in 1..=samples {
                let tau = j as f64 / samples as f64;
                let t = t_a + clock.partial(&curve, basis, tt, tau);
                probe.state(&curve, basis, tt, tau);
                for (e, event) in events.iter().enumerate() {
                    let g = event.evaluate(t, &probe.at.q, &probe.at.p);
                    if !g.is_finite() {
                        let error = GviError::NonFinite {
                            what: format!("event '{}' on step {step} at t = {t}", event.name()),
                            value: g,
                        };
                        return Err(fail(error, run));
                    }
                    current[e] = g;
                }
                for (e, event) in events.iter().enumerate() {
                    let (ga, gb) = (previous[e], current[e]);
                    let crosses = ga != 0.0 && (gb == 0.0 || (ga < 0.0) != (gb < 0.0));
                    let rising = ga < 0.0;
                    if !crosses || !event.accepts(rising) {
                        continue;
                    }
                    let mut f = |x: f64| {
                        let t = t_a + probe.clock.partial(&curve, basis, tt, x);
                        probe.state(&curve, basis, tt, x);
                        event.evaluate(t, &probe.at.q, &probe.at.p)
                    };
                    let root = illinois(&mut f, (tau_prev, ga), (tau, gb), tau_tol);
                    let t_root = t_a + probe.clock.partial(&curve, basis, tt, root);
                    if t_root > t_end {
                        continue;
                    }
                    probe.state(&curve, basis, tt, root);
                    let crossing = Crossing {
                        event: e,
                        name: event.name().to_string(),
                        t: t_root,
                        q: probe.at.q.clone(),
                        p: probe.at.p.clone(),
                        step,
                        rising,
                    };
                    found.push((crossing, root));
                }
                std::mem::swap(&mut previous, &mut current);
                tau_prev = tau;
                if found.iter().any(|(c, _)| events[c.event].stops()) {
                    break;
                }
            }
            found.sort_by(|a, b| a.0.t.total_cmp(&b.0.t));
            if let Some(k) = found.iter().position(|(c, _)| events[c.event].stops()) {
                found.truncate(k + 1);
                stop_at = Some(found[k].1);
            }
            run.crossings.extend(found.iter().map(|(c, _)| c.clone()));
        }
        let stop_t = match stop_at {
            Some(_) => run.crossings.last().map_or(f64::INFINITY, |c| c.t),
            None => f64::INFINITY,
        };
        // Output times and t_end in this step, each the zero of t(τ) − target on the curve.
        let limit = t_b.min(stop_t);
        loop {
            let target = next_output(k_out).min(t_end);
            if target > limit || target == f64::INFINITY {
                break;
            }
            let mut f = |x: f64| t_a + clock.partial(&curve, basis, tt, x) - target;
            let tau = if target >= t_b {
                1.0
            } else {
                illinois(&mut f, (0.0, t_a - target), (1.0, t_b - target), tau_tol)
            };
            probe.state(&curve, basis, tt, tau);
            let located = OutputState {
                t: target,
                s: curve.start_time() + tau * curve.h(),
                q: probe.at.q.clone(),
                p: probe.at.p.clone(),
                step,
                dt,
            };
            if next_output(k_out) <= target {
                run.outputs.push(located.clone());
                k_out += 1;
            }
            if target == t_end {
                run.end = located;
                if options.keep_steps {
                    let mut end = run.end.clone();
                    end.step = step + 1;
                    run.step_ends.push(end);
                }
                run.end.step = step + 1;
                return Ok(run);
            }
        }
        if let (Some(tau), Some(c)) = (stop_at, run.crossings.last()) {
            let s = curve.start_time() + curve.h() * tau;
            run.end = OutputState {
                t: c.t,
                s,
                q: c.q.clone(),
                p: c.p.clone(),
                step: step + 1,
                dt,
            };
            if options.keep_steps {
                run.step_ends.push(run.end.clone());
            }
            run.stopped = true;
            return Ok(run);
        }
        run.end = OutputState {
            t: t_b,
            s: stepper.fictitious_time(),
            q: stepper.position().to_vec(),
            p: stepper.momentum().to_vec(),
            step: step + 1,
            dt,
        };
        if options.keep_steps {
            run.step_ends.push(run.end.clone());
        }
    }
}
