"""Benchmark of the orientation scans / TI, the total-orientation workspace and the dexterity field of
any mechanism (kinematics/mechanism_orientation.py, mechanism_dexterity.py). Prints; asserts nothing.

In one run, medians of alternating runs (``--repeat``, default 3), each row as a ratio to the paper
path on the paper's default design measured in the same run, with the load average:

  1. the orientation scans and TI_1, TI_2 (``--angle-step``, ``--position-step``; z0 = 130): the paper
     path (kinematics/orientation.py), the paper preset (routed to it: its ratio should stay 1.00), the
     general path on the paper preset (whether its TI agree with the paper path's), and the
     gough-stewart, 6-pups and 6-pss presets;
  2. the total-orientation workspace (tilt 15, torsion 15, step 5) at ``--voxel`` (default 4), the
     intersection only (the position workspace computed once before): the same rows;
  3. the dexterity field (1/kappa at the resolved carriage) at ``--dex-voxel`` (default 8): the same rows.

Usage: python benchmarks/bench_mechanism_orientation.py [--repeat N] [--angle-step A] [--position-step S]
                                                        [--voxel H] [--dex-voxel H]
"""

from __future__ import annotations

import argparse
import os
import pathlib
import statistics
import sys
import time
from collections.abc import Callable

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from paraspace.kinematics.design import Design  # noqa: E402
from paraspace.kinematics.dexterity import dexterity_field  # noqa: E402
from paraspace.kinematics.dexterous import total_orientation_workspace  # noqa: E402
from paraspace.kinematics.mechanism_dexterity import mechanism_dexterity_field  # noqa: E402
from paraspace.kinematics.mechanism_orientation import (  # noqa: E402
    general_orientation_workspace,
    mechanism_orientation_workspace,
    mechanism_total_orientation,
)
from paraspace.kinematics.mechanism_workspace import (  # noqa: E402
    compute_general_workspace,
    compute_mechanism_workspace,
    warm_up_general,
)
from paraspace.kinematics.orientation import OrientationSettings, orientation_workspace  # noqa: E402
from paraspace.kinematics.presets import preset  # noqa: E402
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace, warm_up  # noqa: E402

PRESETS = ("gough-stewart", "6-pups", "6-pss")


def _medians(rows: dict[str, Callable[[], object]], repeat: int) -> dict[str, float]:
    """Median seconds of each row, the rows run in turn ``repeat`` times (alternating)."""
    times: dict[str, list[float]] = {k: [] for k in rows}
    for _ in range(repeat):
        for k, fn in rows.items():
            t0 = time.perf_counter()
            fn()
            times[k].append(time.perf_counter() - t0)
    return {k: statistics.median(v) for k, v in times.items()}


def _print(title: str, med: dict[str, float], base: str, notes: dict[str, str]) -> None:
    print(f"\n{title}  (load average {', '.join(f'{x:.2f}' for x in os.getloadavg())})")
    for k, t in med.items():
        print(f"  {k:<34} {1000 * t:10.1f} ms   x{t / med[base]:6.2f}   {notes.get(k, '')}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--angle-step", type=float, default=1.0)
    ap.add_argument("--position-step", type=float, default=2.0)
    ap.add_argument("--voxel", type=float, default=4.0)
    ap.add_argument("--dex-voxel", type=float, default=8.0)
    ns = ap.parse_args()
    print(f"2 shared cores; the machine is loaded (load average {os.getloadavg()[0]:.2f} at start)")
    warm_up()
    warm_up_general()
    design, paper = Design(), preset("paper")
    mechs = {name: preset(name) for name in PRESETS}

    scan = OrientationSettings(angle_step=ns.angle_step, position_step=ns.position_step)
    p = orientation_workspace(design, scan)
    g = general_orientation_workspace(paper, scan)
    rows: dict[str, Callable[[], object]] = {
        "paper path": lambda: orientation_workspace(design, scan),
        "paper preset (routed)": lambda: mechanism_orientation_workspace(paper, scan),
        "general path on the paper preset": lambda: general_orientation_workspace(paper, scan),
        **{name: (lambda m=m: mechanism_orientation_workspace(m, scan)) for name, m in mechs.items()},
    }
    _print(f"1. orientation scans and TI (angle step {ns.angle_step:g}, position step {ns.position_step:g})",
           _medians(rows, ns.repeat), "paper path",
           {"general path on the paper preset": f"TI {g.ti1:.6g}, {g.ti2:.6g} (paper path {p.ti1:.6g}, {p.ti2:.6g})"})

    settings = WorkspaceSettings(voxel=ns.voxel)
    pos_paper = compute_workspace(design, settings)
    pos_routed = compute_mechanism_workspace(paper, settings)
    pos_general = compute_general_workspace(paper, WorkspaceSettings(voxel=ns.voxel, bounds=(pos_paper.grid.lo,
                                                                                               pos_paper.grid.hi)))
    pos = {name: compute_mechanism_workspace(m, settings) for name, m in mechs.items()}
    tt = (15.0, 15.0, 5.0)
    a = total_orientation_workspace(design, *tt, settings, position=pos_paper)
    b = mechanism_total_orientation(paper, *tt, WorkspaceSettings(voxel=ns.voxel, bounds=(pos_paper.grid.lo,
                                                                                          pos_paper.grid.hi)),
                                    position=pos_general)
    rows = {
        "paper path": lambda: total_orientation_workspace(design, *tt, settings, position=pos_paper),
        "paper preset (routed)": lambda: mechanism_total_orientation(paper, *tt, settings, position=pos_routed),
        "general path on the paper preset": lambda: mechanism_total_orientation(
            paper, *tt, pos_general.settings, position=pos_general),
        **{name: (lambda m=m, r=pos[name]: mechanism_total_orientation(m, *tt, settings, position=r))
           for name, m in mechs.items()},
    }
    notes = {"general path on the paper preset": f"{b.voxels} voxels (paper path {a.voxels}; identical: "
                                                 f"{bool((a.occupancy == b.occupancy).all())})"}
    for name, m in mechs.items():
        kept = mechanism_total_orientation(m, *tt, settings, position=pos[name]).voxels
        notes[name] = f"{pos[name].voxels} -> {kept} voxels"
    _print(f"2. total orientation (tilt {tt[0]:g}, torsion {tt[1]:g}, step {tt[2]:g}) at h = {ns.voxel:g}, "
           f"{pos_paper.voxels} voxels of the paper's workspace", _medians(rows, ns.repeat), "paper path", notes)

    dset = WorkspaceSettings(voxel=ns.dex_voxel)
    dpaper = compute_workspace(design, dset)
    droute = compute_mechanism_workspace(paper, dset)
    dgen = compute_general_workspace(paper, WorkspaceSettings(voxel=ns.dex_voxel, bounds=(dpaper.grid.lo,
                                                                                           dpaper.grid.hi)))
    dpos = {name: compute_mechanism_workspace(m, dset) for name, m in mechs.items()}
    rows = {
        "paper path": lambda: dexterity_field(dpaper, 0.005),
        "paper preset (routed)": lambda: mechanism_dexterity_field(droute, 0.005),
        "general path on the paper preset": lambda: mechanism_dexterity_field(dgen, 0.005),
        **{name: (lambda r=dpos[name]: mechanism_dexterity_field(r, 0.005)) for name in mechs},
    }
    gci, gci_paper = mechanism_dexterity_field(dgen, 0.005).gci, dexterity_field(dpaper, 0.005).gci
    notes = {"general path on the paper preset": f"GCI {gci:.4g} (L = the mean platform radius, mechanism_ik's "
                                                 f"carriage; the paper path's {gci_paper:.4g}: L = a/2, its own "
                                                 "resolver)"}
    notes.update({name: f"{dpos[name].voxels} voxels" for name in mechs})
    notes["paper path"] = f"{dpaper.voxels} voxels"
    _print(f"3. dexterity field at h = {ns.dex_voxel:g}", _medians(rows, ns.repeat), "paper path", notes)


if __name__ == "__main__":
    main()
