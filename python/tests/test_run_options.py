"""run_scene takes every method option of `gvi run` (quadrature points: explicit, economical,
compact, collocation; basis, quadrature, solver; tol with control, ladder and auto_h), each equal to the
Integrator with the same method, and refuses bad values and combinations with typed
exceptions naming the option."""

import numpy as np
import pytest

import galerkin_vi as gv
from test_kepler import kepler_exact

KEPLER = gv.systems.Kepler(1.0)
Q0, P0 = [0.4, 0.0], [0.0, 2.0]


@pytest.mark.parametrize(
    "options, integrator",
    [
        (dict(quad_points=40), dict(quad_points=40)),
        (dict(economical=True), dict(quad_points=48)),
        (dict(compact=True), dict(quad_points=32)),
        (dict(economical=True), dict(economical=True)),
        (dict(compact=True), dict(compact=True)),
        (dict(collocation=True), dict(quad_points=31)),
        (dict(collocation=True), dict(collocation=True)),
    ],
)
def test_quadrature_points_equal_the_integrator(options, integrator):
    traj = gv.run_scene("kepler", steps=20, **options)
    gvi = gv.Integrator(n=32, h=2.0, basis="chebyshev", **integrator)
    again = gvi.integrate(KEPLER, Q0, P0, 20)
    np.testing.assert_array_equal(traj.q, again.q)
    np.testing.assert_array_equal(traj.p, again.p)


def test_economical_keeps_the_accuracy_and_compact_costs_accuracy_at_h2():
    """`QuadratureKind::economical_points`: at h = 2, n = 32, ⌈3n/2⌉ points give 4.40e-6
    against 4.41e-6 with 2n; `compact_points`: n points cost ~100× the error there."""
    err = {}
    for name, options in [("paper", {}), ("econ", dict(economical=True)),
                          ("compact", dict(compact=True))]:
        with np.errstate(all="ignore"):
            traj = gv.run_scene("kepler", **options)
        err[name] = np.abs(traj.q - kepler_exact(traj.t)).max()
    assert err["paper"] == pytest.approx(4.409e-6, rel=1e-3)
    assert err["econ"] == pytest.approx(4.40e-6, rel=1e-2)
    assert 30 * err["paper"] < err["compact"] < 1e-3
    assert gv.Integrator(n=32, economical=True).quad_points == 48
    assert gv.Integrator(n=13, compact=True).quad_points == 13
    assert gv.Integrator(n=13, collocation=True).quad_points == 12


def test_one_way_of_choosing_the_integrators_quadrature_points():
    with pytest.raises(gv.InvalidInputError, match="give one way"):
        gv.Integrator(n=13, compact=True, collocation=True)
    with pytest.raises(gv.InvalidInputError, match="give one way"):
        gv.Integrator(n=13, quad_points=20, collocation=True)


def test_basis_quadrature_and_solver_options():
    a = gv.run_scene("kepler", steps=10, n=12, h=0.5, basis="legendre", solver="exact")
    b = gv.Integrator(n=12, h=0.5, basis="legendre", solver="exact").integrate(KEPLER, Q0, P0, 10)
    np.testing.assert_array_equal(a.q, b.q)
    c = gv.run_scene("kepler", steps=10, n=12, h=0.5, quadrature="gauss-lobatto")
    d = gv.Integrator(n=12, h=0.5, quadrature="gauss-lobatto").integrate(KEPLER, Q0, P0, 10)
    np.testing.assert_array_equal(c.q, d.q)


def test_tolerance_options():
    traj = gv.run_scene("kepler", tol=1e-6, steps=50)
    err = np.abs(traj.q - kepler_exact(traj.t)).max()
    assert err < 1e-5
    ladder = gv.run_scene("kepler", tol=1e-6, steps=50, ladder=[8, 16, 24, 32, 48],
                          control="indicator")
    assert np.abs(ladder.q - kepler_exact(ladder.t)).max() < 1e-4
    auto = gv.run_scene("kepler", tol=1e-6, auto_h=True)
    # auto_h keeps the horizon h·steps = 200 and chooses h from the tolerance.
    assert auto.t[-1] == pytest.approx(200.0, rel=1e-12)
    assert auto.h != 2.0
    assert np.abs(auto.q - kepler_exact(auto.t)).max() < 1e-4


@pytest.mark.parametrize(
    "options, exc, words",
    [
        (dict(tol=1e-6, n=16), gv.InvalidInputError, "n: with tol"),
        (dict(tol=1e-6, economical=True), gv.InvalidInputError, "economical: with tol"),
        (dict(tol=1e-6, quad_points=20), gv.InvalidInputError, "quad_points: with tol"),
        (dict(ladder=[8, 16]), gv.InvalidInputError, "ladder: only a tolerance-driven"),
        (dict(control="indicator"), gv.InvalidInputError, "control"),
        (dict(auto_h=True), gv.InvalidInputError, "auto_h"),
        (dict(economical=True, compact=True), gv.InvalidInputError, "economical and compact"),
        (dict(compact=True, collocation=True), gv.InvalidInputError, "compact and collocation"),
        (dict(tol=1e-6, collocation=True), gv.InvalidInputError, "collocation: with tol"),
        (dict(economical="yes"), gv.InvalidInputError, "economical: expected True or False"),
        (dict(quad_points=2.5), gv.InvalidInputError, "quad_points"),
        (dict(quad_points=3), gv.InvalidMethodError, "quadrature"),
        (dict(tol=1e-6, control="zzz"), gv.InvalidInputError, "zzz"),
        (dict(tol=1e-6, ladder="8,16"), gv.InvalidInputError, "ladder"),
        (dict(tol=float("nan")), gv.NonFiniteError, "tol"),
        (dict(retraction="exp"), gv.InvalidInputError, "not a rigid-body scene"),
        (dict(steps=10**9), gv.InvalidMethodError, "steps"),
        (dict(colour=1), gv.InvalidInputError, "unknown option 'colour'"),
    ],
)
def test_bad_options_raise_typed_exceptions(options, exc, words):
    with pytest.raises(exc) as info:
        gv.run_scene("kepler", **options)
    assert words in str(info.value)
