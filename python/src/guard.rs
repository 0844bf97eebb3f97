//! Checks before any work, the `gvi` tool's own: the step count, the memory the runs will
//! hold (estimated with the tool's [`galerkin_vi_lab::memory`] and held to its limit,
//! [`LIMIT_BYTES`](galerkin_vi_lab::memory::LIMIT_BYTES), 4 GB) and the start of each run
//! (the regularity of an expression Lagrangian there, coincident bodies, non-finite initial
//! invariants: [`galerkin_vi_lab::run::check_start`]).

use crate::errors::{IntoPy, lab_error};
use crate::systems::SysKind;
use galerkin_vi::GviError;
use galerkin_vi::integrator::MAX_STEPS;
use galerkin_vi_lab::error::LabError;
use galerkin_vi_lab::memory::{ensure_fits, trajectory_bytes_per_step};
use pyo3::prelude::*;

/// 1 ≤ steps ≤ [`MAX_STEPS`], else `InvalidMethodError` (before the memory estimate, so that
/// an absurd count is named as such).
pub fn ensure_steps(steps: usize) -> PyResult<()> {
    if steps == 0 || steps > MAX_STEPS {
        return Err(GviError::InvalidStepCount {
            steps,
            reason: format!("need 1 ≤ steps ≤ {MAX_STEPS}"),
        })
        .py_err();
    }
    Ok(())
}

/// Refuse `members` runs of `steps` steps with n basis functions in dimension d, all kept
/// until they return, when their estimated memory is above the limit: a `MemoryLimitError`
/// quoting the estimate and the limit.
pub fn ensure_runs_fit(members: usize, steps: usize, n: usize, d: usize) -> PyResult<()> {
    let estimate = members as f64 * steps as f64 * trajectory_bytes_per_step(n, d);
    let what = match members {
        1 => format!("a run of {steps} steps (n = {n}, D = {d})"),
        _ => format!("{members} runs of {steps} steps each (n = {n}, D = {d})"),
    };
    ensure_fits(
        what,
        estimate,
        "every state and Galerkin curve is kept until the call returns: fewer steps or \
         members, or several shorter calls each starting from the last state of the one before",
    )
    .map_err(lab_error)
}

/// The start checks of `gvi run` for (q0, p0) at t = 0: an expression Lagrangian's
/// regularity there (its velocity Hessian), then coincident bodies and non-finite initial
/// invariants.
pub fn check_start(kind: &SysKind, q0: &[f64], p0: &[f64]) -> Result<(), LabError> {
    if let SysKind::Expression(e) = kind {
        e.check_state(q0, p0)?;
    }
    galerkin_vi_lab::run::check_start(kind, q0, p0, 0.0)
}

/// [`check_start`] for member `i` of a batch: the exception names the member.
pub fn check_member_start(
    py: Python<'_>,
    i: usize,
    kind: &SysKind,
    q0: &[f64],
    p0: &[f64],
) -> PyResult<()> {
    check_start(kind, q0, p0).map_err(|e| {
        let err = lab_error(e);
        PyErr::from_type(
            err.get_type(py),
            format!("member {i} (q0s[{i}], p0s[{i}]): {}", err.value(py)),
        )
    })
}
