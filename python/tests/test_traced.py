"""Lagrangians written as Python functions (traced once into the expression tape) and as
sympy expressions: the same tape, hence bit-identical trajectories, as the expression string;
usable wherever an Expression is; clear errors for what one trace cannot record."""

import math

import numpy as np
import pytest

import galerkin_vi as gv

HH_TEXT = "(x_dot^2 + y_dot^2)/2 - (x^2 + y^2)/2 - lam*(x^2*y - y^3/3)"


def henon_heiles(q, v, lam):
    x, y = q
    xd, yd = v
    return (xd**2 + yd**2) / 2 - (x**2 + y**2) / 2 - lam * (x**2 * y - y**3 / 3)


def test_traced_function_compiles_to_the_tape_of_the_string():
    traced = gv.systems.from_function(henon_heiles, ["x", "y"], {"lam": 1.0})
    text = gv.systems.Expression(HH_TEXT, ["x", "y"], {"lam": 1.0})
    assert isinstance(traced, gv.systems.Expression)
    assert traced.tape == text.tape
    assert traced.is_separable and text.is_separable
    assert traced.lagrangian == "(x_dot^2 + y_dot^2)/2 - (x^2 + y^2)/2 - lam*(x^2*y - y^3/3)"


def test_traced_and_string_give_bit_identical_trajectories():
    traced = gv.systems.from_function(henon_heiles, ["x", "y"], {"lam": 1.0})
    text = gv.systems.Expression(HH_TEXT, ["x", "y"], {"lam": 1.0})
    gvi = gv.Integrator(n=16, h=1.0)
    a = gvi.integrate(traced, [0.0, 0.1], [0.35, 0.0], 200)
    b = gvi.integrate(text, [0.0, 0.1], [0.35, 0.0], 200)
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.p, b.p)
    np.testing.assert_array_equal(a.coefficients, b.coefficients)
    # The scene's measured energy error (docs/guide/expression-lagrangians.md: 3.6e-16).
    assert a.check()["max_energy_error"] < 1e-14
    many = gv.integrate_many(traced, [[0.0, 0.1], [0.0, 0.1]], [[0.35, 0.0]] * 2, 200, gvi)
    np.testing.assert_array_equal(many[1].q, b.q)


def test_the_double_pendulum_traced_matches_its_scene_run():
    """The built-in double-pendulum scene's Lagrangian, written in Python with gv.cos: the
    trajectory is the scene's, bit for bit (the tapes are the same)."""
    m1 = m2 = l1 = l2 = g = 1.0

    def lagrangian(q, v):
        a, b = q
        ad, bd = v
        return (
            (m1 + m2) * l1**2 * ad**2 / 2
            + m2 * l2**2 * bd**2 / 2
            + m2 * l1 * l2 * ad * bd * gv.cos(a - b)
            + (m1 + m2) * g * l1 * gv.cos(a)
            + m2 * g * l2 * gv.cos(b)
        )

    traced = gv.systems.from_function(lagrangian, ["a", "b"])
    assert "cos(a - b)" in traced.lagrangian
    traj = gv.Integrator(n=16, h=0.5).integrate(traced, [1.0, 0.5], [0.0, 0.0], 40)
    e = traj.invariants["energy"]
    assert np.abs(e - e[0]).max() < 1e-9


def test_time_parameters_force_and_numpy_ufuncs():
    def lagrangian(q, v, t, k):
        return v[0] ** 2 / 2 - k * q[0] ** 2 / 2 + q[0] * np.cos(t)

    traced = gv.systems.from_function(
        lagrangian, ["x"], {"k": 2.0}, force=lambda q, v: [-0.1 * v[0]]
    )
    assert traced.lagrangian == "x_dot^2/2 - k*x^2/2 + x*cos(t)"
    assert traced.force == ["-0.1*x_dot"]
    text = gv.systems.Expression(
        "x_dot^2/2 - k*x^2/2 + x*cos(t)", ["x"], {"k": 2.0}, force=["-0.1*x_dot"]
    )
    gvi = gv.Integrator(n=8, h=0.25)
    a = gvi.integrate(traced, [1.0], [0.0], 80)
    b = gvi.integrate(text, [1.0], [0.0], 80)
    np.testing.assert_array_equal(a.q, b.q)
    # The forced, time-dependent run has an energy balance instead of an invariant.
    assert np.abs(a.energy_balance()["defect"]).max() < 1e-10


def test_coordinate_count_and_grouping_follow_python():
    def lagrangian(q, v):
        return v[0] ** 2 / 2 - (q[0] - (q[0] - 1)) * 2 ** -q[0] + (-q[0]) ** 2 / 8 - abs(q[0])

    sys = gv.systems.from_function(lagrangian, 1)
    assert sys.lagrangian == "q0_dot^2/2 - (q0 - (q0 - 1))*2^(-q0) + (-q0)^2/8 - abs(q0)"
    # The value Python computes for numbers (the tree is Python's): at v = 0 (p = 0) the
    # energy p·v − L is −L(q, 0).
    for x in (0.3, -1.7):
        energy = sys.invariants([x], [0.0])["energy"]
        assert energy == pytest.approx(-lagrangian([x], [0.0]), rel=1e-15, abs=1e-15)


@pytest.mark.parametrize(
    "body, words",
    [
        (lambda q, v: v[0] ** 2 / 2 - (q[0] if q[0] > 0 else -q[0]), "no truth value"),
        (lambda q, v: v[0] ** 2 / 2 - math.sin(q[0]), "gv.sin"),
        (lambda q, v: v[0] ** 2 / 2 - float(q[0]), "cannot become a float"),
        (lambda q, v: v[0] ** 2 / 2 - np.arcsin(q[0]), "numpy.arcsin"),
        (lambda q, v: v[0] ** 2 / 2 - q[0] // 2, "floor"),
        (lambda q, v: [v[0]], "scalar"),
        (lambda q, v: v[0] ** 2 / 2 + "x", "str"),
    ],
)
def test_what_one_trace_cannot_record_is_a_type_error(body, words):
    with pytest.raises(TypeError) as info:
        gv.systems.from_function(body, ["x"])
    assert words in str(info.value)


def test_expression_errors_of_the_traced_text_are_typed():
    with pytest.raises(gv.ExpressionError, match="velocity"):
        gv.systems.from_function(lambda q, v: q[0] ** 2, ["x"])
    with pytest.raises(gv.NonFiniteError):
        gv.systems.from_function(lambda q, v: v[0] ** 2 * float("inf"), ["x"])
    with pytest.raises(TypeError, match="extra"):
        gv.systems.from_function(lambda q, v, t, extra: v[0] ** 2, ["x"])


def test_package_functions_take_numbers_too():
    assert gv.sin(0.5) == np.sin(0.5)
    np.testing.assert_array_equal(gv.exp(np.array([0.0, 1.0])), np.exp([0.0, 1.0]))
    assert gv.atan2(1.0, 1.0) == np.arctan2(1.0, 1.0)


def test_sympy_expression_compiles_to_the_same_tape():
    sympy = pytest.importorskip("sympy")
    x, y, xd, yd, lam = sympy.symbols("x y x_dot y_dot lam")
    expr = (xd**2 + yd**2) / 2 - (x**2 + y**2) / 2 - lam * (x**2 * y - y**3 / 3)
    sys = gv.systems.from_sympy(expr, [x, y], [xd, yd], {lam: 1.0})
    text = gv.systems.Expression(HH_TEXT, ["x", "y"], {"lam": 1.0})
    gvi = gv.Integrator(n=16, h=1.0)
    a = gvi.integrate(sys, [0.0, 0.1], [0.35, 0.0], 200)
    b = gvi.integrate(text, [0.0, 0.1], [0.35, 0.0], 200)
    # sympy reorders sums and products, so equal to round-off rather than bit for bit.
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-12)
    assert a.check()["max_energy_error"] < 1e-14
    # A pendulum with sympy functions and pi; dynamicsymbols-style coordinates.
    t = sympy.Symbol("t")
    th = sympy.Function("th")(t)
    pend = sympy.Derivative(th, t) ** 2 / 2 + sympy.cos(th) + 0 * sympy.pi
    sys = gv.systems.from_sympy(pend, [th], [sympy.Derivative(th, t)], t=t)
    assert "cos(th)" in sys.lagrangian
    with pytest.raises(gv.ExpressionError, match="not a coordinate"):
        gv.systems.from_sympy(xd**2 / 2 - y, [x], [xd])
    with pytest.raises(gv.ExpressionError, match="no counterpart"):
        gv.systems.from_sympy(xd**2 / 2 - sympy.besselj(0, x), [x], [xd])


def test_numpy_arrays_of_traced_values():
    """np.array(q) of traced values: numpy's sums, products and ufuncs trace element by
    element (numpy scalars are numbers)."""
    sys = gv.systems.from_function(
        lambda q, v: np.float64(0.5) * np.sum(np.array(v) ** 2) - np.sum(np.cos(np.array(q))),
        ["a", "b"],
    )
    assert sys.lagrangian == "0.5*(a_dot^2 + b_dot^2) - (cos(a) + cos(b))"
    text = gv.systems.Expression("0.5*(a_dot^2 + b_dot^2) - (cos(a) + cos(b))", ["a", "b"])
    assert sys.tape == text.tape
