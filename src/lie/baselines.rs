//! Classical rigid-body integrators, for negative controls and the work–precision study.
//!
//! - [`rk4_step`]: classical RK4 on the matrix ODE Ṙ = RΩ̂, μ̇ = μ × Ω − f(R). Neither
//!   orthogonal nor symplectic: R drifts off SO(3), energy and momentum drift.
//! - [`splitting_step`]: the Lie–Poisson splitting of the free body's Hamiltonian
//!   H = Σ μ_i²/(2I_i) into three exactly solvable rotations (McLachlan, Phys. Rev. Lett. 71
//!   (1993); Dullweber, Leimkuhler & McLachlan, J. Chem. Phys. 107 (1997)): Strang order 2, and
//!   order 4 by Yoshida's triple jump.
//! - [`rattle_step`]: RATTLE for the rigid body in its constrained formulation, which is the
//!   discrete Moser–Veselov map (McLachlan & Scovel, J. Nonlinear Sci. 5 (1995)); computed in the
//!   Lie group form h μ_k = (sin‖f‖/‖f‖) 𝕀f + ((1 − cos‖f‖)/‖f‖²) f × 𝕀f, F = exp(f̂),
//!   R_{k+1} = R_k F, μ_{k+1} = Fᵀμ_k (Lee, Leok & McClamroch, Comput. Methods Appl. Mech.
//!   Engrg. 196 (2007)). Order 2, symplectic and exactly momentum conserving. Free body only.

use super::body::RigidBody;
use super::integrator::LieState;
use super::so3::{self, Mat3, Retraction};
use crate::error::{GviError, Result};
use num_dual::Dual64;

/// One classical RK4 step of the Euler–Poincaré equations on (R, μ) as a 12-dimensional ODE.
pub fn rk4_step<S: RigidBody>(body: &S, s: &LieState, h: f64) -> LieState {
    let add = |a: &LieState, k: &(Mat3<f64>, [f64; 3]), c: f64| {
        let mut out = *a;
        for i in 0..3 {
            for j in 0..3 {
                out.r[i][j] += c * k.0[i][j];
            }
            out.mu[i] += c * k.1[i];
        }
        out
    };
    let f = |x: &LieState| body.vector_field(&x.r, &x.mu);
    let k1 = f(s);
    let k2 = f(&add(s, &k1, 0.5 * h));
    let k3 = f(&add(s, &k2, 0.5 * h));
    let k4 = f(&add(s, &k3, h));
    let mut out = *s;
    for i in 0..3 {
        for j in 0..3 {
            out.r[i][j] +=
                h / 6.0 * (k1.0[i][j] + 2.0 * k2.0[i][j] + 2.0 * k3.0[i][j] + k4.0[i][j]);
        }
        out.mu[i] += h / 6.0 * (k1.1[i] + 2.0 * k2.1[i] + 2.0 * k3.1[i] + k4.1[i]);
    }
    out
}

/// The exact flow of H_i = μ_i²/(2I_i) for time t: a rotation about body axis i at rate μ_i/I_i.
fn axis_flow(s: &mut LieState, inertia: &[f64; 3], axis: usize, t: f64) {
    let angle = t * s.mu[axis] / inertia[axis];
    let rot = so3::axis_rotation(axis, angle);
    s.r = so3::mul(&s.r, &rot);
    s.mu = so3::mul_tr_vec(&rot, &s.mu);
}

/// Strang splitting Φ₁(h/2) Φ₂(h/2) Φ₃(h) Φ₂(h/2) Φ₁(h/2) of the free body.
fn strang(s: &mut LieState, inertia: &[f64; 3], h: f64) {
    axis_flow(s, inertia, 0, 0.5 * h);
    axis_flow(s, inertia, 1, 0.5 * h);
    axis_flow(s, inertia, 2, h);
    axis_flow(s, inertia, 1, 0.5 * h);
    axis_flow(s, inertia, 0, 0.5 * h);
}

/// One step of the free-body Lie–Poisson splitting of order 2 (Strang) or 4 (triple jump).
pub fn splitting_step(inertia: &[f64; 3], s: &LieState, h: f64, order: usize) -> LieState {
    let mut out = *s;
    if order >= 4 {
        let c = 2f64.powf(1.0 / 3.0);
        let (g1, g2) = (1.0 / (2.0 - c), -c / (2.0 - c));
        strang(&mut out, inertia, g1 * h);
        strang(&mut out, inertia, g2 * h);
        strang(&mut out, inertia, g1 * h);
    } else {
        strang(&mut out, inertia, h);
    }
    out
}

/// One RATTLE (discrete Moser–Veselov) step of the free body; Newton on f to round-off.
pub fn rattle_step(inertia: &[f64; 3], s: &LieState, h: f64) -> Result<LieState> {
    let target = s.mu.map(|m| h * m);
    let mut f = [
        target[0] / inertia[0],
        target[1] / inertia[1],
        target[2] / inertia[2],
    ];
    let residual = |y: &[Dual64; 3]| {
        let sq = so3::dot(y, y);
        let (c0, c1, _) = so3::exp_coefficients(sq);
        let jf = [y[0] * inertia[0], y[1] * inertia[1], y[2] * inertia[2]];
        let cr = so3::cross(y, &jf);
        [
            jf[0] * c0 + cr[0] * c1 - target[0],
            jf[1] * c0 + cr[1] * c1 - target[1],
            jf[2] * c0 + cr[2] * c1 - target[2],
        ]
    };
    for _ in 0..50 {
        let mut xs = f.map(Dual64::from_re);
        let mut jac = [[0.0; 3]; 3];
        let mut val = [0.0; 3];
        for k in 0..3 {
            xs[k].eps = 1.0;
            let y = residual(&xs);
            xs[k].eps = 0.0;
            for i in 0..3 {
                jac[i][k] = y[i].eps;
                val[i] = y[i].re;
            }
        }
        let d = super::node::solve3(&jac, &val);
        let mut dn = 0.0f64;
        for k in 0..3 {
            f[k] -= d[k];
            dn = dn.max(d[k].abs());
        }
        if dn <= 1e-16 * f.iter().fold(1.0f64, |a, x| a.max(x.abs())) {
            break;
        }
        if !dn.is_finite() {
            break;
        }
    }
    let e = Retraction::Exp.map(&f);
    let out = LieState {
        r: so3::mul(&s.r, &e),
        mu: so3::mul_tr_vec(&e, &s.mu),
    };
    if out.mu.iter().all(|v| v.is_finite()) {
        Ok(out)
    } else {
        Err(GviError::Unsupported(format!(
            "RATTLE step did not converge at h = {h}"
        )))
    }
}
