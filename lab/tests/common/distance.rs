//! Distances between trajectories for the map-agreement tests. Include with
//! `#[path = "common/distance.rs"] mod distance;`.

use galerkin_vi::Trajectory;

/// Max-norm distance of the final states (q and p), relative to the final state's size.
pub fn final_state_distance(a: &Trajectory, b: &Trajectory) -> f64 {
    let k = a.steps();
    let diff = a.q[k]
        .iter()
        .zip(&b.q[k])
        .chain(a.p[k].iter().zip(&b.p[k]))
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    let scale = a.q[k]
        .iter()
        .chain(&a.p[k])
        .fold(0.0f64, |m, x| m.max(x.abs()));
    diff / scale.max(1e-300)
}
