//! The stage equations of one step as Newton sees them: which rows and unknowns a solve uses
//! ([`Mode`]), the residual assembled from the action gradient ∂S/∂Q
//! ([`discrete_action`](super::discrete_action)) and the Legendre-transform rows
//! ([`legendre_transform`](super::legendre_transform)), and the exact Newton matrix
//! ∂²S/∂Q_a∂Q_b.

use super::node_model::node_hessian;
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
    /// Residual of the stage equations for `mode` into the Newton right-hand side (negated, ready for the
    /// Newton solve); returns its max-norm.
    pub(super) fn residual(&self, ws: &mut Workspace, mode: Mode, p_k: &[f64]) -> f64 {
        let (d, n) = (ws.d, ws.n);
        let rows = mode.count(n) * d;
        let off = mode.row_offset() * d;
        let mut norm = 0.0f64;
        if mode == Mode::InitialValue {
            self.legendre_transform_rows(ws, p_k);
        }
        let rhs = ws.system.rhs_mut(rows);
        for i in 0..rows {
            let r = if mode == Mode::InitialValue && i < d {
                rhs[i]
            } else {
                ws.stage.grad[off + i]
            };
            rhs[i] = -r;
            norm = norm.max(r.abs());
            if !r.is_finite() {
                norm = f64::INFINITY;
            }
        }
        norm
    }

    /// Assemble the exact Jacobian ∂²S/∂Q_a∂Q_b for `mode` into the Newton matrix (uses the curve values
    /// left in the workspace by the last gradient evaluation). Returns Hessian evaluations.
    pub(super) fn jacobian<L: Lagrangian>(&self, lag: &L, ws: &mut Workspace, mode: Mode) -> usize {
        let evals = self.jacobian_rows(lag, ws, mode);
        if mode == Mode::InitialValue {
            // Row block 0 of the Legendre-transform equation as residual() forms it:
            // Σ_{a<n−1} u_a (row block a).
            let t = self.tables();
            let (n, d) = (t.n, ws.d);
            let size = (n - 1) * d;
            let (first, rest) = ws.system.jacobian_mut(size).split_at_mut(d * size);
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
        let jac = ws.system.jacobian_mut(size);
        match (&ws.separable, mode) {
            (Some(sep), Mode::InitialValue) => jac.copy_from_slice(sep.kinetic_jacobian()),
            (Some(sep), Mode::BoundaryValue) => {
                for a in 0..cnt {
                    for b in 0..cnt {
                        let k = t.kinetic[(a + r0) * n + b + u0] / h;
                        for r in 0..d {
                            for s in 0..d {
                                jac[(a * d + r) * size + b * d + s] = k * sep.mass()[r * d + s];
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
            ws.stage.evaluate_node_jacobians(lag);
            if d <= 4 && dd <= m {
                // Few coordinates: all d² blocks in one pass over the nodes (the same products
                // and the same order of summation as the per-block products below).
                gram_blocks_fused(
                    t,
                    &ws.stage.hall,
                    &mut ws.stage.gram,
                    jac,
                    (cnt, d, h, r0, u0),
                );
                return m;
            }
            for r in 0..d {
                for s in 0..d {
                    for a in 0..cnt {
                        for j in 0..m {
                            ws.stage.gram[a * m + j] = t.phi[j * n + a + r0]
                                * t.weights[j]
                                * h
                                * ws.stage.hall[j * dd + r * d + s];
                        }
                    }
                    gram_accumulate(
                        &ws.stage.gram,
                        &t.phi,
                        &mut ws.stage.block,
                        jac,
                        (cnt, m, n, u0),
                        (r, s),
                    );
                }
            }
            return m;
        }
        general_blocks(t, lag, ws, (cnt, d, h, r0, u0));
        m
    }
}

/// The Newton matrix of a general (non-separable) Lagrangian, added to `jac` (size × size,
/// size = cnt·d):
///
///   J[(a,r),(b,s)] = Σ_j x_a(j)ᵀ C_j[(·,r),(·,s)] y_b(j),
///
/// x_a = (φ_{a+r0}, φ'_{a+r0})(c_j), y_b = (φ_{b+u0}, φ'_{b+u0})(c_j) and the node blocks
/// C_j = b_j [[h ∂g_q/∂q, ∂g_q/∂v], [∂g_v/∂q, ∂g_v/∂v / h]] (node_model.rs). Formed as
/// Gram-type products, as the separable path forms its potential part: the node blocks once
/// (m node Hessians), then for each column coordinate s the row side
/// Z_s[(a,r),(j,l)] = x_a(j)_0 C_j[r, l d + s] + x_a(j)_1 C_j[d + r, l d + s] and one product
/// Z_s Ψ with Ψ[(j,l), b] = y_b(j)_l (size × 2m × cnt, formed transposed), added to the
/// columns (b, s).
/// That is ~2·d²·cnt²·2m flops in contiguous, vectorised loops, where the per-node, per-(a, b)
/// loop it replaces made ~8·m·cnt²·d² in D-long inner loops (57 % of a Pythagorean
/// time-transformed run, docs/guide/time-transformations.md). The sums are in another order:
/// the matrix, and so the Newton iterates, differ from that loop's at round-off.
fn general_blocks<L: Lagrangian>(
    t: &Tables,
    lag: &L,
    ws: &mut Workspace,
    (cnt, d, h, r0, u0): (usize, usize, f64, usize, usize),
) {
    let (n, m) = (t.n, t.m);
    let (size, dd, two_m) = (cnt * d, d * d, 2 * t.m);
    let forced = ws.stage.forced();
    let st = &mut ws.stage;
    // The weighted node blocks, [h b_j g_qq | b_j g_qv | b_j g_vq | b_j g_vv / h] per node.
    for j in 0..m {
        let (q, v) = (&st.qj[j * d..(j + 1) * d], &st.vj[j * d..(j + 1) * d]);
        node_hessian(
            lag,
            forced,
            (st.tj[j], q, v),
            [&mut st.hqq, &mut st.hqv, &mut st.hvq, &mut st.hvv],
            &mut st.fq,
            &mut st.fv,
        );
        // Stored transposed (entry (r, s) at s·d + r), so that the row side below reads
        // each column s of a block as a contiguous D-vector.
        let w = t.weights[j];
        let node = &mut st.jac_nodes[4 * dd * j..4 * dd * (j + 1)];
        for r in 0..d {
            for c in 0..d {
                let (i, o) = (r * d + c, c * d + r);
                node[o] = w * h * st.hqq[i];
                node[dd + o] = w * st.hqv[i];
                node[2 * dd + o] = w * st.hvq[i];
                node[3 * dd + o] = w / h * st.hvv[i];
            }
        }
    }
    // Ψᵀ (cnt × 2m): column 2j the basis values at node j, column 2j + 1 their derivatives.
    for b in 0..cnt {
        let row = &mut st.jac_psi[b * two_m..(b + 1) * two_m];
        for j in 0..m {
            row[2 * j] = t.phi[j * n + b + u0];
            row[2 * j + 1] = t.dphi[j * n + b + u0];
        }
    }
    let jac = ws.system.jacobian_mut(size);
    for s in 0..d {
        // Z_sᵀ (2m × size), so that the product's inner loop runs over the size = cnt·d rows
        // of J (contiguous, vectorised) rather than over its cnt columns.
        for j in 0..m {
            let node = &st.jac_nodes[4 * dd * j..4 * dd * (j + 1)];
            let column = |k: usize| &node[k * dd + s * d..k * dd + (s + 1) * d];
            let (qq, qv, vq, vv) = (column(0), column(1), column(2), column(3));
            let (phi, dphi) = (&t.phi[j * n + r0..], &t.dphi[j * n + r0..]);
            let (z0, z1) = st.jac_rows[2 * j * size..(2 * j + 2) * size].split_at_mut(size);
            for (a, (z0, z1)) in z0
                .chunks_exact_mut(d)
                .zip(z1.chunks_exact_mut(d))
                .enumerate()
            {
                let (pa, da) = (phi[a], dphi[a]);
                for r in 0..d {
                    z0[r] = pa * qq[r] + da * vq[r];
                    z1[r] = pa * qv[r] + da * vv[r];
                }
            }
        }
        // (Z_s Ψ)ᵀ = Ψᵀ Z_sᵀ (cnt × size), then added to the columns (b, s) of J.
        gemm(
            cnt,
            two_m,
            size,
            1.0,
            &st.jac_psi,
            Strided::rows(0, two_m),
            &st.jac_rows,
            Strided::rows(0, size),
            0.0,
            &mut st.jac_block,
            Strided::rows(0, size),
        );
        for b in 0..cnt {
            let column = &st.jac_block[b * size..(b + 1) * size];
            for (i, &x) in column.iter().enumerate() {
                jac[i * size + b * d + s] += x;
            }
        }
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
