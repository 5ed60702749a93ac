"""Tilt-and-torsion (T&T) orientation workspace at a point (Bonev & Gosselin's T&T angles).

Angles (degrees in every public function): azimuth ``phi``, tilt ``theta``, torsion ``sigma``,

    R = Rz(phi) Ry(theta) Rz(-phi) Rz(sigma)                                              (T1)

so the platform normal ``R z = (cos phi sin theta, sin phi sin theta, cos theta)`` is tilted by
``theta`` in the vertical plane of azimuth ``phi``, and ``sigma`` is the torsion about it. At zero
tilt ``R = Rz(sigma)`` for every azimuth; at zero torsion ``R`` is the pure tilt (no spin about
the normal). (T1) has no representation singularity inside ``theta < 180``.

Reachability of an orientation at the position ``P``: all three chains pass the workspace engine's
per-chain existence test (:func:`kinematics.workspace.reachable_pairs`: exact in ``d``, the arc
stroke sampled every ``eta_step``), i.e. a voxel centred at ``P`` would be reachable in the
constant-orientation workspace of ``R``.

Reported (our definitions)
--------------------------
* **Maximal tilt per azimuth at zero torsion** ``theta_max(phi)``: for each azimuth
  ``phi_k = k azimuth_step`` (``k = 0 .. 360/azimuth_step - 1``) the tilts ``0, s, 2 s, ...``
  (``s = coarse_step``, up to ``tilt_limit``) are tested; between the last reachable sample before
  the first unreachable one and that unreachable sample the boundary is located by bisection to
  ``tolerance``. ``theta_max`` is the reachable end of the final bracket, so it is itself a
  reachable tilt and ``theta_max + tolerance`` is not (inner approximation). It is the extent of
  the tilt ray reachable from zero tilt: a gap narrower than ``coarse_step`` between reachable
  samples can be stepped over (the only sampling error besides ``tolerance``). ``tilt_limit``
  (default 90) is reported as ``saturated`` when every coarse sample up to it is reachable.
* **Torsion range at zero tilt** ``[sigma_min, sigma_max]``: the same scan-and-bisect from
  ``sigma = 0`` in both directions, up to ``torsion_limit`` (default 180).

Cost: one batched launch for the coarse scan of all azimuths (``n_az x tilt_limit / coarse_step``
orientation tests), then ``log2(coarse_step / tolerance)`` launches of ``n_az`` tests; about
``7,000 + 7 x 72`` single-point tests with the defaults.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from .design import Design, ParameterError
from .joints import Joints
from .settings import TILT_TORSION
from .workspace import reachable_pairs


def tt_rotations(azimuth: np.ndarray, tilt: np.ndarray, torsion: np.ndarray) -> np.ndarray:
    """(T1) for arrays of equal shape (degrees): rotation matrices of shape ``(*shape, 3, 3)``."""
    phi, theta, sigma = (np.radians(np.asarray(v, float)) for v in np.broadcast_arrays(azimuth, tilt, torsion))
    a = sigma - phi  # R = Rz(phi) Ry(theta) Rz(sigma - phi)
    cp, sp, ct, st, ca, sa = np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta), np.cos(a), np.sin(a)
    R = np.empty(phi.shape + (3, 3))
    # Rz(phi) Ry(theta) = [[cp ct, -sp, cp st], [sp ct, cp, sp st], [-st, 0, ct]]; times Rz(a)
    R[..., 0, 0] = cp * ct * ca - sp * sa
    R[..., 0, 1] = -cp * ct * sa - sp * ca
    R[..., 0, 2] = cp * st
    R[..., 1, 0] = sp * ct * ca + cp * sa
    R[..., 1, 1] = -sp * ct * sa + cp * ca
    R[..., 1, 2] = sp * st
    R[..., 2, 0] = -st * ca
    R[..., 2, 1] = st * sa
    R[..., 2, 2] = ct
    return R


def tt_rotation(azimuth: float, tilt: float, torsion: float) -> np.ndarray:
    """(T1): ``R = Rz(phi) Ry(theta) Rz(-phi) Rz(sigma)`` for one triple (degrees)."""
    return tt_rotations(np.array(azimuth), np.array(tilt), np.array(torsion))


def tt_angles(rot: np.ndarray) -> tuple[float, float, float]:
    """Inverse of (T1): ``(azimuth, tilt, torsion)`` in degrees, tilt in ``[0, 180]``, azimuth and
    torsion in ``(-180, 180]`` (the azimuth is 0 at zero tilt, where it is undefined)."""
    R = np.asarray(rot, float)
    theta = math.degrees(math.acos(max(-1.0, min(1.0, R[2, 2]))))
    st = math.hypot(R[0, 2], R[1, 2])
    if st < 1e-12:
        return 0.0, theta, math.degrees(math.atan2(R[1, 0], R[0, 0]))  # R = Rz(sigma) (theta = 0)
    phi = math.atan2(R[1, 2], R[0, 2])
    a = math.atan2(R[2, 1], -R[2, 0])
    sigma = math.remainder(phi + a, 2.0 * math.pi)
    return math.degrees(phi), theta, math.degrees(sigma)


def _num(field: str, value, lo: float, hi: float, lo_open: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(field, value, f"{'(' if lo_open else '['}{lo:g}, {hi:g}] (a number)") from None
    if not math.isfinite(v) or v > hi or v < lo or (lo_open and v == lo):
        raise ParameterError(field, value, f"{'(' if lo_open else '['}{lo:g}, {hi:g}]")
    return v


@dataclasses.dataclass(frozen=True)
class TiltTorsionSettings:
    """Sampling of the T&T report (module docstring); angles in degrees."""

    azimuth_step: float = 5.0
    coarse_step: float = 1.0
    tolerance: float = 0.01
    tilt_limit: float = 90.0
    torsion_limit: float = 180.0
    eta_step: float = 0.5

    def __post_init__(self) -> None:
        for name in ("azimuth_step", "coarse_step", "tilt_limit", "torsion_limit", "eta_step"):
            object.__setattr__(self, name, float(TILT_TORSION[name].parse(getattr(self, name))))
        object.__setattr__(self, "tolerance", _num("tolerance", self.tolerance, 0.0, self.coarse_step, True))


def azimuths(settings: TiltTorsionSettings) -> np.ndarray:
    """``phi_k = k azimuth_step`` in ``[0, 360)`` (degrees)."""
    n = max(1, int(math.ceil(360.0 / settings.azimuth_step - 1e-9)))
    return np.arange(n) * settings.azimuth_step


def _ray_extent(test, n_rays: int, limit: float, coarse: float, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Scan-and-bisect along ``n_rays`` rays ``t in [0, limit]``: ``test(ray_index (K,), t (K,))``
    returns reachability. Returns (extent, saturated) per ray; NaN where ``t = 0`` fails."""
    n = int(math.ceil(limit / coarse - 1e-9))
    ts = np.minimum(np.arange(n + 1) * coarse, limit)
    rr, tt = np.meshgrid(np.arange(n_rays), ts, indexing="ij")
    ok = test(rr.ravel(), tt.ravel()).reshape(n_rays, n + 1)
    extent = np.full(n_rays, np.nan)
    saturated = np.zeros(n_rays, bool)
    lo = np.zeros(n_rays)
    hi = np.zeros(n_rays)
    active = np.zeros(n_rays, bool)
    for k in range(n_rays):
        if not ok[k, 0]:
            continue
        bad = np.flatnonzero(~ok[k])
        if bad.size == 0:
            extent[k], saturated[k] = limit, True
            continue
        lo[k], hi[k] = ts[bad[0] - 1], ts[bad[0]]
        active[k] = True
    idx = np.flatnonzero(active)
    while idx.size and np.any(hi[idx] - lo[idx] > tol):
        mid = 0.5 * (lo[idx] + hi[idx])
        good = test(idx, mid)
        lo[idx] = np.where(good, mid, lo[idx])
        hi[idx] = np.where(good, hi[idx], mid)
    extent[active] = lo[active]
    return extent, saturated


@dataclasses.dataclass
class TiltTorsionReport:
    """The T&T orientation workspace at one position (module docstring); angles in degrees."""

    position: list[float]
    reachable: bool  # the zero orientation is reachable there
    azimuths: list[float]
    max_tilt: list[float | None]  # per azimuth, at zero torsion (None where unreachable)
    tilt_saturated: list[bool]  # the tilt scan reached tilt_limit
    torsion_min: float | None  # at zero tilt
    torsion_max: float | None
    torsion_saturated: list[bool]  # [negative side, positive side] reached torsion_limit
    settings: TiltTorsionSettings

    @property
    def min_max_tilt(self) -> float | None:
        """The tilt reachable in every direction (at zero torsion): ``min_phi theta_max(phi)``."""
        vals = [v for v in self.max_tilt if v is not None]
        return min(vals) if vals and len(vals) == len(self.max_tilt) else None

    def to_dict(self) -> dict:
        vals = [v for v in self.max_tilt if v is not None]
        return {"position": self.position, "reachable": self.reachable, "azimuths": self.azimuths,
                "max_tilt": self.max_tilt, "tilt_saturated": self.tilt_saturated,
                "min_max_tilt": self.min_max_tilt, "max_max_tilt": max(vals) if vals else None,
                "torsion_range": [self.torsion_min, self.torsion_max],
                "torsion_saturated": self.torsion_saturated,
                "settings": dataclasses.asdict(self.settings)}


def tilt_torsion_at(design: Design, position: Sequence[float],
                    settings: TiltTorsionSettings = TiltTorsionSettings(),
                    joints: Joints | None = None) -> TiltTorsionReport:
    """The T&T report at ``position`` (module docstring): ``theta_max`` per azimuth at zero torsion
    and the torsion range at zero tilt (with the joint cones and leg interference of ``joints``)."""
    p = np.asarray(position, float).reshape(1, 3)
    if not np.all(np.isfinite(p)):
        raise ParameterError("at", list(position), "three finite numbers x,y,z")
    az = azimuths(settings)
    s = settings

    def tilt_test(ray: np.ndarray, t: np.ndarray) -> np.ndarray:
        rots = tt_rotations(az[ray], t, np.zeros_like(t))
        return reachable_pairs(design, p, rots, s.eta_step, joints)[0]

    def torsion_test(ray: np.ndarray, t: np.ndarray) -> np.ndarray:
        sign = np.where(ray == 0, -1.0, 1.0)
        rots = tt_rotations(np.zeros_like(t), np.zeros_like(t), sign * t)
        return reachable_pairs(design, p, rots, s.eta_step, joints)[0]

    tilt, tsat = _ray_extent(tilt_test, az.size, s.tilt_limit, s.coarse_step, s.tolerance)
    tors, ssat = _ray_extent(torsion_test, 2, s.torsion_limit, s.coarse_step, s.tolerance)
    ok = bool(np.isfinite(tors[0]))
    def f(v: float) -> float | None:
        return float(v) if np.isfinite(v) else None

    return TiltTorsionReport(
        position=[float(v) for v in p[0]], reachable=ok, azimuths=[float(v) for v in az],
        max_tilt=[f(v) for v in tilt], tilt_saturated=[bool(v) for v in tsat],
        torsion_min=(-float(tors[0]) + 0.0) if ok else None, torsion_max=f(tors[1]),
        torsion_saturated=[bool(v) for v in ssat], settings=s)
