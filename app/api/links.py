"""Routes of the short links: ``POST /links`` makes ``/s/{token}``; ``GET /s?{query}`` and
``GET /s/{token}`` answer 307 to the explorer with that state, after validating it like the
explorer does. Links are built from the configured addresses (``serve --public-url``), never from
the request's Host header, which a client controls."""

from __future__ import annotations

import zlib
from typing import Any

from fastapi import APIRouter, Path, Request
from fastapi.responses import RedirectResponse

from .context import ApiContext, Ctx, api_router
from .errors import ERROR_RESPONSES, ApiError, error_field
from .models import LinkRequest
from .tokens import decode_link_token, encode_link_token

router = api_router()
#: ``/s`` and ``/s/{token}``: at the server's root, outside the versioned prefix.
short_links = APIRouter()


def _checked_query(query: str) -> str:
    """The query without its leading ``?``; 422 naming each field the explorer would refuse."""
    from ..urlstate import parse_query

    query = query.lstrip("?")
    _state, errors = parse_query(query)
    if errors:
        raise ApiError(422, [{"field": error_field(m), "message": m} for m in errors])  # type: ignore[arg-type]
    return query


def _explorer_base(ctx: ApiContext) -> str | None:
    """The explorer URL from the configuration (``serve --public-url``)."""
    return ctx.explorer_url.rstrip("/") if ctx.explorer_url else None


def _explorer_redirect(ctx: ApiContext, query: str) -> RedirectResponse:
    base = _explorer_base(ctx)
    if not base:
        raise ApiError(404, "no explorer is attached to this API server, so short links are disabled")
    query = _checked_query(query)
    target = base + "/" + (f"?{query}" if query else "")
    return RedirectResponse(target, status_code=307)


@router.post("/links", summary="Make a short link to an explorer state")
def make_link(req: LinkRequest, request: Request, ctx: Ctx) -> dict[str, Any]:
    """Validates the query like the explorer does; returns ``/s/{token}`` (stateless)."""
    query = _checked_query(req.query)
    token = encode_link_token(query)
    # the API's own address from the configuration (serve), never from the request's Host header
    base = (ctx.api_url or "").rstrip("/")
    return {"token": token, "path": f"/s/{token}", "short_url": f"{base}/s/{token}",
            "explorer_url": (_explorer_base(ctx) + "/?" + query) if ctx.explorer_url else None}  # type: ignore[operator]


@short_links.get("/s", summary="Short link: redirect to the explorer with this query", status_code=307,
                 response_class=RedirectResponse, responses={307: {"description": "redirect"}, **ERROR_RESPONSES})
def short_query(request: Request, ctx: Ctx) -> RedirectResponse:
    """``/s?a=60&z=120`` -> ``{explorer}/?a=60&z=120`` after validating the state."""
    return _explorer_redirect(ctx, request.url.query)


@short_links.get("/s/{token}", summary="Short link by token", status_code=307, response_class=RedirectResponse,
                 responses={307: {"description": "redirect"}, **ERROR_RESPONSES})
def short_token(request: Request, ctx: Ctx, token: str = Path(max_length=8192)) -> RedirectResponse:
    """Token from ``POST /api/v1/links``."""
    try:
        query = decode_link_token(token)
    except (ValueError, UnicodeDecodeError, zlib.error):
        raise ApiError(404, f"not a valid short-link token: {token[:40]!r}") from None
    return _explorer_redirect(ctx, query)
