"""ASGI middleware: the host and origin rules of :mod:`paraspace.app.hostcheck` on every API
request (403 with ``{"detail": sentence}`` before anything else runs)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..hostcheck import HostPolicy
from .errors import error_json


class HostGuard:
    """Refuse requests whose ``Host`` or ``Origin`` the policy does not allow (403)."""

    def __init__(self, app: Any, policy: HostPolicy) -> None:
        self.app, self.policy = app, policy

    async def __call__(self, scope: dict, receive: Callable, send: Callable) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        host = origin = None
        for k, v in scope.get("headers", []):
            if k == b"host":
                host = v.decode("latin-1")
            elif k == b"origin":
                origin = v.decode("latin-1")
        why = self.policy.refusal(host, origin, scope.get("scheme", "http"))
        if why is not None:
            await error_json(403, why)(scope, receive, send)
            return
        await self.app(scope, receive, send)
