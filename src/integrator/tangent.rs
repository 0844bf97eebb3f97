//! The exact derivative of the one-step map (its tangent map), by the implicit function
//! theorem — no finite differences.
//!
//! With X = (Q_1 … Q_{n−1}) the stage equations F(X; q_k, p_k) = 0 are
//! F_0 = p_k + ∂S/∂Q_0 and F_a = ∂S/∂Q_a (a = 1 … n−2), with Q_0 = q_k. Differentiating,
//! F_X dX + F_q dq_k + F_p dp_k = 0 where F_X = ∂²S/∂Q_a∂Q_b (rows a = 0 … n−2, columns
//! b = 1 … n−1; the Newton matrix), F_q is the column block b = 0 of the full Hessian of the
//! action, and F_p is the identity on the first D rows. Then dq_{k+1} = dQ_{n−1} and
//! dp_{k+1} = Σ_b ∂²S/∂Q_{n−1}∂Q_b dQ_b (all b, including b = 0 with dQ_0 = dq_k).
//!
//! Numerically, dp_{k+1} is evaluated in the algebraically identical impulse form
//! dp_{k+1} = dp_k + h Σ_j b_j (L_qq δq(c_j) + L_qv δq̇(c_j)) — the derivative of
//! p_{k+1} = p_k + h Σ_j b_j L_q(c_j), which is how [`GalerkinIntegrator::step`] computes
//! p_{k+1} — because it does not subtract the large kinetic terms of the row n−1 of the
//! Hessian (docs/DESIGN.md §4). The two agree on the solution manifold of the stage equations.

use super::{GalerkinIntegrator, MAX_STEPS, Workspace};
use crate::basis::Basis;
use crate::error::{GviError, Result, ensure_finite, ensure_len};
use crate::lagrangian::Lagrangian;
use crate::linalg::Lu;
use crate::quadrature::Quadrature;
use nalgebra::DMatrix;

/// The exact Jacobian of one step (q_k, p_k) ↦ (q_{k+1}, p_{k+1}) and the step's result.
#[derive(Debug, Clone, PartialEq)]
pub struct StepJacobian {
    /// ∂(q_{k+1}, p_{k+1}) / ∂(q_k, p_k), 2D×2D, with coordinates ordered (q, p): rows and
    /// columns 0…D−1 are positions, D…2D−1 momenta.
    pub matrix: DMatrix<f64>,
    /// q_{k+1}.
    pub q_next: Vec<f64>,
    /// p_{k+1}.
    pub p_next: Vec<f64>,
}

/// Buffers for the exact step Jacobian of one integrator and one Lagrangian, so that
/// [`GalerkinIntegrator::step_jacobian_into`] allocates nothing (tangent maps and Lyapunov
/// estimates along a run). Create with [`GalerkinIntegrator::tangent_workspace`].
#[derive(Debug, Clone)]
pub struct TangentWorkspace {
    d: usize,
    n: usize,
    /// The constant mass matrix of a separable Lagrangian (D×D row-major), else `None`.
    mass: Option<Vec<f64>>,
    /// Curve values and velocities at the nodes (m×D).
    q: Vec<f64>,
    v: Vec<f64>,
    /// L_qq, L_qv, L_vv per node (m×D×D, row-major blocks).
    qq: Vec<f64>,
    qv: Vec<f64>,
    vv: Vec<f64>,
    /// The full action Hessian ∂²S/∂Q_a∂Q_b, (nD)×(nD) row-major.
    hess: Vec<f64>,
    /// F_X (rows a = 0 … n−2, columns b = 1 … n−1), its LU, one right-hand side and scratch.
    fx: Vec<f64>,
    lu: Lu,
    col: Vec<f64>,
    scratch: Vec<f64>,
    /// dQ for all coefficients and the 2D unit directions, (nD)×(2D) row-major.
    dq_all: Vec<f64>,
    /// δq and δq̇ at one node for the 2D directions (D×2D).
    dqj: Vec<f64>,
    dvj: Vec<f64>,
}

impl TangentWorkspace {
    /// Configuration dimension D.
    pub fn dim(&self) -> usize {
        self.d
    }
}

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// Perform one step from (q, p) and return its exact Jacobian (implicit function theorem
    /// on the stage equations, see the module docs of `integrator::tangent`) with the new state.
    ///
    /// ```
    /// use galerkin_vi::prelude::*;
    /// use galerkin_vi::geometry::symplecticity_defect;
    ///
    /// let gvi = GalerkinIntegrator::spectral(8, 0.5)?;
    /// let kepler = Kepler::new(1.0)?;
    /// let jac = gvi.step_jacobian(&kepler, &[0.4, 0.0], &[0.0, 2.0])?;
    /// assert_eq!(jac.matrix.shape(), (4, 4));
    /// // The one-step map is symplectic: JᵀΩJ = Ω to round-off.
    /// assert!(symplecticity_defect(&jac.matrix) < 1e-11);
    /// # Ok::<(), galerkin_vi::GviError>(())
    /// ```
    pub fn step_jacobian<L: Lagrangian>(
        &self,
        lag: &L,
        q: &[f64],
        p: &[f64],
    ) -> Result<StepJacobian> {
        self.check_state(lag, q, p)?;
        let mut ws = self.workspace(lag)?;
        self.step_jacobian_in(lag, &mut ws, q, p, 0)
    }

    /// [`step_jacobian`](Self::step_jacobian) with a caller-owned workspace (whose previous
    /// curve seeds the initial guess); `step_index` only labels errors.
    pub fn step_jacobian_in<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        q: &[f64],
        p: &[f64],
        step_index: usize,
    ) -> Result<StepJacobian> {
        let d = lag.dim();
        let mut tws = self.tangent_workspace(lag)?;
        let (mut q_next, mut p_next) = (vec![0.0; d], vec![0.0; d]);
        let mut matrix = DMatrix::<f64>::zeros(2 * d, 2 * d);
        self.step_jacobian_into(
            lag,
            ws,
            &mut tws,
            q,
            p,
            (&mut q_next, &mut p_next),
            &mut matrix,
            step_index,
        )?;
        Ok(StepJacobian {
            matrix,
            q_next,
            p_next,
        })
    }

    /// Buffers for [`step_jacobian_into`](Self::step_jacobian_into) with this integrator and
    /// Lagrangian.
    pub fn tangent_workspace<L: Lagrangian>(&self, lag: &L) -> Result<TangentWorkspace> {
        crate::forcing::ensure_conservative(lag, "the exact step Jacobian")?;
        let t = self.tables();
        let (n, m, d) = (t.n, t.m, lag.dim());
        let mass = match lag.mass_matrix() {
            Some(mass) if mass.shape() != (d, d) => {
                return Err(GviError::DimensionMismatch {
                    what: "mass matrix".into(),
                    expected: d,
                    got: mass.nrows().max(mass.ncols()),
                });
            }
            Some(mass) => Some((0..d * d).map(|k| mass[(k / d, k % d)]).collect()),
            None => None,
        };
        let (nd, nu) = (n * d, (n - 1) * d);
        Ok(TangentWorkspace {
            d,
            n,
            mass,
            q: vec![0.0; m * d],
            v: vec![0.0; m * d],
            qq: vec![0.0; m * d * d],
            qv: vec![0.0; m * d * d],
            vv: vec![0.0; m * d * d],
            hess: vec![0.0; nd * nd],
            fx: vec![0.0; nu * nu],
            lu: Lu::with_capacity(nu),
            col: vec![0.0; nu],
            scratch: vec![0.0; nu],
            dq_all: vec![0.0; nd * 2 * d],
            dqj: vec![0.0; d * 2 * d],
            dvj: vec![0.0; d * 2 * d],
        })
    }

    /// [`step_jacobian_in`](Self::step_jacobian_in) without allocation: the step from (q, p)
    /// writes the new state into `next` and its exact Jacobian (2D×2D, order (q, p)) into
    /// `jacobian`, using the buffers of `tws` (from
    /// [`tangent_workspace`](Self::tangent_workspace) for the same Lagrangian).
    #[allow(clippy::too_many_arguments)]
    pub fn step_jacobian_into<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        tws: &mut TangentWorkspace,
        q: &[f64],
        p: &[f64],
        next: (&mut [f64], &mut [f64]),
        jacobian: &mut DMatrix<f64>,
        step_index: usize,
    ) -> Result<()> {
        self.check_state(lag, q, p)?;
        let d = lag.dim();
        ensure_len("workspace dimension", d, ws.dim())?;
        ensure_len("tangent workspace dimension", d, tws.d)?;
        ensure_len("tangent workspace basis size", self.n(), tws.n)?;
        ensure_len("q_next", d, next.0.len())?;
        ensure_len("p_next", d, next.1.len())?;
        if jacobian.shape() != (2 * d, 2 * d) {
            return Err(GviError::DimensionMismatch {
                what: "step Jacobian".into(),
                expected: 2 * d,
                got: jacobian.nrows().max(jacobian.ncols()),
            });
        }
        self.step(lag, ws, q, p, next.0, next.1)
            .map_err(|f| GviError::NewtonFailure {
                step: step_index,
                t: step_index as f64 * self.step_size(),
                residual: f.residual,
                iterations: f.iterations,
                reason: f.reason,
            })?;
        self.jacobian_from_coefficients_into(lag, ws.coefficients(), tws, jacobian)
    }

    /// The step Jacobian at a solved step, from that step's Galerkin coefficients (n×D
    /// row-major, row i = Q_i, e.g. [`Trajectory::coefficients`](crate::Trajectory)`[k]`).
    /// The coefficients must solve the stage equations; p_k does not enter the Jacobian.
    pub fn step_jacobian_from_coefficients<L: Lagrangian>(
        &self,
        lag: &L,
        coefficients: &[f64],
    ) -> Result<DMatrix<f64>> {
        let d = lag.dim();
        let mut tws = self.tangent_workspace(lag)?;
        let mut jac = DMatrix::<f64>::zeros(2 * d, 2 * d);
        self.jacobian_from_coefficients_into(lag, coefficients, &mut tws, &mut jac)?;
        Ok(jac)
    }

    /// The step Jacobian from the coefficients into `jac`, in the buffers of `tws`.
    fn jacobian_from_coefficients_into<L: Lagrangian>(
        &self,
        lag: &L,
        coefficients: &[f64],
        tws: &mut TangentWorkspace,
        jac: &mut DMatrix<f64>,
    ) -> Result<()> {
        let t = self.tables();
        let (n, m, h, d) = (t.n, t.m, self.step_size(), lag.dim());
        ensure_len("Galerkin coefficients", n * d, coefficients.len())?;
        ensure_finite("Galerkin coefficients", coefficients)?;
        self.node_hessians(lag, coefficients, tws);
        self.full_action_hessian(tws);
        let (nd, nu, d2) = (n * d, (n - 1) * d, 2 * d);
        // Solve F_X dX = −(F_q dq + F_p dp) for the 2D unit directions.
        for r in 0..nu {
            tws.fx[r * nu..(r + 1) * nu].copy_from_slice(&tws.hess[r * nd + d..r * nd + nd]);
        }
        tws.lu
            .refactor(&tws.fx)
            .map_err(|_| GviError::NewtonFailure {
                step: 0,
                t: 0.0,
                residual: f64::NAN,
                iterations: 0,
                reason: "step Jacobian: singular stage matrix".into(),
            })?;
        // dQ for all coefficients: dQ_0 = dq, dQ_1 … dQ_{n−1} = dX.
        tws.dq_all.iter_mut().for_each(|x| *x = 0.0);
        for r in 0..d {
            tws.dq_all[r * d2 + r] = 1.0;
        }
        for c in 0..d2 {
            for r in 0..nu {
                tws.col[r] = if c < d { -tws.hess[r * nd + c] } else { 0.0 };
            }
            if c >= d {
                tws.col[c - d] -= 1.0;
            }
            tws.lu.solve_in_place(&mut tws.col, &mut tws.scratch);
            for r in 0..nu {
                tws.dq_all[(d + r) * d2 + c] = tws.col[r];
            }
        }
        jac.fill(0.0);
        for r in 0..d {
            for c in 0..d2 {
                jac[(r, c)] = tws.dq_all[(nu + r) * d2 + c];
            }
        }
        // dp_{k+1} = dp_k + h Σ_j b_j (L_qq δq_j + L_qv δv_j).
        for r in 0..d {
            jac[(d + r, d + r)] = 1.0;
        }
        let (dqj, dvj) = (&mut tws.dqj, &mut tws.dvj);
        for j in 0..m {
            let (phi, dphi) = (&t.phi[j * n..(j + 1) * n], &t.dphi[j * n..(j + 1) * n]);
            dqj.iter_mut().for_each(|x| *x = 0.0);
            dvj.iter_mut().for_each(|x| *x = 0.0);
            for i in 0..n {
                let (a, b) = (phi[i], dphi[i] / h);
                for s in 0..d {
                    for c in 0..d2 {
                        let x = tws.dq_all[(i * d + s) * d2 + c];
                        dqj[s * d2 + c] += a * x;
                        dvj[s * d2 + c] += b * x;
                    }
                }
            }
            let w = h * t.weights[j];
            let (qq, qv) = (
                &tws.qq[j * d * d..(j + 1) * d * d],
                &tws.qv[j * d * d..(j + 1) * d * d],
            );
            for r in 0..d {
                for c in 0..d2 {
                    let mut acc = 0.0;
                    for s in 0..d {
                        acc += qq[r * d + s] * dqj[s * d2 + c] + qv[r * d + s] * dvj[s * d2 + c];
                    }
                    jac[(d + r, c)] += w * acc;
                }
            }
        }
        if jac.iter().any(|x| !x.is_finite()) {
            return Err(GviError::NonFinite {
                what: "step Jacobian".into(),
                value: f64::NAN,
            });
        }
        Ok(())
    }

    /// Curve and second derivatives of L at every node for the given coefficients, into `tws`.
    fn node_hessians<L: Lagrangian>(&self, lag: &L, coeffs: &[f64], tws: &mut TangentWorkspace) {
        let t = self.tables();
        let (n, m, h, d) = (t.n, t.m, self.step_size(), lag.dim());
        tws.q.iter_mut().for_each(|x| *x = 0.0);
        tws.v.iter_mut().for_each(|x| *x = 0.0);
        let separable = tws.mass.is_some();
        for j in 0..m {
            let (phi, dphi) = (&t.phi[j * n..(j + 1) * n], &t.dphi[j * n..(j + 1) * n]);
            let (qj, vj) = (
                &mut tws.q[j * d..(j + 1) * d],
                &mut tws.v[j * d..(j + 1) * d],
            );
            for i in 0..n {
                for r in 0..d {
                    qj[r] += phi[i] * coeffs[i * d + r];
                    vj[r] += dphi[i] / h * coeffs[i * d + r];
                }
            }
            let blk = j * d * d..(j + 1) * d * d;
            if separable {
                // L_qv = 0; the constant L_vv = M enters through the kinetic matrix.
                lag.force_jacobian(qj, &mut tws.qq[blk]);
            } else {
                lag.hessian(
                    qj,
                    vj,
                    &mut tws.qq[blk.clone()],
                    &mut tws.qv[blk.clone()],
                    &mut tws.vv[blk],
                );
            }
        }
    }

    /// The full (nD)×(nD) Hessian ∂²S/∂Q_a∂Q_b of the discrete action (the same formulas as
    /// the Newton Jacobian, over all rows and columns) from the node values in `tws`.
    fn full_action_hessian(&self, tws: &mut TangentWorkspace) {
        let t = self.tables();
        let (n, m, h, d) = (t.n, t.m, self.step_size(), tws.d);
        let nd = n * d;
        let hess = &mut tws.hess;
        hess.iter_mut().for_each(|x| *x = 0.0);
        if let Some(mass) = &tws.mass {
            for a in 0..n {
                for b in 0..n {
                    let k = t.kinetic[a * n + b] / h;
                    for r in 0..d {
                        for s in 0..d {
                            hess[(a * d + r) * nd + b * d + s] = k * mass[r * d + s];
                        }
                    }
                }
            }
        }
        let separable = tws.mass.is_some();
        for j in 0..m {
            let w = t.weights[j];
            let (phi, dphi) = (&t.phi[j * n..(j + 1) * n], &t.dphi[j * n..(j + 1) * n]);
            let blk = j * d * d..(j + 1) * d * d;
            let (qq, qv, vv) = (&tws.qq[blk.clone()], &tws.qv[blk.clone()], &tws.vv[blk]);
            for a in 0..n {
                let (pa, da) = (phi[a], dphi[a]);
                for b in 0..n {
                    let (pb, db) = (phi[b], dphi[b]);
                    let cqq = w * h * pa * pb;
                    if separable {
                        for r in 0..d {
                            for s in 0..d {
                                hess[(a * d + r) * nd + b * d + s] += cqq * qq[r * d + s];
                            }
                        }
                        continue;
                    }
                    let (cqv, cvq, cvv) = (w * pa * db, w * da * pb, w * da * db / h);
                    for r in 0..d {
                        for s in 0..d {
                            hess[(a * d + r) * nd + b * d + s] += cqq * qq[r * d + s]
                                + cqv * qv[r * d + s]
                                + cvq * qv[s * d + r]
                                + cvv * vv[r * d + s];
                        }
                    }
                }
            }
        }
    }

    /// The step Jacobians J_0, J_1, … of a run of `steps` steps from (q0, p0), each handed to
    /// `visit` in turn (2D×2D, order (q, p)): the walk the tangent map and the Lyapunov
    /// estimate share, with one workspace and no allocation per step.
    fn walk_step_jacobians<L: Lagrangian>(
        &self,
        lag: &L,
        q0: &[f64],
        p0: &[f64],
        steps: usize,
        mut visit: impl FnMut(&DMatrix<f64>),
    ) -> Result<()> {
        check_steps(steps)?;
        self.check_state(lag, q0, p0)?;
        let mut ws = self.workspace(lag)?;
        let mut tws = self.tangent_workspace(lag)?;
        let d = lag.dim();
        let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
        let (mut qn, mut pn) = (vec![0.0; d], vec![0.0; d]);
        let mut jac = DMatrix::<f64>::zeros(2 * d, 2 * d);
        for k in 0..steps {
            self.step_jacobian_into(
                lag,
                &mut ws,
                &mut tws,
                &q,
                &p,
                (&mut qn, &mut pn),
                &mut jac,
                k,
            )?;
            visit(&jac);
            std::mem::swap(&mut q, &mut qn);
            std::mem::swap(&mut p, &mut pn);
        }
        Ok(())
    }

    /// The tangent map along a run of `steps` steps from (q0, p0): the cumulative products
    /// Φ_k = J_{k−1} ⋯ J_0 for k = 1 … steps (each 2D×2D, order (q, p)), i.e. the solution of
    /// the discrete variational equations.
    pub fn tangent_map<L: Lagrangian>(
        &self,
        lag: &L,
        q0: &[f64],
        p0: &[f64],
        steps: usize,
    ) -> Result<Vec<DMatrix<f64>>> {
        let d2 = 2 * lag.dim();
        let mut phi = DMatrix::<f64>::identity(d2, d2);
        let mut out = Vec::with_capacity(steps.min(1 << 16));
        self.walk_step_jacobians(lag, q0, p0, steps, |jac| {
            phi = jac * &phi;
            out.push(phi.clone());
        })?;
        Ok(out)
    }

    /// Estimates of all 2D Lyapunov exponents of the discrete flow from (q0, p0) over
    /// `steps` steps (time steps·h), by re-orthonormalising the tangent map with a QR
    /// factorisation every step (Benettin's method). Sorted in decreasing order; for a
    /// symplectic map they come in ± pairs (to the accuracy of the finite-time estimate).
    pub fn lyapunov_estimate<L: Lagrangian>(
        &self,
        lag: &L,
        q0: &[f64],
        p0: &[f64],
        steps: usize,
    ) -> Result<Vec<f64>> {
        let d2 = 2 * lag.dim();
        let mut basis = DMatrix::<f64>::identity(d2, d2);
        let mut sums = vec![0.0; d2];
        self.walk_step_jacobians(lag, q0, p0, steps, |jac| {
            let qr = (jac * &basis).qr();
            let r = qr.r();
            for (i, s) in sums.iter_mut().enumerate() {
                *s += r[(i, i)].abs().ln();
            }
            basis = qr.q();
        })?;
        let time = steps as f64 * self.step_size();
        let mut exps: Vec<f64> = sums.iter().map(|s| s / time).collect();
        exps.sort_by(|a, b| b.total_cmp(a));
        Ok(exps)
    }
}

fn check_steps(steps: usize) -> Result<()> {
    if steps == 0 || steps > MAX_STEPS {
        return Err(GviError::InvalidStepCount {
            steps,
            reason: format!("need 1 ≤ steps ≤ {MAX_STEPS}"),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::stage::Mode;
    use super::*;
    use crate::systems::{Kepler, Pendulum};

    /// The stage block of the full action Hessian is the Newton matrix of `jacobian_rows` (both
    /// evaluated on the converged curve), for the separable and the general path.
    fn check_block<L: Lagrangian>(lag: &L, q: &[f64], p: &[f64]) {
        let gvi = GalerkinIntegrator::spectral(7, 0.4).unwrap();
        let mut ws = gvi.workspace(lag).unwrap();
        let d = lag.dim();
        let (mut qn, mut pn) = (vec![0.0; d], vec![0.0; d]);
        gvi.step(lag, &mut ws, q, p, &mut qn, &mut pn).unwrap();
        let mut tws = gvi.tangent_workspace(lag).unwrap();
        gvi.node_hessians(lag, ws.coefficients(), &mut tws);
        gvi.full_action_hessian(&mut tws);
        let nd = 7 * d;
        let hess = |r: usize, c: usize| tws.hess[r * nd + c];
        gvi.jacobian_rows(lag, &mut ws, Mode::InitialValue);
        let nu = 6 * d;
        for r in 0..nu {
            for c in 0..nu {
                let (a, b) = (hess(r, c + d), ws.system.jacobian(nu)[r * nu + c]);
                assert!(
                    (a - b).abs() <= 1e-12 * (1.0 + a.abs()),
                    "({r},{c}): {a} vs {b}"
                );
            }
        }
    }

    struct General(Kepler);
    impl Lagrangian for General {
        fn dim(&self) -> usize {
            2
        }
        fn lagrangian<T: num_dual::DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
            self.0.lagrangian(q, v) + (q[0] * v[1] - q[1] * v[0]) * 0.3
        }
    }

    #[test]
    fn full_hessian_contains_the_newton_matrix() {
        let k = Kepler::new(1.0).unwrap();
        check_block(&k, &[0.4, 0.0], &[0.0, 2.0]);
        check_block(&Pendulum::unit(), &[1.0], &[0.3]);
        check_block(&General(k), &[0.4, 0.0], &[0.0, 2.0]);
    }
}
