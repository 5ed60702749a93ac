"""Suite-wide set-up: compile every kernel a request can reach once, before any test runs
(kinematics/warmup.py), so that no request in a test waits on a numba compile however busy the
machine is (the kernels' on-disk cache then serves the CLI subprocesses too).

On a cold cache (a fresh clone, as CI runs it) that compile is about 250 s of one core: numba
compiles one kernel at a time. So the processes of the run share it (kinematics/warmup.run_unclaimed):
each claims the next warm-up step that no process has claimed yet (a file created exclusively in the
run's shared temporary folder), compiles it into the on-disk cache and marks it done, until every
step is claimed (the first process from the first step forwards, the others from the last one
backwards, so that no two compile the kernels that neighbouring steps share at once); it then
waits for the steps the others claimed and runs warm_up(), which loads
every kernel from the cache. Under pytest-xdist (`scripts/test.sh` runs the suite on two worker
processes, a test file each at a time) the workers share it; in one process a helper process started
for the purpose does, on a cold cache only. The kernels and the results are the same either way
(warm_up() still calls every kernel)."""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys
import time
from collections.abc import Callable

import pytest

# the helper process of a run in one process: it shares the warm-up of the folder it is given
_HELPER = ("import pathlib, sys\nfrom paraspace.kinematics.warmup import run_unclaimed\n"
           "run_unclaimed(pathlib.Path(sys.argv[1]), backwards=True)\n")


#: The test files that take longest (seconds of a fresh-clone run on 2 cores, 2026-12-03: the
#: browser 165, the explorer 105, the load 58, memory 47, hardening 46, the others 24-34), run first
#: in this order: pytest-xdist hands the workers a file at a time in collection order
#: (``--no-loadscope-reorder`` in scripts/test.sh; by default it orders them by their number of tests,
#: which left these for the end and one worker idle for the last 53 s of that run). The other files
#: keep pytest's order after them.
LONGEST_FIRST = ("test_browser.py", "test_explorer.py", "test_load_explorer.py", "test_memory.py",
                 "test_hardening.py", "test_measures.py", "test_explorer_mechanism.py", "test_bracket.py",
                 "test_security.py", "test_optimize.py", "test_bracket_children.py", "test_feasibility_plain.py")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The files of :data:`LONGEST_FIRST` first, in its order (a stable sort: each file's tests keep
    their order, as do the other files)."""
    rank = {name: k for k, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))


def _cache_is_cold() -> bool:
    """Whether numba's cache next to the core holds nothing of the general engine yet (its kernels
    are warmed last, so a cache that has them is warm)."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        where = pathlib.Path(os.environ["NUMBA_CACHE_DIR"])
        return not any(where.rglob("mechanism_workspace.*.nbi"))
    from paraspace.kinematics import mechanism_workspace

    pycache = pathlib.Path(mechanism_workspace.__file__).parent / "__pycache__"
    return not any(pycache.glob("mechanism_workspace.*.nbi"))


def _share_the_warm_up(folder: pathlib.Path, backwards: bool = False, alive: Callable[[], bool] = lambda: True,
                       timeout: float = 300.0) -> None:
    """Claim and warm the steps no other process has claimed (module docstring); return once every
    step is done, once ``alive()`` says the others are gone, or after ``timeout`` seconds (warm_up()
    then compiles what is left itself)."""
    from paraspace.kinematics.warmup import run_unclaimed, steps_done

    run_unclaimed(folder, backwards)
    deadline = time.monotonic() + timeout
    while not steps_done(folder) and alive() and time.monotonic() < deadline:
        time.sleep(0.2)


@pytest.fixture(scope="session", autouse=True)
def warm_kernels(tmp_path_factory: pytest.TempPathFactory) -> None:
    from paraspace.kinematics.warmup import warm_up

    if os.environ.get("PYTEST_XDIST_WORKER") is not None:
        # the workers' base temporary folders (popen-gw0, ...) share a parent, new for each run
        _share_the_warm_up(tmp_path_factory.getbasetemp().parent / "warm-up",
                           backwards=os.environ["PYTEST_XDIST_WORKER"] != "gw0")
    elif _cache_is_cold():
        folder = tmp_path_factory.getbasetemp() / "warm-up"
        helper = subprocess.Popen([sys.executable, "-c", _HELPER, str(folder)], stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL)
        try:
            _share_the_warm_up(folder, alive=lambda: helper.poll() is None)
        finally:
            if helper.poll() is None:
                helper.terminate()
            helper.wait(30)
    warm_up()
