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
fn source_points(n: usize) -> usize {
    (2 * n).max(8)
}

/// The energy balance accumulated step by step, for runs that do not keep their trajectory
/// (a streamed `gvi run`): feed it every step's Galerkin curve and end state.
#[derive(Debug, Clone)]
pub struct EnergyMeter {
    rule: crate::quadrature::QuadratureRule,
    balance: Balance,
    work: f64,
    /// Scratch: basis values, a state, the force.
    phi: Vec<f64>,
    dphi: Vec<f64>,
    q: Vec<f64>,
    v: Vec<f64>,
    f: Vec<f64>,
}

impl EnergyMeter {
    /// Start at (t0, q0, p0), with steps of at most n basis functions; v0 from the inverse
    /// Legendre transform, starting from `v_guess`.
    ///
    /// Errors: wrong lengths, an inverse Legendre transform that does not converge.
    pub fn new<L: Lagrangian>(
        lagrangian: &L,
        n: usize,
        (t0, q0, p0): (f64, &[f64], &[f64]),
        v_guess: &[f64],
    ) -> Result<Self> {
        let d = lagrangian.dim();
        ensure_len("q0", d, q0.len())?;
        ensure_len("p0", d, p0.len())?;
        let rule = QuadratureKind::GaussLegendre.build(source_points(n))?;
        let v0 = velocity_of_momentum(lagrangian, t0, q0, p0, v_guess)?;
        let mut meter = EnergyMeter {
            rule,
            balance: Balance::default(),
            work: 0.0,
            phi: vec![0.0; n],
            dphi: vec![0.0; n],
            q: vec![0.0; d],
            v: vec![0.0; d],
            f: vec![0.0; d],
        };
        meter.record(lagrangian, t0, q0, &v0);
        Ok(meter)
    }

    fn record<L: Lagrangian>(&mut self, lagrangian: &L, t: f64, q: &[f64], v: &[f64]) {
        self.balance.t.push(t);
        self.balance.value.push(lagrangian.energy_at(t, q, v));
        self.balance.source.push(self.work);
    }

    /// Add one step: its curve (in `basis`, starting at its own time) and the end state
    /// (q_{k+1}, p_{k+1}).
    ///
    /// Errors: a curve of more basis functions than the meter was made for, wrong lengths, an
    /// inverse Legendre transform that does not converge.
    pub fn step<L: Lagrangian, B: crate::basis::Basis + ?Sized>(
        &mut self,
        lagrangian: &L,
        curve: crate::curve::GalerkinCurveRef<'_>,
        basis: &B,
        (q1, p1): (&[f64], &[f64]),
    ) -> Result<()> {
        let n = curve.n();
        if n > self.phi.len() {
            self.phi.resize(n, 0.0);
            self.dphi.resize(n, 0.0);
        }
        ensure_len("step dimension", self.q.len(), curve.dim())?;
        let (t0, h) = (curve.start_time(), curve.h());
        let mut sum = 0.0;
        for (&c, &b) in self.rule.nodes.iter().zip(&self.rule.weights) {
            curve.state_into(
                basis,
                c,
                &mut self.phi,
                &mut self.dphi,
                &mut self.q,
                &mut self.v,
            );
            let t = t0 + c * h;
            lagrangian.external_force(t, &self.q, &self.v, &mut self.f);
            let power: f64 = self.f.iter().zip(&self.v).map(|(a, b)| a * b).sum();
            sum += b * (power - lagrangian.time_derivative(t, &self.q, &self.v));
        }
        self.work += h * sum;
        // The curve's end velocity starts the inverse Legendre transform at t_{k+1}.
        curve.state_into(
            basis,
            1.0,
            &mut self.phi,
            &mut self.dphi,
            &mut self.q,
            &mut self.v,
        );
        let t1 = t0 + h;
        let v1 = velocity_of_momentum(lagrangian, t1, q1, p1, &self.v)?;
        self.record(lagrangian, t1, q1, &v1);
        Ok(())
    }

    /// The balance so far.
    pub fn balance(&self) -> &Balance {
        &self.balance
    }

    /// The balance, consuming the meter.
    pub fn into_balance(self) -> Balance {
        self.balance
    }
}

/// The energy balance E_k − E_0 = ∫ (f·q̇ − ∂L/∂t) dt of a trajectory of `lagrangian`
/// (forced or time-dependent or both): E_k from the step-end state (q_k, p_k) (the velocity
/// from the inverse Legendre transform at t_k), the source integrated along the Galerkin curves
/// with a Gauss–Legendre rule of max(2n, 8) points per step ([`EnergyMeter`]).
///
/// Errors: a trajectory of another dimension; an inverse Legendre transform that does not
/// converge (L_vv singular).
pub fn energy_balance<L: Lagrangian>(lagrangian: &L, traj: &Trajectory) -> Result<Balance> {
    let d = lagrangian.dim();
    ensure_len("trajectory dimension", d, traj.dim)?;
    let n = (0..traj.steps())
        .map(|k| traj.n_of_step(k))
        .max()
        .unwrap_or(2);
    let t0 = traj.time(0);
    let v_guess = traj.state_on_curve(t0)?.1;
    let mut meter = EnergyMeter::new(lagrangian, n, (t0, &traj.q[0], &traj.p[0]), &v_guess)?;
    for k in 0..traj.steps() {
        let curve = traj.curve(k)?;
        let basis = traj.basis_with(curve.n())?;
        meter.step(lagrangian, curve, basis, (&traj.q[k + 1], &traj.p[k + 1]))?;
    }
    Ok(meter.into_balance())
}

/// The momentum-map balance J_k − J_0 = ∫ f·ξ(q) dt for a symmetry of the Lagrangian with
/// generator ξ (`map`): J_k = p_k·ξ(q_k) at the step ends, the impulse along the Galerkin
/// curves with a Gauss–Legendre rule of max(2n, 8) points per step. Without a force the source
/// is zero and the balance is Noether's conservation law.
///
/// Errors: a trajectory of another dimension.
pub fn momentum_balance<L: Lagrangian, M: MomentumMap + ?Sized>(
    lagrangian: &L,
    map: &M,
    traj: &Trajectory,
) -> Result<Balance> {
    let d = lagrangian.dim();
    ensure_len("trajectory dimension", d, traj.dim)?;
    let n = (0..traj.steps())
        .map(|k| traj.n_of_step(k))
        .max()
        .unwrap_or(2);
    let rule = QuadratureKind::GaussLegendre.build(source_points(n))?;
    let (mut f, mut xi) = (vec![0.0; d], vec![0.0; d]);
    let mut balance = Balance::default();
    let mut impulse = 0.0;
    for k in 0..=traj.steps() {
        let t = traj.time(k);
        balance.t.push(t);
        balance.value.push(map.value(&traj.q[k], &traj.p[k]));
        balance.source.push(impulse);
        if k < traj.steps() {
            let h = traj.time(k + 1) - t;
            let mut sum = 0.0;
            for (&c, &b) in rule.nodes.iter().zip(&rule.weights) {
                let (q, v) = traj.state_on_curve(t + c * h)?;
                lagrangian.external_force(t + c * h, &q, &v, &mut f);
                map.generator(&q, &mut xi);
                sum += b * f.iter().zip(&xi).map(|(a, b)| a * b).sum::<f64>();
            }
            impulse += h * sum;
        }
    }
    Ok(balance)
}

/// The velocity v with ∂L/∂v(t, q, v) = p: Newton's method on the Legendre transform from
/// `v_guess` (the Galerkin curve's velocity there).
pub(crate) fn velocity_of_momentum<L: Lagrangian>(
    lagrangian: &L,
    t: f64,
    q: &[f64],
    p: &[f64],
    v_guess: &[f64],
) -> Result<Vec<f64>> {
    let d = lagrangian.dim();
    let mut v = v_guess.to_vec();
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
