"""Short-link tokens: an explorer URL query packed into a URL-safe token for ``/s/{token}``.

Stateless (the token is the query itself, zlib-compressed when that is shorter), so links survive
restarts; decoding is bounded (16 KiB of text at most) and refuses anything no encoder produces.
"""

from __future__ import annotations

import base64
import zlib


def encode_link_token(query: str) -> str:
    """Explorer query -> URL-safe token for ``/s/{token}`` (stateless: survives restarts)."""
    raw = query.lstrip("?").encode()
    packed = zlib.compress(raw, 9)
    body, tag = (packed, "z") if len(packed) < len(raw) else (raw, "q")
    return tag + base64.urlsafe_b64encode(body).decode().rstrip("=")


_TOKEN_BODY = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-_")


def decode_link_token(token: str) -> str:
    """Inverse of :func:`encode_link_token`; raises ValueError on a malformed token (a character
    outside the URL-safe base64 alphabet, a length no encoder produces, a broken or trailing zlib
    stream, or text that is not UTF-8)."""
    if not token or token[0] not in "zq" or len(token) > 8192:
        raise ValueError("not a link token")
    body = token[1:]
    if not set(body) <= _TOKEN_BODY or len(body) % 4 == 1:
        raise ValueError("not a link token")
    data = base64.urlsafe_b64decode(body + "=" * (-len(body) % 4))
    if token[0] == "z":
        d = zlib.decompressobj()
        try:
            data = d.decompress(data, 16384)
        except zlib.error as exc:
            raise ValueError("not a link token") from exc
        if d.unconsumed_tail:
            raise ValueError("link token too long")
        if not d.eof or d.unused_data:
            raise ValueError("not a link token")
    return data.decode("utf-8")
