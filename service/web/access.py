"""A page's job and its template rendering: another owner's job is 404, as in the API."""

from __future__ import annotations

from pathlib import Path

from fastapi import HTTPException, Request
from fastapi.templating import Jinja2Templates
from starlette.concurrency import run_in_threadpool
from starlette.responses import Response

from service.server.routes_jobs import JOB_ID
from service.server.store import Job

templates = Jinja2Templates(directory=Path(__file__).parent / "templates")


async def owned_job(request: Request, job_id: str, owner: str) -> Job:
    """The owner's job.

    Raises:
        HTTPException: 404 for an unknown id or another owner's job (its existence is not revealed).
    """
    job = await run_in_threadpool(request.app.state.store.get, job_id, owner) if JOB_ID.fullmatch(job_id) else None
    if job is None:
        raise HTTPException(404, f"no job {job_id}")
    return job


def page(request: Request, template: str, status: int = 200, **context: object) -> Response:
    """``template`` rendered with ``context``, and whether tokens are in use (for the sign-out button)."""
    return templates.TemplateResponse(request, template, {"tokens": bool(request.app.state.owners), **context},
                                      status_code=status)
