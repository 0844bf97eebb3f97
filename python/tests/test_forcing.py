"""Forced and time-dependent systems: Lagrange–d'Alembert forces and `t` in expressions, the
energy balance that replaces conservation, and event functions given as expressions."""

import numpy as np
import pytest

import galerkin_vi as gv

ZETA = 0.1


def damped_exact(t):
    wd = np.sqrt(1 - ZETA**2)
    return np.exp(-ZETA * t) * (np.cos(wd * t) + ZETA / wd * np.sin(wd * t))


@pytest.fixture(scope="module")
def damped():
    system = gv.systems.Expression("(x_dot^2 - x^2)/2", ["x"], {"zeta": ZETA},
                                   force=["-2*zeta*x_dot"])
    return gv.Integrator(n=12, h=1.0).integrate(system, [1.0], [0.0], 30)


def test_damped_oscillator_follows_its_exact_solution(damped):
    t = np.arange(31.0)
    # n = 12, h = 1: geometric convergence reaches round-off (measured 7e-16 from n = 8).
    assert np.abs(damped.q[:, 0] - damped_exact(t)).max() < 1e-13


def test_energy_balance_replaces_conservation(damped):
    balance = damped.energy_balance()
    assert set(balance) == {"t", "energy", "source", "defect"}
    # The energy falls by half, and the work of the force accounts for all of it.
    assert balance["energy"][0] - balance["energy"][-1] > 0.4
    assert np.abs(balance["defect"]).max() < 1e-13
    # A forced system reports no conserved energy.
    assert damped.invariants == {}


def test_time_in_the_lagrangian_equals_the_same_drive_as_a_force():
    driven = gv.systems.Expression("(x_dot^2 - x^2)/2 + x*0.5*cos(1.2*t)", ["x"])
    forced = gv.systems.Expression("(x_dot^2 - x^2)/2", ["x"], force=["0.5*cos(1.2*t)"])
    gvi = gv.Integrator(n=14, h=0.5)
    a = gvi.integrate(driven, [1.0], [0.0], 40)
    b = gvi.integrate(forced, [1.0], [0.0], 40)
    np.testing.assert_allclose(a.q, b.q, atol=1e-13)
    # Exact: x = (1 − a) cos t + a cos 1.2t with a = 0.5/(1 − 1.44).
    amp = 0.5 / (1 - 1.44)
    t = np.arange(41) * 0.5
    np.testing.assert_allclose(a.q[:, 0], (1 - amp) * np.cos(t) + amp * np.cos(1.2 * t),
                               atol=1e-12)


def test_event_functions_as_expressions(damped):
    # The zeros of x on the curve agree with the callable form.
    text = damped.crossings("x", direction="falling")
    call = damped.crossings(lambda t, q, p: q[0], direction="falling")
    assert len(text) == len(call) > 3
    np.testing.assert_allclose([c["t"] for c in text], [c["t"] for c in call], atol=1e-14)
    # Built-in systems name their coordinates q0, q1, … and momenta p_q0, …
    ho = gv.Integrator(n=12, h=1.0).integrate(gv.systems.HarmonicOscillator(), [1.0], [0.0],
                                              10)
    ups = ho.crossings("p_q0", direction="rising")
    np.testing.assert_allclose([c["t"] for c in ups], [np.pi, 3 * np.pi], atol=1e-9)


def test_bad_forces_and_events_are_typed_errors(damped):
    with pytest.raises(gv.GalerkinError):
        gv.systems.Expression("(x_dot^2 - x^2)/2", ["x"], force=["0", "1"])
    with pytest.raises(gv.GalerkinError, match="k"):
        gv.systems.Expression("(x_dot^2 - x^2)/2", ["x"], force=["-k*x_dot"])
    with pytest.raises(gv.GalerkinError, match="unknown"):
        damped.crossings("y")
