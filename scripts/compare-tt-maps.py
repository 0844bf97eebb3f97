#!/usr/bin/env python3
"""Same one-step maps of a time-transformed method, before and after a change to the stage
equations (examples/record_maps/, which scripts/same-maps.sh compares, has no time-transformed
case).

    python3 scripts/compare-tt-maps.py BASE_GVI NEW_GVI

runs `BASE_GVI run pythagorean --t-end 5` (through the first close encounters) and
`BASE_GVI run kepler-e099 --t-end 12.6` (two orbits at e = 0.99), takes every 150th
(pythagorean) or 10th (Kepler) step end as an initial state, and from each takes ONE fictitious
step with both binaries, with the step Δs set to the physical step that led to the state (so
that the normalised monitor gives the run's own step there). Prints, per state, the largest
difference of q and of p relative to the largest |q| and |p|, and how many of the maps are
bit-for-bit the same. Exits 1 if a relative difference exceeds --tol (default 1e-14).
"""

import argparse
import csv
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def open_scene(name, tmp):
    """The scene without its t_end, so that `--steps 1` ends the run after one step."""
    text = (ROOT / "scenes" / f"{name}.toml").read_text()
    path = Path(tmp) / f"{name}-open.toml"
    path.write_text("\n".join(l for l in text.splitlines() if not l.startswith("t_end")) + "\n")
    return path


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def state(row, dim):
    return [row[f"q{i}"] for i in range(dim)], [row[f"p{i}"] for i in range(dim)]


def one_step(gvi, scene, h, q, p, out):
    cmd = [gvi, "run", str(scene), "--steps", "1", "--h", h, "--q0", ",".join(q),
           "--p0", ",".join(p), "--output", str(out)]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode:
        sys.exit(f"{' '.join(cmd)}: {done.stderr[-400:]}")
    last = rows(out)[-1]
    return [float(x) for x in state(last, len(q))[0] + state(last, len(q))[1]]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("base")
    ap.add_argument("new")
    ap.add_argument("--tol", type=float, default=1e-14)
    args = ap.parse_args()
    worst, same, total = 0.0, 0, 0
    with tempfile.TemporaryDirectory() as tmp:
        for scene, t_end, every, dim in (("pythagorean", "5", 150, 6), ("kepler-e099", "12.6", 10, 2)):
            run = Path(tmp) / f"{scene}.csv"
            subprocess.run([args.base, "run", scene, "--t-end", t_end, "--output", str(run)],
                           capture_output=True, check=True)
            opened = open_scene(scene, tmp)
            for row in rows(run)[every::every]:
                q, p = state(row, dim)
                a = one_step(args.base, opened, row["dt"], q, p, Path(tmp) / "a.csv")
                b = one_step(args.new, opened, row["dt"], q, p, Path(tmp) / "b.csv")
                qs, ps = max(map(abs, a[:dim])), max(map(abs, a[dim:]))
                dq = max(abs(x - y) for x, y in zip(a[:dim], b[:dim])) / qs
                dp = max(abs(x - y) for x, y in zip(a[dim:], b[dim:])) / ps
                print(f"{scene} t = {float(row['t']):.4f} Δs = {float(row['dt']):.2e}: "
                      f"dq/|q| {dq:.1e}, dp/|p| {dp:.1e}")
                worst = max(worst, dq, dp)
                same += a == b
                total += 1
    print(f"{same} of {total} one-step maps bit-for-bit the same; largest relative difference {worst:.1e}")
    sys.exit(1 if worst > args.tol else 0)


if __name__ == "__main__":
    main()
