//! The Galerkin curve of a step in Chebyshev modes: its Chebyshev coefficients, and the modal
//! indicators the tolerance-driven n reads from the size of its last modes.

use super::GalerkinIntegrator;
use crate::basis::Basis;
use crate::quadrature::Quadrature;

/// C (n×n) with a = C·Q the Chebyshev coefficients of the curve Σ Q_i φ_i: values at the n
/// Chebyshev–Lobatto points, then the discrete Chebyshev transform (DCT-I).
pub(super) fn chebyshev_transform<B: Basis + ?Sized>(basis: &B, n: usize) -> Vec<f64> {
    let nodes = crate::basis::chebyshev_lobatto_points(n);
    let (mut v, mut dv) = (vec![0.0; n], vec![0.0; n]);
    // E[k][i] = φ_i(τ_k)
    let mut e = vec![0.0; n * n];
    for (k, &x) in nodes.iter().enumerate() {
        basis.eval(x, &mut v, &mut dv);
        e[k * n..(k + 1) * n].copy_from_slice(&v);
    }
    // τ_k = (1 − cos θ_k)/2 ⇒ x_k = 2τ_k − 1 = −cos θ_k, and T_j(−cos θ) = (−1)^j cos jθ.
    let m = (n - 1).max(1) as f64;
    let mut c = vec![0.0; n * n];
    for j in 0..n {
        let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
        let end_j = if j == 0 || j == n - 1 { 0.5 } else { 1.0 };
        for k in 0..n {
            let end_k = if k == 0 || k == n - 1 { 0.5 } else { 1.0 };
            let w =
                2.0 / m * end_j * end_k * sign * (std::f64::consts::PI * (j * k) as f64 / m).cos();
            for i in 0..n {
                c[j * n + i] += w * e[k * n + i];
            }
        }
    }
    c
}

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// Chebyshev coefficients (n×D, row j = a_j) of a step's Galerkin curve given its basis
    /// coefficients (n×D). Their decay is the spectral error indicator (chebfun's "happiness").
    pub fn chebyshev_coefficients(&self, coeffs: &[f64], dim: usize) -> Vec<f64> {
        let n = self.tables.n;
        let mut a = vec![0.0; n * dim];
        crate::linalg::gemm(
            n,
            n,
            dim,
            1.0,
            &self.tables.chebyshev,
            crate::linalg::Strided::rows(0, n),
            coeffs,
            crate::linalg::Strided::rows(0, dim),
            0.0,
            &mut a,
            crate::linalg::Strided::rows(0, dim),
        );
        a
    }

    /// The modal error indicator of a step: the max-norm of the last two Chebyshev
    /// coefficients of its Galerkin curve (two, because odd and even modes alternate).
    ///
    /// Allocation-free (it is evaluated for every solve of a tolerance-driven run); NaN when
    /// `coeffs` does not hold n×`dim` values (`dim` ≥ 1).
    pub fn modal_indicator(&self, coeffs: &[f64], dim: usize) -> f64 {
        let n = self.tables.n;
        if dim == 0 || coeffs.len() != n * dim {
            return f64::NAN;
        }
        // NaN coefficients give a NaN indicator (never a small, converged-looking one).
        crate::reduce::max_error(
            (n.saturating_sub(2)..n).map(|j| self.chebyshev_mode_size(coeffs, dim, j)),
        )
    }

    /// max_r |a_{j,r}|: the size of Chebyshev mode j of a step's Galerkin curve (basis
    /// coefficients n×`dim`), without allocating. Summed in the order of
    /// [`Self::chebyshev_coefficients`], so it equals the largest entry of that matrix's row
    /// j bit for bit. NaN when j ≥ n or `coeffs` does not hold n×`dim` values.
    ///
    /// ```
    /// use galerkin_vi::prelude::*;
    ///
    /// let gvi = GalerkinIntegrator::spectral(8, 0.5)?;
    /// let kepler = Kepler::new(1.0)?;
    /// let (q0, p0) = Kepler::paper_initial_state();
    /// let mut ws = gvi.workspace(&kepler)?;
    /// let (mut q1, mut p1) = ([0.0; 2], [0.0; 2]);
    /// gvi.step(&kepler, &mut ws, &q0, &p0, &mut q1, &mut p1)?;
    /// let a = gvi.chebyshev_coefficients(ws.coefficients(), 2);
    /// let size = gvi.chebyshev_mode_size(ws.coefficients(), 2, 5);
    /// assert_eq!(size, a[10].abs().max(a[11].abs()));
    /// // Bad input gives NaN, not a panic: no mode 8 at n = 8, or a wrong dimension.
    /// assert!(gvi.chebyshev_mode_size(ws.coefficients(), 2, 8).is_nan());
    /// assert!(gvi.modal_indicator(ws.coefficients(), 3).is_nan());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn chebyshev_mode_size(&self, coeffs: &[f64], dim: usize, j: usize) -> f64 {
        let n = self.tables.n;
        if j >= n || dim == 0 || coeffs.len() != n * dim {
            return f64::NAN;
        }
        let row = &self.tables.chebyshev[j * n..(j + 1) * n];
        (0..dim)
            .map(|r| {
                row.iter()
                    .zip(coeffs.chunks_exact(dim))
                    .fold(0.0f64, |s, (c, q)| s + c * q[r])
                    .abs()
            })
            .fold(0.0f64, crate::reduce::nan_max)
    }
}
