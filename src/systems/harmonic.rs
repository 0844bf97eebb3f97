//! The harmonic oscillator L = m q̇²/2 − k q²/2 (paper §5.1).

use super::{ExactSolution, System, positive};
use crate::error::{Result, ensure_len};
use crate::lagrangian::Mechanical;
use nalgebra::DMatrix;
use num_dual::DualNum;

/// One-dimensional harmonic oscillator with mass m and stiffness k (ω = √(k/m)).
///
/// ```
/// use galerkin_vi::systems::{HarmonicOscillator, System};
/// let ho = HarmonicOscillator::unit();
/// let exact = ho.exact_solution(0.0, &[1.0], &[0.0]).unwrap().unwrap();
/// assert!((exact.position(std::f64::consts::PI)[0] + 1.0).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HarmonicOscillator {
    mass: f64,
    stiffness: f64,
}

impl HarmonicOscillator {
    /// Mass m > 0 and stiffness k > 0.
    pub fn new(mass: f64, stiffness: f64) -> Result<Self> {
        Ok(HarmonicOscillator {
            mass: positive("mass", mass)?,
            stiffness: positive("stiffness", stiffness)?,
        })
    }

    /// The paper's oscillator, m = k = 1.
    pub fn unit() -> Self {
        HarmonicOscillator {
            mass: 1.0,
            stiffness: 1.0,
        }
    }

    /// Angular frequency ω = √(k/m).
    pub fn omega(&self) -> f64 {
        (self.stiffness / self.mass).sqrt()
    }
}

impl Mechanical for HarmonicOscillator {
    fn degrees_of_freedom(&self) -> usize {
        1
    }
    fn mass(&self) -> DMatrix<f64> {
        DMatrix::from_element(1, 1, self.mass)
    }
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        q[0] * q[0] * (0.5 * self.stiffness)
    }
    fn potential_gradient(&self, q: &[f64], out: &mut [f64]) {
        out[0] = self.stiffness * q[0];
    }
    fn potential_hessian(&self, _q: &[f64], out: &mut [f64]) {
        out[0] = self.stiffness;
    }
}

impl System for HarmonicOscillator {
    fn name(&self) -> &'static str {
        "harmonic"
    }
    /// The period 2π √(m/k).
    fn shortest_time_scale(&self, _q: &[f64], _p: &[f64]) -> Option<f64> {
        Some(std::f64::consts::TAU * (self.mass / self.stiffness).sqrt())
    }
    fn invariant_names(&self) -> &'static [&'static str] {
        &["energy"]
    }
    fn invariants(&self, q: &[f64], p: &[f64], out: &mut [f64]) {
        out[0] = 0.5 * p[0] * p[0] / self.mass + 0.5 * self.stiffness * q[0] * q[0];
    }
    fn exact_solution(&self, t0: f64, q0: &[f64], p0: &[f64]) -> Result<Option<ExactSolution>> {
        ensure_len("q0", 1, q0.len())?;
        ensure_len("p0", 1, p0.len())?;
        let (w, m, q0, p0) = (self.omega(), self.mass, q0[0], p0[0]);
        Ok(Some(ExactSolution::new(move |t| {
            let (s, c) = (w * (t - t0)).sin_cos();
            let q = q0 * c + p0 / (m * w) * s;
            let p = -q0 * m * w * s + p0 * c;
            (vec![q], vec![p])
        })))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_and_exact_solution() {
        let ho = HarmonicOscillator::new(2.0, 3.0).unwrap();
        crate::systems::derivative_tests::check_against_ad(&ho, &[0.7]);
        let ex = ho.exact_solution(1.0, &[0.5], &[-0.3]).unwrap().unwrap();
        let mut e = [0.0];
        ho.invariants(&[0.5], &[-0.3], &mut e);
        for k in 0..50 {
            let t = 1.0 + 0.37 * k as f64;
            let (q, p) = ex.state(t);
            let mut ek = [0.0];
            ho.invariants(&q, &p, &mut ek);
            assert!((ek[0] - e[0]).abs() < 1e-14);
            // q̇ = p/m by central difference
            let dq = (ex.position(t + 1e-6)[0] - ex.position(t - 1e-6)[0]) / 2e-6;
            assert!((dq - p[0] / 2.0).abs() < 1e-8);
        }
        assert!(HarmonicOscillator::new(0.0, 1.0).is_err());
        assert!(HarmonicOscillator::new(1.0, f64::NAN).is_err());
    }
}
