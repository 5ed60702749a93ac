"""Versioned REST API of paraspace (FastAPI), served beside the viser explorer.

Everything lives under ``/api/v1`` (OpenAPI docs at ``/docs``, schema at ``/openapi.json``):

==========================================  ===================================================
``GET  /api/v1/health``                     liveness, job counts, limits
``GET  /api/v1/design/defaults``            design fields, defaults, model and slider ranges
``POST /api/v1/ik``                         pose (+ optional carriages ``d``, ``eta``) -> IK
``POST /api/v1/workspace``                  design + settings -> job (``?wait=s`` to block)
``GET  /api/v1/workspace/{id}``             the workspace's measures (when done)
``GET  /api/v1/workspace/{id}/shell.{fmt}`` its boundary surface as stl, ply, obj or glb
``POST /api/v1/orientation``                orientation workspace / tilt indices -> job
``POST /api/v1/sweep``                      1-D or 2-D parameter study -> job
``POST /api/v1/optimize``                   multi-objective optimisation (Pareto front) -> job
``POST /api/v1/task``                       a region or pose list: contained, margin, binding -> job
``GET  /api/v1/jobs``                       the caller's unfinished jobs
``GET  /api/v1/jobs/{id}``                  status and progress of a job
``DELETE /api/v1/jobs/{id}``                cancel a job
``GET  /api/v1/jobs/{id}/result``           the result of a finished job
``POST /api/v1/links``                      make a short link to an explorer state
``GET  /s?{query}``, ``GET /s/{token}``     307 redirect to the explorer with that state
==========================================  ===================================================

Errors are JSON. Bad input gets **422** with ``{"detail": [{"field": "design.a", "message": "a = -5
is invalid: valid range [1e-06, 1000]"}]}`` (request validation and the core's
:class:`~kinematics.design.ParameterError` alike). Requests over a resource limit get **413**
(too big: voxels, sweep points, orientation samples, body size) or **429** (too many unfinished
jobs; with ``Retry-After``), before anything runs: nothing is queued without bound. A failing job
ends ``failed`` with a one-line error and the server stays healthy.

Finished results are cached by (design, settings) in a small LRU: repeating a request is instant.

Layout: ``models`` (request models), ``errors`` (the error model and handlers), ``limits``
(:class:`ApiLimits`), ``body_limit`` (the body-size middleware), ``tokens`` (short-link tokens),
``context`` (:class:`ApiContext`: the job manager, limits and caches the routers share) and one
router per resource: ``meta`` (health, design defaults, landing page), ``ik``, ``workspace``,
``orientation``, ``sweep``, ``optimize``, ``task``, ``jobs``, ``links``.
"""

from __future__ import annotations

from fastapi import FastAPI
from fastapi_offline import FastAPIOffline

from ..hostcheck import HostPolicy
from ..jobs import JobManager
from . import ik, links, meta, optimize, orientation, sweep, task, workspace
from . import jobs as jobs_routes
from .body_limit import BodyLimit
from .context import API_PREFIX, API_VERSION, ApiContext
from .errors import install_error_handlers
from .host_guard import HostGuard
from .limits import ApiLimits
from .tokens import decode_link_token, encode_link_token

__all__ = ["ApiLimits", "create_api", "API_PREFIX", "encode_link_token", "decode_link_token"]

#: The routers in the order their routes are matched and listed in the OpenAPI document.
ROUTERS = (meta.router, ik.router, workspace.router, orientation.router, sweep.router, optimize.router,
           task.router, jobs_routes.router, links.router, links.short_links, meta.site)


def create_api(jobs: JobManager, *, explorer_url: str | None = None,
               limits: ApiLimits = ApiLimits(), api_url: str | None = None,
               hosts: HostPolicy | None = None) -> FastAPI:
    """Build the FastAPI application.

    Args:
        jobs: the shared job manager (the explorer uses the same one).
        explorer_url: base URL of the viser explorer, used by the short links; ``None`` disables
            them (404 with a message).
        limits: resource limits (see :class:`ApiLimits`).
        api_url: this API's base URL as clients reach it, for the absolute short links
            (``None``: ``short_url`` is the path alone). Links never use the request's Host header.
        hosts: the allowed hosts and origins (:mod:`paraspace.app.hostcheck`; default: loopback
            names only, no explorer origin). Every other request gets 403.
    """
    # The interactive docs at /docs load Swagger UI's script and style from this server (the
    # fastapi-offline package ships them), never from a CDN: they render without internet.
    app = FastAPIOffline(
        title="paraspace API",
        version=API_VERSION,
        description=("Workspace, orientation capability, parameter studies and inverse kinematics of the "
                     "3-(arc-P, P, 2-(UPS)) redundant parallel mechanism. Long computations are jobs: "
                     "POST returns a job id, poll `GET /api/v1/jobs/{id}`, fetch `.../result`. "
                     "Bad input: 422 naming the field and its valid range; over a limit: 413/429."),
        docs_url="/docs",
        openapi_url="/openapi.json",
        redoc_url=None,
        static_url="/docs-assets",
    )
    ctx = ApiContext(jobs, limits, explorer_url, api_url)
    app.state.api = ctx  # what the routers receive (context.Ctx)
    app.state.jobs = jobs
    app.state.limits = limits
    app.state.explorer_url = explorer_url
    app.state.caches = ctx.caches
    install_error_handlers(app)
    app.add_middleware(BodyLimit, max_bytes=limits.max_body_bytes, seconds=limits.max_body_seconds)
    app.add_middleware(HostGuard, policy=hosts or HostPolicy())  # added last: runs first
    for router in ROUTERS:
        app.include_router(router)
    return app
