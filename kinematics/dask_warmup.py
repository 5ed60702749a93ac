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
    """``warm_up()`` in the worker process at set-up (idempotent: once per process)."""

    name = "paraspace-warm-up"
    idempotent = True

    def setup(self, worker: Any) -> None:
        from .warmup import warm_up

        warm_up()
