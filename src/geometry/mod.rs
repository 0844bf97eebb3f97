//! Geometric diagnostics: symplecticity of one-step maps, energy and Noether momentum maps
//! at the step ends and along the Galerkin curves, and the `gvi check` report.
//!
//! Phase-space coordinates are ordered (q, p) throughout, and the canonical structure is
//! Ω = [[0, I], [−I, 0]].
//!
//! The properties checked are the ones a variational integrator guarantees (Marsden and
//! West, recalled in the paper's §1.1, and the discrete Noether theorem of its §3.4): the
//! one-step map Φ is symplectic, ΦᵀΩΦ = Ω, measured by
//! [`symplecticity_defect`] on the exact step Jacobian ([`crate::StepJacobian`]); a symmetry
//! generator ξ with an invariant Lagrangian gives a momentum map J(q, p) = p · ξ(q)
//! ([`MomentumMap`], [`Rotation`], [`Translation`]) conserved to round-off; energy is not
//! conserved but bounded, with no drift over long runs. [`check_report`] gathers all three
//! for one run (what `gvi check` prints).
//!
//! Each property has a negative control in the tests: RK4 fails the symplecticity and the
//! momentum checks, so the checks can fail. The measurements are in the guide's page on
//! geometric guarantees (docs/guide/geometric-guarantees.md in the repository).

mod invariants;
mod report;

pub use crate::symmetries::{Generator, MomentumMap, NamedMomentumMap, Rotation, Translation};
pub use invariants::{
    Series, Trend, energy_along_curves, energy_at_step_ends, linear_trend, momentum_along_curves,
    momentum_at_step_ends,
};
pub use report::{
    CURVE_SAMPLES_PER_STEP, CheckReport, MomentumDrift, check_report, check_report_with,
    known_symmetries,
};

use nalgebra::DMatrix;

/// The canonical symplectic matrix Ω = [[0, I], [−I, 0]] of size 2D×2D.
pub fn canonical_structure(d: usize) -> DMatrix<f64> {
    let mut omega = DMatrix::zeros(2 * d, 2 * d);
    for r in 0..d {
        omega[(r, d + r)] = 1.0;
        omega[(d + r, r)] = -1.0;
    }
    omega
}

/// The symplecticity defect ‖JᵀΩJ − Ω‖_F (Frobenius norm) of a 2D×2D Jacobian J in (q, p)
/// order. Zero exactly when the linear map J is symplectic. A matrix that is not square of
/// even size (so not a phase-space map) has infinite defect.
///
/// ```
/// use galerkin_vi::geometry::symplecticity_defect;
/// use nalgebra::DMatrix;
///
/// // The exact flow of the harmonic oscillator, a rotation of phase space: symplectic.
/// let (c, s) = (0.3f64.cos(), 0.3f64.sin());
/// let rot = DMatrix::from_row_slice(2, 2, &[c, s, -s, c]);
/// assert!(symplecticity_defect(&rot) < 1e-15);
/// // A contraction is not: det = 0.81, defect = √2 · |det − 1|.
/// let shrink = DMatrix::from_row_slice(2, 2, &[0.9, 0.0, 0.0, 0.9]);
/// assert!((symplecticity_defect(&shrink) - 2f64.sqrt() * 0.19).abs() < 1e-14);
/// ```
pub fn symplecticity_defect(j: &DMatrix<f64>) -> f64 {
    let (rows, cols) = j.shape();
    if rows != cols || rows % 2 != 0 || rows == 0 {
        return f64::INFINITY;
    }
    let omega = canonical_structure(rows / 2);
    (j.transpose() * &omega * j - omega).norm()
}

/// The symplecticity defect relative to the size of J: ‖JᵀΩJ − Ω‖_F / max(‖J‖_F², 1).
/// Round-off in forming JᵀΩJ is proportional to ‖J‖², so this is the scale-free measure
/// to compare with machine precision (the floor of 1 keeps the exact Ω of a small J from
/// being magnified).
pub fn relative_symplecticity_defect(j: &DMatrix<f64>) -> f64 {
    let scale = j.norm_squared().max(1.0);
    symplecticity_defect(j) / scale
}

/// The central-difference Jacobian of a one-step map (q, p) ↦ (q′, p′) at (q, p), in the
/// (q, p) order of [`canonical_structure`], with step `eps` in every coordinate: for checking
/// the symplecticity of any map — a user's method, a baseline, a negative control — with
/// [`relative_symplecticity_defect`]. Its truncation error is O(eps²|f‴|) and its round-off
/// O(δ/eps) for a map computed to δ, so eps ≈ 1e-5 suits maps solved to round-off (both
/// ≈ 1e-10 relative).
///
/// ```
/// use galerkin_vi::geometry::{finite_difference_jacobian, relative_symplecticity_defect};
///
/// // The symplectic Euler step of the pendulum: symplectic for any h.
/// let h = 0.3;
/// let euler = |q: &[f64], p: &[f64]| {
///     let p1 = p[0] - h * q[0].sin();
///     (vec![q[0] + h * p1], vec![p1])
/// };
/// let j = finite_difference_jacobian(euler, &[0.4], &[0.1], 1e-5);
/// assert!(relative_symplecticity_defect(&j) < 1e-9);
/// ```
pub fn finite_difference_jacobian(
    step: impl Fn(&[f64], &[f64]) -> (Vec<f64>, Vec<f64>),
    q: &[f64],
    p: &[f64],
    eps: f64,
) -> DMatrix<f64> {
    let d = q.len();
    let mut j = DMatrix::zeros(2 * d, 2 * d);
    let (mut qa, mut pa, mut qb, mut pb) = (q.to_vec(), p.to_vec(), q.to_vec(), p.to_vec());
    for c in 0..2 * d {
        qa.copy_from_slice(q);
        qb.copy_from_slice(q);
        pa.copy_from_slice(p);
        pb.copy_from_slice(p);
        if c < d {
            qa[c] += eps;
            qb[c] -= eps;
        } else {
            pa[c - d] += eps;
            pb[c - d] -= eps;
        }
        let ((qa1, pa1), (qb1, pb1)) = (step(&qa, &pa), step(&qb, &pb));
        let (fa, fb) = (qa1.iter().chain(&pa1), qb1.iter().chain(&pb1));
        for (r, (a, b)) in fa.zip(fb).take(2 * d).enumerate() {
            j[(r, c)] = (a - b) / (2.0 * eps);
        }
    }
    j
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defect_of_shear_and_non_square() {
        // A shear [[1, a], [0, 1]] is symplectic in 1-D.
        let shear = DMatrix::from_row_slice(2, 2, &[1.0, 5.0, 0.0, 1.0]);
        assert!(symplecticity_defect(&shear) < 1e-15);
        assert!(relative_symplecticity_defect(&shear) < 1e-15);
        assert!(symplecticity_defect(&DMatrix::zeros(3, 3)).is_infinite());
        assert!(symplecticity_defect(&DMatrix::zeros(2, 4)).is_infinite());
        // The finite-difference Jacobian of a linear map is the map (to round-off); a
        // non-symplectic one (explicit Euler of the oscillator, det = 1 + h²) fails.
        let h = 0.1;
        let explicit = |q: &[f64], p: &[f64]| (vec![q[0] + h * p[0]], vec![p[0] - h * q[0]]);
        let j = finite_difference_jacobian(explicit, &[0.3], &[0.2], 1e-5);
        let exact = DMatrix::from_row_slice(2, 2, &[1.0, h, -h, 1.0]);
        assert!((&j - &exact).norm() < 1e-10);
        assert!(relative_symplecticity_defect(&j) > 1e-3);
        // In 2-D, a map that is symplectic in each (q_i, p_i) pair but mixes nothing.
        let mut j = DMatrix::identity(4, 4);
        j[(0, 2)] = 0.7;
        assert!(symplecticity_defect(&j) < 1e-15);
        // Scaling one momentum breaks it.
        j[(3, 3)] = 1.1;
        assert!((symplecticity_defect(&j) - 0.1 * 2f64.sqrt()).abs() < 1e-14);
    }
}
