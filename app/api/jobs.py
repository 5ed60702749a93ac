"""Routes of the generic jobs: list the caller's, status, cancel and result (``/jobs...``)."""

from __future__ import annotations

from typing import Any

from fastapi import Request

from paraspace.kinematics.serialize import jsonable

from .context import Ctx, api_router
from .errors import ApiError

router = api_router()


@router.get("/jobs", summary="The caller's unfinished jobs")
async def my_jobs(request: Request, ctx: Ctx) -> dict[str, Any]:
    """Queued and running jobs of this client (oldest first)."""
    return {"jobs": [j.to_dict() for j in ctx.jobs.active(ctx.client_of(request))]}


@router.get("/jobs/{job_id}", summary="Status and progress of a job")
async def job_status(job_id: str, request: Request, ctx: Ctx) -> dict[str, Any]:
    """``status`` is queued, running, done, failed or cancelled; ``progress`` in [0, 1]."""
    job = ctx.api_job(job_id)
    return jsonable({**job.to_dict(), "links": ctx.job_links(job)})


#: Longest wait of a DELETE for the job to reach its final status.
CANCEL_WAIT_SECONDS = 10.0


@router.delete("/jobs/{job_id}", summary="Cancel a job")
def job_cancel(job_id: str, request: Request, ctx: Ctx) -> dict[str, Any]:
    """Only the client that submitted a job may cancel it; cancelling a finished job is a no-op
    (``cancelled: false``). A running job stops at its next cancellation check: the answer waits
    for that (at most :data:`CANCEL_WAIT_SECONDS`), so its ``status`` is ``cancelled``; a job
    still stopping after that answers ``running`` with the message ``cancel requested``."""
    job = ctx.api_job(job_id)
    if job.client != ctx.client_of(request):
        raise ApiError(403, f"job {job_id} belongs to another client; only its submitter may cancel it")
    ok = ctx.jobs.cancel(job_id)
    if ok:
        job.wait(CANCEL_WAIT_SECONDS)
    return jsonable({"cancelled": ok, **job.to_dict()})


@router.get("/jobs/{job_id}/result", summary="Result of a finished job")
def job_result(job_id: str, request: Request, ctx: Ctx) -> dict[str, Any]:
    """The JSON result (409 while running, or when the job failed or was cancelled)."""
    job = ctx.api_job(job_id)
    return jsonable({"job": job.to_dict(), "result": ctx.finished_result(job).payload})
