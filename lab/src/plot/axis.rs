//! Axis scales, data ranges in plot space, and the tick-generating [`Axis`].

use std::ops::Range;

use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};

/// Axis scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Linear axis.
    Linear,
    /// Base-10 logarithmic axis; non-positive values are dropped.
    Log10,
}

/// Maps a data value to plot space (`log10` on log axes); `None` if invalid.
pub(super) fn to_plot(v: f64, scale: Scale) -> Option<f64> {
    match scale {
        Scale::Linear => v.is_finite().then_some(v),
        Scale::Log10 => (v.is_finite() && v > 0.0).then(|| v.log10()),
    }
}

pub(super) fn min_max(it: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    it.fold(None, |acc, v| {
        Some(acc.map_or((v, v), |(a, b): (f64, f64)| (a.min(v), b.max(v))))
    })
}

/// `(min, max)` widened by `frac` of the span per side, or padded around a
/// degenerate value; `None` unless the result is finite with `lo < hi`.
pub(super) fn padded_range((min, max): (f64, f64), log: bool, frac: f64) -> Option<(f64, f64)> {
    let (span, mid) = (max - min, min + 0.5 * (max - min));
    let (lo, hi) = if span > 0.0 && span > mid.abs() * 1e-12 {
        (min - frac * span, max + frac * span)
    } else {
        let pad = match (log, mid == 0.0) {
            (true, _) => 0.5,
            (false, true) => 1.0,
            (false, false) => (0.1 * mid.abs()).max(f64::MIN_POSITIVE),
        };
        (mid - pad, mid + pad)
    };
    valid_range((lo.max(f64::MIN), hi.min(f64::MAX))).or_else(|| valid_range((min, max)))
}

/// `Some(range)` if it is finite, with finite positive span.
pub(super) fn valid_range((lo, hi): (f64, f64)) -> Option<(f64, f64)> {
    ((hi - lo).is_finite() && hi > lo).then_some((lo, hi))
}

/// Widens `(lo, hi)` symmetrically to span `new` (if larger).
pub(super) fn widen((lo, hi): (f64, f64), new: f64) -> (f64, f64) {
    let extra = 0.5 * (new - (hi - lo)).max(0.0);
    (lo - extra, hi + extra)
}

/// Cell edges (plot space) from cell centres; a lone cell is one unit wide.
pub(super) fn cell_edges(c: &[f64]) -> Vec<f64> {
    let (Some(&[a, b]), Some(&[y, z])) = (c.first_chunk(), c.last_chunk()) else {
        return c.iter().flat_map(|v| [v - 0.5, v + 0.5]).collect();
    };
    let mids = c.windows(2).map(|w| 0.5 * (w[0] + w[1]));
    std::iter::once(a - 0.5 * (b - a))
        .chain(mids)
        .chain([z + 0.5 * (z - y)])
        .collect()
}

/// One axis in plot space (`log10` values on log axes) with its ticks.
///
/// Implements [`Ranged`] directly because plotters' `WithKeyPoints` over
/// `f64` lacks the `ValueFormatter` that `configure_mesh` requires.
#[derive(Clone)]
pub(super) struct Axis {
    pub(super) lo: f64,
    pub(super) hi: f64,
    log: bool,
    /// Label all ticks `1e-12`-style (log axes reaching outside `[1e-3, 1e5)`).
    sci: bool,
    bold: Vec<f64>,
    light: Vec<f64>,
}

impl Axis {
    pub(super) fn new((lo, hi): (f64, f64), log: bool, max_ticks: usize) -> Self {
        let (bold, light) = if log {
            log_ticks(lo, hi, max_ticks)
        } else {
            linear_ticks(lo, hi, max_ticks, 5)
        };
        let sci = log && bold.iter().any(|t| !(-3.0..5.0).contains(t));
        Self {
            lo,
            hi,
            log,
            sci,
            bold,
            light,
        }
    }
    pub(super) fn label(&self, v: f64) -> String {
        fmt_num(if self.log { 10f64.powf(v) } else { v }, self.sci)
    }
}

impl Ranged for Axis {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;
    fn map(&self, v: &f64, (p0, p1): (i32, i32)) -> i32 {
        // Clamped so that pixel coordinates stay small even for stray values.
        let t = ((v - self.lo) / (self.hi - self.lo)).clamp(-1.0, 2.0);
        // (A NaN casts to 0.)
        p0 + (f64::from(p1 - p0) * t).round() as i32
    }
    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.light.clone()
        } else {
            self.bold.clone()
        }
    }
    fn range(&self) -> Range<f64> {
        self.lo..self.hi
    }
}

impl ValueFormatter<f64> for Axis {
    fn format(v: &f64) -> String {
        fmt_num(*v, false)
    }
}

/// Multiples of a "nice" (1-2-5) step in `[lo, hi]` (about `max` of them),
/// plus light ticks at `1/sub` of that step.
fn linear_ticks(lo: f64, hi: f64, max: usize, sub: u32) -> (Vec<f64>, Vec<f64>) {
    let raw = (hi - lo) / max.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let nice = [1.0, 2.0, 5.0].into_iter().find(|&m| raw <= m * mag);
    let step = mag * nice.unwrap_or(10.0);
    let multiples = |step: f64| -> Vec<f64> {
        let (a, b) = ((lo / step).ceil(), (hi / step).floor());
        if !(step > 0.0 && a.is_finite() && b.is_finite() && b >= a && b - a <= 1000.0) {
            return Vec::new();
        }
        let snap = |v: f64| if v.abs() < step * 1e-9 { 0.0 } else { v };
        (0..=(b - a) as i64)
            .map(|k| snap((a + k as f64) * step))
            .collect()
    };
    match multiples(step) {
        bold if bold.is_empty() => (vec![lo, hi], Vec::new()),
        bold if sub > 1 => (bold, multiples(step / f64::from(sub))),
        bold => (bold, Vec::new()),
    }
}

/// Ticks for a log axis in plot space: decades (thinned to about `max`), else
/// 1-2-5 multiples, else nice linear ticks for very narrow ranges.
fn log_ticks(lo: f64, hi: f64, max: usize) -> (Vec<f64>, Vec<f64>) {
    let (first, last) = (lo.ceil() as i64, hi.floor() as i64);
    let in_range = |t: &f64| *t >= lo && *t <= hi;
    let sub = |mults: &[f64]| -> Vec<f64> {
        let decades = lo.floor() as i64..=last;
        decades
            .flat_map(|d| mults.iter().map(move |m| d as f64 + m.log10()))
            .filter(in_range)
            .collect()
    };
    let minor = [2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0];
    if last > first {
        let stride = ((last - first + 1) as usize).div_ceil(max.max(1)) as i64;
        let (bold, light): (Vec<i64>, Vec<i64>) =
            (first..=last).partition(|d| d.rem_euclid(stride) == 0);
        let light = if stride == 1 {
            sub(&minor)
        } else {
            light.into_iter().map(|d| d as f64).collect()
        };
        return (bold.into_iter().map(|d| d as f64).collect(), light);
    }
    match sub(&[1.0, 2.0, 5.0]) {
        bold if bold.len() >= 3 => (bold, sub(&minor)),
        _ => {
            let (lin, _) = linear_ticks(10f64.powf(lo), 10f64.powf(hi), max.min(6), 1);
            let ticks = lin.into_iter().filter(|v| *v > 0.0).map(f64::log10);
            (ticks.filter(in_range).collect(), vec![])
        }
    }
}

/// Compact number: plain for moderate magnitudes (unless `sci`), else
/// `1.5e-12` style; trailing zeros removed.
fn fmt_num(v: f64, sci: bool) -> String {
    let trim = |s: &str| s.trim_end_matches('0').trim_end_matches('.').to_owned();
    if !v.is_finite() {
        String::new()
    } else if v == 0.0 {
        "0".into()
    } else if !sci && (1e-3..1e5).contains(&v.abs()) {
        trim(&format!("{v:.6}"))
    } else {
        let s = format!("{v:.3e}");
        s.split_once('e')
            .map_or_else(|| s.clone(), |(m, e)| format!("{}e{e}", trim(m)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_and_number_format() {
        let f = |v| fmt_num(v, false);
        assert_eq!(
            [f(1e-12), f(2.5e7), f(0.1 + 0.2), f(-40.0)],
            ["1e-12", "2.5e7", "0.3", "-40"]
        );
        assert_eq!(fmt_num(100.0, true), "1e2");
        let decades: Vec<f64> = (-12..=-2).map(f64::from).collect();
        assert_eq!(log_ticks(-12.3, -1.7, 12).0, decades);
        assert!((5..=10).contains(&log_ticks(-30.0, 5.0, 10).0.len()));
        assert!(log_ticks(0.01, 0.02, 8).0.len() >= 2);
        let (bold, light) = linear_ticks(-0.1, 1.1, 10, 5);
        assert_eq!((bold.first(), bold.last()), (Some(&0.0), Some(&1.0)));
        assert!(light.len() > bold.len());
        assert_eq!(cell_edges(&[1.0, 2.0, 4.0]), [0.5, 1.5, 3.0, 5.0]);
    }
}
