"""The jobs list page with its upload form: the caller's newest jobs and their figures."""

from __future__ import annotations

from fastapi import Request
from starlette.concurrency import run_in_threadpool
from starlette.responses import Response

from formulations.methods.registry import describe
from service.capture.capture import ASSOCIATIONS
from service.server.store import Job, JobStore
from service.web.access import page
from service.web.job_data import certificate_summary, doubtful_share, job_options
from service.web.upload import MODEL_OPTION

LISTED_JOBS = 100


async def jobs_list(
    request: Request, owner: str, error: str | None = None, status: int = 200, chosen: dict[str, str] | None = None,
    older: int = 0,
) -> Response:
    """The page; ``error`` is an upload's refusal, shown above the form, whose fields keep
    what the user ``chosen`` (formulation, parameters, window, association). ``older`` skips
    that many of the newest jobs: the list shows ``LISTED_JOBS`` at a time, with links on."""
    store, db = request.app.state.store, request.app.state.settings.db
    jobs, total = await run_in_threadpool(store.page, owner, LISTED_JOBS, older)
    rows = [await run_in_threadpool(_row, store, db, job) for job in jobs]
    pages = {"first": older + 1, "last": older + len(rows), "newer": max(older - LISTED_JOBS, 0) if older else None,
             "older": older + LISTED_JOBS if older + LISTED_JOBS < total else None}
    return page(request, "jobs.html", status, rows=rows, total=total, pages=pages,
                formulations=[d.name for d in describe()],
                associations=ASSOCIATIONS, model_option=MODEL_OPTION, error=error,
                chosen={key: "" for key in CHOSEN} | (chosen or {}))


CHOSEN = ("formulation", "parameters", "window", "association", "start", "end", "second_pass")  # the form's option fields


def _row(store: JobStore, db: str, job: Job) -> dict:
    """What the job asked for, how far it is, its share of integral windows and of doubtful labels."""
    windows = store.windows(job.id) if job.windows_done else []
    return {"job": job, "options": job_options(db, job.id),
            "integral": certificate_summary(windows)["integral_window_fraction"] if windows else None,
            "doubtful": doubtful_share(windows)}
