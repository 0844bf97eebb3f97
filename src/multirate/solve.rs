//! The stage solve of the multirate step: Picard sweeps with the fast micro steps in order,
//! the guess, and the sweeps as a [`NewtonIteration`] for the crate's one driver.

use super::coupling::{CouplingPairs, LANES};
use super::{ESTIMATE_BELOW, FLOOR, MAX_ITERATIONS, MultirateGalerkin, TOLERANCE};
use crate::lagrangian::Mechanical;
use crate::linalg::{Strided, gemm, gemm_transposed};
use crate::newton::{Correction, NewtonFailure, NewtonIteration, Termination};

impl MultirateGalerkin {
    /// One Picard sweep of the stage equations: every correction −F/m from the current
    /// iterate, except that the fast bodies' micro steps are taken in order (Gauss–Seidel in
    /// time): micro step r is evaluated from the knot x_r and momentum p^r that the steps
    /// before it reached in this sweep, so a micro step converges at its own rate rather than
    /// at that of a Picard iteration over the whole macro step. The slow bodies are corrected
    /// last, from their mutual forces at the macro nodes and the fast bodies' pull at every
    /// micro node. Leaves the slow momentum increment in `dps`, the fast knot x_R and momentum
    /// p^R in `knot` and `momentum`; returns (max |δ|, max |c|).
    ///
    /// The micro nodes are laid out by coordinate (a row per coordinate, each micro step's
    /// nodes padded to whole vectors of [`LANES`]), so that the coupling pairs run with the
    /// nodes in vector lanes.
    fn sweep(&mut self, first: bool) -> (f64, f64) {
        let (big_h, r) = (self.h, self.shape.micro_steps);
        let h = big_h / r as f64;
        let (mr, mu) = (&self.macro_rule, &self.micro_rule);
        let (k, kf, m, mf) = (mr.k, mu.k, mr.m(), mu.m());
        let st = &mut self.state;
        let (ds, df, stride, sp) = (st.qs.len(), st.qf.len(), st.stride, st.step_stride);
        // The slow curve at the macro nodes (by node) and at the micro nodes (by coordinate).
        for row in st.xs.chunks_exact_mut(ds) {
            row.copy_from_slice(&st.qs);
        }
        let (rk, rd) = (Strided::rows(0, k), Strided::rows(0, ds));
        gemm(
            m, k, ds, big_h, &mr.iota, rk, &st.cs, rd, 1.0, &mut st.xs, rd,
        );
        let (iota_t, _) = self.iota_micro_t.as_chunks::<LANES>();
        let chunks = stride / LANES;
        for (c, row) in st.xs_micro.chunks_exact_mut(stride).enumerate() {
            for (v, out) in row.as_chunks_mut::<LANES>().0.iter_mut().enumerate() {
                // A vector of nodes summed in registers over the modes.
                let mut acc = [st.qs[c]; LANES];
                for a in 0..k {
                    let coef = big_h * st.cs[a * ds + c];
                    let i = &iota_t[a * chunks + v];
                    acc.iter_mut().zip(i).for_each(|(x, i)| *x += i * coef);
                }
                *out = acc;
            }
        }
        // The slow bodies' mutual forces at the macro nodes, weighted by H b_j.
        self.slow_system
            .potential_gradient_at_points(&st.xs, &mut st.gs);
        for (row, &b) in st.gs.chunks_exact_mut(ds).zip(&mr.weights) {
            let w = -big_h * b;
            row.iter_mut().for_each(|x| *x *= w);
        }
        // The fast bodies' micro steps in order.
        let pairs = CouplingPairs {
            g: self.g,
            slow_masses: &self.slow_masses,
            fast_masses: &self.fast_masses,
            stride,
        };
        let equal = 1.0 / (r * mf) as f64;
        st.knot.copy_from_slice(&st.qf);
        st.momentum.copy_from_slice(&st.pf);
        let (mut size, mut scale) = (0.0f64, 0.0f64);
        for step in 0..r {
            let nodes = step * sp..(step + 1) * sp;
            if first && step > 0 {
                // The first sweep continues the micro step just corrected, not its guess.
                let (before, now) = st.cf.split_at_mut(step * kf * df);
                let (rk, rd) = (Strided::rows(0, kf), Strided::rows(0, df));
                let from = &before[(step - 1) * kf * df..];
                gemm(
                    kf,
                    kf,
                    df,
                    1.0,
                    &mu.extrapolate,
                    rk,
                    from,
                    rd,
                    0.0,
                    &mut now[..kf * df],
                    rd,
                );
            }
            let modes = &mut st.cf[step * kf * df..(step + 1) * kf * df];
            // Picard corrections of this micro step alone (the slow curves as they are), until
            // it converges: the fast body needs more of them than the slow ones, and they cost
            // only its own pairs. Then one evaluation at the converged curve gives the pull on
            // the slow bodies and the momentum at the next knot.
            let mut previous = f64::INFINITY;
            let weights = &self.weights_micro[nodes.clone()];
            let curve = |modes: &[f64], knot: &[f64], xf: &mut [f64]| {
                for c in 0..df {
                    let row = &mut xf[c * stride + nodes.start..c * stride + nodes.end];
                    for (j, iota) in mu.iota.chunks_exact(kf).enumerate() {
                        let sum: f64 = iota
                            .iter()
                            .zip(modes.iter().skip(c).step_by(df))
                            .map(|(i, v)| i * v)
                            .sum();
                        row[j] = knot[c] + h * sum;
                    }
                    let last = row[mf - 1];
                    row[mf..].iter_mut().for_each(|x| *x = last);
                }
            };
            let fast_forces =
                |xs: &[f64], xf: &[f64], gs: &mut [f64], gf: &mut [f64], slow: bool| {
                    for row in gf.chunks_exact_mut(stride) {
                        row[nodes.clone()].iter_mut().for_each(|x| *x = 0.0);
                    }
                    let gs = if slow {
                        for row in gs.chunks_exact_mut(stride) {
                            row[nodes.clone()].iter_mut().for_each(|x| *x = 0.0);
                        }
                        Some(gs)
                    } else {
                        None
                    };
                    match self.dim {
                        2 => pairs.forces::<2>(xs, xf, gs, gf, nodes.clone()),
                        _ => pairs.forces::<3>(xs, xf, gs, gf, nodes.clone()),
                    }
                    // Weighted: h β_i = H β_i/R (zero on the padding).
                    for row in gf.chunks_exact_mut(stride) {
                        for (x, &w) in row[nodes.clone()].iter_mut().zip(weights) {
                            *x *= big_h * w;
                        }
                    }
                };
            for inner in 0..MAX_ITERATIONS {
                curve(modes, &st.knot, &mut st.xf);
                // After the first sweep this is the micro step's only evaluation: it gives the
                // pull on the slow bodies too.
                fast_forces(&st.xs_micro, &st.xf, &mut st.gs_micro, &mut st.gf, !first);
                self.evaluations += mf;
                // The correction of this micro step from p^r.
                let (mut step_size, mut step_scale) = (0.0f64, 0.0f64);
                for i in 0..df {
                    let g = &st.gf[i * stride + nodes.start..i * stride + nodes.start + mf];
                    let mass = self.fast_mass[i];
                    for b in 0..kf {
                        let proj: f64 = mu
                            .psi
                            .iter()
                            .skip(b)
                            .step_by(kf)
                            .zip(g)
                            .map(|(p, g)| p * g)
                            .sum();
                        let pb = if b == 0 { st.momentum[i] } else { 0.0 };
                        let y = &mut modes[b * df + i];
                        let delta = -((mass * *y + proj) - pb) / mass;
                        *y += delta;
                        step_size = step_size.max(delta.abs());
                        step_scale = step_scale.max(y.abs());
                    }
                }
                if inner == 0 {
                    // What this sweep moved the fast body by: the outer test's share.
                    size = size.max(step_size);
                }
                scale = scale.max(step_scale);
                let tol = TOLERANCE * step_scale.max(self.scale_hint);
                // (θ from the second correction on: the first one's predecessor is the guess.)
                let theta = if inner > 0 {
                    step_size / previous
                } else {
                    f64::INFINITY
                };
                previous = step_size;
                // Converged by the tolerance, by the contraction estimate, or at the round-off
                // floor (the corrections stopped shrinking there).
                let floor = FLOOR * step_scale.max(self.scale_hint);
                let converged = step_size <= tol
                    || (theta < ESTIMATE_BELOW && theta / (1.0 - theta) * step_size <= tol)
                    || (inner > 0 && theta >= ESTIMATE_BELOW && step_size <= floor)
                    || !step_size.is_finite();
                if converged {
                    break;
                }
                if !first {
                    // After the first sweep the fast body moves only with the slow curves'
                    // corrections, which are small: one correction per sweep (Gauss–Seidel),
                    // its evaluation serving the momenta and the pull on the slow bodies.
                    break;
                }
            }
            // The pull on the slow bodies (on the first sweep from the converged curve; weighted
            // as the fast side, or equally in the negative control: a rule the fast bodies'
            // equations do not use, so no common action term), then p^{r+1} and x_{r+1}.
            if first {
                curve(modes, &st.knot, &mut st.xf);
                fast_forces(&st.xs_micro, &st.xf, &mut st.gs_micro, &mut st.gf, true);
                self.evaluations += mf;
            }
            for row in st.gs_micro.chunks_exact_mut(stride) {
                for (x, &w) in row[nodes.clone()].iter_mut().zip(weights) {
                    let w = if self.consistent || w == 0.0 {
                        w
                    } else {
                        equal
                    };
                    *x *= big_h * w;
                }
            }
            for i in 0..df {
                let g = &st.gf[i * stride + nodes.start..i * stride + nodes.start + mf];
                st.momentum[i] += g.iter().sum::<f64>();
                st.knot[i] += h * modes[i];
            }
        }
        // The slow bodies: ψᵀ G over the macro nodes plus Σ_μ ψ_μ g_μ over the micro nodes.
        gemm_transposed(k, m, ds, &mr.psi, &st.gs, 0.0, &mut st.ds);
        for (c, row) in st.gs_micro.chunks_exact(stride).enumerate() {
            let (g, _) = row.as_chunks::<LANES>();
            for (b, psi) in self.psi_micro_t.chunks_exact(stride).enumerate() {
                // Σ_μ ψ_b(τ_μ) g_μ, a vector of nodes at a time.
                let (psi, _) = psi.as_chunks::<LANES>();
                let mut acc = [0.0f64; LANES];
                for (p, g) in psi.iter().zip(g) {
                    acc.iter_mut()
                        .zip(p.iter().zip(g))
                        .for_each(|(x, (p, g))| *x += p * g);
                }
                st.ds[b * ds + c] += acc.iter().sum::<f64>();
            }
        }
        for (b, (d, c)) in st
            .ds
            .chunks_exact(ds)
            .zip(st.cs.chunks_exact_mut(ds))
            .enumerate()
        {
            for (i, (&d, c)) in d.iter().zip(c.iter_mut()).enumerate() {
                let mass = self.slow_mass[i];
                let p = if b == 0 { st.ps[i] } else { 0.0 };
                let delta = -((mass * *c + d) - p) / mass;
                *c += delta;
                size = size.max(delta.abs());
                scale = scale.max(c.abs());
            }
        }
        // p_S,k+1 − p_S,k from this sweep's forces.
        st.dps.iter_mut().for_each(|x| *x = 0.0);
        for row in st.gs.chunks_exact(ds) {
            st.dps.iter_mut().zip(row).for_each(|(p, x)| *p += x);
        }
        for (p, row) in st.dps.iter_mut().zip(st.gs_micro.chunks_exact(stride)) {
            *p += row.iter().sum::<f64>();
        }
        self.evaluations += m;
        self.scale_hint = scale;
        (size, scale)
    }

    /// The guess: the previous step's curves continued (slow: one macro step; fast: each micro
    /// step from the one before), or constant velocities on the first step.
    pub(super) fn guess(&mut self) {
        let (r, k, kf) = (self.shape.micro_steps, self.macro_rule.k, self.micro_rule.k);
        let st = &mut self.state;
        let (ds, df) = (st.qs.len(), st.qf.len());
        if st.has_prev {
            let (rk, rd) = (Strided::rows(0, k), Strided::rows(0, ds));
            let e = &self.macro_rule.extrapolate;
            gemm(k, k, ds, 1.0, e, rk, &st.cs_prev, rd, 0.0, &mut st.cs, rd);
            let (rk, rd) = (Strided::rows(0, kf), Strided::rows(0, df));
            let e = &self.micro_rule.extrapolate;
            let size = kf * df;
            for step in 0..r {
                let (before, now) = st.cf.split_at_mut(step * size);
                let from = if step == 0 {
                    &st.cf_prev[(r - 1) * size..]
                } else {
                    &before[(step - 1) * size..]
                };
                gemm(kf, kf, df, 1.0, e, rk, from, rd, 0.0, &mut now[..size], rd);
            }
            if st.cs.iter().chain(&st.cf).all(|x| x.is_finite()) {
                return;
            }
        }
        st.cs.iter_mut().for_each(|x| *x = 0.0);
        st.cf.iter_mut().for_each(|x| *x = 0.0);
        for (i, (c, &p)) in st.cs[..ds].iter_mut().zip(&st.ps).enumerate() {
            *c = p / self.slow_mass[i];
        }
        for step in 0..r {
            let c = &mut st.cf[step * kf * df..step * kf * df + df];
            for (i, (c, &p)) in c.iter_mut().zip(&st.pf).enumerate() {
                *c = p / self.fast_mass[i];
            }
        }
    }
}

/// The Picard iteration of the stage equations as a [`NewtonIteration`] (the identity for its
/// linear solve, M⁻¹ for the correction) run by the crate's one driver.
pub(super) struct StageIteration<'m> {
    pub(super) m: &'m mut MultirateGalerkin,
}

impl NewtonIteration for StageIteration<'_> {
    /// The correction is the residual of the iterate before it (over the masses); this
    /// reports the last one.
    fn residual(&mut self, _: usize) -> f64 {
        self.m.state.last
    }

    fn correct(
        &mut self,
        iteration: usize,
    ) -> std::result::Result<(Correction, Termination), NewtonFailure> {
        self.m.iterations += 1;
        let (size, scale) = self.m.sweep(iteration == 0);
        self.m.state.last = size;
        if !(size.is_finite() && scale.is_finite()) {
            return Err(NewtonFailure {
                residual: size,
                iterations: iteration + 1,
                reason: "non-finite stage value (a collision?)".into(),
            });
        }
        // The contraction estimate and the floor from the third sweep on: the first sweep's
        // size is the fast body's guess error (its micro steps converge inside that sweep),
        // not a correction the next one can be compared with.
        let trusted = iteration >= 2;
        let termination = Termination::new(
            MAX_ITERATIONS,
            TOLERANCE,
            trusted.then_some(ESTIMATE_BELOW),
            if trusted { FLOOR } else { 0.0 },
            ESTIMATE_BELOW,
        );
        Ok((
            Correction {
                size,
                scale: scale.max(f64::MIN_POSITIVE),
            },
            termination,
        ))
    }
}
