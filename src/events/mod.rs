//! Events on the Galerkin curve: zero crossings of a function g(t, q, p), located on each
//! step's curve — the dense output the method already computes — with a direction filter and
//! an action (record, stop, or apply a map to the state and restart).
//!
//! A fixed-step method with large steps (the spectral method's h is a sizeable part of an
//! orbit) cannot find events by looking at the step ends: a close approach, or a coordinate
//! that crosses a level and returns within one step, is invisible there. Here each step's
//! curve q(t), with p(t) = ∂L/∂v(q(t), q̇(t)), is sampled at `samples_per_step` equally spaced
//! times, and a sign change of g between two samples is refined by regula falsi (Illinois)
//! on the curve itself to a local-time tolerance of a few ulps. When nothing crosses, an
//! event costs `samples_per_step` evaluations of the curve and of g per step, O(1) in the
//! length of the run, and nothing is allocated.
//!
//! Two entry points: [`integrate_with_events`] steps a [`Stepper`](crate::integrator::Stepper)
//! and acts on the events as they occur; [`crossings_on_trajectory`] scans a stored
//! [`Trajectory`] afterwards (record only).
//!
//! ```
//! use galerkin_vi::events::{Event, EventOptions, integrate_with_events};
//! use galerkin_vi::prelude::*;
//!
//! // q = cos t: the downward zero crossings of q are at t = π/2 + 2πk.
//! let ho = HarmonicOscillator::unit();
//! let gvi = GalerkinIntegrator::spectral(14, 1.0)?;
//! let mut events = [Event::new("q = 0", |_t: f64, q: &[f64], _p: &[f64]| q[0]).falling()];
//! let run = integrate_with_events(&gvi, &ho, 0.0, &[1.0], &[0.0], 10.0, &mut events,
//!                                 &EventOptions::default())?;
//! let t: Vec<f64> = run.crossings.iter().map(|c| c.t).collect();
//! assert_eq!(t.len(), 2);
//! assert!((t[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-11);
//! assert!((t[1] - 2.5 * std::f64::consts::PI).abs() < 1e-11);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod encounter;
mod expression;
mod locate;
#[cfg(test)]
mod tests;

pub use encounter::close_encounter;
pub use expression::ExpressionEvent;

use crate::basis::Basis;
use crate::curve::GalerkinCurveRef;
use crate::error::{GviError, Result, ensure_finite};
use crate::integrator::GalerkinIntegrator;
use crate::lagrangian::Lagrangian;
use crate::quadrature::Quadrature;
use crate::trajectory::Trajectory;
use locate::refine;
// The curve probe and the root finder serve the time-transformed runs too (`time_transform`).
pub(crate) use locate::{CurveProbe, illinois};

/// A function g(t, q, p) whose zeros are the events; implemented by closures
/// `Fn(f64, &[f64], &[f64]) -> f64`.
pub trait EventFunction {
    /// g at time t and state (q, p).
    fn value(&self, t: f64, q: &[f64], p: &[f64]) -> f64;
}

impl<F: Fn(f64, &[f64], &[f64]) -> f64> EventFunction for F {
    fn value(&self, t: f64, q: &[f64], p: &[f64]) -> f64 {
        self(t, q, p)
    }
}

/// Which crossings of zero count.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// g goes from negative to positive.
    Rising,
    /// g goes from positive to negative.
    Falling,
    /// Both.
    Either,
}

impl Direction {
    fn accepts(self, rising: bool) -> bool {
        match self {
            Direction::Rising => rising,
            Direction::Falling => !rising,
            Direction::Either => true,
        }
    }
}

/// A map applied to the state at an event: `(t, q, p)` with q and p to be changed in place.
pub type EventMap<'a> = Box<dyn FnMut(f64, &mut [f64], &mut [f64]) + 'a>;

/// What happens at an event.
pub enum Action<'a> {
    /// Record the crossing and go on.
    Record,
    /// Record it and stop the run there (the run's final state is the event's).
    Stop,
    /// Record it, apply the map to the state at the event and restart from the mapped state
    /// (an impact, a velocity kick, a switch).
    Apply(EventMap<'a>),
}

impl std::fmt::Debug for Action<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Action::Record => "Record",
            Action::Stop => "Stop",
            Action::Apply(_) => "Apply(..)",
        })
    }
}

/// One event: a name, its function g, the crossings that count and the action.
pub struct Event<'a> {
    name: String,
    function: Box<dyn EventFunction + 'a>,
    direction: Direction,
    action: Action<'a>,
}

impl std::fmt::Debug for Event<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Event")
            .field("name", &self.name)
            .field("direction", &self.direction)
            .field("action", &self.action)
            .finish()
    }
}

impl<'a> Event<'a> {
    /// An event at the zeros of g, either direction, recorded.
    pub fn new(name: impl Into<String>, g: impl EventFunction + 'a) -> Self {
        Event {
            name: name.into(),
            function: Box::new(g),
            direction: Direction::Either,
            action: Action::Record,
        }
    }

    /// Only crossings from negative to positive.
    pub fn rising(self) -> Self {
        self.direction(Direction::Rising)
    }

    /// Only crossings from positive to negative.
    pub fn falling(self) -> Self {
        self.direction(Direction::Falling)
    }

    /// The crossings that count.
    pub fn direction(mut self, direction: Direction) -> Self {
        self.direction = direction;
        self
    }

    /// Stop the run at the first crossing that counts.
    pub fn stop(mut self) -> Self {
        self.action = Action::Stop;
        self
    }

    /// At each crossing that counts, apply `map` to (t, q, p) and restart from there.
    pub fn apply(mut self, map: impl FnMut(f64, &mut [f64], &mut [f64]) + 'a) -> Self {
        self.action = Action::Apply(Box::new(map));
        self
    }

    /// The event's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// g(t, q, p).
    pub(crate) fn evaluate(&self, t: f64, q: &[f64], p: &[f64]) -> f64 {
        self.function.value(t, q, p)
    }

    /// Whether a crossing in this direction counts.
    pub(crate) fn accepts(&self, rising: bool) -> bool {
        self.direction.accepts(rising)
    }

    /// Whether the event stops the run.
    pub(crate) fn stops(&self) -> bool {
        matches!(self.action, Action::Stop)
    }

    /// Whether the event maps the state.
    pub(crate) fn maps(&self) -> bool {
        matches!(self.action, Action::Apply(_))
    }
}

/// How events are looked for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EventOptions {
    /// Equally spaced samples of g on each step's curve (≥ 1; 1 looks at step ends only). Two
    /// crossings closer than h / samples_per_step can cancel; raise it for events that come
    /// and go faster than that. Default 8.
    pub samples_per_step: usize,
    /// Tolerance of the located time, as a fraction of h (default 4ε: the root is located to
    /// the resolution of the curve's local time).
    pub local_time_tolerance: f64,
}

impl Default for EventOptions {
    fn default() -> Self {
        EventOptions {
            samples_per_step: 8,
            local_time_tolerance: 4.0 * f64::EPSILON,
        }
    }
}

impl EventOptions {
    pub(crate) fn validate(&self) -> Result<()> {
        if self.samples_per_step == 0 {
            return Err(GviError::InvalidInput {
                name: "samples_per_step".into(),
                reason: "must be at least 1".into(),
            });
        }
        let tol = self.local_time_tolerance;
        if !(tol.is_finite() && tol > 0.0 && tol < 1.0) {
            return Err(GviError::InvalidParameter {
                name: "local_time_tolerance".into(),
                value: tol,
                reason: "must be in (0, 1)".into(),
            });
        }
        Ok(())
    }
}

/// A located crossing.
#[derive(Debug, Clone, PartialEq)]
pub struct Crossing {
    /// Index of the event in the slice given.
    pub event: usize,
    /// Its name.
    pub name: String,
    /// The time of the zero of g on the curve.
    pub t: f64,
    /// The state on the curve there: q(t) …
    pub q: Vec<f64>,
    /// … and p(t) = ∂L/∂v(q(t), q̇(t)).
    pub p: Vec<f64>,
    /// The step (counted from the run's start, restarts included) whose curve holds it.
    pub step: usize,
    /// Whether g went from negative to positive.
    pub rising: bool,
}

/// The result of [`integrate_with_events`].
#[derive(Debug, Clone, PartialEq)]
pub struct EventRun {
    /// Every crossing that counted, in time order.
    pub crossings: Vec<Crossing>,
    /// The final time: the end of the last step (at or just past t_end), or the stopping
    /// event's time.
    pub t: f64,
    /// The final position …
    pub q: Vec<f64>,
    /// … and momentum.
    pub p: Vec<f64>,
    /// Steps taken.
    pub steps: usize,
    /// Whether an event with [`Action::Stop`] ended the run.
    pub stopped: bool,
    /// Evaluations of the curve's state with the event functions on it (samples and root
    /// finding): `samples_per_step` per step when nothing crosses.
    pub curve_evaluations: usize,
}

/// A run with events that failed: the error (a step's solver failure naming the step, a
/// non-finite g or map) and the run up to the last completed step.
#[derive(Debug)]
pub struct EventFailure {
    /// What went wrong.
    pub error: GviError,
    /// The run before it (boxed: a failure stays small).
    pub partial: Box<EventRun>,
}

impl std::fmt::Display for EventFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} (kept: {} steps to t = {}, {} crossings)",
            self.error,
            self.partial.steps,
            self.partial.t,
            self.partial.crossings.len()
        )
    }
}

impl std::error::Error for EventFailure {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.error)
    }
}

impl EventRun {
    /// A run that has not started (no state: t is NaN).
    fn empty() -> Self {
        EventRun {
            crossings: Vec::new(),
            t: f64::NAN,
            q: Vec::new(),
            p: Vec::new(),
            steps: 0,
            stopped: false,
            curve_evaluations: 0,
        }
    }
}

impl From<GviError> for EventFailure {
    /// A failure before the first step (nothing computed).
    fn from(error: GviError) -> Self {
        EventFailure {
            error,
            partial: Box::new(EventRun::empty()),
        }
    }
}

/// The sign-change scan of a run: the previous sample of every g, the probe's buffers.
struct Scanner {
    probe: CurveProbe,
    /// g at the previous sample; 0 means "no sign yet" (an event that is exactly zero at the
    /// start, or the event just acted on): the next sample sets it without a crossing.
    previous: Vec<f64>,
    /// g at the current sample.
    current: Vec<f64>,
    options: EventOptions,
}

impl Scanner {
    fn new(n: usize, d: usize, events: usize, options: EventOptions) -> Self {
        Scanner {
            probe: CurveProbe::new(n, d),
            previous: vec![0.0; events],
            current: vec![0.0; events],
            options,
        }
    }

    /// g of every event at (t, q, p), into `previous` (the start of a run or a restart).
    fn start(&mut self, events: &[Event<'_>], t: f64, q: &[f64], p: &[f64]) -> Result<()> {
        for (e, event) in events.iter().enumerate() {
            let g = event.function.value(t, q, p);
            if !g.is_finite() {
                return Err(GviError::NonFinite {
                    what: format!("event '{}' at t = {t}", event.name),
                    value: g,
                });
            }
            self.previous[e] = g;
        }
        Ok(())
    }

    /// Scan one step's curve; crossings that count are appended to `found` in time order —
    /// with `act`, up to and including the first whose event acts (its index in `found` is
    /// returned). Crossings after `t_end` are not reported.
    #[allow(clippy::too_many_arguments)]
    fn scan<B: Basis + ?Sized, L: Lagrangian>(
        &mut self,
        curve: &GalerkinCurveRef<'_>,
        basis: &B,
        lag: &L,
        events: &[Event<'_>],
        step: usize,
        t_end: f64,
        act: bool,
        found: &mut Vec<Crossing>,
    ) -> Result<Option<usize>> {
        let samples = self.options.samples_per_step;
        let mut tau_prev = 0.0;
        for j in 1..=samples {
            let tau = j as f64 / samples as f64;
            let t = self.probe.state(curve, basis, lag, tau);
            self.probe.evaluations += 1;
            for (e, event) in events.iter().enumerate() {
                let g = event.function.value(t, &self.probe.q, &self.probe.p);
                if !g.is_finite() {
                    return Err(GviError::NonFinite {
                        what: format!(
                            "event '{}' on the curve of step {step} at t = {t}",
                            event.name
                        ),
                        value: g,
                    });
                }
                self.current[e] = g;
            }
            // Crossings in this interval, each located, then taken in time order.
            let first = found.len();
            for (e, event) in events.iter().enumerate() {
                let (ga, gb) = (self.previous[e], self.current[e]);
                let crosses = ga != 0.0 && (gb == 0.0 || (ga < 0.0) != (gb < 0.0));
                let rising = ga < 0.0;
                if !crosses || !event.direction.accepts(rising) {
                    continue;
                }
                let tau_root = refine(
                    &mut self.probe,
                    curve,
                    basis,
                    lag,
                    event.function.as_ref(),
                    (tau_prev, ga),
                    (tau, gb),
                    self.options.local_time_tolerance,
                );
                let t_root = curve.start_time() + tau_root * curve.h();
                if t_root > t_end {
                    continue;
                }
                found.push(Crossing {
                    event: e,
                    name: event.name.clone(),
                    t: t_root,
                    q: self.probe.q.clone(),
                    p: self.probe.p.clone(),
                    step,
                    rising,
                });
            }
            found[first..].sort_by(|a, b| a.t.total_cmp(&b.t));
            if let Some(k) = (first..found.len())
                .find(|&k| act && !matches!(events[found[k].event].action, Action::Record))
            {
                found.truncate(k + 1);
                return Ok(Some(k));
            }
            std::mem::swap(&mut self.previous, &mut self.current);
            tau_prev = tau;
        }
        Ok(None)
    }
}

/// Integrate from (q0, p0) at t0 to t_end with `gvi`, locating the zeros of each event's g
/// on every step's Galerkin curve and acting on them (see the [module](self) docs).
///
/// The run ends at the first step end at or past t_end (the step size is fixed), or at an
/// event with [`Action::Stop`]. After an [`Action::Apply`] the stepper restarts from the
/// mapped state at the event's time (so later steps are no longer on the grid t0 + k h), and
/// that event's sign is taken afresh from the next sample (a crossing of the same event
/// within the first h / samples_per_step after the restart is not seen). An event that is
/// exactly zero at t0 is not reported there.
///
/// Errors (with the run so far in [`EventFailure::partial`]): invalid options or t_end, a g
/// that is not finite at the start or on a curve, a map that makes the state non-finite, a
/// step whose solver fails (naming the step and the residual).
#[allow(clippy::too_many_arguments)]
pub fn integrate_with_events<B: Basis, Q: Quadrature, L: Lagrangian>(
    gvi: &GalerkinIntegrator<B, Q>,
    lag: &L,
    t0: f64,
    q0: &[f64],
    p0: &[f64],
    t_end: f64,
    events: &mut [Event<'_>],
    options: &EventOptions,
) -> std::result::Result<EventRun, EventFailure> {
    options.validate()?;
    if !(t_end.is_finite() && t_end >= t0) {
        return Err(GviError::InvalidParameter {
            name: "t_end".into(),
            value: t_end,
            reason: format!("must be finite and at least t0 = {t0}"),
        }
        .into());
    }
    let mut stepper = gvi.stepper(lag, t0, q0, p0)?;
    let mut scanner = Scanner::new(gvi.n(), lag.dim(), events.len(), *options);
    scanner.start(events, t0, q0, p0)?;
    let mut run = EventRun {
        crossings: Vec::new(),
        t: t0,
        q: q0.to_vec(),
        p: p0.to_vec(),
        steps: 0,
        stopped: false,
        curve_evaluations: 0,
    };
    let h = gvi.step_size();
    // The last step may end past t_end by round-off of the grid; not by a whole step.
    let end = t_end - 1e-12 * h;
    let fail = |error: GviError, run: &mut EventRun, scanner: &Scanner| {
        run.curve_evaluations = scanner.probe.evaluations;
        EventFailure {
            error,
            partial: Box::new(std::mem::replace(run, EventRun::empty())),
        }
    };
    while stepper.time() < end {
        if let Err(e) = stepper.step() {
            return Err(fail(e, &mut run, &scanner));
        }
        run.steps += 1;
        let acted = {
            let curve = stepper.curve();
            scanner.scan(
                &curve,
                gvi.basis(),
                lag,
                events,
                run.steps - 1,
                t_end,
                true,
                &mut run.crossings,
            )
        };
        let acted = match acted {
            Ok(a) => a,
            Err(e) => return Err(fail(e, &mut run, &scanner)),
        };
        let Some(k) = acted else {
            continue;
        };
        let crossing = &run.crossings[k];
        let (t, mut q, mut p) = (crossing.t, crossing.q.clone(), crossing.p.clone());
        let e = crossing.event;
        match &mut events[e].action {
            Action::Record => {}
            Action::Stop => {
                (run.t, run.q, run.p) = (t, q, p);
                run.stopped = true;
                run.curve_evaluations = scanner.probe.evaluations;
                return Ok(run);
            }
            Action::Apply(map) => {
                map(t, &mut q, &mut p);
                let restarted = ensure_finite("state after the event map", &q)
                    .and_then(|_| ensure_finite("state after the event map", &p))
                    .and_then(|_| stepper.set_state(t, &q, &p))
                    .and_then(|_| scanner.start(events, t, &q, &p));
                if let Err(err) = restarted {
                    return Err(fail(err, &mut run, &scanner));
                }
                scanner.previous[e] = 0.0;
            }
        }
    }
    run.t = stepper.time();
    run.q.copy_from_slice(stepper.position());
    run.p.copy_from_slice(stepper.momentum());
    run.curve_evaluations = scanner.probe.evaluations;
    Ok(run)
}

/// The crossings of each event's g along a stored trajectory's Galerkin curves (record
/// only: the events' actions are ignored), in time order.
///
/// Errors: invalid options, a Lagrangian of another dimension, a trajectory without its
/// basis (a deserialised user's basis not attached), a g that is not finite.
pub fn crossings_on_trajectory<L: Lagrangian>(
    trajectory: &Trajectory,
    lag: &L,
    events: &[Event<'_>],
    options: &EventOptions,
) -> Result<Vec<Crossing>> {
    options.validate()?;
    crate::error::ensure_len("Lagrangian dimension", trajectory.dim, lag.dim())?;
    let max_n = (0..trajectory.steps())
        .map(|k| trajectory.n_of_step(k))
        .max()
        .unwrap_or(1);
    let mut scanner = Scanner::new(max_n, lag.dim(), events.len(), *options);
    scanner.start(
        events,
        trajectory.time(0),
        &trajectory.q[0],
        &trajectory.p[0],
    )?;
    let mut found = Vec::new();
    let t_end = trajectory.end_time();
    for k in 0..trajectory.steps() {
        let curve = trajectory.curve(k)?;
        let basis = trajectory.basis_with(curve.n())?;
        scanner.scan(&curve, basis, lag, events, k, t_end, false, &mut found)?;
    }
    Ok(found)
}
