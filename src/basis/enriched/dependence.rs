//! The numerical-dependence tests of the enriched basis's trigonometric functions: among one
//! frequency's harmonics, and among several frequencies (parent module, "Conditioning as
//! ωh → 0" and "Several fast frequencies").
//!
//! Both measure the same thing: the Gram matrix G_ab = ⟨u_a, u_b⟩ of the functions' Chebyshev
//! tails (the modes of degree > p, which is all that distinguishes them modulo P_p), each
//! normalised to unit length. Its reciprocal condition number is the square of the smallest
//! singular value of the coefficient matrix: below 1e-10 some combination of the functions is
//! within 1e-5 of P_p — the stage matrix then loses about ten digits — and the basis is refused.

use super::Trig;
use crate::error::{GviError, Result};

/// The smallest Gram reciprocal condition number accepted.
const GRAM_RCOND: f64 = 1e-10;

/// The reciprocal condition number of the Gram matrix of the trigonometric functions'
/// normalised tail coefficients (1 is orthogonal, 0 dependent).
pub(super) fn tail_gram_rcond(trig: &[Trig], degree: usize) -> f64 {
    let m = trig.len();
    let len = trig.iter().map(|t| t.coefficients.len()).max().unwrap_or(0);
    let unit: Vec<Vec<f64>> = trig
        .iter()
        .map(|t| {
            let mut v = vec![0.0; len];
            v[..t.coefficients.len()].copy_from_slice(&t.coefficients);
            v[..=degree].iter_mut().for_each(|x| *x = 0.0);
            // Scale by the largest entry first: at tiny ωh the squares would underflow.
            let largest = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            v.iter_mut().for_each(|x| *x /= largest);
            let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            v.iter_mut().for_each(|x| *x /= norm);
            v
        })
        .collect();
    let gram: Vec<f64> = unit
        .iter()
        .flat_map(|a| {
            unit.iter()
                .map(move |b| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>())
        })
        .collect();
    crate::linalg::reciprocal_condition(&gram, m)
}

/// Refuse harmonics of one frequency that are numerically dependent at this θ. With one
/// harmonic the Gram reciprocal condition stays near 1/(2p + 4)² for every θ (the sine and
/// cosine tend to different combinations of T_{p+1} and T_{p+2}).
pub(super) fn check_harmonics(trig: &[Trig], degree: usize, theta: f64) -> Result<()> {
    let m = trig.len();
    let rcond = tail_gram_rcond(trig, degree);
    if rcond.is_nan() || rcond < GRAM_RCOND {
        return Err(GviError::InvalidParameter {
            name: "harmonics".into(),
            value: (m / 2) as f64,
            reason: format!(
                "at ωh = {theta:.3e} the {} harmonics are numerically dependent (Gram \
                 reciprocal condition {rcond:.1e} < {GRAM_RCOND:.0e}); use one harmonic or a \
                 larger h",
                m / 2
            ),
        });
    }
    Ok(())
}

/// Refuse a set of frequencies whose trigonometric functions are numerically dependent
/// together (each frequency's own harmonics have passed [`check_harmonics`]). `trig` holds,
/// per frequency in order, the sine and cosine of harmonics 1 … K.
pub(super) fn check_frequencies(
    trig: &[Trig],
    degree: usize,
    harmonics: usize,
    frequencies: &[f64],
    h: f64,
) -> Result<()> {
    let rcond = tail_gram_rcond(trig, degree);
    if !(rcond.is_nan() || rcond < GRAM_RCOND) {
        return Ok(());
    }
    // Name the pair of frequencies in τ (kω_ih, k'ω_jh, i ≠ j) that are closest.
    let per = 2 * harmonics;
    let label = |a: usize| {
        let (j, k) = (a / per, (a % per) / 2 + 1);
        let w = frequencies[j];
        if k == 1 {
            format!("ω = {w}")
        } else {
            format!("{k}·ω with ω = {w}")
        }
    };
    let mut closest = (f64::INFINITY, 0, 0);
    for a in (0..trig.len()).step_by(2) {
        for b in (a + 2..trig.len()).step_by(2) {
            let gap = (trig[a].x - trig[b].x).abs();
            if a / per != b / per && gap < closest.0 {
                closest = (gap, a, b);
            }
        }
    }
    let (gap, a, b) = closest;
    Err(GviError::InvalidParameter {
        name: "omega".into(),
        value: frequencies[b / per],
        reason: format!(
            "the enrichment frequencies cannot be told apart at h = {h}: their functions are \
             numerically dependent (Gram reciprocal condition {rcond:.1e} < {GRAM_RCOND:.0e}); \
             closest: {} and {}, {gap:.3e} apart in ωh. Give one frequency for nearly equal \
             ones, drop a frequency that is another's harmonic, or, where the polynomials \
             already resolve these frequencies at this h, use fewer frequencies or a larger h",
            label(a),
            label(b)
        ),
    })
}
