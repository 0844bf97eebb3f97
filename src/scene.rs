//! Scenes: small TOML files naming a system, its parameters, an initial state and a method.
//!
//! Built-in scenes (`harmonic`, `kepler`, `pendulum`) are compiled into the crate from the
//! `scenes/` directory; any other argument is read as a path to a user's TOML file. Unknown
//! keys are rejected so that a typo is an error, not a silently ignored setting.
//!
//! ```
//! use galerkin_vi::scene::Scene;
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

use crate::basis::BasisKind;
use crate::error::{GviError, Result};
use crate::quadrature::QuadratureKind;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The built-in scenes: (name, TOML text).
pub const BUILTIN_SCENES: [(&str, &str); 3] = [
    ("harmonic", include_str!("../scenes/harmonic.toml")),
    ("kepler", include_str!("../scenes/kepler.toml")),
    ("pendulum", include_str!("../scenes/pendulum.toml")),
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
    /// The mechanical system.
    pub system: SystemSpec,
    /// Initial state.
    pub initial: InitialState,
    /// Integration method.
    pub method: MethodSpec,
}

/// A built-in system and its parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum SystemSpec {
    /// [`HarmonicOscillator`](crate::systems::HarmonicOscillator).
    Harmonic {
        /// Mass m.
        #[serde(default = "one")]
        mass: f64,
        /// Stiffness k.
        #[serde(default = "one")]
        stiffness: f64,
    },
    /// [`Kepler`](crate::systems::Kepler).
    Kepler {
        /// Gravitational parameter μ.
        #[serde(default = "one")]
        mu: f64,
    },
    /// [`Pendulum`](crate::systems::Pendulum).
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
}

fn one() -> f64 {
    1.0
}

/// Initial time and state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialState {
    /// Initial time.
    #[serde(default)]
    pub t0: f64,
    /// Initial position.
    pub q: Vec<f64>,
    /// Initial momentum.
    pub p: Vec<f64>,
}

/// Method settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MethodSpec {
    /// Basis kind.
    #[serde(default)]
    pub basis: BasisKind,
    /// Quadrature kind.
    #[serde(default)]
    pub quadrature: QuadratureKind,
    /// Number of basis functions.
    pub n: usize,
    /// Quadrature points (default: the rule's default for n, 2n for Gauss–Legendre).
    #[serde(default)]
    pub quad_points: Option<usize>,
    /// Step size.
    pub h: f64,
    /// Number of steps.
    pub steps: usize,
}

impl Scene {
    /// Parse a scene from TOML text; `origin` names it in errors.
    pub fn from_toml_str(origin: &str, text: &str) -> Result<Scene> {
        let mut scene: Scene = toml::from_str(text).map_err(|e| GviError::Scene {
            source_name: origin.to_string(),
            reason: e.to_string(),
        })?;
        if scene.name.is_empty() {
            scene.name = origin.to_string();
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
            let text = std::fs::read_to_string(path).map_err(|source| GviError::Io {
                path: path.to_path_buf(),
                source,
            })?;
            return Scene::from_toml_str(name_or_path, &text);
        }
        Err(GviError::Scene {
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
                Err(GviError::Scene { .. }) => {}
                other => panic!("expected a scene error for {text:?}, got {other:?}"),
            }
        }
        assert!(matches!(
            Scene::load("/no/such/scene.toml"),
            Err(GviError::Scene { .. })
        ));
    }
}
