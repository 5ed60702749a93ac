"""Design for a task: does the paper's design hold a box at every tilt up to 15 degrees, and follow
a short trajectory without the carriages jumping?

Prints the region's answers (fraction, certified, margin, the binding limit) and the trajectory's
(jumps, carriage travel, the range each actuator uses against its stroke).

    python examples/06_design_for_a_task.py
"""

from __future__ import annotations

import numpy as np

import paraspace as ps
from paraspace.kinematics.task import OrientationSet, PoseList, Region, TaskSettings, pose_list_task, region_task


def main(voxel: float = 4.0, poses: int = 100) -> tuple[object, object]:
    design = ps.Design()
    box = Region("box", (0.0, 0.0, 135.0), (30.0, 30.0, 20.0))
    res = region_task(design, box, OrientationSet(tilt=15.0), TaskSettings(voxel=voxel))
    print(f"box 30 x 30 x 20 at z = 135, tilt <= 15: fraction {res.fraction:.3f}, certified {res.certified}, "
          f"margin {res.margin:g} ({res.binding['message']})")
    s = np.linspace(0.0, 1.0, poses)
    path = np.stack([25 * np.cos(2 * np.pi * s), 25 * np.sin(2 * np.pi * s), 130 + 10 * s, 5 * np.sin(2 * np.pi * s),
                     5 * s, 0 * s], axis=1)
    traj = pose_list_task(design, PoseList(path, 10.0 * s), TaskSettings())
    car = traj.details["carriage"]
    print(f"trajectory of {poses} poses: fraction {traj.fraction:.3f}, {len(traj.discontinuities or [])} jumps, "
          f"carriage travel d {car['travel_d']:.3g}, eta {car['travel_eta']:.3g} deg")
    for a in traj.details["actuators"]:
        print(f"  {a['name']:<7} {a['min']:8.3f} .. {a['max']:8.3f} of [{a['stroke'][0]:g}, {a['stroke'][1]:g}]")
    return res, traj


if __name__ == "__main__":
    main()
