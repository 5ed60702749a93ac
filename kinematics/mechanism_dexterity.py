"""Dexterity of any :class:`~kinematics.mechanism.Mechanism`: the local conditioning ``1/kappa`` as a
field over a computed workspace, its GCI and the well-conditioned workspace (the quantities of
:mod:`kinematics.dexterity` for a description).

**Definition.** At the centre ``P`` of every reachable voxel of a workspace computed at the constant
orientation ``(psi, theta, phi)``, with ``q*(P)`` the carriage values of the redundancy resolution
(:func:`kinematics.mechanism_workspace.mechanism_ik`: per chain the values of largest smallest length
margin) and ``J = J_h^{-1} J_q`` of :mod:`kinematics.mechanism_jacobian` ((21), ``J_h`` homogenised
by the mean platform-joint radius ``L``)

    1/kappa(P) = sigma_min(J(P, R, q*(P))) / sigma_max(J(P, R, q*(P)))      (0 where J_h is singular)   (X1)
    GCI = mean of (X1) over the reachable voxels,  well conditioned: 1/kappa >= kappa_min.            (X2)

Only the resolved carriage (``mode="resolved"``) is computed for a general mechanism (``"best"`` is
refused by name). The paper's mechanism (a result computed by the paper's engine,
``engine == "paper"``) is routed to :func:`kinematics.dexterity.dexterity_field`: the paper path's
numbers exactly (its ``L = a/2`` and its compiled resolver).

Cost: one :func:`~kinematics.mechanism_workspace.mechanism_ik` (numpy, ``K x 401`` margins and two
zooms per chain, ``K`` the chain's carriage samples) and one ``6 x 6`` solve and SVD per voxel; use
coarse voxels for mechanisms with revolute carriage joints.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

import numpy as np

from .design import ParameterError
from .dexterity import DexterityField, check_kappa_min, dexterity_field
from .mechanism import Mechanism
from .mechanism_jacobian import mechanism_jacobians
from .mechanism_workspace import MechanismWorkspaceResult, mechanism_ik
from .progress import CancelToken, ProgressFn, Reporter, check


def inverse_condition_at(mech: Mechanism, position: Sequence[float] | np.ndarray, orientation: Sequence[float],
                         eta_step: float = 0.5, length_step: float = 1.0) -> float:
    """(X1) at one position: ``1/kappa`` at the resolved carriage (0 where ``J_h`` is singular)."""
    chains = mechanism_ik(mech, position, orientation, eta_step, length_step)
    cond = mechanism_jacobians(mech, position, orientation, [c.q for c in chains]).condition_number
    return 0.0 if not math.isfinite(cond) or cond <= 0.0 else 1.0 / cond


def mechanism_dexterity_field(result: MechanismWorkspaceResult, kappa_min: float = 0.1, mode: str = "resolved",
                              progress: ProgressFn | None = None, cancel: CancelToken = None) -> DexterityField:
    """(X1)-(X2) over the reachable voxels of ``result`` (a workspace of a description, at its
    orientation); the paper's engine's results run :func:`kinematics.dexterity.dexterity_field`."""
    if result.engine == "paper":
        return dexterity_field(result, kappa_min, mode, progress=progress, cancel=cancel)
    if mode != "resolved":
        raise ParameterError("dexterity_mode", mode, "'resolved' for a general mechanism ('best' only for the "
                             "paper's mechanism)")
    kappa_min = check_kappa_min(kappa_min)
    mech = result.mechanism
    if mech is None:
        raise ParameterError("result", "workspace", "a workspace of a mechanism description")
    rep = Reporter(progress)
    t0 = time.perf_counter()
    occ = np.asarray(result.occupancy, bool)
    pts = result.grid.points()[occ]
    orientation = tuple(float(v) for v in result.settings.orientation)
    vals = np.zeros(pts.shape[0])
    for i, p in enumerate(pts):
        if i % 64 == 0:
            check(cancel)
            rep(i / max(pts.shape[0], 1), "dexterity")
        vals[i] = inverse_condition_at(mech, p, orientation, result.settings.eta_step, result.length_step)
    field = np.full(occ.shape, np.nan)
    field[occ] = vals
    well = np.zeros(occ.shape, bool)
    well[occ] = vals >= kappa_min
    vv = result.grid.voxel_volume
    n = vals.size
    rep(1.0, "done")
    return DexterityField(
        inverse_condition=field, gci=float(vals.mean()) if n else float("nan"), kappa_min=kappa_min,
        well_conditioned=well, well_conditioned_volume=float(well.sum()) * vv, volume=n * vv, mode=mode,
        seconds=time.perf_counter() - t0, minimum=float(vals.min()) if n else float("nan"),
        maximum=float(vals.max()) if n else float("nan"))
