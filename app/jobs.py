"""The one worker machinery shared by the explorer and the REST API.

A :class:`JobManager` runs callables ``fn(progress, cancel)`` on a small pool of threads (the
numba kernels release the GIL, so threads compute in parallel). Every job is a :class:`Job` that
can be polled (status, progress, message), waited for and cancelled.

Semantics:

* **Cooperative cancellation.** ``fn`` receives ``cancel`` (a :class:`threading.Event`) and must
  check it between chunks of work; the core raises :class:`kinematics.progress.Cancelled`, which
  ends the job as ``"cancelled"``. The ``progress(fraction, message)`` callable given to ``fn``
  also raises ``Cancelled`` once the token is set, so a function that reports progress is
  cancellable even if it never looks at the token itself.
* **Failures never escape.** Any other exception ends the job as ``"failed"`` with a one-line
  ``error`` (``"ValueError: ..."``); the worker thread survives.
* **Time limit.** A watchdog sets the cancel token of a job running longer than its time limit
  (``max_seconds``); the job is reported ``"failed"`` with ``"time limit of N s exceeded"`` at
  once, whether or not ``fn`` cooperates (a non-cooperating ``fn`` keeps its worker busy until it
  returns, and its result is discarded).
* **Limits.** ``submit`` raises :class:`LimitExceeded` at once when the client already has
  ``max_jobs_per_client`` unfinished jobs or the manager ``max_jobs_total``: work is never queued
  without bound. Jobs whose cancellation was requested do not count (they hold no queue slot and
  at most ``max_workers`` of them are still winding down).
* **Supersede** ("the last slider value wins"). ``submit(..., supersede=True)`` first cancels the
  client's unfinished jobs of the same ``kind``. Once a job's cancellation is requested it can no
  longer end ``"done"``: a result that arrives later is dropped and the job ends ``"cancelled"``.
* **Dedupe by key.** When ``key`` is given and the same client already has an unfinished,
  non-cancelled job of the same ``kind`` and ``key``, that job is returned instead of starting a
  second identical computation (``on_done`` is attached to it).
* **History.** Finished jobs are kept for polling, the most recent ``history`` of them; their
  results together are bounded by ``history_bytes`` (estimated with
  :func:`paraspace.kinematics.bytecache.nbytes`): the oldest finished jobs lose their result first (the job
  stays, with ``result_dropped = True``), so a page that closed leaves no grid behind.
* **Fair queueing.** Workers take the queued job of the client with the fewest running jobs (then
  the oldest), and one client never runs more than ``max_running_per_client`` jobs *of one kind*
  at once (default ``max_workers - 1``, at least 1): another client's small job finds a free worker
  instead of waiting behind one client's batch of heavy jobs, while one explorer page may still
  compute its shell and its orientation maps side by side. (The numba kernels are serialised by
  ``kinematics.parallel.KERNEL_LOCK`` and use every core, so a client loses little by this cap.)
  Besides the ``max_workers`` workers, one *reserve* worker runs only a job of a client that has
  nothing running: whatever kinds one client keeps busy, another client's job starts at once.

``on_done(job)`` is called exactly once per submission when the job reaches a final status
(``done``, ``failed`` or ``cancelled``); check ``job.status``. It runs in the worker thread (or, for
a job cancelled while still queued, in the thread that cancelled it) and must not block long;
exceptions it raises are logged and ignored.
"""

from __future__ import annotations

import collections
import errno
import logging
import secrets
import threading
import time
from collections.abc import Callable, Hashable
from typing import Any, Literal

from paraspace.kinematics.bytecache import nbytes
from paraspace.kinematics.progress import Cancelled

__all__ = ["Job", "JobManager", "LimitExceeded", "JobStatus", "ProgressFn", "FINAL_STATUSES"]

log = logging.getLogger(__name__)

JobStatus = Literal["queued", "running", "done", "failed", "cancelled"]
FINAL_STATUSES: frozenset[str] = frozenset({"done", "failed", "cancelled"})
ProgressFn = Callable[[float, str], None]
JobFn = Callable[[ProgressFn, threading.Event], Any]


class LimitExceeded(Exception):
    """A submission would exceed a resource limit; the message names the limit and its value.

    Attributes:
        limit: name of the limit (``"max_jobs_per_client"``, ``"max_jobs_total"``, ...).
        value: the limit's value.
    """

    def __init__(self, limit: str, value: Any, message: str) -> None:
        self.limit = limit
        self.value = value
        super().__init__(message)


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, errno.EDQUOT):
        return "the server's disk is full (No space left on device); free some space and retry"
    text = " ".join(str(exc).split())
    name = type(exc).__name__
    text = f"{name}: {text}" if text else name
    return text if len(text) <= 500 else text[:497] + "..."


class Job:
    """One unit of work and its observable state.

    Attributes:
        id: unique, unguessable id (16 hex digits).
        kind: what the job computes (``"workspace"``, ``"sweep"``, ...); supersede works per kind.
        client: who submitted it (an IP address, a header value, ``"local"``, a viser client id).
        key: optional hashable identity of the computation (used for dedupe).
        status: ``"queued" | "running" | "done" | "failed" | "cancelled"``.
        progress: fraction in ``[0, 1]``.
        message: last progress message (or the reason of the final status).
        progress_message: the last progress message the work itself reported (kept when the job
            ends, so that a stopped job can say where it was).
        result: ``fn``'s return value once ``done`` (``None`` otherwise).
        error: one-line error of a ``failed`` job, else ``None``.
        created, started, finished: ``time.time()`` stamps (``started``/``finished`` are ``None``
            until then).
    """

    def __init__(self, manager: JobManager, job_id: str, kind: str, client: str,
                 key: Hashable | None, max_seconds: float) -> None:
        self._manager = manager
        self.id = job_id
        self.kind = kind
        self.client = client
        self.key = key
        self.max_seconds = max_seconds
        self.status: JobStatus = "queued"
        self.progress = 0.0
        self.message = "queued"
        self.progress_message = ""
        self.result: Any = None
        self.result_dropped = False  # the history's byte budget dropped the result (see JobManager)
        self._summarize: Any = None  # callable, None (drop), or False (already summarised)
        self.error: str | None = None
        self.created = time.time()
        self.started: float | None = None
        self.finished: float | None = None
        self.cancel_token = threading.Event()
        self._cancel_requested = False
        self._timed_out = False
        self._done_event = threading.Event()
        self._callbacks: list[Callable[[Job], None]] = []
        self._progress_hooks: list[Callable[[Job], None]] = []
        self._t_start = 0.0  # perf_counter at start (watchdog)

    # ----- public ------------------------------------------------------------------------
    @property
    def finished_ok(self) -> bool:
        """Whether the job ended ``"done"``."""
        return self.status == "done"

    @property
    def is_final(self) -> bool:
        """Whether the job reached a final status."""
        return self.status in FINAL_STATUSES

    def wait(self, timeout: float | None = None) -> bool:
        """Block until the job is final; returns whether it is (False on timeout)."""
        return self._done_event.wait(timeout)

    def cancel(self) -> None:
        """Request cancellation (no effect on a finished job)."""
        self._manager.cancel(self.id)

    @property
    def elapsed(self) -> float | None:
        """Seconds it has run, or ran (``None`` while queued)."""
        if self.started is None:
            return None
        return (self.finished or time.time()) - self.started

    def to_dict(self) -> dict[str, Any]:
        """JSON-serializable state (without ``result``)."""
        elapsed = self.elapsed
        return {
            "id": self.id,
            "kind": self.kind,
            "client": self.client,
            "status": self.status,
            "progress": round(float(self.progress), 6),
            "message": self.message,
            "error": self.error,
            "created": self.created,
            "started": self.started,
            "finished": self.finished,
            "elapsed_seconds": None if elapsed is None else round(elapsed, 6),
            "time_limit_seconds": self.max_seconds,
        }

    def __repr__(self) -> str:  # pragma: no cover - debugging aid
        return f"<Job {self.id} {self.kind} {self.client} {self.status} {self.progress:.2f}>"


class JobManager:
    """Runs jobs on a bounded thread pool with limits, supersede, time limit and history.

    Args:
        max_workers: worker threads (jobs running at once).
        max_jobs_total: unfinished (queued + running) jobs allowed over all clients.
        max_jobs_per_client: unfinished jobs allowed per client.
        max_seconds: default run-time limit of a job, in seconds.
        history: finished jobs kept for polling (oldest dropped first).
        history_bytes: budget of the results held by finished jobs (oldest results dropped first).
        max_running_per_client: jobs of one client and one kind running at once (default
            ``max_workers - 1``, at least 1).
    """

    def __init__(self, max_workers: int = 2, max_jobs_total: int = 16, max_jobs_per_client: int = 4,
                 max_seconds: float = 300.0, history: int = 256, history_bytes: int = 64 << 20,
                 max_running_per_client: int | None = None) -> None:
        for name, val in (("max_workers", max_workers), ("max_jobs_total", max_jobs_total),
                          ("max_jobs_per_client", max_jobs_per_client), ("history", history)):
            if not isinstance(val, int) or val < 1:
                raise ValueError(f"{name} = {val!r} is invalid: valid range integers >= 1")
        if not (isinstance(max_seconds, (int, float)) and max_seconds > 0):
            raise ValueError(f"max_seconds = {max_seconds!r} is invalid: valid range > 0")
        self.max_workers = max_workers
        self.max_jobs_total = max_jobs_total
        self.max_jobs_per_client = max_jobs_per_client
        self.max_seconds = float(max_seconds)
        self.history = history
        self.history_bytes = int(history_bytes)
        self.max_running_per_client = (max(1, max_workers - 1) if max_running_per_client is None
                                       else int(max_running_per_client))
        if self.max_running_per_client < 1:
            raise ValueError(f"max_running_per_client = {max_running_per_client!r} is invalid: valid range >= 1")
        self._lock = threading.RLock()
        self._jobs: collections.OrderedDict[str, Job] = collections.OrderedDict()
        self._unfinished: dict[str, Job] = {}
        self._queue: list[tuple[Job, JobFn]] = []
        self._running: collections.Counter[str] = collections.Counter()  # worker occupancy per client
        self._running_kind: collections.Counter[tuple[str, str]] = collections.Counter()  # per (client, kind)
        self._kept: collections.OrderedDict[str, int] = collections.OrderedDict()  # job id -> result bytes
        self._kept_total = 0
        self._departed: collections.OrderedDict[str, None] = collections.OrderedDict()  # forget_client
        self._closed = False
        self._wake = threading.Condition(self._lock)
        self._work = threading.Condition(self._lock)
        self._workers = [threading.Thread(target=self._worker, name=f"paraspace-job-{i}", daemon=True)
                         for i in range(max_workers)]
        self._workers.append(threading.Thread(target=self._worker, args=(True,), name="paraspace-job-reserve",
                                              daemon=True))
        for w in self._workers:
            w.start()
        self._watchdog = threading.Thread(target=self._watch, name="paraspace-job-watchdog", daemon=True)
        self._watchdog.start()

    # ----- submission ----------------------------------------------------------------------
    def submit(self, fn: JobFn, *, kind: str, client: str = "local", key: Hashable | None = None,
               supersede: bool = False, on_done: Callable[[Job], None] | None = None,
               on_progress: Callable[[Job], None] | None = None,
               max_seconds: float | None = None,
               summarize: Callable[[Any], Any] | None = None,
               client_limit: int | None = None) -> Job:
        """Queue ``fn(progress, cancel)`` and return its :class:`Job` at once.

        Args:
            fn: the work; gets ``progress(fraction, message)`` and ``cancel`` (an Event).
            kind: job kind (supersede and dedupe are per kind).
            client: submitter identity (limits are per client).
            key: optional hashable identity of the computation; an unfinished identical job of
                the same client and kind is returned instead of a new one.
            supersede: cancel this client's unfinished jobs of the same kind first.
            on_done: called once with the job when it reaches a final status.
            on_progress: called with the job after each progress update (in the worker thread).
            max_seconds: run-time limit of this job (default: the manager's; never above it).
            summarize: what the history keeps of the result once the results of finished jobs
                exceed ``history_bytes`` (default: nothing).
            client_limit: the client's limit of unfinished jobs for this submission (default
                ``max_jobs_per_client``). The explorer's sessions, whose jobs are bounded by
                construction (one per kind, superseded, plus the pins), pass their own bound.

        Raises:
            LimitExceeded: the client or the manager is at its limit of unfinished jobs.
            RuntimeError: the manager was shut down.
        """
        limit = self.max_seconds if max_seconds is None else min(float(max_seconds), self.max_seconds)
        to_finish: list[Job] = []
        with self._lock:
            if self._closed:
                raise RuntimeError("the job manager is shut down")
            same = None
            if key is not None:
                for job in self._unfinished.values():
                    if (job.client == client and job.kind == kind and job.key == key
                            and not job._cancel_requested):
                        same = job
                        break
            if same is not None:
                if on_done is not None:
                    same._callbacks.append(on_done)
                if on_progress is not None:
                    same._progress_hooks.append(on_progress)
                if supersede:
                    to_finish = self._supersede_locked(kind, client, keep=same)
        if same is not None:
            self._finish_all(to_finish)
            return same
        with self._lock:
            if self._closed:
                raise RuntimeError("the job manager is shut down")
            if supersede:
                to_finish = self._supersede_locked(kind, client, keep=None)
            live = [j for j in self._unfinished.values() if not j._cancel_requested]
            n_client = sum(1 for j in live if j.client == client)
            per_client = self.max_jobs_per_client if client_limit is None else int(client_limit)
            if n_client >= per_client:
                exc = LimitExceeded(
                    "max_jobs_per_client", per_client,
                    f"too many jobs for client {client!r}: limit max_jobs_per_client = "
                    f"{per_client} unfinished jobs; wait for one to finish or cancel it")
            elif len(live) >= self.max_jobs_total:
                exc = LimitExceeded(
                    "max_jobs_total", self.max_jobs_total,
                    f"server busy: limit max_jobs_total = {self.max_jobs_total} unfinished jobs "
                    f"reached; retry later")
            else:
                exc = None
            if exc is None:
                job_id = secrets.token_hex(8)  # unguessable: ids are used to cancel over HTTP
                while job_id in self._jobs:
                    job_id = secrets.token_hex(8)
                job = Job(self, job_id, kind, client, key, limit)
                job._summarize = summarize
                if on_done is not None:
                    job._callbacks.append(on_done)
                if on_progress is not None:
                    job._progress_hooks.append(on_progress)
                self._jobs[job_id] = job
                self._unfinished[job_id] = job
                self._prune_locked()
        self._finish_all(to_finish)
        if exc is not None:
            raise exc
        with self._lock:
            if not job.is_final:
                self._queue.append((job, fn))
                self._work.notify_all()  # the reserve worker may take it, or only a normal one may
        return job

    # ----- queries ---------------------------------------------------------------------------
    def get(self, job_id: str) -> Job:
        """The job with this id (also finished ones still in the history).

        Raises:
            KeyError: unknown (or forgotten) id.
        """
        with self._lock:
            return self._jobs[job_id]

    def active(self, client: str | None = None) -> list[Job]:
        """Unfinished jobs (queued or running), oldest first, optionally of one client."""
        with self._lock:
            jobs = list(self._unfinished.values())
        jobs.sort(key=lambda j: j.created)
        return [j for j in jobs if client is None or j.client == client]

    def jobs(self) -> list[Job]:
        """All jobs in the history (finished and unfinished), oldest first."""
        with self._lock:
            return list(self._jobs.values())

    def stats(self) -> dict[str, Any]:
        """Counts by status and the configured limits (JSON)."""
        with self._lock:
            counts = collections.Counter(j.status for j in self._jobs.values())
        return {"workers": self.max_workers, "max_jobs_total": self.max_jobs_total,
                "max_jobs_per_client": self.max_jobs_per_client, "max_seconds": self.max_seconds,
                "max_running_per_client": self.max_running_per_client,
                "history_result_bytes": self._kept_total, "history_bytes": self.history_bytes,
                "counts": {s: counts.get(s, 0) for s in ("queued", "running", "done", "failed", "cancelled")}}

    # ----- cancellation ----------------------------------------------------------------------
    def cancel(self, job_id: str) -> bool:
        """Request cancellation of a job; returns False when it is unknown or already final.

        A queued job ends ``"cancelled"`` at once; a running job when ``fn`` notices the token.
        """
        with self._lock:
            job = self._jobs.get(job_id)
            if job is None or job.is_final:
                return False
            finish = self._request_cancel_locked(job, "cancelled")
        self._finish_all(finish)
        return True

    def forget_client(self, client: str) -> int:
        """Drop the kept results of ``client``'s finished jobs (a browser that left: nobody will
        fetch them), and keep none of its jobs that finish later; returns how many were dropped."""
        dropped = 0
        with self._lock:
            self._departed[client] = None
            while len(self._departed) > 4096:
                self._departed.popitem(last=False)
            for job_id in list(self._kept):
                job = self._jobs.get(job_id)
                if job is not None and job.client == client and job.is_final:
                    self._kept_total -= self._kept.pop(job_id)
                    job.result, job.result_dropped = None, True
                    dropped += 1
        return dropped

    def shutdown(self, wait: bool = False) -> None:
        """Cancel every unfinished job and stop accepting work.

        Args:
            wait: block until the worker threads have ended.
        """
        with self._lock:
            self._closed = True
            finish: list[Job] = []
            for job in list(self._unfinished.values()):
                finish += self._request_cancel_locked(job, "cancelled: server shutting down")
            self._queue.clear()
            self._wake.notify_all()
            self._work.notify_all()
        self._finish_all(finish)
        if wait:
            for w in self._workers:
                if w is not threading.current_thread():
                    w.join()

    # ----- internals -------------------------------------------------------------------------
    def _supersede_locked(self, kind: str, client: str, keep: Job | None) -> list[Job]:
        out: list[Job] = []
        for job in list(self._unfinished.values()):
            if job is not keep and job.client == client and job.kind == kind and not job._cancel_requested:
                out += self._request_cancel_locked(job, "superseded by a newer request")
        return out

    def _request_cancel_locked(self, job: Job, why: str) -> list[Job]:
        """Mark cancel requested; returns [job] when it can be finalized right away (queued)."""
        job._cancel_requested = True
        job.cancel_token.set()
        job.message = why
        if job.status == "queued":
            self._finalize_locked(job, "cancelled", why)
            return [job]
        return []

    def _finalize_locked(self, job: Job, status: JobStatus, message: str,
                         result: Any = None, error: str | None = None) -> bool:
        if job.is_final:
            return False
        job.status = status
        job.message = message
        job.result = result if status == "done" else None
        job.error = error
        job.finished = time.time()
        if status == "done":
            job.progress = 1.0
        self._unfinished.pop(job.id, None)
        self._prune_locked()
        return True

    def _keep_result_locked(self, job: Job) -> None:
        """Account a finished job's result (after its callbacks ran). Over ``history_bytes``, the
        oldest full results are first replaced by their summary (``summarize``; none: dropped),
        then, if still over, the oldest summaries are dropped too."""
        if job.result is None or job.id not in self._jobs:
            return
        if job.client in self._departed:  # its page left: nobody will fetch it (forget_client)
            job.result, job.result_dropped = None, True
            return
        self._kept[job.id] = self._measure(job.result)
        self._kept_total += self._kept[job.id]
        for old_id in list(self._kept):
            if self._kept_total <= self.history_bytes:
                return
            old = self._jobs.get(old_id)
            if old is None or old._summarize is False:  # already a summary
                continue
            summary = None
            if old._summarize is not None:
                try:
                    summary = old._summarize(old.result)
                except Exception:  # noqa: BLE001
                    log.exception("summarize of job %s raised", old.id)
            old._summarize = False
            self._kept_total -= self._kept.pop(old_id)
            old.result, old.result_dropped = summary, summary is None
            if summary is not None:
                self._kept[old_id] = self._measure(summary)
                self._kept_total += self._kept[old_id]
                self._kept.move_to_end(old_id, last=False)
        while self._kept_total > self.history_bytes and self._kept:
            old_id, m = self._kept.popitem(last=False)
            self._kept_total -= m
            old = self._jobs.get(old_id)
            if old is not None:
                old.result, old.result_dropped = None, True

    def _measure(self, obj: Any) -> int:
        try:
            return nbytes(obj)
        except Exception:  # noqa: BLE001 - an unmeasurable result counts as large
            return self.history_bytes + 1

    def _forget_result_locked(self, job_id: str) -> None:
        m = self._kept.pop(job_id, None)
        if m is not None:
            self._kept_total -= m

    def _finish_all(self, jobs: list[Job]) -> None:
        """Outside the lock: wake waiters and run on_done callbacks of finalized jobs."""
        for job in jobs:
            job._done_event.set()
            callbacks, job._callbacks = job._callbacks, []
            for cb in callbacks:
                try:
                    cb(job)
                except Exception:  # noqa: BLE001 - a callback must not kill the worker
                    log.exception("on_done callback of job %s raised", job.id)
            if job.status == "done":
                with self._lock:
                    self._keep_result_locked(job)

    def _prune_locked(self) -> None:
        excess = len(self._jobs) - len(self._unfinished) - self.history
        if excess <= 0:
            return
        for job_id in list(self._jobs):
            if excess <= 0:
                break
            if self._jobs[job_id].is_final:
                del self._jobs[job_id]
                self._forget_result_locked(job_id)
                excess -= 1

    def _make_progress(self, job: Job) -> ProgressFn:
        def progress(fraction: float, message: str = "") -> None:
            if job.cancel_token.is_set():
                raise Cancelled()
            try:
                f = float(fraction)
            except (TypeError, ValueError):
                f = job.progress
            if f != f:  # NaN
                f = job.progress
            job.progress = min(1.0, max(0.0, f))
            if message:
                job.message = job.progress_message = str(message)
            for hook in list(job._progress_hooks):
                try:
                    hook(job)
                except Exception:  # noqa: BLE001
                    log.exception("on_progress hook of job %s raised", job.id)
        return progress

    def _pick_locked(self, reserve: bool = False) -> tuple[Job, JobFn] | None:
        """The next queued job to run: among jobs whose (client, kind) is under
        ``max_running_per_client``, the one whose client has the fewest running jobs, then the
        oldest submission (for the reserve worker: only jobs of a client with nothing running).
        Drops finalized entries."""
        self._queue = [(j, f) for j, f in self._queue if not j.is_final]
        best = None
        for i, (job, _fn) in enumerate(self._queue):
            if self._running_kind[(job.client, job.kind)] >= self.max_running_per_client:
                continue
            running = self._running[job.client]
            if reserve and (running or sum(self._running.values()) < self.max_workers):
                continue  # the reserve serves a client with nothing running, when every worker is busy
            rank = (running, i)
            if best is None or rank < best[0]:
                best = (rank, i)
        if best is None:
            return None
        return self._queue.pop(best[1])

    def _worker(self, reserve: bool = False) -> None:
        while True:
            with self._lock:
                pick = None
                while not self._closed:
                    pick = self._pick_locked(reserve)
                    if pick is not None:
                        break
                    self._work.wait()
                if pick is None:
                    return
                job, fn = pick
                self._running[job.client] += 1
                self._running_kind[(job.client, job.kind)] += 1
            try:
                self._run(job, fn)
            except BaseException:  # noqa: BLE001 - _run reports every failure; keep the worker alive
                log.exception("worker failed on job %s", job.id)
            finally:
                with self._lock:
                    self._running[job.client] -= 1
                    if self._running[job.client] <= 0:
                        del self._running[job.client]
                    self._running_kind[(job.client, job.kind)] -= 1
                    if self._running_kind[(job.client, job.kind)] <= 0:
                        del self._running_kind[(job.client, job.kind)]
                    self._work.notify_all()

    def _run(self, job: Job, fn: JobFn) -> None:
        with self._lock:
            if job.is_final or job._cancel_requested:
                return  # cancelled while queued (already finalized)
            job.status = "running"
            job.started = time.time()
            job._t_start = time.perf_counter()
            job.message = "running"
            self._wake.notify_all()
        status: JobStatus
        result: Any = None
        error: str | None = None
        try:
            result = fn(self._make_progress(job), job.cancel_token)
            status, message = "done", "done"
        except Cancelled:
            status, message = "cancelled", "cancelled"
        except BaseException as exc:  # noqa: BLE001 - every failure is reported, never raised
            status, error = "failed", _one_line(exc)
            message = "failed"
            if not isinstance(exc, Exception):  # pragma: no cover - KeyboardInterrupt/SystemExit
                log.warning("job %s interrupted: %s", job.id, error)
        with self._lock:
            if job._timed_out:
                return  # the watchdog already reported it failed
            if job._cancel_requested and status == "done":
                status, message, result = "cancelled", job.message or "cancelled", None
            elif job._cancel_requested and status == "cancelled":
                message = job.message or "cancelled"
            finalized = self._finalize_locked(job, status, message, result, error)
        if finalized:
            self._finish_all([job])

    def _watch(self) -> None:
        while True:
            expired: list[Job] = []
            with self._lock:
                if self._closed and not self._unfinished:
                    return
                now = time.perf_counter()
                next_due = 0.5
                for job in list(self._unfinished.values()):
                    if job.status != "running":
                        continue
                    due = job._t_start + job.max_seconds - now
                    if due <= 0:
                        job._timed_out = True
                        job._cancel_requested = True
                        job.cancel_token.set()
                        err = f"time limit of {job.max_seconds:g} s exceeded"
                        self._finalize_locked(job, "failed", err, error=err)
                        expired.append(job)
                    else:
                        next_due = min(next_due, due)
                if not expired:
                    self._wake.wait(timeout=max(0.01, next_due))
            self._finish_all(expired)
