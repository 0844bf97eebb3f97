//! The discrete action of one step and its derivatives (docs/DESIGN.md §2; paper §2).
//!
//! For a Galerkin curve q(t) = Σ_i Q_i φ_i(τ) over [t_k, t_k + h] the discrete action is
//!
//!   S_d(Q) = h Σ_j b_j L(q(c_j h), q̇(c_j h)),
//!
//! the quadrature of the action integral that paper eq. (1) extremises over the curves with
//! fixed ends to define the discrete Lagrangian L_d(q_k, q_{k+1}). Everything the integrator
//! solves is a derivative of S_d:
//! - ∂S_d/∂Q_i = h Σ_j b_j [L_q φ_i(c_j) + L_v φ_i'(c_j)/h], whose interior components are the
//!   internal stage equations (paper eq. (3)) and whose end components are the discrete
//!   Legendre transforms ([`super::legendre_transform`]; paper eq. (4));
//! - ∂²S_d/∂Q_a∂Q_b, the Newton matrix (assembled in `stage.rs` from the node values left here).
//!
//! Here: the curve at the quadrature nodes ([`GalerkinIntegrator::evaluate_curve`], from the
//! Newton increments ΔQ_i = Q_i − u_i q_k, docs/DESIGN.md §4), the gradient
//! (`action_gradient`, with the exactly summed kinetic part of separable Lagrangians), the
//! value ([`GalerkinIntegrator::discrete_action`]) and the extremum over curves with fixed
//! ends ([`GalerkinIntegrator::discrete_lagrangian`]). The public functions take a
//! [`GalerkinCurveRef`] and evaluate with the same tables and the same code as a step, so a
//! researcher can check a step's variational equations by finite differences of the value
//! (`tests/paper_objects.rs` does). Guide: docs/guide/paper-objects.md.

use super::dd::dd_acc_columns;
use super::legendre_transform::legendre_transforms_of_gradient;
use super::node_model::node_gradient;
use super::stage::Mode;
use super::stage_scratch::StageScratch;
use super::{GalerkinIntegrator, StepStats, Workspace};
use crate::basis::Basis;
use crate::curve::GalerkinCurveRef;
use crate::error::{GviError, Result, ensure_finite, ensure_len};
use crate::lagrangian::Lagrangian;
use crate::linalg::{Strided, gemm, gemm_transposed};
use crate::quadrature::Quadrature;

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// The discrete action S_d(Q) = h Σ_j b_j L(q(c_j h), q̇(c_j h)) of a Galerkin curve in
    /// this integrator's basis (the quantity paper eq. (1) extremises), evaluated by the
    /// step's own tables. At a solved step's curve it is L_d(q_k, q_{k+1}).
    ///
    /// Errors: a curve whose n, h or dimension is not this integrator's and the Lagrangian's.
    pub fn discrete_action<L: Lagrangian>(
        &self,
        lag: &L,
        curve: GalerkinCurveRef<'_>,
    ) -> Result<f64> {
        let mut ws = self.workspace_at_curve(lag, curve)?;
        self.evaluate_curve(&mut ws, false);
        Ok(self.action_value(lag, &ws))
    }

    /// The gradient ∂S_d/∂Q_i of the discrete action at a curve, n×D row-major (row i =
    /// ∂S_d/∂Q_i): zero in the interior rows at a solved step (the internal stage equations,
    /// paper eq. (3)), −p_k and p_{k+1} in the first and last rows (the discrete Legendre
    /// transforms, paper eq. (4)). The same code as the step's residual.
    ///
    /// Errors: as [`discrete_action`](Self::discrete_action).
    pub fn discrete_action_gradient<L: Lagrangian>(
        &self,
        lag: &L,
        curve: GalerkinCurveRef<'_>,
    ) -> Result<Vec<f64>> {
        let mut ws = self.workspace_at_curve(lag, curve)?;
        self.action_gradient(lag, &mut ws, false);
        Ok(ws.stage.grad.clone())
    }

    /// A fresh workspace whose iterate is `curve`: q_k = Q_0 and the increments
    /// ΔQ_i = Q_i − u_i Q_0 (ΔQ_0 = 0), with velocities evaluated for every Lagrangian.
    pub(super) fn workspace_at_curve<L: Lagrangian>(
        &self,
        lag: &L,
        curve: GalerkinCurveRef<'_>,
    ) -> Result<Workspace> {
        let (t, d) = (self.tables(), lag.dim());
        ensure_len("basis size n of the Galerkin curve", t.n, curve.n())?;
        ensure_len("dimension of the Galerkin curve", d, curve.dim())?;
        if curve.h() != self.step_size() {
            return Err(GviError::InvalidParameter {
                name: "step size h of the Galerkin curve".into(),
                value: curve.h(),
                reason: format!("the integrator's tables are for h = {}", self.step_size()),
            });
        }
        ensure_finite("Galerkin curve coefficients", curve.coefficients())?;
        let mut ws = self.workspace(lag)?;
        ws.need_velocities = true;
        // A time-dependent or forced system is evaluated at the curve's own times.
        ws.stage
            .set_step_start(curve.start_time(), self.step_size(), &self.rule().nodes);
        let q0 = curve.start();
        ws.iterate.set_origin(q0);
        for (i, (row, q)) in ws
            .iterate
            .increments_mut()
            .chunks_exact_mut(d)
            .zip(curve.coefficients().chunks_exact(d))
            .enumerate()
        {
            for ((x, &qi), &b) in row.iter_mut().zip(q).zip(q0) {
                *x = if i == 0 { 0.0 } else { qi - t.unit[i] * b };
            }
        }
        Ok(ws)
    }

    /// h Σ_j b_j L(q(c_j), q̇(c_j)) from the node values in the workspace (left there by
    /// [`evaluate_curve`](Self::evaluate_curve) with velocities).
    pub(super) fn action_value<L: Lagrangian>(&self, lag: &L, ws: &Workspace) -> f64 {
        let (t, d) = (self.tables(), ws.d);
        let mut value = 0.0;
        for j in 0..t.m {
            value += t.weights[j]
                * lag.value_at(
                    ws.stage.tj[j],
                    &ws.stage.qj[j * d..(j + 1) * d],
                    &ws.stage.vj[j * d..(j + 1) * d],
                );
        }
        self.step_size() * value
    }

    /// Curve values q(c_j) and velocities q̇(c_j) at every quadrature node from the increments
    /// ΔQ in `coeffs` (or `cand`): q = q_k + Φ ΔQ and q̇ = Φ' ΔQ / h as two matrix products
    /// (Σ u_i φ_i ≡ 1 and Σ u_i φ_i' ≡ 0, so the constant part is added, not multiplied).
    pub(super) fn evaluate_curve(&self, ws: &mut Workspace, coeffs_from_cand: bool) {
        let t = self.tables();
        let (n, m, d, h) = (t.n, t.m, ws.d, self.step_size());
        let coeffs = if coeffs_from_cand {
            ws.guess.candidate()
        } else {
            ws.iterate.increments()
        };
        ws.stage.set_curve_of_candidate(coeffs_from_cand);
        let (rn, rd) = (Strided::rows(0, n), Strided::rows(0, d));
        // q_k + (Φ ΔQ + δq_k): the small parts first, then the large one.
        for (j, row) in ws.stage.qj.chunks_exact_mut(d).enumerate() {
            row.copy_from_slice(ws.iterate.origin_lo());
            if !coeffs_from_cand {
                let phi_last = t.phi[j * n + n - 1];
                for (x, lo) in row.iter_mut().zip(ws.iterate.last_lo()) {
                    *x += phi_last * lo;
                }
            }
        }
        gemm(
            m,
            n,
            d,
            1.0,
            &t.phi,
            rn,
            coeffs,
            rd,
            1.0,
            &mut ws.stage.qj,
            rd,
        );
        ws.stage.add_to_nodes(ws.iterate.origin());
        // Velocities: the separable residual and Jacobian never use them (the kinetic part is
        // the precomputed K ΔQ), only the general path and the value of L_d do.
        if ws.separable.is_none() || ws.need_velocities {
            gemm(
                m,
                n,
                d,
                1.0 / h,
                &t.dphi,
                rn,
                coeffs,
                rd,
                0.0,
                &mut ws.stage.vj,
                rd,
            );
        }
    }

    /// The forces L_q at the nodes of the curve in `stage.qj` into `stage.lq`, and the weighted
    /// forces h b_j L_q(c_j) into `stage.scaled` (separable Lagrangians): what the stage
    /// equations project on their test functions, in either form.
    pub(super) fn weighted_forces<L: Lagrangian>(&self, lag: &L, stage: &mut StageScratch) {
        let (t, h) = (self.tables(), self.step_size());
        let d = stage.lq.len() / t.m.max(1);
        lag.force_at_points(&stage.qj, &mut stage.lq);
        for (j, (s, f)) in stage
            .scaled
            .chunks_exact_mut(d)
            .zip(stage.lq.chunks_exact(d))
            .enumerate()
        {
            let w = t.weights[j] * h;
            for (s, &f) in s.iter_mut().zip(f) {
                *s = w * f;
            }
        }
    }

    /// ∂S/∂Q_a for every a into `ws.stage.grad`, from the iterate's increments (or
    /// the candidate guess). Returns the number of first-derivative evaluations.
    pub(super) fn action_gradient<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        cand: bool,
    ) -> usize {
        self.evaluate_curve(ws, cand);
        let t = self.tables();
        let (n, m, d, h) = (t.n, t.m, ws.d, self.step_size());
        ws.stage.grad.iter_mut().for_each(|x| *x = 0.0);
        if let Some(sep) = &ws.separable {
            // Kinetic part (1/h) Σ_b K_ab M ΔQ_b with ΔQ_b = Q_b − u_b q_k: constants applied to
            // the increments, never to Q (docs/DESIGN.md §4).
            let coeffs = if cand {
                ws.guess.candidate()
            } else {
                ws.iterate.increments()
            };
            match sep.mass_diagonal() {
                // M diagonal (N-body): the same products without the D − 1 zero terms.
                Some(diag) => {
                    for (mq, x) in ws.stage.mq.chunks_exact_mut(d).zip(coeffs.chunks_exact(d)) {
                        for ((y, &m), &x) in mq.iter_mut().zip(diag).zip(x) {
                            *y = m * x;
                        }
                    }
                }
                None => {
                    for b in 0..n {
                        for r in 0..d {
                            let mut s = 0.0;
                            for c in 0..d {
                                s += sep.mass()[r * d + c] * coeffs[b * d + c];
                            }
                            ws.stage.mq[b * d + r] = s;
                        }
                    }
                }
            }
            let rd = Strided::rows(0, d);
            if self.options().exact_kinetic && !cand {
                for a in 0..n {
                    let row = &t.kinetic[a * n..(a + 1) * n];
                    ws.stage.dd_hi.iter_mut().for_each(|x| *x = 0.0);
                    ws.stage.dd_lo.iter_mut().for_each(|x| *x = 0.0);
                    dd_acc_columns(
                        n,
                        |b| row[b],
                        &ws.stage.mq,
                        d,
                        &mut ws.stage.dd_hi,
                        &mut ws.stage.dd_lo,
                    );
                    for ((g, hi), lo) in ws.stage.grad[a * d..(a + 1) * d]
                        .iter_mut()
                        .zip(&ws.stage.dd_hi)
                        .zip(&ws.stage.dd_lo)
                    {
                        *g = (hi + lo) / h;
                    }
                }
            } else {
                gemm(
                    n,
                    n,
                    d,
                    1.0 / h,
                    &t.kinetic,
                    Strided::rows(0, n),
                    &ws.stage.mq,
                    rd,
                    0.0,
                    &mut ws.stage.grad,
                    rd,
                );
            }
            if !cand {
                // The low part of ΔQ_{n−1} in every kinetic row (the Legendre-transform row and
                // the curve see it too), so that all equations see the same unknown.
                for r in 0..d {
                    let mut s = 0.0;
                    for c in 0..d {
                        s += sep.mass()[r * d + c] * ws.iterate.last_lo()[c];
                    }
                    ws.stage.small_rhs[r] = s / h;
                }
                for a in 0..n {
                    let k = t.kinetic[a * n + n - 1];
                    for r in 0..d {
                        ws.stage.grad[a * d + r] += k * ws.stage.small_rhs[r];
                    }
                }
            }
            self.weighted_forces(lag, &mut ws.stage);
            // grad += Φᵀ (h b ∘ L_q).
            gemm_transposed(n, m, d, &t.phi, &ws.stage.scaled, 1.0, &mut ws.stage.grad);
        } else {
            let forced = ws.stage.forced();
            for j in 0..m {
                let (lq, lv) = (
                    &mut ws.stage.lq[j * d..(j + 1) * d],
                    &mut ws.stage.lv[j * d..(j + 1) * d],
                );
                // L_q + f and L_v at the node time (node_model.rs).
                node_gradient(
                    lag,
                    forced,
                    (
                        ws.stage.tj[j],
                        &ws.stage.qj[j * d..(j + 1) * d],
                        &ws.stage.vj[j * d..(j + 1) * d],
                    ),
                    lq,
                    lv,
                    &mut ws.stage.fj,
                );
                let w = t.weights[j];
                for a in 0..n {
                    let (fq, fv) = (w * h * t.phi[j * n + a], w * t.dphi[j * n + a]);
                    for r in 0..d {
                        ws.stage.grad[a * d + r] += fq * lq[r] + fv * lv[r];
                    }
                }
            }
        }
        m
    }

    /// The discrete Lagrangian L_d(q0, q1) = ext h Σ_j b_j L(q(c_j), q̇(c_j)) over Galerkin
    /// curves with q(0) = q0 and q(h) = q1 (paper eq. (1)), together with the discrete
    /// Legendre transforms p0 = −D₁L_d(q0, q1) and p1 = D₂L_d(q0, q1) (paper §1.1).
    pub fn discrete_lagrangian<L: Lagrangian>(
        &self,
        lag: &L,
        q0: &[f64],
        q1: &[f64],
    ) -> Result<DiscreteLagrangian> {
        let d = lag.dim();
        ensure_len("q0", d, q0.len())?;
        ensure_len("q1", d, q1.len())?;
        ensure_finite("q0", q0)?;
        ensure_finite("q1", q1)?;
        let mut ws = self.workspace(lag)?;
        ws.need_velocities = true;
        let t = self.tables();
        let n = t.n;
        // Start from the straight line between the ends, as increments from q0.
        ws.iterate.set_origin(q0);
        let increments = ws.iterate.increments_mut();
        for i in 0..n {
            for r in 0..d {
                increments[i * d + r] = t.ramp[i] * (q1[r] - q0[r]);
            }
        }
        increments[..d].iter_mut().for_each(|x| *x = 0.0);
        for r in 0..d {
            increments[(n - 1) * d + r] = q1[r] - q0[r];
        }
        let mut stats = StepStats::default();
        self.newton(
            lag,
            &mut ws,
            Mode::BoundaryValue,
            &[],
            &mut stats,
            self.options().solver,
        )
        .map_err(|f| GviError::NewtonFailure {
            step: 0,
            t: 0.0,
            residual: f.residual,
            iterations: f.iterations,
            reason: format!("discrete Lagrangian: {}", f.reason),
        })?;
        let (p0, p1) = legendre_transforms_of_gradient(&ws);
        Ok(DiscreteLagrangian {
            value: self.action_value(lag, &ws),
            p0,
            p1,
            coefficients: {
                self.finish_step(&mut ws, q1);
                ws.last.coefficients().to_vec()
            },
        })
    }
}

/// The discrete Lagrangian and its discrete Legendre transforms at one pair of end points.
#[derive(Debug, Clone, PartialEq)]
pub struct DiscreteLagrangian {
    /// L_d(q0, q1).
    pub value: f64,
    /// p0 = −D₁L_d(q0, q1) (the discrete Legendre transform F⁻L_d).
    pub p0: Vec<f64>,
    /// p1 = D₂L_d(q0, q1) (F⁺L_d).
    pub p1: Vec<f64>,
    /// The extremal Galerkin curve's coefficients (n×D).
    pub coefficients: Vec<f64>,
}
