//! No heap allocation inside the step loop after warm-up, proved with a counting allocator:
//! for a separable system with hand-written derivatives (Kepler) and for a non-separable
//! Lagrangian whose derivatives come from automatic differentiation, and for a tolerance-driven
//! run (nothing per step beyond the trajectory it returns).

use galerkin_vi::prelude::*;

use crate::common::counting::allocations;
use crate::common::systems;
use systems::Magnetic;

fn allocations_in_steps<L: Lagrangian>(
    lag: &L,
    gvi: &GalerkinIntegrator,
    q0: &[f64],
    p0: &[f64],
) -> usize {
    let mut ws = gvi.workspace(lag).unwrap();
    let d = q0.len();
    let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
    let (mut qn, mut pn) = (vec![0.0; d], vec![0.0; d]);
    for _ in 0..3 {
        gvi.step(lag, &mut ws, &q, &p, &mut qn, &mut pn).unwrap();
        std::mem::swap(&mut q, &mut qn);
        std::mem::swap(&mut p, &mut pn);
    }
    let before = allocations();
    for _ in 0..50 {
        gvi.step(lag, &mut ws, &q, &p, &mut qn, &mut pn).unwrap();
        std::mem::swap(&mut q, &mut qn);
        std::mem::swap(&mut p, &mut pn);
    }
    allocations() - before
}

#[test]
fn the_step_loop_does_not_allocate() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    for (n, h) in [(8, 0.5), (32, 2.0)] {
        let gvi = GalerkinIntegrator::spectral(n, h).unwrap();
        let count = allocations_in_steps(&kepler, &gvi, &q0, &p0);
        assert_eq!(count, 0, "Kepler n = {n}: {count} allocations in 50 steps");
    }
    let gvi = GalerkinIntegrator::spectral(12, 0.3).unwrap();
    let count = allocations_in_steps(&Magnetic, &gvi, &[0.3, 0.1], &[0.2, -0.1]);
    assert_eq!(count, 0, "AD Lagrangian: {count} allocations in 50 steps");
    // The counter works: a control that does allocate is seen.
    let before = allocations();
    let v: Vec<f64> = std::hint::black_box(vec![1.0; 100]);
    assert!(allocations() > before && v.len() == 100);
}

/// A tolerance-driven run allocates nothing per step beyond the trajectory it returns (three
/// vectors per step: q, p and the curve's coefficients): the rungs, their workspaces and
/// scratch are built before the loop, and the transfer matrices between rungs once per pair
/// used. Measured as the difference between runs of 400 and 200 steps (the modal indicator
/// used to allocate its Chebyshev coefficients for every solve: 338 extra allocations here,
/// measured with that code put back, which this bound catches).
#[test]
fn the_adaptive_step_loop_allocates_only_the_trajectory() {
    use galerkin_vi::adaptive::{AdaptiveOptions, integrate_adaptive};
    let kepler = Kepler::new(1.0).unwrap();
    let e = 0.6;
    let (q0, p0) = ([1.0 - e, 0.0], [0.0, ((1.0 + e) / (1.0 - e)).sqrt()]);
    let opts = AdaptiveOptions::new(
        1e-8,
        BasisKind::Legendre,
        QuadratureKind::GaussLegendre,
        0.25,
    );
    let count = |steps: usize| {
        let before = allocations();
        let run = integrate_adaptive(&kepler, &opts, 0.0, &q0, &p0, steps).unwrap();
        assert!(
            run.checks > steps / 4,
            "the run must exercise checks and jumps"
        );
        allocations() - before
    };
    let (short, long) = (count(200), count(400));
    let extra = long as f64 - short as f64 - 3.0 * 200.0;
    assert!(
        extra.abs() <= 20.0,
        "{long} − {short} allocations: {extra} beyond the trajectory's 3 per step"
    );
}

/// Allocations in 50 steps of a baseline after 3 warm-up steps.
fn allocations_in_baseline_steps<M: galerkin_vi::baselines::OneStepMethod>(
    m: &mut M,
    q0: &[f64],
    p0: &[f64],
) -> usize {
    let d = q0.len();
    let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
    let (mut qn, mut pn) = (vec![0.0; d], vec![0.0; d]);
    let mut t = 0.0;
    let mut run = |m: &mut M, n: usize| {
        for _ in 0..n {
            m.step(t, &q, &p, &mut qn, &mut pn).unwrap();
            t += m.step_size();
            std::mem::swap(&mut q, &mut qn);
            std::mem::swap(&mut p, &mut pn);
        }
    };
    run(m, 3);
    let before = allocations();
    run(m, 50);
    allocations() - before
}

/// The classical baselines, as the work–precision study runs them, allocate nothing per step
/// (DOP853: per sample interval, each a full adaptive solve with a fixed-size state and no
/// stored history); the `Vec<f64>`-state DOP853 fallback does, which shows the count works.
/// Gauss collocation's simplified-Newton path used to build its matrix, LU and residuals per
/// step with nalgebra: 394 allocations in the 50 oscillator steps here, measured with that
/// code put back.
#[test]
fn baseline_steps_do_not_allocate() {
    use galerkin_vi::baselines::{Composition, CompositionScheme, GaussCollocationBaseline};
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let h = 2.0 / 64.0;
    let mut counts: Vec<(String, usize)> = Vec::new();
    let mut count = |m: &mut dyn FnMut() -> (String, usize)| counts.push(m());
    count(&mut || {
        let mut m = Rk4::new(&kepler, h).unwrap();
        (m.name(), allocations_in_baseline_steps(&mut m, &q0, &p0))
    });
    count(&mut || {
        let mut m = StormerVerlet::new(&kepler, h).unwrap();
        (m.name(), allocations_in_baseline_steps(&mut m, &q0, &p0))
    });
    count(&mut || {
        let mut m = GaussCollocationBaseline::new(&kepler, 2, h).unwrap();
        (m.name(), allocations_in_baseline_steps(&mut m, &q0, &p0))
    });
    // The oscillator at h = 5: h²ρ(A²) = 25/12 > 1, the fixed-point iteration diverges and
    // simplified Newton does every step.
    count(&mut || {
        let ho = HarmonicOscillator::unit();
        let mut m = GaussCollocationBaseline::new(&ho, 2, 5.0).unwrap();
        let name = format!("{} on the oscillator", m.name());
        (name, allocations_in_baseline_steps(&mut m, &[1.0], &[0.0]))
    });
    count(&mut || {
        let mut m = Composition::new(&kepler, CompositionScheme::Yoshida6, h).unwrap();
        (m.name(), allocations_in_baseline_steps(&mut m, &q0, &p0))
    });
    #[cfg(feature = "dop853")]
    {
        use galerkin_vi_lab::dop853::Dop853Baseline;
        count(&mut || {
            let mut m = Dop853Baseline::new(&kepler, 2.0, 1e-12).unwrap();
            assert!(m.has_static_state());
            (m.name(), allocations_in_baseline_steps(&mut m, &q0, &p0))
        });
        let mut m = Dop853Baseline::new_dynamic(&kepler, 2.0, 1e-12).unwrap();
        let dynamic = allocations_in_baseline_steps(&mut m, &q0, &p0);
        assert!(dynamic > 50, "Vec-state DOP853: {dynamic} allocations");
    }
    for (name, n) in &counts {
        assert_eq!(*n, 0, "{name}: {n} allocations in 50 steps");
    }
}

/// The Kepler-adapted steps allocate nothing per step either: `InnerKeplerGalerkin` (its
/// stage values, drifts, lane-kernel rows and freezing state are owned buffers; the kernel's
/// scratch is grown in the warm-up) and `KeplerAdaptedGalerkin` with one body on its orbit.
#[test]
fn kepler_adapted_steps_do_not_allocate() {
    use galerkin_vi::kepler_adapted::{InnerKeplerGalerkin, KeplerAdaptedGalerkin};
    use galerkin_vi::systems::NBody;
    // A star, a fast inner planet and two slower ones (G = 1, circular orbits).
    let nb = NBody::new(vec![1.0, 1e-5, 1e-3, 3e-4], 1.0, 3).unwrap();
    let v = |r: f64| (1.0 / r).sqrt();
    #[rustfmt::skip]
    let mut q0 = vec![0.0, 0.0, 0.0, 0.4, 0.0, 0.01, -2.0, 0.0, 0.0, 0.0, 5.0, -0.03];
    #[rustfmt::skip]
    let mut v0 = vec![0.0, 0.0, 0.0, 0.0, v(0.4), 0.0, 0.0, -v(2.0), 0.02, -v(5.0), 0.0, 0.0];
    nb.to_barycentric(&mut q0, &mut v0).unwrap();
    let p0 = nb.momenta(&v0);
    let mut inner = InnerKeplerGalerkin::new(&nb, 6, 0.5, 1).unwrap();
    let inner_count = allocations_in_baseline_steps(&mut inner, &q0, &p0);
    let mut listed = KeplerAdaptedGalerkin::with_kepler_bodies(&nb, 6, 0.5, &[1]).unwrap();
    let listed_count = allocations_in_baseline_steps(&mut listed, &q0, &p0);
    assert!(
        inner.partial_force_evaluations() > 0,
        "freezing must have run for the count to cover it"
    );
    assert_eq!(
        (inner_count, listed_count),
        (0, 0),
        "allocations in 50 steps: inner {inner_count}, with_kepler_bodies {listed_count}"
    );
}
