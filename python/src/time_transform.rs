//! Poincaré time transformations from Python: `TimeTransform` (the monitor, its exponent,
//! E₀, the physical end time and output spacing: `[method.time_transform]` of a scene, the
//! `--time-transform` flags of `gvi run`) and `TimeTransformedTrajectory`, a run in physical
//! time (docs/guide/time-transformations.md). The run itself is the lab's, the one `gvi run`
//! makes ([`galerkin_vi_lab::run::time_transform`]), so the rows are the CSV's bit for bit.

use crate::convert::finite;
use crate::errors::{IntoPy, InvalidInputError, lab_error};
use crate::interrupt::interruptible;
use galerkin_vi::GviError;
use galerkin_vi::method::{InitialState, MethodSpec};
use galerkin_vi::time_transform::{MonitorKind, TimeTransformSpec};
use galerkin_vi_lab::run::time_transform::TimeTransformResult;
use numpy::IntoPyArray;
use numpy::ndarray::Array2;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A Poincaré time transformation: `TimeTransform(monitor="sundman", alpha=1.5,
/// energy_level=None, t_end=None, every=None)`. The monitor g is one of "sundman" (|q|^alpha
/// for Kepler, a smooth minimum of the pair distances^alpha for N bodies), "radius",
/// "min-distance", "softmin-distance" or "product-distance"; `energy_level` is E₀ (default:
/// the initial state's energy); `t_end` the physical end time and `every` the spacing of
/// the output rows in physical time, each located on t(s). Given to
/// `Integrator(time_transform=...)` or `run_scene(..., time_transform=...)`. An unknown
/// monitor is an `InvalidInputError`; alpha, energy_level, t_end or every not finite (every
/// not positive) an `InvalidParameterError` or `NonFiniteError`, here, before any run.
#[pyclass(frozen, module = "galerkin_vi")]
#[derive(Clone)]
pub struct TimeTransform {
    pub(crate) spec: TimeTransformSpec,
}

#[pymethods]
impl TimeTransform {
    #[new]
    #[pyo3(signature = (monitor = "sundman", alpha = 1.5, energy_level = None, t_end = None,
                        every = None))]
    fn new(
        monitor: &str,
        alpha: f64,
        energy_level: Option<f64>,
        t_end: Option<f64>,
        every: Option<f64>,
    ) -> PyResult<Self> {
        let kind = monitor.parse::<MonitorKind>().py_err()?;
        let spec = TimeTransformSpec {
            monitor: kind,
            alpha: finite("alpha", alpha)?,
            energy: energy_level
                .map(|e| finite("energy_level", e))
                .transpose()?,
            t_end: t_end.map(|t| finite("t_end", t)).transpose()?,
            every: every.map(|e| finite("every", e)).transpose()?,
        };
        spec.validate().py_err()?;
        Ok(TimeTransform { spec })
    }

    /// The monitor's name.
    #[getter]
    fn monitor(&self) -> &'static str {
        self.spec.monitor.as_str()
    }

    /// The monitor's exponent alpha.
    #[getter]
    fn alpha(&self) -> f64 {
        self.spec.alpha
    }

    /// E₀, or None for the initial state's energy.
    #[getter]
    fn energy_level(&self) -> Option<f64> {
        self.spec.energy
    }

    /// The physical end time, or None (run the method's steps).
    #[getter]
    fn t_end(&self) -> Option<f64> {
        self.spec.t_end
    }

    /// The spacing of the output rows in physical time, or None (rows at the step ends).
    #[getter]
    fn every(&self) -> Option<f64> {
        self.spec.every
    }

    fn __repr__(&self) -> String {
        let opt = |x: Option<f64>| x.map_or("None".to_string(), |v| v.to_string());
        format!(
            "TimeTransform(monitor='{}', alpha={}, energy_level={}, t_end={}, every={})",
            self.spec.monitor.as_str(),
            self.spec.alpha,
            opt(self.spec.energy),
            opt(self.spec.t_end),
            opt(self.spec.every)
        )
    }
}

/// `time_transform=` of `run_scene` and `Integrator`: a `TimeTransform`, or a monitor name
/// for `TimeTransform(monitor)`.
pub fn spec_of(value: &Bound<'_, PyAny>) -> PyResult<TimeTransformSpec> {
    if let Ok(tt) = value.cast::<TimeTransform>() {
        return Ok(tt.get().spec.clone());
    }
    match value.extract::<String>() {
        Ok(name) => Ok(TimeTransformSpec::new(
            name.parse::<MonitorKind>().py_err()?,
        )),
        Err(_) => Err(InvalidInputError::new_err(format!(
            "time_transform: expected a TimeTransform or a monitor name ({}), got {value}",
            MonitorKind::NAMES.join(", ")
        ))),
    }
}

/// A time-transformed run in physical time: one row per fictitious step end (or per output
/// time t₀ + k·every, located on t(s)): `t`, `s` (fictitious time), `dt` (the physical length
/// of the step holding the row), `step`, `q`, `p`, the invariants, the position error
/// against the exact solution when it is known (Kepler), and a `summary` (energy error,
/// physical step range, force evaluations, seconds) — the rows and summary `gvi run` prints.
#[pyclass(frozen, module = "galerkin_vi")]
pub struct TimeTransformedTrajectory {
    result: TimeTransformResult,
    dim: usize,
}

impl TimeTransformedTrajectory {
    /// The result of a run that reached its end, or the exception of the failure that ended
    /// it early (the rows before it are not returned: a partial run is not silently
    /// trusted).
    pub fn from_result(result: TimeTransformResult, dim: usize) -> PyResult<Self> {
        match result.failure {
            Some(e) => Err(lab_error(e)),
            None => Ok(TimeTransformedTrajectory { result, dim }),
        }
    }

    fn column(&self, name: &str) -> Option<Vec<f64>> {
        let i = self.result.columns.iter().position(|c| c == name)?;
        Some(self.result.rows.iter().map(|r| r[i]).collect())
    }

    /// Columns `first..first + dim` as a (rows, dim) array.
    fn block<'py>(&self, py: Python<'py>, first: usize) -> Bound<'py, PyAny> {
        let d = self.dim;
        let flat: Vec<f64> = self
            .result
            .rows
            .iter()
            .flat_map(|r| r[first..first + d].iter().copied())
            .collect();
        match Array2::from_shape_vec((self.result.rows.len(), d), flat) {
            Ok(a) => a.into_pyarray(py).into_any(),
            Err(_) => Array2::<f64>::zeros((0, d)).into_pyarray(py).into_any(),
        }
    }
}

/// The first state column: after `step, s, t, dt`.
const STATE: usize = 4;

#[pymethods]
impl TimeTransformedTrajectory {
    /// Physical times of the rows.
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.column("t")
            .unwrap_or_default()
            .into_pyarray(py)
            .into_any()
    }

    /// Fictitious times s of the rows.
    #[getter]
    fn s<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.column("s")
            .unwrap_or_default()
            .into_pyarray(py)
            .into_any()
    }

    /// The physical length of the fictitious step that ends at (or holds) each row (0 for
    /// the initial state).
    #[getter]
    fn dt<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.column("dt")
            .unwrap_or_default()
            .into_pyarray(py)
            .into_any()
    }

    /// The fictitious step of each row (steps completed, for a step end).
    #[getter]
    fn step(&self) -> Vec<usize> {
        self.column("step")
            .unwrap_or_default()
            .into_iter()
            .map(|x| x as usize)
            .collect()
    }

    /// Positions, shape (rows, D).
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.block(py, STATE)
    }

    /// Physical momenta p = M dq/dt, shape (rows, D).
    #[getter]
    fn p<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.block(py, STATE + self.dim)
    }

    /// The invariants of every row, as a dict name → array.
    #[getter]
    fn invariants<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for name in self.result.columns.iter().skip(STATE + 2 * self.dim) {
            if name == "position_error" {
                continue;
            }
            if let Some(c) = self.column(name) {
                dict.set_item(name, c.into_pyarray(py))?;
            }
        }
        Ok(dict)
    }

    /// The max-norm position error against the exact solution at every row, or None when
    /// the system has none (only the Kepler problem has one).
    #[getter]
    fn position_error<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyAny>> {
        self.column("position_error")
            .map(|c| c.into_pyarray(py).into_any())
    }

    /// Fictitious steps taken.
    #[getter]
    fn steps(&self) -> usize {
        self.result.summary.steps
    }

    /// Configuration dimension D.
    #[getter]
    fn dim(&self) -> usize {
        self.dim
    }

    /// The summary `gvi run` prints, as a dict: system, method, steps, t (reached),
    /// energy_level (E₀), max_energy_error, max_relative_energy_error, max_position_error
    /// (or None), min_step and max_step (physical), newton_iterations_per_step,
    /// force_evaluations, seconds (wall clock of the integration).
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.result.summary;
        let dict = PyDict::new(py);
        dict.set_item("system", &s.system)?;
        dict.set_item("method", &s.method)?;
        dict.set_item("steps", s.steps)?;
        dict.set_item("t", s.t)?;
        dict.set_item("energy_level", s.energy_level)?;
        dict.set_item("max_energy_error", s.max_energy_error)?;
        dict.set_item("max_relative_energy_error", s.max_relative_energy_error)?;
        dict.set_item("max_position_error", s.max_position_error)?;
        dict.set_item("min_step", s.min_step)?;
        dict.set_item("max_step", s.max_step)?;
        dict.set_item("newton_iterations_per_step", s.newton_iterations_per_step)?;
        dict.set_item("force_evaluations", s.force_evaluations)?;
        dict.set_item("seconds", s.seconds)?;
        Ok(dict)
    }

    fn __len__(&self) -> usize {
        self.result.rows.len()
    }

    fn __repr__(&self) -> String {
        let s = &self.result.summary;
        format!(
            "<galerkin_vi TimeTransformedTrajectory: {} fictitious steps to t = {}, {} rows, \
             D = {}>",
            s.steps,
            s.t,
            self.result.rows.len(),
            self.dim
        )
    }
}

/// `Integrator(time_transform=...).integrate(system, q0, p0, steps)`: `steps` fictitious
/// steps at most (to the transformation's `t_end` if it has one), from t = 0, interruptible
/// by Ctrl-C within a step.
pub fn integrate(
    py: Python<'_>,
    method: &MethodSpec,
    kind: &crate::systems::SysKind,
    q0: &[f64],
    p0: &[f64],
    steps: usize,
) -> PyResult<TimeTransformedTrajectory> {
    let method = MethodSpec {
        steps,
        ..method.clone()
    };
    let initial = InitialState {
        t0: 0.0,
        q: q0.to_vec(),
        p: p0.to_vec(),
    };
    let result = interruptible(py, |stop| {
        galerkin_vi_lab::run::time_transform::run_time_transformed_system(
            kind,
            &method,
            &initial,
            &|| stop.requested(),
        )
    })?
    .py_err()?;
    TimeTransformedTrajectory::from_result(result, q0.len())
}

/// A time-transformed scene (`[method.time_transform]`, or `run_scene(...,
/// time_transform=...)`), as `gvi run` runs it.
pub fn run_scene(
    py: Python<'_>,
    scene: &galerkin_vi_lab::scene::BuiltScene,
) -> PyResult<TimeTransformedTrajectory> {
    let dim = scene.initial.q.len();
    let result = interruptible(py, |stop| {
        galerkin_vi_lab::run::time_transform::run_time_transformed_until(scene, false, &|| {
            stop.requested()
        })
    })?
    .py_err()?;
    // As for the other scenes: a relative energy error above `gvi run --strict`'s threshold
    // is a `RuntimeWarning`, so that a run that returns is not silently trusted.
    let rel = result.summary.max_relative_energy_error;
    if rel > galerkin_vi_lab::run::SANITY_THRESHOLD {
        let message = std::ffi::CString::new(format!(
            "run_scene('{}'): relative energy error {rel:.3e} above {:e}",
            scene.name,
            galerkin_vi_lab::run::SANITY_THRESHOLD
        ))
        .unwrap_or_default();
        PyErr::warn(
            py,
            &py.get_type::<pyo3::exceptions::PyRuntimeWarning>(),
            &message,
            1,
        )?;
    }
    TimeTransformedTrajectory::from_result(result, dim)
}

/// A `GviError` for options that only a time-transformed run uses.
pub fn only_with_transform(name: &str) -> PyErr {
    crate::errors::core_error(GviError::InvalidInput {
        name: name.into(),
        reason: "only a time-transformed run uses it; give time_transform as well (or run a \
                 scene with [method.time_transform])"
            .into(),
    })
}
