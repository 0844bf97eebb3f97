//! The composite trapezoid rule (docs/DESIGN.md §2): degree 1, but spectrally accurate for smooth
//! periodic integrands.

use super::{Quadrature, QuadratureKind, QuadratureRule};
use crate::error::Result;

/// The composite trapezoid rule with m ≥ 2 equally spaced points τ_j = j/(m − 1) on [0, 1]
/// (both ends included): weights 1/(m − 1), halved at the ends. Exact only to degree 1, so the
/// integrator rejects it for polynomial bases (`GviError::QuadratureTooWeak`); with the
/// [`Fourier`](crate::basis::Fourier) basis it is an inexpensive, non-exact choice.
///
/// ```
/// use galerkin_vi::quadrature::{Quadrature, Trapezoid};
/// let rule = Trapezoid::new(5).unwrap().rule().unwrap();
/// assert_eq!(rule.degree, 1);
/// assert_eq!(rule.nodes, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
/// assert!((rule.integrate(|t| 3.0 * t - 1.0) - 0.5).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Trapezoid {
    points: usize,
}

impl Trapezoid {
    /// The largest number of points accepted.
    pub const MAX_POINTS: usize = 1_000_000;

    /// The rule with 2 ≤ m ≤ [`MAX_POINTS`](Trapezoid::MAX_POINTS) points.
    pub fn new(points: usize) -> Result<Self> {
        super::check_points("the trapezoid rule", points, 2, Self::MAX_POINTS)?;
        Ok(Trapezoid { points })
    }
}

impl Quadrature for Trapezoid {
    fn points(&self) -> usize {
        self.points
    }

    fn degree_of_exactness(&self) -> usize {
        1
    }

    fn name(&self) -> String {
        format!("trapezoid ({} points)", self.points)
    }

    fn rule(&self) -> Result<QuadratureRule> {
        let m = self.points;
        let intervals = (m - 1) as f64;
        let nodes: Vec<f64> = (0..m).map(|j| j as f64 / intervals).collect();
        let weights: Vec<f64> = (0..m)
            .map(|j| {
                if j == 0 || j == m - 1 {
                    0.5 / intervals
                } else {
                    1.0 / intervals
                }
            })
            .collect();
        let rule = QuadratureRule {
            family: QuadratureKind::Trapezoid.as_str().into(),
            nodes,
            weights,
            degree: 1,
        };
        rule.validate()?;
        Ok(rule)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::exactness_tests::assert_sharp_degree;

    #[test]
    fn degree_is_exact_and_sharp() {
        for m in [2, 3, 4, 10, 101, 256] {
            let rule = Trapezoid::new(m).unwrap().rule().unwrap();
            assert_eq!(rule.len(), m);
            assert_sharp_degree(&rule);
        }
    }

    #[test]
    fn spectral_for_periodic_integrands() {
        // ∫₀¹ exp(sin 2πτ) dτ = I₀(1) = 1.2660658777520082…
        let rule = Trapezoid::new(21).unwrap().rule().unwrap();
        let got = rule.integrate(|t| (2.0 * std::f64::consts::PI * t).sin().exp());
        assert!((got - 1.266_065_877_752_008_4).abs() < 1e-14, "{got}");
    }

    #[test]
    fn rejects_bad_sizes() {
        assert!(Trapezoid::new(0).is_err());
        assert!(Trapezoid::new(1).is_err());
    }
}
