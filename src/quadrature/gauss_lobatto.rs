//! Gauss–Lobatto (Legendre–Gauss–Lobatto) quadrature: both ends plus the Gauss–Jacobi(1, 1)
//! nodes, exact to degree 2m − 3 (docs/DESIGN.md §2, quadrature choices).

use super::{Quadrature, QuadratureKind, QuadratureRule};
use crate::error::{GviError, Result};
use gauss_quad::jacobi::GaussJacobi;
use std::num::NonZeroUsize;

/// Gauss–Lobatto quadrature with m ≥ 2 points on [0, 1], including both ends: exact to degree
/// 2m − 3.
///
/// On [−1, 1] the interior nodes are the zeros of P'_{m−1}, i.e. the m − 2 Gauss–Jacobi nodes
/// for the weight (1 − x)(1 + x) (taken from `gauss_quad`, then polished by Newton's method on
/// P'_{m−1}), and every weight is 2 / (m(m − 1) P_{m−1}(x_j)²); the rule is mapped to [0, 1]
/// by τ = (1 + x)/2 with halved weights.
///
/// For m ≤ [`GOLUB_WELSCH_MAX`](GaussLobatto::GOLUB_WELSCH_MAX) the interior nodes come from
/// `gauss_quad`'s Golub–Welsch eigenvalue solve (cubic cost in m: 0.3 s at m = 513, 26 s at
/// m = 2049); above it, from Newton's method on (x² − 1) P'_{m−1}(x) started at the
/// Chebyshev–Lobatto points (as in Trefethen's `lglnodes`), quadratic cost. Both paths agree
/// to round-off (tested).
///
/// ```
/// use galerkin_vi::quadrature::{GaussLobatto, Quadrature};
/// let rule = GaussLobatto::new(4).unwrap().rule().unwrap();
/// assert_eq!(rule.degree, 5);
/// assert_eq!((rule.nodes[0], rule.nodes[3]), (0.0, 1.0));
/// assert!((rule.integrate(|t| t.powi(5)) - 1.0 / 6.0).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GaussLobatto {
    points: usize,
}

impl GaussLobatto {
    /// The largest number of points accepted (enough for the default 2n + 1 at n = 1024).
    pub const MAX_POINTS: usize = 4097;

    /// The largest m for which the nodes come from the Golub–Welsch solve of `gauss_quad`.
    pub const GOLUB_WELSCH_MAX: usize = 512;

    /// The rule with 2 ≤ m ≤ [`MAX_POINTS`](GaussLobatto::MAX_POINTS) points.
    pub fn new(points: usize) -> Result<Self> {
        super::check_points("Gauss–Lobatto", points, 2, Self::MAX_POINTS)?;
        Ok(GaussLobatto { points })
    }
}

/// (P_N(x), P_N'(x)) by the three-term recurrence and P_N' = N (x P_N − P_{N−1}) / (x² − 1)
/// replaced by the derivative recurrence P'_{k+1} = P'_{k−1} + (2k + 1) P_k (valid at x = ±1).
pub(crate) fn legendre_with_derivative(big_n: usize, x: f64) -> (f64, f64) {
    if big_n == 0 {
        return (1.0, 0.0);
    }
    let (mut p0, mut p1) = (1.0, x);
    let (mut d0, mut d1) = (0.0, 1.0);
    for k in 1..big_n {
        let kf = k as f64;
        let p2 = ((2.0 * kf + 1.0) * x * p1 - kf * p0) / (kf + 1.0);
        let d2 = d0 + (2.0 * kf + 1.0) * p1;
        (p0, p1) = (p1, p2);
        (d0, d1) = (d1, d2);
    }
    (p1, d1)
}

/// The zeros of P'_N in (−1, 1), by Newton's method on f = x P_N − P_{N−1} = (x² − 1) P'_N / N
/// (f' = (N + 1) P_N) from the Chebyshev–Lobatto points cos(jπ/N), j = 1 … N − 1.
fn interior_nodes_by_newton(big_n: usize) -> Vec<f64> {
    let nf = big_n as f64;
    (1..big_n)
        .map(|j| {
            let mut x = (std::f64::consts::PI * j as f64 / nf).cos();
            for _ in 0..100 {
                let (p, _) = legendre_with_derivative(big_n, x);
                let (q, _) = legendre_with_derivative(big_n - 1, x);
                let dx = (x * p - q) / ((nf + 1.0) * p);
                x -= dx;
                if dx.abs() <= 1e-16 || !dx.is_finite() {
                    break;
                }
            }
            x
        })
        .collect()
}

impl Quadrature for GaussLobatto {
    fn points(&self) -> usize {
        self.points
    }

    fn degree_of_exactness(&self) -> usize {
        2 * self.points - 3
    }

    fn name(&self) -> String {
        format!("gauss-lobatto ({} points)", self.points)
    }

    fn rule(&self) -> Result<QuadratureRule> {
        let m = self.points;
        let big_n = m - 1;
        let mut xs = vec![-1.0];
        if m > Self::GOLUB_WELSCH_MAX {
            xs.extend(interior_nodes_by_newton(big_n));
        } else if let Some(interior) = NonZeroUsize::new(m - 2) {
            let one = gauss_quad::FiniteAboveNegOneF64::new(1.0).ok_or_else(|| {
                GviError::InvalidQuadrature {
                    reason: "Gauss–Jacobi parameter".into(),
                }
            })?;
            let gj = GaussJacobi::new(interior, one, one);
            let nf = big_n as f64;
            for &(x0, _) in gj.iter() {
                // Newton polish on P'_N: P''_N = (2x P'_N − N(N+1) P_N) / (1 − x²).
                let mut x = x0;
                for _ in 0..3 {
                    let (p, d) = legendre_with_derivative(big_n, x);
                    let dd = (2.0 * x * d - nf * (nf + 1.0) * p) / (1.0 - x * x);
                    if dd != 0.0 && dd.is_finite() {
                        let step = d / dd;
                        if step.abs() < 1e-3 {
                            x -= step;
                        }
                    }
                }
                xs.push(x);
            }
        }
        xs.push(1.0);
        xs.sort_by(f64::total_cmp);
        let scale = 2.0 / ((m * (m - 1)) as f64);
        let mut nodes = Vec::with_capacity(m);
        let mut weights = Vec::with_capacity(m);
        for &x in &xs {
            let (p, _) = legendre_with_derivative(big_n, x);
            nodes.push(0.5 * (1.0 + x));
            weights.push(0.5 * scale / (p * p));
        }
        let rule = QuadratureRule {
            family: QuadratureKind::GaussLobatto.as_str().into(),
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
        for m in [2, 3, 4, 5, 8, 13, 21, 33] {
            let rule = GaussLobatto::new(m).unwrap().rule().unwrap();
            assert_eq!(rule.len(), m);
            assert_eq!(rule.nodes[0], 0.0);
            assert_eq!(rule.nodes[m - 1], 1.0);
            assert!(rule.nodes.windows(2).all(|w| w[0] < w[1]));
            assert_sharp_degree(&rule);
        }
    }

    #[test]
    fn nodes_are_symmetric_and_known_for_small_m() {
        // m = 5: interior nodes 0, ±√(3/7) on [−1, 1]; weights 1/10, 49/90, 32/45 (halved).
        let rule = GaussLobatto::new(5).unwrap().rule().unwrap();
        let x1 = 0.5 * (1.0 - (3.0f64 / 7.0).sqrt());
        assert!((rule.nodes[1] - x1).abs() < 1e-15);
        assert!((rule.nodes[2] - 0.5).abs() < 1e-15);
        assert!((rule.weights[0] - 0.05).abs() < 1e-15);
        assert!((rule.weights[1] - 49.0 / 180.0).abs() < 1e-15);
        assert!((rule.weights[2] - 16.0 / 45.0).abs() < 1e-15);
        let big = GaussLobatto::new(129).unwrap().rule().unwrap();
        for j in 0..129 {
            assert!((big.nodes[j] + big.nodes[128 - j] - 1.0).abs() < 1e-14);
            assert!((big.weights[j] - big.weights[128 - j]).abs() < 1e-15);
        }
        assert_sharp_degree(&big);
    }

    #[test]
    fn newton_nodes_agree_with_golub_welsch() {
        for m in [3, 4, 9, 64, 301] {
            let big_n = m - 1;
            let gj = GaussLobatto::new(m).unwrap().rule().unwrap();
            let mut newton = interior_nodes_by_newton(big_n);
            newton.sort_by(f64::total_cmp);
            for (j, x) in newton.iter().enumerate() {
                let tau = 0.5 * (1.0 + x);
                assert!((tau - gj.nodes[j + 1]).abs() < 1e-15, "m = {m}, node {j}");
            }
        }
        // The Newton path (m > GOLUB_WELSCH_MAX) is exact and sharp too, and fast.
        let start = std::time::Instant::now();
        let big = GaussLobatto::new(GaussLobatto::MAX_POINTS)
            .unwrap()
            .rule()
            .unwrap();
        assert!(start.elapsed().as_secs_f64() < 5.0);
        assert!(big.nodes.windows(2).all(|w| w[0] < w[1]));
        let rule = GaussLobatto::new(600).unwrap().rule().unwrap();
        assert_sharp_degree(&rule);
    }

    #[test]
    fn rejects_bad_sizes() {
        assert!(GaussLobatto::new(0).is_err());
        assert!(GaussLobatto::new(1).is_err());
        assert!(GaussLobatto::new(GaussLobatto::MAX_POINTS + 1).is_err());
    }
}
