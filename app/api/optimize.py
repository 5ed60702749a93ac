"""Route ``POST /optimize``: a multi-objective optimisation (issue 11) as a job, with its limits check
(:func:`optimize_limits_check`) and its computation (:func:`optimize_compute`)."""

from __future__ import annotations

from typing import Any

from fastapi import Request
from fastapi.responses import JSONResponse
from starlette.concurrency import run_in_threadpool

from paraspace.kinematics.design import ParameterError
from paraspace.kinematics.serialize import jsonable

from ..jobs import Job
from ..limits import orientation_samples, workspace_voxels
from .context import WAIT_QUERY, ApiContext, ApiResult, Ctx, api_router
from .errors import ApiError
from .limits import ApiLimits
from .models import OptimizeRequest

router = api_router()


@router.post("/optimize", status_code=202, summary="Start a multi-objective optimisation job",
             responses={200: {"description": "finished within `wait`"}, 202: {"description": "job accepted"}})
async def optimize_job(req: OptimizeRequest, request: Request, ctx: Ctx, wait: float = WAIT_QUERY) -> JSONResponse:
    """Pareto front of the objectives over the free parameters (``kinematics.optimize``);
    evaluations share the sweeps' result cache. The result: ``front`` (``{"design",
    "measures"}`` each), ``hypervolume`` per generation, ``settings``, ``failed``..."""
    job, cached = await run_in_threadpool(_start_optimize, ctx, req, request)
    return await ctx.job_response(job, wait, cached)


def _start_optimize(ctx: ApiContext, req: OptimizeRequest, request: Request) -> tuple[Job, bool]:
    settings = req.build()
    key = settings.key()
    cached = ctx.caches["optimize"].get(key) is not None
    if not cached:
        ctx.quota_check(request)
        optimize_limits_check(settings, ctx.limits)
    sweep_cache = ctx.sweep_cache
    return ctx.submit(request, "optimize", key,
                      lambda progress, cancel: optimize_compute(settings, progress, cancel, sweep_cache)), cached


def optimize_limits_check(settings: Any, limits: ApiLimits) -> None:
    """413 when the run is over ``max_optimize_evaluations`` or ``max_optimize_voxels`` (see
    :class:`ApiLimits`), or when one orientation evaluation is over ``max_orientation_samples``."""
    import itertools

    n_eval = settings.population * settings.generations
    if n_eval > limits.max_optimize_evaluations:
        raise ApiError(413, f"optimisation of {n_eval} evaluations (population x generations) exceeds the limit "
                            f"max_optimize_evaluations = {limits.max_optimize_evaluations}")
    per_design = 0
    n_ori = 0
    ori = settings.orientation_used
    for corner in itertools.product(*[settings.bounds_of(p) for p in settings.params]):
        try:
            d = settings.design_at(corner)
        except ParameterError:
            continue  # an invalid corner (d_s > r, l_max <= l_min) is never evaluated
        if settings.general:  # a preset's design: the general engine's grid and carriage samples
            per_design = max(per_design, _general_voxels(d, settings, limits))
            continue
        per_design = max(per_design, workspace_voxels(d, settings.workspace, analytic=True))
        if ori is not None:
            n_ori = max(n_ori, orientation_samples(d, ori))
    total = per_design * n_eval
    if total > limits.max_optimize_voxels:
        raise ApiError(413, f"optimisation of up to {total} voxels in all ({n_eval} evaluations x {per_design} "
                            f"voxels of the largest design) exceeds the limit max_optimize_voxels = "
                            f"{limits.max_optimize_voxels}: use a larger voxel (now {settings.workspace.voxel:g}), "
                            f"a smaller population or fewer generations")
    if n_ori > limits.max_orientation_samples:
        raise ApiError(413, f"orientation part of {n_ori} samples per design exceeds the limit "
                            f"max_orientation_samples = {limits.max_orientation_samples}")
    task = getattr(settings, "task_used", None)
    if task is not None and not hasattr(task.task, "poses"):
        from paraspace.kinematics.task import region_samples

        n_task = region_samples(task.task, task.orientations, task.settings)
        if n_task > limits.max_task_samples:
            raise ApiError(413, f"task part of {n_task:,} samples per design exceeds the limit "
                                f"max_task_samples = {limits.max_task_samples:,}")


def _general_voxels(design: Any, settings: Any, limits: ApiLimits) -> int:
    """The general engine's grid size for one preset design (its carriage samples checked as the
    workspace route does: 413 over :data:`~.workspace.MAX_API_CARRIAGE_SAMPLES` per chain). The
    corners of the bounds bound the grid when the reach grows monotonically with each parameter
    (the presets' radii, lengths and strokes); a design between them may lay a slightly larger grid."""
    from paraspace.kinematics.mechanism_workspace import general_plan

    from .workspace import MAX_API_CARRIAGE_SAMPLES

    grid, samples = general_plan(design.mechanism(), settings.workspace, settings.length_step)
    if max(samples) > MAX_API_CARRIAGE_SAMPLES:
        raise ApiError(413, f"{max(samples):,} carriage samples in a chain: at most {MAX_API_CARRIAGE_SAMPLES:,} "
                            "per evaluation (a larger settings.eta_step or mechanism.length_step)")
    return int(grid.size)


def optimize_compute(settings: Any, progress: Any, cancel: Any, cache: Any = None) -> ApiResult:
    """Run the optimisation in this process (the job's thread); the payload is
    ``OptimizeResult.to_dict()`` (``front``, ``hypervolume`` per generation, ``settings``...)."""
    from paraspace.kinematics.optimize import optimize

    res = optimize(settings, cache=cache, progress=progress, cancel=cancel)
    return ApiResult(raw=None, payload=jsonable(res.to_dict()))
