//! Distances between states that keep a NaN visible: a run that blew up must not look like a
//! perfect one, and `f64::max` silently drops a NaN.

/// max(a, b), but NaN if either is NaN: the library's ([`galerkin_vi::reduce`]), so the lab
/// and the library keep a NaN the same way (`f64::max` drops it, which turns a run that blew
/// up into a perfect-looking error of 0).
pub(crate) use galerkin_vi::reduce::nan_max;

/// Max-norm of a − b; NaN if any difference is NaN.
pub(crate) fn max_norm_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, nan_max)
}
