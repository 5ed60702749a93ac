"""Which hosts and origins may talk to the local servers: DNS rebinding and cross-site websockets.

A web page the user visits must not drive the explorer or read the API. Two rules decide every
request, on both ports (the explorer's page and websocket, the REST API):

**Host rule.** The request's ``Host`` header names an allowed host: ``localhost``, ``127.0.0.1``,
``::1``, the address the server is bound to (unless a wildcard), the host of ``--public-url``,
and any ``--allowed-host``. A rebinding domain (``attacker.example`` resolving to 127.0.0.1)
sends its own name as ``Host`` and is refused. ``--allowed-host '*'`` turns the rule off (for a
deployment that checks hosts itself).

**Origin rule.** A request that carries an ``Origin`` (browsers send one with every websocket
handshake and every cross-site ``fetch``) comes from the server's own origin (the ``Origin``'s
host and port equal the request's ``Host``), from the explorer's origin (for the API: an allowed
host at the explorer's port, or ``--public-url``'s origin), or is refused. ``Origin: null``
(sandboxed frames, ``file:`` pages) is refused. A request without ``Origin`` is not from a
cross-site page (no browser omits it where it matters) and passes the origin rule.

A refusal is a 403 with one sentence naming the header, its value and how to allow it.
"""

from __future__ import annotations

import dataclasses
import urllib.parse
from collections.abc import Iterable

__all__ = ["HostPolicy", "LOOPBACK_HOSTS", "host_name", "parse_allowed_hosts"]

#: Always allowed: the loopback names.
LOOPBACK_HOSTS = frozenset({"localhost", "127.0.0.1", "::1"})
_WILDCARDS = frozenset({"", "0.0.0.0", "::"})
_DEFAULT_PORTS = {"http": 80, "https": 443, "ws": 80, "wss": 443}


def host_name(host_header: str) -> str:
    """The host name of a ``Host`` header value (``Example.org:8080`` -> ``example.org``,
    ``[::1]:8080`` -> ``::1``), lower case, without a trailing dot."""
    value = host_header.strip().lower()
    if value.startswith("["):
        end = value.find("]")
        return value[1:end] if end > 0 else value
    if value.count(":") == 1:
        value = value.split(":", 1)[0]
    return value.rstrip(".")


def _netloc(host_header: str, scheme: str) -> tuple[str, int]:
    """``(host, port)`` of a Host header value, the scheme's default port when absent."""
    parts = urllib.parse.urlsplit(f"//{host_header.strip()}")
    return (parts.hostname or "").rstrip("."), int(parts.port or _DEFAULT_PORTS.get(scheme, 80))


def _origin(origin: str) -> tuple[str, str, int] | None:
    """``(scheme, host, port)`` of an ``Origin`` value, ``None`` for ``null`` or malformed."""
    parts = urllib.parse.urlsplit(origin.strip())
    if parts.scheme not in ("http", "https") or not parts.hostname:
        return None
    try:
        port = parts.port
    except ValueError:
        return None
    return parts.scheme, parts.hostname.rstrip("."), int(port or _DEFAULT_PORTS[parts.scheme])


def parse_allowed_hosts(text: str | None) -> tuple[str, ...]:
    """``--allowed-host`` values: comma-separated host names (``*`` allows every host)."""
    if not text:
        return ()
    return tuple(h for h in (host_name(p) if p.strip() != "*" else "*" for p in text.split(",")) if h)


@dataclasses.dataclass(frozen=True)
class HostPolicy:
    """The allowed hosts and the explorer's origins (see the module docstring for the rules)."""

    hosts: frozenset[str] = LOOPBACK_HOSTS
    explorer_port: int | None = None
    public_origin: tuple[str, str, int] | None = None
    any_host: bool = False

    @classmethod
    def for_server(cls, bind_host: str = "127.0.0.1", *, explorer_port: int | None = None,
                   public_url: str | None = None, allowed_hosts: Iterable[str] = ()) -> HostPolicy:
        """The policy of a server bound to ``bind_host`` (see the module docstring)."""
        hosts = set(LOOPBACK_HOSTS)
        if host_name(bind_host) not in _WILDCARDS:
            hosts.add(host_name(bind_host))
        public = _origin(public_url) if public_url else None
        if public is not None:
            hosts.add(public[1])
        extra = list(allowed_hosts)
        hosts.update(h for h in extra if h != "*")
        return cls(frozenset(hosts), explorer_port, public, any_host="*" in extra)

    def refusal(self, host: str | None, origin: str | None, scheme: str = "http") -> str | None:
        """``None`` when a request with these ``Host`` and ``Origin`` headers may be served, else
        the sentence of its 403."""
        if not self.any_host:
            name = host_name(host or "")
            if name not in self.hosts:
                return (f"Host {host!r} is not allowed: this server answers to {', '.join(sorted(self.hosts))}. "
                        "Start it with --allowed-host NAME to add a host name.")
        if origin is None:
            return None
        parsed = _origin(origin)
        if parsed is not None:
            o_scheme, o_host, o_port = parsed
            if host and (o_host, o_port) == _netloc(host, o_scheme if o_scheme else scheme):
                return None  # the server's own origin
            if parsed == self.public_origin:
                return None
            if (self.explorer_port is not None and o_port == self.explorer_port
                    and (self.any_host or o_host in self.hosts)):
                return None  # the explorer's page (for the API)
        return (f"Origin {origin!r} is not allowed: only pages served by paraspace itself may connect "
                "(a page on another site cannot drive this server).")
