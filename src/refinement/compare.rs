//! Comparing bases (or any integrators) on one problem: the largest difference of their
//! dense output at common times.

use super::*;

/// An integrator as a trait object, for comparing integrators of different basis and
/// quadrature types on one problem ([`compare_bases`]). Every [`GalerkinIntegrator`]
/// implements it; a wrapper around another one-step method that produces a [`Trajectory`]
/// can too.
pub trait DynIntegrator<L: Lagrangian> {
    /// A label for reports, e.g. `bernstein n=12 gauss-radau(12) h=0.5`.
    fn label(&self) -> String;
    /// The step size h.
    fn step_size(&self) -> f64;
    /// Integrate `steps` steps from (q0, p0) at t0, keeping the Galerkin curves.
    fn integrate_dyn(
        &self,
        lagrangian: &L,
        t0: f64,
        q0: &[f64],
        p0: &[f64],
        steps: usize,
    ) -> Result<Trajectory>;
}

impl<B: Basis, Q: Quadrature, L: Lagrangian> DynIntegrator<L> for GalerkinIntegrator<B, Q> {
    fn label(&self) -> String {
        format!(
            "{} n={} {}({}) h={}",
            self.basis().name(),
            self.n(),
            self.rule().family,
            self.rule().len(),
            self.step_size()
        )
    }
    fn step_size(&self) -> f64 {
        GalerkinIntegrator::step_size(self)
    }
    fn integrate_dyn(
        &self,
        lagrangian: &L,
        t0: f64,
        q0: &[f64],
        p0: &[f64],
        steps: usize,
    ) -> Result<Trajectory> {
        Ok(self.integrate(lagrangian, t0, q0, p0, steps)?)
    }
}

/// The pairwise differences of several runs' dense output (see [`compare_trajectories`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// A label per run, in input order.
    pub labels: Vec<String>,
    /// Number of sample times compared.
    pub samples: usize,
    /// `position[a][b]`: max over the sample times of ‖q_a(t) − q_b(t)‖_∞ (symmetric, zero
    /// diagonal).
    pub position: Vec<Vec<f64>>,
    /// `velocity[a][b]`: the same for q̇(t).
    pub velocity: Vec<Vec<f64>>,
    /// The largest entry of `position`.
    pub max_position: f64,
    /// The largest entry of `velocity`.
    pub max_velocity: f64,
}

/// The largest pairwise difference of the dense output q(t), q̇(t) of several trajectories at
/// the given times (any bases, step sizes and quadratures; each trajectory evaluates its own
/// curves). Labels are "basis n=… quadrature(points) h=…" from each trajectory's record.
///
/// Errors: no trajectories or no times ([`GviError::InvalidInput`]); trajectories of different
/// dimensions ([`GviError::DimensionMismatch`]); a time outside a trajectory's span or dense
/// output unavailable (the error of [`Trajectory::state_on_curve`]).
pub fn compare_trajectories(trajectories: &[&Trajectory], times: &[f64]) -> Result<Comparison> {
    let Some(first) = trajectories.first() else {
        return Err(GviError::InvalidInput {
            name: "trajectories".into(),
            reason: "nothing to compare".into(),
        });
    };
    if times.is_empty() {
        return Err(GviError::InvalidInput {
            name: "times".into(),
            reason: "no sample times".into(),
        });
    }
    for t in trajectories {
        ensure_len("trajectory dimension", first.dim, t.dim)?;
    }
    let m = trajectories.len();
    let mut position = vec![vec![0.0f64; m]; m];
    let mut velocity = vec![vec![0.0f64; m]; m];
    let mut states = Vec::with_capacity(m);
    for &t in times {
        states.clear();
        for traj in trajectories {
            states.push(traj.state_on_curve(t)?);
        }
        for a in 0..m {
            for b in a + 1..m {
                let dq = max_abs_diff(&states[a].0, &states[b].0);
                let dv = max_abs_diff(&states[a].1, &states[b].1);
                position[a][b] = position[a][b].max(dq);
                velocity[a][b] = velocity[a][b].max(dv);
            }
        }
    }
    for a in 0..m {
        for b in 0..a {
            position[a][b] = position[b][a];
            velocity[a][b] = velocity[b][a];
        }
    }
    // A NaN difference (a run that blew up) must not vanish from the largest one.
    let largest = |x: &Vec<Vec<f64>>| crate::reduce::max_error(x.iter().flatten().copied());
    Ok(Comparison {
        labels: trajectories
            .iter()
            .map(|t| {
                format!(
                    "{} n={} {}({}) h={}",
                    t.basis, t.n, t.quadrature, t.quad_points, t.h
                )
            })
            .collect(),
        samples: times.len(),
        max_position: largest(&position),
        max_velocity: largest(&velocity),
        position,
        velocity,
    })
}

/// Run several integrators — any bases, quadratures and step sizes — on one problem and
/// compare their dense output: the max pairwise difference of q(t) and q̇(t) at the times
/// t0 + T i/N, i = 0 … N, with N = `samples_per_step` × the largest number of steps of
/// any run.
///
/// Polynomial bases of the same n under the same quadrature define the same discrete
/// Lagrangian (docs/DESIGN.md §2), so their differences are round-off; a basis of another
/// space (Fourier) or another quadrature differs by the methods' errors.
///
/// Errors: no integrators or `samples_per_step` = 0 ([`GviError::InvalidInput`]); as
/// [`Problem::run`] and [`compare_trajectories`].
pub fn compare_bases<L: Lagrangian>(
    integrators: &[&dyn DynIntegrator<L>],
    problem: &Problem<'_, L>,
    samples_per_step: usize,
) -> Result<Comparison> {
    if integrators.is_empty() {
        return Err(GviError::InvalidInput {
            name: "integrators".into(),
            reason: "nothing to compare".into(),
        });
    }
    if samples_per_step == 0 {
        return Err(GviError::InvalidInput {
            name: "samples per step".into(),
            reason: "need at least 1 sample per step".into(),
        });
    }
    let trajectories = integrators
        .iter()
        .map(|gvi| problem.run(*gvi))
        .collect::<Result<Vec<_>>>()?;
    let steps = trajectories.iter().map(|t| t.steps()).max().unwrap_or(1);
    let samples = steps.saturating_mul(samples_per_step);
    let (t0, span) = (problem.t0(), problem.horizon());
    let mut times: Vec<f64> = (0..samples)
        .map(|i| t0 + span * i as f64 / samples as f64)
        .collect();
    // The last time is each run's own end time (they agree to HORIZON_TOLERANCE).
    times.push(
        trajectories
            .iter()
            .map(|t| t.end_time())
            .fold(f64::INFINITY, f64::min),
    );
    let refs: Vec<&Trajectory> = trajectories.iter().collect();
    let mut comparison = compare_trajectories(&refs, &times)?;
    comparison.labels = integrators.iter().map(|g| g.label()).collect();
    Ok(comparison)
}
