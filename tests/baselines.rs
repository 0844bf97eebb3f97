//! Orders of the classical baselines, measured on the Kepler problem (e = 0.6, one period)
//! against the exact solution and fitted with `fit_algebraic` (its automatic window drops
//! pre-asymptotic points and the round-off floor).

use galerkin_vi::baselines::{
    Composition, CompositionScheme, GaussCollocationBaseline, OneStepMethod, Rk4, StormerVerlet,
    integrate_one_step,
};
use galerkin_vi::fit::fit_algebraic;
use galerkin_vi::systems::{HarmonicOscillator, Kepler, System};

const Q0: [f64; 2] = [0.4, 0.0];
const P0: [f64; 2] = [0.0, 2.0];
const PERIOD: f64 = 2.0 * std::f64::consts::PI;

/// Max position error over the step ends of one Kepler period with `steps` steps.
fn kepler_error<M: OneStepMethod>(build: impl Fn(f64) -> M, steps: usize) -> f64 {
    let kepler = Kepler::new(1.0).unwrap();
    let exact = kepler.exact_solution(0.0, &Q0, &P0).unwrap().unwrap();
    let h = PERIOD / steps as f64;
    let mut m = build(h);
    let (qs, _) = integrate_one_step(&mut m, &Q0, &P0, steps).unwrap();
    qs.iter()
        .enumerate()
        .map(|(k, q)| {
            let e = exact.position(k as f64 * h);
            (q[0] - e[0]).abs().max((q[1] - e[1]).abs())
        })
        .fold(0.0, f64::max)
}

fn order<M: OneStepMethod>(build: impl Fn(f64) -> M, steps: &[usize]) -> (f64, Vec<f64>) {
    let hs: Vec<f64> = steps.iter().map(|&s| PERIOD / s as f64).collect();
    let errs: Vec<f64> = steps.iter().map(|&s| kepler_error(&build, s)).collect();
    let fit = fit_algebraic(&hs, &errs).unwrap();
    (fit.order, errs)
}

fn geometric(from: usize, factor: f64, count: usize) -> Vec<usize> {
    (0..count)
        .map(|i| (from as f64 * factor.powi(i as i32)).round() as usize)
        .collect()
}

fn check(label: &str, expected: f64, got: (f64, Vec<f64>)) {
    eprintln!("{label}: order {:.3}, errors {:?}", got.0, got.1);
    assert!(
        (got.0 - expected).abs() <= 0.3,
        "{label}: measured order {:.3}, expected {expected}; errors {:?}",
        got.0,
        got.1
    );
}

static KEPLER: std::sync::LazyLock<Kepler> = std::sync::LazyLock::new(|| Kepler::new(1.0).unwrap());

#[test]
fn verlet_is_second_order() {
    let steps = geometric(2000, 1.5, 6);
    check(
        "stormer-verlet",
        2.0,
        order(|h| StormerVerlet::new(&*KEPLER, h).unwrap(), &steps),
    );
}

#[test]
fn rk4_is_fourth_order() {
    let steps = geometric(1000, 1.4, 6);
    check(
        "rk4",
        4.0,
        order(|h| Rk4::new(&*KEPLER, h).unwrap(), &steps),
    );
}

#[test]
fn gauss_s_stages_has_order_2s() {
    let ranges = [
        (1, geometric(2000, 1.5, 6)),
        (2, geometric(300, 1.4, 6)),
        (3, geometric(100, 1.3, 6)),
    ];
    for (s, steps) in ranges {
        check(
            &format!("gauss-{s}"),
            2.0 * s as f64,
            order(
                |h| GaussCollocationBaseline::new(&*KEPLER, s, h).unwrap(),
                &steps,
            ),
        );
    }
}

#[test]
fn compositions_have_their_orders() {
    for (scheme, steps) in [
        (CompositionScheme::Yoshida6, geometric(200, 1.3, 6)),
        (CompositionScheme::KahanLi8, geometric(100, 1.25, 6)),
    ] {
        let c = scheme.coefficients();
        assert!(
            (c.iter().sum::<f64>() - 1.0).abs() < 1e-14,
            "{scheme:?} consistency"
        );
        check(
            scheme.as_str(),
            scheme.order() as f64,
            order(|h| Composition::new(&*KEPLER, scheme, h).unwrap(), &steps),
        );
    }
}

#[test]
fn gauss_conserves_quadratic_energy_of_the_oscillator_at_large_steps() {
    let ho = HarmonicOscillator::unit();
    for s in [1, 2, 5, 8] {
        let mut g = GaussCollocationBaseline::new(&ho, s, 20.0).unwrap();
        let (qs, ps) = integrate_one_step(&mut g, &[1.0], &[0.0], 50).unwrap();
        for (q, p) in qs.iter().zip(&ps) {
            let e = (q[0] * q[0] + p[0] * p[0] - 1.0).abs();
            // Round-off only: the stage system at h = 20 amplifies it by ~h²/4 per step.
            assert!(e < 1e-11, "s = {s}: {e:e} at q = {q:?}");
        }
        assert!(g.force_evaluations() > 0);
    }
    assert!(GaussCollocationBaseline::new(&ho, 9, 1.0).is_err());
    assert!(GaussCollocationBaseline::new(&ho, 0, 1.0).is_err());
}

#[test]
fn force_evaluation_counts() {
    let ho = HarmonicOscillator::unit();
    let mut v = StormerVerlet::new(&ho, 0.1).unwrap();
    integrate_one_step(&mut v, &[1.0], &[0.0], 10).unwrap();
    assert_eq!(v.force_evaluations(), 11, "first same as last");
    let mut r = Rk4::new(&ho, 0.1).unwrap();
    integrate_one_step(&mut r, &[1.0], &[0.0], 10).unwrap();
    assert_eq!(r.force_evaluations(), 40);
    let mut c = Composition::new(&ho, CompositionScheme::Yoshida6, 0.1).unwrap();
    integrate_one_step(&mut c, &[1.0], &[0.0], 10).unwrap();
    assert_eq!(c.force_evaluations(), 71);
}

#[cfg(feature = "dop853")]
#[test]
fn dop853_meets_its_tolerance_on_kepler() {
    use galerkin_vi::baselines::Dop853Baseline;
    let mut last = f64::INFINITY;
    for tol in [1e-6, 1e-9, 1e-12] {
        let e = kepler_error(|h| Dop853Baseline::new(&*KEPLER, h, tol).unwrap(), 10);
        eprintln!("dop853 tol {tol:e}: error {e:.3e}");
        assert!(e < 1e3 * tol && e < last, "tol {tol:e}: error {e:e}");
        last = e;
    }
}
