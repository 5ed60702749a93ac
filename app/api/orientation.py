"""Route ``POST /orientation``: the orientation workspace along the z, y' and x lines (a job)."""

from __future__ import annotations

from typing import Any

from fastapi import Request
from fastapi.responses import JSONResponse
from starlette.concurrency import run_in_threadpool

from paraspace.kinematics.serialize import jsonable

from ..jobs import Job
from ..limits import orientation_samples
from .context import WAIT_QUERY, ApiContext, ApiResult, Ctx, api_router
from .errors import ApiError, call_core
from .models import OrientationRequest, mechanism_or_design

router = api_router()


@router.post("/orientation", status_code=202, summary="Start an orientation-workspace job",
             responses={200: {"description": "finished within `wait`"}, 202: {"description": "job accepted"}})
async def orientation(req: OrientationRequest, request: Request, ctx: Ctx, wait: float = WAIT_QUERY) -> JSONResponse:
    """Orientation capability along the z, y' and x lines; the result has TI_1, TI_2, the Δ's
    and the nine regions."""
    job, cached = await run_in_threadpool(_start_orientation, ctx, req, request)
    return await ctx.job_response(job, wait, cached)


def _start_orientation(ctx: ApiContext, req: OrientationRequest, request: Request) -> tuple[Job, bool]:
    from paraspace.kinematics.orientation import orientation_workspace

    limits = ctx.limits
    settings = req.settings.build()
    mech, design = mechanism_or_design(req)
    if design is None:
        return _start_general(ctx, req, request, mech, settings)
    key = (design.key(), settings.key())
    cached = ctx.caches["orientation"].get(key) is not None
    if not cached:
        ctx.quota_check(request)
        n = call_core("orientation", lambda: orientation_samples(design, settings))
        if n > limits.max_orientation_samples:
            raise ApiError(413, f"orientation request of {n} samples exceeds the limit "
                                f"max_orientation_samples = {limits.max_orientation_samples}: use larger "
                                f"angle_step / position_step")

    def compute(progress: Any, cancel: Any) -> ApiResult:
        res = orientation_workspace(design, settings, progress, cancel)
        return ApiResult(raw=None, payload=jsonable(res.to_dict(include_grids=False)))

    return ctx.submit(request, "orientation", key, compute), cached


def _start_general(ctx: ApiContext, req: OrientationRequest, request: Request, mech: Any,
                   settings: Any) -> tuple[Job, bool]:
    """A general mechanism's scans (kinematics/mechanism_orientation.py), their size checked first."""
    import json

    from paraspace.kinematics.mechanism_orientation import mechanism_orientation_workspace, scan_plan

    from .workspace import MAX_API_CARRIAGE_SAMPLES

    assert req.mechanism is not None
    length_step = req.mechanism.length_step
    key = ("mechanism", json.dumps(mech.to_dict(), sort_keys=True), settings.key(), length_step)
    cached = ctx.caches["orientation"].get(key) is not None
    if not cached:
        ctx.quota_check(request)
        n, samples = call_core("settings", lambda: scan_plan(mech, settings, length_step))
        if max(samples) > MAX_API_CARRIAGE_SAMPLES:
            raise ApiError(413, f"{max(samples):,} carriage samples in a chain: at most "
                                f"{MAX_API_CARRIAGE_SAMPLES:,} per request (a larger settings.eta_step or "
                                f"mechanism.length_step)")
        if n > ctx.limits.max_orientation_samples:
            raise ApiError(413, f"orientation request of {n} samples exceeds the limit "
                                f"max_orientation_samples = {ctx.limits.max_orientation_samples}: use larger "
                                f"angle_step / position_step")

    def compute(progress: Any, cancel: Any) -> ApiResult:
        res = mechanism_orientation_workspace(mech, settings, length_step, progress, cancel)
        return ApiResult(raw=None, payload=jsonable(res.to_dict(include_grids=False)))

    return ctx.submit(request, "orientation", key, compute), cached
