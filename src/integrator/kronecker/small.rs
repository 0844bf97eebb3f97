//! The frozen-Hessian solve of [`super::KroneckerWork::solve`] for few coordinates (D ≤
//! [`SMALL_MAX_D`], full frozen Hessian), with D a constant and each coordinate's k values
//! contiguous: the same operations in the same order, so the same bits, without the general
//! route's strided products.
//!
//! For Kepler-like problems a solve is a few hundred multiply–adds (R r, r V, the
//! back-substitution with T, ζ Vᵀ, U ζ; k = n − 1 ≈ 12, D = 2), and the general route's
//! index arithmetic and bounds checks around them cost about ten instructions per
//! multiply–add: the Kronecker correction was 37 % of a step in issue 35's profile of the
//! fastest Kepler configuration at 1e-9. Here every product runs along contiguous columns
//! (R and U are stored by columns once), and the back-substitution's coupling sums are
//! contiguous dot products per coordinate.

use crate::linalg::{PANEL, panel_product};

/// The column stride of the stored R and U: [`PANEL`] when the panel kernel applies.
fn column_stride(k: usize) -> usize {
    if k <= PANEL { PANEL } else { k }
}

/// out (k×D, by rows) = C x for the k×k matrix C stored by columns (stride
/// [`column_stride`]) and x (k×D, by rows): each entry summed over the columns in order from
/// zero, as one register panel for k ≤ [`PANEL`] and the plain loop otherwise (the same
/// bits).
fn columns_times<const D: usize>(cols: &[f64], x: &[f64], k: usize, out: &mut [f64]) {
    if k <= PANEL {
        let acc = panel_product::<D>(cols, x, k);
        for (i, o) in out.chunks_exact_mut(D).enumerate() {
            for s in 0..D {
                o[s] = acc[s][i];
            }
        }
        return;
    }
    out.iter_mut().for_each(|v| *v = 0.0);
    for (col, row) in cols.chunks_exact(k).zip(x.chunks_exact(D)) {
        let xr: [f64; D] = std::array::from_fn(|s| row[s]);
        for (o, &c) in out.chunks_exact_mut(D).zip(col) {
            for s in 0..D {
                o[s] += c * xr[s];
            }
        }
    }
}

/// Largest D served by this kernel; N-body systems keep the general route (which vectorises
/// along the coordinates).
pub(crate) const SMALL_MAX_D: usize = 4;

/// R and U stored by columns for this kernel: column a at `[a·w ..][..k]`, w =
/// [`column_stride`] (the rows beyond k zero), from the row-major k×k `m`.
pub(super) fn by_columns(m: &[f64], k: usize) -> Vec<f64> {
    let w = column_stride(k);
    let mut out = vec![0.0; k * w];
    for i in 0..k {
        for a in 0..k {
            out[a * w + i] = m[i * k + a];
        }
    }
    out
}

/// The solve's per-coordinate scratch (the Schur factors by columns are in the tables:
/// [`super::KroneckerTables::r_cols`], [`super::KroneckerTables::u_cols`]).
#[derive(Debug, Clone)]
pub(crate) struct SmallSolve {
    k: usize,
    /// R r, (R r) V, ζ and ζ Vᵀ (k×D each, by rows, as the right-hand side).
    y: Vec<f64>,
    yh: Vec<f64>,
    zeta: Vec<f64>,
    back: Vec<f64>,
}

impl SmallSolve {
    /// Buffers for k = n − 1 unknown blocks and D ≤ [`SMALL_MAX_D`] coordinates.
    pub(crate) fn new(k: usize, d: usize) -> Self {
        SmallSolve {
            k,
            y: vec![0.0; d * k],
            yh: vec![0.0; d * k],
            zeta: vec![0.0; d * k],
            back: vec![0.0; d * k],
        }
    }

    /// x = U ζ Vᵀ with ζ from the back-substitution of (I/h + h μ_r T) ζ_r = ((R r) V)_r, in
    /// place (`rhs`: k×D, block-row-major). `v`, `vt`: V and Vᵀ (D×D, row-major); `mu`: the
    /// eigenvalues; `inv`: the diagonal blocks' inverses as [`super::KroneckerWork`] stores
    /// them (four entries per (row of T, coordinate), at the block's first row).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn solve(
        &mut self,
        kt: &super::KroneckerTables,
        h: f64,
        v: &[f64],
        mu: &[f64],
        inv: &[f64],
        d: usize,
        rhs: &mut [f64],
    ) {
        match d {
            1 => self.solve_static::<1>(kt, h, v, mu, inv, rhs),
            2 => self.solve_static::<2>(kt, h, v, mu, inv, rhs),
            3 => self.solve_static::<3>(kt, h, v, mu, inv, rhs),
            _ => self.solve_static::<4>(kt, h, v, mu, inv, rhs),
        }
    }

    fn solve_static<const D: usize>(
        &mut self,
        kt: &super::KroneckerTables,
        h: f64,
        v: &[f64],
        mu: &[f64],
        inv: &[f64],
        rhs: &mut [f64],
    ) {
        let k = self.k;
        // y = R r: each entry summed over a in order from zero (the general route's
        // few-column product), by columns of R, the D coordinates of a row side by side.
        let y = &mut self.y[..k * D];
        columns_times::<D>(&kt.r_cols, rhs, k, y);
        // ŷ = y V: ŷ_ar = Σ_s y_as V[s][r], s in order from zero.
        for (yh, y) in self.yh.chunks_exact_mut(D).zip(y.chunks_exact(D)) {
            for (r, o) in yh.iter_mut().enumerate() {
                let mut sum = 0.0;
                for s in 0..D {
                    sum += y[s] * v[s * D + r];
                }
                *o = sum;
            }
        }
        // Back-substitution over the diagonal blocks of T, last first, the D coordinates side
        // by side: ζ_i = inv_i (ŷ_i − h μ Σ_{j beyond the block} T_ij ζ_j), each sum over j in
        // order from zero (the general route skips zero T_ij, whose products would change at
        // most the sign of an exactly zero sum).
        let hmu: [f64; D] = std::array::from_fn(|r| h * mu[r]);
        let zeta = &mut self.zeta[..k * D];
        for &(i, s) in kt.blocks.iter().rev() {
            let mut acc = [[0.0f64; D]; 2];
            for (p, acc) in acc.iter_mut().enumerate().take(s) {
                let row = i + p;
                let mut sum = [0.0f64; D];
                let t_row = &kt.t[row * k + i + s..(row + 1) * k];
                for (&tij, z) in t_row.iter().zip(zeta[(i + s) * D..].chunks_exact(D)) {
                    for r in 0..D {
                        sum[r] += tij * z[r];
                    }
                }
                for r in 0..D {
                    acc[r] = self.yh[row * D + r] - hmu[r] * sum[r];
                }
            }
            for r in 0..D {
                let b = &inv[4 * (i * D + r)..4 * (i * D + r) + 4];
                if s == 1 {
                    zeta[i * D + r] = b[0] * acc[0][r];
                } else {
                    zeta[i * D + r] = b[0] * acc[0][r] + b[1] * acc[1][r];
                    zeta[(i + 1) * D + r] = b[2] * acc[0][r] + b[3] * acc[1][r];
                }
            }
        }
        // ζ Vᵀ: entry (a, s) is Σ_r ζ_ar V[s][r], r in order from zero.
        for (back, z) in self.back.chunks_exact_mut(D).zip(zeta.chunks_exact(D)) {
            for (s, o) in back.iter_mut().enumerate() {
                let mut sum = 0.0;
                for r in 0..D {
                    sum += z[r] * v[s * D + r];
                }
                *o = sum;
            }
        }
        // x = U (ζ Vᵀ), by columns of U, c in order from zero, into the right-hand side.
        columns_times::<D>(&kt.u_cols, &self.back, k, &mut rhs[..k * D]);
    }
}
