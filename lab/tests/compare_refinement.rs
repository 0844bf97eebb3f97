//! n- against h-refinement at reduced size.

use galerkin_vi::basis::BasisKind;
use galerkin_vi_lab::scene::Scene;
use galerkin_vi_lab::studies::compare_refinement::{
    CompareConfig, compare_refinement, lower_envelope,
};
use galerkin_vi_lab::studies::refine::Vary;

#[test]
fn kepler_paths_and_cheapest() {
    let mut scene = Scene::load("kepler").unwrap();
    scene.method.steps = 5;
    let study = compare_refinement(&scene.build().unwrap(), &CompareConfig::quick()).unwrap();
    assert_eq!(study.paths.len(), 4 * BasisKind::ALL.len());
    // Refining costs more overall along every path (not always monotonically: at the
    // coarsest points Newton may need its fallback guesses), and errors fall along the
    // n-paths at h = 2.
    for p in &study.paths {
        let evals: Vec<usize> = p.points.iter().map(|m| m.gradient_evaluations).collect();
        assert!(
            evals.last() > evals.iter().min(),
            "{}: {evals:?}",
            p.label()
        );
    }
    let n_path = study
        .paths
        .iter()
        .find(|p| p.vary == Vary::N && p.fixed == 2.0 && p.basis == BasisKind::Chebyshev)
        .unwrap();
    // (n = 4 at h = 2 may fail to converge: failures are kept, with their message.)
    let e: Vec<f64> = n_path.points[1..].iter().map(|m| m.map_error).collect();
    assert!(n_path.points[1..].iter().all(|m| m.failure.is_none()));
    assert!(e[2] < 1e-2 * e[0], "{e:?}");
    for m in n_path.points.iter().filter(|m| m.failure.is_some()) {
        assert!(!m.failure.as_deref().unwrap_or("").is_empty());
    }
    // The cheapest run reaching 1e-6 exists and really reaches it.
    let c = study.cheapest.iter().find(|c| c.target == 1e-6).unwrap();
    let (label, n, h, evals) = c.by_evaluations.clone().unwrap();
    let m = study
        .paths
        .iter()
        .filter(|p| p.label() == label)
        .flat_map(|p| &p.points)
        .find(|m| m.n == n && m.h == h)
        .unwrap();
    assert!(m.map_error <= 1e-6 && m.gradient_evaluations == evals);
    for p in study.paths.iter().flat_map(|p| &p.points) {
        if p.failure.is_none() && p.map_error <= 1e-6 {
            assert!(p.gradient_evaluations >= evals);
        }
    }
    assert_eq!(
        study.csv().unwrap().lines().count(),
        1 + BasisKind::ALL.len() * (2 * 4 + 2 * 4)
    );
}

#[test]
fn envelope_is_monotone() {
    let env = lower_envelope(vec![
        (3.0, 1.0),
        (1.0, 5.0),
        (2.0, 6.0),
        (4.0, 0.5),
        (5.0, 0.7),
    ]);
    assert_eq!(env, vec![(1.0, 5.0), (3.0, 1.0), (4.0, 0.5)]);
}
