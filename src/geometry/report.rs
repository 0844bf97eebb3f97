//! The geometric health check of a run (`gvi check SCENE`).

use super::{
    NamedMomentumMap, energy_along_curves, energy_at_step_ends, momentum_along_curves,
    momentum_at_step_ends, relative_symplecticity_defect, symplecticity_defect,
};
use crate::basis::Basis;
use crate::error::Result;
use crate::integrator::GalerkinIntegrator;
use crate::quadrature::Quadrature;
use crate::reduce::{max_error, nan_max};
use crate::systems::System;
use std::fmt;

/// Sample points per step used for errors along the Galerkin curves.
pub const CURVE_SAMPLES_PER_STEP: usize = 8;

/// The continuous symmetries of a built-in system, by its [`System::name`]: the planar Kepler
/// problem is rotation invariant (angular momentum); the harmonic oscillator and the pendulum
/// (one degree of freedom, not invariant under translation) have none listed.
pub fn known_symmetries<S: System + ?Sized>(system: &S) -> Vec<NamedMomentumMap> {
    system.symmetries()
}

/// Drift of one momentum map over a run.
#[derive(Debug, Clone, PartialEq)]
pub struct MomentumDrift {
    /// Name of the momentum map.
    pub name: String,
    /// Its initial value J(q_0, p_0).
    pub initial: f64,
    /// max_k |J(q_k, p_k) − J(q_0, p_0)| over the step ends.
    pub max_drift_ends: f64,
    /// max_t |J(q(t), p(t)) − J(q_0, p_0)| along the Galerkin curves, p(t) = ∂L/∂v.
    pub max_drift_curves: f64,
}

/// What `gvi check` reports: the symplecticity of every step's Jacobian, energy errors and
/// momentum-map drifts, at the step ends and along the curves.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckReport {
    /// System name.
    pub system: String,
    /// Method description (basis, n, quadrature, h).
    pub method: String,
    /// Number of steps.
    pub steps: usize,
    /// Step size.
    pub h: f64,
    /// max over steps of ‖JᵀΩJ − Ω‖_F for the exact step Jacobian J.
    pub max_symplecticity_defect: f64,
    /// max over steps of the relative defect (divided by max(‖J‖_F², 1)).
    pub max_relative_symplecticity_defect: f64,
    /// Initial energy (`None` when the system has no energy invariant).
    pub initial_energy: Option<f64>,
    /// max_k |E_k − E_0| at step ends.
    pub energy_max_error_ends: Option<f64>,
    /// mean_k |E_k − E_0| at step ends.
    pub energy_mean_error_ends: Option<f64>,
    /// max_t |E(t) − E_0| along the curves.
    pub energy_max_error_curves: Option<f64>,
    /// mean_t |E(t) − E_0| along the curves.
    pub energy_mean_error_curves: Option<f64>,
    /// Momentum-map drifts for the system's symmetries.
    pub momenta: Vec<MomentumDrift>,
    /// Mean Newton iterations per step.
    pub mean_newton_iterations: f64,
}

/// Integrate `steps` steps of `system` from (q0, p0) and measure its geometry: the exact
/// step Jacobian of every step (from the stored Galerkin coefficients) and its
/// symplecticity defect, energy errors at step ends and along the curves
/// ([`CURVE_SAMPLES_PER_STEP`] samples per step), and the drift of the momentum maps of
/// [`known_symmetries`].
pub fn check_report<S: System, B: Basis, Q: Quadrature>(
    integrator: &GalerkinIntegrator<B, Q>,
    system: &S,
    q0: &[f64],
    p0: &[f64],
    steps: usize,
) -> Result<CheckReport> {
    check_report_with(integrator, system, q0, p0, steps, &known_symmetries(system))
}

/// Diagnostics of a run that overflowed are meaningless (an error of inf − inf is NaN, which
/// a max would drop): the first non-finite state or invariant is an error.
fn ensure_finite_run<S: System>(system: &S, traj: &crate::Trajectory) -> Result<()> {
    let mut inv = vec![0.0; system.invariant_names().len()];
    for k in 0..traj.q.len() {
        let (q, p) = (&traj.q[k], &traj.p[k]);
        system.invariants(q, p, &mut inv);
        let names = (0..q.len())
            .map(|i| format!("position q{i}"))
            .chain((0..p.len()).map(|i| format!("momentum p{i}")))
            .chain(system.invariant_names().iter().map(|s| s.to_string()));
        let values = q.iter().chain(p).chain(&inv);
        if let Some((what, &value)) = names.zip(values).find(|(_, v)| !v.is_finite()) {
            return Err(crate::GviError::NonFiniteResult {
                what,
                value,
                step: k,
                t: traj.time(k),
            });
        }
    }
    Ok(())
}

/// [`check_report`] with an explicit list of momentum maps.
pub fn check_report_with<S: System, B: Basis, Q: Quadrature>(
    integrator: &GalerkinIntegrator<B, Q>,
    system: &S,
    q0: &[f64],
    p0: &[f64],
    steps: usize,
    symmetries: &[NamedMomentumMap],
) -> Result<CheckReport> {
    crate::forcing::ensure_conservative(system, "the geometric check (symplecticity, energy)")?;
    let traj = integrator.integrate(system, 0.0, q0, p0, steps)?;
    ensure_finite_run(system, &traj)?;
    let (mut defect, mut relative) = (0.0f64, 0.0f64);
    for c in &traj.coefficients {
        let j = integrator.step_jacobian_from_coefficients(system, c)?;
        defect = nan_max(defect, symplecticity_defect(&j));
        relative = nan_max(relative, relative_symplecticity_defect(&j));
    }
    let (e0, emax, emean, cmax, cmean) = match energy_at_step_ends(system, &traj) {
        Ok(ends) => {
            let e0 = ends.values.first().copied().unwrap_or(f64::NAN);
            let curves = energy_along_curves(system, &traj, CURVE_SAMPLES_PER_STEP)?;
            let dev: Vec<f64> = curves.values.iter().map(|v| (v - e0).abs()).collect();
            let cmax = max_error(dev.iter().copied());
            let cmean = dev.iter().sum::<f64>() / dev.len().max(1) as f64;
            (
                Some(e0),
                Some(ends.max_deviation()),
                Some(ends.mean_deviation()),
                Some(cmax),
                Some(cmean),
            )
        }
        Err(_) => (None, None, None, None, None),
    };
    let mut momenta = Vec::with_capacity(symmetries.len());
    for sym in symmetries {
        let ends = momentum_at_step_ends(&*sym.map, &traj);
        let j0 = ends.values.first().copied().unwrap_or(f64::NAN);
        let curves = momentum_along_curves(system, &*sym.map, &traj, CURVE_SAMPLES_PER_STEP)?;
        let along = max_error(curves.values.iter().map(|v| (v - j0).abs()));
        momenta.push(MomentumDrift {
            name: sym.name.clone(),
            initial: j0,
            max_drift_ends: ends.max_deviation(),
            max_drift_curves: along,
        });
    }
    Ok(CheckReport {
        system: system.name().into(),
        method: format!(
            "{} basis, n = {}, {}, h = {}",
            integrator.basis().name(),
            integrator.n(),
            integrator.quadrature().name(),
            integrator.step_size()
        ),
        steps,
        h: integrator.step_size(),
        max_symplecticity_defect: defect,
        max_relative_symplecticity_defect: relative,
        initial_energy: e0,
        energy_max_error_ends: emax,
        energy_mean_error_ends: emean,
        energy_max_error_curves: cmax,
        energy_mean_error_curves: cmean,
        momenta,
        mean_newton_iterations: traj.newton_iterations() as f64 / steps.max(1) as f64,
    })
}

impl fmt::Display for CheckReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "system:   {}", self.system)?;
        writeln!(f, "method:   {}", self.method)?;
        writeln!(
            f,
            "run:      {} steps, t = 0 … {}",
            self.steps,
            self.steps as f64 * self.h
        )?;
        writeln!(
            f,
            "Newton:   {:.2} iterations per step",
            self.mean_newton_iterations
        )?;
        writeln!(
            f,
            "symplecticity defect ‖JᵀΩJ − Ω‖_F: max {:.3e} (relative {:.3e})",
            self.max_symplecticity_defect, self.max_relative_symplecticity_defect
        )?;
        match (
            self.initial_energy,
            self.energy_max_error_ends,
            self.energy_mean_error_ends,
            self.energy_max_error_curves,
            self.energy_mean_error_curves,
        ) {
            (Some(e0), Some(a), Some(b), Some(c), Some(d)) => {
                writeln!(f, "energy E0 = {e0:.16e}")?;
                writeln!(f, "  |E − E0| at step ends:    max {a:.3e}, mean {b:.3e}")?;
                writeln!(f, "  |E − E0| along curves:    max {c:.3e}, mean {d:.3e}")?;
            }
            _ => writeln!(f, "energy: not available for this system")?,
        }
        if self.momenta.is_empty() {
            writeln!(f, "momentum maps: none known for this system")?;
        }
        for m in &self.momenta {
            writeln!(f, "{} J0 = {:.16e}", m.name, m.initial)?;
            writeln!(
                f,
                "  |J − J0| at step ends:    max {:.3e}",
                m.max_drift_ends
            )?;
            writeln!(
                f,
                "  |J − J0| along curves:    max {:.3e}",
                m.max_drift_curves
            )?;
        }
        Ok(())
    }
}
