"""Design for a task: does the mechanism hold a region (or follow a pose list), by what margin, and
which limit binds? (our documented definitions; every test is the workspace engine's).

Task
----
* A **region** ``R`` of platform-centre positions: a box (centre ``c``, edges ``L_x, L_y, L_z``), a
  cylinder with a vertical axis (centre ``c``, radius ``rho``, height ``H``: ``|P_xy - c_xy| <=
  rho``, ``|P_z - c_z| <= H/2``) or a sphere (``|P - c| <= rho``), with an **orientation set** ``O``
  required at every point: one fixed orientation ``(psi, theta, phi)`` (eq. (2)), or every tilt
  ``<= T`` at every azimuth and every torsion in ``[-Q, Q]`` (the T&T angles (T1) of
  :mod:`kinematics.tilt_torsion`), sampled as the total-orientation workspace samples it
  (:func:`kinematics.dexterous.orientation_samples`, spacing ``angle_step``).
* A **pose list** (or trajectory): rows ``x, y, z, psi, theta, phi`` (degrees, eq. (2)), optionally a
  time ``t`` in seconds (strictly increasing), at most :data:`MAX_POSES` rows.

Sampling of a region. The region's bounding box is cut into ``n_a = ceil(E_a / h)`` equal cells per
axis (``E_a`` its extent; cell edge ``h_a = E_a / n_a <= h``); the **sample points** are the cell
centres inside ``R`` (for a box every cell; never none). The lattice is continued outward with the
same spacing up to ``margin_range`` for the margin. Each region has a signed distance ``s_R(q)``
(Euclidean distance to ``R`` outside, minus the distance to its boundary inside).

Answers
-------
* A sample pose ``(P, O_m)`` is *reachable* when :func:`kinematics.workspace.reachable_pairs` (the
  engine's test, exact in ``d``, arc sampled every ``eta_step``, with the joint options) accepts it;
  a point when it is reachable at every orientation sample. ``fraction`` = reachable sample points /
  sample points (a share of the region's volume, cell by cell) or reachable poses / poses for a
  pose list; ``contained`` = ``fraction == 1``.
* ``certified`` (never wrong): ``"not contained"`` when some task pose is proven outside the
  continuous workspace -- at a sample pose the per-chain test fails for some chain with the leg
  limits relaxed by the arc slack ``R_D Delta_eta / 2`` (``R_D = sqrt(r^2 + b^2/4)``) and the cones
  by the joint motion over half an arc spacing (the volume bracket's outside test,
  :mod:`kinematics.bracket`, with zero cell size: every carriage angle of the stroke is within half
  a spacing of a sample); ``"contained"`` when every pose of the **continuous** task is proven
  inside: for a pose list every pose is reachable (the engine's reachable poses come with a real
  carriage pose); for a region every cell ``C`` that meets ``R`` (half-diagonal ``delta``) passes,
  at every orientation sample, the tightened test at its centre with

      e = delta + a alpha + (alpha l_max where S cones are set) + eps                     (K1)

  where ``alpha`` bounds the rotation between any orientation of ``O`` and its nearest sample
  (:func:`cover_angle`): a platform point ``P + R u`` (``|u| = a``) then moves by at most ``delta +
  a alpha`` and an S cone's axis by ``alpha`` (its (J1) function by ``alpha |B - D| <= alpha
  l_max``); by the Lipschitz lemma of :mod:`kinematics.blocks` the carriage pose that passes the
  tightened test serves every pose of the cell. With leg interference a region is never certified
  contained (the bracket does not model it); ``"undecided"`` otherwise.
* ``margin`` of a region: the largest ``m`` such that the region grown by ``m`` (every point within
  ``m`` of ``R``; shrunk, ``m < 0``: the points at depth ``>= -m``) lies in the workspace. With
  ``W`` the positions reachable at every orientation sample,

      m = min { s_R(q) : q not in W }                                                    (K2)

  over the lattice (``m <= 0`` exactly when some sample point is unreachable); when no unreachable
  lattice point lies within ``margin_range`` the margin is reported as ``margin_range`` with
  ``margin_saturated``. Lattice resolution: ``h sqrt(3) / 2``.
* For a pose list the carriages are chosen continuously (below); at each pose the **slacks** at
  the chosen carriage pose are the legs' ``min(l - l_min, l_max - l)`` (length), the carriages'
  distances to their stroke ends (``d`` in length, ``eta`` in degrees) and, with cones, the joints'
  ``theta - angle`` (degrees). ``margin`` of a pose list is the smallest leg slack (negative: the
  largest violation at an unreachable pose).
* ``worst``: the pose where the margin is attained: for a region the sample pose nearest the
  unreachable lattice point ``q*`` of (K2) (``q*`` itself is reported as ``at``); for a pose list
  the pose of the smallest leg slack. ``binding``: the limit that fails first there: at ``q*`` for a
  region (the first limit the grown region meets), at an unreachable worst pose, or the nearest
  limit at a reachable one: ``chain`` and ``leg``, ``limit`` in ``l_max``, ``l_min``, ``u_cone``,
  ``s_cone``, ``cones``, ``interference``, ``sampling`` (as :mod:`kinematics.diagnostics` names
  them) or ``stroke`` (a carriage at its stroke's end), with the stroke end the least violation
  sits at, if any.

Carriage motion along a pose list (per chain; the chains are independent)
-------------------------------------------------------------------------
On the grid of the engine's arc samples ``eta_k`` times ``n_rho`` rail values the chain's margin
``M(eta, rho)`` = the smallest of its legs' slacks and, with cones, the (J1) slacks ``a . v -
cos(theta) |v|`` (length units); ``F_n = {M >= 0}`` at pose ``n``. Sample 0 takes the grid's best
cell. At sample ``n`` the previous carriage ``c_{n-1}`` is **kept** when its margin at pose ``n``
is at least ``mu_n = min(carriage_margin, max M / 2)``; otherwise the carriage moves to the nearest
(``|Delta rho|^2 + (R_D Delta eta)^2``) cell with ``M >= mu_n`` among the components of ``F_n``
that meet the component of ``c_{n-1}`` in ``F_{n-1}`` (the carriage can slide inside ``F_{n-1}`` to
a pose that serves both samples), stopping at the first point of the straight move that has the
margin. When no such component exists the carriages **must jump**: the sample is a discontinuity
(chain and jump size reported) and the nearest cell of ``F_n`` is taken. The choice is greedy: it
never reports a jump where the sets of consecutive samples are connected, but it cannot undo an
earlier choice of component. Where the engine reaches a pose that the grid misses (a feasible set
thinner than a grid cell) the engine's carriage pose is used. Unreachable samples take the least
violation and restart the motion. Per sample the 12 actuator values ``q = [l_1^1 .. l_3^2, d_1 ..
d_3, eta_1 .. eta_3]`` (eq. (20)); the carriage travel (sum of ``|Delta d|``, of ``|Delta eta|``),
the largest carriage speeds when ``t`` is given, and each actuator's range used against its stroke.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
from numba import njit, prange
from scipy import ndimage as ndi

from .blocks import FAIL, OK, decide_chain, rounding_margin, sub_arcs
from .design import Design, ParameterError
from .dexterous import _pow2, orientation_samples
from .diagnostics import _violated_limit
from .feasibility import ChainTables, _chain_excluded, chain_points, chain_search, default_n_eta
from .geometry import GAMMA, LEG_SIGN, base_points, platform_points, platform_points_local
from .interference import interference_free
from .joints import Joints, cone_angles, cone_table
from .kernel_args import kernel_args
from .parallel import KERNEL_LOCK
from .pose import POSE_FIELDS, POSE_LIMITS, Pose
from .progress import CancelToken, ProgressFn, Reporter, check
from .redundancy import _best_carriage, _chain_margins, _engine_carriage, resolve_redundancy
from .rotation import euler_zyx_deg
from .settings import TASK, TOTAL_ORIENTATION, WORKSPACE
from .tilt_torsion import tt_rotations
from .workspace import chain_masks_at, reachable_pairs, rotation_tables

__all__ = ["Region", "OrientationSet", "TaskSettings", "PoseList", "TaskResult", "SHAPES", "MAX_POSES",
           "MAX_CSV_BYTES", "MAX_POINTS", "region_task", "pose_list_task", "read_pose_csv", "cover_angle",
           "evaluate_task", "poses_reachable", "pose_binding", "region_samples", "TaskSpec"]

SHAPES: dict[str, tuple[str, ...]] = {"box": ("LX", "LY", "LZ"), "cylinder": ("R", "H"), "sphere": ("R",)}
#: Largest pose list (rows of a CSV), the same everywhere.
MAX_POSES = int(TASK["max_poses"].hi)
#: Largest pose-list CSV text (bytes): about 100 bytes per row of :data:`MAX_POSES`.
MAX_CSV_BYTES = 100 * MAX_POSES
#: Largest number of lattice points of a region (with its margin shell) times orientation samples.
MAX_POINTS = 50_000_000
#: Rail values of the carriage grid of a pose list.
N_RHO = 81
#: Orientation samples per launch of the pair kernel.
BATCH = 16


def _num(field: str, value: Any, key: str) -> float:
    """``value`` checked by the :data:`kinematics.settings.TASK` entry ``key``, named ``field``."""
    try:
        return float(TASK[key].parse(value))
    except ParameterError as err:
        raise ParameterError(field, value, err.valid) from None


# --------------------------------------------------------------------------------------------
# task definitions


@dataclasses.dataclass(frozen=True)
class Region:
    """A box, a vertical cylinder or a sphere (module docstring). ``sizes``: box ``(LX, LY, LZ)``
    edges, cylinder ``(R, H)``, sphere ``(R,)``."""

    shape: str
    center: tuple[float, float, float]
    sizes: tuple[float, ...]

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise ParameterError("shape", self.shape, " or ".join(SHAPES))
        c = tuple(self.center) if isinstance(self.center, (list, tuple, np.ndarray)) else ()
        if len(c) != 3:
            raise ParameterError("center", self.center, "three numbers CX,CY,CZ")
        object.__setattr__(self, "center", tuple(_num(n, v, "center") for n, v in zip(("CX", "CY", "CZ"), c)))
        names = SHAPES[self.shape]
        s = tuple(self.sizes) if isinstance(self.sizes, (list, tuple, np.ndarray)) else ()
        if len(s) != len(names):
            raise ParameterError(self.shape, self.sizes, f"{len(names)} sizes {','.join(names)}")
        object.__setattr__(self, "sizes", tuple(_num(n, v, "size") for n, v in zip(names, s)))

    @classmethod
    def parse(cls, shape: str, values: Sequence[float]) -> Region:
        """From the CLI's ``CX,CY,CZ,<sizes>`` numbers."""
        names = ("CX", "CY", "CZ", *SHAPES.get(shape, ()))
        vals = list(values)
        if shape not in SHAPES or len(vals) != len(names):
            raise ParameterError(shape, ",".join(f"{v:g}" for v in vals), f"{len(names)} numbers {','.join(names)}")
        return cls(shape, tuple(vals[:3]), tuple(vals[3:]))  # type: ignore[arg-type]

    @property
    def extent(self) -> np.ndarray:
        """Edges of the bounding box."""
        if self.shape == "box":
            return np.array(self.sizes)
        if self.shape == "cylinder":
            return np.array([2 * self.sizes[0], 2 * self.sizes[0], self.sizes[1]])
        return np.full(3, 2 * self.sizes[0])

    @property
    def volume(self) -> float:
        if self.shape == "box":
            return float(np.prod(self.sizes))
        if self.shape == "cylinder":
            return math.pi * self.sizes[0] ** 2 * self.sizes[1]
        return 4.0 / 3.0 * math.pi * self.sizes[0] ** 3

    def sdf(self, pts: np.ndarray) -> np.ndarray:
        """Signed distance ``s_R`` (negative inside) of points (N, 3)."""
        q = np.asarray(pts, float) - np.asarray(self.center)
        if self.shape == "sphere":
            return np.linalg.norm(q, axis=1) - self.sizes[0]
        if self.shape == "box":
            d = np.abs(q) - 0.5 * np.asarray(self.sizes)
        else:
            d = np.stack([np.hypot(q[:, 0], q[:, 1]) - self.sizes[0], np.abs(q[:, 2]) - 0.5 * self.sizes[1]], axis=1)
        out = np.linalg.norm(np.maximum(d, 0.0), axis=1)
        return out + np.minimum(d.max(axis=1), 0.0)

    def to_dict(self) -> dict[str, Any]:
        return {"shape": self.shape, "center": list(self.center),
                **{n.lower(): v for n, v in zip(SHAPES[self.shape], self.sizes)}}


@dataclasses.dataclass(frozen=True)
class OrientationSet:
    """One fixed orientation ``fixed = (psi, theta, phi)`` (eq. (2)), or, when ``tilt`` or
    ``torsion`` is given, every tilt ``<= tilt`` (all azimuths) and torsion in ``[-torsion, torsion]``
    about the home orientation (degrees)."""

    tilt: float | None = None
    torsion: float | None = None
    fixed: tuple[float, float, float] = (0.0, 0.0, 0.0)
    step: float = 5.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "step", float(TASK["angle_step"].parse(self.step)))
        if self.total:
            for name in ("tilt", "torsion"):
                v = getattr(self, name)
                object.__setattr__(self, name, float(TOTAL_ORIENTATION[name].parse(0.0 if v is None else v)))
            if any(abs(float(a)) > 0.0 for a in self.fixed):
                raise ParameterError("orientation", list(self.fixed), "(0, 0, 0) with a tilt or torsion (T&T angles "
                                     "are about the home orientation)")
        o = tuple(float(v) for v in self.fixed)
        if len(o) != 3:
            raise ParameterError("orientation", self.fixed, "three angles psi,theta,phi in degrees")
        for name, v in zip(("psi", "theta", "phi"), o):
            lo, hi = POSE_LIMITS[name]
            if not (math.isfinite(v) and lo <= v <= hi):
                raise ParameterError(name, v, f"[{lo:g}, {hi:g}] degrees")
        object.__setattr__(self, "fixed", o)

    @property
    def total(self) -> bool:
        return self.tilt is not None or self.torsion is not None

    def samples(self) -> np.ndarray:
        """``(azimuth, tilt, torsion)`` rows, hardest first (empty for a fixed orientation)."""
        if not self.total:
            return np.zeros((0, 3))
        return orientation_samples(self.tilt or 0.0, self.torsion or 0.0, self.step)

    def rotations(self) -> np.ndarray:
        """The orientation samples as rotation matrices (M, 3, 3)."""
        if not self.total:
            return euler_zyx_deg(*self.fixed)[None]
        s = self.samples()
        return tt_rotations(s[:, 0], s[:, 1], s[:, 2])

    def to_dict(self) -> dict[str, Any]:
        if self.total:
            return {"tilt": self.tilt, "torsion": self.torsion, "angle_step": self.step,
                    "orientations": int(self.samples().shape[0]), "cover_angle": math.degrees(cover_angle(self))}
        return {"fixed": list(self.fixed)}


def cover_angle(oset: OrientationSet) -> float:
    """``alpha`` of (K1), radians: every orientation of the continuous set is reached from its
    nearest sample by turning the azimuth at its own tilt (angular speed ``|z - R z| = 2 sin(theta/2)``
    per radian of azimuth, since ``R = Rz(phi) Ry(theta) Rz(sigma - phi)``), then the tilt and the
    torsion (unit speed each); the sum of the three turns bounds the rotation between them. Near zero
    tilt (the ring ``theta = 0``, one azimuth) ``R`` is a turn by ``theta`` from ``Rz(sigma)``."""
    if not oset.total:
        return 0.0
    tilt, torsion, step = oset.tilt or 0.0, oset.torsion or 0.0, oset.step
    alpha = 0.0
    if torsion > 0:
        alpha += torsion / _pow2(2 * torsion, step, 1)  # half the torsion spacing
    if tilt > 0:
        m = _pow2(tilt, step, 1)
        half = 0.5 * tilt / m
        worst = 0.0
        for r in range(m + 1):
            th = r * tilt / m
            top = min(th + half, tilt)
            if r == 0:  # R(phi, theta, sigma) is a turn by theta from Rz(sigma): no azimuth turn
                worst = max(worst, math.radians(top))
                continue
            na = _pow2(360.0 * math.sin(math.radians(th)), step, 2)
            worst = max(worst, math.radians(half) + 2.0 * math.sin(math.radians(top) / 2.0) * math.pi / na)
        return math.radians(alpha) + worst
    return math.radians(alpha)


@dataclasses.dataclass(frozen=True)
class TaskSettings:
    """How a task is sampled (ranges: :data:`kinematics.settings.TASK`; ``voxel`` and ``eta_step``:
    :data:`kinematics.settings.WORKSPACE`)."""

    voxel: float = 2.0
    eta_step: float = 0.5
    margin_range: float = 10.0
    carriage_margin: float = 1.0
    joints: Joints = Joints()

    def __post_init__(self) -> None:
        for name in ("voxel", "eta_step", "margin_range", "carriage_margin"):
            table = WORKSPACE if name in ("voxel", "eta_step") else TASK
            object.__setattr__(self, name, float(table[name].parse(getattr(self, name))))
        if not isinstance(self.joints, Joints):
            raise ParameterError("joints", self.joints, "a Joints value")


@dataclasses.dataclass(frozen=True)
class PoseList:
    """Poses (N, 6): ``x, y, z, psi, theta, phi`` (degrees); ``t`` (N,) seconds or ``None``."""

    poses: np.ndarray
    t: np.ndarray | None = None

    def __post_init__(self) -> None:
        p = np.asarray(self.poses, float)
        if p.ndim != 2 or p.shape[1] != 6 or p.shape[0] < 1:
            raise ParameterError("poses", f"shape {p.shape}", "rows of 6 numbers x,y,z,psi,theta,phi")
        if p.shape[0] > MAX_POSES:
            raise ParameterError("poses", f"{p.shape[0]:,} rows", f"at most {MAX_POSES:,} poses")
        for k, name in enumerate(POSE_FIELDS):
            lo, hi = POSE_LIMITS[name]
            bad = np.flatnonzero(~(np.isfinite(p[:, k]) & (p[:, k] >= lo) & (p[:, k] <= hi)))
            if bad.size:
                raise ParameterError(f"{name} (row {int(bad[0]) + 1})", float(p[bad[0], k]), f"[{lo:g}, {hi:g}]")
        object.__setattr__(self, "poses", p)
        if self.t is not None:
            t = np.asarray(self.t, float).reshape(-1)
            if t.shape[0] != p.shape[0] or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
                raise ParameterError("t", "column", "one finite, strictly increasing time per pose (seconds)")
            object.__setattr__(self, "t", t)

    def __len__(self) -> int:
        return int(self.poses.shape[0])


def read_pose_csv(text: str | bytes) -> PoseList:
    """A pose list from CSV text with the header ``x,y,z,psi,theta,phi[,t]`` (any column order;
    angles in degrees, ``t`` in seconds); at most :data:`MAX_POSES` rows."""
    if len(text) > MAX_CSV_BYTES:
        raise ParameterError("points", f"{len(text):,} bytes", f"at most {MAX_CSV_BYTES:,} bytes (at most "
                             f"{MAX_POSES:,} poses)")
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8-sig")
        except UnicodeDecodeError:
            raise ParameterError("points", "file", "UTF-8 CSV text") from None
    try:
        return _read_rows(text)
    except csv.Error as err:
        raise ParameterError("points", "CSV", f"readable CSV text ({err})") from None


def _read_rows(text: str) -> PoseList:
    reader = csv.reader(io.StringIO(text))
    header = None
    rows: list[list[float]] = []
    for line_no, row in enumerate(reader, 1):
        if not row or all(not c.strip() for c in row):
            continue
        if header is None:
            header = [c.strip().lower() for c in row]
            missing = [f for f in POSE_FIELDS if f not in header]
            if missing:
                raise ParameterError("points", ",".join(header), "a CSV with the header x,y,z,psi,theta,phi[,t]")
            cols = [header.index(f) for f in POSE_FIELDS] + ([header.index("t")] if "t" in header else [])
            continue
        if len(rows) >= MAX_POSES:
            raise ParameterError("poses", f"more than {MAX_POSES:,} rows", f"at most {MAX_POSES:,} poses")
        try:
            rows.append([float(row[c]) for c in cols])
        except (ValueError, IndexError):
            raise ParameterError(f"points (line {line_no})", ",".join(row), "numbers in every column") from None
    if header is None or not rows:
        raise ParameterError("points", "empty", "a CSV with the header x,y,z,psi,theta,phi[,t] and at least one row")
    arr = np.array(rows)
    return PoseList(arr[:, :6], arr[:, 6] if arr.shape[1] == 7 else None)


# --------------------------------------------------------------------------------------------
# certification kernel


@njit(parallel=True, cache=True, nogil=True)
def _certify_kernel(points, e_tight, can_fail, pidx, midx, us, jcs, cos_t, sin_t, arc, seg_k, seg_arc, hb,
                    rho_lo, rho_hi, lmin, lmax, e_relax, cone_relax, e_bound, out):
    """Per pair ``(points[pidx[q]], orientation midx[q])``: 1 when every chain passes the tightened test
    (leg limits by ``e_tight[p]``), 2 when some chain fails the relaxed one (only where ``can_fail[p]``),
    else 0 (:func:`kinematics.blocks.decide_chain`)."""
    n = cos_t.shape[1]
    for q in prange(pidx.shape[0]):
        p = pidx[q]
        m = midx[q]
        win = np.empty(3, np.int64)
        res = 1
        for i in range(3):
            win[0] = n // 2
            win[1] = 0
            win[2] = n - 1
            st = decide_chain(points[p, 0], points[p, 1], points[p, 2], us[m], i, cos_t, sin_t, arc, seg_k, seg_arc,
                              hb, rho_lo, rho_hi, lmin, lmax, jcs[m], e_bound, e_relax, cone_relax, e_tight[p], True,
                              win)
            if st == FAIL and can_fail[p]:
                res = 2
                break
            if st != OK:
                res = 0
        out[q] = res


@njit(parallel=True, cache=True, nogil=True)
def _poses_kernel(points, us, jcs, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, out):
    """The engine's test of :func:`kinematics.workspace.reachable_pairs` for pose ``k`` = (point ``k``,
    rotation ``k``) (the diagonal of the pair kernel)."""
    n_eta = cos_t.shape[1]
    for k in prange(points.shape[0]):
        ok = True
        for i in range(3):
            b1x, b1y, b1z, b2x, b2y, b2z = chain_points(points[k, 0], points[k, 1], points[k, 2], us[k], i)
            if _chain_excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc[i], rho_lo, rho_hi, lmin2, lmax2):
                ok = False
                break
            if chain_search(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i], sin_t[i], hb, rho_lo, rho_hi, lmin2, lmax2,
                            jcs[k, i], n_eta // 2) < 0:
                ok = False
                break
        out[k] = ok


def poses_reachable(design: Design, points: np.ndarray, rotations: np.ndarray, eta_step: float = 0.5,
                    joints: Joints | None = None) -> np.ndarray:
    """Whether pose ``k`` (``points[k]``, ``rotations[k]``) is reachable, for every ``k``: the test of
    :func:`kinematics.workspace.reachable_pairs` (with leg interference) in one launch."""
    pts = np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 3))
    rots = np.asarray(rotations, dtype=np.float64).reshape(-1, 3, 3)
    jn = joints or Joints()
    n_eta = default_n_eta(design, eta_step)
    _, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, _ = kernel_args(design, np.eye(3), n_eta)
    us, jcs = rotation_tables(design, rots, jn)
    out = np.zeros(pts.shape[0], np.bool_)
    if out.size:
        with KERNEL_LOCK:
            _poses_kernel(pts, us, jcs, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, out)
        if jn.min_distance > 0.0:
            for k in np.flatnonzero(out):
                out[k] = interference_free(design, jn, pts[k], rots[k][None], n_eta)[0, 0]
    return out


class _Certifier:
    """The tightened / relaxed tests of the module docstring for one design, orientation set, joints."""

    def __init__(self, design: Design, rots: np.ndarray, joints: Joints, eta_step: float, reach_xy: float) -> None:
        n_eta = default_n_eta(design, eta_step)
        args = kernel_args(design, np.eye(3), n_eta)
        _, self.cos_t, self.sin_t, self.arc, self.hb, self.rho_lo, self.rho_hi, lmin2, lmax2, _ = args
        self.lmin, self.lmax = math.sqrt(lmin2), math.sqrt(lmax2)
        self.us, self.jcs = rotation_tables(design, rots, joints)
        self.seg_k, self.seg_arc = sub_arcs(self.cos_t, self.sin_t)
        lo, hi = design.eta_limits
        d_eta = math.radians(hi - lo) / (n_eta - 1) if n_eta > 1 else 0.0
        r_d = math.hypot(design.r, 0.5 * design.b)
        self.arc_slack = r_d * 0.5 * d_eta
        self.cone_slack = max(r_d, reach_xy + design.a) * 0.5 * d_eta
        self.eps = rounding_margin(self.lmax, (np.array([reach_xy]),))

    def run(self, points: np.ndarray, e_tight: np.ndarray, can_fail: np.ndarray, pidx: np.ndarray,
            midx: np.ndarray) -> np.ndarray:
        out = np.zeros(pidx.shape[0], np.int8)
        if out.size:
            with KERNEL_LOCK:
                _certify_kernel(np.ascontiguousarray(points, dtype=np.float64),
                                np.ascontiguousarray(e_tight + self.eps),
                                np.ascontiguousarray(can_fail, dtype=np.bool_), np.ascontiguousarray(pidx, np.int64),
                                np.ascontiguousarray(midx, np.int64), self.us, self.jcs, self.cos_t, self.sin_t,
                                self.arc, self.seg_k, self.seg_arc, self.hb, self.rho_lo, self.rho_hi, self.lmin,
                                self.lmax, self.arc_slack + self.eps, self.cone_slack + self.eps, self.eps, out)
        return out

    def proven_outside(self, points: np.ndarray, midx: np.ndarray) -> np.ndarray:
        """Per (point, orientation) pair: the pose is proven outside the continuous workspace."""
        n = points.shape[0]
        big = np.full(n, 1e300)  # no inside test
        return self.run(points, big, np.ones(n, bool), np.arange(n), midx) == 2


# --------------------------------------------------------------------------------------------
# binding limit and slacks at one pose


def _stroke_end(design: Design, d: float, eta: float) -> str | None:
    tol_d = 1e-6 * max(1.0, design.d_s)
    lo, hi = design.eta_limits
    if design.d_s > 0 and d <= tol_d:
        return "d = 0 (outer end)"
    if design.d_s > 0 and d >= design.d_s - tol_d:
        return "d = d_s (inner end)"
    if hi > lo and eta <= lo + 1e-6:
        return f"eta = {lo:g} (arc end)"
    if hi > lo and eta >= hi - 1e-6:
        return f"eta = {hi:g} (arc end)"
    return None


def pose_binding(design: Design, position: Sequence[float] | np.ndarray, rotation: np.ndarray, joints: Joints,
                 eta_step: float = 0.5) -> dict[str, Any]:
    """Which limit fails at a pose (:mod:`kinematics.diagnostics`' names): the first chain that fails,
    with ``l_max`` / ``l_min`` / ``sampling`` at its least-violation carriage pose (and the stroke end
    that pose sits at), or the cone that stops it; ``interference`` when the chains pass alone; ``limit
    None`` ("reachable") at a reachable pose."""
    p = np.asarray(position, float).reshape(1, 3)
    rot = np.asarray(rotation, float)
    plain = int(chain_masks_at(design, p, rot, eta_step, Joints())[0])
    cones = Joints(theta_u=joints.theta_u, theta_s=joints.theta_s, cone_axis=joints.cone_axis)
    with_cones = int(chain_masks_at(design, p, rot, eta_step, cones)[0]) if cones.has_cones else plain
    B = platform_points(design, p[0], rot)
    for i in range(3):
        if (with_cones >> i) & 1:
            continue
        if not (plain >> i) & 1:
            limit = _violated_limit(design, B[i], i)
            d, eta = _best_carriage(design, B[i], i)
            lengths = np.linalg.norm(B[i] - base_points(design, [d] * 3, [eta] * 3)[i], axis=1)
            j = int(np.argmin(np.minimum(lengths - design.l_min, design.l_max - lengths)))
            end = _stroke_end(design, d, eta)
            msg = f"chain {i + 1}, leg {j + 1}: {limit}" + (f" with the carriage at {end}" if end else "")
            return {"chain": i + 1, "leg": j + 1, "limit": limit, "stroke_end": end, "message": msg}
        only_u = int(chain_masks_at(design, p, rot, eta_step, dataclasses.replace(cones, theta_s=None))[0])
        only_s = int(chain_masks_at(design, p, rot, eta_step, dataclasses.replace(cones, theta_u=None))[0])
        limit = "u_cone" if not (only_u >> i) & 1 else ("s_cone" if not (only_s >> i) & 1 else "cones")
        return {"chain": i + 1, "leg": None, "limit": limit, "stroke_end": None,
                "message": f"chain {i + 1}: the {limit.replace('_', ' ')} "
                           f"(theta_U = {joints.theta_u}, theta_S = {joints.theta_s} degrees)"}
    if joints.min_distance > 0.0 and not reachable_pairs(design, p, rot[None], eta_step, joints)[0, 0]:
        return {"chain": None, "leg": None, "limit": "interference", "stroke_end": None,
                "message": f"legs closer than leg_diameter + clearance = {joints.min_distance:g}"}
    return {"chain": None, "leg": None, "limit": None, "stroke_end": None, "message": "reachable"}


def _slacks(design: Design, joints: Joints, position: np.ndarray, rot: np.ndarray, d: np.ndarray,
            eta: np.ndarray) -> dict[str, Any]:
    """Slacks at a carriage pose: legs (length), strokes (d length, eta degrees), cones (degrees)."""
    b = platform_points(design, position, rot)
    dp = base_points(design, d, eta)
    lengths = np.linalg.norm(b - dp, axis=-1)
    leg = np.minimum(lengths - design.l_min, design.l_max - lengths)
    lo, hi = design.eta_limits
    out: dict[str, Any] = {"leg": float(leg.min()), "leg_at": [int(v) + 1 for v in np.unravel_index(int(np.argmin(leg)),
                                                                                                      (3, 2))],
                           "leg_limit": None, "d": float(np.minimum(d, design.d_s - d).min()),
                           "eta": float(np.minimum(eta - lo, hi - eta).min()), "u_cone": None, "s_cone": None}
    i, j = out["leg_at"][0] - 1, out["leg_at"][1] - 1
    out["leg_limit"] = "l_min" if lengths[i, j] - design.l_min <= design.l_max - lengths[i, j] else "l_max"
    if joints.has_cones:
        ang = cone_angles(design, joints, rot, b, dp, eta)
        if joints.theta_u is not None:
            out["u_cone"] = float(joints.theta_u - ang[:, :, 0].max())
        if joints.theta_s is not None:
            out["s_cone"] = float(joints.theta_s - ang[:, :, 1].max())
    return out


# --------------------------------------------------------------------------------------------
# results


@dataclasses.dataclass
class TaskResult:
    """Answers for a task (module docstring); ``to_dict`` is the CLI's and REST's JSON."""

    kind: str  # "region" or "poses"
    fraction: float
    contained: bool
    certified: str
    margin: float
    worst: dict[str, Any]
    binding: dict[str, Any]
    slack: dict[str, Any]
    details: dict[str, Any]
    seconds: float
    poses: list[dict[str, Any]] | None = None
    discontinuities: list[dict[str, Any]] | None = None
    #: a region's sample points (N, 3) and whether each is reachable at every orientation sample
    #: (for drawing; not in ``to_dict``)
    cells: np.ndarray | None = None
    cells_ok: np.ndarray | None = None

    def to_dict(self) -> dict[str, Any]:
        out = {"kind": self.kind, "fraction": self.fraction, "contained": self.contained,
               "certified": self.certified, "margin": self.margin, "worst": self.worst, "binding": self.binding,
               "slack": self.slack, **self.details, "seconds": self.seconds}
        if self.poses is not None:
            out["poses"] = self.poses
            out["discontinuities"] = self.discontinuities
        return out


def _rot_of(oset: OrientationSet, m: int, rots: np.ndarray) -> dict[str, Any]:
    if oset.total:
        s = oset.samples()[m]
        return {"azimuth": float(s[0]), "tilt": float(s[1]), "torsion": float(s[2])}
    return {"psi": oset.fixed[0], "theta": oset.fixed[1], "phi": oset.fixed[2]}


def _reach_points(design: Design, pts: np.ndarray, rots: np.ndarray, settings: TaskSettings, rep: Reporter,
                  cancel: CancelToken) -> tuple[np.ndarray, np.ndarray]:
    """Per point: reachable at every orientation, and the first batch at which it failed (-1)."""
    alive = np.ones(pts.shape[0], bool)
    failed_at = np.full(pts.shape[0], -1, np.int64)
    n = rots.shape[0]
    for s in range(0, n, BATCH):
        check(cancel)
        live = np.flatnonzero(alive)
        if not live.size:
            break
        ok = reachable_pairs(design, pts[live], rots[s:s + BATCH], settings.eta_step, settings.joints).all(axis=1)
        alive[live[~ok]] = False
        failed_at[live[~ok]] = s
        rep(min(1.0, (s + BATCH) / n), f"task: {int(alive.sum()):,} of {pts.shape[0]:,} points reachable")
    return alive, failed_at


def _first_failure(design: Design, p: np.ndarray, rots: np.ndarray, start: int, settings: TaskSettings) -> int:
    ok = reachable_pairs(design, p.reshape(1, 3), rots[start:start + BATCH], settings.eta_step, settings.joints)[0]
    bad = np.flatnonzero(~ok)
    return start + int(bad[0]) if bad.size else start


def _lattice(region: Region, h: float, grow: float) -> tuple[list[np.ndarray], int, np.ndarray]:
    """Lattice points (N, 3) of the region's cells continued ``grow`` outward, their signed
    distances, and the cells' half-extent per axis (3,)."""
    ext = region.extent
    axes, half = [], np.zeros(3)
    for a in range(3):
        if ext[a] > 0:
            n = max(1, int(math.ceil(ext[a] / h - 1e-9)))
            ha = ext[a] / n
            g = int(math.ceil(grow / ha - 1e-9))
            k = np.arange(-g, n + g)
            axes.append(region.center[a] - 0.5 * ext[a] + ha * (k + 0.5))
            half[a] = 0.5 * ha
        else:
            g = int(math.ceil(grow / h - 1e-9))
            axes.append(region.center[a] + h * np.arange(-g, g + 1))
    count = int(np.prod([len(x) for x in axes]))
    return axes, count, half


def region_samples(region: Region, orientations: OrientationSet = OrientationSet(),
                   settings: TaskSettings = TaskSettings()) -> int:
    """Lattice points of the region's box with its margin shell times orientation samples: the size
    of the work (an upper bound; checked against :data:`MAX_POINTS` before anything runs)."""
    _, count, _ = _lattice(region, settings.voxel, settings.margin_range)
    return count * int(orientations.rotations().shape[0])


def region_lattice(region: Region, orientations: OrientationSet, settings: TaskSettings
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """A region task's samples: ``(rotations, half cell, points, sdf, inside, tol)``, the lattice
    points within ``margin_range`` of the region (with their signed distance), those in it, and the
    distance tolerance of both tests; refused past
    :data:`MAX_POINTS` samples (lattice points x orientations)."""
    rots = orientations.rotations()
    axes, count, half = _lattice(region, settings.voxel, settings.margin_range)
    if count * rots.shape[0] > MAX_POINTS:
        raise ParameterError("task", f"{count:,} lattice points x {rots.shape[0]} orientations",
                             f"at most {MAX_POINTS:,} samples (a coarser voxel, a smaller region or margin_range, "
                             "or a larger angle_step)")
    gx, gy, gz = np.meshgrid(*axes, indexing="ij")
    pts = np.stack([gx.ravel(), gy.ravel(), gz.ravel()], axis=1)
    sdf = region.sdf(pts)
    tol = 1e-9 * max(1.0, float(np.abs(pts).max()))
    keep = sdf <= settings.margin_range + tol
    pts, sdf = pts[keep], sdf[keep]
    return rots, half, pts, sdf, sdf <= tol, tol


def region_task(design: Design, region: Region, orientations: OrientationSet = OrientationSet(),
                settings: TaskSettings = TaskSettings(), progress: ProgressFn | None = None,
                cancel: CancelToken = None, certify: bool = True) -> TaskResult:
    """The answers of the module docstring for a region with an orientation set (``certify=False``:
    ``certified`` is ``"undecided"`` without running the certification, for studies)."""
    rep = Reporter(progress)
    t0 = time.perf_counter()
    rots, half, pts, sdf, inside, tol = region_lattice(region, orientations, settings)
    delta = float(np.linalg.norm(half))
    ok, failed_at = _reach_points(design, pts, rots, settings, rep.sub(0.0, 0.8), cancel)
    n_in = int(inside.sum())
    n_ok = int((ok & inside).sum())
    fraction = n_ok / n_in
    contained = n_ok == n_in
    bad = np.flatnonzero(~ok)
    saturated = bad.size == 0
    if saturated:
        margin = settings.margin_range
        qi = None
    else:
        qi = int(bad[np.argmin(sdf[bad])])
        margin = float(sdf[qi])
    # certification
    check(cancel)
    outside: dict[str, Any] | None = None
    reach_xy = float(np.hypot(np.abs(pts[:, 0]).max(), np.abs(pts[:, 1]).max())) + delta
    cert = _Certifier(design, rots, settings.joints, settings.eta_step, reach_xy)
    alpha = cover_angle(orientations)
    if not certify:
        certified = "undecided"
    elif not contained:
        # the deepest unreachable sample points first, at the orientation each failed first
        cand = np.flatnonzero(inside & ~ok)
        cand = cand[np.argsort(sdf[cand], kind="stable")]
        head = cand[:64]
        mids = np.array([_first_failure(design, pts[c], rots, int(failed_at[c]), settings) for c in head], np.int64)
        proven = cert.proven_outside(pts[head], mids)
        hit = (int(head[np.argmax(proven)]), int(mids[np.argmax(proven)])) if proven.any() else None
        if hit is None and cand.size > 64:  # every orientation of the rest
            rest = cand[64:]
            pi, mi = (a.ravel() for a in np.meshgrid(np.arange(rest.size), np.arange(rots.shape[0]), indexing="ij"))
            res = cert.run(pts[rest], np.full(rest.size, 1e300), np.ones(rest.size, bool), pi, mi) == 2
            if res.any():
                hit = (int(rest[pi[np.argmax(res)]]), int(mi[np.argmax(res)]))
        certified = "not contained" if hit is not None else "undecided"
        if hit is not None:
            outside = {"position": pts[hit[0]].tolist(), "orientation": _rot_of(orientations, hit[1], rots)}
    elif settings.joints.min_distance > 0.0:
        certified = "undecided"
    else:
        cover = np.flatnonzero(sdf <= delta + tol)
        e = delta + design.a * alpha + (alpha * design.l_max if settings.joints.theta_s is not None else 0.0)
        certified = "contained"
        for s in range(0, rots.shape[0], BATCH):
            check(cancel)
            m = np.arange(s, min(s + BATCH, rots.shape[0]))
            gp, gm = np.meshgrid(np.arange(cover.size), m, indexing="ij")
            res = cert.run(pts[cover], np.full(cover.size, e), np.zeros(cover.size, bool), gp.ravel(), gm.ravel())
            if not np.all(res == 1):
                certified = "undecided"
                break
    rep(0.9, "task: the binding limit")
    # worst pose and binding limit
    if qi is None:
        sample = int(np.flatnonzero(inside)[np.argmax(np.abs(pts[inside] - np.asarray(region.center)).sum(axis=1))])
        worst = {"position": pts[sample].tolist(), "orientation": _rot_of(orientations, 0, rots), "reachable": True}
        binding = {"chain": None, "leg": None, "limit": None, "stroke_end": None,
                   "message": f"no unreachable point within margin_range = {settings.margin_range:g}"}
        m_worst = 0
    else:
        m_q = _first_failure(design, pts[qi], rots, int(failed_at[qi]), settings)
        ins = np.flatnonzero(inside)
        sample = qi if inside[qi] else int(ins[np.argmin(np.linalg.norm(pts[ins] - pts[qi], axis=1))])
        m_worst = m_q if sample == qi else 0
        worst = {"position": pts[sample].tolist(), "orientation": _rot_of(orientations, m_worst, rots),
                 "reachable": bool(ok[sample]),
                 "at": {"position": pts[qi].tolist(), "orientation": _rot_of(orientations, m_q, rots)}}
        binding = pose_binding(design, pts[qi], rots[m_q], settings.joints, settings.eta_step)
    slack = _resolved_slack(design, pts[sample], rots[m_worst], settings.joints, settings.eta_step)
    details = {"region": region.to_dict(), "orientations": orientations.to_dict(), "design": design.to_dict(),
               "joints": settings.joints.to_dict(), "voxel": settings.voxel, "margin_range": settings.margin_range,
               "margin_saturated": bool(saturated), "sample_points": n_in, "reachable_points": n_ok,
               "lattice_points": int(pts.shape[0]), "orientation_samples": int(rots.shape[0]),
               "volume": region.volume, "cell_half_diagonal": delta, "cover_angle": math.degrees(alpha),
               "outside_pose": outside}
    rep(1.0, "task done")
    return TaskResult(kind="region", fraction=fraction, contained=contained, certified=certified, margin=margin,
                      worst=worst, binding=binding, slack=slack, details=details, seconds=time.perf_counter() - t0,
                      cells=pts[inside], cells_ok=ok[inside])


def _resolved_slack(design: Design, position: np.ndarray, rot: np.ndarray, joints: Joints,
                    eta_step: float) -> dict[str, Any]:
    """Slacks at the redundancy resolution's carriage pose (:func:`resolve_redundancy`)."""
    from .rotation import euler_zyx_from_matrix

    psi, theta, phi = euler_zyx_from_matrix(rot)
    x, y, z = (float(v) for v in position)
    res = resolve_redundancy(design, Pose(x, y, z, psi, theta, phi), joints, eta_step)
    return _slacks(design, joints, np.asarray(position, float), rot, res.d, res.eta)


# --------------------------------------------------------------------------------------------
# pose lists: continuous carriage motion


class _ChainGrid:
    """Margin grids of one chain over (arc samples, rail values) (module docstring)."""

    def __init__(self, design: Design, chain: int, eta_step: float, joints: Joints) -> None:
        tab = ChainTables(design, default_n_eta(design, eta_step))
        self.design, self.chain, self.joints = design, chain, joints
        self.eta = tab.eta_deg
        lo, hi = design.rho_limits
        self.rho = np.linspace(lo, hi, N_RHO) if hi > lo else np.array([lo])
        self.r_d = math.hypot(design.r, 0.5 * design.b)

    def margins(self, B: np.ndarray, rot: np.ndarray, eta: np.ndarray, rho: np.ndarray) -> np.ndarray:
        design, i = self.design, self.chain
        varpi = GAMMA[i] + np.radians(eta)
        m = _chain_margins(design, B, varpi, rho)
        if self.joints.has_cones:
            jc = cone_table(design, self.joints, rot)[i]
            c, s = np.cos(varpi)[:, None], np.sin(varpi)[:, None]
            for j in range(2):
                lat = LEG_SIGN[j] * design.b / 2.0
                dx = c * rho[None, :] - s * lat
                dy = s * rho[None, :] + c * lat
                vx, vy, vz = B[j, 0] - dx, B[j, 1] - dy, np.full_like(dx, B[j, 2])
                norm = np.sqrt(vx * vx + vy * vy + vz * vz)
                if jc[j, 6] > -1.0:
                    ax = jc[j, 0] * c - jc[j, 1] * s
                    ay = jc[j, 0] * s + jc[j, 1] * c
                    m = np.minimum(m, ax * vx + ay * vy + jc[j, 2] * vz - jc[j, 6] * norm)
                if jc[j, 7] > -1.0:
                    m = np.minimum(m, jc[j, 3] * vx + jc[j, 4] * vy + jc[j, 5] * vz - jc[j, 7] * norm)
        return m

    def dist2(self, eta0: float, rho0: float) -> np.ndarray:
        de = np.radians(self.eta - eta0)[:, None] * self.r_d
        dr = (self.rho - rho0)[None, :]
        return de * de + dr * dr

    def cell(self, eta0: float, rho0: float) -> tuple[int, int]:
        return int(np.argmin(np.abs(self.eta - eta0))), int(np.argmin(np.abs(self.rho - rho0)))


def pose_list_task(design: Design, poses: PoseList, settings: TaskSettings = TaskSettings(),
                   progress: ProgressFn | None = None, cancel: CancelToken = None) -> TaskResult:
    """The answers of the module docstring for a pose list, with the continuous carriage motion."""
    rep = Reporter(progress)
    t0 = time.perf_counter()
    joints = settings.joints
    n = len(poses)
    P = poses.poses
    rots = np.stack([euler_zyx_deg(*row[3:]) for row in P])
    reach = poses_reachable(design, P[:, :3], rots, settings.eta_step, joints)
    rep(0.2, "task: reachability")
    grids = [_ChainGrid(design, i, settings.eta_step, joints) for i in range(3)]
    d = np.zeros((n, 3))
    eta = np.zeros((n, 3))
    jumps: list[dict[str, Any]] = []
    prev: list[tuple[float, float, np.ndarray, np.ndarray] | None] = [None, None, None]
    pts_local = platform_points_local(design)
    for k in range(n):
        if k % 64 == 0:
            check(cancel)
            rep(0.2 + 0.7 * k / n, f"task: carriage motion, pose {k + 1:,} of {n:,}")
        B_all = P[k, :3] + pts_local @ rots[k].T
        for i in range(3):
            g = grids[i]
            B = B_all[i]
            M = g.margins(B, rots[k], g.eta, g.rho)
            F = M >= 0.0
            best = np.unravel_index(int(np.argmax(M)), M.shape)
            choice = (float(g.eta[best[0]]), float(g.rho[best[1]]))
            jump = None
            if reach[k] and not F.any():  # a feasible set thinner than a grid cell: the engine's pose
                found = _engine_carriage(design, B, i, joints, rots[k], settings.eta_step)
                if found is not None:
                    choice = (found[1], design.r - found[0])
                prev[i] = None
            elif reach[k] and prev[i] is not None:
                e0, r0, F0, L0 = prev[i]  # type: ignore[misc]
                mu = min(settings.carriage_margin, 0.5 * float(M.max()))
                m_here = float(g.margins(B, rots[k], np.array([e0]), np.array([r0]))[0, 0])
                if m_here >= mu:
                    choice = (e0, r0)
                else:
                    L1, _ = ndi.label(F)
                    c0 = g.cell(e0, r0)
                    lab0 = L0[c0]
                    if lab0 == 0 and F0.any():  # the exact pose sits between cells: its nearest feasible cell
                        dd = np.where(F0, g.dist2(e0, r0), np.inf)
                        lab0 = L0[np.unravel_index(int(np.argmin(dd)), dd.shape)]
                    comp = (L0 == lab0) & F
                    labels = np.unique(L1[comp])
                    linked = np.isin(L1, labels[labels > 0])
                    cand = linked & (M >= mu)
                    if not cand.any():
                        cand = linked
                    if not cand.any():
                        cand = M >= mu
                        jump = True
                    dd = np.where(cand, g.dist2(e0, r0), np.inf)
                    tgt = np.unravel_index(int(np.argmin(dd)), dd.shape)
                    target = (float(g.eta[tgt[0]]), float(g.rho[tgt[1]]))
                    if jump:
                        choice = target
                    else:  # the first point of the straight move with the margin
                        ss = np.linspace(0.0, 1.0, 17)[1:]
                        ee = e0 + ss * (target[0] - e0)
                        rr = r0 + ss * (target[1] - r0)
                        mm = np.array([g.margins(B, rots[k], ee[q:q + 1], rr[q:q + 1])[0, 0] for q in range(ss.size)])
                        q = int(np.argmax(mm >= min(mu, M[tgt]) - 1e-12))
                        choice = (float(ee[q]), float(rr[q]))
                    if jump:
                        jumps.append({"index": k, "chain": i + 1,
                                      "jump_d": abs((design.r - choice[1]) - (design.r - r0)),
                                      "jump_eta": abs(choice[0] - e0)})
            eta[k, i], d[k, i] = choice[0], design.r - choice[1]
            if reach[k] and F.any():
                L, _ = ndi.label(F)
                prev[i] = (choice[0], choice[1], F, L)
            elif not reach[k]:
                prev[i] = None
    rep(0.92, "task: actuator values")
    # actuator values and slacks
    qv = np.zeros((n, 12))
    rows: list[dict[str, Any]] = []
    slacks = []
    for k in range(n):
        b = P[k, :3] + pts_local @ rots[k].T
        dp = base_points(design, d[k], eta[k])
        lengths = np.linalg.norm(b - dp, axis=-1)
        qv[k] = np.concatenate([lengths.reshape(6), d[k], eta[k]])
        sl = _slacks(design, joints, P[k, :3], rots[k], d[k], eta[k])
        slacks.append(sl)
        rows.append({"index": k, "reachable": bool(reach[k]), "q": [float(v) for v in qv[k]],
                     "leg_slack": sl["leg"], **({"t": float(poses.t[k])} if poses.t is not None else {})})
    leg = np.array([s["leg"] for s in slacks])
    order = np.where(reach, leg, leg - 1e12)  # an unreachable pose first
    w = int(np.argmin(order))
    fraction = float(reach.mean())
    contained = bool(reach.all())
    outside_index = None
    if contained:
        certified = "contained"
    else:
        cert = _Certifier(design, rots, joints, settings.eta_step,
                          float(np.hypot(np.abs(P[:, 0]).max(), np.abs(P[:, 1]).max())))
        bad = np.flatnonzero(~reach)
        proven = cert.proven_outside(P[bad, :3], bad)
        certified = "not contained" if proven.any() else "undecided"
        outside_index = int(bad[np.argmax(proven)]) if proven.any() else None
    if reach[w]:
        sl = slacks[w]
        i, j = sl["leg_at"]
        binding = {"chain": i, "leg": j, "limit": sl["leg_limit"], "stroke_end": _stroke_end(design, d[w, i - 1],
                                                                                                 eta[w, i - 1]),
                   "message": f"chain {i}, leg {j} nearest {sl['leg_limit']} (slack {sl['leg']:.3g})"}
    else:
        binding = pose_binding(design, P[w, :3], rots[w], joints, settings.eta_step)
    names = [f"l_{i + 1}^{j + 1}" for i in range(3) for j in range(2)] + [f"d_{i + 1}" for i in range(3)] + \
        [f"eta_{i + 1}" for i in range(3)]
    lo_eta, hi_eta = design.eta_limits
    strokes = [(design.l_min, design.l_max)] * 6 + [(0.0, design.d_s)] * 3 + [(lo_eta, hi_eta)] * 3
    used = qv[reach] if reach.any() else qv
    actuators = []
    for a, name in enumerate(names):
        lo, hi = strokes[a]
        span = hi - lo
        u_lo, u_hi = float(used[:, a].min()), float(used[:, a].max())
        actuators.append({"name": name, "min": u_lo, "max": u_hi, "stroke": [lo, hi],
                          "used_fraction": (u_hi - u_lo) / span if span > 0 else 0.0})
    dd = np.abs(np.diff(d, axis=0))
    de = np.abs(np.diff(eta, axis=0))
    both = (reach[1:] & reach[:-1])[:, None]
    carriage: dict[str, Any] = {"travel_d": float((dd * both).sum()), "travel_eta": float((de * both).sum()),
                                "travel_d_per_chain": (dd * both).sum(axis=0).tolist(),
                                "travel_eta_per_chain": (de * both).sum(axis=0).tolist()}
    if poses.t is not None and n > 1:
        dt = np.diff(poses.t)[:, None]
        carriage["max_speed_d"] = float(((dd / dt) * both).max())
        carriage["max_speed_eta"] = float(((de / dt) * both).max())
    smin: dict[str, Any] = {}
    for key in ("leg", "d", "eta", "u_cone", "s_cone"):
        vals = [(s[key], k) for k, s in enumerate(slacks) if s[key] is not None and reach[k]]
        if vals:
            v, k = min(vals)
            smin[key] = {"value": v, "index": k}
    worst = {"index": w, "pose": P[w].tolist(), "reachable": bool(reach[w])}
    details = {"design": design.to_dict(), "joints": joints.to_dict(), "count": n,
               "unreachable": np.flatnonzero(~reach).tolist(), "carriage": carriage, "actuators": actuators,
               "actuator_names": names, "outside_index": outside_index}
    rep(1.0, "task done")
    return TaskResult(kind="poses", fraction=fraction, contained=contained, certified=certified,
                      margin=float(leg[w]), worst=worst, binding=binding, slack=smin, details=details,
                      seconds=time.perf_counter() - t0, poses=rows, discontinuities=jumps)


def evaluate_task(design: Design, task: Region | PoseList, orientations: OrientationSet = OrientationSet(),
                  settings: TaskSettings = TaskSettings(), progress: ProgressFn | None = None,
                  cancel: CancelToken = None) -> TaskResult:
    """:func:`region_task` or :func:`pose_list_task`, by the task's kind."""
    if isinstance(task, PoseList):
        return pose_list_task(design, task, settings, progress, cancel)
    return region_task(design, task, orientations, settings, progress, cancel)


@dataclasses.dataclass(frozen=True)
class TaskSpec:
    """A task as the studies and the optimiser take it: the task, its orientation set and sampling.
    :meth:`measures` gives the measures ``task_fraction``, ``task_margin`` and ``contains_task``
    (``fraction``, ``margin`` and ``contained`` of :func:`evaluate_task`, without certification)."""

    task: Region | PoseList
    orientations: OrientationSet = OrientationSet()
    settings: TaskSettings = TaskSettings()

    def __post_init__(self) -> None:
        if not isinstance(self.task, (Region, PoseList)):
            raise ParameterError("task", type(self.task).__name__, "a Region or a PoseList")

    def measures(self, design: Design, cancel: CancelToken = None) -> dict[str, Any]:
        if isinstance(self.task, PoseList):
            res = pose_list_task(design, self.task, self.settings, cancel=cancel)
        else:
            res = region_task(design, self.task, self.orientations, self.settings, cancel=cancel, certify=False)
        return {"task_fraction": res.fraction, "task_margin": res.margin, "contains_task": res.contained,
                "task_binding": res.binding.get("limit")}

    def to_dict(self) -> dict[str, Any]:
        task = (self.task.to_dict() if isinstance(self.task, Region) else
                {"poses": self.task.poses.tolist(), "t": None if self.task.t is None else self.task.t.tolist()})
        return {"task": task, "orientations": self.orientations.to_dict(),
                "settings": {**{k: getattr(self.settings, k) for k in ("voxel", "eta_step", "margin_range",
                                                                         "carriage_margin")},
                             "joints": self.settings.joints.to_dict()}}

