"""The HTML pages: ``/`` (the caller's jobs and the upload form) and ``/jobs/{id}``.

Without a valid session cookie (tokens configured) a page answers 401 with the sign-in
form; see ``session`` for why a cookie. ``mount_web`` adds every web route and the static
files to the app.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

from fastapi import APIRouter, FastAPI, HTTPException, Query, Request
from fastapi.staticfiles import StaticFiles
from starlette.concurrency import run_in_threadpool
from starlette.responses import Response

from service.server.routes_jobs import job_warnings
from service.server.store import ACTIVE
from service.web import actions, job_files
from service.web.access import owned_job, page
from service.web.job_data import certificate_summary, doubtful_share, job_labels, job_options
from service.web.listing import jobs_list
from service.web.plots.cameras import best_views
from service.web.plots.timeline import state_masks
from service.web.plots.trajectories import chosen_markers
from service.web.session import signed_in

router = APIRouter(include_in_schema=False)


def mount_web(app: FastAPI) -> None:
    app.mount("/static", StaticFiles(directory=Path(__file__).parent / "static"), name="static")
    for web in (router, actions.router, job_files.router):
        app.include_router(web)


@router.get("/")
async def jobs_page(request: Request, older: Annotated[int, Query(ge=0, le=2**62)] = 0) -> Response:
    owner = signed_in(request)
    if owner is None:
        return page(request, "sign_in.html", 401, signed_in=False)
    return await jobs_list(request, owner, older=older)


@router.get("/jobs/{job_id}")
async def job_page(request: Request, job_id: str, markers: Annotated[list[str] | None, Query()] = None) -> Response:
    owner = signed_in(request)
    if owner is None:
        return page(request, "sign_in.html", 401, signed_in=False)
    try:
        job = await owned_job(request, job_id, owner)
    except HTTPException as missing:
        return page(request, "missing.html", 404, message=missing.detail)
    store, db = request.app.state.store, request.app.state.settings.db
    windows = await run_in_threadpool(store.windows, job.id)
    labels = await run_in_threadpool(job_labels, db, job)
    context = {"job": job, "active": job.state in ACTIVE, "options": job_options(db, job.id), "windows": windows,
               "summary": certificate_summary(windows) if windows else None, "labels": labels,
               # the labels drawn, once there are: the stored windows' counts predate the second pass
               "doubtful": labels.doubtful_share() if labels is not None else doubtful_share(windows),
               "warnings": await run_in_threadpool(job_warnings, request, job),
               "first_frame": await run_in_threadpool(store.upload_start, job.id)}
    if labels is not None:
        chosen = chosen_markers(labels, markers or [])
        counts = [(name, *(int(mask[:, m].sum()) for _, mask in state_masks(labels)))
                  for m, name in enumerate(labels.names)]
        left_out = [name for name in dict.fromkeys(markers or []) if name in labels.names and name not in chosen]
        context |= {"chosen": chosen, "left_out": left_out, "counts": counts, "best_views": best_views(labels)}
    return page(request, "job.html", **context)
