//! The scene-file form of an expression Lagrangian (`[system] type = "lagrangian"`).

use super::ExpressionLagrangian;
use crate::error::Result;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// `[system]` of a scene with `type = "lagrangian"`:
///
/// ```toml
/// [system]
/// type = "lagrangian"
/// coordinates = ["x", "y"]                 # velocities are written x_dot, y_dot
/// parameters = { lambda = 1.0 }
/// lagrangian = "(x_dot^2 + y_dot^2)/2 - (x^2 + y^2)/2 - lambda*(x^2*y - y^3/3)"
/// invariants = { energy = true }           # optional (default: energy reported)
/// # optional: q(t) through the initial state, one expression in t per coordinate, e.g.
/// # exact = ["cos(t)", "0.5*sin(t)"] for L = (x_dot^2 + y_dot^2)/2 - (x^2 + y^2)/2 from
/// # q = (1, 0), p = (0, 0.5)
/// force = ["-0.1*x_dot", "0"]              # optional: f(t, q, q̇), one per coordinate
/// ```
///
/// The Lagrangian and the force may read the time `t`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LagrangianSpec {
    /// Coordinate names; the velocity of `x` is `x_dot`.
    pub coordinates: Vec<String>,
    /// Named parameters (numbers), usable in the expressions.
    #[serde(default)]
    pub parameters: BTreeMap<String, f64>,
    /// L(q, q̇) as an expression.
    pub lagrangian: String,
    /// Which invariants to report.
    #[serde(default)]
    pub invariants: ExpressionInvariants,
    /// A closed-form solution q(t) through the scene's initial state, one expression in `t`
    /// (and the parameters) per coordinate; runs then report the error against it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exact: Option<Vec<String>>,
    /// A non-conservative force f(t, q, q̇), one expression per coordinate (discrete
    /// Lagrange–d'Alembert principle).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<Vec<String>>,
}

/// The invariants an expression Lagrangian reports.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExpressionInvariants {
    /// The energy p·v − L (Legendre transform).
    #[serde(default = "yes")]
    pub energy: bool,
}

impl Default for ExpressionInvariants {
    fn default() -> Self {
        ExpressionInvariants { energy: true }
    }
}

fn yes() -> bool {
    true
}

impl LagrangianSpec {
    /// Parse and compile the system (no state check; see [`LagrangianSpec::check`]).
    pub fn build(&self) -> Result<ExpressionLagrangian> {
        let coordinates: Vec<&str> = self.coordinates.iter().map(String::as_str).collect();
        let parameters: Vec<(&str, f64)> = self
            .parameters
            .iter()
            .map(|(n, v)| (n.as_str(), *v))
            .collect();
        let mut system = ExpressionLagrangian::parse(&self.lagrangian, &coordinates, &parameters)?
            .with_energy(self.invariants.energy);
        if let Some(force) = &self.force {
            let force: Vec<&str> = force.iter().map(String::as_str).collect();
            system = system.with_force(&force)?;
        }
        match &self.exact {
            Some(exact) => {
                let exact: Vec<&str> = exact.iter().map(String::as_str).collect();
                system.with_exact_solution(&exact)
            }
            None => Ok(system),
        }
    }

    /// Build the system and check the initial state at t = 0: lengths of q and p, and that
    /// the Lagrangian is regular there ([`ExpressionLagrangian::check_state`]).
    pub fn check(&self, q: &[f64], p: &[f64]) -> Result<ExpressionLagrangian> {
        self.check_at(0.0, q, p)
    }

    /// [`check`](Self::check) at the initial time t0.
    pub fn check_at(&self, t0: f64, q: &[f64], p: &[f64]) -> Result<ExpressionLagrangian> {
        let system = self.build()?;
        system.check_state_at(t0, q, p)?;
        Ok(system)
    }
}
