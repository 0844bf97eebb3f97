//! The Fourier (sine) basis: linear end functions plus a sine series, docs/DESIGN.md §2.

use super::{Basis, check_size};
use crate::error::Result;

/// Boundary-adapted Fourier basis: φ_0 = 1 − τ, φ_{n−1} = τ and the sines
/// φ_k = sin(kπτ), k = 1 … n − 2, which vanish at both ends.
///
/// This is not a polynomial space ([`polynomial_degree`](Basis::polynomial_degree) is `None`),
/// so no quadrature is exact for it and the integrator only checks that the kinetic matrix is
/// well conditioned. Because the sine series of a curve minus its chord converges only
/// algebraically unless the curve's odd periodic extension is smooth, the Galerkin method with
/// this basis converges algebraically in n (error ≈ C n^{−p}), not geometrically like the
/// polynomial bases; see the tests for the measured orders.
///
/// Curve fitting interpolates at the n equispaced points τ_j = j/(n − 1), where the interior
/// collocation block is the (orthogonal, perfectly conditioned) DST-I matrix. Sines are
/// evaluated with exact argument reduction (sin(kπτ) is exactly 0 at τ = 0, 1 for every k).
///
/// ```
/// use galerkin_vi::basis::{Basis, Fourier};
/// let b = Fourier::new(5).unwrap();
/// assert_eq!(b.polynomial_degree(), None);
/// let (mut v, mut d) = (vec![0.0; 5], vec![0.0; 5]);
/// b.eval(0.5, &mut v, &mut d);
/// assert_eq!(v, vec![0.5, 1.0, 0.0, -1.0, 0.5]);
/// assert!((d[2] + 2.0 * std::f64::consts::PI).abs() < 1e-14);
/// ```
#[derive(Debug, Clone)]
pub struct Fourier {
    n: usize,
}

impl Fourier {
    /// The largest n accepted.
    pub const MAX_N: usize = 4096;

    /// The basis with n ≥ 2 functions (n − 2 sines).
    pub fn new(n: usize) -> Result<Self> {
        check_size("fourier", n, 2, Self::MAX_N)?;
        Ok(Fourier { n })
    }
}

/// (sin πx, cos πx) with the argument reduced exactly to [−½, ½]: exact zeros at integers.
fn sin_cos_pi(x: f64) -> (f64, f64) {
    let pi = std::f64::consts::PI;
    // r ∈ [−1, 1]: subtracting an even integer is exact for |x| < 2^52.
    let r = x - 2.0 * (0.5 * x).round();
    if r > 0.5 {
        let (s, c) = (pi * (1.0 - r)).sin_cos();
        (s, -c)
    } else if r < -0.5 {
        let (s, c) = (pi * (1.0 + r)).sin_cos();
        (-s, -c)
    } else {
        (pi * r).sin_cos()
    }
}

impl Basis for Fourier {
    fn len(&self) -> usize {
        self.n
    }

    fn name(&self) -> &'static str {
        "fourier"
    }

    fn eval(&self, tau: f64, values: &mut [f64], derivatives: &mut [f64]) {
        let n = self.n;
        let pi = std::f64::consts::PI;
        for k in 1..n - 1 {
            let kf = k as f64;
            let (s, c) = sin_cos_pi(kf * tau);
            values[k] = s;
            derivatives[k] = kf * pi * c;
        }
        values[0] = 1.0 - tau;
        derivatives[0] = -1.0;
        values[n - 1] = tau;
        derivatives[n - 1] = 1.0;
    }

    fn polynomial_degree(&self) -> Option<usize> {
        None
    }

    fn interpolation_nodes(&self) -> Vec<f64> {
        let n = self.n;
        (0..n).map(|j| j as f64 / (n - 1) as f64).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::basis::CurveFit;
    use crate::basis::contract_tests::check_contract;

    #[test]
    fn contract_and_derivatives() {
        for n in [2, 3, 4, 7, 16, 33, 64, 200] {
            let b = Fourier::new(n).unwrap();
            let fd = check_contract(&b);
            assert!(fd < 1e-6, "n = {n}: finite-difference mismatch {fd}");
        }
    }

    #[test]
    fn argument_reduction_matches_libm() {
        for j in 0..200 {
            let x = -7.3 + 0.0731 * j as f64;
            let (s, c) = sin_cos_pi(x);
            let (s0, c0) = (std::f64::consts::PI * x).sin_cos();
            assert!((s - s0).abs() < 1e-14 && (c - c0).abs() < 1e-14, "x = {x}");
        }
        for k in 0..5000 {
            assert_eq!(sin_cos_pi(k as f64).0, 0.0);
        }
    }

    #[test]
    fn curve_fit_of_smooth_curves() {
        // f − chord vanishes at the ends; its odd extension has a kink in f'', so the sine
        // interpolant converges like n^{-2}·(|f''(0)| + |f''(1)|)-ish. Check the fit is an
        // interpolant with small error between the nodes.
        for (n, tol) in [(16, 3e-3), (64, 2e-4)] {
            let b = Fourier::new(n).unwrap();
            let fit = CurveFit::new(&b).unwrap();
            let f = |t: f64| (3.0 * t).cos();
            let mut c: Vec<f64> = fit.nodes().iter().map(|&t| f(t)).collect();
            fit.values_to_coefficients(&mut c, 1);
            assert!((c[0] - 1.0).abs() < 1e-13 && (c[n - 1] - f(1.0)).abs() < 1e-13);
            let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
            let mut worst: f64 = 0.0;
            for j in 0..=200 {
                let t = j as f64 / 200.0;
                b.eval(t, &mut v, &mut d);
                let got: f64 = v.iter().zip(&c).map(|(a, b)| a * b).sum();
                worst = worst.max((got - f(t)).abs());
            }
            assert!(worst < tol, "n = {n}: fit error {worst:e}");
        }
        // A curve in the span is reproduced exactly.
        let n = 10;
        let b = Fourier::new(n).unwrap();
        let fit = CurveFit::new(&b).unwrap();
        let f = |t: f64| 2.0 - t + 0.5 * (3.0 * std::f64::consts::PI * t).sin();
        let mut c: Vec<f64> = fit.nodes().iter().map(|&t| f(t)).collect();
        fit.values_to_coefficients(&mut c, 1);
        let want = [2.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        for (a, b) in c.iter().zip(want) {
            assert!((a - b).abs() < 1e-13, "{c:?}");
        }
    }

    #[test]
    fn rejects_bad_sizes() {
        assert!(Fourier::new(1).is_err());
        assert!(Fourier::new(Fourier::MAX_N + 1).is_err());
    }
}
