//! The stopping variant of the fixed-n run behind [`super::solve_until`]: the loop of
//! [`GalerkinIntegrator::integrate`] (a [`Stepper`](crate::integrator::Stepper) whose steps
//! are appended to a [`Trajectory`]) with a question before every step.

use crate::error::GviError;
use crate::integrator::{GalerkinIntegrator, IntegrationFailure, MAX_STEPS};
use crate::lagrangian::Lagrangian;
use crate::trajectory::Trajectory;

/// [`GalerkinIntegrator::integrate`], asking `stop` before every step whether to stop there:
/// a `true` ends the run with [`GviError::Interrupted`] and the steps before it as the
/// partial trajectory. With a `stop` that never says yes, the trajectory is `integrate`'s bit
/// for bit (both are the same stepper; `tests.rs` checks it).
pub(super) fn integrate_until<L: Lagrangian>(
    gvi: &GalerkinIntegrator<crate::basis::AnyBasis, crate::quadrature::QuadratureRule>,
    lagrangian: &L,
    t0: f64,
    q0: &[f64],
    p0: &[f64],
    steps: usize,
    stop: &dyn Fn() -> bool,
) -> Result<Trajectory, IntegrationFailure> {
    let fail = |error| IntegrationFailure {
        error,
        partial: None,
    };
    if steps == 0 || steps > MAX_STEPS {
        return Err(fail(GviError::InvalidStepCount {
            steps,
            reason: format!("need 1 ≤ steps ≤ {MAX_STEPS}"),
        }));
    }
    let mut stepper = gvi.stepper(lagrangian, t0, q0, p0).map_err(fail)?;
    let mut traj = gvi.empty_trajectory(t0, lagrangian.dim(), steps);
    traj.push_state(q0, p0);
    for k in 0..steps {
        if stop() {
            return Err(IntegrationFailure {
                error: GviError::Interrupted {
                    step: k,
                    t: stepper.time(),
                },
                partial: Some(Box::new(traj)),
            });
        }
        match stepper.step() {
            Ok(stats) => traj.push_step(
                stepper.curve(),
                stepper.position(),
                stepper.momentum(),
                stats,
            ),
            Err(error) => {
                return Err(IntegrationFailure {
                    error,
                    partial: Some(Box::new(traj)),
                });
            }
        }
    }
    Ok(traj)
}
