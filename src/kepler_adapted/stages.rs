//! The stage equations of the Kepler-adapted step ([`super`]): the right-hand side of (1) at
//! the stage values (the listed bodies' drifts and pulled-back kicks, the polynomial bodies'
//! Hamilton equations), the fixed-point update, and that iteration as the crate's driver runs
//! it.

use super::jacobi::{add, dot, scale};
use super::{DriftError, ESTIMATE_BELOW, FLOOR, KeplerAdaptedGalerkin, MAX_ITERATIONS, warm_drift};
use crate::newton::{Correction, Divergence, NewtonFailure, NewtonIteration, Termination};

impl KeplerAdaptedGalerkin {
    /// The right-hand side of (1) at every stage value into `fq`, `fp`: per stage, the Kepler
    /// drifts of the planets over c_j h, the interaction gradient at the drifted positions,
    /// and the pulled-back kick (0, −∂H_I/∂r′).
    pub(super) fn evaluate(&mut self) -> std::result::Result<(), (usize, DriftError)> {
        let (s, h) = (self.s, self.h);
        let st = &mut self.stages;
        let n = st.n;
        for j in 0..s {
            st.drifts.clear();
            for i in 0..n {
                let (body, k) = (i + 1, j * n + i);
                if !self.kepler[body] {
                    // A polynomial body is where its stage value is.
                    st.positions[body] = st.zq[k];
                    continue;
                }
                let m = self.jacobi.jacobi_mass(body);
                let (mu, t) = (self.jacobi.mu(body), self.c[j] * h);
                let drift = warm_drift(mu, m, st.zq[k], st.zp[k], t, &mut st.anomaly[k])
                    .map_err(|e| (body, e))?;
                st.positions[body] = drift.position();
                st.drifts.push(drift);
            }
            st.positions[0] = [0.0; 3];
            self.jacobi.interaction_gradient(
                &st.positions,
                &mut st.cartesian,
                &mut st.cartesian_gradient,
                &mut st.gradient,
            );
            let mut drifts = st.drifts.iter();
            for i in 0..n {
                let (body, k) = (i + 1, j * n + i);
                let m = self.jacobi.jacobi_mass(body);
                let drift = if self.kepler[body] {
                    drifts.next()
                } else {
                    None
                };
                match drift {
                    // The pulled-back kick (0, −∂H_I/∂r′).
                    Some(drift) => {
                        let kick = scale(-1.0 / m, st.gradient[body]);
                        let (dr, dv) = drift.pull_back([0.0; 3], kick);
                        st.fq[k] = dr;
                        st.fp[k] = scale(m, dv);
                    }
                    // Hamilton's equations of H_R for a polynomial body: its Kepler term
                    // p²/2m′ − m′μ/|r′| is in H_R, so its force is −∂H_I/∂r′ − m′μ r′/|r′|³.
                    None => {
                        let r = st.zq[k];
                        let r2 = dot(r, r);
                        let kepler = m * self.jacobi.mu(body) / (r2 * r2.sqrt());
                        st.fq[k] = scale(1.0 / m, st.zp[k]);
                        st.fp[k] = scale(-1.0, add(st.gradient[body], scale(kepler, r)));
                    }
                }
            }
        }
        self.evaluations += s;
        Ok(())
    }

    /// One fixed-point update Z_j ← z_k + h Σ_l a_jl F_l; returns the largest change relative
    /// to each planet's Jacobi position and momentum.
    pub(super) fn update(&mut self) -> f64 {
        let (s, h) = (self.s, self.h);
        let st = &mut self.stages;
        let n = st.n;
        let mut change = 0.0f64;
        for j in 0..s {
            for i in 0..n {
                let (body, k) = (i + 1, j * n + i);
                let (mut dq, mut dp) = ([0.0; 3], [0.0; 3]);
                for l in 0..s {
                    let w = h * self.a[j * s + l];
                    dq = add(dq, scale(w, st.fq[l * n + i]));
                    dp = add(dp, scale(w, st.fp[l * n + i]));
                }
                let (q0, p0) = (st.rj[body], st.pj[body]);
                let (qn, pn) = (add(q0, dq), add(p0, dp));
                let (sq, sp) = (norm_max(q0), norm_max(p0));
                for c in 0..3 {
                    change = change.max((qn[c] - st.zq[k][c]).abs() / sq);
                    change = change.max((pn[c] - st.zp[k][c]).abs() / sp);
                }
                st.zq[k] = qn;
                st.zp[k] = pn;
            }
        }
        change
    }
}

/// The termination of the stage iteration after `corrections` corrections: converged when an
/// update is at most one ulp of the stage values (relative, per planet), or — from the third
/// correction on — when the contraction estimate bounds the remaining error by that,
/// θ/(1 − θ)·|δ| ≤ ε with θ < 0.05, or when the updates stopped shrinking at the round-off
/// floor; failed when, after 6 corrections, one is more than twice the last. The iteration
/// contracts by O(ε h²ω²) per step, so it ends after about three corrections (measured: 3.0 per
/// step on J2000 at h = 12.5–25 d, s = 8, against 4.7–4.8 when iterating to an exactly zero
/// update; the end states differ by less than the run's own round-off scatter, see
/// docs/guide/kepler-adapted.md).
pub(super) fn termination(corrections: usize) -> Termination {
    // The first update is the stage increment itself, not a correction of it, so the first
    // ratio θ compares unlike quantities: θ is trusted from the third correction on.
    let trusted = corrections > 2;
    let floor = if trusted { FLOOR } else { 0.0 };
    Termination {
        divergence: Some(Divergence {
            after: 6,
            growth: 2.0,
        }),
        ..Termination::new(
            MAX_ITERATIONS,
            f64::EPSILON,
            trusted.then_some(ESTIMATE_BELOW),
            floor,
            f64::from_bits(1f64.to_bits() - 1),
        )
    }
}

/// max |xᵢ| (at least the smallest positive normal).
fn norm_max(x: [f64; 3]) -> f64 {
    x.iter().fold(f64::MIN_POSITIVE, |m, v| m.max(v.abs()))
}

/// The fixed-point iteration of the stage equations as a [`NewtonIteration`] (the identity for
/// its linear solve) run by the crate's one driver.
pub(super) struct StageIteration<'m> {
    pub(super) m: &'m mut KeplerAdaptedGalerkin,
    /// The last update's relative size (0 before the first).
    pub(super) last: f64,
}

impl NewtonIteration for StageIteration<'_> {
    /// The update is the residual of the iterate before it; this reports the last one.
    fn residual(&mut self, _: usize) -> f64 {
        self.last
    }

    fn correct(
        &mut self,
        iteration: usize,
    ) -> std::result::Result<(Correction, Termination), NewtonFailure> {
        self.m.evaluate().map_err(|(body, e)| NewtonFailure {
            residual: self.last,
            iterations: iteration + 1,
            reason: format!("Kepler drift of body {body}: {e}"),
        })?;
        self.m.iterations += 1;
        self.last = self.m.update();
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
        Ok((correction, termination(iteration + 1)))
    }
}
