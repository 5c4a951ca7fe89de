"""The FastAPI application: ``create_app(settings)``.

On start it opens the store and the executor and re-queues every ``queued`` or
``running`` job, which resumes after its last stored window. Errors are JSON
``{"message": ...}``: a user's mistake is a 4xx naming the field, the store not answering a
503 with Retry-After, and only a bug is a 500.
"""

from __future__ import annotations

import logging
from contextlib import asynccontextmanager

from anyio import CapacityLimiter
from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.openapi.utils import get_openapi
from fastapi.responses import JSONResponse
from fastapi_offline import FastAPIOffline
from sqlalchemy.exc import OperationalError
from starlette.concurrency import run_in_threadpool
from starlette.exceptions import HTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from service.capture.document import CaptureDocument
from service.errors import InputError
from service.server import routes_info, routes_jobs, routes_models, routes_solve
from service.server.events import EventStreams
from service.server.executor import DaskExecutor, Executor, ProcessPoolExecutor
from service.server.limits import BodyLimit
from service.server.metrics import metrics_registry
from service.server.settings import Settings
from service.server.store import store_for
from service.web.pages import mount_web

log = logging.getLogger("markerflow.server")
BUG_MESSAGE = "internal error; the server log has the details"


def create_app(settings: Settings) -> FastAPI:
    """The service, configured by ``settings``.

    Raises:
        InputError: A non-loopback host without tokens.
    """
    settings.check_exposure()
    docs = settings.api_docs  # False: no /docs, /redoc or /openapi.json
    # FastAPIOffline serves Swagger UI's and ReDoc's scripts from its package, not a CDN.
    app = (FastAPIOffline if docs else FastAPI)(
        title="markerflow", version="1", lifespan=_lifespan,
        description="Label optical motion-capture markers as durable jobs: submit, follow, fetch.",
        docs_url="/docs" if docs else None, redoc_url="/redoc" if docs else None,
        openapi_url="/openapi.json" if docs else None,
    )
    app.state.settings = settings
    app.state.owners = settings.owners()
    app.state.event_streams = EventStreams(settings.max_event_streams_per_token)
    app.add_middleware(BodyLimit, max_bytes=settings.limits.max_body_bytes, owners=app.state.owners,
                       read_seconds=settings.read_timeout_seconds)
    app.add_middleware(CatchBugs)  # outermost of ours: a bug in BodyLimit is caught too
    app.state.model_fits = CapacityLimiter(settings.max_parallel_jobs)  # POST /v1/models fits at once
    for router in (routes_jobs.router, routes_solve.router, routes_models.router, routes_info.router):
        app.include_router(router)
    mount_web(app)
    # Starlette types every handler as taking any Exception; each of these gets only its own class.
    app.add_exception_handler(InputError, _input_error)  # type: ignore[arg-type]
    app.add_exception_handler(RequestValidationError, _validation_error)  # type: ignore[arg-type]
    app.add_exception_handler(HTTPException, _http_error)  # type: ignore[arg-type]
    app.add_exception_handler(OperationalError, _store_down)  # type: ignore[arg-type]
    app.add_exception_handler(Exception, _bug)  # what CatchBugs cannot answer (a response under way)
    app.openapi = lambda: _openapi(app)  # type: ignore[method-assign]  # FastAPI's documented way to extend the schema
    return app


def _executor(settings: Settings) -> Executor:
    if settings.dask:
        return DaskExecutor(settings.db, settings.dask)
    return ProcessPoolExecutor(settings.db, settings.max_parallel_jobs, settings.shutdown_grace_seconds)


@asynccontextmanager
async def _lifespan(app: FastAPI):
    settings: Settings = app.state.settings
    store = await run_in_threadpool(store_for, settings.db)
    executor = await run_in_threadpool(_executor, settings)
    app.state.store, app.state.executor, app.state.metrics = store, executor, metrics_registry(store)
    unfinished = await run_in_threadpool(store.unfinished)
    for job_id in unfinished:
        await run_in_threadpool(executor.submit, job_id)
    if unfinished:
        log.info("resumed %d unfinished job%s", len(unfinished), "s" * (len(unfinished) != 1))
    yield
    await run_in_threadpool(executor.close)


def _openapi(app: FastAPI) -> dict:
    """FastAPI's schema plus ``CaptureDocument``, which the hand-read bodies refer to."""
    if app.openapi_schema is None:
        schema = get_openapi(title=app.title, version=app.version, description=app.description, routes=app.routes)
        document = CaptureDocument.model_json_schema(ref_template="#/components/schemas/{model}")
        components = schema.setdefault("components", {}).setdefault("schemas", {})
        components.update(document.pop("$defs", {}))
        components["CaptureDocument"] = document
        app.openapi_schema = schema
    return app.openapi_schema


async def _input_error(request: Request, error: InputError) -> JSONResponse:
    return JSONResponse({"message": str(error)}, status_code=422)


async def _validation_error(request: Request, error: RequestValidationError) -> JSONResponse:
    """``query.limit: Input should be ...``: the field path first, as for capture documents."""
    problems = error.errors()
    first = problems[0]
    path = ".".join(str(part) for part in first["loc"])
    message = f"{path}: {first['msg'].removeprefix('Value error, ')}"
    if len(problems) > 1:
        message += f" (and {len(problems) - 1} more problems)"
    detail = [{"loc": list(p["loc"]), "msg": p["msg"], "type": p["type"]} for p in problems]
    return JSONResponse({"message": message, "detail": detail}, status_code=422)


async def _http_error(request: Request, error: HTTPException) -> JSONResponse:
    return JSONResponse({"message": str(error.detail)}, status_code=error.status_code, headers=error.headers)


async def _store_down(request: Request, error: OperationalError) -> JSONResponse:
    """The database is down or full: not a bug, and over once it answers (jobs resume then)."""
    log.warning("the job store failed on %s %s: %s", request.method, request.url.path, error.orig)
    retry = str(request.app.state.settings.retry_after_seconds)
    return JSONResponse({"message": "the job store is not answering; retry later"}, status_code=503,
                        headers={"Retry-After": retry})


async def _bug(request: Request, error: Exception) -> JSONResponse:
    log.exception("internal error on %s %s", request.method, request.url.path)
    return JSONResponse({"message": BUG_MESSAGE}, status_code=500)


class CatchBugs:
    """ASGI middleware: an unexpected exception answers the one-line 500 and ends there.

    Starlette's ``Exception`` handler (``_bug``) answers too, but then re-raises, and uvicorn
    closes the connection: a keep-alive client's next request on it fails (connection reset).
    A response already under way cannot be replaced, so that exception is re-raised.
    """

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        started = False

        async def watched(message: Message) -> None:
            nonlocal started
            started = started or message["type"] == "http.response.start"
            await send(message)

        try:
            await self.app(scope, receive, watched)
        except Exception:
            if started:
                raise
            log.exception("internal error on %s %s", scope["method"], scope["path"])
            await JSONResponse({"message": BUG_MESSAGE}, status_code=500)(scope, receive, send)
