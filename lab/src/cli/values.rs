//! Typed values of the command line: clap value parsers (comma lists use clap's
//! `value_delimiter = ','` with these per-item parsers) and the `A:B:STEP` sweep [`Range`].
//! The studies receive numbers, never text; clap reports a bad value with the flag's name.

use std::str::FromStr;

/// A number (`f64`; `nan` and `inf` pass, the scene's checks refuse them with context).
pub fn number(s: &str) -> Result<f64, String> {
    let s = s.trim();
    s.parse()
        .map_err(|_| format!("'{s}' is not a number (expected a comma-separated list)"))
}

/// A finite number, or a constant expression such as `2*pi/1.2` (no variables).
pub fn expression_number(s: &str) -> Result<f64, String> {
    if let Ok(x) = number(s) {
        return Ok(x);
    }
    use galerkin_vi::events::{EventFunction, ExpressionEvent};
    let e = ExpressionEvent::parse(s, &[], &[]).map_err(|e| e.to_string())?;
    // `t` reads as NaN here: an expression in t is not a constant.
    let x = e.value(f64::NAN, &[], &[]);
    if x.is_finite() {
        Ok(x)
    } else {
        Err(format!(
            "`{s}` is not a finite constant (numbers, pi and functions only)"
        ))
    }
}

/// Any value with a `FromStr` (bases, quadratures, error controls); the type's own message.
pub fn parsed<T: FromStr>(s: &str) -> Result<T, String>
where
    T::Err: std::fmt::Display,
{
    s.trim().parse().map_err(|e: T::Err| e.to_string())
}

/// A whole number of basis functions ≥ 2 (a rung of an n ladder).
pub fn basis_count(s: &str) -> Result<usize, String> {
    let s = s.trim();
    s.parse::<usize>()
        .ok()
        .filter(|&v| v >= 2)
        .ok_or_else(|| format!("'{s}' is not a whole number of basis functions ≥ 2"))
}

/// A whole number ≥ 1.
pub fn count(s: &str) -> Result<usize, String> {
    let s = s.trim();
    s.parse::<usize>()
        .ok()
        .filter(|&v| v >= 1)
        .ok_or_else(|| format!("'{s}' is not a whole number ≥ 1 (expected a comma-separated list)"))
}

/// A number of Fourier modes K, checked by [`crate::periodic::check_modes`] (the check the
/// scene's `[periodic] modes` gets too).
pub fn modes(s: &str) -> Result<usize, String> {
    let s = s.trim();
    let k = s.parse::<usize>().map_err(|_| {
        format!(
            "K must be an integer in 1..={}, got '{s}'",
            crate::periodic::MAX_MODES
        )
    })?;
    crate::periodic::check_modes(k)
}

/// Sweep values: `A:B:STEP` (arithmetic, from min(A, B) to max(A, B)) or `A:B:xF`
/// (geometric, factor F > 1); at most 10 000 values, bounds positive and finite.
#[derive(Debug, Clone, PartialEq)]
pub struct Range {
    values: Vec<f64>,
}

impl Range {
    /// The values, ascending.
    pub fn values(&self) -> &[f64] {
        &self.values
    }
}

impl FromStr for Range {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let bad = |reason: &str| format!("'{text}': {reason} (expected A:B:STEP or A:B:xFACTOR)");
        let parts: Vec<&str> = text.split(':').map(str::trim).collect();
        if parts.len() != 3 {
            return Err(bad("three fields needed"));
        }
        let num = |s: &str| s.parse::<f64>().map_err(|_| bad("not a number"));
        let (a, b) = (num(parts[0])?, num(parts[1])?);
        if !(a.is_finite() && b.is_finite() && a > 0.0 && b > 0.0) {
            return Err(bad("bounds must be positive and finite"));
        }
        let (lo, hi) = (a.min(b), a.max(b));
        let mut values = Vec::new();
        if let Some(f) = parts[2].strip_prefix('x') {
            let f = num(f)?;
            if !(f.is_finite() && f > 1.0) {
                return Err(bad("the factor must exceed 1"));
            }
            // Counted before they are made: a range is never cut short without a word.
            let count = ((hi / lo).ln() / f.ln() + 1e-9).floor() + 1.0;
            if count.is_nan() || count > 10_000.0 {
                return Err(bad(&format!(
                    "{count:.0} values, more than 10000 (a larger factor)"
                )));
            }
            let mut x = lo;
            while x <= hi * (1.0 + 1e-12) {
                values.push(x);
                x *= f;
            }
        } else {
            let step = num(parts[2])?;
            if !(step.is_finite() && step > 0.0) {
                return Err(bad("the step must be positive"));
            }
            let count = ((hi - lo) / step + 1e-9).floor() as usize + 1;
            if count > 10_000 {
                return Err(bad("more than 10000 values"));
            }
            values.extend((0..count).map(|i| lo + step * i as f64));
        }
        Ok(Range { values })
    }
}

/// Tolerances: `A:B` for every decade from the larger to the smaller, or a comma list; all
/// finite and positive.
#[derive(Debug, Clone, PartialEq)]
pub struct Tolerances {
    values: Vec<f64>,
}

impl Tolerances {
    /// The tolerances, in the order given (decades: descending).
    pub fn values(&self) -> &[f64] {
        &self.values
    }
}

impl FromStr for Tolerances {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let values: Vec<f64> = match text.split_once(':') {
            Some((a, b)) => {
                let (a, b) = (number(a)?, number(b)?);
                if !(a > 0.0 && b > 0.0 && a.is_finite() && b.is_finite()) {
                    return Err("the range ends must be positive".into());
                }
                let (hi, lo) = (
                    a.max(b).log10().round() as i32,
                    a.min(b).log10().round() as i32,
                );
                (lo..=hi).rev().map(|e| 10f64.powi(e)).collect()
            }
            None => text.split(',').map(number).collect::<Result<_, _>>()?,
        };
        if values.is_empty() || values.iter().any(|t| !(t.is_finite() && *t > 0.0)) {
            return Err("tolerances must be finite and positive".into());
        }
        Ok(Tolerances { values })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_parse() {
        let r: Range = "4:10:2".parse().unwrap();
        assert_eq!(r.values(), [4.0, 6.0, 8.0, 10.0]);
        let g: Range = "0.1:1:x2".parse().unwrap();
        assert_eq!(g.values().len(), 4);
        assert!((g.values()[3] - 0.8).abs() < 1e-12);
        for bad in [
            "4:10",
            "a:b:c",
            "4:10:0",
            "0:10:1",
            "1:2:x1",
            "1:1e9:1e-9",
            "4:8:x1.00001",
        ] {
            assert!(bad.parse::<Range>().is_err(), "{bad}");
        }
    }

    #[test]
    fn tolerances_and_counts_parse() {
        let t: Tolerances = "1e-6:1e-8".parse().unwrap();
        assert_eq!(t.values(), [1e-6, 1e-7, 1e-8]);
        let t: Tolerances = "1e-3,1e-5".parse().unwrap();
        assert_eq!(t.values(), [1e-3, 1e-5]);
        for bad in ["0:1e-6", "x", "1e-3,-1", "inf"] {
            assert!(bad.parse::<Tolerances>().is_err(), "{bad}");
        }
        assert_eq!(basis_count(" 8"), Ok(8));
        assert!(basis_count("1").is_err() && basis_count("2.5").is_err());
        assert!(count("0").is_err() && modes("4097").is_err() && modes("0").is_err());
        assert!(number("abc").unwrap_err().contains("not a number"));
    }
}
