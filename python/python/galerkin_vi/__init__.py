"""Spectral variational integrators (Hall & Leok) from Python.

The numerics are the Rust crate galerkin-vi; this package is a thin layer over it:

- ``run_scene(name_or_path, **options)`` runs a built-in scene ("kepler", "harmonic",
  "double-pendulum", "rigid-body", ...) or a TOML scene file with the method options of
  ``gvi run`` and returns a :class:`Trajectory` (a :class:`RigidBodyTrajectory` for a rigid
  body, run on SO(3) by the Lie group integrator);
- ``Integrator(basis=..., n=..., quadrature=..., h=..., solver=...).integrate(system, q0, p0,
  steps)`` integrates a system of :mod:`galerkin_vi.systems`;
- ``TimeTransform(monitor="sundman", alpha=1.5, energy_level=None, t_end=None, every=None)``
  is a Poincaré time transformation (variable physical steps that stay symplectic), given as
  ``Integrator(time_transform=...)`` or ``run_scene(..., time_transform=...)``; such runs
  (and the scenes "kepler-e099" and "pythagorean") return a
  :class:`TimeTransformedTrajectory` in physical time;
- ``integrate_many(system, q0s, p0s, steps)`` integrates many initial states in parallel
  (all cores, the GIL released);
- ``systems.from_function(L, coordinates)`` compiles a Python function ``L(q, v)`` written
  with ordinary arithmetic and ``sin``, ``cos``, ``exp``, ``sqrt``, ... of this package into
  an expression Lagrangian by tracing it once (``systems.from_sympy`` does the same for a
  sympy expression);
- every error is a subclass of :class:`GalerkinError` (work above the 4 GB memory limit is
  refused before it starts with :class:`MemoryLimitError`); Ctrl-C stops long calls with
  ``KeyboardInterrupt``.

>>> import galerkin_vi as gv
>>> traj = gv.run_scene("kepler", n=16, steps=10)
>>> traj.q.shape
(11, 2)
"""

from ._native import (
    ExpressionError,
    GalerkinError,
    Integrator,
    InvalidInputError,
    InvalidMethodError,
    InvalidParameterError,
    MemoryLimitError,
    NonFiniteError,
    NonFiniteResultError,
    RigidBodyTrajectory,
    SceneError,
    ShapeError,
    SolverError,
    TimeTransform,
    TimeTransformedTrajectory,
    Trajectory,
    UnsupportedError,
    integrate_many,
    run_scene,
)
from . import systems, trace
from .trace import atan2, cos, cosh, exp, log, pow, sin, sinh, sqrt, tan, tanh

#: π, as the expression grammar's ``pi`` (a float: traced, it prints as the same number).
pi = 3.141592653589793

__all__ = [
    "ExpressionError",
    "GalerkinError",
    "Integrator",
    "InvalidInputError",
    "InvalidMethodError",
    "InvalidParameterError",
    "MemoryLimitError",
    "NonFiniteError",
    "NonFiniteResultError",
    "RigidBodyTrajectory",
    "SceneError",
    "ShapeError",
    "SolverError",
    "TimeTransform",
    "TimeTransformedTrajectory",
    "Trajectory",
    "UnsupportedError",
    "atan2",
    "cos",
    "cosh",
    "exp",
    "integrate_many",
    "log",
    "pi",
    "pow",
    "run_scene",
    "sin",
    "sinh",
    "sqrt",
    "systems",
    "tan",
    "tanh",
    "trace",
]
