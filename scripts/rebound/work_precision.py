#!/usr/bin/env python3
"""REBOUND (IAS15, WHFast with symplectic correctors, WHCKL, SABA) as external peers of
`gvi work-precision`.

Runs REBOUND (pinned in scripts/rebound/requirements.txt) on one of the crate's built-in scenes
with the study's protocol -- positions sampled at t_k = t0 + k*Delta (Delta = the scene's h),
error = max over the samples of the max-norm position error against the study's own reference
positions, written by `gvi work-precision SCENE --write-reference FILE` -- and writes rows in the
study's CSV schema, for `gvi work-precision SCENE --external FILE.csv`.

Setup (from the repository root):

    python3 -m venv .venv-rebound && .venv-rebound/bin/pip install -r scripts/rebound/requirements.txt
    cargo build --release
    .venv-rebound/bin/python scripts/rebound/work_precision.py kepler --out docs/studies/external/rebound-kepler-T200.csv

Models:
- kepler (q'' = -mu q/|q|^3): G = 1, a central body of mass mu at rest at the origin and a
  test particle (mass 0) at (q, 0), velocity (p, 0); the position is the test particle's
  relative to the central body, so its motion is the Kepler problem exactly. For two bodies
  the Wisdom-Holman family (WHFast, WHCKL, SABA) is exact up to rounding: its Kepler drift is
  solved analytically and the interaction term is zero.
- nbody: G = the scene's g (1 with gm values), masses = the scene's masses (GM), velocities
  as given, moved to the barycentre exactly as the scene does (`barycentric = true`); the
  positions compared are all bodies' barycentric coordinates in scene order, as in the study.
  The script checks that its initial positions agree with the reference's first row.

Integrators, each as REBOUND's documentation recommends for planetary systems:
- IAS15 (default PRS23 adaptive mode) at epsilon = 1e-2 ... 1e-12 in half decades, integrating
  to every sample with exact_finish_time = 1 (sim.integrate(t));
- WHFast in Jacobi coordinates without corrector and with symplectic correctors of order 11
  and 17 (rebound-whfast, rebound-whfast-c11, rebound-whfast-c17), WHCKL (WHFast, lazy implementer's kernel,
  corrector 17; rebound-whckl), SABA(10,6,4) and SABA(8,6,4) (rebound-saba-10-6-4,
  rebound-saba-8-6-4), all with safe_mode = 0 and keep_unsynchronized = 1, swept over
  dt = Delta/m (m in DIVISORS, increasing, until the error stalls at its floor or a run takes
  longer than --max-seconds). Each takes m steps per sample interval (sim.steps(m), which ends
  with a synchronisation that applies the corrector, on a copy, so the stepping never depends
  on the sampling): the samples are step boundaries, as dt divides Delta.
The calls sim.integrate / sim.steps go to the C functions they wrap (reb_simulation_integrate,
reb_simulation_steps), skipping the
Python layer's message polling after each call; messages are processed once after the run,
and a non-zero return code is an error.
Each row's parameters name the integrator, its corrector/kernel and dt.

Timing: only the integration (the integrate / steps calls, synchronising and reading the
positions at each sample) is timed with time.perf_counter, the median of --repeats runs,
each on a fresh simulation built outside the timed region.
force_evaluations: 0 (not counted; REBOUND does not report them).
"""

import argparse
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib

from ctypes import byref, c_double, c_int, c_size_t

import rebound

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def load_scene(name):
    path = name if os.path.exists(name) else os.path.join(ROOT, "scenes", name + ".toml")
    with open(path, "rb") as f:
        return tomllib.load(f)


def model(scene):
    """(kind, G, masses, q, v): the initial state as the Rust scene builds it."""
    system = scene["system"]
    kind = system["type"]
    if kind == "kepler":
        init = scene["initial"]
        return kind, 1.0, [system.get("mu", 1.0), 0.0], [[0.0, 0.0, 0.0], list(init["q"]) + [0.0]], [
            [0.0, 0.0, 0.0],
            list(init["p"]) + [0.0],
        ]
    if kind != "nbody":
        sys.exit(f"unsupported scene type {kind!r} (kepler and nbody only)")
    if system.get("aggregate"):
        sys.exit("aggregated bodies are not supported by this script")
    dim = system["dim"]
    bodies = system["bodies"]
    uses_gm = "gm" in bodies[0]
    g = 1.0 if uses_gm else system.get("g", 1.0)
    masses = [b["gm"] if uses_gm else b["mass"] for b in bodies]
    pad = lambda x: list(x) + [0.0] * (3 - dim)
    q = [pad(b["q"]) for b in bodies]
    v = [pad(b["v"]) for b in bodies]
    if system.get("barycentric", False):
        # As NBody::to_barycentric: c = sum(m x) / sum(m), per component, positions then velocities.
        total = sum(masses)
        for x in (q, v):
            c = [sum(m * xi[d] for m, xi in zip(masses, x)) / total for d in range(3)]
            for xi in x:
                for d in range(3):
                    xi[d] -= c[d]
    return kind, g, masses, q, v


def positions(kind, sim, dim):
    # Iterating over sim.particles builds the particle view once (indexing it builds it per
    # particle: 2-200 us each in REBOUND 5.2.2's Python layer).
    ps = list(sim.particles)
    if kind == "kepler":
        return [ps[1].x - ps[0].x, ps[1].y - ps[0].y]
    out = []
    for p in ps:
        out.extend((p.x, p.y, p.z)[:dim])
    return out


# The integration calls go straight to REBOUND's C library: reb_simulation_integrate and
# reb_simulation_steps are what sim.integrate and sim.steps call, without the Python layer's message polling after every call
# (5-25 us each in 5.2.2, not the integrator's cost). Messages (warnings, errors) are
# processed once after the run.
_LIB = rebound.clibrebound
_RET = {1: "generic error", 2: "no particles", 3: "close encounter", 4: "escape", 6: "interrupted",
        7: "collision"}


def _check(sim, ret):
    if ret not in (0, 5):
        sim.process_messages()
        raise RuntimeError(f"REBOUND stopped: {_RET.get(ret, ret)}")


def _integrate(sim, t):
    _check(sim, _LIB.reb_simulation_integrate(byref(sim), c_double(t)))


def _steps(sim, m):
    _check(sim, _LIB.reb_simulation_steps(byref(sim), c_size_t(m)))



def read_reference(path):
    ts, qs = [], []
    with open(path) as f:
        header = f.readline().strip().split(",")
        if header[:2] != ["k", "t"]:
            sys.exit(f"{path}: not a reference file (header {header[:2]})")
        for line in f:
            row = line.strip().split(",")
            if len(row) < 3:
                continue
            ts.append(float(row[1]))
            qs.append([float(x) for x in row[2:]])
    return ts, qs


def build(kind, g, masses, q, v):
    sim = rebound.Simulation()
    sim.G = g
    for m, x, u in zip(masses, q, v):
        sim.add(m=m, x=x[0], y=x[1], z=x[2], vx=u[0], vy=u[1], vz=u[2])
    return sim


def run_ias15(state, ts, epsilon, dim):
    sim = build(*state)
    sim.integrator = "ias15"
    sim.integrator.epsilon = epsilon
    sim.t = ts[0]
    sim.exact_finish_time = c_int(1)
    out = [positions(state[0], sim, dim)]
    start = time.perf_counter()
    for t in ts[1:]:
        _integrate(sim, t)
        out.append(positions(state[0], sim, dim))
    seconds = time.perf_counter() - start
    sim.process_messages()
    return seconds, out, 0


# The fixed-step families: (method name, integrator setup, parameter text). Each is REBOUND's
# own recommended configuration for planetary systems (Rein & Tamayo 2015; Rein, Tamayo &
# Brown 2019): WHFast in Jacobi coordinates with symplectic correctors of order 11 or 17,
# WHCKL (WHFast, lazy implementer's kernel, corrector 17), and SABA(10,6,4) / SABA(8,6,4).
def _whfast(corrector, kernel="default"):
    def setup(sim):
        sim.integrator = "whfast"
        sim.integrator.coordinates = "jacobi"
        sim.integrator.corrector = corrector
        sim.integrator.kernel = kernel
        sim.integrator.safe_mode = 0
        sim.integrator.keep_unsynchronized = 1
    return setup


def _saba(kind):
    def setup(sim):
        sim.integrator = "saba"
        sim.integrator.type = kind
        sim.integrator.safe_mode = 0
        sim.integrator.keep_unsynchronized = 1
    return setup


FAMILIES = {
    "whfast": ("rebound-whfast", _whfast(0), "WHFast, Jacobi, no corrector"),
    "whfast-c11": ("rebound-whfast-c11", _whfast(11), "WHFast, Jacobi, corrector 11"),
    "whfast-c17": ("rebound-whfast-c17", _whfast(17), "WHFast, Jacobi, corrector 17"),
    "whckl": ("rebound-whckl", _whfast(17, "lazy"), "WHCKL (WHFast, Jacobi, lazy kernel, corrector 17)"),
    "saba-10-6-4": ("rebound-saba-10-6-4", _saba("10_6_4"), "SABA(10,6,4)"),
    "saba-8-6-4": ("rebound-saba-8-6-4", _saba("8_6_4"), "SABA(8,6,4)"),
}


def run_fixed(state, ts, setup, m, dim):
    """m steps of dt = Delta/m per sample interval (sim.steps(m)): the samples are step
    boundaries. safe_mode = 0 and keep_unsynchronized = 1: the synchronisation at the end of
    every sim.steps call (which applies the symplectic corrector, where there is one) works on
    a copy, so the stepping never depends on the sampling."""
    sim = build(*state)
    setup(sim)
    sim.dt = (ts[1] - ts[0]) / m
    sim.t = ts[0]
    out = [positions(state[0], sim, dim)]
    start = time.perf_counter()
    for _ in ts[1:]:
        # reb_simulation_steps ends with a synchronisation (on a copy, applying the
        # corrector): the positions are bit for bit those after an explicit synchronize,
        # which would only apply the corrector a second time.
        _steps(sim, m)
        out.append(positions(state[0], sim, dim))
    seconds = time.perf_counter() - start
    sim.process_messages()
    return seconds, out, 0


# Steps per sample interval: every divisor of 2^a 5^b up to 1000 and a few more, so that
# dt = Delta/m lands on the sample times and the sweep is fine enough to find each family's
# cheapest step for a given error.
DIVISORS = [1, 2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 25, 32, 40, 50, 64, 80, 100, 128, 160, 200,
            256, 320, 400, 512, 640, 800, 1000, 1280, 1600, 2000, 2560, 4096]


def max_error(qs, ref):
    """Max over the samples of the max-norm position error (inf if any position is NaN)."""
    worst = 0.0
    for q, r in zip(qs, ref):
        for a, b in zip(q, r):
            d = abs(a - b)
            if not d <= worst:
                if d != d:
                    return math.inf
                worst = d
    return worst


def timed(run, repeats):
    times, result = [], None
    for _ in range(repeats):
        try:
            seconds, qs, evals = run()
        except Exception as e:  # a failed run is a row with its failure, as in the study
            return math.nan, None, 0, f"{type(e).__name__}: {e}".replace('"', "'")
        times.append(seconds)
        result = (qs, evals)
    return statistics.median(times), result[0], result[1], ""


def fmt(x):
    return "" if x is None else repr(float(x))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", help="built-in scene name (kepler, outer-solar-system, solar-system) or TOML path")
    ap.add_argument("--horizon", type=float, help="time span (default: the scene's h * steps)")
    ap.add_argument("--reference", help="reference CSV from gvi --write-reference (default: call gvi)")
    ap.add_argument("--gvi", default=os.environ.get("GVI", os.path.join(ROOT, "target", "release", "gvi")))
    ap.add_argument("--out", help="output CSV (the study's schema)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--epsilons", type=float, nargs="*",
                    default=[10.0 ** (-k / 2) for k in range(4, 25)],
                    help="IAS15 epsilons (default 1e-2 ... 1e-12 in half decades)")
    ap.add_argument("--divisors", type=int, nargs="*", default=DIVISORS,
                    help="fixed-step families: steps per sample interval (dt = Delta/m), "
                         "swept in increasing order")
    ap.add_argument("--families", nargs="*", default=list(FAMILIES), choices=list(FAMILIES),
                    help="fixed-step families to sweep (default: all)")
    ap.add_argument("--max-seconds", type=float, default=1.5,
                    help="stop a fixed-step family's sweep after a run slower than this")
    ap.add_argument("--compare-reference", action="store_true",
                    help="only compare IAS15 at --compare-epsilons with the reference and print it")
    ap.add_argument("--compare-epsilons", type=float, nargs="*", default=[1e-10, 1e-11, 1e-12])
    args = ap.parse_args()

    scene = load_scene(args.scene)
    with tempfile.TemporaryDirectory() as tmp:
        ref_path = args.reference
        if ref_path is None:
            ref_path = os.path.join(tmp, "reference.csv")
            cmd = [args.gvi, "work-precision", args.scene, "--write-reference", ref_path]
            if args.horizon is not None:
                cmd += ["--horizon", repr(args.horizon)]
            subprocess.run(cmd, check=True)
        ts, ref = read_reference(ref_path)
    if len(ts) < 2:
        sys.exit("the reference has fewer than two samples")
    state = model(scene)
    dim = len(ref[0]) if state[0] == "kepler" else scene["system"]["dim"]
    q0 = positions(state[0], build(*state), dim)
    start_diff = max(abs(a - b) for a, b in zip(q0, ref[0]))
    print(f"{args.scene}: {len(ts)} samples, t = {ts[0]} ... {ts[-1]}, initial positions vs the "
          f"reference's first row: {start_diff:.2e}", file=sys.stderr)
    if start_diff > 1e-12:
        sys.exit("the initial state does not match the reference (different scene or frame?)")

    if args.compare_reference:
        runs = {}
        for eps in args.compare_epsilons:
            seconds, qs, _, failure = timed(lambda: run_ias15(state, ts, eps, dim), 1)
            if failure:
                print(f"IAS15 epsilon = {eps:g}: failed: {failure}")
                continue
            runs[eps] = qs
            worst_k = max(range(len(ts)), key=lambda k: max(abs(a - b) for a, b in zip(qs[k], ref[k])))
            print(f"IAS15 epsilon = {eps:g} ({seconds:.3f} s): max position difference from the gvi "
                  f"reference {max_error(qs, ref):.3e} (largest at t = {ts[worst_k]})")
        eps = sorted(runs)
        for a, b in zip(eps, eps[1:]):
            print(f"IAS15 epsilon = {a:g} vs {b:g}: {max_error(runs[a], runs[b]):.3e}")
        return

    rows = []
    for eps in args.epsilons:
        seconds, qs, evals, failure = timed(lambda: run_ias15(state, ts, eps, dim), args.repeats)
        error = max_error(qs, ref) if qs else math.inf
        rows.append(("rebound-ias15", f"IAS15, epsilon = {eps:.3g}", None, eps, error, seconds, evals, failure))
        print(f"  rebound-ias15 epsilon = {eps:g}: error {error:.3e}, {seconds:.3e} s", file=sys.stderr)
    delta = ts[1] - ts[0]
    for family in args.families:
        method, setup, label = FAMILIES[family]
        best, stalled = math.inf, 0
        for m in sorted(set(args.divisors)):
            dt = delta / m
            seconds, qs, evals, failure = timed(lambda: run_fixed(state, ts, setup, m, dim), args.repeats)
            error = max_error(qs, ref) if qs else math.inf
            if not math.isfinite(error):
                error, failure = math.inf, failure or "non-finite positions"
            rows.append((method, f"{label}, dt = {dt:.6g} (Delta/{m})", dt, None, error, seconds, evals,
                         failure))
            print(f"  {method} dt = {dt:g}: error {error:.3e}, {seconds:.3e} s", file=sys.stderr)
            # At its round-off floor a family gains nothing from smaller steps.
            stalled = stalled + 1 if error < 1e-8 and error > 0.5 * best else 0
            best = min(best, error)
            if stalled >= 3 or (math.isfinite(seconds) and seconds > args.max_seconds):
                break

    lines = [
        f"# REBOUND {rebound.__version__} (Python {platform.python_version()}, {platform.machine()}) on scene "
        f"{args.scene}, T = {ts[-1] - ts[0]}, samples every {delta}; {args.repeats} repeats, median seconds",
        "# written by scripts/rebound/work_precision.py; read with gvi work-precision SCENE --external FILE",
        "method,parameters,h,n,tolerance,error,seconds,force_evaluations,pareto,failure",
    ]
    for method, params, h, tol, error, seconds, evals, failure in rows:
        err = "inf" if not math.isfinite(error) else repr(error)
        sec = "0.0" if not math.isfinite(seconds) else repr(seconds)
        fail = f'"{failure}"' if failure else ""
        lines.append(f'{method},"{params}",{fmt(h)},,{fmt(tol)},{err},{sec},{evals},false,{fail}')
    text = "\n".join(lines) + "\n"
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, "w") as f:
            f.write(text)
        print(f"  wrote {args.out}", file=sys.stderr)
    else:
        sys.stdout.write(text)


if __name__ == "__main__":
    main()
