//! The one-step map: stage equations, their exact Jacobian, initial guesses and Newton.

use super::{GalerkinIntegrator, Tables, Workspace};
use crate::basis::Basis;
use crate::error::{GviError, Result, ensure_finite, ensure_len};
use crate::lagrangian::Lagrangian;
use crate::linalg::{Strided, gemm};
use crate::quadrature::Quadrature;
use serde::{Deserialize, Serialize};

/// How the Newton iteration of each step is started.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum InitialGuess {
    /// The constant curve q(t) = q_k.
    Constant,
    /// The straight line q_k + (t − t_k) v_k, with v_k the end velocity of the previous curve
    /// (or the inverse Legendre transform of p_k on the first step).
    Linear,
    /// The previous step's Galerkin curve continued over the new step.
    Extrapolate,
    /// A cheap explicit predictor: classical Runge–Kutta 4 on the Euler–Lagrange equations
    /// q̈ = M⁻¹ L_q(q) over the step (separable Lagrangians only), sampled at the basis's
    /// interpolation nodes by cubic Hermite interpolation and fitted in the basis.
    Predictor,
    /// Whichever of the three has the smallest stage residual (with very large steps
    /// extrapolation can be worse than a constant guess, so it is measured, not assumed).
    #[default]
    BestResidual,
    /// Coefficients supplied for one step by [`Workspace::warm_start`] (reported in
    /// [`StepStats::guess`]; as an option it behaves like `BestResidual`).
    Warm,
}

/// Newton iteration settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NewtonOptions {
    /// Iteration limit per step.
    pub max_iterations: usize,
    /// Stop when the estimated remaining error of the Newton unknowns (the increments
    /// ΔQ_i = Q_i − u_i q_k) is below `tolerance · max|ΔQ|` (error estimated from the
    /// contraction of successive Newton increments). The default 1e-16 is just below ε: with
    /// 1e-15 the Hermite and Chebyshev flows of `tests/bases.rs` drift apart by 1.1e-10 in
    /// 10 steps at n = 22 (the solve error, not the basis); 1e-16 costs 2.61 linear solves per
    /// step at n = 32, h = 2 with the exactly summed residuals of
    /// [`exact_kinetic`](Self::exact_kinetic) (2.96 with rounded ones; `tests/counts.rs`). The
    /// long-run results of `tests/roundoff.rs` are measured with the default.
    pub tolerance: f64,
    /// Also stop, as converged at the round-off floor, once increments below
    /// `floor_tolerance · max|ΔQ|` stop shrinking (iterating further only stirs noise).
    pub floor_tolerance: f64,
    /// How each step's iteration starts.
    pub initial_guess: InitialGuess,
    /// Substeps of the RK4 predictor guess (`None`: max(n, 8)).
    pub predictor_substeps: Option<usize>,
    /// Simplified Newton: reuse the factorised Jacobian across iterations and steps while
    /// the iteration contracts by at least `reuse_contraction` per iteration.
    pub reuse_jacobian: bool,
    /// Contraction factor above which a reused Jacobian is refactorised (full Newton).
    pub reuse_contraction: f64,
    /// Also start each step with the previous step's factorisation (pays off when h is small
    /// compared with the time scale, so that the Newton matrix changes little per step).
    pub reuse_across_steps: bool,
    /// Accumulate q and p across steps with compensated (Kahan–Babuška/TwoSum) summation of
    /// the step increments, in [`integrate`](GalerkinIntegrator::integrate) and the
    /// [`GalerkinMethod`](crate::baselines::GalerkinMethod) adapter (DESIGN.md §4). Costs 2D
    /// extra additions per step; removes the O(√N ε) (or O(N ε)) round-off drift of the
    /// naive sums over N steps.
    #[serde(default = "default_true")]
    pub compensated: bool,
    /// Sum the kinetic part (1/h) Σ_b K_ab M ΔQ_b of the stage rows in Newton's residuals in
    /// double-double (exact products by FMA, TwoSum) instead of one rounded matrix product
    /// (default true; the residuals that only rank initial guesses stay rounded). Rounded,
    /// those products leave an error ≈ ε·|K|·|ΔQ|/h in the stage rows, which the Newton matrix
    /// (condition up to 1e8 with nodal bases) turns into a solution error along directions the
    /// residual barely sees, and which carries a one-signed bias when K's entries are not
    /// short binary fractions (the Chebyshev–Lagrange basis; the Legendre basis's entries are
    /// snapped to exact values). Measured, rounded → exact: the symmetric two-body problem
    /// (Chebyshev n = 24, h = 2, 100 steps) keeps its barycentre to 2.8e-16 instead of 4.5e-13
    /// and its relative motion within 5.8e-12 of the Kepler run instead of 2.6e-10; Kepler
    /// e = 0.6 over T = 20,000 with Chebyshev n = 24, h = 0.5 reaches 1.8e-8 instead of
    /// 1.9e-7; Newton needs 2.61 instead of 2.96 solves per step (n = 32, h = 2). Costs
    /// ≈ n² D TwoProds per residual (≈ 7 % of the step at n = 10, nothing measurable at
    /// n = 24).
    #[serde(default = "default_true")]
    pub exact_kinetic: bool,
}

fn default_true() -> bool {
    true
}

impl Default for NewtonOptions {
    fn default() -> Self {
        NewtonOptions {
            max_iterations: 40,
            tolerance: 1e-16,
            floor_tolerance: 1e-10,
            initial_guess: InitialGuess::BestResidual,
            predictor_substeps: None,
            reuse_jacobian: true,
            reuse_contraction: 0.1,
            reuse_across_steps: false,
            exact_kinetic: true,
            compensated: true,
        }
    }
}

/// What one step cost.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct StepStats {
    /// Newton iterations (Jacobian factorisations) taken.
    pub iterations: usize,
    /// Max-norm of the stage residual at the accepted coefficients.
    pub residual: f64,
    /// Evaluations of the Lagrangian's first derivatives (or force), counted per quadrature
    /// point, plus the force evaluations of the RK4 predictor guess: the "right-hand-side
    /// evaluations" of the step.
    pub gradient_evaluations: usize,
    /// Evaluations of second derivatives, per quadrature point.
    pub hessian_evaluations: usize,
    /// LU factorisations of the Newton matrix.
    pub factorizations: usize,
    /// The initial guess that was used.
    pub guess: InitialGuess,
}

/// Which rows and unknowns a solve uses: the initial-value step (rows 0…n−2, unknowns
/// 1…n−1) or the two-point problem of the discrete Lagrangian (rows and unknowns 1…n−2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Mode {
    InitialValue,
    BoundaryValue,
}

impl Mode {
    fn first_row(self) -> usize {
        0
    }
    fn first_unknown(self) -> usize {
        1
    }
    fn count(self, n: usize) -> usize {
        match self {
            Mode::InitialValue => n - 1,
            Mode::BoundaryValue => n - 2,
        }
    }
    fn row_offset(self) -> usize {
        match self {
            Mode::InitialValue => self.first_row(),
            Mode::BoundaryValue => 1,
        }
    }
}

/// Knuth's TwoSum: s = fl(a + b) and the exact rounding error e, a + b = s + e.
#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// hi + lo += a·b with the product exact (FMA) and the sum compensated (TwoSum).
#[inline]
fn dd_acc(hi: &mut f64, lo: &mut f64, a: f64, b: f64) {
    let prod = a * b;
    let low = a.mul_add(b, -prod);
    let (s, e) = two_sum(*hi, prod);
    *hi = s;
    *lo += e + low;
}

/// (a_hi + a_lo) + (b_hi + b_lo) as a normalised hi + lo pair (double-double addition):
/// unlike Kahan's `two_sum(a, b + a_lo)`, the low parts are not rounded away when the
/// increment is as large as the sum (steps of a large-h spectral method).
#[inline]
fn dd_add(a_hi: f64, a_lo: f64, b_hi: f64, b_lo: f64) -> (f64, f64) {
    let (s, e) = two_sum(a_hi, b_hi);
    let (t, f) = two_sum(a_lo, b_lo);
    let (s, e) = fast_two_sum(s, e + t);
    fast_two_sum(s, e + f)
}

/// Dekker's Fast2Sum for |a| ≥ |b|.
#[inline]
fn fast_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    (s, b - (s - a))
}

/// Steps between full competitions of the initial guesses.
const GUESS_RECHECK: usize = 16;
/// A remembered guess is taken without a competition if its residual is at most this multiple
/// of the residual of the last competition's winner.
const GUESS_SLACK: f64 = 4.0;

fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// Curve values q(c_j) and velocities q̇(c_j) at every quadrature node from the increments
    /// ΔQ in `coeffs` (or `cand`): q = q_k + Φ ΔQ and q̇ = Φ' ΔQ / h as two matrix products
    /// (Σ u_i φ_i ≡ 1 and Σ u_i φ_i' ≡ 0, so the constant part is added, not multiplied).
    fn evaluate_curve(&self, ws: &mut Workspace, coeffs_from_cand: bool) {
        let t = self.tables();
        let (n, m, d, h) = (t.n, t.m, ws.d, self.step_size());
        let coeffs = if coeffs_from_cand {
            &ws.cand
        } else {
            &ws.coeffs
        };
        ws.curve_from_cand = coeffs_from_cand;
        let (rn, rd) = (Strided::rows(0, n), Strided::rows(0, d));
        // q_k + (Φ ΔQ + δq_k): the small parts first, then the large one.
        for (j, row) in ws.qj.chunks_exact_mut(d).enumerate() {
            row.copy_from_slice(&ws.base_err);
            if !coeffs_from_cand {
                let phi_last = t.phi[j * n + n - 1];
                for (x, lo) in row.iter_mut().zip(&ws.last_lo) {
                    *x += phi_last * lo;
                }
            }
        }
        gemm(m, n, d, 1.0, &t.phi, rn, coeffs, rd, 1.0, &mut ws.qj, rd);
        for row in ws.qj.chunks_exact_mut(d) {
            for (x, b) in row.iter_mut().zip(&ws.base) {
                *x += b;
            }
        }
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
                &mut ws.vj,
                rd,
            );
        }
    }

    /// ∂S/∂Q_a for every a into `ws.grad`, from the coefficients in `ws.coeffs` (or
    /// `ws.cand`). Returns the number of first-derivative evaluations.
    fn action_gradient<L: Lagrangian>(&self, lag: &L, ws: &mut Workspace, cand: bool) -> usize {
        self.evaluate_curve(ws, cand);
        let t = self.tables();
        let (n, m, d, h) = (t.n, t.m, ws.d, self.step_size());
        ws.grad.iter_mut().for_each(|x| *x = 0.0);
        if let Some(sep) = &ws.separable {
            // Kinetic part (1/h) Σ_b K_ab M ΔQ_b with ΔQ_b = Q_b − u_b q_k: constants applied to
            // the increments, never to Q (DESIGN.md §4).
            let coeffs = if cand { &ws.cand } else { &ws.coeffs };
            for b in 0..n {
                for r in 0..d {
                    let mut s = 0.0;
                    for c in 0..d {
                        s += sep.mass[r * d + c] * coeffs[b * d + c];
                    }
                    ws.mq[b * d + r] = s;
                }
            }
            let rd = Strided::rows(0, d);
            if self.options().exact_kinetic && !cand {
                for a in 0..n {
                    let row = &t.kinetic[a * n..(a + 1) * n];
                    for r in 0..d {
                        let (mut hi, mut lo) = (0.0, 0.0);
                        for (b, &k) in row.iter().enumerate() {
                            dd_acc(&mut hi, &mut lo, k, ws.mq[b * d + r]);
                        }
                        ws.grad[a * d + r] = (hi + lo) / h;
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
                    &ws.mq,
                    rd,
                    0.0,
                    &mut ws.grad,
                    rd,
                );
            }
            if !cand {
                // The low part of ΔQ_{n−1} in every kinetic row (the Legendre-transform row and
                // the curve see it too), so that all equations see the same unknown.
                for r in 0..d {
                    let mut s = 0.0;
                    for c in 0..d {
                        s += sep.mass[r * d + c] * ws.last_lo[c];
                    }
                    ws.small_rhs[r] = s / h;
                }
                for a in 0..n {
                    let k = t.kinetic[a * n + n - 1];
                    for r in 0..d {
                        ws.grad[a * d + r] += k * ws.small_rhs[r];
                    }
                }
            }
            for j in 0..m {
                lag.force(&ws.qj[j * d..(j + 1) * d], &mut ws.lq[j * d..(j + 1) * d]);
                let w = t.weights[j] * h;
                for r in 0..d {
                    ws.scaled[j * d + r] = w * ws.lq[j * d + r];
                }
            }
            // grad += Φᵀ (h b ∘ L_q): the transpose is a strided view of the table.
            let phi_t = Strided {
                offset: 0,
                row_stride: 1,
                col_stride: n,
            };
            gemm(
                n,
                m,
                d,
                1.0,
                &t.phi,
                phi_t,
                &ws.scaled,
                rd,
                1.0,
                &mut ws.grad,
                rd,
            );
        } else {
            for j in 0..m {
                let (lq, lv) = (
                    &mut ws.lq[j * d..(j + 1) * d],
                    &mut ws.lv[j * d..(j + 1) * d],
                );
                lag.gradient(
                    &ws.qj[j * d..(j + 1) * d],
                    &ws.vj[j * d..(j + 1) * d],
                    lq,
                    lv,
                );
                let w = t.weights[j];
                for a in 0..n {
                    let (fq, fv) = (w * h * t.phi[j * n + a], w * t.dphi[j * n + a]);
                    for r in 0..d {
                        ws.grad[a * d + r] += fq * lq[r] + fv * lv[r];
                    }
                }
            }
        }
        m
    }

    /// The Legendre-transform rows of the initial-value residual into `ws.rhs[..D]`, and the
    /// step's total impulse h Σ_j b_j L_q(c_j) into `ws.impulse` + `ws.impulse_lo`.
    ///
    /// The rows are p_k + impulse − ∂S/∂ΔQ_{n−1} = 0, the form that makes
    /// p_{k+1} = p_k + impulse exactly D₂L_d of the discrete Lagrangian the tables define (q_k
    /// enters every node with coefficient exactly 1 and the velocities not at all); in exact
    /// arithmetic it is p_k + Σ_{a<n−1} u_a ∂S/∂Q_a = 0, the paper's eq. (3.2) plus
    /// u-weighted stage equations.
    ///
    /// Round-off (DESIGN.md §4): the terms p_k, the impulse, and both parts of ∂S/∂ΔQ_{n−1}
    /// are O(|p|) each (near periapsis of an eccentric orbit the impulse of a large step is as
    /// large as p) and cancel to O(ε). Rounding them in working precision leaves an error
    /// ε|p| in the row, i.e. in q_{k+1}, every step — and, measured, not a random one: it
    /// made the energy drift linearly (Kepler e = 0.6, Legendre n = 24, h = 0.5:
    /// ΔE = −4e-14 at T = 2000 and −7e-14 at T = 4000, every realisation the same sign; the
    /// harmonic oscillator likewise). So for separable Lagrangians the whole row is summed in
    /// double-double: products exact by FMA, sums by TwoSum, including the low parts of the
    /// state (p_err) and of ΔQ_{n−1}. The drift fell below the random walk (`tests/roundoff.rs`).
    fn legendre_transform_rows(&self, ws: &mut Workspace, p_k: &[f64]) {
        let (t, h) = (self.tables(), self.step_size());
        let (d, n) = (ws.d, ws.n);
        let last = (n - 1) * d;
        for r in 0..d {
            let (mut hi, mut lo) = (0.0, 0.0);
            for j in 0..t.m {
                dd_acc(&mut hi, &mut lo, h * t.weights[j], ws.lq[j * d + r]);
            }
            (ws.impulse[r], ws.impulse_lo[r]) = two_sum(hi, lo);
            ws.rhs[r] = (p_k[r] - ws.grad[last + r]) + (ws.impulse[r] + ws.p_err[r]);
        }
        let Some(sep) = &ws.separable else {
            return;
        };
        let x = if ws.curve_from_cand {
            &ws.cand
        } else {
            &ws.coeffs
        };
        let nd = n * d;
        for r in 0..d {
            // p_k + impulse …
            let (mut s, mut e) = two_sum(p_k[r], ws.impulse[r]);
            e += ws.p_err[r] + ws.impulse_lo[r];
            // … − Σ_j φ_{n−1}(c_j) h b_j L_q(c_j) …
            for j in 0..t.m {
                let (w, f) = (h * t.weights[j], ws.lq[j * d + r]);
                let g = w * f;
                let phi = t.phi[j * n + n - 1];
                dd_acc(&mut s, &mut e, -phi, g);
                e -= phi * w.mul_add(f, -g);
            }
            // … − (1/h) Σ_b K_{n−1,b} M ΔQ_b.
            let kinetic = &sep.kinetic_last[r * nd..(r + 1) * nd];
            for (c, v) in kinetic.iter().zip(x) {
                dd_acc(&mut s, &mut e, -c, *v);
            }
            if !ws.curve_from_cand {
                for (c, lo) in kinetic[last..].iter().zip(&ws.last_lo) {
                    e -= c * lo;
                }
            }
            ws.rhs[r] = s + e;
        }
    }

    /// Residual of the stage equations for `mode` into `ws.rhs` (negated, ready for the
    /// Newton solve); returns its max-norm.
    fn residual(&self, ws: &mut Workspace, mode: Mode, p_k: &[f64]) -> f64 {
        let (d, n) = (ws.d, ws.n);
        let rows = mode.count(n) * d;
        let off = mode.row_offset() * d;
        let mut norm = 0.0f64;
        if mode == Mode::InitialValue {
            self.legendre_transform_rows(ws, p_k);
        }
        for i in 0..rows {
            let r = if mode == Mode::InitialValue && i < d {
                ws.rhs[i]
            } else {
                ws.grad[off + i]
            };
            ws.rhs[i] = -r;
            norm = norm.max(r.abs());
            if !r.is_finite() {
                norm = f64::INFINITY;
            }
        }
        norm
    }

    /// Assemble the exact Jacobian ∂²S/∂Q_a∂Q_b for `mode` into `ws.jac` (uses the curve values
    /// left in the workspace by the last gradient evaluation). Returns Hessian evaluations.
    pub(super) fn jacobian<L: Lagrangian>(&self, lag: &L, ws: &mut Workspace, mode: Mode) -> usize {
        let evals = self.jacobian_rows(lag, ws, mode);
        if mode == Mode::InitialValue {
            // Row block 0 of the Legendre-transform equation as residual() forms it:
            // Σ_{a<n−1} u_a (row block a).
            let t = self.tables();
            let (n, d) = (t.n, ws.d);
            let size = (n - 1) * d;
            let (first, rest) = ws.jac[..size * size].split_at_mut(d * size);
            for a in 1..n - 1 {
                let u = t.unit[a];
                if u != 0.0 {
                    let block = &rest[(a - 1) * d * size..a * d * size];
                    for (x, y) in first.iter_mut().zip(block) {
                        *x += u * y;
                    }
                }
            }
        }
        evals
    }

    /// The rows ∂²S/∂Q_a∂Q_b of [`jacobian`](Self::jacobian), before row block 0 is combined.
    pub(super) fn jacobian_rows<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        mode: Mode,
    ) -> usize {
        let t: &Tables = self.tables();
        let (n, m, d, h) = (t.n, t.m, ws.d, self.step_size());
        let cnt = mode.count(n);
        let size = cnt * d;
        let (r0, u0) = (mode.row_offset(), mode.first_unknown());
        let jac = &mut ws.jac[..size * size];
        match (&ws.separable, mode) {
            (Some(sep), Mode::InitialValue) => jac.copy_from_slice(&sep.kinetic_jacobian),
            (Some(sep), Mode::BoundaryValue) => {
                for a in 0..cnt {
                    for b in 0..cnt {
                        let k = t.kinetic[(a + r0) * n + b + u0] / h;
                        for r in 0..d {
                            for s in 0..d {
                                jac[(a * d + r) * size + b * d + s] = k * sep.mass[r * d + s];
                            }
                        }
                    }
                }
            }
            (None, _) => jac.iter_mut().for_each(|x| *x = 0.0),
        }
        if ws.separable.is_some() {
            // Potential part Σ_j h b_j φ_a(c_j) φ_b(c_j) L_qq(c_j) as d² weighted Gram
            // products Φᵀ diag(g_rs) Φ (one GEMM each) instead of scalar loops (DESIGN.md §4).
            let dd = d * d;
            for j in 0..m {
                let q = &ws.qj[j * d..(j + 1) * d];
                lag.force_jacobian(q, &mut ws.hall[j * dd..(j + 1) * dd]);
            }
            if d <= 4 && dd <= m {
                // Few coordinates: all d² blocks in one pass over the nodes (the same products
                // and the same order of summation as the per-block products below).
                gram_blocks_fused(t, &ws.hall, &mut ws.gram, jac, (cnt, d, h, r0, u0));
                return m;
            }
            for r in 0..d {
                for s in 0..d {
                    for a in 0..cnt {
                        for j in 0..m {
                            ws.gram[a * m + j] = t.phi[j * n + a + r0]
                                * t.weights[j]
                                * h
                                * ws.hall[j * dd + r * d + s];
                        }
                    }
                    gram_accumulate(
                        &ws.gram,
                        &t.phi,
                        &mut ws.block,
                        jac,
                        (cnt, m, n, u0),
                        (r, s),
                    );
                }
            }
            return m;
        }
        for j in 0..m {
            let q = &ws.qj[j * d..(j + 1) * d];
            let w = t.weights[j];
            let (phi, dphi) = (&t.phi[j * n..(j + 1) * n], &t.dphi[j * n..(j + 1) * n]);
            {
                let v = &ws.vj[j * d..(j + 1) * d];
                lag.hessian(q, v, &mut ws.hqq, &mut ws.hqv, &mut ws.hvv);
                for a in 0..cnt {
                    let (pa, da) = (phi[a + r0], dphi[a + r0]);
                    for b in 0..cnt {
                        let (pb, db) = (phi[b + u0], dphi[b + u0]);
                        let cqq = w * h * pa * pb;
                        let cqv = w * pa * db;
                        let cvq = w * da * pb;
                        let cvv = w * da * db / h;
                        for r in 0..d {
                            let row = (a * d + r) * size + b * d;
                            for s in 0..d {
                                jac[row + s] += cqq * ws.hqq[r * d + s]
                                    + cqv * ws.hqv[r * d + s]
                                    + cvq * ws.hqv[s * d + r]
                                    + cvv * ws.hvv[r * d + s];
                            }
                        }
                    }
                }
            }
        }
        m
    }

    /// Velocity v with ∂L/∂v(q, v) = p into `ws.vel` (inverse Legendre transform), starting
    /// from the value already in `ws.vel`.
    fn inverse_legendre<L: Lagrangian>(&self, lag: &L, ws: &mut Workspace, q: &[f64], p: &[f64]) {
        let d = ws.d;
        if let Some(sep) = &ws.separable {
            ws.vel.copy_from_slice(p);
            sep.mass_lu
                .solve_in_place(&mut ws.vel, &mut ws.small_scratch);
            return;
        }
        // Newton on L_v(q, v) = p with Jacobian L_vv.
        for _ in 0..20 {
            let (lq, lv) = (&mut ws.lq[..d], &mut ws.lv[..d]);
            lag.gradient(q, &ws.vel, lq, lv);
            let mut err = 0.0f64;
            for r in 0..d {
                ws.small_rhs[r] = p[r] - lv[r];
                err = err.max(ws.small_rhs[r].abs());
            }
            if err <= 1e-15 * (1.0 + max_abs(p)) {
                return;
            }
            lag.hessian(q, &ws.vel, &mut ws.hqq, &mut ws.hqv, &mut ws.hvv);
            if ws.small.refactor(&ws.hvv).is_err() {
                return;
            }
            ws.small
                .solve_in_place(&mut ws.small_rhs, &mut ws.small_scratch);
            for r in 0..d {
                ws.vel[r] += ws.small_rhs[r];
            }
            if !ws.vel.iter().all(|x| x.is_finite()) {
                ws.vel.copy_from_slice(p);
                return;
            }
        }
    }

    /// The RK4 predictor into `ws.cand`; false when unavailable (non-separable Lagrangian) or
    /// not finite.
    fn predict<L: Lagrangian>(&self, lag: &L, ws: &mut Workspace, q: &[f64], p: &[f64]) -> bool {
        let Some(sep) = &ws.separable else {
            return false;
        };
        let t = self.tables();
        let (d, h) = (ws.d, self.step_size());
        let sub = ws.rk_substeps;
        let dt = h / sub as f64;
        let w = 2 * d;
        // State y = (q, v) at every substep end, v = M⁻¹p at the start.
        ws.rk_states[..d].copy_from_slice(q);
        ws.vel.copy_from_slice(p);
        sep.mass_lu
            .solve_in_place(&mut ws.vel, &mut ws.small_scratch);
        ws.rk_states[d..w].copy_from_slice(&ws.vel);
        for s in 0..sub {
            let (done, rest) = ws.rk_states.split_at_mut((s + 1) * w);
            let y0 = &done[s * w..];
            let y1 = &mut rest[..w];
            // k_i = f(y0 + c_i dt k_{i−1}); f(q, v) = (v, M⁻¹ L_q(q)).
            for stage in 0..4 {
                let c = match stage {
                    0 => 0.0,
                    3 => dt,
                    _ => 0.5 * dt,
                };
                for r in 0..w {
                    let prev = if stage == 0 {
                        0.0
                    } else {
                        ws.rk_k[(stage - 1) * w + r]
                    };
                    ws.rk_tmp[r] = y0[r] + c * prev;
                }
                let k = &mut ws.rk_k[stage * w..(stage + 1) * w];
                k[..d].copy_from_slice(&ws.rk_tmp[d..w]);
                lag.force(&ws.rk_tmp[..d], &mut k[d..w]);
                ws.guess_force_evaluations += 1;
                sep.mass_lu
                    .solve_in_place(&mut k[d..w], &mut ws.small_scratch);
            }
            for r in 0..w {
                let k = &ws.rk_k;
                y1[r] =
                    y0[r] + dt / 6.0 * (k[r] + 2.0 * k[w + r] + 2.0 * k[2 * w + r] + k[3 * w + r]);
            }
        }
        // Cubic Hermite interpolation at the interpolation nodes, then fit coefficients.
        for (k, &x) in t.fit.nodes().iter().enumerate() {
            let pos = (x * sub as f64).clamp(0.0, sub as f64);
            let i = (pos.floor() as usize).min(sub - 1);
            let s = pos - i as f64;
            let (s2, s3) = (s * s, s * s * s);
            let (h00, h10, h01, h11) = (
                2.0 * s3 - 3.0 * s2 + 1.0,
                s3 - 2.0 * s2 + s,
                -2.0 * s3 + 3.0 * s2,
                s3 - s2,
            );
            let (a, b) = (
                &ws.rk_states[i * w..(i + 1) * w],
                &ws.rk_states[(i + 1) * w..(i + 2) * w],
            );
            // Increments from q_k (h00 + h01 = 1).
            for r in 0..d {
                ws.cand[k * d + r] = h00 * (a[r] - q[r])
                    + h10 * dt * a[d + r]
                    + h01 * (b[r] - q[r])
                    + h11 * dt * b[d + r];
            }
        }
        t.fit
            .values_to_coefficients_with(&mut ws.cand, d, &mut ws.fit_col, &mut ws.fit_scratch);
        true
    }

    /// Fill `ws.cand` with the guess of kind `g`; false if that guess is unavailable.
    fn make_guess<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        g: InitialGuess,
        q: &[f64],
        p: &[f64],
    ) -> bool {
        let t = self.tables();
        let (n, d, h) = (t.n, ws.d, self.step_size());
        match g {
            InitialGuess::Constant | InitialGuess::BestResidual | InitialGuess::Warm => {
                ws.cand.iter_mut().for_each(|x| *x = 0.0);
            }
            InitialGuess::Linear => {
                if ws.has_prev {
                    // End velocity of the previous Galerkin curve.
                    for r in 0..d {
                        ws.vel[r] = (0..n)
                            .map(|i| t.dphi_end[i] * ws.prev[i * d + r])
                            .sum::<f64>()
                            / h;
                    }
                } else {
                    ws.vel.copy_from_slice(p);
                    self.inverse_legendre(lag, ws, q, p);
                }
                for i in 0..n {
                    for r in 0..d {
                        ws.cand[i * d + r] = t.ramp[i] * h * ws.vel[r];
                    }
                }
            }
            InitialGuess::Predictor => {
                if !self.predict(lag, ws, q, p) {
                    return false;
                }
            }
            InitialGuess::Extrapolate => {
                let Some(e) = &t.extrapolate else {
                    return false;
                };
                if !ws.has_prev {
                    return false;
                }
                // The previous curve is q_{k−1} + Σ ΔP_i φ_i and q_k = q_{k−1} + ΔP_{n−1}; E
                // maps constants to constants, so the continued curve's increments from q_k
                // are E ΔP − u ΔP_{n−1}.
                let last = (n - 1) * d;
                for i in 0..n {
                    for r in 0..d {
                        let c: f64 = (0..n).map(|k| e[i * n + k] * ws.prev[k * d + r]).sum();
                        ws.cand[i * d + r] = c - t.unit[i] * ws.prev[last + r];
                    }
                }
            }
        }
        // The start of the curve is q_k exactly: ΔQ_0 = 0.
        ws.cand[..d].iter_mut().for_each(|x| *x = 0.0);
        ws.cand.iter().all(|x| x.is_finite())
    }

    /// Choose the initial guess into `ws.coeffs`; returns (choice, gradient evaluations).
    fn initial_guess<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        q: &[f64],
        p: &[f64],
    ) -> (InitialGuess, usize) {
        if ws.has_warm {
            ws.has_warm = false;
            // Absolute coefficients to increments from q_k (ΔQ_0 = 0).
            let (t, d) = (self.tables(), ws.d);
            for i in 0..t.n {
                for r in 0..d {
                    ws.coeffs[i * d + r] = ws.warm[i * d + r] - t.unit[i] * q[r];
                }
            }
            ws.coeffs[..d].iter_mut().for_each(|x| *x = 0.0);
            return (InitialGuess::Warm, 0);
        }
        let choice = self.options().initial_guess;
        if !matches!(choice, InitialGuess::BestResidual | InitialGuess::Warm) {
            let g = if self.make_guess(lag, ws, choice, q, p) {
                choice
            } else {
                self.make_guess(lag, ws, InitialGuess::Linear, q, p);
                InitialGuess::Linear
            };
            ws.coeffs.copy_from_slice(&ws.cand);
            return (g, 0);
        }
        let mut evals = 0;
        // Between full competitions (every GUESS_RECHECK steps) the previous winner is taken
        // at once if its residual is within GUESS_SLACK of the last competition's: the ranking
        // changes slowly along a trajectory, and the competition costs three more residuals and
        // an RK4 integration (more than the Newton iteration itself at small h). Its residual
        // is Newton's first (`ws.residual_ready`), so the check costs nothing when it passes.
        if let Some(winner) = ws.guess_winner
            && ws.guess_age < GUESS_RECHECK
            && self.make_guess(lag, ws, winner, q, p)
        {
            evals += self.action_gradient(lag, ws, true);
            let r = self.residual(ws, Mode::InitialValue, p);
            if r <= GUESS_SLACK * ws.guess_reference {
                ws.guess_age += 1;
                ws.coeffs.copy_from_slice(&ws.cand);
                ws.residual_ready = Some(r);
                return (winner, evals);
            }
        }
        let mut best = (InitialGuess::Constant, f64::INFINITY);
        for g in [
            InitialGuess::Predictor,
            InitialGuess::Extrapolate,
            InitialGuess::Linear,
            InitialGuess::Constant,
        ] {
            if !self.make_guess(lag, ws, g, q, p) {
                continue;
            }
            evals += self.action_gradient(lag, ws, true);
            let r = self.residual(ws, Mode::InitialValue, p);
            if r < best.1 {
                best = (g, r);
                ws.best.copy_from_slice(&ws.cand);
            }
        }
        if best.1.is_finite() {
            ws.coeffs.copy_from_slice(&ws.best);
            ws.guess_winner = Some(best.0);
            ws.guess_reference = best.1;
            ws.guess_age = 0;
        } else {
            self.make_guess(lag, ws, InitialGuess::Constant, q, p);
            ws.coeffs.copy_from_slice(&ws.cand);
        }
        (best.0, evals)
    }

    /// Newton's method on the stage equations of `mode`, from the coefficients in
    /// `ws.coeffs`; on success the coefficients solve them and `ws.grad` holds ∂S/∂Q at the
    /// solution.
    fn newton<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        mode: Mode,
        p_k: &[f64],
        stats: &mut StepStats,
    ) -> std::result::Result<(), StepFailure> {
        let opts = self.options();
        let (n, d) = (ws.n, ws.d);
        let size = mode.count(n) * d;
        let u0 = mode.first_unknown() * d;
        let mut previous_increment = f64::INFINITY;
        ws.last_lo.iter_mut().for_each(|x| *x = 0.0);
        let fail = |residual: f64, iterations, reason: &str| StepFailure {
            residual,
            iterations,
            reason: reason.to_string(),
        };
        if size == 0 {
            stats.gradient_evaluations += self.action_gradient(lag, ws, false);
            stats.residual = self.residual(ws, mode, p_k);
            return Ok(());
        }
        // Simplified Newton: keep the factorised Jacobian (from an earlier iteration or the
        // previous step) while the iteration contracts fast; refactor at the current iterate
        // (full Newton) as soon as it does not.
        let reuse = opts.reuse_jacobian && mode == Mode::InitialValue;
        let mut have_lu = reuse && opts.reuse_across_steps && ws.lu_valid && ws.lu.dim() == size;
        let mut fresh = false;
        let mut it = 0;
        loop {
            // The initial guess's residual may already be in the workspace (same point).
            let res = match ws.residual_ready.take().filter(|_| it == 0) {
                Some(r) => r,
                None => {
                    stats.gradient_evaluations += self.action_gradient(lag, ws, false);
                    self.residual(ws, mode, p_k)
                }
            };
            stats.residual = res;
            if !res.is_finite() {
                ws.lu_valid = false;
                return Err(fail(
                    res,
                    it,
                    "non-finite residual (the iteration diverged)",
                ));
            }
            if it >= opts.max_iterations {
                ws.lu_valid = false;
                return Err(fail(res, it, "iteration limit reached"));
            }
            if !have_lu {
                stats.hessian_evaluations += self.jacobian(lag, ws, mode);
                if ws.lu.dim() != size {
                    ws.lu = crate::linalg::Lu::with_capacity(size);
                }
                stats.factorizations += 1;
                if ws.lu.refactor(&ws.jac[..size * size]).is_err() {
                    ws.lu_valid = false;
                    return Err(fail(res, it, "singular Jacobian"));
                }
                ws.lu_valid = mode == Mode::InitialValue;
                have_lu = true;
                fresh = true;
            }
            ws.lu
                .solve_in_place(&mut ws.rhs[..size], &mut ws.scratch[..size]);
            it += 1;
            stats.iterations += 1;
            let delta = max_abs(&ws.rhs[..size]);
            // ΔQ_{n−1} (the increment of q) is kept as hi + lo: the corrections of the last
            // iterations lie below its ulp, and the compensated Legendre-transform row resolves
            // them.
            let last = (n - 1) * d;
            for i in 0..size {
                let k = u0 + i;
                if k >= last && ws.separable.is_some() {
                    let (s, e) = two_sum(ws.coeffs[k], ws.rhs[i]);
                    ws.coeffs[k] = s;
                    ws.last_lo[k - last] += e;
                } else {
                    ws.coeffs[k] += ws.rhs[i];
                }
            }
            // The scale of the unknowns, the increments ΔQ (which the stage equations determine
            // to a relative accuracy far better than ε|q_k| when h is small).
            let scale = max_abs(&ws.coeffs).max(f64::MIN_POSITIVE);
            if !delta.is_finite() || !scale.is_finite() {
                ws.lu_valid = false;
                return Err(fail(f64::INFINITY, it, "non-finite Newton update"));
            }
            // θ estimates the contraction; undefined on the first iteration.
            let theta = if previous_increment.is_finite() {
                delta / previous_increment
            } else {
                f64::INFINITY
            };
            let converged = delta == 0.0
                || delta <= opts.tolerance * scale
                || (theta < 1.0 && theta / (1.0 - theta) * delta <= opts.tolerance * scale)
                || (theta.is_finite() && theta >= 0.5 && delta <= opts.floor_tolerance * scale);
            if converged {
                stats.gradient_evaluations += self.action_gradient(lag, ws, false);
                stats.residual = self.residual(ws, mode, p_k);
                return Ok(());
            }
            // A reused (stale) Jacobian that does not contract quickly is replaced.
            let slow = theta.is_finite() && theta > opts.reuse_contraction;
            let growing = delta > previous_increment;
            if !reuse || slow || growing || (!fresh && it >= 2 && !theta.is_finite()) {
                have_lu = false;
            }
            previous_increment = delta;
        }
    }

    /// One step of the discrete flow: (q_k, p_k) ↦ (q_{k+1}, p_{k+1}). The step's Galerkin
    /// coefficients are left in [`Workspace::coefficients`] and remembered for the next
    /// step's extrapolated guess.
    ///
    /// The Newton unknowns are the increments ΔQ_i = Q_i − u_i q_k (u: the coefficients of
    /// the constant curve), so the curve is q_k + Σ ΔQ_i φ_i and q_{k+1} = q_k + ΔQ_{n−1}
    /// with ΔQ_{n−1} computed to full relative accuracy. p_{k+1} is computed as
    /// p_k + h Σ_j b_j L_q(c_j), which equals ∂S/∂Q_{n−1} once the stage equations hold (the
    /// basis reproduces constants, so Σ_a u_a ∂S/∂Q_a is the total impulse) but avoids the
    /// cancellation of large kinetic terms when h is small. See
    /// [`step_compensated`](Self::step_compensated) for the variant that also carries the
    /// rounding errors of these two sums across steps.
    pub fn step<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        q: &[f64],
        p: &[f64],
        q_next: &mut [f64],
        p_next: &mut [f64],
    ) -> std::result::Result<StepStats, StepFailure> {
        let stats = self.solve_step(lag, ws, q, p)?;
        let d = ws.d;
        let last = (ws.n - 1) * d;
        for r in 0..d {
            // Correctly rounded sums of the state and the double-double increments.
            q_next[r] = dd_add(q[r], 0.0, ws.coeffs[last + r], ws.last_lo[r]).0;
            p_next[r] = dd_add(p[r], 0.0, ws.impulse[r], ws.impulse_lo[r]).0;
        }
        self.finish_step(ws, q_next);
        Ok(stats)
    }

    /// [`step`](Self::step) with compensated summation of the state, in place: (q, p) is
    /// advanced by one step and `q_err`, `p_err` carry the rounding errors of the sums
    /// q_{k+1} = q_k + ΔQ_{n−1} and p_{k+1} = p_k + impulse (Kahan–Babuška with Knuth's
    /// TwoSum), so that q + q_err and p + p_err represent the state to about twice the
    /// working precision over any number of steps. Start with `q_err = p_err = 0`. The step
    /// itself is solved at the rounded (q, p); only the increments are compensated, as in
    /// IAS15. On failure the state is unchanged.
    pub fn step_compensated<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        q: &mut [f64],
        q_err: &mut [f64],
        p: &mut [f64],
        p_err: &mut [f64],
    ) -> std::result::Result<StepStats, StepFailure> {
        ws.base_err.copy_from_slice(q_err);
        ws.p_err.copy_from_slice(p_err);
        let solved = self.solve_step(lag, ws, q, p);
        ws.base_err.iter_mut().for_each(|x| *x = 0.0);
        ws.p_err.iter_mut().for_each(|x| *x = 0.0);
        let stats = solved?;
        let d = ws.d;
        let last = (ws.n - 1) * d;
        for r in 0..d {
            (q[r], q_err[r]) = dd_add(q[r], q_err[r], ws.coeffs[last + r], ws.last_lo[r]);
            (p[r], p_err[r]) = dd_add(p[r], p_err[r], ws.impulse[r], ws.impulse_lo[r]);
        }
        self.finish_step(ws, q);
        Ok(stats)
    }

    /// Absolute coefficients for [`Workspace::coefficients`] (Q_i = u_i q_k + ΔQ_i, with the
    /// ends exactly q_k and the returned q_{k+1}), and the increments kept for the next guess.
    fn finish_step(&self, ws: &mut Workspace, q_next: &[f64]) {
        let t = self.tables();
        let (n, d) = (t.n, ws.d);
        for i in 1..n - 1 {
            for r in 0..d {
                ws.abs[i * d + r] = t.unit[i] * ws.base[r] + ws.coeffs[i * d + r];
            }
        }
        ws.abs[..d].copy_from_slice(&ws.base);
        ws.abs[(n - 1) * d..].copy_from_slice(q_next);
        ws.prev.copy_from_slice(&ws.coeffs);
        ws.has_prev = true;
    }

    /// Solve the stage equations of one step from (q, p): on success `ws.coeffs` holds the
    /// increments ΔQ and `ws.impulse` the total impulse h Σ_j b_j L_q(c_j).
    fn solve_step<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        q: &[f64],
        p: &[f64],
    ) -> std::result::Result<StepStats, StepFailure> {
        ws.base.copy_from_slice(q);
        let mut stats = StepStats::default();
        let (guess, evals) = self.initial_guess(lag, ws, q, p);
        stats.guess = guess;
        stats.gradient_evaluations += evals;
        if let Err(first) = self.newton(lag, ws, Mode::InitialValue, p, &mut stats) {
            // Fallback: Newton from each of the other guesses before giving up (with very large
            // steps the residual-best guess can lie in the basin of no root, or of another).
            let mut solved = false;
            for g in [
                InitialGuess::Predictor,
                InitialGuess::Extrapolate,
                InitialGuess::Linear,
                InitialGuess::Constant,
            ] {
                if g == guess || !self.make_guess(lag, ws, g, q, p) {
                    continue;
                }
                ws.coeffs.copy_from_slice(&ws.cand);
                if self
                    .newton(lag, ws, Mode::InitialValue, p, &mut stats)
                    .is_ok()
                {
                    stats.guess = g;
                    solved = true;
                    break;
                }
            }
            if !solved {
                ws.has_prev = false;
                ws.guess_force_evaluations = 0;
                return Err(StepFailure {
                    iterations: stats.iterations,
                    ..first
                });
            }
        }
        // The RK4 predictor's force evaluations are right-hand-side evaluations too.
        stats.gradient_evaluations += std::mem::take(&mut ws.guess_force_evaluations);
        // The total impulse h Σ_j b_j L_q(c_j) at the solution is left in ws.impulse by the
        // last residual evaluation.
        Ok(stats)
    }

    /// The discrete Lagrangian L_d(q0, q1) = ext h Σ_j b_j L(q(c_j), q̇(c_j)) over Galerkin
    /// curves with q(0) = q0 and q(h) = q1 (paper eq. (1.1)), together with the discrete
    /// Legendre transforms p0 = −D₁L_d(q0, q1) and p1 = D₂L_d(q0, q1).
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
        ws.base.copy_from_slice(q0);
        for i in 0..n {
            for r in 0..d {
                ws.coeffs[i * d + r] = t.ramp[i] * (q1[r] - q0[r]);
            }
        }
        ws.coeffs[..d].iter_mut().for_each(|x| *x = 0.0);
        for r in 0..d {
            ws.coeffs[(n - 1) * d + r] = q1[r] - q0[r];
        }
        let mut stats = StepStats::default();
        self.newton(lag, &mut ws, Mode::BoundaryValue, &[], &mut stats)
            .map_err(|f| GviError::NewtonFailure {
                step: 0,
                t: 0.0,
                residual: f.residual,
                iterations: f.iterations,
                reason: format!("discrete Lagrangian: {}", f.reason),
            })?;
        let h = self.step_size();
        let mut value = 0.0;
        for j in 0..t.m {
            value +=
                t.weights[j] * lag.value(&ws.qj[j * d..(j + 1) * d], &ws.vj[j * d..(j + 1) * d]);
        }
        Ok(DiscreteLagrangian {
            value: h * value,
            p0: ws.grad[..d].iter().map(|x| -x).collect(),
            p1: ws.grad[(n - 1) * d..n * d].to_vec(),
            coefficients: {
                self.finish_step(&mut ws, q1);
                ws.abs.clone()
            },
        })
    }
}

/// The potential part of the Newton matrix for d ≤ 4 coordinates, every block at once:
/// jac[(a d + r)·size + b d + s] += Σ_j (φ_{a+r0}(c_j) b_j h H_j[r, s]) φ_{b+u0}(c_j), summed
/// over j in order, exactly as [`gram_accumulate`] sums each block (bit-for-bit the same
/// matrix), without the d² separate products. `acc` needs d²·cnt entries. Exploiting the
/// symmetry of H_j (accumulating only the blocks r ≤ s, bit-for-bit the same when H_j is
/// exactly symmetric) was measured 2–5 % slower on Kepler (d = 2, n = 10): with 9 columns per
/// block the loop overhead outweighs the quarter of the products it saves.
fn gram_blocks_fused(
    t: &Tables,
    hall: &[f64],
    acc: &mut [f64],
    jac: &mut [f64],
    dims: (usize, usize, f64, usize, usize),
) {
    let (cnt, d, h, r0, u0) = dims;
    let (n, m, dd) = (t.n, t.m, d * d);
    let size = cnt * d;
    let acc = &mut acc[..dd * cnt];
    for a in 0..cnt {
        acc.iter_mut().for_each(|x| *x = 0.0);
        for j in 0..m {
            let base = t.phi[j * n + a + r0] * t.weights[j] * h;
            let row = &t.phi[j * n + u0..j * n + u0 + cnt];
            for (rs, &hrs) in hall[j * dd..(j + 1) * dd].iter().enumerate() {
                let g = base * hrs;
                if g == 0.0 {
                    continue;
                }
                for (x, &y) in acc[rs * cnt..(rs + 1) * cnt].iter_mut().zip(row) {
                    *x += g * y;
                }
            }
        }
        for r in 0..d {
            for s in 0..d {
                let block = &acc[(r * d + s) * cnt..(r * d + s + 1) * cnt];
                let row = (a * d + r) * size + s;
                for (b, &v) in block.iter().enumerate() {
                    jac[row + b * d] += v;
                }
            }
        }
    }
}

/// jac[(a d + r)·size + b d + s] += Σ_j gram[a m + j] · phi[j n + u0 + b] for a, b < cnt,
/// where size = cnt·d (jac is size×size): one block (r, s) of the Newton matrix as a single
/// matrix product.
fn gram_accumulate(
    gram: &[f64],
    phi: &[f64],
    block: &mut [f64],
    jac: &mut [f64],
    dims: (usize, usize, usize, usize),
    rs: (usize, usize),
) {
    let (cnt, m, n, u0) = dims;
    let (r, s, d) = (rs.0, rs.1, jac.len().isqrt() / cnt.max(1));
    let size = cnt * d;
    // Contiguous product first (vectorised inner loop), then scatter into the (r, s) block.
    gemm(
        cnt,
        m,
        cnt,
        1.0,
        gram,
        Strided::rows(0, m),
        phi,
        Strided::rows(u0, n),
        0.0,
        block,
        Strided::rows(0, cnt),
    );
    for a in 0..cnt {
        let row = (a * d + r) * size + s;
        for b in 0..cnt {
            jac[row + b * d] += block[a * cnt + b];
        }
    }
}

/// A step's Newton failure, as returned by [`GalerkinIntegrator::step`] (and turned into
/// [`GviError::NewtonFailure`] by `integrate`).
#[derive(Debug, Clone, PartialEq)]
pub struct StepFailure {
    /// Max-norm of the stage residual at the last iterate.
    pub residual: f64,
    /// Iterations taken.
    pub iterations: usize,
    /// Why it stopped.
    pub reason: String,
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
