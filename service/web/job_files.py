"""What a job page loads beside its HTML, on the session cookie: the event stream, the result
files and the plots. Each is the caller's job only (404 otherwise, as in the API)."""

from __future__ import annotations

from typing import Annotated, Literal

from fastapi import APIRouter, Depends, HTTPException, Query, Request
from starlette.concurrency import run_in_threadpool
from starlette.responses import Response

from service.server.results import MEDIA_TYPES, attachment, job_file
from service.web.access import owned_job
from service.web.job_data import Labels, capture_document, job_labels, window_stats
from service.web.plots.cameras import cameras_svg, detections_used
from service.web.plots.certificate import certificate_svg
from service.web.plots.timeline import timeline_svg
from service.web.plots.trajectories import chosen_markers, trajectories_svg
from service.web.session import page_owner

router = APIRouter(prefix="/jobs/{job_id}", include_in_schema=False)
SVG = "image/svg+xml"


@router.get("/events")
async def events(request: Request, job_id: str, owner: str = Depends(page_owner)) -> Response:
    """The API's event stream of the job (``/v1/jobs/{id}/events``), for the page's ``EventSource``."""
    job = await owned_job(request, job_id, owner)
    return request.app.state.event_streams.response(owner, request.app.state.store, job.id,
                                                    request.app.state.settings.events_poll_seconds)


@router.get("/result.{format}")
async def result(request: Request, job_id: str, format: Literal["json", "csv", "c3d"],
                 owner: str = Depends(page_owner)) -> Response:
    """The result file as ``/v1/jobs/{id}/result`` serves it; a job that ended before it was
    done gives its stored windows (``partial=true``)."""
    job = await owned_job(request, job_id, owner)
    if job.state not in ("done", "failed", "cancelled"):
        raise HTTPException(409, f"job {job_id} is {job.state}; its result comes when it ends")
    content = await run_in_threadpool(job_file, request.app.state.store, job.id, format, job.state == "done")
    return Response(content, media_type=MEDIA_TYPES[format], headers={"Content-Disposition": attachment(job, format)})


@router.get("/plots/certificate.svg")
async def certificate_plot(request: Request, job_id: str, owner: str = Depends(page_owner)) -> Response:
    job = await owned_job(request, job_id, owner)
    windows = await run_in_threadpool(request.app.state.store.windows, job.id)
    return _svg(await run_in_threadpool(certificate_svg, window_stats(windows), job.windows_total))


@router.get("/plots/timeline.svg")
async def timeline_plot(request: Request, job_id: str, owner: str = Depends(page_owner)) -> Response:
    labels = await _labels(request, job_id, owner)
    return _svg(await run_in_threadpool(timeline_svg, labels))


@router.get("/plots/trajectories.svg")
async def trajectories_plot(request: Request, job_id: str, markers: Annotated[list[str] | None, Query()] = None,
                            owner: str = Depends(page_owner)) -> Response:
    labels = await _labels(request, job_id, owner)
    return _svg(await run_in_threadpool(trajectories_svg, labels, chosen_markers(labels, markers or [])))


@router.get("/plots/cameras.svg")
async def cameras_plot(request: Request, job_id: str, owner: str = Depends(page_owner)) -> Response:
    labels = await _labels(request, job_id, owner)
    document = await run_in_threadpool(capture_document, request.app.state.store, job_id)
    if document.detections is None:
        raise HTTPException(404, f"job {job_id} labeled 3D points, not camera detections")
    counts = await run_in_threadpool(detections_used, document.capture(), labels)
    return _svg(await run_in_threadpool(cameras_svg, counts))


async def _labels(request: Request, job_id: str, owner: str) -> Labels:
    job = await owned_job(request, job_id, owner)
    labels = await run_in_threadpool(job_labels, request.app.state.settings.db, job)
    if labels is None:
        when = "no window was stored before it ended" if job.state in ("failed", "cancelled") else "drawn when it ends"
        raise HTTPException(409, f"job {job_id} is {job.state}; it has no labels to draw ({when})")
    return labels


def _svg(content: bytes) -> Response:
    return Response(content, media_type=SVG, headers={"Cache-Control": "no-store"})
