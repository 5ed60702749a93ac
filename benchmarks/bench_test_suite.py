"""Benchmark of the test suite's fixed costs (prints; asserts nothing). In one process, medians of
alternating runs, ratios to a baseline measured in the same run, with the load average (the machine
is shared: read the ratios and the CPU seconds, not the wall seconds):

1. one ``paraspace`` command as a subprocess (``python -m paraspace.app.cli``: an interpreter, the
   imports and every kernel it calls loaded from numba's disk cache) against the same command
   through ``main()`` in this process (tests/cli_inprocess.py), for a refusal (``workspace --a -5``),
   ``ik`` and ``workspace --voxel 8 --json``: CPU seconds (the child's or this process's) and wall;
2. with ``--cold``: the suite's session warm-up (tests/conftest.py) on an empty numba cache, as a
   fresh clone runs it: ``warm_up()`` alone against ``warm_up()`` with the conftest's helper process
   (each in a fresh process with its own empty ``NUMBA_CACHE_DIR``; minutes each on a loaded
   machine). The CPU seconds of the process that runs the tests are its wall time on a quiet
   2-core machine (the helper runs on the other core).
"""

from __future__ import annotations

import argparse
import os
import pathlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

COMMANDS = {
    "refusal": ["workspace", "--a", "-5"],
    "ik": ["ik", "--pose", "10,-5,135,3,-2,4", "--json"],
    "workspace h=8": ["workspace", "--voxel", "8", "--json"],
}


def _cpu(who: int) -> float:
    r = resource.getrusage(who)
    return r.ru_utime + r.ru_stime


def _subprocess(args: list[str]) -> tuple[float, float]:
    c0, t0 = _cpu(resource.RUSAGE_CHILDREN), time.perf_counter()
    subprocess.run([sys.executable, "-m", "paraspace.app.cli", *args], capture_output=True, text=True, check=False)
    return _cpu(resource.RUSAGE_CHILDREN) - c0, time.perf_counter() - t0


def _inprocess(args: list[str]) -> tuple[float, float]:
    from cli_inprocess import run_cli

    c0, t0 = _cpu(resource.RUSAGE_SELF), time.perf_counter()
    run_cli(*args)
    return _cpu(resource.RUSAGE_SELF) - c0, time.perf_counter() - t0


def bench_cli(runs: int) -> None:
    from paraspace.kinematics.warmup import warm_up

    warm_up()  # as the suite's session fixture does before any test
    for name, args in COMMANDS.items():
        got: dict[str, list[tuple[float, float]]] = {"subprocess": [], "in-process": []}
        for _ in range(runs):  # alternating
            got["subprocess"].append(_subprocess(args))
            got["in-process"].append(_inprocess(args))
        med = {k: (statistics.median(c for c, _ in v), statistics.median(w for _, w in v)) for k, v in got.items()}
        (sc, sw), (ic, iw) = med["subprocess"], med["in-process"]
        print(f"{name:15s} subprocess cpu {sc:6.2f} s wall {sw:6.2f} s | in-process cpu {ic:6.2f} s wall {iw:6.2f} s"
              f" | cpu ratio in/sub {ic / max(sc, 1e-9):.3f}, wall ratio {iw / max(sw, 1e-9):.3f}")


_COLD = r'''
import resource, subprocess, sys, time
sys.path.insert(0, sys.argv[2])
t = time.perf_counter()
import conftest
from paraspace.kinematics.warmup import warm_up
helper = None
if sys.argv[1] == "helper":
    assert conftest._cache_is_cold()
    helper = subprocess.Popen([sys.executable, "-c", conftest._HELPER])
warm_up()
first = None
if helper is not None:
    first = helper.poll() is not None
    if not first:
        helper.terminate()
    helper.wait(30)
me, ch = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
print(f"tests' process cpu {me.ru_utime + me.ru_stime:.1f} s, helper cpu {ch.ru_utime + ch.ru_stime:.1f} s, "
      f"wall {time.perf_counter() - t:.1f} s, helper done first: {first}")
'''


def bench_cold() -> None:
    for mode in ("alone", "helper"):
        env = dict(os.environ, NUMBA_CACHE_DIR=tempfile.mkdtemp(prefix="nbcache_"))
        out = subprocess.run([sys.executable, "-c", _COLD, mode, str(ROOT / "tests")], env=env, capture_output=True,
                             text=True, check=False)
        print(f"cold warm-up, {mode:6s}: {out.stdout.strip() or out.stderr[-500:]} (load {os.getloadavg()})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--cold", action="store_true", help="also the cold-cache warm-up (minutes)")
    ns = ap.parse_args()
    print(f"load average {os.getloadavg()}, {os.cpu_count()} cores")
    bench_cli(ns.runs)
    if ns.cold:
        bench_cold()
    print(f"load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
