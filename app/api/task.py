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
from .errors import ApiError, FieldError
from .models import TaskRequest, mechanism_or_design

router = api_router()


@router.post("/task", status_code=202, summary="Start a task job (region or pose list)",
             responses={200: {"description": "finished within `wait`"}, 202: {"description": "job accepted"}})
async def task(req: TaskRequest, request: Request, ctx: Ctx, wait: float = WAIT_QUERY) -> JSONResponse:
    """fraction, contained, certified, margin, worst, binding; for a pose list also the poses (reachable,
    the 12 actuator values), the carriage motion and its discontinuities."""
    job, cached = await run_in_threadpool(_start_task, ctx, req, request)
    return await ctx.job_response(job, wait, cached)


def _start_task(ctx: ApiContext, req: TaskRequest, request: Request) -> tuple[Job, bool]:
    from paraspace.kinematics.task import evaluate_task

    _, task, oset, settings = req.build()
    mech, design = mechanism_or_design(req)
    if design is None:
        return _start_general(ctx, req, request, mech, task, oset, settings)
    key = (design.key(), _task_key(task), oset, settings)
    cached = ctx.caches["task"].get(key) is not None
    if not cached:
        ctx.quota_check(request)
        _check_region_size(ctx, task, oset, settings)

    def compute(progress: Any, cancel: Any) -> ApiResult:
        res = evaluate_task(design, task, oset, settings, progress, cancel)
        return ApiResult(raw=None, payload=jsonable(res.to_dict()))

    return ctx.submit(request, "task", key, compute), cached


def _task_key(task: Any) -> Any:
    import hashlib

    from paraspace.kinematics.task import PoseList

    if isinstance(task, PoseList):
        return ("poses", hashlib.sha256(task.poses.tobytes() + (b"" if task.t is None else task.t.tobytes()))
                .hexdigest(), task.t is None)
    return task


def _check_region_size(ctx: ApiContext, task: Any, oset: Any, settings: Any) -> None:
    """413 when a region task's lattice points x orientations exceed ``max_task_samples`` (a pose list is
    bounded by the body limit already)."""
    from paraspace.kinematics.task import PoseList, region_samples

    if isinstance(task, PoseList):
        return
    n = region_samples(task, oset, settings)
    if n > ctx.limits.max_task_samples:
        raise ApiError(413, f"task of {n:,} samples (lattice points x orientations) exceeds the limit "
                            f"max_task_samples = {ctx.limits.max_task_samples:,}: use a coarser voxel, a "
                            f"smaller region or margin_range, or a larger angle_step")


def _start_general(ctx: ApiContext, req: TaskRequest, request: Request, mech: Any, task: Any, oset: Any,
                   settings: Any) -> tuple[Job, bool]:
    """A task on a general mechanism (kinematics/mechanism_task.py), its sizes checked first."""
    import json

    from paraspace.kinematics.design import ParameterError
    from paraspace.kinematics.joints import Joints
    from paraspace.kinematics.mechanism_task import evaluate_mechanism_task
    from paraspace.kinematics.mechanism_workspace import general_plan
    from paraspace.kinematics.workspace import WorkspaceSettings

    from .workspace import MAX_API_CARRIAGE_SAMPLES

    assert req.mechanism is not None
    length_step = req.mechanism.length_step
    if settings.joints != Joints():
        raise FieldError("settings.joints", "settings.joints: none for a mechanism description (its legs carry their "
                                            "own u_cone/s_cone)")
    key = ("mechanism", json.dumps(mech.to_dict(), sort_keys=True), length_step, _task_key(task), oset, settings)
    cached = ctx.caches["task"].get(key) is not None
    if not cached:
        ctx.quota_check(request)
        try:
            _, samples = general_plan(mech, WorkspaceSettings(voxel=40.0, eta_step=settings.eta_step), length_step)
        except ParameterError as exc:
            raise FieldError(f"settings.{exc.field}", str(exc)) from None
        if max(samples) > MAX_API_CARRIAGE_SAMPLES:
            raise ApiError(413, f"{max(samples):,} carriage samples in a chain: at most {MAX_API_CARRIAGE_SAMPLES:,} "
                                "per request (a larger settings.eta_step or mechanism.length_step)")
        _check_region_size(ctx, task, oset, settings)

    def compute(progress: Any, cancel: Any) -> ApiResult:
        res = evaluate_mechanism_task(mech, task, oset, settings, length_step, progress, cancel)
        return ApiResult(raw=None, payload=jsonable(res.to_dict()))

    return ctx.submit(request, "task", key, compute), cached
