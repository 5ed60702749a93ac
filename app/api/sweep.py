"""Route ``POST /sweep``: a 1-D or 2-D parameter study (a job), each point a workspace."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
from fastapi import Request
from fastapi.responses import JSONResponse
from starlette.concurrency import run_in_threadpool

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.joints import Joints
from paraspace.kinematics.presets import PresetDesign
from paraspace.kinematics.serialize import jsonable

from ..jobs import Job
from ..limits import orientation_samples, workspace_voxels
from .context import WAIT_QUERY, ApiContext, ApiResult, Ctx, api_router
from .errors import ApiError, FieldError, call_core
from .models import SweepRequest, refuse_design_with_mechanism, study_settings

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
    design, length_step = _study_design(req)
    general = isinstance(design, PresetDesign)
    settings, ori = study_settings(req.settings, req.orientation)
    if general and ori is not None:
        raise FieldError("orientation", "orientation: not with a general mechanism (TI_1/TI_2 exist for the "
                                        "paper's model only)")
    if general and settings.joints != Joints():
        raise FieldError("settings.joints", "settings.joints: none for a general mechanism (its legs carry their "
                                            "own u_cone/s_cone)")
    axes = [("x", req.x)] + ([("y", req.y)] if req.y is not None else [])
    if len(axes) == 2 and req.x.param == req.y.param:  # type: ignore[union-attr]
        raise FieldError("y.param", f"y.param = {req.y.param!r} is invalid: "  # type: ignore[union-attr]
                                    f"valid values any design parameter other than x.param")
    vals: list[list[float]] = []
    for name, ax in axes:
        if (ax.values is None) == (ax.n is None):
            raise FieldError(name, f"{name}: give exactly one of values (a list) or n (a count); "
                                   f"n valid range [1, 10000]")
        try:
            lo, hi = sw.param_range(design, ax.param, f"{name}.param")
        except ParameterError as exc:
            raise FieldError(f"{name}.param", str(exc)) from None
        if ax.values is None:
            assert ax.n is not None  # exactly one of values and n (checked above)
            vs = [float(v) for v in sw.study_values(ax.param, ax.n, design)]
        else:
            vs = [float(v) for v in ax.values]
        for i, v in enumerate(vs):
            if not (lo <= v <= hi):
                raise FieldError(f"{name}.values[{i}]", f"{ax.param} = {v!r} is invalid: valid range "
                                                        f"[{lo:g}, {hi:g}]")
        vals.append(vs)
    n_points = int(np.prod([len(v) for v in vals]))
    if n_points > limits.max_sweep_points:
        raise ApiError(413, f"sweep of {n_points} points exceeds the limit max_sweep_points = "
                            f"{limits.max_sweep_points}")
    key = (design.key(), settings.key(), None if ori is None else ori.key(),
           tuple((ax.param, tuple(v)) for (_, ax), v in zip(axes, vals)), length_step)
    cached = ctx.caches["sweep"].get(key) is not None
    if not cached and general:
        ctx.quota_check(request)
        points = _grid_points(design, [ax.param for _, ax in axes], vals, [n for n, _ in axes])
        with ctx.prechecks():
            total = sum(_general_point_voxels(ctx, d, settings, length_step, i) for i, d in enumerate(points))
        if total > limits.max_sweep_voxels:
            raise ApiError(413, f"sweep of {total} voxels in all exceeds the limit max_sweep_voxels = "
                                f"{limits.max_sweep_voxels}: use a larger voxel (now {settings.voxel:g}) or fewer "
                                f"points")
    elif not cached:
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
        more: dict[str, Any] = {"length_step": length_step} if general else {}
        if len(axes) == 1:
            rows = sw.sweep_1d(design, req.x.param, vals[0], settings, orientation=ori,
                               progress=progress, cancel=cancel, cache=sweep_cache, **more)
            payload = {"mode": "1d", "param": req.x.param, "values": vals[0], "points": rows}
        else:
            out = sw.sweep_2d(design, req.x.param, vals[0], req.y.param, vals[1],  # type: ignore[union-attr]
                              settings, orientation=ori, progress=progress, cancel=cancel, cache=sweep_cache,
                              **more)
            payload = {"mode": "2d", "param_x": req.x.param, "values_x": vals[0],
                       "param_y": req.y.param, "values_y": vals[1], **dict(out)}  # type: ignore[union-attr]
        return ApiResult(raw=None, payload=jsonable(payload))

    return ctx.submit(request, "sweep", key, compute), cached


def _study_design(req: SweepRequest) -> tuple[Design | PresetDesign, float | None]:
    """The sweep's base design and ``length_step``: ``design``, or ``mechanism``'s preset (the paper
    preset as its :class:`Design`, any other as a :class:`PresetDesign`; a description is refused)."""
    if req.mechanism is None:
        return req.design.build(), None
    from paraspace.kinematics.presets import PRESETS

    refuse_design_with_mechanism(req)
    if req.mechanism.description is not None or req.mechanism.preset is None:
        raise FieldError("mechanism.preset", "mechanism.preset: a sweep varies a preset's parameters: valid values "
                                             f"{', '.join(PRESETS)} (not a description)")
    req.mechanism.build()  # the preset's name and params validated (422 naming mechanism.<field>)
    name, params = str(req.mechanism.preset), dict(req.mechanism.params)
    design = call_core("mechanism", functools.partial(PresetDesign.of, name, params))
    if name == "paper":
        return Design(**dict(design.values)), None
    return design, req.mechanism.length_step


def _general_point_voxels(ctx: ApiContext, design: PresetDesign, settings: Any, length_step: float | None,
                          point: int) -> int:
    """One preset point's grid size, after the workspace route's checks (413: carriage samples per
    chain, ``max_voxels``)."""
    from paraspace.kinematics.mechanism_workspace import general_plan

    from .workspace import MAX_API_CARRIAGE_SAMPLES

    try:
        grid, samples = general_plan(design.mechanism(), settings, 1.0 if length_step is None else length_step)
    except ParameterError as exc:
        raise FieldError(f"settings.{exc.field}", str(exc)) from None
    if max(samples) > MAX_API_CARRIAGE_SAMPLES:
        raise ApiError(413, f"sweep point {point}: {max(samples):,} carriage samples in a chain: at most "
                            f"{MAX_API_CARRIAGE_SAMPLES:,} per request (a larger settings.eta_step or "
                            f"mechanism.length_step)")
    if grid.size > ctx.limits.max_voxels:
        raise ApiError(413, f"sweep point {point}: a grid of {grid.size:,} voxels at voxel = {settings.voxel:g} "
                            f"(limit max_voxels = {ctx.limits.max_voxels})")
    return int(grid.size)


def _grid_points(design: Any, params: list[str], vals: list[list[float]], names: list[str]) -> list[Any]:
    """Designs of a sweep's grid (validated: a bad combination names the axis and index)."""
    out: list[Any] = []
    if len(params) == 1:
        for i, v in enumerate(vals[0]):
            out.append(call_core(f"{names[0]}.values[{i}]", functools.partial(design.replace, **{params[0]: v})))
        return out
    for i, vx in enumerate(vals[0]):
        for j, vy in enumerate(vals[1]):
            out.append(call_core(f"{names[0]}.values[{i}]/{names[1]}.values[{j}]",
                                 functools.partial(design.replace, **{params[0]: vx, params[1]: vy})))
    return out
