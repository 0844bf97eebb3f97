//! What a run watches at every step end: the first non-finite value (a typed failure, the
//! steps before it kept), the invariant drifts (absolute and relative), the position error
//! against an exact solution, and for point masses the closest approach of two bodies.
//!
//! The same monitor serves the in-memory table ([`super::run_scene`]) and the streamed one
//! ([`super::stream`]), so both report the same figures.

use crate::energy::energy_scale;
use crate::error::LabError;
use crate::error::{GviError, Result};
use galerkin_vi::systems::{ExactSolution, NBody, System};

/// Relative error above which a run's result is called untrustworthy: a warning on stderr,
/// an error with `--strict`. A 1 % drift of the energy or of the position is far outside any
/// accuracy the method is used for, and inside what an escaped orbit or a blown-up step
/// produces.
pub const SANITY_THRESHOLD: f64 = 1e-2;

/// Closest approach of two bodies over a run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Encounter {
    /// First body.
    pub a: String,
    /// Second body.
    pub b: String,
    /// Smallest separation, on the Galerkin curves (each step's curve is searched between
    /// its ends, `Monitor::closest_on_curve`) or at a step end.
    pub separation: f64,
    /// Its time.
    pub t: f64,
    /// How far the pair moved relative to each other over the step that ended there. When
    /// this exceeds the separation the step cannot resolve the encounter.
    pub relative_step: f64,
}

/// Running figures of a run, updated at each step end.
pub(crate) struct Monitor {
    names: Vec<String>,
    inv0: Vec<f64>,
    inv: Vec<f64>,
    /// Max |I(t_k) − I(t_0)|.
    pub inv_err: Vec<f64>,
    /// Max position error at step ends (max norm), if an exact solution is known.
    pub max_pos: Option<f64>,
    /// Max |q_exact(t_k)|∞, the scale of the relative position error.
    pub pos_scale: f64,
    bodies: Option<Vec<String>>,
    spatial: usize,
    previous_q: Vec<f64>,
    /// The closest approach so far (N-body systems).
    pub encounter: Option<Encounter>,
    /// Initial separation of each pair (a, b > a), row-major over a.
    initial_separation: Vec<f64>,
    /// The scale of the relative energy error and how it was taken
    /// ([`crate::energy::energy_scale`]).
    pub energy_scale: Option<(&'static str, f64)>,
    /// The first close encounter the step cannot resolve: a pair within a tenth of its
    /// initial separation that moved more than its separation relative to each other in the
    /// step that ended there. (Ordinary orbital motion over long spectral steps, such as the
    /// paper's solar-system run with h = 100 d, is not an encounter: the pairs stay far apart
    /// relative to where they started.)
    pub unresolved: Option<Encounter>,
}

/// Fraction of a pair's initial separation below which an approach is a close encounter.
const ENCOUNTER_FRACTION: f64 = 0.1;

impl Monitor {
    /// Start at (q0, p0); rejects coincident bodies.
    pub fn new<S: System>(system: &S, q0: &[f64], p0: &[f64], t0: f64) -> Result<Self> {
        let names: Vec<String> = system
            .invariant_names()
            .iter()
            .map(|s| s.to_string())
            .collect();
        let mut inv0 = vec![0.0; names.len()];
        system.invariants(q0, p0, &mut inv0);
        let bodies = system.body_names();
        let spatial = bodies.as_ref().map_or(0, |b| system.dim() / b.len().max(1));
        // Coincident bodies first: their infinite energy is a collision, not bad input.
        let mut m = Monitor {
            inv: vec![0.0; names.len()],
            inv_err: vec![0.0; names.len()],
            names,
            inv0,
            max_pos: None,
            pos_scale: 0.0,
            bodies,
            spatial,
            previous_q: q0.to_vec(),
            encounter: None,
            initial_separation: Vec::new(),
            unresolved: None,
            energy_scale: None,
        };
        m.closest(q0, 0, t0)?;
        for (name, &v) in m.names.iter().zip(&m.inv0) {
            if !v.is_finite() {
                return Err(GviError::NonFinite {
                    what: format!("initial {name} (check the initial state and parameters)"),
                    value: v,
                }
                .into());
            }
        }
        let e0 = m
            .names
            .iter()
            .position(|n| n == "energy")
            .map(|i| m.inv0[i]);
        m.energy_scale = e0.map(|e0| energy_scale(system, q0, p0, e0));
        Ok(m)
    }

    #[allow(clippy::too_many_arguments)]
    /// Observe step end k at time t; appends the invariants (and position error) to `row`
    /// after the state. Fails at the first non-finite value or coincident bodies.
    pub fn observe<S: System>(
        &mut self,
        system: &S,
        exact: Option<&ExactSolution>,
        k: usize,
        t: f64,
        q: &[f64],
        p: &[f64],
        row: &mut Vec<f64>,
    ) -> Result<()> {
        let nonfinite = |what: String, value: f64| -> LabError {
            GviError::NonFiniteResult {
                what,
                value,
                step: k,
                t,
            }
            .into()
        };
        if !t.is_finite() {
            return Err(nonfinite("time".into(), t));
        }
        for (i, &x) in q.iter().enumerate() {
            if !x.is_finite() {
                return Err(nonfinite(format!("position q{i}"), x));
            }
        }
        for (i, &x) in p.iter().enumerate() {
            if !x.is_finite() {
                return Err(nonfinite(format!("momentum p{i}"), x));
            }
        }
        system.invariants(q, p, &mut self.inv);
        for i in 0..self.inv.len() {
            let v = self.inv[i];
            let e = (v - self.inv0[i]).abs();
            if !e.is_finite() {
                return Err(nonfinite(self.names[i].clone(), v));
            }
            self.inv_err[i] = self.inv_err[i].max(e);
        }
        row.extend_from_slice(&self.inv);
        if let Some(ex) = exact {
            let qe = ex.position(t);
            let e = q
                .iter()
                .zip(&qe)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, crate::distance::nan_max);
            if !e.is_finite() {
                return Err(nonfinite("position error".into(), e));
            }
            self.pos_scale = qe.iter().fold(self.pos_scale, |m, x| m.max(x.abs()));
            self.max_pos = Some(self.max_pos.unwrap_or(0.0).max(e));
            row.push(e);
        }
        self.closest(q, k, t)?;
        self.previous_q.copy_from_slice(q);
        Ok(())
    }

    /// Update the closest approach with the step end (q, k, t).
    fn closest(&mut self, q: &[f64], k: usize, t: f64) -> Result<()> {
        let Some(bodies) = &self.bodies else {
            return Ok(());
        };
        let s = self.spatial;
        if s == 0 {
            return Ok(());
        }
        for a in 0..bodies.len() {
            for b in a + 1..bodies.len() {
                let (mut r2, mut m2) = (0.0, 0.0);
                for c in 0..s {
                    let r = q[a * s + c] - q[b * s + c];
                    let r_prev = self.previous_q[a * s + c] - self.previous_q[b * s + c];
                    r2 += r * r;
                    m2 += (r - r_prev) * (r - r_prev);
                }
                let sep = r2.sqrt();
                let pair = a * bodies.len() + b;
                if self.initial_separation.len() <= pair {
                    // First call (t0): record the initial separations.
                    self.initial_separation.resize(pair + 1, sep);
                    self.initial_separation[pair] = sep;
                }
                if sep == 0.0 {
                    return Err(LabError::Collision {
                        a: bodies[a].clone(),
                        b: bodies[b].clone(),
                        step: k,
                        t,
                        separation: sep,
                    });
                }
                let close = sep < ENCOUNTER_FRACTION * self.initial_separation[pair];
                if close && self.unresolved.is_none() && m2.sqrt() > sep {
                    self.unresolved = Some(Encounter {
                        a: bodies[a].clone(),
                        b: bodies[b].clone(),
                        separation: sep,
                        t,
                        relative_step: m2.sqrt(),
                    });
                }
                if self.encounter.as_ref().is_none_or(|e| sep < e.separation) {
                    self.encounter = Some(Encounter {
                        a: bodies[a].clone(),
                        b: bodies[b].clone(),
                        separation: sep,
                        t,
                        relative_step: m2.sqrt(),
                    });
                }
            }
        }
        Ok(())
    }

    /// Search the Galerkin curve of the step from `t_a` to `t_b` (whose ends were observed)
    /// for a closer approach than the one so far: the closest pair
    /// ([`NBody::closest_pair`]) at [`CURVE_SAMPLES`] interior points, then a golden-section
    /// search of that pair's separation around the smallest sample. `position(t)` is the
    /// curve's q(t). A closest approach between step ends is otherwise missed entirely (two
    /// bodies that pass each other within a step).
    pub fn closest_on_curve(
        &mut self,
        nbody: &NBody,
        t_a: f64,
        t_b: f64,
        position: &dyn Fn(f64) -> Option<Vec<f64>>,
    ) {
        let Some(bodies) = &self.bodies else {
            return;
        };
        let record = self
            .encounter
            .as_ref()
            .map_or(f64::INFINITY, |e| e.separation);
        let dt = (t_b - t_a) / CURVE_SAMPLES as f64;
        let mut best: Option<(f64, usize, usize, f64)> = None;
        for j in 0..=CURVE_SAMPLES {
            let t = t_a + j as f64 * dt;
            let Some((a, b, r)) = position(t).and_then(|q| nbody.closest_pair(&q)) else {
                continue;
            };
            if best.is_none_or(|(_, _, _, rb)| r < rb) {
                best = Some((t, a, b, r));
            }
        }
        let Some((t_best, a, b, r_best)) = best else {
            return;
        };
        // Only a sample within a factor of the record can lead to a closer approach (the
        // pair's separation is smooth over a step's fraction).
        if r_best.is_nan() || r_best >= 2.0 * record {
            return;
        }
        let d = self.spatial;
        let pair = |t: f64| -> f64 {
            position(t).map_or(f64::INFINITY, |q| {
                (0..d)
                    .map(|c| (q[a * d + c] - q[b * d + c]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
        };
        let (t, r) = golden_minimum(&pair, (t_best - dt).max(t_a), (t_best + dt).min(t_b));
        let (t, r) = if r < r_best { (t, r) } else { (t_best, r_best) };
        if r < record {
            let step = |q: Option<Vec<f64>>| {
                q.map(|q| {
                    (0..d)
                        .map(|c| q[a * d + c] - q[b * d + c])
                        .collect::<Vec<_>>()
                })
            };
            let moved = match (step(position(t_a)), step(position(t_b))) {
                (Some(ra), Some(rb)) => ra
                    .iter()
                    .zip(&rb)
                    .map(|(x, y)| (x - y).powi(2))
                    .sum::<f64>()
                    .sqrt(),
                _ => f64::NAN,
            };
            self.encounter = Some(Encounter {
                a: bodies[a].clone(),
                b: bodies[b].clone(),
                separation: r,
                t,
                relative_step: moved,
            });
        }
    }

    /// Relative invariant errors of the energy, max|E − E₀| over its
    /// [`crate::energy::energy_scale`] (which
    /// does not vanish for a parabolic orbit, as E₀ does); NaN for the other invariants
    /// (momenta are often zero up to round-off in the barycentric frame, where a relative
    /// error is meaningless) and where the scale is 0.
    pub fn relative_errors(&self) -> Vec<f64> {
        let scale = self.energy_scale.map_or(0.0, |(_, s)| s);
        self.inv_err
            .iter()
            .zip(&self.names)
            .map(|(e, name)| {
                if name == "energy" && scale != 0.0 {
                    e / scale
                } else {
                    f64::NAN
                }
            })
            .collect()
    }

    /// Warnings for figures above [`SANITY_THRESHOLD`] and for unresolved close encounters.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        for ((name, rel), abs) in self
            .names
            .iter()
            .zip(self.relative_errors())
            .zip(&self.inv_err)
        {
            if name == "energy" && rel > SANITY_THRESHOLD {
                let (label, scale) = self.energy_scale.unwrap_or(("|E₀|", f64::NAN));
                w.push(format!(
                    "relative energy error {rel:.3e} (absolute {abs:.3e} over {label} = \
                     {scale:.3e}) exceeds {SANITY_THRESHOLD:e}: the step is too large for this \
                     system or the orbit has escaped"
                ));
            }
        }
        if let Some(e) = self.max_pos {
            let rel = e / self.pos_scale.max(f64::MIN_POSITIVE);
            if rel > SANITY_THRESHOLD {
                w.push(format!(
                    "relative position error {rel:.3e} (max error {e:.3e} over the orbit's size \
                     {:.3e}) exceeds {SANITY_THRESHOLD:e}",
                    self.pos_scale
                ));
            }
        }
        if let Some(c) = &self.unresolved {
            w.push(format!(
                "close encounter not resolved: {} and {} came within {:.3e} (under a tenth of their \
                 initial separation) at t = {:.6e} while \
                 moving {:.3e} relative to each other in one step (reduce h)",
                c.a, c.b, c.separation, c.t, c.relative_step
            ));
        }
        w
    }
}

/// Interior points of each step's curve at which [`Monitor::closest_on_curve`] looks for the
/// closest pair before refining.
pub const CURVE_SAMPLES: usize = 8;

/// The minimum of `f` on [lo, hi] by golden-section search to a relative width of 1e-12 of
/// the interval (at most 80 evaluations): (argmin, minimum).
fn golden_minimum(f: &dyn Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> (f64, f64) {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let width = hi - lo;
    let (mut x1, mut x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..80 {
        if hi - lo <= 1e-12 * width.abs() {
            break;
        }
        if f1 < f2 {
            (hi, x2, f2) = (x2, x1, f1);
            x1 = hi - g * (hi - lo);
            f1 = f(x1);
        } else {
            (lo, x1, f1) = (x1, x2, f2);
            x2 = lo + g * (hi - lo);
            f2 = f(x2);
        }
    }
    if f1 < f2 { (x1, f1) } else { (x2, f2) }
}

/// Reject a time span whose times cannot be told apart at the step's resolution: every
/// t_k = t0 + k h up to t0 + steps·h must be finite, and the spacing of doubles there must be
/// below a thousandth of h (at t0 = 1.7e308 the time column would otherwise freeze).
pub(crate) fn check_time_span(t0: f64, h: f64, steps: usize) -> Result<()> {
    if !t0.is_finite() {
        return Err(GviError::NonFinite {
            what: "initial time t0".into(),
            value: t0,
        }
        .into());
    }
    let end = t0 + steps as f64 * h;
    let top = t0.abs().max(end.abs());
    // Spacing of doubles at `top` (one unit in the last place).
    let ulp = if top == 0.0 { 0.0 } else { top * f64::EPSILON };
    if !end.is_finite() || ulp > 1e-3 * h {
        return Err(GviError::InvalidParameter {
            name: "t0".into(),
            value: t0,
            reason: format!(
                "the run ends at t = {end:e}, where doubles are {ulp:.3e} apart: more than a \
                 thousandth of the step h = {h:e}, so the times of the steps cannot be \
                 represented (use a t0 closer to 0)"
            ),
        }
        .into());
    }
    Ok(())
}
