//! Maxima over errors that keep a NaN visible.
//!
//! `f64::max` returns the other operand when one is NaN, so `errors.fold(0.0, f64::max)`
//! silently drops every NaN: a run that blew up half-way reports the largest finite error of
//! the steps before, and looks like it conserved its energy. Every maximum of an error that
//! reaches a user goes through [`nan_max`] (or [`max_error`]) instead, so one NaN makes the
//! whole maximum NaN.

/// max(a, b), but NaN if either is NaN (`f64::max` drops a NaN).
///
/// ```
/// use galerkin_vi::reduce::nan_max;
/// assert_eq!(nan_max(1.0, 2.0), 2.0);
/// assert!(nan_max(1.0, f64::NAN).is_nan() && nan_max(f64::NAN, 1.0).is_nan());
/// assert!(f64::max(1.0, f64::NAN) == 1.0); // what this replaces
/// ```
pub fn nan_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// The largest of `errors`, 0 for none, NaN if any is NaN.
///
/// ```
/// use galerkin_vi::reduce::max_error;
/// assert_eq!(max_error([1e-3, 2e-3]), 2e-3);
/// assert_eq!(max_error([]), 0.0);
/// assert!(max_error([1e-3, f64::NAN, 2e-3]).is_nan());
/// ```
pub fn max_error(errors: impl IntoIterator<Item = f64>) -> f64 {
    errors.into_iter().fold(0.0, nan_max)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A NaN anywhere, first, last or between, makes the maximum NaN; infinities are kept.
    /// Negative control: the `fold(0.0, f64::max)` this replaces returns a finite number for
    /// the same series.
    #[test]
    fn a_nan_anywhere_makes_the_maximum_nan() {
        for series in [
            [f64::NAN, 1.0, 2.0],
            [1.0, f64::NAN, 2.0],
            [1.0, 2.0, f64::NAN],
        ] {
            assert!(max_error(series).is_nan(), "{series:?}");
            assert_eq!(series.iter().copied().fold(0.0, f64::max), 2.0);
        }
        assert_eq!(max_error([1.0, f64::INFINITY]), f64::INFINITY);
        assert_eq!(max_error([3.0, -1.0, 2.0]), 3.0);
    }
}
