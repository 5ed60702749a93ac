"""Platform pose ``(x, y, z, psi, theta, phi)``: position of P and Z-Y-X Euler angles (eq. (2))."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from .design import ParameterError, check_pose_value
from .rotation import euler_zyx_deg

POSE_FIELDS: tuple[str, ...] = ("x", "y", "z", "psi", "theta", "phi")
#: Angles are limited to a half-turn; positions to a generous box (model validity, not reach).
POSE_LIMITS: dict[str, tuple[float, float]] = {
    "x": (-1e4, 1e4), "y": (-1e4, 1e4), "z": (-1e4, 1e4),
    "psi": (-180.0, 180.0), "theta": (-90.0, 90.0), "phi": (-180.0, 180.0),
}


@dataclasses.dataclass(frozen=True)
class Pose:
    """Pose of the moving platform: position ``P_o = (x, y, z)`` and Euler angles in degrees.

    The rotation is ``R1 = Rz(psi) Ry(theta) Rx(phi)`` (paper eq. (2)).
    """

    x: float = 0.0
    y: float = 0.0
    z: float = 130.0
    psi: float = 0.0
    theta: float = 0.0
    phi: float = 0.0

    def __post_init__(self) -> None:
        for name in POSE_FIELDS:
            lo, hi = POSE_LIMITS[name]
            object.__setattr__(self, name, check_pose_value(name, getattr(self, name), lo, hi))

    @property
    def position(self) -> np.ndarray:
        """``P_o`` as a 3-vector."""
        return np.array([self.x, self.y, self.z])

    @property
    def rotation(self) -> np.ndarray:
        """``R1`` of eq. (2)."""
        return euler_zyx_deg(self.psi, self.theta, self.phi)

    def as_array(self) -> np.ndarray:
        """``[x, y, z, psi, theta, phi]`` (degrees)."""
        return np.array([getattr(self, f) for f in POSE_FIELDS])

    @classmethod
    def from_array(cls, values: Any) -> Pose:
        """From ``[x, y, z, psi, theta, phi]``; raises :class:`ParameterError` on a wrong length."""
        vals = list(values)
        if len(vals) != 6:
            raise ParameterError("pose", values, "6 numbers x,y,z,psi,theta,phi")
        return cls(*vals)

    def to_dict(self) -> dict[str, float]:
        return dataclasses.asdict(self)
