//! Symplecticity of a map on T*SO(3), measured in canonical coordinates.
//!
//! Near (R₀, μ₀) use ζ with R = R₀ exp(ζ̂) and π = J_r(ζ)ᵀμ: the cotangent lift of the chart
//! ζ ↦ R₀ exp(ζ̂), hence canonical coordinates (ζ, π) of T*SO(3) in which the symplectic form is
//! the standard one. Around the image use the same chart centred at its orientation. The 6 × 6
//! Jacobian M of the map in these coordinates by central differences gives the defect
//! ‖MᵀJM − J‖_F ([`crate::geometry::symplecticity_defect`]), zero for a symplectic map up to
//! the O(δ²) truncation and O(ε/δ) round-off of the differences (about 1e-10 at δ = 1e-5).

use super::integrator::LieState;
use super::node::solve3;
use super::so3::{self, Mat3, Retraction};
use crate::error::{GviError, Result};
use nalgebra::DMatrix;

fn to_state(x: &[f64; 6], base: &Mat3<f64>) -> LieState {
    let zeta = [x[0], x[1], x[2]];
    let jr: Mat3<f64> = Retraction::Exp.right_jacobian(&zeta);
    let mu = solve3(&so3::transpose(&jr), &[x[3], x[4], x[5]]);
    LieState {
        r: so3::mul(base, &Retraction::Exp.map(&zeta)),
        mu,
    }
}

fn to_coords(s: &LieState, base: &Mat3<f64>) -> [f64; 6] {
    let zeta = Retraction::Exp.inverse(&so3::mul(&so3::transpose(base), &s.r));
    let jr: Mat3<f64> = Retraction::Exp.right_jacobian(&zeta);
    let pi = so3::mul_tr_vec(&jr, &s.mu);
    [zeta[0], zeta[1], zeta[2], pi[0], pi[1], pi[2]]
}

/// ‖MᵀJM − J‖_F of `map` at `state`, M by central differences of step `delta` in the
/// canonical coordinates above.
pub fn symplecticity_defect(
    map: impl Fn(&LieState) -> Result<LieState>,
    state: &LieState,
    delta: f64,
) -> Result<f64> {
    if !(delta.is_finite() && delta > 0.0) {
        return Err(GviError::InvalidInput {
            name: "delta".into(),
            reason: format!("finite-difference step {delta} must be finite and positive"),
        });
    }
    let image = map(state)?;
    let mut m = DMatrix::<f64>::zeros(6, 6);
    for c in 0..6 {
        let mut cols = [[0.0; 6]; 2];
        for (side, sign) in [1.0, -1.0].into_iter().enumerate() {
            let mut x = [0.0, 0.0, 0.0, state.mu[0], state.mu[1], state.mu[2]];
            x[c] += sign * delta;
            cols[side] = to_coords(&map(&to_state(&x, &state.r))?, &image.r);
        }
        for r in 0..6 {
            m[(r, c)] = (cols[0][r] - cols[1][r]) / (2.0 * delta);
        }
    }
    Ok(crate::geometry::symplecticity_defect(&m))
}
