//! Linear stability of a periodic orbit: the monodromy matrix over one period as the product
//! of the exact step Jacobians of a time-stepping run along the orbit, and its eigenvalues,
//! the Floquet multipliers.
//!
//! Each step Jacobian is symplectic to round-off (the integrator is a variational integrator),
//! so the monodromy is too and its multipliers come in quadruples λ, 1/λ, λ̄, 1/λ̄. Every
//! continuous symmetry contributes a Jordan block at 1: the time shift (the flow direction,
//! with the change of energy, which changes the period), each translation (with the boost,
//! which changes the total momentum) and each rotation (with the change of angular momentum).
//! For the planar three-body problem that is 2 + 2·2 + 2 = 8 trivial multipliers; the other
//! four decide stability. A Jordan block perturbed by ε splits its pair of multipliers by
//! about √ε, so the trivial ones are identified within a tolerance of order 1e-5.

use crate::error::{GviError, Result};
use crate::integrator::GalerkinIntegrator;
use crate::lagrangian::Lagrangian;
use crate::method::MethodSpec;
use nalgebra::{DMatrix, Schur};

/// Monodromy matrix and Floquet multipliers of a periodic orbit.
#[derive(Debug, Clone, PartialEq)]
pub struct Floquet {
    /// The monodromy matrix ∂(q(T), p(T))/∂(q(0), p(0)), 2D×2D, coordinates ordered (q, p).
    pub monodromy: DMatrix<f64>,
    /// The multipliers (re, im), sorted by distance from 1 (trivial ones first).
    pub multipliers: Vec<[f64; 2]>,
    /// How many multipliers lie within [`TRIVIAL_TOLERANCE`] of 1.
    pub trivial: usize,
    /// max | |λ| − 1 | over all multipliers.
    pub max_modulus_defect: f64,
    /// ‖MᵀΩM − Ω‖_F of the monodromy.
    pub symplecticity_defect: f64,
    /// The state after one period of time stepping (q, p).
    pub end_state: (Vec<f64>, Vec<f64>),
}

/// Multipliers within this distance of 1 are counted as trivial (symmetry) multipliers.
pub const TRIVIAL_TOLERANCE: f64 = 1e-4;

/// Multiply the exact step Jacobians of `steps` steps of the scene's method (with its h
/// replaced by `period / steps`) from (q0, p0): the monodromy over one period, and its
/// multipliers.
pub fn monodromy<L: Lagrangian>(
    lag: &L,
    method: &MethodSpec,
    q0: &[f64],
    p0: &[f64],
    period: f64,
    steps: usize,
) -> Result<Floquet> {
    crate::forcing::ensure_conservative(lag, "the monodromy of a periodic orbit")?;
    if steps == 0 {
        return Err(GviError::InvalidStepCount {
            steps,
            reason: "one period needs at least one step".into(),
        });
    }
    let gvi = integrator_for_period(method, period, steps)?;
    let d = lag.dim();
    let mut ws = gvi.workspace(lag)?;
    let mut m = DMatrix::<f64>::identity(2 * d, 2 * d);
    let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
    for k in 0..steps {
        let jac = gvi.step_jacobian_in(lag, &mut ws, &q, &p, k)?;
        m = &jac.matrix * m;
        q = jac.q_next;
        p = jac.p_next;
    }
    let schur = Schur::try_new(m.clone(), f64::EPSILON, 100_000).ok_or_else(|| {
        GviError::Unsupported("the Schur decomposition of the monodromy did not converge".into())
    })?;
    let mut multipliers: Vec<[f64; 2]> = schur
        .complex_eigenvalues()
        .iter()
        .map(|z| [z.re, z.im])
        .collect();
    let dist = |z: &[f64; 2]| (z[0] - 1.0).hypot(z[1]);
    multipliers.sort_by(|a, b| dist(a).total_cmp(&dist(b)));
    let trivial = multipliers
        .iter()
        .filter(|z| dist(z) <= TRIVIAL_TOLERANCE)
        .count();
    let max_modulus_defect = multipliers
        .iter()
        .map(|z| (z[0].hypot(z[1]) - 1.0).abs())
        .fold(0.0, crate::reduce::nan_max);
    Ok(Floquet {
        symplecticity_defect: crate::geometry::symplecticity_defect(&m),
        monodromy: m,
        multipliers,
        trivial,
        max_modulus_defect,
        end_state: (q, p),
    })
}

/// The scene's method with h = period / steps.
pub fn integrator_for_period(
    method: &MethodSpec,
    period: f64,
    steps: usize,
) -> Result<GalerkinIntegrator<crate::basis::AnyBasis, crate::quadrature::QuadratureRule>> {
    let mut m = method.clone();
    m.h = period / steps as f64;
    m.tol = None;
    m.integrator()
}
