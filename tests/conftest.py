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

Under pytest-xdist (`scripts/test.sh` runs the suite on worker processes, a test file each at a
time) the workers share the compile instead: each claims the next step of kinematics/warmup.STEPS
that no worker has claimed yet (a file created exclusively in the run's shared temporary folder),
warms it, marks it done, and goes on until every step is claimed; it then waits for the steps the
others claimed and runs warm_up(), which loads every kernel from the cache. A worker takes the next
step as soon as it is free, so the compile spreads over the cores whatever each step costs. No
helper process is started."""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys
import time

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


def _share_the_warm_up(folder: pathlib.Path, timeout: float = 900.0) -> None:
    """Claim and warm the steps no other worker has claimed (module docstring); return once every
    step is done (or after ``timeout`` seconds: warm_up() then compiles what is left itself)."""
    from paraspace.kinematics.warmup import STEPS, run_steps

    folder.mkdir(parents=True, exist_ok=True)
    slugs = [(name, name.replace(" ", "-")) for name, _ in STEPS]
    for name, slug in slugs:
        try:
            os.close(os.open(folder / f"{slug}.claimed", os.O_CREAT | os.O_EXCL | os.O_WRONLY))
        except FileExistsError:
            continue
        try:
            run_steps([name])
        finally:
            (folder / f"{slug}.done").touch()
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and not all((folder / f"{slug}.done").exists() for _, slug in slugs):
        time.sleep(0.2)


@pytest.fixture(scope="session", autouse=True)
def warm_kernels(tmp_path_factory: pytest.TempPathFactory) -> None:
    from paraspace.kinematics.warmup import warm_up

    helper = None
    if os.environ.get("PYTEST_XDIST_WORKER") is not None:
        # the workers' base temporary folders share a parent, new for each run
        _share_the_warm_up(tmp_path_factory.getbasetemp().parent / "warm-up")
    elif _cache_is_cold():
        helper = subprocess.Popen([sys.executable, "-c", _HELPER], stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL)
    try:
        warm_up()
    finally:
        if helper is not None and helper.poll() is None:  # nothing left for it to do: this process has it all
            helper.terminate()
            helper.wait(30)
