//! Balance laws of forced and time-dependent motions, measured along the Galerkin curves.
//!
//! Without forcing and explicit time, energy and the momentum maps of symmetries are
//! conserved (nearly, and exactly, for a variational integrator). With them, what holds is a
//! balance: along a motion of L(t, q, v) under a force f,
//!
//! - dE/dt = f·q̇ − ∂L/∂t (E = L_v·v − L), so E(t) − E(t₀) = W(t), the work of f minus the
//!   integral of ∂L/∂t;
//! - for a symmetry of L with generator ξ and momentum map J = p·ξ(q), dJ/dt = f·ξ(q), so
//!   J(t) − J(t₀) is the impulse of f along ξ.
//!
//! The discrete Lagrange–d'Alembert principle gives the momentum balance exactly at the step
//! ends when the impulse is taken with the integrator's own quadrature (the discrete Noether
//! theorem with forcing); with a finer rule, as here, the two agree to the quadrature's
//! accuracy. The energy balance holds to the method's accuracy: geometrically in n.

use crate::error::{GviError, Result, ensure_len};
use crate::lagrangian::Lagrangian;
use crate::quadrature::QuadratureKind;
use crate::symmetries::MomentumMap;
use crate::trajectory::Trajectory;

/// A balance law sampled at the step ends: the quantity, the accumulated source, and their
/// mismatch.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Balance {
    /// The step-end times t_k.
    pub t: Vec<f64>,
    /// The quantity at the step ends (E_k, or J_k).
    pub value: Vec<f64>,
    /// The accumulated source from t₀ to t_k (work minus ∫∂L/∂t, or the impulse along ξ).
    pub source: Vec<f64>,
}

impl Balance {
    /// value_k − value_0 − source_k at every step end: zero for the exact motion.
    pub fn defects(&self) -> Vec<f64> {
        let v0 = self.value.first().copied().unwrap_or(0.0);
        self.value
            .iter()
            .zip(&self.source)
            .map(|(v, s)| v - v0 - s)
            .collect()
    }

    /// Largest |defect|.
    pub fn max_defect(&self) -> f64 {
        self.defects().iter().fold(0.0, |m, x| m.max(x.abs()))
    }

    /// Largest |value_k − value_0|: how far the quantity moved (the scale of the defect).
    pub fn max_change(&self) -> f64 {
        let v0 = self.value.first().copied().unwrap_or(0.0);
        self.value.iter().fold(0.0, |m, x| m.max((x - v0).abs()))
    }
}

/// Gauss–Legendre points per step for the source integrals: well beyond the curve's degree.
fn source_points(traj: &Trajectory) -> usize {
    let n = (0..traj.steps())
        .map(|k| traj.n_of_step(k))
        .max()
        .unwrap_or(2);
    (2 * n).max(8)
}

/// ∫ over step k of `integrand(t, q, q̇)` along the Galerkin curve.
fn integrate_step(
    traj: &Trajectory,
    k: usize,
    nodes: &[f64],
    weights: &[f64],
    mut integrand: impl FnMut(f64, &[f64], &[f64]) -> f64,
) -> Result<f64> {
    let (t0, t1) = (traj.time(k), traj.time(k + 1));
    let h = t1 - t0;
    let mut sum = 0.0;
    for (&c, &b) in nodes.iter().zip(weights) {
        let t = t0 + c * h;
        let (q, v) = traj.state_on_curve(t)?;
        sum += b * integrand(t, &q, &v);
    }
    Ok(h * sum)
}

/// The energy balance E_k − E_0 = ∫ (f·q̇ − ∂L/∂t) dt of a trajectory of `lagrangian`
/// (forced or time-dependent or both): E_k from the step-end state (q_k, p_k) (the velocity
/// from the inverse Legendre transform at t_k), the source integrated along the Galerkin curves
/// with a Gauss–Legendre rule of max(2n, 8) points per step.
///
/// Errors: a trajectory of another dimension; an inverse Legendre transform that does not
/// converge (L_vv singular).
pub fn energy_balance<L: Lagrangian>(lagrangian: &L, traj: &Trajectory) -> Result<Balance> {
    let d = lagrangian.dim();
    ensure_len("trajectory dimension", d, traj.dim)?;
    let rule = QuadratureKind::GaussLegendre.build(source_points(traj))?;
    let mut f = vec![0.0; d];
    let mut balance = Balance::default();
    let mut work = 0.0;
    for k in 0..=traj.steps() {
        let t = traj.time(k);
        let v = velocity_of_momentum(lagrangian, traj, k)?;
        balance.t.push(t);
        balance.value.push(lagrangian.energy_at(t, &traj.q[k], &v));
        balance.source.push(work);
        if k < traj.steps() {
            work += integrate_step(traj, k, &rule.nodes, &rule.weights, |t, q, v| {
                lagrangian.external_force(t, q, v, &mut f);
                let power: f64 = f.iter().zip(v).map(|(a, b)| a * b).sum();
                power - lagrangian.time_derivative(t, q, v)
            })?;
        }
    }
    Ok(balance)
}

/// The momentum-map balance J_k − J_0 = ∫ f·ξ(q) dt for a symmetry of the Lagrangian with
/// generator ξ (`map`): J_k = p_k·ξ(q_k) at the step ends, the impulse along the Galerkin
/// curves as in [`energy_balance`]. Without a force the source is zero and the balance is
/// Noether's conservation law.
///
/// Errors: a trajectory of another dimension.
pub fn momentum_balance<L: Lagrangian, M: MomentumMap + ?Sized>(
    lagrangian: &L,
    map: &M,
    traj: &Trajectory,
) -> Result<Balance> {
    let d = lagrangian.dim();
    ensure_len("trajectory dimension", d, traj.dim)?;
    let rule = QuadratureKind::GaussLegendre.build(source_points(traj))?;
    let (mut f, mut xi) = (vec![0.0; d], vec![0.0; d]);
    let mut balance = Balance::default();
    let mut impulse = 0.0;
    for k in 0..=traj.steps() {
        balance.t.push(traj.time(k));
        balance.value.push(map.value(&traj.q[k], &traj.p[k]));
        balance.source.push(impulse);
        if k < traj.steps() {
            impulse += integrate_step(traj, k, &rule.nodes, &rule.weights, |t, q, v| {
                lagrangian.external_force(t, q, v, &mut f);
                map.generator(q, &mut xi);
                f.iter().zip(&xi).map(|(a, b)| a * b).sum()
            })?;
        }
    }
    Ok(balance)
}

/// The velocity v with ∂L/∂v(t_k, q_k, v) = p_k at step end k: Newton's method on the
/// Legendre transform from the Galerkin curve's velocity there.
pub(crate) fn velocity_of_momentum<L: Lagrangian>(
    lagrangian: &L,
    traj: &Trajectory,
    k: usize,
) -> Result<Vec<f64>> {
    let d = lagrangian.dim();
    let t = traj.time(k);
    let (q, p) = (&traj.q[k], &traj.p[k]);
    let mut v = traj.state_on_curve(t)?.1;
    let (mut lq, mut lv) = (vec![0.0; d], vec![0.0; d]);
    let (mut a, mut b, mut lvv) = (vec![0.0; d * d], vec![0.0; d * d], vec![0.0; d * d]);
    let scale = 1.0 + p.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for _ in 0..50 {
        lagrangian.gradient_at(t, q, &v, &mut lq, &mut lv);
        let r: Vec<f64> = p.iter().zip(&lv).map(|(a, b)| a - b).collect();
        if r.iter().all(|x| x.abs() <= 4.0 * f64::EPSILON * scale) {
            return Ok(v);
        }
        lagrangian.hessian_at(t, q, &v, &mut a, &mut b, &mut lvv);
        let m = nalgebra::DMatrix::from_row_slice(d, d, &lvv);
        let delta = m
            .lu()
            .solve(&nalgebra::DVector::from_vec(r.clone()))
            .ok_or_else(|| GviError::Unsupported(format!("L_vv is singular at t = {t}")))?;
        let before = r.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for (x, dx) in v.iter_mut().zip(delta.iter()) {
            *x += dx;
        }
        // Converged to round-off: the residual no longer decreases.
        if delta.iter().fold(0.0f64, |m, x| m.max(x.abs()))
            <= 4.0 * f64::EPSILON * (1.0 + v.iter().fold(0.0f64, |m, x| m.max(x.abs())))
            && before <= 1e-10 * scale
        {
            return Ok(v);
        }
    }
    Err(GviError::Unsupported(format!(
        "the inverse Legendre transform at t = {t} did not converge"
    )))
}
