//! Double-double helpers: error-free sums and products (TwoSum, Fast2Sum, FMA) used to keep
//! the stage residuals and the state increments free of rounding bias (docs/DESIGN.md §4),
//! and the max-norm the Newton iteration measures its residuals and increments with.

/// The max-norm max_i |x_i| (0 for an empty slice).
pub(super) fn max_abs(x: &[f64]) -> f64 {
    // Four running maxima side by side (one alone is a serial chain of `max` latencies, 4 %
    // of a Kepler step); `max` is exact and ignores NaN, so the order does not matter.
    let mut lanes = [0.0f64; 4];
    let chunks = x.chunks_exact(4);
    let rest = chunks.remainder();
    for c in chunks {
        for (l, v) in lanes.iter_mut().zip(c) {
            *l = l.max(v.abs());
        }
    }
    let m = lanes[0].max(lanes[1]).max(lanes[2].max(lanes[3]));
    rest.iter().fold(m, |m, v| m.max(v.abs()))
}

/// max |x_i|, or ∞ when an entry is not finite: [`max_abs`] with NaN counted as ∞ (a select
/// per entry, so the lanes still vectorise, where a separate `is_finite` test per entry kept
/// the residual's closing loop scalar: 5 % of the outer solar system's step).
pub(super) fn max_abs_or_infinite(x: &[f64]) -> f64 {
    let mut lanes = [0.0f64; 4];
    let size = |v: f64| if v.is_nan() { f64::INFINITY } else { v.abs() };
    let chunks = x.chunks_exact(4);
    let rest = chunks.remainder();
    for c in chunks {
        for (l, &v) in lanes.iter_mut().zip(c) {
            *l = l.max(size(v));
        }
    }
    let m = lanes[0].max(lanes[1]).max(lanes[2].max(lanes[3]));
    rest.iter().fold(m, |m, &v| m.max(size(v)))
}

/// Knuth's TwoSum: s = fl(a + b) and the exact rounding error e, a + b = s + e.
#[inline]
pub(super) fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// hi + lo += a·b with the product exact (FMA) and the sum compensated (TwoSum).
#[inline]
pub(super) fn dd_acc(hi: &mut f64, lo: &mut f64, a: f64, b: f64) {
    let prod = a * b;
    let low = a.mul_add(b, -prod);
    let (s, e) = two_sum(*hi, prod);
    *hi = s;
    *lo += e + low;
}

/// (a_hi + a_lo) + (b_hi + b_lo) as a normalised hi + lo pair (double-double addition):
/// unlike Kahan's `two_sum(a, b + a_lo)`, the low parts are not rounded away when the
/// increment is as large as the sum (steps of a large-h spectral method).
#[inline]
pub(super) fn dd_add(a_hi: f64, a_lo: f64, b_hi: f64, b_lo: f64) -> (f64, f64) {
    let (s, e) = two_sum(a_hi, b_hi);
    let (t, f) = two_sum(a_lo, b_lo);
    let (s, e) = fast_two_sum(s, e + t);
    fast_two_sum(s, e + f)
}

/// Dekker's Fast2Sum for |a| ≥ |b|.
#[inline]
fn fast_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    (s, b - (s - a))
}

/// Lanes of the column-wise double-double sums: the D sums of a row are independent, so they
/// are accumulated side by side (vectorised, and without the latency of one serial TwoSum
/// chain), each in the same order of terms as a sum on its own — bit for bit the same result.
const LANES: usize = 8;

/// (hi[r], lo[r]) += Σ_j c(j)·x[j·d + r] for r = 0…d−1 by [`dd_acc`], the terms of each sum
/// in the order of j (x: rows of length d; hi, lo: length d).
#[inline]
pub(super) fn dd_acc_columns(
    terms: usize,
    c: impl Fn(usize) -> f64,
    x: &[f64],
    d: usize,
    hi: &mut [f64],
    lo: &mut [f64],
) {
    for r0 in (0..d).step_by(LANES) {
        let w = LANES.min(d - r0);
        let (mut h, mut l) = ([0.0; LANES], [0.0; LANES]);
        h[..w].copy_from_slice(&hi[r0..r0 + w]);
        l[..w].copy_from_slice(&lo[r0..r0 + w]);
        for j in 0..terms {
            let cj = c(j);
            let xs = &x[j * d + r0..j * d + r0 + w];
            for ((h, l), &x) in h.iter_mut().zip(l.iter_mut()).zip(xs) {
                dd_acc(h, l, cj, x);
            }
        }
        hi[r0..r0 + w].copy_from_slice(&h[..w]);
        lo[r0..r0 + w].copy_from_slice(&l[..w]);
    }
}
