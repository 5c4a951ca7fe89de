"""``/v1/jobs``: submit, list, follow, fetch and cancel labeling jobs."""

from __future__ import annotations

import re
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Depends, Header, HTTPException, Query, Request, Response
from starlette.concurrency import run_in_threadpool

from service.errors import InputError
from service.server.auth import caller
from service.server.bodies import read_submission, request_body
from service.server.results import MEDIA_TYPES, attachment, job_file
from service.server.schemas import ErrorBody, JobAccepted, JobPage, JobStatus, JobSummary, LabeledResult, WindowSummary
from service.server.store import ACTIVE, Job, JobStore
from service.server.tables import JobState

ERRORS: dict[int | str, dict[str, Any]] = {
    401: {"model": ErrorBody}, 404: {"model": ErrorBody, "description": "No such job for this caller."}}
JOB_ID = re.compile(r"[0-9a-f]{32}")
router = APIRouter(prefix="/v1/jobs", tags=["jobs"], responses={401: {"model": ErrorBody}})


def _store(request: Request) -> JobStore:
    return request.app.state.store


async def _job(request: Request, job_id: str, owner: str) -> Job:
    """The caller's job; another owner's job is 404 too, so its existence is not revealed.

    An id that is not 32 hex digits (what ``JobStore.add`` makes) is no job: the store
    never sees it (PostgreSQL refuses text with a NUL byte).
    """
    job = await run_in_threadpool(_store(request).get, job_id, owner) if JOB_ID.fullmatch(job_id) else None
    if job is None:
        raise HTTPException(404, f"no job {job_id}")
    return job


async def _status(request: Request, job: Job) -> JobStatus:
    windows = await run_in_threadpool(_store(request).windows, job.id)
    warnings = await run_in_threadpool(job_warnings, request, job)
    return JobStatus(**JobSummary.of(job).model_dump(), windows=[WindowSummary.of_stored(w) for w in windows],
                     warnings=warnings)


def job_warnings(request: Request, job: Job) -> list[str]:
    """What the job's status says beside its figures: once done, what the labeling warns of; while
    queued, why it may not start soon (``Executor.waiting``). Blocking: the store and the cluster."""
    if job.state in ("done", "running"):  # a running job's: its second pass's progress (``JobStore.note``)
        return _store(request).warnings(job.id)
    idle = request.app.state.executor.waiting() if job.state == "queued" else None
    return [idle] if idle else []


@router.post(
    "", status_code=202, response_model=JobAccepted, openapi_extra=request_body(
        "A capture document (JSON), or a labeled .c3d/.trc/.csv upload relabeled from its first frame.", upload=True),
    responses={413: {"model": ErrorBody}, 415: {"model": ErrorBody}, 422: {"model": ErrorBody},
               429: {"model": ErrorBody, "description": "The queue is full; retry after the Retry-After seconds."}},
)
async def submit_job(
    request: Request, response: Response, owner: str = Depends(caller),
    idempotency_key: str | None = Header(
        None, alias="Idempotency-Key", pattern=r"^[!-~]{1,200}$",
        description="Any printable ASCII up to 200 characters, new for each capture: a retried POST with the "
                    "same key (and token) and the same capture gets the job the first one made, not a second job; "
                    "the key with another capture is a 422."),
) -> JobAccepted:
    """Queue a capture for labeling; answered once the job and its input are committed."""
    store, settings = _store(request), request.app.state.settings
    earlier, queued = await run_in_threadpool(store.intake, owner, idempotency_key)  # one thread hop
    if earlier is None and queued >= settings.max_queued_jobs:
        raise HTTPException(429, f"{queued} jobs are queued, the limit (max_queued_jobs); retry later",
                            headers={"Retry-After": str(settings.retry_after_seconds)})
    # read and checked even for a retry: a key reused for another capture must not answer with the first's job
    submission = await read_submission(request, settings.limits, upload=True)
    if earlier is not None:
        await _same_capture(store, earlier, submission.stored())
        return _accepted(response, earlier)
    job, new = await run_in_threadpool(store.add, owner, submission.source, submission.stored(), submission.n_windows,
                                       idempotency_key, submission.upload)
    if not new:  # a concurrent POST with the key committed first: the same check as above
        await _same_capture(store, job, submission.stored())
        return _accepted(response, job)
    await run_in_threadpool(request.app.state.executor.submit, job.id)
    idle = await run_in_threadpool(request.app.state.executor.waiting)
    return _accepted(response, job, [*submission.warnings, *([idle] if idle else [])])


async def _same_capture(store: JobStore, earlier: Job, stored: bytes) -> None:
    """A key reused for another capture must not answer with the first capture's job."""
    if await run_in_threadpool(store.input, earlier.id) != stored:
        raise InputError(f"Idempotency-Key: already used for another capture (job {earlier.id}); use a new key")


def _accepted(response: Response, job: Job, warnings: list[str] | None = None) -> JobAccepted:
    base = f"/v1/jobs/{job.id}"
    response.headers["Location"] = base
    return JobAccepted(**JobSummary.of(job).model_dump(), warnings=warnings or [],
                       links={"status": base, "events": f"{base}/events", "result": f"{base}/result"})


@router.get("", response_model=JobPage)
async def list_jobs(
    request: Request, owner: str = Depends(caller),
    limit: int = Query(50, ge=1, le=500), offset: int = Query(0, ge=0, le=2**62),
    state: Annotated[JobState | None, Query(description="Only jobs in this state; another value is 422.")] = None,
) -> JobPage:
    """The caller's jobs, newest first; ``total`` counts those in ``state`` if given."""
    jobs, total = await run_in_threadpool(_store(request).page, owner, limit, offset, state)
    return JobPage(jobs=[JobSummary.of(job) for job in jobs], total=total, limit=limit, offset=offset)


@router.get("/{job_id}", response_model=JobStatus, responses=ERRORS)
async def get_job(request: Request, job_id: str, owner: str = Depends(caller)) -> JobStatus:
    """State, windows done / total, each window's certificate, and the error if it failed."""
    return await _status(request, await _job(request, job_id, owner))


@router.delete("/{job_id}", response_model=JobStatus,
               responses={**ERRORS, 409: {"model": ErrorBody}, 204: {"description": "Removed (`remove=true`)."}})
async def cancel_job(request: Request, job_id: str, owner: str = Depends(caller),
                     remove: Annotated[bool, Query(description="Delete a finished job and all it stored.")] = False,
                     ) -> JobStatus | Response:
    """Cancel a queued or running job; on the in-process pool its running window stops at once,
    on Dask after it ends. The windows stored so far stay (``result?partial=true``). With
    ``remove=true``, delete a done, failed or cancelled job and everything stored with it (204)."""
    job = await _job(request, job_id, owner)
    if remove:
        if not await run_in_threadpool(_store(request).remove, job.id):
            raise HTTPException(409, f"job {job_id} is {job.state}: cancel it first, then remove it")
        return Response(status_code=204)
    if job.state in ACTIVE:
        await run_in_threadpool(_store(request).cancel, job.id)
        await run_in_threadpool(request.app.state.executor.cancel, job.id)
        job = await _job(request, job_id, owner)
    if job.state != "cancelled":
        raise HTTPException(409, f"job {job_id} is already {job.state}")
    return await _status(request, job)


@router.get(
    "/{job_id}/events", responses={
        **ERRORS, 429: {"model": ErrorBody, "description": "This token has max_event_streams_per_token streams open."},
        200: {"content": {"text/event-stream": {"schema": {"type": "string"}}},
              "description": "`window` events, then `state` events (`removed` if the job is removed meanwhile)."}},
)
async def job_progress(request: Request, job_id: str, owner: str = Depends(caller)) -> Response:
    """Server-sent events: one `window` event per finished window, `state` at each change; ends with the job.

    A token may hold ``max_event_streams_per_token`` streams open; past that, 429."""
    job = await _job(request, job_id, owner)
    poll = request.app.state.settings.events_poll_seconds
    return request.app.state.event_streams.response(owner, _store(request), job.id, poll)


@router.get(
    "/{job_id}/result", response_model=LabeledResult,
    responses={**ERRORS, 409: {"model": ErrorBody, "description": "The job is not done."},
               200: {"content": {"text/csv": {"schema": {"type": "string"}},
                                 "application/octet-stream": {"schema": {"type": "string", "format": "binary"}}},
                     "description": "JSON (below), CSV, or C3D."}},
)
async def job_result(
    request: Request, job_id: str, owner: str = Depends(caller),
    format: Literal["json", "csv", "c3d"] = Query("json", description="json, csv or c3d."),
    partial: bool = Query(False, description="Before the job is done (failed, cancelled, running): the frames "
                                             "its stored windows labeled; later frames are occluded (null)."),
) -> Response:
    """The labeled trajectories, once the job is done (or, with ``partial=true``, so far)."""
    job = await _job(request, job_id, owner)
    if job.state != "done" and not partial:
        raise HTTPException(409, f"job {job_id} is {job.state}, not done (partial=true gives its stored windows)")
    content = await run_in_threadpool(job_file, _store(request), job.id, format, job.state == "done")
    return Response(content, media_type=MEDIA_TYPES[format], headers={"Content-Disposition": attachment(job, format)})

