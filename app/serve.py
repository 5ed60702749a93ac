"""Run the explorer (viser) and the REST API (uvicorn) in one process, sharing one JobManager.

``serve()`` is what ``paraspace serve`` calls::

    paraspace serve --host 127.0.0.1 --port 8080 --api-port 8081

viser runs its own websocket/HTTP server on ``port`` (it cannot be mounted into an ASGI app, see
the viser notes §1); uvicorn serves the FastAPI app of :mod:`app.api` on ``api_port`` in a thread,
on the same host. Ctrl-C (SIGINT) or SIGTERM (``docker stop``) stops both cleanly: running jobs are
cancelled, the servers close their ports.
"""

from __future__ import annotations

import asyncio
import dataclasses
import logging
import signal
import socket
import sys
import threading
import time
import urllib.parse
from typing import Any

import uvicorn
from uvicorn.protocols.http.h11_impl import H11Protocol

from paraspace.kinematics.design import ParameterError

from . import memory
from .api import ApiLimits, create_api
from .hostcheck import HostPolicy
from .jobs import JobManager

__all__ = ["ApiServer", "Running", "serve", "start_api", "free_port"]

log = logging.getLogger(__name__)


def free_port(host: str = "127.0.0.1") -> int:
    """A currently free TCP port on ``host`` (for tests and ``--port 0``)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])


def _url_host(host: str) -> str:
    """Host part for printed URLs: a wildcard bind is reachable on loopback."""
    return "127.0.0.1" if host in ("0.0.0.0", "", "::") else host


@dataclasses.dataclass
class ApiServer:
    """A uvicorn server running in a daemon thread."""

    server: uvicorn.Server
    thread: threading.Thread
    host: str
    port: int

    @property
    def url(self) -> str:
        """Base URL (``http://host:port``)."""
        return f"http://{_url_host(self.host)}:{self.port}"

    def stop(self, timeout: float = 10.0) -> None:
        """Ask uvicorn to exit and join its thread."""
        self.server.should_exit = True
        self.thread.join(timeout)


#: Connections (and requests) the API serves at once; more get 503 at once.
MAX_CONNECTIONS = 200
#: Connections one client address may hold; a new one beyond it closes that address's oldest idle one.
MAX_CONNECTIONS_PER_CLIENT = 64
#: Connections kept free for others: when more than ``MAX_CONNECTIONS - RESERVE`` are open, a new
#: connection closes the oldest idle connection of the address holding the most.
RESERVE = 16
#: Seconds a new connection may take to send its request line and headers.
HEADER_TIMEOUT = 10.0
#: Seconds an idle keep-alive connection is kept.
KEEP_ALIVE = 5


class _TimedH11(H11Protocol):
    """uvicorn's h11 protocol with a deadline for the request head: a connection that has not sent
    a complete request line and headers within :data:`HEADER_TIMEOUT` seconds is closed (slowloris).
    (Idle keep-alive connections are closed after :data:`KEEP_ALIVE` s by uvicorn itself; bodies
    are read against a deadline by the API's body-limit middleware.)"""

    header_timeout = HEADER_TIMEOUT
    _head_timer: asyncio.TimerHandle | None
    per_client = MAX_CONNECTIONS_PER_CLIENT
    room = MAX_CONNECTIONS - RESERVE

    def connection_made(self, transport: Any) -> None:
        super().connection_made(transport)
        self._opened = time.monotonic()
        self._head_timer = self.loop.call_later(self.header_timeout, self._head_deadline)
        self._make_room()

    def _idle(self) -> bool:
        """No request in progress: head not sent yet, or a keep-alive connection between requests."""
        return self.cycle is None or self.cycle.response_complete

    def _make_room(self) -> None:
        """Fairness between clients (a client is a peer address): one address holds at most
        ``per_client`` connections, and ``MAX_CONNECTIONS - room`` stay free for others; a new
        connection over either bound closes the oldest *idle* connection (no request in progress)
        of its own address, or else of the address holding the most. Busy connections are never
        closed; if none is idle the new one gets uvicorn's 503 when the total is reached."""
        me = self.client[0] if self.client else None
        others = [p for p in list(self.connections) if p is not self and isinstance(p, _TimedH11)]
        by_addr: dict[str | None, list[_TimedH11]] = {}
        for p in others:
            by_addr.setdefault(p.client[0] if p.client else None, []).append(p)
        mine = by_addr.get(me, [])
        if len(mine) >= self.per_client:
            pool = mine
        elif len(others) + 1 > self.room:
            pool = max(by_addr.values(), key=len, default=[])
        else:
            return
        idle = [p for p in pool if p._idle() and not p.transport.is_closing()]
        if idle:
            min(idle, key=lambda p: p._opened).transport.close()

    def _head_deadline(self) -> None:
        if self.cycle is None and not self.transport.is_closing():
            self.transport.close()

    def handle_events(self) -> None:
        self._opened = time.monotonic()  # activity: the oldest idle connection is the longest unused
        super().handle_events()
        timer = getattr(self, "_head_timer", None)
        if self.cycle is not None and timer is not None:
            timer.cancel()
            self._head_timer = None

    def connection_lost(self, exc: Exception | None) -> None:
        timer = getattr(self, "_head_timer", None)
        if timer is not None:
            timer.cancel()
            self._head_timer = None
        super().connection_lost(exc)


def start_api(app: Any, host: str = "127.0.0.1", port: int = 8081, *, log_level: str = "warning",
              timeout: float = 20.0, trusted_proxy: str | None = None,
              header_timeout: float = HEADER_TIMEOUT) -> ApiServer:
    """Start uvicorn for ``app`` in a daemon thread and wait until it accepts connections.

    Args:
        port: TCP port; 0 picks a free one (read it from the returned ``port``).
        trusted_proxy: address(es) of reverse proxies whose ``X-Forwarded-For`` is believed (comma
            separated, uvicorn's ``forwarded_allow_ips``); ``None``: forwarded headers are ignored
            and a client is its connection's peer address (they cannot pretend to be many).
        header_timeout: seconds a connection may take to send its request head.

    Raises:
        RuntimeError: the server did not start (e.g. the port is in use).
    """
    config = uvicorn.Config(app, host=host, port=port, log_level=log_level, access_log=False,
                            lifespan="off", timeout_graceful_shutdown=3,
                            http=type("TimedH11", (_TimedH11,), {"header_timeout": float(header_timeout)}),
                            proxy_headers=bool(trusted_proxy), forwarded_allow_ips=trusted_proxy or "",
                            limit_concurrency=MAX_CONNECTIONS, timeout_keep_alive=KEEP_ALIVE,
                            h11_max_incomplete_event_size=16384)
    server = uvicorn.Server(config)
    errors: list[BaseException] = []

    def run() -> None:
        try:
            server.run()
        except BaseException as e:  # noqa: BLE001 - uvicorn calls sys.exit(1) on bind failures
            errors.append(e)

    thread = threading.Thread(target=run, name=f"paraspace-api-{port}", daemon=True)
    thread.start()
    deadline = time.monotonic() + timeout
    while not server.started:
        if not thread.is_alive() or time.monotonic() > deadline:
            server.should_exit = True
            why = f"{type(errors[0]).__name__}: {errors[0]}" if errors else "did not start in time"
            raise RuntimeError(f"the API server could not listen on {host}:{port} ({why}); "
                               f"is the port in use? choose another with --api-port")
        time.sleep(0.01)
    actual = port
    for srv in getattr(server, "servers", []) or []:
        for sock in srv.sockets:
            actual = int(sock.getsockname()[1])
            break
    return ApiServer(server=server, thread=thread, host=host, port=actual)


@dataclasses.dataclass
class Running:
    """The running explorer and API; ``stop()`` shuts everything down (idempotent)."""

    jobs: JobManager
    api: ApiServer
    explorer: Any = None
    _stopped: bool = False

    @property
    def api_url(self) -> str:
        """Base URL of the REST API."""
        return self.api.url

    @property
    def explorer_url(self) -> str | None:
        """URL of the viser explorer (``None`` when it was not started)."""
        if self.explorer is None:
            return None
        return str(self.explorer.url)

    def stop(self) -> None:
        """Cancel running jobs, stop the explorer and the API server."""
        if self._stopped:
            return
        self._stopped = True
        self.jobs.shutdown(wait=False)
        if self.explorer is not None:
            try:
                self.explorer.stop()
            except Exception:  # noqa: BLE001 - stopping must not raise
                log.exception("stopping the explorer failed")
        self.api.stop()

    def wait(self) -> None:
        """Block until Ctrl-C / SIGTERM, then :meth:`stop`."""
        stop = threading.Event()
        previous = {}
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                previous[sig] = signal.signal(sig, lambda *_: stop.set())
        try:
            while not stop.is_set() and self.api.thread.is_alive():
                stop.wait(0.5)
        except KeyboardInterrupt:
            pass
        finally:
            for sig, handler in previous.items():
                signal.signal(sig, handler)
            print("\nparaspace: shutting down ...", file=sys.stderr, flush=True)
            self.stop()


NO_AUTH_NOTICE = ("paraspace has no authentication: anyone who can reach these ports can use them. "
                  "Bind to 127.0.0.1 (the default), or put the server behind a reverse proxy that adds "
                  "authentication (and pass --public-url and --trusted-proxy).")


def check_public_url(url: str) -> str:
    """``url`` as the explorer's public base URL (``http(s)://host[:port][/path]``), or
    :class:`ParameterError` naming ``public-url``."""
    parts = urllib.parse.urlsplit(url.strip())
    if parts.scheme not in ("http", "https") or not parts.hostname or parts.query or parts.fragment:
        raise ParameterError("public-url", url, "an http:// or https:// URL with a host and no query, "
                                                "e.g. https://robots.example.org/paraspace")
    return urllib.parse.urlunsplit(parts).rstrip("/") + "/"


def serve(host: str = "127.0.0.1", port: int = 8080, api_port: int = 8081, *, block: bool = True,
          explorer: bool = True, limits: ApiLimits = ApiLimits(), max_workers: int = 2,
          quiet: bool = False, public_url: str | None = None,
          trusted_proxy: str | None = None, allowed_hosts: tuple[str, ...] = ()) -> Running:
    """Start the explorer on ``port`` and the API on ``api_port`` (both on ``host``).

    Args:
        host: interface to bind (``0.0.0.0`` in a container; ``127.0.0.1`` by default).
        port: viser explorer port (viser moves to the next free port when busy; the printed URL is
            the real one). 0 picks a free port.
        api_port: REST API port (fails clearly when busy). 0 picks a free port.
        block: wait for Ctrl-C / SIGTERM, then stop everything and return.
        explorer: also start the viser explorer (False: API only).
        limits: API resource limits; ``limits.max_jobs_*`` also bound the shared JobManager.
        max_workers: computation threads shared by the explorer and the API.
        quiet: do not print the URLs.
        public_url: the explorer's URL as users reach it (behind a proxy); short links and the
            landing page point there. Default: ``http://{host}:{port}/`` (loopback for a wildcard
            bind). The request's Host header is never used to build a link.
        trusted_proxy: see :func:`start_api`.
        allowed_hosts: host names accepted in a request's ``Host`` header besides the loopback
            names, the bind address and ``public_url``'s host (``"*"``: any host); see
            :mod:`paraspace.app.hostcheck`.

    Returns:
        The :class:`Running` servers (already stopped when ``block`` is true).

    Raises:
        ParameterError: ``api_port`` cannot be bound (in use); names ``api-port``.
    """
    memory.limit_arenas()  # before the worker threads start: freed memory returns to the system
    jobs = JobManager(max_workers=max_workers, max_jobs_total=max(limits.max_jobs_total, 16),
                      max_jobs_per_client=max(limits.max_jobs_per_client, 4),
                      max_seconds=max(limits.max_job_seconds, 1.0))
    exp = None
    try:
        if public_url:
            public_url = check_public_url(public_url)
        if explorer:
            from .explorer import Explorer

            exp = Explorer(host, port, jobs)
            exp.start()
            exp.set_hosts(HostPolicy.for_server(host, explorer_port=exp.port, public_url=public_url,
                                                allowed_hosts=allowed_hosts))
        # Links are built from configuration only, never from a request's Host header.
        if exp is None:
            explorer_url = None
        elif public_url:
            explorer_url = check_public_url(public_url)
        else:
            explorer_url = f"http://{_bracket(_url_host(host))}:{int(exp.port)}/"
        if api_port == 0:
            api_port = free_port(_url_host(host))
        api_url: str | None = f"http://{_bracket(_url_host(host))}:{api_port}"
        if public_url:  # behind a proxy the API's public address is the proxy's business: relative links
            api_url = None
        hosts = HostPolicy.for_server(host, explorer_port=exp.port if exp is not None else None,
                                      public_url=public_url, allowed_hosts=allowed_hosts)
        app = create_api(jobs, explorer_url=explorer_url, limits=limits, api_url=api_url, hosts=hosts)
        try:
            api = start_api(app, host, api_port, trusted_proxy=trusted_proxy)
        except RuntimeError as e:
            raise ParameterError("api-port", api_port, f"a free TCP port on {host} ({e})") from None
    except BaseException:
        jobs.shutdown(wait=False)
        if exp is not None:
            exp.stop()
        raise
    running = Running(jobs=jobs, api=api, explorer=exp)
    threading.Thread(target=_warm_up, args=(quiet,), name="paraspace-warmup-api", daemon=True).start()
    if not quiet:
        if exp is not None:
            print(f"paraspace explorer: {running.explorer_url}", flush=True)
        print(f"paraspace API:      {api.url}{'/api/v1'}  (docs: {api.url}/docs)", flush=True)
        if host in ("0.0.0.0", "::"):
            print(f"  (bound to {host}: reachable from other machines on these ports)", flush=True)
        print(NO_AUTH_NOTICE, flush=True)
    if block:
        running.wait()
    return running


def _warm_up(quiet: bool) -> None:
    """Compile every kernel a request can reach (kinematics/warmup.py), then say so."""
    from paraspace.kinematics.warmup import warm_up

    try:
        seconds = warm_up()
    except Exception:  # noqa: BLE001 - a failed warm-up leaves the first requests slower, not broken
        log.exception("warm-up failed")
        return
    if not quiet:
        print(f"paraspace: warm-up done ({seconds:.1f} s): every request now answers without compiling",
              flush=True)


def _bracket(host: str) -> str:
    return f"[{host}]" if ":" in host and not host.startswith("[") else host
