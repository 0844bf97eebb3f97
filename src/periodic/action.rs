//! The discrete action of a periodic curve and its exact derivatives.
//!
//! With θ_j = j/M (j = 0…M−1), A_j = φ(θ_j + s_r), B_j = φ'(θ_j + s_r)/T the basis and its
//! time derivative at the node of coordinate r (shift s_r), the curve is q_j = A_j c, q̇_j = B_j c
//! and the trapezoid rule (spectrally accurate for periodic integrands) gives
//!
//! S(c, T) = (T/M) Σ_j L(q_j, q̇_j),
//! ∂S/∂c = (T/M) Σ_j (A_jᵀ L_q + B_jᵀ L_v),
//! ∂²S/∂c² = (T/M) Σ_j (Aᵀ L_qq A + Aᵀ L_qv B + Bᵀ L_vq A + Bᵀ L_vv B).
//!
//! With the period unknown and the energy E₀ prescribed, the unknowns are (c, T) and the
//! function made stationary is F = S + E₀ T: since q̇ = q'(θ)/T, ∂S/∂T = (1/M) Σ_j (L − L_v·q̇)
//! = −Ē (the mean energy over the nodes), so ∂F/∂T = 0 is exactly the energy condition Ē = E₀
//! and the Newton matrix stays symmetric:
//! ∂²F/∂c∂T = (1/M) Σ_j (Aᵀ L_q − Aᵀ L_qv q̇ − Bᵀ L_vv q̇), ∂²F/∂T² = (1/(MT)) Σ_j q̇ᵀ L_vv q̇.

use super::curve::{FourierCurve, Layout, basis_at, basis_len};
use crate::lagrangian::Lagrangian;
use nalgebra::DMatrix;

/// The basis at the nodes of every shift class: `phi[class][j * nb + m]`.
pub(crate) struct Tables {
    phi: Vec<Vec<f64>>,
    dphi: Vec<Vec<f64>>,
    class: Vec<usize>,
}

impl Tables {
    pub(crate) fn new(layout: &Layout, modes: usize, nodes: usize) -> Self {
        let nb = basis_len(modes);
        let (shifts, class) = layout.shift_classes();
        let mut phi = Vec::with_capacity(shifts.len());
        let mut dphi = Vec::with_capacity(shifts.len());
        let mut d2 = vec![0.0; nb];
        for &s in &shifts {
            let (mut p, mut dp) = (vec![0.0; nodes * nb], vec![0.0; nodes * nb]);
            for j in 0..nodes {
                let theta = j as f64 / nodes as f64 + s;
                basis_at(
                    theta,
                    modes,
                    &mut p[j * nb..(j + 1) * nb],
                    &mut dp[j * nb..(j + 1) * nb],
                    &mut d2,
                );
            }
            phi.push(p);
            dphi.push(dp);
        }
        Tables { phi, dphi, class }
    }
}

/// Action, gradient and Hessian of F at a curve.
pub(crate) struct Evaluation {
    pub action: f64,
    pub energy: f64,
    pub energy_spread: f64,
    pub gradient: Vec<f64>,
    pub hessian: Option<DMatrix<f64>>,
}

/// Fixed period, or unknown period with a prescribed energy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PeriodCondition {
    /// The period is the curve's `period` and stays fixed.
    Fixed,
    /// The period is unknown (the curve's `period` is the guess); the mean energy over the
    /// orbit must equal this value.
    Energy(f64),
}

/// Default number of trapezoid nodes for K modes.
pub fn default_nodes(layout: &Layout, modes: usize) -> usize {
    let m = (4 * (modes + 1)).max(32);
    match *layout {
        Layout::Choreography { bodies, .. } => m.div_ceil(bodies) * bodies,
        Layout::Orbit { .. } => m,
    }
}

pub(crate) fn evaluate<L: Lagrangian>(
    lag: &L,
    curve: &FourierCurve,
    tables: &Tables,
    nodes: usize,
    condition: PeriodCondition,
    with_hessian: bool,
) -> Evaluation {
    let layout = &curve.layout;
    let (d, nc, nb) = (layout.dim(), layout.components(), basis_len(curve.modes));
    let p = nb * nc;
    let energy_unknown = matches!(condition, PeriodCondition::Energy(_));
    let nu = p + usize::from(energy_unknown);
    let t = curve.period;
    let mf = nodes as f64;
    let w = t / mf;
    let c = &curve.coefficients;
    let mut grad = vec![0.0; nu];
    let mut hess = if with_hessian {
        Some(DMatrix::<f64>::zeros(nu, nu))
    } else {
        None
    };
    let (mut q, mut v) = (vec![0.0; d], vec![0.0; d]);
    let (mut lq, mut lv) = (vec![0.0; d], vec![0.0; d]);
    let (mut lqq, mut lqv, mut lvv) = (vec![0.0; d * d], vec![0.0; d * d], vec![0.0; d * d]);
    let (mut action, mut esum) = (0.0, 0.0);
    let (mut emin, mut emax) = (f64::INFINITY, f64::NEG_INFINITY);
    for j in 0..nodes {
        for r in 0..d {
            let cls = tables.class[r];
            let a = &tables.phi[cls][j * nb..(j + 1) * nb];
            let b = &tables.dphi[cls][j * nb..(j + 1) * nb];
            let comp = layout.component(r);
            let (mut x, mut dx) = (0.0, 0.0);
            for m in 0..nb {
                x += a[m] * c[m * nc + comp];
                dx += b[m] * c[m * nc + comp];
            }
            q[r] = x;
            v[r] = dx / t;
        }
        let l = lag.value(&q, &v);
        lag.gradient(&q, &v, &mut lq, &mut lv);
        action += w * l;
        let e = lv.iter().zip(&v).map(|(x, y)| x * y).sum::<f64>() - l;
        esum += e;
        emin = emin.min(e);
        emax = emax.max(e);
        for r in 0..d {
            let cls = tables.class[r];
            let a = &tables.phi[cls][j * nb..(j + 1) * nb];
            let b = &tables.dphi[cls][j * nb..(j + 1) * nb];
            let comp = layout.component(r);
            for m in 0..nb {
                grad[m * nc + comp] += w * (a[m] * lq[r] + b[m] / t * lv[r]);
            }
        }
        let Some(h) = hess.as_mut() else { continue };
        lag.hessian(&q, &v, &mut lqq, &mut lqv, &mut lvv);
        for r in 0..d {
            let (cr, cls_r) = (layout.component(r), tables.class[r]);
            let ar = &tables.phi[cls_r][j * nb..(j + 1) * nb];
            let br = &tables.dphi[cls_r][j * nb..(j + 1) * nb];
            for s in 0..d {
                let (x, y, yt, z) = (
                    lqq[r * d + s],
                    lqv[r * d + s],
                    lqv[s * d + r],
                    lvv[r * d + s],
                );
                if x == 0.0 && y == 0.0 && yt == 0.0 && z == 0.0 {
                    continue;
                }
                let (cs, cls_s) = (layout.component(s), tables.class[s]);
                let as_ = &tables.phi[cls_s][j * nb..(j + 1) * nb];
                let bs = &tables.dphi[cls_s][j * nb..(j + 1) * nb];
                for m in 0..nb {
                    // H_(m,r),(n,s) = w (A_r A_s L_qq + A_r B_s L_qv + B_r A_s L_vq + B_r B_s L_vv).
                    let alpha = w * (ar[m] * x + br[m] / t * yt);
                    let beta = w * (ar[m] * y + br[m] / t * z) / t;
                    if alpha == 0.0 && beta == 0.0 {
                        continue;
                    }
                    let row = m * nc + cr;
                    for n in 0..nb {
                        h[(row, n * nc + cs)] += alpha * as_[n] + beta * bs[n];
                    }
                }
            }
        }
        if energy_unknown {
            // ∂²F/∂c∂T and ∂²F/∂T² (module docs).
            let mut vlv = 0.0;
            for r in 0..d {
                let (qv_v, vv_v): (f64, f64) = (0..d)
                    .map(|s| (lqv[r * d + s] * v[s], lvv[r * d + s] * v[s]))
                    .fold((0.0, 0.0), |(x, y), (a, b)| (x + a, y + b));
                vlv += v[r] * vv_v;
                let cls = tables.class[r];
                let a = &tables.phi[cls][j * nb..(j + 1) * nb];
                let b = &tables.dphi[cls][j * nb..(j + 1) * nb];
                let comp = layout.component(r);
                for m in 0..nb {
                    let val = (a[m] * (lq[r] - qv_v) - b[m] / t * vv_v) / mf;
                    h[(m * nc + comp, p)] += val;
                    h[(p, m * nc + comp)] += val;
                }
            }
            h[(p, p)] += vlv / (mf * t);
        }
    }
    let energy = esum / mf;
    if let PeriodCondition::Energy(e0) = condition {
        grad[p] = e0 - energy;
    }
    Evaluation {
        action,
        energy,
        energy_spread: emax - emin,
        gradient: grad,
        hessian: hess,
    }
}

/// Max-norm over `samples` equally spaced times of the Euler–Lagrange residual
/// d/dt L_v − L_q = L_vq q̇ + L_vv q̈ − L_q along the curve: the error of the truncated series
/// as a solution of the equations of motion (phase-independent, needs no reference).
pub fn equation_residual<L: Lagrangian>(lag: &L, curve: &FourierCurve, samples: usize) -> f64 {
    let d = curve.layout.dim();
    let (mut q, mut v, mut a) = (vec![0.0; d], vec![0.0; d], vec![0.0; d]);
    let (mut lq, mut lv) = (vec![0.0; d], vec![0.0; d]);
    let (mut lqq, mut lqv, mut lvv) = (vec![0.0; d * d], vec![0.0; d * d], vec![0.0; d * d]);
    let mut worst: f64 = 0.0;
    for i in 0..samples.max(1) {
        let t = curve.period * i as f64 / samples.max(1) as f64;
        curve.state_at(t, &mut q, &mut v, &mut a);
        lag.gradient(&q, &v, &mut lq, &mut lv);
        lag.hessian(&q, &v, &mut lqq, &mut lqv, &mut lvv);
        for r in 0..d {
            let mut e = -lq[r];
            for s in 0..d {
                e += lqv[s * d + r] * v[s] + lvv[r * d + s] * a[s];
            }
            worst = worst.max(e.abs());
        }
    }
    worst
}

/// The action, mean energy and its spread at a curve (no Newton).
pub fn action_and_energy<L: Lagrangian>(
    lag: &L,
    curve: &FourierCurve,
    nodes: usize,
) -> (f64, f64, f64) {
    let tables = Tables::new(&curve.layout, curve.modes, nodes);
    let e = evaluate(lag, curve, &tables, nodes, PeriodCondition::Fixed, false);
    (e.action, e.energy, e.energy_spread)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::systems::NBody;

    /// The exact Hessian and ∂/∂T terms against central differences of the gradient.
    #[test]
    fn hessian_matches_differences_of_the_gradient() {
        let nb = NBody::new(vec![1.0, 1.0, 1.0], 1.0, 2).unwrap();
        let layout = Layout::Choreography {
            bodies: 3,
            body_dim: 2,
        };
        let mut c = FourierCurve::zeros(3, layout, 6.0).unwrap();
        c.set_mode(1, &[0.05, -0.02], &[1.0, 0.03]).unwrap();
        c.set_mode(2, &[0.01, 0.3], &[0.02, 0.01]).unwrap();
        c.set_mode(3, &[0.0, 0.01], &[0.02, 0.0]).unwrap();
        let nodes = 48;
        let tables = Tables::new(&c.layout, c.modes, nodes);
        let cond = PeriodCondition::Energy(-1.3);
        let e = evaluate(&nb, &c, &tables, nodes, cond, true);
        let h = e.hessian.unwrap();
        let nu = e.gradient.len();
        let eps = 1e-6;
        let mut worst: f64 = 0.0;
        for k in 0..nu {
            let (mut cp, mut cm) = (c.clone(), c.clone());
            if k < nu - 1 {
                cp.coefficients[k] += eps;
                cm.coefficients[k] -= eps;
            } else {
                cp.period += eps;
                cm.period -= eps;
            }
            let gp = evaluate(&nb, &cp, &tables, nodes, cond, false).gradient;
            let gm = evaluate(&nb, &cm, &tables, nodes, cond, false).gradient;
            for i in 0..nu {
                let fd = (gp[i] - gm[i]) / (2.0 * eps);
                worst = worst.max((fd - h[(i, k)]).abs());
            }
        }
        // Central differences with ε = 1e-6 carry ~1e-10 relative round-off and ε² truncation.
        let scale = h.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(
            worst < 1e-7 * scale,
            "Hessian vs differences: {worst:.3e} (max entry {scale:.3e})"
        );
        // The action gradient against differences of the action.
        let mut cp = c.clone();
        cp.coefficients[3] += eps;
        let mut cm = c.clone();
        cm.coefficients[3] -= eps;
        let sp = evaluate(&nb, &cp, &tables, nodes, cond, false).action;
        let sm = evaluate(&nb, &cm, &tables, nodes, cond, false).action;
        assert!(((sp - sm) / (2.0 * eps) - e.gradient[3]).abs() < 1e-7);
    }
}
