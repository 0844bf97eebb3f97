//! Exact self-blocks of the fast coordinate blocks (the fast bodies of an N-body system) in
//! the Kronecker preconditioner.
//!
//! The frozen-Hessian solve of [`super::kronecker`] replaces every node Jacobian H_j by the
//! step's mean H̄. For a body that turns through a large angle in one step (Mercury at
//! h = 100 d: (h ω)² ≈ 50) the neglected variation H_j − H̄ is larger than the kinetic term in
//! the low modes: the frozen iteration stalls, and GMRES has to recover those modes one
//! iteration at a time. For such a
//! block c (b coordinates) the preconditioner instead solves its exact, time-varying
//! self-block of the Newton matrix,
//!
//! A_c = (P ⊗ I) [ (1/h) K_s ⊗ M_cc + h Σ_j b_j (φ(c_j) φ(c_j)ᵀ)_s ⊗ H_j,cc ],
//!
//! ((n−1)b)², factorised once per freeze; the other blocks keep the Kronecker solve (which
//! is block diagonal per body already, so the two combine into one block-Jacobi
//! preconditioner). A block is treated exactly when h² max |μ| exceeds the rate
//! (`StructuredOptions::self_block_rate`, default [`FAST_RATE`]), μ the eigenvalues of its frozen
//! block relative to its mass; at most [`MAX_SELF_BLOCKS`] blocks, the fastest.
//!
//! The velocity form's frozen iteration ([`super::velocity`]) takes the same blocks of its own
//! Newton matrix, A_c = I ⊗ M_cc/h + h Σ_j b_j ψ_j ι_jᵀ ⊗ H_j,cc ([`SelfBlocks::factor_velocity`]),
//! above its own threshold ([`VELOCITY_FAST_RATE`]): at the large steps of the fastest
//! configurations (the outer solar system at h = 912.5 d, where Jupiter turns through 76° in
//! a step) the mean H̄ leaves out most of the variation of Jupiter's block over the step.

use crate::linalg::{Lu, Strided, gemm};

use super::Tables;

/// h² |μ| above which a block's exact self-block replaces the frozen one.
pub(crate) const FAST_RATE: f64 = 4.0;

/// The threshold of the velocity form's exact self-blocks
/// ([`StructuredOptions::velocity_self_block_rate`]).
///
/// [`StructuredOptions::velocity_self_block_rate`]: super::StructuredOptions::velocity_self_block_rate
pub(crate) const VELOCITY_FAST_RATE: f64 = 1.0;

/// At most this many blocks get exact self-blocks (the fastest ones): it bounds the memory,
/// ((n − 1) b)² per block, and the factorisations per freeze for large N.
pub(crate) const MAX_SELF_BLOCKS: usize = 8;

/// Assembly scratch of the self-blocks: A_c ((k b)²), the weighted node values and the Gram
/// blocks (m×k and k×k per distinct entry of a b×b block).
#[derive(Debug, Clone)]
struct Assembly {
    mat: Vec<f64>,
    weighted: Vec<f64>,
    gram: Vec<f64>,
}

/// The exact self-blocks of one workspace (allocated once, for at most [`MAX_SELF_BLOCKS`]).
#[derive(Debug, Clone)]
pub(crate) struct SelfBlocks {
    b: usize,
    k: usize,
    rate: f64,
    /// The block indices with an exact self-block (at most [`MAX_SELF_BLOCKS`]).
    active: Vec<usize>,
    lus: Vec<Lu>,
    /// Assembly scratch of the blocks being factorised.
    assembly: Assembly,
    /// The right-hand sides of the active blocks (kb each) and a solve scratch (kb).
    saved: Vec<f64>,
    scratch: Vec<f64>,
}

impl SelfBlocks {
    /// Buffers for k unknown blocks, m nodes, D coordinates in blocks of b (none when b = D).
    /// `rate`: the threshold on h² max |μ| ([`StructuredOptions::self_block_rate`]); m = 0 or
    /// b = D: no self-blocks.
    ///
    /// [`StructuredOptions::self_block_rate`]: super::StructuredOptions::self_block_rate
    pub(crate) fn new(k: usize, m: usize, d: usize, b: usize, rate: f64) -> Self {
        let blocks = if b < d && b > 0 && m > 0 && rate < f64::MAX {
            (d / b).min(MAX_SELF_BLOCKS)
        } else {
            0
        };
        let kb = k * b;
        let pairs = b * (b + 1) / 2;
        SelfBlocks {
            b,
            k,
            rate,
            active: Vec::with_capacity(blocks),
            lus: (0..blocks).map(|_| Lu::with_capacity(kb)).collect(),
            assembly: Assembly {
                mat: if blocks > 0 {
                    vec![0.0; kb * kb]
                } else {
                    vec![]
                },
                // m×k and k×k for the nodal blocks; the velocity form's assembly takes the
                // b(b+1)/2 entries of a symmetric block side by side.
                weighted: if blocks > 0 {
                    vec![0.0; m * k * pairs]
                } else {
                    vec![]
                },
                gram: if blocks > 0 {
                    vec![0.0; k * k * pairs]
                } else {
                    vec![]
                },
            },
            saved: vec![0.0; blocks * kb],
            scratch: vec![0.0; kb],
        }
    }

    /// No exact self-blocks until the next [`Self::factor`].
    pub(crate) fn clear(&mut self) {
        self.active.clear();
    }

    /// Factorise the exact self-blocks of the blocks whose frozen eigenvalues `mu` (D) give
    /// h² max |μ| above the threshold. `node_entry(j, r, s)` is entry (r, s) of the force
    /// Jacobian at node j (only diagonal blocks are asked for); `mass` is M (D×D).
    pub(crate) fn factor(
        &mut self,
        t: &Tables,
        h: f64,
        mass: &[f64],
        mu: &[f64],
        node_entry: impl Fn(usize, usize, usize) -> f64,
    ) {
        let (b, k) = (self.b, self.k);
        let (n, m) = (t.n, t.m);
        let d = mu.len();
        let kb = k * b;
        self.factor_selected(h, mu, |c, asm| {
            let o = c * b;
            // Kinetic part (1/h) K_s ⊗ M_cc.
            for a in 0..k {
                for e in 0..k {
                    let kin = t.kinetic[a * n + e + 1] / h;
                    for r in 0..b {
                        for s in 0..b {
                            asm.mat[(a * b + r) * kb + e * b + s] = kin * mass[(o + r) * d + o + s];
                        }
                    }
                }
            }
            // Potential part: for each (r, s) the Gram block Σ_j h b_j H_j,rs φ_a φ_{e+1}.
            for r in 0..b {
                for s in 0..b {
                    for j in 0..m {
                        let w = h * t.weights[j] * node_entry(j, o + r, o + s);
                        for e in 0..k {
                            asm.weighted[j * k + e] = w * t.phi[j * n + e + 1];
                        }
                    }
                    let phi_t = Strided::transposed(n);
                    let rk = Strided::rows(0, k);
                    gemm(
                        k,
                        m,
                        k,
                        1.0,
                        &t.phi,
                        phi_t,
                        &asm.weighted,
                        rk,
                        0.0,
                        &mut asm.gram,
                        rk,
                    );
                    for a in 0..k {
                        for e in 0..k {
                            asm.mat[(a * b + r) * kb + e * b + s] += asm.gram[a * k + e];
                        }
                    }
                }
            }
            // P: row block 0 += Σ_{a ≥ 1} u_a (row block a).
            for a in 1..k {
                let u = t.unit[a];
                if u != 0.0 {
                    let (first, rest) = asm.mat.split_at_mut(b * kb);
                    let block = &rest[(a - 1) * b * kb..a * b * kb];
                    for (f, x) in first.iter_mut().zip(block) {
                        *f += u * x;
                    }
                }
            }
        });
    }

    /// [`Self::factor`] for the velocity form ([`super::velocity`]): the exact self-block of
    /// block c in the velocity modes,
    ///
    /// A_c = I_k ⊗ M_cc / h + h Σ_j b_j ψ_j ι_jᵀ ⊗ H_j,cc,
    ///
    /// (k b)²: the block of the velocity form's Newton matrix (`assemble_dense`) that couples
    /// block c's modes to themselves, divided by h as the Kronecker solve's bracket is, with
    /// the time-varying H_j instead of the frozen mean. `psi` and
    /// `iota` are the m×k tables ψ_jb and ι_ja, `weights` the quadrature weights b_j.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn factor_velocity(
        &mut self,
        psi: &[f64],
        iota: &[f64],
        weights: &[f64],
        h: f64,
        mass: &[f64],
        mu: &[f64],
        node_entry: impl Fn(usize, usize, usize) -> f64,
    ) {
        let (b, k) = (self.b, self.k);
        let (d, m, kb) = (mu.len(), weights.len(), k * b);
        let pairs = b * (b + 1) / 2;
        self.factor_selected(h, mu, |c, asm| {
            let o = c * b;
            // H_j,cc is symmetric: its b(b+1)/2 entries r ≤ s, each weighted W_rs = h b_j H_j,rs ι_j
            // (m×k) side by side, and all their Gram blocks ψᵀ W_rs (k×k) in one product.
            let width = pairs * k;
            for j in 0..m {
                let iota_j = &iota[j * k..(j + 1) * k];
                let row = &mut asm.weighted[j * width..(j + 1) * width];
                let mut p = 0;
                for r in 0..b {
                    for s in r..b {
                        let w = h * weights[j] * node_entry(j, o + r, o + s);
                        for (x, &y) in row[p * k..(p + 1) * k].iter_mut().zip(iota_j) {
                            *x = w * y;
                        }
                        p += 1;
                    }
                }
            }
            let rw = Strided::rows(0, width);
            let psi_t = Strided::transposed(k);
            gemm(
                k,
                m,
                width,
                1.0,
                psi,
                psi_t,
                &asm.weighted,
                rw,
                0.0,
                &mut asm.gram,
                rw,
            );
            for row in 0..k {
                let gram = &asm.gram[row * width..(row + 1) * width];
                let mut p = 0;
                for r in 0..b {
                    for s in r..b {
                        for a in 0..k {
                            let v = gram[p * k + a];
                            asm.mat[(row * b + r) * kb + a * b + s] = v;
                            asm.mat[(row * b + s) * kb + a * b + r] = v;
                        }
                        p += 1;
                    }
                }
            }
            for a in 0..k {
                for r in 0..b {
                    for s in 0..b {
                        asm.mat[(a * b + r) * kb + a * b + s] += mass[(o + r) * d + o + s] / h;
                    }
                }
            }
        });
    }

    /// Assemble (`assemble(c, scratch)` into `scratch.mat`) and factorise the exact self-blocks
    /// of the blocks [`selection`] picks from the frozen eigenvalues `mu`, in the order of the
    /// coordinates; a singular block keeps the frozen solve.
    fn factor_selected(
        &mut self,
        h: f64,
        mu: &[f64],
        mut assemble: impl FnMut(usize, &mut Assembly),
    ) {
        self.active.clear();
        if self.lus.is_empty() {
            return;
        }
        let (rate, floor) = selection(self.b, self.rate, self.lus.len(), h, mu);
        for c in 0..mu.len() / self.b {
            if rate(c) <= floor || self.active.len() == self.lus.len() {
                continue;
            }
            assemble(c, &mut self.assembly);
            let slot = self.active.len();
            if self.lus[slot].refactor(&self.assembly.mat).is_ok() {
                self.active.push(c);
            }
        }
    }

    /// Keep the right-hand side's entries of the active blocks (before the Kronecker solve
    /// overwrites them).
    pub(crate) fn save(&mut self, d: usize, rhs: &[f64]) {
        let (b, k) = (self.b, self.k);
        let kb = k * b;
        for (slot, &c) in self.active.iter().enumerate() {
            let saved = &mut self.saved[slot * kb..(slot + 1) * kb];
            for a in 0..k {
                saved[a * b..(a + 1) * b].copy_from_slice(&rhs[a * d + c * b..a * d + c * b + b]);
            }
        }
    }

    /// Overwrite the active blocks of the solution with their exact self-block solves.
    pub(crate) fn solve(&mut self, d: usize, x: &mut [f64]) {
        let (b, k) = (self.b, self.k);
        let kb = k * b;
        for (slot, &c) in self.active.iter().enumerate() {
            let saved = &mut self.saved[slot * kb..(slot + 1) * kb];
            self.lus[slot].solve_in_place_lanes(saved, &mut self.scratch);
            for a in 0..k {
                x[a * d + c * b..a * d + c * b + b].copy_from_slice(&saved[a * b..(a + 1) * b]);
            }
        }
    }
}

/// The rate h² max |μ| of block c (b coordinates), and the floor a block's rate must exceed to
/// get an exact self-block: the threshold, raised to the capacity-th largest rate when more
/// blocks are above it than there are buffers (ties may leave fewer).
fn selection(
    b: usize,
    threshold: f64,
    capacity: usize,
    h: f64,
    mu: &[f64],
) -> (impl Fn(usize) -> f64 + '_, f64) {
    let rate = move |c: usize| {
        mu[c * b..(c + 1) * b]
            .iter()
            .fold(0.0f64, |r, x| r.max(h * h * x.abs()))
    };
    let blocks = mu.len() / b;
    let mut floor = threshold;
    let mut above = (0..blocks).filter(|&c| rate(c) > floor).count();
    while above > capacity {
        floor = (0..blocks)
            .map(rate)
            .filter(|&r| r > floor)
            .fold(f64::INFINITY, f64::min);
        above = (0..blocks).filter(|&c| rate(c) > floor).count();
    }
    (rate, floor)
}
