"""Poincaré time transformations from Python (docs/guide/time-transformations.md): the scenes
kepler-e099 and pythagorean through `run_scene`, `Integrator(time_transform=...)`, rows in
physical time, each accuracy claim against a negative control, and typed errors for bad
input."""

import math
import warnings

import numpy as np
import pytest

import galerkin_vi as gv

# kepler-e099: a = 1, mu = 1 (period 2π), from periapsis r_p = 0.01 on the +x axis.
E = 0.99
Q0 = [0.01, 0.0]
P0 = [0.0, 14.106735979665885]  # sqrt((1 + e) / (1 − e)), as the scene writes it
H_SCENE = 1.9077256080879920e-4  # the scene's fictitious step: 60 steps per orbit
T_END = 200.0 * math.pi  # 100 orbits


def kepler_exact(t, e=E):
    """The exact position at times t (a = 1, mu = 1, periapsis at t = 0): Kepler's equation
    E − e sin E = t by Newton from E = π (monotone convergence for every e < 1)."""
    m = np.mod(np.asarray(t, dtype=float), 2.0 * np.pi)
    ecc = np.full_like(m, np.pi)
    for _ in range(60):
        ecc -= (ecc - e * np.sin(ecc) - m) / (1.0 - e * np.cos(ecc))
    return np.stack([np.cos(ecc) - e, math.sqrt(1.0 - e * e) * np.sin(ecc)], axis=-1)


@pytest.fixture(scope="module")
def e099():
    # Rows at 16 physical times per orbit, each located on t(s).
    return gv.run_scene("kepler-e099", every=2.0 * math.pi / 16.0)


def test_kepler_e099_runs_in_physical_time_to_1e_11(e099):
    assert isinstance(e099, gv.TimeTransformedTrajectory)
    assert len(e099) == 1601 and e099.q.shape == (1601, 2) and e099.p.shape == (1601, 2)
    # The requested times are hit exactly (located on t(s), not interpolated).
    np.testing.assert_array_equal(e099.t, np.arange(1601) * (2.0 * math.pi / 16.0))
    # 6000 fictitious steps make 100 orbits up to round-off: whether t(s) reaches t_end at
    # the end of step 6000 or a hair into step 6001 depends on the last bits of t(s).
    assert e099.summary["t"] == T_END and e099.steps in (6000, 6001)
    err = np.abs(e099.q - kepler_exact(e099.t)).max()
    # Measured 2.4e-12 (n = 12, 60 fictitious steps per orbit; 1.1e-11 with the Newton
    # matrix summed in another order: the error is at the round-off floor of the phase).
    assert err < 3e-11
    # The run's own column is against the orbit with elements computed from the state, this
    # against a = 1, e = 0.99: the two exact solutions differ by ~1e-12 after 100 orbits.
    assert e099.position_error.max() == pytest.approx(err, abs=1e-12)
    energy = e099.invariants["energy"]
    assert np.abs(energy + 0.5).max() < 1e-11  # measured 2.9e-12 (5.4e-12 before the Newton-matrix change)
    # The physical steps follow the monitor: from Δs at periapsis to ~2800 Δs at apoapsis.
    assert e099.summary["min_step"] == pytest.approx(1.93e-4, rel=1e-2)
    assert e099.summary["max_step"] == pytest.approx(0.531, rel=1e-2)


def test_same_step_count_without_the_transformation_loses_the_orbit(e099):
    """Negative control: the fixed physical step of the same n and step count (60 steps per
    orbit, 6000 steps) does not resolve the periapsis passage: the orbit is lost (energy
    +2.48 instead of −0.5, measured) and the position error is O(1). (At h = T/6001 Newton
    fails outright at the first periapsis.)"""
    steps = 6000
    gvi = gv.Integrator(n=12, h=2.0 * math.pi / 60.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fixed = gvi.integrate(gv.systems.Kepler(), Q0, P0, steps)
    err = np.abs(fixed.q - kepler_exact(fixed.t)).max()
    assert err > 0.5
    assert err > 1e9 * np.abs(e099.q - kepler_exact(e099.t)).max()
    assert abs(fixed.invariants["energy"][-1] + 0.5) > 1.0


def test_integrator_with_a_time_transform_is_the_scene_bit_for_bit(e099):
    tt = gv.TimeTransform("sundman", alpha=1.5, t_end=T_END, every=2.0 * math.pi / 16.0)
    gvi = gv.Integrator(n=12, h=H_SCENE, time_transform=tt)
    assert gvi.time_transform.monitor == "sundman" and gvi.time_transform.t_end == T_END
    run = gvi.integrate(gv.systems.Kepler(), Q0, P0, 20000)
    np.testing.assert_array_equal(run.q, e099.q)
    np.testing.assert_array_equal(run.p, e099.p)
    np.testing.assert_array_equal(run.t, e099.t)
    # A monitor name is TimeTransform(name) with the defaults; on run_scene it replaces the
    # scene's monitor and keeps its t_end.
    named = gv.run_scene("kepler-e099", time_transform="radius", steps=20000)
    assert named.summary["t"] == T_END


def test_rows_at_step_ends_carry_fictitious_time_and_physical_steps():
    run = gv.run_scene("kepler-e099", t_end=2.0 * math.pi)
    # 60 fictitious steps make one orbit, up to round-off in t(s) (see above).
    assert run.step[0] == 0 and run.step[-1] == run.steps and run.steps in (60, 61)
    # Fixed fictitious steps; the last ends where t(s) = t_end, located on its curve (τ = 1
    # up to round-off, or a hair into a 61st step: the located zero, not the step end).
    np.testing.assert_allclose(np.diff(run.s)[:-1], H_SCENE, rtol=1e-12)
    assert 0.0 < np.diff(run.s)[-1] <= H_SCENE * (1 + 1e-9)
    # dt is the physical length of the step ending at the row: the increments of t (the
    # last row: the length of the step holding t_end).
    np.testing.assert_allclose(run.dt[1:-1], np.diff(run.t)[:-1], rtol=1e-9, atol=0)


@pytest.fixture(scope="module")
def pythagorean():
    # Through the first close encounters (t ≈ 1.9), 1.7 s.
    return gv.run_scene("pythagorean", t_end=5.0)


def test_pythagorean_through_its_first_encounters(pythagorean):
    run = pythagorean
    assert run.dim == 6 and run.t[-1] == 5.0
    # Physical steps from 1e-2 down to ~2e-6 in the encounter, at a fixed fictitious step.
    assert run.summary["max_step"] > 5e-3 and run.summary["min_step"] < 1e-5
    # Measured 1.46e-12 relative energy error to t = 5.
    assert run.summary["max_relative_energy_error"] < 1e-11
    # The pair-distance monitor is translation and rotation invariant: the momentum maps
    # are conserved to round-off (discrete Noether) at the step ends (measured ≤ 2.2e-14). The
    # last row, t_end located inside a step, is a state on the Galerkin curve, where the
    # discrete Noether theorem says nothing (measured 1.1e-12 there).
    inv = run.invariants
    for name in ("px", "py", "angular_momentum"):
        assert np.abs(inv[name][:-1] - inv[name][0]).max() < 1e-13, name


def test_the_kinked_minimum_loses_orders_of_magnitude_in_energy(pythagorean):
    """Negative control: the plain minimum of the pair distances has a kink where the
    closest pair changes; the same step loses orders of magnitude of energy accuracy
    (measured to t = 5: 1.8e-6 relative, against 1.46e-12 with the smooth minimum)."""
    kinked = gv.run_scene("pythagorean", t_end=5.0, time_transform="min-distance")
    smooth = pythagorean.summary["max_relative_energy_error"]
    assert kinked.summary["max_relative_energy_error"] > 1e4 * smooth


def test_bad_time_transforms_are_typed_errors():
    with pytest.raises(gv.NonFiniteError, match="energy_level"):
        gv.TimeTransform(energy_level=float("nan"))
    with pytest.raises(gv.NonFiniteError, match="energy_level"):
        gv.run_scene("kepler-e099", energy_level=float("inf"))
    with pytest.raises(gv.NonFiniteError, match="alpha"):
        gv.TimeTransform(alpha=float("inf"))
    with pytest.raises(gv.InvalidParameterError, match="every"):
        gv.TimeTransform(every=-1.0)
    with pytest.raises(gv.InvalidInputError, match="monitor"):
        gv.TimeTransform("nearest")
    with pytest.raises(gv.InvalidInputError, match="time_transform"):
        gv.Integrator(time_transform=3)
    # A monitor that is not positive at the start: (r/r_p)^400 underflows to 0 at r = 0.01,
    # and r^-400 overflows.
    with pytest.raises(gv.InvalidParameterError, match="finite and positive"):
        gv.run_scene("kepler-e099", alpha=400.0)
    with pytest.raises(gv.InvalidParameterError, match="finite and positive"):
        gv.run_scene("kepler-e099", alpha=-400.0)
    # A monitor that does not fit the system.
    with pytest.raises(gv.UnsupportedError, match="radius"):
        gv.run_scene("pythagorean", time_transform="radius")
    nbody = gv.systems.NBody([1.0, 1.0])
    with pytest.raises(gv.UnsupportedError, match="radius"):
        gv.Integrator(time_transform="radius").integrate(
            nbody, [1.0, 0.0, -1.0, 0.0], [0.0, 0.5, 0.0, -0.5], 10
        )
    # Options that only a time-transformed run uses, and tol with one.
    with pytest.raises(gv.InvalidInputError, match="alpha"):
        gv.run_scene("kepler", alpha=1.0)
    with pytest.raises(gv.InvalidInputError, match="tol"):
        gv.run_scene("kepler-e099", tol=1e-8)
    with pytest.raises(gv.UnsupportedError, match="integrate_many"):
        gv.integrate_many(
            gv.systems.Kepler(), [Q0], [P0], 10, gv.Integrator(time_transform="radius")
        )
    # Fewer fictitious steps than t_end needs: refused, not a silently short run.
    with pytest.raises(gv.InvalidMethodError, match="max_steps"):
        gv.run_scene("kepler-e099", steps=100)
