"""Mobility by the modified Grubler-Kutzbach criterion, paper eq. (1):

    M = d (n - g - 1) + sum_k f_k + nu - xi

counted from the mechanism's topology (:func:`topology`): a fixed base; per chain an arc
carriage (arc-P on the base), a radial slider (P on the arc carriage), and two U-P-S legs from the
slider to the platform (two bodies per leg); one platform.
"""

from __future__ import annotations

import dataclasses

JOINT_DOF = {"P": 1, "arc-P": 1, "R": 1, "U": 2, "S": 3}


@dataclasses.dataclass(frozen=True)
class Topology:
    """Links and joints of a mechanism: ``joints`` lists (type, link_a, link_b)."""

    links: tuple[str, ...]
    joints: tuple[tuple[str, str, str], ...]

    @property
    def n(self) -> int:
        return len(self.links)

    @property
    def g(self) -> int:
        return len(self.joints)

    @property
    def f_sum(self) -> int:
        return sum(JOINT_DOF[j[0]] for j in self.joints)


def topology(chains: int = 3, legs_per_chain: int = 2) -> Topology:
    """The 3-(arc-P, P, 2-(UPS)) topology (Fig. 1)."""
    links = ["base", "platform"]
    joints = []
    for i in range(1, chains + 1):
        arc, slider = f"arc_carriage_{i}", f"slider_{i}"
        links += [arc, slider]
        joints += [("arc-P", "base", arc), ("P", arc, slider)]
        for j in range(1, legs_per_chain + 1):
            cyl, rod = f"cylinder_{i}{j}", f"rod_{i}{j}"
            links += [cyl, rod]
            joints += [("U", slider, cyl), ("P", cyl, rod), ("S", rod, "platform")]
    return Topology(tuple(links), tuple(joints))


def mobility(top: Topology | None = None, d: int = 6, nu: int = 0, xi: int = 0) -> int:
    """Mobility by eq. (1): ``M = d (n - g - 1) + sum f + nu - xi``.

    Parameters
    ----------
    top : Topology, optional
        Links and joints (default: the paper's mechanism, 20 links and 24 joints with 42 freedoms).
    d : int, optional
        Dimension of the motion space (6: spatial).
    nu : int, optional
        Redundant constraints.
    xi : int, optional
        Passive (idle) freedoms.

    Returns
    -------
    int
        The mobility ``M``; the paper's count is 6(20 - 24 - 1) + 42 = 12.

    Examples
    --------
    >>> import paraspace as ps
    >>> ps.mobility()
    12
    """
    t = top or topology()
    return d * (t.n - t.g - 1) + t.f_sum + nu - xi
