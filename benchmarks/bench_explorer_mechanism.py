"""Benchmark of the explorer's mechanism selector (prints; asserts nothing).

In one process, medians of alternating runs, with the load average before and after:

  1. the explorer's workspace job (``app/explorer/workspace_job.workspace_job``: engine, display
     shell, measures; no cache) for the paper's design and for each preset of the selector at h = 2,
     beside the engine alone (``compute_workspace`` / ``compute_mechanism_workspace``), as ratios to
     the paper's job measured in the same run;
  2. a pose change (the short branch, no job): the paper's IK (``resolve`` and ``reachable``) against
     the selector's (``mechanism_ik``, ``reachable_general`` and the drawing's geometry
     ``mechanism_pose``), per preset.

Usage: python benchmarks/bench_explorer_mechanism.py [--voxel H] [--reps N]
"""

from __future__ import annotations

import argparse
import os
import pathlib
import statistics
import sys
import threading
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from paraspace.app.explorer.mechanism_scene import mechanism_pose  # noqa: E402
from paraspace.app.explorer.pose_controller import resolve  # noqa: E402
from paraspace.app.explorer.workspace_job import run_engine, workspace_job  # noqa: E402
from paraspace.app.mechanism_link import MECH_PRESETS, preset_link  # noqa: E402
from paraspace.app.urlstate import ExplorerState  # noqa: E402
from paraspace.kinematics.bytecache import ByteLRU  # noqa: E402
from paraspace.kinematics.mechanism_workspace import (  # noqa: E402
    mechanism_ik,
    platform_rotation,
    reachable_general,
)
from paraspace.kinematics.pose import Pose  # noqa: E402
from paraspace.kinematics.workspace import reachable  # noqa: E402


def job_seconds(s: ExplorerState) -> float:
    fn = workspace_job(s, ByteLRU(1 << 30), show=lambda *a: None, show_measures=lambda *a: None)
    t0 = time.perf_counter()
    fn(lambda f, m: None, threading.Event())
    return time.perf_counter() - t0


def engine_seconds(s: ExplorerState) -> float:
    t0 = time.perf_counter()
    run_engine(s, s.voxel)
    return time.perf_counter() - t0


def pose_seconds(s: ExplorerState, reps: int = 20) -> float:
    t0 = time.perf_counter()
    for k in range(reps):
        st = s.replace(pose=Pose(x=float(k % 5), y=0.0, z=s.pose.z))
        if st.mechanism is None:
            resolve(st)
            reachable(st.design, st.pose.position[None, :], (0.0, 0.0, 0.0), joints=st.joints)
        else:
            mech = st.mechanism.mechanism()
            iks = mechanism_ik(mech, st.pose.position)
            reachable_general(mech, st.pose.position[None, :])
            mechanism_pose(mech, [ik.q for ik in iks], st.pose.position, platform_rotation(mech, (0.0, 0.0, 0.0)))
    return (time.perf_counter() - t0) / reps


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--voxel", type=float, default=2.0)
    ap.add_argument("--reps", type=int, default=3)
    a = ap.parse_args()
    print(f"load average before: {os.getloadavg()} ({os.cpu_count()} cores; shared machine)")
    states = {"paper": ExplorerState(voxel=a.voxel)}
    states.update({n: ExplorerState(voxel=a.voxel, mechanism=preset_link(n)) for n in MECH_PRESETS})
    for s in states.values():  # compile / load the kernels, warm the caches of the presets
        job_seconds(s.replace(voxel=6.0))
        pose_seconds(s, 2)
    jobs: dict[str, list[float]] = {n: [] for n in states}
    engines: dict[str, list[float]] = {n: [] for n in states}
    poses: dict[str, list[float]] = {n: [] for n in states}
    for _ in range(a.reps):  # alternating: every state once per round
        for n, s in states.items():
            engines[n].append(engine_seconds(s))
            jobs[n].append(job_seconds(s))
            poses[n].append(pose_seconds(s))
    base_job = statistics.median(jobs["paper"])
    base_pose = statistics.median(poses["paper"])
    print(f"\nh = {a.voxel:g}, medians of {a.reps} alternating runs")
    print(f"{'mechanism':<15}{'engine s':>10}{'job s':>10}{'job/paper':>11}{'pose ms':>10}{'pose/paper':>12}")
    for n in states:
        e, j, p = (statistics.median(x[n]) for x in (engines, jobs, poses))
        print(f"{n:<15}{e:>10.3f}{j:>10.3f}{j / base_job:>11.2f}{1e3 * p:>10.2f}{p / base_pose:>12.2f}")
    print(f"\nload average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
