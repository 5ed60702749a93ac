"""Orientation workspace along the mechanism's symmetry lines (paper Sec. III, Fig. 3(e)-(g), eq. (28)).

Naming (the paper's Sec. III reuses eq. (2)'s letters with another meaning)
----------------------------------------------------------------------------
In eq. (2) ``psi`` is the rotation about z and ``phi`` the one about x (Z-Y-X Euler angles). In
Sec. III and eq. (28) the paper writes ``phi`` for the rotation about **z**, ``tau`` for the
rotation about **y'** and ``psi`` for the rotation about **x**. To avoid the clash the code names
the three rotations by their axis:

* ``"phi_z"``      -- rotation by ``phi`` about the world z axis, ``R = Rz(phi)``;
* ``"tau_yprime"`` -- rotation by ``tau`` about ``y' = (cos 60, sin 60, 0)``, Euler-Rodrigues
  (eq. (27) corrected, :func:`kinematics.rotation.axis_angle`);
* ``"psi_x"``      -- rotation by ``psi`` about the world x axis, ``R = Rx(psi)``.

Each rotation acts about axes through the platform centre ``P`` (``B = P + R u_bar``, eq. (3)) with
the other two angles zero. User-facing symbols (``"Δφ_z"``, ``"Δτ_y'"``...) follow the paper.

Lines (Sec. III: "x=0, y'=0; x=0, z=z0; y'=0, z=z0")
-----------------------------------------------------
* ``"z"``:       ``P = (0, 0, s)``, ``s`` from ``z_min`` (default 0: the platform stays above the
  base plane) to ``z_max`` (default ``l_max``);
* ``"y_prime"``: ``P = (s cos 60, s sin 60, z0)``, ``s in [-s_max, s_max]``;
* ``"x"``:       ``P = (s, 0, z0)``, ``s in [-s_max, s_max]``;

with default ``s_max = sqrt(r^2 + b^2/4) + l_max``. Both default ranges are rigorous covers for any
rotation: the six platform joints are centred on ``P`` (``sum_k R u_k = 0``), so some joint ``k``
has ``(R u_k) . e >= 0`` for any direction ``e``; its leg reaches from a U joint in the base plane
at radius ``<= sqrt(r^2 + b^2/4)``, hence ``P_z <= B_z <= l_max`` and
``|P_xy| <= |B_xy| <= sqrt(r^2 + b^2/4) + l_max``.

Sampling
--------
Positions ``s_k = k h_s`` (lattice through 0, step ``position_step``) inside the range; angles
``alpha_m = m h_a`` in ``[-A, A]`` (``A = angle_range``, ``h_a = angle_step``). A sample
``(s_k, alpha_m)`` is *feasible* when :func:`kinematics.workspace.reachable` accepts the pose
(compiled, exact in ``d``, arc stroke sampled every ``eta_step``); all the (position, angle) pairs of
a line and rotation are tested in one parallel launch that walks along the line coarse to fine
(:mod:`kinematics.line_scan`: the same answer as the pair-by-pair test, proof there).

Definition of the Δ's of eq. (28) (our precise reading)
--------------------------------------------------------
The paper: "Δφ_z represents the incremental difference in the projection of the boundary of φ on
the horizontal coordinate", and Δz the same on the vertical (position) coordinate. Each sample
stands for its cell (as a voxel does), clipped to the scanned box:

    C_km = [s_k - h_s/2, s_k + h_s/2] x [alpha_m - h_a/2, alpha_m + h_a/2]  ∩  [s_lo, s_hi] x [-A, A]

so the sampled boundary lies midway between a feasible and an infeasible sample. Let ``S`` be the
region's set of samples: all feasible samples (``region="all"``), or only the 4-connected
components of the feasible samples that contain a zero-rotation sample (``region="connected"``).
Then (projections of the union of the cells of ``S``)

    Δα = min(A, max_S alpha + h_a/2) - max(-A, min_S alpha - h_a/2)                       (D1)
    Δs = min(s_hi, max_S s + h_s/2) - max(s_lo, min_S s - h_s/2)                          (D2)
    area = sum_S |C_km|                                                                    (D3)

(all 0 for an empty region). A region that is a full rectangle of samples has ``area = Δα Δs``.
With ``delta="extent"`` (the paper's reading) each product of eq. (28) is ``P = Δα Δs`` of its
region; with ``delta="area"`` it is ``P = area`` (the actual size of a non-convex region). With
``position_delta="line"`` the position Δ of a line is that of the union of its three regions (the
paper's "Δz" is one number per line) instead of each region's own (``"per_region"``, default); it
only matters for ``delta="extent"``. ``position_delta="phi"`` is the literal reading of eq. (28):
one position Δ per line (``Δz``, ``Δy'``, ``Δx``) taken from the φ region of that line and used
in all three of the line's products.

A Δ is **saturated** when it equals the whole scanned range (``Δα = 2A`` or ``Δs = s_hi -
s_lo``): the index then measures the scan, not the mechanism (the result's ``saturated`` flags;
joint cones, :mod:`kinematics.joints`, are what makes φ finite for most designs). Eq. (28) is then

    TI_1 = (P(phi, z) + P(phi, y') + P(phi, x)) / 3                                       (28a)
    TI_2 = (P(tau, z) + P(psi, z) + P(tau, y') + P(psi, y') + P(tau, x) + P(psi, x)) / 6    (28b)

in degree x length.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from typing import Any

import numpy as np

from .design import Design, ParameterError
from .joints import Joints
from .line_scan import reachable_along
from .progress import CancelToken, ProgressFn, Reporter, check
from .rotation import Y_PRIME_AXIS, axis_angle, rot_x, rot_z
from .settings import ORIENTATION
from .workspace import reachable, reachable_pairs  # noqa: F401 - the documented test and its oracle

#: Line keys and their unit direction (``None``: the z line, positions are heights).
LINES: tuple[str, ...] = ("z", "y_prime", "x")
#: Rotation keys (named by axis; see the module docstring for the clash with eq. (2)).
ROTATIONS: tuple[str, ...] = ("phi_z", "tau_yprime", "psi_x")
#: The paper's symbols of Sec. III / eq. (28).
ROTATION_SYMBOL: dict[str, str] = {"phi_z": "φ", "tau_yprime": "τ", "psi_x": "ψ"}
LINE_SYMBOL: dict[str, str] = {"z": "z", "y_prime": "y'", "x": "x"}
DELTAS: tuple[str, ...] = ("extent", "area")
REGION_MODES: tuple[str, ...] = ("all", "connected")
POSITION_DELTAS: tuple[str, ...] = ("per_region", "line", "phi")

#: Largest (positions x angles) grid of one line that :func:`orientation_workspace` accepts.
MAX_SAMPLES = 20_000_000

_LINE_DIRECTION = {"y_prime": np.array([0.5, math.sqrt(3.0) / 2.0, 0.0]), "x": np.array([1.0, 0.0, 0.0])}


def _num(field: str, value: Any, lo: float, hi: float, *, lo_open: bool = False) -> float:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if ok:
        v = float(value)
        ok = (v > lo if lo_open else v >= lo) and v <= hi
    if not ok:
        raise ParameterError(field, value, f"{'(' if lo_open else '['}{lo:g}, {hi:g}]")
    return float(value)


def _choice(field: str, value: Any, options: tuple[str, ...]) -> str:
    if value not in options:
        raise ParameterError(field, value, "one of " + ", ".join(repr(o) for o in options))
    return value


@dataclasses.dataclass(frozen=True)
class OrientationSettings:
    """How the orientation workspace along the symmetry lines is sampled and measured.

    Attributes:
        z0: height of the x and y' lines (paper: 130).
        angle_range: angles are scanned in ``[-angle_range, angle_range]`` degrees, (0, 180].
        angle_step: angle sample spacing in degrees, [0.01, 30].
        position_step: position sample spacing along a line, [0.01, 100].
        delta: ``"extent"`` (paper: products ``Δα Δs``) or ``"area"`` (region area), eq. (28).
        region: ``"all"`` feasible samples or the ``"connected"`` components holding zero rotation.
        position_delta: ``"per_region"`` or ``"line"`` (union of a line's three regions).
        eta_step: arc-stroke sampling of the reachability test, degrees, [0.01, 10].
        z_min: lower end of the z line (default 0, the base plane).
        z_max: upper end of the z line; ``None``: a rigorous cover (``l_max`` for the paper's design; for a
            mechanism description the chains' reach, (S3) of :mod:`kinematics.mechanism_orientation`).
        s_max: half-length of the x and y' lines; ``None``: ``sqrt(r^2 + b^2/4) + l_max``.
        joints: passive-joint cones and leg interference of the reachability test
            (:mod:`kinematics.joints`); default: none (the paper's model).
    """

    z0: float = 130.0
    angle_range: float = 90.0
    angle_step: float = 0.5
    position_step: float = 1.0
    delta: str = "extent"
    region: str = "all"
    position_delta: str = "per_region"
    eta_step: float = 0.5
    z_min: float = 0.0
    z_max: float | None = None
    s_max: float | None = None
    joints: Joints = Joints()

    def __post_init__(self) -> None:
        set_ = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731
        if not isinstance(self.joints, Joints):
            raise ParameterError("joints", self.joints, "a Joints value")
        for name, spec in ORIENTATION.items():
            set_(name, spec.check(getattr(self, name)))
        if self.z_max is not None:
            set_("z_max", _num("z_max", self.z_max, self.z_min, 1e4))
        if self.s_max is not None:
            set_("s_max", _num("s_max", self.s_max, 0.0, 1e4))
        _choice("delta", self.delta, DELTAS)
        _choice("region", self.region, REGION_MODES)
        _choice("position_delta", self.position_delta, POSITION_DELTAS)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-serializable dict of the fields."""
        return dataclasses.asdict(self)

    def key(self) -> tuple:
        """Hashable identity used by caches."""
        return dataclasses.astuple(self)


# --------------------------------------------------------------------------------------------
# rotations and lines


def rotation_matrix(rotation: str, angle_deg: float) -> np.ndarray:
    """Rotation of the platform about an axis through its centre (paper Sec. III).

    ``"phi_z"``: ``Rz(phi)``; ``"tau_yprime"``: Euler-Rodrigues about ``y'`` (eq. (27), corrected:
    ``R' = c I + (1 - c) n n^T + s [n]_x`` with ``n = (1/2, sqrt(3)/2, 0)``); ``"psi_x"``: ``Rx(psi)``.
    """
    _choice("rotation", rotation, ROTATIONS)
    a = math.radians(float(angle_deg))
    if rotation == "phi_z":
        return rot_z(a)
    if rotation == "psi_x":
        return rot_x(a)
    return axis_angle(Y_PRIME_AXIS, a)


def line_points(line: str, positions: np.ndarray, z0: float = 130.0) -> np.ndarray:
    """Platform-centre positions ``P`` (N, 3) of the samples ``positions`` along ``line``."""
    _choice("line", line, LINES)
    s = np.asarray(positions, dtype=float).reshape(-1)
    if line == "z":
        pts = np.zeros((s.size, 3))
        pts[:, 2] = s
        return pts
    pts = s[:, None] * _LINE_DIRECTION[line][None, :]
    pts[:, 2] = z0
    return pts


def line_range(design: Design, line: str, settings: OrientationSettings) -> tuple[float, float]:
    """Scanned position interval ``[s_lo, s_hi]`` of a line (module docstring, "Lines")."""
    _choice("line", line, LINES)
    if line == "z":
        z_max = design.l_max if settings.z_max is None else settings.z_max
        return settings.z_min, max(settings.z_min, z_max)
    s_max = math.hypot(design.r, 0.5 * design.b) + design.l_max if settings.s_max is None else settings.s_max
    return -s_max, s_max


def _lattice(lo: float, hi: float, step: float) -> np.ndarray:
    """Multiples of ``step`` inside ``[lo, hi]`` (tolerant at the ends)."""
    k0 = math.ceil(lo / step - 1e-9)
    k1 = math.floor(hi / step + 1e-9)
    if k1 < k0:
        return np.zeros(0)
    return np.arange(k0, k1 + 1) * step


def angle_samples(settings: OrientationSettings) -> np.ndarray:
    """Angle samples ``m h_a`` in ``[-A, A]`` (degrees); always contains 0."""
    return _lattice(-settings.angle_range, settings.angle_range, settings.angle_step)


def position_samples(design: Design, line: str, settings: OrientationSettings) -> np.ndarray:
    """Position samples ``k h_s`` inside the line's range."""
    lo, hi = line_range(design, line, settings)
    return _lattice(lo, hi, settings.position_step)


# --------------------------------------------------------------------------------------------
# regions


def _cell_extent(values: np.ndarray, step: float, lo: float, hi: float) -> float:
    """Eqs. (D1)/(D2): length of the projection of the (clipped) cells centred at ``values``."""
    if values.size == 0:
        return 0.0
    return float(max(0.0, min(hi, values.max() + 0.5 * step) - max(lo, values.min() - 0.5 * step)))


def _cell_widths(values: np.ndarray, step: float, lo: float, hi: float) -> np.ndarray:
    return np.clip(np.minimum(values + 0.5 * step, hi) - np.maximum(values - 0.5 * step, lo), 0.0, None)


def select_region(feasible: np.ndarray, angles: np.ndarray, mode: str = "all") -> np.ndarray:
    """Samples making up the region: all feasible ones, or the 4-connected components of the
    feasible samples that contain a zero-angle sample (``mode="connected"``)."""
    _choice("region", mode, REGION_MODES)
    feasible = np.asarray(feasible, dtype=bool)
    if mode == "all" or not feasible.any():
        return feasible.copy()
    from scipy import ndimage

    labels, _n = ndimage.label(feasible)  # default structure: 4-connectivity in 2-D
    zero = np.flatnonzero(np.isclose(np.asarray(angles, float), 0.0, atol=1e-12))
    keep = np.unique(labels[:, zero])
    keep = keep[keep > 0]
    return np.isin(labels, keep)


@dataclasses.dataclass
class OrientationRegion:
    """Feasible (position, angle) samples of one rotation along one line, and their Δ's (D1)-(D3).

    ``feasible[k, m]`` is the reachability of position ``positions[k]`` at angle ``angles[m]``;
    ``selected`` the samples of the region (== ``feasible`` for ``region="all"``). The Δ's and
    ``area`` are computed from ``selected``.
    """

    line: str
    rotation: str
    positions: np.ndarray
    angles: np.ndarray
    feasible: np.ndarray
    delta_angle: float
    delta_position: float
    area: float
    selected: np.ndarray | None = None
    position_range: tuple[float, float] = (0.0, 0.0)
    angle_range: tuple[float, float] = (0.0, 0.0)
    angle_interval: tuple[float, float] | None = None
    position_interval: tuple[float, float] | None = None

    @property
    def symbol(self) -> str:
        """The paper's name of the region, e.g. ``"φ_z"`` or ``"τ_y'"``."""
        return f"{ROTATION_SYMBOL[self.rotation]}_{LINE_SYMBOL[self.line]}"

    @property
    def extent_product(self) -> float:
        """``Δα Δs`` of this region."""
        return self.delta_angle * self.delta_position

    @property
    def angle_saturated(self) -> bool:
        """``Δα`` equals the whole scanned angle range (limited by the scan, not the mechanism)."""
        return self.delta_angle >= (self.angle_range[1] - self.angle_range[0]) - 1e-9 > 0.0

    @property
    def position_saturated(self) -> bool:
        """``Δs`` equals the whole scanned line."""
        return self.delta_position >= (self.position_range[1] - self.position_range[0]) - 1e-9 > 0.0

    def to_dict(self, include_grid: bool = False) -> dict[str, Any]:
        """JSON-serializable summary; with ``include_grid`` also the sample axes and the grids."""
        sel = self.feasible if self.selected is None else self.selected
        out: dict[str, Any] = {
            "line": self.line, "rotation": self.rotation, "symbol": self.symbol,
            "delta_angle": float(self.delta_angle), "delta_position": float(self.delta_position),
            "area": float(self.area), "extent_product": float(self.extent_product),
            "angle_interval": None if self.angle_interval is None else [float(v) for v in self.angle_interval],
            "position_interval": None if self.position_interval is None else [float(v) for v in self.position_interval],
            "n_positions": int(len(self.positions)), "n_angles": int(len(self.angles)),
            "n_feasible": int(np.count_nonzero(self.feasible)), "n_selected": int(np.count_nonzero(sel)),
            "position_range": [float(v) for v in self.position_range],
            "angle_range": [float(v) for v in self.angle_range],
            "angle_saturated": bool(self.angle_saturated), "position_saturated": bool(self.position_saturated),
        }
        if include_grid:
            out["positions"] = [float(v) for v in self.positions]
            out["angles"] = [float(v) for v in self.angles]
            out["feasible"] = np.asarray(self.feasible, dtype=bool).tolist()
            out["selected"] = np.asarray(sel, dtype=bool).tolist()
        return out


def make_region(line: str, rotation: str, positions: np.ndarray, angles: np.ndarray, feasible: np.ndarray,
                *, position_step: float, angle_step: float,
                position_range: tuple[float, float] | None = None,
                angle_range: tuple[float, float] | None = None, region: str = "all") -> OrientationRegion:
    """Build a region and its Δ's from a feasibility grid (eqs. (D1)-(D3) of the module docstring).

    ``position_range``/``angle_range`` are the scanned box the cells are clipped to (default: the
    sample span widened by half a step on each side, i.e. no clipping).
    """
    _choice("line", line, LINES)
    _choice("rotation", rotation, ROTATIONS)
    pos = np.asarray(positions, dtype=float).reshape(-1)
    ang = np.asarray(angles, dtype=float).reshape(-1)
    feas = np.asarray(feasible, dtype=bool)
    if feas.shape != (pos.size, ang.size):
        raise ValueError(f"feasible has shape {feas.shape}, expected {(pos.size, ang.size)}")
    hs, ha = float(position_step), float(angle_step)
    if position_range is None:
        position_range = ((pos.min() - 0.5 * hs, pos.max() + 0.5 * hs) if pos.size else (0.0, 0.0))
    if angle_range is None:
        angle_range = ((ang.min() - 0.5 * ha, ang.max() + 0.5 * ha) if ang.size else (0.0, 0.0))
    sel = select_region(feas, ang, region)
    rows = sel.any(axis=1)
    cols = sel.any(axis=0)
    slo, shi = position_range
    alo, ahi = angle_range
    d_pos = _cell_extent(pos[rows], hs, slo, shi)
    d_ang = _cell_extent(ang[cols], ha, alo, ahi)
    if sel.any():
        area = float(_cell_widths(pos, hs, slo, shi) @ sel.astype(float) @ _cell_widths(ang, ha, alo, ahi))
        a_int = (float(max(alo, ang[cols].min() - 0.5 * ha)), float(min(ahi, ang[cols].max() + 0.5 * ha)))
        p_int = (float(max(slo, pos[rows].min() - 0.5 * hs)), float(min(shi, pos[rows].max() + 0.5 * hs)))
    else:
        area, a_int, p_int = 0.0, None, None
    return OrientationRegion(line=line, rotation=rotation, positions=pos, angles=ang, feasible=feas,
                             delta_angle=d_ang, delta_position=d_pos, area=area, selected=sel,
                             position_range=(float(slo), float(shi)), angle_range=(float(alo), float(ahi)),
                             angle_interval=a_int, position_interval=p_int)


def _line_position_delta(regions: list[OrientationRegion]) -> float:
    """Position Δ of the union of a line's regions (``position_delta="line"``)."""
    ints = [r.position_interval for r in regions if r.position_interval is not None]
    if not ints:
        return 0.0
    return float(max(i[1] for i in ints) - min(i[0] for i in ints))


def tilt_indices(regions: dict[tuple[str, str], OrientationRegion], delta: str = "extent",
                 position_delta: str = "per_region") -> tuple[float, float, dict[str, float]]:
    """Eq. (28): ``(TI_1, TI_2, deltas)`` from the nine regions (products as in the module docstring).

    ``deltas`` names every Δ as in the paper: ``"Δφ_z"`` (angle) and ``"Δz(φ)"`` (position of the
    φ region on the z line) etc., 18 entries, plus the nine products ``"P(φ_z)"``.
    """
    _choice("delta", delta, DELTAS)
    _choice("position_delta", position_delta, POSITION_DELTAS)
    missing = [k for k in ((ln, rt) for ln in LINES for rt in ROTATIONS) if k not in regions]
    if missing:
        raise ValueError(f"missing regions {missing}")
    deltas: dict[str, float] = {}
    products: dict[tuple[str, str], float] = {}
    for ln in LINES:
        line_regions = [regions[(ln, rt)] for rt in ROTATIONS]
        d_line = _line_position_delta(line_regions) if position_delta == "line" else \
            regions[(ln, "phi_z")].delta_position
        for rt in ROTATIONS:
            reg = regions[(ln, rt)]
            d_pos = reg.delta_position if position_delta == "per_region" else d_line
            deltas[f"Δ{ROTATION_SYMBOL[rt]}_{LINE_SYMBOL[ln]}"] = float(reg.delta_angle)
            deltas[f"Δ{LINE_SYMBOL[ln]}({ROTATION_SYMBOL[rt]})"] = float(d_pos)
            products[(ln, rt)] = float(reg.area) if delta == "area" else float(reg.delta_angle) * d_pos
    for (ln, rt), p in products.items():
        deltas[f"P({ROTATION_SYMBOL[rt]}_{LINE_SYMBOL[ln]})"] = p
    ti1 = sum(products[(ln, "phi_z")] for ln in LINES) / 3.0
    ti2 = sum(products[(ln, "tau_yprime")] + products[(ln, "psi_x")] for ln in LINES) / 6.0
    return float(ti1), float(ti2), deltas


@dataclasses.dataclass
class OrientationResult:
    """The nine regions (3 lines x 3 rotations) and the indices of eq. (28)."""

    settings: OrientationSettings
    regions: dict[tuple[str, str], OrientationRegion]
    ti1: float
    ti2: float
    compute_seconds: float
    deltas: dict[str, float] = dataclasses.field(default_factory=dict)
    design: Design | None = None

    @property
    def saturated(self) -> dict[str, bool]:
        """Per Δ of eq. (28) (``"Δφ_z"``, ``"Δz(φ)"``...): whether it equals the scanned range."""
        out: dict[str, bool] = {}
        for (ln, rt), reg in self.regions.items():
            out[f"Δ{ROTATION_SYMBOL[rt]}_{LINE_SYMBOL[ln]}"] = bool(reg.angle_saturated)
            out[f"Δ{LINE_SYMBOL[ln]}({ROTATION_SYMBOL[rt]})"] = bool(reg.position_saturated)
        return out

    def saturation_note(self) -> str:
        """One sentence naming, per index, the rotations and lines whose angle Δ spans the whole scan
        ``[-angle_range, angle_range]`` ('' when none does), e.g. "TI_1: φ on the z, y', x lines"."""
        a = self.settings.angle_range
        parts = []
        for index, rots in (("TI_1", ("phi_z",)), ("TI_2", ("tau_yprime", "psi_x"))):
            what = []
            for rt in rots:
                lines = [LINE_SYMBOL[ln] for ln in LINES if self.regions[(ln, rt)].angle_saturated]
                if lines:
                    what.append(f"{ROTATION_SYMBOL[rt]} on the {', '.join(lines)} line{'s' if len(lines) > 1 else ''}")
            if what:
                parts.append(f"{index}: {'; '.join(what)}")
        if not parts:
            return ""
        return (f"limited by the scan range ±{a:g}°, not by the mechanism: the angle reaches both bounds "
                f"-{a:g}° and {a:g}° for {'; '.join(parts)}; set joint cones or widen the scan (--angle-range)")

    def to_dict(self, include_grids: bool = False) -> dict[str, Any]:
        """JSON-serializable: ``"TI_1"``, ``"TI_2"``, ``"deltas"``, ``"saturated"`` (per Δ),
        ``"scan"`` (the scanned ranges), ``"regions"`` (keyed ``"<line>/<rotation>"``),
        ``"settings"``, ``"design"``, ``"compute_seconds"``."""
        return {
            "TI_1": float(self.ti1), "TI_2": float(self.ti2),
            "deltas": {k: float(v) for k, v in self.deltas.items()},
            "saturated": self.saturated,
            "saturation_note": self.saturation_note(),
            "scan": {"angle_range": [-float(self.settings.angle_range), float(self.settings.angle_range)],
                     "lines": {ln: [float(v) for v in reg.position_range]
                               for (ln, rt), reg in self.regions.items() if rt == "phi_z"}},
            "regions": {f"{ln}/{rt}": reg.to_dict(include_grid=include_grids)
                        for (ln, rt), reg in self.regions.items()},
            "settings": self.settings.to_dict(),
            "design": None if self.design is None else self.design.to_dict(),
            "compute_seconds": float(self.compute_seconds),
        }


@functools.lru_cache(maxsize=9)
def _rotation_table(rotation: str, angle_range: float, angle_step: float) -> np.ndarray:
    """:func:`rotation_matrix` of every angle sample, (M, 3, 3), built once per scan setting
    (read-only; the same matrices as one call per angle)."""
    ang = _lattice(-angle_range, angle_range, angle_step)
    rots = np.stack([rotation_matrix(rotation, a) for a in ang]) if ang.size else np.zeros((0, 3, 3))
    rots.setflags(write=False)
    return rots


def scan_line(design: Design, line: str, rotation: str, settings: OrientationSettings,
              progress: ProgressFn | None = None, cancel: CancelToken = None) -> OrientationRegion:
    """Feasibility grid of one rotation along one line: every (position, angle) pair in one parallel
    launch over the angles (:func:`kinematics.line_scan.reachable_along`, identical to
    :func:`kinematics.workspace.reachable_pairs`), in slices of angles for progress and
    cancellation."""
    rep = Reporter(progress)
    pos = position_samples(design, line, settings)
    ang = angle_samples(settings)
    pts = line_points(line, pos, settings.z0)
    feas = np.zeros((pos.size, ang.size), dtype=bool)
    if pos.size:
        rots = _rotation_table(rotation, settings.angle_range, settings.angle_step)
        step = max(1, min(ang.size, 4_000_000 // max(pos.size, 1)))
        for m in range(0, ang.size, step):
            check(cancel)
            rep(m / ang.size, f"orientation {LINE_SYMBOL[line]} line, {ROTATION_SYMBOL[rotation]}")
            feas[:, m:m + step] = reachable_along(design, pts, rots[m:m + step], settings.eta_step,
                                                  settings.joints)
    rep(1.0, "")
    return make_region(line, rotation, pos, ang, feas, position_step=settings.position_step,
                       angle_step=settings.angle_step, position_range=line_range(design, line, settings),
                       angle_range=(-settings.angle_range, settings.angle_range), region=settings.region)


def orientation_workspace(design: Design, settings: OrientationSettings = OrientationSettings(),
                          progress: ProgressFn | None = None, cancel: CancelToken = None) -> OrientationResult:
    """Orientation workspace along the z, y' and x lines and the indices TI_1, TI_2 of eq. (28).

    See the module docstring for the lines, the rotations and the definition (D1)-(D3) of the
    Deltas.

    Parameters
    ----------
    design : Design
        The mechanism's dimensions.
    settings : OrientationSettings, optional
        Height ``z0`` of the lines, angle range and steps, position step and the Delta definitions.
    progress : callable, optional
        ``progress(fraction, message)``.
    cancel : threading.Event or callable, optional
        Checked every few angles: when it is set the computation stops.

    Returns
    -------
    OrientationResult
        The reachable (position, angle) masks of the three lines, their Deltas and ``ti1``, ``ti2``
        (degree x length units).

    Raises
    ------
    Cancelled
        When ``cancel`` is set.

    Examples
    --------
    >>> import paraspace as ps
    >>> o = ps.orientation_workspace(ps.Design(), ps.OrientationSettings(angle_step=5.0, position_step=8.0))
    >>> o.ti1, o.ti2
    (28800.0, 12680.0)
    """
    rep = Reporter(progress)
    t0 = time.perf_counter()
    n_ang = angle_samples(settings).size
    for ln in LINES:
        n_pos = position_samples(design, ln, settings).size
        if n_pos * n_ang > MAX_SAMPLES:
            raise ParameterError("position_step", settings.position_step,
                                 f"coarser: {n_pos} x {n_ang} samples on the {ln} line exceed {MAX_SAMPLES}")
    regions: dict[tuple[str, str], OrientationRegion] = {}
    keys = [(ln, rt) for ln in LINES for rt in ROTATIONS]
    for n, (ln, rt) in enumerate(keys):
        check(cancel)
        regions[(ln, rt)] = scan_line(design, ln, rt, settings, rep.sub(n / len(keys), (n + 1) / len(keys)), cancel)
    ti1, ti2, deltas = tilt_indices(regions, settings.delta, settings.position_delta)
    seconds = time.perf_counter() - t0
    rep(1.0, "done")
    return OrientationResult(settings=settings, regions=regions, ti1=ti1, ti2=ti2, compute_seconds=seconds,
                             deltas=deltas, design=design)
