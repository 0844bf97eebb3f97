//! s-stage Gauss–Legendre collocation (implicit Runge–Kutta of order 2s, symplectic) for the
//! canonical equations of a mechanical Lagrangian, q̇ = M⁻¹p, ṗ = f(q) = −∇V(q).
//!
//! Butcher tableau: c_i the Gauss–Legendre nodes on [0, 1], b_i their weights,
//! a_ij = ∫₀^{c_i} ℓ_j(τ) dτ (ℓ_j the Lagrange polynomials at the nodes); Hairer, Lubich &
//! Wanner, *Geometric Numerical Integration*, §II.1.3.
//!
//! For separable systems the stage momenta can be eliminated: with v₀ = M⁻¹p, the stage
//! positions are Q_i = q + h c_i v₀ + Z_i where
//! Z = h² (A² ⊗ M⁻¹) F(Z), F_i = f(q + h c_i v₀ + Z_i),
//! and then q' = q + h v₀ + h² Σ_i (bᵀA)_i M⁻¹F_i, p' = p + h Σ_i b_i F_i.
//! The sD equations are solved by simplified Newton (Jacobian I − h²(A²⊗M⁻¹)·(I⊗∂f(q)),
//! factorised once per step) iterated until the increment stops decreasing at round-off level.

use super::{CanonicalParts, OneStepMethod, StaticKernel, force_static};
use crate::error::{GviError, Result};
use crate::lagrangian::Lagrangian;
use crate::linalg::Lu;
use crate::newton::{converges, drive};
use crate::quadrature::{GaussLegendre, Quadrature};

mod iterations;

use iterations::{FixedPoint, StageNewton, Stages, StaticStages, fixed_point_termination};

/// The largest number of stages accepted.
pub const MAX_GAUSS_STAGES: usize = 8;

/// s-stage Gauss–Legendre collocation (order 2s, symplectic, A-stable) for q̇ = M⁻¹p,
/// ṗ = −∇V(q).
///
/// ```
/// use galerkin_vi::baselines::{GaussCollocationBaseline, OneStepMethod};
/// use galerkin_vi::systems::HarmonicOscillator;
///
/// let ho = HarmonicOscillator::unit();
/// let mut g = GaussCollocationBaseline::new(&ho, 3, 0.1)?;
/// let (mut q, mut p) = ([0.0], [0.0]);
/// g.step(0.0, &[1.0], &[0.0], &mut q, &mut p)?;
/// assert!((q[0] - 0.1f64.cos()).abs() < 1e-12);
/// // Quadratic invariants are conserved exactly by Gauss methods.
/// assert!((q[0] * q[0] + p[0] * p[0] - 1.0).abs() < 1e-14);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
#[derive(Debug, Clone)]
pub struct GaussCollocationBaseline<'a, L: Lagrangian> {
    lagrangian: &'a L,
    h: f64,
    s: usize,
    parts: CanonicalParts,
    c: Vec<f64>,
    b: Vec<f64>,
    /// (A²)_ij, row-major s×s.
    a2: Vec<f64>,
    /// (bᵀA)_j.
    ba: Vec<f64>,
    evaluations: usize,
    iterations: usize,
    // Work buffers.
    v0: Vec<f64>,
    z: Vec<f64>,
    f: Vec<f64>,
    minv_f: Vec<f64>,
    stage_q: Vec<f64>,
    jac: Vec<f64>,
    // Simplified Newton: M⁻¹∂f, the iteration matrix and its LU, residual and scratch.
    mj: Vec<f64>,
    newton_matrix: Vec<f64>,
    lu: Lu,
    res: Vec<f64>,
    scratch: Vec<f64>,
}

impl<'a, L: Lagrangian> GaussCollocationBaseline<'a, L> {
    /// Gauss collocation with `s` stages (1 ≤ s ≤ 8) and step h for a mechanical Lagrangian.
    pub fn new(lagrangian: &'a L, s: usize, h: f64) -> Result<Self> {
        if !(1..=MAX_GAUSS_STAGES).contains(&s) {
            return Err(GviError::InvalidInput {
                name: "Gauss collocation stages".into(),
                reason: format!("s = {s}; need 1 ≤ s ≤ {MAX_GAUSS_STAGES}"),
            });
        }
        let parts = CanonicalParts::new(lagrangian, h)?;
        let (c, b, a) = gauss_tableau(s)?;
        let mut a2 = vec![0.0; s * s];
        for i in 0..s {
            for j in 0..s {
                a2[i * s + j] = (0..s).map(|k| a[i * s + k] * a[k * s + j]).sum();
            }
        }
        let ba = (0..s)
            .map(|j| (0..s).map(|i| b[i] * a[i * s + j]).sum())
            .collect();
        let d = parts.d;
        Ok(GaussCollocationBaseline {
            lagrangian,
            h,
            s,
            parts,
            c,
            b,
            a2,
            ba,
            evaluations: 0,
            iterations: 0,
            v0: vec![0.0; d],
            z: vec![0.0; s * d],
            f: vec![0.0; s * d],
            minv_f: vec![0.0; s * d],
            stage_q: vec![0.0; d],
            jac: vec![0.0; d * d],
            mj: vec![0.0; d * d],
            newton_matrix: vec![0.0; s * d * s * d],
            lu: Lu::with_capacity(s * d),
            res: vec![0.0; s * d],
            scratch: vec![0.0; s * d],
        })
    }

    /// Number of stages s (the order is 2s).
    pub fn stages(&self) -> usize {
        self.s
    }

    /// Total simplified-Newton iterations so far.
    pub fn iterations(&self) -> usize {
        self.iterations
    }

    /// Forces F_i at the current Z, and M⁻¹F_i.
    fn eval_forces(&mut self, q: &[f64]) {
        let (d, h) = (self.parts.d, self.h);
        for i in 0..self.s {
            for r in 0..d {
                self.stage_q[r] = q[r] + h * self.c[i] * self.v0[r] + self.z[i * d + r];
            }
            self.lagrangian
                .force(&self.stage_q, &mut self.f[i * d..(i + 1) * d]);
            self.parts.velocity(
                &self.f[i * d..(i + 1) * d],
                &mut self.minv_f[i * d..(i + 1) * d],
            );
        }
        self.evaluations += self.s;
    }
}

impl<L: Lagrangian> OneStepMethod for GaussCollocationBaseline<'_, L> {
    fn name(&self) -> String {
        format!("gauss-{} (h = {})", self.s, self.h)
    }

    fn step_size(&self) -> f64 {
        self.h
    }

    fn force_evaluations(&self) -> usize {
        self.evaluations
    }

    fn step(
        &mut self,
        t: f64,
        q: &[f64],
        p: &[f64],
        q_next: &mut [f64],
        p_next: &mut [f64],
    ) -> Result<()> {
        self.parts.check(q, p, q_next, p_next)?;
        self.increments(t, q, p, q_next, p_next)?;
        for r in 0..q.len() {
            q_next[r] += q[r];
            p_next[r] += p[r];
        }
        Ok(())
    }
}

impl<L: Lagrangian> GaussCollocationBaseline<'_, L> {
    /// The step's state increments (Δq, Δp) = (q_{k+1} − q_k, p_{k+1} − p_k), each computed to
    /// full relative accuracy, so that a caller can accumulate the state with compensated
    /// summation ([`integrate_compensated`](Self::integrate_compensated)).
    pub fn increments(
        &mut self,
        t: f64,
        q: &[f64],
        p: &[f64],
        dq_out: &mut [f64],
        dp_out: &mut [f64],
    ) -> Result<()> {
        self.parts.check(q, p, dq_out, dp_out)?;
        let mut v0 = std::mem::take(&mut self.v0);
        self.parts.velocity(p, &mut v0);
        self.v0 = v0;
        if self.fixed_point(q) {
            self.finish(dq_out, dp_out);
            return Ok(());
        }
        self.newton(t, q, dq_out, dp_out)
    }

    /// The simplified Newton iteration from Z = 0 (with `v0` = M⁻¹p already set), for steps
    /// where the fixed-point iteration does not contract.
    fn newton(&mut self, t: f64, q: &[f64], dq_out: &mut [f64], dp_out: &mut [f64]) -> Result<()> {
        let (d, s, h) = (self.parts.d, self.s, self.h);
        // Simplified Newton matrix I − h² (A² ⊗ M⁻¹ ∂f(q)), factorised in place.
        self.lagrangian.force_jacobian(q, &mut self.jac);
        let minv = &self.parts.inverse_mass;
        for r in 0..d {
            for c in 0..d {
                self.mj[r * d + c] = (0..d).map(|k| minv[(r, k)] * self.jac[k * d + c]).sum();
            }
        }
        let size = s * d;
        self.newton_matrix.iter_mut().for_each(|x| *x = 0.0);
        for k in 0..size {
            self.newton_matrix[k * size + k] = 1.0;
        }
        for i in 0..s {
            for j in 0..s {
                let w = h * h * self.a2[i * s + j];
                for r in 0..d {
                    for c in 0..d {
                        self.newton_matrix[(i * d + r) * size + j * d + c] -=
                            w * self.mj[r * d + c];
                    }
                }
            }
        }
        let singular = self.lu.refactor(&self.newton_matrix).is_err();
        self.z.iter_mut().for_each(|x| *x = 0.0);
        let scale = q.iter().fold(1e-300f64, |m, x| m.max(x.abs()));
        let fail = |residual: f64, iterations: usize, reason: &str| GviError::NewtonFailure {
            step: (t / h).round().max(0.0) as usize,
            t,
            residual,
            iterations,
            reason: format!("Gauss collocation (s = {s}): {reason}"),
        };
        let mut newton = StageNewton {
            g: self,
            q,
            singular,
            scale,
            residual: f64::NAN,
        };
        let first = newton.termination(scale);
        if let Err(f) = drive(&mut newton, &first) {
            return Err(fail(f.residual, f.iterations, &f.reason));
        }
        self.finish(dq_out, dp_out);
        if dq_out.iter().chain(dp_out.iter()).any(|x| !x.is_finite()) {
            return Err(fail(f64::NAN, 0, "non-finite state"));
        }
        Ok(())
    }

    /// Fixed-point iteration Z ← h² (A² ⊗ M⁻¹) F(Z) from Z = 0: cheap for small steps of
    /// non-stiff problems (no Jacobian, no factorisation). Returns false — leaving the
    /// simplified Newton iteration to do the work — when it does not contract fast.
    fn fixed_point(&mut self, q: &[f64]) -> bool {
        self.z.iter_mut().for_each(|x| *x = 0.0);
        let scale = q.iter().fold(1e-300f64, |m, x| m.max(x.abs()));
        let mut iteration = FixedPoint::new(Stages { g: self, q }, scale);
        // A stall is a hand-over, not an error: `converges` builds no failure (no allocation).
        converges(&mut iteration, &fixed_point_termination(0))
    }

    /// One application of the fixed-point map, Z ← h² (A² ⊗ M⁻¹) F(Z); returns max |ΔZ|.
    fn fixed_point_update(&mut self, q: &[f64]) -> f64 {
        let (d, s, h) = (self.parts.d, self.s, self.h);
        self.eval_forces(q);
        self.iterations += 1;
        let mut change = 0.0f64;
        for i in 0..s {
            for r in 0..d {
                let sum: f64 = (0..s)
                    .map(|j| self.a2[i * s + j] * self.minv_f[j * d + r])
                    .sum();
                let z = h * h * sum;
                change = change.max((z - self.z[i * d + r]).abs());
                self.z[i * d + r] = z;
            }
        }
        change
    }

    /// The increments from the converged stage values (forces already evaluated).
    fn finish(&self, dq_out: &mut [f64], dp_out: &mut [f64]) {
        let (d, s, h) = (self.parts.d, self.s, self.h);
        for r in 0..d {
            let mut dq = 0.0;
            let mut dp = 0.0;
            for i in 0..s {
                dq += self.ba[i] * self.minv_f[i * d + r];
                dp += self.b[i] * self.f[i * d + r];
            }
            dq_out[r] = h * self.v0[r] + h * h * dq;
            dp_out[r] = h * dp;
        }
    }

    /// Integrate `steps` steps from (q0, p0) at t = 0 with compensated (Kahan) summation of
    /// the state updates — the high-accuracy reference of the N-body report — recording the
    /// state every `record_every` steps (the first record is the initial state).
    pub fn integrate_compensated(
        &mut self,
        q0: &[f64],
        p0: &[f64],
        steps: usize,
        record_every: usize,
    ) -> Result<super::States> {
        let d = self.parts.d;
        crate::error::ensure_len("q0", d, q0.len())?;
        crate::error::ensure_len("p0", d, p0.len())?;
        crate::error::ensure_finite("q0", q0)?;
        crate::error::ensure_finite("p0", p0)?;
        let every = record_every.max(1);
        let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
        let (mut cq, mut cp) = (vec![0.0; d], vec![0.0; d]);
        let (mut dq, mut dp) = (vec![0.0; d], vec![0.0; d]);
        let (mut qs, mut ps) = (vec![q.clone()], vec![p.clone()]);
        for k in 0..steps {
            self.increments(k as f64 * self.h, &q, &p, &mut dq, &mut dp)?;
            for (x, (c, dx)) in q.iter_mut().zip(cq.iter_mut().zip(&dq)) {
                kahan(x, c, *dx);
            }
            for (x, (c, dx)) in p.iter_mut().zip(cp.iter_mut().zip(&dp)) {
                kahan(x, c, *dx);
            }
            if (k + 1) % every == 0 {
                qs.push(q.clone());
                ps.push(p.clone());
            }
        }
        Ok((qs, ps))
    }
}

/// The Butcher tableau (c, b, A) of s-stage Gauss–Legendre collocation on [0, 1]: c the
/// Gauss nodes, b their weights and a_ij = ∫₀^{c_i} ℓ_j(τ) dτ, A row-major s×s (Hairer, Lubich &
/// Wanner, *Geometric Numerical Integration*, §II.1.3). Shared with the Kepler-adapted
/// integrator, which runs the same collocation in the interaction picture.
pub(crate) fn gauss_tableau(s: usize) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    let rule = GaussLegendre::new(s)?.rule()?;
    let (c, b) = (rule.nodes.clone(), rule.weights.clone());
    // a_ij = ∫₀^{c_i} ℓ_j: the s-point Gauss rule mapped to [0, c_i] is exact (degree s−1).
    let lagrange = |j: usize, x: f64| {
        (0..s)
            .filter(|&k| k != j)
            .map(|k| (x - c[k]) / (c[j] - c[k]))
            .product::<f64>()
    };
    let mut a = vec![0.0; s * s];
    for i in 0..s {
        for j in 0..s {
            a[i * s + j] = c[i] * (0..s).map(|k| b[k] * lagrange(j, c[i] * c[k])).sum::<f64>();
        }
    }
    Ok((c, b, a))
}

/// x += dx with the running compensation c (Kahan summation).
#[inline]
fn kahan(x: &mut f64, c: &mut f64, dx: f64) {
    let y = dx - *c;
    let t = *x + y;
    *c = (t - *x) - y;
    *x = t;
}

impl<L: Lagrangian> GaussCollocationBaseline<'_, L> {
    /// Stage forces F_i and M⁻¹F_i at the current Z, fixed-size (as `eval_forces`).
    #[inline(always)]
    fn eval_forces_static<const D: usize>(
        &mut self,
        q: &[f64; D],
        v0: &[f64; D],
        z: &[[f64; D]; MAX_GAUSS_STAGES],
        f: &mut [[f64; D]; MAX_GAUSS_STAGES],
        minv_f: &mut [[f64; D]; MAX_GAUSS_STAGES],
    ) {
        let h = self.h;
        for i in 0..self.s {
            let stage_q: [f64; D] = std::array::from_fn(|r| q[r] + h * self.c[i] * v0[r] + z[i][r]);
            f[i] = force_static(self.lagrangian, &stage_q);
            minv_f[i] = self.parts.velocity_static(&f[i]);
        }
        self.evaluations += self.s;
    }
}

impl<L: Lagrangian> StaticKernel for GaussCollocationBaseline<'_, L> {
    fn dim(&self) -> usize {
        self.parts.d
    }

    /// The fixed-point iteration of `fixed_point` on fixed-size stages; when it does not
    /// contract, the general step (fixed point again, then simplified Newton) takes over.
    fn advance<const D: usize>(
        &mut self,
        t: f64,
        q: &mut [f64; D],
        p: &mut [f64; D],
        _fsal: &mut Option<[f64; D]>,
    ) -> Result<()> {
        let (s, h) = (self.s, self.h);
        let v0 = self.parts.velocity_static(p);
        let mut z = [[0.0; D]; MAX_GAUSS_STAGES];
        let mut f = [[0.0; D]; MAX_GAUSS_STAGES];
        let mut minv_f = [[0.0; D]; MAX_GAUSS_STAGES];
        let scale = q.iter().fold(1e-300f64, |m, x| m.max(x.abs()));
        let stages = StaticStages {
            g: &mut *self,
            q,
            v0: &v0,
            z: &mut z,
            f: &mut f,
            minv_f: &mut minv_f,
        };
        let mut iteration = FixedPoint::new(stages, scale);
        let converged = converges(&mut iteration, &fixed_point_termination(0));
        if !converged {
            // As the general step: the simplified Newton iteration from Z = 0.
            self.v0.copy_from_slice(&v0);
            let (mut dq, mut dp) = ([0.0; D], [0.0; D]);
            self.newton(t, q, &mut dq, &mut dp)?;
            for r in 0..D {
                q[r] += dq[r];
                p[r] += dp[r];
            }
            return Ok(());
        }
        for r in 0..D {
            let mut dq = 0.0;
            let mut dp = 0.0;
            for i in 0..s {
                dq += self.ba[i] * minv_f[i][r];
                dp += self.b[i] * f[i][r];
            }
            q[r] += h * v0[r] + h * h * dq;
            p[r] += h * dp;
        }
        Ok(())
    }
}
