"""Route ``POST /ik``: inverse kinematics of one pose (redundancy resolved, or carriages by hand)."""

from __future__ import annotations

from typing import Any

from starlette.concurrency import run_in_threadpool

from paraspace.kinematics.serialize import jsonable

from .context import api_router
from .errors import FieldError, call_core
from .models import IkRequest, mechanism_or_design

router = api_router()


@router.post("/ik", summary="Inverse kinematics of one pose")
async def ik(req: IkRequest) -> dict[str, Any]:  # ~1 ms of numpy: on the event loop, never queued
    # behind the thread pool that heavy requests may fill
    """Redundancy resolved automatically (no ``d``/``eta``) or with hand-set carriages."""
    from paraspace.kinematics.redundancy import inverse_kinematics, resolve_redundancy

    pose = req.pose.build()
    mech, found = mechanism_or_design(req)
    if found is None:
        return await run_in_threadpool(_ik_general, req, mech, pose)
    design = found
    if (req.d is None) != (req.eta is None):
        missing = "eta" if req.eta is None else "d"
        raise FieldError(missing, f"{missing} is required when {'d' if missing == 'eta' else 'eta'} is "
                                  f"given: set both carriages d_1..d_3 and eta_1..eta_3, or neither")
    joints = req.joints.build()
    if req.d is None:
        run = lambda: resolve_redundancy(design, pose, joints)  # noqa: E731
    else:
        d, eta = req.d, req.eta
        assert eta is not None  # both carriages or neither (checked above)
        run = lambda: call_core("carriage", lambda: inverse_kinematics(design, pose, d, eta, joints))  # noqa: E731
    # with joint options the engine's compiled witness search runs: off the event loop
    res = run() if joints.is_default else await run_in_threadpool(run)
    return jsonable({"design": design.to_dict(), "pose": pose.to_dict(), **res.to_dict()})


def _ik_general(req: IkRequest, mech: Any, pose: Any) -> dict[str, Any]:
    """A general mechanism: per chain the carriage values of largest smallest length margin and the
    Jacobians there (kinematics/mechanism_workspace.py, mechanism_jacobian.py)."""
    from paraspace.kinematics.mechanism_jacobian import mechanism_jacobians
    from paraspace.kinematics.mechanism_workspace import mechanism_ik

    for name in ("d", "eta", "joints"):
        if name in req.model_fields_set:
            raise FieldError(name, f"{name}: only for the paper's mechanism (a description carries its own "
                                   f"cones; its carriage values are resolved)")
    assert req.mechanism is not None
    angles = (pose.psi, pose.theta, pose.phi)
    step = req.mechanism.length_step
    chains = call_core("mechanism", lambda: mechanism_ik(mech, pose.position, angles, length_step=step))
    jac = mechanism_jacobians(mech, pose.position, angles, [c.q for c in chains])
    return jsonable({"mechanism": mech.to_dict(), "pose": pose.to_dict(),
                     "feasible": all(c.feasible for c in chains), "chains": [c.to_dict() for c in chains],
                     "condition_number": jac.condition_number})
