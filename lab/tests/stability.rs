//! The stability study reproduces the known linear-stability limits on the harmonic
//! oscillator and classifies the spectral method's large steps as accurate.

use galerkin_vi_lab::scene::Scene;
use galerkin_vi_lab::studies::stability::{Class, StabilityConfig, stability};

#[test]
fn oscillator_limits_and_spectral_map() {
    let scene = Scene::load("harmonic").unwrap();
    let config = StabilityConfig::quick();
    let study = stability(&scene.build().unwrap(), &config).unwrap();
    let limit = |name: &str| {
        study
            .baselines
            .iter()
            .find(|b| b.method == name)
            .unwrap_or_else(|| panic!("{name} missing"))
    };
    // Bisection brackets [largest stable, smallest unstable] of relative width ≤ tolerance.
    let brackets = |name: &str, exact: f64| {
        let b = limit(name);
        let slack = config.tolerance * exact + 1e-9;
        assert!(
            b.largest_stable_h <= exact + slack && b.smallest_unstable_h >= exact - slack,
            "{name}: [{}, {}] should bracket {exact}",
            b.largest_stable_h,
            b.smallest_unstable_h
        );
        assert!(
            b.smallest_unstable_h - b.largest_stable_h <= 2.0 * slack,
            "{name} width"
        );
    };
    brackets("stormer-verlet", 2.0);
    // |R(iy)|² = 1 − y⁶/72 + y⁸/576 ≤ 1 iff y ≤ 2√2 (classical RK4 on the imaginary axis).
    brackets("rk4", 2.0 * 2f64.sqrt());
    // Gauss collocation is A-stable: no limit below h_max.
    let g = limit("gauss-2");
    assert!(g.smallest_unstable_h.is_infinite(), "{g:?}");
    // The spectral method at h = 20 with many basis functions is accurate.
    for n in [24, 40] {
        let c = study.cell(n, 20.0).unwrap();
        assert_eq!(c.class, Class::Accurate, "n = {n}: {c:?}");
    }
    // And at n = 4 it is not (h = 20 is 3 periods per step).
    assert_ne!(study.cell(4, 20.0).unwrap().class, Class::Accurate);
    let svg = study.heat_map().to_svg_string().unwrap();
    assert!(svg.contains("accurate"));
}

#[test]
fn kepler_large_steps_show_solver_failures() {
    let scene = Scene::load("kepler").unwrap();
    let config = StabilityConfig {
        hs: vec![2.0, 50.0],
        ns: vec![4, 32],
        steps: 10,
        ..StabilityConfig::quick()
    };
    let study = stability(&scene.build().unwrap(), &config).unwrap();
    assert_eq!(study.cells.len(), 4);
    // The paper's setting (h = 2, n = 32) is accurate over these steps.
    assert_eq!(study.cell(32, 2.0).unwrap().class, Class::Accurate);
    for c in &study.cells {
        if c.class == Class::SolverFailure {
            assert!(c.message.as_deref().is_some_and(|m| !m.is_empty()), "{c:?}");
        }
    }
    let csv = study.csv().unwrap();
    assert_eq!(csv.lines().count(), 5);
}
