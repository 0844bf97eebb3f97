#!/usr/bin/env python3
"""Why butterfly I, moth I and Broucke R1 are not built-in periodic scenes (periodic-orbits.md).

For butterfly I and moth I (Šuvakov & Dmitrašinović, PRL 110, 114301 (2013); 15-digit data
of Šuvakov & Dmitrašinović, Am. J. Phys. 82, 609 (2014), Table I): x1 = (-1, 0), x2 = (1, 0),
x3 = 0, v1 = v2 = (p1, p2), v3 = -2 (p1, p2), G = m = 1. Time-steps one published period with
`gvi run` (the figure-eight scene supplies three unit masses in the plane; its state is
replaced) and prints the distance from closing, the closest approach of two bodies and the
size of Fourier modes k of x1(t) and x2(t) over the period.

Usage: scripts/suvakov-orbits.py [path/to/gvi]   (default target/release/gvi)
Pure Python (no numpy).
"""
import cmath
import csv
import math
import subprocess
import sys
import tempfile

def suvakov(name, p1, p2, period):
    """x1 = (-1, 0), x2 = (1, 0), x3 = 0, v1 = v2 = (p1, p2), v3 = -2 (p1, p2)."""
    return name, [-1.0, 0.0, 1.0, 0.0, 0.0, 0.0], [p1, p2, p1, p2, -2 * p1, -2 * p2], period


ORBITS = [
    suvakov("butterfly I", 0.306892758965492, 0.125506782829762, 6.23564136316479),
    suvakov("moth I", 0.464445237398184, 0.396059973403921, 14.8939113169584),
    # Broucke R1 (R. Broucke, Celest. Mech. 12, 439 (1975)), 10-digit data as listed in the
    # Šuvakov–Dmitrašinović gallery (E = -1.464959, L = 1.606147).
    ("Broucke R1", [0.8083106230, 0.0, -0.4954148566, 0.0, -0.3128957664, 0.0],
     [0.0, 0.9901979166, 0.0, -2.7171431768, 0.0, 1.7269452602], 5.226525),
]
STEPS = 16384
MODES = [16, 32, 64, 128, 256, 512]


def main():
    gvi = sys.argv[1] if len(sys.argv) > 1 else "target/release/gvi"
    for name, q0, p0, period in ORBITS:
        with tempfile.NamedTemporaryFile(suffix=".csv") as out:
            subprocess.run(
                [gvi, "run", "figure-eight", "--q0=" + ",".join(map(repr, q0)),
                 "--p0=" + ",".join(map(repr, p0)), "--h", repr(period / STEPS),
                 "--steps", str(STEPS), "--n", "16", "--format", "csv", "--output", out.name],
                check=True, capture_output=True)
            rows = list(csv.reader(open(out.name)))[1:]
        states = [[float(v) for v in r[2:14]] for r in rows]
        energy = [float(r[14]) for r in rows]
        closing = max(abs(a - b) for a, b in zip(states[-1], states[0]))
        rmin = min(math.hypot(s[2 * i] - s[2 * j], s[2 * i + 1] - s[2 * j + 1])
                   for s in states for i, j in ((0, 1), (0, 2), (1, 2)))
        sizes = {}
        for body in (0, 1):
            x = [s[2 * body] for s in states[:-1]]
            n = len(x)
            sizes[body] = []
            for k in MODES:
                c = sum(v * cmath.exp(-2j * math.pi * k * m / n) for m, v in enumerate(x)) * 2 / n
                sizes[body].append(f"{k}: {abs(c):.1e}")
        print(f"{name}: T = {period}, energy {energy[0]:.15f} (drift "
              f"{max(abs(e - energy[0]) for e in energy):.1e}), closing after one period "
              f"{closing:.2e}, closest approach {rmin:.4f}")
        print(f"  |mode k| of x1(t): {', '.join(sizes[0])}")
        print(f"  |mode k| of x2(t): {', '.join(sizes[1])}")


if __name__ == "__main__":
    main()
