"""What a page changes: sign in and out, submit a capture, cancel or delete a job.

Each answers a redirect (303) to the page to show next, so the forms work without script;
an upload the API would refuse shows the jobs page again with the API's one-line message.
"""

from __future__ import annotations

from fastapi import APIRouter, Depends, HTTPException, Request
from starlette.concurrency import run_in_threadpool
from starlette.responses import RedirectResponse, Response

from service.errors import InputError
from service.server.auth import bearer_token
from service.server.store import ACTIVE
from service.web.access import owned_job
from service.web.listing import CHOSEN, jobs_list
from service.web.session import forget_token, keep_token, page_owner, same_origin
from service.web.upload import FIELDS, form_submission

router = APIRouter(include_in_schema=False)


@router.post("/session", status_code=204)
async def sign_in(request: Request) -> Response:
    """Keep the bearer token this request sends (the sign-in form's script sends it) in the
    session cookie; the body-size middleware has already refused an unknown token (401)."""
    same_origin(request)
    token = bearer_token(request.headers.get("authorization", ""))
    if token is None:
        raise HTTPException(401, "send the token as Authorization: Bearer <token>")
    response = Response(status_code=204)
    keep_token(response, request, token)
    return response


@router.post("/session/end")
async def sign_out(request: Request) -> Response:
    same_origin(request)
    response = RedirectResponse("/", status_code=303)
    forget_token(response)
    return response


@router.post("/jobs")
async def submit(request: Request, owner: str = Depends(page_owner)) -> Response:
    """Queue the form's capture, as ``POST /v1/jobs`` does, and show its page."""
    store, settings = request.app.state.store, request.app.state.settings
    _, queued = await run_in_threadpool(store.intake, owner, None)
    if queued >= settings.max_queued_jobs:
        raise HTTPException(429, f"{queued} jobs are queued, the limit (max_queued_jobs); retry later",
                            headers={"Retry-After": str(settings.retry_after_seconds)})
    async with request.form(max_files=2, max_fields=len(FIELDS)) as form:
        try:
            submission = await run_in_threadpool(form_submission, form, settings.limits)
        except InputError as error:
            chosen = {key: value for key in CHOSEN if isinstance(value := form.get(key), str)}
            return await jobs_list(request, owner, error=str(error), status=422, chosen=chosen)
    job, _ = await run_in_threadpool(store.add, owner, submission.source, submission.stored(), submission.n_windows,
                                     None, submission.upload)
    await run_in_threadpool(request.app.state.executor.submit, job.id)
    return RedirectResponse(f"/jobs/{job.id}", status_code=303)


@router.post("/jobs/{job_id}/cancel")
async def cancel(request: Request, job_id: str, owner: str = Depends(page_owner)) -> Response:
    """Cancel the job if it is still queued or running; its page shows the outcome either way."""
    job = await owned_job(request, job_id, owner)
    if job.state in ACTIVE:
        await run_in_threadpool(request.app.state.store.cancel, job.id)
        await run_in_threadpool(request.app.state.executor.cancel, job.id)
    return RedirectResponse(f"/jobs/{job.id}", status_code=303)


@router.post("/jobs/{job_id}/delete")
async def delete(request: Request, job_id: str, owner: str = Depends(page_owner)) -> Response:
    """Delete a finished job and all it stored, then show the list (a running one: its page)."""
    job = await owned_job(request, job_id, owner)
    if not await run_in_threadpool(request.app.state.store.remove, job.id):
        return RedirectResponse(f"/jobs/{job.id}", status_code=303)
    return RedirectResponse("/", status_code=303)
