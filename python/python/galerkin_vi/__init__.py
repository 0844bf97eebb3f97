"""Spectral variational integrators (Hall & Leok) from Python.

The numerics are the Rust crate galerkin-vi; this package is a thin layer over it:

- ``run_scene(name_or_path, **overrides)`` runs a built-in scene ("kepler", "harmonic",
  "double-pendulum", ...) or a TOML scene file and returns a :class:`Trajectory`;
- ``Integrator(basis=..., n=..., quadrature=..., h=..., solver=...).integrate(system, q0, p0,
  steps)`` integrates a system of :mod:`galerkin_vi.systems`;
- ``integrate_many(system, q0s, p0s, steps)`` integrates many initial states in parallel
  (all cores, the GIL released);
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
    SceneError,
    ShapeError,
    SolverError,
    Trajectory,
    UnsupportedError,
    integrate_many,
    run_scene,
)
from . import systems

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
    "SceneError",
    "ShapeError",
    "SolverError",
    "Trajectory",
    "UnsupportedError",
    "integrate_many",
    "run_scene",
    "systems",
]
