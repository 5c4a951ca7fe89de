"""What the service offers and how it is doing: formulations, health, metrics."""

from __future__ import annotations

from fastapi import APIRouter, Depends, Request, Response
from prometheus_client import CONTENT_TYPE_LATEST, generate_latest
from starlette.concurrency import run_in_threadpool

from formulations.methods.registry import describe
from service.server.auth import caller
from service.server.schemas import ErrorBody, FormulationInfo, Health, ParameterInfo

router = APIRouter(tags=["service"])


@router.get("/v1/formulations", response_model=list[FormulationInfo])
def formulations() -> list[FormulationInfo]:
    """Every window formulation with its parameters, defaults and docs."""
    return [
        FormulationInfo(name=d.name, doc=d.doc, parameters=[ParameterInfo(name=p.name, default=p.default, doc=p.doc)
                                                            for p in d.parameters])
        for d in describe()
    ]


@router.get("/healthz", response_model=Health)
async def healthz(request: Request) -> Health:
    """OK when the store answers; nothing else, and no token needed (for load balancers)."""
    await run_in_threadpool(request.app.state.store.queued)
    return Health(status="ok")


@router.get("/metrics", response_class=Response, dependencies=[Depends(caller)],
            responses={200: {"content": {CONTENT_TYPE_LATEST: {"schema": {"type": "string"}}},
                             "description": "Prometheus text exposition."}, 401: {"model": ErrorBody}})
async def metrics(request: Request) -> Response:
    """Jobs by state, windows solved, window solve-time histogram (Prometheus text).

    Counts over all owners, with no owner label; with tokens configured, any token may read them.
    """
    text = await run_in_threadpool(generate_latest, request.app.state.metrics)
    return Response(text, media_type=CONTENT_TYPE_LATEST)
