//! Running a rigid-body scene (`gvi run rigid-body`, `gvi run heavy-top`): the table has the
//! orientation r00 … r22 (row-major), the body momentum mu0 … mu2 and angular velocity
//! w0 … w2, the spatial angular momentum lx, ly, lz, the energy and ‖RᵀR − I‖; with the
//! elliptic-function reference (free body, I₁ < I₂ < I₃, rotation about the third axis) also
//! the orientation error ‖R − R_exact‖_F and the body-momentum error.
//!
//! Scene conventions: `[initial] q` is the rotation vector of R₀ = exp(q̂) and `p` the body
//! momentum μ₀; `[method] retraction` is `exp` (default) or `cayley`.

use crate::distance::nan_max;
use crate::error::{GviError, Result};
use crate::run::{RunResult, RunSummary};
use crate::scene::BuiltScene;
use galerkin_vi::lie::body::RigidBody;
use galerkin_vi::lie::elliptic::FreeBodyExact;
use galerkin_vi::lie::integrator::{LieState, LieTrajectory};
use galerkin_vi::lie::so3::{self, Mat3};
use galerkin_vi::solve::{RigidBodySolution, rigid_body_initial_state, solve_rigid_body};
use std::time::Instant;

pub use crate::scene::AnyRigidBody;

/// R₀ and μ₀ from a built scene's `[initial]` (rotation vector, body momentum; its lengths
/// and finiteness were checked by [`crate::scene::Scene::build`]): the library's convention,
/// [`rigid_body_initial_state`].
pub fn initial_state(scene: &BuiltScene) -> Result<(Mat3<f64>, [f64; 3])> {
    Ok(rigid_body_initial_state(&scene.initial)?)
}

/// Run a built rigid-body scene.
pub fn run_rigid_body(body: &AnyRigidBody, scene: &BuiltScene) -> Result<RunResult> {
    match body {
        AnyRigidBody::Free(b) => run_body(b, scene),
        AnyRigidBody::Heavy(b) => run_body(b, scene),
    }
}

fn run_body<S: RigidBody>(body: &S, scene: &BuiltScene) -> Result<RunResult> {
    let start = Instant::now();
    // The library refuses a tolerance-driven method here (the Lie group integrator runs at
    // fixed n).
    let RigidBodySolution {
        trajectory: traj,
        integrator: gvi,
    } = solve_rigid_body(body, &scene.initial, &scene.method)?;
    let seconds = start.elapsed().as_secs_f64();
    let LieState { r: r0, mu: mu0 } = traj.states[0];
    let exact = if body.has_potential() {
        None
    } else {
        FreeBodyExact::new(body.inertia(), &r0, &mu0).ok()
    };
    let mut result = tabulate(body, scene, &gvi.describe(), &traj, exact.as_ref(), seconds)?;
    // The symplecticity defect of the first step in canonical coordinates (12 extra steps).
    let defect = galerkin_vi::lie::geometry::symplecticity_defect(
        |s| gvi.step(body, s),
        &traj.states[0],
        1e-5,
    )?;
    result
        .summary
        .invariant_errors
        .push(("step-0 symplecticity defect".into(), defect));
    // One evaluation of ℓ's derivatives per quadrature node per Newton iteration.
    result.summary.force_evaluations =
        traj.iterations.iter().sum::<usize>() * gvi.quadrature_points();
    Ok(result)
}

fn tabulate<S: RigidBody>(
    body: &S,
    scene: &BuiltScene,
    method: &str,
    traj: &LieTrajectory,
    exact: Option<&FreeBodyExact>,
    seconds: f64,
) -> Result<RunResult> {
    let mut columns: Vec<String> = vec!["step".into(), "t".into()];
    columns.extend((0..9).map(|k| format!("r{}{}", k / 3, k % 3)));
    columns.extend(
        [
            "mu0", "mu1", "mu2", "w0", "w1", "w2", "lx", "ly", "lz", "energy",
        ]
        .map(String::from),
    );
    columns.push("orthogonality".into());
    let times: Vec<f64> = (0..traj.states.len()).map(|k| k as f64 * traj.h).collect();
    let reference = match exact {
        Some(ex) => {
            columns.push("orientation_error".into());
            columns.push("momentum_error".into());
            Some(ex.orientations(&times)?)
        }
        None => None,
    };
    let s0 = traj.states[0];
    let (e0, l0) = (body.energy(&s0.r, &s0.mu), s0.spatial_momentum());
    // The relative energy error's scale, as for every run: T₀ + |V₀| (the heavy top's E₀
    // vanishes where its kinetic energy cancels its potential).
    let kinetic0 = body.energy(&s0.r, &s0.mu) - body.potential(&s0.r);
    let (scale_label, scale) =
        crate::energy::energy_scale_of_parts(kinetic0, body.potential(&s0.r), e0);
    let (mut de, mut dl, mut orth, mut err): (f64, f64, f64, f64) = (0.0, 0.0, 0.0, 0.0);
    let mut rows = Vec::with_capacity(traj.states.len());
    for (k, s) in traj.states.iter().enumerate() {
        let mut row = vec![k as f64, traj.t0 + times[k]];
        row.extend(s.r.iter().flatten());
        row.extend(s.mu);
        row.extend(body.angular_velocity(&s.mu));
        let l = s.spatial_momentum();
        row.extend(l);
        let e = body.energy(&s.r, &s.mu);
        row.push(e);
        let o = so3::orthogonality_defect(&s.r);
        row.push(o);
        // nan_max: a NaN must not vanish from the maxima (f64::max drops it).
        de = nan_max(de, (e - e0).abs());
        // The free body conserves all of L; gravity's torque is horizontal, so a heavy top
        // conserves only lz.
        let axes = if body.has_potential() { 2..3 } else { 0..3 };
        dl = nan_max(
            dl,
            axes.fold(0.0f64, |a, i| nan_max(a, (l[i] - l0[i]).abs())),
        );
        orth = nan_max(orth, o);
        if let (Some(refs), Some(ex)) = (&reference, exact) {
            let oe = so3::distance(&s.r, &refs[k]);
            let mu = ex.body_momentum(times[k]);
            let me = (0..3).fold(0.0f64, |a, i| nan_max(a, (mu[i] - s.mu[i]).abs()));
            err = nan_max(err, oe);
            row.push(oe);
            row.push(me);
        }
        rows.push(row);
    }
    // A non-finite entry is a failure at its step; the rows before it are kept (as for every
    // `gvi run`).
    let mut failure: Option<crate::error::LabError> = None;
    if let Some((k, c)) = rows
        .iter()
        .enumerate()
        .find_map(|(k, row)| row.iter().position(|x| !x.is_finite()).map(|c| (k, c)))
    {
        failure = Some(
            GviError::NonFiniteResult {
                what: columns
                    .get(c)
                    .cloned()
                    .unwrap_or_else(|| format!("column {c}")),
                value: rows[k][c],
                step: k,
                t: rows[k][1],
            }
            .into(),
        );
        rows.truncate(k);
    }
    let iters: usize = traj.iterations.iter().sum();
    let steps = traj.iterations.len();
    let lnorm = (l0[0] * l0[0] + l0[1] * l0[1] + l0[2] * l0[2]).sqrt();
    let relative = |err: f64, scale: f64| if scale > 0.0 { err / scale } else { err };
    let summary = RunSummary {
        energy_balance: None,
        system: body.name().to_string(),
        method: format!("Lie group Galerkin, {method}"),
        steps,
        max_position_error: reference.as_ref().map(|_| err),
        max_curve_error: None,
        invariant_errors: vec![
            ("energy".into(), de),
            (
                if body.has_potential() {
                    "vertical angular momentum lz".into()
                } else {
                    "spatial angular momentum".into()
                },
                dl,
            ),
            ("orthogonality ‖RᵀR − I‖".into(), orth),
        ],
        relative_invariant_errors: vec![
            ("energy".into(), relative(de, scale)),
            (
                if body.has_potential() {
                    "vertical angular momentum lz".into()
                } else {
                    "spatial angular momentum".into()
                },
                relative(dl, lnorm),
            ),
            ("orthogonality ‖RᵀR − I‖".into(), orth),
        ],
        energy_scale: (scale > 0.0).then(|| (scale_label.to_string(), scale)),
        closest_approach: None,
        newton_iterations_per_step: iters as f64 / steps.max(1) as f64,
        seconds,
        command_seconds: None,
        force_evaluations: 0,
        warnings: Vec::new(),
        step_choice: None,
    };
    Ok(RunResult {
        scene: scene.scene(),
        columns,
        rows,
        summary,
        trajectory: None,
        failure,
        chart: None,
        inner_chart: None,
        n_chart: None,
    })
}
