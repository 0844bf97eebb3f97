#!/usr/bin/env python3
"""REBOUND's IAS15 on the problems of docs/guide/time-transformations.md, for its tables.

- Kepler e = 0.9 and e = 0.99 (a = 1, mu = 1, period 2 pi) from periapsis over 100 orbits: the
  max-norm position error against the exact solution of the initial state (its elements as the
  crate's KeplerOrbit::from_state computes them, Kepler's equation solved by Newton) at the
  guide's sample times t = k 2 pi / 16, k = 0 ... 1600;
- the Pythagorean three-body problem (masses 3, 4, 5 at rest at (1, 3), (-2, -1), (1, -1),
  G = 1) to T = 70, sampled at t = 0.1 k: the max relative energy error over the samples, and
  how long the positions agree (max norm, to 1e-6 and to 1e-2) with the guide's tight DOP853
  reference (tol = 1e-15), written by

      cargo run --release -j 1 -p galerkin-vi-lab --example pythagorean_reference -- target/pythagorean-dop853.csv

IAS15 runs at its best, as scripts/rebound/work_precision.py runs it: the default adaptive
mode (PRS23), exact_finish_time = 1, the integration through the C function
reb_simulation_integrate (skipping the Python layer's message polling), only the integration
and the reading of the positions at the samples timed (time.perf_counter, the median of
--repeats runs, each on a fresh simulation built outside the timed region). Kepler: a central
mass mu at the origin and a test particle, the position the particle's relative to it (the
Kepler problem exactly). Steps are REBOUND's steps_done; force evaluations are not reported
by REBOUND.

    gvi run pythagorean --every 0.1 --output target/pythagorean-galerkin.csv
    /tmp/venv-rebound/bin/python scripts/rebound/time_transform.py --reference target/pythagorean-dop853.csv --galerkin target/pythagorean-galerkin.csv

prints Markdown rows for the guide's tables and the load average before and after.
"""

import argparse
import math
import os
import statistics
import time

from ctypes import byref, c_double, c_int

import rebound

_LIB = rebound.clibrebound


def _integrate(sim, t):
    ret = _LIB.reb_simulation_integrate(byref(sim), c_double(t))
    if ret not in (0, 5):
        sim.process_messages()
        raise RuntimeError(f"REBOUND stopped with status {ret}")


class KeplerOrbit:
    """The exact orbit of a state (mu = 1), with the elements computed from the floating-point
    state as galerkin_vi::systems::kepler_orbit::KeplerOrbit::from_state computes them (the
    guide's exact solution): at e = 0.99 the rounding of the state's energy moves the period by
    ~1e-14, 5e-10 in position at periapsis after 100 orbits, so an orbit with a = 1 and e
    exactly would put that floor under every error."""

    def __init__(self, q, v):
        r = math.hypot(q[0], q[1])
        v2 = v[0] * v[0] + v[1] * v[1]
        energy = 0.5 * v2 - 1.0 / r
        self.a = -0.5 / energy
        e_cos = r * v2 - 1.0
        e_sin = (q[0] * v[0] + q[1] * v[1]) / math.sqrt(self.a)
        self.e = math.hypot(e_cos, e_sin)
        ecc = math.atan2(e_sin, e_cos)
        self.m0 = ecc - self.e * math.sin(ecc)
        self.n = math.sqrt(1.0 / self.a) / self.a
        self.sense = math.copysign(1.0, q[0] * v[1] - q[1] * v[0])
        x, y = self.perifocal(ecc)
        self.w = math.atan2(q[1], q[0]) - math.atan2(y, x)

    def perifocal(self, ecc):
        e, a = self.e, self.a
        return a * (math.cos(ecc) - e), self.sense * a * math.sqrt(1.0 - e * e) * math.sin(ecc)

    def position(self, t):
        """E - e sin E = M by Newton from E = pi (monotone for every e < 1)."""
        m = math.fmod(self.m0 + self.n * t, 2.0 * math.pi)
        ecc = math.pi
        for _ in range(100):
            step = (ecc - self.e * math.sin(ecc) - m) / (1.0 - self.e * math.cos(ecc))
            ecc -= step
            if abs(step) < 1e-17:
                break
        x, y = self.perifocal(ecc)
        c, s = math.cos(self.w), math.sin(self.w)
        return c * x - s * y, s * x + c * y


def kepler_at_periapsis(e):
    """The guide's initial state (tests/common/kepler_periapsis.rs): a = 1, mu = 1."""
    return (1.0 - e, 0.0), (0.0, math.sqrt((1.0 + e) / (1.0 - e)))


def kepler_sim(e, epsilon):
    sim = rebound.Simulation()
    sim.G = 1.0
    sim.add(m=1.0)
    q, v = kepler_at_periapsis(e)
    sim.add(m=0.0, x=q[0], y=q[1], vx=v[0], vy=v[1])
    sim.integrator = "ias15"
    sim.integrator.epsilon = epsilon
    sim.exact_finish_time = c_int(1)
    return sim


def run_kepler(e, epsilon, repeats):
    times = [k * 2.0 * math.pi / 16.0 for k in range(1601)]
    best = []
    for _ in range(repeats):
        sim = kepler_sim(e, epsilon)
        out = []
        start = time.perf_counter()
        for t in times[1:]:
            _integrate(sim, t)
            ps = list(sim.particles)
            out.append((ps[1].x - ps[0].x, ps[1].y - ps[0].y))
        best.append(time.perf_counter() - start)
        sim.process_messages()
    orbit = KeplerOrbit(*kepler_at_periapsis(e))
    err = 0.0
    for t, (x, y) in zip(times[1:], out):
        xe, ye = orbit.position(t)
        err = max(err, abs(x - xe), abs(y - ye))
    return sim.steps_done, err, statistics.median(best)


def pythagorean_sim(epsilon):
    sim = rebound.Simulation()
    sim.G = 1.0
    for m, x, y in [(3.0, 1.0, 3.0), (4.0, -2.0, -1.0), (5.0, 1.0, -1.0)]:
        sim.add(m=m, x=x, y=y)
    sim.integrator = "ias15"
    sim.integrator.epsilon = epsilon
    sim.exact_finish_time = c_int(1)
    return sim


def run_pythagorean(epsilon, repeats):
    best = []
    for _ in range(repeats):
        sim = pythagorean_sim(epsilon)
        out = [[1.0, 3.0, -2.0, -1.0, 1.0, -1.0]]
        start = time.perf_counter()
        for k in range(1, 701):
            _integrate(sim, 0.1 * k)
            row = []
            for p in sim.particles:
                row.extend((p.x, p.y))
            out.append(row)
        best.append(time.perf_counter() - start)
        sim.process_messages()
    steps = sim.steps_done
    # The energy at the samples, outside the timed region, from a replay of the same
    # (deterministic) run.
    sim = pythagorean_sim(epsilon)
    e0 = sim.energy()
    energy = 0.0
    for k in range(1, 701):
        _integrate(sim, 0.1 * k)
        energy = max(energy, abs((sim.energy() - e0) / e0))
    return steps, energy, statistics.median(best), out


def read_reference(path):
    rows = []
    with open(path) as f:
        header = f.readline().strip().split(",")
        if header[:2] != ["k", "t"]:
            raise SystemExit(f"{path}: not a reference file (header {header[:2]})")
        for line in f:
            cells = line.strip().split(",")
            if len(cells) == 8:
                rows.append([float(x) for x in cells[2:]])
    if len(rows) != 701:
        raise SystemExit(f"{path}: expected 701 samples (t = 0, 0.1, ..., 70), got {len(rows)}")
    return rows


def read_galerkin(path):
    """The positions q0 ... q5 of `gvi run pythagorean --every 0.1`'s CSV (701 rows)."""
    import csv

    with open(path, newline="") as f:
        rows = [[float(r[f"q{i}"]) for i in range(6)] for r in csv.DictReader(f)]
    if len(rows) != 701:
        raise SystemExit(f"{path}: expected 701 rows (t = 0, 0.1, ..., 70), got {len(rows)}")
    return rows


def agree_until(a, b, tol):
    """The first sample time at which the positions differ by more than tol (max norm), as
    agree_until in lab/tests/timetransform_study.rs."""
    for k, (x, y) in enumerate(zip(a, b)):
        d = max(abs(u - v) for u, v in zip(x, y))
        if not d <= tol:
            return 0.1 * k
    return 0.1 * (min(len(a), len(b)) - 1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reference", help="the DOP853 1e-15 reference CSV (Pythagorean)")
    parser.add_argument(
        "--galerkin",
        help="the time-transformed Galerkin run at t = 0, 0.1, ..., 70 "
             "(gvi run pythagorean --every 0.1 --output FILE): agreement with it too")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--kepler-epsilons", default="1e-6,1e-7,1e-8,1e-9,1e-10,1e-11",
        help="IAS15 epsilons for Kepler (comma-separated)")
    parser.add_argument(
        "--pythagorean-epsilons", default="1e-6,1e-7,1e-8,1e-9,1e-10,1e-11",
        help="IAS15 epsilons for the Pythagorean problem")
    args = parser.parse_args()
    print(f"REBOUND {rebound.__version__}; load average before: {os.getloadavg()}")
    for e in (0.99, 0.9):
        print(f"\nKepler e = {e}, 100 orbits, max position error at 16 times per orbit")
        print("| method | steps | force evaluations | max error | seconds |")
        print("|---|---|---|---|---|")
        for eps in [float(x) for x in args.kepler_epsilons.split(",")]:
            steps, err, seconds = run_kepler(e, eps, args.repeats)
            print(f"| IAS15 epsilon = {eps:g} | {steps} | not reported | {err:.2e} | {seconds:.3f} |")
    if args.reference:
        reference = read_reference(args.reference)
        print("\nPythagorean problem to t = 70 (samples every 0.1)")
        galerkin = read_galerkin(args.galerkin) if args.galerkin else None
        extra = " | agrees with the Galerkin run to 1e-6 until | to 1e-2 until" if galerkin else ""
        print("| run | steps | max relative energy error | seconds "
              f"| agrees with DOP853 1e-15 to 1e-6 until | to 1e-2 until{extra} |")
        print("|---|---|---|---|---|---|" + ("---|---|" if galerkin else ""))
        for eps in [float(x) for x in args.pythagorean_epsilons.split(",")]:
            steps, energy, seconds, out = run_pythagorean(eps, args.repeats)
            cells = [agree_until(out, reference, 1e-6), agree_until(out, reference, 1e-2)]
            if galerkin:
                cells += [agree_until(out, galerkin, 1e-6), agree_until(out, galerkin, 1e-2)]
            print(f"| IAS15 epsilon = {eps:g} | {steps} | {energy:.1e} | {seconds:.3f} | "
                  + " | ".join(f"{c:.1f}" for c in cells) + " |")
        if galerkin:
            print(f"Galerkin run against DOP853 1e-15: to 1e-6 until "
                  f"{agree_until(galerkin, reference, 1e-6):.1f}, to 1e-2 until "
                  f"{agree_until(galerkin, reference, 1e-2):.1f}")
    print(f"\nload average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
