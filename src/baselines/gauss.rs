//! Gauss collocation: the s-stage Gauss–Legendre implicit Runge–Kutta method (order 2s,
//! symplectic), solved by fixed-point iteration — the classical high-order reference.

use super::{CanonicalParts, OneStepMethod, States};
use crate::error::{GviError, Result, ensure_finite, ensure_len};
use crate::lagrangian::Lagrangian;
use crate::quadrature::{GaussLegendre, Quadrature};

/// The s-stage Gauss–Legendre collocation method for q̇ = M⁻¹p, ṗ = −∇V(q) of a mechanical
/// Lagrangian: order 2s, symplectic, symmetric.
///
/// The stage equations Qᵢ = q + h Σⱼ aᵢⱼ M⁻¹Pⱼ, Pᵢ = p + h Σⱼ aᵢⱼ F(Qⱼ) are solved by
/// fixed-point iteration from the guess Qᵢ = q + cᵢ h M⁻¹p, Pᵢ = p + cᵢ h F(q), until the
/// update stops shrinking at round-off level (at most 200 iterations; otherwise
/// [`GviError::NewtonFailure`] with the iteration count). Fixed-point iteration converges for
/// h‖∂f/∂y‖ small enough — the regime of accurate references; for very large steps use the
/// Galerkin integrator. [`integrate_compensated`](GaussCollocation::integrate_compensated)
/// adds compensated (Kahan) summation of the state updates for long high-accuracy references.
///
/// ```
/// use galerkin_vi::baselines::{GaussCollocation, OneStepMethod};
/// use galerkin_vi::systems::HarmonicOscillator;
///
/// let ho = HarmonicOscillator::unit();
/// let mut gauss = GaussCollocation::new(&ho, 4, 0.25)?; // order 8
/// let (mut q, mut p) = ([0.0], [0.0]);
/// gauss.step(0.0, &[1.0], &[0.0], &mut q, &mut p)?;
/// assert!((q[0] - 0.25f64.cos()).abs() < 1e-9);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
#[derive(Debug, Clone)]
pub struct GaussCollocation<'a, L: Lagrangian> {
    lagrangian: &'a L,
    h: f64,
    s: usize,
    /// Butcher matrix, row-major s×s; weights b.
    a: Vec<f64>,
    b: Vec<f64>,
    c: Vec<f64>,
    parts: CanonicalParts,
    /// Stage increments Zq, Zp (s·D) and stage derivatives Fq = M⁻¹P, Fp = F(Q).
    zq: Vec<f64>,
    zp: Vec<f64>,
    fq: Vec<f64>,
    fp: Vec<f64>,
    stage: Vec<f64>,
    iterations: usize,
}

/// Largest number of stages accepted.
pub const MAX_STAGES: usize = 16;
const MAX_ITERATIONS: usize = 200;

impl<'a, L: Lagrangian> GaussCollocation<'a, L> {
    /// The s-stage method (1 ≤ s ≤ 16) with step h for a mechanical Lagrangian.
    pub fn new(lagrangian: &'a L, s: usize, h: f64) -> Result<Self> {
        if s == 0 || s > MAX_STAGES {
            return Err(GviError::InvalidArgument {
                name: "stages".into(),
                reason: format!("Gauss collocation needs 1 ≤ s ≤ {MAX_STAGES}, got {s}"),
            });
        }
        let parts = CanonicalParts::new(lagrangian, h)?;
        let rule = GaussLegendre::new(s)?.rule()?;
        let (c, b) = (rule.nodes, rule.weights);
        // aᵢⱼ = ∫₀^{cᵢ} ℓⱼ(τ) dτ = cᵢ Σ_k b_k ℓⱼ(cᵢ c_k) (the s-point rule is exact for ℓⱼ).
        let lagrange = |j: usize, x: f64| {
            (0..s)
                .filter(|&m| m != j)
                .map(|m| (x - c[m]) / (c[j] - c[m]))
                .product::<f64>()
        };
        let mut a = vec![0.0; s * s];
        for i in 0..s {
            for j in 0..s {
                a[i * s + j] = c[i] * (0..s).map(|k| b[k] * lagrange(j, c[i] * c[k])).sum::<f64>();
            }
        }
        let d = parts.d;
        Ok(GaussCollocation {
            lagrangian,
            h,
            s,
            a,
            b,
            c,
            parts,
            zq: vec![0.0; s * d],
            zp: vec![0.0; s * d],
            fq: vec![0.0; s * d],
            fp: vec![0.0; s * d],
            stage: vec![0.0; d],
            iterations: 0,
        })
    }

    /// Number of stages s (the order is 2s).
    pub fn stages(&self) -> usize {
        self.s
    }

    /// Fixed-point iterations taken by the last step.
    pub fn last_iterations(&self) -> usize {
        self.iterations
    }

    /// Stage derivatives at the current stage increments.
    fn derivatives(&mut self, q: &[f64], p: &[f64]) {
        let d = self.parts.d;
        for i in 0..self.s {
            let blk = i * d..(i + 1) * d;
            for r in 0..d {
                self.stage[r] = p[r] + self.zp[i * d + r];
            }
            self.parts.velocity(&self.stage, &mut self.fq[blk.clone()]);
            for r in 0..d {
                self.stage[r] = q[r] + self.zq[i * d + r];
            }
            self.lagrangian.force(&self.stage, &mut self.fp[blk]);
        }
    }

    /// Solve the stage equations at (q, p) and write the increments q_{k+1} − q_k and
    /// p_{k+1} − p_k into `dq`, `dp`.
    fn increments(
        &mut self,
        t: f64,
        q: &[f64],
        p: &[f64],
        dq: &mut [f64],
        dp: &mut [f64],
    ) -> Result<()> {
        let (d, s, h) = (self.parts.d, self.s, self.h);
        // Guess: the explicit Euler line through the stages.
        self.zq.iter_mut().for_each(|x| *x = 0.0);
        self.zp.iter_mut().for_each(|x| *x = 0.0);
        self.derivatives(q, p);
        for i in 0..s {
            for r in 0..d {
                self.zq[i * d + r] = self.c[i] * h * self.fq[r];
                self.zp[i * d + r] = self.c[i] * h * self.fp[r];
            }
        }
        let scale_q = q
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()))
            .max(f64::MIN_POSITIVE);
        let scale_p = p
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()))
            .max(f64::MIN_POSITIVE);
        let mut previous = f64::INFINITY;
        let mut converged = false;
        self.iterations = 0;
        while self.iterations < MAX_ITERATIONS {
            self.iterations += 1;
            self.derivatives(q, p);
            let mut change = 0.0f64;
            for i in 0..s {
                for r in 0..d {
                    let (mut nq, mut np) = (0.0, 0.0);
                    for j in 0..s {
                        nq += self.a[i * s + j] * self.fq[j * d + r];
                        np += self.a[i * s + j] * self.fp[j * d + r];
                    }
                    let (nq, np) = (h * nq, h * np);
                    change = change
                        .max((nq - self.zq[i * d + r]).abs() / scale_q)
                        .max((np - self.zp[i * d + r]).abs() / scale_p);
                    self.zq[i * d + r] = nq;
                    self.zp[i * d + r] = np;
                }
            }
            if !change.is_finite() {
                break;
            }
            // Converged: at round-off, or no longer shrinking once near it.
            if change <= 4.0 * f64::EPSILON || (change >= previous && change <= 1e-11) {
                converged = true;
                break;
            }
            previous = change;
        }
        if !converged {
            return Err(GviError::NewtonFailure {
                step: (t / h).round().max(0.0) as usize,
                t,
                residual: previous,
                iterations: self.iterations,
                reason: "Gauss collocation fixed-point iteration did not converge (step too \
                         large for fixed-point iteration?)"
                    .into(),
            });
        }
        self.derivatives(q, p);
        for r in 0..d {
            let (mut sq, mut sp) = (0.0, 0.0);
            for i in 0..s {
                sq += self.b[i] * self.fq[i * d + r];
                sp += self.b[i] * self.fp[i * d + r];
            }
            dq[r] = h * sq;
            dp[r] = h * sp;
        }
        Ok(())
    }

    /// Integrate `steps` steps from (q0, p0) at t = 0 with compensated (Kahan) summation of
    /// the state updates, recording the state every `record_every` steps (the first record is
    /// the initial state; `steps` should be a multiple of `record_every`).
    pub fn integrate_compensated(
        &mut self,
        q0: &[f64],
        p0: &[f64],
        steps: usize,
        record_every: usize,
    ) -> Result<States> {
        let d = self.parts.d;
        ensure_len("q0", d, q0.len())?;
        ensure_len("p0", d, p0.len())?;
        ensure_finite("q0", q0)?;
        ensure_finite("p0", p0)?;
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

/// x += dx with the running compensation c.
#[inline]
fn kahan(x: &mut f64, c: &mut f64, dx: f64) {
    let y = dx - *c;
    let t = *x + y;
    *c = (t - *x) - y;
    *x = t;
}

impl<L: Lagrangian> OneStepMethod for GaussCollocation<'_, L> {
    fn name(&self) -> String {
        format!(
            "gauss collocation (s = {}, order {}, h = {})",
            self.s,
            2 * self.s,
            self.h
        )
    }

    fn step_size(&self) -> f64 {
        self.h
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
        for r in 0..self.parts.d {
            q_next[r] += q[r];
            p_next[r] += p[r];
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::systems::{HarmonicOscillator, Kepler};

    #[test]
    fn butcher_tableau_satisfies_simplifying_assumptions() {
        let ho = HarmonicOscillator::unit();
        for s in [1, 2, 3, 6, 8] {
            let g = GaussCollocation::new(&ho, s, 0.1).unwrap();
            // C(s): Σⱼ aᵢⱼ cⱼ^{k−1} = cᵢ^k / k.
            for i in 0..s {
                for k in 1..=s {
                    let lhs: f64 = (0..s)
                        .map(|j| g.a[i * s + j] * g.c[j].powi(k as i32 - 1))
                        .sum();
                    assert!(
                        (lhs - g.c[i].powi(k as i32) / k as f64).abs() < 1e-14,
                        "s={s}"
                    );
                }
            }
        }
        assert!(GaussCollocation::new(&ho, 0, 0.1).is_err());
        assert!(GaussCollocation::new(&ho, 17, 0.1).is_err());
    }

    #[test]
    fn order_2s_on_kepler() {
        let k = Kepler::new(1.0).unwrap();
        let (q0, p0) = Kepler::paper_initial_state();
        let exact = crate::systems::System::exact_solution(&k, 0.0, &q0, &p0)
            .unwrap()
            .unwrap()
            .position(2.0);
        let err = |s: usize, steps: usize| {
            let mut g = GaussCollocation::new(&k, s, 2.0 / steps as f64).unwrap();
            let (qs, _) = g.integrate_compensated(&q0, &p0, steps, steps).unwrap();
            let q = &qs[1];
            (q[0] - exact[0]).abs().max((q[1] - exact[1]).abs())
        };
        // s = 2 (order 4): halving h divides the error by ≈ 16.
        let ratio = err(2, 40) / err(2, 80);
        assert!((ratio.log2() - 4.0).abs() < 0.3, "ratio {ratio}");
        // s = 6 reaches round-off on this arc.
        assert!(err(6, 40) < 1e-13);
    }
}
