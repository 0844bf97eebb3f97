//! Tests of the rate fits: recovered rates and floors on synthetic data.
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
