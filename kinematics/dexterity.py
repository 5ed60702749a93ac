"""Dexterity: local conditioning ``1/kappa`` of the homogeneous Jacobian (paper eq. (26), ``L = a/2``),
as a value at a pose and as a field over a computed workspace, with the Gosselin-Angeles global
conditioning index (GCI) and the well-conditioned workspace.

Definitions (our documented reading of the paper and of Gosselin & Angeles 1991)
--------------------------------------------------------------------------------
* ``J = J_h^{-1} J_q`` (eq. (26); :mod:`kinematics.jacobian` for ``J_x``, ``J_q``, ``J_h``) at a pose
  and a carriage pose ``(d_i, eta_i)``; ``kappa = sigma_max(J) / sigma_min(J)`` (2-norm condition
  number of the 6 x 12 matrix), and the local conditioning index is ``1/kappa in [0, 1]``
  (0 where ``J_h`` is singular).
* **Resolved** (``mode="resolved"``, default): the carriage pose is the one chosen by the
  redundancy resolution (:func:`kinematics.redundancy.resolve_redundancy`: per chain the
  ``(eta, d)`` that keeps both legs furthest inside their limits).
* **Best** (``mode="best"``): the largest ``1/kappa`` over feasible carriage poses. ``J``'s rows of
  chain ``i`` depend only on chain ``i``'s carriage, but ``kappa`` couples the chains, so the search
  is over a product set. Sampling (stated): per chain the ``n_eta x n_d`` grid of
  ``eta in linspace(eta_lo, eta_hi, n_eta)``, ``d in linspace(0, d_s, n_d)`` (defaults 7 x 6), a
  sample kept only if both of the chain's legs are inside ``[l_min, l_max]``; the search starts at
  the resolved carriage pose and does ``sweeps`` (default 2) passes of coordinate ascent (for
  chain 1, 2, 3 in turn: the best of its feasible samples with the other two chains fixed). It
  is therefore a lower bound of the true best over the continuous strokes, and never below the
  resolved value. :func:`dexterity_at` with ``search="exhaustive"`` searches the whole product of
  the per-chain samples instead (pointwise only; ``(n_eta n_d)^3`` Jacobians).
* **Field** over a :class:`kinematics.workspace.WorkspaceResult`: ``1/kappa`` at the centre of
  every reachable voxel, at the workspace's constant orientation (NaN outside the workspace).
* **GCI** = the mean of ``1/kappa`` over the reachable voxels, the voxel form of Gosselin-Angeles'
  ``int_W (1/kappa) dV / int_W dV``.
* **Well-conditioned workspace**: the reachable voxels with ``1/kappa >= kappa_min``; its volume is
  their count times ``h^3``.

Scale of the numbers: eq. (26) homogenises only ``J_x``; ``J_q``'s arc columns ``f = s . t`` are
lengths per radian (``|t| ~ r - d``, norm about 20 for the paper's design) while its leg and radial
columns are dimensionless (norm 1 and 0.5). ``sigma_max`` is therefore set by the arc columns and
``1/kappa`` stays small: at most about 0.012 over the paper's design's workspace (GCI 0.0029), so
a threshold like 0.1 selects nothing; the CLI's default ``kappa_min`` is 0.005 (about the upper
quarter of the workspace). Dividing the arc columns by ``L`` as well would give ``1/kappa`` 0.14
at the home pose ``(0, 0, 130)``; that is not the paper's definition and is not done here.

Cost (``search="full"``): the resolved carriage pose is found per voxel by a compiled copy of the resolver's search
(a 73 x 61 grid and two 21 x 21 zooms per chain, about 5,300 margins per chain, bounded by blocks
so that about a fifth are computed: :mod:`kinematics.carriage_search`, the same poses), the
Jacobians are assembled by a compiled kernel and ``J`` and its singular values are computed with
numpy's batched ``solve``/``svd`` in chunks of :data:`CHUNK` voxels. ``mode="best"`` adds
``sweeps x 3 x n_eta x n_d`` Jacobians per voxel (252 with the defaults). Measured on 2 shared
cores for the paper's design (resolved) at ``h = 2`` (640,014 voxels): 11 s (32 s in the same run
before the search was bounded, 51 s on a busier day; nearly all of it in the resolver's search).
``search="sweep"`` (:mod:`kinematics.dexterity_sweep`) finds the same carriage poses by the same
bounded search and computes ``1/kappa`` in the same compiled pass (to 1e-9 relative of the SVD's).
The field's default ``search="neighbour"`` (:mod:`kinematics.dexterity_neighbour`) climbs from the
neighbour voxel's carriage pose to a local maximum of the same margin instead: not the same poses,
but within a stated tolerance of the full search's margin, checked at run time on a seeded sample of
voxels (the result's ``check``; a broken tolerance is reported, never silent).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import time
from collections.abc import Sequence

import numpy as np
from numba import njit, prange

from .carriage_search import _margin_cs, resolve_kernel
from .design import Design, ParameterError
from .dexterity_neighbour import MARGIN_TOLERANCE, SampleCheck, chain_margins, compare, neighbour_values, sample_indices
from .dexterity_sweep import _constants, continuation_field, inverse_condition_at, plane_offsets, pose_inputs
from .parallel import KERNEL_LOCK, kernel_launch
from .pose import Pose
from .progress import CancelToken, ProgressFn, Reporter, check
from .redundancy import resolve_redundancy
from .settings import DEXTERITY, DEXTERITY_SEARCHES
from .workspace import WorkspaceResult

MODES: tuple[str, ...] = ("resolved", "best")
#: How the field finds the resolved carriage poses (:func:`dexterity_field`; the first is the
#: default; defined with their words in :data:`kinematics.settings.DEXTERITY_SEARCHES`).
SEARCHES: tuple[str, ...] = tuple(DEXTERITY_SEARCHES)
#: Voxels per batched ``solve``/``svd`` call.
CHUNK = 32768


# --------------------------------------------------------------------------------------------
# compiled kernels


@njit(cache=True, forceinline=True)
def _margin(bx0, by0, bz0, bx1, by1, bz1, varpi, rho, hb, lmin, lmax):
    """:func:`_margin_cs` at the carriage angle ``varpi`` (radians)."""
    return _margin_cs(bx0, by0, bz0, bx1, by1, bz1, math.cos(varpi), math.sin(varpi), rho, hb, lmin, lmax)


@njit(parallel=True, cache=True, nogil=True)
def _assemble_kernel(points, u, R2, rho, eta, hb, inv_L, J_h, J_q):
    """``J_h`` (N, 6, 6) and ``J_q`` (N, 6, 12) of eqs. (23), (25), (26) for per-point carriages
    ``rho = r - d`` (N, 3) and ``eta`` (N, 3, radians); ``J_q`` must come zeroed."""
    for p in prange(points.shape[0]):
        for i in range(3):
            varpi = 2.0 * math.pi * i / 3.0 + eta[p, i]
            c, s = math.cos(varpi), math.sin(varpi)
            for j in range(2):
                row = 2 * i + j
                lat = hb if j == 0 else -hb
                ux, uy, uz = u[i, j, 0], u[i, j, 1], u[i, j, 2]
                vx = points[p, 0] + ux - (c * rho[p, i] - s * lat)
                vy = points[p, 1] + uy - (s * rho[p, i] + c * lat)
                vz = points[p, 2] + uz
                n = math.sqrt(vx * vx + vy * vy + vz * vz)
                sx, sy, sz = vx / n, vy / n, vz / n
                # -s^T [u]_x R2 = (u x s)^T R2
                cx = uy * sz - uz * sy
                cy = uz * sx - ux * sz
                cz = ux * sy - uy * sx
                J_h[p, row, 0] = sx
                J_h[p, row, 1] = sy
                J_h[p, row, 2] = sz
                for k in range(3):
                    J_h[p, row, 3 + k] = (cx * R2[0, k] + cy * R2[1, k] + cz * R2[2, k]) * inv_L
                J_q[p, row, row] = 1.0
                J_q[p, row, 6 + i] = -(sx * c + sy * s)  # s . h, h = -(cos, sin, 0)
                J_q[p, row, 9 + i] = sx * (-rho[p, i] * s - lat * c) + sy * (rho[p, i] * c - lat * s)


@njit(parallel=True, cache=True, nogil=True)
def _chain_ok_kernel(points, u, i, rho, eta, hb, lmin, lmax, out):
    """Whether chain ``i``'s legs are inside their limits at per-point carriage (rho, eta rad)."""
    g = 2.0 * math.pi * i / 3.0
    for p in prange(points.shape[0]):
        m = _margin(points[p, 0] + u[i, 0, 0], points[p, 1] + u[i, 0, 1], points[p, 2] + u[i, 0, 2],
                    points[p, 0] + u[i, 1, 0], points[p, 1] + u[i, 1, 1], points[p, 2] + u[i, 1, 2],
                    g + eta, rho, hb, lmin, lmax)
        out[p] = m >= -1e-9


# --------------------------------------------------------------------------------------------
# batched linear algebra


def _inv_kappa_batch(J_h: np.ndarray, J_q: np.ndarray) -> np.ndarray:
    """``1/kappa`` of ``J_h^{-1} J_q`` for a stack; 0 where ``J_h`` is singular."""
    out = np.zeros(J_h.shape[0])
    try:
        J = np.linalg.solve(J_h, J_q)
        ok = np.ones(J_h.shape[0], bool)
    except np.linalg.LinAlgError:
        J = np.empty_like(J_q)
        ok = np.zeros(J_h.shape[0], bool)
        for k in range(J_h.shape[0]):
            try:
                J[k] = np.linalg.solve(J_h[k], J_q[k])
                ok[k] = True
            except np.linalg.LinAlgError:
                pass
    if ok.any():
        sv = np.linalg.svd(J[ok], compute_uv=False)
        with np.errstate(invalid="ignore", divide="ignore"):
            r = sv[:, -1] / sv[:, 0]
        out[ok] = np.where(np.isfinite(r), r, 0.0)
    return out


def resolved_carriages(design: Design, points: np.ndarray, orientation: Sequence[float] = (0.0, 0.0, 0.0),
                       bounded: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The redundancy resolution's carriage pose (module docstring) at many positions of one
    orientation ``(psi, theta, phi)`` (degrees): ``d`` (N, 3) and ``eta`` (N, 3, degrees).
    ``bounded=False`` computes every grid point of the full search (the same poses, slower: the
    reference of the tests)."""
    pts = np.ascontiguousarray(np.asarray(points, float).reshape(-1, 3))
    u, _R2, hb, _ = _constants(design, orientation)
    e_lo, e_hi = (math.radians(v) for v in design.eta_limits)
    r_lo, r_hi = design.rho_limits
    rho = np.zeros((pts.shape[0], 3))
    eta = np.zeros((pts.shape[0], 3))
    if pts.shape[0]:
        with KERNEL_LOCK:
            resolve_kernel(pts, u, e_lo, e_hi, r_lo, r_hi, hb, design.l_min, design.l_max, rho, eta, bool(bounded))
    return design.r - rho, np.degrees(eta) + 0.0


def inverse_condition_batch(design: Design, points: np.ndarray, d: np.ndarray, eta_deg: np.ndarray,
                            orientation: Sequence[float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """``1/kappa`` of eq. (26)'s ``J`` at positions ``points`` (N, 3) of one orientation with
    per-point carriages ``d`` (N, 3) and ``eta_deg`` (N, 3); batched (see the module docstring)."""
    pts, rho, eta, u, R2, hb, inv_L = pose_inputs(design, points, d, eta_deg, orientation)
    n = pts.shape[0]
    out = np.zeros(n)
    for s in range(0, n, CHUNK):
        sl = slice(s, min(n, s + CHUNK))
        m = sl.stop - sl.start
        J_h = np.zeros((m, 6, 6))
        J_q = np.zeros((m, 6, 12))
        with KERNEL_LOCK:
            _assemble_kernel(pts[sl], u, R2, rho[sl], eta[sl], hb, inv_L, J_h, J_q)
        out[sl] = _inv_kappa_batch(J_h, J_q)
    return out


def carriage_samples(design: Design, n_eta: int = 7, n_d: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """The per-chain carriage samples of ``mode="best"``: ``(d, eta_deg)``, each of length
    ``n_eta * n_d`` (``eta`` outer), on ``linspace`` grids over the strokes."""
    if not (isinstance(n_eta, int) and isinstance(n_d, int) and 1 <= n_eta <= 101 and 1 <= n_d <= 101):
        raise ParameterError("carriage_samples", (n_eta, n_d), "[1, 101] samples of eta and of d")
    lo, hi = design.eta_limits
    eta = np.linspace(lo, hi, n_eta) if hi > lo and n_eta > 1 else np.array([lo])
    d = np.linspace(0.0, design.d_s, n_d) if design.d_s > 0 and n_d > 1 else np.array([0.0])
    ee, dd = np.meshgrid(eta, d, indexing="ij")
    return dd.ravel(), ee.ravel()


def _chain_ok(design: Design, pts: np.ndarray, u: np.ndarray, i: int, d: float, eta_deg: float, hb: float
              ) -> np.ndarray:
    out = np.zeros(pts.shape[0], np.bool_)
    with KERNEL_LOCK:
        _chain_ok_kernel(pts, u, i, design.r - d, math.radians(eta_deg), hb, design.l_min, design.l_max, out)
    return out


def best_inverse_condition_batch(design: Design, points: np.ndarray, orientation: Sequence[float] = (0.0, 0.0, 0.0),
                                 n_eta: int = 7, n_d: int = 6, sweeps: int = 2,
                                 cancel: CancelToken = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``mode="best"`` at many positions (module docstring: coordinate ascent from the resolved
    carriage pose over the per-chain samples). Returns ``(best, resolved, d, eta_deg)``: the best
    ``1/kappa`` found, the resolved one, and the carriage pose of the best (N, 3 each)."""
    pts = np.ascontiguousarray(np.asarray(points, float).reshape(-1, 3))
    d, eta = resolved_carriages(design, pts, orientation)
    resolved = inverse_condition_batch(design, pts, d, eta, orientation)
    best = resolved.copy()
    u, _R2, hb, _ = _constants(design, orientation)
    ds, es = carriage_samples(design, n_eta, n_d)
    for _sweep in range(int(sweeps)):
        for i in range(3):
            for dv, ev in zip(ds, es):
                check(cancel)
                ok = _chain_ok(design, pts, u, i, float(dv), float(ev), hb)
                if not ok.any():
                    continue
                dd, ee = d[ok].copy(), eta[ok].copy()
                dd[:, i], ee[:, i] = dv, ev
                val = inverse_condition_batch(design, pts[ok], dd, ee, orientation)
                better = val > best[ok]
                idx = np.flatnonzero(ok)[better]
                best[idx] = val[better]
                d[idx], eta[idx] = dd[better], ee[better]
    return best, resolved, d, eta


# --------------------------------------------------------------------------------------------
# pointwise


@dataclasses.dataclass
class Dexterity:
    """``1/kappa`` of eq. (26) at one pose (module docstring)."""

    inverse_condition: float  # 1/kappa at the carriage pose below
    resolved: float  # 1/kappa at the redundancy resolution's carriage pose
    d: list[float]
    eta: list[float]  # degrees
    mode: str
    feasible: bool  # the resolution found a feasible carriage pose for every chain

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


def _check_mode(mode: str) -> str:
    if mode not in MODES:
        raise ParameterError("mode", mode, " or ".join(MODES))
    return mode


def dexterity_at(design: Design, pose: Pose, mode: str = "resolved", *, n_eta: int = 7, n_d: int = 6,
                 sweeps: int = 2, search: str = "coordinate") -> Dexterity:
    """``1/kappa`` of ``J = J_h^{-1} J_q`` (eq. (26), ``L = a/2``) at ``pose``: at the resolved
    carriage pose, or (``mode="best"``) the best over the per-chain carriage samples, by
    coordinate ascent (``search="coordinate"``, as the field) or over their whole product
    (``search="exhaustive"``). See the module docstring."""
    _check_mode(mode)
    if search not in ("coordinate", "exhaustive"):
        raise ParameterError("search", search, "coordinate or exhaustive")
    res = resolve_redundancy(design, pose)
    p = pose.position[None, :]
    o = (pose.psi, pose.theta, pose.phi)
    resolved = float(inverse_condition_batch(design, p, res.d[None, :], res.eta[None, :], o)[0])
    if mode == "resolved":
        return Dexterity(resolved, resolved, [float(v) for v in res.d], [float(v) for v in res.eta], mode,
                         res.feasible)
    if search == "coordinate":
        best, _r, d, eta = best_inverse_condition_batch(design, p, o, n_eta, n_d, sweeps)
        return Dexterity(float(best[0]), resolved, [float(v) for v in d[0]], [float(v) for v in eta[0]], mode,
                         res.feasible)
    u, _R2, hb, _ = _constants(design, o)
    ds, es = carriage_samples(design, n_eta, n_d)
    per_chain = []
    for i in range(3):
        ok = np.array([_chain_ok(design, np.ascontiguousarray(p), u, i, float(a), float(b), hb)[0]
                       for a, b in zip(ds, es)])
        cand = [(float(a), float(b)) for a, b, k in zip(ds, es, ok) if k]
        cand.append((float(res.d[i]), float(res.eta[i])))
        per_chain.append(cand)
    combos = list(itertools.product(*per_chain))
    dd = np.array([[c[0] for c in combo] for combo in combos])
    ee = np.array([[c[1] for c in combo] for combo in combos])
    vals = inverse_condition_batch(design, np.repeat(p, len(combos), axis=0), dd, ee, o)
    k = int(np.argmax(vals))
    return Dexterity(float(vals[k]), resolved, [float(v) for v in dd[k]], [float(v) for v in ee[k]], mode,
                     res.feasible)


# --------------------------------------------------------------------------------------------
# field over a workspace


@dataclasses.dataclass
class DexterityField:
    """``1/kappa`` over a computed workspace, its GCI and the well-conditioned workspace."""

    inverse_condition: np.ndarray  # float, grid shape; NaN outside the workspace
    gci: float  # mean of 1/kappa over the reachable voxels (NaN for an empty workspace)
    kappa_min: float  # threshold on 1/kappa
    well_conditioned: np.ndarray  # bool, grid shape: reachable and 1/kappa >= kappa_min
    well_conditioned_volume: float
    volume: float  # of the workspace
    mode: str
    seconds: float
    minimum: float
    maximum: float
    search: str = "full"  # how the carriage poses were found (SEARCHES)
    check: SampleCheck | None = None  # search="neighbour": the run-time check against the full search

    def well_conditioned_result(self, result: WorkspaceResult) -> WorkspaceResult:
        """The well-conditioned workspace as a :class:`WorkspaceResult` on ``result``'s grid (so its
        volume, shell and measures are computed as for the position workspace)."""
        return dataclasses.replace(result, occupancy=self.well_conditioned.copy(), chain_mask=None,
                                   volume_inner=None, volume_outer=None)

    def summary(self) -> dict:
        """The scalar results as a JSON-ready dict."""
        def f(v: float) -> float | None:
            return None if not math.isfinite(v) else float(v)

        return {"gci": f(self.gci), "kappa_min": self.kappa_min,
                "well_conditioned_volume": float(self.well_conditioned_volume),
                "well_conditioned_fraction": f(self.well_conditioned_volume / self.volume) if self.volume else None,
                "inverse_condition_min": f(self.minimum), "inverse_condition_max": f(self.maximum),
                "dexterity_mode": self.mode, "dexterity_seconds": self.seconds,
                "dexterity_search": self.search,
                "dexterity_check": None if self.check is None else self.check.to_dict()}


def check_kappa_min(kappa_min: float) -> float:
    """Validate the threshold on ``1/kappa``: a number in ``(0, 1]``."""
    try:
        v = float(kappa_min)
    except (TypeError, ValueError):
        raise ParameterError("kappa_min", kappa_min, "(0, 1] (a number)") from None
    if not (math.isfinite(v) and 0.0 < v <= 1.0):
        raise ParameterError("kappa_min", kappa_min, "(0, 1]")
    return v


def check_search(search: str) -> str:
    """Validate the dexterity field's carriage search: one of :data:`SEARCHES`."""
    if search not in SEARCHES:
        raise ParameterError("dexterity_search", search, " or ".join(SEARCHES))
    return search


def check_margin_tolerance(margin_tolerance: float) -> float:
    """Validate the neighbour search's tolerance ``epsilon`` on the margin gap
    (:data:`kinematics.settings.DEXTERITY`)."""
    return float(DEXTERITY["margin_tolerance"].check(margin_tolerance))


def _sample_check(design: Design, occ: np.ndarray, axes: Sequence[np.ndarray], vals: np.ndarray,
                  margins: np.ndarray, orientation: Sequence[float], margin_tolerance: float) -> SampleCheck:
    """The neighbour search's run-time check (:mod:`kinematics.dexterity_neighbour`): a seeded sample
    of the reachable voxels of ``occ`` (C order; a grid of ``axes``) through the full search
    (:func:`resolved_carriages`), ``1/kappa`` at its poses by the same compiled eigenvalues as the
    field's (:func:`kinematics.dexterity_sweep.inverse_condition_at`: the check measures the poses'
    difference, not two methods'; numpy's SVD took 10 of the check's 31 ms at h = 2)."""
    idx = sample_indices(vals.shape[0])
    ii, jj, kk = np.unravel_index(np.flatnonzero(occ)[idx], occ.shape)
    p = np.stack([np.asarray(axes[0])[ii], np.asarray(axes[1])[jj], np.asarray(axes[2])[kk]], axis=1)
    d, eta = resolved_carriages(design, p, orientation)
    full = inverse_condition_at(design, p, d, eta, orientation)
    return compare(vals[idx], margins[idx], full, chain_margins(design, p, d, eta, orientation), vals.shape[0],
                   margin_tolerance)


@njit(parallel=True, cache=True, nogil=True)
def _scatter_kernel(occ, offset, vals, kappa_min, field, well):
    """``field``: ``vals`` (over the reachable voxels of ``occ`` in C order; ``offset[i]`` the index of
    plane ``i``'s first) at the reachable voxels, NaN elsewhere; ``well``: ``field >= kappa_min``
    there, False elsewhere (one parallel pass instead of numpy's two masked assignments)."""
    nx, ny, nz = occ.shape
    for i in prange(nx):
        m = offset[i]
        for j in range(ny):
            for k in range(nz):
                if occ[i, j, k]:
                    v = vals[m]
                    field[i, j, k] = v
                    well[i, j, k] = v >= kappa_min
                    m += 1
                else:
                    field[i, j, k] = np.nan
                    well[i, j, k] = False


def dexterity_field(result: WorkspaceResult, kappa_min: float = 0.1, mode: str = "resolved", *,
                    n_eta: int = 7, n_d: int = 6, sweeps: int = 2, progress: ProgressFn | None = None,
                    cancel: CancelToken = None, search: str = SEARCHES[0],
                    margin_tolerance: float = MARGIN_TOLERANCE) -> DexterityField:
    """``1/kappa`` at every reachable voxel centre of ``result`` (at its orientation), the GCI and
    the well-conditioned workspace ``1/kappa >= kappa_min`` (module docstring). ``search`` (resolved
    mode): ``"neighbour"`` (default) climbs from the neighbour voxel's carriage pose to a local
    maximum of the resolver's margin and checks a sample against the full search with the stated
    tolerance ``margin_tolerance`` (:mod:`kinematics.dexterity_neighbour`; the result's ``check``),
    ``"sweep"`` finds the resolver's carriage poses and ``1/kappa`` in one compiled pass
    (:mod:`kinematics.dexterity_sweep`: the same poses), ``"full"`` runs the resolver's full search
    at every voxel and numpy's SVD. ``mode="best"`` starts from the full
    search's poses whatever ``search`` says."""
    _check_mode(mode)
    check_search(search)
    margin_tolerance = check_margin_tolerance(margin_tolerance)
    kappa_min = check_kappa_min(kappa_min)
    rep = Reporter(progress)
    t0 = time.perf_counter()
    design = result.design
    occ = np.asarray(result.occupancy, bool)
    orientation = result.settings.orientation
    sample = None
    if mode == "resolved" and search == "neighbour":
        vals, margins = neighbour_values(design, occ, result.grid.axes(), orientation, rep, cancel)
        check(cancel)
        sample = _sample_check(design, occ, result.grid.axes(), vals, margins, orientation, margin_tolerance)
    elif mode == "resolved" and search == "sweep":
        vals = continuation_field(design, occ, result.grid.axes(), orientation, rep, cancel)[0]
    else:
        pts = result.grid.points()[occ]
        vals = np.zeros(pts.shape[0])
        step = 8 * CHUNK
        for s in range(0, pts.shape[0], step):
            check(cancel)
            p = pts[s:s + step]
            if mode == "resolved":
                d, eta = resolved_carriages(design, p, orientation)
                vals[s:s + step] = inverse_condition_batch(design, p, d, eta, orientation)
            else:
                vals[s:s + step] = best_inverse_condition_batch(design, p, orientation, n_eta, n_d, sweeps,
                                                                cancel)[0]
            rep(min(1.0, (s + step) / max(pts.shape[0], 1)), "dexterity")
    field = np.empty(occ.shape)
    well = np.empty(occ.shape, bool)
    occ_c = np.ascontiguousarray(occ)
    with kernel_launch(occ.shape[0]):
        _scatter_kernel(occ_c, plane_offsets(occ_c)[0], np.ascontiguousarray(vals, float), float(kappa_min), field,
                        well)
    vv = result.grid.voxel_volume
    n = vals.size
    return DexterityField(
        inverse_condition=field, gci=float(vals.mean()) if n else float("nan"), kappa_min=kappa_min,
        well_conditioned=well, well_conditioned_volume=float(np.count_nonzero(vals >= kappa_min)) * vv,
        volume=n * vv, mode=mode,
        seconds=time.perf_counter() - t0, minimum=float(vals.min()) if n else float("nan"),
        maximum=float(vals.max()) if n else float("nan"),
        search=search if mode == "resolved" else "full", check=sample)
