//! The velocity form's equations as the iteration of [`super::solve`] uses them: the initial
//! modes, the residual F(c) = M c_b + h Σ_j b_j ψ_b(c_j) f_j − δ_b0 p_k with its momentum row in
//! double-double, the dense exact Newton matrix, and the converged modes written back as the
//! basis's coefficients, the impulse and the state the next step extrapolates from.

use super::momentum::{MomentumRow, MomentumRows, momentum_row, rounded_momentum_row};
use super::state::VelocityState;
use super::{VelocityTables, panel_times};
use crate::basis::Basis;
use crate::integrator::dd::{dd_acc, dd_acc_columns, max_abs_or_infinite, two_sum};
use crate::integrator::separable::Separable;
use crate::integrator::stage_scratch::StageScratch;
use crate::integrator::{GalerkinIntegrator, InitialGuess, Workspace};
use crate::lagrangian::Lagrangian;
use crate::linalg::{Lu, Strided, gemm, gemm_transposed, panel_product};
use crate::quadrature::Quadrature;

/// The dense exact Newton matrix of the velocity form and its factorisation.
#[derive(Debug, Clone)]
pub(super) struct DenseNewton {
    pub jac: Vec<f64>,
    /// D² partial rows of one row block (D²·k).
    pub acc: Vec<f64>,
    pub lu: Lu,
    pub scratch: Vec<f64>,
}

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// The initial modes: the previous step's velocity continued (exact for polynomials),
    /// else the RK4 predictor's curve projected on the modes, else constant velocity M⁻¹p.
    pub(super) fn velocity_guess<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        vt: &VelocityTables,
        q: &[f64],
        p: &[f64],
        extrapolate: bool,
    ) -> InitialGuess {
        let (k, d, n, h) = (vt.k, ws.d, self.tables().n, self.step_size());
        if let Some(vs) = ws.velocity.as_mut()
            && vs.has_prev
            && extrapolate
        {
            let rk = Strided::rows(0, k);
            let rd = Strided::rows(0, d);
            if !panel_times(&vt.extrapolate_cols, &vs.prev, k, k, d, 1.0, &mut vs.c) {
                gemm(
                    k,
                    k,
                    d,
                    1.0,
                    &vt.extrapolate,
                    rk,
                    &vs.prev,
                    rd,
                    0.0,
                    &mut vs.c,
                    rd,
                );
            }
            return InitialGuess::Extrapolate;
        }
        let predicted = self.predict_values(lag, ws, q, p);
        let Some(vs) = ws.velocity.as_mut() else {
            return InitialGuess::Constant;
        };
        if predicted {
            let (rn, rd) = (Strided::rows(0, n), Strided::rows(0, d));
            let cand = ws.guess.candidate();
            if !panel_times(&vt.from_values_cols, cand, n, k, d, 1.0 / h, &mut vs.c) {
                gemm(
                    k,
                    n,
                    d,
                    1.0 / h,
                    &vt.from_values,
                    rn,
                    cand,
                    rd,
                    0.0,
                    &mut vs.c,
                    rd,
                );
            }
            if vs.c.iter().all(|x| x.is_finite()) {
                return InitialGuess::Predictor;
            }
        }
        vs.c.iter_mut().for_each(|x| *x = 0.0);
        vs.c[..d].copy_from_slice(p);
        if let Some(sep) = &ws.separable {
            sep.solve_mass(&mut vs.c[..d], &mut ws.stage.small_scratch);
        }
        InitialGuess::Constant
    }

    /// F(c) at the iterate: the curve at the nodes into `ws.stage.qj`, the forces into
    /// `ws.stage.lq`, −F into the state's `delta`; returns max |F|.
    ///
    /// For D ≤ 4 (Kepler-like problems, where the general machinery around a few hundred
    /// multiply–adds dominated a step: issue 35's profile) the same arithmetic runs with the
    /// coordinates as a static array, in the same order, so the two give the same bits (up to
    /// the sign of an exactly zero entry).
    pub(super) fn velocity_residual<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        vt: &VelocityTables,
        p_k: &[f64],
        momentum: MomentumRow,
    ) -> f64 {
        if let Some(vs) = ws.velocity.as_mut()
            && let Some(rows) = vs.masked.as_mut()
        {
            if vs.freeze.as_ref().is_some_and(|f| f.masked()) {
                return self.velocity_residual_on_blocks(lag, ws, vt, p_k, momentum);
            }
            rows.forget();
        }
        match ws.d {
            1 => self.velocity_residual_small::<1, L>(lag, ws, vt, p_k, momentum),
            2 => self.velocity_residual_small::<2, L>(lag, ws, vt, p_k, momentum),
            3 => self.velocity_residual_small::<3, L>(lag, ws, vt, p_k, momentum),
            4 => self.velocity_residual_small::<4, L>(lag, ws, vt, p_k, momentum),
            _ => self.velocity_residual_general(lag, ws, vt, p_k, momentum),
        }
    }

    /// [`Self::velocity_residual`] with D a constant: the curve at node j summed over the
    /// modes in order (as the few-column product of `gemm` does), the forces in one batch,
    /// then one pass over the nodes for the projections Σ_j ψ_jb (h b_j f_j) (each summed over
    /// j in order from zero, as `gemm_transposed` does, which skips zero coefficients: adding
    /// their zero products changes at most the sign of an exactly zero sum) and the
    /// double-double momentum row.
    fn velocity_residual_small<const D: usize, L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        vt: &VelocityTables,
        p_k: &[f64],
        momentum: MomentumRow,
    ) -> f64 {
        let t = self.tables();
        let (m, k, h) = (t.m, vt.k, self.step_size());
        let (Some(vs), Some(sep)) = (ws.velocity.as_mut(), ws.separable.as_ref()) else {
            return f64::NAN;
        };
        let arr = |x: &[f64]| -> [f64; D] { std::array::from_fn(|r| x[r]) };
        let (origin, origin_lo) = (arr(ws.iterate.origin()), arr(ws.iterate.origin_lo()));
        let c0_lo = arr(&vs.c0_lo);
        // q_j = q_k + (δq_k + h ι_j0 c_0,lo + h Σ_a ι_ja c_a).
        let small = |w: f64, r: usize| origin_lo[r] + w * c0_lo[r];
        if vt.iota_cols.is_empty() {
            for (qj, iota) in ws
                .stage
                .qj
                .chunks_exact_mut(D)
                .zip(vt.iota.chunks_exact(k))
                .take(m)
            {
                let mut acc = [0.0f64; D];
                for (&x, c) in iota.iter().zip(vs.c.chunks_exact(D)) {
                    for r in 0..D {
                        acc[r] += x * c[r];
                    }
                }
                let w = h * iota[0];
                for r in 0..D {
                    qj[r] = (h * acc[r] + small(w, r)) + origin[r];
                }
            }
        } else {
            // m ≤ PANEL nodes: the same sums as one register panel.
            let acc = panel_product::<D>(&vt.iota_cols, &vs.c, k);
            for (j, qj) in ws.stage.qj.chunks_exact_mut(D).take(m).enumerate() {
                let w = h * vt.iota[j * k];
                for r in 0..D {
                    qj[r] = (h * acc[r][j] + small(w, r)) + origin[r];
                }
            }
        }
        lag.force_at_points(&ws.stage.qj, &mut ws.stage.lq);
        let panel = !vt.psi_rows.is_empty();
        if !panel {
            vs.delta.iter_mut().for_each(|x| *x = 0.0);
        }
        // Row 0, the momentum condition: in double-double (`momentum_row`, the force terms
        // added node by node below), or rounded from its projection.
        let compensated = momentum == MomentumRow::Compensated;
        let mut hi = [0.0f64; D];
        let mut lo = [0.0f64; D];
        if compensated {
            for r in 0..D {
                (hi[r], lo[r]) =
                    momentum_row(sep, &vs.c, &vs.c0_lo, p_k, ws.iterate.momentum_lo(), r);
            }
        }
        for (j, ((f, sc), psi)) in ws
            .stage
            .lq
            .chunks_exact(D)
            .zip(ws.stage.scaled.chunks_exact_mut(D))
            .zip(vt.psi.chunks_exact(k))
            .take(m)
            .enumerate()
        {
            let w = t.weights[j] * h;
            let g: [f64; D] = std::array::from_fn(|r| w * f[r]);
            sc.copy_from_slice(&g);
            if !panel {
                for (&x, delta) in psi.iter().zip(vs.delta.chunks_exact_mut(D)) {
                    for r in 0..D {
                        delta[r] += x * g[r];
                    }
                }
            }
            if compensated {
                let psi0 = psi[0];
                for r in 0..D {
                    dd_acc(&mut hi[r], &mut lo[r], psi0, g[r]);
                    lo[r] += psi0 * w.mul_add(f[r], -g[r]);
                }
            }
        }
        if panel {
            // k ≤ PANEL modes: Σ_j ψ_jb g_j, the same sums, as one register panel.
            let acc = panel_product::<D>(&vt.psi_rows, &ws.stage.scaled, m);
            for (b, delta) in vs.delta.chunks_exact_mut(D).take(k).enumerate() {
                for r in 0..D {
                    delta[r] = acc[r][b];
                }
            }
        }
        let row0: [f64; D] = std::array::from_fn(|r| {
            if compensated {
                hi[r] + lo[r]
            } else {
                rounded_momentum_row(sep, &vs.c, p_k, vs.delta[r], r)
            }
        });
        close_rows(
            sep,
            vs.mass_tiled.as_deref(),
            &vs.c,
            &mut vs.delta,
            |r| row0[r],
            D,
        )
    }

    /// [`Self::velocity_residual`] for any D, through the strided products.
    fn velocity_residual_general<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        vt: &VelocityTables,
        p_k: &[f64],
        momentum: MomentumRow,
    ) -> f64 {
        let t = self.tables();
        let (m, k, d, h) = (t.m, vt.k, ws.d, self.step_size());
        let (Some(vs), Some(sep)) = (ws.velocity.as_mut(), ws.separable.as_ref()) else {
            return f64::NAN;
        };
        let (rk, rd) = (Strided::rows(0, k), Strided::rows(0, d));
        // q_j = q_k + (δq_k + h ι_j0 c_0,lo + h Σ_a ι_ja c_a): the small parts first.
        for (j, row) in ws.stage.qj.chunks_exact_mut(d).enumerate() {
            let w = h * vt.iota[j * k];
            for ((x, &e), &lo) in row.iter_mut().zip(ws.iterate.origin_lo()).zip(&vs.c0_lo) {
                *x = e + w * lo;
            }
        }
        gemm(
            m,
            k,
            d,
            h,
            &vt.iota,
            rk,
            &vs.c,
            rd,
            1.0,
            &mut ws.stage.qj,
            rd,
        );
        ws.stage.add_to_nodes(ws.iterate.origin());
        self.weighted_forces(lag, &mut ws.stage);
        // Σ_j ψ_jb (h b_j f_j).
        gemm_transposed(k, m, d, &vt.psi, &ws.stage.scaled, 0.0, &mut vs.delta);
        let (stage, momentum_lo) = (&mut ws.stage, ws.iterate.momentum_lo());
        self.momentum_rows(vt, sep, vs, stage, (p_k, momentum_lo), &[(0, d)], momentum);
        let row0 = &ws.stage.dd_hi;
        close_rows(
            sep,
            vs.mass_tiled.as_deref(),
            &vs.c,
            &mut vs.delta,
            |r| row0[r],
            d,
        )
    }

    /// Row 0 of F, the momentum condition, for the coordinates of `columns` into the stage's
    /// `dd_hi` ([`MomentumRows::fill`]), from the projections in the state's `delta`, the
    /// stage's forces and p_k with its low part (`momentum`).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn momentum_rows(
        &self,
        vt: &VelocityTables,
        sep: &Separable,
        vs: &VelocityState,
        stage: &mut StageScratch,
        (p_k, momentum_lo): (&[f64], &[f64]),
        columns: &[(usize, usize)],
        momentum: MomentumRow,
    ) {
        let rows = MomentumRows {
            sep,
            c: &vs.c,
            c0_lo: &vs.c0_lo,
            p_k,
            momentum_lo,
            weights: &self.tables().weights,
            psi: &vt.psi,
            lq: &stage.lq,
            k: vt.k,
            h: self.step_size(),
            d: vs.c0_lo.len(),
        };
        rows.fill(
            columns,
            momentum,
            &vs.delta,
            &mut stage.dd_hi,
            &mut stage.dd_lo,
        );
    }

    /// The converged modes as the nodal solve leaves its result: increments ΔQ_i = h Σ_a B_ia
    /// c_a (ΔQ_{n−1} = h c_0 as hi + lo), the impulse h Σ_j b_j f_j (double-double) from the
    /// forces of the last residual, and the modes remembered for the next guess.
    pub(super) fn finish_velocity_form(&self, ws: &mut Workspace, vt: &VelocityTables) {
        let t = self.tables();
        let (n, k, d, h) = (t.n, vt.k, ws.d, self.step_size());
        let Some(vs) = ws.velocity.as_mut() else {
            return;
        };
        let (rk, rd) = (Strided::rows(0, k), Strided::rows(0, d));
        let (increments, last_lo) = ws.iterate.increments_and_last_lo_mut();
        if !panel_times(&vt.to_basis_cols, &vs.c, k, n, d, h, increments) {
            gemm(n, k, d, h, &vt.to_basis, rk, &vs.c, rd, 0.0, increments, rd);
        }
        let last = (n - 1) * d;
        for r in 0..d {
            let c0 = vs.c[r];
            let hi = h * c0;
            increments[r] = 0.0;
            increments[last + r] = hi;
            last_lo[r] = h.mul_add(c0, -hi) + h * vs.c0_lo[r];
        }
        vs.prev.copy_from_slice(&vs.c);
        vs.has_prev = true;
        self.impulse(ws);
    }

    /// The total impulse h Σ_j b_j L_q(c_j) of the forces in `ws.stage.lq`, in double-double,
    /// into the iterate's impulse (hi + lo).
    pub(in crate::integrator) fn impulse(&self, ws: &mut Workspace) {
        let (t, h, d) = (self.tables(), self.step_size(), ws.d);
        ws.stage.dd_hi.iter_mut().for_each(|x| *x = 0.0);
        ws.stage.dd_lo.iter_mut().for_each(|x| *x = 0.0);
        let weights = &t.weights;
        dd_acc_columns(
            t.m,
            |j| h * weights[j],
            &ws.stage.lq,
            d,
            &mut ws.stage.dd_hi,
            &mut ws.stage.dd_lo,
        );
        let (impulse, impulse_lo) = ws.iterate.impulse_mut();
        for r in 0..d {
            (impulse[r], impulse_lo[r]) = two_sum(ws.stage.dd_hi[r], ws.stage.dd_lo[r]);
        }
    }
}

/// −F into `delta` (k×D): row 0 the momentum row `row0(r)`, rows b ≥ 1 M c_b plus the
/// projections already in `delta`; returns max |F| (∞ if an entry is not finite).
///
/// With a diagonal M (`tiled`: its diagonal repeated for every mode) rows b ≥ 1 are one flat
/// loop over their (k − 1)·D entries, which vectorises; the same products and sums as the
/// row-by-row form below.
fn close_rows(
    sep: &Separable,
    tiled: Option<&[f64]>,
    c: &[f64],
    delta: &mut [f64],
    row0: impl Fn(usize) -> f64,
    d: usize,
) -> f64 {
    for (r, x) in delta[..d].iter_mut().enumerate() {
        *x = -row0(r);
    }
    match tiled {
        Some(tiled) => {
            // Rows b ≥ 1 and the max-norm in one pass, whole blocks of eight as arrays (the
            // same operations per entry; a maximum does not depend on its order).
            const LANES: usize = 8;
            let size = |v: f64| if v.is_nan() { f64::INFINITY } else { v.abs() };
            let mut lanes = [0.0f64; LANES];
            let (xb, xr) = delta[d..].as_chunks_mut::<LANES>();
            let (cb, cr) = c[d..].as_chunks::<LANES>();
            let (mb, mr) = tiled[d..].as_chunks::<LANES>();
            for ((x, c), m) in xb.iter_mut().zip(cb).zip(mb) {
                *x = std::array::from_fn(|l| -(m[l] * c[l] + x[l]));
                lanes = std::array::from_fn(|l| lanes[l].max(size(x[l])));
            }
            for ((x, &c), &m) in xr.iter_mut().zip(cr).zip(mr) {
                *x = -(m * c + *x);
                lanes[0] = lanes[0].max(size(*x));
            }
            let rows0 = max_abs_or_infinite(&delta[..d]);
            return lanes.iter().fold(rows0, |a, &b| a.max(b));
        }
        None => {
            for (delta, c) in delta.chunks_exact_mut(d).zip(c.chunks_exact(d)).skip(1) {
                for (r, x) in delta.iter_mut().enumerate() {
                    *x = -(sep.mass_row_times(r, c) + *x);
                }
            }
        }
    }
    max_abs_or_infinite(delta)
}

/// The exact Newton matrix of the velocity form, J = I ⊗ M + h² Σ_j b_j ψ_j ι_jᵀ ⊗ H_j, from the
/// node force Jacobians `hall` (m×D×D), into `dn.jac`: per row block b, the D² sums
/// Σ_j (h² b_j ψ_jb H_j[r, s]) ι_j· accumulated along the rows of ι (contiguous, vectorised),
/// as the nodal Newton matrix is (`stage.rs`), then scattered into the blocks.
pub(super) fn assemble_dense(
    vt: &VelocityTables,
    weights: &[f64],
    h: f64,
    d: usize,
    hall: &[f64],
    sep: Option<&crate::integrator::separable::Separable>,
    dn: &mut DenseNewton,
) {
    let k = vt.k;
    let (size, dd) = (k * d, d * d);
    let h2 = h * h;
    for b in 0..k {
        let acc = &mut dn.acc[..dd * k];
        acc.iter_mut().for_each(|x| *x = 0.0);
        for (j, hj) in hall.chunks_exact(dd).enumerate() {
            let base = h2 * weights[j] * vt.psi[j * k + b];
            if base == 0.0 {
                continue;
            }
            let row = &vt.iota[j * k..(j + 1) * k];
            for (rs, &hrs) in hj.iter().enumerate() {
                let g = base * hrs;
                if g == 0.0 {
                    continue;
                }
                for (x, &y) in acc[rs * k..(rs + 1) * k].iter_mut().zip(row) {
                    *x += g * y;
                }
            }
        }
        for r in 0..d {
            let jrow = (b * d + r) * size;
            for s in 0..d {
                let block = &acc[(r * d + s) * k..(r * d + s + 1) * k];
                for (a, &v) in block.iter().enumerate() {
                    dn.jac[jrow + a * d + s] = v;
                }
            }
        }
    }
    if let Some(sep) = sep {
        for b in 0..k {
            for r in 0..d {
                for s in 0..d {
                    dn.jac[(b * d + r) * size + b * d + s] += sep.mass()[r * d + s];
                }
            }
        }
    }
}
