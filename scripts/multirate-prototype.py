"""A multirate Galerkin variational step for the J2000 10-body scene, prototyped to count
its work before building it (issue 35; docs/solvers.md, "a multirate step").

The velocity form of the polynomial Galerkin step (the tables of src/integrator/velocity):
the slow bodies (the Sun and every planet but Mercury) take macro steps H with n modes and
m Gauss points; Mercury takes R micro steps h = H/R with its own modes, its momentum chained
through the micro steps. The discrete action is the slow bodies' kinetic and mutual potential
terms on the macro rule plus Mercury's kinetic term and its pairs with every slow body on the
micro rules (the same quadrature of each pair in both bodies' equations: a Galerkin
variational integrator, so symplectic, and momentum-conserving, which |P| checks). Modes:

  single N M DIV                the single-rate step (h = 100/DIV d), no freezing: checks the
                                prototype against gvi's error
  gauss-seidel N M DIV R NF MF  slow bodies then Mercury, each solved to convergence with the
                                other's curve fixed, rounds until neither moves
  joint N M DIV R NF MF         joint Picard iterations until the slow bodies converge, then
                                Mercury alone micro step by micro step, then a confirmation
  scene-without-mercury         the scene with Mercury's mass folded into the Sun (TOML)

Counts pair-node evaluations (a pair of bodies at one quadrature node) per 100 days and
measures the largest position error at the 100 sample times against the study's reference:

  gvi work-precision solar-system --write-reference out/reference-solar-system.csv
  python3 scripts/multirate-prototype.py gauss-seidel 9 8 3 3 9 8     (needs numpy)
"""
import argparse, csv, os, sys, tomllib
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def scene_without_mercury():
    """The J2000 scene with Mercury's mass folded into the Sun (TOML on stdout)."""
    text = open(os.path.join(ROOT, 'scenes', 'solar-system.toml')).read()
    head, *parts = text.split('[[system.bodies]]')
    sun, mercury = parts[0], parts[1]
    gm = lambda t: float(t.split('gm = ')[1].split()[0])
    old = sun.split('gm = ')[1].split()[0]
    sun = sun.replace(old, repr(gm(sun) + gm(mercury)), 1)
    head = head.replace('name = "solar-system"', 'name = "solar-system-without-mercury"')
    sys.stdout.write(head + '[[system.bodies]]' + sun + ''.join('[[system.bodies]]' + b for b in parts[2:]))


if __name__ == '__main__' and sys.argv[1:2] == ['scene-without-mercury']:
    scene_without_mercury()
    sys.exit()

import numpy as np  # noqa: E402
from numpy.polynomial import legendre as L

scene = tomllib.load(open(os.path.join(ROOT, 'scenes', 'solar-system.toml'), 'rb'))
bodies = scene['system']['bodies']
mass = np.array([b['gm'] for b in bodies])
N = len(mass)
REF = os.environ.get('REFERENCE', 'out/reference-solar-system.csv')
ref = [list(map(float, r)) for r in list(csv.reader(open(REF)))[1:]] if os.path.exists(REF) else None
q0 = np.array(ref[0][2:]).reshape(N, 3) if ref else np.array([b['q'] for b in bodies])
v0 = np.array([b['v'] for b in bodies])
v0 -= (mass[:, None] * v0).sum(0) / mass.sum()
p0 = mass[:, None] * v0


def tables(n, m):
    k = n - 1
    x, w = L.leggauss(m)
    c = (x + 1) / 2
    b = w / 2
    def modes(tau):
        xx = 2 * np.asarray(tau) - 1
        P = np.array([L.legval(xx, np.eye(k + 1)[a]) for a in range(k + 1)])  # (k+1, len)
        vals = np.array([np.sqrt(2 * a + 1) * P[a] for a in range(k)])
        ints = np.array([np.asarray(tau) if a == 0 else (P[a + 1] - P[a - 1]) / (2 * np.sqrt(2 * a + 1)) for a in range(k)])
        return vals.T, ints.T  # (len, k)
    pt, it = modes(c)
    psi = it.copy(); psi[:, 0] -= 1
    pt1, _ = modes(c + 1)
    E = (b[:, None] * pt).T @ pt1  # c_next = E c_prev
    return dict(k=k, m=m, c=c, b=b, iota=it, psi=psi, E=E, modes=modes)


def pair_forces(qa, qb, ma, mb):
    """force on a from b (arrays (..., 3)), G = 1."""
    d = qb - qa
    r2 = (d * d).sum(-1)
    return (ma * mb / (r2 * np.sqrt(r2)))[..., None] * d


def forces_all(q):  # q (..., N, 3)
    f = np.zeros_like(q)
    for i in range(N):
        for j in range(i + 1, N):
            x = pair_forces(q[..., i, :], q[..., j, :], mass[i], mass[j])
            f[..., i, :] += x
            f[..., j, :] -= x
    return f


count = dict(pairs=0)
TOL = 2e-16
# The coupling forces on the slow bodies are taken once per Gauss-Seidel round (their
# dependence on the slow curves is O(Mercury's mass)); the next round corrects them.
FIX_FS = True


def single_run(n, m, h, steps_per_sample, samples):
    T = tables(n, m)
    k = T['k']
    q, p = q0.copy(), p0.copy()
    cprev = None
    err = 0.0
    for s in range(samples):
        for _ in range(steps_per_sample):
            c = np.tile(p / mass[:, None], (k, 1, 1)) * (np.arange(k) == 0)[:, None, None] if cprev is None else np.einsum('ba,aij->bij', T['E'], cprev)
            last = np.inf
            for it in range(60):
                qn = q + h * np.einsum('ja,axy->jxy', T['iota'], c)
                f = forces_all(qn); count['pairs'] += 45 * m
                F = mass[None, :, None] * c + h * np.einsum('jb,jxy->bxy', T['psi'], T['b'][:, None, None] * f)
                F[0] -= p
                d = -F / mass[None, :, None]
                c = c + d
                if np.abs(d).max() <= TOL * np.abs(c).max():
                    break
            qn = q + h * np.einsum('ja,axy->jxy', T['iota'], c)
            f = forces_all(qn); count['pairs'] += 45 * m
            q = q + h * c[0]
            p = p + h * np.einsum('j,jxy->xy', T['b'], f)
            cprev = c
        e = np.sqrt(((q - np.array(ref[s + 1][2:]).reshape(N, 3)) ** 2).sum(-1)).max()
        err = max(err, e)
    return err


FAST = [1]
SLOW = [i for i in range(N) if i not in FAST]


def multirate_run(n, m, H, R, nf, mf, steps_per_sample, samples, verbose=False):
    Ts, Tf = tables(n, m), tables(nf, mf)
    ks, kf = Ts['k'], Tf['k']
    h = H / R
    # slow modes at the micro nodes, in macro time
    tau = np.concatenate([(r + Tf['c']) / R for r in range(R)])
    _, iota_mu = Ts['modes'](tau)
    psi_mu = iota_mu.copy(); psi_mu[:, 0] -= 1
    bmu = np.concatenate([Tf['b'] for _ in range(R)]) / R  # weights in macro units
    ms, mfm = mass[SLOW], mass[FAST]
    q, p = q0.copy(), p0.copy()
    cS_prev = cF_prev = None
    err = 0.0
    stats = dict(fast_iters=0, slow_iters=0, rounds=0, steps=0)
    for s in range(samples):
        for _ in range(steps_per_sample):
            stats['steps'] += 1
            qS, pS, qF, pF = q[SLOW], p[SLOW], q[FAST], p[FAST]
            if cS_prev is None:
                cS = np.zeros((ks,) + qS.shape); cS[0] = pS / ms[:, None]
                cF = np.zeros((R, kf) + qF.shape); cF[:, 0] = pF / mfm[:, None]
            else:
                cS = np.einsum('ba,axy->bxy', Ts['E'], cS_prev)
                cF = np.empty_like(cF_prev)
                prev = cF_prev[-1]
                for r in range(R):
                    prev = np.einsum('ba,axy->bxy', Tf['E'], prev)
                    cF[r] = prev
            qF_mu = np.zeros((R * mf,) + qF.shape)
            qf_ = qF.copy()
            for r in range(R):
                qF_mu[r * mf:(r + 1) * mf] = qf_ + h * np.einsum('ja,axy->jxy', Tf['iota'], cF[r])
                qf_ = qf_ + h * cF[r][0]
            for rnd in range(12):
                stats['rounds'] += 1
                # (b) the slow bodies with Mercury's curve fixed
                slow_change = 0.0
                for it in range(60):
                    qn = qS + H * np.einsum('ja,axy->jxy', Ts['iota'], cS)
                    qfull = np.zeros((m, N, 3)); qfull[:, SLOW] = qn
                    fss = forces_all_subset(qn)
                    count['pairs'] += len(SLOW) * (len(SLOW) - 1) // 2 * m
                    if it == 0 or not FIX_FS:
                        qmu = qS + H * np.einsum('ja,axy->jxy', iota_mu, cS)
                        ffs = pair_forces(qmu[:, :, None, :], qF_mu[:, None, :, :], ms[None, :, None], mfm[None, None, :]).sum(2)
                        count['pairs'] += len(SLOW) * len(FAST) * R * mf
                    stats['slow_iters'] += 1
                    stats.setdefault(f'slow_r{min(rnd,3)}', 0); stats[f'slow_r{min(rnd,3)}'] += 1
                    F = ms[None, :, None] * cS + H * np.einsum('jb,jxy->bxy', Ts['psi'], Ts['b'][:, None, None] * fss) \
                        + H * np.einsum('jb,jxy->bxy', psi_mu, bmu[:, None, None] * ffs)
                    F[0] -= pS
                    d = -F / ms[None, :, None]
                    cS = cS + d
                    if it == 0:
                        slow_change = np.abs(d).max() / np.abs(cS).max()
                    if np.abs(d).max() <= TOL * np.abs(cS).max():
                        break
                # (a) Mercury's micro steps with the slow curves fixed
                qS_mu = qS + H * np.einsum('ja,axy->jxy', iota_mu, cS)  # (R*mf, S, 3)
                qf, pf = qF.copy(), pF.copy()
                fF_all = np.zeros((R * mf,) + qF.shape)
                fast_change = 0.0
                for r in range(R):
                    qs_r = qS_mu[r * mf:(r + 1) * mf]
                    c = cF[r]
                    for it in range(60):
                        qn = qf + h * np.einsum('ja,axy->jxy', Tf['iota'], c)
                        f = pair_forces(qn[:, :, None, :], qs_r[:, None, :, :], mfm[None, :, None], ms[None, None, :]).sum(2)
                        count['pairs'] += len(SLOW) * len(FAST) * mf
                        stats['fast_iters'] += 1
                        stats.setdefault(f'fast_r{min(rnd,3)}', 0); stats[f'fast_r{min(rnd,3)}'] += 1
                        F = mfm[None, :, None] * c + h * np.einsum('jb,jxy->bxy', Tf['psi'], Tf['b'][:, None, None] * f)
                        F[0] -= pf
                        d = -F / mfm[None, :, None]
                        c = c + d
                        if it == 0:
                            fast_change = max(fast_change, np.abs(d).max() / np.abs(c).max())
                        if np.abs(d).max() <= TOL * np.abs(c).max():
                            break
                    cF[r] = c
                    qn = qf + h * np.einsum('ja,axy->jxy', Tf['iota'], c)
                    f = pair_forces(qn[:, :, None, :], qs_r[:, None, :, :], mfm[None, :, None], ms[None, None, :]).sum(2)
                    qF_mu[r * mf:(r + 1) * mf] = qn
                    fF_all[r * mf:(r + 1) * mf] = f
                    pf = pf + h * np.einsum('j,jxy->xy', Tf['b'], f)
                    qf = qf + h * c[0]
                if rnd > 0 and fast_change <= 4 * TOL and slow_change <= 4 * TOL:
                    break
            qn = qS + H * np.einsum('ja,axy->jxy', Ts['iota'], cS)
            fss = forces_all_subset(qn)
            qmu = qS + H * np.einsum('ja,axy->jxy', iota_mu, cS)
            ffs = pair_forces(qmu[:, :, None, :], qF_mu[:, None, :, :], ms[None, :, None], mfm[None, None, :]).sum(2)
            q[SLOW] = qS + H * cS[0]
            p[SLOW] = pS + H * np.einsum('j,jxy->xy', Ts['b'], fss) + H * np.einsum('j,jxy->xy', bmu, ffs)
            q[FAST], p[FAST] = qf, pf
            cS_prev, cF_prev = cS, cF
        e = np.sqrt(((q - np.array(ref[s + 1][2:]).reshape(N, 3)) ** 2).sum(-1))
        err = max(err, e.max())
    P = p.sum(0)
    if verbose:
        print('  per-body max err last sample', e)
    return err, stats, np.abs(P).max()


def forces_all_subset(qs):
    ms = mass[SLOW]
    f = np.zeros_like(qs)
    nS = len(SLOW)
    for i in range(nS):
        for j in range(i + 1, nS):
            x = pair_forces(qs[..., i, :], qs[..., j, :], ms[i], ms[j])
            f[..., i, :] += x
            f[..., j, :] -= x
    return f


def multirate_joint(n, m, H, R, nf, mf, steps_per_sample, samples):
    """Joint Picard iterations (slow correction + Mercury's micro steps, momenta chained from
    the same iterate's forces) until the slow bodies converge; then Mercury alone, micro step
    by micro step to convergence (slow curves frozen); then one joint confirmation."""
    Ts, Tf = tables(n, m), tables(nf, mf)
    ks, kf = Ts['k'], Tf['k']
    h = H / R
    tau = np.concatenate([(r + Tf['c']) / R for r in range(R)])
    _, iota_mu = Ts['modes'](tau)
    psi_mu = iota_mu.copy(); psi_mu[:, 0] -= 1
    bmu = np.concatenate([Tf['b'] for _ in range(R)]) / R
    ms, mfm = mass[SLOW], mass[FAST]
    q, p = q0.copy(), p0.copy()
    cS_prev = cF_prev = None
    err = 0.0
    st = dict(joint=0, fast_only=0, steps=0, confirm_fail=0)

    def fast_curve(qF, cF):
        qmu = np.zeros((R * mf,) + qF.shape)
        ends = [qF.copy()]
        qf = qF.copy()
        for r in range(R):
            qmu[r * mf:(r + 1) * mf] = qf + h * np.einsum('ja,axy->jxy', Tf['iota'], cF[r])
            qf = qf + h * cF[r][0]
            ends.append(qf)
        return qmu, ends

    for s in range(samples):
        for _ in range(steps_per_sample):
            st['steps'] += 1
            qS, pS, qF, pF = q[SLOW], p[SLOW], q[FAST], p[FAST]
            if cS_prev is None:
                cS = np.zeros((ks,) + qS.shape); cS[0] = pS / ms[:, None]
                cF = np.zeros((R, kf) + qF.shape); cF[:, 0] = pF / mfm[:, None]
            else:
                cS = np.einsum('ba,axy->bxy', Ts['E'], cS_prev)
                cF = np.empty_like(cF_prev)
                prev = cF_prev[-1]
                for r in range(R):
                    prev = np.einsum('ba,axy->bxy', Tf['E'], prev)
                    cF[r] = prev
            phase = 'joint'
            prev_slow = np.inf
            for it in range(80):
                if phase in ('joint', 'confirm'):
                    st['joint'] += 1
                    count['pairs'] += (len(SLOW) * (len(SLOW) - 1) // 2) * m + len(SLOW) * R * mf
                    qn = qS + H * np.einsum('ja,axy->jxy', Ts['iota'], cS)
                    fss = forces_all_subset(qn)
                    qmu_s = qS + H * np.einsum('ja,axy->jxy', iota_mu, cS)
                    qmu_f, _ = fast_curve(qF, cF)
                    x = pair_forces(qmu_s[:, :, None, :], qmu_f[:, None, :, :], ms[None, :, None], mfm[None, None, :])
                    ffs = x.sum(2)           # on slow
                    ff = -x.sum(1)           # on Mercury
                    F = ms[None, :, None] * cS + H * np.einsum('jb,jxy->bxy', Ts['psi'], Ts['b'][:, None, None] * fss) \
                        + H * np.einsum('jb,jxy->bxy', psi_mu, bmu[:, None, None] * ffs)
                    F[0] -= pS
                    dS = -F / ms[None, :, None]
                    pf = pF.copy()
                    dF = np.empty_like(cF)
                    for r in range(R):
                        f = ff[r * mf:(r + 1) * mf]
                        Fr = mfm[None, :, None] * cF[r] + h * np.einsum('jb,jxy->bxy', Tf['psi'], Tf['b'][:, None, None] * f)
                        Fr[0] -= pf
                        dF[r] = -Fr / mfm[None, :, None]
                        pf = pf + h * np.einsum('j,jxy->xy', Tf['b'], f)
                    cS = cS + dS
                    cF = cF + dF
                    scale = max(np.abs(cS).max(), np.abs(cF).max())
                    sl, fa = np.abs(dS).max(), np.abs(dF).max()
                    if phase == 'confirm':
                        if max(sl, fa) <= 4 * TOL * scale:
                            break
                        st['confirm_fail'] += 1
                        phase = 'joint'
                        continue
                    theta = sl / prev_slow
                    prev_slow = sl
                    if sl <= TOL * scale or (theta < 0.5 and theta / (1 - theta) * sl <= TOL * scale):
                        phase = 'fast'
                else:
                    # Mercury alone, micro step by micro step to convergence, slow curves frozen
                    qmu_s = qS + H * np.einsum('ja,axy->jxy', iota_mu, cS)
                    qf, pf = qF.copy(), pF.copy()
                    for r in range(R):
                        qs_r = qmu_s[r * mf:(r + 1) * mf]
                        c = cF[r]
                        prev = np.inf
                        for _k in range(60):
                            st['fast_only'] += 1
                            count['pairs'] += len(SLOW) * mf
                            qn = qf + h * np.einsum('ja,axy->jxy', Tf['iota'], c)
                            f = pair_forces(qn[:, :, None, :], qs_r[:, None, :, :], mfm[None, :, None], ms[None, None, :]).sum(2)
                            Fr = mfm[None, :, None] * c + h * np.einsum('jb,jxy->bxy', Tf['psi'], Tf['b'][:, None, None] * f)
                            Fr[0] -= pf
                            d = -Fr / mfm[None, :, None]
                            c = c + d
                            dd = np.abs(d).max(); th = dd / prev; prev = dd
                            if dd <= TOL * np.abs(c).max() or (th < 0.5 and th / (1 - th) * dd <= TOL * np.abs(c).max()):
                                break
                        cF[r] = c
                        qn = qf + h * np.einsum('ja,axy->jxy', Tf['iota'], c)
                        f = pair_forces(qn[:, :, None, :], qs_r[:, None, :, :], mfm[None, :, None], ms[None, None, :]).sum(2)
                        pf = pf + h * np.einsum('j,jxy->xy', Tf['b'], f)
                        qf = qf + h * c[0]
                    phase = 'confirm'
            # step end from the final iterate's forces
            qn = qS + H * np.einsum('ja,axy->jxy', Ts['iota'], cS)
            fss = forces_all_subset(qn)
            qmu_s = qS + H * np.einsum('ja,axy->jxy', iota_mu, cS)
            qmu_f, ends = fast_curve(qF, cF)
            x = pair_forces(qmu_s[:, :, None, :], qmu_f[:, None, :, :], ms[None, :, None], mfm[None, None, :])
            q[SLOW] = qS + H * cS[0]
            p[SLOW] = pS + H * np.einsum('j,jxy->xy', Ts['b'], fss) + H * np.einsum('j,jxy->xy', bmu, x.sum(2))
            q[FAST] = ends[-1]
            p[FAST] = pF + h * np.einsum('j,jxy->xy', np.concatenate([Tf['b']] * R), -x.sum(1))
            cS_prev, cF_prev = cS, cF
        e = np.sqrt(((q - np.array(ref[s + 1][2:]).reshape(N, 3)) ** 2).sum(-1))
        err = max(err, e.max())
    steps = st['steps']
    print(f'joint n={n} m={m} H={H:.3f} R={R} nf={nf} mf={mf}: err {err:.3e}, |P| {np.abs(p.sum(0)).max():.1e}; per macro step: joint {st["joint"]/steps:.2f}, '
          f'Mercury-only {st["fast_only"]/steps:.2f} ({st["fast_only"]/steps/R:.2f} per micro step), confirmations failed {st["confirm_fail"]/steps:.2f}; '
          f'pair-node evals per 100 d {count["pairs"]/steps*steps_per_sample:.0f}')




if __name__ == '__main__':
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('mode', choices=['single', 'gauss-seidel', 'joint', 'scene-without-mercury'])
    ap.add_argument('numbers', type=int, nargs='*', help='N M DIV [R NF MF]: slow n, Gauss points, steps per 100 d; micro steps, Mercury n and points')
    ap.add_argument('--samples', type=int, default=100)
    a = ap.parse_args()
    if ref is None:
        sys.exit(f'no reference at {REF}: gvi work-precision solar-system --write-reference {REF}')
    if a.mode == 'single':
        n, m, div = a.numbers
        e = single_run(n, m, 100.0 / div, div, a.samples)
        print(f'single n={n} m={m} h={100/div:.3f}: err {e:.3e}, pair-node evaluations per 100 d {count["pairs"]/a.samples:.0f}')
    elif a.mode == 'gauss-seidel':
        n, m, div, R, nf, mf = a.numbers
        e, st, P = multirate_run(n, m, 100.0 / div, R, nf, mf, div, a.samples)
        steps = st['steps']
        print(f'gauss-seidel n={n} m={m} H={100/div:.3f} R={R} nf={nf} mf={mf}: err {e:.3e}, |P| {P:.1e}; per macro step: '
              f'Mercury iterations {st["fast_iters"]/steps:.1f}, slow iterations {st["slow_iters"]/steps:.2f}, rounds {st["rounds"]/steps:.2f}; '
              f'pair-node evaluations per 100 d {count["pairs"]/steps*div:.0f}')
    else:
        n, m, div, R, nf, mf = a.numbers
        multirate_joint(n, m, 100.0 / div, R, nf, mf, div, a.samples)
