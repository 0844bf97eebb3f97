"""Plot the Kepler orbit of the paper's run (n = 32, h = 2, 100 steps) with its dense output.

    pip install ./python matplotlib
    python python/examples/plot_kepler.py kepler.png

The markers are the step ends (one every h = 2, a third of an orbit); the line is the Galerkin
curve sampled 40 times per step, which follows the exact ellipse to ~4e-6.
"""

import sys

import numpy as np

import galerkin_vi as gv


def main(path="kepler.png"):
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: pip install matplotlib", file=sys.stderr)
        return 0
    traj = gv.run_scene("kepler")
    t = np.linspace(0.0, traj.t[-1], 40 * traj.steps + 1)
    q = traj.position_at(t)
    fig, ax = plt.subplots(figsize=(5, 5))
    ax.plot(q[:, 0], q[:, 1], lw=0.8, label="Galerkin curves (dense output)")
    ax.plot(traj.q[:, 0], traj.q[:, 1], "o", ms=3, label=f"step ends (h = {traj.h})")
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_title(f"Kepler, e = 0.6, n = {traj.n}, {traj.steps} steps")
    ax.legend(loc="lower left", fontsize=8)
    fig.savefig(path, dpi=120, bbox_inches="tight")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
