//! The Lagrangian's derivatives at one quadrature node on the general (non-separable) path,
//! with explicit time and forcing.
//!
//! The stage equations project two node quantities on the test functions (paper eq. (3)):
//! the force-like row L_q(c_j) weighted by h b_j φ_a(c_j) and the momentum-like row L_v(c_j)
//! weighted by b_j φ_a'(c_j). The discrete Lagrange–d'Alembert principle adds the force
//! f(t, q, v) to the first (docs/DESIGN.md §2), and a non-autonomous L is evaluated at the
//! node time t_k + c_j h. So at every node the integrator needs
//!
//! - the first row g_q = L_q + f and the second row g_v = L_v;
//! - their derivatives in (q, v): ∂g_q/∂q = L_qq + f_q, ∂g_q/∂v = L_qv + f_v,
//!   ∂g_v/∂q = L_vq = L_qvᵀ and ∂g_v/∂v = L_vv. Without forcing the Newton matrix is
//!   symmetric and ∂g_v/∂q is the transpose of ∂g_q/∂v; with it, the two are kept apart.
//!
//! For an autonomous, unforced system these are exactly the calls the general path always
//! made (`gradient_at` and `hessian_at` default to `gradient` and `hessian`), so its maps
//! are bit-for-bit unchanged.

use crate::lagrangian::Lagrangian;

/// g_q = L_q + f and g_v = L_v at (t, q, v) into `lq`, `lv`; `f` is scratch (D).
pub(super) fn node_gradient<L: Lagrangian>(
    lag: &L,
    forced: bool,
    (t, q, v): (f64, &[f64], &[f64]),
    lq: &mut [f64],
    lv: &mut [f64],
    f: &mut [f64],
) {
    lag.gradient_at(t, q, v, lq, lv);
    if forced {
        lag.external_force(t, q, v, f);
        for (a, b) in lq.iter_mut().zip(f.iter()) {
            *a += b;
        }
    }
}

/// The four D×D blocks ∂g_q/∂q, ∂g_q/∂v, ∂g_v/∂q, ∂g_v/∂v at (t, q, v) (row-major, entry
/// (r, s) the derivative of component r by coordinate s); `fq`, `fv` are scratch (D×D).
#[allow(clippy::too_many_arguments)]
pub(super) fn node_hessian<L: Lagrangian>(
    lag: &L,
    forced: bool,
    (t, q, v): (f64, &[f64], &[f64]),
    [hqq, hqv, hvq, hvv]: [&mut [f64]; 4],
    fq: &mut [f64],
    fv: &mut [f64],
) {
    let d = q.len();
    lag.hessian_at(t, q, v, hqq, hqv, hvv);
    for r in 0..d {
        for s in 0..d {
            hvq[r * d + s] = hqv[s * d + r];
        }
    }
    if forced {
        lag.external_force_jacobian(t, q, v, fq, fv);
        for (a, b) in hqq.iter_mut().zip(fq.iter()) {
            *a += b;
        }
        for (a, b) in hqv.iter_mut().zip(fv.iter()) {
            *a += b;
        }
    }
}
