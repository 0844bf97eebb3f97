//! Periodic Galerkin: choreographies and periodic orbits with the Fourier basis.

use galerkin_vi::periodic::{self, PeriodicOptions, PeriodicRequest};
use galerkin_vi::scene::Scene;

#[test]
fn scratch() {
    let mut scene = Scene::load("figure-eight").unwrap();
    for (k, nodes, steps, n) in [
        (40, 165, 32, 16),
        (40, 330, 32, 16),
        (50, 408, 32, 16),
        (50, 408, 64, 20),
        (60, 600, 64, 24),
    ] {
        scene.periodic.as_mut().unwrap().steps = Some(steps);
        scene.method.n = n;
        let req = PeriodicRequest {
            periods: 0,
            modes: vec![k],
            options: PeriodicOptions {
                nodes: Some(nodes),
                ..Default::default()
            },
            ..Default::default()
        };
        let r = periodic::analyse_scene(&scene, &req).unwrap();
        eprintln!(
            "K {k} M {nodes} steps {steps} n {n}: T = {:.12} res = {:e} it = {} tail = {:e} eq = {:e} defect {:?}",
            r.period, r.residual, r.iterations, r.tail, r.equation_residual, r.max_modulus_defect
        );
        eprintln!("mult = {:?}", &r.multipliers[..8]);
    }
}
