//! Tests of [`super`].
use super::*;
use crate::basis::{ChebyshevLagrange, Fourier, Hermite, Legendre};
use crate::quadrature::GaussLegendre;
use crate::systems::{Kepler, System};

fn kepler_reference() -> (Kepler, [f64; 2], [f64; 2], crate::systems::ExactSolution) {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let exact = kepler.exact_solution(0.0, &q0, &p0).unwrap().unwrap();
    (kepler, q0, p0, exact)
}

/// Chebyshev n = 4 (degree s = 3) with 8-point Gauss–Legendre on Kepler e = 0.6 over one
/// period, h = 2π/64 … 2π/256: the one-step map has order 2s = 2(n − 1) = 6 (the
/// superconvergence of Galerkin methods with exact-enough quadrature; the guide's
/// "order 2(n − 1)"), the Galerkin curves only about s + 1 = 4 (the local error of the
/// interior of the curve). Measured: map order 6.0014 with a max log-residual 8.6e-4
/// (errors 1.2e-5 … 3.0e-9, all above the floor); curve order 4.27, residual 0.14 (its
/// local slopes fall from 4.6 to 3.9: pre-asymptotic). Tolerances: 0.1 on the map order
/// (70× the measured deviation; a wrong order is off by ≥ 1) and [3.5, 5] on the curve order.
/// Negative control: the curve error, fitted as if it were the map's, misses 6.
#[test]
fn h_refinement_of_chebyshev_n4_has_order_six() {
    let (kepler, q0, p0, exact) = kepler_reference();
    let period = std::f64::consts::TAU;
    let problem = Problem::new(&kepler, 0.0, &q0, &p0, period).unwrap();
    let hs: Vec<f64> = [64.0, 96.0, 128.0, 192.0, 256.0]
        .iter()
        .map(|s| period / s)
        .collect();
    let points = h_refinement(
        |h| GalerkinIntegrator::new(ChebyshevLagrange::new(4)?, GaussLegendre::new(8)?, h),
        &hs,
        &problem,
        |t| exact.position(t),
        8,
    )
    .unwrap();
    for p in &points {
        println!(
            "h = {:.4e}: map {:.3e}, curve {:.3e}",
            p.h, p.map_error, p.error
        );
        assert!(p.error >= p.map_error && p.n == 4);
        assert_eq!(p.steps, steps_for_horizon(period, p.h).unwrap());
    }
    let map = fitted_rate(&points, RefineBy::H, ErrorMeasure::Map).unwrap();
    let curve = fitted_rate(&points, RefineBy::H, ErrorMeasure::Curve).unwrap();
    println!("map {map:?}\ncurve {curve:?}");
    assert_eq!((map.used, map.ignored), (points.len(), 0));
    assert!((map.rate - 6.0).abs() < 0.1, "order {}", map.rate);
    assert!(map.max_residual < 0.05, "{map:?}");
    assert!(map.rho().is_none());
    assert!(
        (3.5..5.0).contains(&curve.rate),
        "curve order {}",
        curve.rate
    );
    assert!((curve.rate - 6.0).abs() > 0.5);
}

/// n-refinement of the spectral method at a large fixed step (Kepler e = 0.6, h = 1,
/// T = 20, n = 6 … 20): every added pair of basis functions lowers both errors, and the
/// fitted factor per basis function r is well below 1 (geometric convergence). Measured:
/// map errors 4.7e-1 … 1.8e-8, r = 0.30 (ρ = 3.3), max log-residual 0.36; curve errors
/// 6.5e-1 … 3.1e-7, r = 0.36, residual 1.0 (the curve error falls more slowly at large
/// n, as the paper's square-root rate for the curves says). Bounds: r < 0.6 (an algebraic
/// rate n⁻ᵖ would show a factor creeping towards 1) and a straight law (max log-residual
/// < 2, i.e. within e² of C rⁿ).
#[test]
fn n_refinement_decreases_geometrically() {
    let (kepler, q0, p0, exact) = kepler_reference();
    let problem = Problem::new(&kepler, 0.0, &q0, &p0, 20.0).unwrap();
    let ns: Vec<usize> = (6..=20).step_by(2).collect();
    let points = n_refinement(
        |n| GalerkinIntegrator::spectral(n, 1.0),
        &ns,
        &problem,
        |t| exact.position(t),
        8,
    )
    .unwrap();
    for p in &points {
        println!(
            "n = {:2}: map {:.3e}, curve {:.3e}, {} evaluations",
            p.n, p.map_error, p.error, p.gradient_evaluations
        );
        assert!(p.gradient_evaluations > 0 && p.steps == 20);
    }
    for w in points.windows(2) {
        if w[1].map_error > ROUND_OFF_FLOOR {
            assert!(w[1].map_error < w[0].map_error, "{w:?}");
            assert!(w[1].error < w[0].error, "{w:?}");
        }
    }
    let map = fitted_rate(&points, RefineBy::N, ErrorMeasure::Map).unwrap();
    let curve = fitted_rate(&points, RefineBy::N, ErrorMeasure::Curve).unwrap();
    println!("map {map:?}\ncurve {curve:?}");
    assert!(map.rate < 0.6 && curve.rate < 0.6, "{map:?} {curve:?}");
    assert!(map.rho().is_some_and(|rho| rho > 1.0 / 0.6));
    assert!(map.max_residual < 2.0 && curve.max_residual < 2.0);
}

/// Points at the round-off floor or non-finite are ignored by the fit, and reported.
#[test]
fn the_fit_ignores_the_floor_and_diverged_runs() {
    let point = |n: usize, error: f64| RefinementPoint {
        n,
        h: 1.0,
        steps: 1,
        error,
        map_error: error,
        gradient_evaluations: 0,
        newton_iterations: 0,
    };
    // error = 10 · 0.5ⁿ exactly, then the floor, then a diverged run.
    let mut points: Vec<RefinementPoint> = (2..8)
        .map(|n| point(n, 10.0 * 0.5f64.powi(n as i32)))
        .collect();
    points.push(point(40, 3e-15));
    points.push(point(42, f64::NAN));
    points.push(point(44, f64::INFINITY));
    let fit = fitted_rate(&points, RefineBy::N, ErrorMeasure::Curve).unwrap();
    assert_eq!((fit.used, fit.ignored), (6, 3));
    assert!((fit.rate - 0.5).abs() < 1e-14 && (fit.intercept - 10f64.ln()).abs() < 1e-13);
    assert!((fit.rho().unwrap() - 2.0).abs() < 1e-13 && fit.max_residual < 1e-13);
    // Algebraic: error = 3 h⁴.
    let hs = [0.1, 0.05, 0.025];
    let pts: Vec<RefinementPoint> = hs
        .iter()
        .map(|&h| RefinementPoint {
            h,
            ..point(4, 3.0 * h.powi(4))
        })
        .collect();
    let fit = fitted_rate(&pts, RefineBy::H, ErrorMeasure::Map).unwrap();
    assert!((fit.rate - 4.0).abs() < 1e-12 && (fit.intercept - 3f64.ln()).abs() < 1e-11);
    // Too few usable points, or no spread in x: typed errors, no panic.
    assert!(matches!(
        fitted_rate(&points[6..], RefineBy::N, ErrorMeasure::Map),
        Err(GviError::InvalidInput { .. })
    ));
    assert!(matches!(
        fitted_rate(
            &[point(3, 1e-3), point(3, 1e-4)],
            RefineBy::N,
            ErrorMeasure::Map
        ),
        Err(GviError::InvalidInput { .. })
    ));
    assert!(fitted_rate(&[], RefineBy::H, ErrorMeasure::Map).is_err());
    assert!(fitted_rate_above(&pts, RefineBy::H, ErrorMeasure::Map, f64::NAN).is_err());
    let bad_h = [RefinementPoint { h: 0.0, ..pts[0] }, pts[1]];
    assert!(fitted_rate(&bad_h, RefineBy::H, ErrorMeasure::Map).is_err());
}

/// User input that cannot make a study is refused with a typed error, never a panic.
#[test]
fn invalid_studies_are_typed_errors() {
    let (kepler, q0, p0, exact) = kepler_reference();
    let reference = |t: f64| exact.position(t);
    let family = |n: usize| GalerkinIntegrator::spectral(n, 0.5);
    let input = |r: Result<Vec<RefinementPoint>>| matches!(r, Err(GviError::InvalidInput { .. }));
    for horizon in [f64::NAN, f64::INFINITY, 0.0, -1.0] {
        assert!(matches!(
            Problem::new(&kepler, 0.0, &q0, &p0, horizon),
            Err(GviError::InvalidInput { .. })
        ));
    }
    assert!(matches!(
        Problem::new(&kepler, 0.0, &q0[..1], &p0, 1.0),
        Err(GviError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        Problem::new(&kepler, f64::NAN, &q0, &p0, 1.0),
        Err(GviError::NonFinite { .. })
    ));
    assert!(matches!(
        Problem::new(&kepler, 0.0, &q0, &[0.0, f64::INFINITY], 1.0),
        Err(GviError::NonFinite { .. })
    ));
    let problem = Problem::new(&kepler, 0.0, &q0, &p0, 2.0).unwrap();
    assert!(input(n_refinement(family, &[], &problem, reference, 4)));
    assert!(input(h_refinement(
        |h| GalerkinIntegrator::spectral(6, h),
        &[],
        &problem,
        reference,
        4
    )));
    // 2.0 is not a whole number of steps of 0.3 …
    assert!(input(h_refinement(
        |h| GalerkinIntegrator::spectral(6, h),
        &[0.5, 0.3],
        &problem,
        reference,
        4
    )));
    // … nor of an integrator's own h = 0.75 …
    assert!(input(n_refinement(
        |n| GalerkinIntegrator::spectral(n, 0.75),
        &[6],
        &problem,
        reference,
        4
    )));
    // … and 2 = 4 × 0.5 is.
    assert_eq!(steps_for_horizon(2.0, 0.5).unwrap(), 4);
    assert!(steps_for_horizon(1e300, 1e-300).is_err());
    assert!(matches!(
        steps_for_horizon(1.0, -0.5),
        Err(GviError::InvalidStepSize { .. })
    ));
    // Zero samples per step; a reference of the wrong length or non-finite.
    assert!(input(n_refinement(family, &[6], &problem, reference, 0)));
    assert!(matches!(
        n_refinement(family, &[6], &problem, |_| vec![0.0; 3], 4),
        Err(GviError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        n_refinement(family, &[6], &problem, |_| vec![0.0, f64::NAN], 4),
        Err(GviError::NonFinite { .. })
    ));
    // The family's own error is passed through (n = 1 is not a basis).
    assert!(matches!(
        n_refinement(family, &[1], &problem, reference, 4),
        Err(GviError::InvalidBasisSize { .. })
    ));
    let empty: [&dyn DynIntegrator<Kepler>; 0] = [];
    assert!(matches!(
        compare_bases(&empty, &problem, 4),
        Err(GviError::InvalidInput { .. })
    ));
    assert!(compare_trajectories(&[], &[0.0]).is_err());
}

/// Chebyshev, Legendre and Hermite with the same n and quadrature are the same method
/// (docs/DESIGN.md §2): their dense output agrees to round-off even at different types,
/// compared through `DynIntegrator`. Fourier spans another space: its difference is the
/// methods' error (negative control). Measured (Kepler, n = 12, 24 Gauss points, h = 0.5,
/// T = 10, 161 sample times): polynomial bases within 3.3e-15 in position and 1.3e-13 in
/// velocity (bounds 1e-13 and 1e-11); Fourier differs by 7.5e-4 in position.
#[test]
fn polynomial_bases_agree_and_fourier_differs() {
    let (kepler, q0, p0, _) = kepler_reference();
    let problem = Problem::new(&kepler, 0.0, &q0, &p0, 10.0).unwrap();
    let quad = || GaussLegendre::new(24).unwrap();
    let cheb = GalerkinIntegrator::new(ChebyshevLagrange::new(12).unwrap(), quad(), 0.5).unwrap();
    let leg = GalerkinIntegrator::new(Legendre::new(12).unwrap(), quad(), 0.5).unwrap();
    let her = GalerkinIntegrator::new(Hermite::new(12).unwrap(), quad(), 0.5).unwrap();
    let same = compare_bases(&[&cheb, &leg, &her], &problem, 8).unwrap();
    println!("{same:?}");
    assert_eq!(same.labels[1], "legendre n=12 gauss-legendre(24) h=0.5");
    assert_eq!(same.samples, 20 * 8 + 1);
    assert!(
        same.max_position < 1e-13 && same.max_velocity < 1e-11,
        "{same:?}"
    );
    assert_eq!(same.position[0][0], 0.0);
    assert_eq!(same.position[1][2], same.position[2][1]);
    let fourier = GalerkinIntegrator::new(Fourier::new(12).unwrap(), quad(), 0.5).unwrap();
    let other = compare_bases(&[&cheb, &fourier], &problem, 8).unwrap();
    println!("{other:?}");
    assert!(other.max_position > 1e-5, "{other:?}");
}
