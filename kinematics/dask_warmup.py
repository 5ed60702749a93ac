"""Worker plugin that warms a Dask worker: :func:`kinematics.warmup.warm_up` when the worker joins.

A worker of a local cluster started by :func:`kinematics.distributed.shared_client` compiles (or
loads from numba's on-disk cache, about 3 s) every kernel a design evaluation reaches before its
first task, also when the nanny restarts it after a death, so that no generation of the optimiser
waits on a cold worker. Imported only where Dask is used (this module imports ``distributed``).
"""

from __future__ import annotations

from typing import Any

from distributed.diagnostics.plugin import WorkerPlugin

__all__ = ["WarmUp"]


class WarmUp(WorkerPlugin):
    """In the worker process at set-up (idempotent: once per process): numba takes the thread count
    the worker's environment names (:func:`kinematics.parallel.adopt_thread_env`; the environment
    arrives after numba may have been imported), then ``warm_up()``."""

    name = "paraspace-warm-up"
    idempotent = True

    def setup(self, worker: Any) -> None:
        from .parallel import adopt_thread_env
        from .warmup import warm_up

        adopt_thread_env()
        warm_up()
