//! The Lie group Galerkin (spectral) variational integrator on SO(3).
//!
//! One step from (R_k, μ_k): the curve R(t_k + τh) = R_k τ(ξ(τ)), ξ(τ) = Σ_i Ξ_i φ_i(τ) with
//! Ξ_0 = 0; the discrete action S = h Σ_j b_j ℓ(R_k τ(ξ_j), J_r(ξ_j) ξ̇_j). With X = Ξ_{n−1}
//! and ν = μ_k − h Σ_j b_j τ(ξ_j) f(R_k τ(ξ_j)), the 3(n − 1) unknowns Ξ_1 … Ξ_{n−1} solve
//!
//! - ∂S/∂Ξ_i = 0, i = 1 … n − 2 (internal stages, the discrete Euler–Poincaré equations),
//! - J_l(X)ᵀ ν = ∂S/∂Ξ_{n−1} (μ_k = −D₁L_d, the left discrete Legendre transform),
//!
//! and then R_{k+1} = R_k τ(X), μ_{k+1} = τ(X)ᵀ ν (= J_r(X)⁻ᵀ ∂S/∂Ξ_{n−1} = D₂L_d, the right
//! transform). See [`crate::lie`] for the derivation. Newton runs on the Ξ with the exact
//! Jacobian: second derivatives of ℓ by hyper-dual numbers at each quadrature node, the
//! torque and the J_l(X)ᵀ term by dual numbers.

use super::body::RigidBody;
use super::node::{check_initial, jacobian3, node_derivatives, solve3};
use super::so3::{self, Mat3, Retraction};
use crate::basis::{AnyBasis, Basis, BasisKind, CurveFit};
use crate::error::{GviError, Result};
use crate::linalg::Lu;
use crate::newton::{Correction, NewtonFailure, NewtonIteration, Termination, drive};
use crate::quadrature::{QuadratureKind, QuadratureRule};
use num_dual::Dual64;

/// A state on T*SO(3), left-trivialised: orientation R (body to space) and body momentum μ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LieState {
    /// Orientation.
    pub r: Mat3<f64>,
    /// Body angular momentum.
    pub mu: [f64; 3],
}

impl LieState {
    /// Spatial angular momentum R μ.
    pub fn spatial_momentum(&self) -> [f64; 3] {
        so3::mul_vec(&self.r, &self.mu)
    }
}

/// The states of a run at t₀ + k h.
#[derive(Debug, Clone, PartialEq)]
pub struct LieTrajectory {
    /// Initial time.
    pub t0: f64,
    /// Step size.
    pub h: f64,
    /// States at the step ends (steps + 1).
    pub states: Vec<LieState>,
    /// Newton iterations of each step.
    pub iterations: Vec<usize>,
}

/// Newton settings of the step solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LieNewtonOptions {
    /// Iteration limit.
    pub max_iterations: usize,
    /// Converged when the max-norm increment is below `tolerance · max(1, ‖Ξ‖)`, or when it
    /// stops decreasing below 1e-9 (the round-off floor).
    pub tolerance: f64,
    /// RK4 substeps per interpolation-node gap of the initial guess.
    pub guess_substeps: usize,
}

impl Default for LieNewtonOptions {
    fn default() -> Self {
        LieNewtonOptions {
            max_iterations: 40,
            tolerance: 1e-15,
            guess_substeps: 4,
        }
    }
}

/// The Lie group Galerkin variational integrator for rigid bodies.
#[derive(Debug, Clone)]
pub struct LieGalerkin<B: Basis = AnyBasis> {
    basis: B,
    rule: QuadratureRule,
    h: f64,
    retraction: Retraction,
    options: LieNewtonOptions,
    /// φ_i(c_j), row j.
    phi: Vec<f64>,
    /// φ_i'(c_j)/h, row j.
    dphi: Vec<f64>,
    fit: CurveFit,
}

/// Reusable buffers of one run (no allocation in the step loop).
struct Workspace {
    x: Vec<f64>,
    res: Vec<f64>,
    jac: Vec<f64>,
    grad: Vec<f64>,
    hess: Vec<f64>,
    lu: Lu,
    scratch: Vec<f64>,
    values: Vec<f64>,
    col: Vec<f64>,
    torque: Vec<[f64; 3]>,
    dtorque: Vec<Mat3<f64>>,
}

impl LieGalerkin<AnyBasis> {
    /// The spectral default: Chebyshev–Lagrange basis, 2n Gauss–Legendre points, exp map.
    pub fn spectral(n: usize, h: f64) -> Result<Self> {
        Self::from_kinds(
            BasisKind::Chebyshev,
            n,
            QuadratureKind::GaussLegendre,
            None,
            h,
        )
    }

    /// Build from named kinds (points: the rule's default for n when `None`).
    pub fn from_kinds(
        basis: BasisKind,
        n: usize,
        quadrature: QuadratureKind,
        points: Option<usize>,
        h: f64,
    ) -> Result<Self> {
        let b = basis.build(n)?;
        let rule = quadrature.build(points.unwrap_or_else(|| quadrature.default_points(n)))?;
        Self::new(b, rule, h)
    }
}

impl<B: Basis> LieGalerkin<B> {
    /// Build from a basis, a quadrature rule and a step size.
    pub fn new(basis: B, rule: QuadratureRule, h: f64) -> Result<Self> {
        if !(h.is_finite() && h > 0.0) {
            return Err(GviError::InvalidStepSize { h });
        }
        rule.validate()?;
        let n = basis.len();
        if let Some(deg) = basis.polynomial_degree() {
            let required = 2 * deg.saturating_sub(1);
            if rule.degree < required {
                return Err(GviError::InvalidQuadrature {
                    reason: format!(
                        "{} points of {} integrate degree {} but the {} basis with n = {n} \
                         needs degree {required} (φ_a'φ_b' exactly)",
                        rule.len(),
                        rule.family,
                        rule.degree,
                        basis.name()
                    ),
                });
            }
        }
        let m = rule.len();
        let (mut phi, mut dphi) = (vec![0.0; m * n], vec![0.0; m * n]);
        for (j, &c) in rule.nodes.iter().enumerate() {
            basis.eval(
                c,
                &mut phi[j * n..(j + 1) * n],
                &mut dphi[j * n..(j + 1) * n],
            );
        }
        dphi.iter_mut().for_each(|d| *d /= h);
        let fit = CurveFit::new(&basis)?;
        Ok(LieGalerkin {
            basis,
            rule,
            h,
            retraction: Retraction::Exp,
            options: LieNewtonOptions::default(),
            phi,
            dphi,
            fit,
        })
    }

    /// Use another retraction (Cayley instead of exp).
    pub fn with_retraction(mut self, retraction: Retraction) -> Self {
        self.retraction = retraction;
        self
    }

    /// Replace the Newton settings.
    pub fn with_options(mut self, options: LieNewtonOptions) -> Self {
        self.options = options;
        self
    }

    /// The step size.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// Number of basis functions n.
    pub fn n(&self) -> usize {
        self.basis.len()
    }

    /// Number of quadrature points m.
    pub fn quadrature_points(&self) -> usize {
        self.rule.len()
    }

    /// The retraction.
    pub fn retraction(&self) -> Retraction {
        self.retraction
    }

    /// A description, e.g. "chebyshev n = 8, gauss-legendre (16 points), exp, h = 0.5".
    pub fn describe(&self) -> String {
        format!(
            "{} n = {}, {}, {}, h = {}",
            self.basis.name(),
            self.n(),
            crate::quadrature::Quadrature::name(&self.rule),
            self.retraction,
            self.h
        )
    }

    fn workspace(&self) -> Workspace {
        let n = self.n();
        let m = self.rule.len();
        let dim = 3 * (n - 1);
        Workspace {
            x: vec![0.0; dim],
            res: vec![0.0; dim],
            jac: vec![0.0; dim * dim],
            grad: vec![0.0; 3 * n],
            hess: vec![0.0; 9 * n * n],
            lu: Lu::with_capacity(dim),
            scratch: vec![0.0; dim.max(3 * n)],
            values: vec![0.0; 3 * n],
            col: vec![0.0; n],
            torque: vec![[0.0; 3]; m],
            dtorque: vec![[[0.0; 3]; 3]; m],
        }
    }

    /// Integrate `steps` steps from (R₀, μ₀) at t₀.
    pub fn integrate<S: RigidBody>(
        &self,
        body: &S,
        t0: f64,
        r0: &Mat3<f64>,
        mu0: &[f64; 3],
        steps: usize,
    ) -> Result<LieTrajectory> {
        check_initial(r0, mu0, steps)?;
        let mut ws = self.workspace();
        let mut states = Vec::with_capacity(steps + 1);
        let mut iterations = Vec::with_capacity(steps);
        let mut state = LieState { r: *r0, mu: *mu0 };
        states.push(state);
        for k in 0..steps {
            let (next, it) = self.step_with(body, &state, &mut ws, k, t0 + k as f64 * self.h)?;
            state = next;
            states.push(state);
            iterations.push(it);
        }
        Ok(LieTrajectory {
            t0,
            h: self.h,
            states,
            iterations,
        })
    }

    /// One step (allocates its buffers; use [`integrate`](Self::integrate) for runs).
    pub fn step<S: RigidBody>(&self, body: &S, state: &LieState) -> Result<LieState> {
        check_initial(&state.r, &state.mu, 1)?;
        let mut ws = self.workspace();
        self.step_with(body, state, &mut ws, 0, 0.0).map(|s| s.0)
    }

    fn step_with<S: RigidBody>(
        &self,
        body: &S,
        state: &LieState,
        ws: &mut Workspace,
        step: usize,
        t: f64,
    ) -> Result<(LieState, usize)> {
        self.initial_guess(body, state, ws);
        let fail = |residual: f64, iterations: usize, reason: &str| GviError::NewtonFailure {
            step,
            t,
            residual,
            iterations,
            reason: reason.into(),
        };
        let mut newton = LieNewton {
            lie: self,
            body,
            state,
            ws,
            residual: f64::NAN,
        };
        let first = self.termination(1.0);
        let iterations = match drive(&mut newton, &first) {
            Ok((_, iterations)) => iterations,
            Err(f) => return Err(fail(f.residual, f.iterations, &f.reason)),
        };
        // ν at the converged curve (μ_k for a free body), then the update.
        let n = self.n();
        let mut nu = state.mu;
        if body.has_potential() {
            let w = self.node_curve(ws, state, body, false);
            for k in 0..3 {
                nu[k] -= w[k];
            }
        }
        let x: [f64; 3] = [
            ws.x[3 * (n - 2)],
            ws.x[3 * (n - 2) + 1],
            ws.x[3 * (n - 2) + 2],
        ];
        let e = self.retraction.map(&x);
        let next = LieState {
            r: so3::mul(&state.r, &e),
            mu: so3::mul_tr_vec(&e, &nu),
        };
        if !next
            .mu
            .iter()
            .chain(next.r.iter().flatten())
            .all(|v| v.is_finite())
        {
            return Err(fail(f64::NAN, iterations, "non-finite state"));
        }
        Ok((next, iterations))
    }

    /// The termination of the step's Newton solve (exact Jacobian, quadratic convergence):
    /// converged when the max-norm correction is at most `tolerance · max(1, ‖Ξ‖_∞)`, or at
    /// the round-off floor when it is below 1e-9 (absolute) and no longer halves.
    ///
    /// The two tests have different scales (relative to ‖Ξ‖ ≥ 1, absolute), so the
    /// corrections are reported with scale 1 and `xnorm` is folded into the tolerance; the
    /// floor and its θ are the largest doubles below 1e-9 and ½, so that the driver's
    /// `|δ| ≤ floor` and `θ > floor_theta` are exactly this solver's `|δ| < 1e-9` and
    /// `|δ| ≥ ½|δ_prev|` (a quotient of doubles below ½ is at most the double below ½), and
    /// the maps are bit for bit those of the hand-written loop this replaces.
    fn termination(&self, xnorm: f64) -> Termination {
        Termination::new(
            self.options.max_iterations,
            self.options.tolerance * xnorm,
            None,
            ROUNDOFF_FLOOR,
            FLOOR_THETA,
        )
    }

    /// ξ(c_j) for node j from the current coefficients (Ξ_0 = 0).
    fn xi_at(&self, ws: &Workspace, j: usize, derivative: bool) -> [f64; 3] {
        let n = self.n();
        let table = if derivative { &self.dphi } else { &self.phi };
        let row = &table[j * n..(j + 1) * n];
        let mut v = [0.0; 3];
        for a in 1..n {
            for c in 0..3 {
                v[c] += ws.x[3 * (a - 1) + c] * row[a];
            }
        }
        v
    }

    /// h Σ_j b_j τ(ξ_j) f(R_k τ(ξ_j)); with `jacobian`, also fills the per-node torque and its
    /// derivative in the workspace.
    fn node_curve<S: RigidBody>(
        &self,
        ws: &mut Workspace,
        state: &LieState,
        body: &S,
        jacobian: bool,
    ) -> [f64; 3] {
        let mut total = [0.0; 3];
        let rk: Mat3<Dual64> = so3::lift(&state.r);
        for j in 0..self.rule.len() {
            let xi = self.xi_at(ws, j, false);
            let tau = self.retraction;
            let f = |y: &[Dual64; 3]| {
                let e = tau.map(y);
                let r = so3::mul(&rk, &e);
                so3::mul_vec(&e, &body.torque(&r))
            };
            let (val, jac) = jacobian3(f, xi, jacobian);
            let w = self.h * self.rule.weights[j];
            for k in 0..3 {
                total[k] += w * val[k];
            }
            ws.torque[j] = val;
            ws.dtorque[j] = jac;
        }
        total
    }

    /// Residual and exact Jacobian of the step equations at the current coefficients.
    fn assemble<S: RigidBody>(&self, body: &S, state: &LieState, ws: &mut Workspace) {
        let n = self.n();
        let dim = 3 * (n - 1);
        let inertia = body.inertia();
        let tau = self.retraction;
        let potential = body.has_potential();
        let rk = state.r;
        ws.grad.iter_mut().for_each(|g| *g = 0.0);
        ws.hess.iter_mut().for_each(|g| *g = 0.0);
        let (mut g6, mut h36) = ([0.0; 6], [0.0; 36]);
        for j in 0..self.rule.len() {
            let xi = self.xi_at(ws, j, false);
            let v = self.xi_at(ws, j, true);
            let y = [xi[0], xi[1], xi[2], v[0], v[1], v[2]];
            node_derivatives(body, &rk, tau, inertia, potential, &y, &mut g6, &mut h36);
            let w = self.h * self.rule.weights[j];
            let (p, dp) = (
                &self.phi[j * n..(j + 1) * n],
                &self.dphi[j * n..(j + 1) * n],
            );
            for a in 1..n {
                for c in 0..3 {
                    ws.grad[3 * a + c] += w * (g6[c] * p[a] + g6[3 + c] * dp[a]);
                }
                for b in 1..n {
                    let (pp, pd, dpp, dd) =
                        (p[a] * p[b], p[a] * dp[b], dp[a] * p[b], dp[a] * dp[b]);
                    for c in 0..3 {
                        for e in 0..3 {
                            let hv = pp * h36[c * 6 + e]
                                + pd * h36[c * 6 + 3 + e]
                                + dpp * h36[(3 + c) * 6 + e]
                                + dd * h36[(3 + c) * 6 + 3 + e];
                            ws.hess[(3 * a + c) * 3 * n + 3 * b + e] += w * hv;
                        }
                    }
                }
            }
        }
        // Stage rows: ∂S/∂Ξ_a, a = 1 … n − 2 (unknown index a − 1).
        for a in 1..n - 1 {
            for c in 0..3 {
                let row = 3 * (a - 1) + c;
                ws.res[row] = ws.grad[3 * a + c];
                for b in 1..n {
                    for e in 0..3 {
                        ws.jac[row * dim + 3 * (b - 1) + e] =
                            ws.hess[(3 * a + c) * 3 * n + 3 * b + e];
                    }
                }
            }
        }
        // Momentum rows: J_l(X)ᵀ ν − ∂S/∂Ξ_{n−1}.
        let mut nu = state.mu;
        if potential {
            let w = self.node_curve(ws, state, body, true);
            for k in 0..3 {
                nu[k] -= w[k];
            }
        }
        let base = 3 * (n - 2);
        let x = [ws.x[base], ws.x[base + 1], ws.x[base + 2]];
        let nud = nu.map(Dual64::from_re);
        let (jl_nu, djl) = jacobian3(
            |y: &[Dual64; 3]| so3::mul_tr_vec(&tau.left_jacobian(y), &nud),
            x,
            true,
        );
        let jl: Mat3<f64> = tau.left_jacobian(&x);
        for c in 0..3 {
            let row = base + c;
            ws.res[row] = jl_nu[c] - ws.grad[3 * (n - 1) + c];
            for b in 1..n {
                for e in 0..3 {
                    let mut v = -ws.hess[(3 * (n - 1) + c) * 3 * n + 3 * b + e];
                    if b == n - 1 {
                        v += djl[c][e];
                    }
                    if potential {
                        // J_l(X)ᵀ ∂ν/∂Ξ_b, ∂ν/∂Ξ_b = −h Σ_j b_j φ_b(c_j) Dτ_j.
                        let mut s = 0.0;
                        for j in 0..self.rule.len() {
                            let wj = self.h * self.rule.weights[j] * self.phi[j * n + b];
                            for k in 0..3 {
                                s -= jl[k][c] * wj * ws.dtorque[j][k][e];
                            }
                        }
                        v += s;
                    }
                    ws.jac[row * dim + 3 * (b - 1) + e] = v;
                }
            }
        }
    }

    /// Initial guess: RK4 on the chart equations ξ̇ = J_r(ξ)⁻¹Ω, μ̇ = μ × Ω − f(R_k τ(ξ)) to the
    /// basis's interpolation nodes, then the coefficients that interpolate those values.
    fn initial_guess<S: RigidBody>(&self, body: &S, state: &LieState, ws: &mut Workspace) {
        let n = self.n();
        let nodes = self.fit.nodes();
        let tau = self.retraction;
        let rhs = |xi: &[f64; 3], mu: &[f64; 3]| -> ([f64; 3], [f64; 3]) {
            let w = body.angular_velocity(mu);
            let jr: Mat3<f64> = tau.right_jacobian(xi);
            let xd = solve3(&jr, &w);
            let mut md = so3::cross(mu, &w);
            if body.has_potential() {
                let r = so3::mul(&state.r, &tau.map(xi));
                let f = body.torque(&r);
                for k in 0..3 {
                    md[k] -= f[k];
                }
            }
            (xd, md)
        };
        let (mut xi, mut mu) = ([0.0; 3], state.mu);
        let mut tprev = 0.0;
        let sub = self.options.guess_substeps.max(1);
        for (i, &x) in nodes.iter().enumerate() {
            let dt = (x - tprev) * self.h / sub as f64;
            if dt > 0.0 {
                for _ in 0..sub {
                    let axpy = |a: &[f64; 3], s: f64, b: &[f64; 3]| {
                        [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
                    };
                    let (k1x, k1m) = rhs(&xi, &mu);
                    let (k2x, k2m) = rhs(&axpy(&xi, 0.5 * dt, &k1x), &axpy(&mu, 0.5 * dt, &k1m));
                    let (k3x, k3m) = rhs(&axpy(&xi, 0.5 * dt, &k2x), &axpy(&mu, 0.5 * dt, &k2m));
                    let (k4x, k4m) = rhs(&axpy(&xi, dt, &k3x), &axpy(&mu, dt, &k3m));
                    for k in 0..3 {
                        xi[k] += dt / 6.0 * (k1x[k] + 2.0 * k2x[k] + 2.0 * k3x[k] + k4x[k]);
                        mu[k] += dt / 6.0 * (k1m[k] + 2.0 * k2m[k] + 2.0 * k3m[k] + k4m[k]);
                    }
                }
            }
            tprev = x;
            ws.values[3 * i..3 * i + 3].copy_from_slice(&xi);
        }
        self.fit
            .values_to_coefficients_with(&mut ws.values, 3, &mut ws.col, &mut ws.scratch);
        ws.x.copy_from_slice(&ws.values[3..3 * n]);
    }
}

/// Below 1e-9 a correction that no longer halves is at the round-off floor of the step's
/// residual: the largest double below 1e-9, so that `|δ| ≤` it means `|δ| < 1e-9`.
const ROUNDOFF_FLOOR: f64 = f64::from_bits(1e-9f64.to_bits() - 1);

/// The contraction above which a correction no longer halves: the largest double below ½,
/// so that `θ >` it means `|δ| ≥ ½|δ_prev|`.
const FLOOR_THETA: f64 = f64::from_bits(0.5f64.to_bits() - 1);

/// The step's Newton solve as a [`NewtonIteration`] run by the crate's Newton driver
/// ([`crate::newton::drive`]): the residual and the exact Jacobian of the discrete
/// Euler–Poincaré equations (`LieGalerkin::assemble`), solved by dense LU.
struct LieNewton<'a, B: Basis, S: RigidBody> {
    lie: &'a LieGalerkin<B>,
    body: &'a S,
    state: &'a LieState,
    ws: &'a mut Workspace,
    /// The last residual's max-norm.
    residual: f64,
}

impl<B: Basis, S: RigidBody> NewtonIteration for LieNewton<'_, B, S> {
    fn residual(&mut self, _: usize) -> f64 {
        self.lie.assemble(self.body, self.state, self.ws);
        self.residual = self.ws.res.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        self.residual
    }

    fn correct(&mut self, iteration: usize) -> Result<(Correction, Termination), NewtonFailure> {
        let ws = &mut *self.ws;
        let dim = ws.x.len();
        if ws.lu.refactor(&ws.jac[..dim * dim]).is_err() {
            return Err(NewtonFailure {
                residual: self.residual,
                iterations: iteration,
                reason: "singular Jacobian".into(),
            });
        }
        ws.res.iter_mut().for_each(|r| *r = -*r);
        ws.lu.solve_in_place(&mut ws.res, &mut ws.scratch);
        let mut dnorm = 0.0f64;
        let mut xnorm = 1.0f64;
        for (x, d) in ws.x.iter_mut().zip(&ws.res) {
            *x += d;
            dnorm = dnorm.max(d.abs());
            xnorm = xnorm.max(x.abs());
        }
        // Scale 1: `xnorm` is in the tolerance (see `LieGalerkin::termination`).
        let correction = Correction {
            size: dnorm,
            scale: 1.0,
        };
        Ok((correction, self.lie.termination(xnorm)))
    }
}
