"""Dense output, coefficients, invariants and the geometric check."""

import numpy as np
import pytest

import galerkin_vi as gv


@pytest.fixture(scope="module")
def oscillator():
    # q(t) = cos t, p(t) = −sin t.
    gvi = gv.Integrator(n=12, h=1.0)
    return gvi.integrate(gv.systems.HarmonicOscillator(), [1.0], [0.0], 10)


def test_dense_output_follows_the_exact_solution(oscillator):
    t = np.linspace(0.0, 10.0, 401)
    q = oscillator.position_at(t)
    p = oscillator.momentum_at(t)
    assert q.shape == (401, 1) and p.shape == (401, 1)
    # n = 12, h = 1: the Galerkin curves are spectrally accurate (measured ~1e-10).
    assert np.abs(q[:, 0] - np.cos(t)).max() < 1e-8
    assert np.abs(p[:, 0] + np.sin(t)).max() < 1e-8
    # A scalar t gives one state; at step ends it is the step-end state.
    np.testing.assert_allclose(oscillator.position_at(3.0), oscillator.q[3], atol=1e-13)
    assert oscillator.position_at(2.5).shape == (1,)


def test_dense_output_outside_the_run_is_an_error(oscillator):
    with pytest.raises(gv.InvalidInputError):
        oscillator.position_at(11.5)
    with pytest.raises(gv.NonFiniteError, match="t"):
        oscillator.position_at(float("nan"))


def test_coefficients_shape_and_curve_ends(oscillator):
    c = oscillator.coefficients
    assert c.shape == (10, 12, 1)
    # Chebyshev–Lagrange: the first and last coefficients are the curve's end values.
    np.testing.assert_allclose(c[:, 0, 0], oscillator.q[:-1, 0], atol=1e-14)
    np.testing.assert_allclose(c[:, -1, 0], oscillator.q[1:, 0], atol=1e-12)


def test_invariants_and_check():
    traj = gv.run_scene("kepler", n=24, h=1.0, steps=30)
    inv = traj.invariants
    assert set(inv) == {"energy", "angular_momentum"}
    assert inv["energy"].shape == (31,)
    report = traj.check()
    # Symplectic to round-off and angular momentum conserved (discrete Noether).
    assert report["max_symplecticity_defect"] < 1e-9
    assert report["momentum_errors"]["angular_momentum"] < 1e-13
    assert report["max_energy_error"] == pytest.approx(
        np.abs(inv["energy"] - inv["energy"][0]).max(), rel=1e-12
    )


def test_symplectic_even_when_inaccurate():
    # Symplecticity is structural, not a by-product of accuracy: an under-resolved run
    # (n = 3, h = 3, a pendulum at large amplitude) has a large energy error, yet every step
    # Jacobian is symplectic to round-off. The two figures of check() are independent.
    traj = gv.Integrator(n=3, h=3.0).integrate(gv.systems.Pendulum(), [2.5], [0.0], 10)
    report = traj.check()
    assert report["max_symplecticity_defect"] < 1e-9
    assert report["max_energy_error"] > 1e-3


def test_expression_system_matches_builtin():
    expr = gv.systems.Expression("x_dot^2/2 - k*x^2/2", ["x"], {"k": 1.0})
    builtin = gv.systems.HarmonicOscillator()
    gvi = gv.Integrator(n=10, h=0.5)
    a = gvi.integrate(expr, [1.0], [0.0], 20)
    b = gvi.integrate(builtin, [1.0], [0.0], 20)
    np.testing.assert_allclose(a.q, b.q, atol=1e-12)
    assert expr.invariant_names == ["energy"]


def test_nbody_two_bodies_conserve_momentum():
    nb = gv.systems.NBody([1.0, 1.0], dim=2, g=1.0)
    q0 = [-0.5, 0.0, 0.5, 0.0]
    p0 = [0.0, -0.5, 0.0, 0.5]  # a bound orbit about the origin (total momentum 0)
    traj = gv.Integrator(n=16, h=0.25).integrate(nb, q0, p0, 40)
    total = traj.p[:, 0::2].sum(axis=1), traj.p[:, 1::2].sum(axis=1)
    assert np.abs(total[0]).max() < 1e-12 and np.abs(total[1]).max() < 1e-12


def test_crossings_on_the_curve_find_events_between_step_ends(oscillator):
    # q = cos t crosses 0 at π/2 + kπ: three times in [0, 10], located on the curves.
    down = oscillator.crossings(lambda t, q, p: q[0], direction="falling")
    assert [c["rising"] for c in down] == [False, False]
    times = [c["t"] for c in oscillator.crossings(lambda t, q, p: q[0])]
    np.testing.assert_allclose(times, np.pi / 2 + np.pi * np.arange(3), atol=1e-9)
    # q > 0.99 only within w = 0.1415 of t = 0 and t = 2π: the second visit lies inside the
    # step [6, 7], where the curve finds both crossings and the step ends alone
    # (samples_per_step=1) none; they see only the first, t = w, where q(1) < 0.99.
    level = lambda t, q, p: q[0] - 0.99
    w = np.arccos(0.99)
    found = oscillator.crossings(level)
    np.testing.assert_allclose([c["t"] for c in found], [w, 2 * np.pi - w, 2 * np.pi + w],
                               atol=1e-9)
    ends = oscillator.crossings(level, samples_per_step=1)
    np.testing.assert_allclose([c["t"] for c in ends], [w], atol=1e-9)
    assert found[1]["q"].shape == (1,) and found[1]["step"] == 6


def test_crossings_errors(oscillator):
    with pytest.raises(gv.InvalidInputError, match="direction"):
        oscillator.crossings(lambda t, q, p: q[0], direction="up")
    with pytest.raises(gv.InvalidInputError, match="callable"):
        oscillator.crossings(3.0)
    with pytest.raises(gv.InvalidInputError, match="samples_per_step"):
        oscillator.crossings(lambda t, q, p: q[0], samples_per_step=0)
    with pytest.raises(gv.NonFiniteError):
        oscillator.crossings(lambda t, q, p: float("nan"))

    def boom(t, q, p):
        raise ZeroDivisionError("from g")

    with pytest.raises(ZeroDivisionError, match="from g"):
        oscillator.crossings(boom)
