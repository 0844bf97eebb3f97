//! The work–precision study at reduced size: every method is present, the Pareto front is
//! non-dominated and complete, and the Galerkin points are where the theory puts them.

use galerkin_vi_lab::scene::Scene;
use galerkin_vi_lab::studies::work_precision::{WorkPrecisionConfig, mark_pareto, work_precision};

#[test]
fn reduced_kepler_study() {
    let mut scene = Scene::load("kepler").unwrap();
    scene.method.steps = 5; // T = 10
    let study = work_precision(&scene.build().unwrap(), &WorkPrecisionConfig::quick()).unwrap();
    for family in [
        "galerkin-chebyshev",
        "stormer-verlet",
        "rk4",
        "gauss-2",
        "yoshida-6",
        "kahan-li-8",
    ] {
        assert!(
            study.points.iter().any(|p| p.method == family),
            "{family} missing"
        );
    }
    #[cfg(feature = "dop853")]
    assert!(study.points.iter().any(|p| p.method == "dop853"));
    // Spectral convergence: at h = 2 the error falls with n.
    let g = |n: usize| {
        study
            .points
            .iter()
            .find(|p| p.n == Some(n) && p.h == Some(2.0))
            .unwrap()
            .error
    };
    assert!(
        g(16) < 1e-2 * g(8),
        "n = 8: {:e}, n = 16: {:e}",
        g(8),
        g(16)
    );
    // Pareto front: non-dominated, and every other successful point is dominated by it.
    let front = study.pareto_front();
    assert!(!front.is_empty());
    for a in &front {
        for b in &study.points {
            if b.failure.is_none() && !std::ptr::eq(*a, b) {
                assert!(
                    !(b.seconds <= a.seconds && b.error < a.error),
                    "{} dominates front point {}",
                    b.parameters,
                    a.parameters
                );
            }
        }
    }
    for b in study
        .points
        .iter()
        .filter(|p| p.failure.is_none() && !p.pareto)
    {
        assert!(
            front
                .iter()
                .any(|a| a.seconds <= b.seconds && a.error <= b.error)
        );
    }
    assert!(
        study
            .points
            .iter()
            .all(|p| p.failure.is_some() || p.force_evaluations > 0)
    );
    let csv = study.csv().unwrap();
    assert_eq!(csv.lines().count(), study.points.len() + 1);
    assert!(
        study
            .chart()
            .to_svg_string()
            .unwrap()
            .contains("Pareto front")
    );
}

#[test]
fn pareto_marks_by_hand() {
    let mut scene = Scene::load("harmonic").unwrap();
    scene.method.h = 1.0;
    scene.method.steps = 4;
    let mut study = work_precision(&scene.build().unwrap(), &WorkPrecisionConfig::quick()).unwrap();
    // Synthetic times: the front is recomputed from scratch.
    for (i, p) in study.points.iter_mut().enumerate() {
        p.seconds = 1.0 + i as f64;
        p.error = if i == 2 {
            1e-20
        } else {
            1.0 / (1.0 + i as f64)
        };
        p.failure = None;
    }
    mark_pareto(&mut study.points);
    let marked: Vec<usize> = (0..study.points.len())
        .filter(|&i| study.points[i].pareto)
        .collect();
    assert_eq!(marked, vec![0, 1, 2]);
}

/// The long-run preset sweeps only Legendre and Chebyshev–Lagrange and the accurate end of
/// the peers; at a shortened horizon (T = 400) its Legendre runs already beat every peer's
/// best error (DOP853 at 1e-14, Gauss s = 4 and Kahan–Li-8 at Δ/128), the ordering that
/// `gvi work-precision kepler --long` shows at T = 20,000
/// (docs/guide/long-runs.md).
#[test]
fn long_preset_at_a_short_horizon() {
    let scene = Scene::load("kepler").unwrap();
    let mut config = WorkPrecisionConfig::long();
    assert_eq!(config.horizon, Some(20_000.0));
    config.horizon = Some(400.0);
    let study = work_precision(&scene.build().unwrap(), &config).unwrap();
    let families: std::collections::BTreeSet<&str> =
        study.points.iter().map(|p| p.method.as_str()).collect();
    assert!(families.contains("galerkin-legendre") && families.contains("galerkin-chebyshev"));
    assert!(!families.contains("galerkin-hermite") && !families.contains("galerkin-fourier"));
    let best = |m: &str| {
        study
            .points
            .iter()
            .filter(|p| p.method == m)
            .map(|p| p.error)
            .fold(f64::INFINITY, f64::min)
    };
    let legendre = best("galerkin-legendre");
    eprintln!(
        "T = 400: Legendre {legendre:.2e}, DOP853 {:.2e}, Gauss-4 {:.2e}",
        best("dop853"),
        best("gauss-4")
    );
    assert!(legendre < 1e-10, "Legendre best {legendre:e}");
    for peer in [
        "stormer-verlet",
        "rk4",
        "yoshida-6",
        "kahan-li-8",
        "gauss-4",
    ] {
        assert!(
            legendre < best(peer),
            "{peer} {:e} ≤ {legendre:e}",
            best(peer)
        );
    }
    if cfg!(feature = "dop853") {
        assert!(legendre < best("dop853"));
    }
}
