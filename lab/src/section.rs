//! Poincaré sections and stroboscopic maps (`gvi section`): the crossings of an event g(t, q, p)
//! = 0 located on the Galerkin curves (galerkin_vi::events), for one orbit or a fan of orbits
//! on one energy surface, run in parallel.

use crate::error::{LabError, Result};
use crate::plot::{Chart, Series};
use crate::scene::BuiltScene;
use galerkin_vi::events::{
    Direction, Event, EventFunction, EventOptions, ExpressionEvent, integrate_with_events,
};
use galerkin_vi::systems::{AnySystem, System};
use rayon::prelude::*;

/// What defines the section.
#[derive(Debug, Clone)]
pub enum SectionEvent {
    /// g(t, q, p) = 0 crossed in this direction (an expression over the names).
    Expression(String, Direction),
    /// The stroboscopic map t = t0 + k·period.
    Every(f64),
}

/// How to pick the initial states: the scene's, or `orbits` values of one component spread
/// over a range, with another component solved for an energy.
#[derive(Debug, Clone, Default)]
pub struct Fan {
    /// Number of orbits (≥ 1).
    pub orbits: usize,
    /// A component (coordinate name or `p_<name>`) and its range [a, b].
    pub vary: Option<(String, f64, f64)>,
    /// The energy of every orbit, reached by solving for `solve`.
    pub energy: Option<f64>,
    /// The component solved for the energy (its sign taken from the scene's state).
    pub solve: Option<String>,
}

/// One point of the section.
#[derive(Debug, Clone)]
pub struct SectionPoint {
    /// The orbit it belongs to.
    pub orbit: usize,
    /// Its time.
    pub t: f64,
    /// The state there.
    pub q: Vec<f64>,
    /// See `q`.
    pub p: Vec<f64>,
}

/// The section of every orbit, and the orbits that failed (with the crossings found before).
#[derive(Debug, Default)]
pub struct Section {
    /// The names of q and p (coordinate names and `p_<name>`).
    pub names: Vec<String>,
    /// The points, orbit by orbit in time order.
    pub points: Vec<SectionPoint>,
    /// Initial states used, per orbit.
    pub starts: Vec<State>,
    /// Orbits skipped (no state at that energy) or failed, with why.
    pub notes: Vec<String>,
    /// Whether some orbit failed (its points up to the failure are kept).
    pub failed: bool,
}

/// Coordinate names of a scene's system (its own for expression scenes, q0, q1, … otherwise:
/// [`crate::names::coordinate_names`]) and its parameters.
pub fn names_of(system: &AnySystem) -> (Vec<String>, Vec<(String, f64)>) {
    let params = system
        .as_expression()
        .map(|e| e.parameters().to_vec())
        .unwrap_or_default();
    (crate::names::coordinate_names(system), params)
}

use crate::names::momentum_name;

/// Index into (q, p) of a component name: (is momentum, index).
fn component(names: &[String], name: &str) -> Result<(bool, usize)> {
    if let Some(i) = names.iter().position(|c| c == name) {
        return Ok((false, i));
    }
    if let Some(i) = names.iter().position(|c| momentum_name(c) == name) {
        return Ok((true, i));
    }
    Err(LabError::InvalidArgument {
        name: "--vary/--solve/--axes".into(),
        reason: format!(
            "unknown component `{name}`; known: {}",
            names
                .iter()
                .flat_map(|c| [c.clone(), momentum_name(c)])
                .collect::<Vec<_>>()
                .join(", ")
        ),
    })
}

/// The energy E(q, p) of the system, when it reports one.
fn energy(system: &AnySystem, q: &[f64], p: &[f64]) -> Option<f64> {
    let idx = system
        .invariant_names()
        .iter()
        .position(|n| *n == "energy")?;
    let mut inv = vec![0.0; system.invariant_names().len()];
    system.invariants(q, p, &mut inv);
    inv.get(idx).copied().filter(|e| e.is_finite())
}

/// Solve E(q, p) = target for the component `(mom, i)` on the side of zero given by `sign`:
/// bracket from 0 outwards, then bisect. `None` when E(component = 0) is already above the
/// target or no bracket is found (the energy surface does not cross this line).
fn solve_energy(
    system: &AnySystem,
    (q, p): (&mut [f64], &mut [f64]),
    (mom, i): (bool, usize),
    target: f64,
    sign: f64,
) -> Option<()> {
    let eval = |s: f64, q: &mut [f64], p: &mut [f64]| {
        if mom {
            p[i] = s
        } else {
            q[i] = s
        }
        energy(system, q, p).map(|e| e - target)
    };
    let f0 = eval(0.0, q, p)?;
    if f0 > 0.0 {
        return None;
    }
    let (mut lo, mut hi) = (0.0, sign);
    let mut found = false;
    for _ in 0..60 {
        match eval(hi, q, p) {
            Some(f) if f > 0.0 => {
                found = true;
                break;
            }
            Some(_) => {
                lo = hi;
                hi *= 2.0;
            }
            None => hi = 0.5 * (lo + hi),
        }
    }
    if !found {
        return None;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid == lo || mid == hi {
            break;
        }
        match eval(mid, q, p) {
            Some(f) if f > 0.0 => hi = mid,
            Some(_) => lo = mid,
            None => hi = mid,
        }
    }
    eval(lo, q, p).map(|_| ())
}

/// An initial state (q, p).
type State = (Vec<f64>, Vec<f64>);

/// The initial states of the fan, and notes on the orbits skipped.
fn starts(scene: &BuiltScene, names: &[String], fan: &Fan) -> Result<(Vec<State>, Vec<String>)> {
    let system = scene.euclidean()?;
    let (q0, p0) = (&scene.initial.q, &scene.initial.p);
    let k = fan.orbits.max(1);
    let mut states = Vec::with_capacity(k);
    let mut notes = Vec::new();
    let vary = match &fan.vary {
        Some((name, a, b)) => Some((component(names, name)?, *a, *b)),
        None => None,
    };
    let solve = match (&fan.solve, fan.energy) {
        (Some(name), Some(e)) => {
            if energy(system, q0, p0).is_none() {
                return Err(LabError::InvalidArgument {
                    name: "--energy".into(),
                    reason: "the scene's system reports no energy (forced or time-dependent \
                             systems have none)"
                        .into(),
                });
            }
            Some((component(names, name)?, e))
        }
        (None, None) => None,
        _ => {
            return Err(LabError::InvalidArgument {
                name: "--energy/--solve".into(),
                reason: "give both: the energy and the component solved for it".into(),
            });
        }
    };
    for j in 0..k {
        let (mut q, mut p) = (q0.clone(), p0.clone());
        if let Some(((mom, i), a, b)) = vary {
            let s = if k == 1 {
                a
            } else {
                a + (b - a) * j as f64 / (k - 1) as f64
            };
            if mom { p[i] = s } else { q[i] = s }
        }
        if let Some(((mom, i), e)) = solve {
            let now = if mom { p0[i] } else { q0[i] };
            let sign = if now < 0.0 { -1.0 } else { 1.0 };
            if solve_energy(system, (&mut q, &mut p), (mom, i), e, sign).is_none() {
                notes.push(format!(
                    "orbit {j}: no state with energy {e} on this line (skipped)"
                ));
                continue;
            }
        }
        states.push((q, p));
    }
    Ok((states, notes))
}

/// Run the section: every orbit from its start to t0 + steps·h, in parallel.
pub fn run_section(scene: &BuiltScene, event: &SectionEvent, fan: &Fan) -> Result<Section> {
    let system = scene.euclidean()?;
    let (names, params) = names_of(system);
    let gvi = scene.method.integrator()?;
    let t0 = scene.initial.t0;
    let t_end = t0 + scene.method.h * scene.method.steps as f64;
    let coords: Vec<&str> = names.iter().map(String::as_str).collect();
    let pars: Vec<(&str, f64)> = params.iter().map(|(n, v)| (n.as_str(), *v)).collect();
    let (g, direction): (Box<dyn EventFunction + Sync>, Direction) = match event {
        SectionEvent::Expression(text, dir) => {
            // Momenta are named p_<name> (p0, p1, … for q0, q1, …).
            let text = rename_numbered_momenta(text, &names);
            (
                Box::new(ExpressionEvent::parse(&text, &coords, &pars)?),
                *dir,
            )
        }
        SectionEvent::Every(period) => {
            if !(period.is_finite() && *period > 0.0) {
                return Err(LabError::InvalidArgument {
                    name: "--every".into(),
                    reason: format!("the period must be positive and finite, not {period}"),
                });
            }
            let (t0, period) = (t0, *period);
            // Zero at t0 + k·period, with alternating slopes: both directions.
            let strobe = move |t: f64, _: &[f64], _: &[f64]| {
                (std::f64::consts::PI * (t - t0) / period).sin()
            };
            (Box::new(strobe), Direction::Either)
        }
    };
    let (states, notes) = starts(scene, &names, fan)?;
    let bar = crate::progress::bar(states.len(), "section");
    let results: Vec<_> = states
        .par_iter()
        .enumerate()
        .map(|(j, (q, p))| {
            let mut events =
                [
                    Event::new("section", |t: f64, q: &[f64], p: &[f64]| g.value(t, q, p))
                        .direction(direction),
                ];
            let r = integrate_with_events(
                &gvi,
                system,
                t0,
                q,
                p,
                t_end,
                &mut events,
                &EventOptions::default(),
            );
            bar.inc(1);
            (j, r)
        })
        .collect();
    bar.finish_and_clear();
    let mut section = Section {
        names: names
            .iter()
            .cloned()
            .chain(names.iter().map(|c| momentum_name(c)))
            .collect(),
        notes,
        ..Section::default()
    };
    for (j, r) in results {
        let run = match r {
            Ok(run) => run,
            Err(f) => {
                section.failed = true;
                section.notes.push(format!("orbit {j} failed: {}", f.error));
                *f.partial
            }
        };
        section
            .points
            .extend(run.crossings.into_iter().map(|c| SectionPoint {
                orbit: j,
                t: c.t,
                q: c.q,
                p: c.p,
            }));
    }
    section.starts = states;
    Ok(section)
}

/// `p0`, `p1`, … are momenta of the default names q0, q1, …; the expressions know them as
/// `p_q0`, …, so rewrite whole-word occurrences.
fn rename_numbered_momenta(text: &str, names: &[String]) -> String {
    let mut out = text.to_string();
    for c in names {
        let m = momentum_name(c);
        if m.starts_with("p_") {
            continue;
        }
        let mut rebuilt = String::new();
        let mut rest = out.as_str();
        while let Some(at) = rest.find(&m) {
            let before_ok = rest[..at]
                .chars()
                .last()
                .is_none_or(|ch| !(ch.is_ascii_alphanumeric() || ch == '_'));
            let after = &rest[at + m.len()..];
            let after_ok = after
                .chars()
                .next()
                .is_none_or(|ch| !(ch.is_ascii_alphanumeric() || ch == '_'));
            rebuilt.push_str(&rest[..at]);
            let renamed = format!("p_{c}");
            rebuilt.push_str(if before_ok && after_ok { &renamed } else { &m });
            rest = after;
        }
        rebuilt.push_str(rest);
        out = rebuilt;
    }
    out
}

impl Section {
    /// CSV: orbit, t, then q and p by name.
    pub fn to_csv(&self) -> Result<String> {
        let mut header = vec!["orbit".to_string(), "t".to_string()];
        header.extend(self.names.iter().cloned());
        let rows = self.points.iter().map(|pt| {
            let mut row = vec![pt.orbit.to_string(), crate::table::number(pt.t)];
            row.extend(pt.q.iter().chain(&pt.p).map(|x| crate::table::number(*x)));
            row
        });
        crate::table::csv_records(&header, rows)
    }

    /// The chart of two components, one colour per orbit.
    pub fn chart(&self, title: &str, axes: (&str, &str)) -> Result<Chart> {
        let idx = |name: &str| {
            self.names
                .iter()
                .position(|n| n == name)
                .ok_or_else(|| LabError::InvalidArgument {
                    name: "--axes".into(),
                    reason: format!(
                        "unknown component `{name}`; known: {}",
                        self.names.join(", ")
                    ),
                })
        };
        let (a, b) = (idx(axes.0)?, idx(axes.1)?);
        let d = self.names.len() / 2;
        let value = |pt: &SectionPoint, i: usize| if i < d { pt.q[i] } else { pt.p[i - d] };
        let mut chart = Chart::new(title, axes.0, axes.1).size(900, 800);
        let orbits = self.starts.len();
        for j in 0..orbits {
            let pts: Vec<(f64, f64)> = self
                .points
                .iter()
                .filter(|pt| pt.orbit == j)
                .map(|pt| (value(pt, a), value(pt, b)))
                .collect();
            // A fan of orbits is told apart by colour; a legend of many entries would only
            // cover the section.
            let label = if orbits <= 4 {
                format!("orbit {j}")
            } else {
                String::new()
            };
            if !pts.is_empty() {
                chart.push(Series::markers(label, pts).with_color(j));
            }
        }
        Ok(chart)
    }
}
