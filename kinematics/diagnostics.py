"""Which leg limit shapes the workspace surface (our documented definition).

The surface layer ``S`` is the set of unreachable voxels face-adjacent to a reachable one (the
layer just outside the workspace's surface). For a sample of ``S`` (all of it, or
``max_samples`` voxels drawn with a fixed seed) and for each chain that cannot reach the voxel's
centre, the chain's redundancy resolution (:mod:`kinematics.redundancy`: the carriage pose of
least violation over the strokes) names the leg and the limit it violates there:

* ``"l_max"`` -- the leg is too long even at the best carriage pose (out of reach);
* ``"l_min"`` -- the leg is too short (the platform is too close to the carriage);
* ``"sampling"`` -- the continuous optimiser finds a feasible carriage pose that the engine's arc
  samples missed (the engine's documented one-sided error; rare, at the very surface).

With the joint options of :mod:`kinematics.joints` a chain that the strokes alone allow but the
cones do not is attributed to ``"u_cone"`` (it passes with the S cones alone), ``"s_cone"`` (it
passes with the U cones alone) or ``"cones"`` (only both together stop it); a voxel whose three
chains pass on their own but whose legs collide in every configuration the witness search tries
counts once as ``"interference"``.

Reported per chain and overall as fractions of the chain failures in the sample, with a sentence
a designer can read ("the surface is set by l_max (71 %) ...": lengthen the legs' stroke upward).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy import ndimage as ndi

from .geometry import platform_points
from .inverse import leg_margin
from .joints import Joints
from .redundancy import _best_carriage, _chain_margins
from .rotation import euler_zyx_deg
from .workspace import WorkspaceResult, chain_masks_at

LIMITS: tuple[str, ...] = ("l_max", "l_min", "u_cone", "s_cone", "cones", "interference", "sampling")


@dataclasses.dataclass
class LimitBinding:
    """Result of :func:`limit_binding` (fractions are of the chain failures counted)."""

    samples: int
    failures: int
    fractions: dict[str, float]
    per_chain: list[dict]
    summary: str

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


_HINTS: dict[str, str] = {
    "l_max": "legs too short to reach: a longer stroke l_s (or a larger l_min) moves it out",
    "l_min": "legs too long at the closest approach: a smaller l_min moves it out",
    "u_cone": "the U joints' cone: a wider theta_U or tilted U mounts (cone axis 'home') move it out",
    "s_cone": "the S joints' cone: a wider theta_S or tilted S mounts move it out",
    "cones": "the U and S cones together",
    "interference": "legs collide: thinner legs or a wider spacing b move it out",
}


def surface_layer(occupancy: np.ndarray) -> np.ndarray:
    """Unreachable voxels face-adjacent to a reachable one (bool, same shape)."""
    occ = np.asarray(occupancy, bool)
    return ndi.binary_dilation(occ) & ~occ


def _violated_limit(design, B: np.ndarray, chain: int) -> str:
    d, eta = _best_carriage(design, B, chain)
    varpi = np.radians(np.array([eta])) + (2.0 * np.pi * chain / 3.0)
    m = _chain_margins(design, B, varpi, np.array([design.r - d]))
    if m[0, 0] >= -1e-9:
        return "sampling"
    # recompute the two lengths at that carriage pose to see which limit is crossed
    c, s = np.cos(varpi[0]), np.sin(varpi[0])
    rho = design.r - d
    lengths = []
    for j, sign in enumerate((1.0, -1.0)):
        lat = sign * design.b / 2.0
        D = np.array([c * rho - s * lat, s * rho + c * lat, 0.0])
        lengths.append(float(np.linalg.norm(B[j] - D)))
    worst = int(np.argmin(leg_margin(design, np.array(lengths))))
    return "l_max" if lengths[worst] > design.l_max else "l_min"


def limit_binding(result: WorkspaceResult, *, voxels: np.ndarray | None = None,
                  max_samples: int | None = 1500, seed: int = 0) -> LimitBinding:
    """Which limit binds at the workspace surface, per chain (module docstring).

    Args:
        voxels: bool mask of the voxels to analyse (default: :func:`surface_layer`).
        max_samples: analyse at most this many of them (fixed-seed sample; ``None``: all).
    """
    design = result.design
    layer = surface_layer(result.occupancy) if voxels is None else np.asarray(voxels, bool)
    idx = np.argwhere(layer)
    if max_samples is not None and len(idx) > max_samples:
        idx = idx[np.random.default_rng(seed).choice(len(idx), size=max_samples, replace=False)]
    pts = np.asarray(result.grid.origin) + result.grid.h * idx
    orientation = result.settings.orientation
    joints = result.settings.joints
    step = result.settings.eta_step
    cones = Joints(theta_u=joints.theta_u, theta_s=joints.theta_s, cone_axis=joints.cone_axis)

    def masks_with(j: Joints) -> np.ndarray:
        return chain_masks_at(design, pts, orientation, step, j) if len(pts) else np.zeros(0, np.uint8)

    plain = masks_with(Joints())
    masks = masks_with(cones) if cones.has_cones else plain
    only_u = masks_with(dataclasses.replace(cones, theta_s=None)) if cones.has_cones else plain
    only_s = masks_with(dataclasses.replace(cones, theta_u=None)) if cones.has_cones else plain
    rot = euler_zyx_deg(*orientation)
    counts = np.zeros((3, len(LIMITS)), int)
    collisions = 0
    for n, (p, mask) in enumerate(zip(pts, masks)):
        if mask == 7:
            collisions += joints.min_distance > 0.0
            continue
        B = platform_points(design, p, rot)
        for i in range(3):
            if (mask >> i) & 1:
                continue
            if (plain[n] >> i) & 1:
                lim = "u_cone" if not (only_u[n] >> i) & 1 else ("s_cone" if not (only_s[n] >> i) & 1 else "cones")
            else:
                lim = _violated_limit(design, B[i], i)
            counts[i, LIMITS.index(lim)] += 1
    total = int(counts.sum()) + collisions
    frac = {lim: (float(counts[:, k].sum()) / total if total else 0.0) for k, lim in enumerate(LIMITS)}
    frac["interference"] = collisions / total if total else 0.0
    per_chain = []
    for i in range(3):
        n = int(counts[i].sum())
        per_chain.append({"chain": i + 1, "failures": n,
                          **{lim: (float(counts[i, k]) / n if n else 0.0) for k, lim in enumerate(LIMITS)}})
    physical = [k for k in LIMITS if k != "sampling"]
    if total and sum(frac[k] for k in physical) == 0.0:
        summary = "every chain failure in the sample is within the arc-sampling error (eta_step)"
    elif total:
        main = max(physical, key=lambda k: frac[k])
        hint = _HINTS[main]
        rest = ", ".join(f"{k} {100 * frac[k]:.0f} %" for k in physical if frac[k] > 0.0)
        summary = f"the workspace surface is set by {main} in {100 * frac[main]:.0f} % of the failures ({hint}); {rest}"
    else:
        summary = "no surface layer (empty workspace or no unreachable neighbour)"
    return LimitBinding(samples=int(len(pts)), failures=total, fractions=frac, per_chain=per_chain, summary=summary)
