"""Parameter studies on a Dask cluster: the Cartesian product of several design parameters.

:func:`sweep_grid` evaluates :func:`kinematics.sweep.evaluate_design` (pure, picklable) at every
point of ``product(params[p1], params[p2], ...)``, e.g. a 4-D study over ``a, d_s, eta_s, l_s``:

* by default on a ``distributed.LocalCluster`` of processes (one single-threaded worker per core,
  numba limited to one thread per worker so the cores are not oversubscribed); or on an existing
  cluster with ``scheduler="tcp://host:8786"``;
* one warm client per process: :func:`shared_client` keeps the client (and the local cluster it
  started, its workers warmed once by :func:`kinematics.warmup.warm_up`) keyed by the scheduler
  address or the number of local workers, so that later sweeps, optimiser generations and
  optimiser runs in the same process reuse it; a client whose scheduler stopped answering is
  replaced, and every kept client is closed at exit (:func:`close_clients`);
* progress is reported as points complete (``as_completed``); ``cancel`` stops waiting, cancels
  the points not yet finished and raises :class:`~kinematics.progress.Cancelled`;
* robust: every point has ``retries=1``; a point that still fails, or whose worker keeps dying
  (the scheduler's ``allowed-failures``), is returned with ``"ok": False`` and a one-line
  ``"error"`` while every other point is returned normally;
* a lost cluster ends the call, never hangs it: when the scheduler stops answering or has had no
  worker for ``lost_after`` seconds (default 10), the points not finished are returned with
  ``"ok": False`` and ``"error": "cluster lost: ..."``, within ``lost_after`` plus a few seconds, and
  so are the points whose result went with a worker before it was fetched (``"...; this point: ..."``);
* the rows are in grid order (first parameter outermost) and, apart from the bookkeeping keys
  ``params``, ``index``, ``ok`` and the wall-clock ``compute_seconds``, identical to calling
  ``evaluate_design`` serially.

The default backend of the command line's sweeps and optimiser (:func:`default_workers`): a
machine with at least ``LOCAL_CLUSTER_MIN_CORES`` (8) usable cores runs them on a local cluster of
``cores // 2`` single-threaded workers (a generation's designs then run side by side, each on one
core, while this process and the scheduler keep the other half); a smaller machine runs them
serially in this process, whose kernels already use every core. An explicit ``--scheduler`` or
``--workers`` wins (``--workers 0``: serially in this process).

This module is part of the numerical core: it imports no web packages (Dask is imported lazily).
"""

from __future__ import annotations

import atexit
import itertools
import logging
import math
import os
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from .design import PARAMS, Design, ParameterError
from .progress import Cancelled, CancelToken, ProgressFn, is_cancelled
from .workspace import WorkspaceSettings

if TYPE_CHECKING:  # pragma: no cover - types only
    from .presets import PresetDesign

__all__ = ["sweep_grid", "grid_designs", "WORKER_ENV", "LOCAL_CLUSTER_MIN_CORES", "usable_cores", "default_workers",
           "shared_client", "close_clients"]

log = logging.getLogger(__name__)

#: Environment of the worker processes of the local cluster: one numba/BLAS thread each.
WORKER_ENV: dict[str, str] = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
                              "MKL_NUM_THREADS": "1"}


#: Usable cores from which the command line's sweeps and optimiser run on a local cluster by default.
LOCAL_CLUSTER_MIN_CORES = 8


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity where the system says, else all)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def default_workers(cores: int | None = None) -> int | None:
    """Workers of the default local cluster for ``cores`` usable cores (default: this machine's):
    ``cores // 2`` where ``cores >= LOCAL_CLUSTER_MIN_CORES``, else ``None`` (serial in this process)."""
    n = usable_cores() if cores is None else int(cores)
    return n // 2 if n >= LOCAL_CLUSTER_MIN_CORES else None


def grid_designs(design: Design | PresetDesign, params: Mapping[str, Sequence[float]]
                 ) -> tuple[list[tuple[int, ...]], list[dict[str, float]], list[Design | PresetDesign]]:
    """The points of the grid, validated before anything runs (``design`` may also be a preset's
    :class:`~kinematics.presets.PresetDesign`: its numeric parameters, each in its ``[lo, hi]``;
    then pass ``evaluate=functools.partial(evaluate_design, length_step=...)`` to :func:`sweep_grid`
    for another spacing than 1).

    Returns:
        ``(indices, values, designs)`` in grid order (first parameter outermost).
    Raises:
        ParameterError: an unknown parameter, an empty value list, a value outside the
            parameter's range, or a combination the model rejects (e.g. ``d_s > r``).
    """
    if not isinstance(params, Mapping) or not params:
        raise ParameterError("params", params, "a mapping of 1 or more design parameters to value lists")
    names = list(params)
    lists: list[list[float]] = []
    from .sweep import param_range  # a Design's fields or a preset design's parameters (PresetDesign)

    for name in names:
        if isinstance(design, Design) and name not in PARAMS:
            raise ParameterError("params", name, "design parameters " + ", ".join(PARAMS))
        lo, hi = param_range(design, name, "params")
        raw = params[name]
        if isinstance(raw, (str, bytes)) or not hasattr(raw, "__len__") or len(raw) == 0:
            raise ParameterError(name, raw, "a non-empty list of numbers")
        vals = []
        for v in raw:
            try:
                f = float(v)
            except (TypeError, ValueError):
                raise ParameterError(name, v, f"a number in [{lo:g}, {hi:g}]") from None
            if not (math.isfinite(f) and lo <= f <= hi):
                raise ParameterError(name, v, f"[{lo:g}, {hi:g}]")
            vals.append(f)
        lists.append(vals)
    indices: list[tuple[int, ...]] = []
    values: list[dict[str, float]] = []
    designs: list[Design | PresetDesign] = []
    for idx in itertools.product(*[range(len(v)) for v in lists]):
        point = {n: lists[k][i] for k, (n, i) in enumerate(zip(names, idx))}
        designs.append(design.replace(**point))
        indices.append(tuple(idx))
        values.append(point)
    return indices, values, designs


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    text = f"{type(exc).__name__}: {text}" if text else type(exc).__name__
    return text if len(text) <= 500 else text[:497] + "..."


def _open_client(scheduler: str | None, n_workers: int | None, connect_timeout: float) -> tuple[Any, Any]:
    """``(client, cluster_or_None)``; the cluster is ours to close when we started it."""
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            client = Client(scheduler, timeout=connect_timeout)
        except (OSError, TimeoutError) as e:
            # a ParameterError, so command-line and API callers report it like any other bad input
            raise ParameterError("scheduler", scheduler,
                                 f"the address of a reachable Dask scheduler, e.g. tcp://host:8786 (could not "
                                 f"connect within {connect_timeout:g} s: {_one_line(e)}; start one with "
                                 f"`dask scheduler` and `dask worker ADDRESS`)") from None
        return client, None
    n = n_workers or max(1, os.cpu_count() or 1)
    # no dashboard; the scheduler's own HTTP routes on a free port of 127.0.0.1 (with no address they
    # take 8787, and a second cluster -- two optimisations at once -- warned "Port 8787 is already in use")
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                           dashboard_address="127.0.0.1:0", scheduler_kwargs={"dashboard": False},
                           silence_logs=logging.ERROR, env=dict(WORKER_ENV))
    try:
        client = Client(cluster)
    except BaseException:
        cluster.close()
        raise
    return client, cluster


def _cluster_trouble(client: Any, timeout: float = 3.0) -> str | None:
    """``None`` while the scheduler answers and has at least one worker, else why not."""
    import concurrent.futures

    ex = concurrent.futures.ThreadPoolExecutor(1)
    try:
        workers = ex.submit(client.nthreads).result(timeout=timeout)
    except concurrent.futures.TimeoutError:
        return "the scheduler does not answer"
    except Exception as e:  # noqa: BLE001
        return f"the scheduler does not answer ({_one_line(e)})"
    finally:
        ex.shutdown(wait=False)
    return None if workers else "no worker"


def _close_quietly(client: Any, cluster: Any) -> None:
    """Close the client (and a local cluster) without waiting long or logging tracebacks when
    the scheduler is already gone."""
    quiet = [logging.getLogger(n) for n in ("distributed", "distributed.client", "distributed.comm",
                                             "distributed.batched", "asyncio", "tornado")]
    levels = [lg.level for lg in quiet]
    for lg in quiet:
        lg.setLevel(logging.CRITICAL)
    try:
        try:
            client.close(timeout=5)
        except Exception:  # noqa: BLE001
            pass
        if cluster is not None:
            try:
                cluster.close(timeout=10)
            except Exception:  # noqa: BLE001
                pass
    finally:
        for lg, lv in zip(quiet, levels):
            lg.setLevel(lv)


_clients: dict[tuple[str, Any], tuple[Any, Any]] = {}
_clients_lock = threading.Lock()
_atexit_registered = False


def _client_key(scheduler: str | None, n_workers: int | None) -> tuple[str, Any]:
    if scheduler is not None:
        return ("scheduler", scheduler.strip())
    return ("local", n_workers or usable_cores())


def shared_client(scheduler: str | None = None, n_workers: int | None = None, *,
                  connect_timeout: float = 10.0) -> Any:
    """The process's warm ``distributed.Client`` for ``scheduler`` (an address) or for a local
    cluster of ``n_workers`` single-threaded process workers (default: one per usable core).

    The first call opens it (a local cluster's workers run :func:`kinematics.warmup.warm_up`
    as they join); later calls with the same key return the same client while its scheduler
    answers and has a worker, else close it and open a new one. Kept clients are closed at exit.

    Raises:
        ParameterError: an unreachable ``scheduler``.
    """
    global _atexit_registered
    key = _client_key(scheduler, n_workers)
    with _clients_lock:
        entry = _clients.pop(key, None)
        if entry is not None:
            client, cluster = entry
            if getattr(client, "status", None) == "running" and _cluster_trouble(client) is None:
                _clients[key] = entry
                return client
            log.info("shared_client: %s no longer answers; opening a new client", key)
            _close_quietly(client, cluster)
        client, cluster = _open_client(scheduler, key[1] if scheduler is None else None, connect_timeout)
        if cluster is not None:
            from .dask_warmup import WarmUp

            try:
                client.register_plugin(WarmUp())
            except BaseException:
                _close_quietly(client, cluster)
                raise
        _clients[key] = (client, cluster)
        if not _atexit_registered:
            atexit.register(close_clients)
            _atexit_registered = True
        return client


def discard_client(client: Any) -> None:
    """Close ``client`` (and its local cluster) and forget it, e.g. after its cluster was lost."""
    with _clients_lock:
        for key, (c, cluster) in list(_clients.items()):
            if c is client:
                del _clients[key]
                _close_quietly(c, cluster)
                return


def close_clients() -> int:
    """Close every kept client and the local clusters they started; returns how many."""
    with _clients_lock:
        entries = list(_clients.values())
        _clients.clear()
    for client, cluster in entries:
        _close_quietly(client, cluster)
    return len(entries)


def sweep_grid(design: Design | PresetDesign, params: Mapping[str, Sequence[float]], settings: WorkspaceSettings, *,
               orientation: Any = None, scheduler: str | None = None, n_workers: int | None = None,
               progress: ProgressFn | None = None, cancel: CancelToken = None, retries: int = 1,
               evaluate: Callable[..., dict] | None = None, connect_timeout: float = 10.0,
               lost_after: float = 10.0) -> list[dict]:
    """Evaluate every design of the Cartesian product of ``params`` on a Dask cluster.

    Args:
        design: the base design; each point replaces the swept fields.
        params: ``{name: values}``, e.g. ``{"a": [40, 60], "d_s": [30, 50], "eta_s": [20, 40],
            "l_s": [40, 60]}``; the first name varies slowest.
        settings: workspace sampling of every point.
        orientation: optional ``OrientationSettings``: also TI_1, TI_2 per point.
        scheduler: address of a running scheduler (``"tcp://host:8786"``); ``None``: a local
            cluster of processes, started by the first call and kept warm for later ones
            (:func:`shared_client`).
        n_workers: workers of the local cluster (default: the number of cores); only without
            ``scheduler``.
        progress: ``progress(fraction, message)`` as points complete.
        cancel: stop waiting, cancel unfinished points, raise ``Cancelled``.
        retries: automatic retries of a failing point (default 1).
        evaluate: the unit of work (default :func:`kinematics.sweep.evaluate_design`); any
            picklable ``f(design, settings, *, orientation) -> dict``.
        connect_timeout: seconds to reach ``scheduler``.
        lost_after: seconds without a worker, or without an answer from the scheduler, after
            which the cluster counts as lost (unfinished points are returned failed).

    Returns:
        One dict per point in grid order: ``{**evaluate(...), "params": {name: value},
        "index": [i, ...], "ok": True}`` or, for a point that failed, ``{"params", "index",
        "ok": False, "error": "one line", "design": {...}}``.

    Raises:
        ParameterError: bad ``params`` (checked before anything starts), bad ``n_workers``, or
            ``n_workers`` together with ``scheduler``.
            A ``scheduler`` that cannot be reached is also a ParameterError naming ``scheduler``.
        Cancelled: when ``cancel`` is set.
    """
    if scheduler is not None and n_workers is not None:
        raise ParameterError("workers", n_workers, "omit it with a scheduler address (the scheduler's "
                                                   "workers are used)")
    if n_workers is not None and (not isinstance(n_workers, int) or isinstance(n_workers, bool)
                                  or not 1 <= n_workers <= 256):
        raise ParameterError("workers", n_workers, "an integer in [1, 256]")
    if not isinstance(retries, int) or retries < 0:
        raise ParameterError("retries", retries, "an integer >= 0")
    if scheduler is not None and (not isinstance(scheduler, str) or not scheduler.strip()):
        raise ParameterError("scheduler", scheduler, "an address such as tcp://host:8786")
    indices, values, designs = grid_designs(design, params)
    if evaluate is None:
        from .sweep import evaluate_design as evaluate
    n = len(designs)
    rows: list[dict | None] = [None] * n
    if progress is not None:
        progress(0.0, f"starting {'cluster' if scheduler is None else 'client'} for {n} points")
    if is_cancelled(cancel):
        raise Cancelled()

    from distributed import as_completed

    t0 = time.perf_counter()
    client = shared_client(scheduler, n_workers, connect_timeout=connect_timeout)
    try:
        futures = client.map(evaluate, designs, settings=settings, orientation=orientation,
                             retries=retries, pure=False)
        where = {f.key: i for i, f in enumerate(futures)}
        ac = as_completed(futures)
        done = failed = 0
        pending = set(f.key for f in futures)
        alive_at = last_check = time.monotonic()
        lost: str | None = None
        unfetched: set[int] = set()  # points that failed without their evaluation's own error

        def fail(i: int, why: str) -> None:
            rows[i] = {"params": values[i], "index": list(indices[i]), "ok": False, "error": why,
                       "design": designs[i].to_dict()}

        while pending:
            if is_cancelled(cancel):
                client.cancel([f for f in futures if f.key in pending])
                raise Cancelled()
            try:
                batch = ac.next_batch(block=False) if ac.has_ready() else []
            except Exception as e:  # noqa: BLE001 - the connection to the scheduler broke
                lost = f"cluster lost: {_one_line(e)}"
                break
            if not batch:
                now = time.monotonic()
                if now - last_check >= 1.0:
                    last_check = now
                    why = _cluster_trouble(client)
                    if why is None:
                        alive_at = now
                    elif now - alive_at >= lost_after:
                        lost = f"cluster lost: {why} for {now - alive_at:.0f} s"
                        break
                time.sleep(0.02)
                continue
            for fut in batch:
                i = where[fut.key]
                pending.discard(fut.key)
                # every wait on a future is bounded: one whose worker left may never resolve (the CI of
                # 2026-12-04 waited 600 s in fut.exception() after the cluster was scaled to 0)
                if fut.status == "finished":
                    try:
                        res = fut.result(timeout=lost_after)
                    except Exception as e:  # noqa: BLE001 - e.g. the data was lost with its worker
                        fail(i, f"finished, but its result did not come within {lost_after:g} s"
                             if isinstance(e, TimeoutError) else _one_line(e))
                        unfetched.add(i)
                        failed += 1
                    else:
                        rows[i] = {**res, "params": values[i], "index": list(indices[i]), "ok": True}
                else:
                    exc = None
                    try:
                        exc = fut.exception(timeout=lost_after)
                    except TimeoutError:
                        exc = None  # reported as "point <status>"
                    except Exception as e:  # noqa: BLE001 - cancelled futures raise here
                        exc = e
                    fail(i, _one_line(exc) if exc else f"point {fut.status}")
                    if fut.status != "error" or exc is None:  # not the evaluation's own error
                        unfetched.add(i)
                    failed += 1
                fut.release()
                done += 1
                if progress is not None:
                    msg = f"{done}/{n} points" + (f" ({failed} failed)" if failed else "")
                    progress(done / n, msg)
        if lost is not None:
            # a point whose result could not be fetched before the cluster was found lost went with
            # its worker (seen in CI: a result finished as the last worker retired): the same cause
            for i in unfetched:
                row = rows[i]
                assert row is not None  # written with i
                row["error"] = f"{lost}; this point: {row['error']}"
            for f in futures:
                if f.key in pending:
                    fail(where[f.key], lost)
                    failed += 1
            log.warning("sweep_grid: %s; %d of %d points not finished", lost, len(pending), n)
            discard_client(client)
        log.info("sweep_grid: %d points (%d failed) in %.2f s", n, failed, time.perf_counter() - t0)
    except BaseException:
        if client.status != "running":
            discard_client(client)
        raise
    return [r for r in rows if r is not None]
