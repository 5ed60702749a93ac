"""Dask sweeps on real LocalClusters of processes: identical to the serial path, partial results when
a point fails or kills its worker, validation before anything starts, cancellation."""

from __future__ import annotations

import os
import sys
import threading
import time

import pytest

from paraspace.kinematics import distributed
from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.distributed import close_clients, default_workers, grid_designs, shared_client, sweep_grid
from paraspace.kinematics.progress import Cancelled
from paraspace.kinematics.sweep import evaluate_design
from paraspace.kinematics.warmup import is_warm
from paraspace.kinematics.workspace import WorkspaceSettings

BOOKKEEPING = ("params", "index", "ok", "compute_seconds")
COARSE = WorkspaceSettings(voxel=10.0)


def _strip(row: dict) -> dict:
    return {k: v for k, v in row.items() if k not in BOOKKEEPING}


# ----- units of work used to inject failures (module level: pickled by value, see fixture) -----

def evaluate_or_die(design, settings, *, orientation=None):
    """Kills its worker process for a = 60, else the real evaluate_design."""
    if design.a == 60.0:
        os._exit(13)
    return evaluate_design(design, settings, orientation=orientation)


def evaluate_or_raise(design, settings, *, orientation=None):
    """Raises for l_s = 60, else the real evaluate_design."""
    if design.l_s == 60.0:
        raise ArithmeticError("injected failure\nfor l_s = 60")
    return evaluate_design(design, settings, orientation=orientation)


def evaluate_slowly(design, settings, *, orientation=None):
    time.sleep(0.5)
    return evaluate_design(design, settings, orientation=orientation)


@pytest.fixture(scope="module")
def cluster():
    """A separate LocalCluster (2 process workers) reached through its scheduler address."""
    import cloudpickle
    import dask
    from distributed import LocalCluster

    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    # a point whose worker dies is given up at the first death (default: after 3)
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        c = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                         dashboard_address=None, silence_logs=50)
        yield c
        close_clients()  # the warm clients kept by the sweeps, before their scheduler goes
        c.close()


def test_validation_before_anything_starts():
    with pytest.raises(ParameterError, match="a = -1 is invalid"):
        sweep_grid(Design(), {"a": [50, -1]}, COARSE)
    with pytest.raises(ParameterError, match="params"):
        sweep_grid(Design(), {"zz": [1]}, COARSE)
    with pytest.raises(ParameterError, match="d_s"):  # d_s > r is rejected per point
        sweep_grid(Design(), {"d_s": [50, 150]}, COARSE)
    with pytest.raises(ParameterError, match="workers"):
        sweep_grid(Design(), {"a": [50]}, COARSE, scheduler="tcp://127.0.0.1:1", n_workers=2)
    with pytest.raises(ParameterError, match="workers"):
        sweep_grid(Design(), {"a": [50]}, COARSE, n_workers=0)
    idx, vals, designs = grid_designs(Design(), {"a": [40, 60], "d_s": [30, 40, 50]})
    assert idx[:4] == [(0, 0), (0, 1), (0, 2), (1, 0)]
    assert vals[3] == {"a": 60.0, "d_s": 30.0} and designs[3].a == 60.0 and designs[3].d_s == 30.0


@pytest.mark.slow
def test_local_cluster_identical_to_serial():
    """Default path: a LocalCluster of 2 process workers started by the first call, kept warm
    (same client, same worker processes) for the second, closed by close_clients."""
    params = {"a": [40.0, 60.0], "l_s": [40.0, 60.0]}
    seen = []
    close_clients()
    t0 = time.perf_counter()
    rows = sweep_grid(Design(), params, COARSE, n_workers=2, progress=lambda f, m: seen.append((f, m)))
    t_dist = time.perf_counter() - t0
    client = shared_client(None, 2)
    pids = sorted(client.run(os.getpid).values())
    assert len(pids) == 2 and os.getpid() not in pids
    # the workers were warmed when they joined: every kernel compiled or loaded in each of them
    assert all(client.run(is_warm).values())
    again = sweep_grid(Design(), {"a": [60.0], "l_s": [40.0]}, COARSE, n_workers=2)
    assert shared_client(None, 2) is client and sorted(client.run(os.getpid).values()) == pids  # no new cluster
    assert _strip(again[0]) == _strip(rows[2])
    assert close_clients() == 1 and client.status != "running"
    t0 = time.perf_counter()
    serial = [evaluate_design(Design(a=a, l_s=l), COARSE) for a in params["a"] for l in params["l_s"]]
    t_ser = time.perf_counter() - t0
    print(f"4 points at h=10: dask (2 process workers, incl. start-up) {t_dist:.2f} s, serial {t_ser:.2f} s")
    assert len(rows) == 4 and all(r["ok"] for r in rows)
    assert [r["params"] for r in rows] == [{"a": a, "l_s": l} for a in params["a"] for l in params["l_s"]]
    assert [r["index"] for r in rows] == [[0, 0], [0, 1], [1, 0], [1, 1]]
    assert [_strip(r) for r in rows] == [_strip(s) for s in serial]
    assert all(r["volume"] > 0 for r in rows)
    assert seen[-1][0] == 1.0 and "4/4" in seen[-1][1]
    assert [f for f, _ in seen] == sorted(f for f, _ in seen)


@pytest.mark.slow
def test_worker_death_keeps_partial_results(cluster):
    params = {"a": [40.0, 60.0], "l_s": [50.0]}
    t0 = time.perf_counter()
    rows = sweep_grid(Design(), params, COARSE, scheduler=cluster.scheduler_address, evaluate=evaluate_or_die)
    print(f"sweep with a worker death: {time.perf_counter() - t0:.2f} s")
    assert [r["ok"] for r in rows] == [True, False]
    assert rows[0]["params"] == {"a": 40.0, "l_s": 50.0}
    assert _strip(rows[0]) == _strip(evaluate_design(Design(a=40.0, l_s=50.0), COARSE))
    bad = rows[1]
    assert bad["params"] == {"a": 60.0, "l_s": 50.0} and bad["design"]["a"] == 60.0
    assert "KilledWorker" in bad["error"] and "\n" not in bad["error"]


@pytest.mark.slow
def test_failing_point_retried_then_reported(cluster):
    calls_before = time.perf_counter()
    rows = sweep_grid(Design(), {"l_s": [40.0, 60.0, 50.0]}, COARSE, scheduler=cluster.scheduler_address,
                      evaluate=evaluate_or_raise, retries=1)
    print(f"sweep with a failing point: {time.perf_counter() - calls_before:.2f} s")
    assert [r["ok"] for r in rows] == [True, False, True]
    assert rows[1]["error"] == "ArithmeticError: injected failure for l_s = 60"
    assert rows[2]["volume"] > 0


@pytest.mark.slow
def test_cancel(cluster):
    cancel = threading.Event()

    def progress(f, m):
        if f > 0:
            cancel.set()

    with pytest.raises(Cancelled):
        sweep_grid(Design(), {"a": [30.0, 40.0, 50.0, 60.0, 70.0, 80.0]}, COARSE,
                   scheduler=cluster.scheduler_address, evaluate=evaluate_slowly, progress=progress, cancel=cancel)


def test_unreachable_scheduler_is_a_clear_error():
    with pytest.raises(ParameterError, match="scheduler = 'tcp://127.0.0.1:9' is invalid.*reachable Dask scheduler"):
        sweep_grid(Design(), {"a": [50.0]}, COARSE, scheduler="tcp://127.0.0.1:9", connect_timeout=1.0)


def test_default_backend_rule_by_core_count(monkeypatch):
    """>= 8 usable cores: a local cluster of cores // 2 workers; fewer: serial (None); the
    command line's default follows it, an explicit --workers or --scheduler wins, 0 is serial."""
    import argparse

    from paraspace.app.sweep_cli import backend_workers

    assert [default_workers(c) for c in (1, 2, 4, 7)] == [None] * 4
    assert [default_workers(c) for c in (8, 9, 16, 64)] == [4, 4, 8, 32]
    for cores, expected in ((2, None), (16, 8)):
        monkeypatch.setattr(distributed, "usable_cores", lambda cores=cores: cores)
        assert default_workers() == expected
        assert backend_workers(argparse.Namespace(workers=None, scheduler=None)) == expected
        assert backend_workers(argparse.Namespace(workers=None, scheduler=None), auto=False) is None
        assert backend_workers(argparse.Namespace(workers=3, scheduler=None)) == 3
        assert backend_workers(argparse.Namespace(workers=0, scheduler=None)) is None
        assert backend_workers(argparse.Namespace(workers=None, scheduler="tcp://h:8786")) is None


def test_usable_cores_is_the_affinity():
    assert distributed.usable_cores() == (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                                          else os.cpu_count())


def test_a_local_cluster_serves_http_on_a_free_local_port_and_says_nothing():
    """The local cluster of the studies binds its scheduler's HTTP routes to 127.0.0.1 on a free
    port, with no dashboard: with 8787 taken (a user's own Dask dashboard, or a second optimisation
    at once) it warned "Port 8787 is already in use" before, and nothing outside the machine reaches
    it either way."""
    import socket
    import warnings

    held = socket.socket()
    try:
        try:
            held.bind(("127.0.0.1", 8787))
            held.listen()
        except OSError:
            pass  # already taken by something else: the same situation
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            client, local = distributed._open_client(None, 1, 10.0)
        try:
            http = local.scheduler.services["dashboard"]
            assert http.address == "127.0.0.1" and http.port not in (0, 8787)
            assert not [w for w in caught if "already in use" in str(w.message)], [str(w.message) for w in caught]
            assert client.submit(sum, [1, 2]).result(timeout=60) == 3
        finally:
            client.close()
            local.close()
    finally:
        held.close()
