//! One Picard iteration of [`InnerKeplerGalerkin`]'s stage equations ([`super`]): the
//! right-hand sides at the active slots' stage values, their update, and the iteration as the
//! crate's driver runs it, the converged slots frozen as in the velocity form.

use super::super::jacobi::{add, dot, scale, sub};
use super::super::stages::termination;
use super::super::{DriftError, ESTIMATE_BELOW, MAX_ITERATIONS, warm_drift};
use super::InnerKeplerGalerkin;
use crate::lagrangian::{ByCoordinate, Mechanical};
use crate::newton::{Adapt, Correction, NewtonFailure, NewtonIteration, Progress, Termination};

/// A masked iteration whose correction contracts by less than this (or grows) has stalled at
/// some slot's round-off: freezing stops, and the executor's tests (with their floor) decide.
const STALLED: f64 = 0.5;

/// The relative correction (per slot) up to which the confirmation of the frozen slots ends
/// the iteration. Measured on J2000 (s = 8, h = 16.7–25 d, Mercury Kepler-adapted): the
/// confirmations' corrections are 2–4e-16 (median 3e-16), up to 3.8e-15 at h = 25 d; a larger
/// one continues the iteration with every slot.
const CONFIRMATION_FLOOR: f64 = 4e-15;

impl InnerKeplerGalerkin {
    /// Whether slot `b` is iterated (every slot when nothing is frozen).
    fn active(&self, b: usize) -> bool {
        !self.freeze.freezing() || self.freeze.active()[b]
    }

    /// The right-hand sides at the active slots' stage values: the Kepler slots' drifts, the
    /// potential's gradient (in vector lanes over the stages, the pairs with a body whose force
    /// is needed), and from it the polynomial slots' forces and the Kepler slots' pulled-back
    /// kicks.
    pub(super) fn evaluate(&mut self) -> Result<(), (usize, DriftError)> {
        let (s, h, k, dim) = (self.s, self.h, self.kepler, self.dim);
        let n = self.slots.n;
        let chain_active = (0..=k).any(|b| self.active(b));
        let mut all = true;
        for b in 0..n {
            let on = if b <= k { chain_active } else { self.active(b) };
            self.slots.need[b] = on;
            all &= on;
        }
        for b in 1..=k {
            if !self.active(b) {
                continue;
            }
            let m = self.mass[b];
            for j in 0..s {
                let idx = j * n + b;
                let st = &mut self.slots;
                let (mu, t) = (self.prefix.mu(b), self.c[j] * h);
                let drift = warm_drift(mu, m, st.q[idx], st.zp[idx], t, &mut st.anomaly[idx])
                    .map_err(|e| (b, e))?;
                st.drifts[idx] = Some(drift);
            }
        }
        // The chain's Cartesian positions, if it moved (the bodies after it have their stage
        // positions in `x` already).
        let st = &mut self.slots;
        for j in (0..s).filter(|_| chain_active) {
            st.chain[0] = st.q[j * n];
            for b in 1..=k {
                st.chain[b] = st.drifts[j * n + b].map_or(st.q[j * n + b], |d| d.position());
            }
            self.prefix
                .positions_from_jacobi(&st.chain, &mut st.chain_out);
            for (b, x) in st.chain_out.iter().enumerate() {
                for (c, &v) in x.iter().enumerate().take(dim) {
                    st.x[(b * dim + c) * s + j] = v;
                }
            }
        }
        self.system
            .potential_gradient_at_points_by_coordinate_on_blocks(
                &st.x,
                ByCoordinate::new(s, s),
                &st.need,
                &mut st.gradient,
            );
        if all {
            self.evaluations += s;
        } else {
            self.masked_evaluations += s;
        }
        let g = |st: &super::Slots, b: usize, j: usize| -> [f64; 3] {
            let mut out = [0.0; 3];
            for (c, o) in out.iter_mut().enumerate().take(dim) {
                *o = st.gradient[(b * dim + c) * s + j];
            }
            out
        };
        for j in 0..s {
            if chain_active {
                for b in 0..=k {
                    st.chain[b] = g(st, b, j);
                }
                // The chain's gradients in its Jacobi coordinates (slot 0: their sum).
                self.prefix.covector_to_jacobi(&st.chain, &mut st.chain_out);
                st.f[j * n] = scale(-1.0, st.chain_out[0]);
                for b in 1..=k {
                    let idx = j * n + b;
                    let Some(drift) = st.drifts[idx] else {
                        continue;
                    };
                    // ∂H_R/∂r′ = ∂V/∂r′ + m′μ r′/|r′|³ (V's Kepler part taken out), and the
                    // pulled-back kick (0, −∂H_R/∂r′).
                    let (m, r) = (self.mass[b], drift.position());
                    let r2 = dot(r, r);
                    let kepler = m * self.prefix.mu(b) / (r2 * r2.sqrt());
                    let perturbation = sub(st.chain_out[b], scale(kepler, r));
                    let (dr, dv) = drift.pull_back([0.0; 3], scale(-1.0 / m, perturbation));
                    st.fq[idx] = dr;
                    st.f[idx] = scale(m, dv);
                }
            }
        }
        Ok(())
    }

    /// One update of the active slots' stage values from their right-hand sides, each slot's
    /// change (relative to its scale: positions and momenta separately for a Kepler slot)
    /// recorded for the freezing test; returns the largest.
    ///
    /// `first`: the first update after the guess, which for a Kepler slot (and a polynomial
    /// one on a new start) is the stage increment itself rather than a correction of a
    /// prediction: it is recorded as unbounded, so that the freezing test's ratio θ starts
    /// with the second and third corrections.
    pub(super) fn update(&mut self, first: bool) -> f64 {
        let (s, h, n) = (self.s, self.h, self.slots.n);
        let freezing = self.freeze.freezing();
        let mut largest = 0.0f64;
        for b in 0..n {
            if !self.active(b) {
                continue;
            }
            let kepler = self.is_kepler(b);
            let m = self.mass[b];
            let st = &mut self.slots;
            let mut change = 0.0f64;
            if kepler {
                let (iq, ip) = (
                    1.0 / super::norm_max(st.q0[b]),
                    1.0 / super::norm_max(st.p0[b]),
                );
                for j in 0..s {
                    let (mut dq, mut dp) = ([0.0; 3], [0.0; 3]);
                    for l in 0..s {
                        let w = h * self.a[j * s + l];
                        dq = add(dq, scale(w, st.fq[l * n + b]));
                        dp = add(dp, scale(w, st.f[l * n + b]));
                    }
                    let idx = j * n + b;
                    let (qn, pn) = (add(st.q0[b], dq), add(st.p0[b], dp));
                    for c in 0..3 {
                        let dq = (qn[c] - st.q[idx][c]).abs() * iq;
                        let dp = (pn[c] - st.zp[idx][c]).abs() * ip;
                        // Comparisons, not `f64::max` (its NaN rule costs; a NaN stage value
                        // ends the step as a non-finite drift or state, a typed error).
                        change = if dq > change { dq } else { change };
                        change = if dp > change { dp } else { change };
                    }
                    st.q[idx] = qn;
                    st.zp[idx] = pn;
                }
            } else if b == 0 {
                let v = scale(h / m, st.p0[0]);
                let h2m = h * h / m;
                for j in 0..s {
                    let mut dq = [0.0; 3];
                    for l in 0..s {
                        dq = add(dq, scale(self.a2t[l * s + j], st.f[l * n]));
                    }
                    let qn = add(st.q0[0], add(scale(self.c[j], v), scale(h2m, dq)));
                    for c in 0..3 {
                        change = change.max((qn[c] - st.q[j * n][c]).abs());
                    }
                    st.q[j * n] = qn;
                }
                change /= st.scale[0];
            } else {
                // A body after the chain, a coordinate (a row over the stages) at a time, with
                // s a constant: Q_j = q + c_j h v − (h²/m) Σ_l (A²)_jl ∇V_l.
                let rows = b * self.dim * s..(b + 1) * self.dim * s;
                let (q0, v) = (st.q0[b], scale(h / m, st.p0[b]));
                let (x, g) = (&mut st.x[rows.clone()], &st.gradient[rows]);
                let (a2t, c, h2m) = (&self.a2t[..], &self.c[..], h * h / m);
                macro_rules! stages {
                    ($($n:literal)*) => {
                        match s {
                            $($n => slot_rows::<$n>(x, g, a2t, c, q0, v, h2m),)*
                            _ => None,
                        }
                    };
                }
                // (None only if the tables did not have s entries: a failed iteration.)
                change = stages!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16).unwrap_or(f64::NAN);
                change /= st.scale[b];
            }
            if freezing {
                let increment = first && (kepler || !self.slots.has_previous);
                let recorded = if increment { f64::INFINITY } else { change };
                self.freeze.record(b, recorded, 1.0);
            }
            largest = largest.max(change);
        }
        largest
    }
}

/// The rows of a polynomial slot after the chain (`x` and `gradient`: one row of S stage
/// values per coordinate): Q_j ← q + (c_j h v − (h²/m) Σ_l (A²)_jl ∇V_l), with `a2t` holding
/// (A²)ᵀ row-major. Returns the largest |ΔQ|, or `None` if a table is shorter than S.
#[allow(clippy::too_many_arguments)]
fn slot_rows<const S: usize>(
    x: &mut [f64],
    gradient: &[f64],
    a2t: &[f64],
    c: &[f64],
    q0: [f64; 3],
    hv: [f64; 3],
    h2m: f64,
) -> Option<f64> {
    let c: &[f64; S] = c.first_chunk()?;
    let mut change = 0.0f64;
    let rows = x.chunks_exact_mut(S).zip(gradient.chunks_exact(S));
    for ((row, g), (&q0, &v)) in rows.zip(q0.iter().zip(&hv)) {
        let mut acc = [0.0; S];
        for (l, &gl) in g.iter().enumerate() {
            let column: &[f64; S] = a2t.get(l * S..)?.first_chunk()?;
            for (x, &a) in acc.iter_mut().zip(column) {
                *x += a * gl;
            }
        }
        for ((x, &acc), &cj) in row.iter_mut().zip(&acc).zip(c) {
            let qn = q0 + (cj * v - h2m * acc);
            let d = (qn - *x).abs();
            change = if d > change { d } else { change };
            *x = qn;
        }
    }
    Some(change)
}

/// The stage iteration as a [`NewtonIteration`] (the identity for its linear solve) run by
/// the crate's one driver.
pub(super) struct SlotIteration<'m> {
    pub(super) m: &'m mut InnerKeplerGalerkin,
    /// The last update's relative size (0 before the first).
    pub(super) last: f64,
    /// The last correction confirmed the frozen slots.
    pub(super) confirmation: bool,
}

impl NewtonIteration for SlotIteration<'_> {
    /// The update is the residual of the iterate before it; this reports the last one.
    fn residual(&mut self, _: usize) -> f64 {
        self.last
    }

    fn correct(&mut self, iteration: usize) -> Result<(Correction, Termination), NewtonFailure> {
        self.m.evaluate().map_err(|(body, e)| NewtonFailure {
            residual: self.last,
            iterations: iteration + 1,
            reason: format!("Kepler drift of body {body}: {e}"),
        })?;
        self.m.iterations += 1;
        self.last = self.m.update(iteration == 0);
        if !self.last.is_finite() {
            return Err(NewtonFailure {
                residual: self.last,
                iterations: iteration + 1,
                reason: "non-finite stage value".into(),
            });
        }
        let correction = Correction {
            size: self.last,
            scale: 1.0,
        };
        let freeze = &mut self.m.freeze;
        self.confirmation = false;
        if freeze.freezing() {
            // A confirmation of every slot ends freezing; otherwise the slots that pass the
            // test are frozen, and while any is, this correction cannot end the iteration.
            self.confirmation = freeze.confirmed();
            if self.confirmation {
                // Every slot corrected once more: the frozen ones moved by what the others'
                // later corrections changed in their forces, at the round-off floor.
                let confirmed =
                    Termination::new(MAX_ITERATIONS, f64::EPSILON, None, CONFIRMATION_FLOOR, 0.0);
                return Ok((correction, confirmed));
            }
            if freeze.update(f64::EPSILON, 1.0, ESTIMATE_BELOW) {
                let masked = Termination::new(MAX_ITERATIONS, 0.0, None, 0.0, 1.0);
                return Ok((correction, masked));
            }
        }
        Ok((correction, termination(iteration + 1)))
    }

    fn adapt(&mut self, progress: &Progress) -> Adapt {
        if std::mem::replace(&mut self.confirmation, false) {
            // The confirmation's ratio to the last masked correction is a frozen slot's drift
            // against the slowest slot's last step, not a contraction.
            return Adapt::Continue;
        }
        let freeze = &mut self.m.freeze;
        if freeze.masked() && (progress.growing || progress.theta > STALLED) {
            freeze.stop();
            return Adapt::Restart;
        }
        Adapt::Continue
    }
}
