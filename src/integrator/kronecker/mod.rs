//! Simplified Newton with a frozen Hessian, solved through the Kronecker structure of the
//! stage Jacobian (the structured solver the paper's conclusion points to).
//!
//! For a separable Lagrangian L = ½ vᵀMv − V(q) the Newton matrix of the initial-value step is
//!
//! J = (P ⊗ I) [ (1/h) K_s ⊗ M + h Σ_j b_j (φ(c_j) φ(c_j)ᵀ)_s ⊗ H_j ],
//!
//! with K_s, the s-blocks, the rows 0…n−2 and columns 1…n−1 of the n×n basis matrices, H_j the
//! force Jacobian L_qq at node j, and P the row operation that turns row block 0 into the
//! Legendre-transform row (row 0 plus Σ_{a ≥ 1} u_a row a). Freezing H_j at one D×D matrix H̄
//! (the quadrature-weighted mean Σ_j b_j H_j) leaves
//!
//! J̃ = (P ⊗ I)(K_s ⊗ I) [ I ⊗ M/h + h C ⊗ H̄ ],   C = K_s⁻¹ G_s,  G_s = Σ_j b_j (φφᵀ)_s.
//!
//! C depends only on (basis, quadrature, n), so its real Schur form C = U T Uᵀ is computed once
//! per integrator. A solve J̃ x = r is then z = (Uᵀ K_s⁻¹ P⁻¹ ⊗ I) r, a block back-substitution
//! with the quasi-triangular T — one D×D system (M/h + h t_ii H̄) per real eigenvalue of C and
//! one 2D×2D system per complex pair — and x = (U ⊗ I) z: O(n²D + nD²) per solve and
//! O(n D³) per factorisation, instead of O((nD)³). The Schur form, not an eigendecomposition,
//! is used so that an ill-conditioned eigenvector basis of the non-symmetric C never enters.

mod small;

use crate::error::{GviError, Result};
use crate::linalg::{Lu, Strided, gemm};
use small::{SMALL_MAX_D, SmallSolve, by_columns};

use super::Tables;
use super::self_blocks::SelfBlocks;

/// The (basis, quadrature, n)-dependent part of the Kronecker solver.
#[derive(Debug, Clone)]
pub(crate) struct KroneckerTables {
    /// k = n − 1, the number of unknown blocks.
    pub k: usize,
    /// R = Uᵀ K_s⁻¹ P⁻¹ (k×k, row-major).
    pub r: Vec<f64>,
    /// The Schur vectors U (k×k).
    pub u: Vec<f64>,
    /// The quasi-upper-triangular Schur factor T (k×k).
    pub t: Vec<f64>,
    /// Diagonal blocks of T: (first index, size 1 or 2).
    pub blocks: Vec<(usize, usize)>,
    /// R and U by columns, for the few-coordinate solve (`small.rs`).
    pub r_cols: Vec<f64>,
    /// See [`r_cols`](Self::r_cols).
    pub u_cols: Vec<f64>,
}

impl KroneckerTables {
    /// Build from the integrator's tables. `None` when K_s is singular or the Schur
    /// iteration fails (the exact solver is then the only one available).
    pub(crate) fn build(t: &Tables) -> Option<Self> {
        let (n, m) = (t.n, t.m);
        if n < 2 {
            return None;
        }
        let k = n - 1;
        let mut ks = vec![0.0; k * k];
        let mut gs = vec![0.0; k * k];
        for a in 0..k {
            for b in 0..k {
                ks[a * k + b] = t.kinetic[a * n + b + 1];
                let mut s = 0.0;
                for j in 0..m {
                    s += t.weights[j] * t.phi[j * n + a] * t.phi[j * n + b + 1];
                }
                gs[a * k + b] = s;
            }
        }
        let lu = Lu::factor(ks, k).ok()?;
        // C = K_s⁻¹ G_s.
        let mut c = gs;
        lu.solve_columns_in_place(&mut c, k);
        // P⁻¹: the identity with first row (1, −u_1, …, −u_{k−1}); X = K_s⁻¹ P⁻¹.
        let mut x = vec![0.0; k * k];
        for a in 0..k {
            x[a * k + a] = 1.0;
        }
        for b in 1..k {
            x[b] = -t.unit[b];
        }
        lu.solve_columns_in_place(&mut x, k);
        Self::from_pencil(&c, &x, k)
    }

    /// The Schur form C = U T Uᵀ of a k×k stage pencil C, with R = Uᵀ X for the map X that
    /// brings a right-hand side to the form (I ⊗ M/h + h C ⊗ H̄) z = X r. The nodal stage
    /// equations have C = K_s⁻¹ G_s and X = K_s⁻¹ P⁻¹; the velocity form has
    /// its own C and X = I.
    pub(crate) fn from_pencil(c: &[f64], x: &[f64], k: usize) -> Option<Self> {
        let cm = nalgebra::DMatrix::from_row_slice(k, k, c);
        let schur = nalgebra::linalg::Schur::try_new(cm, f64::EPSILON, 10_000)?;
        let (um, tm) = schur.unpack();
        if um.iter().chain(tm.iter()).any(|v| !v.is_finite()) {
            return None;
        }
        let mut u = vec![0.0; k * k];
        let mut tt = vec![0.0; k * k];
        for a in 0..k {
            for b in 0..k {
                u[a * k + b] = um[(a, b)];
                tt[a * k + b] = tm[(a, b)];
            }
        }
        // R = Uᵀ X.
        let mut r = vec![0.0; k * k];
        for a in 0..k {
            for c2 in 0..k {
                let ua = u[c2 * k + a];
                if ua != 0.0 {
                    for b in 0..k {
                        r[a * k + b] += ua * x[c2 * k + b];
                    }
                }
            }
        }
        // Diagonal blocks: a nonzero subdiagonal entry couples i and i+1 (a complex pair).
        let scale = tt.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        let mut blocks = Vec::new();
        let mut i = 0;
        while i < k {
            let coupled = i + 1 < k && tt[(i + 1) * k + i].abs() > 1e-14 * scale;
            if coupled {
                blocks.push((i, 2));
                i += 2;
            } else {
                if i + 1 < k {
                    tt[(i + 1) * k + i] = 0.0;
                }
                blocks.push((i, 1));
                i += 1;
            }
        }
        Some(KroneckerTables {
            k,
            r_cols: by_columns(&r, k),
            u_cols: by_columns(&u, k),
            r,
            u,
            t: tt,
            blocks,
        })
    }

    /// The eigenvalues of C (real parts and imaginary parts), for diagnostics.
    pub(super) fn eigenvalues(&self) -> Vec<(f64, f64)> {
        let k = self.k;
        let mut out = Vec::with_capacity(k);
        for &(i, s) in &self.blocks {
            let a = self.t[i * k + i];
            if s == 1 {
                out.push((a, 0.0));
            } else {
                let (b, c, d) = (
                    self.t[i * k + i + 1],
                    self.t[(i + 1) * k + i],
                    self.t[(i + 1) * k + i + 1],
                );
                let mean = 0.5 * (a + d);
                let disc = 0.25 * (a - d) * (a - d) + b * c;
                if disc >= 0.0 {
                    out.push((mean + disc.sqrt(), 0.0));
                    out.push((mean - disc.sqrt(), 0.0));
                } else {
                    out.push((mean, (-disc).sqrt()));
                    out.push((mean, -(-disc).sqrt()));
                }
            }
        }
        out
    }
}

/// Per-workspace buffers of the Kronecker solver: the frozen Hessian, its eigen-decomposition
/// relative to the mass matrix, and the scalar inverses of the decoupled diagonal blocks.
///
/// With H̄ V = M V Λ, VᵀMV = I (H̄ and M symmetric, M positive definite), the substitution
/// z_i = V ζ_i turns the block system (M/h) z_i + h Σ_j T_ij H̄ z_j = y_i into D independent
/// quasi-triangular systems ζ_i/h + h Λ Σ_j T_ij ζ_j = Vᵀ y_i, one per eigenvalue of the
/// pencil: back-substitution is then elementwise over the D coordinates (vectorised), with a
/// closed-form 2×2 inverse for the complex pairs of T.
#[derive(Debug, Clone)]
pub(crate) struct KroneckerWork {
    d: usize,
    /// Coordinate block size b (b = D: the full frozen Hessian; b < D: its diagonal blocks
    /// only, V block diagonal).
    block: usize,
    /// H̄, D×D.
    pub hbar: Vec<f64>,
    /// L⁻¹ for M = L Lᵀ (D×D, lower triangular).
    linv: Vec<f64>,
    /// L⁻¹ H̄ L⁻ᵀ and then its eigenvectors W (D×D each), the eigenvalues μ (D), V = L⁻ᵀ W.
    hhat: Vec<f64>,
    w: Vec<f64>,
    mu: Vec<f64>,
    v: Vec<f64>,
    /// Vᵀ, stored so that both transforms are contiguous products.
    vt: Vec<f64>,
    /// Per row i of T and coordinate r: the inverse of the diagonal block (1×1: entry 0; 2×2:
    /// the four entries of the inverse, stored at the block's first row), 4·k·D.
    inv: Vec<f64>,
    /// R r, then (R r) V, the solution ζ (k×D each), and the coupling sums (2D).
    y: Vec<f64>,
    yh: Vec<f64>,
    zeta: Vec<f64>,
    acc: Vec<f64>,
    /// Exact self-blocks of the fast coordinate blocks ([`super::self_blocks`]).
    pub(crate) exact: SelfBlocks,
    /// The same solve with D a constant, for few coordinates ([`small`]; full frozen
    /// Hessian, D ≤ [`SMALL_MAX_D`]).
    small: Option<SmallSolve>,
}

impl KroneckerWork {
    /// Buffers for k = n − 1 unknown blocks, dimension `d` and the constant mass matrix
    /// `mass` (D×D); `None` when M is not symmetric positive definite. They do not depend on
    /// the Schur form, which the tables build when a solve first needs it.
    pub(crate) fn new(
        k: usize,
        d: usize,
        mass: &[f64],
        blocks: Option<usize>,
        nodes: usize,
        self_block_rate: f64,
    ) -> Option<Self> {
        // Block mode needs b | D and a block-diagonal M (then L⁻¹ is block diagonal too).
        let block = match blocks {
            Some(b) if b > 0 && b < d && d.is_multiple_of(b) => {
                let diagonal_blocks =
                    (0..d).all(|r| (0..d).all(|s| r / b == s / b || mass[r * d + s] == 0.0));
                if diagonal_blocks { b } else { d }
            }
            _ => d,
        };
        // Cholesky M = L Lᵀ, then L⁻¹ by forward substitution.
        let mut l = vec![0.0; d * d];
        for i in 0..d {
            for j in 0..=i {
                let mut s = mass[i * d + j];
                for k in 0..j {
                    s -= l[i * d + k] * l[j * d + k];
                }
                if i == j {
                    if !(s > 0.0 && s.is_finite()) {
                        return None;
                    }
                    l[i * d + i] = s.sqrt();
                } else {
                    l[i * d + j] = s / l[j * d + j];
                }
            }
        }
        let mut linv = vec![0.0; d * d];
        for c in 0..d {
            for i in c..d {
                let mut s = if i == c { 1.0 } else { 0.0 };
                for k in c..i {
                    s -= l[i * d + k] * linv[k * d + c];
                }
                linv[i * d + c] = s / l[i * d + i];
            }
        }
        Some(KroneckerWork {
            d,
            block,
            hbar: vec![0.0; d * d],
            linv,
            hhat: vec![0.0; d * d],
            w: vec![0.0; d * d],
            mu: vec![0.0; d],
            v: vec![0.0; d * d],
            vt: vec![0.0; d * d],
            inv: vec![0.0; 4 * k * d],
            y: vec![0.0; k * d],
            yh: vec![0.0; k * d],
            zeta: vec![0.0; k * d],
            acc: vec![0.0; 2 * d],
            exact: SelfBlocks::new(k, nodes, d, block, self_block_rate),
            small: (block == d && d <= SMALL_MAX_D).then(|| SmallSolve::new(k, d)),
        })
    }

    /// Decompose the frozen Hessian in `self.hbar` against M and invert the decoupled diagonal
    /// blocks 1/h + h T_ii μ_r (and the 2×2 blocks of complex pairs).
    /// The coordinate block size b of the frozen Hessian (b = D: full).
    pub(crate) fn block(&self) -> usize {
        self.block
    }

    /// The configuration dimension D.
    pub(crate) fn dim(&self) -> usize {
        self.d
    }

    pub(crate) fn factor(&mut self, kt: &KroneckerTables, h: f64) -> Result<()> {
        let (d, k) = (self.d, kt.k);
        if self.block < d {
            self.decompose_blocks();
        } else {
            self.decompose_full();
        }
        let singular = |i: usize| GviError::InvalidParameter {
            name: "frozen stage Jacobian".into(),
            value: f64::NAN,
            reason: format!("singular diagonal block {i}"),
        };
        for &(i, s) in &kt.blocks {
            for r in 0..d {
                let mu = self.mu[r];
                let a = 1.0 / h + h * kt.t[i * k + i] * mu;
                let base = 4 * (i * d + r);
                if s == 1 {
                    if a == 0.0 || !a.is_finite() {
                        return Err(singular(i));
                    }
                    self.inv[base] = 1.0 / a;
                } else {
                    let b = h * kt.t[i * k + i + 1] * mu;
                    let c = h * kt.t[(i + 1) * k + i] * mu;
                    let e = 1.0 / h + h * kt.t[(i + 1) * k + i + 1] * mu;
                    let det = a * e - b * c;
                    if det == 0.0 || !det.is_finite() {
                        return Err(singular(i));
                    }
                    self.inv[base..base + 4].copy_from_slice(&[
                        e / det,
                        -b / det,
                        -c / det,
                        a / det,
                    ]);
                }
            }
        }
        Ok(())
    }

    /// Ĥ = L⁻¹ H̄ L⁻ᵀ (symmetrised: H̄ is symmetric up to round-off) = W diag(μ) Wᵀ, and
    /// V = L⁻ᵀ W, Vᵀ.
    fn decompose_full(&mut self) {
        let d = self.d;
        let rd = Strided::rows(0, d);
        gemm(
            d,
            d,
            d,
            1.0,
            &self.linv,
            rd,
            &self.hbar,
            rd,
            0.0,
            &mut self.w,
            rd,
        );
        let lt = Strided::transposed(d);
        gemm(
            d,
            d,
            d,
            1.0,
            &self.w,
            rd,
            &self.linv,
            lt,
            0.0,
            &mut self.hhat,
            rd,
        );
        for i in 0..d {
            for j in 0..i {
                let s = 0.5 * (self.hhat[i * d + j] + self.hhat[j * d + i]);
                self.hhat[i * d + j] = s;
                self.hhat[j * d + i] = s;
            }
        }
        crate::linalg::symmetric_eigen(&mut self.hhat, d, &mut self.mu, &mut self.w);
        gemm(
            d,
            d,
            d,
            1.0,
            &self.linv,
            lt,
            &self.w,
            rd,
            0.0,
            &mut self.v,
            rd,
        );
        for i in 0..d {
            for j in 0..d {
                self.vt[j * d + i] = self.v[i * d + j];
            }
        }
    }

    /// As [`Self::decompose_full`] for the diagonal b×b blocks of Ĥ only: V is block
    /// diagonal, stored as b×b blocks at the start of `v` (and transposed in `vt`).
    fn decompose_blocks(&mut self) {
        let (d, b) = (self.d, self.block);
        let bb = b * b;
        for c in 0..d / b {
            let o = c * b;
            // Ĥ_cc = L⁻¹_cc H̄_cc L⁻ᵀ_cc into hhat[..bb] (w[..bb] as scratch).
            for i in 0..b {
                for j in 0..b {
                    let mut s = 0.0;
                    for k in 0..b {
                        s += self.linv[(o + i) * d + o + k] * self.hbar[(o + k) * d + o + j];
                    }
                    self.w[i * b + j] = s;
                }
            }
            for i in 0..b {
                for j in 0..b {
                    let mut s = 0.0;
                    for k in 0..b {
                        s += self.w[i * b + k] * self.linv[(o + j) * d + o + k];
                    }
                    self.hhat[i * b + j] = s;
                }
            }
            for i in 0..b {
                for j in 0..i {
                    let s = 0.5 * (self.hhat[i * b + j] + self.hhat[j * b + i]);
                    self.hhat[i * b + j] = s;
                    self.hhat[j * b + i] = s;
                }
            }
            let (hb, wb) = (&mut self.hhat[..bb], &mut self.w[..bb]);
            crate::linalg::symmetric_eigen(hb, b, &mut self.mu[o..o + b], wb);
            // V_c = L⁻ᵀ_cc W_c.
            for i in 0..b {
                for j in 0..b {
                    let mut s = 0.0;
                    for k in 0..b {
                        s += self.linv[(o + k) * d + o + i] * wb[k * b + j];
                    }
                    self.v[c * bb + i * b + j] = s;
                    self.vt[c * bb + j * b + i] = s;
                }
            }
        }
    }

    /// out (k×D) = x (k×D) · m, for m = V or Vᵀ, full (b = D) or block diagonal with b×b
    /// blocks stored one after another.
    fn transform(d: usize, b: usize, m: &[f64], k: usize, x: &[f64], out: &mut [f64]) {
        if b == d {
            let rd = Strided::rows(0, d);
            gemm(k, d, d, 1.0, x, rd, m, rd, 0.0, out, rd);
            return;
        }
        match b {
            // The N-body blocks (3-D and 2-D bodies): the block size a constant.
            3 => Self::transform_blocks::<3>(d, m, k, x, out),
            2 => Self::transform_blocks::<2>(d, m, k, x, out),
            _ => {
                let bb = b * b;
                for (xr, or) in x.chunks_exact(d).zip(out.chunks_exact_mut(d)).take(k) {
                    for c in 0..d / b {
                        let blk = &m[c * bb..(c + 1) * bb];
                        let (xs, os) = (&xr[c * b..(c + 1) * b], &mut or[c * b..(c + 1) * b]);
                        for (j, o) in os.iter_mut().enumerate() {
                            let mut s = 0.0;
                            for (i, &xv) in xs.iter().enumerate() {
                                s += xv * blk[i * b + j];
                            }
                            *o = s;
                        }
                    }
                }
            }
        }
    }

    /// [`Self::transform`] for block diagonal m with B×B blocks, B a constant: each block's
    /// product is straight-line code (through run-time loops over b = 3 it took 17
    /// instructions per multiply–add on the outer solar system), every sum over i in order
    /// from zero as there, so the same bits.
    fn transform_blocks<const B: usize>(d: usize, m: &[f64], k: usize, x: &[f64], out: &mut [f64]) {
        for (xr, or) in x.chunks_exact(d).zip(out.chunks_exact_mut(d)).take(k) {
            let rows = xr.chunks_exact(B).zip(or.chunks_exact_mut(B));
            for ((xs, os), blk) in rows.zip(m.chunks_exact(B * B)) {
                for (j, o) in os.iter_mut().enumerate() {
                    let mut s = 0.0;
                    for i in 0..B {
                        s += xs[i] * blk[i * B + j];
                    }
                    *o = s;
                }
            }
        }
    }

    /// Solve J̃ x = r in place (`rhs` holds k×D values, block-row-major).
    pub(crate) fn solve(&mut self, kt: &KroneckerTables, h: f64, rhs: &mut [f64]) {
        let (d, k) = (self.d, kt.k);
        if let Some(small) = self.small.as_mut() {
            // Few coordinates (no self-blocks: those need b < D): the same operations below,
            // in the same order, with D a constant.
            small.solve(kt, h, &self.v, &self.mu, &self.inv, d, rhs);
            return;
        }
        self.exact.save(d, rhs);
        let (rd, rk) = (Strided::rows(0, d), Strided::rows(0, k));
        gemm(k, k, d, 1.0, &kt.r, rk, rhs, rd, 0.0, &mut self.y, rd);
        Self::transform(d, self.block, &self.v, k, &self.y, &mut self.yh);
        // Back-substitution over the diagonal blocks of T, last first, elementwise in r:
        // ζ_i = inv_i (ŷ_i − h μ ∘ Σ_{j beyond the block} T_ij ζ_j).
        for &(i, s) in kt.blocks.iter().rev() {
            for p in 0..s {
                let row = i + p;
                let acc = &mut self.acc[p * d..(p + 1) * d];
                let t_row = &kt.t[row * k..(row + 1) * k];
                // Few coordinates (D ≤ 4): their sums held in registers (a sum kept in memory
                // is bound by store-to-load latency there); each sum runs over j in order, so
                // the result is bit for bit that of the plain loop, which is kept for larger
                // D, where it vectorises along the coordinates (measured 6 % faster on the
                // 10-body problem, D = 30).
                if d > 4 {
                    acc.iter_mut().for_each(|x| *x = 0.0);
                    for (j, &tij) in t_row.iter().enumerate().skip(i + s) {
                        if tij != 0.0 {
                            for (a, z) in acc.iter_mut().zip(&self.zeta[j * d..(j + 1) * d]) {
                                *a += tij * z;
                            }
                        }
                    }
                }
                for r0 in (0..d).step_by(4).filter(|_| d <= 4) {
                    let w = 4.min(d - r0);
                    let out = &mut acc[r0..r0 + w];
                    let (zeta, first) = (&self.zeta[..], i + s);
                    match w {
                        1 => coupling_sum::<1>(t_row, zeta, d, r0, first, out),
                        2 => coupling_sum::<2>(t_row, zeta, d, r0, first, out),
                        3 => coupling_sum::<3>(t_row, zeta, d, r0, first, out),
                        _ => coupling_sum::<4>(t_row, zeta, d, r0, first, out),
                    }
                }
                for ((a, &mu), &y) in acc.iter_mut().zip(&self.mu).zip(&self.yh[row * d..]) {
                    *a = y - h * mu * *a;
                }
            }
            for r in 0..d {
                let inv = &self.inv[4 * (i * d + r)..4 * (i * d + r) + 4];
                if s == 1 {
                    self.zeta[i * d + r] = inv[0] * self.acc[r];
                } else {
                    let (b0, b1) = (self.acc[r], self.acc[d + r]);
                    self.zeta[i * d + r] = inv[0] * b0 + inv[1] * b1;
                    self.zeta[(i + 1) * d + r] = inv[2] * b0 + inv[3] * b1;
                }
            }
        }
        // z = ζ Vᵀ (into y), x = U z.
        Self::transform(d, self.block, &self.vt, k, &self.zeta, &mut self.y);
        gemm(k, k, d, 1.0, &kt.u, rk, &self.y, rd, 0.0, rhs, rd);
        self.exact.solve(d, rhs);
    }

    /// The exact self-blocks (mutable) beside the frozen eigenvalues μ (D) that select them.
    pub(crate) fn parts(&mut self) -> KroneckerWorkParts<'_> {
        KroneckerWorkParts {
            exact: &mut self.exact,
            mu: &self.mu,
        }
    }
}

/// Borrowed parts of a [`KroneckerWork`].
pub(crate) struct KroneckerWorkParts<'a> {
    pub exact: &'a mut SelfBlocks,
    pub mu: &'a [f64],
}

/// out[r] = Σ_{j ≥ first} t_row[j] ζ[j·d + r0 + r] for r < W, the terms in the order of j, zero
/// coefficients skipped.
fn coupling_sum<const W: usize>(
    t_row: &[f64],
    zeta: &[f64],
    d: usize,
    r0: usize,
    first: usize,
    out: &mut [f64],
) {
    let mut a = [0.0f64; W];
    for (j, &tij) in t_row.iter().enumerate().skip(first) {
        if tij != 0.0 {
            let z = &zeta[j * d + r0..j * d + r0 + W];
            for r in 0..W {
                a[r] += tij * z[r];
            }
        }
    }
    out.copy_from_slice(&a);
}
