//! The names of a system's coordinates and momenta in tables, JSON and charts.
//!
//! An expression Lagrangian names its own coordinates (`coordinates = ["theta"]`): its tables
//! have the columns `theta` and `p_theta`, the names its events, sections and Python
//! expressions already use. The built-in systems keep the numbered names `q0, q1, …` and
//! `p0, p1, …` of the documented CSV format (N-body states body-major), which scripts and the
//! Python tests read; their charts use the natural axis names (`x`, `y` for Kepler and the
//! N-body orbit charts).
//!
//! ```
//! use galerkin_vi_lab::names::{momentum_name, state_columns};
//! use galerkin_vi_lab::scene::Scene;
//!
//! let built = Scene::load("double-pendulum")?.build()?;
//! let system = built.euclidean()?;
//! assert_eq!(state_columns(system), ["th1", "th2", "p_th1", "p_th2"]);
//! assert_eq!(momentum_name("q0"), "p0");
//! let kepler = Scene::load("kepler")?.build()?;
//! assert_eq!(state_columns(kepler.euclidean()?), ["q0", "q1", "p0", "p1"]);
//! # Ok::<(), galerkin_vi_lab::error::LabError>(())
//! ```

use galerkin_vi::Lagrangian;
use galerkin_vi::systems::AnySystem;

/// The coordinate names of a system: an expression Lagrangian's own, `q0, q1, …` otherwise.
pub fn coordinate_names(system: &AnySystem) -> Vec<String> {
    match system.as_expression() {
        Some(e) => e.coordinates().to_vec(),
        None => (0..system.dim()).map(|i| format!("q{i}")).collect(),
    }
}

/// The momentum name of coordinate `c`: `p_theta` for `theta`, `p0` for the numbered `q0`.
pub fn momentum_name(c: &str) -> String {
    match c.strip_prefix('q') {
        Some(i) if !i.is_empty() && i.chars().all(|ch| ch.is_ascii_digit()) => format!("p{i}"),
        _ => format!("p_{c}"),
    }
}

/// The momentum names of a system, in coordinate order ([`momentum_name`]).
pub fn momentum_names(system: &AnySystem) -> Vec<String> {
    coordinate_names(system)
        .iter()
        .map(|c| momentum_name(c))
        .collect()
}

/// The state columns of a table: the coordinate names, then the momentum names.
pub fn state_columns(system: &AnySystem) -> Vec<String> {
    let mut names = coordinate_names(system);
    names.extend(momentum_names(system));
    names
}

/// Axis names for charts of the configuration: `x`, `y` for Kepler's plane, the coordinate
/// names of an expression Lagrangian, `q` for a one-dimensional built-in system and
/// `q0, q1, …` otherwise.
pub fn axis_names(system: &AnySystem) -> Vec<String> {
    match system {
        AnySystem::Kepler(_) => vec!["x".into(), "y".into()],
        AnySystem::Expression(e) => e.coordinates().to_vec(),
        _ if system.dim() == 1 => vec!["q".into()],
        _ => coordinate_names(system),
    }
}

/// The unit of a scene quantity for an axis label: ` (AU)` for a given unit, ` (length
/// units)` when the scene gives none (`what` is `length` or `time`).
pub fn unit_suffix(unit: Option<&str>, what: &str) -> String {
    match unit.map(str::trim) {
        Some(u) if !u.is_empty() => format!(" ({u})"),
        _ => format!(" ({what} units)"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    #[test]
    fn expression_scenes_use_their_own_names_and_builtins_numbered_ones() {
        let system = |name: &str| Scene::load(name).unwrap().build().unwrap();
        let hh = system("henon-heiles");
        let hh = hh.euclidean().unwrap();
        assert_eq!(state_columns(hh), ["x", "y", "p_x", "p_y"]);
        assert_eq!(axis_names(hh), ["x", "y"]);
        let kepler = system("kepler");
        assert_eq!(axis_names(kepler.euclidean().unwrap()), ["x", "y"]);
        let pendulum = system("pendulum");
        let pendulum = pendulum.euclidean().unwrap();
        assert_eq!(state_columns(pendulum), ["q0", "p0"]);
        assert_eq!(axis_names(pendulum), ["q"]);
        assert_eq!(momentum_name("q12"), "p12");
        assert_eq!(momentum_name("q"), "p_q");
        assert_eq!(momentum_name("qx"), "p_qx");
        assert_eq!(unit_suffix(Some("AU"), "length"), " (AU)");
        assert_eq!(unit_suffix(Some(" "), "length"), " (length units)");
        assert_eq!(unit_suffix(None, "time"), " (time units)");
    }
}
