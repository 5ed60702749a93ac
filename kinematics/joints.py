"""Passive-joint limits and leg interference: the physical options of the reachability test.

The paper names three factors of a workspace (leg strokes, joint motion limits, interference
between parts) and models only the first. :class:`Joints` adds the other two; its defaults keep
the paper's model, so every number computed without them stays as it is.

**Joint cones** (our definition). Each U joint (on its carriage) and each S joint (on the
platform) lets its leg point anywhere inside a cone of half-angle ``theta_U`` / ``theta_S``
about a mount axis ``a``; with ``D`` the U joint and ``B`` the S joint of a leg the constraint is

    a . (B - D)  >=  |B - D| cos(theta)                                                   (J1)

(no ``acos``). Mount axes (``cone_axis``):

* ``"normal"`` (default): the base normal ``z`` for U joints, the platform normal ``R z`` for S
  joints. With zero orientation both cones read ``B_z >= L cos(theta)``: an upper bound
  ``L <= B_z / cos(theta)`` on the leg length.
* ``"home"``: the leg's direction at the home pose (every carriage at mid-stroke, the platform
  at ``(0, 0, z_home)`` with zero orientation and every leg at mid-length), fixed in the
  carriage for U joints and in the platform for S joints.

At a fixed carriage angle the U joint moves on a line, ``D = rho e + sigma (b/2) t``, so the
left side of (J1) is affine in ``rho`` and the right side is ``cos(theta)`` times the convex
``sqrt((rho - p)^2 + q)`` of (F1): (J1) holds on ONE interval of ``rho`` (a sublevel set of a
convex function), found in closed form from a quadratic (:func:`kinematics.feasibility.
cone_interval`). The cones therefore join the per-chain test exactly in ``rho``, like the leg
limits, and are sampled in the arc angle like them.

**Leg interference** (our definition). Each leg is a capsule around the segment ``D B`` of
diameter ``leg_diameter``; two legs interfere when their axes come closer than ``leg_diameter +
clearance`` (closed-form segment-segment distance). See :mod:`kinematics.interference` for how
the engine decides existence with this coupled constraint.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Literal

import numpy as np

from .design import Design, ParameterError
from .geometry import GAMMA, LEG_SIGN, platform_points_local

ConeAxis = Literal["normal", "home"]
CONE_AXES: tuple[str, ...] = ("normal", "home")

#: Valid ranges ``(lo, hi, lo_open, text)``: one rule and one message for every entry point (CLI,
#: REST, URL, explorer).
JOINT_RANGES: dict[str, tuple[float, float, bool, str]] = {
    "theta_u": (0.0, 90.0, True, "(0, 90] degrees"),
    "theta_s": (0.0, 90.0, True, "(0, 90] degrees"),
    "leg_diameter": (0.0, 100.0, False, "[0, 100] (length units)"),
    "clearance": (0.0, 100.0, False, "[0, 100] (length units)"),
}


def check_joint_value(name: str, value: Any) -> float:
    """Validate one joint field against :data:`JOINT_RANGES` (the one message for every entry point)."""
    lo, hi, lo_open, text = JOINT_RANGES[name]
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(name, value, text) from None
    if not math.isfinite(v) or v > hi or v < lo or (lo_open and v <= lo):
        raise ParameterError(name, value, text)
    return v


@dataclasses.dataclass(frozen=True)
class Joints:
    """Passive-joint cones and leg interference (module docstring); defaults: none of them.

    Attributes:
        theta_u: half-angle of every U joint's cone in degrees, ``(0, 90]``; ``None``: no limit.
        theta_s: half-angle of every S joint's cone in degrees, ``(0, 90]``; ``None``: no limit.
        cone_axis: ``"normal"`` or ``"home"`` (module docstring).
        leg_diameter: diameter of each leg's capsule; 0 turns interference off.
        clearance: extra distance required between two legs' capsules.
    """

    theta_u: float | None = None
    theta_s: float | None = None
    cone_axis: ConeAxis = "normal"
    leg_diameter: float = 0.0
    clearance: float = 0.0

    def __post_init__(self) -> None:
        for name in ("theta_u", "theta_s"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, check_joint_value(name, getattr(self, name)))
        if self.cone_axis not in CONE_AXES:
            raise ParameterError("cone_axis", self.cone_axis, " or ".join(CONE_AXES))
        for name in ("leg_diameter", "clearance"):
            object.__setattr__(self, name, check_joint_value(name, getattr(self, name)))
        if self.clearance > 0.0 and self.leg_diameter <= 0.0:
            raise ParameterError("clearance", self.clearance, "0 unless leg_diameter > 0")

    @property
    def has_cones(self) -> bool:
        """Whether any joint cone is set."""
        return self.theta_u is not None or self.theta_s is not None

    @property
    def min_distance(self) -> float:
        """Smallest allowed distance between two legs' axes (0: interference off)."""
        return self.leg_diameter + self.clearance if self.leg_diameter > 0.0 else 0.0

    @property
    def is_default(self) -> bool:
        """True for the paper's model (no cones, no interference)."""
        return self == Joints()

    def to_dict(self) -> dict[str, Any]:
        """JSON form (every field; ``None`` for an unset cone)."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any] | None) -> Joints:
        """Build from a dict, rejecting unknown keys with a :class:`ParameterError`."""
        data = dict(data or {})
        known = {f.name for f in dataclasses.fields(cls)}
        for key in data:
            if key not in known:
                raise ParameterError(key, data[key], "not a joints field; fields: " + ", ".join(sorted(known)))
        return cls(**data)

    def key(self) -> tuple:
        """Hashable identity used by caches."""
        return dataclasses.astuple(self)


def home_height(design: Design) -> float:
    """``z_home``: the platform height at which, with zero orientation and every carriage at
    mid-stroke, the legs have mid-stroke length ``(l_min + l_max) / 2`` (all six legs are alike by
    symmetry when the arc range is centered; otherwise the first leg of chain 1 defines it)."""
    lo, hi = design.eta_limits
    varpi = GAMMA[0] + math.radians(0.5 * (lo + hi))
    rho = design.r - 0.5 * design.d_s
    dx = rho * math.cos(varpi) - LEG_SIGN[0] * 0.5 * design.b * math.sin(varpi)
    dy = rho * math.sin(varpi) + LEG_SIGN[0] * 0.5 * design.b * math.cos(varpi)
    bx, by, _ = platform_points_local(design)[0, 0]
    horiz2 = (bx - dx) ** 2 + (by - dy) ** 2
    lmid = 0.5 * (design.l_min + design.l_max)
    return math.sqrt(max(lmid * lmid - horiz2, 0.0))


def home_leg_directions(design: Design) -> np.ndarray:
    """Unit leg directions ``(B - D) / |B - D|`` at the home pose, shape (3, 2, 3), world frame."""
    lo, hi = design.eta_limits
    eta_mid = 0.5 * (lo + hi)
    z = home_height(design)
    b_pts = platform_points_local(design) + np.array([0.0, 0.0, z])
    out = np.empty((3, 2, 3))
    rho = design.r - 0.5 * design.d_s
    for i in range(3):
        varpi = GAMMA[i] + math.radians(eta_mid)
        e = np.array([math.cos(varpi), math.sin(varpi), 0.0])
        t = np.array([-math.sin(varpi), math.cos(varpi), 0.0])
        for j in range(2):
            d = rho * e + LEG_SIGN[j] * 0.5 * design.b * t
            v = b_pts[i, j] - d
            out[i, j] = v / np.linalg.norm(v)
    return out


def cone_table(design: Design, joints: Joints, rotation: np.ndarray) -> np.ndarray:
    """Per-leg constants of (J1) for the compiled test, shape (3, 2, 8), float64:
    ``[a_e, a_t, a_z, n_x, n_y, n_z, k_U, k_S]``.

    ``(a_e, a_t, a_z)`` is the U joint's axis in its carriage frame (rail direction ``e``, lateral
    ``t``, ``z``), ``n`` the S joint's axis in the base frame at platform rotation ``rotation``,
    ``k = cos(theta)``; ``k = -1`` marks a cone that is not set ((J1) then always holds).
    """
    out = np.zeros((3, 2, 8))
    k_u = math.cos(math.radians(joints.theta_u)) if joints.theta_u is not None else -1.0
    k_s = math.cos(math.radians(joints.theta_s)) if joints.theta_s is not None else -1.0
    rot = np.asarray(rotation, float)
    if joints.cone_axis == "normal":
        out[:, :, 2] = 1.0
        out[:, :, 3:6] = rot @ np.array([0.0, 0.0, 1.0])
    else:
        dirs = home_leg_directions(design)  # world == platform frame at the home pose
        lo, hi = design.eta_limits
        for i in range(3):
            varpi = GAMMA[i] + math.radians(0.5 * (lo + hi))
            e = np.array([math.cos(varpi), math.sin(varpi), 0.0])
            t = np.array([-math.sin(varpi), math.cos(varpi), 0.0])
            for j in range(2):
                v = dirs[i, j]
                out[i, j, 0:3] = (v @ e, v @ t, v[2])
                out[i, j, 3:6] = rot @ v
    out[:, :, 6] = k_u
    out[:, :, 7] = k_s
    return np.ascontiguousarray(out)


def cone_angles(design: Design, joints: Joints, rotation: np.ndarray, b_pts: np.ndarray,
                d_pts: np.ndarray, eta_deg: np.ndarray) -> np.ndarray:
    """Angles (degrees) between each leg and its U and S mount axes, shape (3, 2, 2): ``[..., 0]``
    at the U joint, ``[..., 1]`` at the S joint (for diagnostics and the brute-force tests)."""
    tab = cone_table(design, joints, rotation)
    out = np.zeros((3, 2, 2))
    for i in range(3):
        varpi = GAMMA[i] + math.radians(float(eta_deg[i]))
        e = np.array([math.cos(varpi), math.sin(varpi), 0.0])
        t = np.array([-math.sin(varpi), math.cos(varpi), 0.0])
        for j in range(2):
            v = b_pts[i, j] - d_pts[i, j]
            n = np.linalg.norm(v)
            au = tab[i, j, 0] * e + tab[i, j, 1] * t + tab[i, j, 2] * np.array([0.0, 0.0, 1.0])
            out[i, j, 0] = math.degrees(math.acos(max(-1.0, min(1.0, float(au @ v) / n))))
            out[i, j, 1] = math.degrees(math.acos(max(-1.0, min(1.0, float(tab[i, j, 3:6] @ v) / n))))
    return out
