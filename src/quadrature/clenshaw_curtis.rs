//! Clenshaw–Curtis quadrature: interpolatory at the Chebyshev extrema (docs/DESIGN.md §2).

use super::{Quadrature, QuadratureKind, QuadratureRule};
use crate::error::Result;

/// Clenshaw–Curtis quadrature with m points on [0, 1].
///
/// For m ≥ 2 the nodes are the Chebyshev extrema τ_j = (1 − cos(jπ/N))/2, N = m − 1 (both ends
/// included), and the weights are those of the interpolating polynomial, by the explicit
/// cosine-sum formula of Trefethen's `clencurt` (*Spectral Methods in MATLAB*, 2000, ch. 12;
/// Waldvogel 2006 gives the equivalent FFT form). The rule is exact to degree m − 1, and to
/// degree m when m is odd (a symmetric rule integrates the next odd degree for free).
/// m = 1 is the midpoint rule (degree 1).
///
/// ```
/// use galerkin_vi::quadrature::{ClenshawCurtis, Quadrature};
/// let rule = ClenshawCurtis::new(5).unwrap().rule().unwrap();
/// assert_eq!(rule.degree, 5);
/// // N = 4: end weights 1/(N² − 1) on [−1, 1], halved on [0, 1].
/// assert!((rule.weights[0] - 1.0 / 30.0).abs() < 1e-15);
/// assert!((rule.integrate(|t| t.powi(5)) - 1.0 / 6.0).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ClenshawCurtis {
    points: usize,
}

impl ClenshawCurtis {
    /// The largest number of points accepted (the weights cost O(m²)).
    pub const MAX_POINTS: usize = 20_000;

    /// The rule with 1 ≤ m ≤ [`MAX_POINTS`](ClenshawCurtis::MAX_POINTS) points.
    pub fn new(points: usize) -> Result<Self> {
        super::check_points("Clenshaw–Curtis", points, 1, Self::MAX_POINTS)?;
        Ok(ClenshawCurtis { points })
    }
}

impl Quadrature for ClenshawCurtis {
    fn points(&self) -> usize {
        self.points
    }

    fn degree_of_exactness(&self) -> usize {
        let m = self.points;
        if m % 2 == 1 { m } else { m - 1 }
    }

    fn name(&self) -> String {
        format!("clenshaw-curtis ({} points)", self.points)
    }

    fn rule(&self) -> Result<QuadratureRule> {
        let m = self.points;
        let (nodes, weights) = if m == 1 {
            (vec![0.5], vec![1.0])
        } else {
            let big_n = m - 1;
            let nf = big_n as f64;
            let pi = std::f64::consts::PI;
            // τ_j = sin²(jπ/(2N)): increasing, exact at the ends and symmetric.
            let nodes: Vec<f64> = (0..m)
                .map(|j| {
                    let s = (0.5 * pi * j as f64 / nf).sin();
                    s * s
                })
                .collect();
            let mut weights = vec![0.0; m];
            // Weights on [−1, 1] (clencurt), halved at the end for [0, 1].
            let end = if big_n.is_multiple_of(2) {
                1.0 / (nf * nf - 1.0)
            } else {
                1.0 / (nf * nf)
            };
            weights[0] = 0.5 * end;
            weights[big_n] = 0.5 * end;
            for (j, w) in weights.iter_mut().enumerate().take(big_n).skip(1) {
                let theta = pi * j as f64 / nf;
                let mut v = 1.0;
                for k in 1..=(big_n - 1) / 2 {
                    let kf = k as f64;
                    v -= 2.0 * (2.0 * kf * theta).cos() / (4.0 * kf * kf - 1.0);
                }
                if big_n.is_multiple_of(2) {
                    v -= (nf * theta).cos() / (nf * nf - 1.0);
                }
                *w = v / nf; // 2v/N on [−1, 1], halved
            }
            (nodes, weights)
        };
        let rule = QuadratureRule {
            family: QuadratureKind::ClenshawCurtis.as_str().into(),
            nodes,
            weights,
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
        for m in [1, 2, 3, 4, 5, 6, 9, 16, 17, 32, 65] {
            let rule = ClenshawCurtis::new(m).unwrap().rule().unwrap();
            assert_eq!(rule.len(), m);
            assert!(rule.nodes.windows(2).all(|w| w[0] < w[1]));
            assert!(rule.weights.iter().all(|&w| w > 0.0));
            assert_sharp_degree(&rule);
        }
    }

    #[test]
    fn trapezoid_and_simpson_are_special_cases() {
        let r2 = ClenshawCurtis::new(2).unwrap().rule().unwrap();
        assert_eq!(r2.nodes, vec![0.0, 1.0]);
        assert!((r2.weights[0] - 0.5).abs() < 1e-16 && (r2.weights[1] - 0.5).abs() < 1e-16);
        let r3 = ClenshawCurtis::new(3).unwrap().rule().unwrap();
        for (w, want) in r3.weights.iter().zip([1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0]) {
            assert!((w - want).abs() < 1e-15);
        }
    }

    #[test]
    fn rejects_bad_sizes() {
        assert!(ClenshawCurtis::new(0).is_err());
        assert!(ClenshawCurtis::new(ClenshawCurtis::MAX_POINTS + 1).is_err());
    }
}
