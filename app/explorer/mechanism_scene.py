"""The 3-D drawing of a mechanism description (:mod:`kinematics.mechanism`) at the current pose.

**Definition.** At the carriage values ``q_c`` of each chain (``mechanism_ik``: redundancy resolved,
the legs furthest inside their ranges) and the platform pose ``(p, R)``, the drawing shows, by
(M1)-(M2) of :mod:`kinematics.mechanism`:

* for every carriage joint ``m`` of chain ``c`` and every leg ``j`` it carries, the path of the
  leg's base joint while ``q_m`` runs over its range and the chain's other joints stay put,

      { T_c(q_1 .. q_{m-1}, s, q_{m+1} .. q_k) D0_j  :  s in [lo_m, hi_m] },

  a straight rail for a prismatic joint, an arc about the joint's axis for a revolute joint;
* the base joints ``D_j(q_c)``, the platform joints ``B_j = p + R u_j`` and each leg ``D_j B_j``
  coloured by :func:`leg_state` (the paper drawing's colours, :data:`app.scene.LEG_COLORS`, and
  :data:`CONE_COLOR` for a leg outside one of its joint cones);
* the platform polygon through the ``B_j`` (ordered by angle about the platform's z axis), green
  when the pose lies in the workspace and red otherwise.

The paper's own drawing (:class:`app.scene.MechanismScene`) is hidden meanwhile (the grid, the
axes and the platform frame with its label stay).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import viser

from paraspace.kinematics.mechanism import Chain, Leg, Mechanism

from .scene import (
    _UNIT_CYLINDER,
    _UNIT_SPHERE,
    ARC_COLOR,
    LEG_COLORS,
    LEG_STATE_TEXT,
    PLATFORM_COLOR,
    RAIL_COLOR,
    REACHABLE_COLOR,
    UNREACHABLE_COLOR,
    MechanismScene,
    segment_transforms,
)

#: A leg outside one of its joint cones (the paper drawing has no cones of its own).
CONE_COLOR = (150, 60, 190)
STATE_COLORS: dict[str, tuple[int, int, int]] = {**LEG_COLORS, "out_of_cone": CONE_COLOR}
STATE_TEXT: dict[str, str] = {**LEG_STATE_TEXT, "out_of_cone": "out of its cone"}
#: Samples of a revolute joint's arc.
ARC_SAMPLES = 33
#: A leg within this fraction of its stroke from a limit is "at a limit".
AT_LIMIT = 0.01
#: Relative tolerance of a leg's length test: ``mechanism_ik`` places an exact prismatic joint to
#: within ``stroke / 400^3`` (about 2e-6 for a stroke of 150), so a fixed-length leg
#: (``length = [l, l]``) is met to that accuracy, far inside ``1e-6 l``.
LENGTH_RTOL = 1e-6
#: The paper drawing's nodes hidden while a description is drawn.
PAPER_NODES = ("base_circle", "arc_rails", "legs", "joints", "carriages", "radials", "platform_mesh")


def leg_state(leg: Leg, base: np.ndarray, top: np.ndarray, carriage_rot: np.ndarray,
              platform_rot: np.ndarray) -> str:
    """``too_short`` / ``too_long`` (length outside ``leg.length``), ``out_of_cone`` (the direction
    ``top - base`` more than a cone's angle from its axis: ``u_cone`` in the carriage frame,
    ``s_cone`` in the platform frame), ``at_limit`` (within :data:`AT_LIMIT` of the stroke from a
    limit) or ``inside``; lengths are compared with the tolerance :data:`LENGTH_RTOL` ``* hi``."""
    v = np.asarray(top, float) - np.asarray(base, float)
    length = float(np.linalg.norm(v))
    lo, hi = leg.length
    tol = LENGTH_RTOL * hi
    if length < lo - tol:
        return "too_short"
    if length > hi + tol:
        return "too_long"
    for cone, rot in ((leg.u_cone, carriage_rot), (leg.s_cone, platform_rot)):
        if cone is not None and length > 0.0:
            cos = float(v @ (rot @ np.asarray(cone.axis, float))) / length
            if cos < math.cos(math.radians(cone.angle)) - 1e-9:
                return "out_of_cone"
    if hi > lo and min(length - lo, hi - length) <= AT_LIMIT * (hi - lo):
        return "at_limit"
    return "inside"


def joint_paths(chain: Chain, q: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """Segments ``(N, 2, 3)`` and their colours ``(N, 2, 3)`` of the chain's joint paths (module
    docstring): one rail per prismatic joint and leg, an arc of :data:`ARC_SAMPLES` points per
    revolute joint and leg."""
    segs, cols = [], []
    for m, joint in enumerate(chain.carriage):
        lo, hi = joint.range
        values = np.linspace(lo, hi, ARC_SAMPLES if joint.type == "revolute" else 2)
        pts = []
        for v in values:
            qm = list(q)
            qm[m] = float(v)
            pts.append(chain.base_points(qm))
        path = np.stack(pts, axis=1)  # (legs, samples, 3)
        colour = ARC_COLOR if joint.type == "revolute" else RAIL_COLOR
        for leg_path in path:
            s = np.stack([leg_path[:-1], leg_path[1:]], axis=1)
            segs.append(s)
            cols.append(np.broadcast_to(np.array(colour, np.uint8), s.shape))
    if not segs:
        return np.zeros((0, 2, 3)), np.zeros((0, 2, 3), np.uint8)
    return np.concatenate(segs), np.concatenate(cols)


@dataclasses.dataclass
class MechanismPose:
    """What the drawing shows at one pose: base and platform joints (6, 3), leg states, the joint
    paths and the platform polygon (world coordinates)."""

    base: np.ndarray
    top: np.ndarray
    states: list[str]
    rails: np.ndarray
    rail_colors: np.ndarray
    polygon: np.ndarray  # (7, 3): the centre p, then the six B_j in order
    q: list[list[float]]


def mechanism_pose(mech: Mechanism, q: list[list[float]], position: np.ndarray, rotation: np.ndarray) -> MechanismPose:
    """The drawing's geometry (:class:`MechanismPose`) at carriage values ``q`` (one list per chain)
    and platform pose ``(position, rotation)``."""
    position = np.asarray(position, float)
    top = mech.platform_points(position, rotation)
    base = mech.base_points(q)
    states, segs, cols = [], [], []
    k = 0
    for chain, qc in zip(mech.chains, q):
        crot, _ = chain.transform(qc)
        for leg in chain.legs:
            states.append(leg_state(leg, base[k], top[k], crot, rotation))
            k += 1
        s, c = joint_paths(chain, qc)
        segs.append(s)
        cols.append(c)
    local = np.array([leg.platform for _, _, leg in mech.legs], float)
    order = np.argsort(np.arctan2(local[:, 1], local[:, 0]))
    polygon = np.vstack([position[None, :], top[order]])
    return MechanismPose(base, top, states, np.concatenate(segs), np.concatenate(cols), polygon, q)


def _polygon_faces() -> np.ndarray:
    return np.array([[0, 1 + k, 1 + (k + 1) % 6] for k in range(6)], np.uint32)


def _sizes(mech: Mechanism) -> tuple[float, float]:
    """Leg and joint radii for the mechanism's size (the paper drawing's 1.5 and 2.7 at r = 100)."""
    scale = max(float(np.linalg.norm(leg.base)) for _, _, leg in mech.legs)
    lr = max(1.0, 0.015 * scale)
    return lr, 1.8 * lr


class GeneralMechanismScene:
    """The drawing of one description in a client's scene (module docstring); :meth:`update` moves
    it to another pose, :meth:`remove` takes it away (a new description gets a new drawing)."""

    def __init__(self, scene: viser.SceneApi, mech: Mechanism, pose: MechanismPose) -> None:
        self.scene = scene
        self.mech = mech
        self.leg_radius, jr = _sizes(mech)
        rails, rail_cols = self._rails(pose)
        self.rails = scene.add_line_segments("/gmech/rails", rails, rail_cols, thickness=3.0)
        wxyz, ctr, length = segment_transforms(pose.base, pose.top)
        lr = self.leg_radius
        self.legs = scene.add_batched_meshes_simple(
            "/gmech/legs", _UNIT_CYLINDER.vertices, _UNIT_CYLINDER.faces, wxyz, ctr,
            batched_scales=np.c_[np.full(6, lr), np.full(6, lr), length], batched_colors=self._colors(pose),
            lod="off", cast_shadow=False, receive_shadow=False, material="toon3")
        self.joints = scene.add_batched_meshes_simple(
            "/gmech/joints", _UNIT_SPHERE.vertices, _UNIT_SPHERE.faces, np.tile([1.0, 0.0, 0.0, 0.0], (12, 1)),
            np.vstack([pose.base, pose.top]), batched_scales=np.full(12, jr),
            batched_colors=np.array([(60, 60, 70)] * 6 + [(200, 80, 40)] * 6), lod="off", cast_shadow=False,
            receive_shadow=False)
        self.plate = scene.add_mesh_simple("/gmech/plate", pose.polygon, _polygon_faces(), color=PLATFORM_COLOR,
                                           opacity=0.85, side="double", cast_shadow=False, receive_shadow=False)
        self.labels = [scene.add_label(f"/gmech/leg_label_{k}", "", position=(0.0, 0.0, 0.0), visible=False,
                                       font_size_mode="screen", font_screen_scale=0.75) for k in range(6)]
        self._show_labels(pose)

    @staticmethod
    def _rails(pose: MechanismPose) -> tuple[np.ndarray, np.ndarray]:
        if len(pose.rails):
            return pose.rails, pose.rail_colors
        # a fixed base (Gough-Stewart): a dot at each base joint keeps the node's shape valid
        return np.stack([pose.base, pose.base], axis=1), np.zeros((6, 2, 3), np.uint8)

    @staticmethod
    def _colors(pose: MechanismPose) -> np.ndarray:
        return np.array([STATE_COLORS.get(s, (128, 128, 128)) for s in pose.states], np.uint8)

    def _show_labels(self, pose: MechanismPose) -> None:
        for k, (lab, state) in enumerate(zip(self.labels, pose.states)):
            if state in ("inside", "at_limit"):
                lab.visible = False
                continue
            lab.text = f"leg {k + 1}: {STATE_TEXT[state]}"
            x, y, z = (float(v) for v in pose.top[k])
            lab.position = (x, y, z)
            lab.visible = True

    def update(self, pose: MechanismPose, reachable: bool) -> None:
        """Move every node to ``pose`` (no re-creation); the plate's colour says ``reachable``."""
        rails, cols = self._rails(pose)
        self.rails.points = rails
        self.rails.colors = cols
        wxyz, ctr, length = segment_transforms(pose.base, pose.top)
        lr = self.leg_radius
        self.legs.batched_wxyzs = wxyz
        self.legs.batched_positions = ctr
        self.legs.batched_scales = np.c_[np.full(6, lr), np.full(6, lr), length]
        self.legs.batched_colors = self._colors(pose)
        self.joints.batched_positions = np.vstack([pose.base, pose.top])
        self.plate.vertices = pose.polygon
        self.plate.color = REACHABLE_COLOR if reachable else UNREACHABLE_COLOR
        self._show_labels(pose)

    def remove(self) -> None:
        """Take the drawing out of the scene."""
        for node in (self.rails, self.legs, self.joints, self.plate, *self.labels):
            node.remove()


def show_paper_drawing(paper: MechanismScene, visible: bool) -> None:
    """Show or hide the paper drawing's own nodes (:data:`PAPER_NODES` and its chain and leg labels)."""
    nodes: list[Any] = [getattr(paper, name) for name in PAPER_NODES]
    for node in nodes + list(paper.labels):
        node.visible = visible
    if not visible:
        for lab in paper.leg_labels:
            lab.visible = False
