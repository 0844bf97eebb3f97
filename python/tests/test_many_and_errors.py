"""integrate_many equals a loop of integrate; bad input raises typed exceptions naming the
argument."""

import numpy as np
import pytest

import galerkin_vi as gv


def test_integrate_many_equals_a_loop():
    k = gv.systems.Kepler()
    gvi = gv.Integrator(n=12, h=0.5)
    rng = np.random.default_rng(1)
    q0s = np.array([0.4, 0.0]) + 1e-2 * rng.standard_normal((6, 2))
    p0s = np.array([0.0, 2.0]) + 1e-2 * rng.standard_normal((6, 2))
    many = gv.integrate_many(k, q0s, p0s, 15, integrator=gvi)
    assert len(many) == 6
    for traj, q0, p0 in zip(many, q0s, p0s):
        one = gvi.integrate(k, q0, p0, 15)
        np.testing.assert_array_equal(traj.q, one.q)
        np.testing.assert_array_equal(traj.p, one.p)


def test_integrate_many_default_integrator():
    many = gv.integrate_many(gv.systems.HarmonicOscillator(), [[1.0], [0.5]], [[0.0], [0.0]], 5)
    assert [t.n for t in many] == [16, 16]
    np.testing.assert_allclose(many[1].q, 0.5 * many[0].q, rtol=1e-12, atol=1e-15)


def test_exception_hierarchy():
    for cls in (
        gv.InvalidInputError,
        gv.ShapeError,
        gv.NonFiniteError,
        gv.InvalidMethodError,
        gv.InvalidParameterError,
        gv.ExpressionError,
        gv.SceneError,
        gv.SolverError,
        gv.NonFiniteResultError,
        gv.UnsupportedError,
    ):
        assert issubclass(cls, gv.GalerkinError)
    assert issubclass(gv.ShapeError, gv.InvalidInputError)
    assert not issubclass(gv.SolverError, gv.InvalidInputError)


k = gv.systems.Kepler()
gvi = gv.Integrator(n=8, h=0.5)


@pytest.mark.parametrize(
    "call, exc, words",
    [
        (lambda: gvi.integrate(k, [0.4, 0, 1], [0, 2], 3), gv.ShapeError, "q0"),
        (lambda: gvi.integrate(k, [0.4, 0], [[0, 2]], 3), gv.ShapeError, "p0"),
        (lambda: gvi.integrate(k, [np.nan, 0], [0, 2], 3), gv.NonFiniteError, "q0[0]"),
        (lambda: gvi.integrate(k, [0.4, 0], [0, np.inf], 3), gv.NonFiniteError, "p0[1]"),
        (lambda: gvi.integrate(k, "ab", [0, 2], 3), gv.InvalidInputError, "q0"),
        (lambda: gvi.integrate(k, [0.4, 0], [0, 2], 0), gv.InvalidMethodError, "steps"),
        (lambda: gv.integrate_many(k, [[0.4, 0]], [[0, 2], [0, 2]], 3), gv.ShapeError, "q0s"),
        (lambda: gv.integrate_many(k, [[0.4, 0, 0]], [[0, 2, 0]], 3), gv.ShapeError, "q0s"),
        (lambda: gv.integrate_many(k, [[0.4, np.nan]], [[0, 2]], 3), gv.NonFiniteError, "q0s[0, 1]"),
        (lambda: gv.run_scene("no-such-scene"), gv.SceneError, "no-such-scene"),
        (lambda: gv.run_scene("kepler", basis="zzz"), gv.InvalidInputError, "basis"),
        (lambda: gv.run_scene("kepler", quadrature="zzz"), gv.InvalidInputError, "quadrature"),
        (lambda: gv.run_scene("kepler", solver="zzz"), gv.InvalidInputError, "solver"),
        (lambda: gv.run_scene("kepler", colour=1), gv.InvalidInputError, "colour"),
        (lambda: gv.run_scene("kepler", q0=[1.0]), gv.ShapeError, "q0"),
        (lambda: gv.run_scene("kepler", h=float("nan")), gv.NonFiniteError, "h"),
        (lambda: gv.run_scene("kepler", n=1), gv.InvalidMethodError, "n = 1"),
        (lambda: gv.run_scene("rigid-body", solver="exact"), gv.InvalidInputError, "solver"),
        (lambda: gv.Integrator(basis="zzz"), gv.InvalidInputError, "basis"),
        (lambda: gv.Integrator(h=-1.0), gv.InvalidMethodError, "h = -1"),
        (lambda: gv.systems.Kepler(mu=float("nan")), gv.NonFiniteError, "mu"),
        (lambda: gv.systems.HarmonicOscillator(mass=-1.0), gv.InvalidParameterError, "mass"),
        (lambda: gv.systems.Expression("x_dot^2/2 - y", ["x"]), gv.ExpressionError, "y"),
        (lambda: gv.systems.NBody([1.0, -1.0]), gv.InvalidParameterError, "mass"),
    ],
)
def test_bad_input_raises_a_typed_exception_naming_the_argument(call, exc, words):
    with pytest.raises(exc) as info:
        call()
    assert words in str(info.value)


def test_solver_failure_is_a_solver_error():
    # A pendulum over the top with a huge step: Newton cannot converge.
    gvi = gv.Integrator(n=4, h=50.0, solver="exact")
    with pytest.raises((gv.SolverError, gv.NonFiniteResultError)):
        gvi.integrate(gv.systems.Pendulum(), [3.0], [10.0], 50)
