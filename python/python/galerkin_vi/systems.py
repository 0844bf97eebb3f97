"""Mechanical systems: the built-ins and Lagrangians written as expressions.

Every class derives from :class:`System` (``dim``, ``name``, ``invariant_names``,
``invariants(q, p)``).

- ``Kepler(mu=1.0)``: planar Kepler problem, D = 2;
- ``HarmonicOscillator(mass=1.0, stiffness=1.0)``: D = 1;
- ``Pendulum(length=1.0, gravity=1.0, mass=1.0)``: D = 1;
- ``Fpu(springs=3, omega=50.0)``: the Fermi–Pasta–Ulam chain (Hairer–Lubich–Wanner form),
  D = 2·springs;
- ``NBody(masses, dim=2, g=1.0)``: point masses, body-major coordinates, p = m v;
- ``Expression(lagrangian, coordinates, parameters=None, force=None)``: L(q, q̇) as an
  expression, e.g. ``Expression("x_dot^2/2 - x^2/2", ["x"])``;
- ``from_function(L, coordinates, parameters=None, force=None)``: a Python function
  ``L(q, v)`` (or ``L(q, v, t)``) traced once into an ``Expression`` (:mod:`galerkin_vi.trace`);
- ``from_sympy(expr, coordinates, velocities, parameters=None, t=None, force=None)``: a sympy
  expression converted into an ``Expression``.
"""

from ._native import Expression, Fpu, HarmonicOscillator, Kepler, NBody, Pendulum, System
from .trace import from_function, from_sympy

__all__ = [
    "Expression",
    "Fpu",
    "HarmonicOscillator",
    "Kepler",
    "NBody",
    "Pendulum",
    "System",
    "from_function",
    "from_sympy",
]
