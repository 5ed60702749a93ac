"""The API's error model: every error answer is JSON ``{"detail": ...}``.

Bad input is **422** with one ``{"field", "message"}`` entry per bad field, the message naming the
value and the field's valid range (request validation and the core's
:class:`~kinematics.design.ParameterError` alike); other errors carry a sentence (413, 404, 409, 429,
507...). :data:`RANGES` is the registry of valid-range texts the request models fill in
(``models.py``) and :func:`validation_items` reads.
"""

from __future__ import annotations

import errno
import logging
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import BaseModel
from starlette.exceptions import HTTPException as StarletteHTTPException

from paraspace.kinematics.design import ParameterError

log = logging.getLogger("paraspace.app.api")

from ..schema import RANGES, FieldError, call_core  # noqa: E402,F401 - the inputs' registry and errors


class ApiError(Exception):
    """An HTTP error with a plain-text ``detail`` (413, 404, 409, 429, ...)."""

    def __init__(self, status: int, detail: str, headers: dict[str, str] | None = None) -> None:
        self.status, self.detail, self.headers = status, detail, headers
        super().__init__(detail)


def _short_repr(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def validation_items(errors: list[dict[str, Any]]) -> list[dict[str, str]]:
    """Pydantic errors -> ``[{"field", "message"}]`` naming the field and its valid range."""
    items: list[dict[str, str]] = []
    for err in errors:
        loc = list(err.get("loc", ()))
        where = loc[0] if loc and loc[0] in ("body", "query", "path", "header") else None
        parts = loc[1:] if where else loc
        field = ""
        for p in parts:
            if isinstance(p, int):
                field += f"[{p}]"
            else:
                field += ("." if field else "") + str(p)
        field = field or (where or "request")
        names = [p for p in parts if isinstance(p, str)]
        name = names[-1] if names else field
        section = names[-2] if len(names) >= 2 else (where or "")
        rng = RANGES.get((section, name))
        if rng is None:
            matches = {v for (s, n), v in RANGES.items() if n == name}
            rng = matches.pop() if len(matches) == 1 else None
        etype = err.get("type", "")
        ctx = err.get("ctx") or {}
        value = err.get("input")
        if etype == "missing":
            msg = f"{field} is required" + (f" (valid range {rng})" if rng else "")
        elif etype == "extra_forbidden":
            msg = f"{field} is not an accepted field"
        elif etype in ("literal_error", "enum"):
            msg = f"{field} = {_short_repr(value)} is invalid: valid values {ctx.get('expected', '')}"
        elif etype == "json_invalid":
            msg = f"the request body is not valid JSON: {ctx.get('error', err.get('msg', ''))}"
            field = "body"
        elif rng is not None:
            msg = f"{name} = {_short_repr(value)} is invalid: valid range {rng}"
            if etype not in ("greater_than_equal", "less_than_equal", "greater_than", "less_than",
                             "finite_number"):
                msg += f" ({err.get('msg', '')})"
        else:
            msg = f"{field} = {_short_repr(value)} is invalid: {err.get('msg', '')}"
        items.append({"field": field, "message": msg})
    return items


def error_field(message: str) -> str:
    """The field a urlstate message names (its first word before ' = ' or ':')."""
    head = message.split(" = ", 1)[0].split(":", 1)[0].strip()
    return head if head and " " not in head else "query"


class FieldProblem(BaseModel):
    """One bad field: its dotted name and a sentence with the value and the valid range."""

    field: str
    message: str


class ErrorOut(BaseModel):
    """Every error answer: ``detail`` is a sentence, or (422) one entry per bad field."""

    detail: str | list[FieldProblem]


#: What any endpoint may answer besides its success codes (declared in the OpenAPI document).
ERROR_RESPONSES: dict[int | str, dict[str, Any]] = {
    code: {"model": ErrorOut, "description": text} for code, text in (
        (403, "the request's Host or Origin is not allowed (DNS rebinding, cross-site pages)"),
        (404, "unknown job, or short links disabled"),
        (408, "request body not received in time"),
        (409, "the job has no result (yet)"),
        (410, "the result was dropped from memory; submit again"),
        (413, "over a size limit (grid, sweep, body)"),
        (422, "bad input: the field and its valid range"),
        (429, "too many unfinished jobs; retry later"),
        (507, "the server's disk is full"),
    )}


def error_json(status: int, detail: Any, headers: dict[str, str] | None = None) -> JSONResponse:
    """The one shape of every error answer: ``{"detail": detail}`` with ``status``."""
    return JSONResponse(status_code=status, content={"detail": detail}, headers=headers)


def install_error_handlers(app: FastAPI) -> None:
    """Answer every error of ``app`` as :func:`error_json` (422 naming the field for bad input)."""

    @app.exception_handler(RequestValidationError)
    async def _on_validation(request: Request, exc: RequestValidationError) -> JSONResponse:
        return error_json(422, validation_items(list(exc.errors())))

    @app.exception_handler(StarletteHTTPException)
    async def _on_http(request: Request, exc: StarletteHTTPException) -> JSONResponse:
        # FastAPI answers a body it cannot parse (invalid UTF-8, nesting too deep for the JSON
        # parser, truncated JSON) with a bare 400: name the field instead.
        if exc.status_code == 400 and "parsing the body" in str(exc.detail):
            return error_json(422, [{"field": "body", "message": "body = <unreadable> is invalid: expected a "
                                     "UTF-8 JSON object (at most a few levels deep) as documented for this endpoint"}])
        return error_json(exc.status_code, exc.detail, dict(exc.headers or {}))

    @app.exception_handler(OSError)
    async def _on_os(request: Request, exc: OSError) -> JSONResponse:
        if getattr(exc, "errno", None) in (errno.ENOSPC, errno.EDQUOT):
            log.error("disk full on %s %s: %s", request.method, request.url.path, exc)
            return error_json(507, "the server's disk is full, so this request cannot be stored; "
                                   "requests that need no disk (health, ik, cached results) still work")
        log.exception("unhandled OS error on %s %s", request.method, request.url.path)
        return error_json(500, f"internal error: {type(exc).__name__}: {' '.join(str(exc).split())[:300]}")

    @app.exception_handler(FieldError)
    async def _on_field(request: Request, exc: FieldError) -> JSONResponse:
        return error_json(422, [{"field": exc.field, "message": exc.message}])

    @app.exception_handler(ParameterError)
    async def _on_param(request: Request, exc: ParameterError) -> JSONResponse:
        return error_json(422, [{"field": exc.field, "message": str(exc)}])

    @app.exception_handler(ApiError)
    async def _on_api(request: Request, exc: ApiError) -> JSONResponse:
        return error_json(exc.status, exc.detail, exc.headers)

    @app.exception_handler(Exception)
    async def _on_crash(request: Request, exc: Exception) -> JSONResponse:  # pragma: no cover - bugs only
        log.exception("unhandled error on %s %s", request.method, request.url.path)
        return error_json(500, f"internal error: {type(exc).__name__}: {' '.join(str(exc).split())[:300]}")
