"""Rigid bodies from Python: run_scene runs them on SO(3) by the Lie group integrator, as
`gvi run` does, state for state; the free body against its elliptic-function solution and
its conserved quantities, the heavy top's energy and vertical angular momentum."""

import os
import pathlib
import subprocess

import numpy as np
import pytest

import galerkin_vi as gv


def gvi_binary(repo):
    """The gvi binary CI builds with the README's main command (or $GVI_BIN)."""
    given = os.environ.get("GVI_BIN")
    if given:
        return pathlib.Path(given)
    return repo / "target" / "release" / "gvi"


def test_free_body_against_the_exact_solution():
    traj = gv.run_scene("rigid-body")
    assert isinstance(traj, gv.RigidBodyTrajectory)
    assert traj.system == "rigid-body" and traj.steps == 16 and traj.n == 16
    assert traj.R.shape == (17, 3, 3) and traj.mu.shape == (17, 3)
    assert traj.omega.shape == (17, 3) and traj.angular_momentum.shape == (17, 3)
    np.testing.assert_allclose(traj.t, 1.7278907507449373 * np.arange(17), rtol=1e-15)
    # `gvi run rigid-body`: max position (orientation) error at step ends 6.036e-14.
    assert traj.orientation_error.max() < 1e-12
    assert traj.momentum_error.max() < 1e-12
    np.testing.assert_allclose(traj.omega, traj.mu / [1.0, 2.0, 3.0], rtol=1e-15)
    c = traj.check()
    # Conserved to round-off: energy, spatial angular momentum, the Casimir |μ|, RᵀR = I.
    assert c["max_energy_error"] < 1e-14
    assert max(c["momentum_errors"].values()) < 1e-14
    assert set(c["momentum_errors"]) == {"lx", "ly", "lz"}
    assert c["max_casimir_error"] < 1e-14
    assert c["max_orthogonality_defect"] < 1e-14
    # The finite-difference defect of every step's map (floor ~1e-10, see check()).
    assert c["max_symplecticity_defect"] < 1e-8
    assert c["max_orientation_error"] == traj.orientation_error.max()
    inv = traj.invariants
    np.testing.assert_allclose(inv["mu_norm"], np.linalg.norm(traj.mu, axis=1), rtol=1e-15)
    assert abs(inv["mu_norm"][0] ** 2 - 10.16) < 1e-12


def test_heavy_top_conserves_energy_and_vertical_momentum():
    traj = gv.run_scene("heavy-top", steps=50)
    assert traj.system == "heavy-top" and traj.orientation_error is None
    c = traj.check()
    assert set(c["momentum_errors"]) == {"lz"} and c["max_casimir_error"] is None
    # `gvi run heavy-top` (200 steps): energy 1.208e-13, lz 1.599e-14.
    assert c["max_energy_error"] < 1e-12
    assert c["momentum_errors"]["lz"] < 1e-13
    # The horizontal components are not conserved (gravity's torque is horizontal).
    assert np.ptp(traj.angular_momentum[:, 0]) > 1e-2


def test_rigid_body_options():
    exp = gv.run_scene("rigid-body", steps=4)
    cay = gv.run_scene("rigid-body", steps=4, retraction="cayley")
    assert 0 < np.abs(exp.R - cay.R).max() < 1e-10
    econ = gv.run_scene("rigid-body", steps=4, n=12, economical=True, basis="chebyshev")
    assert econ.n == 12 and econ.orientation_error.max() < 1e-6
    for bad, exc, words in [
        (dict(solver="exact"), gv.InvalidInputError, "no stage solver"),
        (dict(retraction="zzz"), gv.InvalidInputError, "zzz"),
        (dict(tol=1e-8), gv.UnsupportedError, "fixed n"),
        (dict(q0=[0.0, 0.0]), gv.ShapeError, "q"),
        (dict(n=1), gv.InvalidMethodError, "n"),
    ]:
        with pytest.raises(exc, match=words):
            gv.run_scene("rigid-body", **bad)
    with pytest.raises(gv.InvalidInputError, match="retraction"):
        gv.run_scene("kepler", retraction="cayley")


@pytest.mark.parametrize("scene", ["rigid-body", "heavy-top"])
def test_states_equal_the_cli_csv(repo, tmp_path, scene):
    gvi = gvi_binary(repo)
    if not gvi.exists():
        pytest.skip(f"{gvi} not built (CI builds it with the README's main command)")
    csv = tmp_path / f"{scene}.csv"
    subprocess.run(
        [str(gvi), "run", scene, "--steps", "40", "--output", str(csv)],
        check=True,
        capture_output=True,
    )
    table = np.genfromtxt(csv, delimiter=",", names=True)
    traj = gv.run_scene(scene, steps=40)
    # The CSV prints shortest round-trip floats: the same numbers, bit for bit.
    np.testing.assert_array_equal(traj.t, table["t"])
    for k in range(9):
        np.testing.assert_array_equal(traj.R[:, k // 3, k % 3], table[f"r{k // 3}{k % 3}"])
    for i in range(3):
        np.testing.assert_array_equal(traj.mu[:, i], table[f"mu{i}"])
        np.testing.assert_array_equal(traj.omega[:, i], table[f"w{i}"])
        name = ("lx", "ly", "lz")[i]
        np.testing.assert_array_equal(traj.angular_momentum[:, i], table[name])
    np.testing.assert_array_equal(traj.energy, table["energy"])
    np.testing.assert_array_equal(traj.orthogonality, table["orthogonality"])
    if traj.orientation_error is not None:
        np.testing.assert_array_equal(traj.orientation_error, table["orientation_error"])
        np.testing.assert_array_equal(traj.momentum_error, table["momentum_error"])
