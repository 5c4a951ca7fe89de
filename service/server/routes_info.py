"""What the service offers and how it is doing: formulations, health, metrics."""

from __future__ import annotations

from fastapi import APIRouter, Request, Response
from prometheus_client import CONTENT_TYPE_LATEST, generate_latest
from starlette.concurrency import run_in_threadpool

from formulations.methods.registry import describe
from service.server.schemas import FormulationInfo, Health, ParameterInfo

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
    """OK when the store answers."""
    return Health(status="ok", jobs=await run_in_threadpool(request.app.state.store.count_by_state))


@router.get("/metrics", response_class=Response,
            responses={200: {"content": {CONTENT_TYPE_LATEST: {"schema": {"type": "string"}}},
                             "description": "Prometheus text exposition."}})
async def metrics(request: Request) -> Response:
    """Jobs by state, windows solved, window solve-time histogram (Prometheus text)."""
    text = await run_in_threadpool(generate_latest, request.app.state.metrics)
    return Response(text, media_type=CONTENT_TYPE_LATEST)
