//! Classical fourth-order Runge–Kutta on the canonical equations (not symplectic: the
//! negative control of the geometric checks).

use super::{CanonicalParts, OneStepMethod, StaticKernel, force_static};
use crate::error::Result;
use crate::lagrangian::Lagrangian;

/// Classical RK4 for q̇ = M⁻¹p, ṗ = −∇V(q) of a mechanical Lagrangian.
///
/// ```
/// use galerkin_vi::baselines::{OneStepMethod, Rk4};
/// use galerkin_vi::systems::HarmonicOscillator;
///
/// let ho = HarmonicOscillator::unit();
/// let mut rk4 = Rk4::new(&ho, 0.1)?;
/// let (mut q, mut p) = ([0.0], [0.0]);
/// rk4.step(0.0, &[1.0], &[0.0], &mut q, &mut p)?;
/// assert!((q[0] - 0.1f64.cos()).abs() < 1e-7);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Rk4<'a, L: Lagrangian> {
    lagrangian: &'a L,
    h: f64,
    parts: CanonicalParts,
    /// Stage buffers: stage positions/momenta and their derivatives (4 stages).
    qs: Vec<f64>,
    ps: Vec<f64>,
    kq: Vec<f64>,
    kp: Vec<f64>,
    evaluations: usize,
}

impl<'a, L: Lagrangian> Rk4<'a, L> {
    /// RK4 with step h for a mechanical Lagrangian (error for a non-separable one).
    pub fn new(lagrangian: &'a L, h: f64) -> Result<Self> {
        let parts = CanonicalParts::new(lagrangian, h)?;
        let d = parts.d;
        Ok(Rk4 {
            lagrangian,
            h,
            parts,
            qs: vec![0.0; d],
            ps: vec![0.0; d],
            kq: vec![0.0; 4 * d],
            kp: vec![0.0; 4 * d],
            evaluations: 0,
        })
    }
}

impl<L: Lagrangian> OneStepMethod for Rk4<'_, L> {
    fn name(&self) -> String {
        format!("rk4 (h = {})", self.h)
    }

    fn step_size(&self) -> f64 {
        self.h
    }

    fn force_evaluations(&self) -> usize {
        self.evaluations
    }

    fn step(
        &mut self,
        _t: f64,
        q: &[f64],
        p: &[f64],
        q_next: &mut [f64],
        p_next: &mut [f64],
    ) -> Result<()> {
        self.parts.check(q, p, q_next, p_next)?;
        let (d, h) = (self.parts.d, self.h);
        let c = [0.0, 0.5, 0.5, 1.0];
        self.evaluations += 4;
        for s in 0..4 {
            for r in 0..d {
                if s == 0 {
                    self.qs[r] = q[r];
                    self.ps[r] = p[r];
                } else {
                    self.qs[r] = q[r] + c[s] * h * self.kq[(s - 1) * d + r];
                    self.ps[r] = p[r] + c[s] * h * self.kp[(s - 1) * d + r];
                }
            }
            self.parts
                .velocity(&self.ps, &mut self.kq[s * d..(s + 1) * d]);
            self.lagrangian
                .force(&self.qs, &mut self.kp[s * d..(s + 1) * d]);
        }
        for r in 0..d {
            let comb = |k: &[f64]| k[r] + 2.0 * k[d + r] + 2.0 * k[2 * d + r] + k[3 * d + r];
            q_next[r] = q[r] + h / 6.0 * comb(&self.kq);
            p_next[r] = p[r] + h / 6.0 * comb(&self.kp);
        }
        Ok(())
    }
}

impl<L: Lagrangian> StaticKernel for Rk4<'_, L> {
    fn dim(&self) -> usize {
        self.parts.d
    }

    #[inline]
    fn advance<const D: usize>(
        &mut self,
        _t: f64,
        q: &mut [f64; D],
        p: &mut [f64; D],
        _fsal: &mut Option<[f64; D]>,
    ) -> Result<()> {
        let h = self.h;
        let c = [0.0, 0.5, 0.5, 1.0];
        self.evaluations += 4;
        let mut kq = [[0.0; D]; 4];
        let mut kp = [[0.0; D]; 4];
        for s in 0..4 {
            let (qs, ps) = if s == 0 {
                (*q, *p)
            } else {
                (
                    std::array::from_fn(|r| q[r] + c[s] * h * kq[s - 1][r]),
                    std::array::from_fn(|r| p[r] + c[s] * h * kp[s - 1][r]),
                )
            };
            kq[s] = self.parts.velocity_static(&ps);
            kp[s] = force_static(self.lagrangian, &qs);
        }
        for r in 0..D {
            let comb = |k: &[[f64; D]; 4]| k[0][r] + 2.0 * k[1][r] + 2.0 * k[2][r] + k[3][r];
            q[r] += h / 6.0 * comb(&kq);
            p[r] += h / 6.0 * comb(&kp);
        }
        Ok(())
    }
}
