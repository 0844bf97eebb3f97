//! The `[periodic]` table of a scene: the kind of curve, the number of modes, the period
//! condition and the crude initial guess.
//!
//! ```toml
//! [periodic]
//! kind = "choreography"   # or "orbit" (one curve per coordinate; the default)
//! modes = 40              # K
//! condition = "energy"    # or "period" (fixed period)
//! period = 6.0            # the fixed period, or the guess when condition = "energy"
//! # energy = -1.28        # default: the energy of the scene's initial state
//! [[periodic.guess]]      # the low modes of the guess; every other coefficient is zero
//! k = 1
//! a = [0.0, 0.0]
//! b = [1.0, 0.0]
//! ```

use super::curve::{FourierCurve, Layout};
use serde::{Deserialize, Serialize};

/// What the unknown curve describes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CurveKind {
    /// One curve per configuration coordinate.
    #[default]
    Orbit,
    /// One curve shared by all (equal-mass) bodies: q_{i+1}(t) = q_i(t + T/N).
    Choreography,
}

/// Fixed period or fixed energy.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ConditionKind {
    /// The period is fixed at `period`.
    #[default]
    Period,
    /// The period is unknown; the energy is `energy` (default: the initial state's).
    Energy,
}

/// One mode of the initial guess.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GuessMode {
    /// Mode number k (0: the mean).
    pub k: usize,
    /// Cosine coefficients a_k, one per curve component.
    pub a: Vec<f64>,
    /// Sine coefficients b_k (omitted for k = 0).
    #[serde(default)]
    pub b: Vec<f64>,
}

/// The `[periodic]` table of a scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeriodicSpec {
    /// Orbit or choreography.
    #[serde(default)]
    pub kind: CurveKind,
    /// Number of Fourier modes K.
    pub modes: usize,
    /// Fixed period or energy condition.
    #[serde(default)]
    pub condition: ConditionKind,
    /// The fixed period, or the guess of the period.
    pub period: f64,
    /// The energy for `condition = "energy"` (default: the scene's initial state's).
    #[serde(default)]
    pub energy: Option<f64>,
    /// Trapezoid nodes over the period (default 4(K + 1), at least 32).
    #[serde(default)]
    pub nodes: Option<usize>,
    /// Steps per period of the time-stepping runs (monodromy, closing); default the scene's
    /// `method.steps`.
    #[serde(default)]
    pub steps: Option<usize>,
    /// Basis functions per step of the time-stepping runs; default the scene's `method.n`.
    #[serde(default)]
    pub n: Option<usize>,
    /// The published period, for comparison (with `condition = "energy"`).
    #[serde(default)]
    pub reference_period: Option<f64>,
    /// The low modes of the initial guess.
    pub guess: Vec<GuessMode>,
}

impl PeriodicSpec {
    /// The guess as a curve with `modes` modes in `layout`.
    pub fn guess_curve(&self, layout: Layout, modes: usize) -> crate::Result<FourierCurve> {
        let mut c = FourierCurve::zeros(modes, layout, self.period)?;
        for g in &self.guess {
            c.set_mode(g.k, &g.a, &g.b)?;
        }
        Ok(c)
    }
}
