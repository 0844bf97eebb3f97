//! Lagrange polynomials at the Chebyshev–Lobatto points: the paper's spectral basis (§3.2.1).

use super::{Basis, chebyshev_lobatto_points, check_size};
use crate::error::Result;

/// Lagrange interpolating polynomials ℓ_0 … ℓ_{n−1} at the n Chebyshev–Lobatto points
/// τ_i = (1 − cos(iπ/(n−1)))/2 of [0, 1]: degree n − 1, nodal (Q_i = q(t_k + τ_i h)).
///
/// Values use the second barycentric formula with the closed-form Chebyshev weights
/// (−1)^i δ_i (δ = ½ at the ends), which is stable for any n (Berrut & Trefethen 2004).
/// Derivatives use ℓ_i'(τ) = Σ_k ℓ_k(τ) D_{ki} with the barycentric differentiation matrix D
/// (diagonal by the negative-sum trick), exact for polynomials of degree n − 1 and free of the
/// cancellation that the direct quotient-rule formula suffers near a node.
///
/// ```
/// use galerkin_vi::basis::{Basis, ChebyshevLagrange};
/// let b = ChebyshevLagrange::new(8).unwrap();
/// let (mut v, mut d) = (vec![0.0; 8], vec![0.0; 8]);
/// b.eval(0.3, &mut v, &mut d);
/// // Partition of unity: the constant curve has all coefficients 1.
/// assert!((v.iter().sum::<f64>() - 1.0).abs() < 1e-14);
/// assert!(d.iter().sum::<f64>().abs() < 1e-12);
/// ```
#[derive(Debug, Clone)]
pub struct ChebyshevLagrange {
    nodes: Vec<f64>,
    weights: Vec<f64>,
    /// Differentiation matrix, row-major: diff[k*n + i] = ℓ_i'(τ_k).
    diff: Vec<f64>,
}

impl ChebyshevLagrange {
    /// The largest n accepted (the barycentric formulas stay accurate far beyond it).
    pub const MAX_N: usize = 1024;

    /// The basis with n ≥ 2 functions (degree n − 1).
    pub fn new(n: usize) -> Result<Self> {
        check_size("chebyshev", n, 2, Self::MAX_N)?;
        let nodes = chebyshev_lobatto_points(n);
        let weights: Vec<f64> = (0..n)
            .map(|i| {
                let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
                if i == 0 || i == n - 1 {
                    0.5 * sign
                } else {
                    sign
                }
            })
            .collect();
        let mut diff = vec![0.0; n * n];
        for k in 0..n {
            let mut diag = 0.0;
            for i in 0..n {
                if i != k {
                    let d = (weights[i] / weights[k]) / (nodes[k] - nodes[i]);
                    diff[k * n + i] = d;
                    diag -= d;
                }
            }
            diff[k * n + k] = diag;
        }
        Ok(ChebyshevLagrange {
            nodes,
            weights,
            diff,
        })
    }

    /// The interpolation nodes τ_i.
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// Extrapolation (τ outside [0, 1]), where the second barycentric formula is unstable: its
    /// denominator Σ w_i/(τ − τ_i) is ~1/ℓ(τ) and cancels catastrophically (relative error
    /// 1e-3 at τ = 2 for n = 20). Use the first ("modified Lagrange") form instead, backward
    /// stable everywhere (Higham 2004): ℓ_i(τ) = ℓ(τ) w̃_i/(τ − τ_i) with the true weights
    /// w̃_i = (−1)^{N} 4^N/(2N) · w_i (N = n − 1), and ℓ_i'(τ) = ℓ_i(τ) Σ_{j≠i} 1/(τ − τ_j),
    /// whose terms all have one sign outside [0, 1] (prefix + suffix sums, no cancellation).
    /// For very large n and far extrapolation the values overflow (they are genuinely huge).
    fn eval_outside(&self, tau: f64, values: &mut [f64], derivatives: &mut [f64]) {
        let n = self.nodes.len();
        let big_n = (n - 1) as f64;
        let sign = if (n - 1).is_multiple_of(2) { 1.0 } else { -1.0 };
        // (−1)^N 4^N/(2N) Π_j (τ − τ_j) = (−1)^N Π_j 4(τ − τ_j) / (8N).
        let mut scale = sign / (8.0 * big_n);
        for &x in &self.nodes {
            scale *= 4.0 * (tau - x);
        }
        let mut prefix = 0.0;
        for (d, &x) in derivatives.iter_mut().zip(&self.nodes) {
            *d = prefix;
            prefix += 1.0 / (tau - x);
        }
        let mut suffix = 0.0;
        for i in (0..n).rev() {
            let t = 1.0 / (tau - self.nodes[i]);
            let li = scale * self.weights[i] * t;
            values[i] = li;
            derivatives[i] = li * (derivatives[i] + suffix);
            suffix += t;
        }
    }
}

impl Basis for ChebyshevLagrange {
    fn len(&self) -> usize {
        self.nodes.len()
    }

    fn name(&self) -> &'static str {
        "chebyshev"
    }

    fn eval(&self, tau: f64, values: &mut [f64], derivatives: &mut [f64]) {
        if !(0.0..=1.0).contains(&tau) {
            self.eval_outside(tau, values, derivatives);
            return;
        }
        let n = self.nodes.len();
        // Values by the second barycentric formula; an exact node hit gives a unit vector.
        let hit = self.nodes.iter().position(|&x| x == tau);
        match hit {
            Some(k) => {
                values.iter_mut().for_each(|v| *v = 0.0);
                values[k] = 1.0;
            }
            None => {
                let mut denom = 0.0;
                for i in 0..n {
                    let t = self.weights[i] / (tau - self.nodes[i]);
                    values[i] = t;
                    denom += t;
                }
                for v in values.iter_mut() {
                    *v /= denom;
                }
            }
        }
        // Derivatives: ℓ_i'(τ) = Σ_k ℓ_k(τ) D_{ki}.
        derivatives.iter_mut().for_each(|d| *d = 0.0);
        for (k, &lk) in values.iter().enumerate() {
            if lk != 0.0 {
                let row = &self.diff[k * n..(k + 1) * n];
                for (d, &dki) in derivatives.iter_mut().zip(row) {
                    *d += lk * dki;
                }
            }
        }
    }

    fn polynomial_degree(&self) -> Option<usize> {
        Some(self.nodes.len() - 1)
    }

    fn interpolation_nodes(&self) -> Vec<f64> {
        self.nodes.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::basis::contract_tests::check_contract;

    #[test]
    fn contract_and_derivatives() {
        for n in [2, 3, 4, 7, 16, 33, 64] {
            let b = ChebyshevLagrange::new(n).unwrap();
            let fd = check_contract(&b);
            assert!(fd < 1e-6, "n = {n}: finite-difference mismatch {fd}");
        }
    }

    #[test]
    fn reproduces_polynomials_to_high_degree() {
        // Interpolating a polynomial of degree n−1 is exact; check value and derivative of
        // T_{n-1}(2τ−1) against cos/sin closed forms at n = 64.
        let n = 64;
        let b = ChebyshevLagrange::new(n).unwrap();
        let m = (n - 1) as f64;
        let coeff: Vec<f64> = b
            .nodes()
            .iter()
            .map(|&t| (m * (2.0 * t - 1.0).acos()).cos())
            .collect();
        let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
        let mut worst_v: f64 = 0.0;
        let mut worst_d: f64 = 0.0;
        for k in 0..101 {
            let tau = 0.005 + 0.99 * (k as f64) / 100.0;
            b.eval(tau, &mut v, &mut d);
            let x: f64 = 2.0 * tau - 1.0;
            let th = x.acos();
            let exact = (m * th).cos();
            // d/dτ T_m(2τ−1) = 2 m sin(mθ)/sin θ
            let exact_d = 2.0 * m * (m * th).sin() / th.sin();
            let val: f64 = v.iter().zip(&coeff).map(|(a, c)| a * c).sum();
            let der: f64 = d.iter().zip(&coeff).map(|(a, c)| a * c).sum();
            worst_v = worst_v.max((val - exact).abs());
            worst_d = worst_d.max((der - exact_d).abs() / (2.0 * m * m));
        }
        assert!(worst_v < 1e-13, "value error {worst_v}");
        assert!(worst_d < 1e-12, "relative derivative error {worst_d}");
    }

    #[test]
    fn extrapolation_is_accurate() {
        // ℓ_i outside [0, 1] against an independent evaluation: the same polynomials expanded
        // in the Legendre basis (three-term recurrence, stable for growing P_k) through an
        // exact change of basis on [0, 1].
        use crate::basis::{CurveFit, Legendre};
        for n in [2, 3, 8, 20, 40] {
            let (cheb, leg) = (
                ChebyshevLagrange::new(n).unwrap(),
                Legendre::new(n).unwrap(),
            );
            let fit = CurveFit::new(&leg).unwrap();
            let mut coef = vec![0.0; n * n];
            let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
            for (k, &x) in fit.nodes().iter().enumerate() {
                cheb.eval(x, &mut v, &mut d);
                coef[k * n..(k + 1) * n].copy_from_slice(&v);
            }
            fit.values_to_coefficients(&mut coef, n);
            let (mut lv, mut ld) = (vec![0.0; n], vec![0.0; n]);
            for tau in [1.0 + 1e-9, 1.01, 1.3, 1.5, 2.0, -0.5, -1e-12] {
                cheb.eval(tau, &mut v, &mut d);
                leg.eval(tau, &mut lv, &mut ld);
                let big = v.iter().fold(1.0f64, |m, x| m.max(x.abs()));
                let dbig = d.iter().fold(1.0f64, |m, x| m.max(x.abs()));
                for i in 0..n {
                    let want: f64 = (0..n).map(|a| coef[a * n + i] * lv[a]).sum();
                    let dwant: f64 = (0..n).map(|a| coef[a * n + i] * ld[a]).sum();
                    assert!((v[i] - want).abs() < 1e-12 * big, "n={n} τ={tau} ℓ_{i}");
                    assert!((d[i] - dwant).abs() < 1e-11 * dbig, "n={n} τ={tau} ℓ_{i}'");
                }
            }
        }
    }

    #[test]
    fn rejects_too_few_functions() {
        assert!(ChebyshevLagrange::new(1).is_err());
        assert!(ChebyshevLagrange::new(0).is_err());
    }
}
