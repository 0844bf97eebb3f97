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
        let n = self.n;
        for i in 0..n {
            scratch[i] = b[self.piv[i]];
        }
        let a = &self.lu;
        for i in 0..n {
            let mut s = scratch[i];
            for j in 0..i {
                s -= a[i * n + j] * scratch[j];
            }
            scratch[i] = s;
        }
        for i in (0..n).rev() {
            let mut s = scratch[i];
            for j in i + 1..n {
                s -= a[i * n + j] * scratch[j];
            }
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

/// A strided matrix operand for [`gemm`]: element (i, j) is `data[offset + i·row_stride +
/// j·col_stride]`.
#[derive(Debug, Clone, Copy)]
pub struct Strided {
    /// Offset of element (0, 0).
    pub offset: usize,
    /// Distance between rows.
    pub row_stride: usize,
    /// Distance between columns.
    pub col_stride: usize,
}

impl Strided {
    /// Dense row-major storage with `cols` columns, starting at `offset`.
    pub fn rows(offset: usize, cols: usize) -> Self {
        Strided {
            offset,
            row_stride: cols,
            col_stride: 1,
        }
    }

    fn last(&self, rows: usize, cols: usize) -> usize {
        self.offset + (rows.max(1) - 1) * self.row_stride + (cols.max(1) - 1) * self.col_stride
    }
}

/// C ← Aᵀ B + β C for a row-major table A (k×m), B (k×n) and C (m×n), both row-major: the
/// projection of node values B on the columns of a node table A (Φᵀ F, ψᵀ F).
pub fn gemm_transposed(
    m: usize,
    k: usize,
    n: usize,
    a: &[f64],
    b: &[f64],
    beta: f64,
    c: &mut [f64],
) {
    let at = Strided {
        offset: 0,
        row_stride: 1,
        col_stride: m,
    };
    let rn = Strided::rows(0, n);
    gemm(m, k, n, 1.0, a, at, b, rn, beta, c, rn);
}

/// C ← α A B + β C for A (m×k), B (k×n), C (m×n) given as strided views into slices.
///
/// A plain i-k-j loop whose innermost loop runs over contiguous rows of B and C when their
/// column stride is 1 (so it vectorises), and which never allocates — BLAS-style libraries
/// allocate packing buffers on every call, which the step loop must not do. The matrices of
/// a step are small (at most a few hundred rows), where this loop is within a small factor of
/// a packed kernel. Panics only on inconsistent strides (a programming error inside the
/// crate, never on user data).
#[allow(clippy::too_many_arguments)]
pub fn gemm(
    m: usize,
    k: usize,
    n: usize,
    alpha: f64,
    a: &[f64],
    sa: Strided,
    b: &[f64],
    sb: Strided,
    beta: f64,
    c: &mut [f64],
    sc: Strided,
) {
    if m == 0 || n == 0 {
        return;
    }
    assert!(k == 0 || sa.last(m, k) < a.len(), "gemm: A out of bounds");
    assert!(k == 0 || sb.last(k, n) < b.len(), "gemm: B out of bounds");
    assert!(sc.last(m, n) < c.len(), "gemm: C out of bounds");
    if n <= 4 && sb.col_stride == 1 {
        // Few columns (C = Φ Q or Φᵀ F with D ≤ 4): static sizes, so the D sums of a row of C
        // are unrolled and kept in registers (the "static sizes for small D" of the step).
        // Both loop orders keep the summation order of the general loop below (bit-for-bit
        // the same results).
        let args = (m, k, alpha, a, sa, b, sb, beta);
        let row_major = sa.col_stride == 1;
        match (n, row_major) {
            (1, true) => thin::<1>(args, c, sc),
            (2, true) => thin::<2>(args, c, sc),
            (3, true) => thin::<3>(args, c, sc),
            (_, true) => thin::<4>(args, c, sc),
            (1, false) => thin_accumulate::<1>(args, c, sc),
            (2, false) => thin_accumulate::<2>(args, c, sc),
            (3, false) => thin_accumulate::<3>(args, c, sc),
            (_, false) => thin_accumulate::<4>(args, c, sc),
        }
        return;
    }
    if n <= 4 && sa.col_stride == 1 {
        // Few columns of a strided B: the n sums of a row of A accumulated together.
        for i in 0..m {
            let a0 = sa.offset + i * sa.row_stride;
            let mut acc = [0.0f64; 4];
            for (kk, &x) in a[a0..a0 + k].iter().enumerate() {
                let b0 = sb.offset + kk * sb.row_stride;
                for (j, s) in acc.iter_mut().enumerate().take(n) {
                    *s += x * b[b0 + j * sb.col_stride];
                }
            }
            for (j, &s) in acc.iter().enumerate().take(n) {
                let ci = sc.offset + i * sc.row_stride + j * sc.col_stride;
                c[ci] = alpha * s + if beta == 0.0 { 0.0 } else { beta * c[ci] };
            }
        }
        return;
    }
    let contiguous = sb.col_stride == 1 && sc.col_stride == 1;
    for i in 0..m {
        let c0 = sc.offset + i * sc.row_stride;
        if beta == 0.0 {
            for j in 0..n {
                c[c0 + j * sc.col_stride] = 0.0;
            }
        } else if beta != 1.0 {
            for j in 0..n {
                c[c0 + j * sc.col_stride] *= beta;
            }
        }
        let a0 = sa.offset + i * sa.row_stride;
        for kk in 0..k {
            let aik = alpha * a[a0 + kk * sa.col_stride];
            if aik == 0.0 {
                continue;
            }
            let b0 = sb.offset + kk * sb.row_stride;
            if contiguous {
                let crow = &mut c[c0..c0 + n];
                for (x, &y) in crow.iter_mut().zip(&b[b0..b0 + n]) {
                    *x += aik * y;
                }
            } else {
                for j in 0..n {
                    c[c0 + j * sc.col_stride] += aik * b[b0 + j * sb.col_stride];
                }
            }
        }
    }
}

/// The operands of [`thin`]: (m, k, alpha, A, its strides, B, its strides, beta).
type ThinArgs<'a> = (
    usize,
    usize,
    f64,
    &'a [f64],
    Strided,
    &'a [f64],
    Strided,
    f64,
);

/// C = alpha·A·B + beta·C for B with D contiguous columns (row-major rows of length D) and
/// A with contiguous rows: each row of C is D independent sums kept in registers, then
/// scaled. Bounds were checked by [`gemm`].
fn thin<const D: usize>(args: ThinArgs<'_>, c: &mut [f64], sc: Strided) {
    let (m, k, alpha, a, sa, b, sb, beta) = args;
    // Four rows of C at a time: their sums are independent, so interleaving them hides the
    // latency of each serial sum (every entry is still summed over k in order: the same bits).
    let store = |c: &mut [f64], i: usize, acc: &[f64; D]| {
        for j in 0..D {
            let ci = sc.offset + i * sc.row_stride + j * sc.col_stride;
            c[ci] = alpha * acc[j] + if beta == 0.0 { 0.0 } else { beta * c[ci] };
        }
    };
    let blocked = m - m % ROWS;
    for i in (0..blocked).step_by(ROWS) {
        let mut acc = [[0.0f64; D]; ROWS];
        for kk in 0..k {
            let o = sb.offset + kk * sb.row_stride;
            let br = &b[o..o + D];
            for (r, acc) in acc.iter_mut().enumerate() {
                let x = a[sa.offset + (i + r) * sa.row_stride + kk * sa.col_stride];
                for j in 0..D {
                    acc[j] += x * br[j];
                }
            }
        }
        for (r, acc) in acc.iter().enumerate() {
            store(c, i + r, acc);
        }
    }
    for i in blocked..m {
        let a0 = sa.offset + i * sa.row_stride;
        let mut acc = [0.0f64; D];
        for kk in 0..k {
            let x = a[a0 + kk * sa.col_stride];
            let o = sb.offset + kk * sb.row_stride;
            let br = &b[o..o + D];
            for j in 0..D {
                acc[j] += x * br[j];
            }
        }
        store(c, i, &acc);
    }
}

/// Rows of C the few-column kernels accumulate together.
const ROWS: usize = 4;

/// [`thin`] for A with strided rows (e.g. Φᵀ): C's row is scaled by beta first and
/// alpha·a_ik·B_k accumulated into it, in the order of the general loop of [`gemm`].
fn thin_accumulate<const D: usize>(args: ThinArgs<'_>, c: &mut [f64], sc: Strided) {
    let (m, k, alpha, a, sa, b, sb, beta) = args;
    let load = |c: &[f64], i: usize| {
        let c0 = sc.offset + i * sc.row_stride;
        let mut acc = [0.0f64; D];
        for (j, x) in acc.iter_mut().enumerate() {
            let cij = c[c0 + j * sc.col_stride];
            *x = if beta == 0.0 {
                0.0
            } else if beta != 1.0 {
                cij * beta
            } else {
                cij
            };
        }
        acc
    };
    let store = |c: &mut [f64], i: usize, acc: &[f64; D]| {
        let c0 = sc.offset + i * sc.row_stride;
        for (j, x) in acc.iter().enumerate() {
            c[c0 + j * sc.col_stride] = *x;
        }
    };
    // Four rows at a time, as in `thin`. A zero a_ik is skipped (as the general loop does):
    // adding its zero product instead would change nothing for finite B, but skip it anyway
    // so that every entry sees exactly the operations of the unblocked loop.
    let blocked = m - m % ROWS;
    for i in (0..blocked).step_by(ROWS) {
        let mut acc: [[f64; D]; ROWS] = std::array::from_fn(|r| load(c, i + r));
        for kk in 0..k {
            let o = sb.offset + kk * sb.row_stride;
            let br = &b[o..o + D];
            for (r, acc) in acc.iter_mut().enumerate() {
                let aik = alpha * a[sa.offset + (i + r) * sa.row_stride + kk * sa.col_stride];
                if aik == 0.0 {
                    continue;
                }
                for j in 0..D {
                    acc[j] += aik * br[j];
                }
            }
        }
        for (r, acc) in acc.iter().enumerate() {
            store(c, i + r, acc);
        }
    }
    for i in blocked..m {
        let mut acc = load(c, i);
        let a0 = sa.offset + i * sa.row_stride;
        for kk in 0..k {
            let aik = alpha * a[a0 + kk * sa.col_stride];
            if aik == 0.0 {
                continue;
            }
            let o = sb.offset + kk * sb.row_stride;
            let br = &b[o..o + D];
            for j in 0..D {
                acc[j] += aik * br[j];
            }
        }
        store(c, i, &acc);
    }
}

#[cfg(test)]
mod gemm_tests {
    use super::*;

    /// The static-size few-column kernels (D = 1…4) against a naive product, for row-major
    /// and transposed A, contiguous and strided B, and every beta case.
    #[test]
    fn few_column_kernels_match_a_naive_product() {
        let (m, k) = (5, 7);
        let a: Vec<f64> = (0..m * k).map(|x| (x as f64 * 0.3).sin()).collect();
        let at: Vec<f64> = (0..k * m).map(|idx| a[(idx % m) * k + idx / m]).collect();
        for n in 1..=4 {
            let b: Vec<f64> = (0..k * n).map(|x| (x as f64 * 0.7).cos()).collect();
            let bt: Vec<f64> = (0..n * k).map(|idx| b[(idx % k) * n + idx / k]).collect();
            let a_views = [
                (&a, Strided::rows(0, k)),
                (
                    &at,
                    Strided {
                        offset: 0,
                        row_stride: 1,
                        col_stride: m,
                    },
                ),
            ];
            let b_views = [
                (&b, Strided::rows(0, n)),
                (
                    &bt,
                    Strided {
                        offset: 0,
                        row_stride: 1,
                        col_stride: k,
                    },
                ),
            ];
            for (av, sa) in a_views {
                for (bv, sb) in b_views {
                    for (alpha, beta) in [(1.0, 0.0), (2.0, 1.0), (-1.5, 0.5)] {
                        let mut c = vec![0.25; m * n];
                        gemm(
                            m,
                            k,
                            n,
                            alpha,
                            av,
                            sa,
                            bv,
                            sb,
                            beta,
                            &mut c,
                            Strided::rows(0, n),
                        );
                        for i in 0..m {
                            for j in 0..n {
                                let dot: f64 = (0..k).map(|t| a[i * k + t] * b[t * n + j]).sum();
                                let exact = alpha * dot + beta * 0.25;
                                assert!((c[i * n + j] - exact).abs() < 1e-13, "n = {n}");
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn gemm_matches_a_naive_product_with_strides() {
        let (m, k, n) = (3, 4, 5);
        let a: Vec<f64> = (0..m * k).map(|x| (x as f64).sin()).collect();
        let b: Vec<f64> = (0..k * n).map(|x| (x as f64 * 0.7).cos()).collect();
        // B transposed view: B stored as n×k.
        let bt: Vec<f64> = (0..n * k).map(|idx| b[(idx % k) * n + idx / k]).collect();
        let mut c = vec![1.0; 2 * m * n];
        let sc = Strided {
            offset: 1,
            row_stride: 2 * n,
            col_stride: 2,
        };
        gemm(
            m,
            k,
            n,
            2.0,
            &a,
            Strided::rows(0, k),
            &bt,
            Strided {
                offset: 0,
                row_stride: 1,
                col_stride: k,
            },
            0.5,
            &mut c,
            sc,
        );
        for i in 0..m {
            for j in 0..n {
                let exact: f64 =
                    0.5 + 2.0 * (0..k).map(|t| a[i * k + t] * b[t * n + j]).sum::<f64>();
                assert!((c[1 + i * 2 * n + 2 * j] - exact).abs() < 1e-13);
            }
        }
        assert_eq!(c[0], 1.0);
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
