"""Route ``POST /sweep``: a 1-D or 2-D parameter study (a job), each point a workspace."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
from fastapi import Request
from fastapi.responses import JSONResponse
from starlette.concurrency import run_in_threadpool

from paraspace.kinematics.design import PARAMS, Design
from paraspace.kinematics.serialize import jsonable

from ..jobs import Job
from ..limits import orientation_samples, workspace_voxels
from .context import WAIT_QUERY, ApiContext, ApiResult, Ctx, api_router
from .errors import ApiError, FieldError, call_core
from .models import SweepRequest, study_settings

router = api_router()


@router.post("/sweep", status_code=202, summary="Start a 1-D or 2-D parameter study job",
             responses={200: {"description": "finished within `wait`"}, 202: {"description": "job accepted"}})
async def sweep(req: SweepRequest, request: Request, ctx: Ctx, wait: float = WAIT_QUERY) -> JSONResponse:
    """Each point is ``kinematics.sweep.evaluate_design`` of the design with the swept
    parameter(s) replaced; 2-D when ``y`` is given."""
    job, cached = await run_in_threadpool(_start_sweep, ctx, req, request)
    return await ctx.job_response(job, wait, cached)


def _start_sweep(ctx: ApiContext, req: SweepRequest, request: Request) -> tuple[Job, bool]:
    from paraspace.kinematics import sweep as sw

    limits = ctx.limits
    design = req.design.build()
    settings, ori = study_settings(req.settings, req.orientation)
    axes = [("x", req.x)] + ([("y", req.y)] if req.y is not None else [])
    if len(axes) == 2 and req.x.param == req.y.param:  # type: ignore[union-attr]
        raise FieldError("y.param", f"y.param = {req.y.param!r} is invalid: "  # type: ignore[union-attr]
                                    f"valid values any design parameter other than x.param")
    vals: list[list[float]] = []
    for name, ax in axes:
        if (ax.values is None) == (ax.n is None):
            raise FieldError(name, f"{name}: give exactly one of values (a list) or n (a count); "
                                   f"n valid range [1, 10000]")
        spec = PARAMS[ax.param]
        if ax.values is None:
            assert ax.n is not None  # exactly one of values and n (checked above)
            vs = [float(v) for v in sw.study_values(ax.param, ax.n)]
        else:
            vs = [float(v) for v in ax.values]
        for i, v in enumerate(vs):
            if not (spec.model_min <= v <= spec.model_max):
                raise FieldError(f"{name}.values[{i}]", f"{ax.param} = {v!r} is invalid: valid range "
                                                        f"[{spec.model_min:g}, {spec.model_max:g}]")
        vals.append(vs)
    n_points = int(np.prod([len(v) for v in vals]))
    if n_points > limits.max_sweep_points:
        raise ApiError(413, f"sweep of {n_points} points exceeds the limit max_sweep_points = "
                            f"{limits.max_sweep_points}")
    key = (design.key(), settings.key(), None if ori is None else ori.key(),
           tuple((ax.param, tuple(v)) for (_, ax), v in zip(axes, vals)))
    cached = ctx.caches["sweep"].get(key) is not None
    if not cached:
        ctx.quota_check(request)
        total = 0
        n_ori = 0
        points = _grid_points(design, [ax.param for _, ax in axes], vals, [n for n, _ in axes])
        with ctx.prechecks():
            for i, d in enumerate(points):
                ctx.grid_check(d, settings, point=i)  # each point obeys the workspace limit
        for d in points:
            total += workspace_voxels(d, settings, analytic=True)
            if ori is not None:
                n_ori = max(n_ori, call_core("orientation", functools.partial(orientation_samples, d, ori)))
        if total > limits.max_sweep_voxels:
            raise ApiError(413, f"sweep of {total} voxels in all (analytical reach boxes) exceeds the limit "
                                f"max_sweep_voxels = {limits.max_sweep_voxels}: use a larger voxel "
                                f"(now {settings.voxel:g}) or fewer points")
        if n_ori > limits.max_orientation_samples:
            raise ApiError(413, f"orientation part of {n_ori} samples per point exceeds the limit "
                                f"max_orientation_samples = {limits.max_orientation_samples}")
    sweep_cache = ctx.sweep_cache

    def compute(progress: Any, cancel: Any) -> ApiResult:
        if len(axes) == 1:
            rows = sw.sweep_1d(design, req.x.param, vals[0], settings, orientation=ori,
                               progress=progress, cancel=cancel, cache=sweep_cache)
            payload = {"mode": "1d", "param": req.x.param, "values": vals[0], "points": rows}
        else:
            out = sw.sweep_2d(design, req.x.param, vals[0], req.y.param, vals[1],  # type: ignore[union-attr]
                              settings, orientation=ori, progress=progress, cancel=cancel, cache=sweep_cache)
            payload = {"mode": "2d", "param_x": req.x.param, "values_x": vals[0],
                       "param_y": req.y.param, "values_y": vals[1], **dict(out)}  # type: ignore[union-attr]
        return ApiResult(raw=None, payload=jsonable(payload))

    return ctx.submit(request, "sweep", key, compute), cached


def _grid_points(design: Design, params: list[str], vals: list[list[float]], names: list[str]) -> list[Design]:
    """Designs of a sweep's grid (validated: a bad combination names the axis and index)."""
    out: list[Design] = []
    if len(params) == 1:
        for i, v in enumerate(vals[0]):
            out.append(call_core(f"{names[0]}.values[{i}]", functools.partial(design.replace, **{params[0]: v})))
        return out
    for i, vx in enumerate(vals[0]):
        for j, vy in enumerate(vals[1]):
            out.append(call_core(f"{names[0]}.values[{i}]/{names[1]}.values[{j}]",
                                 functools.partial(design.replace, **{params[0]: vx, params[1]: vy})))
    return out
