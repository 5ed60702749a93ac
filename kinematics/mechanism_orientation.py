"""Orientation scans, TI_1 / TI_2 and the total-orientation workspace of any
:class:`~kinematics.mechanism.Mechanism` (the paper's Sec. III and :mod:`kinematics.dexterous` for a
description).

**Symmetry order.** With ``S_n = Rz(360/n)`` (about the base z axis through the base origin), the
description is ``n``-fold symmetric when conjugating by ``S_n`` maps it onto itself

    S_n T_c(q) S_n^T = T_c'(q),  S_n D0_j = D0_j',  S_n u_j = u_j'                        (S1)

for a permutation of its chains ``c -> c'`` and of each chain's legs ``j -> j'`` (every joint axis
and cone axis turned by ``S_n``, joint types, ranges, leg lengths and diameters equal; by (M1)
``S T_m(q) S^T`` is the joint of axis ``S axis_m``). Then ``(P, R)`` is reachable iff
``(S P, S R S^T)`` is. The order is the largest ``n`` in ``6, 5, 4, 3, 2`` for which (S1) holds
(tolerance ``1e-9`` of the description's size), else 1 (:func:`symmetry_order`).

**Lines and rotations (the rule).** The scan lines pass through the symmetry axis as the paper's:

    "z":        P = (0, 0, s),                     s in [z_min, z_max]
    "y_prime":  P = (s cos b, s sin b, z0),        s in [-s_max, s_max],   b = 180 / max(n, 2)   (S2)
    "x":        P = (s, 0, z0),                    s in [-s_max, s_max]

and the three rotations are about ``z``, about ``e(b) = (cos b, sin b, 0)`` and about ``x``, through
the platform origin (``R = Rot(reference) Rot(axis, alpha)``; the axes are the reference frame's,
the base axes for a zero reference). ``b`` is the direction midway between the x axis and its image
under ``S_n``: for the 3-fold presets (``paper``, ``gough-stewart``, ``6-pups``, ``6-pss``) ``b = 60``,
the paper's ``y'``; a 4-fold mechanism gets ``b = 45``, a 6-fold one ``b = 30``; a mechanism with no
axis of order 3 or more (``n`` = 1 or 2) gets ``b = 90``: the base axes z, y, x. The result keeps the
paper's keys (``"y_prime"``, ``"tau_yprime"``) for the second line and rotation and states ``b``.

**Ranges.** ``z_min``, ``z0``, the steps and an explicit ``z_max`` / ``s_max`` (then ``[-s_max, s_max]``)
are the settings'. By default the ranges are rigorous covers of the engine's feasible set at every
rotation: the engine keeps leg ``j``'s base joint within its whole-chain ball ``(c_j, rho_j)``
(:mod:`kinematics.mechanism_workspace`), and ``|B_j - P| = |u_j|``, so ``|P - c_j| <= L_j = lmax_j +
rho_j + |u_j|`` for every leg. On a line ``P = o + s e`` (``o = 0`` for the z line, ``(0, 0, z0)`` for
the others) that is ``s`` in ``[e.(c_j - o) -+ sqrt(disc_j)]`` with ``disc_j = (e.(c_j - o))^2 -
|c_j - o|^2 + L_j^2``, and the range is the intersection over the legs

    s_lo = max_j (e.(c_j - o) - sqrt(disc_j)),   s_hi = min_j (e.(c_j - o) + sqrt(disc_j))     (S3)

(the z line keeps ``s_lo = z_min``; an empty intersection scans the single sample ``s = 0``).

**Samples, regions and indices** are those of :mod:`kinematics.orientation` (lattices through 0,
(D1)-(D3), eq. (28) by :func:`~kinematics.orientation.tilt_indices`): a sample ``(s_k, alpha_m)`` is
feasible when :func:`kinematics.mechanism_workspace.reachable_general` accepts the pose (exact in
one prismatic joint per chain, revolute joints every ``eta_step``, a second prismatic joint every
``length_step``). The paper's mechanism (:func:`~kinematics.mechanism_workspace.paper_design`) is
routed to :func:`kinematics.orientation.orientation_workspace`: the paper path's result exactly.

**Total orientation.** As :mod:`kinematics.dexterous` defines it: the voxels of the zero-orientation
workspace (:func:`~kinematics.mechanism_workspace.compute_mechanism_workspace`) whose centre is
reachable at EVERY orientation of the sample set ``S(tilt, torsion, step)`` of
:func:`kinematics.dexterous.orientation_samples` (T&T angles about the reference), i.e. the
intersection over ``S`` of the general engine's constant-orientation workspaces on one grid. The
paper's mechanism is routed to :func:`kinematics.dexterous.total_orientation_workspace`.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
from numba import njit, prange

from .design import ParameterError
from .dexterous import BATCH, DexterousResult, orientation_samples
from .dexterous import total_orientation_workspace as paper_total_orientation
from .joints import Joints
from .mechanism import Chain, Leg, Mechanism
from .mechanism_workspace import (
    KernelTables,
    MechanismWorkspaceResult,
    _chain_ok,
    _check_general,
    check_length_step,
    compute_mechanism_workspace,
    kernel_tables,
    paper_design,
    platform_rotation,
)
from .orientation import (
    LINE_SYMBOL,
    LINES,
    MAX_SAMPLES,
    ROTATION_SYMBOL,
    ROTATIONS,
    OrientationRegion,
    OrientationResult,
    OrientationSettings,
    _lattice,
    angle_samples,
    make_region,
    orientation_workspace,
    tilt_indices,
)
from .parallel import KERNEL_LOCK
from .progress import CancelToken, ProgressFn, Reporter, check
from .rotation import axis_angle
from .tilt_torsion import tt_rotations
from .workspace import WorkspaceSettings

#: Symmetry orders tried, largest first (S1).
ORDERS: tuple[int, ...] = (6, 5, 4, 3, 2)
_SYM_TOL = 1e-9
#: The scan of :class:`~kinematics.orientation.OrientationSettings`' defaults.
DEFAULT_SCAN = OrientationSettings()


# --------------------------------------------------------------------------------------------
# symmetry (S1) and the lines (S2)


def _rot_vec(rz: np.ndarray, v: tuple[float, float, float]) -> np.ndarray:
    return rz @ np.asarray(v, float)


def _leg_key(leg: Leg, rz: np.ndarray | None) -> np.ndarray:
    """A leg as numbers (turned by ``rz`` when given): base, platform, length, cones, diameter."""
    turn = (lambda v: _rot_vec(rz, v)) if rz is not None else (lambda v: np.asarray(v, float))
    parts = [turn(leg.base), turn(leg.platform), np.asarray(leg.length, float), [leg.diameter]]
    for cone in (leg.u_cone, leg.s_cone):
        parts.append([0.0] * 4 if cone is None else [*turn(cone.axis), cone.angle])
    parts.append([leg.u_cone is None, leg.s_cone is None])
    return np.concatenate([np.asarray(p, float).ravel() for p in parts])


def _chain_matches(a: Chain, b: Chain, rz: np.ndarray, tol: float) -> bool:
    """(S1) for one pair: ``b`` is ``a`` conjugated by ``rz`` (its legs in any order)."""
    if len(a.carriage) != len(b.carriage) or len(a.legs) != len(b.legs):
        return False
    for ja, jb in zip(a.carriage, b.carriage):
        if ja.type != jb.type or np.abs(np.subtract(ja.range, jb.range)).max() > tol:
            return False
        if np.abs(_rot_vec(rz, ja.axis) - np.asarray(jb.axis)).max() > tol:
            return False
    left = [_leg_key(leg, None) for leg in b.legs]
    for leg in a.legs:
        key = _leg_key(leg, rz)
        hit = next((i for i, k in enumerate(left) if np.abs(k - key).max() <= tol), None)
        if hit is None:
            return False
        left.pop(hit)
    return True


def is_symmetric(mech: Mechanism, n: int) -> bool:
    """Whether ``Rz(360/n)`` maps the description onto itself (S1)."""
    a = 2.0 * math.pi / n
    rz = np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]])
    scale = 1.0 + max(max(abs(x) for x in (*leg.base, *leg.platform, *leg.length)) for _, _, leg in mech.legs)
    tol = _SYM_TOL * scale
    left = list(mech.chains)
    for chain in mech.chains:
        hit = next((i for i, other in enumerate(left) if _chain_matches(chain, other, rz, tol)), None)
        if hit is None:
            return False
        left.pop(hit)
    return True


def symmetry_order(mech: Mechanism) -> int:
    """The largest ``n`` of :data:`ORDERS` with (S1), else 1."""
    return next((n for n in ORDERS if is_symmetric(mech, n)), 1)


def line_azimuth(order: int) -> float:
    """``b`` of (S2), degrees: the second line's direction and rotation axis."""
    return 180.0 / max(order, 2)


def line_direction(line: str, azimuth: float) -> np.ndarray | None:
    """Unit direction of a horizontal line of (S2) (``None`` for the z line)."""
    if line == "z":
        return None
    b = math.radians(azimuth) if line == "y_prime" else 0.0
    return np.array([math.cos(b), math.sin(b), 0.0])


def rotation_axis(rotation: str, azimuth: float) -> np.ndarray:
    """The axis of a rotation of (S2) in the reference frame."""
    if rotation == "phi_z":
        return np.array([0.0, 0.0, 1.0])
    if rotation == "psi_x":
        return np.array([1.0, 0.0, 0.0])
    b = math.radians(azimuth)
    return np.array([math.cos(b), math.sin(b), 0.0])


def scan_points(line: str, positions: np.ndarray, z0: float, azimuth: float) -> np.ndarray:
    """Platform positions ``(N, 3)`` of the samples ``positions`` along ``line`` (S2)."""
    s = np.asarray(positions, float).reshape(-1)
    e = line_direction(line, azimuth)
    if e is None:
        pts = np.zeros((s.size, 3))
        pts[:, 2] = s
        return pts
    pts = s[:, None] * e[None, :]
    pts[:, 2] = z0
    return pts


def scan_range(tables: KernelTables, plat0: np.ndarray, line: str, settings: OrientationSettings,
               azimuth: float) -> tuple[float, float]:
    """``[s_lo, s_hi]`` of a line: the settings' explicit bounds, else the covers (S3)."""
    if line == "z" and settings.z_max is not None:
        return settings.z_min, settings.z_max
    if line != "z" and settings.s_max is not None:
        return -settings.s_max, settings.s_max
    reach = np.sqrt(tables.out2) + np.linalg.norm(plat0, axis=1)  # L_j (out2 holds lmax_j + rho_j + eps)
    e = line_direction(line, azimuth)
    o = np.zeros(3) if e is None else np.array([0.0, 0.0, settings.z0])
    e = np.array([0.0, 0.0, 1.0]) if e is None else e
    rel = tables.centre - o
    proj = rel @ e
    disc = proj ** 2 - np.einsum("jc,jc->j", rel, rel) + reach ** 2
    if np.any(disc < 0.0):
        return (settings.z_min, settings.z_min) if line == "z" else (0.0, 0.0)
    lo = float(np.max(proj - np.sqrt(disc)))
    hi = float(np.min(proj + np.sqrt(disc)))
    if line == "z":
        return settings.z_min, max(settings.z_min, hi)
    return (lo, hi) if lo <= hi else (0.0, 0.0)

# --------------------------------------------------------------------------------------------
# the scans


def _listed(v: np.ndarray | None) -> list[float] | None:
    """A direction as a JSON list (``None`` for the z line, which has no horizontal direction)."""
    return None if v is None else [float(x) for x in v]


@dataclasses.dataclass
class MechanismOrientationResult(OrientationResult):
    """An :class:`~kinematics.orientation.OrientationResult` of a description: ``order`` (S1),
    ``azimuth`` ``b`` of (S2), the engine (``"paper"`` when routed) and the mechanism."""

    mechanism: Mechanism | None = None
    engine: str = "general"
    order: int = 1
    azimuth: float = 60.0
    length_step: float = 1.0

    def to_dict(self, include_grids: bool = False) -> dict:
        out = super().to_dict(include_grids)
        out["engine"] = self.engine
        out["symmetry_order"] = self.order
        out["lines"] = {ln: {"symbol": LINE_SYMBOL[ln],
                             "direction": _listed(line_direction(ln, self.azimuth))}
                        for ln in LINES}
        out["rotation_axes"] = {rt: [float(v) for v in rotation_axis(rt, self.azimuth)] for rt in ROTATIONS}
        out["second_line_azimuth"] = float(self.azimuth)
        out["mechanism"] = None if self.mechanism is None else self.mechanism.to_dict()
        return out


@njit(parallel=True, cache=True, nogil=True)
def _scan_kernel(points, plats, s_axes, k0, nk, l0, nl, s_lo, s_hi, w, base, u_axis, k_u, k_s, lmin2, lmax2,
                 centre, out2, in2, kb0, blk_centre, blk_out2, blk_in2, out):
    """``out[p, m]``: the general engine's test (:func:`kinematics.mechanism_workspace._chain_ok` for
    every chain) at position ``points[p]`` and rotation ``m`` (``plats[m]`` = ``R u_j``, ``s_axes[m]``
    the S-cone axes). One rotation per thread, its line walked with a warm start per chain (the
    answer does not depend on the start: every block of samples is searched unless its bound rejects)."""
    n_chains = k0.shape[0]
    for m in prange(plats.shape[0]):
        gap_lo = np.empty(8)
        gap_hi = np.empty(8)
        start = np.empty(n_chains, np.int64)
        for c in range(n_chains):
            start[c] = nk[c] // 2
        plat = plats[m]
        s_axis = s_axes[m]
        first = 0
        for p in range(points.shape[0]):
            ok = True
            for cc in range(n_chains):
                c = (first + cc) % n_chains
                if not _chain_ok(points[p, 0], points[p, 1], points[p, 2], c, start, k0, nk, l0, nl, s_lo, s_hi, w,
                                 base, u_axis, k_u, plat, s_axis, k_s, lmin2, lmax2, centre, out2, in2, kb0,
                                 blk_centre, blk_out2, blk_in2, gap_lo, gap_hi, 0.0):
                    ok = False
                    first = c
                    break
            out[p, m] = ok


def reachable_rotations(tables: KernelTables, plat0: np.ndarray, s_axis0: np.ndarray, rots: np.ndarray,
                        pts: np.ndarray) -> np.ndarray:
    """``(N, M)``: the general engine's test at every position ``pts[p]`` and rotation ``rots[m]`` in
    one launch (the answers of :func:`~kinematics.mechanism_workspace.reachable_general` per rotation;
    tested)."""
    rots = np.asarray(rots, float).reshape(-1, 3, 3)
    pts = np.ascontiguousarray(np.asarray(pts, float).reshape(-1, 3))
    out = np.zeros((len(pts), len(rots)), np.bool_)
    if len(pts) and len(rots):
        plats = np.ascontiguousarray(np.einsum("jc,mdc->mjd", plat0, rots))
        s_axes = np.ascontiguousarray(np.einsum("jc,mdc->mjd", s_axis0, rots))
        t = tables
        with KERNEL_LOCK:
            _scan_kernel(pts, plats, s_axes, t.k0, t.nk, t.l0, t.nl, t.s_lo, t.s_hi, t.w, t.base, t.u_axis, t.k_u,
                         t.k_s, t.lmin2, t.lmax2, t.centre, t.out2, t.in2, t.kb0, t.blk_centre, t.blk_out2,
                         t.blk_in2, out)
    return out


def _unrotated(mech: Mechanism, eta_step: float, length_step: float) -> tuple[KernelTables, np.ndarray, np.ndarray]:
    """Tables at the identity and the platform points / S-cone axes before any rotation."""
    tables = kernel_tables(mech, np.eye(3), eta_step, length_step)
    plat0 = np.array([leg.platform for _, _, leg in mech.legs], float)
    s_axis0 = np.array([(0.0, 0.0, 0.0) if leg.s_cone is None else leg.s_cone.axis for _, _, leg in mech.legs])
    return tables, plat0, s_axis0


def _check_mechanism(mech: Mechanism, joints: Joints) -> None:
    if joints != Joints():
        raise ParameterError("joints", joints.to_dict(),
                             "none for a mechanism description: its legs carry their own u_cone/s_cone")
    _check_general(mech, WorkspaceSettings())


def mechanism_orientation_workspace(mech: Mechanism, settings: OrientationSettings = DEFAULT_SCAN,
                                    length_step: float = 1.0, progress: ProgressFn | None = None,
                                    cancel: CancelToken = None) -> MechanismOrientationResult:
    """The nine regions (3 lines x 3 rotations of (S2)) and TI_1, TI_2 of eq. (28) for ``mech``
    (module docstring); the paper's mechanism runs the paper path
    (:func:`kinematics.orientation.orientation_workspace`, its result exactly)."""
    length_step = check_length_step(length_step)
    design = paper_design(mech)
    if design is None:
        return general_orientation_workspace(mech, settings, length_step, progress, cancel)
    res = orientation_workspace(design, settings, progress, cancel)
    fields = {f.name: getattr(res, f.name) for f in dataclasses.fields(OrientationResult)}
    order = symmetry_order(mech)
    return MechanismOrientationResult(**fields, mechanism=mech, engine="paper", order=order,
                                      azimuth=line_azimuth(order), length_step=length_step)


def scan_plan(mech: Mechanism, settings: OrientationSettings = DEFAULT_SCAN,
              length_step: float = 1.0) -> tuple[int, tuple[int, ...]]:
    """The general scan's size before running (for limits): the (position, angle) samples of the
    nine maps and each chain's number of carriage samples."""
    _check_mechanism(mech, settings.joints)
    tables, plat0, _ = _unrotated(mech, settings.eta_step, check_length_step(length_step))
    azimuth = line_azimuth(symmetry_order(mech))
    n_pos = sum(_lattice(*scan_range(tables, plat0, ln, settings, azimuth), settings.position_step).size
                for ln in LINES)
    return n_pos * angle_samples(settings).size * len(ROTATIONS), tuple(len(t.q) for t in tables.chains)


def general_orientation_workspace(mech: Mechanism, settings: OrientationSettings = DEFAULT_SCAN,
                                  length_step: float = 1.0, progress: ProgressFn | None = None,
                                  cancel: CancelToken = None) -> MechanismOrientationResult:
    """The scans of :func:`mechanism_orientation_workspace` by the general engine (never routed)."""
    length_step = check_length_step(length_step)
    _check_mechanism(mech, settings.joints)
    order = symmetry_order(mech)
    azimuth = line_azimuth(order)
    rep = Reporter(progress)
    t0 = time.perf_counter()
    tables, plat0, s_axis0 = _unrotated(mech, settings.eta_step, length_step)
    ang = angle_samples(settings)
    ranges = {ln: scan_range(tables, plat0, ln, settings, azimuth) for ln in LINES}
    positions = {ln: _lattice(*ranges[ln], settings.position_step) for ln in LINES}
    for ln in LINES:
        if positions[ln].size * ang.size > MAX_SAMPLES:
            raise ParameterError("position_step", settings.position_step,
                                 f"coarser: {positions[ln].size} x {ang.size} samples on the {ln} line exceed "
                                 f"{MAX_SAMPLES}")
    ref = platform_rotation(mech, np.eye(3))
    regions: dict[tuple[str, str], OrientationRegion] = {}
    keys = [(ln, rt) for ln in LINES for rt in ROTATIONS]
    for n, (ln, rt) in enumerate(keys):
        pts = scan_points(ln, positions[ln], settings.z0, azimuth)
        axis = rotation_axis(rt, azimuth)
        rots = np.stack([ref @ axis_angle(axis, math.radians(float(a))) for a in ang]) if ang.size else \
            np.zeros((0, 3, 3))
        feas = np.zeros((pts.shape[0], ang.size), bool)
        step = max(1, min(ang.size, 2_000_000 // max(pts.shape[0], 1)))
        for m in range(0, ang.size, step):
            check(cancel)
            rep((n + m / max(ang.size, 1)) / len(keys), f"orientation {LINE_SYMBOL[ln]} line, {ROTATION_SYMBOL[rt]}")
            feas[:, m:m + step] = reachable_rotations(tables, plat0, s_axis0, rots[m:m + step], pts)
        regions[(ln, rt)] = make_region(ln, rt, positions[ln], ang, feas, position_step=settings.position_step,
                                        angle_step=settings.angle_step, position_range=ranges[ln],
                                        angle_range=(-settings.angle_range, settings.angle_range),
                                        region=settings.region)
    ti1, ti2, deltas = tilt_indices(regions, settings.delta, settings.position_delta)
    rep(1.0, "done")
    return MechanismOrientationResult(settings=settings, regions=regions, ti1=ti1, ti2=ti2,
                                      compute_seconds=time.perf_counter() - t0, deltas=deltas, design=None,
                                      mechanism=mech, engine="general", order=order, azimuth=azimuth,
                                      length_step=length_step)


# --------------------------------------------------------------------------------------------
# total orientation


def mechanism_total_orientation(mech: Mechanism, tilt: float, torsion: float, step: float = 5.0,
                                settings: WorkspaceSettings = WorkspaceSettings(), length_step: float = 1.0,
                                position: MechanismWorkspaceResult | None = None,
                                progress: ProgressFn | None = None,
                                cancel: CancelToken = None) -> DexterousResult:
    """The total-orientation workspace of ``mech`` for ``tilt`` and ``torsion`` (module docstring):
    the voxels of the zero-orientation workspace reachable at every orientation of
    :func:`~kinematics.dexterous.orientation_samples`. ``position``: an already computed
    zero-orientation workspace of ``mech`` with these settings (else computed)."""
    samples = orientation_samples(tilt, torsion, step)
    length_step = check_length_step(length_step)
    if any(abs(a) > 0 for a in settings.orientation):
        raise ParameterError("orientation", settings.orientation,
                             "(0, 0, 0): T&T angles are about the home orientation")
    rep = Reporter(progress)
    if position is None:
        position = compute_mechanism_workspace(mech, settings, length_step, rep.sub(0.0, 0.3), cancel)
    elif position.mechanism != mech or any(abs(a) > 0 for a in position.settings.orientation):
        raise ParameterError("position", "workspace", "the zero-orientation workspace of the same mechanism")
    if position.engine == "paper":
        assert position.design is not None
        return paper_total_orientation(position.design, tilt, torsion, step, settings, position,
                                       rep.sub(0.3, 1.0), cancel)
    t0 = time.perf_counter()
    tables, plat0, s_axis0 = _unrotated(mech, position.settings.eta_step, position.length_step)
    ref = platform_rotation(mech, np.eye(3))
    occ = np.asarray(position.occupancy, bool)
    idx = np.flatnonzero(occ.ravel())
    pts = position.grid.points().reshape(-1, 3)[idx]
    rots = tt_rotations(samples[:, 0], samples[:, 1], samples[:, 2])
    rots = np.einsum("ab,mbc->mac", ref, rots)
    alive = np.ones(idx.size, bool)
    n = samples.shape[0]
    for m in range(0, n, BATCH):
        check(cancel)
        rep(0.3 + 0.7 * m / n, f"total-orientation workspace: {int(alive.sum())} voxels left")
        live = np.flatnonzero(alive)
        if not live.size:
            break
        ok = reachable_rotations(tables, plat0, s_axis0, rots[m:m + BATCH], pts[live]).all(axis=1)
        alive[live[~ok]] = False
    flat = np.zeros(occ.size, bool)
    flat[idx[alive]] = True
    seconds = time.perf_counter() - t0
    result = dataclasses.replace(position, occupancy=flat.reshape(occ.shape), chain_mask=None, volume_inner=None,
                                 volume_outer=None, compute_seconds=position.compute_seconds + seconds)
    rep(1.0, "done")
    return DexterousResult(result=result, position=position, tilt=float(tilt), torsion=float(torsion),
                           step=float(step), samples=samples, seconds=seconds)
