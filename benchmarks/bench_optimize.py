"""Benchmark of the multi-objective optimisation (kinematics.optimize); prints, asserts nothing.

In one run, at voxel --voxel (default 4) over the default free parameters a, d_s, eta_s, l_s
(paper Table I's ranges), with the load average before each part (the machine is shared: read
the ratios, all measured in the same run):
  1. issue 24 target 2: one optimiser evaluation of ``volume,-footprint`` (only the measures it
     names) on the default design, as a ratio to the plain engine on that design (target <= 2x at
     h = 4), beside an evaluation of every measure (medians of alternating runs);
  2. evaluations per second of one population of --population random designs: serially in this
     process (numba kernels on every core) and on the warm local Dask cluster of --workers
     process workers (kinematics.distributed.shared_client; its start-up and warm-up timed
     separately), with the ratio;
  3. issue 24 target 8: a 2-objective (volume, -footprint) optimisation, --population x
     --generations evaluations, serially; on a local cluster started for the run (what every run
     paid before the warm client: a fresh cluster and cold workers); and again on the warm client
     kept by that run (same client, same worker processes). Each with its first generation's wall
     time, the median of the later ones and the total, the ratio to serial, and whether the front
     is the serial one.

Usage:
  python benchmarks/bench_optimize.py [--voxel 4] [--population 16] [--generations 6] [--workers 2] [--skip-dask]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))  # measure this checkout

from paraspace.kinematics.design import Design  # noqa: E402
from paraspace.kinematics.distributed import close_clients, shared_client  # noqa: E402
from paraspace.kinematics.optimize import OptimizeSettings, evaluate_population, optimize  # noqa: E402
from paraspace.kinematics.sweep import ResultCache, evaluate_design  # noqa: E402
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace, warm_up  # noqa: E402


def _load() -> str:
    return f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs"


def _alternating(fns: dict, runs: int) -> dict:
    """Median seconds of each callable of ``fns``, called in turn ``runs`` times (drift hits all)."""
    times: dict = {k: [] for k in fns}
    for _ in range(runs):
        for k, f in fns.items():
            t = time.perf_counter()
            f()
            times[k].append(time.perf_counter() - t)
    return {k: statistics.median(v) for k, v in times.items()}


def evaluation_row(voxel: float, runs: int) -> None:
    """Target 2: one optimiser evaluation against the plain engine on the same design."""
    d = Design()
    ws = WorkspaceSettings(voxel=voxel)
    names = OptimizeSettings(objectives="volume,-footprint", workspace=ws).measure_fields
    med = _alternating({"engine": lambda: compute_workspace(d, ws),
                        "named": lambda: evaluate_design(d, ws, measures=names),
                        "all": lambda: evaluate_design(d, ws)}, runs)
    print(f"1. target 2, one optimiser evaluation at h = {voxel:g}, default design ({_load()}; median of {runs}):")
    print(f"   plain engine                               {med['engine'] * 1e3:8.1f} ms")
    print(f"   volume,-footprint ({', '.join(names)})  {med['named'] * 1e3:8.1f} ms   "
          f"x{med['named'] / med['engine']:.2f} engine (target <= 2x at h = 4)")
    print(f"   every measure (a sweep point)              {med['all'] * 1e3:8.1f} ms   "
          f"x{med['all'] / med['engine']:.2f} engine")


def timed_run(s: OptimizeSettings, **kw) -> tuple[float, list[float], object]:
    """``(total seconds, wall seconds of each generation, result)``."""
    marks = [time.perf_counter()]
    res = optimize(s, on_generation=lambda info: marks.append(time.perf_counter()), **kw)
    total = time.perf_counter() - marks[0]
    return total, list(np.diff(marks)), res


def _gen_text(name: str, total: float, gens: list[float], base: float | None) -> str:
    later = statistics.median(gens[1:]) if len(gens) > 1 else float("nan")
    ratio = f"   x{total / base:.2f} serial" if base else ""
    return (f"   {name:<38} generation 1 {gens[0]:6.2f} s, later (median) {later:6.2f} s, "
            f"total {total:6.1f} s{ratio}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--voxel", type=float, default=4.0)
    ap.add_argument("--population", type=int, default=16)
    ap.add_argument("--generations", type=int, default=6)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=3, help="repeats of the timed measurements (median)")
    ap.add_argument("--skip-dask", action="store_true")
    ns = ap.parse_args()
    print(f"compile/warm-up: {warm_up():.2f} s ({_load()}; the machine is shared: read the ratios)")
    evaluation_row(ns.voxel, max(3, ns.repeats))

    ws = WorkspaceSettings(voxel=ns.voxel)
    s = OptimizeSettings(objectives="volume,-footprint", workspace=ws, population=ns.population,
                         generations=ns.generations, seed=1)
    rng = np.random.default_rng(0)
    lows = np.array([s.bounds_of(p)[0] for p in s.params])
    highs = np.array([s.bounds_of(p)[1] for p in s.params])
    designs = [s.design_at(lows + (highs - lows) * rng.random(len(s.params))) for _ in range(ns.population)]

    def rate(client) -> float:
        times = []
        for _ in range(ns.repeats):
            t0 = time.perf_counter()
            rows, n = evaluate_population(designs, ws, cache=ResultCache(), client=client)
            times.append(time.perf_counter() - t0)
            assert n == len(designs) and all(r["ok"] for r in rows)
        return len(designs) / statistics.median(times)

    print(f"2. evaluations/s at h = {ns.voxel:g} ({len(designs)} random designs, every measure, median of "
          f"{ns.repeats}; {_load()}):")
    serial_rate = rate(None)
    print(f"   serial (in process)        {serial_rate:8.2f} /s")
    if not ns.skip_dask:
        close_clients()
        t0 = time.perf_counter()
        client = shared_client(None, ns.workers)
        startup = time.perf_counter() - t0
        dask_rate = rate(client)
        print(f"   Dask local, {ns.workers} workers      {dask_rate:8.2f} /s   ratio Dask/serial "
              f"{dask_rate / serial_rate:.2f}   (cluster start-up with the workers' warm-up {startup:.1f} s, "
              "not included)")
        close_clients()

    print(f"3. target 8, a 2-objective (volume, -footprint) run over {', '.join(s.params)} at h = {ns.voxel:g}, "
          f"{ns.population} x {ns.generations} evaluations ({_load()}):")
    t_serial, g_serial, serial = timed_run(s)
    print(_gen_text("serial (in process)", t_serial, g_serial, None)
          + f"; front {len(serial.front)} designs, hypervolume {serial.hypervolume[-1]:.4f}")
    if not ns.skip_dask:
        try:
            t_cold, g_cold, cold = timed_run(s, workers=ns.workers)
            client = shared_client(None, ns.workers)
            pids = sorted(client.run(os.getpid).values())
            t_warm, g_warm, warm = timed_run(s, workers=ns.workers)
            same_client = shared_client(None, ns.workers) is client and sorted(client.run(os.getpid).values()) == pids
            for name, res in (("cold", cold), ("warm", warm)):
                assert [e["design"] for e in res.front] == [e["design"] for e in serial.front], name
            print(_gen_text(f"{ns.workers} workers, cluster started by the run", t_cold, g_cold, t_serial)
                  + "   (before: every run)")
            print(_gen_text(f"{ns.workers} workers, warm client, next run", t_warm, g_warm, t_serial)
                  + f"   (same client and workers: {same_client})")
            print("   fronts identical to the serial run's: True "
                  f"(load average now {os.getloadavg()[0]:.2f})")
        finally:
            close_clients()


if __name__ == "__main__":
    main()
