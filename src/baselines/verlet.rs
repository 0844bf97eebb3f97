//! Störmer–Verlet (leapfrog, kick–drift–kick): second order and symplectic (a positive
//! control of the geometric checks).

use super::{CanonicalParts, OneStepMethod, StaticKernel, force_static};
use crate::error::Result;
use crate::lagrangian::Lagrangian;

/// Kick–drift–kick Störmer–Verlet for q̇ = M⁻¹p, ṗ = −∇V(q):
/// p_{½} = p + (h/2) f(q), q' = q + h M⁻¹ p_{½}, p' = p_{½} + (h/2) f(q').
///
/// ```
/// use galerkin_vi::baselines::{OneStepMethod, StormerVerlet};
/// use galerkin_vi::systems::HarmonicOscillator;
///
/// let ho = HarmonicOscillator::unit();
/// let mut sv = StormerVerlet::new(&ho, 0.1)?;
/// let (mut q, mut p) = ([0.0], [0.0]);
/// sv.step(0.0, &[1.0], &[0.0], &mut q, &mut p)?;
/// assert!((q[0] - (1.0 - 0.005)).abs() < 1e-15);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
#[derive(Debug, Clone)]
pub struct StormerVerlet<'a, L: Lagrangian> {
    lagrangian: &'a L,
    h: f64,
    parts: CanonicalParts,
    force: Vec<f64>,
    half: Vec<f64>,
    vel: Vec<f64>,
    evaluations: usize,
    /// Position of the last end-of-step force (first same as last).
    cached_q: Vec<f64>,
    has_cache: bool,
}

impl<'a, L: Lagrangian> StormerVerlet<'a, L> {
    /// Störmer–Verlet with step h for a mechanical Lagrangian (error for a non-separable one).
    pub fn new(lagrangian: &'a L, h: f64) -> Result<Self> {
        let parts = CanonicalParts::new(lagrangian, h)?;
        let d = parts.d;
        Ok(StormerVerlet {
            lagrangian,
            h,
            parts,
            force: vec![0.0; d],
            half: vec![0.0; d],
            vel: vec![0.0; d],
            evaluations: 0,
            cached_q: vec![0.0; d],
            has_cache: false,
        })
    }
}

impl<L: Lagrangian> OneStepMethod for StormerVerlet<'_, L> {
    fn name(&self) -> String {
        format!("stormer-verlet (h = {})", self.h)
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
        // `self.force` still holds f(q) when q is the previous step's end (first same as last).
        if !(self.has_cache && self.cached_q.as_slice() == q) {
            self.lagrangian.force(q, &mut self.force);
            self.evaluations += 1;
        }
        for r in 0..d {
            self.half[r] = p[r] + 0.5 * h * self.force[r];
        }
        self.parts.velocity(&self.half, &mut self.vel);
        for r in 0..d {
            q_next[r] = q[r] + h * self.vel[r];
        }
        self.lagrangian.force(q_next, &mut self.force);
        self.evaluations += 1;
        for r in 0..d {
            p_next[r] = self.half[r] + 0.5 * h * self.force[r];
        }
        self.cached_q.copy_from_slice(q_next);
        self.has_cache = true;
        Ok(())
    }
}

impl<L: Lagrangian> StaticKernel for StormerVerlet<'_, L> {
    fn dim(&self) -> usize {
        self.parts.d
    }

    #[inline]
    fn advance<const D: usize>(
        &mut self,
        _t: f64,
        q: &mut [f64; D],
        p: &mut [f64; D],
        fsal: &mut Option<[f64; D]>,
    ) -> Result<()> {
        let h = self.h;
        let f = match fsal {
            Some(f) => *f,
            None => {
                self.evaluations += 1;
                force_static(self.lagrangian, q)
            }
        };
        let half: [f64; D] = std::array::from_fn(|r| p[r] + 0.5 * h * f[r]);
        let vel = self.parts.velocity_static(&half);
        for r in 0..D {
            q[r] += h * vel[r];
        }
        let f = force_static(self.lagrangian, q);
        self.evaluations += 1;
        for r in 0..D {
            p[r] = half[r] + 0.5 * h * f[r];
        }
        *fsal = Some(f);
        Ok(())
    }
}
