//! The enriched basis with several frequencies (module docs, "Several fast frequencies"): the
//! contract, the span, the refusal of frequencies that cannot be told apart, conditioning
//! against their separation, and the quadrature count.

use super::tests::kinetic_condition;
use super::*;
use crate::basis::CurveFit;
use crate::basis::contract_tests::check_contract;
use crate::error::GviError;

fn values(b: &Enriched, tau: f64) -> (Vec<f64>, Vec<f64>) {
    let (mut v, mut d) = (vec![0.0; b.len()], vec![0.0; b.len()]);
    b.eval(tau, &mut v, &mut d);
    (v, d)
}

#[test]
fn one_frequency_is_the_single_frequency_basis_bit_for_bit() {
    for (p, k, omega, h) in [(4, 1, 50.0, 0.04), (6, 2, 3.0, 0.7), (1, 1, 1e-6, 0.1)] {
        let a = Enriched::with_harmonics(p, k, omega, h).unwrap();
        let b = Enriched::with_frequencies(p, k, &[omega], h).unwrap();
        for j in 0..=20 {
            let tau = j as f64 / 10.0 - 0.5;
            assert_eq!(values(&a, tau), values(&b, tau), "τ = {tau}");
        }
        assert_eq!(a.gauss_points(), b.gauss_points());
    }
}

#[test]
fn contract_over_frequency_sets() {
    for p in [1, 4, 9] {
        for (set, h) in [
            (&[50.0, 20.0][..], 0.1),
            (&[50.0, 20.0][..], 0.02),
            (&[50.0, 7.0][..], 0.3),
            (&[3.0, 7.0, 12.0][..], 1.0),
        ] {
            for harmonics in [1, 2] {
                let b = match Enriched::with_frequencies(p, harmonics, set, h) {
                    Ok(b) => b,
                    // With two harmonics, 4r functions of frequencies ≲ 2·max θ_j can be
                    // numerically dependent together (measured: p = 1 and 4 with θ = 5, 2 and
                    // their doubles); with one, where the polynomials resolve every frequency
                    // (2·max θ_j < p + 1: p = 9 with θ = 1, 0.4). Refused by name.
                    Err(GviError::InvalidParameter { name, .. })
                        if (harmonics == 2
                            || 2.0 * set.iter().fold(0.0f64, |m, w| m.max(w * h))
                                < p as f64 + 1.0)
                            && (name == "omega" || name == "harmonics") =>
                    {
                        eprintln!("p = {p}, {set:?}, h = {h}, K = {harmonics}: refused ({name})");
                        continue;
                    }
                    Err(e) => panic!("p = {p}, {set:?}, h = {h}, K = {harmonics}: {e}"),
                };
                assert_eq!(b.len(), p + 1 + 2 * harmonics * set.len());
                assert_eq!(b.omega(), set[0]);
                let fd = check_contract(&b);
                assert!(
                    fd < 1e-6,
                    "p = {p}, {set:?}, K = {harmonics}: FD mismatch {fd}"
                );
            }
        }
    }
}

#[test]
fn the_span_holds_every_frequency() {
    // A curve a + bτ + Σ_j (c_j sin θ_jτ + d_j cos θ_jτ) + a quartic is reproduced by the
    // curve fit (collocation) to round-off: every frequency is in the space.
    for (t1, t2) in [(5.0, 2.0), (0.9, 0.35), (25.0, 3.5)] {
        let b = Enriched::with_frequencies(4, 1, &[t1, t2], 1.0).unwrap();
        let fit = CurveFit::new(&b).unwrap();
        let f = |t: f64| {
            0.3 - t + 0.7 * (t1 * t).sin() - 0.2 * (t1 * t).cos()
                + 0.4 * (t2 * t).sin()
                + 0.9 * (t2 * t).cos()
                + t.powi(4)
        };
        let mut c: Vec<f64> = fit.nodes().iter().map(|&t| f(t)).collect();
        fit.values_to_coefficients(&mut c, 1);
        let worst = (0..=100).fold(0.0f64, |m, j| {
            let t = j as f64 / 100.0;
            let got: f64 = values(&b, t).0.iter().zip(&c).map(|(a, b)| a * b).sum();
            m.max((got - f(t)).abs())
        });
        eprintln!("θ = ({t1}, {t2}): fit error {worst:.1e}");
        assert!(worst < 1e-9, "θ = ({t1}, {t2}): {worst:e}");
    }
}

#[test]
fn frequencies_that_cannot_be_told_apart_are_refused() {
    let omega = |r: Result<Enriched>| match r {
        Err(GviError::InvalidParameter { name, reason, .. }) if name == "omega" => reason,
        other => panic!("expected InvalidParameter omega, got {other:?}"),
    };
    // Equal, nearly equal, and one frequency another's harmonic.
    let e = omega(Enriched::with_frequencies(4, 1, &[50.0, 50.0], 0.1));
    assert!(e.contains("ω = 50 and ω = 50"), "{e}");
    omega(Enriched::with_frequencies(4, 1, &[50.0, 50.0 + 1e-7], 0.1));
    let e = omega(Enriched::with_frequencies(4, 2, &[10.0, 20.0], 0.1));
    assert!(e.contains("2·ω with ω = 10 and ω = 20"), "{e}");
    // Distinct frequencies at so small an h that the polynomials resolve both.
    omega(Enriched::with_frequencies(4, 1, &[50.0, 20.0], 1e-5));
    // The threshold, measured: at θ₁ = 5 (p = 4) the pair (θ₁, θ₁ + δ) is accepted at
    // δ = 1e-2 and refused from δ = 1e-3 (the Gram reciprocal condition falls like 2e-6·δ²:
    // most of δ·τ cos θτ lies in P_p). The kinetic condition number grows like 1/δ² on the
    // way: 2.1e7 at δ = 0.1 and 2.2e9 at δ = 1e-2, against the well separated pair's below.
    let separated = kinetic_condition(
        &Enriched::with_frequencies(4, 1, &[5.0, 2.0], 1.0).unwrap(),
        40,
    );
    eprintln!("θ = (5, 2): kinetic condition {separated:.2e}");
    let mut last_accepted = f64::NAN;
    for delta in [1e-1, 1e-2, 1e-3, 1e-4, 3e-5, 1e-5, 1e-6] {
        match Enriched::with_frequencies(4, 1, &[5.0, 5.0 + delta], 1.0) {
            Ok(b) => {
                last_accepted = delta;
                let cond = kinetic_condition(&b, 40);
                eprintln!("δ = {delta:e}: accepted, kinetic condition {cond:.2e}");
            }
            Err(e) => eprintln!("δ = {delta:e}: refused ({e})"),
        }
    }
    assert!(
        (1e-3..=3e-2).contains(&last_accepted),
        "threshold moved: last accepted δ = {last_accepted:e}"
    );
    // Well separated frequencies are not refused at the evidence's step sizes.
    for h in [0.02, 0.05, 0.1, 0.2] {
        assert!(
            Enriched::with_frequencies(4, 1, &[50.0, 20.0], h).is_ok(),
            "h = {h}"
        );
    }
}

#[test]
fn bad_frequency_lists_are_typed_errors() {
    assert!(matches!(
        Enriched::with_frequencies(4, 1, &[], 0.1),
        Err(GviError::InvalidInput { name, .. }) if name == "omega"
    ));
    let many = vec![1.0; Enriched::MAX_FREQUENCIES + 1];
    assert!(matches!(
        Enriched::with_frequencies(4, 1, &many, 0.1),
        Err(GviError::InvalidInput { name, .. }) if name == "omega"
    ));
    for bad in [0.0, -3.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            Enriched::with_frequencies(4, 1, &[50.0, bad], 0.1),
            Err(GviError::InvalidParameter { name, .. }) if name == "omega"
        ));
    }
    assert!(matches!(
        Enriched::with_frequencies(4, 1, &[50.0, 1e5], 0.1),
        Err(GviError::InvalidParameter { name, .. }) if name == "omega"
    ));
    // An absurd number of harmonics is refused before anything is sized by it (no overflow).
    assert!(matches!(
        Enriched::with_frequencies(4, usize::MAX, &[1.0, 2.0], 1.0),
        Err(GviError::InvalidParameter { name, .. }) if name == "omega"
    ));
    assert!(matches!(
        crate::basis::BasisKind::Enriched.build_with(9, 1.0, Some(&[1.0, 2.0]), Some(usize::MAX)),
        Err(GviError::InvalidBasisSize { .. })
    ));
}

#[test]
fn quadrature_follows_the_highest_frequency() {
    let rule = |m: usize| GaussLegendre::new(m).unwrap().rule().unwrap();
    let two = Enriched::with_frequencies(4, 1, &[20.0, 50.0], 0.5).unwrap(); // θ = 10, 25
    let high = Enriched::new(4, 50.0, 0.5).unwrap();
    let low = Enriched::new(4, 20.0, 0.5).unwrap();
    let m = two.gauss_points();
    eprintln!(
        "θ = (10, 25): {m} points; θ = 25 alone {}, θ = 10 alone {}",
        high.gauss_points(),
        low.gauss_points()
    );
    assert!(m >= high.gauss_points() && m > low.gauss_points());
    assert!(two.check_quadrature(&rule(m)).is_ok());
    let e = two.check_quadrature(&rule(low.gauss_points())).unwrap_err();
    assert!(e.to_string().contains("ωh = 10.000, 25.000"), "{e}");
}
