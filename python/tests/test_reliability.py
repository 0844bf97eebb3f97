"""Issue 32 from Python: work above the memory limit is refused before it starts, a start the
CLI refuses is refused, check() never hides a NaN, and Ctrl-C stops long work promptly with
KeyboardInterrupt. Each test has a negative control: the same call just inside the limit, from
a good start, or without the signal."""

import os
import signal
import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest

import galerkin_vi as gv

k = gv.systems.Kepler()


# --- memory: refused before any work, quoting the estimate and the limit ---------------------


@pytest.mark.parametrize(
    "call",
    [
        lambda: gv.Integrator(n=16, h=1.0).integrate(k, [0.4, 0], [0, 2], 10**7),
        lambda: gv.integrate_many(k, [[0.4, 0]] * 8, [[0, 2]] * 8, 2 * 10**6),
        lambda: gv.run_scene("kepler", steps=10**7),
        lambda: gv.run_scene("kepler", steps=10**8),
        lambda: gv.run_scene("rigid-body", steps=10**7),
    ],
)
def test_work_above_the_memory_limit_is_refused_with_the_estimate(call):
    with pytest.raises(gv.MemoryLimitError) as info:
        call()
    message = str(info.value)
    assert "estimated" in message and "limit 4e9" in message
    assert issubclass(gv.MemoryLimitError, gv.InvalidInputError)


def test_work_inside_the_memory_limit_runs():
    # Negative control: the same calls with fewer steps are not refused.
    assert gv.Integrator(n=16, h=1.0).integrate(k, [0.4, 0], [0, 2], 200).steps == 200
    assert len(gv.integrate_many(k, [[0.4, 0]] * 8, [[0, 2]] * 8, 20)) == 8
    assert gv.run_scene("kepler", steps=20).steps == 20


def test_a_step_count_beyond_the_maximum_is_a_method_error_not_a_memory_one():
    with pytest.raises(gv.InvalidMethodError, match="steps"):
        gv.Integrator().integrate(k, [0.4, 0], [0, 2], 10**9)


# --- the start the CLI refuses, and NaN in check() --------------------------------------------

SINGULAR = "x_dot^2/2 + k/2*(x*y_dot - y*x_dot) + atan2(y, x)"


def test_a_singular_expression_lagrangian_is_refused_at_the_start_as_by_the_cli():
    e = gv.systems.Expression(SINGULAR, ["x", "y"], {"k": 1.0})
    with pytest.raises(gv.ExpressionError, match="not regular"):
        gv.Integrator(n=8, h=0.5).integrate(e, [1.0, 0.5], [0.1, 0.2], 10)
    with pytest.raises(gv.ExpressionError, match=r"member 0 \(q0s\[0\], p0s\[0\]\): expression Lagrangian"):
        gv.integrate_many(e, [[1.0, 0.5]] * 2, [[0.1, 0.2]] * 2, 10)
    # Negative control: the same form with a y_dot^2 term is regular and runs.
    regular = gv.systems.Expression(
        "x_dot^2/2 + y_dot^2/2 + k/2*(x*y_dot - y*x_dot) + atan2(y, x)", ["x", "y"], {"k": 1.0}
    )
    traj = gv.Integrator(n=8, h=0.5).integrate(regular, [1.0, 0.5], [0.1, 0.2], 10)
    assert np.isfinite(traj.check()["max_energy_error"])


def test_a_member_at_a_singular_start_is_named():
    with pytest.raises(gv.GalerkinError, match="member 2"):
        gv.integrate_many(k, [[0.4, 0], [0.5, 0], [0.0, 0.0]], [[0, 2]] * 3, 5)


def test_check_raises_where_the_energy_is_nan_instead_of_reporting_it_as_zero():
    # L = sqrt(1 + v^2) - x^2/2: p = v/sqrt(1 + v^2) lies in (-1, 1), and from x = 3 the force
    # drives the discrete momentum out of that range (|p| = 8.6 at step 5), where the inverse
    # Legendre transform has no solution: the energy there is NaN although the state is finite.
    e = gv.systems.Expression("sqrt(1 + x_dot^2) - x^2/2", ["x"])
    traj = gv.Integrator(n=8, h=0.1).integrate(e, [3.0], [0.0], 40)
    energy = traj.invariants["energy"]
    assert np.isnan(energy).any() and np.isfinite(traj.q).all()  # not vacuous
    with pytest.raises(gv.NonFiniteResultError, match=r"energy is NaN at step \d+"):
        traj.check()
    # Negative control: a small swing keeps |p| < 1, the energy finite, and check() reports.
    calm = gv.Integrator(n=8, h=0.1).integrate(e, [0.3], [0.0], 100)
    assert np.isfinite(calm.invariants["energy"]).all()
    assert calm.check()["max_energy_error"] < 1e-10


def test_run_scene_issues_the_sanity_warnings_of_gvi_run():
    # h = 1e300: the orbit is nonsense; gvi run warns, and so does run_scene.
    with pytest.warns(RuntimeWarning) as record:
        gv.run_scene("kepler", h=1e300, steps=10)
    messages = [str(w.message) for w in record]
    assert any("relative energy error" in m for m in messages), messages
    assert any("relative position error" in m for m in messages), messages
    # Negative control: the paper's run warns of nothing.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gv.run_scene("kepler", steps=20)


# --- Ctrl-C ------------------------------------------------------------------------------------

# Each call would run for minutes (10^6 - 2*10^6 steps) within the memory limit.
LONG_CALLS = {
    "integrate": "gv.Integrator(n=16, h=1.0).integrate(k, [0.4, 0], [0, 2], 2 * 10**6)",
    "integrate_many": "gv.integrate_many(k, [[0.4, 0]] * 4, [[0, 2]] * 4, 10**6)",
    "run_scene": "gv.run_scene('kepler', steps=2 * 10**6)",
    # Hours of Lie group steps (within the memory limit): stopped between chunks of 16 steps.
    "run_scene_rigid_body": "gv.run_scene('rigid-body', steps=2 * 10**6)",
    # Time-transformed: the Pythagorean problem to t = 70 (about 10 s), and 10^6 fictitious
    # Kepler steps; both stopped before the next fictitious step.
    "run_scene_time_transformed": "gv.run_scene('pythagorean')",
    "integrate_time_transformed": (
        "gv.Integrator(n=12, h=1e-4, time_transform='radius').integrate(k, [0.4, 0], [0, 2], 10**6)"
    ),
}

CHILD = """
import sys, galerkin_vi as gv
k = gv.systems.Kepler()
print("started", flush=True)
try:
    {call}
    print("finished", flush=True)
except KeyboardInterrupt:
    print("KeyboardInterrupt", flush=True)
    # Nothing is left corrupt: the module works as before.
    t = gv.Integrator(n=8, h=0.5).integrate(k, [0.4, 0], [0, 2], 10)
    print("after", t.steps, flush=True)
    {reraise}
"""

# A generous bound for "promptly": the uninterrupted calls take minutes; each member stops
# within one step (milliseconds) once the signal is seen (every 20 ms).
PROMPT = 60


def run_child(call, reraise=""):
    code = textwrap.dedent(CHILD).format(call=call, reraise=reraise)
    return subprocess.Popen(
        [sys.executable, "-c", code],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


@pytest.mark.skipif(os.name != "posix", reason="SIGINT to a child process")
@pytest.mark.parametrize("name", sorted(LONG_CALLS))
def test_ctrl_c_stops_long_work_with_keyboard_interrupt(name):
    child = run_child(LONG_CALLS[name])
    try:
        assert child.stdout.readline().strip() == "started"
        # Negative control: the work is still running a second later (it is long).
        try:
            child.wait(timeout=1.0)
        except subprocess.TimeoutExpired:
            pass
        assert child.poll() is None, child.stderr.read()
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=PROMPT)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    assert child.returncode == 0, err
    assert out.split() == ["KeyboardInterrupt", "after", "10"], (out, err)


@pytest.mark.skipif(os.name != "posix", reason="SIGINT to a child process")
def test_an_uncaught_ctrl_c_ends_the_interpreter_as_keyboard_interrupt():
    child = run_child(LONG_CALLS["integrate_many"], reraise="raise")
    try:
        assert child.stdout.readline().strip() == "started"
        try:
            child.wait(timeout=1.0)
        except subprocess.TimeoutExpired:
            pass
        child.send_signal(signal.SIGINT)
        _, err = child.communicate(timeout=PROMPT)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    assert child.returncode == -signal.SIGINT
    assert "KeyboardInterrupt" in err and "PanicException" not in err
