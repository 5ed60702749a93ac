"""Inverse and forward kinematics at one pose.

The mechanism is kinematically redundant: each chain has two carriages (``d_i`` on the line, ``eta_i``
on the arc) for its two legs. ``resolve_redundancy`` picks the carriage values of largest margin;
``inverse_kinematics`` takes hand-set ones; ``forward_kinematics`` finds the pose back from the six
leg lengths.

    python examples/02_inverse_and_forward_kinematics.py
"""

from __future__ import annotations

import paraspace as ps


def main(x: float = 10.0, y: float = -5.0, z: float = 130.0, psi: float = 5.0) -> ps.Pose:
    design = ps.Design()
    pose = ps.Pose(x, y, z, psi=psi)
    best = ps.resolve_redundancy(design, pose)
    print(f"pose            {pose}")
    print(f"resolution      {best.message}")
    for c in best.chains:
        print(f"  chain {c.chain + 1}: d = {c.d:7.3f}, eta = {c.eta:7.3f} deg, "
              f"legs {c.lengths[0]:.3f} / {c.lengths[1]:.3f} ({', '.join(c.leg_status)})")
    back = ps.forward_kinematics(design, best.lengths, best.d, best.eta)
    print(f"forward         {back.pose} ({back.message}, residual {back.residual:.1e})")
    return back.pose


if __name__ == "__main__":
    main()
