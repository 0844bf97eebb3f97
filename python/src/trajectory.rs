//! `Integrator` (a method: basis, n, quadrature, h, stage solver) and `Trajectory` (states,
//! Galerkin coefficients, dense output, invariants and the geometric check).

use crate::convert::{finite, vector};
use crate::errors::{IntoPy, NonFiniteError, NonFiniteResultError};
use crate::guard;
use crate::interrupt::{Stop, interruptible};
use crate::systems::{SysKind, System};
use crate::with_system;
use galerkin_vi::Lagrangian as _;
use galerkin_vi::geometry::{Series, relative_symplecticity_defect, symplecticity_defect};
use galerkin_vi::method::{InitialState, MethodSpec};
use galerkin_vi::solve::solve_until;
use galerkin_vi::systems::System as _;
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::Arc;

/// `omega` of [`Integrator`]: a number or a sequence of numbers.
#[derive(FromPyObject)]
pub(crate) enum Frequencies {
    One(f64),
    Many(Vec<f64>),
}

/// A Galerkin variational integrator: `Integrator(basis="chebyshev", n=16,
/// quadrature="gauss-legendre", h=1.0, solver="auto", quad_points=None, economical=False,
/// compact=False, collocation=False, omega=None, harmonics=None)`. `basis="enriched"` takes the enrichment
/// frequency `omega` (and optionally `harmonics`, default 1): polynomials of degree
/// n − 1 − 2·harmonics plus sin/cos of ωh; `omega` may be a list (`omega=[50.0, 20.0]`),
/// with sin/cos of each frequency in the space (degree n − 1 − 2·harmonics·len(omega)).
/// `quad_points` is an explicit number of quadrature points;
/// `economical=True` takes the quadrature's economical number for n (⌈3n/2⌉ Gauss–Legendre
/// points, as `gvi run --economical`), `compact=True` its compact rule (n Gauss–Legendre
/// points), `collocation=True` n − 1 Gauss–Legendre points (the step is then Gauss
/// collocation with n − 1 stages); at most one of the four. `time_transform` (a `TimeTransform` or a monitor name)
/// makes `h` the fictitious step of a Poincaré time transformation: `integrate` then takes at
/// most `steps` fictitious steps (to the transformation's `t_end`, if it has one) and returns
/// a `TimeTransformedTrajectory` in physical time; only exact Newton applies (`solver` "auto"
/// or "exact": the transformed Lagrangian is not separable).
#[pyclass(frozen, module = "galerkin_vi")]
pub struct Integrator {
    pub(crate) method: MethodSpec,
}

impl Integrator {
    /// Integrate one member without the GIL's help (pure Rust), from t = 0; `stop` is asked
    /// before every step ([`galerkin_vi::solve::solve_until`]: the trajectory is
    /// `GalerkinIntegrator::integrate`'s bit for bit).
    pub(crate) fn run(
        method: &MethodSpec,
        kind: &SysKind,
        q0: &[f64],
        p0: &[f64],
        steps: usize,
        stop: &Stop,
    ) -> Result<galerkin_vi::Trajectory, galerkin_vi::GviError> {
        let method = MethodSpec {
            steps,
            ..method.clone()
        };
        let initial = InitialState {
            t0: 0.0,
            q: q0.to_vec(),
            p: p0.to_vec(),
        };
        with_system!(kind, s => solve_until(s, &initial, &method, &|| stop.requested()))
            .map(|solution| solution.trajectory)
            .map_err(|failure| failure.error)
    }
}

#[pymethods]
impl Integrator {
    #[new]
    #[pyo3(signature = (basis = "chebyshev", n = 16, quadrature = "gauss-legendre", h = 1.0,
                        solver = "auto", quad_points = None, economical = false,
                        compact = false, collocation = false, omega = None,
                        harmonics = None, time_transform = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        basis: &str,
        n: usize,
        quadrature: &str,
        h: f64,
        solver: &str,
        quad_points: Option<usize>,
        economical: bool,
        compact: bool,
        collocation: bool,
        omega: Option<Frequencies>,
        harmonics: Option<usize>,
        time_transform: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let mut method = MethodSpec::spectral(n, finite("h", h)?, 1);
        method.basis = basis.parse::<galerkin_vi::basis::BasisKind>().py_err()?;
        method.quadrature = quadrature
            .parse::<galerkin_vi::quadrature::QuadratureKind>()
            .py_err()?;
        method.omega = match omega {
            None => None,
            Some(Frequencies::One(w)) => Some(vec![finite("omega", w)?]),
            Some(Frequencies::Many(ws)) => Some(
                ws.into_iter()
                    .map(|w| finite("omega", w))
                    .collect::<PyResult<Vec<f64>>>()?,
            ),
        };
        method.harmonics = harmonics;
        method.solver = solver
            .parse::<galerkin_vi::integrator::StageSolver>()
            .py_err()?;
        let rules = [quad_points.is_some(), economical, compact, collocation];
        if rules.iter().filter(|&&given| given).count() > 1 {
            return Err(crate::errors::InvalidInputError::new_err(
                "quad_points, economical, compact and collocation: give one way of choosing the \
                 quadrature points",
            ));
        }
        method.quad_points = if economical {
            Some(method.quadrature.economical_points(n))
        } else if compact {
            Some(method.quadrature.compact_points(n))
        } else if collocation {
            Some(method.quadrature.collocation_points(n))
        } else {
            quad_points
        };
        method.time_transform = time_transform
            .map(crate::time_transform::spec_of)
            .transpose()?;
        // Build once now so that a bad n, h or quadrature is an error here, not later.
        method.integrator().py_err()?;
        Ok(Integrator { method })
    }

    /// Integrate `steps` steps of `system` from (q0, p0) at t = 0. Refused before any work:
    /// a start `gvi run` refuses, and work whose estimated memory is above the limit
    /// (`MemoryLimitError`). Ctrl-C stops the run within a step (`KeyboardInterrupt`). With a
    /// time transformation: a `TimeTransformedTrajectory` of at most `steps` fictitious
    /// steps; a monitor that does not fit the system (radius on N bodies), is not finite and
    /// positive at q0 (r^alpha at r = 0), or a system that is not separable is refused
    /// before any step.
    fn integrate<'py>(
        &self,
        py: Python<'py>,
        system: &Bound<'py, System>,
        q0: &Bound<'py, PyAny>,
        p0: &Bound<'py, PyAny>,
        steps: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        let kind = system.get().kind.clone();
        let d = kind.dim();
        let q0 = vector(q0, "q0", Some(d))?;
        let p0 = vector(p0, "p0", Some(d))?;
        guard::ensure_steps(steps)?;
        guard::ensure_runs_fit(1, steps, self.method.n, d)?;
        guard::check_start(&kind, &q0, &p0).py_err()?;
        if self.method.time_transform.is_some() {
            let traj = crate::time_transform::integrate(py, &self.method, &kind, &q0, &p0, steps)?;
            return Ok(Bound::new(py, traj)?.into_any());
        }
        let method = self.method.clone();
        let traj = interruptible(py, |stop| {
            Integrator::run(&method, &kind, &q0, &p0, steps, stop)
        })?
        .py_err()?;
        Ok(Bound::new(py, Trajectory::new(traj, kind, method))?.into_any())
    }

    /// The time transformation, or None.
    #[getter]
    fn time_transform(&self) -> Option<crate::time_transform::TimeTransform> {
        self.method
            .time_transform
            .clone()
            .map(|spec| crate::time_transform::TimeTransform { spec })
    }

    /// Number of basis functions n.
    #[getter]
    fn n(&self) -> usize {
        self.method.n
    }

    /// Step size h.
    #[getter]
    fn h(&self) -> f64 {
        self.method.h
    }

    /// Number of quadrature points per step (`quad_points`, or the quadrature's default for
    /// n).
    #[getter]
    fn quad_points(&self) -> usize {
        self.method.quadrature_points()
    }

    fn __repr__(&self) -> String {
        let m = &self.method;
        format!(
            "Integrator(basis='{}', n={}, quadrature='{}', h={}, solver='{}', quad_points={})",
            m.basis.as_str(),
            m.n,
            m.quadrature.as_str(),
            m.h,
            m.solver.as_str(),
            m.quadrature_points()
        )
    }
}

/// The result of an integration: `t`, `q`, `p` (numpy arrays, steps + 1 rows), the Galerkin
/// `coefficients` of every step (steps × n × D), dense output along the Galerkin curves and the
/// invariants.
#[pyclass(frozen, module = "galerkin_vi")]
pub struct Trajectory {
    pub(crate) inner: galerkin_vi::Trajectory,
    kind: Arc<SysKind>,
    method: MethodSpec,
}

impl Trajectory {
    pub(crate) fn new(
        inner: galerkin_vi::Trajectory,
        kind: Arc<SysKind>,
        method: MethodSpec,
    ) -> Self {
        Trajectory {
            inner,
            kind,
            method,
        }
    }

    fn rows<'py>(py: Python<'py>, rows: &[Vec<f64>], d: usize) -> Bound<'py, PyArray2<f64>> {
        let flat: Vec<f64> = rows.iter().flatten().copied().collect();
        Array2::from_shape_vec((rows.len(), d), flat)
            .unwrap_or_else(|_| Array2::zeros((0, d)))
            .into_pyarray(py)
    }

    /// Evaluate `f` at a scalar t (1-D result) or at every entry of an array of times (2-D).
    fn dense<'py>(
        &self,
        t: &Bound<'py, PyAny>,
        f: impl Fn(f64) -> PyResult<Vec<f64>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let py = t.py();
        if let Ok(x) = t.extract::<f64>() {
            let x = finite("t", x)?;
            return Ok(f(x)?.into_pyarray(py).into_any());
        }
        let times = vector(t, "t", None)?;
        let d = self.inner.dim;
        let mut out = Vec::with_capacity(times.len() * d);
        for &x in &times {
            out.extend(f(x)?);
        }
        let a = Array2::from_shape_vec((times.len(), d), out)
            .map_err(|e| NonFiniteError::new_err(e.to_string()))?;
        Ok(a.into_pyarray(py).into_any())
    }
}

#[pymethods]
impl Trajectory {
    /// Times t_k = k h (steps + 1 of them).
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        Array1::from(self.inner.times()).into_pyarray(py)
    }

    /// Positions q_k, shape (steps + 1, D).
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        Self::rows(py, &self.inner.q, self.inner.dim)
    }

    /// Momenta p_k, shape (steps + 1, D).
    #[getter]
    fn p<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        Self::rows(py, &self.inner.p, self.inner.dim)
    }

    /// Galerkin coefficients of every step, shape (steps, n, D) (row i = Q_i).
    #[getter]
    fn coefficients<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let (steps, n, d) = (self.inner.steps(), self.inner.n, self.inner.dim);
        let flat: Vec<f64> = self.inner.coefficients.iter().flatten().copied().collect();
        let a = Array3::from_shape_vec((steps, n, d), flat).map_err(|_| {
            crate::errors::UnsupportedError::new_err(
                "coefficients: steps use different n (tolerance-driven run)",
            )
        })?;
        Ok(a.into_pyarray(py))
    }

    /// Number of steps.
    #[getter]
    fn steps(&self) -> usize {
        self.inner.steps()
    }

    /// Step size h.
    #[getter]
    fn h(&self) -> f64 {
        self.inner.h
    }

    /// Number of basis functions n.
    #[getter]
    fn n(&self) -> usize {
        self.inner.n
    }

    /// Configuration dimension D.
    #[getter]
    fn dim(&self) -> usize {
        self.inner.dim
    }

    /// Newton iterations over the run.
    #[getter]
    fn newton_iterations(&self) -> usize {
        self.inner.newton_iterations()
    }

    /// q(t) on the Galerkin curves: t a number (shape (D,)) or an array (shape (len(t), D)).
    fn position_at<'py>(&self, t: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        self.dense(t, |x| self.inner.position_at(x).py_err())
    }

    /// p(t) = ∂L/∂q̇ on the Galerkin curves: t a number or an array.
    fn momentum_at<'py>(&self, t: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        self.dense(t, |x| {
            with_system!(&*self.kind, s => self.inner.momentum_at(s, x)).py_err()
        })
    }

    /// The zero crossings of `g(t, q, p)` (a Python callable returning a float; q and p
    /// numpy arrays of shape (D,); or an expression string over the coordinate names, the
    /// momenta `p_<name>`, `t` and the parameters, e.g. "x") along the Galerkin curves,
    /// located on each step's curve:
    /// g is sampled `samples_per_step` times per step and a sign change is refined on the
    /// curve (regula falsi). `direction`: "either", "rising" (g from − to +) or "falling".
    /// Returns a list of dicts with `t`, `q`, `p` (arrays), `step` and `rising`, in time order.
    /// An exception raised by g is re-raised; a g that returns NaN is a `NonFiniteError`.
    #[pyo3(signature = (g, direction = "either", samples_per_step = 8))]
    fn crossings<'py>(
        &self,
        py: Python<'py>,
        g: &Bound<'py, PyAny>,
        direction: &str,
        samples_per_step: usize,
    ) -> PyResult<Vec<Bound<'py, PyDict>>> {
        use galerkin_vi::events::{Direction, Event, EventOptions, crossings_on_trajectory};
        let direction = match direction {
            "either" => Direction::Either,
            "rising" => Direction::Rising,
            "falling" => Direction::Falling,
            other => {
                return Err(crate::errors::InvalidInputError::new_err(format!(
                    "direction: expected 'either', 'rising' or 'falling', got '{other}'"
                )));
            }
        };
        // g as text: an expression over the coordinate names, p_<name>, t and the parameters.
        if let Ok(text) = g.extract::<String>() {
            use galerkin_vi::events::ExpressionEvent;
            let (names, params) = galerkin_vi_lab::section::names_of(&self.kind);
            let coords: Vec<&str> = names.iter().map(String::as_str).collect();
            let pars: Vec<(&str, f64)> = params.iter().map(|(n, v)| (n.as_str(), *v)).collect();
            let g = ExpressionEvent::parse(&text, &coords, &pars).py_err()?;
            let events = [Event::new("g", g).direction(direction)];
            let options = EventOptions {
                samples_per_step,
                ..EventOptions::default()
            };
            let found = with_system!(&*self.kind, s => {
                crossings_on_trajectory(&self.inner, s, &events, &options)
            });
            return found
                .py_err()?
                .into_iter()
                .map(|c| crossing_dict(py, c))
                .collect();
        }
        if !g.is_callable() {
            return Err(crate::errors::InvalidInputError::new_err(
                "g: expected a callable g(t, q, p) -> float or an expression string",
            ));
        }
        // The first exception raised by g (or a non-float result): the scan then sees NaN and
        // stops, and the exception is raised instead of the scan's error.
        let raised: std::cell::RefCell<Option<PyErr>> = std::cell::RefCell::new(None);
        let function = |t: f64, q: &[f64], p: &[f64]| -> f64 {
            if raised.borrow().is_some() {
                return f64::NAN;
            }
            let args = (t, q.to_vec().into_pyarray(py), p.to_vec().into_pyarray(py));
            match g.call1(args).and_then(|v| v.extract::<f64>()) {
                Ok(v) => v,
                Err(e) => {
                    *raised.borrow_mut() = Some(e);
                    f64::NAN
                }
            }
        };
        let events = [Event::new("g", function).direction(direction)];
        let options = EventOptions {
            samples_per_step,
            ..EventOptions::default()
        };
        let found = with_system!(&*self.kind, s => {
            crossings_on_trajectory(&self.inner, s, &events, &options)
        });
        if let Some(e) = raised.borrow_mut().take() {
            return Err(e);
        }
        found
            .py_err()?
            .into_iter()
            .map(|c| crossing_dict(py, c))
            .collect()
    }

    /// The energy balance of a forced or time-dependent run: a dict of arrays `t`, `energy`
    /// (E_k at the step ends), `source` (the work of the force minus ∫∂L/∂t from t0 to t_k,
    /// integrated along the Galerkin curves) and `defect` = E_k − E_0 − source_k, zero for
    /// the exact motion (galerkin_vi::forcing::energy_balance).
    fn energy_balance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let balance = with_system!(&*self.kind, s => {
            galerkin_vi::forcing::energy_balance(s, &self.inner)
        })
        .py_err()?;
        let dict = PyDict::new(py);
        let defects = balance.defects();
        dict.set_item("t", balance.t.into_pyarray(py))?;
        dict.set_item("energy", balance.value.into_pyarray(py))?;
        dict.set_item("source", balance.source.into_pyarray(py))?;
        dict.set_item("defect", defects.into_pyarray(py))?;
        Ok(dict)
    }

    /// The invariants at every step end, as a dict name → array (steps + 1).
    #[getter]
    fn invariants<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        with_system!(&*self.kind, s => {
            let names = s.invariant_names();
            let mut columns = vec![Vec::with_capacity(self.inner.q.len()); names.len()];
            let mut buf = vec![0.0; names.len()];
            for (q, p) in self.inner.q.iter().zip(&self.inner.p) {
                s.invariants(q, p, &mut buf);
                for (c, v) in columns.iter_mut().zip(&buf) {
                    c.push(*v);
                }
            }
            for (name, c) in names.iter().zip(columns) {
                dict.set_item(*name, c.into_pyarray(py))?;
            }
        });
        Ok(dict)
    }

    /// Geometric check of the run: the symplecticity defect ‖JᵀΩJ − Ω‖_F of every step's
    /// exact Jacobian (max, and relative to ‖J‖_F²), the max energy error and the max error
    /// of each momentum map of the system's symmetries at step ends (a dict). A quantity that
    /// is NaN or infinite at some step is a `NonFiniteResultError` naming it and the step,
    /// never a max that skips it.
    fn check<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        if !self.inner.step_n.is_empty() {
            return Err(crate::errors::UnsupportedError::new_err(
                "check(): the steps of a tolerance-driven run use different n",
            ));
        }
        let method = self.method.clone();
        let inner = &self.inner;
        let kind = self.kind.clone();
        let (defects, energy, momenta) = interruptible(py, |stop| {
            let mut m = method.clone();
            m.n = inner.n;
            let gvi = m.integrator()?;
            with_system!(&*kind, s => {
                let mut defects = Vec::with_capacity(inner.coefficients.len());
                for c in &inner.coefficients {
                    if stop.requested() {
                        break;
                    }
                    let j = gvi.step_jacobian_from_coefficients(s, c)?;
                    defects.push((symplecticity_defect(&j), relative_symplecticity_defect(&j)));
                }
                let energy = galerkin_vi::geometry::energy_at_step_ends(s, inner).ok();
                let momenta: Vec<(String, Series)> = s
                    .symmetries()
                    .iter()
                    .map(|sym| {
                        let series =
                            galerkin_vi::geometry::momentum_at_step_ends(&*sym.map, inner);
                        (sym.name.clone(), series)
                    })
                    .collect();
                Ok::<_, galerkin_vi::GviError>((defects, energy, momenta))
            })
        })?
        .py_err()?;
        let (mut defect, mut relative) = (0.0f64, 0.0f64);
        for (k, &(d, r)) in defects.iter().enumerate() {
            if !(d.is_finite() && r.is_finite()) {
                return Err(NonFiniteResultError::new_err(format!(
                    "check(): the symplecticity defect of step {k} (t = {}) is {d} (its \
                     Jacobian is not finite)",
                    self.inner.time(k)
                )));
            }
            (defect, relative) = (defect.max(d), relative.max(r));
        }
        let energy = energy
            .map(|e| max_deviation("the energy", &e, self))
            .transpose()?;
        let dict = PyDict::new(py);
        dict.set_item("max_symplecticity_defect", defect)?;
        dict.set_item("max_relative_symplecticity_defect", relative)?;
        dict.set_item("max_energy_error", energy)?;
        let m = PyDict::new(py);
        for (name, series) in momenta {
            let what = format!("the momentum map {name}");
            m.set_item(&name, max_deviation(&what, &series, self)?)?;
        }
        dict.set_item("momentum_errors", m)?;
        Ok(dict)
    }

    fn __len__(&self) -> usize {
        self.inner.q.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "<galerkin_vi Trajectory: {} steps of h = {}, n = {}, D = {}>",
            self.inner.steps(),
            self.inner.h,
            self.inner.n,
            self.inner.dim
        )
    }
}

/// A crossing as the dict `Trajectory.crossings` returns.
fn crossing_dict(py: Python<'_>, c: galerkin_vi::events::Crossing) -> PyResult<Bound<'_, PyDict>> {
    let dict = PyDict::new(py);
    dict.set_item("t", c.t)?;
    dict.set_item("q", c.q.into_pyarray(py))?;
    dict.set_item("p", c.p.into_pyarray(py))?;
    dict.set_item("step", c.step)?;
    dict.set_item("rising", c.rising)?;
    Ok(dict)
}

/// Max |value − first value| of a conserved quantity at the step ends, or a
/// `NonFiniteResultError` naming the first step where it is NaN or infinite (a max that
/// skipped NaN would report a broken run as exact) and, for an expression Lagrangian, why its
/// velocity (which the energy needs) cannot be had from the state there.
fn max_deviation(what: &str, series: &Series, traj: &Trajectory) -> PyResult<f64> {
    let first = series.values.first().copied().unwrap_or(0.0);
    let mut worst = 0.0f64;
    for (k, (&t, &v)) in series.t.iter().zip(&series.values).enumerate() {
        if !v.is_finite() {
            let (q, p) = (&traj.inner.q[k], &traj.inner.p[k]);
            let reason = match &*traj.kind {
                SysKind::Expression(e) => match e.velocity_at(t, q, p) {
                    Err(err) => format!(": {err}"),
                    Ok(_) => String::new(),
                },
                _ => String::new(),
            };
            return Err(NonFiniteResultError::new_err(format!(
                "check(): {what} is {v} at step {k} (t = {t}, q = {q:?}, p = {p:?}) of this {} \
                 run although the state is finite; the system cannot evaluate it there{reason}",
                traj.kind.name()
            )));
        }
        worst = worst.max((v - first).abs());
    }
    Ok(worst)
}
