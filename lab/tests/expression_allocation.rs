//! No heap allocation inside the step loop for expression Lagrangians (the tape evaluates into
//! a stack buffer), proved with a counting allocator as in tests/allocation.rs: the
//! non-separable magnetic scene (AD through the tape) and the separable Hénon–Heiles scene
//! (force and force Jacobian from the compiled potential).

use galerkin_vi::prelude::*;
use galerkin_vi_lab::scene::{Scene, SystemSpec};

use crate::common::counting::allocations;

#[test]
fn expression_step_loops_do_not_allocate() {
    for name in ["magnetic", "henon-heiles", "double-pendulum"] {
        let scene = Scene::load(name).unwrap();
        let SystemSpec::Lagrangian(spec) = &scene.system else {
            panic!("{name}")
        };
        let lag = spec.build().unwrap();
        let gvi = GalerkinIntegrator::spectral(12, 0.3).unwrap();
        let mut ws = gvi.workspace(&lag).unwrap();
        let (mut q, mut p) = (scene.initial.q.clone(), scene.initial.p.clone());
        let (mut qn, mut pn) = (vec![0.0; 2], vec![0.0; 2]);
        for _ in 0..3 {
            gvi.step(&lag, &mut ws, &q, &p, &mut qn, &mut pn).unwrap();
            std::mem::swap(&mut q, &mut qn);
            std::mem::swap(&mut p, &mut pn);
        }
        let before = allocations();
        for _ in 0..50 {
            gvi.step(&lag, &mut ws, &q, &p, &mut qn, &mut pn).unwrap();
            std::mem::swap(&mut q, &mut qn);
            std::mem::swap(&mut p, &mut pn);
        }
        let count = allocations() - before;
        assert_eq!(count, 0, "{name}: {count} allocations in 50 steps");
    }
    // The counter works: a control that does allocate is seen.
    let before = allocations();
    let v: Vec<f64> = std::hint::black_box(vec![1.0; 100]);
    assert!(allocations() > before && v.len() == 100);
}
