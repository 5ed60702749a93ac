"""Leg interference of any mechanism description: do the legs clear each other in SOME feasible
carriage configuration? (:mod:`kinematics.interference` is the paper mechanism's.)

**Definition.** Leg ``j`` is the segment from its base joint ``D_j(q_c)`` ((M1)-(M2) of
:mod:`kinematics.mechanism`, ``q_c`` the carriage values of its chain ``c``) to its platform joint
``B_j = P + R u_j``, of diameter ``d_j`` (the leg's ``diameter``). Legs ``i`` and ``j`` *clear*
each other when the distance between their segments (:func:`segment_distances`, the closed form
of :func:`kinematics.interference.segment_distance` vectorised) is at least ``(d_i + d_j) / 2``;
a pair with ``d_i + d_j = 0``, or whose segments share an end point (two legs on one joint, which meet there by
construction), is not tested. A pose ``(P, R)`` is **interference-free** when there are carriage
values ``q_c`` of every chain, each *feasible* for its chain (every leg of the chain in its length
range and inside its cones, as in :mod:`kinematics.mechanism_workspace`), with every pair of legs
clear -- pairs in one chain and pairs of different chains alike.

**Computed on a grid of carriage values.** Each chain's carriage values are taken on its grid
``G_c``: every revolute joint every ``eta_step`` degrees and every prismatic joint every
``length_step`` (``ceil(range / step) + 1`` equally spaced values, both ends): the general engine's
samples of its sampled joints times as many values of its exact joint. The chain's *candidates*
are the points of ``G_c`` feasible for the chain whose own legs are pairwise clear; the pose is
interference-free on the grid when one candidate per chain makes every pair of legs of different
chains clear. A depth-first search over the chains (fewest candidates
first) decides it, abandoning a partial choice at the first colliding pair; it is exact on the grid
(tested equal to the plain enumeration of every combination) and visits at most :data:`MAX_NODES`
partial choices per pose: past that the pose counts as not interference-free and is counted in
``undecided``. On the grid the answer is an inner approximation of the definition: a clearing
configuration between grid values is missed (one-sided, like the engine's sampling; a pose whose
feasible set in the exact joint is thinner than a grid step is then not interference-free).

The workspace of a description with a leg ``diameter`` is the general engine's reachable voxels
that are interference-free on the grid (:func:`interference_filter`, a per-voxel search in Python:
use coarse voxels).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Sequence

import numpy as np

from .design import ParameterError
from .mechanism import Chain, Mechanism, check_length_step, platform_rotation
from .progress import CancelToken, check

__all__ = ["MAX_NODES", "InterferenceResult", "chain_candidates", "interference_free_general", "interference_filter",
           "segment_distances"]

#: Most partial choices the search visits for one pose.
MAX_NODES = 200_000
#: Most carriage values of one chain's grid.
MAX_GRID = 20_000
_EPS = 1e-9


def segment_distances(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Distances between the segments ``[a, b]`` and ``[c, d]`` (arrays ``(..., 3)``, broadcast):
    :func:`kinematics.interference.segment_distance` (Ericson's clamped closest points) vectorised."""
    d1, d2, r = b - a, d - c, a - c
    aa = np.einsum("...i,...i->...", d1, d1)
    ee = np.einsum("...i,...i->...", d2, d2)
    f = np.einsum("...i,...i->...", d2, r)
    cc = np.einsum("...i,...i->...", d1, r)
    bb = np.einsum("...i,...i->...", d1, d2)
    tiny = 1e-300
    denom = aa * ee - bb * bb
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(denom > 0.0, np.clip((bb * f - cc * ee) / np.where(denom > 0.0, denom, 1.0), 0.0, 1.0), 0.0)
        t = (bb * s + f) / np.where(ee > tiny, ee, 1.0)
        s_lo = np.clip(-cc / np.where(aa > tiny, aa, 1.0), 0.0, 1.0)
        s_hi = np.clip((bb - cc) / np.where(aa > tiny, aa, 1.0), 0.0, 1.0)
    s = np.where(t < 0.0, s_lo, np.where(t > 1.0, s_hi, s))
    t = np.clip(t, 0.0, 1.0)
    # degenerate segments (a point)
    point_a, point_c = aa <= tiny, ee <= tiny
    s = np.where(point_a, 0.0, np.where(point_c, s_lo, s))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(point_a & ~point_c, np.clip(f / np.where(ee > tiny, ee, 1.0), 0.0, 1.0),
                     np.where(point_c, 0.0, t))
    gap = a + s[..., None] * d1 - (c + t[..., None] * d2)
    return np.sqrt(np.einsum("...i,...i->...", gap, gap))


def _clear(base_a: np.ndarray, top_a: np.ndarray, diam_a: np.ndarray, base_b: np.ndarray, top_b: np.ndarray,
           diam_b: np.ndarray, same: bool = False) -> np.ndarray:
    """Whether every leg of ``a`` clears every leg of ``b``, for every pair of configurations:
    ``base_a`` ``(Ka, na, 3)``, ``top_a`` ``(na, 3)`` (likewise ``b``) -> bool ``(Ka, Kb)``; with
    ``same`` (one chain, ``Ka = Kb`` the same configurations) the diagonal ``(Ka,)`` of its own pairs."""
    ka, na = base_a.shape[:2]
    kb, nb = base_b.shape[:2]
    out = np.ones(ka if same else (ka, kb), bool)
    for i in range(na):
        for j in range(i + 1 if same else 0, nb):
            need = 0.5 * (diam_a[i] + diam_b[j])
            if need <= 0.0:
                continue
            if same:
                pa, pb, pc, pd = base_a[:, i], top_a[i][None], base_b[:, j], top_b[j][None]
            else:
                pa, pb = base_a[:, None, i], top_a[i][None, None]
                pc, pd = base_b[None, :, j], top_b[j][None, None]
            dist = segment_distances(pa, pb, pc, pd)
            shared = ((np.abs(pa - pc).max(axis=-1) <= 1e-9) | (np.abs(pa - pd).max(axis=-1) <= 1e-9)
                      | (np.abs(pb - pc).max(axis=-1) <= 1e-9) | (np.abs(pb - pd).max(axis=-1) <= 1e-9))
            out &= shared | (dist >= need - _EPS)
    return out


@functools.lru_cache(maxsize=64)
def carriage_grid(chain: Chain, eta_step: float, length_step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The chain's grid ``G_c`` (module docstring): every revolute joint every ``eta_step`` degrees,
    every prismatic joint every ``length_step``, both ends included; its joint values ``(K, k)``,
    base joints ``(K, n, 3)`` and carriage rotations ``(K, 3, 3)`` by (M1)-(M2)."""
    values = []
    for joint in chain.carriage:
        lo, hi = joint.range
        step = eta_step if joint.type == "revolute" else length_step
        n = int(math.ceil((hi - lo) / step - 1e-12)) + 1 if hi > lo else 1
        values.append(np.linspace(lo, hi, n) if n > 1 else np.array([lo]))
    if values:
        mesh = np.meshgrid(*values, indexing="ij")
        q = np.stack([m.ravel() for m in mesh], axis=1)
    else:
        q = np.zeros((1, 0))
    if len(q) > MAX_GRID:
        raise ParameterError("eta_step/length_step", (eta_step, length_step),
                             f"steps giving at most {MAX_GRID:,} carriage values per chain for leg interference "
                             f"(these give {len(q):,})")
    bases = np.array([chain.base_points(row) for row in q])
    rots = np.array([chain.transform(row)[0] for row in q])
    return q, bases, rots


def chain_candidates(mech: Mechanism, c: int, point: np.ndarray, rot: np.ndarray, eta_step: float = 0.5,
                     length_step: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Chain ``c``'s candidates at ``point`` with the platform rotation ``rot`` (already turned by
    the reference): their carriage values ``(K', k)`` and base joints ``(K', n, 3)`` (module
    docstring)."""
    chain = mech.chains[c]
    q, bases, rots = carriage_grid(chain, eta_step, length_step)
    tops = point[None, :] + np.array([leg.platform for leg in chain.legs], float) @ rot.T      # (n, 3)
    v = tops[None] - bases                                                                    # (K, n, 3)
    length = np.linalg.norm(v, axis=2)
    ok = np.ones(len(q), bool)
    for j, leg in enumerate(chain.legs):
        ok &= (length[:, j] >= leg.length[0] - _EPS) & (length[:, j] <= leg.length[1] + _EPS)
        if leg.u_cone is not None:
            axis = rots @ np.asarray(leg.u_cone.axis, float)                                    # (K, 3)
            ok &= np.einsum("kc,kc->k", axis, v[:, j]) >= length[:, j] * math.cos(
                math.radians(leg.u_cone.angle)) - _EPS
        if leg.s_cone is not None:
            axis = rot @ np.asarray(leg.s_cone.axis, float)
            ok &= v[:, j] @ axis >= length[:, j] * math.cos(math.radians(leg.s_cone.angle)) - _EPS
    cand = bases[ok]
    diam = np.array([leg.diameter for leg in chain.legs], float)
    keep = _clear(cand, tops, diam, cand, tops, diam, same=True)
    return q[ok][keep], cand[keep]


@dataclasses.dataclass
class InterferenceResult:
    """Per pose: interference-free on the grid, the carriage values found (one array per chain, or
    ``None``), and whether the search stopped at :data:`MAX_NODES` (``undecided``)."""

    free: bool
    carriages: list[np.ndarray] | None
    undecided: bool = False


def interference_free_general(mech: Mechanism, point: Sequence[float] | np.ndarray,
                              orientation: Sequence[float] | np.ndarray = (0.0, 0.0, 0.0), eta_step: float = 0.5,
                              length_step: float = 1.0, max_nodes: int = MAX_NODES) -> InterferenceResult:
    """The module docstring's decision at one pose (``orientation``: angles or a 3x3 matrix from the
    reference frame), with the clearing carriage values when there are some."""
    length_step = check_length_step(length_step)
    rot = platform_rotation(mech, orientation)
    p = np.asarray(point, float).reshape(3)
    cands = [chain_candidates(mech, c, p, rot, eta_step, length_step) for c in range(len(mech.chains))]
    if any(len(q) == 0 for q, _ in cands):
        return InterferenceResult(False, None)
    tops = [p[None, :] + np.array([leg.platform for leg in ch.legs], float) @ rot.T for ch in mech.chains]
    diam = [np.array([leg.diameter for leg in ch.legs], float) for ch in mech.chains]
    order = sorted(range(len(mech.chains)), key=lambda c: len(cands[c][0]))
    memo: dict[tuple[int, int, int], np.ndarray] = {}

    def compat(c: int, o: int, i_o: int) -> np.ndarray:
        """Which candidates of chain ``c`` clear candidate ``i_o`` of chain ``o`` (computed once)."""
        key = (c, o, i_o)
        if key not in memo:
            memo[key] = _clear(cands[c][1], tops[c], diam[c], cands[o][1][i_o:i_o + 1], tops[o], diam[o])[:, 0]
        return memo[key]

    choice: dict[int, int] = {}
    nodes = 0

    def search(depth: int) -> bool:
        nonlocal nodes
        if depth == len(order):
            return True
        c = order[depth]
        ok = np.ones(len(cands[c][0]), bool)
        for o in order[:depth]:
            ok &= compat(c, o, choice[o])
        for i in np.flatnonzero(ok):
            nodes += 1
            if nodes > max_nodes:
                raise _Budget
            choice[c] = int(i)
            if search(depth + 1):
                return True
            del choice[c]
        return False

    try:
        found = search(0)
    except _Budget:
        return InterferenceResult(False, None, undecided=True)
    if not found:
        return InterferenceResult(False, None)
    return InterferenceResult(True, [cands[c][0][choice[c]] for c in range(len(mech.chains))])


class _Budget(Exception):
    """The search passed ``max_nodes``."""


def interference_filter(mech: Mechanism, points: np.ndarray, orientation: Sequence[float] | np.ndarray,
                        eta_step: float = 0.5, length_step: float = 1.0,
                        cancel: CancelToken = None) -> tuple[np.ndarray, int]:
    """``(free (N,), undecided count)`` at ``points`` (N, 3): the interference test of each point
    (``cancel`` is checked between points)."""
    pts = np.asarray(points, float).reshape(-1, 3)
    free = np.zeros(len(pts), bool)
    undecided = 0
    for i, p in enumerate(pts):
        check(cancel)
        r = interference_free_general(mech, p, orientation, eta_step, length_step)
        free[i] = r.free
        undecided += int(r.undecided)
    return free, undecided
