"""Routes about the service itself: ``/health``, ``/design/defaults``, ``/mechanism/presets`` and the
landing page ``/``."""

from __future__ import annotations

import time
from typing import Any

from fastapi import APIRouter, Request
from fastapi.responses import JSONResponse, Response

from paraspace.kinematics.design import ETA_RANGES, PARAMS, Design

from .context import API_PREFIX, API_VERSION, Ctx, api_router

router = api_router()
#: The landing page at the server's root (outside the versioned prefix and the schema).
site = APIRouter()


@router.get("/health", summary="Liveness, job counts and limits")
async def health(ctx: Ctx) -> dict[str, Any]:
    """Always cheap; 200 while the server can answer."""
    from paraspace.kinematics.warmup import is_warm

    return {"status": "ok", "warm": is_warm(), "api_version": "v1", "version": API_VERSION, "time": time.time(),
            "explorer_url": ctx.explorer_url, "jobs": ctx.jobs.stats(), "limits": ctx.limits.to_dict()}


@router.get("/design/defaults", summary="Design fields, defaults and ranges")
async def design_defaults() -> dict[str, Any]:
    """Every design parameter with its default (the paper's Fig. 3 design), the range the
    model accepts and the slider range of paper Table I."""
    fields = {name: {"default": s.default, "description": s.description, "unit": s.unit or None,
                     "model_min": s.model_min, "model_max": s.model_max,
                     "slider_min": s.slider_min, "slider_max": s.slider_max}
              for name, s in PARAMS.items()}
    return {"fields": fields, "defaults": Design().to_dict(),
            "eta_range": {"default": "centered", "options": list(ETA_RANGES)},
            "constraints": ["d_s <= r"]}


@router.get("/mechanism/presets", summary="Mechanism presets, their parameters and descriptions")
async def mechanism_presets() -> dict[str, Any]:
    """Every preset of ``kinematics.presets`` with its parameters (default, valid range, unit, words)
    and its description at the defaults (the structure ``mechanism.description`` takes)."""
    from paraspace.kinematics.presets import PRESETS

    return {"presets": [
        {"name": p.name, "description": p.description,
         "params": [{"name": q.name, "default": q.default, "description": q.description,
                     **({} if isinstance(q.default, str) else {"min": q.lo, "max": q.hi, "unit": q.unit or None})}
                    for q in p.params],
         "mechanism": p.mechanism().to_dict()}
        for p in PRESETS.values()]}


@site.get("/", include_in_schema=False)
def root(request: Request, ctx: Ctx) -> Response:
    """A browser gets the landing page (static/index.html); a script gets the JSON index."""
    explorer_url = ctx.explorer_url
    if "text/html" in request.headers.get("accept", ""):
        page = landing_page().replace("{{explorer_url}}", explorer_url or "/s").replace("{{api_prefix}}", API_PREFIX)
        return Response(page, media_type="text/html")
    return JSONResponse({"name": "paraspace API", "docs": "/docs", "openapi": "/openapi.json", "api": API_PREFIX,
                         "health": f"{API_PREFIX}/health", "explorer_url": explorer_url})


def landing_page() -> str:
    """``static/index.html``: from the source tree when running from a checkout, else from the
    installed package data ``paraspace.static``."""
    import importlib.resources
    import pathlib

    source = pathlib.Path(__file__).resolve().parents[2] / "static" / "index.html"
    if source.is_file():
        return source.read_text("utf-8")
    return importlib.resources.files("paraspace.static").joinpath("index.html").read_text("utf-8")
