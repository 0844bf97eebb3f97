//! Python bindings of galerkin-vi (module `galerkin_vi._native`, re-exported by the Python
//! package `galerkin_vi`): `run_scene`, `Integrator`, the systems of `galerkin_vi.systems`,
//! `Trajectory` with numpy arrays and dense output, `integrate_many` (rayon, GIL released) and
//! typed exceptions. Every input is checked before it reaches the library; no panic crosses
//! the boundary.

mod convert;
mod errors;
mod guard;
mod interrupt;
mod systems;
mod trajectory;

use convert::{finite, matrix, vector};
use errors::{IntoPy, InvalidInputError, SolverError};
use galerkin_vi::Lagrangian as _;
use galerkin_vi_lab::run::RunOptions;
use galerkin_vi_lab::scene::Scene;
use pyo3::exceptions::PyRuntimeWarning;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use systems::System;
use trajectory::{Integrator, Trajectory};

/// Apply `run_scene`'s keyword overrides to a scene, naming any unknown key.
fn apply_overrides(scene: &mut Scene, overrides: &Bound<'_, PyDict>, dim: usize) -> PyResult<()> {
    for (key, value) in overrides.iter() {
        let key: String = key.extract()?;
        let m = &mut scene.method;
        let bad = |what: &str| InvalidInputError::new_err(format!("{key}: expected {what}"));
        match key.as_str() {
            "n" => m.n = value.extract().map_err(|_| bad("a whole number ≥ 2"))?,
            "steps" => m.steps = value.extract().map_err(|_| bad("a whole number ≥ 1"))?,
            "h" => m.h = finite("h", value.extract().map_err(|_| bad("a number"))?)?,
            "tol" => {
                let tol: Option<f64> = value.extract().map_err(|_| bad("a number or None"))?;
                m.tol = tol.map(|t| finite("tol", t)).transpose()?;
            }
            "basis" => {
                let s: String = value.extract().map_err(|_| bad("a basis name"))?;
                m.basis = s.parse::<galerkin_vi::basis::BasisKind>().py_err()?;
            }
            "quadrature" => {
                let s: String = value.extract().map_err(|_| bad("a quadrature name"))?;
                m.quadrature = s
                    .parse::<galerkin_vi::quadrature::QuadratureKind>()
                    .py_err()?;
            }
            "solver" => {
                let s: String = value.extract().map_err(|_| bad("a stage solver name"))?;
                m.solver = s.parse::<galerkin_vi::integrator::StageSolver>().py_err()?;
            }
            "q0" => scene.initial.q = vector(&value, "q0", Some(dim))?,
            "p0" => scene.initial.p = vector(&value, "p0", Some(dim))?,
            other => {
                return Err(InvalidInputError::new_err(format!(
                    "unknown override '{other}' (expected n, h, steps, basis, quadrature, \
                     solver, tol, q0 or p0)"
                )));
            }
        }
    }
    Ok(())
}

/// Run a scene (a built-in name such as "kepler", or the path of a TOML scene file) with
/// optional overrides of its method and initial state: n, h, steps, basis, quadrature,
/// solver, tol, q0, p0. Returns the `Trajectory`; the sanity warnings of `gvi run` (an energy
/// or position error above 1 %, an unresolved close encounter) are issued as
/// `RuntimeWarning`s. A run whose estimated memory is above the
/// `gvi` tool's limit is refused before any work (`MemoryLimitError`); Ctrl-C stops it within
/// a step (`KeyboardInterrupt`).
#[pyfunction]
#[pyo3(signature = (name_or_path, **overrides))]
fn run_scene(
    py: Python<'_>,
    name_or_path: &str,
    overrides: Option<&Bound<'_, PyDict>>,
) -> PyResult<Trajectory> {
    let mut scene = Scene::load(name_or_path).py_err()?;
    if let Some(o) = overrides {
        let dim = systems::system_of(&scene.build().py_err()?)?.dim();
        apply_overrides(&mut scene, o, dim)?;
    }
    let scene = scene.build().py_err()?;
    let kind = std::sync::Arc::new(systems::system_of(&scene)?);
    // The estimate `gvi run` holds a run kept in memory to (it counts the output text, which
    // the Python arrays returned later stand for).
    let (_, estimate) = galerkin_vi_lab::run::in_memory_bytes(&scene, false);
    galerkin_vi_lab::memory::ensure_fits(
        format!(
            "run_scene('{}') with {} steps",
            scene.name, scene.method.steps
        ),
        estimate,
        "the whole run is kept: fewer steps (the steps override)",
    )
    .py_err()?;
    let options = RunOptions {
        curve_samples_per_step: 0,
        chart: false,
    };
    let result = interrupt::interruptible(py, |stop| {
        galerkin_vi_lab::run::run_scene_until(&scene, options, &|| stop.requested())
    })?
    .py_err()?;
    if let Some(failure) = result.failure {
        return Err(errors::lab_error(failure));
    }
    // The sanity warnings `gvi run` prints (an energy or position error above 1 %, an
    // unresolved close encounter, a tolerance not met) as Python warnings: a run that
    // returns is not silently trusted.
    for warning in &result.summary.warnings {
        let message = std::ffi::CString::new(format!("run_scene('{}'): {warning}", scene.name))
            .unwrap_or_default();
        PyErr::warn(py, &py.get_type::<PyRuntimeWarning>(), &message, 1)?;
    }
    match result.trajectory {
        Some(traj) => Ok(Trajectory::new(traj, kind, scene.method.clone())),
        None => Err(SolverError::new_err("the run produced no trajectory")),
    }
}

/// Integrate many initial states of one system in parallel (rayon over members, the GIL
/// released): `q0s`, `p0s` of shape (members, D). Returns a list of `Trajectory`, in order;
/// equal to a loop of `integrator.integrate`. `integrator` defaults to `Integrator()`.
/// Refused before any work: a member's start that `gvi run` refuses (the exception names the
/// member), and members whose runs together are estimated above the memory limit
/// (`MemoryLimitError`). Ctrl-C stops every member within a step (`KeyboardInterrupt`).
#[pyfunction]
#[pyo3(signature = (system, q0s, p0s, steps, integrator = None))]
fn integrate_many(
    py: Python<'_>,
    system: &Bound<'_, System>,
    q0s: &Bound<'_, PyAny>,
    p0s: &Bound<'_, PyAny>,
    steps: usize,
    integrator: Option<&Bound<'_, Integrator>>,
) -> PyResult<Vec<Trajectory>> {
    let kind = system.get().kind.clone();
    let d = kind.dim();
    let q0s = matrix(q0s, "q0s", d)?;
    let p0s = matrix(p0s, "p0s", d)?;
    if q0s.len() != p0s.len() {
        return Err(errors::ShapeError::new_err(format!(
            "q0s and p0s: {} and {} members (rows) must agree",
            q0s.len(),
            p0s.len()
        )));
    }
    let method = match integrator {
        Some(i) => i.get().method.clone(),
        None => galerkin_vi::method::MethodSpec::spectral(16, 1.0, 1),
    };
    guard::ensure_steps(steps)?;
    guard::ensure_runs_fit(q0s.len(), steps, method.n, d)?;
    for (i, (q, p)) in q0s.iter().zip(&p0s).enumerate() {
        guard::check_member_start(py, i, &kind, q, p)?;
    }
    let results = interrupt::interruptible(py, |stop| {
        q0s.par_iter()
            .zip(&p0s)
            .map(|(q, p)| Integrator::run(&method, &kind, q, p, steps, stop))
            .collect::<Vec<_>>()
    })?;
    results
        .into_iter()
        .map(|r| {
            r.py_err()
                .map(|t| Trajectory::new(t, kind.clone(), method.clone()))
        })
        .collect()
}

/// The extension module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    systems::register(m)?;
    m.add_class::<Integrator>()?;
    m.add_class::<Trajectory>()?;
    m.add_function(wrap_pyfunction!(run_scene, m)?)?;
    m.add_function(wrap_pyfunction!(integrate_many, m)?)?;
    Ok(())
}
