#!/usr/bin/env python3
"""How well can a step's guess be extrapolated from earlier steps' curves? (issue 35)

The velocity form starts each step from the previous step's velocity polynomial continued one
step ahead (`VelocityTables::extrapolate`). On J2000 its first correction is 1e-5 of the modes
near Mercury's aphelion and 1e-2 ... 1e-1 near perihelion (`lab/examples/step_stats.rs`). This
script asks whether more history helps: for a Kepler orbit with e = 0.2 (Mercury's) at
h*omega = 0.89 and 1.19 (Mercury at h = 12.5 and 16.7 d), it fits the exact velocity's
Legendre projections on the r previous steps with one polynomial of degree d (least squares),
continues it over the next step and compares its projection with the exact one (max error
relative to the largest mode). r = 1, d = k - 1 is the crate's extrapolation.

    python3 scripts/guess-extrapolation.py          # needs numpy
"""
import numpy as np
from numpy.polynomial import legendre as L


def kepler_velocity(t, e):
    """Velocity on the Kepler orbit a = 1, mu = 1 (period 2 pi) at mean anomaly t from periapsis."""
    big_e = t.copy()
    for _ in range(50):
        big_e = big_e - (big_e - e * np.sin(big_e) - t) / (1 - e * np.cos(big_e))
    rate = 1 / (1 - e * np.cos(big_e))
    return np.stack([-np.sin(big_e) * rate, np.sqrt(1 - e * e) * np.cos(big_e) * rate], -1)


def orthonormal(x, k):
    """sqrt(2a + 1) P_a(x), a < k, at the points x (the crate's modes on [0, 1] at x = 2 tau - 1)."""
    return np.stack([np.sqrt(2 * a + 1) * L.legval(x, np.eye(k)[a]) for a in range(k)], 1)


def modes(f, k, points=40):
    """The k Legendre modes of f(tau) on [0, 1] (L2 projection by Gauss-Legendre)."""
    x, w = L.leggauss(points)
    return orthonormal(x, k).T @ ((w / 2)[:, None] * f((x + 1) / 2))


def values(c, tau):
    return orthonormal(2 * tau - 1, c.shape[0]) @ c


def extrapolate(previous, k, d):
    """Fit degree d to the curves of len(previous) steps (most recent first) and project the fit
    on the next step."""
    r = len(previous)
    x, w = L.leggauss(max(k, d + 1))
    tau = (x + 1) / 2
    t = np.concatenate([tau - (i + 1) for i in range(r)])
    weights = np.sqrt(np.concatenate([w / 2] * r))[:, None]
    v = np.concatenate([values(c, tau) for c in previous])
    y = 2 * (t + r) / r - 1
    coef = np.linalg.lstsq(L.legvander(y, d) * weights, v * weights, rcond=None)[0]
    return modes(lambda s: L.legvander(2 * (s + r) / r - 1, d) @ coef, k)


def main():
    k, e = 9, 0.2  # n = 10: nine velocity modes; Mercury's eccentricity
    fits = [(1, k - 1), (2, k - 1), (2, k + 1), (2, k + 3), (2, 2 * k - 1), (3, k + 3), (3, k + 6),
            (3, 2 * k), (3, 3 * k - 1), (4, 2 * k), (4, 3 * k)]
    print("r = steps fitted, d = degree; error of the guess relative to the largest mode")
    for hw, label in [(0.89, "h*omega = 0.89 (Mercury, h = 12.5 d)"),
                      (1.19, "h*omega = 1.19 (Mercury, h = 16.7 d)")]:
        print(label)
        for t0, where in [(0.0, "periapsis"), (np.pi, "apoapsis ")]:
            exact = lambda s0: modes(lambda tau: kepler_velocity(s0 + hw * tau, e), k)
            target = exact(t0)
            previous = [exact(t0 - hw * (i + 1)) for i in range(4)]
            errors = []
            for r, d in fits:
                guess = extrapolate(previous[:r], k, d)
                errors.append(f"r{r} d{d}: {np.abs(guess - target).max() / np.abs(target).max():.1e}")
            print(f"  {where}  " + ", ".join(errors))


if __name__ == "__main__":
    main()
