"""Tasks on any mechanism description: does a general mechanism hold a region (with an orientation
set) or reach a pose list, by what margin, and which chain fails first?

The task, its sampling and the answers are those of :mod:`kinematics.task` (its module docstring
defines them; the region lattice, the signed distance ``s_R`` and eq. (K2) are shared), with the
general engine's test:

* A sample pose ``(P, O_m)`` is *reachable* when
  :func:`kinematics.mechanism_workspace.reachable_general` accepts it: every chain has carriage
  values (exact in its longest prismatic joint, the others sampled every ``eta_step`` degrees and
  ``length_step``) with every leg in its length range and inside the description's cones; the
  rotation is ``Rot(reference) R_m`` (:func:`~kinematics.mechanism_workspace.platform_rotation`).
  A region's sample point is reachable when it is at every orientation sample.
* ``fraction``, ``contained`` and the region's ``margin``

      m = min { s_R(q) : q not in W }                                                    (K2)

  over the lattice continued ``margin_range`` outward (``margin_saturated`` when no unreachable
  lattice point lies that near), exactly as :func:`kinematics.task.region_task`.
* ``binding`` of a region: at the lattice point ``q*`` of (K2), at the first orientation sample it
  fails, the chains whose own test fails there (``chains``; the first is ``chain``). Which leg limit
  binds is not computed for a general mechanism (``limit`` is ``None``).
* A pose list: each pose's ``reachable`` is the engine's; its carriage values are
  :func:`~kinematics.mechanism_workspace.mechanism_ik`'s per chain (the values of largest smallest
  length margin ``min_j min(l_j - lmin_j, lmax_j - l_j)``, chosen pose by pose: no continuity of the
  carriages along the list is sought and no jump reported), with the leg lengths there; the pose's
  ``margin`` is the smallest chain margin (negative: the least length violation the carriages can
  reach), the list's ``margin`` the smallest over the poses and ``binding`` the chain that attains
  it at the worst pose. Cones enter ``reachable``, not the margin.
* ``certified`` is ``"undecided"``: the task's certificate (K1) is the paper model's.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from .design import ParameterError
from .mechanism import Mechanism
from .mechanism_workspace import check_length_step, mechanism_ik, reachable_general
from .progress import CancelToken, ProgressFn, Reporter, check
from .rotation import euler_zyx_deg
from .task import (
    OrientationSet,
    PoseList,
    Region,
    TaskResult,
    TaskSettings,
    _rot_of,
    region_lattice,
)

__all__ = ["mechanism_region_task", "mechanism_pose_list_task", "evaluate_mechanism_task", "failing_chains"]

#: the defaults (frozen): one fixed orientation (0, 0, 0), the task's default sampling
_FIXED = OrientationSet()
_SETTINGS = TaskSettings()


def _check_settings(settings: TaskSettings) -> None:
    if settings.joints.theta_u is not None or settings.joints.theta_s is not None or settings.joints.min_distance > 0:
        raise ParameterError("joints", settings.joints.to_dict(),
                             "none for a mechanism description: its legs carry their own u_cone/s_cone")


def failing_chains(mech: Mechanism, point: Sequence[float] | np.ndarray, rotation: np.ndarray,
                   eta_step: float = 0.5, length_step: float = 1.0) -> list[int]:
    """The chains whose own test (each chain alone, as in :func:`reachable_general`) fails at
    ``point`` with the platform rotation ``rotation`` (a 3x3 matrix from the reference frame)."""
    out = []
    p = np.asarray(point, float).reshape(1, 3)
    for c, chain in enumerate(mech.chains):
        alone = dataclasses.replace(mech, chains=(chain,))
        if not reachable_general(alone, p, rotation, eta_step, length_step)[0]:
            out.append(c)
    return out


def mechanism_region_task(mech: Mechanism, region: Region, orientations: OrientationSet = _FIXED,
                          settings: TaskSettings = _SETTINGS, length_step: float = 1.0,
                          progress: ProgressFn | None = None, cancel: CancelToken = None) -> TaskResult:
    """The answers of the module docstring for a region with an orientation set."""
    _check_settings(settings)
    length_step = check_length_step(length_step)
    rep = Reporter(progress)
    t0 = time.perf_counter()
    rots, half, pts, sdf, inside, _ = region_lattice(region, orientations, settings)
    ok = np.ones(len(pts), bool)
    failed_at = np.full(len(pts), -1, np.int64)
    for m in range(rots.shape[0]):
        check(cancel)
        live = np.flatnonzero(ok)
        if not live.size:
            break
        got = reachable_general(mech, pts[live], rots[m], settings.eta_step, length_step)
        ok[live[~got]] = False
        failed_at[live[~got]] = m
        rep((m + 1) / rots.shape[0] * 0.9, f"task: {int(ok.sum()):,} of {len(pts):,} points reachable")
    n_in = int(inside.sum())
    n_ok = int((ok & inside).sum())
    bad = np.flatnonzero(~ok)
    saturated = bad.size == 0
    if saturated:
        margin = settings.margin_range
        ins = np.flatnonzero(inside)
        sample = int(ins[np.argmax(np.abs(pts[ins] - np.asarray(region.center)).sum(axis=1))])
        worst: dict[str, Any] = {"position": pts[sample].tolist(), "orientation": _rot_of(orientations, 0, rots),
                                 "reachable": True}
        binding: dict[str, Any] = {"chain": None, "chains": [], "leg": None, "limit": None,
                                   "message": f"no unreachable point within margin_range = {settings.margin_range:g}"}
    else:
        qi = int(bad[np.argmin(sdf[bad])])
        margin = float(sdf[qi])
        m_q = int(failed_at[qi])
        ins = np.flatnonzero(inside)
        sample = qi if inside[qi] else int(ins[np.argmin(np.linalg.norm(pts[ins] - pts[qi], axis=1))])
        worst = {"position": pts[sample].tolist(), "orientation": _rot_of(orientations, m_q if sample == qi else 0,
                                                                          rots),
                 "reachable": bool(ok[sample]),
                 "at": {"position": pts[qi].tolist(), "orientation": _rot_of(orientations, m_q, rots)}}
        chains = failing_chains(mech, pts[qi], rots[m_q], settings.eta_step, length_step)
        binding = {"chain": chains[0] if chains else None, "chains": chains, "leg": None, "limit": None,
                   "message": (f"chain {', '.join(map(str, chains))} fails first" if chains else
                               "every chain passes alone: the chains' carriage values exist but not together")}
    details = {"region": region.to_dict(), "orientations": orientations.to_dict(), "mechanism": mech.to_dict(),
               "engine": "general", "voxel": settings.voxel, "margin_range": settings.margin_range,
               "length_step": length_step, "margin_saturated": bool(saturated), "sample_points": n_in,
               "reachable_points": n_ok, "lattice_points": int(pts.shape[0]),
               "orientation_samples": int(rots.shape[0]), "volume": region.volume,
               "cell_half_diagonal": float(np.linalg.norm(half))}
    rep(1.0, "task done")
    return TaskResult(kind="region", fraction=n_ok / n_in, contained=n_ok == n_in, certified="undecided",
                      margin=margin, worst=worst, binding=binding, slack={}, details=details,
                      seconds=time.perf_counter() - t0, cells=pts[inside], cells_ok=ok[inside])


def mechanism_pose_list_task(mech: Mechanism, poses: PoseList, settings: TaskSettings = _SETTINGS,
                             length_step: float = 1.0, progress: ProgressFn | None = None,
                             cancel: CancelToken = None) -> TaskResult:
    """The answers of the module docstring for a pose list."""
    _check_settings(settings)
    length_step = check_length_step(length_step)
    rep = Reporter(progress)
    t0 = time.perf_counter()
    rows: list[dict[str, Any]] = []
    for n, pose in enumerate(poses.poses):
        check(cancel)
        rot = euler_zyx_deg(*pose[3:])
        reach = bool(reachable_general(mech, pose[None, :3], rot, settings.eta_step, length_step)[0])
        chains = mechanism_ik(mech, pose[:3], rot, settings.eta_step, length_step)
        margins = [c.margin for c in chains]
        k = int(np.argmin(margins))
        rows.append({"index": n, "pose": pose.tolist(), "reachable": reach, "margin": float(margins[k]),
                     "leg_slack": float(margins[k]), "binding_chain": k, "carriages": [c.q for c in chains],
                     "lengths": [c.lengths for c in chains],
                     "q": [x for c in chains for x in c.lengths] + [x for c in chains for x in c.q],
                     **({} if poses.t is None else {"t": float(poses.t[n])})})
        rep((n + 1) / len(poses), f"task: pose {n + 1}/{len(poses)}")
    pose_margins = np.array([r["margin"] for r in rows])
    w = int(np.argmin(pose_margins))
    n_ok = sum(r["reachable"] for r in rows)
    worst = {"index": w, "pose": rows[w]["pose"], "reachable": rows[w]["reachable"]}
    binding = {"chain": rows[w]["binding_chain"], "chains": [rows[w]["binding_chain"]], "leg": None, "limit": None,
               "message": f"chain {rows[w]['binding_chain']} has the smallest length margin at pose {w}"}
    names = ([f"l_{c}.{j}" for c, j, _ in mech.legs]
             + [f"q_{c}.{m}" for c, chain in enumerate(mech.chains) for m in range(len(chain.carriage))])
    details = {"count": len(rows), "mechanism": mech.to_dict(), "engine": "general", "length_step": length_step,
               "unreachable": [r["index"] for r in rows if not r["reachable"]], "actuator_names": names}
    return TaskResult(kind="poses", fraction=n_ok / len(rows), contained=n_ok == len(rows), certified="undecided",
                      margin=float(pose_margins[w]), worst=worst, binding=binding, slack={}, details=details,
                      seconds=time.perf_counter() - t0, poses=rows, discontinuities=[])


def evaluate_mechanism_task(mech: Mechanism, task: Region | PoseList,
                            orientations: OrientationSet = _FIXED,
                            settings: TaskSettings = _SETTINGS, length_step: float = 1.0,
                            progress: ProgressFn | None = None, cancel: CancelToken = None) -> TaskResult:
    """:func:`mechanism_region_task` or :func:`mechanism_pose_list_task`, by the task's kind."""
    if isinstance(task, PoseList):
        return mechanism_pose_list_task(mech, task, settings, length_step, progress, cancel)
    return mechanism_region_task(mech, task, orientations, settings, length_step, progress, cancel)
