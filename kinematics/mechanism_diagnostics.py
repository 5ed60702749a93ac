"""Which limit shapes a general mechanism's workspace surface, per chain (the paper model's is
:mod:`kinematics.diagnostics`; the same surface layer, limits and report).

The surface layer ``S`` is the set of unreachable voxels face-adjacent to a reachable one
(:func:`kinematics.diagnostics.surface_layer`). For a sample of ``S`` (all of it, or
``max_samples`` voxels drawn with a fixed seed) every chain is tested ALONE at the voxel's centre
by the general engine (:func:`kinematics.mechanism_workspace.reachable_general` on the description
reduced to that chain): first without its cones, then with them. Each chain that fails counts one
failure, attributed to

* ``"l_max"`` / ``"l_min"`` -- it fails without cones: at the carriage values of largest smallest
  length margin (:func:`~kinematics.mechanism_workspace.mechanism_ik`, the chain's redundancy
  resolution) the leg of smallest margin is longer than ``l_max`` (out of reach) or shorter than
  ``l_min``;
* ``"sampling"`` -- it fails without cones, yet those carriage values keep every leg in range (a
  feasible set narrower than the engine's samples of its sampled joints);
* ``"u_cone"`` / ``"s_cone"`` / ``"cones"`` -- it passes without cones but not with them: with the S
  cones alone it passes (``"u_cone"``), with the U cones alone (``"s_cone"``), else both together;
* ``"interference"`` -- every chain passes alone (the chains are independent) but the legs collide
  (a leg ``diameter``, :mod:`kinematics.mechanism_interference`): the voxel counts once.

Reported overall and per chain as fractions of the failures counted, with a sentence.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .diagnostics import LIMITS, LimitBinding, surface_layer
from .mechanism import Chain, Mechanism
from .mechanism_workspace import MechanismWorkspaceResult, mechanism_ik, platform_rotation, reachable_general

__all__ = ["mechanism_limit_binding", "chain_limits"]

_HINTS: dict[str, str] = {
    "l_max": "legs too short to reach: longer legs or longer strokes move it out",
    "l_min": "legs too long at the closest approach: a smaller l_min moves it out",
    "u_cone": "the U joints' cones: wider u_cone angles or other axes move it out",
    "s_cone": "the S joints' cones: wider s_cone angles or other axes move it out",
    "cones": "the U and S cones together",
    "interference": "legs collide: thinner legs or wider joint spacings move it out",
    "sampling": "the engine's samples of the sampled joints (a finer eta_step or length_step)",
}


def _strip(chain: Chain, u: bool, s: bool) -> Chain:
    legs = tuple(dataclasses.replace(leg, diameter=0.0, u_cone=None if u else leg.u_cone,
                                     s_cone=None if s else leg.s_cone) for leg in chain.legs)
    return dataclasses.replace(chain, legs=legs)


def chain_limits(mech: Mechanism, points: np.ndarray, orientation: tuple[float, float, float] = (0.0, 0.0, 0.0),
                 eta_step: float = 0.5, length_step: float = 1.0) -> list[list[str]]:
    """Per point ``(N, 3)``: the limit of each failing chain (module docstring) as ``"c:limit"``
    entries in chain order, or ``["interference"]`` when every chain passes alone and the point is
    unreachable, or ``[]`` when it is reachable."""
    pts = np.asarray(points, float).reshape(-1, 3)
    rot = platform_rotation(mech, orientation)
    whole = reachable_general(mech, pts, orientation, eta_step, length_step) if len(pts) else np.zeros(0, bool)
    tests = {}
    for c, chain in enumerate(mech.chains):
        for key, (u, s) in {"plain": (True, True), "cones": (False, False), "no_s": (False, True),
                            "no_u": (True, False)}.items():
            alone = dataclasses.replace(mech, chains=(_strip(chain, u, s),))
            tests[(c, key)] = reachable_general(alone, pts, orientation, eta_step, length_step)
    out: list[list[str]] = []
    for n, p in enumerate(pts):
        if whole[n]:
            out.append([])
            continue
        row = []
        for c, chain in enumerate(mech.chains):
            if tests[(c, "cones")][n]:
                continue
            if tests[(c, "plain")][n]:
                lim = "u_cone" if tests[(c, "no_u")][n] else ("s_cone" if tests[(c, "no_s")][n] else "cones")
            else:
                alone = dataclasses.replace(mech, chains=(_strip(chain, True, True),))
                ik = mechanism_ik(alone, p, rot, eta_step, length_step)[0]
                if ik.margin >= -1e-9:
                    lim = "sampling"
                else:
                    marg = [min(x - leg.length[0], leg.length[1] - x) for x, leg in zip(ik.lengths, chain.legs)]
                    j = int(np.argmin(marg))
                    lim = "l_max" if ik.lengths[j] > chain.legs[j].length[1] else "l_min"
            row.append(f"{c}:{lim}")
        out.append(row or ["interference"])
    return out


def mechanism_limit_binding(result: MechanismWorkspaceResult, *, voxels: np.ndarray | None = None,
                            max_samples: int | None = 500, seed: int = 0) -> LimitBinding:
    """Which limit binds at the surface of a general mechanism's workspace, per chain (module docstring).

    Args:
        voxels: bool mask of the voxels to analyse (default: the surface layer).
        max_samples: analyse at most this many of them (fixed-seed sample; ``None``: all).
    """
    mech = result.mechanism
    assert mech is not None
    layer = surface_layer(result.occupancy) if voxels is None else np.asarray(voxels, bool)
    idx = np.argwhere(layer)
    if max_samples is not None and len(idx) > max_samples:
        idx = idx[np.random.default_rng(seed).choice(len(idx), size=max_samples, replace=False)]
    pts = np.asarray(result.grid.origin) + result.grid.h * idx
    rows = chain_limits(mech, pts, result.settings.orientation, result.settings.eta_step, result.length_step)
    counts = np.zeros((len(mech.chains), len(LIMITS)), int)
    collisions = 0
    for row in rows:
        for entry in row:
            if entry == "interference":
                collisions += 1
                continue
            chain, lim = entry.split(":")
            counts[int(chain), LIMITS.index(lim)] += 1
    total = int(counts.sum()) + collisions
    frac = {lim: (float(counts[:, k].sum()) / total if total else 0.0) for k, lim in enumerate(LIMITS)}
    frac["interference"] = collisions / total if total else 0.0
    per_chain = []
    for c in range(len(mech.chains)):
        n = int(counts[c].sum())
        per_chain.append({"chain": c, "failures": n,
                          "fractions": {lim: (float(counts[c, k]) / n if n else 0.0) for k, lim in enumerate(LIMITS)}})
    top = sorted(((v, k) for k, v in frac.items() if v > 0), reverse=True)
    summary = ("no unreachable surface voxel analysed" if not top else
               "the surface is set by " + ", ".join(f"{k} ({100 * v:.0f} %)" for v, k in top)
               + f": {_HINTS[top[0][1]]}")
    return LimitBinding(samples=len(pts), failures=total, fractions=frac, per_chain=per_chain, summary=summary)
