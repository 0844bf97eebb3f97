//! Row 0 of the velocity form's residual, the momentum condition F_0 = M c_0 + h Σ_j b_j ψ_j0 f_j
//! − p_k that fixes q_{k+1} = q_k + h c_0: rounded for the step's guesses, in double-double at
//! the iterates.

use crate::integrator::dd::{dd_acc, two_sum};
use crate::integrator::separable::Separable;

/// How [`GalerkinIntegrator::velocity_residual`] sums the momentum row F_0 = M c_0 + h Σ_j b_j
/// ψ_j0 f_j − p_k, whose terms cancel to the size of the force term.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum MomentumRow {
    /// In double-double, with c_0's and the momentum's low parts (`momentum_row`): the
    /// residual the converged modes are judged and finished by.
    Compensated,
    /// In working precision from the projections (an error of a few ulps of |p_k|): for the
    /// step's guesses, whose first correction is many orders above that rounding (1e-5 to
    /// 1e-8 relative on Kepler) and is followed by compensated iterations. Rounded rows
    /// inside the iteration too (after corrections above 1e-10) saved 7 % more on Kepler and
    /// the N-body scenes but made the T = 20 000 energy changes one-signed (|mean|/rms 0.79
    /// over eight realisations; docs/solvers.md).
    Rounded,
}

/// The momentum row F_0 for coordinate r in working precision: (M c_0)_r − p_k,r plus the
/// force term's projection `force` (row 0 of the projections).
pub(super) fn rounded_momentum_row(
    sep: &Separable,
    c: &[f64],
    p_k: &[f64],
    force: f64,
    r: usize,
) -> f64 {
    (sep.mass_row_times(r, c) - p_k[r]) + force
}

/// The start of the momentum row for coordinate r (the condition that fixes q_{k+1} = q_k +
/// h c_0): M c_0 − p_k in double-double (exact products by FMA, TwoSum), with c_0's low part
/// and the momentum's own low part; the force terms are added to it by the caller. M c_0 − p_k
/// cancels to the size of the force term, and a rounded sum would leave a one-signed error in
/// every step's increment (the nodal Legendre-transform row is summed the same way,
/// `legendre_transform`).
pub(super) fn momentum_row(
    sep: &Separable,
    c: &[f64],
    c0_lo: &[f64],
    p_k: &[f64],
    momentum_lo: &[f64],
    r: usize,
) -> (f64, f64) {
    let d = c0_lo.len();
    let (mut hi, mut lo) = (0.0, 0.0);
    match sep.mass_diagonal() {
        Some(diag) => {
            dd_acc(&mut hi, &mut lo, diag[r], c[r]);
            lo += diag[r] * c0_lo[r];
        }
        None => {
            for s in 0..d {
                dd_acc(&mut hi, &mut lo, sep.mass()[r * d + s], c[s]);
                lo += sep.mass()[r * d + s] * c0_lo[s];
            }
        }
    }
    let (s, e) = two_sum(hi, -p_k[r]);
    (s, lo + (e - momentum_lo[r]))
}

/// What row 0, the momentum condition F_0 = M c_0 + h Σ_j b_j ψ_j0 f_j − p_k, is made of:
/// the mass matrix, the modes (c_0 with its low part), the momentum (with its low part), and
/// the forces at the nodes with the rule's weights and the test function ψ_0.
pub(super) struct MomentumRows<'a> {
    pub(super) sep: &'a Separable,
    pub(super) c: &'a [f64],
    pub(super) c0_lo: &'a [f64],
    pub(super) p_k: &'a [f64],
    pub(super) momentum_lo: &'a [f64],
    pub(super) weights: &'a [f64],
    pub(super) psi: &'a [f64],
    pub(super) lq: &'a [f64],
    pub(super) k: usize,
    pub(super) h: f64,
    pub(super) d: usize,
}

impl MomentumRows<'_> {
    /// Row 0 for the coordinates of `columns` (runs [a, b)) into `hi`: rounded from its
    /// projection (row 0 of `projections`), or in double-double (`momentum_row`) with the
    /// force terms added eight coordinates side by side, their (hi, lo) pairs in registers:
    /// each sum runs over j in order (the same bits as one coordinate at a time), independent
    /// sums hide each other's latency, and they vectorise for large D. The row is their sum
    /// hi + lo. The lanes are a constant (8, then 4, 2, 1 for the rest), so the pairs stay in
    /// registers: with the lanes a run-time count they went through the stack (issue 35's
    /// J2000 profile).
    pub(super) fn fill(
        &self,
        columns: &[(usize, usize)],
        momentum: MomentumRow,
        projections: &[f64],
        hi: &mut [f64],
        lo: &mut [f64],
    ) {
        for &(a, b) in columns {
            if momentum == MomentumRow::Rounded {
                for r in a..b {
                    hi[r] = rounded_momentum_row(self.sep, self.c, self.p_k, projections[r], r);
                }
                continue;
            }
            for r in a..b {
                (hi[r], lo[r]) =
                    momentum_row(self.sep, self.c, self.c0_lo, self.p_k, self.momentum_lo, r);
            }
            let mut r0 = a;
            while r0 < b {
                r0 += match b - r0 {
                    8.. => self.add_force_terms::<8>(r0, hi, lo),
                    4..=7 => self.add_force_terms::<4>(r0, hi, lo),
                    2 | 3 => self.add_force_terms::<2>(r0, hi, lo),
                    _ => self.add_force_terms::<1>(r0, hi, lo),
                };
            }
        }
    }

    /// The force terms Σ_j ψ_j0 (h b_j f_j) of coordinates r0 … r0 + L − 1 added to their
    /// (hi, lo) starts in `hi`, `lo`, the sum hi + lo into `hi`; returns L.
    fn add_force_terms<const L: usize>(&self, r0: usize, hi: &mut [f64], lo: &[f64]) -> usize {
        let d = self.d;
        let mut h_acc: [f64; L] = std::array::from_fn(|l| hi[r0 + l]);
        let mut l_acc: [f64; L] = std::array::from_fn(|l| lo[r0 + l]);
        for (j, &b) in self.weights.iter().enumerate() {
            let (w, psi) = (b * self.h, self.psi[j * self.k]);
            let f = &self.lq[j * d + r0..j * d + r0 + L];
            for l in 0..L {
                let g = w * f[l];
                dd_acc(&mut h_acc[l], &mut l_acc[l], psi, g);
                l_acc[l] += psi * w.mul_add(f[l], -g);
            }
        }
        for l in 0..L {
            hi[r0 + l] = h_acc[l] + l_acc[l];
        }
        L
    }
}
