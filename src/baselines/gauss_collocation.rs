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
use crate::newton::{
    Adapt, ConvergedBy, Correction, Divergence, NewtonFailure, NewtonIteration, Progress,
    Termination, converges, drive,
};
use crate::quadrature::{GaussLegendre, Quadrature};

/// The largest number of stages accepted.
pub const MAX_GAUSS_STAGES: usize = 8;

/// Iteration cap of the simplified Newton solve.
const MAX_ITERATIONS: usize = 60;

/// Iteration cap of the fixed-point iteration (then simplified Newton takes over).
const FIXED_POINT_ITERATIONS: usize = 30;

/// The fixed-point iteration converged when max |ΔZ| ≤ this · max(|q|); …
const FIXED_POINT_TOLERANCE: f64 = 1e-15;

/// … or, once it stopped contracting (θ above [`FIXED_POINT_STALL`]), at the round-off floor,
/// max |ΔZ| ≤ this · max(|q|).
const FIXED_POINT_FLOOR: f64 = 1e-14;

/// Contraction per iteration above which the fixed-point iteration has stopped contracting
/// (from its third iteration on): it hands over to simplified Newton unless at the floor.
const FIXED_POINT_STALL: f64 = 0.5;

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

/// The largest double below a positive `x`: `|δ| ≤ below(x)` is `|δ| < x` (the driver's floor
/// test is `≤`, this solver's `<`).
fn below(x: f64) -> f64 {
    debug_assert!(x > 0.0);
    f64::from_bits(x.to_bits() - 1)
}

/// The contraction above which the simplified Newton increment has stopped decreasing: the
/// largest double below 1, so that `θ >` it means `|δ| ≥ |δ_prev|` (a quotient of doubles below
/// 1 is at most the double below 1).
const NEWTON_FLOOR_THETA: f64 = f64::from_bits(1f64.to_bits() - 1);

/// The simplified Newton iteration on the stage equations Z = h² (A² ⊗ M⁻¹) F(Z) as a
/// [`NewtonIteration`] run by the crate's Newton driver ([`crate::newton::drive`]): the
/// residual R = h² (A² ⊗ I) M⁻¹F − Z and the LU of I − h² (A² ⊗ M⁻¹ ∂f(q)), factorised once
/// per step (Hairer, Lubich & Wanner, *Geometric Numerical Integration*, §VIII.6).
struct StageNewton<'g, 'a, L: Lagrangian> {
    g: &'g mut GaussCollocationBaseline<'a, L>,
    q: &'g [f64],
    /// The iteration matrix is singular (reported at the first correction, after a residual).
    singular: bool,
    /// max(|q|) (at least 1e-300).
    scale: f64,
    /// The last residual's max-norm.
    residual: f64,
}

impl<L: Lagrangian> StageNewton<'_, '_, L> {
    /// Converged at round-off: the increment is at machine level of q (`tiny`, the driver's
    /// tolerance test), or it has stopped decreasing (θ ≥ 1) while already small compared
    /// with q and Z (the floor test, 1e-10 · `zmax`). The two tests have different scales, so
    /// the corrections are reported with scale 1 and the scales are folded into the tolerance
    /// and the floor (the largest doubles below the thresholds where this solver's tests are
    /// strict), which keeps the maps bit for bit those of the hand-written loop this replaces.
    /// Diverging: an increment more than twice the previous one after 8 iterations.
    fn termination(&self, zmax: f64) -> Termination {
        Termination {
            divergence: Some(Divergence {
                after: 8,
                growth: 2.0,
            }),
            ..Termination::new(
                MAX_ITERATIONS,
                1e-15 * self.scale,
                None,
                below(1e-10 * zmax),
                NEWTON_FLOOR_THETA,
            )
        }
    }

    fn failure(&self, iteration: usize, reason: &str) -> NewtonFailure {
        NewtonFailure {
            residual: self.residual,
            iterations: iteration + 1,
            reason: reason.into(),
        }
    }
}

impl<L: Lagrangian> NewtonIteration for StageNewton<'_, '_, L> {
    fn residual(&mut self, _: usize) -> f64 {
        let g = &mut *self.g;
        let (d, s, h) = (g.parts.d, g.s, g.h);
        g.eval_forces(self.q);
        g.iterations += 1;
        // Residual R = h² (A² ⊗ I) M⁻¹F − Z.
        for i in 0..s {
            for r in 0..d {
                let sum: f64 = (0..s).map(|j| g.a2[i * s + j] * g.minv_f[j * d + r]).sum();
                g.res[i * d + r] = h * h * sum - g.z[i * d + r];
            }
        }
        self.residual = amax(&g.res);
        self.residual
    }

    fn correct(&mut self, iteration: usize) -> Result<(Correction, Termination), NewtonFailure> {
        if self.singular {
            return Err(self.failure(iteration, "singular iteration matrix"));
        }
        let g = &mut *self.g;
        // The increment, in place of the residual.
        g.lu.solve_in_place(&mut g.res, &mut g.scratch);
        let size = amax(&g.res);
        if !size.is_finite() {
            return Err(self.failure(iteration, "non-finite iterate"));
        }
        for (z, dz) in g.z.iter_mut().zip(&g.res) {
            *z += dz;
        }
        let zmax = g.z.iter().fold(self.scale, |m, x| m.max(x.abs()));
        let correction = Correction { size, scale: 1.0 };
        Ok((correction, self.termination(zmax)))
    }

    /// At machine level (the tolerance test) the forces of the last iterate are the
    /// converged ones; at the floor they are re-evaluated: Z can be h² times larger than the
    /// forces it carries.
    fn finish(&mut self, by: ConvergedBy) -> Result<(), NewtonFailure> {
        if by == ConvergedBy::Floor {
            self.g.eval_forces(self.q);
        }
        Ok(())
    }
}

/// max |x| (NaN entries ignored, as `f64::max` does: a NaN increment shows in the next
/// residual and in the final state check).
fn amax(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// The stage values a fixed-point iteration runs on: the general step's buffers or the
/// static kernel's fixed-size arrays.
trait StageMap {
    /// One application of the map Z ← h² (A² ⊗ M⁻¹) F(Z); returns max |ΔZ|.
    fn update(&mut self) -> f64;
    /// The forces at the converged Z.
    fn refresh(&mut self);
}

/// The general step's stages ([`GaussCollocationBaseline::fixed_point_update`]).
struct Stages<'g, 'a, L: Lagrangian> {
    g: &'g mut GaussCollocationBaseline<'a, L>,
    q: &'g [f64],
}

impl<L: Lagrangian> StageMap for Stages<'_, '_, L> {
    fn update(&mut self) -> f64 {
        self.g.fixed_point_update(self.q)
    }
    fn refresh(&mut self) {
        self.g.eval_forces(self.q);
    }
}

/// The static kernel's stages (`StaticKernel::advance`), fixed-size.
struct StaticStages<'g, 'a, L: Lagrangian, const D: usize> {
    g: &'g mut GaussCollocationBaseline<'a, L>,
    q: &'g [f64; D],
    v0: &'g [f64; D],
    z: &'g mut [[f64; D]; MAX_GAUSS_STAGES],
    f: &'g mut [[f64; D]; MAX_GAUSS_STAGES],
    minv_f: &'g mut [[f64; D]; MAX_GAUSS_STAGES],
}

impl<L: Lagrangian, const D: usize> StageMap for StaticStages<'_, '_, L, D> {
    #[inline(always)]
    fn update(&mut self) -> f64 {
        let g = &mut *self.g;
        g.eval_forces_static(self.q, self.v0, self.z, self.f, self.minv_f);
        g.iterations += 1;
        let (s, h) = (g.s, g.h);
        let mut change = 0.0f64;
        for i in 0..s {
            for r in 0..D {
                let sum: f64 = (0..s).map(|j| g.a2[i * s + j] * self.minv_f[j][r]).sum();
                let zn = h * h * sum;
                change = change.max((zn - self.z[i][r]).abs());
                self.z[i][r] = zn;
            }
        }
        change
    }
    fn refresh(&mut self) {
        self.g
            .eval_forces_static(self.q, self.v0, self.z, self.f, self.minv_f);
    }
}

/// The termination of the fixed-point iteration after `corrections` iterations: converged
/// when max |ΔZ| ≤ 1e-15 · max(|q|), or — from the third iteration on, once it stopped
/// contracting (θ > ½) — at the round-off floor 1e-14 · max(|q|). (The first two increments
/// are not compared: the first is Z itself.)
fn fixed_point_termination(corrections: usize) -> Termination {
    let floor = if corrections > 2 {
        FIXED_POINT_FLOOR
    } else {
        0.0
    };
    Termination::new(
        FIXED_POINT_ITERATIONS,
        FIXED_POINT_TOLERANCE,
        None,
        floor,
        FIXED_POINT_STALL,
    )
}

/// The fixed-point iteration Z ← h² (A² ⊗ M⁻¹) F(Z) from Z = 0 as a [`NewtonIteration`] (the
/// simplified Newton iteration with the identity for its matrix): cheap for small steps of
/// non-stiff problems. It gives up — leaving simplified Newton to do the work — when it stops
/// contracting above the floor, when an increment is not finite, or at its iteration limit.
struct FixedPoint<M: StageMap> {
    map: M,
    /// max(|q|) (at least 1e-300): the scale of the tolerance and the floor.
    scale: f64,
    /// The last increment.
    last: f64,
}

impl<M: StageMap> FixedPoint<M> {
    fn new(map: M, scale: f64) -> Self {
        FixedPoint {
            map,
            scale,
            last: 0.0,
        }
    }
}

impl<M: StageMap> NewtonIteration for FixedPoint<M> {
    /// The map is applied once per iteration, in `correct` (the increment G(Z) − Z is the
    /// residual of the iterate before it); this reports the last increment (0 before the
    /// first), so that stopping at the iteration limit costs no further force evaluation.
    fn residual(&mut self, _: usize) -> f64 {
        self.last
    }

    fn correct(&mut self, iteration: usize) -> Result<(Correction, Termination), NewtonFailure> {
        self.last = self.map.update();
        let correction = Correction {
            size: self.last,
            scale: self.scale,
        };
        Ok((correction, fixed_point_termination(iteration + 1)))
    }

    fn adapt(&mut self, progress: &Progress) -> Adapt {
        let stalled = progress.growing || progress.theta > FIXED_POINT_STALL;
        if progress.iteration > 2 && stalled {
            Adapt::GiveUp
        } else {
            Adapt::Continue
        }
    }

    fn finish(&mut self, _: ConvergedBy) -> Result<(), NewtonFailure> {
        self.map.refresh();
        Ok(())
    }
}
