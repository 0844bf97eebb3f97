//! Per-node derivatives of the step equations: the gradient and Hessian of the trivialised
//! Lagrangian at a quadrature node, small dual-number Jacobians, and input checks.

use super::body::RigidBody;
use super::so3::{self, Mat3, Retraction};
use crate::error::{GviError, Result};
use num_dual::{Dual64, DualNum, HyperDual64};

/// Gradient and Hessian of ℓ(ξ, v) = ½ Ω·𝕀Ω − V(R_k τ(ξ)), Ω = J_r(ξ) v, at one node
/// (z = (ξ, v); `hess` row-major 6 × 6), using that Ω is linear in v: with A = J_r(ξ),
/// A_a = ∂A/∂ξ_a, B = (A_a v)_a and m = 𝕀Ω,
/// ℓ_ξ = Bᵀm, ℓ_v = Aᵀm, ℓ_vv = Aᵀ𝕀A, ℓ_ξv = Bᵀ𝕀A + (A_aᵀm)_a,
/// ℓ_ξξ = Bᵀ𝕀B + (m·A_ab v)_ab, minus the ξ-Hessian of V. A and its first and second
/// derivatives come from six hyper-dual evaluations of J_r (one per pair a ≤ b) instead of the
/// 21 evaluations of ℓ a generic 6-variable Hessian needs; equal to [`node_lagrangian`]'s AD
/// Hessian to round-off (unit test).
#[allow(clippy::too_many_arguments)]
pub(crate) fn node_derivatives<S: RigidBody>(
    body: &S,
    rk: &Mat3<f64>,
    tau: Retraction,
    inertia: [f64; 3],
    potential: bool,
    z: &[f64; 6],
    grad: &mut [f64; 6],
    hess: &mut [f64; 36],
) {
    let xi = [z[0], z[1], z[2]];
    let v = [z[3], z[4], z[5]];
    let mut a = [[0.0; 3]; 3];
    let mut da = [[[0.0; 3]; 3]; 3];
    let mut wab = [[[0.0; 3]; 3]; 3]; // A_ab v
    let (mut gu, mut hu) = ([0.0; 3], [[0.0; 3]; 3]);
    let rkh: Mat3<HyperDual64> = so3::lift(rk);
    for p in 0..3 {
        for q in p..3 {
            let mut x = xi.map(HyperDual64::from_re);
            x[p].eps1 = 1.0;
            x[q].eps2 = 1.0;
            let m = tau.right_jacobian(&x);
            for i in 0..3 {
                for j in 0..3 {
                    a[i][j] = m[i][j].re;
                    da[p][i][j] = m[i][j].eps1;
                    da[q][i][j] = m[i][j].eps2;
                }
                let w = m[i][0].eps1eps2 * v[0] + m[i][1].eps1eps2 * v[1] + m[i][2].eps1eps2 * v[2];
                wab[p][q][i] = w;
                wab[q][p][i] = w;
            }
            if potential {
                let u = body.potential(&so3::mul(&rkh, &tau.map(&x)));
                hu[p][q] = u.eps1eps2;
                hu[q][p] = u.eps1eps2;
                gu[p] = u.eps1;
                gu[q] = u.eps2;
            }
        }
    }
    let om = so3::mul_vec(&a, &v);
    let m = [om[0] * inertia[0], om[1] * inertia[1], om[2] * inertia[2]];
    let b: [[f64; 3]; 3] = [
        so3::mul_vec(&da[0], &v),
        so3::mul_vec(&da[1], &v),
        so3::mul_vec(&da[2], &v),
    ]; // b[p] = ∂Ω/∂ξ_p
    let at_m = so3::mul_tr_vec(&a, &m);
    for p in 0..3 {
        grad[p] = so3::dot(&b[p], &m) - gu[p];
        grad[3 + p] = at_m[p];
        let ap_m = so3::mul_tr_vec(&da[p], &m);
        for q in 0..3 {
            let (mut bb, mut ba, mut aa) = (0.0, 0.0, 0.0);
            for k in 0..3 {
                bb += inertia[k] * b[p][k] * b[q][k];
                ba += inertia[k] * b[p][k] * a[k][q];
                aa += inertia[k] * a[k][p] * a[k][q];
            }
            hess[p * 6 + q] = bb + so3::dot(&m, &wab[p][q]) - hu[p][q];
            let xv = ba + ap_m[q];
            hess[p * 6 + 3 + q] = xv;
            hess[(3 + q) * 6 + p] = xv;
            hess[(3 + p) * 6 + 3 + q] = aa;
        }
    }
}

/// ℓ(R_k τ(ξ), J_r(ξ) v) at one quadrature node; z = (ξ, v). The reference for
/// [`node_derivatives`].
#[cfg_attr(not(test), allow(dead_code))]
fn node_lagrangian<S: RigidBody, T: DualNum<Primitive = f64> + Copy>(
    body: &S,
    rk: &Mat3<f64>,
    tau: Retraction,
    inertia: [f64; 3],
    potential: bool,
    z: &[T],
) -> T {
    let xi = [z[0], z[1], z[2]];
    let v = [z[3], z[4], z[5]];
    let om = so3::mul_vec(&tau.right_jacobian(&xi), &v);
    let kin =
        (om[0] * om[0] * inertia[0] + om[1] * om[1] * inertia[1] + om[2] * om[2] * inertia[2])
            * 0.5;
    if potential {
        let r = so3::mul(&so3::lift(rk), &tau.map(&xi));
        kin - body.potential(&r)
    } else {
        kin
    }
}

/// Value and Jacobian (J[i][k] = ∂f_i/∂x_k) of f: R³ → R³ by dual numbers (value only when
/// `jacobian` is false).
pub(crate) fn jacobian3(
    f: impl Fn(&[Dual64; 3]) -> [Dual64; 3],
    x: [f64; 3],
    jacobian: bool,
) -> ([f64; 3], Mat3<f64>) {
    let mut xs = x.map(Dual64::from_re);
    let mut jac = [[0.0; 3]; 3];
    if !jacobian {
        return (f(&xs).map(|v| v.re), jac);
    }
    let mut val = [0.0; 3];
    for k in 0..3 {
        xs[k].eps = 1.0;
        let y = f(&xs);
        xs[k].eps = 0.0;
        for i in 0..3 {
            jac[i][k] = y[i].eps;
            val[i] = y[i].re;
        }
    }
    (val, jac)
}

/// Solve the 3 × 3 system A x = b by Cramer's rule (A well conditioned: J_r near identity).
pub(crate) fn solve3(a: &Mat3<f64>, b: &[f64; 3]) -> [f64; 3] {
    let c0 = so3::cross(&a_col(a, 1), &a_col(a, 2));
    let det = so3::dot(&a_col(a, 0), &c0);
    let x0 = so3::dot(b, &c0) / det;
    let x1 = so3::dot(&a_col(a, 0), &so3::cross(b, &a_col(a, 2))) / det;
    let x2 = so3::dot(&a_col(a, 0), &so3::cross(&a_col(a, 1), b)) / det;
    [x0, x1, x2]
}

fn a_col(a: &Mat3<f64>, j: usize) -> [f64; 3] {
    [a[0][j], a[1][j], a[2][j]]
}

/// Validate an initial state: finite, R orthogonal (‖RᵀR − I‖ ≤ 1e-10), 1 ≤ steps ≤ 10⁹.
pub(crate) fn check_initial(r: &Mat3<f64>, mu: &[f64; 3], steps: usize) -> Result<()> {
    crate::error::ensure_finite("initial body momentum", mu)?;
    crate::error::ensure_finite("initial orientation", r.as_flattened())?;
    let d = so3::orthogonality_defect(r);
    let det = so3::dot(&a_col(r, 0), &so3::cross(&a_col(r, 1), &a_col(r, 2)));
    if d > 1e-10 || det < 0.0 {
        return Err(GviError::InvalidInput {
            name: "initial orientation".into(),
            reason: format!("not a rotation matrix (‖RᵀR − I‖ = {d:.3e}, det = {det:.6})"),
        });
    }
    if steps == 0 || steps > 1_000_000_000 {
        return Err(GviError::InvalidStepCount {
            steps,
            reason: "need 1 ≤ steps ≤ 10⁹".into(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lie::{FreeRigidBody, HeavyTop};

    fn compare<S: RigidBody>(body: &S, tau: Retraction, z: [f64; 6]) {
        let rk: Mat3<f64> = Retraction::Exp.map(&[0.7, -0.2, 1.1]);
        let inertia = body.inertia();
        let pot = body.has_potential();
        let (mut g, mut h) = ([0.0; 6], [0.0; 36]);
        node_derivatives(body, &rk, tau, inertia, pot, &z, &mut g, &mut h);
        let (mut g2, mut h2) = ([0.0; 6], [0.0; 36]);
        crate::ad::hessian(
            |y| node_lagrangian(body, &rk, tau, inertia, pot, y),
            &z,
            &mut g2,
            &mut h2,
        );
        for i in 0..6 {
            // Absolute near zero, relative elsewhere (about tol·(1 + |AD value|)).
            approx::assert_relative_eq!(g[i], g2[i], epsilon = 1e-13, max_relative = 1e-13);
        }
        for i in 0..36 {
            approx::assert_relative_eq!(h[i], h2[i], epsilon = 1e-12, max_relative = 1e-12);
        }
    }

    #[test]
    fn structured_node_hessian_matches_generic_ad() {
        let free = FreeRigidBody::new([1.0, 2.0, 2.5]).unwrap();
        let top = HeavyTop::new([1.0, 1.5, 2.0], 1.0, 9.81, [0.1, -0.2, 0.5]).unwrap();
        for tau in [Retraction::Exp, Retraction::Cayley] {
            for z in [
                [0.3, -0.5, 0.8, 1.0, -2.0, 0.5],
                [1.5, 0.9, -1.2, 0.3, 0.4, -3.0],
                [0.0, 0.0, 0.0, 1.0, 2.0, 3.0],
            ] {
                compare(&free, tau, z);
                compare(&top, tau, z);
            }
        }
    }
}
