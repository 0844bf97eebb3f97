//! Distances between states that keep a NaN visible: a run that blew up must not look like a
//! perfect one, and `f64::max` silently drops a NaN.

/// max(a, b), but NaN if either is NaN (`f64::max` drops a NaN, which turns a run that blew
/// up into a perfect-looking error of 0).
pub(crate) fn nan_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// Max-norm of a − b; NaN if any difference is NaN.
pub(crate) fn max_norm_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, nan_max)
}
