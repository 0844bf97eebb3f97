//! Python bindings of galerkin-vi (module `galerkin_vi._native`, re-exported by the Python
//! package `galerkin_vi`): `run_scene`, `Integrator`, the systems of `galerkin_vi.systems`,
//! `Trajectory` with numpy arrays and dense output, `integrate_many` (rayon, GIL released) and
//! typed exceptions. Every input is checked before it reaches the library; no panic crosses
//! the boundary.

mod convert;
mod errors;
mod guard;
mod interrupt;
mod rigid;
mod systems;
mod time_transform;
mod trajectory;

use convert::{finite, matrix, vector};
use errors::{IntoPy, InvalidInputError, SolverError};
use galerkin_vi::Lagrangian as _;
use galerkin_vi_lab::run::RunOptions;
use galerkin_vi_lab::scene::{BuiltScene, BuiltSystem, Overrides, Scene};
use pyo3::exceptions::PyRuntimeWarning;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use systems::System;
use trajectory::{Integrator, Trajectory};

/// The keyword options of `run_scene`, the method and initial-state flags of `gvi run`.
const RUN_OPTIONS: &str = "n, h, steps, basis, quadrature, quad_points, economical, compact, \
                           collocation, solver, retraction, tol, control, ladder, auto_h, q0, p0, \
                           time_transform, alpha, energy_level, t_end or every";

/// The options of `run_scene` beyond the lab's [`Overrides`]: `tol=None` (which `Overrides`
/// cannot say: it turns a scene's own tolerance off), `compact`, `collocation`, and a whole
/// `TimeTransform` (`Overrides` names only the monitor).
#[derive(Default)]
struct Extra {
    tol: Option<Option<f64>>,
    compact: bool,
    collocation: bool,
    time_transform: Option<galerkin_vi::time_transform::TimeTransformSpec>,
}

/// `run_scene`'s keyword options as the lab's [`Overrides`] (what `gvi run`'s flags become)
/// and the [`Extra`] ones, each value checked for its type. Combinations `gvi run` refuses
/// before it builds the scene are refused here the same way (`InvalidInputError`): n,
/// quad_points, economical, compact or collocation with tol; control, ladder or auto_h
/// without it; and more than one of quad_points, economical, compact and collocation.
fn overrides_of(options: &Bound<'_, PyDict>) -> PyResult<(Overrides, Extra)> {
    let mut o = Overrides::default();
    let mut extra = Extra::default();
    for (key, value) in options.iter() {
        let key: String = key.extract()?;
        let bad = |what: &str| {
            let got = value
                .get_type()
                .name()
                .map(|n| n.to_string())
                .unwrap_or_else(|_| "?".into());
            InvalidInputError::new_err(format!("{key}: expected {what}, got {got} {value}"))
        };
        let text = |what: &str| value.extract::<String>().map_err(|_| bad(what));
        fn parsed<T: std::str::FromStr<Err = galerkin_vi::GviError>>(s: String) -> PyResult<T> {
            s.parse::<T>().py_err()
        }
        match key.as_str() {
            "n" => o.n = Some(value.extract().map_err(|_| bad("a whole number ≥ 2"))?),
            "steps" => o.steps = Some(value.extract().map_err(|_| bad("a whole number ≥ 1"))?),
            "quad_points" => {
                o.quad_points = value
                    .extract()
                    .map_err(|_| bad("a whole number of quadrature points or None"))?
            }
            "economical" => o.economical = value.extract().map_err(|_| bad("True or False"))?,
            "compact" => extra.compact = value.extract().map_err(|_| bad("True or False"))?,
            "collocation" => {
                extra.collocation = value.extract().map_err(|_| bad("True or False"))?
            }
            "auto_h" => o.auto_h = value.extract().map_err(|_| bad("True or False"))?,
            "h" => o.h = Some(finite("h", value.extract().map_err(|_| bad("a number"))?)?),
            "tol" => {
                let tol: Option<f64> = value.extract().map_err(|_| bad("a number or None"))?;
                let tol = tol.map(|t| finite("tol", t)).transpose()?;
                o.tol = tol;
                extra.tol = Some(tol);
            }
            "basis" => o.basis = Some(parsed(text("a basis name")?)?),
            "quadrature" => o.quadrature = Some(parsed(text("a quadrature name")?)?),
            "solver" => o.solver = Some(parsed(text("a stage solver name")?)?),
            "retraction" => {
                o.retraction = Some(parsed(text("a retraction name (exp or cayley)")?)?)
            }
            "control" => {
                o.control = Some(parsed(text(
                    "an error control name (embedded, indicator or calibrated)",
                )?)?)
            }
            "ladder" => {
                o.ladder = Some(
                    value
                        .extract()
                        .map_err(|_| bad("a list of whole numbers (values of n)"))?,
                )
            }
            "q0" => o.q0 = Some(vector(&value, "q0", None)?),
            "time_transform" => {
                // A name overrides the scene's monitor only (as `gvi run --time-transform`);
                // a `TimeTransform` replaces the scene's whole transformation.
                if let Ok(name) = value.extract::<String>() {
                    o.time_transform = Some(parsed(name)?);
                } else {
                    extra.time_transform = Some(time_transform::spec_of(&value)?);
                }
            }
            "alpha" => {
                o.time_alpha = Some(finite(
                    "alpha",
                    value.extract().map_err(|_| bad("a number"))?,
                )?)
            }
            "energy_level" => {
                let e = value.extract().map_err(|_| bad("a number"))?;
                o.time_energy = Some(finite("energy_level", e)?)
            }
            "t_end" => {
                o.t_end = Some(finite(
                    "t_end",
                    value.extract().map_err(|_| bad("a number"))?,
                )?)
            }
            "every" => {
                o.every = Some(finite(
                    "every",
                    value.extract().map_err(|_| bad("a number"))?,
                )?)
            }
            "p0" => o.p0 = Some(vector(&value, "p0", None)?),
            other => {
                return Err(InvalidInputError::new_err(format!(
                    "unknown option '{other}' (expected {RUN_OPTIONS})"
                )));
            }
        }
    }
    let rules = [
        ("quad_points", o.quad_points.is_some()),
        ("economical", o.economical),
        ("compact", extra.compact),
        ("collocation", extra.collocation),
    ];
    let chosen: Vec<&str> = rules.iter().filter(|r| r.1).map(|r| r.0).collect();
    if chosen.len() > 1 {
        return Err(InvalidInputError::new_err(format!(
            "{}: give one way of choosing the quadrature points",
            chosen.join(" and ")
        )));
    }
    if o.tol.is_some() {
        for (name, given) in [("n", o.n.is_some())].into_iter().chain(rules) {
            if given {
                return Err(InvalidInputError::new_err(format!(
                    "{name}: with tol, n is chosen per step from the ladder, each rung with \
                     its quadrature's default points; {name} would be ignored"
                )));
            }
        }
    } else {
        for (name, given) in [
            ("control", o.control.is_some()),
            ("ladder", o.ladder.is_some()),
            ("auto_h", o.auto_h),
        ] {
            if given {
                return Err(InvalidInputError::new_err(format!(
                    "{name}: only a tolerance-driven run uses it; give tol as well"
                )));
            }
        }
    }
    Ok((o, extra))
}

/// Refuse the options a built scene would ignore, as `gvi run` does: `retraction` outside
/// the rigid-body scenes (only the Lie group integrator has a chart), `solver` on them (that
/// integrator has no stage solver to choose).
fn refuse_unused(scene: &BuiltScene, o: &Overrides) -> PyResult<()> {
    let rigid = matches!(scene.system, BuiltSystem::RigidBody(_));
    if o.retraction.is_some() && !rigid {
        return Err(InvalidInputError::new_err(format!(
            "retraction: {} is not a rigid-body scene; only those (rigid-body, heavy-top, \
             pendulum-3d) run on SO(3) with a retraction",
            scene.name
        )));
    }
    if o.solver.is_some() && rigid {
        return Err(InvalidInputError::new_err(format!(
            "solver: {} is a rigid-body scene, run by the Lie group integrator, which has no \
             stage solver to choose",
            scene.name
        )));
    }
    Ok(())
}

/// Refuse the time-transformation options on a scene run without a time transformation (they
/// would be ignored) and `tol` with one (its steps are fixed in fictitious time), as `gvi run`
/// does.
fn refuse_unused_time_options(scene: &BuiltScene, o: &Overrides) -> PyResult<()> {
    if scene.method.time_transform.is_none() {
        for (name, given) in [
            ("alpha", o.time_alpha.is_some()),
            ("energy_level", o.time_energy.is_some()),
            ("t_end", o.t_end.is_some()),
            ("every", o.every.is_some()),
        ] {
            if given {
                return Err(time_transform::only_with_transform(name));
            }
        }
    } else if o.tol.is_some() {
        return Err(InvalidInputError::new_err(
            "tol: a time-transformed run takes fixed fictitious steps at a fixed n; tol would \
             be ignored",
        ));
    }
    Ok(())
}

/// Run a scene (a built-in name such as "kepler", or the path of a TOML scene file) with
/// optional keyword options, the method and initial-state flags of `gvi run`: n, h, steps,
/// basis, quadrature, quad_points (an explicit number of quadrature points), economical
/// (True: the quadrature's economical number of points for n, ⌈3n/2⌉ Gauss–Legendre points),
/// compact (True: the compact rule, n Gauss–Legendre points; `gvi run --quad-points n`),
/// collocation (True: n − 1 Gauss–Legendre points, with which the step is Gauss collocation;
/// `gvi run --quad-points n-1`),
/// solver, retraction (rigid bodies: "exp" or "cayley"), tol (choose n per step; None turns a
/// scene's own tol off), control, ladder and auto_h (with tol), q0, p0; and the Poincaré
/// time transformation: time_transform (a monitor name, replacing the scene's monitor, or a
/// `TimeTransform`, replacing its whole transformation), alpha, energy_level, t_end and
/// every (with a time transformation only). Returns a `Trajectory`, a
/// `TimeTransformedTrajectory` (rows in physical time) for a time-transformed run
/// (`kepler-e099`, `pythagorean`, or `time_transform=`), or a `RigidBodyTrajectory` for a
/// rigid-body scene (run on SO(3) by the Lie group integrator). Bad options raise
/// `InvalidInputError` or one of its subclasses, naming the option; options `gvi run` refuses together (n with tol, control without tol,
/// retraction outside rigid bodies, solver on them) are refused the same way. The sanity
/// warnings of `gvi run` (an energy or position error above 1 %, an unresolved close
/// encounter) are issued as `RuntimeWarning`s. A run whose estimated memory is above the
/// `gvi` tool's limit is refused before any work (`MemoryLimitError`); Ctrl-C stops it within
/// a step (`KeyboardInterrupt`).
#[pyfunction]
#[pyo3(signature = (name_or_path, **options))]
fn run_scene<'py>(
    py: Python<'py>,
    name_or_path: &str,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let (overrides, extra) = match options {
        Some(o) => overrides_of(o)?,
        None => (Overrides::default(), Extra::default()),
    };
    let loaded = Scene::load(name_or_path).py_err()?;
    if overrides.q0.is_some() || overrides.p0.is_some() {
        // The lengths, named as the options (the built scene would name its `[initial]`).
        let without_state = Overrides {
            q0: None,
            p0: None,
            ..overrides.clone()
        };
        let built = loaded
            .clone()
            .with_overrides(&without_state)
            .build()
            .py_err()?;
        let dim = match &built.system {
            BuiltSystem::Euclidean(s) => s.dim(),
            BuiltSystem::RigidBody(_) => 3,
        };
        for (name, given) in [("q0", &overrides.q0), ("p0", &overrides.p0)] {
            if let Some(v) = given.as_ref().filter(|v| v.len() != dim) {
                return Err(errors::ShapeError::new_err(format!(
                    "{name}: expected a 1-D array of length {dim}, got shape ({},)",
                    v.len()
                )));
            }
        }
    }
    let mut loaded = loaded;
    if let Some(spec) = extra.time_transform.clone() {
        loaded.method.time_transform = Some(spec);
    }
    let mut scene = loaded.with_overrides(&overrides);
    if let Some(tol) = extra.tol {
        scene.method.tol = tol;
    }
    if extra.compact {
        let m = &mut scene.method;
        m.quad_points = Some(m.quadrature.compact_points(m.n));
    }
    if extra.collocation {
        let m = &mut scene.method;
        m.quad_points = Some(m.quadrature.collocation_points(m.n));
    }
    let scene = scene.build().py_err()?;
    refuse_unused(&scene, &overrides)?;
    refuse_unused_time_options(&scene, &overrides)?;
    // The estimate `gvi run` holds a run kept in memory to (it counts the output text, which
    // the Python arrays returned later stand for).
    let (_, estimate) = galerkin_vi_lab::run::in_memory_bytes(&scene, false);
    guard::ensure_steps(scene.method.steps)?;
    galerkin_vi_lab::memory::ensure_fits(
        format!(
            "run_scene('{}') with {} steps",
            scene.name, scene.method.steps
        ),
        estimate,
        "the whole run is kept: fewer steps (the steps option)",
    )
    .py_err()?;
    if let BuiltSystem::RigidBody(body) = &scene.system {
        let traj = rigid::run(py, body, &scene)?;
        return Ok(Bound::new(py, traj)?.into_any());
    }
    if scene.method.time_transform.is_some() {
        let traj = time_transform::run_scene(py, &scene)?;
        return Ok(Bound::new(py, traj)?.into_any());
    }
    let kind = std::sync::Arc::new(systems::system_of(&scene)?);
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
        Some(traj) => {
            let traj = Trajectory::new(traj, kind, scene.method.clone());
            Ok(Bound::new(py, traj)?.into_any())
        }
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
    if method.time_transform.is_some() {
        return Err(errors::UnsupportedError::new_err(
            "integrate_many: a time-transformed Integrator ends each member at its own number \
             of fictitious steps; integrate the members one by one (Integrator.integrate)",
        ));
    }
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
    m.add_class::<rigid::RigidBodyTrajectory>()?;
    m.add_class::<time_transform::TimeTransform>()?;
    m.add_class::<time_transform::TimeTransformedTrajectory>()?;
    m.add_function(wrap_pyfunction!(run_scene, m)?)?;
    m.add_function(wrap_pyfunction!(integrate_many, m)?)?;
    Ok(())
}
