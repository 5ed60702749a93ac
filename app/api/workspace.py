"""Routes of the position workspace: ``POST /workspace`` (a job), ``GET /workspace/{id}`` (its
measures) and ``GET /workspace/{id}/shell.{fmt}`` (its boundary surface as a mesh file)."""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Literal

from fastapi import Path, Query, Request
from fastapi.responses import JSONResponse, Response
from starlette.concurrency import run_in_threadpool

from paraspace.kinematics.serialize import jsonable

from .. import memory
from ..jobs import Job
from .context import WAIT_QUERY, ApiContext, ApiResult, Ctx, api_router
from .errors import RANGES, ApiError, FieldError
from .models import WorkspaceRequest, mechanism_or_design

router = api_router()
RANGES[("query", "max_faces")] = "[100, 2000000]"
#: Most carriage samples of one chain in a general mechanism's request (the work per voxel); the paper's
#: arc at its finest eta_step (0.01 deg over 180 deg) has 18,001.
MAX_API_CARRIAGE_SAMPLES = 20_000


@router.post("/workspace", status_code=202, summary="Start a position-workspace job",
             responses={200: {"description": "finished within `wait`: the result is included"},
                        202: {"description": "job accepted"}})
async def workspace(req: WorkspaceRequest, request: Request, ctx: Ctx, wait: float = WAIT_QUERY) -> JSONResponse:
    """Constant-orientation position workspace; the result has the workspace measures."""
    job, cached = await run_in_threadpool(_start_workspace, ctx, req, request)
    return await ctx.job_response(job, wait, cached)


def _start_workspace(ctx: ApiContext, req: WorkspaceRequest, request: Request) -> tuple[Job, bool]:
    from paraspace.kinematics.workspace import compute_workspace

    settings = req.settings.build()
    mech, design = mechanism_or_design(req)
    if design is None:
        return _start_general(ctx, req, request, mech, settings)
    key = (design.key(), settings.key())
    cached = ctx.caches["workspace"].get(key) is not None
    if not cached:
        ctx.quota_check(request)  # refuse at once, before any pre-computation
        with ctx.prechecks():
            ctx.grid_check(design, settings)

    def compute(progress: Any, cancel: Any) -> ApiResult:
        res = compute_workspace(design, settings, progress, cancel)
        return ApiResult(raw=res, payload=workspace_payload(res, cancel))

    return ctx.submit(request, "workspace", key, compute), cached


def _start_general(ctx: ApiContext, req: WorkspaceRequest, request: Request, mech: Any,
                   settings: Any) -> tuple[Job, bool]:
    """A general mechanism's workspace job (kinematics/mechanism_workspace.py), its grid checked first."""
    import json

    from paraspace.kinematics.design import ParameterError
    from paraspace.kinematics.mechanism_workspace import compute_mechanism_workspace, general_plan

    assert req.mechanism is not None
    length_step = req.mechanism.length_step
    key = ("mechanism", json.dumps(mech.to_dict(), sort_keys=True), settings.key(), length_step)
    cached = ctx.caches["workspace"].get(key) is not None
    if not cached:
        ctx.quota_check(request)
        with ctx.prechecks():
            try:
                grid, samples = general_plan(mech, settings, length_step)
            except ParameterError as exc:
                raise FieldError(f"settings.{exc.field}", str(exc)) from None
            if max(samples) > MAX_API_CARRIAGE_SAMPLES:
                raise ApiError(413, f"{max(samples):,} carriage samples in a chain: at most "
                                    f"{MAX_API_CARRIAGE_SAMPLES:,} per request (a larger settings.eta_step or "
                                    f"mechanism.length_step)")
            if grid.size > ctx.limits.max_voxels:
                h = settings.voxel
                need = math.ceil(h * (grid.size / ctx.limits.max_voxels) ** (1.0 / 3.0) * 10.0 + 1e-9) / 10.0
                raise ApiError(413, f"voxel = {h:g} is invalid: valid range voxel >= {need:g} for this mechanism "
                                    f"(a grid of at most {ctx.limits.max_voxels:,} voxels; voxel {h:g} makes "
                                    f"{grid.size:,}) (limit max_voxels = {ctx.limits.max_voxels})")

    def compute(progress: Any, cancel: Any) -> ApiResult:
        res = compute_mechanism_workspace(mech, settings, length_step, progress, cancel)
        return ApiResult(raw=res, payload=workspace_payload(res, cancel))

    return ctx.submit(request, "workspace", key, compute), cached


@router.get("/workspace/{job_id}", summary="Measures of a finished workspace job")
def workspace_result(job_id: str, request: Request, ctx: Ctx) -> dict[str, Any]:
    """409 while the job runs or when it failed or was cancelled."""
    job = ctx.api_job(job_id, "workspace")
    return jsonable({"job": job.to_dict(), **ctx.finished_result(job).payload})


@router.get("/workspace/{job_id}/shell.{fmt}", summary="Boundary surface of a finished workspace",
            response_class=Response,
            responses={200: {"content": {"model/stl": {}, "application/octet-stream": {}}}})
def workspace_shell(job_id: str, request: Request, ctx: Ctx,
                    fmt: Literal["stl", "ply", "obj", "glb"] = Path(description="mesh format"),
                    max_faces: int | None = Query(None, ge=100, le=2_000_000,
                                                     description="decimate to at most this many faces; "
                                                                 "valid range [100, 2000000]")) -> Response:
    """The workspace shell (marching cubes of the occupancy) as a mesh file download."""
    limits = ctx.limits
    if max_faces is not None and max_faces > limits.max_shell_faces:
        raise FieldError("max_faces", f"max_faces = {max_faces} is invalid: valid range "
                                      f"[100, {limits.max_shell_faces}]")
    job = ctx.api_job(job_id, "workspace")
    res = ctx.finished_result(job)
    skey = (job_id, fmt, max_faces)
    data = ctx.shells.get(skey)
    if data is None:
        from paraspace.kinematics.shell import export_shell
        from paraspace.kinematics.shell import workspace_shell as make_shell

        raw = res.raw
        if raw is None:
            raise ApiError(409, f"the voxel grid of job {job_id} was evicted from the result cache "
                                f"(limit cache_bytes = {limits.cache_bytes}); submit the workspace "
                                f"request again to export its shell")
        if not raw.occupancy.any():
            raise ApiError(409, "the workspace is empty: there is no shell to export")
        with ctx.shell_key_lock(skey), ctx.shell_builds:
            data = ctx.shells.get(skey)  # built by a concurrent request for the same file meanwhile
            if data is None:
                mesh = make_shell(raw, max_faces=max_faces)
                data = export_shell(mesh, fmt)
                del mesh  # a trimesh mesh is a reference cycle: app/memory.trim collects it
                ctx.shells.put(skey, data)
                memory.trim(force=True)  # marching cubes' and decimation's temporaries back to the system
    media = {"stl": "model/stl", "ply": "application/octet-stream", "obj": "model/obj",
             "glb": "model/gltf-binary"}[fmt]
    return Response(content=data, media_type=media,
                    headers={"Content-Disposition": f'attachment; filename="workspace-{job_id}.{fmt}"'})


def workspace_payload(res: Any, cancel: Any = None) -> dict[str, Any]:
    """JSON summary of a WorkspaceResult with its measures."""
    g = res.grid
    payload: dict[str, Any] = {
        "design": res.design.to_dict() if res.design is not None else None,
        "settings": jsonable(dataclasses.asdict(res.settings)),
        "voxels": res.voxels,
        "volume": res.volume,
        "compute_seconds": res.compute_seconds,
        "n_eta": res.n_eta,
        "volume_inner": res.volume_inner,
        "volume_outer": res.volume_outer,
        "grid": {"origin": list(g.origin), "h": g.h, "shape": list(g.shape), "lo": list(g.lo), "hi": list(g.hi),
                 "size": g.size},
    }
    mech = getattr(res, "mechanism", None)
    if mech is not None:
        payload["mechanism"] = mech.to_dict()
        payload["engine"] = res.engine
        payload["carriage_samples"] = list(res.samples)
    try:
        from paraspace.kinematics.measures import measure_workspace
    except ImportError as e:  # pragma: no cover - measures is part of the core
        payload["measures"] = None
        payload["measures_error"] = f"measures unavailable: {e}"
    else:
        payload["measures"] = measure_workspace(res, cancel=cancel).to_dict()
    return jsonable(payload)
