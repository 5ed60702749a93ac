"""Total-orientation (dexterous) workspace: the positions from which EVERY orientation with tilt
``<= tilt`` (all azimuths) and torsion in ``[-torsion, +torsion]`` is reachable (T&T angles of
:mod:`kinematics.tilt_torsion`, eq. (T1)).

Definition (our documented sampling)
------------------------------------
The continuous set of orientations is replaced by a finite sample set ``S(tilt, torsion, step)``;
a voxel of the position workspace's grid belongs to the total-orientation workspace when its
centre is reachable (all three chains pass the engine's per-chain existence test,
:func:`kinematics.workspace.reachable_pairs`) at EVERY orientation of ``S``. It is therefore the
intersection of the constant-orientation workspaces of the orientations of ``S``, on the SAME grid
as the plain (zero-orientation) workspace, so volume, shell and measures apply unchanged.

``S`` is built from the angular step ``step`` (degrees, default 5) with power-of-two counts:

* torsions ``sigma_j = -torsion + j (2 torsion / 2^k)``, ``j = 0..2^k``, with the smallest
  ``k >= 1`` such that the spacing is ``<= step`` (``k >= 1`` keeps ``sigma = 0``); only 0 when
  ``torsion = 0``;
* tilt rings ``theta_r = r tilt / 2^m``, ``r = 0..2^m``, smallest ``m >= 1`` with spacing ``<= step``
  (only 0 when ``tilt = 0``);
* on ring ``theta_r > 0`` the azimuths ``phi = q 360 / 2^n``, smallest ``n >= 2`` such that
  neighbouring platform normals are ``<= step`` apart (``360 sin(theta_r) / 2^n <= step``); one
  azimuth (0) on the ring ``theta = 0``, where the azimuth does not matter;
* ``S`` is every (azimuth, tilt ring) pair combined with every torsion.

So every orientation of the continuous set is within ``step`` of a sample in torsion, in tilt and
in the direction of the normal along its ring. Properties that hold exactly (tested): the result
is a subset of the position workspace (``S`` contains the identity); ``tilt = torsion = 0`` gives
the position workspace voxel for voxel; a smaller ``step`` only adds samples (the counts are
powers of two, so the sets are nested) and only removes voxels; a larger tilt removes voxels
whenever the sample sets nest (e.g. ``tilt`` and ``2 tilt`` with ``tilt > 2 step``). Between
samples the sampling is not certified: a voxel can pass every sample and still miss an
orientation between them (the error is one-sided towards a larger set, and shrinks with
``step``).

Cost: the candidates are the plain workspace's voxels. ``method="pairs"`` tests the orientations
in batches of :data:`BATCH`, hardest first (largest tilt, then largest torsion), and drops a voxel
at its first unreachable orientation: about ``N_plain x (orientations until the first failure)``
plus ``N_result x |S|`` single-point tests. ``method="tree"`` tests each voxel's :data:`FIRST`
hardest orientations one by one, then certifies the others by groups
(:mod:`kinematics.orientation_tree`), so a voxel of the result costs far fewer than ``|S|`` tests.
``method="blocks"`` (the default for the plain model) drops whole blocks of voxels that one of the
:data:`FIRST_BLOCKS` hardest orientations excludes, skips the hardest orientations a block passes with a
margin, and starts each voxel's tree walk from the cut its neighbour left
(:mod:`kinematics.orientation_blocks`). The voxels are the same.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from .design import Design, ParameterError
from .feasibility import default_n_eta
from .orientation_blocks import reachable_on_grid
from .orientation_tree import reachable_at_all
from .progress import CancelToken, ProgressFn, Reporter, check
from .settings import TOTAL_ORIENTATION
from .tilt_torsion import tt_rotations
from .workspace import WorkspaceResult, WorkspaceSettings, compute_workspace, reachable_pairs

#: Orientations per launch of the pair kernel.
BATCH = 16
#: Hardest samples tested one by one before the tree (``method="tree"``), or leading the blocks'
#: frontier (``method="blocks"``): most voxels that fail, fail one of them.
FIRST = 32
#: Hardest samples leading the blocks' frontier (``method="blocks"``): fewer than :data:`FIRST`,
#: since the tree from the neighbour's cut decides the others cheaply (measured at h = 4, 657
#: orientations: 8 cost 0.85x the CPU time of 32, with :data:`kinematics.orientation_blocks.TOP_BLOCK` 64).
FIRST_BLOCKS = 8
#: How the orientations are tested (:func:`total_orientation_workspace`).
METHODS: tuple[str, ...] = ("blocks", "tree", "pairs")


def _angle(field: str, value, hi: float | None = None) -> float:
    """``value`` checked against its row of :data:`kinematics.settings.TOTAL_ORIENTATION`."""
    return float(TOTAL_ORIENTATION[field].parse(value))


def check_step(step) -> float:
    """Validate the angular step (:data:`kinematics.settings.TOTAL_ORIENTATION`, ``[0.25, 30]`` degrees)."""
    return float(TOTAL_ORIENTATION["angle_step"].parse(step))


def _pow2(span: float, step: float, minimum: int) -> int:
    """Smallest ``2^k``, ``k >= minimum``, with ``span / 2^k <= step``."""
    k = minimum
    while span / 2 ** k > step * (1 + 1e-12):
        k += 1
    return 2 ** k


def orientation_samples(tilt: float, torsion: float, step: float = 5.0) -> np.ndarray:
    """The sample set ``S`` of the module docstring as ``(azimuth, tilt, torsion)`` rows (degrees),
    ordered hardest first (largest tilt, then largest ``|torsion|``)."""
    tilt = _angle("tilt", tilt)
    torsion = _angle("torsion", torsion)
    step = check_step(step)
    if torsion > 0:
        n = _pow2(2 * torsion, step, 1)
        sig = -torsion + np.arange(n + 1) * (2 * torsion / n)
        sig[n // 2] = 0.0
    else:
        sig = np.zeros(1)
    rings: list[tuple[float, np.ndarray]] = [(0.0, np.zeros(1))]
    if tilt > 0:
        m = _pow2(tilt, step, 1)
        for r in range(1, m + 1):
            th = r * tilt / m
            na = _pow2(360.0 * math.sin(math.radians(th)), step, 2)
            rings.append((th, np.arange(na) * (360.0 / na)))
    rows = [(a, th, s) for th, az in rings for a in az for s in sig]
    out = np.array(rows, float).reshape(-1, 3)
    order = np.lexsort((-np.abs(out[:, 2]), -out[:, 1]))
    return out[order]


@dataclasses.dataclass
class DexterousResult:
    """A total-orientation workspace: ``result`` is a :class:`WorkspaceResult` on the position
    workspace's grid (so ``volume``, shells and measures work), ``position`` the plain workspace."""

    result: WorkspaceResult
    position: WorkspaceResult
    tilt: float
    torsion: float
    step: float
    samples: np.ndarray  # (M, 3) azimuth, tilt, torsion (degrees)
    seconds: float  # intersection time (the position workspace's is position.compute_seconds)

    @property
    def occupancy(self) -> np.ndarray:
        return self.result.occupancy

    @property
    def voxels(self) -> int:
        return self.result.voxels

    @property
    def volume(self) -> float:
        return self.result.volume

    def summary(self) -> dict:
        """Scalars as a JSON-ready dict."""
        pv = self.position.volume
        return {"tilt": self.tilt, "torsion": self.torsion, "angle_step": self.step,
                "orientations": int(self.samples.shape[0]), "volume": self.volume, "voxels": self.voxels,
                "position_volume": pv, "fraction_of_position": (self.volume / pv) if pv else None,
                "seconds": self.seconds}


def total_orientation_workspace(design: Design, tilt: float, torsion: float, step: float = 5.0,
                                settings: WorkspaceSettings = WorkspaceSettings(),
                                position: WorkspaceResult | None = None,
                                progress: ProgressFn | None = None,
                                cancel: CancelToken = None, *, method: str = "blocks") -> DexterousResult:
    """The total-orientation workspace for ``tilt`` (degrees, ``[0, 90]``) and ``torsion``
    (``[0, 180]``) with the sample set of :func:`orientation_samples` (module docstring).

    Args:
        settings: of the position workspace (its grid is reused); the orientation must be zero.
        position: an already computed position workspace with those settings (else computed).
        method: ``"blocks"`` (default) decides blocks of positions x groups of orientations
            (:mod:`kinematics.orientation_blocks`), ``"tree"`` each voxel by groups of orientations
            (:mod:`kinematics.orientation_tree`), both for the plain model only (with joint cones or
            leg interference they fall back to ``"pairs"``); ``"pairs"`` tests every orientation of
            every candidate in batches (the module docstring's cost). All give the same voxels.
    """
    if method not in METHODS:
        raise ParameterError("method", method, " or ".join(METHODS))
    samples = orientation_samples(tilt, torsion, step)
    if any(abs(a) > 0 for a in settings.orientation):
        raise ParameterError("orientation", settings.orientation,
                             "(0, 0, 0): T&T angles are about the home orientation")
    rep = Reporter(progress)
    if position is None:
        position = compute_workspace(design, settings, rep.sub(0.0, 0.3), cancel)
    elif position.design != design or any(abs(a) > 0 for a in position.settings.orientation):
        raise ParameterError("position", "workspace", "the zero-orientation workspace of the same design")
    t0 = time.perf_counter()
    occ = np.asarray(position.occupancy, bool)
    idx = np.flatnonzero(occ.ravel())
    rots = tt_rotations(samples[:, 0], samples[:, 1], samples[:, 2])
    alive = np.ones(idx.size, bool)
    eta_step = position.settings.eta_step
    joints = position.settings.joints
    n = samples.shape[0]
    plain = not joints.has_cones and joints.min_distance == 0.0
    if not (method == "blocks" and plain):  # the blocks take the grid's axes, not the points
        pts = position.grid.points().reshape(-1, 3)[idx]
    if method == "blocks" and plain:
        grid = position.grid
        mirror = position.settings.symmetry and design.eta_range == "centered"
        inside = reachable_on_grid(design, occ, grid.axes(), grid.h, samples, rots,
                                   default_n_eta(design, eta_step), FIRST_BLOCKS, rep.sub(0.3, 1.0), cancel,
                                   mirror=mirror)
        alive = inside.ravel()[idx]
        n = 0
    elif method == "tree" and plain:
        alive = reachable_at_all(design, pts, samples, rots, default_n_eta(design, eta_step), FIRST,
                                 rep.sub(0.3, 1.0), cancel)
        n = 0
    for s in range(0, n, BATCH):
        check(cancel)
        live = np.flatnonzero(alive)
        if not live.size:
            break
        ok = reachable_pairs(design, pts[live], rots[s:s + BATCH], eta_step, joints).all(axis=1)
        alive[live[~ok]] = False
        rep(0.3 + 0.7 * min(1.0, (s + BATCH) / n), f"total-orientation workspace: {int(alive.sum())} voxels left")
    flat = np.zeros(occ.size, bool)
    flat[idx[alive]] = True
    out = flat.reshape(occ.shape)
    seconds = time.perf_counter() - t0
    result = dataclasses.replace(position, occupancy=out, chain_mask=None, volume_inner=None, volume_outer=None,
                                 compute_seconds=position.compute_seconds + seconds)
    return DexterousResult(result=result, position=position, tilt=float(tilt), torsion=float(torsion),
                           step=float(step), samples=samples, seconds=seconds)
