//! The Fermi–Pasta–Ulam problem with stiff and soft springs, in the form of Hairer, Lubich and
//! Wanner, *Geometric Numerical Integration* (2nd ed.), §I.5.1 and ch. XIII.
//!
//! 2m unit masses in a chain with fixed ends, joined alternately by stiff linear springs
//! (constant ω²) and soft cubic springs. In the book's variables
//! x_{0,i} = (q_{2i} + q_{2i−1})/√2 (the centre of stiff spring i) and
//! x_{1,i} = (q_{2i} − q_{2i−1})/√2 (its elongation), with conjugate momenta y, the
//! Hamiltonian is (GNI eq. (I.5.2))
//!
//! H = ½ Σ (y_{0,i}² + y_{1,i}²) + (ω²/2) Σ x_{1,i}²
//!     + ¼ [ (x_{0,1} − x_{1,1})⁴ + Σ_{i=1}^{m−1} (x_{0,i+1} − x_{1,i+1} − x_{0,i} − x_{1,i})⁴
//!           + (x_{0,m} + x_{1,m})⁴ ].
//!
//! The configuration is ordered (x_{0,1} … x_{0,m}, x_{1,1} … x_{1,m}), so with m = 3 the
//! book's initial value of Fig. I.5.2 is q₁ = 1, p₁ = 1, q₄ = 1/ω, p₄ = 1, all else 0
//! ([`Fpu::hlw_initial_state`]). The energies of the stiff springs,
//! I_j = ½ (y_{1,j}² + ω² x_{1,j}²), exchange energy on the slow time scale ω, while their
//! sum I = I₁ + … + I_m is an adiabatic invariant: I(t) − I(0) = O(1/ω) for times
//! exponentially long in ω (GNI §XIII.2 and Theorem XIII.6.2 for numerical methods).
//!
//! [`Fpu::with_frequencies`] gives each stiff spring its own frequency ω_j (stiffness ω_j²):
//! the same chain with fast coordinate blocks that oscillate at different frequencies, the test
//! case of an enriched basis with several frequencies (docs/guide/enriched-bases.md). Springs of
//! equal frequency exchange energy as above; between different frequencies the exchange is
//! off-resonance, and the oscillatory energy of each group of equal frequency stays near its
//! initial value.

use super::{System, positive};
use crate::error::{GviError, Result};
use crate::lagrangian::Mechanical;
use nalgebra::DMatrix;
use num_dual::DualNum;

/// The Fermi–Pasta–Ulam chain of m stiff springs with stiffness ω² — or ω_j², one frequency
/// per spring ([`with_frequencies`](Fpu::with_frequencies)) — (D = 2m).
///
/// ```
/// use galerkin_vi::systems::{Fpu, System};
/// let fpu = Fpu::new(3, 50.0).unwrap();
/// let (q, p) = fpu.hlw_initial_state();
/// let mut inv = vec![0.0; fpu.invariant_names().len()];
/// fpu.invariants(&q, &p, &mut inv);
/// // I = I₁ = ½ (1 + ω² / ω²) = 1 at the start.
/// assert_eq!(fpu.invariant_names()[1], "oscillatory_energy");
/// assert!((inv[1] - 1.0).abs() < 1e-15 && (inv[2] - 1.0).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Fpu {
    m: usize,
    /// The stiff frequencies ω_1 … ω_m.
    omegas: Vec<f64>,
    /// The soft springs' elongations d_k = c_k · x, k = 0 … m, as (index, coefficient) pairs.
    springs: Vec<[(usize, f64); 4]>,
}

/// Invariant names: energy, I and I₁ … I₈.
const NAMES: [&str; 10] = [
    "energy",
    "oscillatory_energy",
    "I1",
    "I2",
    "I3",
    "I4",
    "I5",
    "I6",
    "I7",
    "I8",
];

impl Fpu {
    /// The largest m accepted (the invariants are named I1 … I8).
    pub const MAX_SPRINGS: usize = 8;

    /// m stiff springs (1 ≤ m ≤ [`MAX_SPRINGS`](Self::MAX_SPRINGS)) of frequency ω > 0.
    ///
    /// Errors: [`GviError::InvalidParameter`] for ω not finite and positive (`omega`) or m out
    /// of range (`springs`).
    pub fn new(m: usize, omega: f64) -> Result<Self> {
        if !(1..=Self::MAX_SPRINGS).contains(&m) {
            return Err(GviError::InvalidParameter {
                name: "springs".into(),
                value: m as f64,
                reason: format!("need 1 ≤ m ≤ {}", Self::MAX_SPRINGS),
            });
        }
        let omega = positive("omega", omega)?;
        Self::with_frequencies(&vec![omega; m])
    }

    /// m = `omegas.len()` stiff springs (1 ≤ m ≤ [`MAX_SPRINGS`](Self::MAX_SPRINGS)), spring j
    /// of frequency ω_j > 0 (stiffness ω_j²).
    ///
    /// ```
    /// use galerkin_vi::systems::Fpu;
    /// // Two blocks of two springs, ω = 50 and ω = 20 (scene fpu-two-frequency).
    /// let fpu = Fpu::with_frequencies(&[50.0, 50.0, 20.0, 20.0]).unwrap();
    /// assert_eq!((fpu.springs(), fpu.omega()), (4, 50.0));
    /// ```
    ///
    /// Errors: as [`new`](Self::new).
    pub fn with_frequencies(omegas: &[f64]) -> Result<Self> {
        let m = omegas.len();
        if !(1..=Self::MAX_SPRINGS).contains(&m) {
            return Err(GviError::InvalidParameter {
                name: "springs".into(),
                value: m as f64,
                reason: format!("need 1 ≤ m ≤ {}", Self::MAX_SPRINGS),
            });
        }
        let omegas = omegas
            .iter()
            .map(|&w| positive("omega", w))
            .collect::<Result<Vec<f64>>>()?;
        // d_0 = x_{0,1} − x_{1,1}; d_i = x_{0,i+1} − x_{1,i+1} − x_{0,i} − x_{1,i};
        // d_m = x_{0,m} + x_{1,m}. Unused slots carry coefficient 0.
        let (x0, x1) = (|i: usize| i - 1, |i: usize| m + i - 1);
        let mut springs = Vec::with_capacity(m + 1);
        springs.push([(x0(1), 1.0), (x1(1), -1.0), (0, 0.0), (0, 0.0)]);
        for i in 1..m {
            springs.push([
                (x0(i + 1), 1.0),
                (x1(i + 1), -1.0),
                (x0(i), -1.0),
                (x1(i), -1.0),
            ]);
        }
        springs.push([(x0(m), 1.0), (x1(m), 1.0), (0, 0.0), (0, 0.0)]);
        Ok(Fpu { m, omegas, springs })
    }

    /// The book's chain: m = 3, ω = 50.
    pub fn hlw() -> Self {
        match Fpu::new(3, 50.0) {
            Ok(f) => f,
            Err(_) => unreachable!("m = 3, ω = 50 are valid"),
        }
    }

    /// The number m of stiff springs.
    pub fn springs(&self) -> usize {
        self.m
    }

    /// The stiff frequency ω (the largest of the springs' frequencies).
    pub fn omega(&self) -> f64 {
        self.omegas.iter().fold(0.0f64, |m, &w| m.max(w))
    }

    /// The stiff frequencies ω_1 … ω_m, one per spring.
    pub fn frequencies(&self) -> &[f64] {
        &self.omegas
    }

    /// The initial value of GNI Fig. I.5.2: x_{0,1} = 1, y_{0,1} = 1, x_{1,1} = 1/ω₁,
    /// y_{1,1} = 1, all else 0 (q₁, p₁, q₄, p₄ for m = 3).
    pub fn hlw_initial_state(&self) -> (Vec<f64>, Vec<f64>) {
        let d = 2 * self.m;
        let (mut q, mut p) = (vec![0.0; d], vec![0.0; d]);
        q[0] = 1.0;
        p[0] = 1.0;
        q[self.m] = 1.0 / self.omegas[0];
        p[self.m] = 1.0;
        (q, p)
    }

    /// The book's initial value with stiff spring j also excited, for each j in `springs`
    /// (0-based): x_{1,j} = 1/ω_j, y_{1,j} = 1, so I_j = 1. Spring 0 is always excited; the
    /// scene fpu-two-frequency excites the first spring of each block so that both frequencies
    /// carry energy (with the book's value alone, a block of another frequency is reached only
    /// off-resonance and stays nearly at rest). Indices ≥ m are ignored.
    pub fn excited_initial_state(&self, springs: &[usize]) -> (Vec<f64>, Vec<f64>) {
        let (mut q, mut p) = self.hlw_initial_state();
        for &j in springs.iter().filter(|&&j| j < self.m) {
            q[self.m + j] = 1.0 / self.omegas[j];
            p[self.m + j] = 1.0;
        }
        (q, p)
    }

    /// The stiff-spring energies I_j = ½ (y_{1,j}² + ω_j² x_{1,j}²), j = 1 … m, into `out`.
    pub fn oscillatory_energies(&self, q: &[f64], p: &[f64], out: &mut [f64]) {
        for (j, o) in out.iter_mut().enumerate().take(self.m) {
            let w2 = self.omegas[j] * self.omegas[j];
            let (x, y) = (q[self.m + j], p[self.m + j]);
            *o = 0.5 * (y * y + w2 * x * x);
        }
    }

    fn elongation<T: DualNum<Primitive = f64> + Copy>(spring: &[(usize, f64); 4], q: &[T]) -> T {
        spring.iter().fold(
            T::zero(),
            |acc, &(i, c)| if c == 0.0 { acc } else { acc + q[i] * c },
        )
    }
}

impl Mechanical for Fpu {
    fn degrees_of_freedom(&self) -> usize {
        2 * self.m
    }
    fn mass(&self) -> DMatrix<f64> {
        DMatrix::identity(2 * self.m, 2 * self.m)
    }
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        let stiff = q[self.m..]
            .iter()
            .zip(&self.omegas)
            .fold(T::zero(), |acc, (&x, &w)| acc + x * x * (0.5 * w * w));
        let soft = self.springs.iter().fold(T::zero(), |acc, s| {
            let d = Self::elongation(s, q);
            let d2 = d * d;
            acc + d2 * d2 * 0.25
        });
        stiff + soft
    }
    /// ∇V = ω_j² x_{1,j} (stiff) + Σ_k d_k³ c_k (soft).
    fn potential_gradient(&self, q: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        for ((o, &x), &w) in out[self.m..].iter_mut().zip(&q[self.m..]).zip(&self.omegas) {
            *o = w * w * x;
        }
        for s in &self.springs {
            let d: f64 = s.iter().map(|&(i, c)| c * q[i]).sum();
            let d3 = d * d * d;
            for &(i, c) in s.iter().filter(|(_, c)| *c != 0.0) {
                out[i] += d3 * c;
            }
        }
    }
    /// ∇²V = ω_j² on the x₁ diagonal + Σ_k 3 d_k² c_k c_kᵀ.
    fn potential_hessian(&self, q: &[f64], out: &mut [f64]) {
        let d = 2 * self.m;
        out.iter_mut().for_each(|o| *o = 0.0);
        for (i, &w) in (self.m..d).zip(&self.omegas) {
            out[i * d + i] = w * w;
        }
        for s in &self.springs {
            let e: f64 = s.iter().map(|&(i, c)| c * q[i]).sum();
            let k = 3.0 * e * e;
            for &(i, ci) in s.iter().filter(|(_, c)| *c != 0.0) {
                for &(j, cj) in s.iter().filter(|(_, c)| *c != 0.0) {
                    out[i * d + j] += k * ci * cj;
                }
            }
        }
    }
}

impl System for Fpu {
    fn name(&self) -> &'static str {
        "fpu"
    }
    /// The energy H, the total oscillatory energy I and the stiff-spring energies I_j.
    fn invariant_names(&self) -> &'static [&'static str] {
        &NAMES[..2 + self.m]
    }
    fn invariants(&self, q: &[f64], p: &[f64], out: &mut [f64]) {
        let kinetic: f64 = 0.5 * p.iter().map(|y| y * y).sum::<f64>();
        out[0] = kinetic + self.potential(q);
        self.oscillatory_energies(q, p, &mut out[2..2 + self.m]);
        out[1] = out[2..2 + self.m].iter().sum();
    }
    /// The stiff period 2π/ω (the largest ω_j).
    fn shortest_time_scale(&self, _q: &[f64], _p: &[f64]) -> Option<f64> {
        Some(std::f64::consts::TAU / self.omega())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_against_ad_and_the_book_hamiltonian() {
        let fpu = Fpu::hlw();
        let q = [0.3, -0.7, 0.4, 0.02, -0.01, 0.03];
        crate::systems::derivative_tests::check_against_ad(&fpu, &q);
        // The potential in the original chain variables q_1 … q_6 (GNI eq. (I.5.1)):
        // ω²/4 Σ (q_{2i} − q_{2i−1})² + Σ_{i=0}^{3} (q_{2i+1} − q_{2i})⁴, q_0 = q_7 = 0.
        let r = std::f64::consts::FRAC_1_SQRT_2;
        let mut chain = [0.0; 8];
        for i in 1..=3 {
            let (x0, x1) = (q[i - 1], q[3 + i - 1]);
            chain[2 * i - 1] = r * (x0 - x1);
            chain[2 * i] = r * (x0 + x1);
        }
        let w = fpu.omega();
        let stiff: f64 = (1..=3)
            .map(|i| 0.25 * w * w * (chain[2 * i] - chain[2 * i - 1]).powi(2))
            .sum();
        let soft: f64 = (0..=3)
            .map(|i| (chain[2 * i + 1] - chain[2 * i]).powi(4))
            .sum();
        let v: f64 = fpu.potential(&q[..]);
        assert!(
            (v - stiff - soft).abs() < 1e-13 * v.abs(),
            "{v} vs {}",
            stiff + soft
        );
    }

    #[test]
    fn invariants_and_errors() {
        let fpu = Fpu::hlw();
        let (q, p) = fpu.hlw_initial_state();
        assert_eq!(q, vec![1.0, 0.0, 0.0, 0.02, 0.0, 0.0]);
        assert_eq!(p, vec![1.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
        let mut inv = [0.0; 5];
        fpu.invariants(&q, &p, &mut inv);
        // H = ½(1 + 1) + ½ω²/ω² + ¼((1 − 1/ω)⁴ + (1 + 1/ω)⁴)... the d_1 spring: −x01 − x11.
        let d0 = 1.0 - 0.02;
        let d1 = -1.0 - 0.02;
        let want = 1.0 + 0.5 + 0.25 * (d0.powi(4) + d1.powi(4));
        assert!((inv[0] - want).abs() < 1e-14, "{} vs {want}", inv[0]);
        assert_eq!(inv[1..], [1.0, 1.0, 0.0, 0.0]);
        assert!(Fpu::new(0, 50.0).is_err() && Fpu::new(9, 50.0).is_err());
        assert!(Fpu::new(3, 0.0).is_err() && Fpu::new(3, f64::NAN).is_err());
        assert!(Fpu::with_frequencies(&[]).is_err());
        assert!(Fpu::with_frequencies(&[50.0, -1.0]).is_err());
    }

    #[test]
    fn frequencies_per_spring() {
        let two = Fpu::with_frequencies(&[50.0, 50.0, 20.0, 20.0]).unwrap();
        let q = [0.3, -0.7, 0.4, 0.1, 0.02, -0.01, 0.03, 0.05];
        crate::systems::derivative_tests::check_against_ad(&two, &q);
        // Equal frequencies are the single-frequency chain, bit for bit.
        assert_eq!(Fpu::with_frequencies(&[50.0; 3]).unwrap(), Fpu::hlw());
        let (q, p) = two.excited_initial_state(&[2]);
        assert_eq!(q, vec![1.0, 0.0, 0.0, 0.0, 0.02, 0.0, 0.05, 0.0]);
        assert_eq!(p, vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0]);
        let mut inv = [0.0; 6];
        two.invariants(&q, &p, &mut inv);
        assert_eq!(inv[1..], [2.0, 1.0, 0.0, 1.0, 0.0]);
        assert_eq!(
            two.shortest_time_scale(&q, &p),
            Some(std::f64::consts::TAU / 50.0)
        );
    }
}
