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

/// Rows of C the wide kernel holds in registers at once. With AVX-512 two rows of [`GROUP`]
/// blocks are 8 of the 32 vector registers; four rows (16) made LLVM spill accumulators to
/// the stack (the 10×9 by 9×30 product of the J2000 step: 230 ns at two rows, 800–1 800 ns at
/// four). With 256-bit vectors a block takes two registers of 16, and one row is fastest
/// (300 ns, against 380 ns at two rows; `x86-64-v3` build).
const WIDE_ROWS: usize = if cfg!(target_feature = "avx512f") {
    2
} else {
    1
};

/// Column blocks of [`LANES`] the wide kernel holds per row.
const GROUP: usize = 4;

/// The general product for contiguous rows of B and C with at least [`LANES`] columns: C is
/// cut into blocks of [`WIDE_ROWS`] rows × [`GROUP`] column blocks of [`LANES`] entries, held
/// in registers over the whole k-loop (the i-k-j loop instead loads and stores its row of C at
/// every k, a chain through memory that bounds it by latency: the GMRES products of the
/// 10-body step spent 41 % there). The t = n mod [`LANES`] columns left over take one block of
/// [`LANES`] ending at column n, which overlaps the block before it; the two are always in one
/// group (groups are taken from the last block back), and a group reads its entries of C
/// before it stores any, so the overlapping lanes repeat the same operations on the same
/// values and store the same bits. D = 30, a 10-body state, is one group: columns 0, 8, 16
/// and 22.
///
/// Each a_ik is read and scaled once per row and k for all of the group's blocks. Issue 35's
/// profile of the J2000 run put 28 % of its time in these products when each row took one
/// block at a time, with that scalar work and a test for a zero α·a_ik per vector
/// multiply–add: 410 ns for the 10×9 by 9×30 product of the curve at the nodes on the
/// AVX-512 machine of the studies, now 230 ns (`x86-64-v3` build: 650 → 300 ns).
///
/// Every entry sees the i-k-j loop's operations in its order — the β-scaled C, then α·a_ik·b_kj
/// for k ascending — except that zero coefficients are not skipped: adding a zero product
/// leaves a finite sum unchanged bit for bit, except that an exactly zero sum −0 becomes +0
/// (and a non-finite b_kj now propagates, as IEEE arithmetic has it).
fn wide(args: ThinArgs<'_>, n: usize, c: &mut [f64], sc: Strided) {
    let full = n / LANES;
    let count = n.div_ceil(LANES);
    // First columns of the blocks: the full ones, then the block ending at column n.
    let block = |g: usize| if g < full { g * LANES } else { n - LANES };
    // Groups from the last block back, so that the overlapping block and the one before it
    // are in one group: each group reads its entries of C before it stores any, so the
    // overlapping lanes repeat the same operations on the same values and store the same bits.
    let mut end = count;
    while end > 0 {
        let g = end.saturating_sub(GROUP);
        match end - g {
            1 => wide_rows::<1>(args, [block(g)], c, sc),
            2 => wide_rows::<2>(args, [block(g), block(g + 1)], c, sc),
            3 => wide_rows::<3>(args, [block(g), block(g + 1), block(g + 2)], c, sc),
            _ => wide_rows::<GROUP>(
                args,
                [block(g), block(g + 1), block(g + 2), block(g + 3)],
                c,
                sc,
            ),
        }
        end = g;
    }
}

/// [`wide`] on every row for one group of G column blocks: [`WIDE_ROWS`] rows at a time, then
/// the remaining rows one by one.
fn wide_rows<const G: usize>(args: ThinArgs<'_>, blocks: [usize; G], c: &mut [f64], sc: Strided) {
    let m = args.0;
    let blocked = m - m % WIDE_ROWS;
    for i in (0..blocked).step_by(WIDE_ROWS) {
        wide_block::<WIDE_ROWS, G, LANES>(args, i, blocks, c, sc);
    }
    for i in blocked..m {
        wide_block::<1, G, LANES>(args, i, blocks, c, sc);
    }
}

/// [`wide`] on rows i … i + R − 1 and the G column blocks of L lanes starting at `blocks`.
#[inline(always)]
fn wide_block<const R: usize, const G: usize, const L: usize>(
    args: ThinArgs<'_>,
    i: usize,
    blocks: [usize; G],
    c: &mut [f64],
    sc: Strided,
) {
    let (_, k, alpha, a, sa, b, sb, beta) = args;
    let mut acc = [[[0.0f64; L]; G]; R];
    for (r, acc) in acc.iter_mut().enumerate() {
        for (acc, &j0) in acc.iter_mut().zip(&blocks) {
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
            for (acc, &j0) in acc.iter_mut().zip(&blocks) {
                let br = &b[o + j0..o + j0 + L];
                for l in 0..L {
                    acc[l] += aik * br[l];
                }
            }
        }
    }
    for (r, acc) in acc.iter().enumerate() {
        for (acc, &j0) in acc.iter().zip(&blocks) {
            let c0 = sc.offset + (i + r) * sc.row_stride + j0;
            c[c0..c0 + L].copy_from_slice(acc);
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

    /// The register-blocked wide kernel gives the bits of the i-k-j loop that adds every
    /// product (zeros too): shapes with row and column remainders, more than one group of
    /// column blocks (n > 32, with and without an overlapping block), A row-major and
    /// transposed, offsets into B and C, and every beta case.
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
            (10, 9, 30),
            (3, 5, 70),
            (11, 9, 36),
            (6, 4, 64),
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
                            for j in 0..n {
                                r[2 + i * n + j] += aik * b[3 + kk * n + j];
                            }
                        }
                    }
                    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(
                        bits(&c),
                        bits(&r),
                        "m = {m}, k = {k}, n = {n}, beta = {beta}"
                    );
                }
            }
        }
    }
}
