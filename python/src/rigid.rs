//! Rigid bodies from Python: a rigid-body scene (`rigid-body`, `heavy-top`, `pendulum-3d`, or a
//! scene file of type "rigid-body" | "heavy-top") runs on SO(3) by the Lie group integrator
//! ([`galerkin_vi::lie`]), as `gvi run` runs it, and returns a [`RigidBodyTrajectory`]:
//! orientations, body momenta, angular velocities, spatial angular momenta and energies as
//! numpy arrays, the errors against the elliptic-function solution where it exists (the free
//! body), and a geometric `check()`.

use crate::errors::{IntoPy, NonFiniteResultError};
use crate::interrupt::{Stop, interruptible};
use galerkin_vi::GviError;
use galerkin_vi::lie::body::RigidBody;
use galerkin_vi::lie::elliptic::FreeBodyExact;
use galerkin_vi::lie::integrator::{LieState, LieTrajectory};
use galerkin_vi::lie::so3;
use galerkin_vi::method::MethodSpec;
use galerkin_vi::solve::rigid_body_initial_state;
use galerkin_vi_lab::scene::{AnyRigidBody, BuiltScene};
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Steps integrated between two questions whether to stop (Ctrl-C). The Lie group integrator's
/// first guess of a step depends on the state alone, so a run made of chunks is the one-piece
/// run state for state.
const CHUNK: usize = 16;

/// Central-difference step of the symplecticity defect in canonical coordinates (the one
/// `gvi run` uses for its step-0 defect).
const DEFECT_DELTA: f64 = 1e-5;

/// Run `$body` with `$b` bound to the concrete rigid body.
macro_rules! with_body {
    ($body:expr, $b:ident => $e:expr) => {
        match $body {
            AnyRigidBody::Free($b) => $e,
            AnyRigidBody::Heavy($b) => $e,
        }
    };
}

/// The errors against the exact (elliptic-function) motion of a free body, per step end.
struct Reference {
    orientation: Vec<f64>,
    momentum: Vec<f64>,
}

/// A rigid-body run on SO(3): the orientation `R` (body to space), the body angular momentum
/// `mu`, the body angular velocity `omega`, the spatial angular momentum `angular_momentum`
/// (R μ), the `energy` and the orthogonality defect ‖RᵀR − I‖ at every step end (numpy
/// arrays, steps + 1 rows); for the free body also `orientation_error` (‖R − R_exact‖_F) and
/// `momentum_error` (max-norm of μ − μ_exact) against the elliptic-function solution, else
/// None.
#[pyclass(frozen, module = "galerkin_vi")]
pub struct RigidBodyTrajectory {
    body: AnyRigidBody,
    method: MethodSpec,
    traj: LieTrajectory,
    reference: Option<Reference>,
    name: String,
}

/// Integrate the rigid body of a built scene with its method, asking `stop` between chunks of
/// [`CHUNK`] steps. Errors: those of [`galerkin_vi::solve::solve_rigid_body`] (a
/// tolerance-driven method, the integrator's parameters, the initial state, a Newton failure),
/// a non-finite state, or [`GviError::Interrupted`].
fn integrate<B: RigidBody>(
    body: &B,
    scene: &BuiltScene,
    stop: &Stop,
) -> Result<LieTrajectory, GviError> {
    let method = &scene.method;
    method.require_fixed_n("the Lie group integrator (rigid bodies)")?;
    let gvi = method.lie_integrator()?;
    let (r0, mu0) = rigid_body_initial_state(&scene.initial)?;
    let t0 = scene.initial.t0;
    let steps = method.steps;
    let mut states = Vec::with_capacity(steps + 1);
    let mut iterations = Vec::with_capacity(steps);
    states.push(LieState { r: r0, mu: mu0 });
    while iterations.len() < steps {
        let k = iterations.len();
        if stop.requested() {
            return Err(GviError::Interrupted {
                step: k,
                t: t0 + k as f64 * method.h,
            });
        }
        let chunk = CHUNK.min(steps - k);
        let last = states[k];
        let part = gvi.integrate(body, t0 + k as f64 * method.h, &last.r, &last.mu, chunk)?;
        for (j, s) in part.states.iter().enumerate().skip(1) {
            let bad = s.r.iter().flatten().chain(&s.mu).find(|x| !x.is_finite());
            if let Some(&value) = bad {
                return Err(GviError::NonFiniteResult {
                    what: "the state (R, μ)".into(),
                    value,
                    step: k + j,
                    t: t0 + (k + j) as f64 * method.h,
                });
            }
        }
        states.extend_from_slice(&part.states[1..]);
        iterations.extend_from_slice(&part.iterations);
    }
    Ok(LieTrajectory {
        t0,
        h: method.h,
        states,
        iterations,
    })
}

/// The errors of a free body's run against its elliptic-function solution (none for a body
/// with a potential, or where the reference does not apply), as `gvi run` tabulates them.
fn reference<B: RigidBody>(body: &B, traj: &LieTrajectory) -> Option<Reference> {
    if body.has_potential() {
        return None;
    }
    let s0 = traj.states.first()?;
    let exact = FreeBodyExact::new(body.inertia(), &s0.r, &s0.mu).ok()?;
    let times: Vec<f64> = (0..traj.states.len()).map(|k| k as f64 * traj.h).collect();
    let orientations = exact.orientations(&times).ok()?;
    let mut orientation = Vec::with_capacity(times.len());
    let mut momentum = Vec::with_capacity(times.len());
    for ((s, r), &t) in traj.states.iter().zip(&orientations).zip(&times) {
        orientation.push(so3::distance(&s.r, r));
        let mu = exact.body_momentum(t);
        momentum.push((0..3).fold(0.0f64, |a, i| a.max((mu[i] - s.mu[i]).abs())));
    }
    Some(Reference {
        orientation,
        momentum,
    })
}

/// Run a built rigid-body scene from Python: with the GIL released, interruptible by Ctrl-C
/// between chunks of [`CHUNK`] steps.
pub fn run(
    py: Python<'_>,
    body: &AnyRigidBody,
    scene: &BuiltScene,
) -> PyResult<RigidBodyTrajectory> {
    let (traj, reference) = interruptible(py, |stop| {
        with_body!(body, b => integrate(b, scene, stop).map(|t| {
            let r = reference(b, &t);
            (t, r)
        }))
    })?
    .py_err()?;
    Ok(RigidBodyTrajectory {
        body: body.clone(),
        method: scene.method.clone(),
        traj,
        reference,
        name: scene.name.clone(),
    })
}

impl RigidBodyTrajectory {
    /// One row of 3 numbers per step end.
    fn rows3<'py>(
        &self,
        py: Python<'py>,
        f: impl Fn(&LieState) -> [f64; 3],
    ) -> Bound<'py, PyArray2<f64>> {
        let flat: Vec<f64> = self.traj.states.iter().flat_map(f).collect();
        Array2::from_shape_vec((self.traj.states.len(), 3), flat)
            .unwrap_or_else(|_| Array2::zeros((0, 3)))
            .into_pyarray(py)
    }

    /// One number per step end.
    fn column<'py>(
        &self,
        py: Python<'py>,
        f: impl Fn(&LieState) -> f64,
    ) -> Bound<'py, PyArray1<f64>> {
        Array1::from(self.traj.states.iter().map(f).collect::<Vec<_>>()).into_pyarray(py)
    }

    fn energy_of(&self, s: &LieState) -> f64 {
        with_body!(&self.body, b => b.energy(&s.r, &s.mu))
    }

    fn has_potential(&self) -> bool {
        with_body!(&self.body, b => b.has_potential())
    }
}

/// max_k |x_k − x_0|, or a `NonFiniteResultError` naming the first step where x is not finite.
fn max_change(what: &str, values: impl Iterator<Item = f64>, h: f64) -> PyResult<f64> {
    let mut first = None;
    let mut worst = 0.0f64;
    for (k, v) in values.enumerate() {
        if !v.is_finite() {
            return Err(NonFiniteResultError::new_err(format!(
                "check(): {what} is {v} at step {k} (t = {})",
                k as f64 * h
            )));
        }
        let x0 = *first.get_or_insert(v);
        worst = worst.max((v - x0).abs());
    }
    Ok(worst)
}

fn norm(x: &[f64; 3]) -> f64 {
    (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt()
}

#[pymethods]
impl RigidBodyTrajectory {
    /// Times t_k = t₀ + k h (steps + 1 of them).
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let (t0, h) = (self.traj.t0, self.traj.h);
        let t: Vec<f64> = (0..self.traj.states.len())
            .map(|k| t0 + k as f64 * h)
            .collect();
        Array1::from(t).into_pyarray(py)
    }

    /// Orientations R_k (body to space), shape (steps + 1, 3, 3).
    #[getter(R)]
    fn orientation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let flat: Vec<f64> = self
            .traj
            .states
            .iter()
            .flat_map(|s| s.r.iter().flatten().copied().collect::<Vec<_>>())
            .collect();
        Array3::from_shape_vec((self.traj.states.len(), 3, 3), flat)
            .unwrap_or_else(|_| Array3::zeros((0, 3, 3)))
            .into_pyarray(py)
    }

    /// Body angular momenta μ_k = 𝕀Ω_k, shape (steps + 1, 3).
    #[getter]
    fn mu<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.rows3(py, |s| s.mu)
    }

    /// Body angular velocities Ω_k = 𝕀⁻¹μ_k, shape (steps + 1, 3).
    #[getter]
    fn omega<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.rows3(
            py,
            |s| with_body!(&self.body, b => b.angular_velocity(&s.mu)),
        )
    }

    /// Spatial angular momenta L_k = R_k μ_k, shape (steps + 1, 3) (conserved for the free
    /// body; the heavy top conserves its vertical component).
    #[getter]
    fn angular_momentum<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.rows3(py, LieState::spatial_momentum)
    }

    /// Energies ½ μ·𝕀⁻¹μ + V(R) at the step ends, shape (steps + 1,).
    #[getter]
    fn energy<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |s| self.energy_of(s))
    }

    /// ‖R_kᵀR_k − I‖_F at the step ends, shape (steps + 1,).
    #[getter]
    fn orthogonality<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |s| so3::orthogonality_defect(&s.r))
    }

    /// ‖R_k − R_exact(t_k)‖_F against the elliptic-function solution (free body), or None.
    #[getter]
    fn orientation_error<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        let r = self.reference.as_ref()?;
        Some(r.orientation.clone().into_pyarray(py))
    }

    /// max_i |μ_k,i − μ_exact,i(t_k)| against the elliptic-function solution (free body), or
    /// None.
    #[getter]
    fn momentum_error<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        let r = self.reference.as_ref()?;
        Some(r.momentum.clone().into_pyarray(py))
    }

    /// The invariants at every step end, as a dict name → array: `energy`, the spatial
    /// angular momentum `lx`, `ly`, `lz` and `mu_norm` = |μ| (the Casimir of the free body's
    /// reduced motion; a heavy top conserves only energy and lz).
    #[getter]
    fn invariants<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        dict.set_item("energy", self.energy(py))?;
        for (i, name) in ["lx", "ly", "lz"].iter().enumerate() {
            dict.set_item(*name, self.column(py, |s| s.spatial_momentum()[i]))?;
        }
        dict.set_item("mu_norm", self.column(py, |s| norm(&s.mu)))?;
        Ok(dict)
    }

    /// Number of steps.
    #[getter]
    fn steps(&self) -> usize {
        self.traj.iterations.len()
    }

    /// Step size h.
    #[getter]
    fn h(&self) -> f64 {
        self.traj.h
    }

    /// Number of basis functions n.
    #[getter]
    fn n(&self) -> usize {
        self.method.n
    }

    /// The body: "rigid-body" (free) or "heavy-top".
    #[getter]
    fn system(&self) -> &'static str {
        with_body!(&self.body, b => b.name())
    }

    /// Newton iterations over the run.
    #[getter]
    fn newton_iterations(&self) -> usize {
        self.traj.iterations.iter().sum()
    }

    /// Geometric check of the run (a dict): `max_energy_error` (max |E_k − E_0|),
    /// `momentum_errors` (max |L_k − L_0| per component of the spatial angular momentum: lx,
    /// ly and lz for the free body, lz for a heavy top), `max_casimir_error` (max ||μ_k| −
    /// |μ_0||, free body; None with a potential), `max_orthogonality_defect` (‖RᵀR − I‖_F),
    /// `max_symplecticity_defect` (‖MᵀJM − J‖_F of the one-step map at every step's start
    /// state, M by central differences of step 1e-5 in canonical coordinates of T*SO(3), the
    /// measure `gvi run` reports for step 0; its floor is the differences' round-off, about
    /// 1e-10), and `max_orientation_error`, `max_momentum_error` against the elliptic-function
    /// solution (free body; else None). The symplecticity defect costs 12 extra steps per
    /// step; Ctrl-C stops it (`KeyboardInterrupt`).
    fn check<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let h = self.traj.h;
        let states = &self.traj.states;
        let energy = max_change("the energy", states.iter().map(|s| self.energy_of(s)), h)?;
        let free = !self.has_potential();
        let components: &[(usize, &str)] = if free {
            &[(0, "lx"), (1, "ly"), (2, "lz")]
        } else {
            &[(2, "lz")]
        };
        let momenta = PyDict::new(py);
        for &(i, name) in components {
            let what = format!("the angular momentum {name}");
            let e = max_change(&what, states.iter().map(|s| s.spatial_momentum()[i]), h)?;
            momenta.set_item(name, e)?;
        }
        let casimir = if free {
            Some(max_change("|μ|", states.iter().map(|s| norm(&s.mu)), h)?)
        } else {
            None
        };
        let orthogonality = states
            .iter()
            .map(|s| so3::orthogonality_defect(&s.r))
            .fold(0.0f64, f64::max);
        let method = &self.method;
        let body = &self.body;
        let steps = &states[..states.len().saturating_sub(1)];
        let defects = interruptible(py, |stop| {
            let gvi = method.lie_integrator()?;
            let mut out = Vec::with_capacity(steps.len());
            for (k, s) in steps.iter().enumerate() {
                if stop.requested() {
                    return Err(GviError::Interrupted {
                        step: k,
                        t: k as f64 * h,
                    });
                }
                let d = with_body!(body, b => {
                    galerkin_vi::lie::geometry::symplecticity_defect(
                        |x| gvi.step(b, x),
                        s,
                        DEFECT_DELTA,
                    )
                })?;
                out.push(d);
            }
            Ok(out)
        })?
        .py_err()?;
        let mut defect = 0.0f64;
        for (k, &d) in defects.iter().enumerate() {
            if !d.is_finite() {
                return Err(NonFiniteResultError::new_err(format!(
                    "check(): the symplecticity defect of step {k} (t = {}) is {d}",
                    self.traj.t0 + k as f64 * h
                )));
            }
            defect = defect.max(d);
        }
        let dict = PyDict::new(py);
        dict.set_item("max_energy_error", energy)?;
        dict.set_item("momentum_errors", momenta)?;
        dict.set_item("max_casimir_error", casimir)?;
        dict.set_item("max_orthogonality_defect", orthogonality)?;
        dict.set_item("max_symplecticity_defect", defect)?;
        let (orientation, momentum) = match &self.reference {
            Some(r) => (
                Some(r.orientation.iter().copied().fold(0.0f64, f64::max)),
                Some(r.momentum.iter().copied().fold(0.0f64, f64::max)),
            ),
            None => (None, None),
        };
        dict.set_item("max_orientation_error", orientation)?;
        dict.set_item("max_momentum_error", momentum)?;
        Ok(dict)
    }

    fn __len__(&self) -> usize {
        self.traj.states.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "<galerkin_vi RigidBodyTrajectory ({}, scene {}): {} steps of h = {}, n = {}>",
            self.system(),
            self.name,
            self.steps(),
            self.traj.h,
            self.method.n
        )
    }
}
