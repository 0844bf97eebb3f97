//! The modal boundary-adapted Legendre basis (integrated Legendre polynomials), docs/DESIGN.md §2.

use super::{Basis, check_size};
use crate::error::Result;

/// Boundary-adapted modal Legendre basis of degree n − 1 (the "integrated Legendre" or
/// Babuška–Shen basis of spectral/hp element methods).
///
/// With x = 2τ − 1: φ_0 = (1 − x)/2, φ_{n−1} = (1 + x)/2 and, for k = 1 … n − 2,
/// φ_k = (P_{k+1}(x) − P_{k−1}(x)) / √(2(2k + 1)). The interior functions vanish at both ends
/// because P_j(±1) = (±1)^j, and since P'_{k+1} − P'_{k−1} = (2k + 1) P_k their derivatives are
/// dφ_k/dτ = 2 √((2k + 1)/2) P_k(x): the interior block of the kinetic matrix
/// ∫₀¹ φ_a' φ_b' dτ is exactly 2·I. The Legendre polynomials come from the three-term
/// recurrence (k + 1) P_{k+1} = (2k + 1) x P_k − k P_{k−1}, linear cost in n and stable for
/// x ∈ [−1, 1]; it also extrapolates (τ outside [0, 1]). Coefficients are modal, not nodal:
/// [`CurveFit`](crate::basis::CurveFit) obtains them by interpolation at Chebyshev–Lobatto
/// points.
///
/// ```
/// use galerkin_vi::basis::{Basis, Legendre};
/// let b = Legendre::new(6).unwrap();
/// let (mut v, mut d) = (vec![0.0; 6], vec![0.0; 6]);
/// b.eval(0.25, &mut v, &mut d);
/// // φ_1 = (P_2 − P_0)/√6 = (3x² − 3)/(2√6) at x = −1/2.
/// assert!((v[1] - (3.0 * 0.25 - 3.0) / (2.0 * 6f64.sqrt())).abs() < 1e-15);
/// // The end functions are linear.
/// assert_eq!((v[0], v[5], d[0], d[5]), (0.75, 0.25, -1.0, 1.0));
/// ```
#[derive(Debug, Clone)]
pub struct Legendre {
    /// 1/√(2(2k + 1)) for k = 0 … n − 2 (entry 0 unused).
    scale: Vec<f64>,
    n: usize,
}

impl Legendre {
    /// The largest n accepted.
    pub const MAX_N: usize = 1024;

    /// The basis with n ≥ 2 functions (degree n − 1).
    pub fn new(n: usize) -> Result<Self> {
        check_size("legendre", n, 2, Self::MAX_N)?;
        let scale = (0..n)
            .map(|k| 1.0 / (2.0 * (2 * k + 1) as f64).sqrt())
            .collect();
        Ok(Legendre { scale, n })
    }
}

impl Basis for Legendre {
    fn len(&self) -> usize {
        self.n
    }

    fn name(&self) -> &'static str {
        "legendre"
    }

    fn eval(&self, tau: f64, values: &mut [f64], derivatives: &mut [f64]) {
        let n = self.n;
        let x = 2.0 * tau - 1.0;
        // Rolling P_{k−1}, P_k; at step k compute P_{k+1} and fill interior function k.
        let (mut p_prev, mut p) = (1.0, x);
        for k in 1..n - 1 {
            let kf = k as f64;
            let p_next = ((2.0 * kf + 1.0) * x * p - kf * p_prev) / (kf + 1.0);
            let s = self.scale[k];
            values[k] = (p_next - p_prev) * s;
            // dφ_k/dτ = 2 (2k + 1) P_k s.
            derivatives[k] = 2.0 * (2.0 * kf + 1.0) * s * p;
            (p_prev, p) = (p, p_next);
        }
        values[0] = 0.5 * (1.0 - x);
        derivatives[0] = -1.0;
        values[n - 1] = 0.5 * (1.0 + x);
        derivatives[n - 1] = 1.0;
    }

    fn polynomial_degree(&self) -> Option<usize> {
        Some(self.n - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::basis::contract_tests::check_contract;
    use crate::basis::{ChebyshevLagrange, CurveFit};
    use crate::quadrature::{GaussLegendre, Quadrature};

    /// P_k(cos θ) = Σ_j g_j g_{k−j} cos((k − 2j)θ), g_j = C(2j, j)/4^j: a positive-coefficient
    /// closed form independent of the recurrence (no cancellation: the terms sum to 1 at θ = 0).
    fn legendre_trig(k: usize, theta: f64) -> f64 {
        let mut g = vec![1.0; k + 1];
        for j in 1..=k {
            g[j] = g[j - 1] * (2 * j - 1) as f64 / (2 * j) as f64;
        }
        (0..=k)
            .map(|j| g[j] * g[k - j] * ((k as f64 - 2.0 * j as f64) * theta).cos())
            .sum()
    }

    #[test]
    fn contract_and_derivatives() {
        for n in [2, 3, 4, 7, 16, 33, 64, 128] {
            let b = Legendre::new(n).unwrap();
            let fd = check_contract(&b);
            assert!(fd < 1e-6, "n = {n}: finite-difference mismatch {fd}");
        }
    }

    #[test]
    fn accurate_at_n_128_against_trig_closed_form() {
        let n = 128;
        let b = Legendre::new(n).unwrap();
        let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
        let mut worst: f64 = 0.0;
        for j in 0..53 {
            // θ from the rounded x (near x = ±1, P_k' ~ k²/2 would amplify the rounding of x).
            let x = (0.013 + 3.1 * j as f64 / 52.0).cos();
            let theta = x.acos();
            b.eval(0.5 * (1.0 + x), &mut v, &mut d);
            for k in [1, 2, 17, 63, 100, 125, 126] {
                let (pm, pk, pp) = (
                    legendre_trig(k - 1, theta),
                    legendre_trig(k, theta),
                    legendre_trig(k + 1, theta),
                );
                let s = 1.0 / (2.0 * (2 * k + 1) as f64).sqrt();
                let ev = (v[k] - (pp - pm) * s).abs();
                let dk = 2.0 * (2 * k + 1) as f64 * s * pk;
                let ed = (d[k] - dk).abs() / (2.0 * (2 * k + 1) as f64 * s);
                worst = worst.max(ev).max(ed);
            }
        }
        assert!(worst < 1e-13, "worst error {worst:e}");
    }

    #[test]
    fn interior_stiffness_block_is_twice_identity() {
        // ∫₀¹ φ_a' φ_b' dτ by 130-point Gauss–Legendre (exact for degree 2·126).
        for n in [5, 40, 128] {
            let b = Legendre::new(n).unwrap();
            let rule = GaussLegendre::new(n + 2).unwrap().rule().unwrap();
            let mut k = vec![0.0; n * n];
            let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
            for (&c, &w) in rule.nodes.iter().zip(&rule.weights) {
                b.eval(c, &mut v, &mut d);
                for a in 0..n {
                    for bb in 0..n {
                        k[a * n + bb] += w * d[a] * d[bb];
                    }
                }
            }
            for a in 1..n - 1 {
                for bb in 1..n - 1 {
                    let want = if a == bb { 2.0 } else { 0.0 };
                    assert!((k[a * n + bb] - want).abs() < 1e-12, "n={n} K[{a}][{bb}]");
                }
                // Interior functions are also stiffness-orthogonal to the linear end functions.
                assert!(k[a * n].abs() < 1e-12 && k[a * n + n - 1].abs() < 1e-12);
            }
        }
    }

    #[test]
    fn curve_fit_reproduces_polynomials_and_smooth_curves() {
        let n = 12;
        let b = Legendre::new(n).unwrap();
        let fit = CurveFit::new(&b).unwrap();
        let poly = |t: f64| {
            (0..n)
                .map(|j| (0.3 * j as f64 - 1.0) * t.powi(j as i32))
                .sum()
        };
        for (f, tol) in [
            (&poly as &dyn Fn(f64) -> f64, 1e-12),
            (&|t: f64| (3.0 * t).cos(), 1e-8),
        ] {
            let mut c: Vec<f64> = fit.nodes().iter().map(|&t| f(t)).collect();
            fit.values_to_coefficients(&mut c, 1);
            // Modal: Q_0, Q_{n−1} are the end values, the rest are not nodal values.
            assert!((c[0] - f(0.0)).abs() < 1e-13 && (c[n - 1] - f(1.0)).abs() < 1e-13);
            let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
            for j in 0..41 {
                let t = j as f64 / 40.0;
                b.eval(t, &mut v, &mut d);
                let got: f64 = v.iter().zip(&c).map(|(a, b)| a * b).sum();
                assert!((got - f(t)).abs() < tol, "τ = {t}: {got} vs {}", f(t));
            }
        }
    }

    #[test]
    fn change_of_basis_from_chebyshev_is_exact() {
        // Same space P_{n−1}: each Chebyshev–Lagrange function is reproduced exactly.
        let n = 20;
        let (leg, cheb) = (
            Legendre::new(n).unwrap(),
            ChebyshevLagrange::new(n).unwrap(),
        );
        let fit = CurveFit::new(&leg).unwrap();
        // values[k*n + i] = ℓ_i(x_k): fit all n Chebyshev functions at once.
        let mut coef = vec![0.0; n * n];
        let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
        for (k, &x) in fit.nodes().iter().enumerate() {
            cheb.eval(x, &mut v, &mut d);
            coef[k * n..(k + 1) * n].copy_from_slice(&v);
        }
        fit.values_to_coefficients(&mut coef, n);
        let (mut lv, mut ld) = (vec![0.0; n], vec![0.0; n]);
        let mut worst: f64 = 0.0;
        for j in 0..50 {
            let t = (j as f64 * 0.618_034) % 1.0;
            cheb.eval(t, &mut v, &mut d);
            leg.eval(t, &mut lv, &mut ld);
            for i in 0..n {
                let got: f64 = (0..n).map(|a| coef[a * n + i] * lv[a]).sum();
                let dgot: f64 = (0..n).map(|a| coef[a * n + i] * ld[a]).sum();
                worst = worst.max((got - v[i]).abs()).max((dgot - d[i]).abs() / 1e3);
            }
        }
        assert!(worst < 1e-12, "change of basis error {worst:e}");
    }

    #[test]
    fn rejects_bad_sizes() {
        assert!(Legendre::new(1).is_err());
        assert!(Legendre::new(Legendre::MAX_N + 1).is_err());
    }
}
