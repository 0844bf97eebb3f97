//! The time transformation as a value of the method ([`crate::method::MethodSpec`]'s
//! `time_transform`, a scene file's `[method.time_transform]` table, the lab's
//! `--time-transform` flag), and [`AnyMonitor`], the built-in monitors chosen at run time.

use super::{CentralDistance, Combine, Monitor, PairDistances};
use crate::error::{GviError, Result};
use crate::systems::AnySystem;
use num_dual::DualNum;
use serde::{Deserialize, Serialize};

/// A built-in monitor by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MonitorKind {
    /// The system's Sundman-type choice: `radius` for the Kepler problem, `softmin-distance`
    /// for N bodies (the smooth minimum: on the Pythagorean problem the kinks of
    /// `min-distance` cost six orders of magnitude in energy, docs/guide/time-transformations.md).
    #[default]
    Sundman,
    /// g = |q|^α ([`CentralDistance`]).
    Radius,
    /// g = (min r_ij)^α ([`PairDistances`], [`Combine::Min`]).
    MinDistance,
    /// g = (Σ r_ij^{−β})^{−α/β} ([`Combine::Softmin`]).
    SoftminDistance,
    /// g = Π r_ij^α ([`Combine::Product`]).
    ProductDistance,
}

impl MonitorKind {
    /// The names accepted in scene files and on the command line.
    pub const NAMES: [&'static str; 5] = [
        "sundman",
        "radius",
        "min-distance",
        "softmin-distance",
        "product-distance",
    ];

    /// The name in scene files and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            MonitorKind::Sundman => "sundman",
            MonitorKind::Radius => "radius",
            MonitorKind::MinDistance => "min-distance",
            MonitorKind::SoftminDistance => "softmin-distance",
            MonitorKind::ProductDistance => "product-distance",
        }
    }
}

impl std::str::FromStr for MonitorKind {
    type Err = GviError;
    fn from_str(s: &str) -> Result<Self> {
        Self::NAMES
            .iter()
            .position(|n| *n == s)
            .map(|i| {
                [
                    MonitorKind::Sundman,
                    MonitorKind::Radius,
                    MonitorKind::MinDistance,
                    MonitorKind::SoftminDistance,
                    MonitorKind::ProductDistance,
                ][i]
            })
            .ok_or_else(|| GviError::InvalidInput {
                name: "time-transform monitor".into(),
                reason: format!("unknown '{s}'; one of {}", Self::NAMES.join(", ")),
            })
    }
}

fn default_alpha() -> f64 {
    1.5
}

/// A Poincaré time transformation as part of a method: the monitor, its exponent α, the
/// energy level E₀ and the physical end time and output spacing of the run.
///
/// In a scene file:
///
/// ```toml
/// [method]
/// n = 12
/// h = 0.05          # the fictitious step Δs (= the physical step at the initial state)
/// steps = 100000    # at most this many fictitious steps
/// [method.time_transform]
/// monitor = "sundman"
/// alpha = 1.5
/// t_end = 70.0      # physical end time, located on t(s)
/// every = 0.5       # rows at t0 + k·every, located on t(s)
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeTransformSpec {
    /// The monitor g.
    #[serde(default)]
    pub monitor: MonitorKind,
    /// Its exponent α (default 1.5).
    #[serde(default = "default_alpha")]
    pub alpha: f64,
    /// E₀ (default: the energy of the initial state).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub energy: Option<f64>,
    /// The physical end time (default: run the method's `steps` fictitious steps).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub t_end: Option<f64>,
    /// Output at t₀ + k·every in physical time (default: at the step ends).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub every: Option<f64>,
}

impl TimeTransformSpec {
    /// The given monitor with α = 1.5 and the defaults otherwise.
    pub fn new(monitor: MonitorKind) -> Self {
        TimeTransformSpec {
            monitor,
            alpha: default_alpha(),
            energy: None,
            t_end: None,
            every: None,
        }
    }

    /// Check what needs no system: α finite, E₀ finite if given, t_end and every finite and
    /// positive if given (t_end relative to t₀ is checked by the run).
    ///
    /// Errors: [`GviError::InvalidParameter`] naming the field.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, value: f64, reason: &str| GviError::InvalidParameter {
            name: format!("time-transform {name}"),
            value,
            reason: reason.into(),
        };
        if !self.alpha.is_finite() {
            return Err(bad("exponent alpha", self.alpha, "must be finite"));
        }
        if let Some(e) = self.energy.filter(|e| !e.is_finite()) {
            return Err(bad("energy E0", e, "must be finite"));
        }
        if let Some(t) = self.t_end.filter(|t| !t.is_finite()) {
            return Err(bad("t_end", t, "must be finite"));
        }
        if let Some(e) = self.every.filter(|e| !(e.is_finite() && *e > 0.0)) {
            return Err(bad("every", e, "must be finite and positive"));
        }
        Ok(())
    }

    /// The monitor this spec names for `system`: `radius` needs the Kepler problem, the
    /// pair-distance monitors an N-body system, `sundman` picks the one that fits.
    ///
    /// Errors: [`validate`](Self::validate)'s; [`GviError::Unsupported`] for a monitor that
    /// does not fit the system.
    pub fn monitor_for(&self, system: &AnySystem) -> Result<AnyMonitor> {
        self.validate()?;
        let pairs = |combine| match system {
            AnySystem::NBody(nb) => Ok(AnyMonitor::Pairs(PairDistances::new(
                nb.bodies(),
                nb.body_dim(),
                self.alpha,
                combine,
            )?)),
            _ => Err(GviError::Unsupported(format!(
                "the time-transform monitor '{}' needs an N-body system",
                self.monitor.as_str()
            ))),
        };
        match (self.monitor, system) {
            (MonitorKind::Sundman | MonitorKind::Radius, AnySystem::Kepler(_)) => {
                Ok(AnyMonitor::Central(CentralDistance::new(self.alpha)?))
            }
            (MonitorKind::Radius, _) => Err(GviError::Unsupported(
                "the time-transform monitor 'radius' (|q|^alpha) is for the Kepler problem in \
                 its relative coordinate"
                    .into(),
            )),
            (MonitorKind::MinDistance, _) => pairs(Combine::Min),
            (MonitorKind::Sundman | MonitorKind::SoftminDistance, _) => pairs(Combine::Softmin),
            (MonitorKind::ProductDistance, _) => pairs(Combine::Product),
        }
    }
}

/// One of the built-in monitors, chosen at run time; a [`Monitor`] by dispatch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AnyMonitor {
    /// [`CentralDistance`].
    Central(CentralDistance),
    /// [`PairDistances`].
    Pairs(PairDistances),
}

impl Monitor for AnyMonitor {
    fn name(&self) -> String {
        match self {
            AnyMonitor::Central(m) => m.name(),
            AnyMonitor::Pairs(m) => m.name(),
        }
    }
    fn value<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        match self {
            AnyMonitor::Central(m) => m.value(q),
            AnyMonitor::Pairs(m) => m.value(q),
        }
    }
    fn dim(&self) -> Option<usize> {
        match self {
            AnyMonitor::Central(m) => m.dim(),
            AnyMonitor::Pairs(m) => m.dim(),
        }
    }
    fn value_f64(&self, q: &[f64]) -> f64 {
        match self {
            AnyMonitor::Central(m) => m.value_f64(q),
            AnyMonitor::Pairs(m) => m.value_f64(q),
        }
    }
    fn gradient(&self, q: &[f64], grad: &mut [f64]) -> f64 {
        match self {
            AnyMonitor::Central(m) => m.gradient(q, grad),
            AnyMonitor::Pairs(m) => m.gradient(q, grad),
        }
    }
    fn hessian(&self, q: &[f64], grad: &mut [f64], hess: &mut [f64]) -> f64 {
        match self {
            AnyMonitor::Central(m) => m.hessian(q, grad, hess),
            AnyMonitor::Pairs(m) => m.hessian(q, grad, hess),
        }
    }
}
