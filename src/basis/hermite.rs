//! The Hermite (Hermite–Birkhoff) basis: end values and end derivatives as degrees of freedom,
//! plus interior nodal values, docs/DESIGN.md §2.

use super::{Basis, ChebyshevLagrange, check_size};
use crate::error::Result;

/// Generalised Hermite basis of degree n − 1 (n ≥ 4). The degrees of freedom, in index order:
///
/// | index | functional |
/// |---|---|
/// | 0 | value at τ = 0 |
/// | 1 | derivative dq/dτ at τ = 0 |
/// | 2 … n − 3 | values at the n − 4 interior points y_1 … y_{n−4} of the (n − 2)-point Chebyshev–Lobatto grid |
/// | n − 2 | derivative dq/dτ at τ = 1 |
/// | n − 1 | value at τ = 1 |
///
/// and φ_i is the polynomial of degree n − 1 on which functional i is 1 and all others are 0.
/// The derivative functions vanish in value at both ends, so the boundary-adapted contract
/// holds; for n = 4 this is the classical cubic Hermite basis.
///
/// Stable construction: with the bubble b(τ) = τ(1 − τ), every φ_i has the form
/// φ_i = ℓ_i + b ψ_i where ℓ_i is the linear end part (1 − τ for i = 0, τ for i = n − 1, else
/// 0) and ψ_i has degree n − 3. Since b(0) = b(1) = 0 and b'(0) = −b'(1) = 1, the Hermite
/// conditions on φ_i become plain Lagrange conditions on ψ_i at the (n − 2)-point
/// Chebyshev–Lobatto grid y_0 = 0, y_1, …, y_{n−3} = 1 (ψ(0) = φ'(0) − ℓ'(0),
/// ψ(1) = ℓ'(1) − φ'(1), ψ(y_k) = (φ(y_k) − ℓ(y_k))/b(y_k)). So ψ_i is a combination of the
/// Chebyshev–Lagrange functions λ_k on that grid, evaluated by the stable barycentric formula
/// ([`ChebyshevLagrange`]); the contract holds exactly because b vanishes exactly at the ends.
/// Large weights 1/b(y_k) ~ n² near the ends make this basis worse conditioned than
/// Chebyshev–Lagrange at large n (see the integration tests).
///
/// ```
/// use galerkin_vi::basis::{Basis, Hermite};
/// let b = Hermite::new(4).unwrap();
/// let (mut v, mut d) = (vec![0.0; 4], vec![0.0; 4]);
/// b.eval(0.5, &mut v, &mut d);
/// // Cubic Hermite: h00(½) = ½, h10(½) = ⅛, h11(½) = −⅛, h01(½) = ½.
/// for (got, want) in v.iter().zip([0.5, 0.125, -0.125, 0.5]) {
///     assert!((got - want).abs() < 1e-15);
/// }
/// ```
#[derive(Debug, Clone)]
pub struct Hermite {
    n: usize,
    /// Lagrange basis of degree n − 3 on the (n − 2)-point Chebyshev–Lobatto grid.
    lagrange: ChebyshevLagrange,
    /// 1/b(y_k), 1/y_k and 1/(1 − y_k) for the interior grid points k = 1 … n − 4 (index k − 1).
    inv_bubble: Vec<f64>,
    inv_left: Vec<f64>,
    inv_right: Vec<f64>,
}

impl Hermite {
    /// The largest n accepted.
    pub const MAX_N: usize = 1024;

    /// The basis with 4 ≤ n ≤ [`MAX_N`](Hermite::MAX_N) functions (degree n − 1).
    pub fn new(n: usize) -> Result<Self> {
        check_size("hermite", n, 4, Self::MAX_N)?;
        let lagrange = ChebyshevLagrange::new(n - 2)?;
        let interior = &lagrange.nodes()[1..n - 3];
        Ok(Hermite {
            n,
            inv_bubble: interior.iter().map(|&y| 1.0 / (y * (1.0 - y))).collect(),
            inv_left: interior.iter().map(|&y| 1.0 / y).collect(),
            inv_right: interior.iter().map(|&y| 1.0 / (1.0 - y)).collect(),
            lagrange,
        })
    }

    /// The n − 4 interior interpolation nodes (degrees of freedom 2 … n − 3).
    pub fn interior_nodes(&self) -> &[f64] {
        &self.lagrange.nodes()[1..self.n - 3]
    }
}

impl Basis for Hermite {
    fn len(&self) -> usize {
        self.n
    }

    fn name(&self) -> &'static str {
        "hermite"
    }

    fn eval(&self, tau: f64, values: &mut [f64], derivatives: &mut [f64]) {
        let n = self.n;
        let last = n - 3; // index of y = 1 on the small grid
        // λ_k, λ_k' into slots 0 … n − 3, then shifted to 1 … n − 2.
        self.lagrange
            .eval(tau, &mut values[..n - 2], &mut derivatives[..n - 2]);
        let (l0, dl0, ll, dll) = (values[0], derivatives[0], values[last], derivatives[last]);
        // ψ_0 = λ_0 − λ_last − Σ λ_k / y_k;  ψ_{n−1} = −λ_0 + λ_last − Σ λ_k / (1 − y_k).
        let (mut s0, mut ds0, mut s1, mut ds1) = (0.0, 0.0, 0.0, 0.0);
        for k in 1..last {
            let (l, dl) = (values[k], derivatives[k]);
            s0 += l * self.inv_left[k - 1];
            ds0 += dl * self.inv_left[k - 1];
            s1 += l * self.inv_right[k - 1];
            ds1 += dl * self.inv_right[k - 1];
        }
        let b = tau * (1.0 - tau);
        let db = 1.0 - 2.0 * tau;
        // Interior value functions φ_{k+1} = b λ_k / b(y_k), from the top down (in place).
        for k in (1..last).rev() {
            let w = self.inv_bubble[k - 1];
            let (l, dl) = (values[k], derivatives[k]);
            values[k + 1] = w * b * l;
            derivatives[k + 1] = w * (db * l + b * dl);
        }
        // Derivative functions φ_1 = b λ_0, φ_{n−2} = −b λ_last.
        values[n - 2] = -b * ll;
        derivatives[n - 2] = -(db * ll + b * dll);
        values[1] = b * l0;
        derivatives[1] = db * l0 + b * dl0;
        let (psi0, dpsi0) = (l0 - ll - s0, dl0 - dll - ds0);
        let (psi1, dpsi1) = (ll - l0 - s1, dll - dl0 - ds1);
        values[0] = (1.0 - tau) + b * psi0;
        derivatives[0] = -1.0 + db * psi0 + b * dpsi0;
        values[n - 1] = tau + b * psi1;
        derivatives[n - 1] = 1.0 + db * psi1 + b * dpsi1;
    }

    fn polynomial_degree(&self) -> Option<usize> {
        Some(self.n - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::basis::contract_tests::check_contract;
    use crate::basis::{CurveFit, Legendre};

    #[test]
    fn contract_and_derivatives() {
        for n in [4, 5, 6, 9, 16, 33, 64] {
            let b = Hermite::new(n).unwrap();
            let fd = check_contract(&b);
            assert!(fd < 1e-6, "n = {n}: finite-difference mismatch {fd}");
        }
    }

    #[test]
    fn functionals_are_dual_to_the_basis() {
        for n in [4, 5, 7, 24, 64] {
            let b = Hermite::new(n).unwrap();
            let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
            let tol = 1e-13 * (n * n) as f64;
            let unit = |i: usize, j: usize| f64::from(u8::from(i == j));
            b.eval(0.0, &mut v, &mut d);
            for i in 0..n {
                assert!(
                    (d[i] - unit(i, 1)).abs() < tol,
                    "n={n} φ_{i}'(0) = {}",
                    d[i]
                );
            }
            b.eval(1.0, &mut v, &mut d);
            for i in 0..n {
                assert!(
                    (d[i] - unit(i, n - 2)).abs() < tol,
                    "n={n} φ_{i}'(1) = {}",
                    d[i]
                );
            }
            for (k, &t) in b.interior_nodes().iter().enumerate() {
                b.eval(t, &mut v, &mut d);
                for i in 0..n {
                    let err = (v[i] - unit(i, k + 2)).abs();
                    assert!(err < 1e-13, "n={n} φ_{i}({t}) = {}", v[i]);
                }
            }
        }
    }

    #[test]
    fn curve_fit_and_change_of_basis() {
        let n = 18;
        let b = Hermite::new(n).unwrap();
        let fit = CurveFit::new(&b).unwrap();
        // Polynomials of degree n − 1 are reproduced; coefficients are the Hermite data.
        let f = |t: f64| {
            (0..n)
                .map(|j| (1.0 - 0.1 * j as f64) * t.powi(j as i32))
                .sum::<f64>()
        };
        let df = |t: f64| {
            (1..n)
                .map(|j| j as f64 * (1.0 - 0.1 * j as f64) * t.powi(j as i32 - 1))
                .sum::<f64>()
        };
        let mut c: Vec<f64> = fit.nodes().iter().map(|&t| f(t)).collect();
        fit.values_to_coefficients(&mut c, 1);
        assert!((c[1] - df(0.0)).abs() < 1e-11 && (c[n - 2] - df(1.0)).abs() < 1e-11);
        let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
        for j in 0..31 {
            let t = j as f64 / 30.0;
            b.eval(t, &mut v, &mut d);
            let got: f64 = v.iter().zip(&c).map(|(a, b)| a * b).sum();
            assert!((got - f(t)).abs() < 1e-12, "τ = {t}");
        }
        // cos 3τ: smooth, fitted to spectral accuracy.
        let mut c: Vec<f64> = fit.nodes().iter().map(|&t| (3.0 * t).cos()).collect();
        fit.values_to_coefficients(&mut c, 1);
        b.eval(0.37, &mut v, &mut d);
        let got: f64 = v.iter().zip(&c).map(|(a, b)| a * b).sum();
        assert!((got - (3.0f64 * 0.37).cos()).abs() < 1e-12);
        // Change of basis: Chebyshev–Lagrange and Legendre functions are reproduced exactly.
        let cheb = ChebyshevLagrange::new(n).unwrap();
        let leg = Legendre::new(n).unwrap();
        let mut worst: f64 = 0.0;
        let (mut w, mut dw) = (vec![0.0; n], vec![0.0; n]);
        for other in [&cheb as &dyn Basis, &leg as &dyn Basis] {
            let mut coef = vec![0.0; n * n];
            for (k, &x) in fit.nodes().iter().enumerate() {
                other.eval(x, &mut w, &mut dw);
                coef[k * n..(k + 1) * n].copy_from_slice(&w);
            }
            fit.values_to_coefficients(&mut coef, n);
            for j in 0..37 {
                let t = (j as f64 * 0.754_877_7) % 1.0;
                other.eval(t, &mut w, &mut dw);
                b.eval(t, &mut v, &mut d);
                for i in 0..n {
                    let got: f64 = (0..n).map(|a| coef[a * n + i] * v[a]).sum();
                    worst = worst.max((got - w[i]).abs());
                }
            }
        }
        assert!(worst < 1e-12, "change of basis error {worst:e}");
    }

    #[test]
    fn rejects_bad_sizes() {
        assert!(Hermite::new(3).is_err());
        assert!(Hermite::new(Hermite::MAX_N + 1).is_err());
    }
}
