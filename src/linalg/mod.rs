//! Small dense linear algebra that never allocates after construction.
//!
//! The Newton solve of every step factorises an ((n−1)D)² matrix. nalgebra's LU allocates its
//! result; this LU with partial pivoting works in buffers owned by the integrator's workspace,
//! so the step loop stays allocation-free (docs/DESIGN.md §4).
//!
//! Contents: [`Lu`] (in-place LU with partial pivoting and its solve), [`gemm`] on strided
//! row-major blocks ([`Strided`]) for the Gram products Φᵀ diag(g) Φ of the Newton matrix,
//! [`reciprocal_condition`] for the conditioning checks of kinetic matrices, and
//! [`symmetric_eigen`] (cyclic Jacobi) for the generalised eigendecomposition of the
//! Kronecker stage solver (docs/solvers.md in the repository). Each routine works on slices in
//! the integrator's buffers; a singular factorisation is a [`Singular`] value, never a panic.

mod gemm;
mod panel;
pub use gemm::{Strided, gemm, gemm_transposed};
pub(crate) use panel::{PANEL, panel_product};

/// Σ x_i y_i, summed in four interleaved lanes (then (l0 + l1) + (l2 + l3)), so that the
/// additions do not wait on each other; serially below eight terms.
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    let len = x.len().min(y.len());
    if len < 8 {
        return x.iter().zip(y).map(|(a, b)| a * b).sum();
    }
    let mut l = [0.0f64; 4];
    let (xc, yc) = (x[..len].chunks_exact(4), y[..len].chunks_exact(4));
    let (xr, yr) = (xc.remainder(), yc.remainder());
    for (a, b) in xc.zip(yc) {
        for k in 0..4 {
            l[k] += a[k] * b[k];
        }
    }
    for (k, (a, b)) in xr.iter().zip(yr).enumerate() {
        l[k] += a * b;
    }
    (l[0] + l[1]) + (l[2] + l[3])
}

/// The matrix was singular to working precision (a zero or negligible pivot).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Singular {
    /// Column at which elimination found no usable pivot.
    pub column: usize,
}

/// LU factorisation with partial pivoting of a square row-major matrix: P A = L U.
#[derive(Debug, Clone, Default)]
pub struct Lu {
    n: usize,
    lu: Vec<f64>,
    piv: Vec<usize>,
}

impl Lu {
    /// An empty factorisation with room for n×n matrices.
    pub fn with_capacity(n: usize) -> Self {
        Lu {
            n,
            lu: vec![0.0; n * n],
            piv: (0..n).collect(),
        }
    }

    /// Factorise `a` (row-major n×n), taking ownership of its storage.
    pub fn factor(a: Vec<f64>, n: usize) -> Result<Self, Singular> {
        let mut lu = Lu {
            n,
            lu: a,
            piv: (0..n).collect(),
        };
        lu.factor_stored()?;
        Ok(lu)
    }

    /// Size n.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Factorise a new matrix of the same size into the existing buffers (no allocation).
    pub fn refactor(&mut self, a: &[f64]) -> Result<(), Singular> {
        debug_assert_eq!(a.len(), self.n * self.n);
        self.lu.copy_from_slice(a);
        for (i, p) in self.piv.iter_mut().enumerate() {
            *p = i;
        }
        self.factor_stored()
    }

    fn factor_stored(&mut self) -> Result<(), Singular> {
        let n = self.n;
        let a = &mut self.lu;
        let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        if !scale.is_finite() || a.iter().any(|x| x.is_nan()) {
            return Err(Singular { column: 0 });
        }
        let tiny = scale * f64::EPSILON * 1e-3;
        for k in 0..n {
            let mut p = k;
            let mut best = a[k * n + k].abs();
            for r in k + 1..n {
                let x = a[r * n + k].abs();
                if x > best {
                    best = x;
                    p = r;
                }
            }
            if best <= tiny || best == 0.0 {
                return Err(Singular { column: k });
            }
            if p != k {
                for c in 0..n {
                    a.swap(k * n + c, p * n + c);
                }
                self.piv.swap(k, p);
            }
            let pivot = a[k * n + k];
            let (top, below) = a.split_at_mut((k + 1) * n);
            let pivot_row = &top[k * n + k + 1..(k + 1) * n];
            for row in below.chunks_exact_mut(n) {
                let f = row[k] / pivot;
                row[k] = f;
                if f != 0.0 {
                    for (x, &y) in row[k + 1..].iter_mut().zip(pivot_row) {
                        *x -= f * y;
                    }
                }
            }
        }
        Ok(())
    }

    /// Solve A x = b in place (b has length n).
    pub fn solve_in_place(&self, b: &mut [f64], scratch: &mut [f64]) {
        self.substitute::<false>(b, scratch);
    }

    /// As [`Self::solve_in_place`], with each row's sum in four lanes ([`dot`]): not bound by
    /// the latency of serial additions (the fast-body self-block solves of the structured
    /// solvers, 72 unknowns, were 10 % of the paper's 10-body run with serial sums), but
    /// rounded differently, so the dense reference solver keeps the serial sums.
    pub fn solve_in_place_lanes(&self, b: &mut [f64], scratch: &mut [f64]) {
        self.substitute::<true>(b, scratch);
    }

    fn substitute<const LANES: bool>(&self, b: &mut [f64], scratch: &mut [f64]) {
        let n = self.n;
        for i in 0..n {
            scratch[i] = b[self.piv[i]];
        }
        let a = &self.lu;
        for i in 0..n {
            if LANES {
                scratch[i] -= dot(&a[i * n..i * n + i], &scratch[..i]);
            } else {
                let mut s = scratch[i];
                for j in 0..i {
                    s -= a[i * n + j] * scratch[j];
                }
                scratch[i] = s;
            }
        }
        for i in (0..n).rev() {
            let s = if LANES {
                scratch[i] - dot(&a[i * n + i + 1..(i + 1) * n], &scratch[i + 1..n])
            } else {
                let mut s = scratch[i];
                for j in i + 1..n {
                    s -= a[i * n + j] * scratch[j];
                }
                s
            };
            scratch[i] = s / a[i * n + i];
        }
        b[..n].copy_from_slice(&scratch[..n]);
    }

    /// Solve A X = B in place for B row-major n × `cols` (each column a right-hand side).
    /// Allocates a small scratch; not for the step loop.
    pub fn solve_columns_in_place(&self, b: &mut [f64], cols: usize) {
        let n = self.n;
        let mut col = vec![0.0; n];
        let mut scratch = vec![0.0; n];
        self.solve_columns_with(b, cols, &mut col, &mut scratch);
    }

    /// [`solve_columns_in_place`](Lu::solve_columns_in_place) with caller-provided scratch
    /// vectors of length n (no allocation).
    pub fn solve_columns_with(
        &self,
        b: &mut [f64],
        cols: usize,
        col: &mut [f64],
        scratch: &mut [f64],
    ) {
        let n = self.n;
        for c in 0..cols {
            for i in 0..n {
                col[i] = b[i * cols + c];
            }
            self.solve_in_place(col, scratch);
            for i in 0..n {
                b[i * cols + c] = col[i];
            }
        }
    }
}

/// Reciprocal 2-norm condition number of a row-major square matrix (via SVD; not for hot
/// paths). Returns 0 for a singular or non-finite matrix.
pub fn reciprocal_condition(a: &[f64], n: usize) -> f64 {
    if n == 0 || a.iter().any(|x| !x.is_finite()) {
        return 0.0;
    }
    let m = nalgebra::DMatrix::from_row_slice(n, n, a);
    let sv = m.singular_values();
    let max = sv.max();
    let min = sv.min();
    if max <= 0.0 { 0.0 } else { min / max }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_pivoting_system() {
        let a = vec![0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 3.0, 0.0, 1.0];
        let lu = Lu::factor(a.clone(), 3).unwrap();
        let x = [1.0, -2.0, 0.5];
        let mut b = [0.0; 3];
        for i in 0..3 {
            b[i] = (0..3).map(|j| a[i * 3 + j] * x[j]).sum();
        }
        let mut s = [0.0; 3];
        lu.solve_in_place(&mut b, &mut s);
        for i in 0..3 {
            assert!((b[i] - x[i]).abs() < 1e-14);
        }
    }

    /// The four-lane substitution solves what the serial one does, to round-off: a 72×72
    /// diagonally dominant system (the size of a body's self-block at n = 25) with a known
    /// solution, relative error below 1e-14 for both and 1e-14 between them; `dot` is exact on
    /// small integers at every length around the lane width.
    #[test]
    fn lane_substitution_solves_the_same_system() {
        let n = 72;
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] = ((i * 7 + j * 13) % 17) as f64 / 17.0 - 0.5;
            }
            a[i * n + i] += n as f64;
        }
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let b: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| a[i * n + j] * x[j]).sum())
            .collect();
        let lu = Lu::factor(a, n).unwrap();
        let (mut serial, mut lanes, mut s) = (b.clone(), b, vec![0.0; n]);
        lu.solve_in_place(&mut serial, &mut s);
        lu.solve_in_place_lanes(&mut lanes, &mut s);
        for i in 0..n {
            assert!((serial[i] - x[i]).abs() < 1e-14, "{i}");
            assert!((lanes[i] - x[i]).abs() < 1e-14, "{i}");
            assert!((lanes[i] - serial[i]).abs() < 1e-14, "{i}");
        }
        for len in 0..20 {
            let u: Vec<f64> = (0..len).map(|i| (i % 5) as f64 - 2.0).collect();
            let v: Vec<f64> = (0..len).map(|i| (i % 3) as f64 + 1.0).collect();
            let exact: f64 = (0..len).map(|i| u[i] * v[i]).sum();
            assert_eq!(dot(&u, &v), exact, "{len}");
        }
    }

    #[test]
    fn detects_singularity() {
        let a = vec![1.0, 2.0, 2.0, 4.0];
        assert!(Lu::factor(a, 2).is_err());
        assert!(Lu::factor(vec![f64::NAN, 0.0, 0.0, 1.0], 2).is_err());
        assert!(reciprocal_condition(&[1.0, 2.0, 2.0, 4.0], 2) < 1e-15);
    }
}

/// Eigen-decomposition of a symmetric n×n matrix by cyclic Jacobi rotations, in place and
/// without allocation: on return `a`'s diagonal holds the eigenvalues (copied into
/// `values`) and the columns of `vectors` (row-major n×n) the orthonormal eigenvectors,
/// A = V diag(λ) Vᵀ. Jacobi is slower than QR for large n but accurate to the last bits for
/// the small matrices of a step (the frozen force Jacobian, D×D) and needs no workspace.
/// Returns the sweeps taken (at most 50).
pub fn symmetric_eigen(a: &mut [f64], n: usize, values: &mut [f64], vectors: &mut [f64]) -> usize {
    vectors[..n * n].iter_mut().for_each(|x| *x = 0.0);
    for i in 0..n {
        vectors[i * n + i] = 1.0;
    }
    let mut sweeps = 0;
    for sweep in 0..50 {
        sweeps = sweep + 1;
        let mut off = 0.0f64;
        let mut diag = 0.0f64;
        for p in 0..n {
            diag = diag.max(a[p * n + p].abs());
            for q in p + 1..n {
                off = off.max(a[p * n + q].abs());
            }
        }
        if off <= f64::EPSILON * 1e-3 * diag || off == 0.0 || !off.is_finite() {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq == 0.0 {
                    continue;
                }
                let (app, aqq) = (a[p * n + p], a[q * n + q]);
                let theta = (aqq - app) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                // A ← Jᵀ A J with the rotation in the (p, q) plane.
                for k in 0..n {
                    let (akp, akq) = (a[k * n + p], a[k * n + q]);
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p * n + k], a[q * n + k]);
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                for k in 0..n {
                    let (vkp, vkq) = (vectors[k * n + p], vectors[k * n + q]);
                    vectors[k * n + p] = c * vkp - s * vkq;
                    vectors[k * n + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    for i in 0..n {
        values[i] = a[i * n + i];
    }
    sweeps
}

#[cfg(test)]
mod eigen_tests {
    use super::symmetric_eigen;

    #[test]
    fn jacobi_reconstructs_a_symmetric_matrix() {
        let n = 5;
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] =
                    1.0 / (1.0 + (i + j) as f64) + if i == j { (i as f64) - 2.0 } else { 0.0 };
            }
        }
        let orig = a.clone();
        let (mut w, mut v) = (vec![0.0; n], vec![0.0; n * n]);
        symmetric_eigen(&mut a, n, &mut w, &mut v);
        let mut err = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let s: f64 = (0..n).map(|k| v[i * n + k] * w[k] * v[j * n + k]).sum();
                err = err.max((s - orig[i * n + j]).abs());
                let o: f64 = (0..n).map(|k| v[k * n + i] * v[k * n + j]).sum();
                err = err.max((o - if i == j { 1.0 } else { 0.0 }).abs());
            }
        }
        assert!(err < 1e-14, "{err}");
    }
}
