//! Robust fitting of convergence rates from refinement studies.
//!
//! Geometric (spectral) data `e(n) ≈ C·Kⁿ` are fitted as a line through
//! `(n, log10 e)`, `K = 10^slope`; algebraic (mesh) data `e(h) ≈ C·hᵖ` as a
//! line through `(log10 h, log10 e)`, `p = slope`. The automatic fits sort the
//! valid points into refinement order (increasing `n`, decreasing `h`;
//! refinement coordinate `t = n` or `t = -log10 h`) and then
//!
//! 1. detect the round-off floor ([`detect_floor`]) and drop the floor points
//!    and the trailing points within a factor 10 of the floor level (unless
//!    fewer than 3 points would be left);
//! 2. estimate the noise `σ` of `log10 e` as the larger of the RMS residual of
//!    a line through the finest half of the remaining points and a
//!    median-based estimate from each point's deviation from the chord through
//!    its two neighbours;
//! 3. among the contiguous windows of at least 3 points ending at the floor
//!    boundary, take the one with the most points whose RMS log10 residual is
//!    at most `max(0.01, 2σ)` decades *and* whose 3 coarsest points deviate on
//!    average from the line through the rest of the window by at most 2.5
//!    standard errors (or 0.01 decades). A curved pre-asymptotic start is thus
//!    dropped; the window actually used is reported. With noisy data a mildly
//!    curved start can stay within tolerance: check `window` and `residual`,
//!    or fit a chosen window with the `*_in` variants.
//!
//! Everything is deterministic and no input makes these functions panic.

use FitError::*;
use serde::{Deserialize, Serialize};

// Tuning constants; see the module and `detect_floor` documentation.
const MIN_AUTO_POINTS: usize = 3;
const FLOOR_DROP: f64 = 3.0;
const FLOOR_EXCESS: f64 = 0.4;
const FLOOR_NOISE: f64 = 4.0;
const TREND_POINTS: usize = 10;
const FLOOR_MARGIN: f64 = 10.0;
const MIN_TOL: f64 = 0.01;
const NOISE_FACTOR: f64 = 2.0;
const COARSE_END: usize = 3;
const COARSE_FACTOR: f64 = 2.5;

/// Result of fitting `e ≈ C·Kⁿ`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GeometricFit {
    /// Convergence factor `K` per unit of `n`.
    pub rate: f64,
    /// Prefactor `C`.
    pub constant: f64,
    /// `(min n, max n)` of the points used.
    pub window: (f64, f64),
    /// Number of points used.
    pub points_used: usize,
    /// RMS of the log10 residuals in decades, `sqrt(SSE / points_used)`.
    pub residual: f64,
    /// Detected round-off floor (always `None` for explicit-window fits).
    pub floor: Option<f64>,
}

/// Result of fitting `e ≈ C·hᵖ`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AlgebraicFit {
    /// Order `p`.
    pub order: f64,
    /// Prefactor `C`.
    pub constant: f64,
    /// `(min h, max h)` of the points used.
    pub window: (f64, f64),
    /// Number of points used.
    pub points_used: usize,
    /// RMS of the log10 residuals in decades, `sqrt(SSE / points_used)`.
    pub residual: f64,
    /// Detected round-off floor (always `None` for explicit-window fits).
    pub floor: Option<f64>,
}

/// Errors of the fitting routines.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
pub enum FitError {
    /// Not enough usable points.
    #[error("need at least {needed} usable points, got {got}")]
    TooFewPoints {
        /// Minimum number of points required.
        needed: usize,
        /// Number of usable points supplied.
        got: usize,
    },
    /// A non-finite value where a finite one is required, or fewer than 3
    /// points left after dropping invalid (non-finite, negative, `h <= 0`) ones.
    #[error("non-finite or invalid values in the data")]
    NonFinite,
    /// A value that must be logarithmed is `<= 0` (`index` into the input).
    #[error("non-positive value {value} at index {index} cannot be log-transformed")]
    NonPositive {
        /// Index of the offending point in the input slices.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// The abscissa and error slices differ in length.
    #[error("length mismatch: {x_len} abscissae but {y_len} errors")]
    LengthMismatch {
        /// Length of the abscissa slice.
        x_len: usize,
        /// Length of the error slice.
        y_len: usize,
    },
    /// All abscissae are equal, so the slope is undefined.
    #[error("all abscissae are equal; the slope is undefined")]
    DegenerateAbscissa,
    /// The explicit window is not finite or has `lo > hi`.
    #[error("invalid fit window [{lo}, {hi}]")]
    InvalidWindow {
        /// Requested lower end.
        lo: f64,
        /// Requested upper end.
        hi: f64,
    },
    /// Fewer than 3 points above the floor, or no window fits a line.
    #[error("no window of at least 3 points above the round-off floor fits a straight line")]
    NoAsymptoticWindow,
}

/// Least-squares line through `(x, log10 y)`: returns `(slope, intercept, rms
/// residual)`, the residual in decades (`sqrt(SSE / len)`).
///
/// Errors: `LengthMismatch`; `NonFinite` for any non-finite `x` or `y`;
/// `NonPositive` for `y <= 0`; `TooFewPoints` for fewer than 2 points;
/// `DegenerateAbscissa` if all `x` are equal.
pub fn log_linear_fit(x: &[f64], y: &[f64]) -> Result<(f64, f64, f64), FitError> {
    check_len(x, y)?;
    for (index, (&xi, &value)) in x.iter().zip(y).enumerate() {
        if !xi.is_finite() || !value.is_finite() {
            return Err(NonFinite);
        } else if value <= 0.0 {
            return Err(NonPositive { index, value });
        }
    }
    let ly: Vec<f64> = y.iter().map(|v| v.log10()).collect();
    line_fit(x, &ly)
}

/// Fit `e ≈ C·Kⁿ` over the automatically chosen window above the round-off
/// floor (algorithm in the module documentation).
///
/// Points may come in any order. Points with non-finite `n` or `err`, or a
/// negative `err`, are dropped; an exact zero error is a floor point.
/// Errors: `LengthMismatch`; with fewer than 3 valid points `NonFinite` if
/// invalid points were dropped, else `TooFewPoints`; `NoAsymptoticWindow` if
/// fewer than 3 points lie above the floor or no window passes the line test.
///
/// ```
/// use galerkin_vi_lab::fit::fit_geometric;
/// let n: Vec<f64> = (1..=60).map(f64::from).collect();
/// let err: Vec<f64> = n.iter().map(|&k| (3.0 * 0.5f64.powf(k)).max(1e-14)).collect();
/// let fit = fit_geometric(&n, &err).unwrap();
/// assert!((fit.rate - 0.5).abs() < 1e-6 && (fit.constant - 3.0).abs() < 1e-6);
/// assert_eq!(fit.floor, Some(1e-14));
/// assert!(fit.window.1 < 49.0); // the floor (n >= 49) is excluded
/// ```
pub fn fit_geometric(n: &[f64], err: &[f64]) -> Result<GeometricFit, FitError> {
    auto_fit(n, err, false).map(geometric)
}

/// Fit `e ≈ C·Kⁿ` over the points with `lo <= n <= hi`; no floor detection.
///
/// Points outside the window are ignored whatever their values; inside it
/// every error must be finite (else `NonFinite`) and positive (else
/// `NonPositive`). At least 2 points are needed. `InvalidWindow` if `lo`/`hi`
/// are not finite or `lo > hi`.
pub fn fit_geometric_in(
    n: &[f64],
    err: &[f64],
    lo: f64,
    hi: f64,
) -> Result<GeometricFit, FitError> {
    explicit_fit(n, err, lo, hi, false).map(geometric)
}

/// Fit `e ≈ C·hᵖ` over the automatically chosen window (above the floor,
/// asymptotic). Input handling and errors as for [`fit_geometric`];
/// additionally points with `h <= 0` are dropped.
pub fn fit_algebraic(h: &[f64], err: &[f64]) -> Result<AlgebraicFit, FitError> {
    auto_fit(h, err, true).map(algebraic)
}

/// Fit `e ≈ C·hᵖ` over the points with `lo <= h <= hi`; no floor detection.
/// Rules as for [`fit_geometric_in`]; an `h <= 0` inside the window gives
/// `NonPositive`.
pub fn fit_algebraic_in(
    h: &[f64],
    err: &[f64],
    lo: f64,
    hi: f64,
) -> Result<AlgebraicFit, FitError> {
    explicit_fit(h, err, lo, hi, true).map(algebraic)
}

/// Detect a round-off floor: the level below which the error stops
/// decreasing. Returns `None` if the data keep decreasing to the end.
///
/// `decreasing_in_x = true`: the error decreases as `x` grows (spectral `n`,
/// refinement coordinate `t = x`); `false`: it decreases as `x` shrinks (mesh
/// size `h`, `t = -log10 x`, points with `x <= 0` dropped). Points with a
/// non-finite value or a negative error are dropped; mismatched lengths give
/// `None`.
///
/// With the points in refinement order, the floor starts at the first exact
/// zero error or at the first index `s >= 2` with at least one point after it
/// satisfying both, whichever comes first:
/// * (A) no meaningful further decrease: at most `(points after s) / 4` later
///   errors lie below `e_s / 3` (tolerates rare lucky low floor values);
/// * (B) stagnation: the least-squares line through `(t, log10 e)` of the (up
///   to 10) points before `s` decreases, and some point from `s` on lies above
///   it by at least `max(0.4, 4σ)` decades (`σ`: chord-based noise estimate).
///
/// (B) keeps slowly converging data, which pass (A) near the end, from being
/// taken for a floor. The level is the median of the positive errors from the
/// floor start on (`0.0` if all are zero).
pub fn detect_floor(x: &[f64], err: &[f64], decreasing_in_x: bool) -> Option<f64> {
    if x.len() != err.len() {
        return None;
    }
    floor_start(&prepare(x, err, !decreasing_in_x).0).map(|(_, level)| level)
}

/// A valid point: original abscissa, refinement coordinate, error.
struct Pt {
    x: f64,
    t: f64,
    e: f64,
}

/// `(slope, intercept, rms)` in the refinement coordinate, window of the
/// original abscissae, points used, floor.
type Raw = ((f64, f64, f64), (f64, f64), usize, Option<f64>);

fn raw(p: &[Pt], line: (f64, f64, f64), floor: Option<f64>) -> Raw {
    let lo = p.iter().map(|q| q.x).fold(f64::INFINITY, f64::min);
    let hi = p.iter().map(|q| q.x).fold(f64::NEG_INFINITY, f64::max);
    (line, (lo, hi), p.len(), floor)
}

fn geometric(((slope, intercept, residual), window, points_used, floor): Raw) -> GeometricFit {
    let (rate, constant) = (10f64.powf(slope), 10f64.powf(intercept));
    GeometricFit {
        rate,
        constant,
        window,
        points_used,
        residual,
        floor,
    }
}

/// With `t = -log10 h`, `log10 e = a + b·t` means `p = -b`.
fn algebraic(((slope, intercept, residual), window, points_used, floor): Raw) -> AlgebraicFit {
    let (order, constant) = (-slope, 10f64.powf(intercept));
    AlgebraicFit {
        order,
        constant,
        window,
        points_used,
        residual,
        floor,
    }
}

fn check_len(x: &[f64], y: &[f64]) -> Result<(), FitError> {
    let (x_len, y_len) = (x.len(), y.len());
    if x_len == y_len {
        Ok(())
    } else {
        Err(LengthMismatch { x_len, y_len })
    }
}

fn coord(x: f64, algebraic: bool) -> f64 {
    if algebraic { -x.log10() } else { x }
}

/// Least-squares line `y = intercept + slope·x` with centred sums.
fn line_fit(x: &[f64], y: &[f64]) -> Result<(f64, f64, f64), FitError> {
    let (needed, got) = (2, x.len());
    if got < needed {
        return Err(TooFewPoints { needed, got });
    } else if x.iter().all(|&v| v == x[0]) {
        return Err(DegenerateAbscissa);
    }
    let nf = got as f64;
    let (mx, my) = (x.iter().sum::<f64>() / nf, y.iter().sum::<f64>() / nf);
    let (mut sxx, mut sxy, mut sse) = (0.0, 0.0, 0.0);
    for (&xi, &yi) in x.iter().zip(y) {
        sxx += (xi - mx) * (xi - mx);
        sxy += (xi - mx) * (yi - my);
    }
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    for (&xi, &yi) in x.iter().zip(y) {
        sse += ((yi - my) - slope * (xi - mx)).powi(2);
    }
    let rms = (sse / nf).sqrt();
    if slope.is_finite() && intercept.is_finite() && rms.is_finite() {
        Ok((slope, intercept, rms))
    } else {
        Err(NonFinite)
    }
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    let m = v.len();
    match m {
        0 => None,
        _ if m % 2 == 1 => Some(v[m / 2]),
        _ => Some(0.5 * (v[m / 2 - 1] + v[m / 2])),
    }
}

/// `(t, log10 e)` of the points with a positive error.
fn log_points(p: &[Pt]) -> (Vec<f64>, Vec<f64>) {
    let pos = p.iter().filter(|q| q.e > 0.0);
    pos.map(|q| (q.t, q.e.log10())).unzip()
}

/// Valid points in refinement order, and the number of dropped points.
fn prepare(x: &[f64], err: &[f64], algebraic: bool) -> (Vec<Pt>, usize) {
    let mut pts = Vec::with_capacity(x.len());
    for (&x, &e) in x.iter().zip(err) {
        if x.is_finite() && e.is_finite() && e >= 0.0 && (!algebraic || x > 0.0) {
            let t = coord(x, algebraic);
            pts.push(Pt { x, t, e });
        }
    }
    pts.sort_by(|a, b| a.t.total_cmp(&b.t));
    let dropped = x.len() - pts.len();
    (pts, dropped)
}

/// Floor start index and level, see [`detect_floor`].
fn floor_start(p: &[Pt]) -> Option<(usize, f64)> {
    let zero = p.iter().position(|q| q.e == 0.0);
    let (t, l) = log_points(p);
    let excess = (FLOOR_NOISE * noise_sigma(&t, &l)).max(FLOOR_EXCESS);
    let found = (2..p.len().saturating_sub(1)).find(|&s| is_floor_start(p, s, excess));
    let s = match (zero, found) {
        (Some(z), Some(s)) => z.min(s),
        (z, s) => z.or(s)?,
    };
    let level = median(p[s..].iter().map(|q| q.e).filter(|&e| e > 0.0).collect());
    Some((s, level.unwrap_or(0.0)))
}

fn is_floor_start(p: &[Pt], s: usize, excess: f64) -> bool {
    let (es, after) = (p[s].e, &p[s + 1..]);
    let below = after.iter().filter(|q| q.e < es / FLOOR_DROP && q.e > 0.0);
    if es <= 0.0 || below.count() > after.len() / 4 {
        return false;
    }
    let (t, l) = log_points(&p[s.saturating_sub(TREND_POINTS)..s]);
    let Ok((b, a, _)) = line_fit(&t, &l) else {
        return false;
    };
    let (t, l) = log_points(&p[s..]);
    b < 0.0 && (0..t.len()).any(|i| l[i] - (a + b * t[i]) >= excess)
}

/// Robust noise level of `l(t)`: median of the normalised deviations of each
/// point from the chord through its neighbours, scaled to a standard deviation.
fn noise_sigma(t: &[f64], l: &[f64]) -> f64 {
    let mut dev = Vec::new();
    for i in 1..t.len().saturating_sub(1) {
        let span = t[i + 1] - t[i - 1];
        if span > 0.0 {
            let w2 = (t[i] - t[i - 1]) / span;
            let w0 = 1.0 - w2;
            let r = l[i] - (w0 * l[i - 1] + w2 * l[i + 1]);
            dev.push(r.abs() / (1.0 + w0 * w0 + w2 * w2).sqrt());
        }
    }
    median(dev).map_or(0.0, |m| m / 0.6745)
}

/// Mean deviation of the (up to `COARSE_END`) coarsest points from the line
/// through the rest of the window (at least 3 points) must be within
/// `COARSE_FACTOR` standard errors, or `MIN_TOL`.
fn coarse_end_ok(t: &[f64], l: &[f64], sigma: f64) -> bool {
    let k = COARSE_END.min(t.len().saturating_sub(3));
    if k == 0 {
        return true;
    }
    let Ok((b, a, _)) = line_fit(&t[k..], &l[k..]) else {
        return false;
    };
    let dev: f64 = (0..k).map(|i| l[i] - (a + b * t[i])).sum();
    let se = sigma * (1.0 / k as f64 + 4.0 / (t.len() - k) as f64).sqrt();
    (dev / k as f64).abs() <= (COARSE_FACTOR * se).max(MIN_TOL)
}

fn auto_fit(x: &[f64], err: &[f64], algebraic: bool) -> Result<Raw, FitError> {
    check_len(x, err)?;
    let (p, dropped) = prepare(x, err, algebraic);
    let (needed, got) = (MIN_AUTO_POINTS, p.len());
    if got < needed && dropped > 0 {
        return Err(NonFinite);
    } else if got < needed {
        return Err(TooFewPoints { needed, got });
    }
    let floor = floor_start(&p);
    let mut end = p.len();
    if let Some((s, level)) = floor {
        end = s;
        while end > 0 && p[end - 1].e < FLOOR_MARGIN * level {
            end -= 1;
        }
        if end < MIN_AUTO_POINTS {
            end = s;
        }
    }
    if end < MIN_AUTO_POINTS {
        return Err(NoAsymptoticWindow);
    }
    let (t, l) = log_points(&p[..end]); // all positive: zeros start the floor
    let half = end - (end / 2).max(MIN_AUTO_POINTS);
    let finest = line_fit(&t[half..], &l[half..]).map_or(0.0, |f| f.2);
    let sigma = finest.max(noise_sigma(&t, &l));
    let tol = (NOISE_FACTOR * sigma).max(MIN_TOL);
    for a in 0..=end - MIN_AUTO_POINTS {
        let Ok(line) = line_fit(&t[a..], &l[a..]) else {
            continue;
        };
        if line.2 <= tol && coarse_end_ok(&t[a..], &l[a..], sigma) {
            return Ok(raw(&p[a..end], line, floor.map(|f| f.1)));
        }
    }
    Err(NoAsymptoticWindow)
}

fn explicit_fit(x: &[f64], err: &[f64], lo: f64, hi: f64, alg: bool) -> Result<Raw, FitError> {
    check_len(x, err)?;
    if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
        return Err(InvalidWindow { lo, hi });
    }
    let mut pts = Vec::new();
    for (index, (&x, &e)) in x.iter().zip(err).enumerate() {
        if !(lo <= x && x <= hi) {
            continue;
        } else if !e.is_finite() {
            return Err(NonFinite);
        } else if e <= 0.0 || (alg && x <= 0.0) {
            let value = if e <= 0.0 { e } else { x };
            return Err(NonPositive { index, value });
        }
        let t = coord(x, alg);
        pts.push(Pt { x, t, e });
    }
    pts.sort_by(|a, b| a.t.total_cmp(&b.t));
    let (t, l) = log_points(&pts);
    Ok(raw(&pts, line_fit(&t, &l)?, None))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic (seeded) multiplicative noise factors in `[1 - amp, 1 + amp)`.
    fn noise(len: usize, amp: f64, seed: u64) -> Vec<f64> {
        use rand::{RngExt, SeedableRng};
        if amp == 0.0 {
            return vec![1.0; len];
        }
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        (0..len)
            .map(|_| rng.random_range(1.0 - amp..1.0 + amp))
            .collect()
    }

    fn near(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() < tol
    }

    /// `e = 3·Kⁿ·(1 ± 20 %)` floored at `floor·(1 ± 20 %)`, n = 4..=60.
    fn spectral(k: f64, floor: f64, seed: u64) -> (Vec<f64>, Vec<f64>) {
        let n: Vec<f64> = (4..=60).map(f64::from).collect();
        let (u, v) = (noise(57, 0.2, seed), noise(57, 0.2, seed + 1));
        let err = |i: usize| (3.0 * k.powf(n[i]) * u[i]).max(floor * v[i]);
        let e = (0..57).map(err).collect();
        (n, e)
    }

    /// `e = 2h⁶(1 + 5h²)·(1 ± amp)` floored at `1e-14·(1 ± amp)`, h = 10^(-3..0).
    fn mesh(amp: f64) -> (Vec<f64>, Vec<f64>) {
        let h: Vec<f64> = (0..=30).map(|i| 10f64.powf(0.1 * i as f64 - 3.0)).collect();
        let (u, v) = (noise(31, amp, 7), noise(31, amp, 8));
        let exact = |h: f64| 2.0 * h.powi(6) * (1.0 + 5.0 * h * h);
        let err = |i: usize| (exact(h[i]) * u[i]).max(1e-14 * v[i]);
        let e = (0..31).map(err).collect();
        (h, e)
    }

    #[test]
    fn geometric_rate_with_noise_and_floor() {
        for seed in 1..=8 {
            let (n, e) = spectral(0.56, 1e-14, seed);
            let f = fit_geometric(&n, &e).unwrap();
            assert!(near(f.rate, 0.56, 0.01) && f.residual < 0.1, "{f:?}");
            assert!(f.floor.is_some_and(|x| near(x, 1e-14, 2e-15)), "{f:?}");
            // The exact error meets the floor at n ≈ 57.5; floor points are excluded.
            let (lo, hi) = f.window;
            assert!(lo == 4.0 && hi < 57.0 && f.points_used >= 45, "{f:?}");
        }
        let (n, e) = spectral(0.56, 1e-10, 11); // long floor from n ≈ 41 on
        let f = fit_geometric(&n, &e).unwrap();
        assert!(near(f.rate, 0.56, 0.01) && f.window.1 < 41.0, "{f:?}");
    }

    #[test]
    fn negative_control_distinguishes_rates() {
        for seed in [21, 22, 23] {
            let (n, e) = spectral(0.74, 1e-14, seed);
            let slow = fit_geometric(&n, &e).unwrap().rate;
            let (n, e) = spectral(0.56, 1e-14, seed);
            let fast = fit_geometric(&n, &e).unwrap().rate;
            assert!(near(slow, 0.74, 0.01) && !near(slow, 0.56, 0.1), "{slow}");
            assert!(near(fast, 0.56, 0.01) && !near(fast, 0.74, 0.1), "{fast}");
        }
    }

    #[test]
    fn algebraic_order_with_floor_and_preasymptotic_start() {
        for amp in [0.0, 0.05, 0.2] {
            let (h, e) = mesh(amp);
            let f = fit_algebraic(&h, &e).unwrap();
            assert!(near(f.order, 6.0, 0.2) && f.floor.is_some(), "{f:?}");
            // Floor below h ≈ 4e-3 and pre-asymptotic start excluded.
            assert!(f.window.0 > 4.5e-3 && f.window.1 < 0.6, "{f:?}");
        }
        // Fitting everything above the floor is biased by the pre-asymptotic start.
        let (h, e) = mesh(0.0);
        let all = fit_algebraic_in(&h, &e, 6e-3, 1.0).unwrap().order;
        let auto = fit_algebraic(&h, &e).unwrap().order;
        assert!(all > 6.2 && near(auto, 6.0, 0.05), "{all} {auto}");
    }

    #[test]
    fn floor_detection_cases() {
        let n: Vec<f64> = (1..=30).map(f64::from).collect();
        let e: Vec<f64> = n.iter().map(|&k| 3.0 * 0.74f64.powf(k)).collect();
        assert_eq!(detect_floor(&n, &e, true), None);
        assert_eq!(fit_geometric(&n, &e).unwrap().floor, None);
        let (n, e) = spectral(0.74, 1e-14, 3); // noisy, slow, never floors
        assert_eq!(detect_floor(&n, &e, true), None);
        let h: Vec<f64> = (0..20).map(|i| 0.5f64.powi(i)).collect();
        let e: Vec<f64> = h.iter().map(|&x| x * x).collect();
        assert_eq!(detect_floor(&h, &e, false), None);
        let f = fit_algebraic(&h, &e).unwrap();
        assert!(near(f.order, 2.0, 1e-9) && f.points_used == 20, "{f:?}");
        let (n, e) = spectral(0.56, 1e-14, 1);
        assert!(detect_floor(&n, &e, true).is_some());
        // Exact zeros are floor points.
        let n: Vec<f64> = (1..=12).map(f64::from).collect();
        let zero_tail = |k: f64| if k > 10.0 { 0.0 } else { 0.1f64.powf(k) };
        let e: Vec<f64> = n.iter().map(|&k| zero_tail(k)).collect();
        assert_eq!(detect_floor(&n, &e, true), Some(0.0));
        let f = fit_geometric(&n, &e).unwrap();
        assert!(near(f.rate, 0.1, 1e-9) && f.window == (1.0, 10.0), "{f:?}");
    }

    #[test]
    fn too_few_points_and_bad_input() {
        let r = fit_geometric(&[1.0, 2.0], &[0.1, 0.01]);
        assert_eq!(r, Err(TooFewPoints { needed: 3, got: 2 }));
        let r = fit_algebraic(&[1.0, 0.5, f64::NAN], &[0.1, 0.01, 0.001]);
        assert_eq!(r, Err(NonFinite));
        let r = fit_geometric(&[1.0, 2.0], &[0.1]);
        assert_eq!(r, Err(LengthMismatch { x_len: 2, y_len: 1 }));
        let r = fit_geometric(&[1.0, 2.0, 3.0, 4.0], &[1.0, 0.0, 0.0, 0.0]);
        assert_eq!(r, Err(NoAsymptoticWindow));
        let r = fit_geometric_in(&[1.0, 2.0], &[0.1, 0.01], 3.0, 2.0);
        assert_eq!(r, Err(InvalidWindow { lo: 3.0, hi: 2.0 }));
        let r = log_linear_fit(&[1.0], &[0.5]);
        assert_eq!(r, Err(TooFewPoints { needed: 2, got: 1 }));
        let r = log_linear_fit(&[1.0, 1.0], &[0.5, 0.2]);
        assert_eq!(r, Err(DegenerateAbscissa));
        let r = log_linear_fit(&[1.0, 2.0], &[0.5, f64::NAN]);
        assert_eq!(r, Err(NonFinite));
        let r = log_linear_fit(&[1.0, 2.0], &[0.5, 0.0]);
        let (index, value) = (1, 0.0);
        assert_eq!(r, Err(NonPositive { index, value }));
        assert_eq!(detect_floor(&[f64::NAN; 5], &[1.0; 5], false), None);
    }

    #[test]
    fn nan_and_inf_are_dropped() {
        let (mut n, mut e) = spectral(0.56, 1e-14, 9);
        let clean = fit_geometric(&n, &e).unwrap();
        (e[3], e[20], n[30]) = (f64::NAN, f64::INFINITY, f64::NAN);
        n.push(f64::INFINITY);
        e.push(1.0);
        let f = fit_geometric(&n, &e).unwrap();
        assert!(near(f.rate, 0.56, 0.01) && near(f.rate, clean.rate, 0.005));
        assert_eq!(f.points_used + 3, clean.points_used);
        assert_eq!(fit_geometric_in(&n, &e, 5.0, 25.0), Err(NonFinite));
    }

    #[test]
    fn unsorted_input_matches_sorted() {
        let (n, e) = spectral(0.56, 1e-14, 4);
        let shuffled = (0..57).map(|i| (n[i * 17 % 57], e[i * 17 % 57]));
        let (ns, es): (Vec<f64>, Vec<f64>) = shuffled.unzip();
        assert_ne!(ns, n);
        assert_eq!(fit_geometric(&ns, &es), fit_geometric(&n, &e));
        let (h, e) = mesh(0.1);
        let (hr, er): (Vec<f64>, Vec<f64>) = h.iter().zip(&e).rev().unzip();
        assert_eq!(fit_algebraic(&hr, &er), fit_algebraic(&h, &e));
    }

    #[test]
    fn explicit_windows_and_log_linear_fit() {
        let (n, e) = spectral(0.56, 1e-14, 5);
        let f = fit_geometric_in(&n, &e, 10.0, 40.0).unwrap();
        assert_eq!((f.points_used, f.window, f.floor), (31, (10.0, 40.0), None));
        assert!(near(f.rate, 0.56, 0.01), "{f:?}");
        let (h, e) = mesh(0.0);
        let f = fit_algebraic_in(&h, &e, 0.005, 0.05).unwrap();
        assert!(near(f.order, 6.0, 0.05), "{f:?}");
        assert!(near(f.constant, 2.0, 0.1), "{f:?}");
        let (x, y) = ([0.0, 1.0, 2.0, 3.0], [10.0, 1.0, 0.1, 0.01]);
        let (s, c, r) = log_linear_fit(&x, &y).unwrap();
        assert!(near(s, -1.0, 1e-12) && near(c, 1.0, 1e-12) && r < 1e-12);
    }
}
