//! The velocity form's per-workspace state: the iterate, the previous step's modes, the
//! frozen-Hessian and dense solves, and the fixed-point correction.

use super::VelocityTables;
use super::equations::DenseNewton;
use super::freeze::BlockFreeze;
use super::masked::MaskedRows;
use crate::integrator::auto;
use crate::integrator::dd::{max_abs, two_sum};
use crate::integrator::kronecker::KroneckerWork;
use crate::integrator::linear::Linear;
use crate::integrator::separable::Separable;
use crate::linalg::Lu;

/// Unknowns (n − 1)·D up to which a step whose frozen Hessian stalls continues with the dense
/// exact Newton matrix of the velocity form before it is handed to the nodal solvers:
/// [`auto::DENSE_SIZE`], the nodal `auto`'s own dense threshold, and up to this many for
/// systems of at most three coordinates (Kepler to n = 129), whose Hessians and Newton matrix
/// stay cheap. Measured on the outer solar system at h = 1825 d, n = 8 (D = 18, 126 unknowns):
/// continuing densely took 1.9e-4 s per step against 9.2e-5 s when the two stalling steps went
/// to the nodal Newton–Krylov solver.
const VELOCITY_DENSE_SMALL_D: usize = 256;

/// Per-workspace state of the velocity form: the iterate, the previous step's modes, and the
/// frozen-Hessian solve.
#[derive(Debug, Clone)]
pub(crate) struct VelocityState {
    /// The iterate: velocity modes c_0 … c_{k−1} (k×D).
    pub(super) c: Vec<f64>,
    /// The low part of c_0 (D): Newton's last corrections lie below its ulp, and
    /// q_{k+1} − q_k = h c_0 is wanted to more than working precision (as the nodal
    /// solve keeps ΔQ_{n−1}; docs/DESIGN.md §4).
    pub(super) c0_lo: Vec<f64>,
    /// The previous step's converged modes, for the extrapolated guess.
    pub(super) prev: Vec<f64>,
    /// Whether `prev` holds the step just before this one.
    pub(super) has_prev: bool,
    /// −F, then the Newton correction (k×D).
    pub(super) delta: Vec<f64>,
    /// The step's guess, kept while the fixed-point iterations run: a hand-over after they
    /// diverged starts the frozen Hessian from it.
    pub(super) start: Vec<f64>,
    /// Scratch for M⁻¹ of a non-diagonal mass matrix (D).
    pub(super) mass_scratch: Vec<f64>,
    /// A diagonal mass matrix's diagonal repeated for every mode (k×D, the layout of `c`), so
    /// that M c_b and M⁻¹F_b run as one flat, vectorised loop over all modes; `None` for a
    /// non-diagonal M.
    pub(super) mass_tiled: Option<Vec<f64>>,
    /// M = I: M⁻¹ is the identity.
    pub(super) unit_mass: bool,
    /// The frozen-Hessian Kronecker solve of I ⊗ M + h² C ⊗ H̄.
    pub(super) kron: KroneckerWork,
    /// The exact Newton matrix, dense, for steps where the frozen Hessian stalls (small
    /// systems, [`auto::DENSE_SIZE`] and [`VELOCITY_DENSE_SMALL_D`]).
    pub(super) dense: Option<DenseNewton>,
    /// The fixed-point iteration's converged blocks ([`super::freeze`]): for a diagonal mass
    /// matrix and at least two coordinate blocks.
    pub(super) freeze: Option<BlockFreeze>,
    /// The masked residual's rows by coordinate ([`super::masked`]), where blocks can freeze.
    pub(super) masked: Option<MaskedRows>,
}

impl VelocityState {
    /// Forget the previous step's modes (after a failed step, or on request): the next guess
    /// does not extrapolate them.
    pub(crate) fn forget_previous(&mut self) {
        self.has_prev = false;
    }

    /// One correction δ = J⁻¹(−F) from the residual in `delta` (left there) with the frozen
    /// Kronecker matrix or the dense exact one, c ← c + δ with c_0 compensated (TwoSum into
    /// its low part).
    pub(super) fn correct(
        &mut self,
        linear: Linear,
        kt: &crate::integrator::kronecker::KroneckerTables,
        h: f64,
        d: usize,
    ) {
        match (linear, self.dense.as_mut()) {
            (Linear::Dense, Some(dn)) => dn.lu.solve_in_place(&mut self.delta, &mut dn.scratch),
            _ => {
                // J̃ = h (I ⊗ M/h + h C ⊗ H̄): the Kronecker solve of the bracket.
                self.delta.iter_mut().for_each(|x| *x /= h);
                self.kron.solve(kt, h, &mut self.delta);
            }
        }
        self.apply_correction(d);
    }

    /// c ← c + δ, c_0 compensated: TwoSum into its low part.
    pub(super) fn apply_correction(&mut self, d: usize) {
        for ((c, lo), &x) in self.c[..d].iter_mut().zip(&mut self.c0_lo).zip(&self.delta) {
            let (s, e) = two_sum(*c, x);
            *c = s;
            *lo += e;
        }
        for (c, x) in self.c[d..].iter_mut().zip(&self.delta[d..]) {
            *c += x;
        }
    }

    /// One fixed-point correction, J̃ = I ⊗ M: each mode's δ_b = M⁻¹(−F_b) from `delta` (left
    /// there), c ← c + δ with c_0 compensated as in [`Self::correct`]; returns (max |δ|,
    /// max |c|), the iteration's size and scale. With a diagonal M the division is one flat
    /// loop over the k×D entries (vectorised; skipped for M = I, where it is exact), the same
    /// arithmetic as row by row: in Kepler's fastest run the per-row calls were 4 % of the time.
    pub(super) fn correct_fixed_point(&mut self, sep: &Separable, d: usize) -> (f64, f64) {
        match self.mass_tiled.as_deref() {
            Some(tiled) if self.unit_mass => {
                fused_correction::<false>(&mut self.c, &mut self.c0_lo, &mut self.delta, tiled, d)
            }
            Some(tiled) => {
                fused_correction::<true>(&mut self.c, &mut self.c0_lo, &mut self.delta, tiled, d)
            }
            None => {
                for row in self.delta.chunks_exact_mut(d) {
                    sep.solve_mass(row, &mut self.mass_scratch);
                }
                self.apply_correction(d);
                (max_abs(&self.delta), max_abs(&self.c))
            }
        }
    }

    /// Buffers for `vt`, D coordinates and the mass matrix of `sep` (coordinate blocks as
    /// `Lagrangian::coordinate_blocks`, exact self-blocks above `self_block_rate`:
    /// `StructuredOptions::velocity_self_block_rate`); `None` without a Schur form of the velocity pencil or
    /// with a mass matrix that is not symmetric positive definite.
    pub(crate) fn new(
        vt: &VelocityTables,
        d: usize,
        sep: &Separable,
        blocks: Option<usize>,
        self_block_rate: f64,
    ) -> Option<Self> {
        let size = vt.k * d;
        let mass = sep.mass();
        let freeze = blocks
            .filter(|_| sep.mass_diagonal().is_some())
            .and_then(|b| BlockFreeze::new(d, b));
        let masked = freeze.as_ref().map(|_| MaskedRows::new(vt, d));
        Some(VelocityState {
            mass_tiled: sep
                .mass_diagonal()
                .map(|diag| diag.iter().copied().cycle().take(size).collect()),
            unit_mass: sep
                .mass_diagonal()
                .is_some_and(|m| m.iter().all(|&x| x == 1.0)),
            c: vec![0.0; size],
            c0_lo: vec![0.0; d],
            prev: vec![0.0; size],
            has_prev: false,
            delta: vec![0.0; size],
            start: vec![0.0; size],
            mass_scratch: vec![0.0; d],
            kron: KroneckerWork::new(
                vt.k,
                d,
                mass,
                blocks,
                vt.iota.len() / vt.k.max(1),
                self_block_rate,
            )?,
            freeze,
            masked,
            dense: (size <= auto::DENSE_SIZE || (d <= 3 && size <= VELOCITY_DENSE_SMALL_D)).then(
                || DenseNewton {
                    jac: vec![0.0; size * size],
                    acc: vec![0.0; d * d * vt.k],
                    lu: Lu::with_capacity(size),
                    scratch: vec![0.0; size],
                },
            ),
        })
    }
}

/// [`VelocityState::correct_fixed_point`] for a diagonal mass matrix tiled over the modes, in
/// one pass: δ = −F/m (`DIVIDE`; M = I leaves δ = −F), c ← c + δ (row 0 compensated, as
/// [`VelocityState::apply_correction`]), and the maxima of |δ| and |c|. The same operations on
/// each entry as the four passes it replaces (the division, the correction, then `max_abs`
/// of each), and a maximum does not depend on its order, so the bits are the same; measured
/// (issue 35, J2000 10-body): the passes were 8.5 % of the run.
fn fused_correction<const DIVIDE: bool>(
    c: &mut [f64],
    c0_lo: &mut [f64],
    delta: &mut [f64],
    tiled: &[f64],
    d: usize,
) -> (f64, f64) {
    const LANES: usize = 8;
    let (mut size, mut scale) = ([0.0f64; LANES], [0.0f64; LANES]);
    let step = |x: &mut f64, m: f64| {
        if DIVIDE {
            *x /= m;
        }
        *x
    };
    for (((c, lo), x), &m) in c[..d].iter_mut().zip(c0_lo).zip(&mut delta[..d]).zip(tiled) {
        let x = step(x, m);
        let (s, e) = two_sum(*c, x);
        *c = s;
        *lo += e;
        size[0] = size[0].max(x.abs());
        scale[0] = scale[0].max(s.abs());
    }
    let (c, delta, tiled) = (&mut c[d..], &mut delta[d..], &tiled[d..]);
    // Whole blocks of eight as arrays, so that each line below is one vector operation.
    let (c_blocks, c_rest) = c.as_chunks_mut::<LANES>();
    let (x_blocks, x_rest) = delta.as_chunks_mut::<LANES>();
    let (m_blocks, m_rest) = tiled.as_chunks::<LANES>();
    for ((c, x), m) in c_blocks.iter_mut().zip(x_blocks).zip(m_blocks) {
        let v: [f64; LANES] = std::array::from_fn(|l| if DIVIDE { x[l] / m[l] } else { x[l] });
        *x = v;
        let y: [f64; LANES] = std::array::from_fn(|l| c[l] + v[l]);
        *c = y;
        size = std::array::from_fn(|l| size[l].max(v[l].abs()));
        scale = std::array::from_fn(|l| scale[l].max(y[l].abs()));
    }
    for ((c, x), &m) in c_rest.iter_mut().zip(x_rest).zip(m_rest) {
        let x = step(x, m);
        *c += x;
        size[0] = size[0].max(x.abs());
        scale[0] = scale[0].max(c.abs());
    }
    let fold = |v: [f64; LANES]| v.iter().fold(0.0f64, |a, &b| a.max(b));
    (fold(size), fold(scale))
}
