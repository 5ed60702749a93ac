"""Benchmark of the studies over a preset's parameters and the general mechanism's extras (prints;
asserts nothing). In one process, medians of alternating runs, ratios to a baseline measured in the
same run, with the load average (the machine is shared: read the ratios, not the seconds):

1. one study evaluation (kinematics.sweep.evaluate_design, volume only) of the paper's Design
   against the same design as the paper preset's PresetDesign (routed to the paper engine: the
   ratio is the routing's cost), and a 6-PUPS PresetDesign (the general engine), at h = 8;
2. the general engine on the paper's chains at h = 16 (eta_step 5, length_step 5) without and with
   leg diameters of 10 (kinematics/mechanism_interference.py: the per-voxel search);
3. a region task on 6-PUPS (kinematics/mechanism_task.py) against its plain workspace at h = 8;
4. the surface diagnostics (kinematics/mechanism_diagnostics.py) against the plain workspace.
"""

from __future__ import annotations

import dataclasses
import os
import statistics
import time

from paraspace.kinematics.design import Design
from paraspace.kinematics.mechanism_diagnostics import mechanism_limit_binding
from paraspace.kinematics.mechanism_task import evaluate_mechanism_task
from paraspace.kinematics.mechanism_workspace import compute_general_workspace, warm_up_general
from paraspace.kinematics.presets import PresetDesign, preset
from paraspace.kinematics.sweep import evaluate_design
from paraspace.kinematics.task import OrientationSet, Region, TaskSettings
from paraspace.kinematics.workspace import WorkspaceSettings, warm_up


def _median(fns: dict, runs: int) -> dict:
    times: dict = {k: [] for k in fns}
    for _ in range(runs):
        for k, fn in fns.items():  # alternating
            t0 = time.perf_counter()
            fn()
            times[k].append(time.perf_counter() - t0)
    return {k: statistics.median(v) for k, v in times.items()}


def _with_diameter(mech, d):
    return dataclasses.replace(mech, chains=tuple(
        dataclasses.replace(c, legs=tuple(dataclasses.replace(leg, diameter=d) for leg in c.legs))
        for c in mech.chains))


def main() -> None:
    warm_up()
    warm_up_general()
    print(f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} {os.getloadavg()[2]:.2f} "
          f"(2 shared cores)")
    ws = WorkspaceSettings(voxel=8.0)
    paper_pd, pups = PresetDesign.of("paper"), PresetDesign.of("6-pups")
    t = _median({"design": lambda: evaluate_design(Design(), ws, measures=("volume",)),
                 "paper preset": lambda: evaluate_design(paper_pd, ws, measures=("volume",)),
                 "6-pups": lambda: evaluate_design(pups, ws, measures=("volume",))}, 7)
    for k, v in t.items():
        print(f"1. evaluate_design {k:<13} {1e3 * v:8.2f} ms  x{v / t['design']:.2f}")
    ws16 = WorkspaceSettings(voxel=16.0, eta_step=5.0)
    plain, thick = preset("paper"), _with_diameter(preset("paper"), 10.0)
    t = _median({"plain": lambda: compute_general_workspace(plain, ws16, length_step=5.0),
                 "diameter 10": lambda: compute_general_workspace(thick, ws16, length_step=5.0)}, 3)
    n0 = compute_general_workspace(plain, ws16, length_step=5.0).voxels
    n1 = compute_general_workspace(thick, ws16, length_step=5.0).voxels
    print(f"2. general engine, paper chains h=16: plain {1e3 * t['plain']:.1f} ms ({n0} voxels), diameter 10 "
          f"{1e3 * t['diameter 10']:.0f} ms ({n1} voxels), x{t['diameter 10'] / t['plain']:.0f}, "
          f"{1e3 * (t['diameter 10'] - t['plain']) / max(n0, 1):.2f} ms per reachable voxel")
    mech = preset("6-pups")
    region = Region.parse("box", [0.0, 0.0, 175.0, 60.0, 60.0, 40.0])
    res = compute_general_workspace(mech, ws)
    t = _median({"workspace": lambda: compute_general_workspace(mech, ws),
                 "task": lambda: evaluate_mechanism_task(mech, region, OrientationSet(tilt=5.0, step=5.0),
                                                         TaskSettings(voxel=8.0)),
                 "diagnostics": lambda: mechanism_limit_binding(res)}, 3)
    for k, v in t.items():
        print(f"3/4. 6-pups h=8 {k:<12} {1e3 * v:8.1f} ms  x{v / t['workspace']:.1f}")
    print(f"load average {os.getloadavg()[0]:.2f} after the run")


if __name__ == "__main__":
    main()
