#!/usr/bin/env python3
"""Bad-input sweep of the Python API (issue 32), the companion of bad_input_sweep.sh.

Every case is a call with bad input, run in a fresh interpreter so that a panic, an abort or a
hang is seen as such. Each must raise a typed exception (a GalerkinError, or the TypeError /
OverflowError / ValueError of a wrong argument type; a callable's own exception re-raised) or
return with a warning (the CLI's sanity warnings, as RuntimeWarning) within 60 s, without a Rust panic
(PanicException), and leave the scene file it reads intact. The Ctrl-C cases start a call that
would run for minutes, send SIGINT a second later and expect KeyboardInterrupt within 60 s.
Prints the counts the guide quotes (docs/guide/python.md, "Bad-input sweep").

    pip install ./python && python scripts/bad_input_sweep_python.py [--controls]

With --controls it runs the negative controls instead: good calls (each must count as a
silent exit 0) and a Ctrl-C that is ignored (it must count as a hang), so that a sweep that
could not see these outcomes is noticed.
"""

import hashlib
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
LIMIT = 60

PRELUDE = """
import sys, numpy as np, galerkin_vi as gv
k = gv.systems.Kepler()
gvi = gv.Integrator(n=8, h=0.5)
def traj():
    return gvi.integrate(k, [0.4, 0], [0, 2], 10)
"""

# A typed exception exits 1, a result with a warning (the CLI's sanity warnings) 3, a plain
# result 0 (silent). ZeroDivisionError is the user's own callable's, re-raised by crossings().
CHILD = PRELUDE + """
import warnings
try:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = ({case})
except (gv.GalerkinError, TypeError, ValueError, OverflowError, ZeroDivisionError) as e:
    print("TYPED", type(e).__name__, str(e)[:160])
    sys.exit(1)
if caught:
    print("WARNED", str(caught[0].message)[:160])
    sys.exit(3)
print("RETURNED", repr(result)[:160])
"""

INTERRUPTED = PRELUDE + """
print("started", flush=True)
{case}
"""

LONG = "x" * 300
BAD = [
    # run_scene: names and files
    "gv.run_scene('no-such-scene')",
    "gv.run_scene('')",
    "gv.run_scene('/tmp')",
    "gv.run_scene('/dev/null')",
    "gv.run_scene('/proc/version')",
    f"gv.run_scene('{LONG}.toml')",
    "gv.run_scene('broken.toml')",
    "gv.run_scene('rigid-body', solver='exact')",
    "gv.run_scene(42)",
    # run_scene: overrides
    "gv.run_scene('s.toml', steps=0)",
    "gv.run_scene('kepler', steps=-1)",
    "gv.run_scene('kepler', steps=1.5)",
    "gv.run_scene('kepler', steps=10**9)",
    "gv.run_scene('kepler', steps=10**7)",
    "gv.run_scene('s.toml', steps=10**8)",
    "gv.run_scene('kepler', n=1)",
    "gv.run_scene('kepler', n=10**6)",
    "gv.run_scene('kepler', h=0)",
    "gv.run_scene('kepler', h=-1)",
    "gv.run_scene('kepler', h=float('nan'))",
    "gv.run_scene('kepler', h=float('inf'))",
    "gv.run_scene('kepler', h=1e300, steps=10)",
    "gv.run_scene('solar-system', n=6, steps=100)",
    "gv.run_scene('kepler', tol=0)",
    "gv.run_scene('kepler', tol=-1e-6)",
    "gv.run_scene('kepler', tol=float('nan'))",
    "gv.run_scene('kepler', basis='zzz')",
    "gv.run_scene('kepler', quadrature='zzz')",
    "gv.run_scene('kepler', solver='zzz')",
    "gv.run_scene('kepler', colour=1)",
    "gv.run_scene('kepler', q0=[float('nan'), 0])",
    "gv.run_scene('kepler', q0=[0, 0])",
    "gv.run_scene('kepler', p0=[0, 1e300])",
    "gv.run_scene('kepler', q0='ab')",
    "gv.run_scene('kepler', q0=[[0.4, 0]])",
    "gv.run_scene('s.toml', q0=[0, 0, 0, 0])",
    # run_scene: the quadrature and tolerance options, rigid bodies
    "gv.run_scene('kepler', economical=True, compact=True)",
    "gv.run_scene('kepler', tol=1e-6, n=8)",
    "gv.run_scene('kepler', ladder=[8, 16])",
    "gv.run_scene('rigid-body', tol=1e-8)",
    "gv.run_scene('rigid-body', retraction='zzz')",
    "gv.run_scene('rigid-body', q0=[0, 0])",
    "gv.run_scene('rigid-body', p0=[float('nan'), 0, 0])",
    # Integrator
    "gv.Integrator(n=0)",
    "gv.Integrator(n=-1)",
    "gv.Integrator(n=10**9)",
    "gv.Integrator(h=0)",
    "gv.Integrator(h=float('nan'))",
    "gv.Integrator(basis='zzz')",
    "gv.Integrator(quadrature='trapezoid', n=40, quad_points=3)",
    "gv.Integrator(quad_points=0)",
    "gv.Integrator(solver='zzz')",
    # integrate
    "gvi.integrate(k, [0.4, 0], [0, 2], 0)",
    "gvi.integrate(k, [0.4, 0], [0, 2], -5)",
    "gvi.integrate(k, [0.4, 0], [0, 2], 10**9)",
    "gv.Integrator(n=16, h=1.0).integrate(k, [0.4, 0], [0, 2], 10**7)",
    "gvi.integrate(k, [0.4, 0, 1], [0, 2], 3)",
    "gvi.integrate(k, [np.nan, 0], [0, 2], 3)",
    "gvi.integrate(k, [0, 0], [0, 2], 3)",
    "gvi.integrate(k, [0.4, 0], [0, 1e300], 3)",
    "gvi.integrate(k, 'ab', [0, 2], 3)",
    "gvi.integrate(None, [0.4, 0], [0, 2], 3)",
    "gvi.integrate(gv.systems.NBody([1, 1]), [0, 0, 0, 0], [0, 0, 0, 0], 3)",
    "gvi.integrate(gv.systems.Expression('x_dot^2/2 + k/2*(x*y_dot - y*x_dot) + atan2(y, x)',"
    " ['x', 'y'], {'k': 1.0}), [1, 0.5], [0.1, 0.2], 10)",
    "gvi.integrate(gv.systems.Expression('x_dot^2/2 - 1/x', ['x']), [0.0], [1.0], 3)",
    "gv.Integrator(n=4, h=50.0, solver='exact').integrate(gv.systems.Pendulum(), [3.0], [10.0], 50)",
    # integrate_many
    "gv.integrate_many(k, [[0.4, 0]], [[0, 2], [0, 2]], 3)",
    "gv.integrate_many(k, np.zeros((0, 2)), np.zeros((0, 2)), 3)",
    "gv.integrate_many(k, np.zeros((2, 2, 2)), np.zeros((2, 2, 2)), 3)",
    "gv.integrate_many(k, [[0.4, np.nan]], [[0, 2]], 3)",
    "gv.integrate_many(k, [[0.4, 0], [0, 0]], [[0, 2], [0, 2]], 3)",
    "gv.integrate_many(k, [[0.4, 0]] * 8, [[0, 2]] * 8, 2 * 10**6)",
    "gv.integrate_many(k, [[0.4, 0]] * 10**5, [[0, 2]] * 10**5, 10**4)",
    "gv.integrate_many(k, [[0.4, 0]], [[0, 2]], 0)",
    # systems
    "gv.systems.Kepler(mu=-1)",
    "gv.systems.Kepler(mu=float('nan'))",
    "gv.systems.HarmonicOscillator(mass=-1.0)",
    "gv.systems.HarmonicOscillator(stiffness=float('inf'))",
    "gv.systems.Pendulum(length=0)",
    "gv.systems.NBody([])",
    "gv.systems.NBody([1.0, -1.0])",
    "gv.systems.NBody([1.0, 1.0], dim=4)",
    "gv.systems.NBody([1.0, 1.0], dim=0)",
    "gv.systems.Expression('', [])",
    "gv.systems.Expression('x_dot^2/2 - y', ['x'])",
    "gv.systems.Expression('x_dot^2/2 +', ['x'])",
    "gv.systems.Expression('x_dot^2/2', ['x', 'x'])",
    "gv.systems.Expression('x_dot^2/2 - a*x', ['x'], {'a': float('nan')})",
    "gv.systems.Expression('(' * 100000 + 'x' + ')' * 100000, ['x'])",
    # Lagrangians traced from Python functions
    "gv.systems.from_function(42, ['x'])",
    "gv.systems.from_function(lambda q, v: v[0]**2 if q[0] > 0 else 0, ['x'])",
    "gv.systems.from_function(lambda q, v: v[0]**2/2 - __import__('math').sin(q[0]), ['x'])",
    "gv.systems.from_function(lambda q, v: q[0]**2, ['x'])",
    # Trajectory
    "traj().position_at(float('nan'))",
    "traj().position_at(1e9)",
    "traj().position_at(-1.0)",
    "traj().momentum_at('x')",
    "traj().position_at([[0.1, 0.2]])",
    "traj().crossings(42)",
    "traj().crossings(lambda t, q, p: 1 / 0)",
    "traj().crossings(lambda t, q, p: float('nan'))",
    "traj().crossings(lambda t, q, p: 'x')",
    "traj().crossings(lambda t, q, p: q[0], direction='up')",
    "traj().crossings(lambda t, q, p: q[0], samples_per_step=0)",
    "gv.run_scene('kepler', tol=1e-6, steps=5).coefficients",
    "gv.run_scene('kepler', tol=1e-6, steps=5).check()",
    "gv.Integrator(n=8, h=0.1).integrate(gv.systems.Expression('sqrt(1 + x_dot^2) - x^2/2', ['x']),"
    " [3.0], [0.0], 40).check()",
]

# Negative controls (`--controls`): good calls, which the sweep must count as silent exit 0,
# and a long call that ignores Ctrl-C (a pure-Python loop catching KeyboardInterrupt), which it
# must count as not interrupted.
CONTROLS = [
    "gvi.integrate(k, [0.4, 0], [0, 2], 10)",
    "gv.run_scene('kepler', steps=5)",
]
CONTROL_CTRL_C = [
    "import time\nwhile True:\n    try:\n        time.sleep(100)\n    except KeyboardInterrupt:\n"
    "        pass",
]

# Calls that would run for minutes: Ctrl-C must end them with KeyboardInterrupt.
CTRL_C = [
    "gv.Integrator(n=16, h=1.0).integrate(k, [0.4, 0], [0, 2], 2 * 10**6)",
    "gv.integrate_many(k, [[0.4, 0]] * 4, [[0, 2]] * 4, 10**6)",
    "gv.run_scene('kepler', steps=2 * 10**6)",
    "gv.run_scene('kepler', steps=10**6, tol=1e-10)",
    "gv.run_scene('rigid-body', steps=2 * 10**6)",
    "gv.Integrator(n=48, h=1.0).integrate(k, [0.4, 0], [0, 2], 10**5).check()",
]


def digest(paths):
    h = hashlib.md5()
    for p in paths:
        h.update(pathlib.Path(p).read_bytes())
    return h.hexdigest()


def main():
    work = pathlib.Path(tempfile.mkdtemp(prefix="gvi-py-sweep-"))
    try:
        os.chdir(work)
        shutil.copy(ROOT / "scenes" / "two-body.toml", "s.toml")
        shutil.copy(ROOT / "scenes" / "figure-eight.toml", "f8.toml")
        big = (work / "f8.toml").read_text().replace("modes = 60", "modes = 1000000")
        (work / "big.toml").write_text(big)
        (work / "broken.toml").write_text("[system\ntype = ")
        inputs = ["s.toml", "f8.toml", "big.toml", "broken.toml"]
        before = digest(inputs)
        tried = panics = hangs = silent = lost = 0

        def judge(case, rc, out, err, hung):
            nonlocal panics, hangs, silent, lost, before
            if hung:
                hangs += 1
                print("HANG:", case)
            if "PanicException" in err or "panicked" in err or (rc is not None and rc < 0
                                                                and rc != -signal.SIGINT):
                panics += 1
                print("PANIC:", case, err[-300:])
            if rc == 0:
                silent += 1
                print("EXIT 0:", case, out[:200])
            if digest(inputs) != before:
                lost += 1
                print("LOST:", case)
                shutil.copy(ROOT / "scenes" / "two-body.toml", "s.toml")
                before = digest(inputs)

        controls = "--controls" in sys.argv[1:]
        bad = CONTROLS if controls else BAD
        ctrl_c = CONTROL_CTRL_C if controls else CTRL_C
        for case in bad:
            tried += 1
            child = [sys.executable, "-c", CHILD.format(case=case)]
            try:
                p = subprocess.run(child, capture_output=True, text=True, timeout=LIMIT)
                judge(case, p.returncode, p.stdout, p.stderr, False)
                if p.returncode == 1 and "TYPED" not in p.stdout:
                    # An exception that is not typed (e.g. a bare Exception) counts as a panic.
                    panics += 1
                    print("UNTYPED:", case, p.stderr[-300:])
            except subprocess.TimeoutExpired:
                judge(case, None, "", "", True)

        for case in ctrl_c:
            tried += 1
            p = subprocess.Popen(
                [sys.executable, "-c", INTERRUPTED.format(case=case)],
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
            )
            p.stdout.readline()
            try:
                p.wait(timeout=1.0)
            except subprocess.TimeoutExpired:
                pass
            p.send_signal(signal.SIGINT)
            try:
                out, err = p.communicate(timeout=LIMIT)
                interrupted = p.returncode == -signal.SIGINT and "KeyboardInterrupt" in err
                judge(case, p.returncode, out, err, False)
                if not interrupted and p.returncode != 0:
                    print("NOT INTERRUPTED:", case, p.returncode, err[-300:])
                    panics += 1
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
                judge(case, None, "", "", True)

        print(
            f"cases tried: {tried}; panics: {panics}; hangs: {hangs}; "
            f"silent exit 0: {silent}; data lost: {lost}"
        )
        if controls:
            ok = silent == len(CONTROLS) and hangs == len(CONTROL_CTRL_C)
            print("negative controls", "detected" if ok else "MISSED")
            return 0 if ok else 1
        return 0 if panics == hangs == silent == lost == 0 else 1
    finally:
        os.chdir(ROOT)
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
