"""Route ``POST /ik``: inverse kinematics of one pose (redundancy resolved, or carriages by hand)."""

from __future__ import annotations

from typing import Any

from starlette.concurrency import run_in_threadpool

from paraspace.kinematics.serialize import jsonable

from .context import api_router
from .errors import FieldError, call_core
from .models import IkRequest

router = api_router()


@router.post("/ik", summary="Inverse kinematics of one pose")
async def ik(req: IkRequest) -> dict[str, Any]:  # ~1 ms of numpy: on the event loop, never queued
    # behind the thread pool that heavy requests may fill
    """Redundancy resolved automatically (no ``d``/``eta``) or with hand-set carriages."""
    from paraspace.kinematics.redundancy import inverse_kinematics, resolve_redundancy

    design, pose = req.design.build(), req.pose.build()
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
