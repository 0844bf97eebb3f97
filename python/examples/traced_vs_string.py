"""The cost of a Lagrangian written as a Python function: traced once into the expression
tape, it is the tape of the same Lagrangian written as a string, so it integrates at the same
speed and gives the same trajectory bit for bit. Prints the one-time cost of building each
system and the integration time of each (Hénon–Heiles, n = 16, h = 1, 2000 steps; the two
integrations interleaved, the median of `rounds` rounds).

    python python/examples/traced_vs_string.py [rounds]
"""

import statistics
import sys
import time

import numpy as np

import galerkin_vi as gv

TEXT = "(x_dot^2 + y_dot^2)/2 - (x^2 + y^2)/2 - lam*(x^2*y - y^3/3)"


def henon_heiles(q, v, lam):
    x, y = q
    xd, yd = v
    return (xd**2 + yd**2) / 2 - (x**2 + y**2) / 2 - lam * (x**2 * y - y**3 / 3)


def build_traced():
    return gv.systems.from_function(henon_heiles, ["x", "y"], {"lam": 1.0})


def build_string():
    return gv.systems.Expression(TEXT, ["x", "y"], {"lam": 1.0})


def median_seconds(f, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def measure(rounds=7, steps=2000):
    """The build and integration times (seconds) and whether the trajectories are equal."""
    traced, string = build_traced(), build_string()
    gvi = gv.Integrator(n=16, h=1.0)
    run = {
        name: (lambda s=s: gvi.integrate(s, [0.0, 0.1], [0.35, 0.0], steps))
        for name, s in (("traced", traced), ("string", string))
    }
    a, b = run["traced"](), run["string"]()
    same = (
        traced.tape == string.tape
        and np.array_equal(a.q, b.q)
        and np.array_equal(a.p, b.p)
    )
    integrate = {"traced": [], "string": []}
    for _ in range(rounds):
        for name in ("traced", "string"):
            start = time.perf_counter()
            run[name]()
            integrate[name].append(time.perf_counter() - start)
    return {
        "build_traced": median_seconds(build_traced, 200),
        "build_string": median_seconds(build_string, 200),
        "integrate_traced": statistics.median(integrate["traced"]),
        "integrate_string": statistics.median(integrate["string"]),
        "bit_identical": same,
    }


if __name__ == "__main__":
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 7
    m = measure(rounds)
    traced, string = m["build_traced"] * 1e6, m["build_string"] * 1e6
    print(f"build:      traced {traced:.0f} µs, string {string:.0f} µs")
    ratio = m["integrate_traced"] / m["integrate_string"]
    print(
        f"integrate:  traced {m['integrate_traced'] * 1e3:.1f} ms, string "
        f"{m['integrate_string'] * 1e3:.1f} ms (ratio {ratio:.3f}; 2000 steps, median of "
        f"{rounds})"
    )
    print(f"same tape and bit-identical trajectories: {m['bit_identical']}")
