"""Route ``POST /task``: does a design hold a region (with an orientation set) or follow a pose list,
by what margin, and which limit binds (``kinematics.task``; a job like the others)."""

from __future__ import annotations

from typing import Any

from fastapi import Request
from fastapi.responses import JSONResponse
from starlette.concurrency import run_in_threadpool

from paraspace.kinematics.serialize import jsonable

from ..jobs import Job
from .context import WAIT_QUERY, ApiContext, ApiResult, Ctx, api_router
from .errors import ApiError
from .models import TaskRequest

router = api_router()


@router.post("/task", status_code=202, summary="Start a task job (region or pose list)",
             responses={200: {"description": "finished within `wait`"}, 202: {"description": "job accepted"}})
async def task(req: TaskRequest, request: Request, ctx: Ctx, wait: float = WAIT_QUERY) -> JSONResponse:
    """fraction, contained, certified, margin, worst, binding; for a pose list also the poses (reachable,
    the 12 actuator values), the carriage motion and its discontinuities."""
    job, cached = await run_in_threadpool(_start_task, ctx, req, request)
    return await ctx.job_response(job, wait, cached)


def _start_task(ctx: ApiContext, req: TaskRequest, request: Request) -> tuple[Job, bool]:
    from paraspace.kinematics.task import PoseList, evaluate_task, region_samples

    design, task, oset, settings = req.build()
    import hashlib

    tkey = (("poses", hashlib.sha256(task.poses.tobytes() + (b"" if task.t is None else task.t.tobytes())).hexdigest(),
             task.t is None) if isinstance(task, PoseList) else task)
    key = (design.key(), tkey, oset, settings)
    cached = ctx.caches["task"].get(key) is not None
    if not cached:
        ctx.quota_check(request)
        if not isinstance(task, PoseList):
            n = region_samples(task, oset, settings)
            if n > ctx.limits.max_task_samples:
                raise ApiError(413, f"task of {n:,} samples (lattice points x orientations) exceeds the limit "
                                    f"max_task_samples = {ctx.limits.max_task_samples:,}: use a coarser voxel, a "
                                    f"smaller region or margin_range, or a larger angle_step")

    def compute(progress: Any, cancel: Any) -> ApiResult:
        res = evaluate_task(design, task, oset, settings, progress, cancel)
        return ApiResult(raw=None, payload=jsonable(res.to_dict()))

    return ctx.submit(request, "task", key, compute), cached
