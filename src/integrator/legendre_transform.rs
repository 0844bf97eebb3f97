//! The discrete Legendre transforms of one step (docs/DESIGN.md §2; paper §1.1 and eq. (4)).
//!
//! The discrete Lagrangian L_d(q_k, q_{k+1}) defines the momenta at the ends of a step,
//!
//!   p_k = −D₁L_d(q_k, q_{k+1}) = −∂S_d/∂Q_0,   p_{k+1} = D₂L_d(q_k, q_{k+1}) = ∂S_d/∂Q_{n−1}
//!
//! (the maps F⁻L_d and F⁺L_d of paper §1.1; the end components of the action gradient of
//! [`super::discrete_action`] at a curve that solves the internal stage equations). A step
//! inverts the first: given (q_k, p_k) it solves p_k + ∂S_d/∂Q_0 = 0 with the internal stage
//! equations (the system of paper eq. (4)), then evaluates the second.
//!
//! Here, in one place:
//! - [`GalerkinIntegrator::discrete_legendre_transforms`]: both transforms at any curve;
//! - `legendre_transform_rows`: the first transform as the step's residual rows, summed in
//!   double-double together with the step's total impulse h Σ_j b_j L_q(c_j), from which
//!   p_{k+1} = p_k + impulse (docs/DESIGN.md §4: the rounding of these rows made the energy
//!   drift);
//! - `inverse_legendre`: the continuous inverse transform v = (∂L/∂v)⁻¹(q, p), for the first
//!   step's linear initial guess.
//!
//! Guide: docs/guide/paper-objects.md.

use super::dd::{dd_acc, max_abs, two_sum};
use super::{GalerkinIntegrator, Workspace};
use crate::basis::Basis;
use crate::curve::GalerkinCurveRef;
use crate::error::Result;
use crate::lagrangian::Lagrangian;
use crate::quadrature::Quadrature;

/// (p_k, p_{k+1}) = (−∂S/∂Q_0, ∂S/∂Q_{n−1}) from the gradient in the workspace.
pub(super) fn legendre_transforms_of_gradient(ws: &Workspace) -> (Vec<f64>, Vec<f64>) {
    let (n, d) = (ws.n, ws.d);
    (
        ws.stage.grad[..d].iter().map(|x| -x).collect(),
        ws.stage.grad[(n - 1) * d..n * d].to_vec(),
    )
}

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// The discrete Legendre transforms of a Galerkin curve in this integrator's basis:
    /// p_k = −∂S_d/∂Q_0 and p_{k+1} = ∂S_d/∂Q_{n−1} (paper §1.1, F⁻L_d and F⁺L_d, and eq. (4)).
    /// For the curve of a solved step (e.g. [`Workspace::curve`] after
    /// [`step`](Self::step)) they are the step's p_k and p_{k+1} to round-off; for any other
    /// curve they are the end momenta its action assigns.
    ///
    /// Errors: a curve whose n, h or dimension is not this integrator's and the Lagrangian's.
    ///
    /// ```
    /// use galerkin_vi::prelude::*;
    ///
    /// let kepler = Kepler::new(1.0)?;
    /// let (q0, p0) = Kepler::paper_initial_state();
    /// let gvi = GalerkinIntegrator::spectral(32, 2.0)?;
    /// let mut ws = gvi.workspace(&kepler)?;
    /// let (mut q1, mut p1) = ([0.0; 2], [0.0; 2]);
    /// gvi.step(&kepler, &mut ws, &q0, &p0, &mut q1, &mut p1)?;
    ///
    /// let curve = ws.curve(); // the step's Galerkin curve, no copy
    /// let (pk, pk1) = gvi.discrete_legendre_transforms(&kepler, curve)?;
    /// let grad = gvi.discrete_action_gradient(&kepler, curve)?; // (−p0, 0, …, 0, p1)
    /// let s = gvi.discrete_action(&kepler, curve)?; // L_d(q0, q1)
    /// let ld = gvi.discrete_lagrangian(&kepler, &q0, &q1)?;
    /// assert!((s - ld.value).abs() < 1e-12 * ld.value.abs());
    /// assert!((pk[1] - p0[1]).abs() < 1e-12 && (pk1[0] - p1[0]).abs() < 1e-12);
    /// assert!(grad[2..62].iter().all(|g| g.abs() < 1e-12));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn discrete_legendre_transforms<L: Lagrangian>(
        &self,
        lag: &L,
        curve: GalerkinCurveRef<'_>,
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        let mut ws = self.workspace_at_curve(lag, curve)?;
        self.action_gradient(lag, &mut ws, false);
        Ok(legendre_transforms_of_gradient(&ws))
    }

    /// The Legendre-transform rows of the initial-value residual into the first D entries of
    /// the Newton right-hand side, and the step's total impulse h Σ_j b_j L_q(c_j) into the
    /// iterate (hi + lo).
    ///
    /// The rows are p_k + impulse − ∂S/∂ΔQ_{n−1} = 0, the form that makes
    /// p_{k+1} = p_k + impulse exactly D₂L_d of the discrete Lagrangian the tables define (q_k
    /// enters every node with coefficient exactly 1 and the velocities not at all); in exact
    /// arithmetic it is p_k + Σ_{a<n−1} u_a ∂S/∂Q_a = 0, the paper's momentum condition,
    /// eq. (4), plus
    /// u-weighted stage equations
    /// (paper eq. (3)).
    ///
    /// Round-off (docs/DESIGN.md §4): the terms p_k, the impulse, and both parts of ∂S/∂ΔQ_{n−1}
    /// are O(|p|) each (near periapsis of an eccentric orbit the impulse of a large step is as
    /// large as p) and cancel to O(ε). Rounding them in working precision leaves an error
    /// ε|p| in the row, i.e. in q_{k+1}, every step — and, measured, not a random one: it
    /// made the energy drift linearly (Kepler e = 0.6, Legendre n = 24, h = 0.5:
    /// ΔE = −4e-14 at T = 2000 and −7e-14 at T = 4000, every realisation the same sign; the
    /// harmonic oscillator likewise). So for separable Lagrangians the whole row is summed in
    /// double-double: products exact by FMA, sums by TwoSum, including the low parts of the
    /// state (p_err) and of ΔQ_{n−1}. The drift fell below the random walk (`tests/roundoff.rs`).
    pub(super) fn legendre_transform_rows(&self, ws: &mut Workspace, p_k: &[f64]) {
        let (t, h) = (self.tables(), self.step_size());
        let (d, n) = (ws.d, ws.n);
        let last = (n - 1) * d;
        self.impulse(ws);
        let (impulse, impulse_lo) = ws.iterate.impulse();
        let p_lo = ws.iterate.momentum_lo();
        let rows = ws.system.rhs_mut(d);
        for r in 0..d {
            rows[r] = (p_k[r] - ws.stage.grad[last + r]) + (impulse[r] + p_lo[r]);
        }
        let Some(sep) = &ws.separable else {
            return;
        };
        let x = if ws.stage.curve_of_candidate() {
            ws.guess.candidate()
        } else {
            ws.iterate.increments()
        };
        // p_k + impulse …
        for r in 0..d {
            let (s, e) = two_sum(p_k[r], impulse[r]);
            ws.stage.dd_hi[r] = s;
            ws.stage.dd_lo[r] = e + (p_lo[r] + impulse_lo[r]);
        }
        // … − Σ_j φ_{n−1}(c_j) h b_j L_q(c_j) (side by side over r, each sum in the order
        // of j) …
        for j in 0..t.m {
            let w = h * t.weights[j];
            let phi = t.phi[j * n + n - 1];
            let lq = &ws.stage.lq[j * d..(j + 1) * d];
            for ((s, e), &f) in ws
                .stage
                .dd_hi
                .iter_mut()
                .zip(ws.stage.dd_lo.iter_mut())
                .zip(lq)
            {
                let g = w * f;
                dd_acc(s, e, -phi, g);
                *e -= phi * w.mul_add(f, -g);
            }
        }
        for r in 0..d {
            let (mut s, mut e) = (ws.stage.dd_hi[r], ws.stage.dd_lo[r]);
            // … − (1/h) Σ_b K_{n−1,b} M ΔQ_b.
            let (kinetic, index) = sep.kinetic_last_row(r);
            for (c, &i) in kinetic.iter().zip(index) {
                dd_acc(&mut s, &mut e, -c, x[i]);
            }
            if !ws.stage.curve_of_candidate() {
                for (c, &i) in kinetic.iter().zip(index) {
                    if i >= last {
                        e -= c * ws.iterate.last_lo()[i - last];
                    }
                }
            }
            rows[r] = s + e;
        }
    }

    /// Velocity v with ∂L/∂v(q, v) = p into `ws.stage.vel` (inverse Legendre transform), starting
    /// from the value already in `ws.stage.vel`.
    pub(super) fn inverse_legendre<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        q: &[f64],
        p: &[f64],
    ) {
        let d = ws.d;
        if let Some(sep) = &ws.separable {
            ws.stage.vel.copy_from_slice(p);
            sep.solve_mass(&mut ws.stage.vel, &mut ws.stage.small_scratch);
            return;
        }
        // Newton on L_v(t_k, q, v) = p with Jacobian L_vv.
        let t_k = ws.stage.step_start();
        for _ in 0..20 {
            let (lq, lv) = (&mut ws.stage.lq[..d], &mut ws.stage.lv[..d]);
            lag.gradient_at(t_k, q, &ws.stage.vel, lq, lv);
            let mut err = 0.0f64;
            for r in 0..d {
                ws.stage.small_rhs[r] = p[r] - lv[r];
                err = err.max(ws.stage.small_rhs[r].abs());
            }
            if err <= 1e-15 * (1.0 + max_abs(p)) {
                return;
            }
            lag.hessian_at(
                t_k,
                q,
                &ws.stage.vel,
                &mut ws.stage.hqq,
                &mut ws.stage.hqv,
                &mut ws.stage.hvv,
            );
            if ws.stage.small.refactor(&ws.stage.hvv).is_err() {
                return;
            }
            ws.stage
                .small
                .solve_in_place(&mut ws.stage.small_rhs, &mut ws.stage.small_scratch);
            for r in 0..d {
                ws.stage.vel[r] += ws.stage.small_rhs[r];
            }
            if !ws.stage.vel.iter().all(|x| x.is_finite()) {
                ws.stage.vel.copy_from_slice(p);
                return;
            }
        }
    }
}
