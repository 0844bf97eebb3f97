use super::*;
use crate::basis::CurveFit;
use crate::basis::contract_tests::check_contract;
use crate::error::GviError;

/// The 2-norm condition number of the stage block of the kinetic matrix under `points`
/// Gauss–Legendre points (what `GalerkinIntegrator::kinetic_condition_number` reports).
pub(super) fn kinetic_condition<B: Basis>(b: &B, points: usize) -> f64 {
    let n = b.len();
    let rule = GaussLegendre::new(points).unwrap().rule().unwrap();
    let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
    let mut k = vec![0.0; n * n];
    for (&c, &w) in rule.nodes.iter().zip(&rule.weights) {
        b.eval(c, &mut v, &mut d);
        for (row, da) in k.chunks_exact_mut(n).zip(&d) {
            for (x, db) in row.iter_mut().zip(&d) {
                *x += w * da * db;
            }
        }
    }
    let m = n - 1;
    let block: Vec<f64> = (0..m)
        .flat_map(|a| (1..n).map(move |bb| (a, bb)))
        .map(|(a, bb)| k[a * n + bb])
        .collect();
    1.0 / crate::linalg::reciprocal_condition(&block, m)
}

/// The textbook enrichment (the negative control of the conditioning tests), one copy shared
/// with tests/enriched.rs.
mod naive {
    use crate::basis::{Basis, Legendre};
    include!("../../../tests/common/naive_enriched.rs");
}
use naive::NaiveEnriched;

#[test]
fn contract_and_derivatives_over_the_frequency_range() {
    for p in [1, 2, 4, 9, 16] {
        for theta in [1e-9, 1e-4, 0.05, 1.0, 3.0, 12.0, 60.0, 250.0] {
            for harmonics in [1, 2] {
                let b = match Enriched::with_harmonics(p, harmonics, theta, 1.0) {
                    Ok(b) => b,
                    // Two harmonics are refused where they are numerically dependent: where
                    // 2θ is small against p, so that polynomials of degree p nearly resolve
                    // them (measured: θ ≤ 0.05 at p = 1, θ = 1 at p = 16).
                    Err(GviError::InvalidParameter { name, .. })
                        if name == "harmonics" && harmonics > 1 && 2.0 * theta < p as f64 + 1.0 =>
                    {
                        continue;
                    }
                    Err(e) => panic!("p = {p}, θ = {theta}, K = {harmonics}: {e}"),
                };
                assert_eq!(b.len(), p + 1 + 2 * harmonics);
                // Derivatives of frequency-θ functions: central differences are exact to
                // ~ (θδ)²; δ = 1e-6 keeps that below 1e-7 up to θ = 250.
                let fd = check_contract(&b);
                assert!(
                    fd < 1e-6,
                    "p = {p}, θ = {theta}, K = {harmonics}: FD mismatch {fd}"
                );
            }
        }
    }
}

#[test]
fn the_trigonometric_functions_are_sin_and_cos_modulo_polynomials() {
    // φ(τ)/scale + chord = f(θτ) − (a degree-p polynomial): so the (p + 1)-th divided
    // difference of φ/scale − f(θ·) on p + 2 points vanishes, while that of f does not.
    let (p, theta) = (4, 7.0);
    let b = Enriched::new(p, theta, 1.0).unwrap();
    let n = b.len();
    let pts: Vec<f64> = (0..p + 2).map(|i| 0.1 + 0.15 * i as f64).collect();
    let divided = |f: &dyn Fn(f64) -> f64| {
        let mut v: Vec<f64> = pts.iter().map(|&x| f(x)).collect();
        for level in 1..v.len() {
            for i in (level..v.len()).rev() {
                v[i] = (v[i] - v[i - 1]) / (pts[i] - pts[i - level]);
            }
        }
        v[v.len() - 1]
    };
    for (slot, t) in b.trig.iter().enumerate() {
        let f = |x: f64| {
            if t.cosine {
                (theta * x).cos()
            } else {
                (theta * x).sin()
            }
        };
        let phi = |x: f64| {
            let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
            b.eval(x, &mut v, &mut d);
            v[p + slot] / t.scale
        };
        let diff = divided(&|x| phi(x) - f(x));
        let reference = divided(&f);
        assert!(
            diff.abs() < 1e-9 * reference.abs(),
            "slot {slot}: {diff:e} vs {reference:e}"
        );
    }
}

#[test]
fn conditioning_stays_bounded_as_omega_h_goes_to_zero() {
    // Stable representation: the kinetic condition number is bounded uniformly in θ and
    // tends to that of a degree-(p + 2) polynomial basis. The naive one grows like θ^{-(p−1)}
    // and is singular to working precision well before θ = 1e-4 (the negative control).
    let p = 6;
    let legendre = kinetic_condition(&Legendre::new(p + 3).unwrap(), 40);
    let mut worst: f64 = 0.0;
    for theta in [1e-12, 1e-8, 1e-4, 1e-2, 0.3, 1.0, 3.0, 10.0, 30.0] {
        let b = Enriched::new(p, theta, 1.0).unwrap();
        let cond = kinetic_condition(&b, 40 + (2.0 * theta) as usize);
        worst = worst.max(cond);
        let naive = NaiveEnriched::new(p, theta);
        let naive_cond = kinetic_condition(&naive, 40 + (2.0 * theta) as usize);
        eprintln!(
            "θ = {theta:e}: enriched {cond:.2e}, naive {naive_cond:.2e}, P_(p+2) {legendre:.2e}"
        );
        if theta <= 1e-4 {
            assert!(
                naive_cond > 1e13 || !naive_cond.is_finite(),
                "θ = {theta}: naive {naive_cond:e}"
            );
        }
    }
    // Measured: at most 1.2e3 (θ ≤ 1e-2; the sine and cosine tails meet at an angle of about
    // 1/(2p + 4)), against 2.0 for the Legendre basis of P_{p+2}.
    assert!(worst < 2e3, "worst enriched condition number {worst:e}");
}

#[test]
fn harmonics_that_cannot_be_told_apart_are_refused() {
    assert!(Enriched::with_harmonics(4, 2, 0.5, 1.0).is_ok());
    assert!(Enriched::with_harmonics(4, 3, 3.0, 1.0).is_ok());
    let e = Enriched::with_harmonics(4, 2, 1e-4, 1.0).unwrap_err();
    assert!(
        matches!(&e, GviError::InvalidParameter { name, .. } if name == "harmonics"),
        "{e}"
    );
    // One harmonic is never refused for being small.
    assert!(Enriched::new(4, 1e-30, 1.0).is_ok());
}

#[test]
fn bad_parameters_are_typed_errors() {
    let param = |r: Result<Enriched>, want: &str| match r {
        Err(GviError::InvalidParameter { name, .. }) => assert_eq!(name, want),
        other => panic!("expected InvalidParameter {want}, got {other:?}"),
    };
    for omega in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        param(Enriched::new(3, omega, 0.1), "omega");
    }
    param(Enriched::new(3, 1e5, 1.0), "omega");
    param(Enriched::new(3, 1e-300, 1e-10), "omega");
    for h in [0.0, -0.1, f64::NAN] {
        assert!(matches!(
            Enriched::new(3, 1.0, h),
            Err(GviError::InvalidStepSize { .. })
        ));
    }
    for (p, k) in [(0, 1), (3, 0), (Enriched::MAX_DEGREE + 1, 1)] {
        assert!(matches!(
            Enriched::with_harmonics(p, k, 1.0, 1.0),
            Err(GviError::InvalidBasisSize { .. })
        ));
    }
}

#[test]
fn quadrature_check_and_recommended_points() {
    let b = Enriched::new(4, 50.0, 0.5).unwrap(); // θ = 25
    let m = b.gauss_points();
    let rule = |m: usize| GaussLegendre::new(m).unwrap().rule().unwrap();
    assert!(b.check_quadrature(&rule(m)).is_ok());
    let e = b.check_quadrature(&rule(m - 1)).unwrap_err();
    assert!(matches!(e, GviError::InvalidQuadrature { .. }), "{e}");
    assert!(
        e.to_string().contains(&format!("at least {m} Gauss")),
        "{e}"
    );
    // The count grows with θ (products up to frequency 2θ), not with p alone.
    let small = Enriched::new(4, 1.0, 0.5).unwrap().gauss_points();
    eprintln!("θ = 25: {m} points; θ = 0.5: {small} points");
    assert!(small < m && m > 25);
}

#[test]
fn interpolation_fits_the_span_exactly() {
    // A curve in the span — a + bτ + c sin(θτ) + d cos(θτ) + a quartic — is reproduced by the
    // curve fit (collocation at the Chebyshev–Lobatto points) at any θ.
    for theta in [0.2, 5.0, 40.0] {
        let b = Enriched::new(4, theta, 1.0).unwrap();
        let fit = CurveFit::new(&b).unwrap();
        let f = |t: f64| 0.3 - t + 0.7 * (theta * t).sin() - 0.2 * (theta * t).cos() + t.powi(4);
        let mut c: Vec<f64> = fit.nodes().iter().map(|&t| f(t)).collect();
        fit.values_to_coefficients(&mut c, 1);
        let n = b.len();
        let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
        let mut worst: f64 = 0.0;
        for j in 0..=100 {
            let t = j as f64 / 100.0;
            b.eval(t, &mut v, &mut d);
            let got: f64 = v.iter().zip(&c).map(|(a, b)| a * b).sum();
            worst = worst.max((got - f(t)).abs());
        }
        assert!(worst < 1e-9, "θ = {theta}: {worst:e}");
    }
}

#[test]
fn extrapolation_continues_the_curve() {
    // The initial guess continues a step's curve to τ ∈ [1, 2]: the enriched functions must
    // extrapolate as sin/cos minus polynomials do there too.
    for theta in [1e-3, 0.8, 6.0, 30.0] {
        let b = Enriched::new(5, theta, 1.0).unwrap();
        let n = b.len();
        let fit = CurveFit::new(&b).unwrap();
        let f = |t: f64| (theta * t).sin() + 0.5 * t * t;
        let mut c: Vec<f64> = fit.nodes().iter().map(|&t| f(t)).collect();
        fit.values_to_coefficients(&mut c, 1);
        let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
        for t in [1.3, 1.7, 2.0] {
            b.eval(t, &mut v, &mut d);
            let got: f64 = v.iter().zip(&c).map(|(a, b)| a * b).sum();
            assert!(
                (got - f(t)).abs() < 1e-8 * (1.0 + f(t).abs()),
                "θ = {theta}, τ = {t}: {got} vs {}",
                f(t)
            );
        }
    }
}
