//! High-order symplectic compositions of Störmer–Verlet, Φ_h = Φ_{γ_s h} ∘ … ∘ Φ_{γ_1 h}
//! with symmetric coefficients γ (Hairer, Lubich & Wanner, *Geometric Numerical
//! Integration*, §V.3).
//!
//! - [`CompositionScheme::Yoshida6`]: order 6, 7 stages, Yoshida's "solution A"
//!   (H. Yoshida, *Construction of higher order symplectic integrators*, Phys. Lett. A 150
//!   (1990) 262–268, Table 1).
//! - [`CompositionScheme::KahanLi8`]: order 8, 15 stages, Kahan & Li's s15odr8
//!   (W. Kahan and R.-C. Li, *Composition constants for raising the orders of unconventional
//!   schemes for ordinary differential equations*, Math. Comp. 66 (1997) 1089–1099; the
//!   coefficients as printed in Hairer–Lubich–Wanner, §V.3.2, eq. (3.12)).
//!
//! Adjacent half-kicks of consecutive Verlet stages are merged, and the force at the end of a
//! step is reused at the start of the next (first same as last), so a step costs s force
//! evaluations.

use super::{CanonicalParts, OneStepMethod, StaticKernel, force_static};
use crate::error::Result;
use crate::lagrangian::Lagrangian;

/// Yoshida (1990), solution A: w₁, w₂, w₃; w₀ = 1 − 2(w₁ + w₂ + w₃).
const YOSHIDA6_W: [f64; 3] = [-1.17767998417887, 0.235573213359357, 0.784513610477560];

/// Kahan & Li (1997) s15odr8: γ₁ … γ₈ (γ_{16−i} = γ_i), as published (26 digits).
#[allow(clippy::excessive_precision)]
const KAHAN_LI8: [f64; 8] = [
    0.741_670_364_350_612_953_448_227_8,
    -0.409_100_825_800_031_593_997_300_1,
    0.190_754_710_296_238_379_953_876_26,
    -0.573_862_471_116_082_266_656_387_73,
    0.299_064_181_303_655_923_844_463_54,
    0.334_624_918_245_298_183_784_957_98,
    0.315_293_092_396_766_596_632_056_66,
    -0.796_887_939_352_916_354_019_788_84,
];

/// Which composition.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CompositionScheme {
    /// Yoshida's order-6, 7-stage composition (solution A).
    Yoshida6,
    /// Kahan–Li's order-8, 15-stage composition (s15odr8).
    KahanLi8,
}

impl CompositionScheme {
    /// Both schemes.
    pub const ALL: [CompositionScheme; 2] =
        [CompositionScheme::Yoshida6, CompositionScheme::KahanLi8];

    /// The stage coefficients γ_1 … γ_s (symmetric, summing to 1).
    pub fn coefficients(self) -> Vec<f64> {
        let half: Vec<f64> = match self {
            CompositionScheme::Yoshida6 => {
                let [w1, w2, w3] = YOSHIDA6_W;
                vec![w3, w2, w1, 1.0 - 2.0 * (w1 + w2 + w3)]
            }
            CompositionScheme::KahanLi8 => KAHAN_LI8.to_vec(),
        };
        let mut all = half.clone();
        all.extend(half.iter().rev().skip(1));
        all
    }

    /// The classical order.
    pub fn order(self) -> usize {
        match self {
            CompositionScheme::Yoshida6 => 6,
            CompositionScheme::KahanLi8 => 8,
        }
    }

    /// Short name, e.g. `yoshida-6`.
    pub fn as_str(self) -> &'static str {
        match self {
            CompositionScheme::Yoshida6 => "yoshida-6",
            CompositionScheme::KahanLi8 => "kahan-li-8",
        }
    }
}

/// A symmetric composition of kick–drift–kick Störmer–Verlet (symplectic, order 6 or 8).
///
/// ```
/// use galerkin_vi::baselines::{Composition, CompositionScheme, OneStepMethod};
/// use galerkin_vi::systems::HarmonicOscillator;
///
/// let ho = HarmonicOscillator::unit();
/// let mut m = Composition::new(&ho, CompositionScheme::KahanLi8, 0.1)?;
/// let (mut q, mut p) = ([0.0], [0.0]);
/// m.step(0.0, &[1.0], &[0.0], &mut q, &mut p)?;
/// assert!((q[0] - 0.1f64.cos()).abs() < 1e-12);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Composition<'a, L: Lagrangian> {
    lagrangian: &'a L,
    scheme: CompositionScheme,
    gamma: Vec<f64>,
    h: f64,
    parts: CanonicalParts,
    evaluations: usize,
    force: Vec<f64>,
    vel: Vec<f64>,
    /// Position at which `cached_force` was evaluated (first same as last).
    cached_q: Vec<f64>,
    cached_force: Vec<f64>,
    has_cache: bool,
}

impl<'a, L: Lagrangian> Composition<'a, L> {
    /// The composition `scheme` with step h for a mechanical Lagrangian.
    pub fn new(lagrangian: &'a L, scheme: CompositionScheme, h: f64) -> Result<Self> {
        let parts = CanonicalParts::new(lagrangian, h)?;
        let d = parts.d;
        Ok(Composition {
            lagrangian,
            scheme,
            gamma: scheme.coefficients(),
            h,
            parts,
            evaluations: 0,
            force: vec![0.0; d],
            vel: vec![0.0; d],
            cached_q: vec![0.0; d],
            cached_force: vec![0.0; d],
            has_cache: false,
        })
    }
}

impl<L: Lagrangian> OneStepMethod for Composition<'_, L> {
    fn name(&self) -> String {
        format!("{} (h = {})", self.scheme.as_str(), self.h)
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
        if self.has_cache && self.cached_q.as_slice() == q {
            self.force.copy_from_slice(&self.cached_force);
        } else {
            self.lagrangian.force(q, &mut self.force);
            self.evaluations += 1;
        }
        q_next.copy_from_slice(q);
        p_next.copy_from_slice(p);
        let s = self.gamma.len();
        let mut kick = 0.5 * self.gamma[0] * h;
        for k in 0..s {
            for r in 0..d {
                p_next[r] += kick * self.force[r];
            }
            self.parts.velocity(p_next, &mut self.vel);
            let drift = self.gamma[k] * h;
            for r in 0..d {
                q_next[r] += drift * self.vel[r];
            }
            self.lagrangian.force(q_next, &mut self.force);
            self.evaluations += 1;
            kick = 0.5 * h * (self.gamma[k] + self.gamma.get(k + 1).copied().unwrap_or(0.0));
        }
        for r in 0..d {
            p_next[r] += kick * self.force[r];
        }
        self.cached_q.copy_from_slice(q_next);
        self.cached_force.copy_from_slice(&self.force);
        self.has_cache = true;
        Ok(())
    }
}

impl<L: Lagrangian> StaticKernel for Composition<'_, L> {
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
        let mut f = match fsal {
            Some(f) => *f,
            None => {
                self.evaluations += 1;
                force_static(self.lagrangian, q)
            }
        };
        let gamma = &self.gamma;
        let s = gamma.len();
        let mut kick = 0.5 * gamma[0] * h;
        for k in 0..s {
            for r in 0..D {
                p[r] += kick * f[r];
            }
            let vel = self.parts.velocity_static(p);
            let drift = gamma[k] * h;
            for r in 0..D {
                q[r] += drift * vel[r];
            }
            f = force_static(self.lagrangian, q);
            kick = 0.5 * h * (gamma[k] + gamma.get(k + 1).copied().unwrap_or(0.0));
        }
        self.evaluations += s;
        for r in 0..D {
            p[r] += kick * f[r];
        }
        *fsal = Some(f);
        Ok(())
    }
}
