//! Newton's method on the stage equations in the velocity form ([`super::velocity_form`]):
//! the residual F(c) = M c_b + h Σ_j b_j ψ_b(c_j) f_j − δ_b0 p_k, the Newton matrix
//! I ⊗ M + h² Σ_j b_j ψ_j ι_jᵀ ⊗ H_j (dense for small systems, frozen at H̄ and solved through
//! its Kronecker structure for large ones), and the conversion of the converged modes to the
//! basis coefficients the rest of the integrator reads.
//!
//! Because the Newton matrix is the mass matrix plus an O(h²) term, its factorisation is kept
//! across steps while the iteration contracts by 0.1 per iteration; a step that does not
//! converge returns a failure, and the step is then solved by the nodal solvers from their own
//! guesses (the caller's fallback), so the velocity form never loses a step the nodal
//! equations would have solved.

use super::dd::{dd_acc, dd_acc_columns, max_abs, two_sum};
use super::kronecker::KroneckerWork;
use super::velocity_form::VelocityTables;
use super::{GalerkinIntegrator, InitialGuess, StepStats, Workspace};
use crate::basis::Basis;
use crate::lagrangian::Lagrangian;
use crate::linalg::{Lu, Strided, gemm, gemm_transposed};
use crate::quadrature::Quadrature;

/// Contraction per iteration above which the frozen Hessian is refrozen at the current
/// iterate (once per step; a second stall hands the step to the nodal solvers).
const VELOCITY_STALL: f64 = 0.5;

/// Steps without a failure after which `Auto` forgets the earlier ones …
const AUTO_CALM: usize = 8;

/// … and the steps it then hands to the nodal solvers directly after a second failure within
/// them (large h·ω, where the frozen Hessian contracts slowly or stalls; measured on Kepler
/// at h = 2–4 the fallbacks made the velocity form 10–20 % slower than exact Newton).
const AUTO_HOLDOFF: usize = 32;

/// Relative residual of the extrapolated guess above which the RK4 predictor is tried too.
/// Measured on Kepler e = 0.6, T = 200 (Legendre n = 10, h = 0.25; n = 18, h = 0.5;
/// n = 12, h = 0.5): trusting every extrapolation is fastest but lets periapsis steps start
/// from residuals of O(10), where the frozen Hessian (taken at that guess) contracts slowly and
/// one step stopped at its noise floor with an angular-momentum error of 2e-15; 1e-6 tries
/// the predictor too often (+13 % time); 1e-3 costs +4 % and had no such step.
const EXTRAPOLATION_TRUST: f64 = 1e-3;

/// Relative increment below which an iteration that stops contracting is at the round-off
/// floor of its residual (converged, not stalled).
const VELOCITY_FLOOR: f64 = 1e-13;

/// The linear solve of a velocity-form iteration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Linear {
    /// The frozen-Hessian Kronecker solve (simplified Newton).
    Frozen,
    /// The exact Newton matrix, dense LU (kept while it contracts by 0.1).
    Dense,
}

/// The dense exact Newton matrix of the velocity form and its factorisation.
#[derive(Debug, Clone)]
struct DenseNewton {
    jac: Vec<f64>,
    /// D² partial rows of one row block (D²·k).
    acc: Vec<f64>,
    lu: Lu,
    scratch: Vec<f64>,
}

/// Unknowns (n − 1)·D up to which a step whose frozen Hessian stalls continues with the dense
/// exact Newton matrix of the velocity form before it is handed to the nodal solvers: 64, the
/// nodal `auto`'s own dense threshold, and up to [`VELOCITY_DENSE_SMALL_D`] for systems of at
/// most three coordinates (Kepler to n = 129), whose Hessians and Newton matrix stay cheap.
/// Measured on the outer solar system at h = 1825 d, n = 8 (D = 18, 126 unknowns): continuing
/// densely took 1.9e-4 s per step against 9.2e-5 s when the two stalling steps went to the
/// nodal Newton–Krylov solver.
const VELOCITY_DENSE_SIZE: usize = 64;

/// See [`VELOCITY_DENSE_SIZE`].
const VELOCITY_DENSE_SMALL_D: usize = 256;

/// Per-workspace state of the velocity form: the iterate, the previous step's modes, and the
/// frozen-Hessian solve.
#[derive(Debug, Clone)]
pub(crate) struct VelocityState {
    /// The iterate: velocity modes c_0 … c_{k−1} (k×D).
    pub c: Vec<f64>,
    /// The low part of c_0 (D): Newton's last corrections lie below its ulp, and
    /// q_{k+1} − q_k = h c_0 is wanted to more than working precision (as the nodal
    /// solve keeps ΔQ_{n−1}; docs/DESIGN.md §4).
    pub c0_lo: Vec<f64>,
    /// The previous step's converged modes, for the extrapolated guess.
    pub prev: Vec<f64>,
    /// Whether `prev` holds the step just before this one.
    pub has_prev: bool,
    /// −F, then the Newton correction (k×D).
    pub delta: Vec<f64>,
    /// The frozen-Hessian Kronecker solve of I ⊗ M + h² C ⊗ H̄.
    kron: KroneckerWork,
    /// The exact Newton matrix, dense, for steps where the frozen Hessian stalls (small
    /// systems, [`VELOCITY_DENSE_SIZE`]).
    dense: Option<DenseNewton>,
    /// `Auto`'s memory: recent steps the velocity form gave up, solves since the last one,
    /// and the steps left to hand to the nodal solvers directly.
    recent_failures: usize,
    calm: usize,
    holdoff: usize,
    /// The same for steps that needed the dense matrix: recent ones, and the steps left that
    /// start with it instead of the frozen Hessian.
    recent_dense: usize,
    dense_calm: usize,
    dense_start: usize,
}

impl VelocityState {
    /// `Auto`: whether this step goes to the nodal solvers directly (the velocity form
    /// failed twice within [`AUTO_CALM`] steps, less than [`AUTO_HOLDOFF`] steps ago).
    pub(super) fn holding_off(&mut self) -> bool {
        if self.holdoff > 0 {
            self.holdoff -= 1;
            return true;
        }
        false
    }

    /// Whether this step starts with the dense matrix (the frozen Hessian stalled in two of the
    /// last 8 steps, less than [`AUTO_HOLDOFF`] steps ago); counts the step.
    fn starts_dense(&mut self) -> bool {
        if self.dense.is_none() {
            return false;
        }
        if self.dense_start > 0 {
            self.dense_start -= 1;
            return true;
        }
        false
    }

    /// Record whether a step's frozen Hessian stalled into the dense matrix.
    fn record_dense(&mut self, escalated: bool) {
        if !escalated {
            self.dense_calm += 1;
            if self.dense_calm > AUTO_CALM {
                self.recent_dense = 0;
            }
            return;
        }
        self.dense_calm = 0;
        self.recent_dense += 1;
        if self.recent_dense >= 2 {
            self.recent_dense = 0;
            self.dense_start = AUTO_HOLDOFF;
        }
    }

    /// Record the outcome of a step's velocity-form solve for `Auto`.
    pub(super) fn record(&mut self, solved: bool) {
        if solved {
            self.calm += 1;
            if self.calm > AUTO_CALM {
                self.recent_failures = 0;
            }
            return;
        }
        self.has_prev = false;
        self.calm = 0;
        self.recent_failures += 1;
        if self.recent_failures >= 2 {
            self.recent_failures = 0;
            self.holdoff = AUTO_HOLDOFF;
        }
    }

    /// One correction δ = J⁻¹(−F) from the residual in `delta` (left there) with the frozen
    /// Kronecker matrix or the dense exact one, c ← c + δ with c_0 compensated (TwoSum into
    /// its low part).
    fn correct(
        &mut self,
        linear: Linear,
        kt: &super::kronecker::KroneckerTables,
        h: f64,
        d: usize,
    ) {
        match (linear, self.dense.as_mut()) {
            (Linear::Dense, Some(dn)) => dn.lu.solve_in_place(&mut self.delta, &mut dn.scratch),
            _ => {
                // J̃ = h (I ⊗ M/h + h C ⊗ H̄): the Kronecker solve of the bracket.
                self.delta.iter_mut().for_each(|x| *x /= h);
                self.kron.solve(kt, h, &mut self.delta);
            }
        }
        for ((c, lo), &x) in self.c[..d].iter_mut().zip(&mut self.c0_lo).zip(&self.delta) {
            let (s, e) = two_sum(*c, x);
            *c = s;
            *lo += e;
        }
        for (c, x) in self.c[d..].iter_mut().zip(&self.delta[d..]) {
            *c += x;
        }
    }

    /// Buffers for `vt`, D coordinates and mass matrix `mass` (coordinate blocks as
    /// `Lagrangian::coordinate_blocks`); `None` without a Schur form of the velocity pencil or
    /// with a mass matrix that is not symmetric positive definite.
    pub(crate) fn new(
        vt: &VelocityTables,
        d: usize,
        mass: &[f64],
        blocks: Option<usize>,
    ) -> Option<Self> {
        let size = vt.k * d;
        Some(VelocityState {
            c: vec![0.0; size],
            c0_lo: vec![0.0; d],
            prev: vec![0.0; size],
            has_prev: false,
            delta: vec![0.0; size],
            kron: KroneckerWork::new(vt.kron.as_ref()?, d, mass, blocks)?,
            dense: (size <= VELOCITY_DENSE_SIZE || (d <= 3 && size <= VELOCITY_DENSE_SMALL_D))
                .then(|| DenseNewton {
                    jac: vec![0.0; size * size],
                    acc: vec![0.0; d * d * vt.k],
                    lu: Lu::with_capacity(size),
                    scratch: vec![0.0; size],
                }),
            recent_failures: 0,
            calm: 0,
            holdoff: 0,
            recent_dense: 0,
            dense_calm: 0,
            dense_start: 0,
        })
    }
}

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// Whether this step can be solved in the velocity form.
    pub(super) fn velocity_form_applies(&self, ws: &Workspace) -> bool {
        ws.velocity.is_some()
            && self.tables().velocity.is_some()
            && self.stage_solver.is_none()
            && !ws.guess.has_warm
            && matches!(
                self.options().solver,
                super::StageSolver::Auto | super::StageSolver::Modal
            )
    }

    /// Solve the step from (q_k, p_k) = (`ws.newton.base`, `p`) in the velocity form. On
    /// success the increments ΔQ (with the low part of ΔQ_{n−1}) and the impulse are in
    /// `ws.newton`, as the nodal solve leaves them.
    pub(super) fn solve_velocity_form<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        q: &[f64],
        p: &[f64],
        stats: &mut StepStats,
    ) -> bool {
        let (Some(vt), Some(_)) = (self.tables().velocity.as_ref(), ws.velocity.as_ref()) else {
            return false;
        };
        let opts = self.options();
        let h = self.step_size();
        stats.guess = self.velocity_guess(lag, ws, vt, q, p, true);
        if let Some(vs) = ws.velocity.as_mut() {
            vs.c0_lo.iter_mut().for_each(|x| *x = 0.0);
        }
        let mut res = self.velocity_residual(lag, ws, vt, p);
        stats.gradient_evaluations += self.tables().m;
        if stats.guess == InitialGuess::Extrapolate
            && let Some(vs) = ws.velocity.as_mut()
            && (res > EXTRAPOLATION_TRUST * max_abs(&vs.c) || res.is_nan())
        {
            // Continuing a high-degree polynomial a full step ahead amplifies its top modes
            // (near Kepler's periapsis the extrapolated residual reaches O(1)): try the RK4
            // predictor and keep the better of the two.
            vs.prev.copy_from_slice(&vs.c);
            let predicted = self.velocity_guess(lag, ws, vt, q, p, false);
            let r = self.velocity_residual(lag, ws, vt, p);
            stats.gradient_evaluations += self.tables().m;
            if r < res || !res.is_finite() {
                (stats.guess, res) = (predicted, r);
            } else if let Some(vs) = ws.velocity.as_mut() {
                vs.c.copy_from_slice(&vs.prev);
                res = self.velocity_residual(lag, ws, vt, p);
                stats.gradient_evaluations += self.tables().m;
            }
        }
        ws.newton.last_lo.iter_mut().for_each(|x| *x = 0.0);
        let mut previous = f64::INFINITY;
        // `factored`: the current linear solve's matrix belongs to this step; `fresh`: it was
        // built at the last iterate.
        let start_dense = ws.velocity.as_mut().is_some_and(|v| v.starts_dense());
        let first = if start_dense {
            Linear::Dense
        } else {
            Linear::Frozen
        };
        let (mut linear, mut factored, mut refrozen) = (first, false, false);
        let mut fresh = false;
        let mut it = 0;
        loop {
            if it > 0 {
                res = self.velocity_residual(lag, ws, vt, p);
                stats.gradient_evaluations += self.tables().m;
            }
            stats.residual = res;
            if !res.is_finite() || it >= opts.max_iterations {
                return false;
            }
            let (Some(vs), Some(kt)) = (ws.velocity.as_mut(), vt.kron.as_ref()) else {
                return false;
            };
            if !factored {
                // At this iterate: the step's guess, or where the iteration stalled.
                stats.factorizations += 1;
                match (linear, vs.dense.as_mut()) {
                    (Linear::Dense, Some(dn)) => {
                        lag.force_jacobian_at_points(&ws.stage.qj, &mut ws.stage.hall);
                        ws.stage.hall_stale = false;
                        stats.hessian_evaluations += self.tables().m;
                        let sep = ws.separable.as_ref();
                        assemble_dense(
                            vt,
                            &self.tables().weights,
                            h,
                            ws.d,
                            &ws.stage.hall,
                            sep,
                            dn,
                        );
                        let size = vt.k * ws.d;
                        if dn.lu.refactor(&dn.jac[..size * size]).is_err() {
                            return false;
                        }
                    }
                    _ => {
                        stats.hessian_evaluations +=
                            self.mean_force_jacobian(lag, &mut ws.stage, &mut vs.kron);
                        if vs.kron.factor(kt, h).is_err() {
                            return false;
                        }
                    }
                }
                factored = true;
                fresh = true;
                previous = f64::INFINITY;
            }
            let d = ws.d;
            vs.correct(linear, kt, h, d);
            it += 1;
            stats.iterations += 1;
            let delta = max_abs(&vs.delta);
            let scale = max_abs(&vs.c).max(f64::MIN_POSITIVE);
            if !delta.is_finite() || !scale.is_finite() {
                return false;
            }
            let theta = if previous.is_finite() {
                delta / previous
            } else {
                f64::INFINITY
            };
            let tol = opts.tolerance * scale;
            // Exact Newton converges quadratically: a slow contraction at small increments is
            // its round-off floor (the nodal solver's `floor_tolerance`); the frozen Hessian's
            // linear iteration gets the floor only much closer to round-off.
            let floor = match linear {
                Linear::Dense => opts.floor_tolerance,
                Linear::Frozen => VELOCITY_FLOOR,
            };
            let converged = delta == 0.0
                || delta <= tol
                || (theta < VELOCITY_STALL && theta / (1.0 - theta) * delta <= tol)
                || (theta.is_finite()
                    && (theta >= VELOCITY_STALL || delta > previous)
                    && delta <= floor * scale);
            if converged {
                // The forces at the solution: the impulse and the step's residual. Its
                // correction costs no force evaluation and is applied too: a linear iteration
                // stopped on its contraction estimate leaves a remainder of one sign along
                // the orbit (measured: Kepler, Legendre n = 24, h = 0.5, T = 20 000 drifts to
                // 1.5e-8 and ΔE = −2.8e-13 without it), the correction shrinks it by the
                // contraction factor. The impulse keeps the forces before it (they differ
                // by O(h²|H|) times a correction at the round-off level).
                stats.residual = self.velocity_residual(lag, ws, vt, p);
                stats.gradient_evaluations += self.tables().m;
                if let Some(vs) = ws.velocity.as_mut() {
                    vs.correct(linear, kt, h, d);
                    if !start_dense {
                        vs.record_dense(linear == Linear::Dense);
                    }
                }
                self.finish_velocity_form(ws, vt);
                return true;
            }
            let stalled = theta.is_finite() && theta > VELOCITY_STALL;
            match linear {
                Linear::Frozen if stalled && !refrozen => {
                    factored = false;
                    refrozen = true;
                }
                Linear::Frozen if stalled => {
                    // The frozen Hessian is too far from the step's even when refrozen: exact
                    // Newton in the same form, where the system is small enough.
                    if vs.dense.is_none() {
                        return false;
                    }
                    linear = Linear::Dense;
                    factored = false;
                    stats.fallbacks += 1;
                }
                Linear::Dense if stalled && fresh => return false,
                // A matrix from an earlier iterate that no longer contracts fast: rebuild it.
                Linear::Dense if theta.is_finite() && theta > opts.reuse_contraction => {
                    factored = false;
                }
                _ => {}
            }
            fresh = false;
            previous = delta;
        }
    }

    /// The initial modes: the previous step's velocity continued (exact for polynomials),
    /// else the RK4 predictor's curve projected on the modes, else constant velocity M⁻¹p.
    fn velocity_guess<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        vt: &VelocityTables,
        q: &[f64],
        p: &[f64],
        extrapolate: bool,
    ) -> InitialGuess {
        let (k, d, n, h) = (vt.k, ws.d, self.tables().n, self.step_size());
        if let Some(vs) = ws.velocity.as_mut()
            && vs.has_prev
            && extrapolate
        {
            let rk = Strided::rows(0, k);
            let rd = Strided::rows(0, d);
            gemm(
                k,
                k,
                d,
                1.0,
                &vt.extrapolate,
                rk,
                &vs.prev,
                rd,
                0.0,
                &mut vs.c,
                rd,
            );
            return InitialGuess::Extrapolate;
        }
        let predicted = self.make_guess(lag, ws, InitialGuess::Predictor, q, p);
        let Some(vs) = ws.velocity.as_mut() else {
            return InitialGuess::Constant;
        };
        if predicted {
            let (rn, rd) = (Strided::rows(0, n), Strided::rows(0, d));
            gemm(
                k,
                n,
                d,
                1.0 / h,
                &vt.from_basis,
                rn,
                &ws.guess.cand,
                rd,
                0.0,
                &mut vs.c,
                rd,
            );
            if vs.c.iter().all(|x| x.is_finite()) {
                return InitialGuess::Predictor;
            }
        }
        vs.c.iter_mut().for_each(|x| *x = 0.0);
        vs.c[..d].copy_from_slice(p);
        if let Some(sep) = &ws.separable {
            sep.solve_mass(&mut vs.c[..d], &mut ws.stage.small_scratch);
        }
        InitialGuess::Constant
    }

    /// F(c) at the iterate: the curve at the nodes into `ws.stage.qj`, the forces into
    /// `ws.stage.lq`, −F into the state's `delta`; returns max |F|.
    fn velocity_residual<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        vt: &VelocityTables,
        p_k: &[f64],
    ) -> f64 {
        let t = self.tables();
        let (m, k, d, h) = (t.m, vt.k, ws.d, self.step_size());
        let (Some(vs), Some(sep)) = (ws.velocity.as_mut(), ws.separable.as_ref()) else {
            return f64::NAN;
        };
        let (rk, rd) = (Strided::rows(0, k), Strided::rows(0, d));
        // q_j = q_k + (δq_k + h ι_j0 c_0,lo + h Σ_a ι_ja c_a): the small parts first.
        for (j, row) in ws.stage.qj.chunks_exact_mut(d).enumerate() {
            let w = h * vt.iota[j * k];
            for ((x, &e), &lo) in row.iter_mut().zip(&ws.newton.base_err).zip(&vs.c0_lo) {
                *x = e + w * lo;
            }
        }
        gemm(
            m,
            k,
            d,
            h,
            &vt.iota,
            rk,
            &vs.c,
            rd,
            1.0,
            &mut ws.stage.qj,
            rd,
        );
        for row in ws.stage.qj.chunks_exact_mut(d) {
            for (x, b) in row.iter_mut().zip(&ws.newton.base) {
                *x += b;
            }
        }
        self.weighted_forces(lag, &mut ws.stage);
        // Σ_j ψ_jb (h b_j f_j).
        gemm_transposed(k, m, d, &vt.psi, &ws.stage.scaled, 0.0, &mut vs.delta);
        // Row 0, the momentum condition that fixes q_{k+1} = q_k + h c_0, in double-double
        // (exact products by FMA, TwoSum): M c_0 − p_k cancels to the size of the force term,
        // and a rounded sum leaves a one-signed error in every step's increment (the nodal
        // Legendre-transform row is summed the same way, `legendre_transform`).
        for r in 0..d {
            let (mut hi, mut lo) = (0.0, 0.0);
            match &sep.mass_diagonal {
                Some(diag) => {
                    dd_acc(&mut hi, &mut lo, diag[r], vs.c[r]);
                    lo += diag[r] * vs.c0_lo[r];
                }
                None => {
                    for s in 0..d {
                        dd_acc(&mut hi, &mut lo, sep.mass[r * d + s], vs.c[s]);
                        lo += sep.mass[r * d + s] * vs.c0_lo[s];
                    }
                }
            }
            let (s, e) = two_sum(hi, -p_k[r]);
            ws.stage.dd_hi[r] = s;
            ws.stage.dd_lo[r] = lo + (e - ws.newton.p_err[r]);
        }
        // The force terms, eight coordinates side by side with their (hi, lo) pairs in
        // registers: each sum runs over j in order (the same bits as one coordinate at a time),
        // independent sums hide each other's latency, and they vectorise for large D.
        const LANES: usize = 8;
        for r0 in (0..d).step_by(LANES) {
            let w_lanes = LANES.min(d - r0);
            let (mut hi, mut lo) = ([0.0f64; LANES], [0.0f64; LANES]);
            hi[..w_lanes].copy_from_slice(&ws.stage.dd_hi[r0..r0 + w_lanes]);
            lo[..w_lanes].copy_from_slice(&ws.stage.dd_lo[r0..r0 + w_lanes]);
            for j in 0..m {
                let (w, psi) = (t.weights[j] * h, vt.psi[j * k]);
                let f = &ws.stage.lq[j * d + r0..j * d + r0 + w_lanes];
                for ((hi, lo), &f) in hi.iter_mut().zip(lo.iter_mut()).zip(f) {
                    let g = w * f;
                    dd_acc(hi, lo, psi, g);
                    *lo += psi * w.mul_add(f, -g);
                }
            }
            ws.stage.dd_hi[r0..r0 + w_lanes].copy_from_slice(&hi[..w_lanes]);
            ws.stage.dd_lo[r0..r0 + w_lanes].copy_from_slice(&lo[..w_lanes]);
        }
        let mut norm = 0.0f64;
        for b in 0..k {
            for r in 0..d {
                let i = b * d + r;
                let f = if b == 0 {
                    ws.stage.dd_hi[r] + ws.stage.dd_lo[r]
                } else {
                    let mc = match &sep.mass_diagonal {
                        Some(diag) => diag[r] * vs.c[i],
                        None => (0..d).map(|s| sep.mass[r * d + s] * vs.c[b * d + s]).sum(),
                    };
                    mc + vs.delta[i]
                };
                vs.delta[i] = -f;
                norm = norm.max(f.abs());
                if !f.is_finite() {
                    norm = f64::INFINITY;
                }
            }
        }
        norm
    }

    /// The converged modes as the nodal solve leaves its result: increments ΔQ_i = h Σ_a B_ia
    /// c_a (ΔQ_{n−1} = h c_0 as hi + lo), the impulse h Σ_j b_j f_j (double-double) from the
    /// forces of the last residual, and the modes remembered for the next guess.
    fn finish_velocity_form(&self, ws: &mut Workspace, vt: &VelocityTables) {
        let t = self.tables();
        let (n, k, d, h) = (t.n, vt.k, ws.d, self.step_size());
        let Some(vs) = ws.velocity.as_mut() else {
            return;
        };
        let (rk, rd) = (Strided::rows(0, k), Strided::rows(0, d));
        gemm(
            n,
            k,
            d,
            h,
            &vt.to_basis,
            rk,
            &vs.c,
            rd,
            0.0,
            &mut ws.newton.coeffs,
            rd,
        );
        let last = (n - 1) * d;
        for r in 0..d {
            let c0 = vs.c[r];
            let hi = h * c0;
            ws.newton.coeffs[r] = 0.0;
            ws.newton.coeffs[last + r] = hi;
            ws.newton.last_lo[r] = h.mul_add(c0, -hi) + h * vs.c0_lo[r];
        }
        vs.prev.copy_from_slice(&vs.c);
        vs.has_prev = true;
        self.impulse(ws);
    }

    /// The total impulse h Σ_j b_j L_q(c_j) of the forces in `ws.stage.lq`, in double-double,
    /// into `ws.newton.impulse` (hi) and `impulse_lo`.
    pub(super) fn impulse(&self, ws: &mut Workspace) {
        let (t, h, d) = (self.tables(), self.step_size(), ws.d);
        ws.stage.dd_hi.iter_mut().for_each(|x| *x = 0.0);
        ws.stage.dd_lo.iter_mut().for_each(|x| *x = 0.0);
        let weights = &t.weights;
        dd_acc_columns(
            t.m,
            |j| h * weights[j],
            &ws.stage.lq,
            d,
            &mut ws.stage.dd_hi,
            &mut ws.stage.dd_lo,
        );
        for r in 0..d {
            (ws.newton.impulse[r], ws.newton.impulse_lo[r]) =
                two_sum(ws.stage.dd_hi[r], ws.stage.dd_lo[r]);
        }
    }
}

/// The exact Newton matrix of the velocity form, J = I ⊗ M + h² Σ_j b_j ψ_j ι_jᵀ ⊗ H_j, from the
/// node force Jacobians `hall` (m×D×D), into `dn.jac`: per row block b, the D² sums
/// Σ_j (h² b_j ψ_jb H_j[r, s]) ι_j· accumulated along the rows of ι (contiguous, vectorised),
/// as the nodal Newton matrix is (`stage.rs`), then scattered into the blocks.
fn assemble_dense(
    vt: &VelocityTables,
    weights: &[f64],
    h: f64,
    d: usize,
    hall: &[f64],
    sep: Option<&super::separable::Separable>,
    dn: &mut DenseNewton,
) {
    let k = vt.k;
    let (size, dd) = (k * d, d * d);
    let h2 = h * h;
    for b in 0..k {
        let acc = &mut dn.acc[..dd * k];
        acc.iter_mut().for_each(|x| *x = 0.0);
        for (j, hj) in hall.chunks_exact(dd).enumerate() {
            let base = h2 * weights[j] * vt.psi[j * k + b];
            if base == 0.0 {
                continue;
            }
            let row = &vt.iota[j * k..(j + 1) * k];
            for (rs, &hrs) in hj.iter().enumerate() {
                let g = base * hrs;
                if g == 0.0 {
                    continue;
                }
                for (x, &y) in acc[rs * k..(rs + 1) * k].iter_mut().zip(row) {
                    *x += g * y;
                }
            }
        }
        for r in 0..d {
            let jrow = (b * d + r) * size;
            for s in 0..d {
                let block = &acc[(r * d + s) * k..(r * d + s + 1) * k];
                for (a, &v) in block.iter().enumerate() {
                    dn.jac[jrow + a * d + s] = v;
                }
            }
        }
    }
    if let Some(sep) = sep {
        for b in 0..k {
            for r in 0..d {
                for s in 0..d {
                    dn.jac[(b * d + r) * size + b * d + s] += sep.mass[r * d + s];
                }
            }
        }
    }
}
