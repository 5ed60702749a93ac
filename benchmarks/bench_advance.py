"""Issue 24 target 7: the engine's per-level ``_advance`` serial (``_advance_serial``, the former
loop) vs parallel, timed inside ``compute_workspace(Design(), WorkspaceSettings(voxel=h))`` with 1
and 2 numba threads (alternating runs, medians): the ``_advance`` calls summed over a run, and the
engine total.

    PYTHONPATH=. python benchmarks/bench_advance.py [runs] [h ...]
"""

from __future__ import annotations

import os
import statistics
import sys
import time

import numba

from paraspace.kinematics import blocks
from paraspace.kinematics.design import Design
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace


def main() -> None:
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    hs = [float(a) for a in sys.argv[2:]] or [0.5, 1.0]
    variants = {"serial": blocks._advance_serial, "parallel": blocks._advance}
    original = blocks._advance
    acc = {"t": 0.0}

    def wrap(fn):
        def timed(*a):
            t = time.perf_counter()
            r = fn(*a)
            acc["t"] += time.perf_counter() - t
            return r
        return timed

    try:
        for h in hs:
            ws = WorkspaceSettings(voxel=h)
            for fn in variants.values():  # compile / warm
                blocks._advance = fn
                ref = compute_workspace(Design(), ws)
            per: dict = {}
            for _ in range(runs):
                for n in (1, 2):
                    numba.set_num_threads(n)
                    for name, fn in variants.items():
                        blocks._advance = wrap(fn)
                        acc["t"] = 0.0
                        t = time.perf_counter()
                        res = compute_workspace(Design(), ws)
                        total = time.perf_counter() - t
                        assert (res.occupancy == ref.occupancy).all()
                        per.setdefault((name, n), []).append((acc["t"], total))
            print(f"h={h:g} ({ref.grid.size:,} voxels), {runs} runs, load average {os.getloadavg()}:")
            for (name, n), v in per.items():
                adv = statistics.median(x[0] for x in v) * 1e3
                tot = statistics.median(x[1] for x in v) * 1e3
                print(f"  {name:8s} {n} thread(s): _advance {adv:7.1f} ms   engine total {tot:7.1f} ms")
    finally:
        blocks._advance = original
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)


if __name__ == "__main__":
    main()
