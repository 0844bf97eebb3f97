//! The stage equations of one step: the curve at the quadrature nodes, the action gradient
//! ∂S/∂Q, the residual (with the compensated Legendre-transform rows) and the exact Newton
//! matrix ∂²S/∂Q_a∂Q_b.

use super::dd::{dd_acc, dd_acc_columns, two_sum};
use super::{GalerkinIntegrator, Tables, Workspace};
use crate::basis::Basis;
use crate::lagrangian::Lagrangian;
use crate::linalg::{Strided, gemm};
use crate::quadrature::Quadrature;

/// Which rows and unknowns a solve uses: the initial-value step (rows 0…n−2, unknowns
/// 1…n−1) or the two-point problem of the discrete Lagrangian (rows and unknowns 1…n−2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Mode {
    InitialValue,
    BoundaryValue,
}

impl Mode {
    fn first_row(self) -> usize {
        0
    }
    pub(super) fn first_unknown(self) -> usize {
        1
    }
    pub(super) fn count(self, n: usize) -> usize {
        match self {
            Mode::InitialValue => n - 1,
            Mode::BoundaryValue => n - 2,
        }
    }
    fn row_offset(self) -> usize {
        match self {
            Mode::InitialValue => self.first_row(),
            Mode::BoundaryValue => 1,
        }
    }
}

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// Curve values q(c_j) and velocities q̇(c_j) at every quadrature node from the increments
    /// ΔQ in `coeffs` (or `cand`): q = q_k + Φ ΔQ and q̇ = Φ' ΔQ / h as two matrix products
    /// (Σ u_i φ_i ≡ 1 and Σ u_i φ_i' ≡ 0, so the constant part is added, not multiplied).
    pub(super) fn evaluate_curve(&self, ws: &mut Workspace, coeffs_from_cand: bool) {
        let t = self.tables();
        let (n, m, d, h) = (t.n, t.m, ws.d, self.step_size());
        let coeffs = if coeffs_from_cand {
            &ws.cand
        } else {
            &ws.coeffs
        };
        ws.curve_from_cand = coeffs_from_cand;
        let (rn, rd) = (Strided::rows(0, n), Strided::rows(0, d));
        // q_k + (Φ ΔQ + δq_k): the small parts first, then the large one.
        for (j, row) in ws.qj.chunks_exact_mut(d).enumerate() {
            row.copy_from_slice(&ws.base_err);
            if !coeffs_from_cand {
                let phi_last = t.phi[j * n + n - 1];
                for (x, lo) in row.iter_mut().zip(&ws.last_lo) {
                    *x += phi_last * lo;
                }
            }
        }
        gemm(m, n, d, 1.0, &t.phi, rn, coeffs, rd, 1.0, &mut ws.qj, rd);
        for row in ws.qj.chunks_exact_mut(d) {
            for (x, b) in row.iter_mut().zip(&ws.base) {
                *x += b;
            }
        }
        // Velocities: the separable residual and Jacobian never use them (the kinetic part is
        // the precomputed K ΔQ), only the general path and the value of L_d do.
        if ws.separable.is_none() || ws.need_velocities {
            gemm(
                m,
                n,
                d,
                1.0 / h,
                &t.dphi,
                rn,
                coeffs,
                rd,
                0.0,
                &mut ws.vj,
                rd,
            );
        }
    }

    /// ∂S/∂Q_a for every a into `ws.grad`, from the coefficients in `ws.coeffs` (or
    /// `ws.cand`). Returns the number of first-derivative evaluations.
    pub(super) fn action_gradient<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        cand: bool,
    ) -> usize {
        self.evaluate_curve(ws, cand);
        let t = self.tables();
        let (n, m, d, h) = (t.n, t.m, ws.d, self.step_size());
        ws.grad.iter_mut().for_each(|x| *x = 0.0);
        if let Some(sep) = &ws.separable {
            // Kinetic part (1/h) Σ_b K_ab M ΔQ_b with ΔQ_b = Q_b − u_b q_k: constants applied to
            // the increments, never to Q (docs/DESIGN.md §4).
            let coeffs = if cand { &ws.cand } else { &ws.coeffs };
            match &sep.mass_diagonal {
                // M diagonal (N-body): the same products without the D − 1 zero terms.
                Some(diag) => {
                    for (mq, x) in ws.mq.chunks_exact_mut(d).zip(coeffs.chunks_exact(d)) {
                        for ((y, &m), &x) in mq.iter_mut().zip(diag).zip(x) {
                            *y = m * x;
                        }
                    }
                }
                None => {
                    for b in 0..n {
                        for r in 0..d {
                            let mut s = 0.0;
                            for c in 0..d {
                                s += sep.mass[r * d + c] * coeffs[b * d + c];
                            }
                            ws.mq[b * d + r] = s;
                        }
                    }
                }
            }
            let rd = Strided::rows(0, d);
            if self.options().exact_kinetic && !cand {
                for a in 0..n {
                    let row = &t.kinetic[a * n..(a + 1) * n];
                    ws.dd_hi.iter_mut().for_each(|x| *x = 0.0);
                    ws.dd_lo.iter_mut().for_each(|x| *x = 0.0);
                    dd_acc_columns(n, |b| row[b], &ws.mq, d, &mut ws.dd_hi, &mut ws.dd_lo);
                    for ((g, hi), lo) in ws.grad[a * d..(a + 1) * d]
                        .iter_mut()
                        .zip(&ws.dd_hi)
                        .zip(&ws.dd_lo)
                    {
                        *g = (hi + lo) / h;
                    }
                }
            } else {
                gemm(
                    n,
                    n,
                    d,
                    1.0 / h,
                    &t.kinetic,
                    Strided::rows(0, n),
                    &ws.mq,
                    rd,
                    0.0,
                    &mut ws.grad,
                    rd,
                );
            }
            if !cand {
                // The low part of ΔQ_{n−1} in every kinetic row (the Legendre-transform row and
                // the curve see it too), so that all equations see the same unknown.
                for r in 0..d {
                    let mut s = 0.0;
                    for c in 0..d {
                        s += sep.mass[r * d + c] * ws.last_lo[c];
                    }
                    ws.small_rhs[r] = s / h;
                }
                for a in 0..n {
                    let k = t.kinetic[a * n + n - 1];
                    for r in 0..d {
                        ws.grad[a * d + r] += k * ws.small_rhs[r];
                    }
                }
            }
            lag.force_at_points(&ws.qj, &mut ws.lq);
            for j in 0..m {
                let w = t.weights[j] * h;
                for r in 0..d {
                    ws.scaled[j * d + r] = w * ws.lq[j * d + r];
                }
            }
            // grad += Φᵀ (h b ∘ L_q): the transpose is a strided view of the table.
            let phi_t = Strided {
                offset: 0,
                row_stride: 1,
                col_stride: n,
            };
            gemm(
                n,
                m,
                d,
                1.0,
                &t.phi,
                phi_t,
                &ws.scaled,
                rd,
                1.0,
                &mut ws.grad,
                rd,
            );
        } else {
            for j in 0..m {
                let (lq, lv) = (
                    &mut ws.lq[j * d..(j + 1) * d],
                    &mut ws.lv[j * d..(j + 1) * d],
                );
                lag.gradient(
                    &ws.qj[j * d..(j + 1) * d],
                    &ws.vj[j * d..(j + 1) * d],
                    lq,
                    lv,
                );
                let w = t.weights[j];
                for a in 0..n {
                    let (fq, fv) = (w * h * t.phi[j * n + a], w * t.dphi[j * n + a]);
                    for r in 0..d {
                        ws.grad[a * d + r] += fq * lq[r] + fv * lv[r];
                    }
                }
            }
        }
        m
    }

    /// The Legendre-transform rows of the initial-value residual into `ws.rhs[..D]`, and the
    /// step's total impulse h Σ_j b_j L_q(c_j) into `ws.impulse` + `ws.impulse_lo`.
    ///
    /// The rows are p_k + impulse − ∂S/∂ΔQ_{n−1} = 0, the form that makes
    /// p_{k+1} = p_k + impulse exactly D₂L_d of the discrete Lagrangian the tables define (q_k
    /// enters every node with coefficient exactly 1 and the velocities not at all); in exact
    /// arithmetic it is p_k + Σ_{a<n−1} u_a ∂S/∂Q_a = 0, the paper's eq. (3.2) plus
    /// u-weighted stage equations.
    ///
    /// Round-off (docs/DESIGN.md §4): the terms p_k, the impulse, and both parts of ∂S/∂ΔQ_{n−1}
    /// are O(|p|) each (near periapsis of an eccentric orbit the impulse of a large step is as
    /// large as p) and cancel to O(ε). Rounding them in working precision leaves an error
    /// ε|p| in the row, i.e. in q_{k+1}, every step — and, measured, not a random one: it
    /// made the energy drift linearly (Kepler e = 0.6, Legendre n = 24, h = 0.5:
    /// ΔE = −4e-14 at T = 2000 and −7e-14 at T = 4000, every realisation the same sign; the
    /// harmonic oscillator likewise). So for separable Lagrangians the whole row is summed in
    /// double-double: products exact by FMA, sums by TwoSum, including the low parts of the
    /// state (p_err) and of ΔQ_{n−1}. The drift fell below the random walk (`tests/roundoff.rs`).
    fn legendre_transform_rows(&self, ws: &mut Workspace, p_k: &[f64]) {
        let (t, h) = (self.tables(), self.step_size());
        let (d, n) = (ws.d, ws.n);
        let last = (n - 1) * d;
        ws.dd_hi.iter_mut().for_each(|x| *x = 0.0);
        ws.dd_lo.iter_mut().for_each(|x| *x = 0.0);
        let weights = &t.weights;
        dd_acc_columns(
            t.m,
            |j| h * weights[j],
            &ws.lq,
            d,
            &mut ws.dd_hi,
            &mut ws.dd_lo,
        );
        for r in 0..d {
            (ws.impulse[r], ws.impulse_lo[r]) = two_sum(ws.dd_hi[r], ws.dd_lo[r]);
            ws.rhs[r] = (p_k[r] - ws.grad[last + r]) + (ws.impulse[r] + ws.p_err[r]);
        }
        let Some(sep) = &ws.separable else {
            return;
        };
        let x = if ws.curve_from_cand {
            &ws.cand
        } else {
            &ws.coeffs
        };
        // p_k + impulse …
        for r in 0..d {
            let (s, e) = two_sum(p_k[r], ws.impulse[r]);
            ws.dd_hi[r] = s;
            ws.dd_lo[r] = e + (ws.p_err[r] + ws.impulse_lo[r]);
        }
        // … − Σ_j φ_{n−1}(c_j) h b_j L_q(c_j) (side by side over r, each sum in the order
        // of j) …
        for j in 0..t.m {
            let w = h * t.weights[j];
            let phi = t.phi[j * n + n - 1];
            let lq = &ws.lq[j * d..(j + 1) * d];
            for ((s, e), &f) in ws.dd_hi.iter_mut().zip(ws.dd_lo.iter_mut()).zip(lq) {
                let g = w * f;
                dd_acc(s, e, -phi, g);
                *e -= phi * w.mul_add(f, -g);
            }
        }
        for r in 0..d {
            let (mut s, mut e) = (ws.dd_hi[r], ws.dd_lo[r]);
            // … − (1/h) Σ_b K_{n−1,b} M ΔQ_b.
            let row = sep.kinetic_last_start[r]..sep.kinetic_last_start[r + 1];
            let (kinetic, index) = (&sep.kinetic_last[row.clone()], &sep.kinetic_last_index[row]);
            for (c, &i) in kinetic.iter().zip(index) {
                dd_acc(&mut s, &mut e, -c, x[i]);
            }
            if !ws.curve_from_cand {
                for (c, &i) in kinetic.iter().zip(index) {
                    if i >= last {
                        e -= c * ws.last_lo[i - last];
                    }
                }
            }
            ws.rhs[r] = s + e;
        }
    }

    /// Residual of the stage equations for `mode` into `ws.rhs` (negated, ready for the
    /// Newton solve); returns its max-norm.
    pub(super) fn residual(&self, ws: &mut Workspace, mode: Mode, p_k: &[f64]) -> f64 {
        let (d, n) = (ws.d, ws.n);
        let rows = mode.count(n) * d;
        let off = mode.row_offset() * d;
        let mut norm = 0.0f64;
        if mode == Mode::InitialValue {
            self.legendre_transform_rows(ws, p_k);
        }
        for i in 0..rows {
            let r = if mode == Mode::InitialValue && i < d {
                ws.rhs[i]
            } else {
                ws.grad[off + i]
            };
            ws.rhs[i] = -r;
            norm = norm.max(r.abs());
            if !r.is_finite() {
                norm = f64::INFINITY;
            }
        }
        norm
    }

    /// Assemble the exact Jacobian ∂²S/∂Q_a∂Q_b for `mode` into `ws.jac` (uses the curve values
    /// left in the workspace by the last gradient evaluation). Returns Hessian evaluations.
    pub(super) fn jacobian<L: Lagrangian>(&self, lag: &L, ws: &mut Workspace, mode: Mode) -> usize {
        let evals = self.jacobian_rows(lag, ws, mode);
        if mode == Mode::InitialValue {
            // Row block 0 of the Legendre-transform equation as residual() forms it:
            // Σ_{a<n−1} u_a (row block a).
            let t = self.tables();
            let (n, d) = (t.n, ws.d);
            let size = (n - 1) * d;
            let (first, rest) = ws.jac[..size * size].split_at_mut(d * size);
            for a in 1..n - 1 {
                let u = t.unit[a];
                if u != 0.0 {
                    let block = &rest[(a - 1) * d * size..a * d * size];
                    for (x, y) in first.iter_mut().zip(block) {
                        *x += u * y;
                    }
                }
            }
        }
        evals
    }

    /// The rows ∂²S/∂Q_a∂Q_b of [`jacobian`](Self::jacobian), before row block 0 is combined.
    pub(super) fn jacobian_rows<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        mode: Mode,
    ) -> usize {
        let t: &Tables = self.tables();
        let (n, m, d, h) = (t.n, t.m, ws.d, self.step_size());
        let cnt = mode.count(n);
        let size = cnt * d;
        let (r0, u0) = (mode.row_offset(), mode.first_unknown());
        let jac = &mut ws.jac[..size * size];
        match (&ws.separable, mode) {
            (Some(sep), Mode::InitialValue) => jac.copy_from_slice(&sep.kinetic_jacobian),
            (Some(sep), Mode::BoundaryValue) => {
                for a in 0..cnt {
                    for b in 0..cnt {
                        let k = t.kinetic[(a + r0) * n + b + u0] / h;
                        for r in 0..d {
                            for s in 0..d {
                                jac[(a * d + r) * size + b * d + s] = k * sep.mass[r * d + s];
                            }
                        }
                    }
                }
            }
            (None, _) => jac.iter_mut().for_each(|x| *x = 0.0),
        }
        if ws.separable.is_some() {
            // Potential part Σ_j h b_j φ_a(c_j) φ_b(c_j) L_qq(c_j) as d² weighted Gram
            // products Φᵀ diag(g_rs) Φ (one GEMM each) instead of scalar loops (docs/DESIGN.md §4).
            let dd = d * d;
            lag.force_jacobian_at_points(&ws.qj, &mut ws.hall);
            ws.hall_stale = false;
            if d <= 4 && dd <= m {
                // Few coordinates: all d² blocks in one pass over the nodes (the same products
                // and the same order of summation as the per-block products below).
                gram_blocks_fused(t, &ws.hall, &mut ws.gram, jac, (cnt, d, h, r0, u0));
                return m;
            }
            for r in 0..d {
                for s in 0..d {
                    for a in 0..cnt {
                        for j in 0..m {
                            ws.gram[a * m + j] = t.phi[j * n + a + r0]
                                * t.weights[j]
                                * h
                                * ws.hall[j * dd + r * d + s];
                        }
                    }
                    gram_accumulate(
                        &ws.gram,
                        &t.phi,
                        &mut ws.block,
                        jac,
                        (cnt, m, n, u0),
                        (r, s),
                    );
                }
            }
            return m;
        }
        for j in 0..m {
            let q = &ws.qj[j * d..(j + 1) * d];
            let w = t.weights[j];
            let (phi, dphi) = (&t.phi[j * n..(j + 1) * n], &t.dphi[j * n..(j + 1) * n]);
            {
                let v = &ws.vj[j * d..(j + 1) * d];
                lag.hessian(q, v, &mut ws.hqq, &mut ws.hqv, &mut ws.hvv);
                for a in 0..cnt {
                    let (pa, da) = (phi[a + r0], dphi[a + r0]);
                    for b in 0..cnt {
                        let (pb, db) = (phi[b + u0], dphi[b + u0]);
                        let cqq = w * h * pa * pb;
                        let cqv = w * pa * db;
                        let cvq = w * da * pb;
                        let cvv = w * da * db / h;
                        for r in 0..d {
                            let row = (a * d + r) * size + b * d;
                            for s in 0..d {
                                jac[row + s] += cqq * ws.hqq[r * d + s]
                                    + cqv * ws.hqv[r * d + s]
                                    + cvq * ws.hqv[s * d + r]
                                    + cvv * ws.hvv[r * d + s];
                            }
                        }
                    }
                }
            }
        }
        m
    }
}

/// The potential part of the Newton matrix for d ≤ 4 coordinates, every block at once:
/// jac[(a d + r)·size + b d + s] += Σ_j (φ_{a+r0}(c_j) b_j h H_j[r, s]) φ_{b+u0}(c_j), summed
/// over j in order, exactly as [`gram_accumulate`] sums each block (bit-for-bit the same
/// matrix), without the d² separate products. `acc` needs d²·cnt entries. Exploiting the
/// symmetry of H_j (accumulating only the blocks r ≤ s, bit-for-bit the same when H_j is
/// exactly symmetric) was measured 2–5 % slower on Kepler (d = 2, n = 10): with 9 columns per
/// block the loop overhead outweighs the quarter of the products it saves.
fn gram_blocks_fused(
    t: &Tables,
    hall: &[f64],
    acc: &mut [f64],
    jac: &mut [f64],
    dims: (usize, usize, f64, usize, usize),
) {
    let (cnt, d, h, r0, u0) = dims;
    let (n, m, dd) = (t.n, t.m, d * d);
    let size = cnt * d;
    let acc = &mut acc[..dd * cnt];
    for a in 0..cnt {
        acc.iter_mut().for_each(|x| *x = 0.0);
        for j in 0..m {
            let base = t.phi[j * n + a + r0] * t.weights[j] * h;
            let row = &t.phi[j * n + u0..j * n + u0 + cnt];
            for (rs, &hrs) in hall[j * dd..(j + 1) * dd].iter().enumerate() {
                let g = base * hrs;
                if g == 0.0 {
                    continue;
                }
                for (x, &y) in acc[rs * cnt..(rs + 1) * cnt].iter_mut().zip(row) {
                    *x += g * y;
                }
            }
        }
        for r in 0..d {
            for s in 0..d {
                let block = &acc[(r * d + s) * cnt..(r * d + s + 1) * cnt];
                let row = (a * d + r) * size + s;
                for (b, &v) in block.iter().enumerate() {
                    jac[row + b * d] += v;
                }
            }
        }
    }
}

/// jac[(a d + r)·size + b d + s] += Σ_j gram[a m + j] · phi[j n + u0 + b] for a, b < cnt,
/// where size = cnt·d (jac is size×size): one block (r, s) of the Newton matrix as a single
/// matrix product.
fn gram_accumulate(
    gram: &[f64],
    phi: &[f64],
    block: &mut [f64],
    jac: &mut [f64],
    dims: (usize, usize, usize, usize),
    rs: (usize, usize),
) {
    let (cnt, m, n, u0) = dims;
    let (r, s, d) = (rs.0, rs.1, jac.len().isqrt() / cnt.max(1));
    let size = cnt * d;
    // Contiguous product first (vectorised inner loop), then scatter into the (r, s) block.
    gemm(
        cnt,
        m,
        cnt,
        1.0,
        gram,
        Strided::rows(0, m),
        phi,
        Strided::rows(u0, n),
        0.0,
        block,
        Strided::rows(0, cnt),
    );
    for a in 0..cnt {
        let row = (a * d + r) * size + s;
        for b in 0..cnt {
            jac[row + b * d] += block[a * cnt + b];
        }
    }
}
