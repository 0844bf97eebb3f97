//! Scenes: small TOML files naming a system, its parameters, an initial state and a method.
//!
//! Built-in scenes (`harmonic`, `kepler`, `pendulum`, the rigid bodies `rigid-body` and
//! `heavy-top`, `pendulum-3d` (run by [`galerkin_vi::lie`]), the N-body scenes `solar-system`,
//! `outer-solar-system`, `two-body`, `figure-eight`, `lagrange-triangle` and the synthetic
//! `planetesimal-ring`, the expression-Lagrangian scenes `henon-heiles`,
//! `double-pendulum` and `magnetic`, and the time-transformed `kepler-e099` and
//! `pythagorean`) are
//! compiled into the crate from the `scenes/` directory; any other argument is read as a path to a user's TOML file. Unknown
//! keys are rejected so that a typo is an error, not a silently ignored setting.
//!
//! ```
//! use galerkin_vi_lab::scene::Scene;
//! let scene = Scene::load("kepler").unwrap();
//! assert_eq!(scene.method.h, 2.0);
//! let custom = Scene::from_toml_str("inline", r#"
//!     [system]
//!     type = "harmonic"
//!     [initial]
//!     q = [0.5]
//!     p = [0.0]
//!     [method]
//!     n = 12
//!     h = 1.0
//!     steps = 10
//! "#).unwrap();
//! assert_eq!(custom.method.n, 12);
//! ```

use crate::error::LabError;
use crate::error::Result;
pub use crate::nbody_scene::Body;
pub use galerkin_vi::method::{InitialState, MethodSpec};
use serde::{Deserialize, Serialize};
use std::path::Path;

mod build;
#[cfg(test)]
mod guide;
mod overrides;
pub use build::{AnyRigidBody, BuiltScene, BuiltSystem};
pub use overrides::Overrides;

/// The built-in scenes: (name, TOML text).
pub const BUILTIN_SCENES: [(&str, &str); 23] = [
    ("harmonic", include_str!("../../../scenes/harmonic.toml")),
    ("kepler", include_str!("../../../scenes/kepler.toml")),
    ("pendulum", include_str!("../../../scenes/pendulum.toml")),
    (
        "solar-system",
        include_str!("../../../scenes/solar-system.toml"),
    ),
    (
        "outer-solar-system",
        include_str!("../../../scenes/outer-solar-system.toml"),
    ),
    ("two-body", include_str!("../../../scenes/two-body.toml")),
    (
        "figure-eight",
        include_str!("../../../scenes/figure-eight.toml"),
    ),
    (
        "planetesimal-ring",
        include_str!("../../../scenes/planetesimal-ring.toml"),
    ),
    (
        "lagrange-triangle",
        include_str!("../../../scenes/lagrange-triangle.toml"),
    ),
    (
        "rigid-body",
        include_str!("../../../scenes/rigid-body.toml"),
    ),
    ("heavy-top", include_str!("../../../scenes/heavy-top.toml")),
    (
        "pendulum-3d",
        include_str!("../../../scenes/pendulum-3d.toml"),
    ),
    (
        "henon-heiles",
        include_str!("../../../scenes/henon-heiles.toml"),
    ),
    (
        "double-pendulum",
        include_str!("../../../scenes/double-pendulum.toml"),
    ),
    ("magnetic", include_str!("../../../scenes/magnetic.toml")),
    ("duffing", include_str!("../../../scenes/duffing.toml")),
    (
        "kepler-e099",
        include_str!("../../../scenes/kepler-e099.toml"),
    ),
    (
        "pythagorean",
        include_str!("../../../scenes/pythagorean.toml"),
    ),
    (
        "damped-oscillator",
        include_str!("../../../scenes/damped-oscillator.toml"),
    ),
    ("fpu", include_str!("../../../scenes/fpu.toml")),
    (
        "varying-frequency",
        include_str!("../../../scenes/varying-frequency.toml"),
    ),
    (
        "fpu-two-frequency",
        include_str!("../../../scenes/fpu-two-frequency.toml"),
    ),
    (
        "spring-pendulum",
        include_str!("../../../scenes/spring-pendulum.toml"),
    ),
];

/// A complete experiment: system, initial state and method.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Short name.
    #[serde(default)]
    pub name: String,
    /// One-line description.
    #[serde(default)]
    pub description: String,
    /// Where the data come from.
    #[serde(default)]
    pub source: String,
    /// The units of the scene's numbers, for labels (`[units]`: `length`, `time`, `mass`;
    /// all optional). Charts of N-body runs label their axes with them.
    #[serde(default, skip_serializing_if = "Units::is_empty")]
    pub units: Units,
    /// The mechanical system.
    pub system: SystemSpec,
    /// Initial state. May be omitted for N-body scenes, whose state comes from the bodies
    /// (filled in by [`Scene::build`]); an explicit `q` or `p` in `[initial]` overrides the
    /// bodies' positions or momenta.
    #[serde(default)]
    pub initial: InitialState,
    /// Integration method.
    pub method: MethodSpec,
    /// Periodic-orbit data and initial guess for `gvi periodic` (see [`crate::periodic`] for
    /// the analysis and [`galerkin_vi::periodic`] for the solver).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub periodic: Option<galerkin_vi::periodic::PeriodicSpec>,
}

/// The `[units]` table of a scene: names of the units its numbers are in, used in labels
/// only (nothing is converted).
///
/// ```toml
/// [units]
/// length = "AU"
/// time = "days"
/// mass = "solar masses"
/// ```
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Units {
    /// Unit of positions (e.g. `AU`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length: Option<String>,
    /// Unit of time (e.g. `days`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time: Option<String>,
    /// Unit of mass (e.g. `solar masses`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<String>,
}

impl Units {
    /// Whether no unit is given.
    pub fn is_empty(&self) -> bool {
        self.length.is_none() && self.time.is_none() && self.mass.is_none()
    }
}

/// A built-in system and its parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum SystemSpec {
    /// [`HarmonicOscillator`](galerkin_vi::systems::HarmonicOscillator).
    Harmonic {
        /// Mass m.
        #[serde(default = "one")]
        mass: f64,
        /// Stiffness k.
        #[serde(default = "one")]
        stiffness: f64,
    },
    /// [`Kepler`](galerkin_vi::systems::Kepler).
    Kepler {
        /// Gravitational parameter μ.
        #[serde(default = "one")]
        mu: f64,
    },
    /// [`NBody`](galerkin_vi::systems::NBody): point masses under Newtonian gravity, one
    /// `[[system.bodies]]` table per body (see [`Body`]). Example:
    ///
    /// ```toml
    /// [system]
    /// type = "nbody"
    /// dim = 2
    /// g = 1.0
    /// barycentric = true
    /// [[system.bodies]]
    /// name = "A"
    /// mass = 1.0
    /// q = [1.0, 0.0]
    /// v = [0.0, 0.5]
    /// ```
    #[serde(rename = "nbody")]
    NBody {
        /// Dimension of each body: 2 or 3.
        dim: usize,
        /// Gravitational constant G (default 1). Must be omitted when the bodies give `gm`.
        #[serde(default)]
        g: Option<f64>,
        /// Names of bodies to merge into one point mass at their barycentre, with their total
        /// mass and momentum, placed where the first of them was (as the paper aggregates the
        /// inner solar system for its outer-system run). Named by joining the names with `+`.
        #[serde(default)]
        aggregate: Option<Vec<String>>,
        /// Move to the barycentric frame (subtract the centre-of-mass position and velocity)
        /// after aggregation.
        #[serde(default)]
        barycentric: bool,
        /// The bodies, in the order of the configuration vector (body-major flattening).
        bodies: Vec<Body>,
    },
    /// [`ExpressionLagrangian`](galerkin_vi::systems::ExpressionLagrangian): L(q, q̇) written as
    /// an expression (see [`LagrangianSpec`](galerkin_vi::systems::expression::LagrangianSpec)).
    Lagrangian(galerkin_vi::systems::expression::LagrangianSpec),
    /// [`Pendulum`](galerkin_vi::systems::Pendulum).
    Pendulum {
        /// Length l.
        #[serde(default = "one")]
        length: f64,
        /// Gravity g.
        #[serde(default = "one")]
        gravity: f64,
        /// Mass m.
        #[serde(default = "one")]
        mass: f64,
    },
    /// [`Fpu`](galerkin_vi::systems::Fpu): the Fermi–Pasta–Ulam chain of m stiff springs of
    /// frequency ω (Hairer–Lubich–Wanner's form; D = 2m), or one frequency per spring.
    Fpu {
        /// Number m of stiff springs (default 3).
        #[serde(default = "three")]
        springs: usize,
        /// Stiff frequency ω (default 50), or a list of m frequencies, one per spring
        /// (`omega = [50.0, 50.0, 20.0, 20.0]`; `springs` must then be m).
        #[serde(
            default,
            skip_serializing_if = "Option::is_none",
            deserialize_with = "galerkin_vi::method::frequencies::deserialize",
            serialize_with = "galerkin_vi::method::frequencies::serialize"
        )]
        omega: Option<Vec<f64>>,
    },
    /// [`SpringPendulum`](galerkin_vi::systems::SpringPendulum): a unit mass on a stiff spring
    /// in the plane under gravity (D = 2), a fast frequency that depends on the state.
    SpringPendulum {
        /// Spring frequency ω = √(k/m) (default 50).
        #[serde(default = "fifty")]
        omega: f64,
        /// Rest length l (default 1).
        #[serde(default = "one")]
        length: f64,
        /// Gravity g (default 1).
        #[serde(default = "one")]
        gravity: f64,
    },
    /// [`FreeRigidBody`](galerkin_vi::lie::FreeRigidBody) on SO(3) (Lie group integrator;
    /// `[initial] q` is the rotation vector of R₀, `p` the body momentum).
    RigidBody {
        /// Principal moments of inertia.
        inertia: [f64; 3],
    },
    /// [`HeavyTop`](galerkin_vi::lie::HeavyTop) on SO(3) (Lie group integrator).
    HeavyTop {
        /// Principal moments of inertia about the fixed point.
        inertia: [f64; 3],
        /// Mass m.
        #[serde(default = "one")]
        mass: f64,
        /// Gravity g.
        #[serde(default = "one")]
        gravity: f64,
        /// Centre of mass in the body frame.
        com: [f64; 3],
    },
}

fn one() -> f64 {
    1.0
}

fn three() -> usize {
    3
}

fn fifty() -> f64 {
    50.0
}

/// The `type` of a `[system]` table, as written in scene files (`kepler`, `nbody`,
/// `lagrangian`, …).
pub fn system_type(system: &SystemSpec) -> &'static str {
    match system {
        SystemSpec::Harmonic { .. } => "harmonic",
        SystemSpec::Kepler { .. } => "kepler",
        SystemSpec::NBody { .. } => "nbody",
        SystemSpec::Lagrangian(_) => "lagrangian",
        SystemSpec::Pendulum { .. } => "pendulum",
        SystemSpec::Fpu { .. } => "fpu",
        SystemSpec::SpringPendulum { .. } => "spring-pendulum",
        SystemSpec::RigidBody { .. } => "rigid-body",
        SystemSpec::HeavyTop { .. } => "heavy-top",
    }
}

/// The `[system]` table is an internally tagged enum, which serde parses from a buffer without
/// positions, so toml points an unknown key inside it (a typo in a `[[system.bodies]]` entry)
/// at the `[system]` header. Find the key's own line instead.
fn locate_unknown_field(text: &str, message: String) -> String {
    let Some(field) = message
        .split("unknown field `")
        .nth(1)
        .and_then(|rest| rest.split('`').next())
    else {
        return message;
    };
    let line = text.lines().position(|l| {
        l.trim_start()
            .strip_prefix(field)
            .is_some_and(|rest| rest.trim_start().starts_with('='))
    });
    match line {
        Some(i) => {
            let detail = message.lines().last().unwrap_or("").trim();
            format!(
                "line {}: {detail}\n  | {}",
                i + 1,
                text.lines().nth(i).unwrap_or("")
            )
        }
        None => message,
    }
}

impl Scene {
    /// Parse a scene from TOML text; `origin` names it in errors.
    pub fn from_toml_str(origin: &str, text: &str) -> Result<Scene> {
        let mut scene: Scene = toml::from_str(text).map_err(|e| LabError::Scene {
            source_name: origin.to_string(),
            reason: locate_unknown_field(text, e.to_string()),
        })?;
        if scene.name.is_empty() {
            scene.name = origin.to_string();
        }
        let nbody = matches!(scene.system, SystemSpec::NBody { .. });
        if !nbody && (scene.initial.q.is_empty() || scene.initial.p.is_empty()) {
            return Err(LabError::Scene {
                source_name: origin.to_string(),
                reason: "missing [initial] q and p".into(),
            });
        }
        Ok(scene)
    }

    /// A built-in scene by name, or a TOML file by path.
    pub fn load(name_or_path: &str) -> Result<Scene> {
        if let Some((_, text)) = BUILTIN_SCENES.iter().find(|(n, _)| *n == name_or_path) {
            return Scene::from_toml_str(name_or_path, text);
        }
        let path = Path::new(name_or_path);
        if path.is_file() {
            let text = std::fs::read_to_string(path).map_err(|source| LabError::Io {
                path: path.to_path_buf(),
                source,
            })?;
            return Scene::from_toml_str(name_or_path, &text);
        }
        let what = match std::fs::metadata(path) {
            Ok(m) if m.is_dir() => Some("a directory"),
            Ok(_) => Some("not a regular file (a device, a FIFO or a socket)"),
            Err(_) => None,
        };
        if let Some(what) = what {
            return Err(LabError::Scene {
                source_name: name_or_path.to_string(),
                reason: format!("{what}; a scene is a built-in name or a TOML file"),
            });
        }
        Err(LabError::Scene {
            source_name: name_or_path.to_string(),
            reason: format!(
                "not a built-in scene ({}) and no such file",
                BUILTIN_SCENES.map(|(n, _)| n).join(", ")
            ),
        })
    }

    /// Names of the built-in scenes.
    pub fn builtin_names() -> Vec<&'static str> {
        BUILTIN_SCENES.iter().map(|(n, _)| *n).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_parse() {
        for name in Scene::builtin_names() {
            let s = Scene::load(name).unwrap();
            assert_eq!(s.name, name);
            assert!(!s.source.is_empty());
            let built = s.build().unwrap();
            assert_eq!(built.initial.q.len(), built.initial.p.len());
        }
    }

    #[test]
    fn malformed_scenes_are_typed_errors() {
        let bad = [
            "not toml [",
            "[system]\ntype = \"kepler\"\n",
            "[system]\ntype = \"warp-drive\"\n[initial]\nq=[1]\np=[0]\n[method]\nn=4\nh=1\nsteps=1",
            "[system]\ntype = \"kepler\"\nmu = 1\nmoo = 2\n[initial]\nq=[1,0]\np=[0,1]\n[method]\nn=4\nh=1\nsteps=1",
            "[system]\ntype = \"kepler\"\n[initial]\nq=[1,0]\np=[0,1]\n[method]\nn=4\nh=1\nsteps=-1",
            "[system]\ntype = \"kepler\"\n[initial]\nq=[1,0]\np=[0,1]\n[method]\nbasis=\"spline\"\nn=4\nh=1\nsteps=1",
        ];
        for text in bad {
            match Scene::from_toml_str("t", text) {
                Err(LabError::Scene { .. }) => {}
                other => panic!("expected a scene error for {text:?}, got {other:?}"),
            }
        }
        assert!(matches!(
            Scene::load("/no/such/scene.toml"),
            Err(LabError::Scene { .. })
        ));
    }

    #[test]
    fn nbody_scenes_derive_their_initial_state() {
        let s = Scene::load("solar-system").unwrap().build().unwrap();
        assert_eq!((s.initial.q.len(), s.initial.p.len()), (30, 30));
        // p = GM v (barycentric correction of the data is below 1e-8 of the Sun's velocity).
        let mercury_vx = 2.137_177_411_241_642e-2;
        assert!((s.initial.p[3] / 0.4912547451450812e-10 - mercury_vx).abs() < 1e-7);
        let two = Scene::load("two-body").unwrap().build().unwrap();
        assert_eq!(two.initial.q, [-0.2, 0.0, 0.2, 0.0]);
        assert_eq!(two.initial.p, [0.0, -0.5, 0.0, 0.5]);
    }

    #[test]
    fn malformed_nbody_scenes_are_scene_errors() {
        let method = "[method]\nn = 8\nh = 1\nsteps = 1\n";
        let head = "[system]\ntype = \"nbody\"\ndim = 2\n";
        let bad = [
            // no bodies
            format!("{head}bodies = []\n{method}"),
            // missing q
            format!("{head}[[system.bodies]]\nname = \"A\"\nmass = 1\nv = [0, 0]\n{method}"),
            // unknown key in a body
            format!(
                "{head}[[system.bodies]]\nname = \"A\"\nmass = 1\nq = [0, 0]\nv = [0, 0]\n\
                 colour = \"red\"\n{method}"
            ),
            // wrong length
            format!(
                "{head}[[system.bodies]]\nname = \"A\"\nmass = 1\nq = [0]\nv = [0, 0]\n{method}"
            ),
            // gm together with g
            format!(
                "[system]\ntype = \"nbody\"\ndim = 2\ng = 2.0\n[[system.bodies]]\nname = \"A\"\n\
                 gm = 1\nq = [0, 0]\nv = [0, 0]\n{method}"
            ),
            // missing dim
            format!("[system]\ntype = \"nbody\"\nbodies = []\n{method}"),
            // a non-N-body scene without [initial]
            format!("[system]\ntype = \"kepler\"\n{method}"),
        ];
        for text in bad {
            match Scene::from_toml_str("t", &text).and_then(|s| s.build()) {
                Err(LabError::Scene { .. }) => {}
                other => panic!("expected a scene error for {text:?}, got {other:?}"),
            }
        }
    }
}
