"""What every router of the API shares: the job manager, the limits, the caches (:class:`ApiContext`).

One :class:`ApiContext` is made per application by ``create_api`` and kept in ``app.state.api``; a
route receives it through the FastAPI dependency :data:`Ctx`. It submits jobs through the limits
(quota per client and in all, grid estimates at most two at a time), turns cached results into
instantly finished jobs, and answers a job as 200 (done within ``wait``) or 202 (accepted).
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import threading
import time
from collections.abc import Callable, Hashable
from typing import TYPE_CHECKING, Annotated, Any

from fastapi import APIRouter, Depends, Query, Request
from fastapi.responses import JSONResponse

import paraspace
from paraspace.kinematics.bytecache import ByteLRU
from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.serialize import jsonable

from ..jobs import Job, JobManager, LimitExceeded
from ..limits import check_workspace_grid
from .errors import ERROR_RESPONSES, RANGES, ApiError
from .limits import ApiLimits

if TYPE_CHECKING:  # pragma: no cover - types only (imported where it is used)
    from paraspace.kinematics.sweep import ResultCache

API_PREFIX = "/api/v1"
API_VERSION = paraspace.__version__  # the package metadata, stated once (pyproject.toml)
CLIENT_PREFIX = "api:"


def api_router() -> APIRouter:
    """A resource's router: under :data:`API_PREFIX`, declaring the error answers of every endpoint."""
    return APIRouter(prefix=API_PREFIX, responses=ERROR_RESPONSES)


#: The ``?wait=`` query of the job-submitting endpoints.
WAIT_QUERY: Any = Query(0.0, ge=0.0, le=60.0, allow_inf_nan=False,
                        description="seconds to wait for the job before answering; valid range [0, 60]")
RANGES[("query", "wait")] = "[0, 60] seconds"


@dataclasses.dataclass
class ApiResult:
    """What an API job returns: the raw core object (for shells) and the JSON payload."""

    raw: Any
    payload: dict[str, Any]


def _payload_only(result: Any) -> Any:
    """What the job history keeps of an API result it cannot afford: the JSON payload."""
    return ApiResult(raw=None, payload=result.payload) if isinstance(result, ApiResult) else None


def _drop_raw(result: Any) -> None:
    if isinstance(result, ApiResult):
        result.raw = None


class ApiContext:
    """The state one API application shares between its routers.

    Attributes:
        jobs: the shared job manager (the explorer uses the same one).
        limits: the resource limits.
        explorer_url: the explorer's base URL for short links (``None``: links disabled).
        api_url: this API's base URL as clients reach it (``None``: links are paths).
        caches: finished results per kind (workspace, orientation, sweep, optimize), by bytes.
        shells: exported shell files by (job, format, max_faces), by bytes.
        sweep_cache: the design-point cache shared by sweeps and optimisations (or ``None``).
    """

    def __init__(self, jobs: JobManager, limits: ApiLimits, explorer_url: str | None,
                 api_url: str | None) -> None:
        self.jobs, self.limits, self.explorer_url, self.api_url = jobs, limits, explorer_url, api_url
        # The workspace cache owns the voxel grids: an evicted result drops its grid (its measures stay),
        # so memory is bounded by cache_bytes however many jobs the history remembers (the job history
        # keeps only the JSON payload of results it cannot afford: JobManager(history_bytes=...)).
        self.caches: dict[str, ByteLRU] = {
            "workspace": ByteLRU(limits.cache_bytes, on_evict=_drop_raw),
            "orientation": ByteLRU(limits.cache_bytes), "sweep": ByteLRU(limits.cache_bytes),
            "optimize": ByteLRU(limits.cache_bytes), "task": ByteLRU(limits.cache_bytes)}
        self.shells = ByteLRU(limits.shell_cache_bytes)
        self.shell_builds = threading.BoundedSemaphore(2)  # marching cubes at most twice at a time
        self._shell_locks = [threading.Lock() for _ in range(32)]  # one build per shell file at a time
        self._submit_lock = threading.Lock()
        self._precheck_slots = threading.BoundedSemaphore(2)  # grid estimates (a coarse scout each) at once
        self.sweep_cache: ResultCache | None = None
        try:
            from paraspace.kinematics.sweep import ResultCache

            self.sweep_cache = ResultCache()
        except Exception:  # noqa: BLE001 - optional: the sweep module may be absent or differ
            self.sweep_cache = None

    # ----- who asks, and how many jobs they have -----------------------------------------------
    def shell_key_lock(self, key: tuple[Any, ...]) -> threading.Lock:
        """The lock that serialises building the shell file ``key`` (striped: 32 locks), so that
        concurrent downloads of one file build it once and the others read the cache."""
        return self._shell_locks[hash(key) % len(self._shell_locks)]

    def client_of(self, request: Request) -> str:
        """The caller's identity: ``limits.client_header`` when set, else the peer address."""
        ident = None
        if self.limits.client_header:
            ident = request.headers.get(self.limits.client_header)
        if not ident:
            ident = request.client.host if request.client else "unknown"
        return CLIENT_PREFIX + ident.strip()[:100]

    def live_api_jobs(self) -> list[Job]:
        """Unfinished, uncancelled jobs submitted through the API."""
        return [j for j in self.jobs.active() if j.client.startswith(CLIENT_PREFIX) and not j.cancel_token.is_set()]

    def quota_check(self, request: Request | None, client: str | None = None,
                    live: list[Job] | None = None) -> None:
        """429 at once when the caller or the server is at its job limit (nothing computed yet)."""
        limits = self.limits
        client = client or self.client_of(request)  # type: ignore[arg-type]
        live = self.live_api_jobs() if live is None else live
        if sum(1 for j in live if j.client == client) >= limits.max_jobs_per_client:
            raise ApiError(429, f"too many unfinished jobs for this client: limit max_jobs_per_client = "
                                f"{limits.max_jobs_per_client}; wait for one to finish or cancel it "
                                f"(DELETE {API_PREFIX}/jobs/{{id}})", {"Retry-After": "1"})
        if len(live) >= limits.max_jobs_total:
            raise ApiError(429, f"server busy: limit max_jobs_total = {limits.max_jobs_total} unfinished "
                                f"jobs reached; retry later", {"Retry-After": "2"})

    @contextlib.contextmanager
    def prechecks(self) -> Any:
        """A slot for a grid estimate (at most two at once); 429 when none frees within 10 s."""
        if not self._precheck_slots.acquire(timeout=10.0):
            raise ApiError(429, "server busy estimating other requests; retry later", {"Retry-After": "2"})
        try:
            yield
        finally:
            self._precheck_slots.release()

    def grid_check(self, design: Design, settings: Any, *, analytic: bool = False,
                   point: int | None = None) -> None:
        """413 with the grid rule's message (app/limits.py) when the grid is over max_voxels."""
        try:
            check_workspace_grid(design, settings, self.limits.max_voxels, analytic=analytic)
        except ParameterError as exc:
            where = "" if point is None else f"sweep point {point}: "
            raise ApiError(413, f"{where}{exc} (limit max_voxels = {self.limits.max_voxels})") from None

    # ----- submitting --------------------------------------------------------------------------
    def submit(self, request: Request, kind: str, key: Hashable, compute: Callable[[Any, Any], ApiResult]) -> Job:
        """Submit through the limits; a cached result becomes an instantly finished job."""
        client = self.client_of(request)
        cache = self.caches[kind]
        cached = cache.get(key)
        fn: Callable[[Any, Any], Any] = (lambda p, c: cached) if cached is not None else compute
        ckey = ("cached", key) if cached is not None else key

        def on_done(job: Job) -> None:
            if job.status == "done" and cached is None and isinstance(job.result, ApiResult):
                cache.put(key, job.result)

        with self._submit_lock:  # check and submit atomically: the limits hold under concurrent requests
            return self._submit_locked(client, kind, ckey, fn, on_done, hit=cached is not None)

    def _submit_locked(self, client: str, kind: str, ckey: Hashable, fn: Callable[[Any, Any], Any],
                       on_done: Callable[[Job], None], *, hit: bool) -> Job:
        live = self.live_api_jobs()
        same = [j for j in live if j.client == client and j.kind == kind and j.key == ckey]
        # a cache hit computes nothing: only the job manager's own limits apply to it
        if not same and not hit:
            self.quota_check(None, client, live)
        try:
            return self.jobs.submit(fn, kind=kind, client=client, key=ckey, on_done=on_done,
                                    max_seconds=self.limits.max_job_seconds, summarize=_payload_only)
        except LimitExceeded as e:
            raise ApiError(429, str(e), {"Retry-After": "2"}) from None
        except RuntimeError as e:
            raise ApiError(409, f"not accepting jobs: {e}") from None

    # ----- answering about jobs ------------------------------------------------------------------
    def job_links(self, job: Job) -> dict[str, str]:
        """The URLs of a job's status, result and cancel (and a workspace's measures and shells)."""
        base = f"{API_PREFIX}/jobs/{job.id}"
        links = {"status": base, "result": f"{base}/result", "cancel": base}
        if job.kind == "workspace":
            links["measures"] = f"{API_PREFIX}/workspace/{job.id}"
            for fmt in ("stl", "ply", "obj", "glb"):
                links[f"shell_{fmt}"] = f"{API_PREFIX}/workspace/{job.id}/shell.{fmt}"
        return links

    async def job_response(self, job: Job, wait: float, cached: bool) -> JSONResponse:
        """200 with the result when the job is done within ``wait`` seconds, else 202 with its links."""
        # Waiting happens on the event loop (no thread is held), so many waiting callers cannot
        # exhaust the thread pool that runs the synchronous endpoints.
        if wait > 0:
            deadline = time.monotonic() + wait
            step = 0.002
            while not job.is_final and time.monotonic() < deadline:
                await asyncio.sleep(min(step, max(0.0, deadline - time.monotonic())))
                step = min(step * 1.5, 0.05)
        body: dict[str, Any] = {"job_id": job.id, "status": job.status, "cached": cached,
                                "job": job.to_dict(), "links": self.job_links(job)}
        if job.status == "done" and isinstance(job.result, ApiResult):
            body["result"] = job.result.payload
            return JSONResponse(status_code=200, content=jsonable(body))
        return JSONResponse(status_code=202, content=jsonable(body),
                            headers={"Location": f"{API_PREFIX}/jobs/{job.id}"})

    def api_job(self, job_id: str, kind: str | None = None) -> Job:
        """The API job ``job_id`` (of ``kind`` when given); 404 when unknown or not the API's."""
        try:
            job = self.jobs.get(job_id)
        except KeyError:
            job = None
        if job is None or not job.client.startswith(CLIENT_PREFIX) or (kind is not None and job.kind != kind):
            what = f"{kind} job" if kind else "job"
            raise ApiError(404, f"no {what} with id {job_id!r} (unknown, or expired from the history)")
        return job

    def finished_result(self, job: Job) -> ApiResult:
        """The job's full result (from the cache when the history kept only the payload); 409 or
        410 with the reason when there is none."""
        if job.status == "done" and isinstance(job.result, ApiResult):
            if job.result.raw is None and job.kind in self.caches:  # the history kept only the payload
                key = job.key[1] if isinstance(job.key, tuple) and job.key[:1] == ("cached",) else job.key
                full = self.caches[job.kind].get(key)
                if isinstance(full, ApiResult):
                    return full
            return job.result
        if job.status == "done" and job.result_dropped:
            raise ApiError(410, f"job {job.id} finished, but its result was dropped from memory (the "
                                f"history's byte budget); submit the same request again to recompute it")
        if job.status in ("queued", "running"):
            raise ApiError(409, f"job {job.id} is {job.status} ({100 * job.progress:.0f}%): "
                                f"the result is available when its status is done",
                           {"Retry-After": "1"})
        why = job.error or job.message
        raise ApiError(409, f"job {job.id} ended {job.status}: {why}; it has no result")


async def api_context(request: Request) -> ApiContext:
    """FastAPI dependency: the application's :class:`ApiContext` (async, so that it runs on the
    event loop and never waits for the thread pool)."""
    return request.app.state.api


#: A route parameter ``ctx: Ctx`` receives the application's :class:`ApiContext`.
Ctx = Annotated[ApiContext, Depends(api_context)]
