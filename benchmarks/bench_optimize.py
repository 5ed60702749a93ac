"""Benchmark of the multi-objective optimisation (kinematics.optimize); prints, asserts nothing.

In one run, at voxel --voxel (default 4) over the default free parameters a, d_s, eta_s, l_s
(paper Table I's ranges):
  1. evaluations per second of one population of --population random designs: serially in this
     process (numba kernels on every core) and on a local Dask cluster of --workers process
     workers (the cluster's start-up is timed separately), with the ratio;
  2. the time to a front of 2 objectives (volume, -footprint) over the 4 parameters with
     --population x --generations evaluations, serially and on the Dask cluster (same seed, so
     the same front; the script checks and says so), with front size and final hypervolume.

Timings on a shared machine are noisy: read the ratios. Usage:
  python benchmarks/bench_optimize.py [--voxel 4] [--population 16] [--generations 12] [--workers 2] [--skip-dask]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))  # measure this checkout

from paraspace.kinematics.distributed import _open_client
from paraspace.kinematics.optimize import OptimizeSettings, evaluate_population, optimize
from paraspace.kinematics.sweep import ResultCache
from paraspace.kinematics.workspace import WorkspaceSettings, warm_up


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--voxel", type=float, default=4.0)
    ap.add_argument("--population", type=int, default=16)
    ap.add_argument("--generations", type=int, default=12)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=3, help="repeats of the evaluations/s measurement (median)")
    ap.add_argument("--skip-dask", action="store_true")
    ns = ap.parse_args()
    print(f"compile/warm-up: {warm_up():.2f} s")
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

    serial_rate = rate(None)
    print(f"1. evaluations/s at h = {ns.voxel:g} ({len(designs)} random designs, median of {ns.repeats}):")
    print(f"   serial (in process)        {serial_rate:8.2f} /s")
    client = cluster = None
    if not ns.skip_dask:
        t0 = time.perf_counter()
        client, cluster = _open_client(None, ns.workers, 10.0)
        startup = time.perf_counter() - t0
        client.run(warm_up)
        dask_rate = rate(client)
        print(f"   Dask local, {ns.workers} workers      {dask_rate:8.2f} /s   ratio Dask/serial {dask_rate / serial_rate:.2f}"
              f"   (cluster start-up {startup:.1f} s, not included)")
    print(f"2. time to a 2-objective (volume, -footprint) front over {', '.join(s.params)} at h = {ns.voxel:g}, "
          f"{ns.population} x {ns.generations} evaluations:")
    t0 = time.perf_counter()
    serial = optimize(s)
    t_serial = time.perf_counter() - t0
    print(f"   serial                     {t_serial:7.1f} s   front {len(serial.front)} designs, "
          f"hypervolume {serial.hypervolume[-1]:.4f}, {serial.computed} computed")
    if client is not None:
        try:
            t0 = time.perf_counter()
            dres = optimize(s, client=client)
            t_dask = time.perf_counter() - t0
            same = [e["design"] for e in dres.front] == [e["design"] for e in serial.front]
            print(f"   Dask local, {ns.workers} workers      {t_dask:7.1f} s   ratio Dask/serial time {t_dask / t_serial:.2f}; "
                  f"same front as serial: {same}")
        finally:
            client.close()
            cluster.close()


if __name__ == "__main__":
    main()
