//! The enriched (oscillation-adapted) basis: polynomials of degree p plus the trigonometric
//! functions sin(kωhτ), cos(kωhτ), k = 1 … K, for dynamics with a known fast frequency ω.
//!
//! The paper's future-work section (Hall & Leok, "Spectral variational integrators", §6)
//! proposes "enriching traditional polynomial approximation spaces with highly oscillatory
//! functions" for problems on radically different time scales. Polynomial Galerkin curves
//! need hω ≪ 1 to follow an oscillation of frequency ω; a space that contains sin(ωt) and
//! cos(ωt) represents it exactly at any hω, so the step is limited by the slow dynamics only.
//! The basis is written against the public [`Basis`] trait alone, as a user would write it
//! (docs/guide/extending.md reproduces it as the worked example).
//!
//! # The functions
//!
//! With θ = ωh and x_k = kθ, the n = p + 1 + 2K functions are, in order:
//! the end function 1 − τ, the p − 1 interior Legendre functions of [`Legendre`] (degrees 2 … p),
//! the 2K interior trigonometric functions, and the end function τ. A trigonometric function is
//! r(τ) = f(x_k τ) − Π_p f(x_k ·)(τ), f = sin or cos, minus its chord (1 − τ) r(0) + τ r(1)
//! and scaled to unit size. Subtracting Π_p (the degree-p Chebyshev truncation of f(x_k τ))
//! and the chord adds only polynomials of degree ≤ p, which the space already has: the span is
//! exactly P_p ⊕ span{sin x_kτ, cos x_kτ}, and the boundary-adapted contract of
//! docs/DESIGN.md §2 holds (every interior function vanishes at both ends).
//!
//! # Conditioning as ωh → 0
//!
//! As θ → 0, sin(θτ) and cos(θτ) become nearly polynomial, and the textbook choice
//! sin(θτ) − τ sin θ is, to O(θ⁵), a multiple of the cubic τ − τ³ — a function the polynomial
//! part already contains when p ≥ 3: the stage matrix then loses digits like θ^{−(p−1)}; at
//! p = 6 its condition number is 4.7e2 at θ = 30, 2.4e9 at θ = 3 and infinite from θ = 1
//! down (measured in this module's tests). The
//! remedy is in the choice of representative: r keeps only the Chebyshev modes of degree
//! above p, whose coefficients are a_j = 2(−1)^{⌊j/2⌋} J_j(θ/2)·(sin or cos of θ/2) by the
//! Jacobi–Anger expansion (`jacobi_anger.rs`), each computed to full relative accuracy, so
//! r is evaluated as the sum of a_j T_j(2τ − 1) over j above p, without cancellation. Scaled
//! to unit size, the sine and cosine functions tend to fixed combinations of T_{p+1} and
//! T_{p+2} as θ → 0: the enriched space tends continuously to P_{p+2} with a bounded
//! condition number (1.2e3 at p = 6 for every θ ≤ 1e-2). That is the fall-back, reached by
//! continuity rather than by a switch: at hω = 1e-8 the enriched map and the degree-(p + 2)
//! polynomial map agree to round-off (3.0e-15, `tests/enriched.rs`).
//!
//! Harmonics (K > 1) are a different matter: as θ → 0 all K sines tend to the *same* limit,
//! so they are nearly dependent among themselves, and more so the larger p is (the part of
//! sin(kθτ) outside P_p shrinks like (kθ/4)^{p+1}/(p + 1)!). No choice of representative cures
//! that without changing the space, so the constructor measures it (the condition of the Gram
//! matrix of the trigonometric functions' Chebyshev coefficients) and refuses, with
//! [`GviError::InvalidParameter`] named `harmonics`, a basis whose harmonics cannot be told
//! apart at this ωh — measured with K = 2: at θ ≤ 0.05 for p = 1, at θ = 1 for p = 16, i.e.
//! where 2θ is small against p and the polynomials already resolve the harmonics. Use K = 1
//! there.
//!
//! # Several fast frequencies
//!
//! [`Enriched::with_frequencies`] takes a set {ω₁, …, ω_r}: the space is
//! P_p ⊕ span{sin(kω_jhτ), cos(kω_jhτ) : k = 1 … K, j = 1 … r}, n = p + 1 + 2rK, each
//! trigonometric function built as above. [`Basis::eval`] returns one value per function,
//! shared by all D coordinates (q(τ) = Σ Q_i φ_i(τ), Q_i ∈ ℝ^D), so every coordinate carries
//! every frequency: a system whose coordinate blocks oscillate at ω₁ and ω₂ gets each block's
//! own frequency in its space, at the price of 2K functions per block that the block does not
//! need. True per-block functions (only sin/cos ω₁ for block 1, only ω₂ for block 2) would
//! save those — n = p + 1 + 2K per coordinate instead of p + 1 + 2rK — but need functions that
//! differ per coordinate: a block-diagonal basis, `eval(τ, block, …)` and stage tables per
//! block, which the trait does not express.
//!
//! Nearly equal frequencies make the space nearly degenerate: sin(x₂τ) − sin(x₁τ) ≈
//! (x₂ − x₁) τ cos(x₁τ), so the two functions differ by a function of size |x₂ − x₁|. The
//! constructor measures the dependence of all the trigonometric functions together (the Gram
//! test above, after each frequency's own harmonics have passed it) and refuses a set that
//! fails it with [`GviError::InvalidParameter`] named `omega`, naming the closest pair; a
//! frequency equal to another one's harmonic (ω₂ = 2ω₁ with K = 2) is refused the same way.
//! It does not merge them: the span would change silently. The same test refuses distinct
//! frequencies at so small an ωh that the polynomials resolve them all (as for harmonics).

mod dependence;
mod jacobi_anger;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_frequencies;

use super::{Basis, Legendre};
use crate::error::{GviError, Result};
use crate::quadrature::{GaussLegendre, Quadrature, QuadratureRule};

/// Polynomials of degree p enriched with sin(kωhτ), cos(kωhτ), k = 1 … K, for one frequency
/// ω or a set of them (module docs).
///
/// The basis is made for one step size h: the trigonometric functions have frequency ωh in
/// the reference variable τ, so an integrator must use the same h
/// ([`Basis::step_size`] lets it check). It is not a polynomial basis
/// ([`polynomial_degree`](Basis::polynomial_degree) is `None`); its quadrature requirement is
/// [`gauss_points`](Enriched::gauss_points), and a rule that does not resolve its products is
/// refused by [`Basis::check_quadrature`].
///
/// ```
/// use galerkin_vi::basis::{Basis, Enriched};
/// // Degree 4 plus sin(θτ), cos(θτ) with θ = ωh = 50 · 0.1 = 5.
/// let b = Enriched::new(4, 50.0, 0.1).unwrap();
/// assert_eq!((b.len(), b.name(), b.polynomial_degree()), (7, "enriched", None));
/// let (mut v, mut d) = (vec![0.0; 7], vec![0.0; 7]);
/// b.eval(1.0, &mut v, &mut d);
/// assert!(v[..6].iter().all(|x| x.abs() < 1e-14) && (v[6] - 1.0).abs() < 1e-14);
/// ```
#[derive(Debug, Clone)]
pub struct Enriched {
    degree: usize,
    harmonics: usize,
    /// ω₁ … ω_r, in the order given; the trigonometric functions are grouped by frequency.
    frequencies: Vec<f64>,
    h: f64,
    polynomial: Legendre,
    trig: Vec<Trig>,
}

/// One interior trigonometric function, scale · (r(τ) − (1 − τ) r(0) − τ r(1)).
#[derive(Debug, Clone)]
struct Trig {
    /// The frequency x = kωh in τ.
    x: f64,
    cosine: bool,
    /// Chebyshev coefficients a_0 … a_N of f(xτ) in T_j(2τ − 1); r keeps j > p.
    coefficients: Vec<f64>,
    r0: f64,
    r1: f64,
    scale: f64,
}

impl Enriched {
    /// The largest polynomial degree accepted.
    pub const MAX_DEGREE: usize = 256;
    /// The largest K·ωh accepted: far beyond what a Gauss rule of a few hundred points
    /// resolves.
    pub const MAX_FREQUENCY: f64 = 1000.0;
    /// The most frequencies accepted by [`with_frequencies`](Self::with_frequencies).
    pub const MAX_FREQUENCIES: usize = 16;

    /// Degree p ≥ 1 polynomials plus sin(ωhτ), cos(ωhτ): n = p + 3 functions.
    ///
    /// Errors: as [`with_harmonics`](Enriched::with_harmonics).
    pub fn new(degree: usize, omega: f64, h: f64) -> Result<Self> {
        Self::with_harmonics(degree, 1, omega, h)
    }

    /// Degree p ≥ 1 polynomials plus sin(kωhτ), cos(kωhτ), k = 1 … K: n = p + 1 + 2K.
    ///
    /// Errors: as [`with_frequencies`](Enriched::with_frequencies).
    pub fn with_harmonics(degree: usize, harmonics: usize, omega: f64, h: f64) -> Result<Self> {
        Self::with_frequencies(degree, harmonics, &[omega], h)
    }

    /// Degree p ≥ 1 polynomials plus sin(kω_jhτ), cos(kω_jhτ), k = 1 … K, for each of the r
    /// frequencies ω_j: n = p + 1 + 2rK (module docs, "Several fast frequencies"). With one
    /// frequency this is [`with_harmonics`](Enriched::with_harmonics), function for function.
    ///
    /// ```
    /// use galerkin_vi::basis::{Basis, Enriched};
    /// // Two stiff blocks at ω = 50 and ω = 20, h = 0.1: θ = 5 and 2.
    /// let b = Enriched::with_frequencies(4, 1, &[50.0, 20.0], 0.1).unwrap();
    /// assert_eq!((b.len(), b.frequencies()), (9, &[50.0, 20.0][..]));
    /// // Nearly equal frequencies make the space nearly degenerate: refused, not merged.
    /// assert!(Enriched::with_frequencies(4, 1, &[50.0, 50.0 + 1e-9], 0.1).is_err());
    /// ```
    ///
    /// Errors: [`GviError::InvalidBasisSize`] for p = 0, p > [`MAX_DEGREE`](Self::MAX_DEGREE)
    /// or K = 0 (too few functions: with no trigonometric function use a polynomial basis);
    /// [`GviError::InvalidInput`] named `omega` for no frequency or more than
    /// [`MAX_FREQUENCIES`](Self::MAX_FREQUENCIES); [`GviError::InvalidParameter`] for a
    /// frequency not finite and positive (`omega`), K·ω_jh above
    /// [`MAX_FREQUENCY`](Self::MAX_FREQUENCY) or so small that the trigonometric part
    /// underflows (`omega`), harmonics that cannot be told apart at this ωh (`harmonics`), or
    /// frequencies that cannot be told apart — nearly equal, one a harmonic of another, or all
    /// resolved by the polynomials at this h (`omega`, module docs);
    /// [`GviError::InvalidStepSize`] for h not finite and positive.
    pub fn with_frequencies(
        degree: usize,
        harmonics: usize,
        frequencies: &[f64],
        h: f64,
    ) -> Result<Self> {
        let r = frequencies.len();
        let n = degree
            .saturating_add(1)
            .saturating_add(harmonics.saturating_mul(2).saturating_mul(r));
        if degree == 0 || degree > Self::MAX_DEGREE || harmonics == 0 {
            return Err(GviError::InvalidBasisSize {
                n,
                basis: "enriched".into(),
                reason: format!(
                    "need polynomial degree 1 ≤ p ≤ {} and at least one harmonic (got p = \
                     {degree}, {harmonics} harmonics); without harmonics use a polynomial basis",
                    Self::MAX_DEGREE
                ),
            });
        }
        if r == 0 || r > Self::MAX_FREQUENCIES {
            return Err(GviError::InvalidInput {
                name: "omega".into(),
                reason: format!(
                    "the enriched basis needs 1 to {} frequencies (got {r})",
                    Self::MAX_FREQUENCIES
                ),
            });
        }
        if let Some(&omega) = frequencies.iter().find(|w| !(w.is_finite() && **w > 0.0)) {
            return Err(GviError::InvalidParameter {
                name: "omega".into(),
                value: omega,
                reason: "the enrichment frequency must be finite and positive".into(),
            });
        }
        if !(h.is_finite() && h > 0.0) {
            return Err(GviError::InvalidStepSize { h });
        }
        // All frequencies in range before anything is allocated (K may be absurdly large).
        for &omega in frequencies {
            let theta = omega * h;
            if theta * harmonics as f64 > Self::MAX_FREQUENCY {
                return Err(GviError::InvalidParameter {
                    name: "omega".into(),
                    value: omega,
                    reason: format!(
                        "K·ωh = {:.3e} exceeds {} (no practical Gauss rule resolves it)",
                        theta * harmonics as f64,
                        Self::MAX_FREQUENCY
                    ),
                });
            }
        }
        let mut trig = Vec::with_capacity(2 * harmonics * r);
        for &omega in frequencies {
            let theta = omega * h;
            let start = trig.len();
            for k in 1..=harmonics {
                for cosine in [false, true] {
                    trig.push(Trig::new(k as f64 * theta, cosine, degree, omega)?);
                }
            }
            // Each frequency's own harmonics first, so that a failure is blamed on K.
            dependence::check_harmonics(&trig[start..], degree, theta)?;
        }
        if r > 1 {
            dependence::check_frequencies(&trig, degree, harmonics, frequencies, h)?;
        }
        Ok(Enriched {
            degree,
            harmonics,
            frequencies: frequencies.to_vec(),
            h,
            polynomial: Legendre::new(degree + 1)?,
            trig,
        })
    }

    /// The polynomial degree p.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The number K of harmonics.
    pub fn harmonics(&self) -> usize {
        self.harmonics
    }

    /// The enrichment frequency ω (the first, ω₁, of a set: [`frequencies`](Self::frequencies)).
    pub fn omega(&self) -> f64 {
        self.frequencies[0]
    }

    /// The enrichment frequencies ω₁ … ω_r, in the order given.
    pub fn frequencies(&self) -> &[f64] {
        &self.frequencies
    }

    /// ωh, the frequency in the reference variable τ (radians per step; ω₁h for a set).
    pub fn theta(&self) -> f64 {
        self.omega() * self.h
    }

    /// The largest frequency in τ of the trigonometric functions, K·max_j ω_jh.
    fn highest(&self) -> f64 {
        self.trig.iter().fold(0.0f64, |m, t| m.max(t.x))
    }

    /// The fewest Gauss–Legendre points that integrate the basis's mass and kinetic products
    /// (Σ_j b_j φ_aφ_b and Σ_j b_j φ_a'φ_b', frequencies up to 2K·max ω_jh and degree 2p) to a
    /// relative 1e-13, the threshold [`Basis::check_quadrature`] applies. A nonlinear
    /// potential adds higher frequencies to the integrand (a quartic one up to 4Kωh), which
    /// this count resolves only approximately; docs/guide/enriched-bases.md measures what
    /// more points buy on the Fermi–Pasta–Ulam problem.
    pub fn gauss_points(&self) -> usize {
        let mut m = self.len().saturating_sub(1).max(1);
        loop {
            let ok = GaussLegendre::new(m)
                .and_then(|g| g.rule())
                .map(|rule| self.product_error(&rule) <= PRODUCT_TOLERANCE)
                .unwrap_or(false);
            if ok || m >= MAX_POINTS {
                return m;
            }
            m += 1;
        }
    }

    /// The relative error of the mass and kinetic products under `rule` against a Gauss rule
    /// with many more points (max over entries, relative to the largest entry).
    fn product_error(&self, rule: &QuadratureRule) -> f64 {
        let reference_points =
            (rule.len() + 40 + (2.0 * self.highest()).ceil() as usize).min(MAX_POINTS + 80);
        let Ok(reference) = GaussLegendre::new(reference_points).and_then(|g| g.rule()) else {
            return f64::INFINITY;
        };
        let (mass, kinetic) = self.products(rule);
        let (mass_ref, kinetic_ref) = self.products(&reference);
        let rel = |a: &[f64], b: &[f64]| {
            let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            a.iter()
                .zip(b)
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
                / scale
        };
        rel(&mass, &mass_ref).max(rel(&kinetic, &kinetic_ref))
    }

    fn products(&self, rule: &QuadratureRule) -> (Vec<f64>, Vec<f64>) {
        let n = self.len();
        let (mut mass, mut kinetic) = (vec![0.0; n * n], vec![0.0; n * n]);
        let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
        for (&c, &w) in rule.nodes.iter().zip(&rule.weights) {
            self.eval(c, &mut v, &mut d);
            let rows = mass.chunks_exact_mut(n).zip(kinetic.chunks_exact_mut(n));
            for ((mass_row, kinetic_row), (va, da)) in rows.zip(v.iter().zip(&d)) {
                for ((m, k), (vb, db)) in mass_row
                    .iter_mut()
                    .zip(kinetic_row.iter_mut())
                    .zip(v.iter().zip(&d))
                {
                    *m += w * va * vb;
                    *k += w * da * db;
                }
            }
        }
        (mass, kinetic)
    }
}

/// The relative accuracy [`Basis::check_quadrature`] demands of the mass and kinetic products.
const PRODUCT_TOLERANCE: f64 = 1e-13;
/// The largest Gauss rule [`Enriched::gauss_points`] proposes.
const MAX_POINTS: usize = 2000;

impl Trig {
    fn new(x: f64, cosine: bool, degree: usize, omega: f64) -> Result<Self> {
        let count = jacobi_anger::coefficient_count(x, degree);
        let coefficients = jacobi_anger::chebyshev_coefficients(x, cosine, count);
        let tail = &coefficients[degree + 1..];
        let size: f64 = tail.iter().map(|a| a.abs()).sum();
        // Below ~1e-280 the leading Bessel values have underflowed (θ of order 1e-280/p):
        // nothing is left to represent.
        if !(size.is_finite() && size > 1e-280) {
            return Err(GviError::InvalidParameter {
                name: "omega".into(),
                value: omega,
                reason: format!(
                    "the part of {}({x:e}τ) outside the polynomials underflows; ωh is too small \
                     for an enrichment (use a polynomial basis of degree p + 2)",
                    if cosine { "cos" } else { "sin" }
                ),
            });
        }
        let r1: f64 = tail.iter().sum();
        let r0: f64 = tail
            .iter()
            .enumerate()
            .map(|(i, a)| {
                if (degree + 1 + i).is_multiple_of(2) {
                    *a
                } else {
                    -*a
                }
            })
            .sum();
        Ok(Trig {
            x,
            cosine,
            coefficients,
            r0,
            r1,
            // Unit size in value, and in slope at large x (r' ≈ x f'(xτ) there), so that the
            // kinetic matrix is not scaled by x² against the polynomial block.
            scale: 1.0 / (size * (0.5 * x).max(1.0)),
        })
    }

    /// (r(τ), dr/dτ).
    fn remainder(&self, tau: f64, degree: usize) -> (f64, f64) {
        let s = 2.0 * tau - 1.0;
        // Inside [0, 1], and outside while the terms a_j T_j(s) still decrease, sum the modes
        // j > p (relatively accurate). Further out (extrapolated initial guesses) the tail
        // sum cancels, and f(xτ) − Π_p f, which is large there, is the accurate form.
        let rho = s.abs() + (s * s - 1.0).max(0.0).sqrt();
        let tail_form = s.abs() <= 1.0 || 0.5 * self.x * rho < (degree + 2) as f64;
        let (mut t_prev, mut t) = (1.0, s); // T_{j−1}, T_j
        let (mut u_prev, mut u) = (0.0, 1.0); // U_{j−2}, U_{j−1}: T_j' = j U_{j−1}
        let (mut head, mut dhead, mut tail, mut dtail) = (self.coefficients[0], 0.0, 0.0, 0.0);
        for (j, &a) in self.coefficients.iter().enumerate().skip(1) {
            let dt = j as f64 * u;
            if j <= degree {
                head += a * t;
                dhead += a * dt;
            } else if tail_form {
                tail += a * t;
                dtail += a * dt;
            } else {
                break;
            }
            (t_prev, t) = (t, 2.0 * s * t - t_prev);
            (u_prev, u) = (u, 2.0 * s * u - u_prev);
        }
        if tail_form {
            (tail, 2.0 * dtail)
        } else {
            let (sx, cx) = (self.x * tau).sin_cos();
            let (f, df) = if self.cosine { (cx, -sx) } else { (sx, cx) };
            (f - head, self.x * df - 2.0 * dhead)
        }
    }
}

impl Basis for Enriched {
    fn len(&self) -> usize {
        self.degree + 1 + self.trig.len()
    }

    fn name(&self) -> &'static str {
        "enriched"
    }

    fn eval(&self, tau: f64, values: &mut [f64], derivatives: &mut [f64]) {
        let (p, n) = (self.degree, self.len());
        // Legendre(p + 1) writes 1 − τ, its p − 1 interior functions and then τ at index p;
        // τ moves to the last slot and the trigonometric functions take p … n − 2.
        self.polynomial
            .eval(tau, &mut values[..=p], &mut derivatives[..=p]);
        values[n - 1] = values[p];
        derivatives[n - 1] = derivatives[p];
        for (i, t) in self.trig.iter().enumerate() {
            let (r, dr) = t.remainder(tau, p);
            values[p + i] = t.scale * (r - (1.0 - tau) * t.r0 - tau * t.r1);
            derivatives[p + i] = t.scale * (dr + t.r0 - t.r1);
        }
    }

    fn polynomial_degree(&self) -> Option<usize> {
        None
    }

    fn step_size(&self) -> Option<f64> {
        Some(self.h)
    }

    fn check_quadrature(&self, rule: &QuadratureRule) -> Result<()> {
        let error = self.product_error(rule);
        if error <= PRODUCT_TOLERANCE {
            return Ok(());
        }
        Err(GviError::InvalidQuadrature {
            reason: format!(
                "{} with {} points integrates the products of the enriched basis (p = {}, \
                 {} harmonic(s), ωh = {}) only to a relative {error:.1e} (> {PRODUCT_TOLERANCE:.0e}); \
                 use at least {} Gauss–Legendre points",
                rule.family,
                rule.len(),
                self.degree,
                self.harmonics,
                self.frequencies
                    .iter()
                    .map(|w| format!("{:.3}", w * self.h))
                    .collect::<Vec<_>>()
                    .join(", "),
                self.gauss_points()
            ),
        })
    }
}
