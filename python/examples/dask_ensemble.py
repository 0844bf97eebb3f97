"""An ensemble over a Dask cluster: one task per chunk of initial conditions.

Each task calls ``galerkin_vi.integrate_many`` on its chunk (which itself uses every core of
its worker, the GIL released) and returns only small per-member results (final state and
energy error), so that the trajectories never travel over the network.

Locally (a LocalCluster of worker processes on this machine):

    pip install ./python "dask[distributed]"
    python python/examples/dask_ensemble.py --members 64 --chunk 16

On a cluster, start ``dask scheduler`` on one node and ``dask worker tcp://HOST:8786`` on the
others (each with ``pip install ./python``), then point the same script at the scheduler:

    python python/examples/dask_ensemble.py --scheduler tcp://HOST:8786 --members 100000
"""

import argparse
import sys
import time

import numpy as np


def initial_conditions(members, sigma, seed):
    """Kepler's e = 0.6 orbit, perturbed: q0s, p0s of shape (members, 2)."""
    rng = np.random.default_rng(seed)
    q0s = np.array([0.4, 0.0]) + sigma * rng.standard_normal((members, 2))
    p0s = np.array([0.0, 2.0]) + sigma * rng.standard_normal((members, 2))
    return q0s, p0s


def run_chunk(q0s, p0s, steps, n, h):
    """One task: integrate a chunk and reduce each member to a row
    (final q, final p, max relative energy error)."""
    import galerkin_vi as gv

    system = gv.systems.Kepler(mu=1.0)
    trajs = gv.integrate_many(system, q0s, p0s, steps, integrator=gv.Integrator(n=n, h=h))
    rows = []
    for traj in trajs:
        energy = traj.invariants["energy"]
        rel = np.abs((energy - energy[0]) / energy[0]).max()
        rows.append(np.concatenate([traj.q[-1], traj.p[-1], [rel]]))
    return np.array(rows)


def run_ensemble(client, members=64, chunk=16, sigma=1e-3, seed=0, steps=50, n=16, h=1.0):
    """Scatter the chunks as tasks, gather the rows in member order."""
    q0s, p0s = initial_conditions(members, sigma, seed)
    futures = [
        client.submit(run_chunk, q0s[i : i + chunk], p0s[i : i + chunk], steps, n, h, pure=False)
        for i in range(0, members, chunk)
    ]
    return np.vstack(client.gather(futures))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scheduler", help="address of a running Dask scheduler")
    parser.add_argument("--members", type=int, default=64)
    parser.add_argument("--chunk", type=int, default=16)
    parser.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    parser.add_argument("--steps", type=int, default=50)
    args = parser.parse_args(argv)
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        print('dask is not installed: pip install "dask[distributed]"', file=sys.stderr)
        return 0
    if args.scheduler:
        client = Client(args.scheduler)
        cluster = None
    else:
        # One thread per worker process: integrate_many parallelises inside each task.
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True)
        client = Client(cluster)
    try:
        start = time.perf_counter()
        rows = run_ensemble(client, members=args.members, chunk=args.chunk, steps=args.steps)
        seconds = time.perf_counter() - start
        print(f"{len(rows)} members in {seconds:.2f} s ({len(rows) / seconds:.1f} members/s)")
        print(f"max relative energy error over the ensemble: {rows[:, 4].max():.3e}")
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
