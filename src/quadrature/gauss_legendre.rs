//! Gauss–Legendre quadrature (nodes and weights from the `gauss-quad` crate).

use super::{Quadrature, QuadratureKind, QuadratureRule};
use crate::error::{GviError, Result};
use std::num::NonZeroUsize;

/// Gauss–Legendre quadrature with m points mapped to [0, 1]: exact to degree 2m − 1.
///
/// The paper's spectral method uses m = 2n points for n basis functions; the stage matrix is
/// invertible as soon as m ≥ n − 1 (the rule then integrates φ_a'φ_b', of degree 2n − 4, exactly).
///
/// ```
/// use galerkin_vi::quadrature::{GaussLegendre, Quadrature};
/// let rule = GaussLegendre::new(3).unwrap().rule().unwrap();
/// assert_eq!(rule.degree, 5);
/// assert!((rule.integrate(|t| t.powi(5)) - 1.0 / 6.0).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GaussLegendre {
    points: NonZeroUsize,
}

impl GaussLegendre {
    /// The largest number of points accepted.
    pub const MAX_POINTS: usize = 100_000;

    /// The rule with m ≥ 1 points.
    pub fn new(points: usize) -> Result<Self> {
        super::check_points("Gauss–Legendre", points, 1, Self::MAX_POINTS)?;
        NonZeroUsize::new(points)
            .map(|p| GaussLegendre { points: p })
            .ok_or_else(|| GviError::InvalidQuadrature {
                reason: "Gauss–Legendre needs at least one point".into(),
            })
    }
}

impl Quadrature for GaussLegendre {
    fn points(&self) -> usize {
        self.points.get()
    }

    fn degree_of_exactness(&self) -> usize {
        2 * self.points.get() - 1
    }

    fn name(&self) -> String {
        format!("gauss-legendre ({} points)", self.points)
    }

    fn rule(&self) -> Result<QuadratureRule> {
        let gl = gauss_quad::legendre::GaussLegendre::new(self.points);
        let mut pairs: Vec<(f64, f64)> =
            gl.iter().map(|(x, w)| (0.5 * (x + 1.0), 0.5 * w)).collect();
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let rule = QuadratureRule {
            family: QuadratureKind::GaussLegendre.as_str().into(),
            nodes: pairs.iter().map(|p| p.0).collect(),
            weights: pairs.iter().map(|p| p.1).collect(),
            degree: self.degree_of_exactness(),
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
        for m in [1, 2, 3, 5, 8, 13, 20] {
            let rule = GaussLegendre::new(m).unwrap().rule().unwrap();
            assert_sharp_degree(&rule);
        }
    }

    #[test]
    fn rejects_zero_points() {
        assert!(GaussLegendre::new(0).is_err());
    }
}
