//! [`Scene::build`]: from the declarative scene to the problem and the method.
//!
//! A scene names its system by a tagged table; building it once gives a value with the
//! concrete system ([`AnySystem`], which implements `System` by dispatch, or a rigid body on
//! SO(3)), the validated initial state and the method — the problem/method split of
//! docs/DESIGN.md §1. Runs, checks, studies and reports take the built scene, so the N-body
//! system is assembled from its bodies once, and this is the one place where initial states are
//! checked (finiteness, lengths against the system's dimension, regularity of an expression
//! Lagrangian, at least one step).

use super::{Scene, SystemSpec};
use crate::error::{GviError, LabError, Result};
use galerkin_vi::lie::body::{FreeRigidBody, HeavyTop};
use galerkin_vi::method::{InitialState, MethodSpec};
use galerkin_vi::systems::{AnySystem, Fpu, HarmonicOscillator, Kepler, Pendulum, SpringPendulum};

/// The rigid body a scene names (run on SO(3) by [`galerkin_vi::lie`]).
#[derive(Debug, Clone)]
pub enum AnyRigidBody {
    /// A free body.
    Free(FreeRigidBody),
    /// A heavy top.
    Heavy(HeavyTop),
}

/// The system of a built scene: on a Euclidean configuration space, or a rigid body on SO(3).
#[derive(Debug, Clone)]
pub enum BuiltSystem {
    /// A system on R^D (every built-in system but the rigid bodies).
    Euclidean(AnySystem),
    /// A rigid body; `[initial] q` is the rotation vector of R₀, `p` the body momentum.
    RigidBody(AnyRigidBody),
}

/// A scene built once: the system, the validated initial state and the method, with the
/// scene's name and description for reports. See [`Scene::build`].
#[derive(Debug, Clone)]
pub struct BuiltScene {
    /// Short name (the scene's, or its origin).
    pub name: String,
    /// One-line description.
    pub description: String,
    /// The system.
    pub system: BuiltSystem,
    /// The initial state, checked against the system (for N-body scenes without an explicit
    /// `[initial]`, formed from the bodies).
    pub initial: InitialState,
    /// The method.
    pub method: MethodSpec,
    /// The scene as written (with overrides), for what is recorded with results (JSON output)
    /// and the periodic-orbit data.
    scene: Scene,
}

impl BuiltScene {
    /// The Euclidean system, or a typed error for rigid bodies (which only `gvi run`
    /// supports).
    pub fn euclidean(&self) -> Result<&AnySystem> {
        match &self.system {
            BuiltSystem::Euclidean(s) => Ok(s),
            BuiltSystem::RigidBody(_) => Err(GviError::Unsupported(
                "rigid bodies live on SO(3): only `gvi run` supports them (galerkin_vi::lie)"
                    .into(),
            )
            .into()),
        }
    }

    /// The scene it was built from, with the method and the initial state this value holds
    /// (so a study that changed the method records the method it ran).
    pub fn scene(&self) -> Scene {
        Scene {
            initial: self.initial.clone(),
            method: self.method.clone(),
            ..self.scene.clone()
        }
    }

    /// The chart title of the scene: `name — description`, or the name alone when the scene
    /// has no description.
    pub fn title(&self) -> String {
        match self.description.trim() {
            "" => self.name.clone(),
            d => format!("{} — {d}", self.name),
        }
    }

    /// The scene's `[units]` (empty when it gives none).
    pub fn units(&self) -> &super::Units {
        &self.scene.units
    }

    /// The scene's `[periodic]` table, if any.
    pub fn periodic(&self) -> Option<&galerkin_vi::periodic::PeriodicSpec> {
        self.scene.periodic.as_ref()
    }
}

impl Scene {
    /// Build the system the scene names, form and check the initial state, and return them
    /// with the method: the one validation point for initial states. Errors: invalid system
    /// parameters, malformed N-body bodies ([`LabError::Scene`]), a non-finite or wrongly sized
    /// initial state, a singular expression Lagrangian at the initial state, zero steps.
    pub fn build(&self) -> Result<BuiltScene> {
        let mut initial = self.initial.clone();
        let system = match &self.system {
            SystemSpec::Harmonic { mass, stiffness } => {
                AnySystem::from(HarmonicOscillator::new(*mass, *stiffness)?).into()
            }
            SystemSpec::Kepler { mu } => AnySystem::from(Kepler::new(*mu)?).into(),
            SystemSpec::Pendulum {
                length,
                gravity,
                mass,
            } => AnySystem::from(Pendulum::new(*length, *gravity, *mass)?).into(),
            SystemSpec::SpringPendulum {
                omega,
                length,
                gravity,
            } => AnySystem::from(SpringPendulum::new(*omega, *length, *gravity)?).into(),
            SystemSpec::Fpu { springs, omega } => match omega.as_deref() {
                None => AnySystem::from(Fpu::new(*springs, 50.0)?).into(),
                Some([w]) => AnySystem::from(Fpu::new(*springs, *w)?).into(),
                Some(ws) if ws.len() == *springs => {
                    AnySystem::from(Fpu::with_frequencies(ws)?).into()
                }
                Some(ws) => {
                    return Err(LabError::Scene {
                        source_name: self.name.clone(),
                        reason: format!(
                            "[system] omega lists {} frequencies for springs = {springs}: give \
                             one frequency, or one per spring",
                            ws.len()
                        ),
                    });
                }
            },
            SystemSpec::NBody {
                dim,
                g,
                aggregate,
                barycentric,
                bodies,
            } => {
                let (system, from_bodies) =
                    crate::nbody_scene::build(*dim, *g, aggregate.as_deref(), *barycentric, bodies)
                        .map_err(|e| match e {
                            LabError::Scene { reason, .. } => LabError::Scene {
                                source_name: self.name.clone(),
                                reason,
                            },
                            e => e,
                        })?;
                // An explicit `[initial]` q or p overrides the bodies' positions or momenta.
                if initial.q.is_empty() {
                    initial.q = from_bodies.q;
                }
                if initial.p.is_empty() {
                    initial.p = from_bodies.p;
                }
                AnySystem::from(system).into()
            }
            SystemSpec::Lagrangian(spec) => {
                // Lengths and regularity of L at the initial state, with the expression's own
                // messages (the number of coordinates, the singular velocity Hessian).
                let system = spec.check_at(initial.t0, &initial.q, &initial.p)?;
                // The exact formula is for one initial state; from another (a scene's typo,
                // --q0) the library drops it. Say so rather than drop it silently.
                if spec.exact.is_some()
                    && matches!(
                        galerkin_vi::systems::System::exact_solution(
                            &system, initial.t0, &initial.q, &initial.p
                        ),
                        Ok(None)
                    )
                {
                    eprintln!(
                        "warning: the exact solution of {} does not pass through the initial \
                         state (q = {:?}, p = {:?}); no position errors are reported",
                        self.name, initial.q, initial.p
                    );
                }
                AnySystem::from(system).into()
            }
            SystemSpec::RigidBody { inertia } => {
                BuiltSystem::RigidBody(AnyRigidBody::Free(FreeRigidBody::new(*inertia)?))
            }
            SystemSpec::HeavyTop {
                inertia,
                mass,
                gravity,
                com,
            } => BuiltSystem::RigidBody(AnyRigidBody::Heavy(HeavyTop::new(
                *inertia, *mass, *gravity, *com,
            )?)),
        };
        check_initial(&system, &initial)?;
        if let Some(spec) = &self.method.time_transform {
            match &system {
                BuiltSystem::Euclidean(s) => {
                    crate::run::time_transform::check(s, spec, &initial.q, &initial.p)?
                }
                BuiltSystem::RigidBody(_) => {
                    return Err(GviError::Unsupported(
                        "a time transformation needs a system on R^D, not a rigid body on SO(3)"
                            .into(),
                    )
                    .into());
                }
            }
        }
        if self.method.steps == 0 {
            return Err(GviError::InvalidStepCount {
                steps: 0,
                reason: format!("need 1 ≤ steps ≤ {}", galerkin_vi::integrator::MAX_STEPS),
            }
            .into());
        }
        Ok(BuiltScene {
            name: self.name.clone(),
            description: self.description.clone(),
            system,
            initial,
            method: self.method.clone(),
            scene: self.clone(),
        })
    }
}

impl From<AnySystem> for BuiltSystem {
    fn from(s: AnySystem) -> Self {
        BuiltSystem::Euclidean(s)
    }
}

/// Finiteness, then the lengths against the system's dimension.
fn check_initial(system: &BuiltSystem, init: &InitialState) -> Result<()> {
    let named = [
        ("initial position q0 (--q0, or q in [initial])", &init.q[..]),
        ("initial momentum p0 (--p0, or p in [initial])", &init.p[..]),
        ("initial time t0 (t0 in [initial])", &[init.t0][..]),
    ];
    for (what, values) in named {
        crate::error::ensure_finite(what, values)?;
    }
    use galerkin_vi::Lagrangian;
    let ensure_len = crate::error::ensure_len;
    match system {
        BuiltSystem::Euclidean(s) => {
            ensure_len("initial q (system dimension)", s.dim(), init.q.len())?;
            ensure_len("initial p (system dimension)", s.dim(), init.p.len())?;
            // The start `gvi run` refuses, every command refuses (`stability` ran from it).
            crate::run::check_start(s, &init.q, &init.p, init.t0)?;
        }
        BuiltSystem::RigidBody(_) => {
            ensure_len("initial q (rotation vector)", 3, init.q.len())?;
            ensure_len("initial p (body momentum)", 3, init.p.len())?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Overrides;
    use galerkin_vi::systems::System;

    fn kepler() -> Scene {
        Scene::load("kepler").unwrap()
    }

    #[test]
    fn the_one_validation_point_refuses_bad_initial_states() {
        let with = |o: Overrides| kepler().with_overrides(&o).build();
        let short = with(Overrides {
            q0: Some(vec![0.4]),
            ..Overrides::default()
        });
        assert!(matches!(
            short,
            Err(LabError::Core(GviError::DimensionMismatch { .. }))
        ));
        let nan = with(Overrides {
            p0: Some(vec![f64::NAN, 0.0]),
            ..Overrides::default()
        });
        match nan {
            Err(e @ LabError::Core(GviError::NonFinite { .. })) => {
                assert!(e.to_string().contains("--p0, or p in [initial]"), "{e}")
            }
            other => panic!("expected NonFinite, got {other:?}"),
        }
        let zero = with(Overrides {
            steps: Some(0),
            ..Overrides::default()
        });
        assert!(matches!(
            zero,
            Err(LabError::Core(GviError::InvalidStepCount { steps: 0, .. }))
        ));
        // Rigid bodies: a rotation vector and a body momentum, three entries each.
        let top = Scene::load("heavy-top")
            .unwrap()
            .with_overrides(&Overrides {
                q0: Some(vec![0.0; 4]),
                ..Overrides::default()
            });
        assert!(matches!(
            top.build(),
            Err(LabError::Core(GviError::DimensionMismatch {
                expected: 3,
                ..
            }))
        ));
    }

    #[test]
    fn built_scenes_hold_the_system_the_state_and_the_method() {
        let built = kepler()
            .with_overrides(&Overrides {
                n: Some(9),
                ..Overrides::default()
            })
            .build()
            .unwrap();
        assert_eq!(built.euclidean().unwrap().name(), "kepler");
        assert_eq!(built.method.n, 9);
        assert_eq!(built.scene().method.n, 9);
        let nb = Scene::load("two-body").unwrap().build().unwrap();
        assert_eq!(nb.euclidean().unwrap().as_nbody().unwrap().bodies(), 2);
        // An explicit q overrides the bodies' positions; p still comes from the bodies.
        let moved = Scene::load("two-body")
            .unwrap()
            .with_overrides(&Overrides {
                q0: Some(vec![-0.3, 0.0, 0.3, 0.0]),
                ..Overrides::default()
            })
            .build()
            .unwrap();
        assert_eq!(moved.initial.q, [-0.3, 0.0, 0.3, 0.0]);
        assert_eq!(moved.initial.p, nb.initial.p);
        let rigid = Scene::load("rigid-body").unwrap().build().unwrap();
        assert!(matches!(rigid.system, BuiltSystem::RigidBody(_)));
        assert!(matches!(
            rigid.euclidean(),
            Err(LabError::Core(GviError::Unsupported(_)))
        ));
    }
}
