"""The examples run at small scale: the Dask ensemble on a local cluster (skipped without
dask) equals the same chunks run in-process, and the plot script writes its figure (skipped
without matplotlib)."""

import importlib.util
import pathlib

import numpy as np
import pytest

EXAMPLES = pathlib.Path(__file__).resolve().parents[1] / "examples"


def load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_dask_ensemble_equals_in_process_run():
    distributed = pytest.importorskip("dask.distributed")
    example = load("dask_ensemble")
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    )
    client = distributed.Client(cluster)
    try:
        rows = example.run_ensemble(client, members=12, chunk=5, steps=10)
    finally:
        client.close()
        cluster.close()
    q0s, p0s = example.initial_conditions(12, 1e-3, 0)
    local = example.run_chunk(q0s, p0s, 10, 16, 1.0)
    assert rows.shape == (12, 5)
    np.testing.assert_array_equal(rows, local)
    assert rows[:, 4].max() < 1e-6


def test_plot_kepler_writes_a_png(tmp_path):
    pytest.importorskip("matplotlib")
    out = tmp_path / "kepler.png"
    assert load("plot_kepler").main(str(out)) == 0
    assert out.stat().st_size > 10_000


def test_traced_vs_string_example_finds_the_same_tape():
    m = load("traced_vs_string").measure(rounds=1, steps=50)
    assert m["bit_identical"]
    assert m["integrate_traced"] > 0 and m["integrate_string"] > 0


def test_many_vs_loop_example_results_are_equal():
    loop, many, equal = load("many_vs_loop").measure(rounds=1, members=4, steps=10)
    assert equal and loop > 0 and many > 0
