//! The geometric checks the enriched-basis tests share (tests/enriched.rs,
//! tests/enriched_frequencies.rs), each with its RK4 negative control.

use galerkin_vi::GalerkinIntegrator;
use galerkin_vi::Lagrangian;
use galerkin_vi::baselines::{Rk4, integrate_one_step};
use galerkin_vi::basis::Basis;
use galerkin_vi::geometry::{finite_difference_jacobian, relative_symplecticity_defect};
use galerkin_vi::quadrature::Quadrature;
use galerkin_vi::systems::Kepler;

/// Symplecticity of `gvi`'s map on `system` from (q0, p0): the worst relative defect
/// ‖JᵀΩJ − Ω‖/‖J‖² of the exact step Jacobian along 20 steps, the exact Jacobian's distance
/// to central differences of the map (relative), and the defect of RK4 at `h_rk4`, differenced
/// the same way (the negative control).
pub fn symplecticity<B: Basis, Q: Quadrature, L: Lagrangian>(
    gvi: &GalerkinIntegrator<B, Q>,
    system: &L,
    q0: &[f64],
    p0: &[f64],
    h_rk4: f64,
) -> (f64, f64, f64) {
    let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
    let mut worst = 0.0f64;
    for _ in 0..20 {
        let jac = gvi.step_jacobian(system, &q, &p).unwrap();
        worst = worst.max(relative_symplecticity_defect(&jac.matrix));
        q = jac.q_next;
        p = jac.p_next;
    }
    let step = |q: &[f64], p: &[f64]| {
        let t = gvi.integrate(system, 0.0, q, p, 1).unwrap();
        (t.q[1].clone(), t.p[1].clone())
    };
    let fd = finite_difference_jacobian(step, q0, p0, 1e-6);
    let exact = gvi.step_jacobian(system, q0, p0).unwrap().matrix;
    let fd_error = (&fd - &exact).amax() / exact.amax();
    let rk4 = finite_difference_jacobian(
        |q, p| {
            let mut m = Rk4::new(system, h_rk4).unwrap();
            let (qs, ps) = integrate_one_step(&mut m, q, p, 1).unwrap();
            (qs[1].clone(), ps[1].clone())
        },
        q0,
        p0,
        1e-6,
    );
    (worst, fd_error, relative_symplecticity_defect(&rk4))
}

/// The discrete Noether theorem on Kepler (rotation-invariant) from the paper's initial state:
/// the largest drift of the angular momentum x p_y − y p_x over `steps` steps of `gvi`, and
/// that of RK4 at the same h (the negative control).
pub fn kepler_angular_momentum_drift<B: Basis, Q: Quadrature>(
    gvi: &GalerkinIntegrator<B, Q>,
    steps: usize,
) -> (f64, f64) {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let traj = gvi.integrate(&kepler, 0.0, &q0, &p0, steps).unwrap();
    let ang = |q: &[f64], p: &[f64]| q[0] * p[1] - q[1] * p[0];
    let l0 = ang(&q0, &p0);
    let drift = |qs: &[Vec<f64>], ps: &[Vec<f64>]| {
        qs.iter()
            .zip(ps)
            .fold(0.0f64, |m, (q, p)| m.max((ang(q, p) - l0).abs()))
    };
    let mut rk4 = Rk4::new(&kepler, gvi.step_size()).unwrap();
    let (qs, ps) = integrate_one_step(&mut rk4, &q0, &p0, steps).unwrap();
    (drift(&traj.q, &traj.p), drift(&qs, &ps))
}
