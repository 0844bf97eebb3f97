//! No heap allocation inside the step loop after warm-up, proved with a counting allocator:
//! for a separable system with hand-written derivatives (Kepler) and for a non-separable
//! Lagrangian whose derivatives come from automatic differentiation.

use galerkin_vi::prelude::*;
use std::alloc::{GlobalAlloc, Layout, System as SystemAlloc};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { SystemAlloc.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { SystemAlloc.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { SystemAlloc.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Charged particle in a magnetic field with a potential: not separable, AD derivatives.
struct Magnetic;
impl Lagrangian for Magnetic {
    fn dim(&self) -> usize {
        2
    }
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        (v[0] * v[0] + v[1] * v[1]) * 0.5 + (q[0] * v[1] - q[1] * v[0]) * 0.5
            - (q[0] * q[0] + q[1] * q[1] * 2.0) * 0.5
    }
}

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
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    for _ in 0..50 {
        gvi.step(lag, &mut ws, &q, &p, &mut qn, &mut pn).unwrap();
        std::mem::swap(&mut q, &mut qn);
        std::mem::swap(&mut p, &mut pn);
    }
    ALLOCATIONS.load(Ordering::SeqCst) - before
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
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    let v: Vec<f64> = std::hint::black_box(vec![1.0; 100]);
    assert!(ALLOCATIONS.load(Ordering::SeqCst) > before && v.len() == 100);
}
