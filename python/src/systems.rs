//! `galerkin_vi.systems`: the built-in systems and expression Lagrangians. Every class derives
//! from `System`, which the integrators accept.

use crate::convert::{finite, vector};
use crate::errors::{IntoPy, UnsupportedError};
use galerkin_vi::Lagrangian as _;
use galerkin_vi::systems::{self as sys, ExpressionLagrangian, System as _};
use galerkin_vi_lab::scene::{BuiltScene, BuiltSystem};
use pyo3::PyClassInitializer;
use pyo3::prelude::*;
use std::collections::BTreeMap;
use std::sync::Arc;

/// The concrete system behind a Python `System`: the library's [`AnySystem`], the built-in
/// systems as one enum (rigid bodies, on SO(3), are run by `run_scene` alone: crate::rigid).
pub use galerkin_vi::systems::AnySystem as SysKind;

/// Run `$body` with `$s` bound to the system. `AnySystem` dispatches every trait method to the
/// concrete system itself, so this is a plain binding (kept as a macro for the call sites).
#[macro_export]
macro_rules! with_system {
    ($kind:expr, $s:ident => $body:expr) => {{
        let $s: &$crate::systems::SysKind = $kind;
        $body
    }};
}

/// The system of a built scene, or `UnsupportedError` for rigid bodies (which live on SO(3)
/// and are not a `System`: `run_scene` runs them by the Lie group integrator).
pub fn system_of(scene: &BuiltScene) -> PyResult<SysKind> {
    match &scene.system {
        BuiltSystem::Euclidean(s) => Ok(s.clone()),
        BuiltSystem::RigidBody(_) => Err(UnsupportedError::new_err(
            "rigid bodies live on SO(3), not in R^D: run them with run_scene (which returns a \
             RigidBodyTrajectory), not as a System",
        )),
    }
}

/// A mechanical system (base class of the systems in `galerkin_vi.systems`).
#[pyclass(subclass, frozen, module = "galerkin_vi.systems")]
pub struct System {
    pub(crate) kind: Arc<SysKind>,
}

impl System {
    pub(crate) fn new(kind: SysKind) -> Self {
        System {
            kind: Arc::new(kind),
        }
    }
}

#[pymethods]
impl System {
    /// Configuration dimension D.
    #[getter]
    fn dim(&self) -> usize {
        self.kind.dim()
    }

    /// Short name, e.g. "kepler".
    #[getter]
    fn name(&self) -> &'static str {
        with_system!(&*self.kind, s => s.name())
    }

    /// Names of the invariants `invariants(q, p)` returns.
    #[getter]
    fn invariant_names(&self) -> Vec<&'static str> {
        with_system!(&*self.kind, s => s.invariant_names().to_vec())
    }

    /// The invariants at (q, p), as a dict name → value.
    fn invariants(
        &self,
        q: &Bound<'_, PyAny>,
        p: &Bound<'_, PyAny>,
    ) -> PyResult<BTreeMap<&'static str, f64>> {
        let d = self.kind.dim();
        let q = vector(q, "q", Some(d))?;
        let p = vector(p, "p", Some(d))?;
        Ok(with_system!(&*self.kind, s => {
            let mut out = vec![0.0; s.invariant_names().len()];
            s.invariants(&q, &p, &mut out);
            s.invariant_names().iter().copied().zip(out).collect()
        }))
    }

    fn __repr__(&self) -> String {
        format!("<galerkin_vi system {} (D = {})>", self.name(), self.dim())
    }
}

/// Planar Kepler problem L = |q̇|²/2 + μ/|q| (D = 2).
#[pyclass(extends = System, frozen, module = "galerkin_vi.systems")]
pub struct Kepler;

#[pymethods]
impl Kepler {
    #[new]
    #[pyo3(signature = (mu = 1.0))]
    fn new(mu: f64) -> PyResult<PyClassInitializer<Self>> {
        let mu = finite("mu", mu)?;
        let s = sys::Kepler::new(mu).py_err()?;
        Ok(PyClassInitializer::from(System::new(SysKind::Kepler(s))).add_subclass(Kepler))
    }
}

/// Harmonic oscillator L = m q̇²/2 − k q²/2 (D = 1).
#[pyclass(extends = System, frozen, module = "galerkin_vi.systems")]
pub struct HarmonicOscillator;

#[pymethods]
impl HarmonicOscillator {
    #[new]
    #[pyo3(signature = (mass = 1.0, stiffness = 1.0))]
    fn new(mass: f64, stiffness: f64) -> PyResult<PyClassInitializer<Self>> {
        let (m, k) = (finite("mass", mass)?, finite("stiffness", stiffness)?);
        let s = sys::HarmonicOscillator::new(m, k).py_err()?;
        Ok(PyClassInitializer::from(System::new(SysKind::Harmonic(s)))
            .add_subclass(HarmonicOscillator))
    }
}

/// Simple pendulum L = m l² θ̇²/2 + m g l cos θ (D = 1).
#[pyclass(extends = System, frozen, module = "galerkin_vi.systems")]
pub struct Pendulum;

#[pymethods]
impl Pendulum {
    #[new]
    #[pyo3(signature = (length = 1.0, gravity = 1.0, mass = 1.0))]
    fn new(length: f64, gravity: f64, mass: f64) -> PyResult<PyClassInitializer<Self>> {
        let l = finite("length", length)?;
        let g = finite("gravity", gravity)?;
        let m = finite("mass", mass)?;
        let s = sys::Pendulum::new(l, g, m).py_err()?;
        Ok(PyClassInitializer::from(System::new(SysKind::Pendulum(s))).add_subclass(Pendulum))
    }
}

/// The Fermi–Pasta–Ulam chain of `springs` stiff springs of frequency `omega` in the
/// variables of Hairer, Lubich & Wanner (D = 2·springs: centres, then elongations); the
/// invariants are the energy, the oscillatory energy I and I₁ … I_m.
#[pyclass(extends = System, frozen, module = "galerkin_vi.systems")]
pub struct Fpu;

#[pymethods]
impl Fpu {
    #[new]
    #[pyo3(signature = (springs = 3, omega = 50.0))]
    fn new(springs: usize, omega: f64) -> PyResult<PyClassInitializer<Self>> {
        let omega = finite("omega", omega)?;
        let s = sys::Fpu::new(springs, omega).py_err()?;
        Ok(PyClassInitializer::from(System::new(SysKind::Fpu(s))).add_subclass(Fpu))
    }
}

/// Newtonian point masses in `dim` = 2 or 3 dimensions with gravitational constant `g`;
/// the configuration is body-major (x₀, y₀, x₁, y₁, …), momenta p = m v.
#[pyclass(extends = System, frozen, module = "galerkin_vi.systems")]
pub struct NBody;

#[pymethods]
impl NBody {
    #[new]
    #[pyo3(signature = (masses, dim = 2, g = 1.0))]
    fn new(masses: &Bound<'_, PyAny>, dim: usize, g: f64) -> PyResult<PyClassInitializer<Self>> {
        let masses = vector(masses, "masses", None)?;
        let g = finite("g", g)?;
        let s = sys::NBody::new(masses, g, dim).py_err()?;
        Ok(PyClassInitializer::from(System::new(SysKind::NBody(s))).add_subclass(NBody))
    }
}

/// A Lagrangian written as an expression in the coordinates, their velocities `x_dot` and
/// named parameters, e.g. `Expression("x_dot^2/2 - x^2/2", ["x"])`. Derivatives by automatic
/// differentiation; the energy p·v − L is the reported invariant. L may read the time `t`, and
/// `force=["-0.1*x_dot + cos(t)"]` (one expression per coordinate) adds a non-conservative
/// force by the discrete Lagrange–d'Alembert principle; the energy is then not an invariant
/// (see `Trajectory.energy_balance`).
#[pyclass(extends = System, frozen, module = "galerkin_vi.systems")]
pub struct Expression;

#[pymethods]
impl Expression {
    #[new]
    #[pyo3(signature = (lagrangian, coordinates, parameters = None, force = None))]
    fn new(
        lagrangian: &str,
        coordinates: Vec<String>,
        parameters: Option<BTreeMap<String, f64>>,
        force: Option<Vec<String>>,
    ) -> PyResult<PyClassInitializer<Self>> {
        let params: Vec<(String, f64)> = parameters.unwrap_or_default().into_iter().collect();
        for (name, value) in &params {
            finite(&format!("parameters['{name}']"), *value)?;
        }
        let coords: Vec<&str> = coordinates.iter().map(String::as_str).collect();
        let p: Vec<(&str, f64)> = params.iter().map(|(n, v)| (n.as_str(), *v)).collect();
        let mut s = ExpressionLagrangian::parse(lagrangian, &coords, &p).py_err()?;
        if let Some(force) = &force {
            let force: Vec<&str> = force.iter().map(String::as_str).collect();
            s = s.with_force(&force).py_err()?;
        }
        Ok(PyClassInitializer::from(System::new(SysKind::Expression(s))).add_subclass(Expression))
    }

    /// The Lagrangian's text (for a traced Python function, the text it was compiled from).
    #[getter]
    fn lagrangian(slf: &Bound<'_, Self>) -> String {
        match &*slf.as_super().get().kind {
            SysKind::Expression(e) => e.text().to_string(),
            _ => String::new(),
        }
    }

    /// The force expressions (one per coordinate), or None for a conservative system.
    #[getter]
    fn force(slf: &Bound<'_, Self>) -> Option<Vec<String>> {
        match &*slf.as_super().get().kind {
            SysKind::Expression(e) => e.force_expressions().map(<[String]>::to_vec),
            _ => None,
        }
    }

    /// A listing of the compiled tape the integrator evaluates (constants folded, common
    /// subexpressions shared). Two systems with equal listings and parameters evaluate L
    /// identically, bit for bit.
    #[getter]
    fn tape(slf: &Bound<'_, Self>) -> String {
        match &*slf.as_super().get().kind {
            SysKind::Expression(e) => format!("{:?}", e.tape()),
            _ => String::new(),
        }
    }

    /// Whether L was recognised as separable, ½ vᵀM v − V(q) with a constant positive-definite
    /// M (the integrator then uses its separable path).
    #[getter]
    fn is_separable(slf: &Bound<'_, Self>) -> bool {
        match &*slf.as_super().get().kind {
            SysKind::Expression(e) => e.is_separable(),
            _ => false,
        }
    }
}

/// Register the system classes.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<System>()?;
    m.add_class::<Kepler>()?;
    m.add_class::<HarmonicOscillator>()?;
    m.add_class::<Pendulum>()?;
    m.add_class::<Fpu>()?;
    m.add_class::<NBody>()?;
    m.add_class::<Expression>()?;
    Ok(())
}
