"""integrate_many against a loop of integrate: 64 perturbed Kepler members (n = 16, h = 1,
200 steps), the median of `rounds` interleaved rounds; the results are equal array for array.

    python python/examples/many_vs_loop.py [rounds]
"""

import statistics
import sys
import time

import numpy as np

import galerkin_vi as gv


def measure(rounds=3, members=64, steps=200):
    """Median seconds of the loop and of integrate_many, and whether their results agree."""
    rng = np.random.default_rng(0)
    q0s = np.array([0.4, 0.0]) + 1e-3 * rng.standard_normal((members, 2))
    p0s = np.array([0.0, 2.0]) + 1e-3 * rng.standard_normal((members, 2))
    kepler, gvi = gv.systems.Kepler(), gv.Integrator(n=16, h=1.0)
    times = {"loop": [], "many": []}
    for _ in range(rounds):
        start = time.perf_counter()
        loop = [gvi.integrate(kepler, q, p, steps) for q, p in zip(q0s, p0s)]
        times["loop"].append(time.perf_counter() - start)
        start = time.perf_counter()
        many = gv.integrate_many(kepler, q0s, p0s, steps, integrator=gvi)
        times["many"].append(time.perf_counter() - start)
    equal = all(np.array_equal(a.q, b.q) and np.array_equal(a.p, b.p) for a, b in zip(loop, many))
    return statistics.median(times["loop"]), statistics.median(times["many"]), equal


if __name__ == "__main__":
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    loop, many, equal = measure(rounds)
    print(
        f"loop {loop:.2f} s, integrate_many {many:.2f} s, {loop / many:.2f}x "
        f"(median of {rounds}); equal: {equal}"
    )
