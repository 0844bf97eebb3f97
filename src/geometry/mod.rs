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
        // In 2-D, a map that is symplectic in each (q_i, p_i) pair but mixes nothing.
        let mut j = DMatrix::identity(4, 4);
        j[(0, 2)] = 0.7;
        assert!(symplecticity_defect(&j) < 1e-15);
        // Scaling one momentum breaks it.
        j[(3, 3)] = 1.1;
        assert!((symplecticity_defect(&j) - 0.1 * 2f64.sqrt()).abs() < 1e-14);
    }
}
