//! Small dense matrix products without allocation: [`gemm`] over strided views
//! ([`Strided`]), with static-size kernels for the few-column products of a step (the curve at
//! the nodes, the projections of node values, D ≤ 4), and [`gemm_transposed`] for the
//! projections on a node table.

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

    /// The transpose of dense row-major storage with `cols` columns starting at offset 0:
    /// element (i, j) is stored entry (j, i), so the view has contiguous columns.
    pub fn transposed(cols: usize) -> Self {
        Strided {
            offset: 0,
            row_stride: 1,
            col_stride: cols,
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
    let at = Strided::transposed(m);
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
            (1, true) => thin::<1, false>(args, c, sc),
            (2, true) => thin::<2, false>(args, c, sc),
            (3, true) => thin::<3, false>(args, c, sc),
            (_, true) => thin::<4, false>(args, c, sc),
            (1, false) => thin::<1, true>(args, c, sc),
            (2, false) => thin::<2, true>(args, c, sc),
            (3, false) => thin::<3, true>(args, c, sc),
            (_, false) => thin::<4, true>(args, c, sc),
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
    if contiguous && n >= LANES {
        wide((m, k, alpha, a, sa, b, sb, beta), n, c, sc);
        return;
    }
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

/// C = alpha·A·B + beta·C for B with D contiguous columns (row-major rows of length D): each
/// row of C is D independent sums kept in registers. Bounds were checked by [`gemm`].
///
/// Two summation orders, each that of a plain loop, so that the blocking changes no bit:
/// - `ACCUMULATE = false` (A with contiguous rows, C = Φ Q): the D sums of a_ik·b_kj from zero,
///   then scaled, alpha·sum + beta·c;
/// - `ACCUMULATE = true` (A with strided rows, e.g. Φᵀ F): C's row is scaled by beta first
///   and alpha·a_ik·B_k accumulated into it, in the order of the general loop of [`gemm`],
///   a zero alpha·a_ik skipped as there (adding its zero product would change nothing for
///   finite B, but every entry then sees exactly the operations of the unblocked loop).
fn thin<const D: usize, const ACCUMULATE: bool>(args: ThinArgs<'_>, c: &mut [f64], sc: Strided) {
    // Four rows of C at a time, the remaining ones as one block too: their sums are
    // independent, so interleaving them hides the latency of each serial sum (every entry is
    // still summed over k in order: the same bits).
    let m = args.0;
    let blocked = m - m % ROWS;
    for i in (0..blocked).step_by(ROWS) {
        thin_rows::<D, ROWS, ACCUMULATE>(args, i, c, sc);
    }
    match m - blocked {
        1 => thin_rows::<D, 1, ACCUMULATE>(args, blocked, c, sc),
        2 => thin_rows::<D, 2, ACCUMULATE>(args, blocked, c, sc),
        3 => thin_rows::<D, 3, ACCUMULATE>(args, blocked, c, sc),
        _ => {}
    }
}

/// [`thin`] on rows i … i + R − 1.
fn thin_rows<const D: usize, const R: usize, const ACCUMULATE: bool>(
    args: ThinArgs<'_>,
    i: usize,
    c: &mut [f64],
    sc: Strided,
) {
    let (_, k, alpha, a, sa, b, sb, beta) = args;
    let mut acc = [[0.0f64; D]; R];
    if ACCUMULATE {
        for (r, acc) in acc.iter_mut().enumerate() {
            let c0 = sc.offset + (i + r) * sc.row_stride;
            for (j, x) in acc.iter_mut().enumerate() {
                *x = scaled_start(beta, c[c0 + j * sc.col_stride]);
            }
        }
    }
    for kk in 0..k {
        let o = sb.offset + kk * sb.row_stride;
        let br = &b[o..o + D];
        for (r, acc) in acc.iter_mut().enumerate() {
            let x = a[sa.offset + (i + r) * sa.row_stride + kk * sa.col_stride];
            let x = if ACCUMULATE { alpha * x } else { x };
            if ACCUMULATE && x == 0.0 {
                continue;
            }
            for j in 0..D {
                acc[j] += x * br[j];
            }
        }
    }
    for (r, acc) in acc.iter().enumerate() {
        for j in 0..D {
            let ci = sc.offset + (i + r) * sc.row_stride + j * sc.col_stride;
            c[ci] = if ACCUMULATE {
                acc[j]
            } else {
                alpha * acc[j] + if beta == 0.0 { 0.0 } else { beta * c[ci] }
            };
        }
    }
}

/// The value an entry of C starts its sum from in the i-k-j loop of [`gemm`]: 0 for β = 0
/// (C is not read), c for β = 1, β·c otherwise — so the register kernels give its bits.
#[inline]
fn scaled_start(beta: f64, c: f64) -> f64 {
    if beta == 0.0 {
        0.0
    } else if beta != 1.0 {
        c * beta
    } else {
        c
    }
}

/// Rows of C the few-column kernels accumulate together.
const ROWS: usize = 4;

/// Columns of C the wide kernel keeps in one register block (one AVX-512 register, two AVX2).
const LANES: usize = 8;

/// The general product for contiguous rows of B and C with at least [`LANES`] columns: C is
/// cut into blocks of [`ROWS`] × [`LANES`] entries held in registers over the whole k-loop
/// (the i-k-j loop instead loads and stores its row of C at every k, a chain through memory
/// that bounds it by latency: the GMRES products of the 10-body step spent 41 % there). The
/// t = n mod [`LANES`] columns left over take a block of 1, 2 or 4 lanes (t ≤ 4; D = 18, an
/// outer-solar-system state, is 8 + 8 + 2) or one of [`LANES`] that overlaps the block before
/// it, of which only the new columns are stored. Every entry sees the operations of the i-k-j
/// loop in the same order — the β-scaled C, then α·a_ik·b_kj for k ascending, a zero α·a_ik
/// skipped — so the results are the same bits.
fn wide(args: ThinArgs<'_>, n: usize, c: &mut [f64], sc: Strided) {
    let m = args.0;
    let full = n - n % LANES;
    let mut blocks = (0..full).step_by(LANES);
    let blocked_rows = m - m % ROWS;
    // Four rows × one column block, or one row × four column blocks: four independent sums
    // in flight either way (one sum alone is bound by the latency of its additions).
    let mut group = [0; ROWS];
    loop {
        let mut len = 0;
        for slot in group.iter_mut() {
            match blocks.next() {
                Some(j0) => {
                    *slot = j0;
                    len += 1;
                }
                None => break,
            }
        }
        if len == 0 {
            break;
        }
        for &j0 in &group[..len] {
            for i in (0..blocked_rows).step_by(ROWS) {
                wide_block::<ROWS, 1, LANES>(args, i, [(j0, 0)], c, sc);
            }
        }
        for i in blocked_rows..m {
            let b = |g: usize| (group[g], 0);
            match len {
                4 => wide_block::<1, 4, LANES>(args, i, [b(0), b(1), b(2), b(3)], c, sc),
                3 => wide_block::<1, 3, LANES>(args, i, [b(0), b(1), b(2)], c, sc),
                2 => wide_block::<1, 2, LANES>(args, i, [b(0), b(1)], c, sc),
                _ => wide_block::<1, 1, LANES>(args, i, [b(0)], c, sc),
            }
        }
    }
    match n - full {
        0 => {}
        1 => wide_tail::<1>(args, n, c, sc),
        2 => wide_tail::<2>(args, n, c, sc),
        3 | 4 => wide_tail::<4>(args, n, c, sc),
        _ => wide_tail::<LANES>(args, n, c, sc),
    }
}

/// The last t ≤ L columns of C with blocks of L lanes ending at column n (L ≤ n), storing only
/// the t columns [`wide`]'s full blocks left.
fn wide_tail<const L: usize>(args: ThinArgs<'_>, n: usize, c: &mut [f64], sc: Strided) {
    let m = args.0;
    let block = (n - L, L - n % LANES);
    let blocked_rows = m - m % ROWS;
    for i in (0..blocked_rows).step_by(ROWS) {
        wide_block::<ROWS, 1, L>(args, i, [block], c, sc);
    }
    for i in blocked_rows..m {
        wide_block::<1, 1, L>(args, i, [block], c, sc);
    }
}

/// [`wide`] on rows i … i + R − 1 and G column blocks of L lanes (start, lanes to skip when
/// storing).
#[inline(always)]
fn wide_block<const R: usize, const G: usize, const L: usize>(
    args: ThinArgs<'_>,
    i: usize,
    blocks: [(usize, usize); G],
    c: &mut [f64],
    sc: Strided,
) {
    let (_, k, alpha, a, sa, b, sb, beta) = args;
    let mut acc = [[[0.0f64; L]; G]; R];
    for (r, acc) in acc.iter_mut().enumerate() {
        for (acc, &(j0, _)) in acc.iter_mut().zip(&blocks) {
            let c0 = sc.offset + (i + r) * sc.row_stride + j0;
            for (x, &cij) in acc.iter_mut().zip(&c[c0..c0 + L]) {
                *x = scaled_start(beta, cij);
            }
        }
    }
    for kk in 0..k {
        let o = sb.offset + kk * sb.row_stride;
        for (r, acc) in acc.iter_mut().enumerate() {
            let aik = alpha * a[sa.offset + (i + r) * sa.row_stride + kk * sa.col_stride];
            if aik == 0.0 {
                continue;
            }
            for (acc, &(j0, _)) in acc.iter_mut().zip(&blocks) {
                let br = &b[o + j0..o + j0 + L];
                for l in 0..L {
                    acc[l] += aik * br[l];
                }
            }
        }
    }
    for (r, acc) in acc.iter().enumerate() {
        for (acc, &(j0, skip)) in acc.iter().zip(&blocks) {
            let c0 = sc.offset + (i + r) * sc.row_stride + j0;
            c[c0 + skip..c0 + L].copy_from_slice(&acc[skip..]);
        }
    }
}

#[cfg(test)]
mod gemm_tests {
    use super::*;

    /// The static-size few-column kernels (D = 1…4) against a naive product, for row-major
    /// and transposed A, contiguous and strided B, and every beta case.
    #[test]
    fn few_column_kernels_match_a_naive_product() {
        // m = 5 … 8: every remainder of the four-row blocks.
        for (m, k) in [(5, 7), (6, 7), (7, 3), (8, 7)] {
            let a: Vec<f64> = (0..m * k).map(|x| (x as f64 * 0.3).sin()).collect();
            let at: Vec<f64> = (0..k * m).map(|idx| a[(idx % m) * k + idx / m]).collect();
            for n in 1..=4 {
                let b: Vec<f64> = (0..k * n).map(|x| (x as f64 * 0.7).cos()).collect();
                let bt: Vec<f64> = (0..n * k).map(|idx| b[(idx % k) * n + idx / k]).collect();
                let a_views = [(&a, Strided::rows(0, k)), (&at, Strided::transposed(m))];
                let b_views = [(&b, Strided::rows(0, n)), (&bt, Strided::transposed(k))];
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
                                    let dot: f64 =
                                        (0..k).map(|t| a[i * k + t] * b[t * n + j]).sum();
                                    let exact = alpha * dot + beta * 0.25;
                                    assert!((c[i * n + j] - exact).abs() < 1e-13, "n = {n}");
                                }
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
            Strided::transposed(k),
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

    /// The register-blocked wide kernel gives the i-k-j loop's bits: shapes with row and
    /// column remainders, A row-major and transposed (with zeros, which both skip), offsets
    /// into B and C, and every beta case.
    #[test]
    fn wide_kernel_gives_the_bits_of_the_ikj_loop() {
        for (m, k, n) in [
            (4, 3, 8),
            (50, 24, 30),
            (7, 5, 19),
            (24, 50, 30),
            (1, 30, 30),
            (2, 7, 41),
            (10, 9, 18),
            (15, 9, 17),
            (9, 10, 20),
            (5, 9, 27),
            (10, 9, 16),
        ] {
            let a: Vec<f64> = (0..m * k)
                .map(|x| {
                    if x % 7 == 3 {
                        0.0
                    } else {
                        (x as f64 * 0.37).sin()
                    }
                })
                .collect();
            let b: Vec<f64> = (0..k * n + 3).map(|x| (x as f64 * 0.71).cos()).collect();
            let views = [Strided::rows(0, k), Strided::transposed(m)];
            for sa in views {
                for (alpha, beta) in [(1.0, 0.0), (1.0, 1.0), (-1.5, 0.5)] {
                    let sb = Strided::rows(3, n);
                    let sc = Strided::rows(2, n);
                    let c0: Vec<f64> = (0..m * n + 2).map(|x| (x as f64 * 0.13).sin()).collect();
                    let mut c = c0.clone();
                    gemm(m, k, n, alpha, &a, sa, &b, sb, beta, &mut c, sc);
                    // The i-k-j loop, written out.
                    let mut r = c0.clone();
                    for i in 0..m {
                        for j in 0..n {
                            let x = &mut r[2 + i * n + j];
                            *x = if beta == 0.0 {
                                0.0
                            } else if beta != 1.0 {
                                *x * beta
                            } else {
                                *x
                            };
                        }
                        for kk in 0..k {
                            let aik = alpha * a[i * sa.row_stride + kk * sa.col_stride];
                            if aik == 0.0 {
                                continue;
                            }
                            for j in 0..n {
                                r[2 + i * n + j] += aik * b[3 + kk * n + j];
                            }
                        }
                    }
                    assert_eq!(c, r, "m = {m}, k = {k}, n = {n}, beta = {beta}");
                }
            }
        }
    }
}
