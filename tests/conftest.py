"""Suite-wide set-up: compile every kernel a request can reach once, before any test runs
(kinematics/warmup.py), so that no request in a test waits on a numba compile however busy the
machine is (the kernels' on-disk cache then serves the CLI subprocesses too).

On a cold cache (a fresh clone, as CI runs it) that compile is a minute or more of one core: numba
compiles one kernel at a time. A helper process compiles, meanwhile, the kernels that warm_up()
reaches last (its steps from the last one backwards, until this process, going forwards, has done
the rest: both cores finish together), into the same on-disk cache, so that this process loads them
instead of compiling them: the two cores share the compile. The kernels and the results are the same
either way (the helper only fills the cache; warm_up() below still calls every kernel). With a warm
cache no helper is started.

Under pytest-xdist (`scripts/test.sh` runs the suite on two worker processes, a file each at a time)
the second worker is that helper: worker gw1 warms the steps from the last one backwards before its
warm_up(), worker gw0 from the first one forwards; no helper process is started."""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys

import pytest

# The helper warms kinematics/warmup.STEPS from the last one backwards, while warm_up() below runs
# them from the first one: they meet in the middle.
_HELPER = ("from paraspace.kinematics.warmup import STEPS, run_steps\n"
           "run_steps([name for name, _ in reversed(STEPS)])\n")


def _cache_is_cold() -> bool:
    """Whether numba's cache next to the core holds nothing of the general engine yet (its kernels
    are warmed last, so a cache that has them is warm)."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        where = pathlib.Path(os.environ["NUMBA_CACHE_DIR"])
        return not any(where.rglob("mechanism_workspace.*.nbi"))
    from paraspace.kinematics import mechanism_workspace

    pycache = pathlib.Path(mechanism_workspace.__file__).parent / "__pycache__"
    return not any(pycache.glob("mechanism_workspace.*.nbi"))


@pytest.fixture(scope="session", autouse=True)
def warm_kernels() -> None:
    from paraspace.kinematics.warmup import warm_up

    helper = None
    worker = os.environ.get("PYTEST_XDIST_WORKER")  # "gw0", "gw1", ... under pytest-xdist
    if worker is not None:
        if worker == "gw1" and _cache_is_cold():
            from paraspace.kinematics.warmup import STEPS, run_steps

            run_steps([name for name, _ in reversed(STEPS)][:len(STEPS) // 2 + 1])
    elif _cache_is_cold():
        helper = subprocess.Popen([sys.executable, "-c", _HELPER], stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL)
    try:
        warm_up()
    finally:
        if helper is not None and helper.poll() is None:  # nothing left for it to do: this process has it all
            helper.terminate()
            helper.wait(30)
