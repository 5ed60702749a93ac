"""ASGI middleware bounding request bodies: 413 over ``max_body_bytes``, 408 when dripped slowly."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from typing import Any

from .errors import error_json


class BodyLimit:
    """ASGI middleware: refuse request bodies over ``max_bytes`` with 413 (before parsing), and
    bodies not complete within ``seconds`` (dripped slowly) with 408."""

    def __init__(self, app: Any, max_bytes: int, seconds: float = 10.0) -> None:
        self.app, self.max_bytes, self.seconds = app, max_bytes, seconds

    async def __call__(self, scope: dict, receive: Callable, send: Callable) -> None:
        if scope["type"] != "http" or scope.get("method") in ("GET", "HEAD", "OPTIONS", "DELETE"):
            await self.app(scope, receive, send)
            return
        too_big = False
        for k, v in scope.get("headers", []):
            if k == b"content-length":
                try:
                    too_big = int(v) > self.max_bytes
                except ValueError:
                    too_big = False
        chunks: list[bytes] = []
        size = 0
        more = not too_big
        deadline = time.monotonic() + self.seconds
        while more:
            try:
                msg = await asyncio.wait_for(receive(), timeout=max(0.01, deadline - time.monotonic()))
            except asyncio.TimeoutError:
                resp = error_json(408, f"request body not received within {self.seconds:g} s (limit max_body_seconds)")
                await resp(scope, receive, send)
                return
            if msg["type"] == "http.disconnect":
                return
            body = msg.get("body", b"")
            size += len(body)
            if size > self.max_bytes:
                too_big = True
                break
            chunks.append(body)
            more = msg.get("more_body", False)
        if too_big:
            resp = error_json(413, f"request body too large: limit max_body_bytes = {self.max_bytes} bytes")
            await resp(scope, receive, send)
            return
        body = b"".join(chunks)
        sent = False

        async def replay() -> dict:
            nonlocal sent
            if not sent:
                sent = True
                return {"type": "http.request", "body": body, "more_body": False}
            return await receive()

        await self.app(scope, replay, send)
