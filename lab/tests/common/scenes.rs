//! Built-in scenes run from a test through the library (no `gvi` process): the scene built
//! with a step count of the test's choosing, its system on R^D, and the invariants along the
//! run. Reached as `crate::common::scenes`.

use galerkin_vi::solve::solve;
use galerkin_vi::systems::{AnySystem, System};
use galerkin_vi_lab::scene::{BuiltScene, BuiltSystem, Overrides, Scene};

/// The built-in scene `name`, built, with its step count replaced by `steps` when given
/// (`None` keeps the scene's own: a default [`Overrides`] changes nothing).
pub fn built(name: &str, steps: Option<usize>) -> BuiltScene {
    Scene::load(name)
        .unwrap_or_else(|e| panic!("scene {name}: {e}"))
        .with_overrides(&Overrides {
            steps,
            ..Overrides::default()
        })
        .build()
        .unwrap_or_else(|e| panic!("scene {name} builds: {e}"))
}

/// The scene's system on R^D; a rigid-body scene fails the test, naming the scene.
pub fn euclidean(scene: &BuiltScene) -> &AnySystem {
    match &scene.system {
        BuiltSystem::Euclidean(system) => system,
        BuiltSystem::RigidBody(_) => panic!("{} is not Euclidean", scene.name),
    }
}

/// The system's invariants ([`System::invariants`], in `invariant_names` order) at every
/// state of the scene's run with its own method, the initial state first.
pub fn invariants_along(scene: &BuiltScene) -> Vec<Vec<f64>> {
    let system = euclidean(scene);
    let traj = solve(system, &scene.initial, &scene.method)
        .unwrap_or_else(|e| panic!("scene {} runs: {e}", scene.name))
        .trajectory;
    let width = system.invariant_names().len();
    traj.q
        .iter()
        .zip(&traj.p)
        .map(|(q, p)| {
            let mut inv = vec![0.0; width];
            system.invariants(q, p, &mut inv);
            inv
        })
        .collect()
}
