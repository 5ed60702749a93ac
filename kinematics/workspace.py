"""Constant-orientation position workspace on a voxel grid.

Definition: a voxel is reachable when its centre ``P`` satisfies, for every chain ``i``, the
existence test of :mod:`kinematics.feasibility` at the fixed platform orientation: SOME
``(d_i, eta_i)`` inside the strokes puts both legs of chain ``i`` inside ``[l_min, l_max]``.
The chains are independent, so the workspace is the intersection of three per-chain sets.

Engines (``WorkspaceSettings.method``): ``"blocks"`` (default) decides blocks of voxels coarse
to fine and is voxel-identical to ``"dense"`` (see :mod:`kinematics.blocks` for the proof), which
is kept as the tests' oracle. Dense engine: a compiled kernel walks each vertical column of voxels
(columns in parallel over the cores) and, per chain, (1) rejects with the conservative whole-stroke
bound, then (2) searches the arc samples outward from the sample that worked for the previous voxel
of the column (a warm start that makes reachable voxels cost about one sample per chain). The chain that failed last
is tested first. Work is issued in chunks of columns so progress is reported and cancellation is
honoured between chunks. With zero rotation and the centered arc range the mechanism is
symmetric under the mirror ``y -> -y`` (chain 1 onto itself, chains 2 and 3 swapped), and only
half of the columns are computed.

Default bounds: a cheap analytical box (each chain bounds ``|P_xy|``) is scouted on a coarse grid;
the reachable box plus two coarse cells is used. If the fine workspace touches a face of that
box that is not a face of the analytical box, the box is enlarged and the computation repeated,
so the default bounds never clip the workspace.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
from numba import njit, prange

from .blocks import rounding_margin, run_blocks
from .bracket import NO_BRACKET_INTERFERENCE, volume_bracket
from .cuda_dense import check_backend, dense_masks_cuda
from .design import Design, ParameterError
from .feasibility import _chain_excluded, chain_points, chain_search, default_n_eta
from .geometry import platform_points_local
from .grid import GridSpec
from .interference import interference_free
from .interference_blocks import interference_free_grid
from .joints import Joints, cone_table
from .kernel_args import kernel_args
from .parallel import KERNEL_LOCK
from .progress import CancelToken, ProgressFn, Reporter, check
from .rotation import euler_zyx_deg
from .settings import WORKSPACE

ALL_CHAINS = 7  # bitmask with the three chain bits set
#: extra mask bit: every chain is feasible on its own but the legs interfere (:mod:`kinematics.interference`)
INTERFERENCE = 8
METHODS: tuple[str, ...] = ("blocks", "dense")


@dataclasses.dataclass(frozen=True)
class WorkspaceSettings:
    """How the position workspace is sampled.

    Attributes:
        voxel: voxel edge ``h``.
        orientation: constant platform orientation ``(psi, theta, phi)`` in degrees (eq. (2)).
        eta_step: largest spacing of the arc-stroke samples, in degrees.
        bounds: ``((xlo, ylo, zlo), (xhi, yhi, zhi))``; ``None`` derives them from the design.
        z_floor: lowest platform height considered by the derived bounds (the platform stays
            above the base plane; the mirror branch ``z < 0`` is excluded).
        symmetry: use the ``y -> -y`` mirror symmetry when it holds exactly.
        diagnostics: also evaluate every chain at every voxel (slower) to report which chain binds.
        method: ``"blocks"`` (coarse-to-fine, default) or ``"dense"`` (every voxel; the oracle);
            both give the same voxels.
        bracket: also compute the certified bracket ``volume_inner <= V <= volume_outer`` of the
            continuous workspace volume (:mod:`kinematics.bracket`).
        joints: passive-joint cones and leg interference (:mod:`kinematics.joints`); the default
            is the paper's model (strokes only).
        bracket_refine: halvings of the bracket's boundary cubes, 0-3 (each about halves the gap
            and costs about four times the previous level; :mod:`kinematics.bracket`).
    """

    voxel: float = 2.0
    orientation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    eta_step: float = 0.5
    bounds: tuple[tuple[float, float, float], tuple[float, float, float]] | None = None
    z_floor: float = 0.0
    symmetry: bool = True
    diagnostics: bool = False
    method: str = "blocks"
    bracket: bool = False
    joints: Joints = Joints()
    bracket_refine: int = 2

    def __post_init__(self) -> None:
        WORKSPACE["bracket_refine"].check(self.bracket_refine)
        if not isinstance(self.joints, Joints):
            raise ParameterError("joints", self.joints, "a Joints value")
        if self.bracket and self.joints.min_distance > 0.0:
            raise ParameterError("bracket", True, NO_BRACKET_INTERFERENCE)
        if self.method not in METHODS:
            raise ParameterError("method", self.method, " or ".join(METHODS))
        WORKSPACE["voxel"].check(self.voxel)
        WORKSPACE["eta_step"].check(self.eta_step)
        WORKSPACE["z_floor"].check(self.z_floor)
        o = tuple(float(x) for x in self.orientation)
        if len(o) != 3 or not all(math.isfinite(x) for x in o):
            raise ParameterError("orientation", self.orientation, "three angles psi,theta,phi in degrees")
        for name, val, lim in zip(("psi", "theta", "phi"), o, (180.0, 90.0, 180.0)):
            if abs(val) > lim:
                raise ParameterError(name, val, f"[-{lim:g}, {lim:g}] degrees")
        object.__setattr__(self, "orientation", o)
        if self.bounds is not None:
            lo, hi = (tuple(float(x) for x in self.bounds[0]), tuple(float(x) for x in self.bounds[1]))
            if len(lo) != 3 or len(hi) != 3 or not all(a < b for a, b in zip(lo, hi)):
                raise ParameterError("bounds", self.bounds, "lo < hi on each of x, y, z")
            object.__setattr__(self, "bounds", (lo, hi))

    def key(self) -> tuple:
        return dataclasses.astuple(self)

    def mirror_symmetric(self, design: Design) -> bool:
        """Whether ``design``'s workspace at these settings is symmetric under ``y -> -y`` and they let
        the engines use it (:meth:`Design.mirror_symmetric`, the ``symmetry`` switch)."""
        return self.symmetry and design.mirror_symmetric(self.orientation)


@dataclasses.dataclass
class WorkspaceResult:
    """A computed workspace: the occupancy grid and how it was obtained."""

    design: Design
    settings: WorkspaceSettings
    grid: GridSpec
    occupancy: np.ndarray  # bool, grid.shape
    chain_mask: np.ndarray | None  # uint8 bitmask per voxel (bit i: chain i feasible) if diagnostics
    compute_seconds: float
    n_eta: int
    volume_inner: float | None = None  # certified bracket (settings.bracket), units^3
    volume_outer: float | None = None
    bracket_seconds: float = 0.0

    @property
    def voxels(self) -> int:
        """Number of reachable voxels."""
        return int(self.occupancy.sum())

    @property
    def volume(self) -> float:
        """Voxel volume ``V = N_reachable h^3``."""
        return self.voxels * self.grid.voxel_volume


# --------------------------------------------------------------------------------------------
# compiled kernel


@njit(parallel=True, cache=True, nogil=True)
def _columns_kernel(col_ix, col_iy, xs, ys, zs, u, cos_t, sin_t, arc, hb,
                    rho_lo, rho_hi, lmin2, lmax2, jc, all_chains, xlo2, xhi2, out):
    """Chain masks of the columns ``(col_ix, col_iy)``: each chain rejected by the whole-stroke bound
    (limits ``[xlo2, xhi2]``: relaxed by the rounding margin of :func:`kinematics.blocks.rounding_margin`)
    or by every arc sample, searched from the sample that served the voxel below."""
    n_cols = col_ix.shape[0]
    n_eta = cos_t.shape[1]
    nz = zs.shape[0]
    for c in prange(n_cols):
        ix = col_ix[c]
        iy = col_iy[c]
        px = xs[ix]
        py = ys[iy]
        start = np.empty(3, np.int64)
        for i in range(3):
            start[i] = n_eta // 2
        first = 0
        for iz in range(nz):
            pz = zs[iz]
            mask = 0
            for kk in range(3):
                i = (first + kk) % 3
                b1x, b1y, b1z, b2x, b2y, b2z = chain_points(px, py, pz, u, i)
                ok = False
                if not _chain_excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc[i],
                                       rho_lo, rho_hi, xlo2, xhi2):
                    k = chain_search(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i], sin_t[i], hb,
                                     rho_lo, rho_hi, lmin2, lmax2, jc[i], start[i])
                    if k >= 0:
                        ok = True
                        start[i] = k
                if ok:
                    mask |= 1 << i
                elif not all_chains:
                    first = i
                    break
            out[ix, iy, iz] = mask


@njit(parallel=True, cache=True, nogil=True)
def _points_kernel(points, u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jc, out):
    """Bitmask of feasible chains for arbitrary points (all chains evaluated)."""
    n_eta = cos_t.shape[1]
    for p in prange(points.shape[0]):
        mask = 0
        for i in range(3):
            b1x, b1y, b1z, b2x, b2y, b2z = chain_points(points[p, 0], points[p, 1], points[p, 2], u, i)
            if _chain_excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc[i], rho_lo, rho_hi, lmin2, lmax2):
                continue
            if chain_search(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i], sin_t[i], hb,
                            rho_lo, rho_hi, lmin2, lmax2, jc[i], n_eta // 2) >= 0:
                mask |= 1 << i
        out[p] = mask


@njit(parallel=True, cache=True, nogil=True)
def _pairs_kernel(points, us, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jcs, out):
    """Reachability of every (point, orientation) pair in one launch: ``us`` holds the rotated
    platform points of each orientation, shape (M, 3, 2, 3), and ``jcs`` its joint-cone table
    (M, 3, 2, 8); ``out`` is (P, M)."""
    n_eta = cos_t.shape[1]
    n_m = us.shape[0]
    for q in prange(points.shape[0] * n_m):
        p = q // n_m
        m = q - p * n_m
        ok = True
        for i in range(3):
            b1x, b1y, b1z, b2x, b2y, b2z = chain_points(points[p, 0], points[p, 1], points[p, 2], us[m], i)
            if _chain_excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc[i], rho_lo, rho_hi, lmin2, lmax2):
                ok = False
                break
            if chain_search(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i], sin_t[i], hb,
                            rho_lo, rho_hi, lmin2, lmax2, jcs[m, i], n_eta // 2) < 0:
                ok = False
                break
        out[p, m] = ok


@njit(parallel=True, cache=True, nogil=True)
def _finish_kernel(out, ny_eval, mirror, bits, occ):
    """The engine's last pass, parallel over x slices: with ``mirror`` the rows ``j >= ny_eval`` get
    the chain masks of their mirror rows ``ny - 1 - j`` (all below ``ny_eval``, so never written
    here) with the bits of :data:`_MIRROR_BITS`; and ``occ = out == 7`` everywhere."""
    nx, ny, nz = out.shape
    for i in prange(nx):
        for j in range(ny):
            if mirror and j >= ny_eval:
                src = ny - 1 - j
                for k in range(nz):
                    out[i, j, k] = bits[out[i, src, k]]
            for k in range(nz):
                occ[i, j, k] = out[i, j, k] == ALL_CHAINS


@njit(parallel=True, cache=True, nogil=True)
def _interference_kernel(out, occ, ok):
    """Leg interference applied in one parallel pass over x slices: a voxel of ``occ`` that ``ok``
    refuses gets the :data:`INTERFERENCE` bit in ``out`` and leaves ``occ`` (numpy's ``bad = occ &
    ~ok; out[bad] |= INTERFERENCE; occ &= ok`` took 16 ms at h = 1 on one thread)."""
    nx, ny, nz = out.shape
    for i in prange(nx):
        for j in range(ny):
            for k in range(nz):
                if occ[i, j, k] and not ok[i, j, k]:
                    out[i, j, k] |= INTERFERENCE
                    occ[i, j, k] = False


# --------------------------------------------------------------------------------------------
# Python drivers

#: chain mask under the mirror ``y -> -y``: chain 1 onto itself, chains 2 and 3 swapped (bits 1, 2)
_MIRROR_BITS = np.array([(v & 1) | (((v >> 2) & 1) << 1) | (((v >> 1) & 1) << 2) for v in range(256)], np.uint8)


def chain_masks_at(design: Design, points: np.ndarray, orientation=(0.0, 0.0, 0.0),
                   eta_step: float = 0.5, joints: Joints | None = None) -> np.ndarray:
    """Bitmask of the chains that can reach each point (bit ``i`` for chain ``i``) at one orientation.

    Args:
        points: platform-centre positions, shape (N, 3).
        orientation: ``(psi, theta, phi)`` in degrees (eq. (2)) or a 3x3 rotation matrix.
    Returns:
        uint8 array (N,); 7 means reachable.
    """
    pts = np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 3))
    out = np.zeros(pts.shape[0], np.uint8)
    args = kernel_args(design, orientation, default_n_eta(design, eta_step), joints)
    with KERNEL_LOCK:
        _points_kernel(pts, *args, out)
    return out


def reachable(design: Design, points: np.ndarray, orientation=(0.0, 0.0, 0.0),
              eta_step: float = 0.5, joints: Joints | None = None) -> np.ndarray:
    """Whether each point is reachable at one orientation.

    Parameters
    ----------
    design : Design
        The mechanism's dimensions.
    points : array_like, shape (N, 3)
        Platform-centre positions.
    orientation : tuple of 3 floats or array_like, shape (3, 3), optional
        ``(psi, theta, phi)`` in degrees (eq. (2)) or a rotation matrix; default the home orientation.
    eta_step : float, optional
        Largest spacing of the arc samples, degrees.
    joints : Joints, optional
        Joint cones and leg interference (default: none).

    Returns
    -------
    numpy.ndarray of bool, shape (N,)
        ``True`` where every chain reaches the point, the test of :func:`compute_workspace`.

    Examples
    --------
    >>> import numpy as np
    >>> import paraspace as ps
    >>> ps.reachable(ps.Design(), np.array([[0.0, 0.0, 130.0], [0.0, 0.0, 1000.0]]))
    array([ True, False])
    """
    ok = chain_masks_at(design, points, orientation, eta_step, joints) == ALL_CHAINS
    if joints is not None and joints.min_distance > 0.0 and ok.any():
        o = np.asarray(orientation, dtype=float)
        rot = o if o.shape == (3, 3) else euler_zyx_deg(*o)
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        ok[ok] = interference_free(design, joints, pts[ok], rot[None], default_n_eta(design, eta_step))[:, 0]
    return ok


def rotation_tables(design: Design, rotations: np.ndarray, joints: Joints) -> tuple[np.ndarray, np.ndarray]:
    """Per rotation ``R`` of ``rotations`` (M, 3, 3): the rotated platform points ``R u`` (M, 3, 2, 3)
    and the joint-cone table (M, 3, 2, 8) of :func:`kinematics.joints.cone_table` (one table for all
    when there is no cone: the S cones' axes are the only part that turns)."""
    rots = np.asarray(rotations, dtype=np.float64).reshape(-1, 3, 3)
    us = np.ascontiguousarray(np.einsum("ijk,mlk->mijl", platform_points_local(design), rots))
    if joints.has_cones:
        jcs = np.ascontiguousarray(np.stack([cone_table(design, joints, r) for r in rots])) if rots.shape[0] else \
            np.zeros((0, 3, 2, 8))
    else:
        # a writable copy for every M (a broadcast view of one rotation would stay read-only, and numba
        # compiles every kernel that takes the table once more for a read-only array)
        jcs = np.repeat(cone_table(design, joints, np.eye(3))[None], rots.shape[0], axis=0)
    return us, jcs


def reachable_pairs(design: Design, points: np.ndarray, rotations: np.ndarray,
                    eta_step: float = 0.5, joints: Joints | None = None) -> np.ndarray:
    """Whether each point is reachable at each orientation: bool array (N, M) for ``points`` (N, 3)
    and rotation matrices ``rotations`` (M, 3, 3), in one parallel launch (the same test as
    :func:`reachable`, column by column)."""
    pts = np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 3))
    rots = np.asarray(rotations, dtype=np.float64).reshape(-1, 3, 3)
    n_eta = default_n_eta(design, eta_step)
    u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, _ = kernel_args(design, np.eye(3), n_eta)
    jn = joints or Joints()
    us, jcs = rotation_tables(design, rots, jn)
    out = np.zeros((pts.shape[0], rots.shape[0]), np.bool_)
    if out.size:
        with KERNEL_LOCK:
            _pairs_kernel(pts, us, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jcs, out)
        if jn.min_distance > 0.0 and out.any():
            out &= interference_free(design, jn, pts, rots, n_eta, where=out)
    return out


def reach_box(design: Design, orientation: tuple[float, float, float] = (0.0, 0.0, 0.0),
              z_floor: float = 0.0) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Analytical box that contains the workspace (may be loose).

    Each leg needs ``|B - D| <= l_max`` with ``|D_xy| <= sqrt(r^2 + b^2/4)`` and ``D_z = 0``, and
    ``B = P + R1 u_bar``; so ``|P_xy + (R1 u_bar)_xy| <= sqrt(r^2 + b^2/4) + l_max`` and
    ``|P_z + (R1 u_bar)_z| <= l_max`` for every platform point: we take the box of the tightest
    per-point bound over x, y and z, and clip z below at ``z_floor``.
    """
    rot = euler_zyx_deg(*orientation)
    u = (platform_points_local(design) @ rot.T).reshape(-1, 3)
    reach_xy = math.hypot(design.r, design.b / 2.0) + design.l_max
    lo = np.max(-reach_xy - u[:, :2], axis=0)
    hi = np.min(reach_xy - u[:, :2], axis=0)
    zlo = max(z_floor, float(np.max(-design.l_max - u[:, 2])))
    zhi = float(np.min(design.l_max - u[:, 2]))
    m = float(max(abs(lo).max(), abs(hi).max()))
    return (-m, -m, zlo), (m, m, max(zhi, zlo + 1e-6))


def _symmetric_box(lo, hi, h: float, z_floor: float | None = None):
    """Snap a box outward to multiples of h, symmetric in x and y about 0. The bottom never goes
    below ``z_floor`` when the box itself starts at or above it (a floor off the grid's multiples,
    e.g. 20 with h = 3, starts the grid at the floor instead of a layer of voxels below it)."""
    m = max(abs(lo[0]), abs(lo[1]), abs(hi[0]), abs(hi[1]))
    m = h * math.ceil(m / h - 1e-9)
    zlo = h * math.floor(lo[2] / h + 1e-9)
    if z_floor is not None and zlo < z_floor <= lo[2] + 1e-9:
        zlo = float(z_floor)
    zhi = h * math.ceil(hi[2] / h - 1e-9)
    return (-m, -m, zlo), (m, m, zhi)


def default_bounds(design: Design, settings: WorkspaceSettings, cancel: CancelToken = None):
    """Box derived from the design's reach: the analytical box, tightened by a coarse scout."""
    alo, ahi = _padded_reach_box(design, settings)
    ext = max(b - a for a, b in zip(alo, ahi))
    hs = max(4.0 * settings.voxel, ext / 48.0)
    scout = GridSpec.from_bounds(alo, ahi, hs)
    check(cancel)
    occ = _run_grid(design, settings, scout, None, cancel)[2]
    if not occ.any():
        return _symmetric_box(alo, ahi, settings.voxel, settings.z_floor)
    idx = np.argwhere(occ)
    axes = scout.axes()
    lo = [max(axes[a][idx[:, a].min()] - 2.5 * hs, alo[a]) for a in range(3)]
    hi = [min(axes[a][idx[:, a].max()] + 2.5 * hs, ahi[a]) for a in range(3)]
    lo[2] = max(lo[2], settings.z_floor)
    return _symmetric_box(lo, hi, settings.voxel, settings.z_floor)


def _padded_reach_box(design: Design, settings: WorkspaceSettings):
    """The analytical box grown by one voxel (except below ``z_floor``): its outermost voxel layer
    lies beyond the reach, so the derived grid never clips the workspace."""
    lo, hi = reach_box(design, settings.orientation, settings.z_floor)
    h = settings.voxel
    return (lo[0] - h, lo[1] - h, lo[2] if lo[2] <= settings.z_floor else lo[2] - h), (hi[0] + h, hi[1] + h, hi[2] + h)


def _use_mirror(design: Design, settings: WorkspaceSettings, grid: GridSpec) -> bool:
    return settings.mirror_symmetric(design) and grid.is_mirror_symmetric_y()


def _run_grid(design: Design, settings: WorkspaceSettings, grid: GridSpec,
              progress: Reporter | None, cancel: CancelToken, all_chains: bool = False, backend: str = "cpu"):
    n_eta = default_n_eta(design, settings.eta_step)
    args = kernel_args(design, settings.orientation, n_eta, settings.joints)
    xs, ys, zs = grid.axes()
    nx, ny, nz = grid.shape
    mirror = _use_mirror(design, settings, grid)
    ny_eval = (ny + 1) // 2 if mirror else ny
    if backend == "cuda":
        out = dense_masks_cuda((xs, ys, zs), ny_eval, args, all_chains, progress, cancel)
    elif settings.method == "blocks":
        out = run_blocks(grid.shape, (xs, ys, zs), grid.h, args, ny_eval, all_chains, progress, cancel)
    else:
        out = np.zeros(grid.shape, np.uint8)
        gx, gy = np.meshgrid(np.arange(nx), np.arange(ny_eval), indexing="ij")
        ix, iy = gx.ravel().astype(np.int64), gy.ravel().astype(np.int64)
        n = ix.size
        eps = rounding_margin(math.sqrt(args[8]), (xs, ys, zs))
        xlo2, xhi2 = max(math.sqrt(args[7]) - eps, 0.0) ** 2, (math.sqrt(args[8]) + eps) ** 2
        # chunks of about 64k voxels: progress/cancel granularity of a few ms
        step = max(64, int(65536 // max(nz, 1)))
        for s in range(0, n, step):
            check(cancel)
            with KERNEL_LOCK:
                _columns_kernel(ix[s:s + step], iy[s:s + step], xs, ys, zs, *args, all_chains, xlo2, xhi2, out)
            if progress is not None:
                frac = min(1.0, (s + step) / n)
                progress(frac, f"computing the workspace, {100 * frac:.0f} %")
    # one parallel pass: the rows that have mirror images (chains 2 and 3 swapped) and out == 7
    occ = np.empty(grid.shape, np.bool_)
    with KERNEL_LOCK:
        _finish_kernel(out, ny_eval, mirror, _MIRROR_BITS, occ)
    if settings.joints.min_distance > 0.0:
        check(cancel)
        if occ.any():
            rot = euler_zyx_deg(*settings.orientation)
            ok = interference_free_grid(design, settings.joints, (xs, ys, zs), grid.h, rot, n_eta, occ, cancel,
                                        mirror)
            with KERNEL_LOCK:
                _interference_kernel(out, occ, ok)
    return out, n_eta, occ


def compute_workspace(design: Design, settings: WorkspaceSettings = WorkspaceSettings(),
                      progress: ProgressFn | None = None, cancel: CancelToken = None,
                      backend: str = "cpu") -> WorkspaceResult:
    """Compute the constant-orientation position workspace (see the module docstring).

    Parameters
    ----------
    design : Design
        The mechanism's dimensions.
    settings : WorkspaceSettings, optional
        Voxel edge ``h``, platform orientation, arc sampling, bounds, engine and options (default:
        ``h = 2`` at the home orientation).
    progress : callable, optional
        ``progress(fraction, message)``, called as the computation advances.
    cancel : threading.Event or callable, optional
        Checked between chunks of work: when it is set the computation stops.
    backend : {"cpu", "cuda"}, optional
        Where the voxels are decided: the CPU engines (default) or the dense test on an NVIDIA GPU
        (:mod:`kinematics.cuda_dense`: the same voxels; strokes only, needs CuPy). The bounds' coarse
        scout and the bracket stay on the CPU.

    Returns
    -------
    WorkspaceResult
        The grid, the occupancy of its voxels, ``voxels`` and ``volume`` (``voxels * h**3``), and
        ``compute_seconds``: the engine time, excluding compilation (which happens on first use;
        call :func:`warm_up` to trigger it early).

    Raises
    ------
    ParameterError
        Invalid settings (the message names the field and its valid range).
    Cancelled
        When ``cancel`` is set.

    Examples
    --------
    >>> import paraspace as ps
    >>> res = ps.compute_workspace(ps.Design(), ps.WorkspaceSettings(voxel=8.0))
    >>> res.voxels, res.grid.h
    (10016, 8.0)
    >>> res.volume == res.voxels * 8.0 ** 3
    True
    """
    check_backend(backend, settings.joints.has_cones, settings.joints.min_distance > 0.0)
    rep = Reporter(progress)
    t0 = time.perf_counter()
    explicit = settings.bounds is not None
    if explicit:
        lo, hi = settings.bounds  # type: ignore[misc]
    else:
        lo, hi = default_bounds(design, settings, cancel)
    alo, ahi = _padded_reach_box(design, settings)
    for _attempt in range(4):
        grid = GridSpec.from_bounds(lo, hi, settings.voxel)
        mask, n_eta, occ = _run_grid(design, settings, grid, rep.sub(0.05, 1.0), cancel,
                                     all_chains=settings.diagnostics, backend=backend)
        if explicit:
            break
        grow = _touching_faces(occ)
        lo2, hi2 = list(lo), list(hi)
        changed = False
        for axis in range(3):
            span = 0.25 * (hi[axis] - lo[axis])
            if grow[axis][0] and lo[axis] > alo[axis] + 1e-9:
                lo2[axis] = max(alo[axis], lo[axis] - span)
                changed = True
            if grow[axis][1] and hi[axis] < ahi[axis] - 1e-9:
                hi2[axis] = min(ahi[axis], hi[axis] + span)
                changed = True
        if not changed:
            break
        lo, hi = _symmetric_box(lo2, hi2, settings.voxel, settings.z_floor)
    seconds = time.perf_counter() - t0
    result = WorkspaceResult(design=design, settings=settings, grid=grid, occupancy=occ,
                             chain_mask=mask if settings.diagnostics else None,
                             compute_seconds=seconds, n_eta=n_eta)
    if settings.bracket:

        t1 = time.perf_counter()
        br = volume_bracket(design, grid, kernel_args(design, settings.orientation, n_eta, settings.joints),
                            n_eta, settings.z_floor, cancel=cancel, refine=settings.bracket_refine,
                            symmetric=settings.mirror_symmetric(design))
        result.volume_inner, result.volume_outer = br.volume_inner, br.volume_outer
        result.bracket_seconds = time.perf_counter() - t1
    rep(1.0, "voxels computed")
    return result


def _touching_faces(occ: np.ndarray) -> list[tuple[bool, bool]]:
    """Per axis, whether the grid's first and last layer hold a reachable voxel (each layer read as a
    view: no copy, no pass over the grid)."""
    def hit(a: int, idx: int) -> bool:
        return bool(occ.shape[a]) and bool(occ[(slice(None),) * a + (idx,)].any())

    return [(hit(a, 0), hit(a, -1)) for a in range(3)]


_WARM = False


def warm_up() -> float:
    """Compile the kernels (cached on disk by numba); returns the seconds it took."""
    global _WARM
    t0 = time.perf_counter()
    if not _WARM:
        d = Design()
        compute_workspace(d, WorkspaceSettings(voxel=40.0, bounds=((-100, -100, 0), (100, 100, 160))))
        compute_workspace(d, WorkspaceSettings(voxel=40.0, bounds=((-100, -100, 0), (100, 100, 160)),
                                               diagnostics=True, bracket=True))
        reachable(d, np.zeros((1, 3)))
        _WARM = True
    return time.perf_counter() - t0
